//! The printer-profile keys the checks read: `head:` (the geometry of the
//! print head, for the collision check and the travel height between parts)
//! and `checks:` (thresholds of the flow, support and planner checks).
//!
//! ```yaml
//! head: { cone_angle: 40, cone_height: 3, tip_diameter: 1, box: [-25, 25, -25, 25], clearance: 1,
//!         gantry: { height: 25, y: [-30, 35] } }
//! checks: { cross_section_max: 2.5, max_bridge: 10, min_move_time: 0.005 }
//! ```

use crate::base::error::{Error, Result};

/// The print head as the collision check sees it (ExtruderTurtle's Fig. 13):
/// a cone round the nozzle from its tip up to `cone_height`, and above that a
/// box (heater block, fan duct, carriage) reaching `box` round the nozzle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Head {
    /// Half-angle of the nozzle's cone from the vertical axis, degrees (0 a
    /// needle, 90 a flat plate at the tip).
    pub(crate) cone_angle: f64,
    /// Height of the cone above the nozzle tip, mm; the box starts there.
    pub(crate) cone_height: f64,
    /// Diameter of the flat face at the nozzle's tip, mm.
    pub(crate) tip_diameter: f64,
    /// The box round the nozzle, `[x_min, x_max, y_min, y_max]` in mm relative
    /// to the nozzle (machine axes), from `cone_height` above the tip upwards.
    pub(crate) head_box: [f64; 4],
    /// Travel between parts rises this far above the highest filament printed
    /// so far (within max z), mm.
    pub(crate) clearance: f64,
    /// What the head hangs from, when the profile says: from this height
    /// above the tip, across the whole bed in x (see [`Gantry`]).
    pub(crate) gantry: Option<Gantry>,
}

/// The gantry (or the x axis' arm, a bed-slinger's): from `height` mm above
/// the nozzle's tip upwards, it spans the whole bed in x and `y` round the
/// nozzle in y. A print taller than that, beside the nozzle in x, meets it:
/// printed one after another, objects taller than `height` over the next
/// one's first layer must lie outside its band (the makers' slicers:
/// Bambu Studio's `extruder_clearance_height_to_rod`, PrusaSlicer's
/// `extruder_clearance_height`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Gantry {
    /// Height of its lowest edge above the nozzle's tip, mm.
    pub(crate) height: f64,
    /// Its band in y round the nozzle, `[y_min, y_max]`, mm (machine axes).
    pub(crate) y: [f64; 2],
}

impl Default for Head {
    fn default() -> Self {
        Head {
            cone_angle: 30.0,
            cone_height: 5.0,
            tip_diameter: 1.0,
            head_box: [-10.0, 10.0, -10.0, 10.0],
            clearance: 1.0,
            gantry: None,
        }
    }
}

/// Thresholds of the flow, support and planner checks (printer key `checks:`).
/// A profile's `checks:` deserialises straight into it (`recipe::schema`'s
/// `RawPrinter`), each absent key [`CheckLimits::default`]'s.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields, default, expecting = "struct CheckLimits")]
pub(crate) struct CheckLimits {
    /// `over-extrusion` warning above this × nozzle² of cross-section.
    pub(crate) cross_section_max: f64,
    /// `over-extrusion` error above this × nozzle².
    pub(crate) cross_section_hard_max: f64,
    /// `thin-string` warning below this × nozzle².
    pub(crate) cross_section_min: f64,
    /// `thin-string` error below this × nozzle².
    pub(crate) cross_section_hard_min: f64,
    /// `flow` is an error above this × `max_flow`.
    pub(crate) flow_hard_max: f64,
    /// Longest bridge reported as a note, mm; longer ones are warnings.
    pub(crate) max_bridge: f64,
    /// Strings touch when their centre lines are closer than this × the mean
    /// of their widths (a string's width: the round bead of its cross-section,
    /// at least the nozzle); the bed holds a string this × its width high.
    pub(crate) support_tolerance: f64,
    /// Shortest move the firmware keeps up with, s: about the time it takes
    /// to receive and plan one G-code line (5 ms on an 8-bit Marlin fed over
    /// USB). Runs of shorter moves drain the planner's buffer, and the
    /// firmware then stretches moves towards `kinematics.min_segment_time`.
    pub(crate) min_move_time: f64,
    /// Moves the planner buffers: shorter runs of short moves are absorbed.
    pub(crate) planner_buffer: u32,
    /// A `first-layer` warning where the nozzle lays filament closer to the
    /// bed than this × the nozzle's diameter.
    pub(crate) first_layer_min: f64,
    /// `small-contact`: bed contact a part needs per mm of its height, mm²/mm.
    pub(crate) min_contact_per_height: f64,
    /// `small-contact`: bed contact a part needs per gram of its filament, mm²/g.
    pub(crate) min_contact_per_gram: f64,
}

