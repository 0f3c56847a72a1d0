//! A printer profile as written (a built-in one or a user's file): the
//! keys of [`crate::machine::Printer`] and its parts, with their defaults.
//! Every value is a plain number already (profiles take no expressions);
//! `crate::recipe::profile` copies them into the machine's types and
//! checks them.
//!
//! serde's messages name the type a value should have ("expected struct
//! Printer"): each form keeps the name of the machine type it becomes
//! (`expecting`), so the messages read as they did when profiles were read
//! straight into the machine's types.

use serde::Deserialize;

use crate::machine::{CheckLimits, Flavor, Head, Kinematics, Retraction};

/// `flavor:` the G-code dialect of the firmware.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase", expecting = "enum Flavor")]
#[allow(missing_docs)]
pub(crate) enum RawFlavor {
    #[default]
    Marlin,
    Klipper,
    Reprap,
    Prusa,
    Bambu,
}

impl RawFlavor {
    /// The firmware flavour the profile's `flavor:` names.
    pub(crate) fn flavor(self) -> Flavor {
        match self {
            RawFlavor::Marlin => Flavor::Marlin,
            RawFlavor::Klipper => Flavor::Klipper,
            RawFlavor::Reprap => Flavor::Reprap,
            RawFlavor::Prusa => Flavor::Prusa,
            RawFlavor::Bambu => Flavor::Bambu,
        }
    }
}

/// `extrusion:` absolute (M82) or relative (M83) E values.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase", expecting = "enum Extrusion")]
#[allow(missing_docs)]
pub(crate) enum RawExtrusion {
    #[default]
    Absolute,
    Relative,
}

/// `bed:` the printable area, `shape: rectangle` or `shape: circle`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(
    tag = "shape",
    rename_all = "lowercase",
    deny_unknown_fields,
    expecting = "internally tagged enum Bed"
)]
pub(crate) enum RawBed {
    /// A rectangular bed.
    Rectangle {
        /// Width and depth, mm.
        size: [f64; 2],
        /// Highest reachable nozzle height, mm.
        max_z: f64,
        /// The front-left corner, machine coordinates, mm ([0, 0]).
        #[serde(default)]
        min: [f64; 2],
    },
    /// A round bed.
    Circle {
        /// Diameter, mm.
        diameter: f64,
        /// Highest reachable nozzle height, mm.
        max_z: f64,
    },
}

/// `retraction:` before long travel moves.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, expecting = "struct Retraction")]
pub(crate) struct RawRetraction {
    /// Filament pulled back, mm (0 for none).
    pub(crate) length: f64,
    /// Retraction speed, mm/s of filament.
    pub(crate) speed: f64,
    /// Travel moves shorter than this are not retracted, mm.
    #[serde(default = "d_min_travel")]
    pub(crate) min_travel: f64,
}

fn d_min_travel() -> f64 {
    Retraction::default().min_travel
}

impl Default for RawRetraction {
    fn default() -> Self {
        let r = Retraction::default();
        RawRetraction {
            length: r.length,
            speed: r.speed,
            min_travel: r.min_travel,
        }
    }
}

