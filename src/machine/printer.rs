//! A printer profile: bed, origin, nozzle, G-code templates and the limits
//! p3dp checks against (data only; [`crate::recipe::profile`] loads it).

use std::collections::BTreeMap;

use glam::DVec3;

use crate::base::error::{Error, Result};
use crate::base::slicer_macro::{Template, Value};

/// G-code dialect of the firmware.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Flavor {
    /// Marlin (and Prusa's Marlin).
    #[default]
    Marlin,
    /// Klipper.
    Klipper,
    /// RepRapFirmware.
    Reprap,
    /// Prusa's firmware (MK3S's Prusa-Firmware, MK4's Buddy): Marlin but for
    /// the pause, `M601`, and pressure advance, `M572`.
    Prusa,
    /// Bambu Lab's firmware: Marlin-like, with Bambu's own commands (the part
    /// fan is `M106 P1`, a pause `M400 U1`).
    Bambu,
}

impl Flavor {
    /// Every flavour, in the order `p3dp printers` and the docs list them.
    #[cfg(any(test, feature = "testing"))]
    pub(crate) const ALL: [Flavor; 5] = [
        Flavor::Marlin,
        Flavor::Prusa,
        Flavor::Klipper,
        Flavor::Reprap,
        Flavor::Bambu,
    ];

    /// The profile's name of the flavour: `marlin`, `prusa`, `klipper`,
    /// `reprap`, `bambu`.
    pub fn name(self) -> &'static str {
        match self {
            Flavor::Marlin => "marlin",
            Flavor::Prusa => "prusa",
            Flavor::Klipper => "klipper",
            Flavor::Reprap => "reprap",
            Flavor::Bambu => "bambu",
        }
    }

    /// The firmware's name in messages: `Marlin`, `Prusa's`, `Klipper`,
    /// `RepRapFirmware`, `Bambu's`.
    pub(crate) fn display_name(self) -> &'static str {
        match self {
            Flavor::Marlin => "Marlin",
            Flavor::Prusa => "Prusa's",
            Flavor::Klipper => "Klipper",
            Flavor::Reprap => "RepRapFirmware",
            Flavor::Bambu => "Bambu's",
        }
    }
}

/// Absolute (M82) or relative (M83) E values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(crate) enum Extrusion {
    /// M82: E is the total filament fed so far.
    #[default]
    Absolute,
    /// M83: E is the filament fed by this move.
    Relative,
}

/// The printable area. Rectangle beds span machine X in [min x, min x +
/// width] and Y in [min y, min y + depth] (`min` is [0, 0] unless the
/// printable area is offset, as a slicer's `bed_shape` may be); round
/// (delta) beds are centred on machine (0, 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bed {
    /// A rectangular bed.
    Rectangle {
        /// Width and depth, mm.
        size: [f64; 2],
        /// Highest reachable nozzle height, mm.
        max_z: f64,
        /// The front-left corner, machine coordinates, mm.
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

impl Bed {
    /// Highest reachable nozzle height, mm.
    pub fn max_z(&self) -> f64 {
        match *self {
            Bed::Rectangle { max_z, .. } | Bed::Circle { max_z, .. } => max_z,
        }
    }

    /// Whether machine point `p` is over the bed (XY only).
    pub(crate) fn contains_xy(&self, p: DVec3) -> bool {
        self.contains_xy_within(p, 0.0)
    }

    /// Whether machine point `p` is over the bed grown by `margin` mm on
    /// every side (XY only).
    pub(crate) fn contains_xy_within(&self, p: DVec3, margin: f64) -> bool {
        const EPS: f64 = 1e-9;
        let m = margin + EPS;
        match *self {
            Bed::Rectangle { size, min, .. } => {
                p.x >= min[0] - m
                    && p.y >= min[1] - m
                    && p.x <= min[0] + size[0] + m
                    && p.y <= min[1] + size[1] + m
            }
            Bed::Circle { diameter, .. } => p.truncate().length() <= diameter / 2.0 + m,
        }
    }

    /// The bed's XY extent, machine coordinates: (min, max) corners (a
    /// round bed's bounding square).
    pub(crate) fn extent(&self) -> ([f64; 2], [f64; 2]) {
        match *self {
            Bed::Rectangle { size, min, .. } => (min, [min[0] + size[0], min[1] + size[1]]),
            Bed::Circle { diameter, .. } => {
                let r = diameter / 2.0;
                ([-r, -r], [r, r])
            }
        }
    }

    /// A short description for reports: `220 × 220 × 250 mm`.
    pub fn describe(&self) -> String {
        match *self {
            Bed::Rectangle {
                size,
                max_z,
                min: [0.0, 0.0],
            } => {
                format!("{} × {} × {} mm", size[0], size[1], max_z)
            }
            Bed::Rectangle { size, max_z, min } => format!(
                "{} × {} × {} mm from ({}, {})",
                size[0], size[1], max_z, min[0], min[1]
            ),
            Bed::Circle { diameter, max_z } => format!("round Ø {diameter} × {max_z} mm"),
        }
    }
}

/// Retraction before long travel moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Retraction {
    /// Filament pulled back, mm (0 for none).
    pub length: f64,
    /// Retraction speed, mm/s of filament.
    pub speed: f64,
    /// Travel moves shorter than this are not retracted, mm.
    pub(crate) min_travel: f64,
}

