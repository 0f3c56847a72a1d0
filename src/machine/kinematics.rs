//! A printer profile's `kinematics:`: the limits the firmware's planner works
//! with, and those limits with every default filled in.

use serde::Serialize;

use crate::base::error::{Error, Result};

/// Marlin's default junction deviation, mm (`JUNCTION_DEVIATION_MM`).
pub(crate) const MARLIN_JUNCTION_DEVIATION: f64 = 0.013;
/// Marlin's default minimum segment time, s (`DEFAULT_MINSEGMENTTIME` 20000 µs).
pub(crate) const MARLIN_MIN_SEGMENT_TIME: f64 = 0.02;
/// Klipper's default `minimum_cruise_ratio`.
pub(crate) const KLIPPER_MINIMUM_CRUISE_RATIO: f64 = 0.5;
/// Klipper's default `instantaneous_corner_velocity` of `[extruder]`, mm/s.
pub(crate) const KLIPPER_INSTANTANEOUS_CORNER_VELOCITY: f64 = 1.0;
/// Klipper's default `max_extrude_only_distance` of `[extruder]`, mm of filament.
pub(crate) const KLIPPER_MAX_EXTRUDE_ONLY_DISTANCE: f64 = 50.0;
/// Klipper's default `max_extrude_cross_section`, × nozzle diameter².
pub(crate) const KLIPPER_CROSS_SECTION_FACTOR: f64 = 4.0;
/// Marlin's default `BLOCK_BUFFER_SIZE` (moves).
pub(crate) const MARLIN_BLOCK_BUFFER_SIZE: u32 = 16;
/// Assumed rate at which Marlin reads, parses and plans G-code lines from SD
/// (lines/s): about 2 ms a line on an 8-bit board; an assumption, not a measurement.
pub(crate) const MARLIN_COMMAND_RATE: f64 = 500.0;

/// A printer profile's `kinematics:` block: the limits the firmware's planner
/// works with. Give `junction_deviation` (Marlin) or `square_corner_velocity`
/// (Klipper), not both; with neither, Marlin's 0.013 mm.
#[derive(Clone, Debug, PartialEq)]
pub struct Kinematics {
    /// Highest head speed, mm/s; the profile's `max_speed` when absent.
    pub(crate) max_velocity: Option<f64>,
    /// Acceleration of printing moves, mm/s² (Marlin's `M204 P`, Klipper's `max_accel`).
    pub max_acceleration: f64,
    /// Acceleration of travel moves, mm/s² (Marlin's `M204 T`); `max_acceleration` when absent.
    pub travel_acceleration: Option<f64>,
    /// Acceleration of E-only moves (retractions), mm/s² of filament
    /// (Marlin's `M204 R`); `max_acceleration` when absent.
    pub(crate) retract_acceleration: Option<f64>,
    /// Marlin's junction deviation, mm (`M205 J`).
    pub(crate) junction_deviation: Option<f64>,
    /// Marlin's classic jerk of X and Y, mm/s (`M205 X`, a slicer's
    /// `machine_max_jerk_x`): without `junction_deviation`, the planner
    /// works with Marlin's own conversion of it, 0.4·jerk²/max_acceleration
    /// (Marlin's `JUNCTION_DEVIATION` notes in Configuration_adv.h).
    pub jerk: Option<f64>,
    /// Klipper's square-corner velocity: the speed of a 90° corner, mm/s.
    pub square_corner_velocity: Option<f64>,
    /// Shortest time a move may take, s (Marlin's `M205 B`, in s here); 0.02
    /// with junction deviation, 0 with square-corner velocity (Klipper has none).
    pub(crate) min_segment_time: Option<f64>,
    /// Klipper's `minimum_cruise_ratio`: the share of a move that must cruise;
    /// 0.5 with square-corner velocity, 0 with junction deviation (Marlin has none).
    pub(crate) minimum_cruise_ratio: Option<f64>,
    /// Highest speed of the Z axis, mm/s (Marlin's `M203 Z`, Klipper's
    /// `max_z_velocity`); none when absent.
    pub(crate) max_z_speed: Option<f64>,
    /// Highest acceleration of the Z axis, mm/s² (Marlin's `M201 Z`,
    /// Klipper's `max_z_accel`); none when absent.
    pub(crate) max_z_acceleration: Option<f64>,
    /// Klipper's `[extruder] instantaneous_corner_velocity`, mm/s of filament:
    /// the largest instant change of E speed at a junction; 1 with
    /// square-corner velocity, none with junction deviation.
    pub(crate) instantaneous_corner_velocity: Option<f64>,
    /// Klipper's `[extruder] max_extrude_only_velocity`, mm/s of filament;
    /// Klipper's default with square-corner velocity, none with junction deviation.
    pub(crate) max_extrude_only_velocity: Option<f64>,
    /// Klipper's `[extruder] max_extrude_only_accel`, mm/s² of filament;
    /// Klipper's default with square-corner velocity, none with junction deviation.
    pub(crate) max_extrude_only_accel: Option<f64>,
    /// Klipper's `[extruder] max_extrude_cross_section`, mm²: the largest
    /// cross-section of a move Klipper runs (4 × nozzle² when absent); a
    /// Klipper printer refuses a move past it (the `klipper-extrusion` check).
    pub(crate) max_extrude_cross_section: Option<f64>,
    /// Klipper's `[extruder] max_extrude_only_distance`, mm of filament: the
    /// longest extrude-only move Klipper runs (50 when absent).
    pub(crate) max_extrude_only_distance: Option<f64>,
    /// Hold every move to at least `min_segment_time` (the old, pessimistic
    /// model) instead of Marlin's buffer-draining slowdown; off by default.
    pub(crate) min_segment_time_floor: bool,
    /// Marlin's `BLOCK_BUFFER_SIZE`, moves (16 by default).
    pub(crate) block_buffer_size: Option<u32>,
    /// Lines per second the firmware reads, parses and plans from SD (500 by
    /// default, an assumption): what refills Marlin's buffer.
    pub(crate) command_rate: Option<f64>,
}

