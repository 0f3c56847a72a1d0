//! The firmware dialects: the commands in which Marlin, Prusa's firmware,
//! Klipper and RepRapFirmware differ (heating and waiting, pause, fan,
//! firmware retraction).
//!
//! | | marlin | prusa | klipper | reprap |
//! |---|---|---|---|---|
//! | nozzle | `M104 S` / `M109 S` | same | `SET_HEATER_TEMPERATURE HEATER=extruder TARGET=` (+ `TEMPERATURE_WAIT SENSOR=extruder MINIMUM=`) | `M104 S` (+ `M116 P0`) |
//! | bed | `M140 S` / `M190 S` | same | `… HEATER=heater_bed …` | `M140 S` (+ `M116 H0`) |
//! | pause | `M0` | `M601` | `PAUSE` | `M226` |
//! | fan | `M106 S0..255`, `M107` | same | same | `M106 S0..1` (`M106 S0` off) |
//! | dwell | `G4 P<ms>` | same | same | same |
//! | firmware retraction | `G10` / `G11` | same (MK3S; not the MK4's Buddy) | same (`[firmware_retraction]`) | same (`M207`) |
//!
//! Waiting follows Marlin's `M109 S`: it waits while heating, not while
//! cooling (Klipper's `MINIMUM=`); a target of 0 (off) is never waited for.
//! Moves (G0/G1, G2/G3), units (G21), positioning (G90) and the extrusion
//! mode (M82/M83) are common to all four and written by [`crate::output::gcode`].

use crate::base::format::fmt_num;
use crate::base::toolpath::Event;
use crate::machine::Flavor;

impl Flavor {
    /// Every flavour, in the order `p3dp printers` and the docs list them.
    pub const ALL: [Flavor; 4] = [
        Flavor::Marlin,
        Flavor::Prusa,
        Flavor::Klipper,
        Flavor::Reprap,
    ];

    /// The profile's name of the flavour: `marlin`, `prusa`, `klipper`, `reprap`.
    pub fn name(self) -> &'static str {
        match self {
            Flavor::Marlin => "marlin",
            Flavor::Prusa => "prusa",
            Flavor::Klipper => "klipper",
            Flavor::Reprap => "reprap",
        }
    }
}

/// The G-code line(s) for an event other than `Retract` and `Extrude` (which
/// are moves), without a trailing newline; `None` for those two.
pub(crate) fn event_line(flavor: Flavor, e: &Event) -> Option<String> {
    Some(match *e {
        Event::Gcode(ref text) => text.to_string(),
        Event::Dwell { ms } => dwell(flavor, ms),
        Event::Pause => pause(flavor),
        Event::NozzleTemp { celsius, wait } => nozzle_temp(flavor, celsius, wait),
        Event::BedTemp { celsius, wait } => bed_temp(flavor, celsius, wait),
        Event::Fan { speed } => fan(flavor, speed),
        Event::Retract | Event::Extrude { .. } => return None,
    })
}

/// Wait `ms` milliseconds: `G4 P<ms>` in every dialect.
pub(crate) fn dwell(_flavor: Flavor, ms: f64) -> String {
    format!("G4 P{} ; dwell", libm::round(ms.max(0.0)) as u64)
}

/// A pause for the operator: Marlin `M0`, Prusa `M601`, Klipper `PAUSE`,
/// RepRapFirmware `M226`.
pub(crate) fn pause(flavor: Flavor) -> String {
    match flavor {
        Flavor::Marlin => "M0 ; pause: press the knob to resume".to_string(),
        Flavor::Prusa => "M601 ; pause: resume from the panel".to_string(),
        Flavor::Klipper => "PAUSE ; resume with RESUME".to_string(),
        Flavor::Reprap => "M226 ; pause: resume from the panel".to_string(),
    }
}

/// A heater as each dialect names it.
struct Heater {
    /// Its name in comments: `nozzle`, `bed`.
    what: &'static str,
    /// Marlin's set code: `M104`, `M140` (RepRapFirmware's too).
    set: &'static str,
    /// Marlin's set-and-wait code: `M109`, `M190`.
    wait: &'static str,
    /// Klipper's heater (and sensor) name.
    klipper: &'static str,
    /// RepRapFirmware's `M116` wait for it alone: `P0` (tool 0), `H0` (bed).
    reprap_wait: &'static str,
}

const NOZZLE: Heater = Heater {
    what: "nozzle",
    set: "M104",
    wait: "M109",
    klipper: "extruder",
    reprap_wait: "P0",
};

const BED: Heater = Heater {
    what: "bed",
    set: "M140",
    wait: "M190",
    klipper: "heater_bed",
    reprap_wait: "H0",
};

/// Set (and with `wait`, wait for) heater `h` in `flavor`'s dialect; a target
/// of 0 (off) is never waited for.
fn heat(flavor: Flavor, h: &Heater, celsius: f64, wait: bool) -> String {
    let t = fmt_num(celsius);
    let what = h.what;
    let waits = wait && celsius > 0.0;
    match flavor {
        Flavor::Marlin | Flavor::Prusa => {
            let m = if wait { h.wait } else { h.set };
            format!("{m} S{t} ; {what} temperature")
        }
        Flavor::Klipper => {
            let k = h.klipper;
            let mut s =
                format!("SET_HEATER_TEMPERATURE HEATER={k} TARGET={t} ; {what} temperature");
            if waits {
                s.push_str(&format!(
                    "\nTEMPERATURE_WAIT SENSOR={k} MINIMUM={t} ; wait for the {what}"
                ));
            }
            s
        }
        Flavor::Reprap => {
            let mut s = format!("{} S{t} ; {what} temperature", h.set);
            if waits {
                s.push_str(&format!("\nM116 {} ; wait for the {what}", h.reprap_wait));
            }
            s
        }
    }
}

