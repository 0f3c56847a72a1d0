//! The printability and safety checks (issue 7), through the real binary.
//!
//! Every recipe of `tests/checks/` is built to trigger exactly one finding,
//! named in its header: `# expect: code=CODE severity=SEVERITY at=[x,y,z]` (or
//! `at=none`). Each is built with `--force --stats-json` and the finding is
//! read back from the JSON: its code, its severity, and its place within 1 mm
//! of the expected one. Every recipe of the gallery has no errors; `allow:`
//! and `--allow` silence checks; unknown codes are unusable input.

use std::path::{Path, PathBuf};

use crate::common::{p3dp, root, tmp};

/// What a corpus recipe's header expects.
#[derive(Debug)]
struct Expect {
    code: String,
    severity: String,
    at: Option<[f64; 3]>,
}

fn expect(path: &Path) -> Expect {
    let text = std::fs::read_to_string(path).unwrap();
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix("# expect:"))
        .unwrap_or_else(|| panic!("{}: no `# expect:` line", path.display()));
    let (mut code, mut severity, mut at) = (None, None, None);
    for word in line.split_whitespace() {
        let (k, v) = word.split_once('=').expect("key=value");
        match k {
            "code" => code = Some(v.to_string()),
            "severity" => severity = Some(v.to_string()),
            "at" if v == "none" => at = Some(None),
            "at" => {
                let xs: Vec<f64> = v
                    .trim_matches(['[', ']'])
                    .split(',')
                    .map(|x| x.trim().parse().unwrap())
                    .collect();
                at = Some(Some([xs[0], xs[1], xs[2]]));
            }
            _ => panic!("{}: unknown key {k}", path.display()),
        }
    }
    Expect {
        code: code.expect("code="),
        severity: severity.expect("severity="),
        at: at.expect("at="),
    }
}

fn corpus() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("tests/checks"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    v.sort();
    v
}

