//! The reader read as each firmware reads, the writer's dialects, and the
//! writer and the reader agreeing: every setting written and read back is
//! the setting.

use super::read::read;
use super::write::{write, Dialect};
use super::*;
use crate::base::format::Chunk;
use crate::base::gcode::lex::{lex, Grammar, Value};
use crate::base::gcode::{Command, Heater, Move, Setting, Shaper};
use crate::machine::printer::Flavor;

fn one(flavor: Flavor, line: &str) -> Vec<Command> {
    read(flavor, line)
        .unwrap_or_else(|e| panic!("{line}: {e}"))
        .commands
}

fn nozzle(celsius: f64, wait: bool) -> Command {
    Command::Set(Setting::Temperature {
        heater: Heater::Nozzle(0),
        celsius,
        wait,
    })
}

#[test]
fn marlin_reads_as_its_parser_does() {
    let m = Flavor::Marlin;
    // the last of a repeated parameter counts
    assert_eq!(one(m, "M104 S200 S255"), [nozzle(255.0, false)]);
    // a space between the letter and the number, a subcode
    assert_eq!(one(m, "M 104 S200"), [nozzle(200.0, false)]);
    assert_eq!(one(m, "M109.7 S300"), [nozzle(300.0, true)]);
    // letters in quotes are parameters; a letter ends a number
    let mv = |l| match &one(m, l)[..] {
        [Command::Move(mv)] => *mv,
        other => panic!("{l}: {other:?}"),
    };
    assert_eq!(
        mv("G1 X100 \"Y5000\"").to,
        [Some(100.0), Some(5000.0), None]
    );
    let x1e3 = mv("G1 X1E3");
    assert_eq!((x1e3.to[0], x1e3.e), (Some(1.0), Some(3.0)));
    // a line number, a checksum, lower case, a run of number characters
    assert_eq!(mv("N10 G1 X5*85").to[0], Some(5.0));
    assert_eq!(mv("g1 x10 y2").to, [Some(10.0), Some(2.0), None]);
    assert_eq!(mv("G1 X1.2.3").to[0], Some(1.2));
    assert_eq!(mv("G1 X-.").to[0], Some(0.0));
    assert_eq!(mv("G1 X").to[0], None);
    assert_eq!(mv("G1 X 7").to[0], Some(7.0));
    // a comment ends the code
    assert_eq!(mv("G1 X1 ; Y9").to, [Some(1.0), None, None]);
}

#[test]
fn klipper_reads_as_gcode_py_does() {
    let k = Flavor::Klipper;
    assert_eq!(one(k, "M104 S200 S255"), [nozzle(255.0, false)]);
    assert_eq!(one(k, "M 104 S200"), [nozzle(200.0, false)]);
    // a subcode is a command of its own, which stock Klipper does not know
    assert_eq!(one(k, "M104.1 S300"), [Command::Other("M104.1".into())]);
    // a value with a quote in it is no number: the command fails
    let e = read(k, "G1 X100 \"Y5000\"").unwrap_err();
    assert!(e.contains("100 \""), "{e}");
    // extended commands: the last word counts, quotes removed
    let t = one(
        k,
        "SET_HEATER_TEMPERATURE HEATER=heater_bed TARGET=60 TARGET=70",
    );
    assert_eq!(
        t,
        [Command::Set(Setting::Temperature {
            heater: Heater::Bed,
            celsius: 70.0,
            wait: false
        })]
    );
    let v = one(k, "SET_VELOCITY_LIMIT ACCEL=5000 SQUARE_CORNER_VELOCITY=5");
    assert_eq!(v.len(), 2, "{v:?}");
    assert_eq!(v[1], Command::Set(Setting::SquareCornerVelocity(5.0)));
    let l = lex(Grammar::Klipper, "RESPOND MSG=\"hello there\"").unwrap();
    assert_eq!(l.word("MSG"), Some("hello there"));
    // commands stock Klipper does not run have no typed meaning
    assert_eq!(one(k, "M205 X10"), [Command::Other("M205".into())]);
}

#[test]
fn reprap_reads_quotes_as_strings() {
    let r = Flavor::Reprap;
    let l = read(r, "M291 P\"Move X5 Y9\" S1").unwrap().line;
    assert!(!l.has("X") && !l.has("Y"));
    assert_eq!(l.get("P"), Some(&Value::Text("Move X5 Y9")));
    assert_eq!(one(r, "G10 P0 S205 R150").len(), 2);
    assert_eq!(one(r, "G10 L2 P1 X0"), [Command::Other("G10".into())]);
    assert_eq!(one(r, "G10"), [Command::FirmwareRetract { undo: false }]);
    // an expression RepRapFirmware evaluates at run time is no value p3dp knows
    assert!(read(r, "G1 X{move.axes[0].max}").is_err());
    // M203 and M566 are in mm/min
    assert_eq!(
        one(r, "M566 X600 Y600"),
        [Command::Set(Setting::Jerk(10.0))]
    );
}

