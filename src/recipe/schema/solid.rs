//! `solid:` as written: features combined, layer and infill settings.

use serde::Deserialize;

use super::num::{Num, Num3};

/// `solid:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawSolid {
    /// mm (0.2).
    #[serde(default)]
    pub layer_height: Option<Num>,
    /// Perimeter loops per layer (2).
    #[serde(default)]
    pub perimeters: Option<Num>,
    /// Extrusion width, mm (0.45).
    #[serde(default)]
    pub line_width: Option<Num>,
    /// Most a chord may stray from an arc, mm (0.01).
    #[serde(default)]
    pub chord_tolerance: Option<Num>,
    /// Infill lines.
    #[serde(default)]
    pub infill: Option<RawInfill>,
    /// The features, combined in order.
    pub features: Vec<RawFeature>,
}

/// `infill:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawInfill {
    /// Degrees from +x (45).
    #[serde(default)]
    pub angle: Option<Num>,
    /// mm between lines of one direction (lines: line_width; grid: 2 × line_width; both solid).
    #[serde(default)]
    pub spacing: Option<Num>,
    /// +angle and −angle on alternate layers (true; lines only).
    #[serde(default)]
    pub alternate: Option<bool>,
    /// lines (default): one direction per layer; grid: both in every layer.
    #[serde(default)]
    pub pattern: Option<RawPattern>,
    /// Join the lines end to end along the boundary where the join stays inside (false).
    #[serde(default)]
    pub connect: Option<bool>,
}

/// `pattern:` of the infill.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RawPattern {
    /// One direction per layer.
    Lines,
    /// Both directions (+angle, then −angle) in every layer.
    Grid,
}

/// A feature as written: `{box: {…}}` or `{cylinder: {…}}`.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RawFeature {
    /// An axis-aligned rectangular prism.
    Box(RawBox),
    /// A vertical cylinder.
    Cylinder(RawCylinder),
}

/// `box:` keys.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawBox {
    /// Centre of the box.
    pub center: Num3,
    /// Sizes along x, y, z.
    pub size: Num3,
    /// union (default), subtract or intersect.
    #[serde(default)]
    pub op: Option<RawOp>,
}

/// `cylinder:` keys.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawCylinder {
    /// Centre of the bottom face.
    pub center: Num3,
    /// Radius.
    pub radius: Num,
    /// Height above the centre.
    pub height: Num,
    /// union (default), subtract or intersect.
    #[serde(default)]
    pub op: Option<RawOp>,
}

/// `op:` of a feature.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RawOp {
    /// Adds material.
    Union,
    /// Removes material.
    Subtract,
    /// Keeps the common part.
    Intersect,
}
