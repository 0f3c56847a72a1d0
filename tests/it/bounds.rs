//! What the G-code may do is bounded whatever the recipe asks (issue 33):
//! fitted arcs stay on the bed over their whole sweep, the turtle's
//! extrusion in place keeps to the machine's feed.

use crate::common::*;

/// An 18-gon of radius 20 round (`cx`, 0), its corners half a step off the
/// axes: an arc through them bulges 0.30 mm past the corners, to x = cx + 20.
fn polygon(cx: f64) -> String {
    use std::f64::consts::PI;
    let mut cmds = Vec::new();
    for k in 0..=18 {
        let a = PI / 18.0 + k as f64 * PI / 9.0;
        let (x, y) = (cx + 20.0 * a.cos(), 20.0 * a.sin());
        let verb = if k == 0 { "move" } else { "draw" };
        cmds.push(format!("{{{verb}: [{x:.6}, {y:.6}, 0.2]}}"));
    }
    format!(
        "p3dp: 1\nname: edge\nprinter: p.yaml\nmaterial: pla\nallow: [first-layer]\nparts:\n  - name: gon\n    primitive: {{path: {{commands: [{}]}}}}\n",
        cmds.join(", ")
    )
}

/// The largest x an arc of `g` reaches on its sweep (sampled finely).
fn arc_max_x(g: &Gcode) -> (usize, f64) {
    let mut n = 0;
    let mut most = f64::MIN;
    for m in g.moves.iter().filter(|m| m.g == 2 || m.g == 3) {
        n += 1;
        let c = [m.from[0] + m.ij[0], m.from[1] + m.ij[1]];
        let r = (m.from[0] - c[0]).hypot(m.from[1] - c[1]);
        let a0 = (m.from[1] - c[1]).atan2(m.from[0] - c[0]);
        let a1 = (m.to[1] - c[1]).atan2(m.to[0] - c[0]);
        let tau = std::f64::consts::TAU;
        let sweep = if m.g == 3 {
            (a1 - a0).rem_euclid(tau)
        } else {
            -(a0 - a1).rem_euclid(tau)
        };
        for i in 0..=1000 {
            let a = a0 + sweep * i as f64 / 1000.0;
            most = most.max(c[0] + r * a.cos());
        }
    }
    (n, most)
}