/// A printer profile: the spec's keys plus the limits p3dp checks against.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, expecting = "struct Printer")]
pub(crate) struct RawPrinter {
    /// Profile name.
    pub(crate) name: String,
    /// The model as its maker's software names it (`MK4`, `X1C`; PrusaSlicer's
    /// `printer_model`, also accepted under that name): `[printer_model]` in
    /// start G-code, the G-code's metadata, Bambu's package (none).
    #[serde(default, alias = "printer_model")]
    pub(crate) model: String,
    /// Firmware dialect.
    #[serde(default)]
    pub(crate) flavor: RawFlavor,
    /// Printable area.
    pub(crate) bed: RawBed,
    /// Where recipe (0, 0, 0) lands, in machine coordinates.
    pub(crate) origin: [f64; 3],
    /// Nozzle diameter, mm.
    pub(crate) nozzle_diameter: f64,
    /// Filament diameter, mm (a material may override it).
    pub(crate) filament_diameter: f64,
    /// Absolute or relative E.
    #[serde(default)]
    pub(crate) extrusion: RawExtrusion,
    /// Extruders (or a filament changer's slots) the start and end G-code
    /// know: the length of the slicers' per-extruder values (1); p3dp prints
    /// with the first.
    #[serde(default = "d_extruders")]
    pub(crate) extruders: u32,
    /// The extruder p3dp prints with, 0-based (0).
    #[serde(default)]
    pub(crate) tool: u32,
    /// G-code before the print, with placeholders.
    #[serde(default)]
    pub(crate) start_gcode: String,
    /// G-code after the print, with the same placeholders.
    #[serde(default)]
    pub(crate) end_gcode: String,
    /// Values of template variables only a slicer knows (none).
    #[serde(default)]
    pub(crate) gcode_variables: indexmap::IndexMap<String, RawVariable>,
    /// Where the start and end G-code may move the head.
    #[serde(default)]
    pub(crate) envelope: RawEnvelope,
    /// Head speed of travel moves, mm/s (120).
    #[serde(default = "d_travel")]
    pub(crate) travel_speed: f64,
    /// Retraction before long travel moves (none).
    #[serde(default)]
    pub(crate) retraction: RawRetraction,
    /// Retract with the firmware's `G10`/`G11` instead of E moves.
    #[serde(default)]
    pub(crate) firmware_retraction: bool,
    /// Hottest nozzle the hot end allows, °C (260).
    #[serde(default = "d_max_nozzle")]
    pub(crate) max_nozzle_temp: f64,
    /// Hottest bed allowed, °C (110).
    #[serde(default = "d_max_bed")]
    pub(crate) max_bed_temp: f64,
    /// Fastest head speed, mm/s (300).
    #[serde(default = "d_max_speed")]
    pub(crate) max_speed: f64,
    /// Hot-end volumetric flow limit, mm³/s (12).
    #[serde(default = "d_max_flow")]
    pub(crate) max_flow: f64,
    /// Shortest extruding run kept as its own move, mm (0.1).
    #[serde(default = "d_min_string")]
    pub(crate) min_string_length: f64,
    /// Fit `G2`/`G3` arcs to runs of strings (off).
    #[serde(default)]
    pub(crate) arcs: bool,
    /// Largest distance between an arc and the strings it replaces, mm (0.025).
    #[serde(default = "d_arc_tolerance")]
    pub(crate) arc_tolerance: f64,
    /// Thumbnails to embed in the G-code, as `WxH` (PNG) or `WxH/FORMAT`
    /// with FORMAT `PNG`, `QOI` or `JPG` (none).
    #[serde(default)]
    pub(crate) thumbnails: Vec<String>,
    /// `M73` progress from the planner's time (on for Marlin and Prusa).
    #[serde(default)]
    pub(crate) progress: Option<bool>,
    /// Klipper's object labels, `EXCLUDE_OBJECT_*` (on for Klipper).
    #[serde(default)]
    pub(crate) object_labels: Option<bool>,
    /// Binary G-code (`.bgcode`) unless the output's name says otherwise (off).
    #[serde(default)]
    pub(crate) binary_gcode: bool,
    /// The start G-code is the maker's own sequence: its nozzle
    /// temperatures held to the printer's limit, the one the print starts
    /// at to the material's (off).
    #[serde(default)]
    pub(crate) maker_temperatures: bool,
    /// Write the firmware's limits (`kinematics`) as `M201`–`M205` before
    /// the start G-code, as PrusaSlicer's `emit_to_gcode` (off).
    #[serde(default)]
    pub(crate) emit_limits: bool,
    /// The firmware's maximum X and Y accelerations, mm/s², written as
    /// `M201 X Y` with `emit_limits` (none).
    #[serde(default)]
    pub(crate) axis_acceleration: Option<[f64; 2]>,
    /// Pressure (linear) advance written after the start G-code, s (none:
    /// the firmware keeps its own); `p3dp calibrate apply` writes it.
    #[serde(default)]
    pub(crate) pressure_advance: Option<f64>,
    /// The firmware planner's limits.
    #[serde(default)]
    pub(crate) kinematics: RawKinematics,
    /// The print head's geometry.
    #[serde(default)]
    pub(crate) head: RawHead,
    /// Thresholds of the flow, support and planner checks.
    #[serde(default)]
    pub(crate) checks: CheckLimits,
}

/// A value under `gcode_variables:`: a boolean, a number, a string or a
/// list of them (a slicer's per-extruder list).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(
    untagged,
    expecting = "a boolean, a number, a string or a list of them"
)]
#[allow(missing_docs)]
pub(crate) enum RawVariable {
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(String),
    List(Vec<RawVariable>),
}

