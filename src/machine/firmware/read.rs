//! A line of G-code read into typed commands, as the flavour's firmware
//! reads it (the line cut by [`crate::base::gcode::lex`] first).
//!
//! | meaning | Marlin, Prusa, Bambu | Klipper | RepRapFirmware |
//! |---|---|---|---|
//! | heaters | `M104`/`M109` `S` (`R` waits both ways, `T` tool), `M140`/`M190`, `M141`/`M191` | the same, and `SET_HEATER_TEMPERATURE HEATER= TARGET=` | the same, and `G10 P S` |
//! | part fan | `M106 S0–255` (`P0`; Bambu's part fan is `P1`), `M107` | the same | `M106 S0–1` (or 0–255) |
//! | pressure advance | `M900 K` (Prusa's Buddy: `M572 S`) | `SET_PRESSURE_ADVANCE ADVANCE=` | `M572 S` |
//! | accelerations | `M204 P T R` (`S` both) | `M204 S`, `SET_VELOCITY_LIMIT ACCEL=` | `M204 P T` |
//! | corners | `M205 J` (junction deviation), `M205 X Y` (jerk) | `SET_VELOCITY_LIMIT SQUARE_CORNER_VELOCITY= MINIMUM_CRUISE_RATIO=` | `M566 X Y` (mm/min) |
//! | input shaping | `M593 F D` | `SET_INPUT_SHAPER` | `M593 P F S` |
//! | limits | `M201`, `M203` (mm/s) | `SET_VELOCITY_LIMIT VELOCITY=` | `M201`, `M203` (mm/min) |
//! | flow, speed | `M221 S`, `M220 S` (%) | the same | the same |
//! | retraction | `M207 S F` (mm/min) | `SET_RETRACTION RETRACT_LENGTH= RETRACT_SPEED=` | `M207 S F` |
//!
//! What has no typed meaning is [`Command::Other`], named by its code: the
//! checks decide whether it may run.

use crate::base::gcode::lex::{lex, Code, Grammar, Line};
use crate::base::gcode::{Arc, Command, Heater, Move, Object, Setting, Shaper};
use crate::machine::printer::Flavor;

/// A line read: its words as the firmware cuts them, and what it means.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Read<'a> {
    /// The line, cut.
    pub(crate) line: Line<'a>,
    /// What it does, in order (most lines do one thing; `SET_VELOCITY_LIMIT`
    /// or `M205 X J` set several; a comment or blank line nothing).
    pub(crate) commands: Vec<Command>,
}

/// The parser whose rules `flavor`'s firmware follows.
pub(crate) fn grammar(flavor: Flavor) -> Grammar {
    match flavor {
        Flavor::Klipper => Grammar::Klipper,
        Flavor::Reprap => Grammar::Reprap,
        Flavor::Marlin | Flavor::Prusa | Flavor::Bambu => Grammar::Marlin,
    }
}

/// Reads `text`, one line, as `flavor`'s firmware does; an error says why
/// the line cannot be read safely (a value the firmware could not read
/// either, a character outside ASCII in the command).
pub(crate) fn read(flavor: Flavor, text: &str) -> Result<Read<'_>, String> {
    let line = lex(grammar(flavor), text)?;
    let commands = match &line.code {
        None => Vec::new(),
        Some(Code::Number { letter, number, .. })
            if flavor == Flavor::Klipper && !klipper_runs(*letter, *number) =>
        {
            other(&line)
        }
        Some(Code::Number {
            letter: b'G',
            number,
            ..
        }) => g(flavor, *number, &line)?,
        Some(Code::Number {
            letter: b'M',
            number,
            ..
        }) => m(flavor, *number, &line)?,
        Some(Code::Number { number, .. }) => vec![Command::Tool(*number)],
        Some(Code::Name(name)) => named(flavor, name, &line)?,
    };
    Ok(Read { line, commands })
}

/// Whether stock Klipper runs traditional command `letter``number` (an
/// unknown one it answers "Unknown command" and skips; a printer's macro
/// of that name is the printer's own, read as [`Command::Other`]).
fn klipper_runs(letter: u8, number: u32) -> bool {
    match letter {
        b'G' => matches!(number, 0..=4 | 10 | 11 | 21 | 28 | 90..=92),
        b'M' => matches!(
            number,
            73 | 82 | 83 | 104 | 106 | 107 | 109 | 140 | 190 | 204 | 220 | 221
        ),
        _ => true,
    }
}

/// The value of `key` the firmware uses, a number.
fn num(l: &Line, key: &str) -> Result<Option<f64>, String> {
    l.number(key)
}

/// X, Y, Z.
fn axes(l: &Line) -> Result<[Option<f64>; 3], String> {
    Ok([num(l, "X")?, num(l, "Y")?, num(l, "Z")?])
}