impl Default for Retraction {
    fn default() -> Self {
        Retraction {
            length: 0.0,
            speed: 35.0,
            min_travel: 2.0,
        }
    }
}

/// Where a profile's own start and end G-code may move the head: the bed
/// grown by `margin` in X and Y (makers purge just outside the bed, Prusa's
/// MK3S at Y −3), or on an axis `x`/`y` names the range the head really
/// reaches (Bambu's A1 purges at X −48.2, Prusa's CORE One parks at Y −9);
/// up to `max_z + margin`, down to `-below_bed` (a probe's declared offset;
/// 0: never below the bed). p3dp's own moves stay on the bed whatever this
/// says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Envelope {
    /// Reach beyond the bed's edges and above its height, mm.
    pub(crate) margin: f64,
    /// Reach below z = 0, mm.
    pub(crate) below_bed: f64,
    /// The head's reach along X, machine mm (lowest, highest), in place of
    /// the bed grown by `margin`; it holds the bed.
    pub(crate) x: Option<[f64; 2]>,
    /// The head's reach along Y, as `x`.
    pub(crate) y: Option<[f64; 2]>,
}

impl Envelope {
    /// Largest `margin` a profile may declare, mm: a purge line beside the
    /// bed, never a move metres away.
    pub(crate) const MAX_MARGIN: f64 = 50.0;
    /// Largest `below_bed` a profile may declare, mm.
    pub(crate) const MAX_BELOW_BED: f64 = 5.0;
    /// Farthest a reach `x`/`y` may extend past the bed's edge, mm: a purge
    /// chute or a park beside the bed.
    pub(crate) const MAX_REACH: f64 = 60.0;

    /// The range the head may reach along axis `k` (0: X, 1: Y) of a bed
    /// spanning `lo` to `hi` there.
    pub(crate) fn reach(&self, k: usize, lo: f64, hi: f64) -> [f64; 2] {
        match [self.x, self.y][k] {
            Some(r) => r,
            None => [lo - self.margin, hi + self.margin],
        }
    }
}

impl Default for Envelope {
    fn default() -> Self {
        Envelope {
            margin: 5.0,
            below_bed: 0.0,
            x: None,
            y: None,
        }
    }
}

