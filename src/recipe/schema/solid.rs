//! `solid:` as written: features combined, layer and infill settings.

use serde::Deserialize;

use super::num::{Num, Num3};

/// `solid:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSolid {
    /// mm (0.2).
    #[serde(default)]
    pub(crate) layer_height: Option<Num>,
    /// Perimeter loops per layer (2).
    #[serde(default)]
    pub(crate) perimeters: Option<Num>,
    /// Extrusion width, mm (0.45).
    #[serde(default)]
    pub(crate) line_width: Option<Num>,
    /// Most a chord may stray from an arc, mm (0.01).
    #[serde(default)]
    pub(crate) chord_tolerance: Option<Num>,
    /// Infill lines.
    #[serde(default)]
    pub(crate) infill: Option<RawInfill>,
    /// The features, combined in order.
    pub(crate) features: Vec<RawFeature>,
}

/// `infill:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawInfill {
    /// Degrees from +x (45).
    #[serde(default)]
    pub(crate) angle: Option<Num>,
    /// mm between lines of one direction (lines: line_width; grid: 2 × line_width; both solid).
    #[serde(default)]
    pub(crate) spacing: Option<Num>,
    /// +angle and −angle on alternate layers (true; lines only).
    #[serde(default)]
    pub(crate) alternate: Option<bool>,
    /// lines (default): one direction per layer; grid: both in every layer.
    #[serde(default)]
    pub(crate) pattern: Option<RawPattern>,
    /// Join the lines end to end along the boundary where the join stays inside (false).
    #[serde(default)]
    pub(crate) connect: Option<bool>,
}

/// `pattern:` of the infill.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub(crate) enum RawPattern {
    /// One direction per layer.
    Lines,
    /// Both directions (+angle, then −angle) in every layer.
    Grid,
}

/// A feature as written: `{box: {…}}` or `{cylinder: {…}}`.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub(crate) enum RawFeature {
    /// An axis-aligned rectangular prism.
    Box(RawBox),
    /// A vertical cylinder.
    Cylinder(RawCylinder),
}

/// `box:` keys.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBox {
    /// Centre of the box.
    pub(crate) center: Num3,
    /// Sizes along x, y, z.
    pub(crate) size: Num3,
    /// union (default), subtract or intersect.
    #[serde(default)]
    pub(crate) op: Option<RawOp>,
}

/// `cylinder:` keys.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCylinder {
    /// Centre of the bottom face.
    pub(crate) center: Num3,
    /// Radius.
    pub(crate) radius: Num,
    /// Height above the centre.
    pub(crate) height: Num,
    /// union (default), subtract or intersect.
    #[serde(default)]
    pub(crate) op: Option<RawOp>,
}

/// `op:` of a feature.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub(crate) enum RawOp {
    /// Adds material.
    Union,
    /// Removes material.
    Subtract,
    /// Keeps the common part.
    Intersect,
}