/// Set (and with `wait`, wait for) the nozzle temperature.
pub(crate) fn nozzle_temp(flavor: Flavor, celsius: f64, wait: bool) -> String {
    heat(flavor, &NOZZLE, celsius, wait)
}

/// Set (and with `wait`, wait for) the bed temperature.
pub(crate) fn bed_temp(flavor: Flavor, celsius: f64, wait: bool) -> String {
    heat(flavor, &BED, celsius, wait)
}

/// Part-cooling fan at `speed` (0 to 1): `M106 S<0..255>` or `M107` for off;
/// RepRapFirmware takes the fraction itself, `M106 S0.50`, and `M106 S0`.
pub(crate) fn fan(flavor: Flavor, speed: f64) -> String {
    let speed = if speed.is_nan() {
        0.0
    } else {
        speed.clamp(0.0, 1.0)
    };
    if flavor == Flavor::Reprap {
        let s = libm::round(speed * 100.0) as u32;
        return if s == 0 {
            "M106 S0 ; fan off".to_string()
        } else {
            format!("M106 S{}.{:02} ; fan", s / 100, s % 100)
        };
    }
    let s = libm::round(speed * 255.0) as u32;
    if s == 0 {
        "M107 ; fan off".to_string()
    } else {
        format!("M106 S{s} ; fan")
    }
}

/// Firmware retraction (`firmware_retraction: true`): `G10`, in every dialect.
pub(crate) fn retract(_flavor: Flavor) -> &'static str {
    "G10 ; retract"
}

/// Firmware unretraction: `G11`, in every dialect.
pub(crate) fn unretract(_flavor: Flavor) -> &'static str {
    "G11 ; unretract"
}

/// Whether a stock firmware of this dialect runs `G2`/`G3` arcs: Marlin
/// (ARC_SUPPORT), Prusa, RepRapFirmware; Klipper with a `[gcode_arcs]` section.
pub(crate) fn arc_note(flavor: Flavor) -> &'static str {
    match flavor {
        Flavor::Klipper => "arcs need `[gcode_arcs]` in printer.cfg",
        Flavor::Marlin => "arcs need ARC_SUPPORT (on in Marlin 2's default configuration)",
        Flavor::Prusa | Flavor::Reprap => "arcs are supported",
    }
}

/// How the dialect's stock firmware cuts an arc into straight moves (see
/// [`crate::base::geom::arc::Firmware`]): Marlin 2 in chords of at most 1 mm and at
/// least 72 a turn; Klipper's `[gcode_arcs]` in 1 mm chords; Prusa's and
/// RepRapFirmware are taken as 1 mm chords too (the cautious choice).
pub(crate) fn arc_firmware(flavor: Flavor) -> crate::base::geom::arc::Firmware {
    crate::base::geom::arc::Firmware {
        max_chord: 1.0,
        min_circle_segments: if flavor == Flavor::Marlin { 72 } else { 0 },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pauses_differ_per_dialect() {
        let first = |f| pause(f).split(' ').next().unwrap().to_string();
        assert_eq!(first(Flavor::Marlin), "M0");
        assert_eq!(first(Flavor::Prusa), "M601");
        assert_eq!(first(Flavor::Klipper), "PAUSE");
        assert_eq!(first(Flavor::Reprap), "M226");
        assert_eq!(dwell(Flavor::Marlin, 250.4), "G4 P250 ; dwell");
        assert!(event_line(Flavor::Marlin, &Event::Retract).is_none());
    }

    #[test]
    fn heating_and_waiting() {
        let wait = Event::NozzleTemp {
            celsius: 215.0,
            wait: true,
        };
        assert_eq!(
            event_line(Flavor::Marlin, &wait).unwrap(),
            "M109 S215 ; nozzle temperature"
        );
        assert_eq!(
            event_line(Flavor::Klipper, &wait).unwrap(),
            "SET_HEATER_TEMPERATURE HEATER=extruder TARGET=215 ; nozzle temperature\n\
             TEMPERATURE_WAIT SENSOR=extruder MINIMUM=215 ; wait for the nozzle"
        );
        assert_eq!(
            event_line(Flavor::Reprap, &wait).unwrap(),
            "M104 S215 ; nozzle temperature\nM116 P0 ; wait for the nozzle"
        );
        assert_eq!(
            bed_temp(Flavor::Prusa, 60.0, true),
            "M190 S60 ; bed temperature"
        );
        assert_eq!(
            bed_temp(Flavor::Reprap, 60.0, true),
            "M140 S60 ; bed temperature\nM116 H0 ; wait for the bed"
        );
        // switching off is never waited for
        assert_eq!(
            bed_temp(Flavor::Klipper, 0.0, true),
            "SET_HEATER_TEMPERATURE HEATER=heater_bed TARGET=0 ; bed temperature"
        );
        assert_eq!(
            nozzle_temp(Flavor::Reprap, 0.0, true),
            "M104 S0 ; nozzle temperature"
        );
    }

    #[test]
    fn fans() {
        assert_eq!(fan(Flavor::Marlin, 0.5), "M106 S128 ; fan");
        assert_eq!(fan(Flavor::Klipper, 0.0), "M107 ; fan off");
        assert_eq!(fan(Flavor::Reprap, 0.5), "M106 S0.50 ; fan");
        assert_eq!(fan(Flavor::Reprap, 1.0), "M106 S1.00 ; fan");
        assert_eq!(fan(Flavor::Reprap, 0.001), "M106 S0 ; fan off");
    }
}