impl Default for Kinematics {
    fn default() -> Self {
        Kinematics {
            max_velocity: None,
            max_acceleration: 1000.0,
            travel_acceleration: None,
            retract_acceleration: None,
            junction_deviation: None,
            jerk: None,
            square_corner_velocity: None,
            min_segment_time: None,
            minimum_cruise_ratio: None,
            max_z_speed: None,
            max_z_acceleration: None,
            instantaneous_corner_velocity: None,
            max_extrude_only_velocity: None,
            max_extrude_only_accel: None,
            max_extrude_cross_section: None,
            max_extrude_only_distance: None,
            min_segment_time_floor: false,
            block_buffer_size: None,
            command_rate: None,
        }
    }
}

/// Largest `min_segment_time`, s (1e300 made every estimate 0 s).
pub(crate) const MAX_MIN_SEGMENT_TIME: f64 = 1.0;

impl Kinematics {
    /// Checks the values; errors name the key under `kinematics.`.
    pub(crate) fn validate(&self) -> Result<()> {
        let check = |key: &str, v: Option<f64>, zero_ok: bool| -> Result<()> {
            match v {
                Some(v) if !v.is_finite() || v < 0.0 || (v == 0.0 && !zero_ok) => {
                    Err(Error::input(
                        format!("kinematics.{key}"),
                        format!(
                            "{v} is not allowed; expected a number {}",
                            if zero_ok { "≥ 0" } else { "> 0" }
                        ),
                    ))
                }
                _ => Ok(()),
            }
        };
        check("max_velocity", self.max_velocity, false)?;
        check("max_acceleration", Some(self.max_acceleration), false)?;
        check("travel_acceleration", self.travel_acceleration, false)?;
        check("retract_acceleration", self.retract_acceleration, false)?;
        check("junction_deviation", self.junction_deviation, true)?;
        check("jerk", self.jerk, true)?;
        check("square_corner_velocity", self.square_corner_velocity, true)?;
        check("min_segment_time", self.min_segment_time, true)?;
        if let Some(t) = self.min_segment_time {
            // Marlin's MIN_SEGMENT_TIME is 20 ms: a second is already no planner
            super::limits::at_most("kinematics.min_segment_time", t, MAX_MIN_SEGMENT_TIME, "s")?;
        }
        check("minimum_cruise_ratio", self.minimum_cruise_ratio, true)?;
        check("max_z_speed", self.max_z_speed, false)?;
        check("max_z_acceleration", self.max_z_acceleration, false)?;
        check(
            "instantaneous_corner_velocity",
            self.instantaneous_corner_velocity,
            true,
        )?;
        check(
            "max_extrude_only_velocity",
            self.max_extrude_only_velocity,
            false,
        )?;
        check("max_extrude_only_accel", self.max_extrude_only_accel, false)?;
        check(
            "max_extrude_cross_section",
            self.max_extrude_cross_section,
            false,
        )?;
        check(
            "max_extrude_only_distance",
            self.max_extrude_only_distance,
            true,
        )?;
        check("command_rate", self.command_rate, false)?;
        if self.block_buffer_size.is_some_and(|n| n < 2) {
            return Err(Error::input(
                "kinematics.block_buffer_size",
                "expected at least 2 moves",
            ));
        }
        if self.minimum_cruise_ratio.is_some_and(|r| r >= 1.0) {
            return Err(Error::input(
                "kinematics.minimum_cruise_ratio",
                "expected a ratio in [0, 1)",
            ));
        }
        let junctions = [
            self.junction_deviation.is_some(),
            self.jerk.is_some(),
            self.square_corner_velocity.is_some(),
        ];
        if junctions.iter().filter(|&&b| b).count() > 1 {
            return Err(Error::input(
                "kinematics",
                "give one of `junction_deviation` or `jerk` (Marlin) and `square_corner_velocity` (Klipper)",
            ));
        }
        Ok(())
    }