/// A printer profile: the spec's keys plus the limits p3dp checks against.
#[derive(Clone, Debug, PartialEq)]
pub struct Printer {
    /// Profile name.
    pub name: String,
    /// The model as its maker's software names it (PrusaSlicer's
    /// `printer_model`: `MK4`, `MK3S`…; Bambu's `X1C`…), for start G-code
    /// that checks it and the hosts that read the G-code's metadata; empty
    /// when unknown.
    pub model: String,
    /// The file the profile was read from, as the user named it (`None`
    /// for a built-in one): errors in its G-code name it.
    pub source: Option<String>,
    /// Firmware dialect.
    pub flavor: Flavor,
    /// Printable area.
    pub bed: Bed,
    /// Where recipe (0, 0, 0) lands, in machine coordinates.
    pub origin: [f64; 3],
    /// Nozzle diameter, mm.
    pub nozzle_diameter: f64,
    /// Filament diameter, mm (a material may override it).
    pub filament_diameter: f64,
    /// Absolute or relative E.
    pub(crate) extrusion: Extrusion,
    /// Extruders (or a filament changer's slots) the start and end G-code
    /// know, the length of the slicers' per-extruder values; p3dp prints
    /// with `tool`.
    pub extruders: usize,
    /// The extruder p3dp prints with, 0-based (0): the one the maker's
    /// start G-code selects (Bambu's H2D its main, right-hand one, 1).
    pub tool: usize,
    /// G-code before the print: a template of the slicers' macro language
    /// (`base::slicer_macro`) over the variables of `VARIABLES`
    /// and `gcode_variables`.
    pub start_gcode: String,
    /// G-code after the print, a template over the same variables.
    pub(crate) end_gcode: String,
    /// Values of template variables only a slicer knows (a print preset's
    /// name, a Bambu bed type), by name.
    pub(crate) gcode_variables: BTreeMap<String, Value>,
    /// Where the start and end G-code may move the head.
    pub(crate) envelope: Envelope,
    /// Head speed of travel moves, mm/s.
    pub(crate) travel_speed: f64,
    /// Retraction before long travel moves.
    pub retraction: Retraction,
    /// Retract with the firmware's `G10`/`G11` (its own length and speed,
    /// `M207`/`M208` or Klipper's `[firmware_retraction]`) instead of E moves.
    pub firmware_retraction: bool,
    /// Hottest nozzle the hot end allows, °C.
    pub max_nozzle_temp: f64,
    /// Hottest bed allowed, °C.
    pub max_bed_temp: f64,
    /// Fastest head speed, mm/s.
    pub max_speed: f64,
    /// Hot-end volumetric flow limit, mm³/s.
    pub max_flow: f64,
    /// Runs of extruding strings shorter than this are merged into one move
    /// (Kanada's `draw` does the same near a globe's poles), mm.
    pub(crate) min_string_length: f64,
    /// Fit `G2`/`G3` arcs to runs of strings on a circle or helix (see
    /// `base::geom::arc`); off by default.
    pub arcs: bool,
    /// Largest distance between an arc and the strings it replaces, mm.
    pub arc_tolerance: f64,
    /// Thumbnails to embed in the G-code, as `WxH` (PNG) or `WxH/FORMAT`
    /// (`PNG`, `QOI`, `JPG`) entries, PrusaSlicer's `thumbnails` (see
    /// `machine::size::thumbnails`); none by default.
    pub thumbnails: Vec<String>,
    /// Write `M73` progress (percent done, minutes left) from the planner's
    /// time: on by default for Marlin and Prusa, whose screens show it.
    pub(crate) progress: bool,
    /// Label each part for the host's cancel-object (Klipper's
    /// `EXCLUDE_OBJECT_DEFINE/START/END`); on by default for Klipper.
    pub(crate) object_labels: bool,
    /// Write Prusa's binary G-code (`.bgcode`) when the output's name does
    /// not say (PrusaSlicer's `binary_gcode`); off by default.
    pub(crate) binary_gcode: bool,
    /// The start G-code is the maker's own sequence (an imported preset's):
    /// its nozzle temperatures (flushes, purges, nozzle cleaning hotter than
    /// the print) are held to `max_nozzle_temp`, and the last one, where
    /// the print starts, to the material's limit; off by default.
    pub(crate) maker_temperatures: bool,
    /// Write the firmware's limits of `kinematics` as `M201`, `M203`,
    /// `M204`, `M205` before the start G-code (PrusaSlicer's
    /// `machine_limits_usage = emit_to_gcode`); off by default.
    pub(crate) emit_limits: bool,
    /// The firmware's maximum X and Y accelerations, mm/s² (a slicer's
    /// `machine_max_acceleration_x`/`_y`), written as `M201 X Y` with
    /// `emit_limits`; the head's highest acceleration when absent.
    pub(crate) axis_acceleration: Option<[f64; 2]>,
    /// Pressure (linear) advance written after the start G-code, s (none:
    /// the firmware keeps its own).
    pub(crate) pressure_advance: Option<f64>,
    /// The firmware planner's limits, for the print-time estimate (see
    /// `Kinematics`).
    pub kinematics: super::kinematics::Kinematics,
    /// The print head's geometry for the collision check and the travel
    /// height between parts (see `Head`).
    pub(crate) head: super::head::Head,
    /// Thresholds of the flow, support and planner checks (see
    /// `CheckLimits`).
    pub(crate) checks: super::head::CheckLimits,
}

