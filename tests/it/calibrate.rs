//! `p3dp calibrate` through the real binary: the gallery listed, each test
//! built clean on every built-in printer it fits (a bed too small refused
//! by name), the bands in the report and the stats, `apply` round-tripping
//! into a profile a rebuild uses, and the estimate following the settings.
//! (The settings read back through the firmware's own reader, per band
//! and flavour, are tested beside the code: `app::command::calibrate`.)

use crate::common::*;

const TESTS: [&str; 11] = [
    "temperature",
    "volumetric-speed",
    "pressure-advance-tower",
    "pressure-advance-line",
    "pressure-advance-pattern",
    "flow",
    "retraction",
    "cornering",
    "input-shaping-frequency",
    "input-shaping-damping",
    "vfa",
];

fn stats(dir: &std::path::Path, file: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join(file)).unwrap()).unwrap()
}

#[test]
fn the_list_names_every_test_in_the_guides_order() {
    let out = p3dp(&root(), &["calibrate", "--list"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let names: Vec<&str> = text
        .lines()
        .map(|l| l.split_whitespace().next().unwrap())
        .collect();
    for t in TESTS {
        assert!(names.contains(&t), "{t} missing from\n{text}");
    }
    let pos = |n: &str| names.iter().position(|x| *x == n).unwrap();
    assert!(pos("temperature") < pos("volumetric-speed"));
    assert!(pos("volumetric-speed") < pos("pressure-advance-tower"));
    assert!(pos("flow") < pos("retraction") && pos("retraction") < pos("cornering"));
    assert!(
        pos("cornering") < pos("input-shaping-frequency")
            && pos("input-shaping-damping") < pos("vfa")
    );
}

/// Every test on every built-in printer (the smallest beds, the A1 mini's
/// and the MINI's 180 mm, among them): clean, with its bands; the
/// volumetric speed test's default range kept under the hot end's hard
/// flow limit (the Ender 3's 8 mm³/s × 1.5: its last band 11 mm³/s).
/// Eleven tests on fifteen printers, each a whole build with its checks and
/// thumbnails: its cost is its coverage, so CI runs it (`--ignored`).
#[test]
#[ignore = "heavy: CI runs it, see README"]
fn every_test_builds_clean_on_every_built_in_printer() {
    let dir = tmp("calibrate-small");
    let mut printers: Vec<String> = std::fs::read_dir(root().join("src/machine/printers"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter_map(|n| n.strip_suffix(".yaml").map(str::to_string))
        .collect();
    printers.sort();
    assert!(printers.len() >= 15, "{printers:?}");
    for printer in &printers {
        let printer = printer.as_str();
        for t in TESTS {
            let out = p3dp(
                &dir,
                &[
                    "calibrate",
                    t,
                    "--printer",
                    printer,
                    "-o",
                    "out.gcode",
                    "--stats-json",
                    "s.json",
                ],
            );
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(out.status.success(), "{t} on {printer}: {err}");
            let report = String::from_utf8_lossy(&out.stdout);
            assert!(report.contains("0 errors"), "{t} on {printer}: {report}");
            let s = stats(&dir, "s.json");
            let bands = s["bands"].as_array().unwrap();
            assert!(bands.len() >= 5, "{t}: {bands:?}");
            assert!(report.contains("  bands:\n"), "{report}");
            if (t, printer) == ("volumetric-speed", "ender3") {
                let last = bands.last().unwrap()["value"].as_f64();
                assert_eq!(last, Some(11.0), "{bands:?}");
            }
        }
    }
}

#[test]
fn a_bed_too_small_is_refused_by_name() {
    let dir = tmp("calibrate-tiny");
    let fixture = root().join("tests/fixtures/printers/tiny-bed.yaml");
    std::fs::copy(fixture, dir.join("tiny-bed.yaml")).unwrap();
    let out = p3dp(
        &dir,
        &[
            "calibrate",
            "temperature",
            "--printer",
            "tiny-bed.yaml",
            "-o",
            "out.gcode",
        ],
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("out-of-bed"), "{err}");
    assert!(!dir.join("out.gcode").exists());
}

#[test]
fn any_range_and_step_gives_its_bands_in_the_stats() {
    let dir = tmp("calibrate-range");
    let out = p3dp(
        &dir,
        &[
            "calibrate",
            "temperature",
            "--material",
            "petg",
            "--set",
            "start=241",
            "--set",
            "end=229",
            "--set",
            "step=-3",
            "-o",
            "t.gcode",
            "--stats-json",
            "t.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = stats(&dir, "t.json");
    assert_eq!(s["material"], "petg");
    let bands = s["bands"].as_array().unwrap();
    let values: Vec<f64> = bands.iter().map(|b| b["value"].as_f64().unwrap()).collect();
    assert_eq!(values, [241.0, 238.0, 235.0, 232.0, 229.0]);
    for (i, b) in bands.iter().enumerate() {
        assert_eq!(b["index"].as_u64(), Some(i as u64));
        assert_eq!(b["z_from"].as_f64(), Some(5.0 * i as f64));
        assert_eq!(b["z_to"].as_f64(), Some(5.0 * (i + 1) as f64));
    }
    let g = std::fs::read_to_string(dir.join("t.gcode")).unwrap();
    for v in values {
        assert_eq!(
            g.matches(&format!("M104 S{v} ; nozzle temperature ; band"))
                .count(),
            1,
            "{v}"
        );
    }
}

/// The report, the stats and a refusal name the test, never the recipe
/// `calibrate` staged in a temporary folder (a file the user never wrote).
#[test]
fn the_report_names_the_test_not_the_staged_recipe() {
    let dir = tmp("calibrate-shown");
    let out = p3dp(
        &dir,
        &[
            "calibrate",
            "pressure-advance-line",
            "-o",
            "pa.gcode",
            "--stats-json",
            "pa.json",
        ],
    );
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        report.lines().next(),
        Some("calibration test pressure-advance-line → pa.gcode"),
        "{report}"
    );
    assert!(!report.contains("p3dp-calibrate-"), "{report}");
    assert_eq!(
        stats(&dir, "pa.json")["recipe"],
        "calibration test pressure-advance-line"
    );
    // a refusal after loading names the test too
    let out = p3dp(
        &dir,
        &[
            "calibrate",
            "temperature",
            "--set",
            "start=400",
            "-o",
            "t.gcode",
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("error: calibration test temperature: "),
        "{err}"
    );
    assert!(!err.contains("p3dp-calibrate-"), "{err}");
}

/// `apply` writes band N's value into a profile inheriting the printer, and
/// a build of another recipe with that profile writes it at the start.
#[test]
fn apply_round_trips_into_a_profile_a_rebuild_uses() {
    let dir = tmp("calibrate-apply");
    let out = p3dp(
        &dir,
        &[
            "calibrate",
            "pressure-advance-tower",
            "--printer",
            "voron-350",
            "-o",
            "pa.gcode",
            "--stats-json",
            "pa.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let band3 = stats(&dir, "pa.json")["bands"][3]["value"]
        .as_f64()
        .unwrap();
    let out = p3dp(
        &dir,
        &[
            "calibrate",
            "apply",
            "pressure-advance-tower",
            "--band",
            "3",
            "--printer",
            "voron-350",
            "-o",
            "my.yaml",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let profile = std::fs::read_to_string(dir.join("my.yaml")).unwrap();
    assert!(profile.contains("inherits: voron-350\n"), "{profile}");
    assert!(
        profile.contains(&format!("pressure_advance: {band3}\n")),
        "{profile}"
    );
    let vase = root().join("recipes/vase.yaml");
    let out = p3dp(
        &dir,
        &[
            "build",
            vase.to_str().unwrap(),
            "--printer",
            "my.yaml",
            "-o",
            "vase.gcode",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let g = std::fs::read_to_string(dir.join("vase.gcode")).unwrap();
    let want = format!("SET_PRESSURE_ADVANCE ADVANCE={band3} ");
    assert_eq!(g.matches(&want).count(), 1, "{want}");
    // the retraction length goes into the profile's retraction map
    let out = p3dp(
        &dir,
        &[
            "calibrate",
            "apply",
            "retraction",
            "--height",
            "4.5",
            "-o",
            "r.yaml",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = std::fs::read_to_string(dir.join("r.yaml")).unwrap();
    // band 2 of 2 mm bands from 0.2 mm in steps of 0.2 mm
    assert!(r.contains("retraction: { length: 0.6 }\n"), "{r}");
}

/// A tower raising the print acceleration: timed as the planner times the
/// same tower with that acceleration in the profile.
#[test]
fn the_estimate_follows_the_settings() {
    let dir = tmp("calibrate-accel");
    let recipe = |set: &str| {
        format!(
            "p3dp: 1\nname: accel\nparts:\n  - speed: 80\n    primitive: {{helix: {{radius: 14, height: 6, pitch: 0.2, segments: 4, center: [0, 0, 0.2]}}}}\n{set}"
        )
    };
    std::fs::write(
        dir.join("set.yaml"),
        recipe("    steps:\n      - set: {every: 3, acceleration: 400}\n"),
    )
    .unwrap();
    std::fs::write(dir.join("plain.yaml"), recipe("")).unwrap();
    std::fs::write(
        dir.join("slow.yaml"),
        "inherits: generic-220\nkinematics: { max_acceleration: 400 }\n",
    )
    .unwrap();
    let time = |r: &str, printer: &str| {
        let out = p3dp(
            &dir,
            &[
                "build",
                r,
                "--printer",
                printer,
                "-o",
                "o.gcode",
                "--stats-json",
                "o.json",
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        stats(&dir, "o.json")["print_time_s"].as_f64().unwrap()
    };
    let with_set = time("set.yaml", "generic-220");
    let in_profile = time("plain.yaml", "slow.yaml");
    let fast = time("plain.yaml", "generic-220");
    assert!(fast < with_set - 1.0, "{fast} {with_set}");
    assert!(
        (with_set - in_profile).abs() < 0.05,
        "{with_set} {in_profile}"
    );
}

#[test]
fn every_gallery_recipe_is_in_the_lock() {
    let lock = std::fs::read_to_string(root().join("p3dp.lock")).unwrap();
    let mut n = 0;
    for e in std::fs::read_dir(root().join("recipes/calibration")).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().to_string();
        if name.ends_with(".yaml") {
            n += 1;
            assert!(
                lock.contains(&format!("recipe: recipes/calibration/{name}\n")),
                "{name} is not locked"
            );
        }
    }
    assert!(n >= 11);
}

/// `volumetric-speed`'s band N lands in the profile's `max_flow`, and a
/// rebuild with that profile holds the `flow` check to it; `vfa`, whose
/// value no profile holds, is refused saying the band's speed and where it
/// goes, and writes nothing.
#[test]
fn apply_writes_max_flow_and_says_what_vfa_gives() {
    let dir = tmp("calibrate-apply-flow");
    let run = |args: &[&str]| p3dp(&dir, args);
    let out = run(&[
        "calibrate",
        "volumetric-speed",
        "--set",
        "step=1/2",
        "-o",
        "f.gcode",
        "--stats-json",
        "f.json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let band = &stats(&dir, "f.json")["bands"][7];
    assert_eq!(band["value"].as_f64(), Some(8.5));
    let out = run(&[
        "calibrate",
        "apply",
        "volumetric-speed",
        "--set",
        "step=1/2",
        "--height",
        &format!("{}", band["z_from"].as_f64().unwrap() + 0.1),
        "-o",
        "flow.yaml",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let profile = std::fs::read_to_string(dir.join("flow.yaml")).unwrap();
    assert!(profile.contains("inherits: generic-220\n"), "{profile}");
    assert!(profile.contains("\nmax_flow: 8.5\n"), "{profile}");
    // 0.1 mm² at 100 mm/s: 10 mm³/s, under generic-220's 12, over 8.5
    std::fs::write(
        dir.join("fast.yaml"),
        "p3dp: 1\nname: fast\nparts:\n  - {cross_section: 0.1, speed: 100, primitive: {helix: {radius: 15, height: 2, pitch: 0.2, segments: 90, center: [0, 0, 0.2]}}}\n",
    )
    .unwrap();
    for (printer, warned) in [("generic-220", false), ("flow.yaml", true)] {
        let out = run(&[
            "build",
            "fast.yaml",
            "--printer",
            printer,
            "-o",
            "fast.gcode",
        ]);
        let all = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out.status.success(), "{all}");
        assert_eq!(
            all.contains("hot end's 8.5 mm³/s"),
            warned,
            "{printer}: {all}"
        );
    }
    let out = run(&["calibrate", "apply", "vfa", "--band", "3", "-o", "v.yaml"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("band 3 gives 50)"), "{err}");
    assert!(err.contains("print walls no faster"), "{err}");
    assert!(!dir.join("v.yaml").exists());
}

/// The guide's chapter runs the tests in the order the calibration guides
/// recommend: temperature, maximum volumetric speed, pressure advance,
/// flow, retraction, cornering, input shaping, VFA; each section's
/// commands name its tests.
#[test]
fn the_guide_runs_the_tests_in_the_recommended_order() {
    let guide = std::fs::read_to_string(root().join("docs/guide/12-calibrate.md")).unwrap();
    assert!(guide.starts_with("# Calibrate your printer\n"));
    let headings: Vec<&str> = guide.lines().filter(|l| l.starts_with("## ")).collect();
    assert_eq!(
        headings,
        [
            "## 1. Temperature",
            "## 2. Maximum volumetric speed",
            "## 3. Pressure advance",
            "## 4. Flow",
            "## 5. Retraction",
            "## 6. Cornering, 7. input shaping, 8. VFA",
        ]
    );
    // the first command of each test comes in that order too
    let at = |t: &str| {
        guide
            .find(&format!("p3dp calibrate {t} "))
            .unwrap_or_else(|| panic!("{t} not in the guide"))
    };
    let order = [
        "temperature",
        "volumetric-speed",
        "pressure-advance-tower",
        "flow",
        "retraction",
        "cornering",
        "input-shaping-frequency",
        "vfa",
    ];
    for w in order.windows(2) {
        assert!(at(w[0]) < at(w[1]), "{} after {}", w[0], w[1]);
    }
}

/// A line test's line has one value: two `set`s giving line 1 two values
/// are refused by name (the bands table and `calibrate apply --band 1`
/// would not know which), nothing written; the same value again is one band.
#[test]
fn a_line_given_two_values_is_refused() {
    let dir = tmp("calibrate-one-value-a-line");
    let recipe = |band: &str| {
        format!(
            "p3dp: 1\nname: lines\nparams: {{lines: 3}}\nparts:\n  - primitive:\n      turtle:\n        program:\n          - for: {{k: \"0..lines - 1\"}}\n            do:\n              - pen_up\n              - {{goto: [-20, \"5*k\", 0.2]}}\n              - pen_down\n              - {{set: {{band: {band}, pressure_advance: \"0.01*k\"}}}}\n              - {{forward: 40}}\n"
        )
    };
    std::fs::write(dir.join("twice.yaml"), recipe("1")).unwrap();
    let out = p3dp(&dir, &["build", "twice.yaml", "-o", "twice.gcode"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("twice.yaml") && err.contains("set.band: line 1 of the line test is given 0"),
        "{err}"
    );
    assert!(!dir.join("twice.gcode").exists());
    std::fs::write(dir.join("each.yaml"), recipe("k")).unwrap();
    let out = p3dp(
        &dir,
        &[
            "build",
            "each.yaml",
            "-o",
            "each.gcode",
            "--stats-json",
            "s.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<u64> = stats(&dir, "s.json")["bands"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["line"].as_u64().unwrap())
        .collect();
    assert_eq!(lines, [0, 1, 2]);
}