fn other(l: &Line) -> Vec<Command> {
    let code = l.code.as_ref().map(Code::shown).unwrap_or_default();
    vec![Command::Other(code)]
}

fn set(s: Setting) -> Vec<Command> {
    vec![Command::Set(s)]
}

fn g(flavor: Flavor, n: u32, l: &Line) -> Result<Vec<Command>, String> {
    let reprap = flavor == Flavor::Reprap;
    Ok(match n {
        0 | 1 => vec![Command::Move(Move {
            travel: n == 0,
            to: axes(l)?,
            e: num(l, "E")?,
            feed: num(l, "F")?,
        })],
        2 | 3 if !l.has("R") => vec![Command::Arc(Arc {
            ccw: n == 3,
            to: axes(l)?,
            ij: [num(l, "I")?.unwrap_or(0.0), num(l, "J")?.unwrap_or(0.0)],
            e: num(l, "E")?,
            feed: num(l, "F")?,
        })],
        // G4 P<ms>, or S<s> (Marlin, RepRapFirmware)
        4 => {
            let ms = match (num(l, "P")?, num(l, "S")?) {
                (Some(p), _) => p,
                (None, Some(s)) if flavor != Flavor::Klipper => s * 1000.0,
                _ => 0.0,
            };
            vec![Command::Dwell { ms }]
        }
        // RepRapFirmware's G10 P S R sets a tool's temperatures; L2/L20 set
        // coordinate offsets (no typed meaning: refused by the checks)
        10 if reprap && (l.has("L") || !l.params.is_empty()) => {
            if l.has("L") {
                other(l)
            } else {
                let tool = num(l, "P")?.unwrap_or(0.0);
                let mut out = Vec::new();
                for key in ["S", "R"] {
                    if let Some(t) = num(l, key)? {
                        out.push(Command::Set(Setting::Temperature {
                            heater: Heater::Nozzle(tool_index(tool)),
                            celsius: t,
                            wait: false,
                        }));
                    }
                }
                out
            }
        }
        10 if l.params.is_empty() || !reprap => vec![Command::FirmwareRetract { undo: false }],
        11 => vec![Command::FirmwareRetract { undo: true }],
        20 => vec![Command::Inches(true)],
        21 => vec![Command::Inches(false)],
        28 => {
            let named = [l.has("X"), l.has("Y"), l.has("Z")];
            let axes = if named.iter().any(|&a| a) {
                named
            } else {
                [true; 3]
            };
            vec![Command::Home { axes }]
        }
        90 => vec![Command::RelativeXyz(false)],
        91 => vec![Command::RelativeXyz(true)],
        92 => {
            let mut axes = axes(l)?;
            let mut e = num(l, "E")?;
            // Klipper's bare G92 sets every axis to 0
            if flavor == Flavor::Klipper && l.params.is_empty() {
                axes = [Some(0.0); 3];
                e = Some(0.0);
            }
            vec![Command::SetPosition { axes, e }]
        }
        _ => other(l),
    })
}

/// A tool number as written (`T1`, `P1`), 0 when it is no small whole number.
fn tool_index(t: f64) -> u8 {
    if t.is_finite() && (0.0..=255.0).contains(&t) && t.fract() == 0.0 {
        t as u8
    } else {
        0
    }
}

/// A temperature command of `heater`: its `S` (or, waiting both ways, `R`).
fn temperature(l: &Line, heater: Heater, wait: bool) -> Result<Vec<Command>, String> {
    let heater = match heater {
        Heater::Nozzle(_) => Heater::Nozzle(tool_index(num(l, "T")?.unwrap_or(0.0))),
        h => h,
    };
    let celsius = match (num(l, "S")?, num(l, "R")?) {
        (Some(s), _) => s,
        (None, Some(r)) if wait => r,
        _ => return Ok(Vec::new()),
    };
    Ok(set(Setting::Temperature {
        heater,
        celsius,
        wait,
    }))
}

/// A percentage factor `S` as a fraction.
fn factor(l: &Line) -> Result<Option<f64>, String> {
    Ok(num(l, "S")?.map(|s| s / 100.0))
}