/// Largest `arc_tolerance`, mm: an arc strays from its strings by up to
/// this, and beyond a nozzle's width it is no longer the path drawn.
pub(crate) const MAX_ARC_TOLERANCE: f64 = 0.5;

impl Printer {
    /// The planner's limits: the profile's `kinematics:` with every default
    /// filled in (Klipper's extrude-only limits from the nozzle and filament).
    pub(crate) fn limits(&self) -> super::kinematics::Limits {
        self.kinematics.limits(
            self.max_speed,
            super::kinematics::extrude_ratio(self.nozzle_diameter, self.filament_diameter),
        )
    }

    /// Checks every value; errors name the key.
    pub(crate) fn validate(&self) -> Result<()> {
        crate::base::safe_text::check("name", &self.name)?;
        let positive = super::head::positive;
        positive("nozzle_diameter", self.nozzle_diameter)?;
        positive("filament_diameter", self.filament_diameter)?;
        positive("travel_speed", self.travel_speed)?;
        positive("bed.max_z", self.bed.max_z())?;
        positive("max_speed", self.max_speed)?;
        positive("max_flow", self.max_flow)?;
        if !(1..=MAX_EXTRUDERS).contains(&self.extruders) {
            return Err(Error::input(
                "extruders",
                format!(
                    "{} is not allowed; expected 1 to {MAX_EXTRUDERS}",
                    self.extruders
                ),
            ));
        }
        if self.tool >= self.extruders {
            return Err(Error::input(
                "tool",
                format!(
                    "{} is not allowed; expected an extruder from 0 to {} (`extruders` is {})",
                    self.tool,
                    self.extruders - 1,
                    self.extruders
                ),
            ));
        }
        positive("arc_tolerance", self.arc_tolerance)?;
        if let Some(k) = self.pressure_advance {
            if k.is_nan() || k < 0.0 {
                return Err(Error::input("pressure_advance", "expected 0 or more"));
            }
            super::limits::at_most(
                "pressure_advance",
                k,
                super::limits::PRESSURE_ADVANCE_MAX,
                "s",
            )?;
        }
        super::limits::at_most("arc_tolerance", self.arc_tolerance, MAX_ARC_TOLERANCE, "mm")?;
        match self.bed {
            Bed::Rectangle { size, .. } => {
                positive("bed.size[0]", size[0])?;
                positive("bed.size[1]", size[1])?;
            }
            Bed::Circle { diameter, .. } => positive("bed.diameter", diameter)?,
        }
        for (k, o) in self.origin.iter().enumerate() {
            if !o.is_finite() {
                return Err(Error::input(
                    format!("origin[{k}]"),
                    "expected a finite number",
                ));
            }
        }
        for (key, t) in [
            ("max_nozzle_temp", self.max_nozzle_temp),
            ("max_bed_temp", self.max_bed_temp),
        ] {
            if !t.is_finite() {
                return Err(Error::input(key, "expected a finite temperature"));
            }
        }
        if self.min_string_length.is_nan() || self.min_string_length < 0.0 {
            return Err(Error::input("min_string_length", "expected a length ≥ 0"));
        }
        let r = &self.retraction;
        if r.length.is_nan() || r.length < 0.0 || r.speed.is_nan() || r.speed <= 0.0 {
            return Err(Error::input(
                "retraction",
                "expected a length ≥ 0 and a speed > 0",
            ));
        }
        self.physical_ranges()?;
        super::size::thumbnails(&self.thumbnails)?;
        self.kinematics.validate()?;
        self.head.validate()?;
        self.checks.validate()?;
        crate::base::safe_text::check("model", &self.model)?;
        self.envelope_ranges()?;
        for (k, a) in self.axis_acceleration.into_iter().flatten().enumerate() {
            let max = super::limits::ACCELERATION_MAX;
            if !(a.is_finite() && a > 0.0 && a <= max) {
                return Err(Error::input(
                    format!("axis_acceleration[{k}]"),
                    format!("{a} mm/s² is not allowed; expected above 0 and at most {max} mm/s²"),
                ));
            }
        }
        for (name, v) in &self.gcode_variables {
            check_variable(name, v)?;
        }
        self.template("start_gcode", &self.start_gcode)?;
        self.template("end_gcode", &self.end_gcode)?;
        Ok(())
    }

