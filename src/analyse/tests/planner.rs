//! The print-time estimate on real recipes, planned again from the G-code:
//! the planner sees exactly the moves written, and it shows that the globe's
//! short strings do not run at full speed on a Marlin printer.
//!
//! Past the public face: the planner itself (`analyse::planner::{Planner,
//! MoveKind, Estimate}`), `Printer::limits`, and `base::format::hms` for the
//! times the report prints. Home: beside `analyse::planner`.

use crate::analyse::planner::{MoveKind, Planner};
use crate::base::testing::*;
use crate::machine::Printer;
use glam::DVec3;

/// Plans the moves of written G-code again, read back as a firmware reads
/// them (up to the end G-code, which the estimate leaves out).
fn replan(gcode: &str, printer: &Printer) -> crate::analyse::planner::Estimate {
    let first_end_line = printer.end_gcode.lines().next().unwrap();
    let body = &gcode[..gcode.find(first_end_line).unwrap()];
    let g = parse(body);
    let mut p = Planner::new(printer.limits());
    let mut part = 0;
    for m in &g.moves {
        if m.part != part {
            part = m.part;
            p.begin_part(&g.parts[part]);
        }
        let kind = if m.g == 0 {
            MoveKind::Travel
        } else {
            MoveKind::Extrude
        };
        p.move_to(DVec3::from_array(m.to), m.de.abs(), m.f / 60.0, kind);
    }
    p.finish()
}

fn close(got: f64, want: f64, rel: f64) {
    assert!(((got - want) / want).abs() <= rel, "got {got}, want {want}");
}

#[test]
fn globe_estimate_is_the_written_moves_planned() {
    let (gcode, s) = build("globe.yaml", None);
    let printer = crate::recipe::profile::built_in("generic-220").unwrap();
    let again = replan(&gcode, &printer);
    close(again.total.planned, s.print_time_s, 1e-9);
    close(again.total.ideal, s.print_time_ideal_s, 1e-9);
    assert_eq!(again.parts.len(), s.parts.len());
    for (a, b) in again.parts.iter().zip(&s.parts) {
        assert_eq!(a.name, b.name);
        close(a.times.planned, b.print_time_s, 1e-9);
    }
    // parts add up to the print
    let sum: f64 = s.parts.iter().map(|p| p.print_time_s).sum();
    close(sum, s.print_time_s, 1e-12);
    // the globe's short strings are slower than distance / speed (its
    // moves of about 15 ms keep Marlin's buffer full: no slowdown for the
    // minimum segment time, see the planner's unit tests)
    assert!(s.print_time_s > s.print_time_ideal_s, "{s:?}");
    assert!(s.time_lost_to_acceleration_s > 0.0);
    assert!(s.time_lost_to_speed_limits_s > 0.0);
    close(
        s.print_time_ideal_s + s.time_lost_to_acceleration_s + s.time_lost_to_speed_limits_s,
        s.print_time_s,
        1e-12,
    );
    // the summary comments carry the estimate, per part too
    let hms = crate::base::format::hms;
    assert!(gcode.contains(&format!(
        "; estimated printing time = {}\n",
        hms(s.print_time_s)
    )));
    for p in &s.parts {
        assert!(gcode.contains(&format!(
            "; estimated time part {} = {}\n",
            p.name,
            hms(p.print_time_s)
        )));
    }
    assert!(gcode.contains("; planner: junction deviation 0.013 mm"));
    // the JSON names the limits used
    let json = serde_json::to_value(&s).unwrap();
    let planner = &json["planner"];
    assert_eq!(planner["junction_deviation"], 0.013);
    assert_eq!(planner["max_acceleration"], 1000.0);
    assert_eq!(planner["min_segment_time"], 0.02);
    assert!(planner["max_velocity"].as_f64().unwrap() > 0.0);
    assert!(planner.get("square_corner_velocity").is_none());
    assert!(json["parts"][1]["time_lost_s"].as_f64().unwrap() > 0.0);
}

#[test]
fn klipper_profile_uses_square_corner_velocity() {
    let dir = tmp("planner-klipper");
    let text =
        std::fs::read_to_string(root().join("src/machine/printers/generic-220.yaml")).unwrap();
    let start = text.find("kinematics:").unwrap();
    let end = start + text[start..].find("start_gcode:").unwrap();
    let klipper = format!(
        "{}kinematics:\n  max_velocity: 300\n  max_acceleration: 3000\n  square_corner_velocity: 5\n{}",
        &text[..start],
        &text[end..]
    );
    let path = dir.join("k.yaml");
    std::fs::write(&path, klipper).unwrap();
    let (gcode, s) = build("cup.yaml", Some(path.to_str().unwrap()));
    let json = serde_json::to_value(&s).unwrap();
    assert_eq!(json["planner"]["square_corner_velocity"], 5.0);
    assert!(json["planner"].get("junction_deviation").is_none());
    assert_eq!(json["planner"]["minimum_cruise_ratio"], 0.5);
    assert_eq!(json["planner"]["min_segment_time"], 0.0);
    let printer = crate::recipe::profile::from_file(&path).unwrap();
    close(replan(&gcode, &printer).total.planned, s.print_time_s, 1e-9);
    assert!(s.print_time_s >= s.print_time_ideal_s);
    // a bad value is named
    std::fs::write(
        &path,
        std::fs::read_to_string(&path)
            .unwrap()
            .replace("max_acceleration: 3000", "max_acceleration: -3"),
    )
    .unwrap();
    let e = crate::recipe::profile::from_file(&path)
        .unwrap_err()
        .to_string();
    assert!(e.contains("kinematics.max_acceleration"), "{e}");
}

fn build(recipe_name: &str, printer: Option<&str>) -> (String, crate::analyse::stats::Stats) {
    let opts = crate::app::prepare::Options {
        printer: printer.map(str::to_string),
        ..Default::default()
    };
    let mut plan = crate::app::prepare::plan(&recipe(recipe_name), &opts).unwrap();
    let mut out = Vec::new();
    let job = crate::app::pipeline::Job {
        hash: true,
        ..Default::default()
    };
    let stats = crate::app::pipeline::write(&mut plan, &job, &mut out)
        .unwrap()
        .stats;
    (String::from_utf8(out).unwrap(), stats)
}
