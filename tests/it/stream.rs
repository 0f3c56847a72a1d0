//! The typed command stream, end to end: what a profile's start G-code
//! sets (`M204`, `M201`, `M221`) changes the estimate and the figures as
//! the firmware would, and the G-code p3dp writes reads back, through the
//! firmware's own reading, as the moves the report counts.

use crate::common::{p3dp, recipe, tmp};

/// A printer on top of generic-220: its kinematics and its start G-code.
fn printer(dir: &std::path::Path, name: &str, kinematics: &str, start_extra: &str) -> String {
    let start = format!(
        "G90\n  M140 S{{bed_temp}}\n  M104 S{{nozzle_temp}}\n  G28\n  M190 S{{bed_temp}}\n  M109 S{{nozzle_temp}}\n  {start_extra}\n"
    );
    let text = format!(
        "inherits: generic-220\nname: {name}\nkinematics: {kinematics}\nstart_gcode: |\n  {start}"
    );
    let file = format!("{name}.yaml");
    std::fs::write(dir.join(&file), text).unwrap();
    file
}

/// `p3dp build sphere --printer FILE`'s stats.
fn stats(dir: &std::path::Path, printer: &str) -> serde_json::Value {
    let sphere = recipe("sphere.yaml");
    let out = dir.join(format!("{printer}.gcode"));
    let json = dir.join(format!("{printer}.json"));
    let o = p3dp(
        dir,
        &[
            "build",
            sphere.to_str().unwrap(),
            "--printer",
            printer,
            "-o",
            out.to_str().unwrap(),
            "--stats-json",
            json.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

fn f(v: &serde_json::Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("{key} in {v}"))
}

#[test]
fn accelerations_a_start_gcode_sets_are_the_estimates() {
    let dir = tmp("stream-accel");
    // the profile allows 3000 mm/s², the start G-code asks for 600 (print)
    // and 900 (travel): the firmware plans with those
    let asked = printer(
        &dir,
        "asked",
        "{max_acceleration: 3000, travel_acceleration: 3000}",
        "M204 P600 T900",
    );
    let profile = printer(
        &dir,
        "profile",
        "{max_acceleration: 600, travel_acceleration: 900}",
        "",
    );
    let fast = printer(
        &dir,
        "fast",
        "{max_acceleration: 3000, travel_acceleration: 3000}",
        "",
    );
    let (a, p, q) = (
        stats(&dir, &asked),
        stats(&dir, &profile),
        stats(&dir, &fast),
    );
    let (ta, tp, tq) = (
        f(&a, "print_time_s"),
        f(&p, "print_time_s"),
        f(&q, "print_time_s"),
    );
    assert!((ta - tp).abs() <= 1e-9 * tp, "{ta} vs {tp}");
    assert!(tq < tp, "3000 mm/s² is faster: {tq} vs {tp}");
    // M201 X Y caps M204's accelerations of the head as Marlin does (a
    // retraction, a move of E alone, is held by M201 E, not by X and Y)
    let capped = printer(
        &dir,
        "capped",
        "{max_acceleration: 3000, travel_acceleration: 3000, retract_acceleration: 600}",
        "M201 X600 Y800\n  M204 P2000 T900",
    );
    let profile2 = printer(
        &dir,
        "profile2",
        "{max_acceleration: 600, travel_acceleration: 600, retract_acceleration: 600}",
        "",
    );
    let (c, p2) = (stats(&dir, &capped), stats(&dir, &profile2));
    let (tc, tp2) = (f(&c, "print_time_s"), f(&p2, "print_time_s"));
    assert!((tc - tp2).abs() <= 1e-9 * tp2, "{tc} vs {tp2}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_flow_factor_in_the_start_gcode_scales_the_filament() {
    let dir = tmp("stream-flow");
    let k = "{max_acceleration: 1000}";
    let (a, b) = (
        stats(&dir, &printer(&dir, "m221", k, "M221 S95")),
        stats(&dir, &printer(&dir, "plain", k, "")),
    );
    for key in [
        "filament_length_mm",
        "filament_volume_mm3",
        "filament_mass_g",
    ] {
        let (x, y) = (f(&a, key), f(&b, key));
        assert!((x - 0.95 * y).abs() <= 1e-9 * y, "{key}: {x} vs 0.95 × {y}");
    }
    // the moves are the same: only what the firmware feeds differs
    assert_eq!(a["extrude_moves"], b["extrude_moves"]);
    std::fs::remove_dir_all(&dir).unwrap();
}