fn m(flavor: Flavor, n: u32, l: &Line) -> Result<Vec<Command>, String> {
    let reprap = flavor == Flavor::Reprap;
    // RepRapFirmware's feeds and jerks are in mm/min
    let per_min = if reprap { 1.0 / 60.0 } else { 1.0 };
    Ok(match n {
        0 | 1 | 601 => vec![Command::Pause],
        226 if reprap => vec![Command::Pause],
        73 => match num(l, "P")? {
            Some(p) if l.get("L").is_none() => vec![Command::Progress {
                percent: p.clamp(0.0, 100.0) as u32,
                minutes_left: num(l, "R")?.unwrap_or(0.0).max(0.0) as u64,
            }],
            _ => other(l),
        },
        82 => vec![Command::RelativeE(false)],
        83 => vec![Command::RelativeE(true)],
        104 => temperature(l, Heater::Nozzle(0), false)?,
        109 => temperature(l, Heater::Nozzle(0), true)?,
        140 => temperature(l, Heater::Bed, false)?,
        190 => temperature(l, Heater::Bed, true)?,
        141 => temperature(l, Heater::Chamber, false)?,
        191 => temperature(l, Heater::Chamber, true)?,
        106 => fan(flavor, l)?,
        107 if part_fan(flavor, l)? => set(Setting::Fan { speed: 0.0 }),
        201 => set(Setting::MaxAcceleration {
            axes: [num(l, "X")?, num(l, "Y")?, num(l, "Z")?, num(l, "E")?],
        }),
        203 => {
            let a = [num(l, "X")?, num(l, "Y")?, num(l, "Z")?, num(l, "E")?];
            set(Setting::MaxFeedrate {
                axes: a.map(|v| v.map(|v| v * per_min)),
            })
        }
        204 => acceleration(flavor, l)?,
        205 if !reprap => m205(l)?,
        207 => set(Setting::Retraction {
            length: num(l, "S")?,
            speed: num(l, "F")?.map(|f| f / 60.0),
        }),
        220 => factor(l)?.map_or_else(Vec::new, |s| set(Setting::Speed(s))),
        221 => factor(l)?.map_or_else(Vec::new, |s| set(Setting::Flow(s))),
        566 if reprap => match (num(l, "X")?, num(l, "Y")?) {
            (Some(x), y) => set(Setting::Jerk(x.min(y.unwrap_or(x)) / 60.0)),
            (None, Some(y)) => set(Setting::Jerk(y / 60.0)),
            _ => Vec::new(),
        },
        572 if matches!(flavor, Flavor::Prusa | Flavor::Reprap) => {
            num(l, "S")?.map_or_else(Vec::new, |k| set(Setting::PressureAdvance { k }))
        }
        593 => input_shaper(flavor, l)?,
        900 if !reprap => {
            num(l, "K")?.map_or_else(Vec::new, |k| set(Setting::PressureAdvance { k }))
        }
        _ => other(l),
    })
}

/// Whether an `M106`/`M107` is for the part-cooling fan: no `P`, or the
/// part fan's index (`P0`; Bambu's `P1`).
fn part_fan(flavor: Flavor, l: &Line) -> Result<bool, String> {
    Ok(match num(l, "P")? {
        None => true,
        Some(p) => p == 0.0 || (flavor == Flavor::Bambu && p == 1.0),
    })
}

/// `M106 S`: 0–255 (RepRapFirmware: 0–1, or 0–255 when above 1).
fn fan(flavor: Flavor, l: &Line) -> Result<Vec<Command>, String> {
    if !part_fan(flavor, l)? {
        return Ok(other(l));
    }
    let s = num(l, "S")?.unwrap_or(255.0);
    let speed = if flavor == Flavor::Reprap && s <= 1.0 {
        s
    } else {
        s / 255.0
    };
    Ok(set(Setting::Fan { speed }))
}

/// `M204`: Marlin's P (print), T (travel), R (retract), S (print and
/// travel); Klipper's S, or the smaller of P and T.
fn acceleration(flavor: Flavor, l: &Line) -> Result<Vec<Command>, String> {
    let (s, p, t, r) = (num(l, "S")?, num(l, "P")?, num(l, "T")?, num(l, "R")?);
    let (print, travel, retract) = match flavor {
        Flavor::Klipper => {
            let a = s.or(match (p, t) {
                (Some(p), Some(t)) => Some(p.min(t)),
                _ => None,
            });
            (a, a, None)
        }
        _ => (p.or(s), t.or(s), r),
    };
    if print.is_none() && travel.is_none() && retract.is_none() {
        return Ok(Vec::new());
    }
    Ok(set(Setting::Acceleration {
        print,
        travel,
        retract,
    }))
}

/// Marlin's `M205`: `J` junction deviation, `X`/`Y` jerk; its other words
/// (`B` minimum segment time, `S`/`T` minimum feeds, `Z`/`E` jerk) have no
/// typed meaning and are left to the checks.
fn m205(l: &Line) -> Result<Vec<Command>, String> {
    let mut out = Vec::new();
    if let Some(j) = num(l, "J")? {
        out.push(Command::Set(Setting::JunctionDeviation(j)));
    }
    let xy = match (num(l, "X")?, num(l, "Y")?) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (a, b) => a.or(b),
    };
    if let Some(j) = xy {
        out.push(Command::Set(Setting::Jerk(j)));
    }
    Ok(out)
}

