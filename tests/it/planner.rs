//! The print-time estimate on real recipes: it is deterministic, and z hops
//! are written at a feed the z axis can do. The estimate planned again from
//! the written moves is checked in `internals::planner`.

use crate::common::*;
use glam::DVec3;

pub(crate) fn build(recipe_name: &str, printer: Option<&str>) -> (String, p3dp::Stats) {
    let opts = p3dp::Options {
        printer: printer.map(str::to_string),
        ..Default::default()
    };
    let mut plan = p3dp::plan(&recipe(recipe_name), &opts).unwrap();
    let mut out = Vec::new();
    let job = p3dp::pipeline::Job {
        hash: true,
        ..Default::default()
    };
    let stats = p3dp::pipeline::write(&mut plan, &job, &mut out)
        .unwrap()
        .stats;
    (String::from_utf8(out).unwrap(), stats)
}

#[test]
fn estimate_is_deterministic() {
    let (g1, s1) = build("globe.yaml", None);
    let (g2, s2) = build("globe.yaml", None);
    assert_eq!(s1.print_time_s.to_bits(), s2.print_time_s.to_bits());
    assert_eq!(s1, s2);
    assert_eq!(g1, g2);
}

#[test]
fn z_hops_are_written_at_a_feed_the_z_axis_can_do() {
    // generic-220's Z: 5 mm/s; the olympic rings hop between rings
    for (recipe, printer, vz) in [
        ("olympic-rings.yaml", "generic-220", 5.0),
        ("olympic-rings.yaml", "voron-350", 15.0),
    ] {
        let (gcode, _) = build(recipe, Some(printer));
        let g = parse(&gcode);
        let mut hops = 0;
        for m in g.moves.iter().filter(|m| m.g == 0) {
            let dz = (m.to[2] - m.from[2]).abs();
            if dz == 0.0 || dz.is_nan() {
                continue;
            }
            let d = DVec3::from_array(m.to).distance(DVec3::from_array(m.from));
            // the Z component of the written feed
            let z_speed = m.f / 60.0 * dz / d;
            assert!(z_speed <= vz + 1e-9, "{printer}: {m:?}");
            hops += 1;
        }
        assert!(hops > 0, "{recipe} on {printer} has no Z travel");
    }
}