impl Default for CheckLimits {
    fn default() -> Self {
        CheckLimits {
            cross_section_max: 2.5,
            cross_section_hard_max: 5.0,
            cross_section_min: 0.1,
            cross_section_hard_min: 0.02,
            flow_hard_max: 1.5,
            max_bridge: 10.0,
            support_tolerance: 1.5,
            min_move_time: 0.005,
            planner_buffer: 16,
            first_layer_min: 0.2,
            min_contact_per_height: 0.4,
            min_contact_per_gram: 0.1,
        }
    }
}

/// `Ok` for a finite number > 0, else an input error naming `key`.
pub(crate) fn positive(key: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::input(
            key,
            format!("{v} is not allowed; expected a number > 0"),
        ))
    }
}

impl Head {
    /// Checks the keys (a printer profile's `head:`).
    pub(crate) fn validate(&self) -> Result<()> {
        if !(self.cone_angle.is_finite() && (0.0..90.0).contains(&self.cone_angle)) {
            return Err(Error::input(
                "head.cone_angle",
                format!(
                    "{} is not allowed; expected an angle from 0 to below 90 degrees",
                    self.cone_angle
                ),
            ));
        }
        positive("head.cone_height", self.cone_height)?;
        positive("head.tip_diameter", self.tip_diameter)?;
        let b = self.head_box;
        if !b.iter().all(|v| v.is_finite()) || b[0] > 0.0 || b[1] < 0.0 || b[2] > 0.0 || b[3] < 0.0
        {
            return Err(Error::input(
                "head.box",
                "expected [x_min, x_max, y_min, y_max] round the nozzle: x_min ≤ 0 ≤ x_max, y_min ≤ 0 ≤ y_max",
            ));
        }
        if !(self.clearance.is_finite() && self.clearance >= 0.0) {
            return Err(Error::input("head.clearance", "expected a length ≥ 0"));
        }
        if let Some(g) = self.gantry {
            positive("head.gantry.height", g.height)?;
            if !g.y.iter().all(|v| v.is_finite()) || g.y[0] > 0.0 || g.y[1] < 0.0 {
                return Err(Error::input(
                    "head.gantry.y",
                    "expected [y_min, y_max] round the nozzle: y_min ≤ 0 ≤ y_max",
                ));
            }
        }
        Ok(())
    }

    /// tan of the cone's half-angle.
    pub(crate) fn tan(&self) -> f64 {
        libm::tan(self.cone_angle.to_radians())
    }

    /// Radius of the cone at its top, mm.
    pub(crate) fn top_radius(&self) -> f64 {
        self.tip_diameter / 2.0 + self.cone_height * self.tan()
    }

    /// Where the head reaches round the nozzle, `[x_min, x_max, y_min,
    /// y_max]`: its box, and the cone's top where it is wider.
    pub(crate) fn reach(&self) -> [f64; 4] {
        let r = self.top_radius();
        let b = self.head_box;
        [b[0].min(-r), b[1].max(r), b[2].min(-r), b[3].max(r)]
    }
}

impl CheckLimits {
    /// Checks the keys (a printer profile's `checks:`).
    pub(crate) fn validate(&self) -> Result<()> {
        for (k, v) in [
            ("checks.cross_section_max", self.cross_section_max),
            ("checks.cross_section_hard_max", self.cross_section_hard_max),
            ("checks.cross_section_min", self.cross_section_min),
            ("checks.cross_section_hard_min", self.cross_section_hard_min),
            ("checks.flow_hard_max", self.flow_hard_max),
            ("checks.max_bridge", self.max_bridge),
            ("checks.support_tolerance", self.support_tolerance),
            ("checks.min_move_time", self.min_move_time),
            ("checks.first_layer_min", self.first_layer_min),
            ("checks.min_contact_per_height", self.min_contact_per_height),
            ("checks.min_contact_per_gram", self.min_contact_per_gram),
        ] {
            positive(k, v)?;
        }
        if self.planner_buffer == 0 {
            return Err(Error::input(
                "checks.planner_buffer",
                "expected a whole number ≥ 1",
            ));
        }
        Ok(())
    }
}