#[test]
fn unreadable_lines_are_errors_never_panics() {
    for l in [
        "é G1 X5",
        "G1 X５",
        "M104 S２００",
        "\u{2028}",
        "G1 X1 ; é is fine in a comment",
    ] {
        for f in Flavor::ALL {
            let _ = read(f, l);
        }
    }
    assert!(read(Flavor::Marlin, "é G1 X5").is_err());
    assert!(read(Flavor::Klipper, "G1 X５").is_err());
    assert!(read(Flavor::Marlin, "G1 X1 ; é").is_ok());
    assert!(read(Flavor::Marlin, &"G1 X1 ".repeat(2000)).is_err());
    // every firmware skips one line number; after it, `N90` is a command
    // none has, which no written line reads back as (found by the fuzzer)
    for f in Flavor::ALL {
        let e = read(f, "N10  N90 M1G").unwrap_err();
        assert!(e.contains("second line number"), "{f:?}: {e}");
        assert_eq!(one(f, "N10 M400").len(), 1, "{f:?}");
    }
    // Klipper's line number is an `N` and whatever follows it up to the
    // next letters (found by the fuzzer: `N 11 08NG` is the command `NG`)
    let k = Flavor::Klipper;
    assert_eq!(one(k, "N 11 08G4 P5").len(), 1);
    assert_eq!(one(k, "N 11 08NG"), [Command::Other("NG".into())]);
    assert!(read(k, "N 1 N 2 G1 X5").is_err());
    assert!(one(k, "N 7").is_empty());
}

/// The settings a calibration writes, each flavour.
fn settings() -> Vec<Setting> {
    vec![
        Setting::Temperature {
            heater: Heater::Nozzle(0),
            celsius: 215.0,
            wait: false,
        },
        Setting::Temperature {
            heater: Heater::Bed,
            celsius: 60.0,
            wait: true,
        },
        Setting::Fan { speed: 0.6 },
        Setting::PressureAdvance { k: 0.045 },
        Setting::Acceleration {
            print: Some(3000.0),
            travel: Some(3000.0),
            retract: None,
        },
        Setting::SpeedLimit { velocity: 250.0 },
        Setting::SquareCornerVelocity(7.5),
        Setting::JunctionDeviation(0.02),
        Setting::Jerk(8.0),
        Setting::MinimumCruiseRatio(0.25),
        Setting::InputShaper {
            frequency: [Some(45.0), Some(45.0)],
            damping: Some(0.1),
            kind: None,
        },
        Setting::Flow(0.95),
        Setting::Speed(0.8),
        Setting::Retraction {
            length: Some(0.8),
            speed: Some(35.0),
        },
    ]
}

#[test]
fn every_setting_written_reads_back_as_itself() {
    for flavor in Flavor::ALL {
        let d = Dialect::of(flavor);
        for s in settings() {
            let c = Command::Set(s);
            if write::refusal(d, &c).is_some() {
                continue;
            }
            let mut out = Chunk::new();
            write(d, &c, "", &mut out);
            let text = String::from_utf8(out.bytes().to_vec()).unwrap();
            let mut got = Vec::new();
            for line in text.lines() {
                got.extend(one(flavor, line));
            }
            // Klipper waits with a second command, read as Other
            got.retain(|c| !matches!(c, Command::Other(_)));
            let want = match (flavor, s) {
                // RepRapFirmware's M116 waits on its own line
                (
                    Flavor::Klipper | Flavor::Reprap,
                    Setting::Temperature {
                        heater,
                        celsius,
                        wait: true,
                    },
                ) => Setting::Temperature {
                    heater,
                    celsius,
                    wait: false,
                },
                // Marlin's speed limit is its X and Y feed limits
                (f, Setting::SpeedLimit { velocity }) if f != Flavor::Klipper => {
                    Setting::MaxFeedrate {
                        axes: [Some(velocity), Some(velocity), None, None],
                    }
                }
                _ => s,
            };
            assert_eq!(got, [Command::Set(want)], "{flavor:?}: {text}");
        }
    }
}

#[test]
fn a_flavour_without_the_command_refuses_the_setting_by_name() {
    let c = Command::Set(Setting::SquareCornerVelocity(5.0));
    let why = write::refusal(Dialect::of(Flavor::Marlin), &c).unwrap();
    assert!(
        why.contains("Marlin") && why.contains("square-corner"),
        "{why}"
    );
    let c = Command::Set(Setting::JunctionDeviation(0.02));
    assert!(write::refusal(Dialect::of(Flavor::Klipper), &c).is_some());
    let c = Command::Set(Setting::InputShaper {
        frequency: [Some(40.0), None],
        damping: None,
        kind: Some(Shaper::Mzv),
    });
    assert!(write::refusal(Dialect::of(Flavor::Marlin), &c).is_some());
    assert!(write::refusal(Dialect::of(Flavor::Klipper), &c).is_none());
}