/// `envelope:` where a profile's start and end G-code may move the head;
/// each absent key is [`crate::machine::printer::Envelope::default`]'s.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default, expecting = "struct Envelope")]
#[allow(missing_docs)]
pub(crate) struct RawEnvelope {
    pub(crate) margin: f64,
    pub(crate) below_bed: f64,
    /// `[lowest, highest]` machine X the head reaches.
    pub(crate) x: Option<[f64; 2]>,
    /// `[lowest, highest]` machine Y the head reaches.
    pub(crate) y: Option<[f64; 2]>,
}

impl Default for RawEnvelope {
    fn default() -> Self {
        let e = crate::machine::printer::Envelope::default();
        RawEnvelope {
            margin: e.margin,
            below_bed: e.below_bed,
            x: e.x,
            y: e.y,
        }
    }
}

impl RawPrinter {
    /// A profile of the given required keys, every other key its default
    /// (what a file naming only those keys parses into).
    pub(crate) fn new(
        name: String,
        bed: RawBed,
        origin: [f64; 3],
        nozzle_diameter: f64,
        filament_diameter: f64,
    ) -> RawPrinter {
        RawPrinter {
            name,
            model: String::new(),
            flavor: RawFlavor::default(),
            bed,
            origin,
            nozzle_diameter,
            filament_diameter,
            extrusion: RawExtrusion::default(),
            extruders: d_extruders(),
            tool: 0,
            start_gcode: String::new(),
            end_gcode: String::new(),
            gcode_variables: indexmap::IndexMap::new(),
            envelope: RawEnvelope::default(),
            travel_speed: d_travel(),
            retraction: RawRetraction::default(),
            firmware_retraction: false,
            max_nozzle_temp: d_max_nozzle(),
            max_bed_temp: d_max_bed(),
            max_speed: d_max_speed(),
            max_flow: d_max_flow(),
            min_string_length: d_min_string(),
            arcs: false,
            arc_tolerance: d_arc_tolerance(),
            thumbnails: Vec::new(),
            progress: None,
            object_labels: None,
            binary_gcode: false,
            maker_temperatures: false,
            emit_limits: false,
            axis_acceleration: None,
            pressure_advance: None,
            kinematics: RawKinematics::default(),
            head: RawHead::default(),
            checks: CheckLimits::default(),
        }
    }
}

fn d_extruders() -> u32 {
    1
}
fn d_travel() -> f64 {
    120.0
}
fn d_max_nozzle() -> f64 {
    260.0
}
fn d_max_bed() -> f64 {
    110.0
}
fn d_max_speed() -> f64 {
    300.0
}
fn d_max_flow() -> f64 {
    12.0
}
fn d_min_string() -> f64 {
    0.1
}
fn d_arc_tolerance() -> f64 {
    0.025
}

/// `kinematics:` the limits the firmware's planner works with; each absent
/// key has the default [`Kinematics::limits`] explains.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, expecting = "struct Kinematics")]
#[allow(missing_docs)]
pub(crate) struct RawKinematics {
    #[serde(default)]
    pub(crate) max_velocity: Option<f64>,
    #[serde(default = "d_accel")]
    pub(crate) max_acceleration: f64,
    #[serde(default)]
    pub(crate) travel_acceleration: Option<f64>,
    #[serde(default)]
    pub(crate) retract_acceleration: Option<f64>,
    #[serde(default)]
    pub(crate) junction_deviation: Option<f64>,
    #[serde(default)]
    pub(crate) jerk: Option<f64>,
    #[serde(default)]
    pub(crate) square_corner_velocity: Option<f64>,
    #[serde(default)]
    pub(crate) min_segment_time: Option<f64>,
    #[serde(default)]
    pub(crate) minimum_cruise_ratio: Option<f64>,
    #[serde(default)]
    pub(crate) max_z_speed: Option<f64>,
    #[serde(default)]
    pub(crate) max_z_acceleration: Option<f64>,
    #[serde(default)]
    pub(crate) instantaneous_corner_velocity: Option<f64>,
    #[serde(default)]
    pub(crate) max_extrude_only_velocity: Option<f64>,
    #[serde(default)]
    pub(crate) max_extrude_only_accel: Option<f64>,
    #[serde(default)]
    pub(crate) max_extrude_cross_section: Option<f64>,
    #[serde(default)]
    pub(crate) max_extrude_only_distance: Option<f64>,
    #[serde(default)]
    pub(crate) min_segment_time_floor: bool,
    #[serde(default)]
    pub(crate) block_buffer_size: Option<u32>,
    #[serde(default)]
    pub(crate) command_rate: Option<f64>,
}

fn d_accel() -> f64 {
    Kinematics::default().max_acceleration
}