/// Builds `recipe` (forced) and returns the findings of its stats JSON.
fn findings(recipe: &Path, name: &str) -> Vec<serde_json::Value> {
    let dir = tmp(&format!("checks-{name}"));
    let out = p3dp(
        &dir,
        &[
            "build",
            recipe.to_str().unwrap(),
            "--force",
            "-o",
            "out.gcode",
            "--stats-json",
            "stats.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}: exit {:?}\n{}",
        recipe.display(),
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("stats.json")).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    json["warnings"].as_array().unwrap().clone()
}

#[test]
fn each_corpus_recipe_triggers_exactly_its_finding() {
    let files = corpus();
    assert!(files.len() >= 12, "only {} recipes", files.len());
    let mut codes = std::collections::BTreeSet::new();
    for f in &files {
        let name = f.file_stem().unwrap().to_string_lossy().to_string();
        let e = expect(f);
        let got = findings(f, &name);
        assert_eq!(got.len(), 1, "{name}: expected one finding, got {got:#?}");
        let g = &got[0];
        assert_eq!(g["code"], e.code.as_str(), "{name}: {g:#?}");
        assert_eq!(g["severity"], e.severity.as_str(), "{name}: {g:#?}");
        let see = format!("; see: p3dp explain {}", e.code);
        assert!(
            g["message"].as_str().unwrap().ends_with(&see),
            "{name}: {g:#?}"
        );
        match e.at {
            None => assert!(g.get("at").is_none(), "{name}: {g:#?}"),
            Some(want) => {
                let at: Vec<f64> = g["at"]
                    .as_array()
                    .unwrap_or_else(|| panic!("{name}: no place in {g:#?}"))
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect();
                let d = ((at[0] - want[0]).powi(2)
                    + (at[1] - want[1]).powi(2)
                    + (at[2] - want[2]).powi(2))
                .sqrt();
                assert!(
                    d <= 1.0,
                    "{name}: found at {at:?}, {d:.2} mm from the expected {want:?}\n{g:#?}"
                );
            }
        }
        codes.insert(e.code);
    }
    // the corpus covers the new checks
    for c in [
        "unsupported",
        "bridge",
        "nozzle-collision",
        "head-collision",
        "over-extrusion",
        "thin-string",
        "starvation",
        "flow",
        "first-layer",
        "klipper-extrusion",
    ] {
        assert!(codes.contains(c), "no corpus recipe for `{c}`");
    }
}

/// Every recipe of `recipes/`, sorted.
fn gallery_recipes() -> Vec<PathBuf> {
    let mut recipes: Vec<PathBuf> = std::fs::read_dir(root().join("recipes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    recipes.sort();
    recipes
}

/// The report of `p3dp check` on every recipe of `recipes/` (by absolute
/// path), which exits 0; run once and shared with `gallery.rs`.
pub(crate) fn gallery_checked() -> std::sync::Arc<String> {
    crate::common::once("p3dp check recipes/*.yaml", || {
        let dir = tmp("checks-gallery");
        let mut args = vec!["check".to_string()];
        args.extend(gallery_recipes().iter().map(|p| p.display().to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = p3dp(&dir, &args);
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(
            out.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        stdout
    })
}

#[test]
fn the_gallery_has_no_errors() {
    let recipes = gallery_recipes();
    let stdout = gallery_checked();
    for r in &recipes {
        let line = stdout
            .lines()
            .find(|l| l.starts_with(&format!("{}:", r.display())))
            .unwrap_or_else(|| panic!("no line for {} in\n{stdout}", r.display()));
        assert!(line.contains(", 0 errors"), "{line}");
    }
    // the Olympic rings say where their arches bridge (the paper needed support)
    let rings = stdout
        .lines()
        .filter(|l| l.contains("[bridge]") && l.contains("ring-"))
        .count();
    assert_eq!(rings, 8, "{stdout}");
}

#[test]
fn checks_are_deterministic() {
    let dir = tmp("checks-determinism");
    let f = root().join("tests/checks/nozzle-beside-wall.yaml");
    let a = p3dp(&dir, &["check", f.to_str().unwrap()]);
    let b = p3dp(&dir, &["check", f.to_str().unwrap()]);
    assert_eq!(a.stdout, b.stdout);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn allow_silences_a_warning() {
    let dir = tmp("checks-allow");
    let bridge = root().join("tests/checks/long-bridge.yaml");
    let f = bridge.to_str().unwrap();
    let out = p3dp(&dir, &["check", f, "--strict"]);
    assert_eq!(out.status.code(), Some(1));
    let out = p3dp(&dir, &["check", f, "--strict", "--allow", "bridge"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("0 warnings, 0 errors"), "{stdout}");
    // in the recipe: `allow: [{code, reason}, code]`
    let allowed = root().join("tests/checks/allow/allowed.yaml");
    let out = p3dp(&dir, &["check", allowed.to_str().unwrap(), "--strict"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("0 warnings, 0 errors"), "{stdout}");
    // a build prints the summary too
    let out = p3dp(&dir, &["build", allowed.to_str().unwrap(), "-o", "a.gcode"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("0 warnings, 0 errors"), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `allow` silences warnings only (docs/checks.md, `p3dp explain`): an
/// error of an allowed code stays an error, says why, and fails the build
/// unless `--force`; the same code's warnings are silenced.
#[test]
fn allow_leaves_an_error_an_error_only_force_writes() {
    let dir = tmp("checks-allow-error");
    for (recipe, code) in [
        ("floating-string.yaml", "unsupported"),
        ("over-extrusion-hard.yaml", "over-extrusion"),
        ("allow/error.yaml", "unsupported"),
    ] {
        let f = root().join("tests/checks").join(recipe);
        let f = f.to_str().unwrap();
        let out = p3dp(&dir, &["build", f, "--allow", code, "-o", "e.gcode"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{recipe}: {stderr}");
        assert!(stderr.contains(&format!("[{code}]")), "{recipe}: {stderr}");
        assert!(
            stderr.contains("`allow` silences warnings and notes only"),
            "{recipe}: {stderr}"
        );
        assert!(!dir.join("e.gcode").exists(), "{recipe}");
        let out = p3dp(
            &dir,
            &["build", f, "--allow", code, "--force", "-o", "e.gcode"],
        );
        assert!(out.status.success(), "{recipe}");
        assert!(dir.join("e.gcode").exists(), "{recipe}");
        std::fs::remove_file(dir.join("e.gcode")).unwrap();
    }
    // the warning of the same code is silenced
    let warn = root().join("tests/checks/over-extrusion.yaml");
    let args = [
        "check",
        warn.to_str().unwrap(),
        "--strict",
        "--allow",
        "over-extrusion",
    ];
    let out = p3dp(&dir, &args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("0 warnings, 0 errors"), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// FullControl's blob printing on a Klipper printer: Klipper refuses its
/// primer line (1.28 mm² against 4 × 0.4² = 0.64 mm²), and so does p3dp,
/// naming the first such move as Klipper would; Creality's K1
/// (max_extrude_cross_section 80 mm²) and a Marlin printer run it.
#[test]
fn klipper_refuses_blob_printing_s_primer_line() {
    let dir = tmp("checks-klipper-blobs");
    let blobs = root().join("recipes/fullcontrol/blob_printing.yaml");
    let b = blobs.to_str().unwrap();
    let out = p3dp(
        &dir,
        &["build", b, "--printer", "voron-350", "-o", "v.gcode"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("[klipper-extrusion]"), "{stderr}");
    assert!(
        stderr.contains("`Move exceeds maximum extrusion (1.280mm^2 vs 0.640mm^2)`"),
        "{stderr}"
    );
    assert!(!dir.join("v.gcode").exists());
    // the first such move: the primer line, from x = 50 + 10 + 20·1.072 to
    // 50 + 10 + 10·1.072 at y = 50, z = 0.76 (recipe mm); its midpoint
    let found = |printer: &str| -> Vec<serde_json::Value> {
        let args = [
            "build",
            b,
            "--printer",
            printer,
            "--force",
            "-o",
            "f.gcode",
            "--stats-json",
            "f.json",
        ];
        assert!(p3dp(&dir, &args).status.success(), "{printer}");
        let v: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("f.json")).unwrap()).unwrap();
        v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|f| f["code"] == "klipper-extrusion")
            .cloned()
            .collect()
    };
    let voron = found("voron-350");
    assert_eq!(voron.len(), 1, "{voron:?}");
    let at: Vec<f64> = voron[0]["at"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let spacing = 1.6 * (1.0 - 0.33);
    let want = [60.0 + 15.0 * spacing, 50.0, 0.95 * 0.8];
    for k in 0..3 {
        assert!((at[k] - want[k]).abs() < 1e-3, "{at:?} against {want:?}");
    }
    assert_eq!(voron[0]["severity"], "error");
    assert!(found("creality-k1").is_empty());
    assert!(found("generic-220").is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Klipper's rule exactly (klippy/kinematics/extruder.py, `check_move`): a
/// move feeding at most nozzle × max_extrude_cross_section of filament
/// volume passes whatever its cross-section; a move with no X or Y is
/// extrude-only, held to max_extrude_only_distance (50 mm) instead.
#[test]
fn klipper_s_tolerance_and_extrude_only_moves() {
    let dir = tmp("checks-klipper-rule");
    let codes = |tag: &str, path: &str| -> Vec<String> {
        let yaml = format!(
            "p3dp: 1\nname: k\nmaterial: pla\ndefaults: {{cross_section: 0.2, speed: 10}}\nparts:\n  - name: p\n    primitive:\n      path:\n{path}"
        );
        let f = dir.join(format!("{tag}.yaml"));
        std::fs::write(&f, yaml).unwrap();
        let out = p3dp(
            &dir,
            &["check", f.to_str().unwrap(), "--printer", "voron-350"],
        );
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|l| Some(l.split_once('[')?.1.split_once(']')?.0.to_string()))
            .collect()
    };
    let wide = |len: f64| {
        format!("        - move: [0, 0, 0.3]\n        - cross_section: 1\n        - draw: {{x: {len}}}\n")
    };
    // 0.2 mm at 1 mm²: 0.2 mm³, under 0.4 × 0.64 = 0.256 mm³: a tiny amount
    assert!(!codes("tiny", &wide(0.2)).contains(&"klipper-extrusion".into()));
    assert!(codes("wide", &wide(0.5)).contains(&"klipper-extrusion".into()));
    // in place: 125 mm³ is 52 mm of 1.75 mm filament, past 50; 110 mm³ is 45.7 mm
    let blob = |mm3: f64| {
        format!("        - move: [0, 0, 0.3]\n        - draw: {{x: 5}}\n        - extrude_volume: {mm3}\n          feed: 1\n")
    };
    assert!(codes("blob-big", &blob(125.0)).contains(&"klipper-extrusion".into()));
    assert!(!codes("blob-small", &blob(110.0)).contains(&"klipper-extrusion".into()));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unknown_codes_are_unusable_input() {
    let dir = tmp("checks-unknown");
    let bad = root().join("tests/checks/allow/unknown-code.yaml");
    let out = p3dp(&dir, &["check", bad.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("allow[1]"), "{stderr}");
    assert!(stderr.contains("`floating`"), "{stderr}");
    assert!(
        stderr.contains("unsupported") && stderr.contains("nozzle-collision"),
        "{stderr}"
    );
    let ok = root().join("tests/checks/bridge.yaml");
    let out = p3dp(&dir, &["check", ok.to_str().unwrap(), "--allow", "nope"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--allow nope"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn notes_never_fail_warnings_fail_under_strict() {
    let dir = tmp("checks-strict");
    let note = root().join("tests/checks/bridge.yaml");
    let out = p3dp(&dir, &["check", note.to_str().unwrap(), "--strict"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("0 warnings, 0 errors, 1 note"), "{stdout}");
    let warn = root().join("tests/checks/long-bridge.yaml");
    let out = p3dp(&dir, &["check", warn.to_str().unwrap()]);
    assert!(out.status.success());
    let out = p3dp(&dir, &["check", warn.to_str().unwrap(), "--strict"]);
    assert_eq!(out.status.code(), Some(1));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn safety_limits_cannot_be_allowed_only_forced() {
    let dir = tmp("checks-safety");
    // in the recipe: exit 2, naming the entry, writing nothing
    let bad = root().join("tests/checks/allow/safety.yaml");
    let out = p3dp(&dir, &["build", bad.to_str().unwrap(), "-o", "s.gcode"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("allow[1]"), "{stderr}");
    assert!(
        stderr.contains("`out-of-bed` is a safety limit"),
        "{stderr}"
    );
    assert!(!dir.join("s.gcode").exists());
    // on the command line, for every safety code
    let edge = root().join("tests/checks/out-of-bed.yaml");
    let e = edge.to_str().unwrap();
    for code in p3dp::SAFETY {
        let out = p3dp(&dir, &["build", e, "--allow", code, "-o", "s.gcode"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{code}: {stderr}");
        assert!(stderr.contains(&format!("--allow {code}")), "{stderr}");
        assert!(!dir.join("s.gcode").exists());
    }
    // without --force the out-of-bed ring fails and writes nothing; with it, it is written
    let out = p3dp(&dir, &["build", e, "-o", "s.gcode"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(!dir.join("s.gcode").exists());
    let out = p3dp(&dir, &["build", e, "--force", "-o", "s.gcode"]);
    assert!(out.status.success());
    assert!(dir.join("s.gcode").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_cup_holds_on_to_the_bed_by_its_first_layer_only() {
    // cup.yaml: one part whose bottom is 3 spiral layers, radius 30, the first at h = 0.2 mm
    // with c = 0.1 mm² and turns 0.45 mm apart: its filament covers
    // a disc: (pi 30² / 0.45) mm of spiral, each string a band c / h = 0.5 mm
    // wide, the bands overlapping (0.45 mm apart) into a disc of radius about
    // 30 (the outer turn closes in from 30 to 29.55, its band 0.25 beyond); the two layers above it, the wall and the skirt's second loop
    // add nothing
    let dir = tmp("checks-first-layer");
    let cup = root().join("recipes/cup.yaml");
    let out = p3dp(
        &dir,
        &[
            "build",
            cup.to_str().unwrap(),
            "-o",
            "c.gcode",
            "--stats-json",
            "c.json",
        ],
    );
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("bed contact: skirt"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("c.json")).unwrap()).unwrap();
    let fl = json["first_layer"].as_array().unwrap();
    let names: Vec<&str> = fl.iter().map(|f| f["part"].as_str().unwrap()).collect();
    assert_eq!(names, ["skirt", "cup"], "{fl:#?}");
    let bottom = &fl[1];
    let length = std::f64::consts::PI * 30.0 * 30.0 / 0.45;
    let got_l = bottom["contact_length_mm"].as_f64().unwrap();
    let got_a = bottom["contact_area_mm2"].as_f64().unwrap();
    assert!((got_l / length - 1.0).abs() < 0.02, "{got_l} vs {length}");
    let disc = std::f64::consts::PI * 30.0 * 30.0;
    assert!((got_a / disc - 1.0).abs() < 0.01, "{got_a} vs {disc}");
    // the spiral's last turn closes in from r = 30 to 30 − 0.45 over a turn
    for k in 0..2 {
        let (lo, hi) = (
            bottom["min"][k].as_f64().unwrap(),
            bottom["max"][k].as_f64().unwrap(),
        );
        assert!(
            (-30.0..-29.55).contains(&lo) && (29.55..=30.0).contains(&hi),
            "{lo} {hi}"
        );
    }
    assert!((bottom["min_height_mm"].as_f64().unwrap() - 0.2).abs() < 1e-9);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The shade's bed contact (mm²) at `segments` strings a turn.
fn shade_contact(segments: u32) -> f64 {
    let dir = tmp(&format!("checks-shade-{segments}"));
    let shade = root().join("recipes/lamp-shade.yaml");
    let set = format!("segments={segments}");
    // the first 2 mm of the helix: the bed contact is the first layer's, and
    // the whole shade at 24,000 segments a turn is 8 million strings
    let out = p3dp(
        &dir,
        &[
            "build",
            shade.to_str().unwrap(),
            "--set",
            &set,
            "--set",
            "height=2",
            "-o",
            "s.gcode",
            "--stats-json",
            "s.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    json["first_layer"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["part"] == "shade")
        .unwrap()["contact_area_mm2"]
        .as_f64()
        .unwrap()
}

#[test]
fn bed_contact_does_not_depend_on_the_segment_count() {
    // the lamp shade stands on its pole: the union of its first strings'
    // bands, however finely the helix is cut
    let (coarse, fine) = (shade_contact(240), shade_contact(24_000));
    assert!(coarse > 5.0, "{coarse}");
    assert!(
        (fine / coarse - 1.0).abs() < 0.05,
        "{coarse} mm² vs {fine} mm²"
    );
}

/// The codes `p3dp check` reports for `text` written as a recipe file.
fn check_codes(tag: &str, text: &str) -> String {
    let dir = tmp(&format!("checks-{tag}"));
    std::fs::write(dir.join("r.yaml"), text).unwrap();
    // the globe's map lies in the gallery's project, outside this folder
    let maps = root().join("maps").display().to_string();
    let out = p3dp(&dir, &["check", "r.yaml", "--allow-read", &maps]);
    let _ = std::fs::remove_dir_all(&dir);
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn the_sphere_and_the_globe_need_a_brim_or_a_stand() {
    for name in ["sphere", "globe"] {
        let text = std::fs::read_to_string(root().join(format!("recipes/{name}.yaml")))
            .unwrap()
            .replace("../maps/", &format!("{}/maps/", root().display()));
        assert!(text.contains("brim: {loops: 8}"), "{name}");
        let with = check_codes(&format!("{name}-brim"), &text);
        assert!(!with.contains("small-contact"), "{with}");
        // the globe also has a stand (its foot)
        let text = text.replace("stand: {radius: 8}", "");
        let bare = text.replace("brim: {loops: 8}", "");
        let without = check_codes(&format!("{name}-no-brim"), &bare);
        assert!(without.contains("warning [small-contact]"), "{without}");
        assert!(without.contains("add a `brim:` or a `stand:`"), "{without}");
        // a stand alone widens the contact enough (the check measures the
        // union of the first layer's bands: nothing special-cased)
        let stand = text.replace("brim: {loops: 8}", "stand: {radius: 7}");
        let with = check_codes(&format!("{name}-stand"), &stand);
        assert!(!with.contains("small-contact"), "{with}");
        assert!(with.contains("0 warnings, 0 errors"), "{with}");
    }
}

/// The stats JSON of building `text` (written as a recipe file).
fn stats_of(tag: &str, text: &str) -> serde_json::Value {
    let dir = tmp(&format!("checks-{tag}"));
    std::fs::write(dir.join("r.yaml"), text).unwrap();
    let out = p3dp(
        &dir,
        &["build", "r.yaml", "-o", "r.gcode", "--stats-json", "s.json"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    v
}

#[test]
fn a_stand_is_printed_first_and_counted() {
    // Kanada's sphere (radius 25, lifted 0.4 mm: z = 0.4 + 25 − √(625 − r²)
    // from its pole) without its brim, bare and on a stand of radius 7
    let text = std::fs::read_to_string(root().join("recipes/sphere.yaml")).unwrap();
    let sphere = |stand: &str| text.replace("brim: {loops: 8}", stand);
    let bare = stats_of("stand-bare", &sphere(""));
    let with = stats_of("stand-with", &sphere("stand: {radius: 7}"));
    // the stand's walls at 7 and 6.55 mm (0.45 apart), 88 and 83 chords of at
    // most 0.5 mm; the nozzle's tip (1 mm) comes within 0.5 mm of the inner
    // wall's inner edge (6.325 mm) over the sphere at r = 5.825 mm, where
    // z = 0.4 + 25 − √(625 − 5.825²) ≈ 1.088: five layers of 0.2 mm fit
    let z = 0.4 + 25.0 - (625.0f64 - 5.825 * 5.825).sqrt();
    let layers = (z / 0.2).floor() as u64;
    assert_eq!(layers, 5);
    // each layer: two closed circles and a travel to each (but the very
    // first), then one travel from the stand to the part
    let per_layer = 88 + 83 + 2;
    let count = |v: &serde_json::Value| {
        v["parts"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == "sphere")
            .unwrap()["strings"]
            .as_u64()
            .unwrap()
    };
    assert_eq!(count(&with) - count(&bare), layers * per_layer);
    let num = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap();
    // its filament: 5 layers of two circles of 0.45 × 0.2 mm² beads, over
    // the filament's area (1.75 mm), less a little for the chords
    let stand_mm =
        5.0 * std::f64::consts::TAU * (7.0 + 6.55) * 0.09 / (std::f64::consts::PI * 0.875 * 0.875);
    let added_mm = num(&with, "filament_length_mm") - num(&bare, "filament_length_mm");
    assert!(
        (added_mm / stand_mm - 1.0).abs() < 0.01,
        "{added_mm} vs {stand_mm}"
    );
    assert!(num(&with, "print_time_s") > num(&bare, "print_time_s"));
    let contact = |v: &serde_json::Value| {
        v["first_layer"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["part"] == "sphere")
            .unwrap()["contact_area_mm2"]
            .as_f64()
            .unwrap()
    };
    assert!(
        contact(&with) > contact(&bare) + 30.0,
        "{} {}",
        contact(&with),
        contact(&bare)
    );
    // a stand past max_strings is refused, naming it
    let limit = count(&with) - 100;
    let over =
        sphere("stand: {radius: 7}").replace("parts:", &format!("max_strings: {limit}\nparts:"));
    let dir = tmp("checks-stand-limit");
    std::fs::write(dir.join("r.yaml"), over).unwrap();
    let out = p3dp(&dir, &["check", "r.yaml"]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("parts[0].stand"), "{err}");
}

/// `-o` asking for a package the printer's firmware does not read is an
/// `output-package` warning, once in the report, the file still written
/// (issue 41): `.bgcode` for a printer without Prusa's Buddy firmware,
/// `.gcode.3mf` for a printer not Bambu Lab's; none for a Prusa MK4S's
/// `.bgcode` nor a Bambu A1's `.gcode.3mf`; `--allow` silences it and
/// `--strict` fails on it as on any warning.
#[test]
fn a_package_the_printer_cannot_read_is_a_warning() {
    let dir = tmp("output-package");
    let sphere = root().join("recipes/sphere.yaml");
    let s = sphere.to_str().unwrap();
    let build = |printer: &str, out: &str, more: &[&str]| {
        let mut args = vec!["build", s, "--printer", printer, "-o", out];
        args.extend(more);
        let o = p3dp(&dir, &args);
        let report = String::from_utf8_lossy(&o.stdout).into_owned();
        (
            o.status.code(),
            report,
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    for (printer, out) in [("prusa-mk4s", "a.bgcode"), ("bambu-a1", "a.gcode.3mf")] {
        let (code, report, err) = build(printer, out, &[]);
        assert_eq!(code, Some(0), "{err}");
        assert!(
            !report.contains("output-package"),
            "{printer} {out}: {report}"
        );
        assert!(report.contains("0 warnings, 0 errors"), "{report}");
    }
    for (printer, out, says) in [
        ("prusa-mk3s", "b.bgcode", "Buddy"),
        ("ender3", "c.bgcode", "Buddy"),
        ("prusa-mk4s", "d.gcode.3mf", "Bambu"),
        ("voron-350", "e.gcode.3mf", "Bambu"),
    ] {
        let (code, report, err) = build(printer, out, &[]);
        assert_eq!(code, Some(0), "{printer} {out}: {err}");
        assert!(dir.join(out).is_file(), "{out} not written");
        assert_eq!(
            report.matches("warning [output-package]: ").count(),
            1,
            "{printer} {out}: {report}"
        );
        assert!(
            report.contains(says) && report.contains(&format!("`{printer}`")),
            "{report}"
        );
        assert!(report.contains("1 warning, 0 errors"), "{report}");
        let (code, report, _) = build(printer, out, &["--allow", "output-package"]);
        assert_eq!(code, Some(0));
        assert!(!report.contains("[output-package]"), "{report}");
        let strict = format!("strict-{out}");
        let (code, _, err) = build(printer, &strict, &["--strict"]);
        assert!(!dir.join(&strict).exists(), "--strict wrote {strict}");
        assert_eq!(code, Some(1), "{printer}: --strict {err}");
        assert!(err.contains("[output-package]"), "{err}");
    }
}
