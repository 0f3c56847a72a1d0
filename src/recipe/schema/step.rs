//! A step as written: deformations, modulations, subdivision, translation.

use serde::Deserialize;

use super::num::{Num, Num3};

/// `keep:` of a modulation.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub(crate) enum RawKeep {
    Flow,
    Speed,
}

/// The keys of `deform_xyz` and `deform_cylinder`.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawDeform {
    #[serde(default)]
    pub(crate) position: Option<Num3>,
    #[serde(default)]
    pub(crate) cross_section: Option<Num>,
    #[serde(default)]
    pub(crate) speed: Option<Num>,
}

/// A step as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) enum RawStep {
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
    /// `set: {every, from, band, <setting>: value, …}`: the printer's
    /// settings as expressions of the position (`x`, `y`, `z`) and the band
    /// index (`band`), written once per band at its first extruding string.
    Set(Box<RawSet>),
}

/// The keys of a `set` step: where its bands are, and the settings (each a
/// number or an expression over the params, `x`, `y`, `z` and `band`).
#[derive(Clone, Debug, Default, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawSet {
    /// Height of a band, mm: band `k` runs from `from + k·every` up.
    #[serde(default)]
    pub(crate) every: Option<Num>,
    /// Height where band 0 begins, mm (0).
    #[serde(default)]
    pub(crate) from: Option<Num>,
    /// This part is band `band` of a line test (no `every`); in a turtle's
    /// or path's `set` command, the line the command begins.
    #[serde(default)]
    pub(crate) band: Option<Num>,
    /// The head's speed of the band's extruding strings, mm/s (no firmware
    /// setting: the moves carry it).
    #[serde(default)]
    pub(crate) speed: Option<Num>,
    /// The flow of the band's extruding strings, mm³/s (each string's speed
    /// is it over the string's cross-section).
    #[serde(default)]
    pub(crate) volumetric_speed: Option<Num>,
    #[serde(default)]
    pub(crate) nozzle_temperature: Option<Num>,
    /// Wait for `nozzle_temperature` (false).
    #[serde(default)]
    pub(crate) wait: Option<bool>,
    #[serde(default)]
    pub(crate) fan: Option<Num>,
    #[serde(default)]
    pub(crate) pressure_advance: Option<Num>,
    #[serde(default)]
    pub(crate) retraction_length: Option<Num>,
    #[serde(default)]
    pub(crate) retraction_speed: Option<Num>,
    #[serde(default)]
    pub(crate) acceleration: Option<Num>,
    #[serde(default)]
    pub(crate) travel_acceleration: Option<Num>,
    #[serde(default)]
    pub(crate) speed_limit: Option<Num>,
    #[serde(default)]
    pub(crate) square_corner_velocity: Option<Num>,
    #[serde(default)]
    pub(crate) junction_deviation: Option<Num>,
    #[serde(default)]
    pub(crate) jerk: Option<Num>,
    #[serde(default)]
    pub(crate) input_shaper_frequency: Option<Num>,
    #[serde(default)]
    pub(crate) input_shaper_damping: Option<Num>,
    /// `zv`, `mzv`, `zvd`, `ei`, `2hump_ei`, `3hump_ei`.
    #[serde(default)]
    pub(crate) input_shaper_type: Option<String>,
    #[serde(default)]
    pub(crate) flow: Option<Num>,
}

impl RawSet {
    /// The pace given (`speed` or `volumetric_speed`): its key and value.
    pub(crate) fn paces(&self) -> Vec<(&'static str, &Num)> {
        [
            ("speed", &self.speed),
            ("volumetric_speed", &self.volumetric_speed),
        ]
        .into_iter()
        .filter_map(|(k, v)| v.as_ref().map(|v| (k, v)))
        .collect()
    }

    /// The firmware settings given, in the order of the docs: key and value.
    pub(crate) fn values(&self) -> Vec<(&'static str, &Num)> {
        [
            ("nozzle_temperature", &self.nozzle_temperature),
            ("fan", &self.fan),
            ("pressure_advance", &self.pressure_advance),
            ("retraction_length", &self.retraction_length),
            ("retraction_speed", &self.retraction_speed),
            ("acceleration", &self.acceleration),
            ("travel_acceleration", &self.travel_acceleration),
            ("speed_limit", &self.speed_limit),
            ("square_corner_velocity", &self.square_corner_velocity),
            ("junction_deviation", &self.junction_deviation),
            ("jerk", &self.jerk),
            ("input_shaper_frequency", &self.input_shaper_frequency),
            ("input_shaper_damping", &self.input_shaper_damping),
            ("flow", &self.flow),
        ]
        .into_iter()
        .filter_map(|(k, v)| v.as_ref().map(|v| (k, v)))
        .collect()
    }
}

/// The coordinate a `mirror` step reflects.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub(crate) enum RawAxis {
    X,
    Y,
    Z,
}

impl RawStep {
    /// The step's key (`deform_xyz`, `translate`): the variant's name as
    /// serde reads it (snake_case), the first segment of its key paths.
    pub(crate) fn key(&self) -> &'static str {
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
            RawStep::Set(_) => "set",
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
            ("set", "{every: 5, nozzle_temperature: 200 + band}"),
        ] {
            let s: RawStep = parse_yaml(&format!("{{{key}: {map}}}"), "t").unwrap();
            assert_eq!(s.key(), key);
        }
    }
}