impl Default for RawKinematics {
    fn default() -> Self {
        let k = Kinematics::default();
        RawKinematics {
            max_velocity: k.max_velocity,
            max_acceleration: k.max_acceleration,
            travel_acceleration: k.travel_acceleration,
            retract_acceleration: k.retract_acceleration,
            junction_deviation: k.junction_deviation,
            jerk: k.jerk,
            square_corner_velocity: k.square_corner_velocity,
            min_segment_time: k.min_segment_time,
            minimum_cruise_ratio: k.minimum_cruise_ratio,
            max_z_speed: k.max_z_speed,
            max_z_acceleration: k.max_z_acceleration,
            instantaneous_corner_velocity: k.instantaneous_corner_velocity,
            max_extrude_only_velocity: k.max_extrude_only_velocity,
            max_extrude_only_accel: k.max_extrude_only_accel,
            max_extrude_cross_section: k.max_extrude_cross_section,
            max_extrude_only_distance: k.max_extrude_only_distance,
            min_segment_time_floor: k.min_segment_time_floor,
            block_buffer_size: k.block_buffer_size,
            command_rate: k.command_rate,
        }
    }
}

/// `head:` the print head as the collision check sees it; each absent key
/// is [`Head::default`]'s.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default, expecting = "struct Head")]
#[allow(missing_docs)]
pub(crate) struct RawHead {
    pub(crate) cone_angle: f64,
    pub(crate) cone_height: f64,
    pub(crate) tip_diameter: f64,
    #[serde(rename = "box")]
    pub(crate) head_box: [f64; 4],
    pub(crate) clearance: f64,
    pub(crate) gantry: Option<RawGantry>,
}

/// `head.gantry:` from `height` above the tip, the whole bed in x, `y`
/// round the nozzle.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawGantry {
    pub(crate) height: f64,
    pub(crate) y: [f64; 2],
}

impl Default for RawHead {
    fn default() -> Self {
        let h = Head::default();
        RawHead {
            cone_angle: h.cone_angle,
            cone_height: h.cone_height,
            tip_diameter: h.tip_diameter,
            head_box: h.head_box,
            clearance: h.clearance,
            gantry: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recipe::yaml::parse_yaml;

    /// `RawPrinter::new` is what a file of the required keys parses into.
    #[test]
    fn new_is_the_defaults_of_a_file() {
        let p: RawPrinter = parse_yaml(
            "name: d\nbed: {shape: circle, diameter: 280, max_z: 300}\norigin: [0,0,0]\nnozzle_diameter: 0.4\nfilament_diameter: 1.75\n",
            "d.yaml",
        )
        .unwrap();
        let new = RawPrinter::new(
            "d".into(),
            RawBed::Circle {
                diameter: 280.0,
                max_z: 300.0,
            },
            [0.0; 3],
            0.4,
            1.75,
        );
        assert_eq!(p, new);
    }

    #[test]
    fn round_bed_and_unknown_keys() {
        let p: RawPrinter = parse_yaml(
            "name: d\nbed: {shape: circle, diameter: 280, max_z: 300}\norigin: [0,0,0]\nnozzle_diameter: 0.4\nfilament_diameter: 1.75\n",
            "d.yaml",
        )
        .unwrap();
        assert!(matches!(p.bed, RawBed::Circle { diameter, .. } if diameter == 280.0));
        let e = parse_yaml::<RawPrinter>(
            "name: d\nbed: {shape: circle, diameter: 280, max_z: 300, size: 3}\norigin: [0,0,0]\nnozzle_diameter: 0.4\nfilament_diameter: 1.75\n",
            "d.yaml",
        )
        .unwrap_err();
        assert!(e.to_string().contains("size"), "{e}");
    }

    #[test]
    fn messages_name_the_machine_types() {
        let e = parse_yaml::<RawPrinter>("5", "p.yaml").unwrap_err();
        assert!(e.message.ends_with("expected struct Printer"), "{e}");
        for (key, ty) in [
            ("flavor: [1]", "enum Flavor"),
            ("extrusion: 3", "enum Extrusion"),
            ("bed: 5", "internally tagged enum Bed"),
            ("retraction: 3", "struct Retraction"),
            ("kinematics: 3", "struct Kinematics"),
            ("head: 3", "struct Head"),
            ("checks: 3", "struct CheckLimits"),
        ] {
            let e = parse_yaml::<RawPrinter>(&format!("name: p\n{key}\n"), "p.yaml").unwrap_err();
            assert!(e.message.ends_with(&format!("expected {ty}")), "{key}: {e}");
        }
    }
}
