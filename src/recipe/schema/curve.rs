//! The curves a program draws in one command (FullControl's `arcXY`,
//! `spiralXY`, `helixZ`, `bezier`, `segmented_line` and `rectangleXY`):
//! each goes through its points in order, its first point included, drawing
//! with the pen down and travelling with it up.

use serde::Deserialize;

use super::num::{Num, RawPoint};

/// `arc:` an arc of a circle about `center`, or of a spiral (`end_radius`)
/// or helix (`rise`): point k of `segments` + 1 at angle start + sweep·k/n,
/// radius radius + (end_radius − radius)·k/n, height center.z + rise·k/n.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawArcCmd {
    /// The centre (missing coordinates: the head's).
    pub(crate) center: RawPoint,
    /// mm, at the first point.
    pub(crate) radius: Num,
    /// Angle of the first point, radians from +x, counter-clockwise (0).
    #[serde(default = "zero")]
    pub(crate) start: Num,
    /// Angle from the first point to the last, radians (negative: clockwise;
    /// `tau`: a full circle).
    pub(crate) sweep: Num,
    /// Strings along the arc (FullControl's `segments`).
    pub(crate) segments: Num,
    /// mm at the last point (a spiral); `radius` when absent.
    #[serde(default)]
    pub(crate) end_radius: Option<Num>,
    /// mm the last point is above the first (a helix); 0 when absent.
    #[serde(default)]
    pub(crate) rise: Option<Num>,
}

/// `bezier:` the Bézier curve of the control `points`, at `segments` + 1
/// evenly spaced values of its parameter, from the first control point to
/// the last.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBezier {
    /// Control points, at least two (missing coordinates: the head's).
    pub(crate) points: Vec<RawPoint>,
    /// Strings along the curve.
    pub(crate) segments: Num,
}

/// `line:` a straight line cut into `segments` equal strings.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLine {
    /// Where it starts; the head when absent.
    #[serde(default)]
    pub(crate) from: Option<RawPoint>,
    /// Where it ends.
    pub(crate) to: RawPoint,
    /// Strings along it.
    pub(crate) segments: Num,
}

/// `rectangle:` four sides from `corner` and back to it, along x first
/// (counter-clockwise for positive sizes), or along y first with
/// `clockwise: true` (FullControl's `rectangleXY`).
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRectangle {
    /// The first (and last) corner.
    pub(crate) corner: RawPoint,
    /// `[dx, dy]`, mm (signed).
    pub(crate) size: [Num; 2],
    /// Along y first (false when absent).
    #[serde(default)]
    pub(crate) clockwise: Option<bool>,
}

/// An arc's default start: +x.
fn zero() -> Num {
    Num::Value(0.0)
}