fn text(flavor: Flavor, c: &Command) -> String {
    let mut out = Chunk::new();
    write(Dialect::of(flavor), c, "", &mut out);
    String::from_utf8(out.bytes().to_vec())
        .unwrap()
        .trim_end()
        .to_string()
}

#[test]
fn dialects_heat_pause_and_fan_their_own_way() {
    let first = |f| {
        text(f, &Command::Pause)
            .split(' ')
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(first(Flavor::Marlin), "M0");
    assert_eq!(first(Flavor::Prusa), "M601");
    assert_eq!(first(Flavor::Klipper), "PAUSE");
    assert_eq!(first(Flavor::Reprap), "M226");
    assert_eq!(
        text(Flavor::Marlin, &Command::Dwell { ms: 250.4 }),
        "G4 P250 ; dwell"
    );
    let wait = nozzle(215.0, true);
    assert_eq!(
        text(Flavor::Marlin, &wait),
        "M109 S215 ; nozzle temperature"
    );
    assert_eq!(
        text(Flavor::Klipper, &wait),
        "SET_HEATER_TEMPERATURE HEATER=extruder TARGET=215 ; nozzle temperature\n\
         TEMPERATURE_WAIT SENSOR=extruder MINIMUM=215 ; wait for the nozzle"
    );
    assert_eq!(
        text(Flavor::Reprap, &wait),
        "M104 S215 ; nozzle temperature\nM116 P0 ; wait for the nozzle"
    );
    // switching off is never waited for
    let off = Command::Set(Setting::Temperature {
        heater: Heater::Bed,
        celsius: 0.0,
        wait: true,
    });
    assert_eq!(
        text(Flavor::Klipper, &off),
        "SET_HEATER_TEMPERATURE HEATER=heater_bed TARGET=0 ; bed temperature"
    );
    let fan = |f, s| text(f, &Command::Set(Setting::Fan { speed: s }));
    assert_eq!(fan(Flavor::Marlin, 0.5), "M106 S128 ; fan");
    assert_eq!(fan(Flavor::Klipper, 0.0), "M107 ; fan off");
    assert_eq!(fan(Flavor::Reprap, 0.5), "M106 S0.50 ; fan");
    assert_eq!(fan(Flavor::Reprap, 0.001), "M106 S0 ; fan off");
    assert_eq!(fan(Flavor::Bambu, 1.0), "M106 P1 S255 ; fan");
}

#[test]
fn moves_are_fixed_point_and_round_once() {
    let m = Command::Move(Move {
        travel: false,
        to: [Some(110.0), Some(-0.0004), None],
        e: Some(0.012345),
        feed: Some(1800.0),
    });
    assert_eq!(
        text(Flavor::Marlin, &m),
        "G1 X110.000 Y0.000 E0.01235 F1800"
    );
    // the state follows relative E and the position
    let mut st = State::new(Flavor::Marlin);
    st.apply(&Command::RelativeE(true));
    st.apply(&m);
    let Motion::Line { de, to, .. } = st.apply(&m) else {
        panic!()
    };
    assert_eq!(de, 0.012345);
    assert_eq!(to[0], Some(110.0));
    // Marlin's G90 makes E absolute again; Klipper's leaves M83 in force
    st.apply(&Command::RelativeXyz(false));
    assert!(!st.e_relative());
    let mut k = State::new(Flavor::Klipper);
    k.apply(&Command::RelativeE(true));
    k.apply(&Command::RelativeXyz(false));
    assert!(k.e_relative());
}

#[test]
fn klipper_object_labels_read_back_as_written() {
    use crate::base::gcode::Object;
    let d = Dialect {
        flavor: Flavor::Klipper,
        object_labels: true,
        prusa_8bit: false,
    };
    // without a NAME Klipper ends the current object: written the same way
    // (found by the fuzzer: it was written `NAME=` and nothing)
    for line in ["EXCLUDE_OBJECT_END", "EXCLUDE_OBJECT_END NAME=cup_1"] {
        let read_once = one(Flavor::Klipper, line);
        let mut chunk = Chunk::new();
        write(d, &read_once[0], "", &mut chunk);
        let text = std::str::from_utf8(chunk.bytes()).unwrap();
        let again: Vec<Command> = text.lines().flat_map(|l| one(Flavor::Klipper, l)).collect();
        assert_eq!(again, read_once, "{line} → {text:?}");
    }
    assert_eq!(
        one(Flavor::Klipper, "EXCLUDE_OBJECT_END"),
        [Command::Object(Object::End(String::new()))]
    );
}
