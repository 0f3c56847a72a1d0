//! A turtle's and a path's `set` command and `{expr}` in raw `gcode`
//! (issue 40), built as a user builds them and read back through the
//! firmware's own reader: one setting per line at the line's first
//! extruding move in every flavour, the same G-code and stats as a `set`
//! step, refusals naming the command's key path.
//!
//! Home: beside `recipe::resolve::turtle` (the commands' compilation) and
//! `base::gcode::named` (the lowering a step and a command share).

use crate::app::testing::{p3dp, FLAVOURS};
use crate::base::gcode::{Command, Setting};
use crate::base::testing::{root, tmp};
use crate::machine::firmware::read;

/// Lines of a pressure advance test as one turtle: line k travels to its
/// start, sets its factor and acceleration from `k` (band k: its line),
/// then prints slow, fast, slow.
const LINES: &str = "p3dp: 1
name: lines
printer: generic-220
material: pla
params: {lines: 5}
defaults: {cross_section: 0.08}
parts:
  - name: lines
    primitive:
      turtle:
        program:
          - for: {k: \"0..lines - 1\"}
            do:
              - pen_up
              - {goto: [-30, \"k*4 - 8\", 0.2]}
              - pen_down
              - {set: {band: k, pressure_advance: \"0.005 + 0.0075*k\", acceleration: \"600 + 50*k\"}}
              - {speed: 20}
              - {forward: 15}
              - {speed: 80}
              - {forward: 30}
              - {speed: 20}
              - {forward: 15}
";

/// `p3dp build FILE --printer P -o out.gcode --stats-json stats.json` in
/// `dir`: the G-code, or the errors.
fn build(dir: &std::path::Path, file: &str, printer: &str) -> Result<String, String> {
    let printer = if printer.ends_with(".yaml") {
        root().join(printer).display().to_string()
    } else {
        printer.to_string()
    };
    let args = [
        "build",
        file,
        "--printer",
        &printer,
        "-o",
        "out.gcode",
        "--stats-json",
        "stats.json",
    ];
    let out = p3dp(dir, &args);
    if !out.success() {
        return Err(out.stderr);
    }
    Ok(std::fs::read_to_string(dir.join("out.gcode")).unwrap())
}

/// Every flavour: read back, each line's pressure advance and acceleration
/// come once each, before the line's first extruding move and after the
/// line before it, with line k's values; the stats' and the report's bands
/// are the lines (`line: k`), each the factor read back.
#[test]
fn one_setting_per_line_at_its_first_extruding_move_in_every_flavour() {
    for (printer, flavor) in FLAVOURS {
        let dir = tmp(&format!("turtle-set-{flavor:?}"));
        std::fs::write(dir.join("lines.yaml"), LINES).unwrap();
        let gcode = build(&dir, "lines.yaml", printer).unwrap_or_else(|e| panic!("{e}"));
        // (line's pressure advance, its acceleration), as each line's
        // first extruding move finds them pending
        let mut seen: Vec<(Option<f64>, Option<f64>)> = Vec::new();
        let mut pending: (Option<f64>, Option<f64>) = (None, None);
        let mut in_part = false;
        for line in gcode.lines() {
            in_part |= line.starts_with("; part: ");
            if !in_part {
                continue;
            }
            for c in read(flavor, line).unwrap().commands {
                match c {
                    Command::Set(Setting::PressureAdvance { k }) => {
                        assert!(pending.0.is_none(), "{flavor:?}: two factors: {line}");
                        pending.0 = Some(k);
                    }
                    Command::Set(Setting::Acceleration { print: Some(a), .. }) => {
                        assert!(pending.1.is_none(), "{flavor:?}: two accelerations: {line}");
                        pending.1 = Some(a);
                    }
                    Command::Move(m)
                        if m.e.is_some_and(|e| e > 0.0)
                            && m.to[0].is_some()
                            && pending != (None, None) =>
                    {
                        // the line's first extruding move
                        seen.push(pending);
                        pending = (None, None);
                    }
                    _ => {}
                }
            }
        }
        let want: Vec<(Option<f64>, Option<f64>)> = (0..5)
            .map(|k| {
                let k = f64::from(k);
                (Some(0.005 + 0.0075 * k), Some(600.0 + 50.0 * k))
            })
            .collect();
        assert_eq!(seen.len(), want.len(), "{flavor:?}: {seen:?}");
        for (got, want) in seen.iter().zip(&want) {
            // written to the writer's decimals (4 for a factor)
            assert!(
                (got.0.unwrap() - want.0.unwrap()).abs() < 6e-5,
                "{flavor:?}: {got:?}"
            );
            assert_eq!(got.1, want.1, "{flavor:?}");
        }
        assert_eq!(
            pending,
            (None, None),
            "{flavor:?}: a setting after the last line"
        );
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("stats.json")).unwrap())
                .unwrap();
        let bands = stats["bands"].as_array().unwrap();
        assert_eq!(bands.len(), seen.len(), "{flavor:?}: {bands:?}");
        for (i, (b, got)) in bands.iter().zip(&seen).enumerate() {
            assert_eq!(b["index"].as_u64(), Some(i as u64));
            assert_eq!(b["line"].as_u64(), Some(i as u64));
            assert_eq!(b["part"], "lines");
            assert!(b.get("z_from").is_none(), "{b}");
            let value = b["value"].as_f64().unwrap();
            assert!((value - got.0.unwrap()).abs() < 6e-5, "{flavor:?}: {b}");
        }
        assert_eq!(gcode.matches(" ; band ").count(), 5, "{flavor:?}");
    }
}

/// A turtle's `set` at its start and a `set` step without bands (written
/// before the part's first extruding string, the same place) give the same
/// bytes and the same estimate and filament: the stream, the planner and
/// the stats follow both alike (the flow factor shrinks the filament, the
/// acceleration stretches the time).
#[test]
fn a_set_command_is_followed_as_a_set_step_is() {
    let body = |set_cmd: &str, step: &str| {
        format!(
            "p3dp: 1
name: square
printer: generic-220
material: pla
parts:
  - name: square
    primitive:
      turtle:
        start: {{position: [-20, -20, 0.2]}}
        program:
{set_cmd}          - repeat: 12
            do: [{{forward: 40}}, {{left: 90}}, {{lift: 0.05}}]
{step}"
        )
    };
    let settings = "{acceleration: 300, flow: 0.9, pressure_advance: 0.04}";
    let dir = tmp("turtle-set-as-step");
    let command = body(&format!("          - {{set: {settings}}}\n"), "");
    let step = body("", &format!("    steps:\n      - set: {settings}\n"));
    let plain = body("", "");
    let mut out = Vec::new();
    for (name, text) in [("command", &command), ("step", &step), ("plain", &plain)] {
        std::fs::write(dir.join("square.yaml"), text).unwrap();
        let gcode = build(&dir, "square.yaml", "generic-220").unwrap_or_else(|e| panic!("{e}"));
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("stats.json")).unwrap())
                .unwrap();
        out.push((name, gcode, stats));
    }
    let (command, step, plain) = (&out[0], &out[1], &out[2]);
    assert_eq!(command.1, step.1, "the command's G-code is the step's");
    assert_eq!(command.2, step.2, "the command's stats are the step's");
    let num =
        |s: &serde_json::Value, k: &str| s[k].as_f64().unwrap_or_else(|| panic!("{k} in {s:#}"));
    assert!(num(&command.2, "print_time_s") > num(&plain.2, "print_time_s") + 1.0);
    let ratio = num(&command.2, "filament_length_mm") / num(&plain.2, "filament_length_mm");
    assert!((ratio - 0.9).abs() < 1e-3, "{ratio}");
}

/// A setting the printer's firmware has no command for, and a value past
/// its limits: the `setting` check refuses the build (status 1, nothing
/// written), naming the command's key path, in a turtle and in a path.
#[test]
fn a_refused_setting_names_the_commands_key_path() {
    let dir = tmp("turtle-set-refused");
    let turtle = "p3dp: 1
name: t
printer: generic-220
material: pla
parts:
  - name: lines
    primitive:
      turtle:
        program:
          - for: {k: \"0..1\"}
            do:
              - {forward: 10}
              - {set: {square_corner_velocity: \"5 + k\"}}
              - {forward: 10}
";
    std::fs::write(dir.join("t.yaml"), turtle).unwrap();
    let e = build(&dir, "t.yaml", "generic-220").unwrap_err();
    assert!(e.contains("[setting]"), "{e}");
    assert!(
        e.contains("`parts[0].primitive.turtle.program[0].do[1].set.square_corner_velocity`"),
        "{e}"
    );
    assert!(e.contains("has 2 settings") && e.contains("Marlin"), "{e}");
    assert!(!dir.join("out.gcode").exists());
    // Klipper has that command: the same recipe builds there
    build(&dir, "t.yaml", "voron-350").unwrap_or_else(|e| panic!("{e}"));
    let path = "p3dp: 1
name: p
printer: generic-220
material: pla
parts:
  - name: a
    primitive: {path: [{move: [0, 0, 0.2]}, {draw: [10, 0, 0.2]}]}
  - name: b
    primitive:
      - path: [{move: [0, 5, 0.2]}, {draw: [10, 5, 0.2]}]
      - path:
          - {set: {fan: 0.5, acceleration: 900, travel_acceleration: 50000}}
          - {move: [0, 10, 0.2]}
          - {draw: [10, 10, 0.2]}
";
    std::fs::write(dir.join("p.yaml"), path).unwrap();
    let e = build(&dir, "p.yaml", "generic-220").unwrap_err();
    assert!(
        e.contains("`parts[1].primitive[1].path[0].set.acceleration`"),
        "{e}"
    );
    assert!(e.contains("50000"), "{e}");
}

/// `gcode_at` takes `{expr}` over the params, and its line is checked as
/// made: a temperature past the material's limit is refused at the key,
/// as the literal line is.
#[test]
fn gcode_at_takes_values_and_checks_the_line_made() {
    let dir = tmp("gcode-at-expr");
    let recipe = |line: &str| {
        format!(
            "p3dp: 1
name: g
printer: generic-220
material: pla
params: {{hot: 215, colour: 2}}
parts:
  - name: wall
    primitive:
      turtle:
        start: {{position: [-10, -10, 0.2]}}
        program: [{{repeat: 60, do: [{{forward: 20}}, {{left: 90}}, {{lift: 0.05}}]}}]
    steps:
      - gcode_at: {{z: 1.5, gcode: \"{line}\"}}
"
        )
    };
    std::fs::write(
        dir.join("g.yaml"),
        recipe("M104 S{hot + 5} ; colour {colour}"),
    )
    .unwrap();
    let gcode = build(&dir, "g.yaml", "generic-220").unwrap_or_else(|e| panic!("{e}"));
    let made: Vec<&str> = gcode
        .lines()
        .filter(|l| l.starts_with("M104 S220"))
        .collect();
    assert_eq!(made, ["M104 S220 ; colour 2"]);
    std::fs::write(dir.join("g.yaml"), recipe("M104 S{hot + 100}")).unwrap();
    let made = build(&dir, "g.yaml", "generic-220").unwrap_err();
    std::fs::write(dir.join("g.yaml"), recipe("M104 S315")).unwrap();
    let literal = build(&dir, "g.yaml", "generic-220").unwrap_err();
    for e in [&made, &literal] {
        assert!(e.contains("parts[0].steps[0].gcode_at.gcode"), "{e}");
        assert!(e.contains("315 °C, above the limit"), "{e}");
    }
    assert!(made.contains("the line `M104 S315` made here"), "{made}");
}
