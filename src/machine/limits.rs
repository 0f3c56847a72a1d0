//! Physically sane ranges of printer and material values, checked at load.
//!
//! G-code drives a hot machine: a value far outside what any printer does
//! (a 1e-9 mm filament, a 900 °C nozzle, travel at 1e9 mm/s) is refused with
//! its key named, never clamped. The bounds are generous: every real machine
//! fits well inside them.

use crate::base::error::{Error, Result};

/// Filament diameter, mm (1.75 and 2.85 mm are the common sizes).
pub(crate) const FILAMENT_DIAMETER: (f64, f64) = (1.0, 3.5);
/// Nozzle diameter, mm.
pub(crate) const NOZZLE_DIAMETER: (f64, f64) = (0.1, 2.0);
/// Hottest nozzle temperature anything may ask for, °C.
pub(crate) const NOZZLE_TEMP_MAX: f64 = 500.0;
/// Hottest bed temperature anything may ask for, °C.
pub(crate) const BED_TEMP_MAX: f64 = 150.0;
/// Fastest speed of the head or the filament, mm/s.
pub(crate) const SPEED_MAX: f64 = 2000.0;
/// Largest acceleration, mm/s².
pub(crate) const ACCELERATION_MAX: f64 = 100_000.0;
/// Longest retraction, mm of filament.
pub(crate) const RETRACTION_MAX: f64 = 20.0;
/// Largest volumetric flow limit, mm³/s.
pub(crate) const FLOW_MAX: f64 = 1000.0;
/// Largest bed side, height, origin offset or other length of a machine, mm.
pub(crate) const MACHINE_LENGTH_MAX: f64 = 10_000.0;
/// Filament density, g/cm³.
pub(crate) const DENSITY: (f64, f64) = (0.1, 25.0);
/// Most filament fed by one move, or fed in place at once, mm: a purge or
/// a blob feeds centimetres; a metre is past any of them (the turtle's
/// `extrude`, `extrude_volume` and a profile's G-code are held to it).
pub(crate) const FEED_MAX: f64 = 1000.0;
/// Hottest chamber temperature anything may ask for, °C (heated chambers
/// reach 60–65 °C).
pub(crate) const CHAMBER_TEMP_MAX: f64 = 80.0;
/// Largest pressure (linear) advance factor, s (Klipper and RepRapFirmware
/// use 0–1, Marlin's linear advance 1.5 and Prusa's 0–0.5).
pub(crate) const PRESSURE_ADVANCE_MAX: f64 = 2.0;
/// Largest corner speed (jerk, square-corner velocity), mm/s.
pub(crate) const CORNER_SPEED_MAX: f64 = 100.0;
/// Largest junction deviation, mm.
pub(crate) const JUNCTION_DEVIATION_MAX: f64 = 1.0;
/// Highest input-shaper frequency, Hz.
pub(crate) const SHAPER_FREQUENCY_MAX: f64 = 500.0;
/// Longest dwell a G-code may ask for, s: an hour of a hot, idle machine.
pub(crate) const DWELL_MAX: f64 = 3600.0;

/// Refuses `v` outside `[min, max]` (or not finite), naming `key` and the range.
pub(crate) fn range(key: &str, v: f64, (min, max): (f64, f64), unit: &str) -> Result<()> {
    if v.is_finite() && v >= min && v <= max {
        return Ok(());
    }
    Err(Error::input(
        key,
        format!("{v} {unit} is not allowed; expected {min} to {max} {unit}"),
    ))
}

/// Refuses `v` above `max` (or not finite), naming `key`; the lower bound is
/// checked where the value is read.
pub(crate) fn at_most(key: &str, v: f64, max: f64, unit: &str) -> Result<()> {
    if v.is_finite() && v <= max {
        return Ok(());
    }
    Err(Error::input(
        key,
        format!("{v} {unit} is not allowed; expected at most {max} {unit}"),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_name_the_key_and_the_bounds() {
        assert!(range("filament_diameter", 1.75, FILAMENT_DIAMETER, "mm").is_ok());
        let e = range("filament_diameter", 1e-9, FILAMENT_DIAMETER, "mm").unwrap_err();
        assert_eq!(e.place.as_deref(), Some("filament_diameter"));
        assert!(e.message.contains("expected 1 to 3.5 mm"), "{e}");
        assert!(at_most("max_speed", f64::NAN, SPEED_MAX, "mm/s").is_err());
        assert!(at_most("max_speed", 1e9, SPEED_MAX, "mm/s").is_err());
    }
}
