//! A step as written: deformations, modulations, subdivision, translation.

use serde::Deserialize;

use super::num::{Num, Num3};

/// `keep:` of a modulation.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum RawKeep {
    Flow,
    Speed,
}

/// The keys of `deform_xyz` and `deform_cylinder`.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct RawDeform {
    #[serde(default)]
    pub position: Option<Num3>,
    #[serde(default)]
    pub cross_section: Option<Num>,
    #[serde(default)]
    pub speed: Option<Num>,
}

/// A step as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
#[allow(missing_docs)]
pub enum RawStep {
    DeformXyz(RawDeform),
    DeformCylinder(RawDeform),
    ModulateCylinder {
        factor: Num,
        #[serde(default)]
        keep: Option<RawKeep>,
    },
    ModulateMap {
        #[serde(default)]
        image: Option<String>,
        #[serde(default)]
        text: Option<String>,
        u: Num,
        v: Num,
        #[serde(default)]
        dark: Option<Num>,
        #[serde(default)]
        light: Option<Num>,
        #[serde(default)]
        threshold: Option<Num>,
        #[serde(default)]
        keep: Option<RawKeep>,
    },
    Subdivide {
        max_length: Num,
    },
    Translate(Num3),
    /// `rotate: {angle, center}`: every point turned by `angle` radians
    /// (counter-clockwise seen from above) about the vertical line through
    /// `center` (the origin when absent).
    Rotate {
        angle: Num,
        #[serde(default)]
        center: Option<Num3>,
    },
    /// `scale: {factor: [sx, sy, sz], center}`: every point's offset from
    /// `center` (the origin when absent) multiplied axis by axis; strings
    /// keep their cross-section and speed.
    Scale {
        factor: Num3,
        #[serde(default)]
        center: Option<Num3>,
    },
    /// `mirror: {axis, at}`: every point reflected in the plane where the
    /// coordinate `axis` (x, y or z) is `at` (0 when absent).
    Mirror {
        axis: RawAxis,
        #[serde(default)]
        at: Option<Num>,
    },
    /// `gcode_at: {z, gcode}`: a printer command (a filament change `M600`)
    /// written before the first extruding string that reaches height `z`.
    GcodeAt {
        z: Num,
        gcode: String,
    },
}

/// The coordinate a `mirror` step reflects.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum RawAxis {
    X,
    Y,
    Z,
}

impl RawStep {
    /// The step's key (`deform_xyz`, `translate`): the variant's name as
    /// serde reads it (snake_case), the first segment of its key paths.
    pub fn key(&self) -> &'static str {
        match self {
            RawStep::DeformXyz(_) => "deform_xyz",
            RawStep::DeformCylinder(_) => "deform_cylinder",
            RawStep::ModulateCylinder { .. } => "modulate_cylinder",
            RawStep::ModulateMap { .. } => "modulate_map",
            RawStep::Subdivide { .. } => "subdivide",
            RawStep::Translate(_) => "translate",
            RawStep::Rotate { .. } => "rotate",
            RawStep::Scale { .. } => "scale",
            RawStep::Mirror { .. } => "mirror",
            RawStep::GcodeAt { .. } => "gcode_at",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recipe::yaml::parse_yaml;

    #[test]
    fn each_step_knows_the_key_it_was_read_by() {
        for (key, map) in [
            ("deform_xyz", "{}"),
            ("deform_cylinder", "{}"),
            ("modulate_cylinder", "{factor: 1}"),
            ("modulate_map", "{u: x, v: y}"),
            ("subdivide", "{max_length: 1}"),
            ("translate", "[0, 0, 1]"),
            ("rotate", "{angle: 1}"),
            ("scale", "{factor: [1, 2, 1]}"),
            ("mirror", "{axis: x}"),
            ("gcode_at", "{z: 10, gcode: M600}"),
        ] {
            let s: RawStep = parse_yaml(&format!("{{{key}: {map}}}"), "t").unwrap();
            assert_eq!(s.key(), key);
        }
    }
}