    /// The limits with every default filled in; `max_speed` is the profile's,
    /// `extrude_ratio` Klipper's `max_extrude_cross_section` over the
    /// filament's area (4·nozzle² / area by default, see [`extrude_ratio`]).
    pub(crate) fn limits(&self, max_speed: f64, extrude_ratio: f64) -> Limits {
        let klipper = self.square_corner_velocity.is_some();
        let accel = self.max_acceleration;
        let max_velocity = self.max_velocity.unwrap_or(max_speed);
        // Klipper config reference, [extruder]: max_extrude_only_velocity and
        // max_extrude_only_accel default to "the limit an XY printing move
        // with a cross section of 4.0·nozzle_diameter² would have"
        // (extruder.py: max_velocity·ratio and max_accel·ratio, ratio =
        // max_extrude_cross_section / filament area)
        let klipper_only = |given: Option<f64>, default: f64| given.or(klipper.then_some(default));
        Limits {
            max_velocity,
            max_acceleration: accel,
            travel_acceleration: self.travel_acceleration.unwrap_or(accel),
            retract_acceleration: self.retract_acceleration.unwrap_or(accel),
            junction_deviation: if klipper {
                None
            } else {
                Some(
                    self.junction_deviation
                        .or(self.jerk.map(|j| 0.4 * j * j / accel))
                        .unwrap_or(MARLIN_JUNCTION_DEVIATION),
                )
            },
            square_corner_velocity: self.square_corner_velocity,
            min_segment_time: self.min_segment_time.unwrap_or(if klipper {
                0.0
            } else {
                MARLIN_MIN_SEGMENT_TIME
            }),
            minimum_cruise_ratio: self.minimum_cruise_ratio.unwrap_or(if klipper {
                KLIPPER_MINIMUM_CRUISE_RATIO
            } else {
                0.0
            }),
            max_z_velocity: self.max_z_speed,
            max_z_acceleration: self.max_z_acceleration,
            instantaneous_corner_velocity: klipper_only(
                self.instantaneous_corner_velocity,
                KLIPPER_INSTANTANEOUS_CORNER_VELOCITY,
            ),
            max_extrude_only_velocity: klipper_only(
                self.max_extrude_only_velocity,
                max_velocity * extrude_ratio,
            ),
            max_extrude_only_accel: klipper_only(
                self.max_extrude_only_accel,
                accel * extrude_ratio,
            ),
            min_segment_time_floor: self.min_segment_time_floor,
            block_buffer_size: self.block_buffer_size.unwrap_or(MARLIN_BLOCK_BUFFER_SIZE),
            command_rate: self.command_rate.unwrap_or(MARLIN_COMMAND_RATE),
        }
    }
}

/// What Klipper's `[extruder]` refuses (klippy/kinematics/extruder.py,
/// `check_move`): a move with X or Y whose cross-section, E × the
/// filament's area / the move's XYZ length, passes `max_cross_section`
/// (unless it feeds at most nozzle × `max_cross_section` / area of
/// filament, "a tiny amount"); an extrude-only move (no X, no Y) of more
/// than `max_only_distance` of filament.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct KlipperExtruder {
    /// `max_extrude_cross_section`, mm².
    pub(crate) max_cross_section: f64,
    /// `max_extrude_only_distance`, mm of filament.
    pub(crate) max_only_distance: f64,
}

impl Kinematics {
    /// Klipper's extruder limits for `nozzle_diameter`: the profile's, else
    /// Klipper's defaults (4 × nozzle², 50 mm).
    pub(crate) fn klipper_extruder(&self, nozzle_diameter: f64) -> KlipperExtruder {
        KlipperExtruder {
            max_cross_section: self
                .max_extrude_cross_section
                .unwrap_or(KLIPPER_CROSS_SECTION_FACTOR * nozzle_diameter * nozzle_diameter),
            max_only_distance: self
                .max_extrude_only_distance
                .unwrap_or(KLIPPER_MAX_EXTRUDE_ONLY_DISTANCE),
        }
    }
}