#[test]
fn a_fitted_arc_never_leaves_the_bed_on_its_sweep() {
    let dir = tmp("bounds-arc");
    let profile = "inherits: generic-220\nname: arcs\narcs: true\narc_tolerance: 0.5\n";
    std::fs::write(dir.join("p.yaml"), profile).unwrap();
    // in the middle of the bed the 18-gon is written as arcs
    std::fs::write(dir.join("r.yaml"), polygon(0.0)).unwrap();
    let out = p3dp(&dir, &["build", "r.yaml", "-o", "mid.gcode"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let g = parse(&std::fs::read_to_string(dir.join("mid.gcode")).unwrap());
    let (arcs, _) = arc_max_x(&g);
    assert!(arcs > 0, "the 18-gon makes arcs");
    // at the edge its corners are on the bed (x ≤ 220) but an arc's sweep
    // would reach 220.2: those strings stay lines
    std::fs::write(dir.join("r.yaml"), polygon(90.2)).unwrap();
    let out = p3dp(&dir, &["build", "r.yaml", "-o", "edge.gcode"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let g = parse(&std::fs::read_to_string(dir.join("edge.gcode")).unwrap());
    let (arcs, most) = arc_max_x(&g);
    assert!(arcs > 0, "the arcs away from the edge stay");
    assert!(most <= 220.0 + 1e-6, "an arc reaches x = {most}");
    let line_max = g.moves.iter().map(|m| m.to[0]).fold(f64::MIN, f64::max);
    assert!(line_max <= 220.0, "{line_max}");
    // and a tolerance past the ceiling is refused, naming the key
    let profile = "inherits: generic-220\nname: arcs\narcs: true\narc_tolerance: 1\n";
    std::fs::write(dir.join("p.yaml"), profile).unwrap();
    let out = p3dp(&dir, &["check", "r.yaml"]);
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{e}");
    assert!(
        e.contains("arc_tolerance") && e.contains("at most 0.5"),
        "{e}"
    );
}

/// The turtle recipe extruding 2 mm in place at `feed` mm/s.
fn turtle_feed(feed: &str) -> String {
    format!(
        "p3dp: 1\nname: feed\nprinter: generic-220\nmaterial: pla\nallow: [first-layer, flow]\nparts:\n  - primitive:\n      turtle:\n        start: {{position: [0, 0, 0.2]}}\n        program: [{{forward: 10}}, {{extrude: 2, feed: {feed}}}, {{forward: 10}}]\n"
    )
}

#[test]
fn the_turtles_extrusion_in_place_keeps_to_the_machines_feed() {
    let dir = tmp("bounds-feed");
    for feed in ["1000000000", "2001"] {
        std::fs::write(dir.join("r.yaml"), turtle_feed(feed)).unwrap();
        let out = p3dp(&dir, &["build", "r.yaml", "-o", "r.gcode"]);
        let e = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{feed}: {e}");
        assert!(
            e.contains(".feed") && e.contains("at most 2000"),
            "{feed}: {e}"
        );
        assert!(!dir.join("r.gcode").exists());
    }
    // under the bound, past the machine's: written at the machine's speed
    // (generic-220: max_speed 200 mm/s, no extrude-only limit of its own);
    // its flow past the hot end's is an error `allow` leaves one: --force
    // writes the G-code whose feed is looked at here
    std::fs::write(dir.join("r.yaml"), turtle_feed("1999")).unwrap();
    let out = p3dp(&dir, &["build", "r.yaml", "-o", "r.gcode", "--force"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("r.gcode")).unwrap();
    let line = text
        .lines()
        .find(|l| l.ends_with("; extrude in place"))
        .unwrap();
    let f: f64 = line
        .split_whitespace()
        .find_map(|w| w.strip_prefix('F'))
        .unwrap()
        .parse()
        .unwrap();
    assert!(f <= 200.0 * 60.0, "{line}");
}

#[test]
fn a_for_over_many_names_is_refused_before_it_allocates() {
    let dir = tmp("bounds-for");
    let part = |names: usize| {
        let loops: Vec<String> = (0..names).map(|k| format!("n{k}: \"0..9999\"")).collect();
        format!(
            "p3dp: 1\nname: many\nparts:\n  - primitive: {{circle: {{radius: 5, center: [0, 0, 0.2]}}}}\n    for: {{{}}}\n",
            loops.join(", ")
        )
    };
    for (names, says) in [
        (30_000, "more than 64"),
        (60, "more than the limit of 10000"),
    ] {
        std::fs::write(dir.join("r.yaml"), part(names)).unwrap();
        let t = std::time::Instant::now();
        let out = p3dp(&dir, &["check", "r.yaml"]);
        let e = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{names}: {e}");
        assert!(
            e.contains("parts[0].for") && e.contains(says),
            "{names}: {e}"
        );
        // 30,000 × 10,000 values would be 2.4 GB; refused at once
        assert!(t.elapsed().as_secs() < 10, "{names}: {:?}", t.elapsed());
    }
}

#[test]
fn jobs_past_the_useful_are_fine() {
    let dir = tmp("bounds-jobs");
    let r = recipe("sphere.yaml").display().to_string();
    let one = p3dp(&dir, &["hash", &r, "-j", "1"]);
    let many = p3dp(&dir, &["hash", &r, "-j", "65535"]);
    assert_eq!(
        many.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&many.stderr)
    );
    assert_eq!(one.stdout, many.stdout);
    let help = p3dp(&dir, &["build", "--help"]);
    assert!(String::from_utf8_lossy(&help.stdout).contains("at most 4 per core"));
}

#[test]
fn previews_and_meshes_of_a_model_metres_away_are_refused_at_once() {
    let dir = tmp("bounds-far");
    let helix = |r: &str| {
        format!("p3dp: 1\nname: far\nparts:\n  - primitive: {{helix: {{radius: {r}, height: 1, pitch: 0.25, segments: 72}}}}\n")
    };
    // 288 strings of radius 1e8 mm: minutes and gigabytes before
    std::fs::write(dir.join("r.yaml"), helix("1e8")).unwrap();
    for args in [
        &["preview", "r.yaml", "-o", "r.png"][..],
        &["preview", "r.yaml", "-o", "r.html"],
        &["mesh", "r.yaml", "-o", "r.stl"],
        &[
            "build",
            "r.yaml",
            "-o",
            "r.gcode",
            "--force",
            "--preview",
            "r.png",
        ],
    ] {
        let t = std::time::Instant::now();
        let out = p3dp(&dir, args);
        let e = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {e}");
        // refused by the previews' bound, or (a build) sooner by the end
        // G-code's lift checked against the travel envelope
        assert!(
            e.contains("farther than 250 mm") || e.contains("travel envelope"),
            "{args:?}: {e}"
        );
        assert!(t.elapsed().as_secs() < 5, "{args:?}: {:?}", t.elapsed());
    }
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(left.len(), 1, "only the recipe: {left:?}");
    // off the bed but near it: drawn, so the user can see where it went
    std::fs::write(dir.join("r.yaml"), helix("150")).unwrap();
    let out = p3dp(&dir, &["preview", "r.yaml", "-o", "r.png"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("r.png").exists());
}

/// A check keeps about 24 bytes a string when a part's strings are all
/// alike (a primitive's): their point, one shared cross-section and speed,
/// and the support check's path length every 64th point. It kept 56 (the
/// attributes and the path length at every point too), so the 50 million
/// strings `max_strings` allows took 2.7 GB (issue 42).
#[test]
fn a_check_of_millions_of_alike_strings_keeps_little_more_than_their_points() {
    let dir = tmp("check-memory");
    std::fs::write(
        dir.join("big.yaml"),
        "p3dp: 1\nname: big\nprinter: generic-220\nmaterial: pla\ndefaults: {cross_section: 0.08, speed: 40}\nparts:\n  - primitive: {helix: {radius: 50, height: 16, pitch: 0.02, segments: 5000, center: [0, 0, 0.2]}}\n",
    )
    .unwrap();
    let (out, peak) = p3dp_peak(&dir, &["check", "big.yaml", "-j", "2"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("big.yaml: "),
        "{text}"
    );
    // 4 million strings: their points are 96 MB; 36 bytes a string and the
    // program's own 30 MB at most (56 bytes a string made 250 MB)
    let strings = 4_000_000u64;
    assert!(peak < (strings * 36 + 30_000_000) / 1024, "peak {peak} kB");
}
