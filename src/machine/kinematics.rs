//! A printer profile's `kinematics:`: the limits the firmware's planner works
//! with, and those limits with every default filled in.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Marlin's default junction deviation, mm (`JUNCTION_DEVIATION_MM`).
pub const MARLIN_JUNCTION_DEVIATION: f64 = 0.013;
/// Marlin's default minimum segment time, s (`DEFAULT_MINSEGMENTTIME` 20000 µs).
pub const MARLIN_MIN_SEGMENT_TIME: f64 = 0.02;
/// Klipper's default `minimum_cruise_ratio`.
pub const KLIPPER_MINIMUM_CRUISE_RATIO: f64 = 0.5;

fn d_accel() -> f64 {
    1000.0
}

/// A printer profile's `kinematics:` block: the limits the firmware's planner
/// works with. Give `junction_deviation` (Marlin) or `square_corner_velocity`
/// (Klipper), not both; with neither, Marlin's 0.013 mm.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Kinematics {
    /// Highest head speed, mm/s; the profile's `max_speed` when absent.
    #[serde(default)]
    pub max_velocity: Option<f64>,
    /// Acceleration of printing moves, mm/s² (Marlin's `M204 P`, Klipper's `max_accel`).
    #[serde(default = "d_accel")]
    pub max_acceleration: f64,
    /// Acceleration of travel moves, mm/s² (Marlin's `M204 T`); `max_acceleration` when absent.
    #[serde(default)]
    pub travel_acceleration: Option<f64>,
    /// Acceleration of E-only moves (retractions), mm/s² of filament
    /// (Marlin's `M204 R`); `max_acceleration` when absent.
    #[serde(default)]
    pub retract_acceleration: Option<f64>,
    /// Marlin's junction deviation, mm (`M205 J`).
    #[serde(default)]
    pub junction_deviation: Option<f64>,
    /// Klipper's square-corner velocity: the speed of a 90° corner, mm/s.
    #[serde(default)]
    pub square_corner_velocity: Option<f64>,
    /// Shortest time a move may take, s (Marlin's `M205 B`, in s here); 0.02
    /// with junction deviation, 0 with square-corner velocity (Klipper has none).
    #[serde(default)]
    pub min_segment_time: Option<f64>,
    /// Klipper's `minimum_cruise_ratio`: the share of a move that must cruise;
    /// 0.5 with square-corner velocity, 0 with junction deviation (Marlin has none).
    #[serde(default)]
    pub minimum_cruise_ratio: Option<f64>,
}

impl Default for Kinematics {
    fn default() -> Self {
        Kinematics {
            max_velocity: None,
            max_acceleration: d_accel(),
            travel_acceleration: None,
            retract_acceleration: None,
            junction_deviation: None,
            square_corner_velocity: None,
            min_segment_time: None,
            minimum_cruise_ratio: None,
        }
    }
}

impl Kinematics {
    /// Checks the values; errors name the key under `kinematics.`.
    pub fn validate(&self) -> Result<()> {
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
        check("square_corner_velocity", self.square_corner_velocity, true)?;
        check("min_segment_time", self.min_segment_time, true)?;
        check("minimum_cruise_ratio", self.minimum_cruise_ratio, true)?;
        if self.minimum_cruise_ratio.is_some_and(|r| r >= 1.0) {
            return Err(Error::input(
                "kinematics.minimum_cruise_ratio",
                "expected a ratio in [0, 1)",
            ));
        }
        if self.junction_deviation.is_some() && self.square_corner_velocity.is_some() {
            return Err(Error::input(
                "kinematics",
                "give `junction_deviation` (Marlin) or `square_corner_velocity` (Klipper), not both",
            ));
        }
        Ok(())
    }

    /// The limits with every default filled in; `max_speed` is the profile's.
    pub fn limits(&self, max_speed: f64) -> Limits {
        let klipper = self.square_corner_velocity.is_some();
        let accel = self.max_acceleration;
        Limits {
            max_velocity: self.max_velocity.unwrap_or(max_speed),
            max_acceleration: accel,
            travel_acceleration: self.travel_acceleration.unwrap_or(accel),
            retract_acceleration: self.retract_acceleration.unwrap_or(accel),
            junction_deviation: if klipper {
                None
            } else {
                Some(self.junction_deviation.unwrap_or(MARLIN_JUNCTION_DEVIATION))
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
        }
    }
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
}

impl Limits {
    /// One line for reports: `Marlin junction deviation 0.013 mm, 1000 mm/s², …`.
    pub fn describe(&self) -> String {
        let junction = match (self.junction_deviation, self.square_corner_velocity) {
            (_, Some(v)) => format!("square-corner velocity {v} mm/s"),
            (Some(d), None) => format!("junction deviation {d} mm"),
            (None, None) => "no junction limit".to_string(),
        };
        let mut s = format!(
            "{junction}, acceleration {} mm/s² (travel {}), max {} mm/s",
            self.max_acceleration, self.travel_acceleration, self.max_velocity
        );
        if self.min_segment_time > 0.0 {
            s.push_str(&format!(
                ", min segment time {} ms",
                crate::format::fmt_num(self.min_segment_time * 1000.0)
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