/// Klipper's default extrude-only ratio: a cross-section of 4·nozzle² over the
/// filament's area (`[extruder] max_extrude_cross_section`).
pub(crate) fn extrude_ratio(nozzle_diameter: f64, filament_diameter: f64) -> f64 {
    let area = std::f64::consts::PI * 0.25 * filament_diameter * filament_diameter;
    KLIPPER_CROSS_SECTION_FACTOR * nozzle_diameter * nozzle_diameter / area
}

/// The limits the planner uses (written into the stats JSON as `planner`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Limits {
    /// Highest head speed, mm/s.
    pub max_velocity: f64,
    /// Acceleration of printing moves, mm/s².
    pub max_acceleration: f64,
    /// Acceleration of travel moves, mm/s².
    pub travel_acceleration: f64,
    /// Acceleration of E-only moves, mm/s².
    pub retract_acceleration: f64,
    /// Marlin's junction deviation, mm (absent under Klipper's model).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub junction_deviation: Option<f64>,
    /// Klipper's square-corner velocity, mm/s (absent under Marlin's model).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub square_corner_velocity: Option<f64>,
    /// Shortest time a move may take, s.
    pub min_segment_time: f64,
    /// Share of each move that must cruise (Klipper), 0 for none.
    pub minimum_cruise_ratio: f64,
    /// Highest Z speed, mm/s (none: no limit of its own).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_z_velocity: Option<f64>,
    /// Highest Z acceleration, mm/s² (none: no limit of its own).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_z_acceleration: Option<f64>,
    /// Klipper's largest instant change of E speed at a junction, mm/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub instantaneous_corner_velocity: Option<f64>,
    /// Klipper's speed limit of E-only moves, mm/s of filament.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_extrude_only_velocity: Option<f64>,
    /// Klipper's acceleration limit of E-only moves, mm/s² of filament.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_extrude_only_accel: Option<f64>,
    /// `min_segment_time` as a hard floor on every move (else Marlin's slowdown).
    pub min_segment_time_floor: bool,
    /// Marlin's block buffer, moves.
    pub block_buffer_size: u32,
    /// Lines per second the firmware reads and plans (refills the buffer).
    pub command_rate: f64,
}

impl Limits {
    /// One line for reports: `Marlin junction deviation 0.013 mm, 1000 mm/s², …`.
    pub(crate) fn describe(&self) -> String {
        let junction = match (self.junction_deviation, self.square_corner_velocity) {
            (_, Some(v)) => format!("square-corner velocity {v} mm/s"),
            (Some(d), None) => format!("junction deviation {d} mm"),
            (None, None) => "no junction limit".to_string(),
        };
        let mut s = format!(
            "{junction}, acceleration {} mm/s² (travel {}), max {} mm/s",
            self.max_acceleration, self.travel_acceleration, self.max_velocity
        );
        if let Some(vz) = self.max_z_velocity {
            s.push_str(&format!(", Z max {vz} mm/s"));
        }
        if let Some(az) = self.max_z_acceleration {
            s.push_str(&format!(" at {az} mm/s²"));
        }
        if self.min_segment_time > 0.0 {
            let how = if self.min_segment_time_floor {
                "on every move".to_string()
            } else {
                format!(
                    "while the {}-move buffer drains, {} lines/s",
                    self.block_buffer_size,
                    crate::base::format::fmt_num(self.command_rate)
                )
            };
            s.push_str(&format!(
                ", min segment time {} ms {how}",
                crate::base::format::fmt_num(self.min_segment_time * 1000.0)
            ));
        }
        if let Some(icv) = self.instantaneous_corner_velocity {
            s.push_str(&format!(", extruder corner velocity {icv} mm/s"));
        }
        if let (Some(v), Some(a)) = (self.max_extrude_only_velocity, self.max_extrude_only_accel) {
            s.push_str(&format!(
                ", extrude-only max {} mm/s at {} mm/s²",
                crate::base::format::fmt_num(v),
                crate::base::format::fmt_num(a)
            ));
        }
        if self.minimum_cruise_ratio > 0.0 {
            s.push_str(&format!(
                ", minimum cruise ratio {}",
                self.minimum_cruise_ratio
            ));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_min_segment_time_past_a_second_is_refused_naming_the_key() {
        let mut k = Kinematics {
            min_segment_time: Some(1e300),
            ..Kinematics::default()
        };
        let e = k.validate().unwrap_err();
        assert_eq!(e.place.as_deref(), Some("kinematics.min_segment_time"));
        k.min_segment_time = Some(0.02);
        k.validate().unwrap();
    }
}
