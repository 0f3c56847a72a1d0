//! The command-line contract of the spec: build, hash, --set, -o, --stats-json.

use crate::common::*;
use p3dp::testing::Insides;
use sha2::{Digest, Sha256};

fn sha256(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn ok(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "exit {:?}\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn build_twice_and_hash_agree_byte_for_byte() {
    let dir = tmp("determinism");
    let globe = recipe("globe.yaml");
    let g = globe.to_str().unwrap();
    ok(&p3dp(
        &dir,
        &["build", g, "-o", "a.gcode", "--stats-json", "a.json"],
    ));
    ok(&p3dp(&dir, &["build", g, "-o", "b.gcode"]));
    let a = std::fs::read(dir.join("a.gcode")).unwrap();
    let b = std::fs::read(dir.join("b.gcode")).unwrap();
    assert!(a == b, "two builds differ");
    let h = p3dp(&dir, &["hash", g]);
    ok(&h);
    let line = String::from_utf8(h.stdout).unwrap();
    assert_eq!(line, format!("{}  {g}\n", sha256(&a)));
    // standard output carries exactly the same bytes
    let s = p3dp(&dir, &["build", g, "-o", "-"]);
    ok(&s);
    assert!(s.stdout == a, "-o - differs from the file");
    // and the stats JSON names the same hash and size
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("a.json")).unwrap()).unwrap();
    assert_eq!(json["gcode_sha256"], sha256(&a));
    assert_eq!(json["gcode_bytes"], a.len() as u64);
    // no path or time in the G-code
    let text = String::from_utf8(a).unwrap();
    assert!(!text.contains(root().to_str().unwrap()));
}

#[test]
fn stats_json_has_every_field_of_the_spec() {
    let dir = tmp("stats");
    ok(&p3dp(
        &dir,
        &[
            "build",
            recipe("globe.yaml").to_str().unwrap(),
            "--stats-json",
            "s.json",
        ],
    ));
    // default output name: ./NAME.gcode
    let gcode = std::fs::read_to_string(dir.join("globe.gcode")).unwrap();
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    for key in [
        "recipe",
        "gcode_sha256",
        "gcode_bytes",
        "extrude_moves",
        "travel_moves",
        "extrude_length_mm",
        "travel_length_mm",
        "filament_length_mm",
        "filament_volume_mm3",
        "filament_mass_g",
        "print_time_s",
        "bbox",
        "max_flow_mm3_s",
        "warnings",
    ] {
        assert!(!s[key].is_null(), "missing {key}");
    }
    assert_eq!(s["bbox"]["min"].as_array().unwrap().len(), 3);
    assert!(s["warnings"].is_array());
    // the numbers agree with the G-code read back
    let g = parse(&gcode);
    let extrude: Vec<&Move> = g
        .moves
        .iter()
        .filter(|m| m.de > 0.0 && m.g == 1 && m.from != m.to)
        .collect();
    assert_eq!(s["extrude_moves"].as_u64().unwrap() as usize, extrude.len());
    let fed: f64 = g.moves.iter().map(|m| m.de).sum();
    let filament = s["filament_length_mm"].as_f64().unwrap();
    assert!((fed - filament).abs() < 1e-4, "{fed} vs {filament}");
    let area = std::f64::consts::PI * 0.875 * 0.875;
    let volume = s["filament_volume_mm3"].as_f64().unwrap();
    assert!((volume - filament * area).abs() < 1e-6 * volume);
    let mass = s["filament_mass_g"].as_f64().unwrap();
    assert!((mass - volume / 1000.0 * 1.24).abs() < 1e-9);
    let len: f64 = extrude
        .iter()
        .map(|m| {
            (0..3)
                .map(|k| (m.to[k] - m.from[k]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .sum();
    let stated = s["extrude_length_mm"].as_f64().unwrap();
    assert!((len - stated).abs() < 1e-3 * stated, "{len} vs {stated}");
    // the globe's 0.2 mm-long polar strings were merged, filament untouched
    assert!(s["merged_strings"].as_u64().unwrap() > 1000);
    let plan = p3dp::plan(&recipe("globe.yaml"), &Default::default()).unwrap();
    let exact: f64 = plan.paths().iter().map(|t| t.volume()).sum::<f64>() / area;
    assert!(
        ((fed - exact) / exact).abs() < 1e-6,
        "fed {fed}, strings {exact}"
    );
}

#[test]
fn merged_moves_are_never_shorter_than_needed_except_at_run_ends() {
    let dir = tmp("merge");
    ok(&p3dp(
        &dir,
        &[
            "build",
            recipe("globe.yaml").to_str().unwrap(),
            "-o",
            "g.gcode",
        ],
    ));
    let g = parse(&std::fs::read_to_string(dir.join("g.gcode")).unwrap());
    let part = g.parts.iter().position(|p| p == "globe").unwrap();
    let moves: Vec<&Move> = g
        .moves
        .iter()
        .filter(|m| m.part == part && m.de > 0.0)
        .collect();
    let short = moves
        .iter()
        .filter(|m| {
            (0..3)
                .map(|k| (m.to[k] - m.from[k]).powi(2))
                .sum::<f64>()
                .sqrt()
                < 0.05
        })
        .count();
    // 45,000 strings, thousands of them under 0.1 mm near the poles: merged
    assert!(short < 20, "{short} moves under 0.05 mm");
}

#[test]
fn set_gives_the_same_bytes_as_editing_the_recipe() {
    let dir = tmp("set");
    let text = std::fs::read_to_string(recipe("sphere.yaml")).unwrap();
    let edited = text.replace("  radius: 25\n", "  radius: 20\n");
    assert_ne!(text, edited);
    std::fs::write(dir.join("sphere.yaml"), edited).unwrap();
    let by_hand = p3dp(&dir, &["hash", "sphere.yaml"]);
    ok(&by_hand);
    let set = p3dp(
        &dir,
        &[
            "hash",
            recipe("sphere.yaml").to_str().unwrap(),
            "--set",
            "radius=40/2",
        ],
    );
    ok(&set);
    let h = |o: &std::process::Output| {
        String::from_utf8_lossy(&o.stdout)
            .split_whitespace()
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(h(&by_hand), h(&set));
    // and it really changed the print
    let plain = p3dp(&dir, &["hash", recipe("sphere.yaml").to_str().unwrap()]);
    assert_ne!(h(&plain), h(&set));
}

#[test]
fn several_recipes_into_a_folder() {
    let dir = tmp("many");
    let out = p3dp(
        &dir,
        &[
            "build",
            recipe("sphere.yaml").to_str().unwrap(),
            recipe("globe.yaml").to_str().unwrap(),
            "-o",
            "out",
        ],
    );
    ok(&out);
    assert!(dir.join("out/sphere.gcode").is_file());
    assert!(dir.join("out/globe.gcode").is_file());
    let report = String::from_utf8(out.stdout).unwrap();
    assert!(report.contains("sphere.gcode") && report.contains("globe.gcode"));
}

#[test]
fn check_runs_without_writing() {
    let dir = tmp("check");
    let out = p3dp(&dir, &["check", recipe("sphere.yaml").to_str().unwrap()]);
    ok(&out);
    assert!(String::from_utf8_lossy(&out.stdout).contains("0 warnings, 0 errors"));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}
