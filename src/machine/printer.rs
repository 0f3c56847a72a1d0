//! A printer profile: bed, origin, nozzle, G-code templates and the limits
//! p3dp checks against (data only; [`crate::recipe::profile`] loads it).

use std::collections::BTreeMap;

use glam::DVec3;

use crate::base::error::{Error, Result};

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
    /// the pause, `M601` (see [`crate::flavor`]).
    Prusa,
}

/// Absolute (M82) or relative (M83) E values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Extrusion {
    /// M82: E is the total filament fed so far.
    #[default]
    Absolute,
    /// M83: E is the filament fed by this move.
    Relative,
}

/// The printable area. Rectangle beds span machine X in [0, width] and Y in
/// [0, depth]; round (delta) beds are centred on machine (0, 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bed {
    /// A rectangular bed.
    Rectangle {
        /// Width and depth, mm.
        size: [f64; 2],
        /// Highest reachable nozzle height, mm.
        max_z: f64,
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
    pub fn contains_xy(&self, p: DVec3) -> bool {
        const EPS: f64 = 1e-9;
        match *self {
            Bed::Rectangle { size, .. } => {
                p.x >= -EPS && p.y >= -EPS && p.x <= size[0] + EPS && p.y <= size[1] + EPS
            }
            Bed::Circle { diameter, .. } => p.truncate().length() <= diameter / 2.0 + EPS,
        }
    }

    /// A short description for reports: `220 × 220 × 250 mm`.
    pub fn describe(&self) -> String {
        match *self {
            Bed::Rectangle { size, max_z } => format!("{} × {} × {} mm", size[0], size[1], max_z),
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
    pub min_travel: f64,
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

/// A printer profile: the spec's keys plus the limits p3dp checks against.
#[derive(Clone, Debug, PartialEq)]
pub struct Printer {
    /// Profile name.
    pub name: String,
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
    pub extrusion: Extrusion,
    /// G-code before the print; `{nozzle_temp}`, `{bed_temp}` and the other
    /// placeholders of [`Printer::fill`] are filled in.
    pub start_gcode: String,
    /// G-code after the print, with the same placeholders.
    pub end_gcode: String,
    /// Head speed of travel moves, mm/s.
    pub travel_speed: f64,
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
    pub min_string_length: f64,
    /// Fit `G2`/`G3` arcs to runs of strings on a circle or helix (see
    /// [`crate::base::geom::arc`]); off by default.
    pub arcs: bool,
    /// Largest distance between an arc and the strings it replaces, mm.
    pub arc_tolerance: f64,
    /// PNG thumbnails to embed in the G-code, as `WxH` sizes (PrusaSlicer's
    /// `; thumbnail begin` blocks); none by default.
    pub thumbnails: Vec<String>,
    /// The firmware planner's limits, for the print-time estimate (see
    /// [`super::Kinematics`]).
    pub kinematics: super::kinematics::Kinematics,
    /// The print head's geometry for the collision check and the travel
    /// height between parts (see [`super::Head`]).
    pub head: super::head::Head,
    /// Thresholds of the flow, support and planner checks (see
    /// [`super::CheckLimits`]).
    pub checks: super::head::CheckLimits,
}

/// Largest `arc_tolerance`, mm: an arc strays from its strings by up to
/// this, and beyond a nozzle's width it is no longer the path drawn.
pub const MAX_ARC_TOLERANCE: f64 = 0.5;

impl Printer {
    /// The planner's limits: the profile's `kinematics:` with every default
    /// filled in (Klipper's extrude-only limits from the nozzle and filament).
    pub fn limits(&self) -> super::kinematics::Limits {
        self.kinematics.limits(
            self.max_speed,
            super::kinematics::extrude_ratio(self.nozzle_diameter, self.filament_diameter),
        )
    }

    /// Checks every value; errors name the key.
    pub fn validate(&self) -> Result<()> {
        crate::base::safe_text::check("name", &self.name)?;
        let positive = super::head::positive;
        positive("nozzle_diameter", self.nozzle_diameter)?;
        positive("filament_diameter", self.filament_diameter)?;
        positive("travel_speed", self.travel_speed)?;
        positive("bed.max_z", self.bed.max_z())?;
        positive("max_speed", self.max_speed)?;
        positive("max_flow", self.max_flow)?;
        positive("arc_tolerance", self.arc_tolerance)?;
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
        super::size::sizes(&self.thumbnails)?;
        self.kinematics.validate()?;
        self.head.validate()?;
        self.checks.validate()?;
        self.fill("start_gcode", &self.start_gcode, &BTreeMap::new())?;
        self.fill("end_gcode", &self.end_gcode, &BTreeMap::new())?;
        Ok(())
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
            Bed::Rectangle { size, .. } => {
                long("bed.size[0]", size[0])?;
                long("bed.size[1]", size[1])?;
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
        if let Some(v) = k.junction_deviation {
            long("kinematics.junction_deviation", v)?;
        }
        Ok(())
    }

    /// Recipe coordinates to machine coordinates.
    pub fn to_machine(&self, p: DVec3) -> DVec3 {
        p + DVec3::from_array(self.origin)
    }

    /// Fills `{name}` placeholders of a G-code template with `values`; an
    /// unknown placeholder is an error naming `key`.
    pub fn fill(
        &self,
        key: &str,
        template: &str,
        values: &BTreeMap<&str, String>,
    ) -> Result<String> {
        let mut out = String::with_capacity(template.len());
        let mut rest = template;
        while let Some(open) = rest.find('{') {
            out.push_str(&rest[..open]);
            let after = &rest[open + 1..];
            let Some(close) = after.find('}') else {
                return Err(Error::input(
                    key,
                    "a `{` is never closed; expected `{placeholder}`",
                ));
            };
            let name = &after[..close];
            match values.get(name) {
                Some(v) => out.push_str(v),
                None if values.is_empty() && PLACEHOLDERS.contains(&name) => {}
                None => {
                    return Err(Error::input(
                        key,
                        format!(
                            "unknown placeholder `{{{name}}}`; expected one of {}",
                            PLACEHOLDERS.map(|p| format!("{{{p}}}")).join(", ")
                        ),
                    ))
                }
            }
            rest = &after[close + 1..];
        }
        out.push_str(rest);
        Ok(out)
    }
}

/// Placeholders a start or end G-code template may use.
pub const PLACEHOLDERS: [&str; 8] = [
    "nozzle_temp",
    "bed_temp",
    "filament_diameter",
    "nozzle_diameter",
    "bed_x",
    "bed_y",
    "max_z",
    "park_z",
];

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
    fn templates_fill_and_refuse_unknown_placeholders() {
        let p = crate::recipe::profile::built_in("generic-220").unwrap();
        let mut v = BTreeMap::new();
        v.insert("nozzle_temp", "210".to_string());
        assert_eq!(p.fill("k", "M104 S{nozzle_temp}", &v).unwrap(), "M104 S210");
        let e = p.fill("start_gcode", "M104 S{hot}", &v).unwrap_err();
        assert!(e.to_string().contains("unknown placeholder `{hot}`"), "{e}");
    }
}
