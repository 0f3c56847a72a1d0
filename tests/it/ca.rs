//! Kanada's self-organised patterns ("Self-organized 3D-printing Patterns
//! Simulated by Cellular Automata") through the real binary: the
//! constant-flow `pattern_helix` print in G-code, the checks of the paper's
//! ranges, the same bytes on every run, and bad values. The automaton's
//! cells against the paper's Figs. 6, 7, 9 and 11 are checked in
//! `internals::ca`.

use crate::common::{p3dp, parse, recipe, tmp};

#[test]
fn pattern_helix_gcode_has_one_speed_and_one_flow_after_the_first_turn() {
    let dir = tmp("ca-pattern-gcode");
    let out = p3dp(
        &dir,
        &[
            "build",
            recipe("self-organised-stripes.yaml").to_str().unwrap(),
            "-o",
            "s.gcode",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let g = parse(&std::fs::read_to_string(dir.join("s.gcode")).unwrap());
    let part = g.parts.iter().position(|p| p == "stripes").unwrap();
    let moves: Vec<_> = g
        .moves
        .iter()
        .filter(|m| m.part == part && m.g == 1 && m.de > 0.0 && m.from != m.to)
        .collect();
    assert_eq!(moves.len(), 150 * 72);
    let area = std::f64::consts::PI * 0.875 * 0.875;
    for (k, m) in moves.iter().enumerate().skip(72) {
        let len = (0..3)
            .map(|a| (m.to[a] - m.from[a]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert_eq!(m.f, 3600.0, "move {k}");
        // E is written to 5 decimals and XYZ to 3: c within rounding
        let c = m.de * area / len;
        assert!((c - 0.045).abs() < 0.001, "move {k}: c = {c}");
    }
    assert!(moves[..72].iter().all(|m| m.f == 900.0));
}

#[test]
fn check_warns_outside_the_papers_ranges() {
    let dir = tmp("ca-ranges");
    let r = recipe("self-organised-stripes.yaml");
    let r = r.to_str().unwrap();
    let out = p3dp(&dir, &["check", r]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("0 warnings, 0 errors"),
        "{text}"
    );
    let sets = [
        "layer_height=0.35",
        "cross_section=0.1",
        "speed=30",
        "first_speed=20",
    ];
    let mut args = vec!["check", r];
    for s in &sets {
        args.extend(["--set", s]);
    }
    let out = p3dp(&dir, &args);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "warnings only: {text}");
    assert!(text.contains("3 warnings, 0 errors"), "{text}");
    for what in ["layer_height 0.35", "cross_section 0.1", "speed 30"] {
        assert!(
            text.contains(&format!("[pattern-range]: part `stripes`: {what}")),
            "{text}"
        );
    }
    args.push("--strict");
    assert_eq!(p3dp(&dir, &args).status.code(), Some(1));

    // a step that modulates the strings after the first turn is found
    let text = std::fs::read_to_string(recipe("self-organised-stripes.yaml")).unwrap();
    let modulated = format!(
        "{text}    steps:\n      - modulate_cylinder: {{factor: \"1 + 0.3*sin(8*theta)\"}}\n"
    );
    std::fs::write(dir.join("m.yaml"), modulated).unwrap();
    let out = p3dp(&dir, &["check", "m.yaml"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("[pattern-modulated]"), "{text}");
}

#[test]
fn builds_are_byte_identical() {
    let dir = tmp("ca-same-bytes");
    let r = recipe("ca-split-merge.yaml");
    let r = r.to_str().unwrap();
    let a = p3dp(&dir, &["hash", r]);
    let b = p3dp(&dir, &["hash", r, "-j", "1"]);
    assert!(a.status.success());
    assert_eq!(a.stdout, b.stdout);
    let c = p3dp(&dir, &["hash", r, "--set", "seed=8"]);
    assert_ne!(a.stdout[..64], c.stdout[..64]);
}

#[test]
fn pattern_needs_one_ca_helix_and_one_build() {
    let dir = tmp("ca-pattern-errors");
    let sos = recipe("self-organised-stripes.yaml");
    let out = p3dp(
        &dir,
        &[
            "build",
            sos.to_str().unwrap(),
            "-o",
            "s.gcode",
            "--pattern",
            "s.png",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--pattern") && err.contains("0 `ca_helix` parts"),
        "{err}"
    );
    assert!(!dir.join("s.gcode").exists() && !dir.join("s.png").exists());
    let ca = recipe("ca-stripes.yaml");
    let out = p3dp(
        &dir,
        &[
            "build",
            ca.to_str().unwrap(),
            "-o",
            "out/",
            "--sweep",
            "seed=1,2",
            "--pattern",
            "c.png",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--pattern"));
    assert!(!dir.join("out").exists() && !dir.join("c.png").exists());
}

const CA: &str = "p3dp: 1\nname: bad\nparts:\n  - primitive:\n      ca_helix: {radius: 20, layers: 10, layer_height: 0.2, KEYS}\n";

const PH: &str = "p3dp: 1\nname: bad\nparts:\n  - primitive:\n      pattern_helix: {radius: 20, layers: 10, layer_height: 0.2, KEYS}\n";

#[test]
fn bad_values_are_input_errors_naming_the_key() {
    let dir = tmp("ca-bad");
    let cases = [
        (CA, "p0: 1.5", "ca_helix.p0"),
        (CA, "p1: -0.1", "ca_helix.p1"),
        (CA, "e1: 1", "ca_helix.e1"),
        (CA, "e1: 0", "ca_helix.e1"),
        (CA, "rule: zigzag", "ca_helix.rule"),
        (CA, "initial: zeros", "ca_helix.initial"),
        (CA, "consume: 0.5", "ca_helix.consume"),
        (CA, "rule: split_merge, consume: 1", "ca_helix.consume"),
        (CA, "noise: 0.1", "ca_helix.noise"),
        (CA, "initial: random, noise: 2", "ca_helix.noise"),
        (CA, "seed: 1.5", "ca_helix.seed"),
        (CA, "seed: -1", "ca_helix.seed"),
        (CA, "cells: 2", "ca_helix.cells"),
        (CA, "center: [0, 0, \"1/0\"]", "ca_helix.center[2]"),
        (CA, "pe: 1", "ca_helix.pe"),
        (PH, "segments: 72.5", "pattern_helix.segments"),
        (PH, "cross_section: 0", "pattern_helix.cross_section"),
        (
            PH,
            "first_layer: {speed: -15}",
            "pattern_helix.first_layer.speed",
        ),
        (
            PH,
            "first_layer: {height: 1}",
            "pattern_helix.first_layer.height",
        ),
    ];
    for (k, (base, keys, place)) in cases.iter().enumerate() {
        let file = format!("bad{k}.yaml");
        std::fs::write(dir.join(&file), base.replace("KEYS", keys)).unwrap();
        let out = p3dp(&dir, &["build", &file]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{keys}: {err}");
        assert!(
            err.contains(&format!("parts[0].primitive.{place}")),
            "{keys}: {err}"
        );
        assert!(!dir.join("bad.gcode").exists());
    }
    for (base, key) in [(CA, "ca_helix"), (PH, "pattern_helix")] {
        let text = base
            .replace("radius: 20", "radius: -20")
            .replace(", KEYS", "");
        std::fs::write(dir.join("neg.yaml"), text).unwrap();
        let out = p3dp(&dir, &["check", "neg.yaml"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2));
        assert!(
            err.contains(&format!("parts[0].primitive.{key}.radius")),
            "{err}"
        );
    }
    // the string count is known before anything is built
    let text = CA
        .replace("name: bad", "name: bad\nmax_strings: 1000")
        .replace(", KEYS", "");
    std::fs::write(dir.join("big.yaml"), text).unwrap();
    let out = p3dp(&dir, &["check", "big.yaml"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert!(err.contains("would make 2880 strings"), "{err}");
}
