//! The empty sphere of Kanada's Fig. 9, built by the real binary and read back.

use crate::common::*;
use p3dp::testing::Insides;

fn build_sphere(dir: &std::path::Path) -> String {
    let out = p3dp(
        dir,
        &[
            "build",
            recipe("sphere.yaml").to_str().unwrap(),
            "-o",
            "sphere.gcode",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::read_to_string(dir.join("sphere.gcode")).unwrap()
}

#[test]
fn every_extruding_point_lies_on_the_sphere() {
    let dir = tmp("sphere-geometry");
    let g = parse(&build_sphere(&dir));
    let part = g
        .parts
        .iter()
        .position(|p| p == "sphere")
        .expect("sphere part");
    let mut n = 0;
    let mut worst: f64 = 0.0;
    // the brim's loops lie on the bed at 0.2 mm, under the pole at 0.4
    let brim = |m: &&Move| to_recipe(m.to)[2] < 0.3;
    for m in g
        .moves
        .iter()
        .filter(|m| m.part == part && m.de > 0.0)
        .filter(|m| !brim(m))
    {
        for p in [m.from, m.to] {
            let [x, y, z] = to_recipe(p);
            // radius 25 from the formula, centre lifted by 0.4
            let d = (x * x + y * y + (z - 25.4) * (z - 25.4)).sqrt();
            worst = worst.max((d - 25.0).abs());
            n += 1;
        }
    }
    assert!(n > 20_000, "only {n} points");
    assert!(worst <= 0.05, "a point is {worst} mm off the sphere");
    // and it is a whole sphere: from the south pole at 0.4 to the north pole at 50.4
    let zs: Vec<f64> = g
        .moves
        .iter()
        .filter(|m| m.part == part && m.de > 0.0)
        .map(|m| m.to[2])
        .collect();
    let top = zs.iter().cloned().fold(f64::MIN, f64::max);
    assert!((top - 50.4).abs() < 1e-3, "top at {top}");
}

#[test]
fn summed_e_equals_c_times_l_over_filament_area() {
    // Σ c·L / (pi (d/2)²) over the strings, from the library, against the E the G-code feeds
    let plan = p3dp::plan(&recipe("sphere.yaml"), &Default::default()).unwrap();
    let area = std::f64::consts::PI * (1.75f64 / 2.0).powi(2);
    let expected: f64 = plan.paths().iter().map(|t| t.volume()).sum::<f64>() / area;
    let dir = tmp("sphere-e");
    let g = parse(&build_sphere(&dir));
    let fed: f64 = g.moves.iter().map(|m| m.de).sum();
    assert!(
        ((fed - expected) / expected).abs() < 1e-6,
        "fed {fed} mm, expected {expected} mm"
    );
    // E never runs backwards except in a retraction that is undone right away
    for (k, m) in g.moves.iter().enumerate() {
        if m.de < 0.0 {
            assert_eq!(m.g, 1);
            let undo = g.moves[k + 1..].iter().find(|n| n.de != 0.0).unwrap();
            assert!(
                (undo.de + m.de).abs() < 1e-9,
                "retraction {} not undone",
                m.de
            );
        }
    }
}

#[test]
fn numbers_are_fixed_point_and_inside_the_bed() {
    let dir = tmp("sphere-numbers");
    let text = build_sphere(&dir);
    for line in text
        .lines()
        .filter(|l| l.starts_with("G0 ") || l.starts_with("G1 "))
    {
        let code = line.split(';').next().unwrap();
        for w in code.split_whitespace().skip(1) {
            let (axis, v) = w.split_at(1);
            assert!(!v.contains(['e', 'E']), "exponent in `{line}`");
            assert!(
                !v.starts_with("-0.000") || v.trim_start_matches("-0.").chars().any(|c| c != '0'),
                "negative zero in `{line}`"
            );
            let decimals = v.split('.').nth(1).map_or(0, str::len);
            match axis {
                "X" | "Y" | "Z" => assert_eq!(decimals, 3, "`{line}`"),
                "E" => assert_eq!(decimals, 5, "`{line}`"),
                "F" => assert_eq!(decimals, 0, "`{line}`"),
                _ => panic!("unexpected `{line}`"),
            }
        }
    }
    for m in parse(&text).moves {
        let [x, y, z] = m.to;
        assert!(
            (0.0..=220.0).contains(&x) && (0.0..=220.0).contains(&y),
            "{m:?}"
        );
        assert!((0.0..=250.0).contains(&z), "{m:?}");
    }
    // the summary slicers write, readable by printers
    assert!(text.contains("; filament used [mm] = "));
    assert!(text.contains("; filament used [g] = "));
    assert!(text.contains("; estimated printing time = "));
    assert!(text.contains("M104 S210") && text.contains("M140 S60"));
}

#[test]
fn relative_extrusion_feeds_the_same_filament() {
    let dir = tmp("sphere-relative");
    let printer = root().join("tests/fixtures/relative-e.yaml");
    let out = p3dp(
        &dir,
        &[
            "build",
            recipe("sphere.yaml").to_str().unwrap(),
            "--printer",
            printer.to_str().unwrap(),
            "-o",
            "rel.gcode",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rel = parse(&std::fs::read_to_string(dir.join("rel.gcode")).unwrap());
    assert!(rel.lines.iter().any(|l| l.starts_with("M83")));
    let abs = parse(&build_sphere(&dir));
    let sum = |g: &Gcode| g.moves.iter().map(|m| m.de).sum::<f64>();
    // printed deltas add up to the absolute total to the last printed digit
    assert!(
        (sum(&rel) - sum(&abs)).abs() < 1e-9,
        "{} vs {}",
        sum(&rel),
        sum(&abs)
    );
}