/// `M593`: Marlin's `[X|Y] F D`, Prusa's `T F D`, RepRapFirmware's `P"type" F S`.
fn input_shaper(flavor: Flavor, l: &Line) -> Result<Vec<Command>, String> {
    let f = num(l, "F")?;
    let (x, y) = (l.has("X"), l.has("Y"));
    let frequency = match (x, y) {
        (true, false) => [f, None],
        (false, true) => [None, f],
        _ => [f, f],
    };
    let damping = match flavor {
        Flavor::Reprap => num(l, "S")?,
        _ => num(l, "D")?,
    };
    let kind = match flavor {
        Flavor::Reprap => l.word("P").and_then(Shaper::parse),
        Flavor::Prusa => num(l, "T")?.and_then(|t| {
            // Buddy's M593 T: 0 ZV, 1 ZVD, 2 MZV, 3 EI, 4 2-hump EI, 5 3-hump EI
            let kinds = [
                Shaper::Zv,
                Shaper::Zvd,
                Shaper::Mzv,
                Shaper::Ei,
                Shaper::TwoHumpEi,
                Shaper::ThreeHumpEi,
            ];
            (t.fract() == 0.0 && t >= 0.0)
                .then(|| kinds.get(t as usize).copied())
                .flatten()
        }),
        _ => None,
    };
    Ok(set(Setting::InputShaper {
        frequency,
        damping,
        kind,
    }))
}

/// Klipper's extended commands with a typed meaning; any other name is
/// [`Command::Other`].
fn named(flavor: Flavor, name: &str, l: &Line) -> Result<Vec<Command>, String> {
    if flavor != Flavor::Klipper {
        return Ok(other(l));
    }
    Ok(match name {
        "SET_HEATER_TEMPERATURE" => {
            let heater = match l.word("HEATER").map(str::to_ascii_lowercase) {
                Some(h) if h == "heater_bed" => Heater::Bed,
                Some(h) if h.starts_with("extruder") => {
                    Heater::Nozzle(h[8..].parse::<u8>().unwrap_or(0))
                }
                Some(h) if h.contains("chamber") => Heater::Chamber,
                _ => return Ok(other(l)),
            };
            match num(l, "TARGET")? {
                Some(t) => set(Setting::Temperature {
                    heater,
                    celsius: t,
                    wait: false,
                }),
                None => Vec::new(),
            }
        }
        "SET_PRESSURE_ADVANCE" => match num(l, "ADVANCE")? {
            Some(k) => set(Setting::PressureAdvance { k }),
            None => other(l),
        },
        "SET_VELOCITY_LIMIT" => velocity_limit(l)?,
        "SET_INPUT_SHAPER" => {
            let kind = l
                .word("SHAPER_TYPE")
                .or_else(|| l.word("SHAPER_TYPE_X"))
                .and_then(Shaper::parse);
            set(Setting::InputShaper {
                frequency: [num(l, "SHAPER_FREQ_X")?, num(l, "SHAPER_FREQ_Y")?],
                damping: num(l, "DAMPING_RATIO_X")?.or(num(l, "DAMPING_RATIO_Y")?),
                kind,
            })
        }
        "SET_RETRACTION" => set(Setting::Retraction {
            length: num(l, "RETRACT_LENGTH")?,
            speed: num(l, "RETRACT_SPEED")?,
        }),
        "PAUSE" => vec![Command::Pause],
        "EXCLUDE_OBJECT_START" | "EXCLUDE_OBJECT_END" => {
            let n = l.word("NAME").unwrap_or_default().to_string();
            vec![Command::Object(if name.ends_with("START") {
                Object::Start(n)
            } else {
                Object::End(n)
            })]
        }
        _ => other(l),
    })
}

/// `SET_VELOCITY_LIMIT`: each of its words a setting.
fn velocity_limit(l: &Line) -> Result<Vec<Command>, String> {
    let mut out = Vec::new();
    if let Some(v) = num(l, "VELOCITY")? {
        out.push(Setting::SpeedLimit { velocity: v });
    }
    if let Some(a) = num(l, "ACCEL")? {
        out.push(Setting::Acceleration {
            print: Some(a),
            travel: Some(a),
            retract: None,
        });
    }
    if let Some(v) = num(l, "SQUARE_CORNER_VELOCITY")? {
        out.push(Setting::SquareCornerVelocity(v));
    }
    if let Some(r) = num(l, "MINIMUM_CRUISE_RATIO")? {
        out.push(Setting::MinimumCruiseRatio(r));
    }
    Ok(out.into_iter().map(Command::Set).collect())
}