    fn envelope_ranges(&self) -> Result<()> {
        let e = &self.envelope;
        let within = |key: &str, v: f64, max: f64| {
            if v.is_finite() && (0.0..=max).contains(&v) {
                Ok(())
            } else {
                Err(Error::input(
                    format!("envelope.{key}"),
                    format!("{v} mm is not allowed; expected 0 to {max} mm"),
                ))
            }
        };
        within("margin", e.margin, Envelope::MAX_MARGIN)?;
        within("below_bed", e.below_bed, Envelope::MAX_BELOW_BED)?;
        let (bmin, bmax) = self.bed.extent();
        for (k, (key, r)) in [("x", e.x), ("y", e.y)].into_iter().enumerate() {
            let Some([lo, hi]) = r else { continue };
            let (b0, b1) = (bmin[k], bmax[k]);
            let m = Envelope::MAX_REACH;
            if !(lo.is_finite()
                && hi.is_finite()
                && lo <= b0
                && hi >= b1
                && lo >= b0 - m
                && hi <= b1 + m)
            {
                return Err(Error::input(
                    format!("envelope.{key}"),
                    format!(
                        "[{lo}, {hi}] mm is not allowed; expected a range holding the bed ({b0} to {b1} mm) and reaching at most {m} mm past it"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The start or end G-code template under `key`, parsed: no character
    /// that breaks a line but `\n`, no syntax error, and no variable
    /// neither p3dp (`VARIABLES`) nor `gcode_variables` gives; errors
    /// name the key and the template's line.
    pub(crate) fn template(&self, key: &str, text: &str) -> Result<Template> {
        let at = |line: usize, message: String| Error::input(format!("{key} line {line}"), message);
        for (k, l) in text.split('\n').enumerate() {
            crate::base::safe_text::check_gcode_line("", l).map_err(|e| at(k + 1, e.message))?;
        }
        let t = Template::parse(text).map_err(|e| at(e.line, e.message))?;
        // the end G-code may read what the start G-code's `global`s set
        let globals = match key {
            "end_gcode" => Template::parse(&self.start_gcode).map_or(Vec::new(), |s| s.globals()),
            _ => Vec::new(),
        };
        for (name, line) in t.variables() {
            if !self.knows(&name) && !globals.contains(&name) {
                return Err(at(
                    line,
                    format!(
                        "unknown variable `{name}`: p3dp does not know it (give it a value under `gcode_variables:` if it is a slicer's setting)"
                    ),
                ));
            }
        }
        Ok(t)
    }

    /// Whether a template may name variable `name` (as itself or, for a
    /// legacy `[name_N]`, as a list `name` indexed): one p3dp gives, one of
    /// `gcode_variables`, or a filament preset's (refused at the build when
    /// the material has none).
    fn knows(&self, name: &str) -> bool {
        let known = |n: &str| {
            gives(n)
                || self.gcode_variables.contains_key(n)
                || super::material::from_filament_preset(n)
        };
        known(name)
            || name
                .rsplit_once('_')
                .is_some_and(|(n, i)| i.parse::<usize>().is_ok() && known(n))
    }

    /// Refuses values outside what a machine can be (see [`crate::machine::limits`]).
    fn physical_ranges(&self) -> Result<()> {
        use crate::machine::limits::*;
        range(
            "nozzle_diameter",
            self.nozzle_diameter,
            NOZZLE_DIAMETER,
            "mm",
        )?;
        range(
            "filament_diameter",
            self.filament_diameter,
            FILAMENT_DIAMETER,
            "mm",
        )?;
        at_most(
            "max_nozzle_temp",
            self.max_nozzle_temp,
            NOZZLE_TEMP_MAX,
            "°C",
        )?;
        at_most("max_bed_temp", self.max_bed_temp, BED_TEMP_MAX, "°C")?;
        at_most("travel_speed", self.travel_speed, SPEED_MAX, "mm/s")?;
        at_most("max_speed", self.max_speed, SPEED_MAX, "mm/s")?;
        at_most("max_flow", self.max_flow, FLOW_MAX, "mm³/s")?;
        at_most(
            "retraction.length",
            self.retraction.length,
            RETRACTION_MAX,
            "mm",
        )?;
        at_most("retraction.speed", self.retraction.speed, SPEED_MAX, "mm/s")?;
        let long = |key: &str, v: f64| at_most(key, v.abs(), MACHINE_LENGTH_MAX, "mm");
        long("retraction.min_travel", self.retraction.min_travel)?;
        long("bed.max_z", self.bed.max_z())?;
        match self.bed {
            Bed::Rectangle { size, min, .. } => {
                long("bed.size[0]", size[0])?;
                long("bed.size[1]", size[1])?;
                long("bed.min[0]", min[0])?;
                long("bed.min[1]", min[1])?;
            }
            Bed::Circle { diameter, .. } => long("bed.diameter", diameter)?,
        }
        for (k, o) in self.origin.iter().enumerate() {
            long(&format!("origin[{k}]"), *o)?;
        }
        long("min_string_length", self.min_string_length)?;
        long("arc_tolerance", self.arc_tolerance)?;
        let k = &self.kinematics;
        if let Some(v) = k.max_velocity {
            at_most("kinematics.max_velocity", v, SPEED_MAX, "mm/s")?;
        }
        for (key, v) in [
            ("kinematics.max_acceleration", Some(k.max_acceleration)),
            ("kinematics.travel_acceleration", k.travel_acceleration),
            ("kinematics.retract_acceleration", k.retract_acceleration),
        ] {
            if let Some(v) = v {
                at_most(key, v, ACCELERATION_MAX, "mm/s²")?;
            }
        }
        if let Some(v) = k.square_corner_velocity {
            at_most("kinematics.square_corner_velocity", v, SPEED_MAX, "mm/s")?;
        }
        if let Some(v) = k.jerk {
            at_most("kinematics.jerk", v, SPEED_MAX, "mm/s")?;
        }
        if let Some(v) = k.junction_deviation {
            long("kinematics.junction_deviation", v)?;
        }
        Ok(())
    }

    /// Recipe coordinates to machine coordinates.
    pub fn to_machine(&self, p: DVec3) -> DVec3 {
        p + DVec3::from_array(self.origin)
    }
}

/// Every variable p3dp gives a start or end G-code template from the
/// profile and the print (the material's are
/// [`super::material::VARIABLES`]), with what it
/// holds (`crate::analyse::frame` computes them from the recipe, the
/// profile and the strings built). Lists, as the slicers hold per-extruder
/// values, have one element per extruder of the profile (`extruders`), the
/// first the one p3dp prints with. p3dp prints strings,
/// not layers: the "layer" values describe the strings honestly (the
/// lowest extruding point's height for `layer_height`, the highest for
/// `max_layer_z`).
pub(crate) const VARIABLES: &[(&str, &str)] = &[
    ("nozzle_temp", "the material's nozzle temperature, °C"),
    ("bed_temp", "the material's bed temperature, °C"),
    ("filament_diameter", "[the filament's diameter], mm"),
    ("nozzle_diameter", "[the nozzle's diameter], mm"),
    ("bed_x", "the bed's width, mm, 3 decimals (0 for a round bed)"),
    ("bed_y", "the bed's depth, mm, 3 decimals (0 for a round bed)"),
    ("max_z", "the highest reachable nozzle height, mm, 3 decimals"),
    ("park_z", "10 mm above the print, at most max_z, mm, 3 decimals"),
    ("first_layer_temperature", "[nozzle temperature], °C"),
    ("temperature", "[nozzle temperature], °C"),
    ("nozzle_temperature_initial_layer", "[nozzle temperature], °C"),
    ("nozzle_temperature", "[nozzle temperature], °C"),
    ("first_layer_bed_temperature", "[bed temperature], °C"),
    ("bed_temperature", "[bed temperature], °C"),
    ("bed_temperature_initial_layer", "[bed temperature], °C"),
    ("bed_temperature_initial_layer_single", "the bed temperature, °C"),
    ("hot_plate_temp", "[bed temperature], °C (every plate type)"),
    ("hot_plate_temp_initial_layer", "[bed temperature], °C"),
    ("cool_plate_temp", "[bed temperature], °C"),
    ("cool_plate_temp_initial_layer", "[bed temperature], °C"),
    ("eng_plate_temp", "[bed temperature], °C"),
    ("eng_plate_temp_initial_layer", "[bed temperature], °C"),
    ("textured_plate_temp", "[bed temperature], °C"),
    ("textured_plate_temp_initial_layer", "[bed temperature], °C"),
    ("filament_type", "[the filament preset's filament_type, else the material's name in capitals]: PLA, ABS, PETG, …"),
    ("filament_settings_id", "[the filament preset's name, else the material's]"),
    ("printer_settings_id", "the profile's name"),
    ("printer_preset", "the profile's name"),
    ("printer_model", "the profile's `model`"),
    ("initial_tool", "0: p3dp prints with the first tool, the one the maker's start G-code selects"),
    ("initial_extruder", "0"),
    ("current_extruder", "0"),
    ("initial_no_support_extruder", "0"),
    ("initial_no_support_tool", "0"),
    ("num_extruders", "the profile's `extruders`"),
    ("is_extruder_used", "[true for the profile's `tool`, false for the others]: 255 long at least, as PrusaSlicer makes it for templates written for more tools"),
    ("filament_map", "[the profile's `tool` + 1]: the extruder (1-based) of the print's one filament"),
    ("first_filaments", "[0 for every extruder]: the print's one filament"),
    ("first_non_support_filaments", "[0 for every extruder]"),
    ("initial_filament_id", "0: the print's one filament"),
    ("initial_no_support_filament_id", "0"),
    ("initial_nozzle_id", "0"),
    ("initial_no_support_hotend", "0: the first hotend (Bambu's hotend rack)"),
    ("first_non_support_hotend", "0"),
    ("current_hotend", "0"),
    ("nozzle_diameter_at_nozzle_id", "[the nozzle's diameter, for every nozzle], mm"),
    ("has_wipe_tower", "false"),
    ("has_single_extruder_multi_material_priming", "false"),
    ("total_toolchanges", "0"),
    ("e_retracted", "[filament retracted where the template runs]: 0 at the start; at the end, the retraction length when the print ends on a retracted travel, mm. The start G-code may assign it (`{e_retracted[t] = …}`), as PrusaSlicer's may: p3dp then unretracts that much before the print"),
    ("e_restart_extra", "[0 for every extruder]: filament pushed beyond the retraction at the next unretraction, mm; assignable as e_retracted"),
    ("zhop", "0: the head is not lifted where the template runs, mm"),
    ("first_layer_height", "the lowest extruding point's height above the bed, mm"),
    ("initial_layer_print_height", "the same, mm"),
    ("layer_height", "the same: the one layer height every print has, mm"),
    ("layer_z", "start: first_layer_height; end: the last extruding point's height, mm"),
    ("max_layer_z", "the highest extruding point's height, mm"),
    ("max_print_z", "the same, mm"),
    ("total_layer_count", "max_layer_z over layer_height, rounded up: the layers a slicer would cut the print's height into"),
    ("layer_num", "start: 0; end: total_layer_count − 1"),
    ("first_layer_print_min", "[x, y]: the least corner of the extruding strings below twice first_layer_height, machine mm"),
    ("first_layer_print_max", "[x, y]: their greatest corner, machine mm"),
    ("first_layer_print_size", "[width, depth] of that extent, mm"),
    ("first_layer_center_no_wipe_tower", "[x, y]: the centre of that extent, machine mm"),
    ("adaptive_bed_mesh_min", "[x, y]: OrcaSlicer's adaptive mesh: first_layer_print_min less the profile's adaptive_bed_mesh_margin (0), within its bed_mesh_min/bed_mesh_max, machine mm"),
    ("adaptive_bed_mesh_max", "[x, y]: first_layer_print_max plus the margin, within the same limits, machine mm"),
    ("bed_mesh_probe_count", "[x, y]: per axis, the mesh's size over the profile's bed_mesh_probe_distance (50 mm) rounded up, plus one, at least 3"),
    ("bed_mesh_algo", "`lagrange` below 4 points an axis, else `bicubic`"),
    ("print_bed_min", "[x, y]: the bed's least corner, machine mm"),
    ("print_bed_max", "[x, y]: the bed's greatest corner, machine mm"),
    ("print_bed_size", "[width, depth] of the bed, mm"),
    ("max_print_height", "the highest reachable nozzle height, mm"),
    ("printable_height", "the same, mm"),
    ("z_offset", "origin z: where recipe z = 0 lands, mm"),
    ("travel_speed", "the profile's travel speed, mm/s"),
    ("retract_length", "[retraction length], mm"),
    ("retraction_length", "[retraction length], mm"),
    ("retract_speed", "[retraction speed], mm/s"),
    ("retraction_speed", "[retraction speed], mm/s"),
    ("retract_lift", "[0]: p3dp lifts for travel between parts, not on retraction"),
    ("z_hop", "[0]"),
    ("extrusion_width", "the first extruding string's cross-section over layer_height, mm"),
    ("line_width", "the same, mm"),
    ("external_perimeter_extrusion_width", "the same, mm"),
    ("initial_layer_speed", "the first extruding string's speed, mm/s"),
    ("external_perimeter_speed", "the same, mm/s"),
    ("outer_wall_speed", "the same, mm/s"),
    ("outer_wall_volumetric_speed", "the highest volumetric flow (cross-section × speed) of the print's extruding strings, mm³/s"),
    ("default_acceleration", "the acceleration of printing moves, at which p3dp prints every string, mm/s²"),
    ("outer_wall_acceleration", "the same, mm/s²"),
    ("initial_layer_acceleration", "the same, mm/s²"),
    ("machine_max_acceleration_extruding", "[acceleration of printing moves], mm/s²"),
    ("machine_max_acceleration_travel", "[acceleration of travel moves], mm/s²"),
    ("machine_max_acceleration_retracting", "[acceleration of retractions], mm/s²"),
    ("machine_max_feedrate_x", "[highest head speed], mm/s"),
    ("machine_max_feedrate_y", "[highest head speed], mm/s"),
    ("machine_max_feedrate_z", "[highest Z speed, or the head's], mm/s"),
    ("input_filename_base", "the recipe's name"),
    ("input_filename", "the recipe's name"),
];

/// Whether p3dp gives a start or end G-code template the variable `name`
/// (or, for a legacy `[name_N]`, the list `name`): one of [`VARIABLES`] or
/// of the material's ([`super::material::VARIABLES`]).
pub(crate) fn gives(name: &str) -> bool {
    let listed = |n: &str| {
        VARIABLES.iter().any(|(v, _)| *v == n)
            || super::material::VARIABLES.iter().any(|(v, _)| *v == n)
    };
    listed(name)
        || name
            .rsplit_once('_')
            .is_some_and(|(b, i)| i.parse::<usize>().is_ok() && listed(b))
}

/// Most extruders (or filament slots) a profile may declare.
pub(crate) const MAX_EXTRUDERS: usize = 16;

/// Refuses a `gcode_variables` value that could break a G-code line or is
/// no finite number.
fn check_variable(name: &str, v: &Value) -> Result<()> {
    let key = format!("gcode_variables.{name}");
    match v {
        Value::Str(s) | Value::Shown(_, s) => crate::base::safe_text::check(&key, s),
        Value::Float(f) if !f.is_finite() => Err(Error::input(key, "expected a finite number")),
        Value::List(items) => items.iter().try_for_each(|i| check_variable(name, i)),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generic_profile_loads_and_maps_the_centre() {
        let p = crate::recipe::profile::built_in("generic-220").unwrap();
        p.validate().unwrap();
        assert_eq!(p.to_machine(DVec3::ZERO), DVec3::new(110.0, 110.0, 0.0));
        assert!(p.bed.contains_xy(DVec3::new(220.0, 0.0, 0.0)));
        assert!(!p.bed.contains_xy(DVec3::new(220.5, 0.0, 0.0)));
    }

    #[test]
    fn templates_refuse_unknown_variables_and_line_breaks() {
        let mut p = crate::recipe::profile::built_in("generic-220").unwrap();
        assert!(p
            .template("k", "M104 S{nozzle_temp}\nM140 S[bed_temp]")
            .is_ok());
        let e = p.template("start_gcode", "G28\nM104 S{hot}").unwrap_err();
        assert_eq!(e.place.as_deref(), Some("start_gcode line 2"));
        assert!(e.message.contains("unknown variable `hot`"), "{e}");
        p.gcode_variables.insert("hot".into(), Value::Int(200));
        assert!(p.template("start_gcode", "G28\nM104 S{hot}").is_ok());
        for bad in ["G28\u{2028}M104 S999", "G28\r\nG1", "G28\u{85}"] {
            let e = p.template("end_gcode", bad).unwrap_err();
            assert!(e.message.contains("line break"), "{e}");
        }
    }
}
