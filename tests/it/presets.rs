//! Slicer printer presets imported (issue 30): every printer preset of
//! Debian's PrusaSlicer vendor bundles imported and building a small vase
//! on its bed, or refused naming the one thing; the figures of a sample
//! equal to the presets'; Prusa's MK3S start G-code equal to what
//! PrusaSlicer itself writes; `.json` inherits chains of our own writing;
//! the commands' outputs and errors.
//!
//! The slicers' profiles are AGPL: they are read where the system installed
//! them (`.ci/run` installs Debian's `prusa-slicer`), never copied here; the
//! `.json` presets under tests/fixtures/presets are our own text in
//! OrcaSlicer's format.

use std::path::{Path, PathBuf};

use crate::common::{p3dp, root, tmp};
use p3dp::testing::presets as map;
use p3dp::testing::presets::{self as preset, Source};
use p3dp::testing::Insides;
use p3dp::testing::Reads;
use p3dp::testing::{Bed, Flavor, Printer};
use p3dp::{plan, Options};

/// Debian's PrusaSlicer vendor bundles.
const BUNDLES: &str = "/usr/share/PrusaSlicer/profiles";

/// A small vase: one helix wall, 16 mm across and 3 mm high, PLA at 215/60 °C.
const VASE: &str = "p3dp: 1
name: tiny-vase
printer: generic-220
material: {name: PLA, density: 1.24, nozzle_temp: 215, bed_temp: 60}
parts:
  - name: vase
    primitive: {helix: {radius: 8, height: 3, pitch: 0.3, segments: 48, center: [0, 0, 0.2]}}
";

/// Whether a test that needs a program or file the system lacks may skip
/// (locally, with a note) or must fail (in CI).
fn skip(what: &str) -> bool {
    assert!(
        std::env::var_os("CI").is_none(),
        "{what} is missing; .ci/run installs it (CI=true: the test must run)"
    );
    eprintln!("note: skipped: {what} is missing (.ci/run installs it)");
    true
}

fn fixture(name: &str) -> PathBuf {
    root().join("tests/fixtures/presets").join(name)
}

fn bundle(vendor: &str) -> PathBuf {
    Path::new(BUNDLES).join(format!("{vendor}.ini"))
}

/// The preset `name` of `file` as a profile, loaded as `--printer` would.
fn import(file: &Path, name: Option<&str>, profiles: Option<&Path>) -> p3dp::Result<Printer> {
    let src = Source {
        file: file.to_path_buf(),
        preset: name.map(str::to_string),
        profiles: profiles.map(Path::to_path_buf),
    };
    p3dp::testing::profile::from_preset(&src, &Reads::default())
}

/// The vase built on `profile` (a profile's YAML file) in `dir`: its
/// G-code (no thumbnails: they are not the point here) and printer.
fn build_vase(dir: &Path, profile: &Path) -> p3dp::Result<(String, Printer, String)> {
    let recipe = dir.join("vase.yaml");
    if !recipe.exists() {
        std::fs::write(&recipe, VASE).unwrap();
    }
    let opts = Options {
        printer: Some(profile.to_str().unwrap().to_string()),
        ..Default::default()
    };
    let mut plan = plan(&recipe, &opts)?;
    plan.recipe_mut().printer.thumbnails.clear();
    let bytes = p3dp::pipeline::write(&mut plan, &p3dp::pipeline::Job::default(), Vec::new())?.out;
    let text = String::from_utf8(bytes).unwrap();
    Ok((text, plan.recipe().printer.clone(), plan.end_gcode()))
}

/// Every move p3dp writes itself (after the start G-code and before the
/// end G-code `end`) ends on `printer`'s bed, within its height.
fn assert_own_moves_on_bed(text: &str, end: &str, printer: &Printer, what: &str) {
    let from = text
        .find("G21 ; millimetres\n")
        .expect("the start block's end");
    let to = if end.is_empty() {
        text.find("; filament used").unwrap()
    } else {
        text.rfind(end.trim_end()).expect("the end G-code")
    };
    let mut moves = 0;
    for line in text[from..to].lines() {
        let code = line.split(';').next().unwrap().trim();
        let mut words = code.split_whitespace();
        if !matches!(words.next(), Some("G0" | "G1")) {
            assert!(
                !matches!(code.split(' ').next(), Some("G2" | "G3")),
                "{what}: an arc"
            );
            continue;
        }
        moves += 1;
        let mut p = [f64::NAN; 3];
        for w in words {
            let (axis, v) = w.split_at(1);
            let k = "XYZ".find(axis);
            if let Some(k) = k {
                p[k] = v.parse().unwrap();
            }
        }
        let eps = 1e-6;
        if p[2].is_finite() {
            assert!(
                p[2] >= -eps && p[2] <= printer.bed.max_z() + eps,
                "{what}: `{line}`"
            );
        }
        match printer.bed {
            Bed::Rectangle { size, min, .. } => {
                for k in 0..2 {
                    if p[k].is_finite() {
                        assert!(
                            p[k] >= min[k] - eps && p[k] <= min[k] + size[k] + eps,
                            "{what}: `{line}` off the bed {:?}",
                            printer.bed
                        );
                    }
                }
            }
            Bed::Circle { diameter, .. } => {
                if p[0].is_finite() && p[1].is_finite() {
                    assert!(
                        p[0].hypot(p[1]) <= diameter / 2.0 + eps,
                        "{what}: `{line}` off the round bed"
                    );
                }
            }
        }
    }
    assert!(moves >= 480, "{what}: {moves} moves");
}

/// How each preset of the Debian bundles fared.
#[derive(Default, Debug)]
struct Tally {
    built: usize,
    refused_import: Vec<String>,
    refused_build: Vec<String>,
}

#[test]
fn every_debian_printer_preset_builds_a_vase_on_its_bed_or_is_refused_by_name() {
    let dir = Path::new(BUNDLES);
    if !dir.is_dir() && skip(BUNDLES) {
        return;
    }
    let work = tmp("debian-presets");
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ini"))
        .collect();
    files.sort();
    let mut t = Tally::default();
    let mut total = 0;
    for file in &files {
        let names = preset::list(file, &Reads::default()).unwrap();
        for (k, name) in names.iter().enumerate() {
            total += 1;
            let what = format!("{} [{name}]", file.display());
            let src = Source {
                file: file.clone(),
                preset: Some(name.clone()),
                profiles: None,
            };
            let imported = preset::load(&src, &Reads::default()).and_then(|p| map::import(&p));
            let yaml = match imported {
                Ok(i) => i.yaml(),
                Err(e) => {
                    let msg = e.to_string();
                    // the file and the key at fault named
                    assert!(msg.contains(&file.display().to_string()), "{msg}");
                    assert!(msg.contains("p3dp cannot"), "{what}: {msg}");
                    t.refused_import.push(msg);
                    continue;
                }
            };
            let profile = work.join(format!(
                "{}-{k}.yaml",
                file.file_stem().unwrap().to_string_lossy()
            ));
            std::fs::write(&profile, &yaml).unwrap();
            match build_vase(&work, &profile) {
                Ok((text, printer, end)) => {
                    assert_eq!(printer.name, *name);
                    assert_own_moves_on_bed(&text, &end, &printer, &what);
                    t.built += 1;
                }
                Err(e) => {
                    let msg = e.to_string();
                    // refused naming the one line of the maker's G-code
                    assert!(
                        msg.contains("start_gcode line") || msg.contains("end_gcode line"),
                        "{what}: {msg}"
                    );
                    t.refused_build.push(format!("{what}: {msg}"));
                }
            }
        }
    }
    eprintln!(
        "Debian's PrusaSlicer bundles: {total} printer presets in {} files: {} import and build the vase on their bed, {} refused at import, {} refused at the build (a line of the maker's G-code named)",
        files.len(),
        t.built,
        t.refused_import.len(),
        t.refused_build.len()
    );
    for m in t.refused_import.iter().chain(&t.refused_build) {
        eprintln!("  {m}");
    }
    assert_eq!(
        total,
        t.built + t.refused_import.len() + t.refused_build.len()
    );
    // PrusaSlicer 2.5's bundles (Debian bookworm/trixie): 385 presets; the
    // 2 resin printers and the 8 CR-20s without a bed among the refused
    if total == 385 {
        let count = |s: &str| t.refused_import.iter().filter(|m| m.contains(s)).count();
        assert_eq!(count("(resin) printer"), 2);
        assert_eq!(count("without a bed"), 8);
        assert!(t.built >= 320, "{t:?}");
    }
}

/// The sample's figures: the presets' own values, in p3dp's terms.
#[test]
fn sample_presets_keep_their_figures() {
    if !Path::new(BUNDLES).is_dir() && skip(BUNDLES) {
        return;
    }
    let mk3s = import(
        &bundle("PrusaResearch"),
        Some("Original Prusa i3 MK3S & MK3S+"),
        None,
    )
    .unwrap();
    assert_eq!(mk3s.flavor, Flavor::Prusa);
    assert_eq!(
        mk3s.bed,
        Bed::Rectangle {
            size: [250.0, 210.0],
            min: [0.0, 0.0],
            max_z: 210.0
        }
    );
    assert_eq!(mk3s.origin, [125.0, 105.0, 0.0]);
    assert_eq!(mk3s.nozzle_diameter, 0.4);
    assert_eq!(mk3s.model, "MK3S");
    assert_eq!(mk3s.max_speed, 200.0);
    assert_eq!(mk3s.kinematics.max_acceleration, 1250.0);
    assert_eq!(mk3s.kinematics.jerk, Some(8.0));
    assert_eq!(mk3s.retraction.length, 0.8);
    assert_eq!(mk3s.thumbnails, ["160x120/PNG"]);

    // the Voron 2.4 350: PrusaSlicer 2.5 has no Klipper flavour, its
    // Vorons say `marlin`
    let voron = import(
        &bundle("Voron"),
        Some("Voron_v2_350_afterburner 0.4 nozzle"),
        None,
    )
    .unwrap();
    assert_eq!(
        voron.bed,
        Bed::Rectangle {
            size: [350.0, 350.0],
            min: [0.0, 0.0],
            max_z: 350.0
        }
    );
    assert_eq!(voron.origin, [175.0, 175.0, 0.0]);
    assert_eq!(voron.flavor, Flavor::Marlin);
    assert_eq!(voron.nozzle_diameter, 0.4);
    assert_eq!(voron.max_speed, 500.0);
    assert_eq!(voron.kinematics.max_acceleration, 1500.0);
    assert_eq!(voron.kinematics.jerk, Some(10.0));
    assert_eq!(voron.retraction.length, 0.75);
    assert_eq!(voron.retraction.speed, 50.0);
    assert_eq!(voron.thumbnails, ["64x64/PNG", "400x300/PNG"]);

    // the Ender-3: a bed offset by 3 mm (bed_shape 3x3,228x3,228x228,3x228)
    let ender = import(
        &bundle("Creality"),
        Some("Creality Ender-3 (0.4 mm nozzle)"),
        None,
    )
    .unwrap();
    assert_eq!(
        ender.bed,
        Bed::Rectangle {
            size: [225.0, 225.0],
            min: [3.0, 3.0],
            max_z: 250.0
        }
    );
    assert_eq!(ender.origin, [115.5, 115.5, 0.0]);
    assert_eq!(ender.flavor, Flavor::Marlin);
    assert_eq!(ender.model, "ENDER3");
    assert_eq!(ender.max_speed, 500.0);
    assert_eq!(ender.kinematics.max_acceleration, 500.0);
    assert_eq!(ender.kinematics.jerk, Some(8.0));
    assert_eq!(ender.retraction.length, 5.0);
    assert_eq!(ender.retraction.speed, 60.0);

    // a delta: a round bed on the origin
    let delta = import(&bundle("FLSun"), Some("FLSun Q5"), None).unwrap();
    assert_eq!(
        delta.bed,
        Bed::Circle {
            diameter: 200.0,
            max_z: 200.0
        }
    );
    assert_eq!(delta.origin, [0.0, 0.0, 0.0]);
}

/// A cube 10 × 10 × 2 mm as ASCII STL, for PrusaSlicer to slice.
fn cube_stl() -> String {
    let v = |x: u8, y: u8, z: u8| [f64::from(x) * 10.0, f64::from(y) * 10.0, f64::from(z) * 2.0];
    let quads = [
        [v(0, 0, 0), v(0, 1, 0), v(1, 1, 0), v(1, 0, 0)],
        [v(0, 0, 1), v(1, 0, 1), v(1, 1, 1), v(0, 1, 1)],
        [v(0, 0, 0), v(1, 0, 0), v(1, 0, 1), v(0, 0, 1)],
        [v(1, 0, 0), v(1, 1, 0), v(1, 1, 1), v(1, 0, 1)],
        [v(1, 1, 0), v(0, 1, 0), v(0, 1, 1), v(1, 1, 1)],
        [v(0, 1, 0), v(0, 0, 0), v(0, 0, 1), v(0, 1, 1)],
    ];
    let mut s = String::from("solid cube\n");
    for q in quads {
        for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            s.push_str("facet normal 0 0 0\nouter loop\n");
            for p in t {
                s.push_str(&format!("vertex {} {} {}\n", p[0], p[1], p[2]));
            }
            s.push_str("endloop\nendfacet\n");
        }
    }
    s + "endsolid cube\n"
}

/// The lines that are not blank.
fn lines(text: &str) -> Vec<&str> {
    text.lines()
        .map(str::trim_end)
        .filter(|l| !l.is_empty())
        .collect()
}

/// Prusa's MK3S start G-code, every placeholder resolved from the recipe
/// (PLA at 215/60 °C, 0.2 mm first layer), is the text PrusaSlicer itself
/// writes for the same preset and temperatures.
#[test]
fn mk3s_start_gcode_is_what_prusaslicer_writes() {
    if !Path::new(BUNDLES).is_dir() && skip(BUNDLES) {
        return;
    }
    let name = "Original Prusa i3 MK3S & MK3S+";
    let dir = tmp("mk3s-vs-prusaslicer");
    let src = Source {
        file: bundle("PrusaResearch"),
        preset: Some(name.into()),
        profiles: None,
    };
    let preset = preset::load(&src, &Reads::default()).unwrap();
    let profile = dir.join("mk3s.yaml");
    std::fs::write(&profile, map::import(&preset).unwrap().yaml()).unwrap();
    let (text, _, _) = build_vase(&dir, &profile).unwrap();
    let opts = Options {
        printer: Some(profile.to_str().unwrap().into()),
        ..Default::default()
    };
    let ours = plan(&dir.join("vase.yaml"), &opts).unwrap().start_gcode();
    assert!(text.contains(&ours));
    assert!(ours.contains("M862.3 P \"MK3S\""), "{ours}");
    assert!(
        ours.contains("M104 S215") && ours.contains("M190 S60"),
        "{ours}"
    );

    // the same preset, flattened, for PrusaSlicer's --load
    let mut ini = String::new();
    for (k, v) in &preset.values {
        if let preset::Setting::Ini(v) = v {
            ini.push_str(&format!("{k} = {v}\n"));
        }
    }
    std::fs::write(dir.join("mk3s.ini"), ini).unwrap();
    std::fs::write(dir.join("cube.stl"), cube_stl()).unwrap();
    let run = std::process::Command::new("prusa-slicer")
        .args(["--export-gcode", "--load", "mk3s.ini"])
        .args(["--first-layer-temperature", "215", "--temperature", "215"])
        .args([
            "--first-layer-bed-temperature",
            "60",
            "--bed-temperature",
            "60",
        ])
        .args(["--layer-height", "0.2", "--first-layer-height", "0.2"])
        .args(["-o", "ps.gcode", "cube.stl"])
        .current_dir(&dir)
        .output();
    let Ok(run) = run else {
        skip("prusa-slicer");
        return;
    };
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let theirs = std::fs::read_to_string(dir.join("ps.gcode")).unwrap();
    let (ours, theirs) = (lines(&ours), lines(&theirs));
    // machine_limits_usage = emit_to_gcode: the firmware's limits first, each
    // word the figure PrusaSlicer writes (its text differs: `X8.00`, comments)
    let limits = ours
        .iter()
        .take_while(|l| {
            ["M201 ", "M203 ", "M204 ", "M205 "]
                .iter()
                .any(|c| l.starts_with(c))
        })
        .count();
    assert_eq!(limits, 4, "{ours:?}");
    let words = |l: &str| -> Vec<(char, f64)> {
        l.split(';')
            .next()
            .unwrap()
            .split_whitespace()
            .skip(1)
            .map(|w| (w.chars().next().unwrap(), w[1..].parse::<f64>().unwrap()))
            .collect()
    };
    for l in &ours[..limits] {
        let code = l.split_whitespace().next().unwrap();
        let t = theirs
            .iter()
            .find(|t| t.starts_with(&format!("{code} ")) && !t.starts_with("M205 S"))
            .unwrap_or_else(|| panic!("PrusaSlicer writes no {code}"));
        let tw = words(t);
        for w in words(l) {
            assert!(tw.contains(&w), "{l} against PrusaSlicer's {t}");
        }
    }
    let ours = &ours[limits..];
    let at = theirs
        .iter()
        .position(|l| *l == ours[0])
        .expect("PrusaSlicer's start G-code");
    assert_eq!(ours, &theirs[at..at + ours.len()]);
}

/// A variable p3dp cannot give is refused, naming it and its line, by
/// `printers import` and by `build --printer FILE.ini` alike (exit 2).
#[test]
fn an_unknown_variable_is_refused_naming_it_and_its_line() {
    let dir = tmp("unknown-variable");
    std::fs::write(dir.join("vase.yaml"), VASE).unwrap();
    let ini = fixture("unknown.ini");
    let ini = ini.to_str().unwrap();
    for args in [
        vec!["printers", "import", ini],
        vec!["build", "vase.yaml", "--printer", ini, "-o", "v.gcode"],
    ] {
        let out = p3dp(&dir, &args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains("unknown.ini"), "{err}");
        assert!(err.contains("start_gcode line 3"), "{err}");
        assert!(err.contains("`bed_probe_temperature`"), "{err}");
        assert!(!dir.join("v.gcode").exists());
    }
}

/// An OrcaSlicer-style chain: a user preset beside its file inherits a
/// system preset of `--profiles DIR/machine`, which inherits a base found
/// by its `"name"` (not its file name), which inherits
/// `fdm_machine_common`; each level's keys over its parents'.
#[test]
fn json_inherits_chains_resolve_through_the_folder_and_profiles() {
    let user = fixture("orca/user/My Acme.json");
    let profiles = fixture("orca/profiles/Acme");
    let e = import(&user, None, None).unwrap_err().to_string();
    assert!(
        e.contains("`My Acme` inherits `Acme One 0.4 nozzle`") && e.contains("--profiles"),
        "{e}"
    );
    let p = import(&user, None, Some(&profiles)).unwrap();
    assert_eq!(p.name, "My Acme");
    assert_eq!(p.model, "Acme One");
    assert_eq!(p.flavor, Flavor::Klipper);
    assert_eq!(p.nozzle_diameter, 0.6); // the user's
    assert_eq!(p.retraction.length, 0.5); // the user's
    assert_eq!(p.retraction.speed, 30.0); // fdm_acme_common's
    assert_eq!(p.max_speed, 500.0); // min of x 600, y 500
    assert_eq!(p.kinematics.max_acceleration, 8000.0);
    assert_eq!(
        p.bed,
        Bed::Rectangle {
            size: [250.0, 230.0],
            min: [-5.0, -5.0],
            max_z: 250.0
        }
    );
    assert_eq!(p.origin, [120.0, 110.0, 0.0]);
    assert_eq!(p.thumbnails, ["48x48/QOI", "300x300/PNG"]);

    let e = import(&fixture("cycle/a.json"), None, None).unwrap_err();
    assert!(
        e.to_string().contains("an inherits cycle: A → B → A"),
        "{e}"
    );
}

/// `printers import -o` writes a profile that builds: the maker's start
/// G-code with the first layer's extent (OrcaSlicer's adaptive purge) and
/// the plate a default the profile shows; never over an input.
#[test]
fn imported_json_profile_builds_with_its_start_gcode() {
    let dir = tmp("orca-import");
    std::fs::write(dir.join("vase.yaml"), VASE).unwrap();
    let user = fixture("orca/user/My Acme.json");
    let profiles = fixture("orca/profiles/Acme");
    let (user, profiles) = (user.to_str().unwrap(), profiles.to_str().unwrap());
    let import = ["printers", "import", user, "--profiles", profiles];
    let out = p3dp(&dir, &[&import[..], &["-o", "acme.yaml"]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let yaml = std::fs::read_to_string(dir.join("acme.yaml")).unwrap();
    assert!(
        yaml.contains("curr_bed_type: \"Textured PEI Plate\""),
        "{yaml}"
    );
    let out = p3dp(
        &dir,
        &[
            "build",
            "vase.yaml",
            "--printer",
            "acme.yaml",
            "-o",
            "v.gcode",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let g = std::fs::read_to_string(dir.join("v.gcode")).unwrap();
    // the vase's first turn: radius 8 about the origin (120, 110); the
    // purge 5 mm before the corner of what lies below twice the first
    // layer's height (the helix rises 0.3 mm a turn from 0.2 mm, so its
    // lowest y, at 270°, is past 0.4 mm: the least y is 103.07, at 240°),
    // as long as the first layer is wide over 20
    for line in [
        "M140 S60",
        "M109 S215",
        "; plate: Textured PEI Plate",
        "G1 X107 Y98.0718 Z0.3 F6000",
        "G1 X133 E0.8 F1200",
        "; thumbnail_QOI begin 48x48",
        "; thumbnail begin 300x300",
    ] {
        assert!(g.contains(line), "{line}:\n{}", &g[..2000.min(g.len())]);
    }
    // never over an input: the preset or a parent
    let parent = fixture("orca/profiles/Acme/machine/acme-common.json");
    let before = std::fs::read(&parent).unwrap();
    let out = p3dp(
        &dir,
        &[&import[..], &["-o", parent.to_str().unwrap()]].concat(),
    );
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(std::fs::read(&parent).unwrap(), before);
}

/// Files that are no preset, or not text, or too big: exit 2, the file named.
#[test]
fn bad_preset_files_are_refused_naming_the_file() {
    let dir = tmp("bad-presets");
    let cases: [(&str, Vec<u8>, &str); 5] = [
        ("list.json", b"[1, 2]".to_vec(), "expected a JSON object"),
        (
            "filament.json",
            br#"{"type": "filament", "name": "PLA"}"#.to_vec(),
            "`filament` preset",
        ),
        (
            "prose.ini",
            b"Dear printer,\nplease print.\n".to_vec(),
            "not a slicer preset",
        ),
        (
            "latin1.ini",
            b"bed_shape = 0x0\nprinter_notes = caf\xe9\n".to_vec(),
            "UTF-8",
        ),
        (
            "nobed.ini",
            b"max_print_height = 100\n".to_vec(),
            "without a bed",
        ),
    ];
    for (name, bytes, expect) in &cases {
        std::fs::write(dir.join(name), bytes).unwrap();
        let out = p3dp(&dir, &["printers", "import", name]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(name) && err.contains(expect), "{name}: {err}");
        assert!(out.stdout.is_empty(), "{name}");
    }
    let huge = std::fs::File::create(dir.join("huge.ini")).unwrap();
    huge.set_len((16 << 20) + 1) // one byte over the cap on text inputs (16 MiB)
        .unwrap();
    let out = p3dp(&dir, &["printers", "list", "huge.ini"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("huge.ini"), "{err}");
}

/// `p3dp printers list FILE` names a bundle's presets but its abstract bases.
#[test]
fn printers_list_names_a_bundles_presets() {
    if !Path::new(BUNDLES).is_dir() && skip(BUNDLES) {
        return;
    }
    let out = p3dp(
        Path::new("."),
        &["printers", "list", bundle("Voron").to_str().unwrap()],
    );
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text
        .lines()
        .any(|l| l == "Voron_v2_350_afterburner 0.4 nozzle"));
    assert!(!text.contains('*'), "abstract presets listed:\n{text}");
}

/// `--printer FILE.ini` takes an exported config (one preset, no sections)
/// directly: its bed, its offset origin and its start G-code, resolved.
#[test]
fn an_exported_config_is_a_printer_directly() {
    let dir = tmp("exported-config");
    std::fs::write(dir.join("vase.yaml"), VASE).unwrap();
    std::fs::write(
        dir.join("mine.ini"),
        "# written for p3dp's tests\nbed_shape = 10x0,210x0,210x180,10x180\nmax_print_height = 150\nnozzle_diameter = 0.6\ngcode_flavor = marlin2\nprinter_model = M1\nstart_gcode = G28\\nM190 S[first_layer_bed_temperature]\\nM109 S{first_layer_temperature[0] + 5}\\nG1 X{print_bed_min[0] + 5} Y2 Z0.3 F3000 ; [printer_model]\nend_gcode = M104 S0\\nG1 Z{max_layer_z + 10} F600\nprinter_settings_id = Mine\n",
    )
    .unwrap();
    let out = p3dp(&dir, &["printers", "list", "mine.ini"]);
    assert_eq!(String::from_utf8_lossy(&out.stdout), "Mine\n");
    let out = p3dp(
        &dir,
        &[
            "build",
            "vase.yaml",
            "--printer",
            "mine.ini",
            "-o",
            "v.gcode",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let g = std::fs::read_to_string(dir.join("v.gcode")).unwrap();
    assert!(g.contains("; printer: Mine (Marlin)"), "{g}");
    // the start G-code first (after the progress line Marlin 2 shows)
    let code: Vec<&str> = g
        .lines()
        .filter(|l| !l.starts_with(';') && !l.starts_with("M73 "))
        .collect();
    assert_eq!(
        code[..5],
        [
            "G28",
            "M190 S60",
            "M109 S220",
            "G1 X15 Y2 Z0.3 F3000 ; M1",
            "G21 ; millimetres"
        ]
    );
    // the vase about the bed's centre (110, 90), 3 mm high from 0.2
    assert!(g.contains("G0 X118.000 Y90.000 Z0.200"), "{g}");
    assert!(g.contains("G1 Z13.2 F600"), "{g}");
}

/// `p3dp build RECIPE ARGS…` in `dir`: the G-code written to `v.gcode`, or
/// the error text (exit 2).
fn build_with(dir: &Path, args: &[&str]) -> Result<String, String> {
    let mut all = vec!["build", "vase.yaml", "-o", "v.gcode"];
    all.extend_from_slice(args);
    let _ = std::fs::remove_file(dir.join("v.gcode"));
    let out = p3dp(dir, &all);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    if out.status.success() {
        Ok(std::fs::read_to_string(dir.join("v.gcode")).unwrap())
    } else {
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(!dir.join("v.gcode").exists());
        Err(err)
    }
}

/// `p3dp printers import FILE [--profiles DIR] -o OUT` run in `dir`.
fn import_to(dir: &Path, file: &Path, profiles: Option<&Path>, out: &str) -> std::process::Output {
    let mut args = vec!["printers", "import", path(file)];
    if let Some(p) = profiles {
        args.extend(["--profiles", path(p)]);
    }
    args.extend(["-o", out]);
    p3dp(dir, &args)
}

fn vase_dir(name: &str) -> crate::common::Tmp {
    let dir = tmp(name);
    std::fs::write(dir.join("vase.yaml"), VASE).unwrap();
    dir
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every line of `g` that is not blank.
fn has_lines(g: &str, lines: &[&str]) {
    for l in lines {
        assert!(
            g.lines().any(|x| x == *l),
            "`{l}` missing in:\n{}",
            &g[..g.len().min(3000)]
        );
    }
}

/// Bambu Studio's presets keep their start and end G-code in template
/// presets they `include`: the build uses the template's G-code, not the
/// parent's placeholder, every variable filled from the printer, the
/// filament preset and the print; an include that cannot be found is
/// refused by name.
#[test]
fn a_bambu_include_is_resolved_or_refused_by_name() {
    let dir = vase_dir("bambu-include");
    let b1 = fixture("bbl/machine/Acme B1 0.4 nozzle.json");
    let pla = fixture("bbl/filament/Acme PLA.json");
    let g = build_with(&dir, &["--printer", path(&b1), "--filament", path(&pla)]).unwrap();
    assert!(!g.contains("placeholder"), "the parent's G-code:\n{g}");
    has_lines(
        &g,
        &[
            ";===== machine: Acme B1 (written for p3dp's tests) =====",
            "; printer Acme B1 0.4 nozzle, 16 layers",
            "M140 S60",
            // the flush at the top of the filament's range (Bambu Studio's
            // rule), at its flow limit: 18 mm³/s / 2.4053 mm² × 60
            "M109 S240 ; flush at the range's top",
            "G1 E5 F449.008",
            "M104 S215",
            "M109 S215",
            "; textured plate",
            "; soft filament: door open",
            "; chamber: 0 (minimum 0)",
            "; range 190-240, 18 mm3/s",
            ";===== Acme B1 end =====",
        ],
    );
    // the notes' line breaks (a line feed and U+2028) stay inside the comment
    let notes = g
        .lines()
        .find(|l| l.starts_with("; filament notes: "))
        .unwrap();
    assert_eq!(
        notes,
        "; filament notes: an Acme PLA\\u{a}M104 S999\\u{2028}M140 S999"
    );
    assert!(!g
        .lines()
        .any(|l| l.starts_with("M104 S999") || l.starts_with("M140 S999")));
    // the material is the filament preset's
    assert!(g.contains("Acme PLA"), "{}", &g[g.len() - 2000..]);

    let broken = fixture("bbl/machine/Acme B1 missing template.json");
    for args in [
        vec!["printers", "import", path(&broken)],
        vec![
            "build",
            "vase.yaml",
            "--printer",
            path(&broken),
            "-o",
            "v.gcode",
        ],
    ] {
        let out = p3dp(&dir, &args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains("`Acme B1 missing template` includes `Acme B1 0.4 nozzle template wrapping_detection_gcode`, found in none of"),
            "{err}"
        );
    }
}

/// Elegoo keeps a preset's parent in a sibling folder (`machine/ECC/` for
/// `machine/EC/`); its jerk of 20000 is no square-corner velocity (Klipper's
/// 5 mm/s stands) and its `bed_shape = rectangular` yields to the corners of
/// `printable_area`.
#[test]
fn a_parent_in_a_sibling_folder_and_the_makers_odd_values() {
    let dir = vase_dir("elegoo-sibling");
    let e = fixture("elegoo/machine/EC/Acme E 0.4 nozzle.json");
    let p = import(&e, None, None).unwrap();
    assert_eq!(p.flavor, Flavor::Klipper);
    assert_eq!(p.kinematics.square_corner_velocity, Some(5.0));
    assert_eq!(
        p.bed,
        Bed::Rectangle {
            size: [256.0, 256.0],
            min: [0.0, 0.0],
            max_z: 256.0
        }
    );
    let g = build_with(&dir, &["--printer", path(&e)]).unwrap();
    has_lines(
        &g,
        &[
            "PRINT_START BED=60 HOTEND=215 CHAMBER=0",
            "; Acme E 0.4 nozzle",
        ],
    );
}

/// `--filament FILE.ini --filament-preset NAME` gives the material (its
/// temperatures, flow limit) and the filament's variables; without it the
/// recipe's material gives them, each from a stated source.
#[test]
fn a_filament_preset_gives_the_material_and_its_variables() {
    let dir = vase_dir("filament-ini");
    let ini = fixture("acme.ini");
    for (name, out) in [("Acme Mini", "mini.yaml"), ("Acme Mini HF0.6", "hf.yaml")] {
        let o = p3dp(
            &dir,
            &[
                "printers",
                "import",
                path(&ini),
                "--preset",
                name,
                "-o",
                out,
            ],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let g = build_with(
        &dir,
        &[
            "--printer",
            "mini.yaml",
            "--filament",
            path(&ini),
            "--filament-preset",
            "Acme PLA",
        ],
    )
    .unwrap();
    has_lines(
        &g,
        &[
            "; nozzle check: P0.4 A0 F0",
            "; Acme Mini for Acme PLA",
            "; chamber 0, at least 0; idle 100",
            "M140 S60",
            "M104 S170",
            "M109 S210",
        ],
    );
    assert!(g.contains("; filament notes: \"Acme's own PLA.\"\\u{a}M104 S999 ; a second line is text, never G-code"));
    assert!(!g.lines().any(|l| l.starts_with("M104 S999")));
    let g = build_with(
        &dir,
        &[
            "--printer",
            "mini.yaml",
            "--filament",
            path(&ini),
            "--filament-preset",
            "Acme PLA-CF",
        ],
    )
    .unwrap();
    has_lines(&g, &["; nozzle check: P0.4 A1 F0", "M109 S230"]);
    let g = build_with(
        &dir,
        &[
            "--printer",
            "hf.yaml",
            "--filament",
            path(&ini),
            "--filament-preset",
            "Acme PLA",
        ],
    )
    .unwrap();
    has_lines(&g, &["; nozzle check: P0.6 A0 F1"]);
    // the recipe's own material: PLA at 215/60 °C, not abrasive, no notes
    let g = build_with(&dir, &["--printer", "mini.yaml"]).unwrap();
    has_lines(
        &g,
        &[
            "; nozzle check: P0.4 A0 F0",
            "; Acme Mini for PLA",
            "; filament notes: ",
            "; chamber 0, at least 0; idle 0",
            "M109 S215",
        ],
    );
    // a filament preset not in the file: named, the closest offered
    let e = build_with(
        &dir,
        &[
            "--printer",
            "mini.yaml",
            "--filament",
            path(&ini),
            "--filament-preset",
            "Acme PLA CF",
        ],
    )
    .unwrap_err();
    assert!(
        e.contains("no filament preset `Acme PLA CF`") && e.contains("did you mean `Acme PLA-CF`"),
        "{e}"
    );
}

/// The filament preset's figures become p3dp's material: the checks hold
/// the print to its temperatures and its flow limit.
#[test]
fn a_filament_presets_figures_are_the_materials() {
    let ini = fixture("acme.ini");
    let src = Source {
        file: ini.clone(),
        preset: Some("Acme PLA".into()),
        profiles: None,
    };
    let p = preset::load_filament(&src, &Reads::default()).unwrap();
    assert_eq!(p.kind, preset::Kind::Filament);
    assert_eq!(p.text("first_layer_temperature").as_deref(), Some("215"));
    let json = fixture("bbl/filament/Acme PLA.json");
    let p = preset::load_filament(
        &Source {
            file: json,
            ..Default::default()
        },
        &Reads::default(),
    )
    .unwrap();
    // the parent found in the vendor folder's sub-folder (filament/base/)
    assert_eq!(
        p.text("nozzle_temperature_range_high").as_deref(),
        Some("240")
    );
    assert_eq!(p.text("filament_density").as_deref(), Some("1.24"));
    let out = p3dp(
        Path::new("."),
        &["printers", "list", "--filaments", path(&ini)],
    );
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "Acme PLA\nAcme PLA-CF\n"
    );
}

/// A multi-tool machine (a 5-tool changer, a 5-slot filament changer, a
/// two-nozzle Bambu whose main nozzle is its second) prints with the tool
/// its maker's start G-code selects, the others left cold.
#[test]
fn multi_tool_machines_print_with_the_tool_their_start_gcode_selects() {
    let dir = vase_dir("multi-tool");
    let ini = fixture("acme.ini");
    for (name, out) in [("Acme XL 5T", "xl.yaml"), ("Acme MK MMU3", "mmu.yaml")] {
        let o = p3dp(
            &dir,
            &[
                "printers",
                "import",
                path(&ini),
                "--preset",
                name,
                "-o",
                out,
            ],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let xl = p3dp::testing::profile::from_file(&dir.join("xl.yaml")).unwrap();
    assert_eq!((xl.extruders, xl.tool), (5, 0));
    let g = build_with(&dir, &["--printer", "xl.yaml"]).unwrap();
    has_lines(
        &g,
        &[
            "; 5 tools, Acme XL 5T",
            "M104 T0 S175",
            "T0",
            "M109 T0 S215",
            "G1 E1.5 F2400",
        ],
    );
    for t in 1..5 {
        assert!(!g.contains(&format!("M104 T{t}")), "tool {t} heated");
    }
    let g = build_with(&dir, &["--printer", "mmu.yaml"]).unwrap();
    has_lines(
        &g,
        &[
            "; nozzle check: P0.4 A0",
            "; loading -13 mm, parking 85 mm",
            "T0",
        ],
    );
    let d2 = fixture("bbl/machine/Acme D2 0.4 nozzle.json");
    let p = import(&d2, None, None).unwrap();
    assert_eq!((p.extruders, p.tool), (2, 1));
    // one note says which extruder prints, not two that disagree
    let o = import_to(&dir, &d2, None, "d2.yaml");
    let notes = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{notes}");
    let tool_notes: Vec<&str> = notes
        .lines()
        .filter(|l| l.contains("p3dp prints with"))
        .collect();
    assert_eq!(tool_notes.len(), 1, "{notes}");
    assert!(
        tool_notes[0].contains("extruder 2, the main one"),
        "{notes}"
    );
    let g = build_with(&dir, &["--printer", path(&d2)]).unwrap();
    has_lines(
        &g,
        &[
            "M104 S215 T0 ; the main nozzle",
            "; calibration temperatures 215 and 215",
            "T0",
            "; nozzle 0.4 of 2",
        ],
    );
    assert!(!g.contains("M104 T1"), "the second nozzle heated");
}

/// PrusaSlicer's reading of a multi-tool template: an index past a
/// vector's end reads its first element, the start G-code's
/// `e_retracted[t]` is read back and unretracted before the print, and
/// Buddy's tool park (`P0`) and MMU test load (`M1704`) are the firmware's
/// own motion; a `.json` G-code written on one line with `\n` is read as
/// OrcaSlicer reads it.
#[test]
fn a_template_for_five_tools_on_two_and_its_retraction_read_back() {
    let dir = vase_dir("xl-2t");
    let ini = fixture("acme.ini");
    let o = p3dp(
        &dir,
        &[
            "printers",
            "import",
            path(&ini),
            "--preset",
            "Acme XL 2T",
            "-o",
            "xl2.yaml",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let g = build_with(&dir, &["--printer", "xl2.yaml"]).unwrap();
    has_lines(
        &g,
        &[
            "; tool four reads 215 as PrusaSlicer does",
            "M1704 P0 ; MMU test load",
            "P0 S1 L1 D0 ; park the tool",
            "G1 E-1.5 F2400 ; retract",
            "M83 ; relative E for the unretraction",
            "G1 E1.5 F2100 ; unretract what the start G-code retracted (e_retracted, e_restart_extra)",
        ],
    );
    // the unretraction follows the start G-code, before p3dp's own modes
    let at = |l: &str| g.find(l).unwrap();
    assert!(at("G92 E0\nM83 ; relative E") < at("G21 ; millimetres"));
    for t in 1..5 {
        assert!(!g.contains(&format!("M104 T{t}")), "tool {t} heated");
    }
    // without the assignment, nothing is unretracted
    let plain = std::fs::read_to_string(dir.join("xl2.yaml"))
        .unwrap()
        .replace(
            "{e_retracted[initial_tool] = retract_length_toolchange[initial_tool]}",
            "",
        );
    std::fs::write(dir.join("plain.yaml"), plain).unwrap();
    let g = build_with(&dir, &["--printer", "plain.yaml"]).unwrap();
    assert!(!g.contains("unretract what the start G-code"), "{g}");
    // a setting of the slicer's is still read-only
    let bad = std::fs::read_to_string(dir.join("xl2.yaml"))
        .unwrap()
        .replace(
            "{e_retracted[initial_tool] =",
            "{retract_length[initial_tool] =",
        );
    std::fs::write(dir.join("bad.yaml"), bad).unwrap();
    let e = build_with(&dir, &["--printer", "bad.yaml"]).unwrap_err();
    assert!(
        e.contains("`retract_length` is no variable of `local` or `global`"),
        "{e}"
    );

    // OrcaSlicer's C escapes in a `.json` string
    let json = dir.join("Acme U1.json");
    std::fs::write(
        &json,
        r#"{"type": "machine", "name": "Acme U1", "instantiation": "true", "gcode_flavor": "klipper",
"printable_area": ["0x0", "270x0", "270x270", "0x270"], "printable_height": "270", "nozzle_diameter": ["0.4"],
"machine_start_gcode": "G28\\nM117 \\\"U1\\\" start\\n{if printer_preset==\\\"Acme U1\\\"}; named{else}; other{endif}\\nM109 S[nozzle_temperature_initial_layer]",
"machine_end_gcode": "M104 S0\\nM84"}"#,
    )
    .unwrap();
    let g = build_with(&dir, &["--printer", path(&json)]).unwrap();
    has_lines(&g, &["G28", "M117 \"U1\" start", "; named", "M84"]);
    assert!(!g.contains("\\n"), "{g}");
}

/// A preset maps to the profile's own type: what `--printer FILE` builds
/// with is what `printers import` writes, read back — for every preset of
/// the fixtures.
#[test]
fn an_imported_profile_written_as_yaml_is_the_same_printer() {
    let dir = tmp("import-round-trip");
    let ini = fixture("acme.ini");
    let mut cases: Vec<(PathBuf, Option<String>)> = preset::list(&ini, &Reads::default())
        .unwrap()
        .into_iter()
        .filter(|n| n != "Acme Bad Variable")
        .map(|n| (ini.clone(), Some(n)))
        .collect();
    for f in [
        "bbl/machine/Acme B1 0.4 nozzle.json",
        "bbl/machine/Acme D2 0.4 nozzle.json",
        "elegoo/machine/EC/Acme E 0.4 nozzle.json",
        "orca/profiles/Acme/machine/Acme One 0.4 nozzle.json",
    ] {
        cases.push((fixture(f), None));
    }
    for (k, (file, name)) in cases.iter().enumerate() {
        let mut direct = import(file, name.as_deref(), None).unwrap();
        let out = dir.join(format!("p{k}.yaml"));
        let mut args = vec!["printers", "import", path(file), "-o", path(&out)];
        if let Some(n) = name {
            args.extend(["--preset", n]);
        }
        let o = p3dp(&dir, &args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let mut back = p3dp::testing::profile::from_file(&out).unwrap();
        (direct.source, back.source) = (None, None);
        assert_eq!(direct, back, "{file:?} {name:?}");
    }
}

/// A `.json` chain's files lie in the preset's project or slicer folder:
/// a parent that is a symlink out of it is refused, as a YAML profile's
/// `inherits` is.
#[cfg(unix)]
#[test]
fn a_json_parent_linked_out_of_the_project_is_refused() {
    let dir = tmp("json-symlink");
    let outside = dir.join("outside");
    let project = dir.join("project");
    std::fs::create_dir_all(&outside).unwrap();
    std::fs::create_dir_all(project.join(".git")).unwrap();
    std::fs::write(
        outside.join("secret.json"),
        r#"{"type": "machine", "name": "base", "printable_area": ["0x0", "200x0", "200x200", "0x200"], "printable_height": "200"}"#,
    )
    .unwrap();
    std::os::unix::fs::symlink(outside.join("secret.json"), project.join("base.json")).unwrap();
    std::fs::write(
        project.join("mine.json"),
        r#"{"type": "machine", "name": "mine", "inherits": "base"}"#,
    )
    .unwrap();
    let out = p3dp(&project, &["printers", "import", "mine.json"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("outside the folders this build may read"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
}

/// `--profiles` holding thousands of links to one big file: the folder is
/// scanned once, each real file read once, within a cap on files and bytes.
#[cfg(unix)]
#[test]
fn a_profile_folder_of_links_to_one_big_file_is_scanned_once() {
    let dir = tmp("json-links");
    // one 15 MB preset, linked 8000 times: the folder made once in the
    // target folder and kept (8000 new inodes on every run cost ext4 up to
    // seconds of searching its recently deleted ones)
    let profiles = links_to_one_big_preset();
    std::fs::write(
        dir.join("mine.json"),
        r#"{"type": "machine", "name": "mine", "inherits": "nowhere", "printable_area": ["0x0", "200x0", "200x200", "0x200"], "printable_height": "200"}"#,
    )
    .unwrap();
    let t = std::time::Instant::now();
    let out = p3dp(
        &dir,
        &[
            "printers",
            "import",
            "mine.json",
            "--profiles",
            profiles.to_str().unwrap(),
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("`mine` inherits `nowhere`, found in none of"),
        "{err}"
    );
    assert!(err.contains("stopped at its cap of 4000 files"), "{err}");
    // unbounded, 8000 parses of 15 MB take minutes
    assert!(t.elapsed().as_secs_f64() < 30.0, "{:?}", t.elapsed());
}

/// A profile folder of 8000 links to one 15 MB preset (`machine/l0000.json`
/// …), in the tests' folder of the target directory: made whole once (in a
/// folder of its own, renamed into place) and reused by later runs.
fn links_to_one_big_preset() -> std::path::PathBuf {
    const LINKS: usize = 8000;
    let root = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let done = root.join("json-links-8000");
    if done
        .join("machine")
        .join(format!("l{:04}.json", LINKS - 1))
        .exists()
    {
        return done;
    }
    let making = root.join(format!("json-links-making-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&making);
    std::fs::create_dir_all(making.join("machine")).unwrap();
    let big = done.join("big.json");
    let pad = "x".repeat(15 << 20);
    std::fs::write(
        making.join("big.json"),
        format!(r#"{{"type": "machine", "name": "big", "printer_notes": "{pad}"}}"#),
    )
    .unwrap();
    for k in 0..LINKS {
        std::os::unix::fs::symlink(&big, making.join(format!("machine/l{k:04}.json"))).unwrap();
    }
    let _ = std::fs::remove_dir_all(&done);
    std::fs::rename(&making, &done).unwrap();
    done
}

/// A Bambu printer's own sequence (a preset written for the tests in its
/// style): imported as Bambu's firmware, its purge chute and the plate's
/// bare edge the profile's reach, its flush above the filament's limit
/// accepted as the maker's, every command read as the firmware reads it;
/// each of those moved past what the maker wrote is refused by name.
#[test]
fn a_bambu_sequence_builds_with_its_reach_and_flush() {
    let dir = vase_dir("bambu-sequence");
    let t9 = fixture("bbl/machine/Acme T9 0.4 nozzle.json");
    let pla = fixture("bbl/filament/Acme PLA.json");
    let out = p3dp(&dir, &["printers", "import", path(&t9), "-o", "t9.yaml"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let yaml = std::fs::read_to_string(dir.join("t9.yaml")).unwrap();
    for line in [
        "flavor: bambu",
        "envelope: { margin: 5, below_bed: 1.01, x: [-48.2, 261] }",
        "maker_temperatures: true",
        "# - envelope.x [-48.2, 261]: where the maker's own G-code takes the head (start_gcode line 16: `G1 X-48.2 Y10 F12000`), past the bed grown by 5 mm",
        "# - envelope.below_bed 1.01: where the maker's own G-code takes the nozzle below the bed (start_gcode line 20: `G0 X128 Y261 Z-1.01 F1200`)",
    ] {
        assert!(yaml.lines().any(|l| l == line), "no `{line}` in\n{yaml}");
    }
    let g = build_with(&dir, &["--printer", "t9.yaml", "--filament", path(&pla)]).unwrap();
    has_lines(
        &g,
        &[
            "G392 S0 ; clog detection off",
            "M109 S250 ; flush hotter than the filament prints",
            "G1 X-48.2 Y10 F12000 ; to the purge chute",
            "G0 X128 Y261 Z-1.01 F1200 ; stop the nozzle on the plate's bare edge",
            "M109 S215",
            "G1 X-48.2 F12000 ; park at the chute",
        ],
    );
    // the same preset built directly reads the same
    let direct = build_with(&dir, &["--printer", path(&t9), "--filament", path(&pla)]).unwrap();
    assert!(direct.contains("G1 X-48.2 Y10 F12000 ; to the purge chute"));

    let edited = |from: &str, to: &str| {
        assert!(yaml.contains(from), "{from}");
        std::fs::write(dir.join("edited.yaml"), yaml.replace(from, to)).unwrap();
        build_with(
            &dir,
            &["--printer", "edited.yaml", "--filament", path(&pla)],
        )
        .unwrap_err()
    };
    let e = edited("G1 X-48.2 Y10 F12000", "G1 X-60 Y10 F12000");
    assert!(
        e.contains("start_gcode line 16: `G1 X-60 Y10 F12000 ; to the purge chute`: x = -60 mm is outside the machine's travel envelope (x from -48.2 to 261 mm: the profile's envelope.x)"),
        "{e}"
    );
    let e = edited("maker_temperatures: true", "maker_temperatures: false");
    assert!(
        e.contains("`M109 S250 ; flush hotter than the filament prints`: a nozzle temperature of 250 °C, above the limit"),
        "{e}"
    );
    // the print would start at the flush temperature
    let e = edited(
        "M109 S{nozzle_temperature_initial_layer[initial_no_support_extruder]}",
        "M117 no print temperature",
    );
    assert!(
        e.contains("start_gcode line 15: `M109 S250 ; flush hotter than the filament prints`: the print would start at 250 °C, above the limit"),
        "{e}"
    );
    let e = edited("G29.1 Z-0.04", "G29.1 Z-4");
    assert!(e.contains("offsets the coordinates by Z -4 mm"), "{e}");
    let e = edited("M211 R", "M290 X40 Y40 Z2");
    assert!(e.contains("`M290` is refused"), "{e}");
}

/// The constructs of Bambu's current start G-code (a preset written for the
/// tests in their style, issue 39): the X1's "reset machine status"
/// `M290`, the H2's `M901 D4`, the hot end's power off and on around the
/// camera's start (`M562`), a flush at 290 °C that sets the printer's
/// `max_nozzle_temp` where the preset names none (the X1E's), and a wipe in
/// circles at the plate's edge whose sweep sets the reach along Y (the A1
/// mini's); each moved past what the maker wrote is refused by name.
#[test]
fn bambus_current_start_gcode_builds_with_its_own_commands() {
    let dir = vase_dir("bambu-current");
    let t8 = fixture("bbl/machine/Acme T8 0.4 nozzle.json");
    let pla = fixture("bbl/filament/Acme PLA.json");
    let out = p3dp(&dir, &["printers", "import", path(&t8), "-o", "t8.yaml"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let yaml = std::fs::read_to_string(dir.join("t8.yaml")).unwrap();
    for line in [
        "flavor: bambu",
        "max_nozzle_temp: 290",
        "envelope: { margin: 5, below_bed: 1.01, x: [-48.2, 261], y: [-5, 262] }",
        "# - max_nozzle_temp 290: the hottest the maker's own G-code heats the nozzle (start_gcode line 10: `M109 S290`); the preset names no limit",
        "# - envelope.y [-5, 262]: where the maker's own G-code takes the head (start_gcode line 17: `G2 I1 J0 X2 Y0 F2000`), past the bed grown by 5 mm",
    ] {
        assert!(yaml.lines().any(|l| l == line), "no `{line}` in\n{yaml}");
    }
    let g = build_with(&dir, &["--printer", "t8.yaml", "--filament", path(&pla)]).unwrap();
    has_lines(
        &g,
        &[
            "M290 X40 Y40 Z2.6666666 ; the firmware's resting state",
            "M901 D4",
            "M562 P1 E0 B1 ; the hot end's power off",
            "M562 P1 E1 B1 ; and on again",
            "M109 S290 ; flush at the common flush temperature",
            "G2 I1 J0 X2 Y0 F2000 ; wipe in circles",
            "M109 S215",
        ],
    );
    let edited = |from: &str, to: &str| {
        assert!(yaml.contains(from), "{from}");
        std::fs::write(dir.join("edited.yaml"), yaml.replace(from, to)).unwrap();
        build_with(
            &dir,
            &["--printer", "edited.yaml", "--filament", path(&pla)],
        )
        .unwrap_err()
    };
    let e = edited("M290 X40 Y40 Z2.6666666", "M290 X40 Y40 Z2");
    assert!(
        e.contains("start_gcode line 2: `M290 X40 Y40 Z2 ; the firmware's resting state`: `M290` is refused: it shifts the coordinates"),
        "{e}"
    );
    let e = edited("G2 I1 J0 X2 Y0 F2000", "G2 I2 J0 X4 Y0 F2000");
    assert!(
        e.contains("the arc's sweep: y = 263 mm is outside the machine's travel envelope (y from -5 to 262 mm: the profile's envelope.y)"),
        "{e}"
    );
    let e = edited("M109 S290 ;", "M109 S295 ;");
    assert!(
        e.contains("`M109 S295 ; flush at the common flush temperature`: a nozzle temperature of 295 °C, above the limit 290 °C"),
        "{e}"
    );
}

/// A Klipper maker's probe sequence (FlyingBear's S1, InfiMech's TX): Z
/// set to 0 where the probe touched (`SET_KINEMATIC_POSITION Z=0`), then
/// homed again before the print; and a park at a placeholder whose value
/// is a constant (Prusa's XL 5T: `Y{(0 < 4 ? -7 : -4.5)}`), which the
/// import's reach reads as the maker's literal. Left unhomed, the build is
/// refused naming the line.
#[test]
fn a_klipper_probe_sequence_and_a_constant_placeholder_build() {
    let dir = vase_dir("orca-probe");
    let profiles = fixture("orca/profiles/Acme");
    let file = fixture("orca/profiles/Acme/machine/Acme Probe 0.4 nozzle.json");
    let out = import_to(&dir, &file, Some(&profiles), "probe.yaml");
    let notes = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{notes}");
    assert!(
        notes.contains("envelope.y [-12, 230]") && notes.contains("start_gcode line 12"),
        "{notes}"
    );
    let g = build_with(&dir, &["--printer", "probe.yaml"]).unwrap();
    for line in [
        "SET_KINEMATIC_POSITION Z=0 ; the probe touched the bed",
        "G0 X30 Y-12 Z10 F6000 ; park at the sheet's edge",
    ] {
        assert!(g.contains(line), "{line}");
    }
    let file = fixture("orca/profiles/Acme/machine/Acme Probe Unhomed 0.4 nozzle.json");
    let out = import_to(&dir, &file, Some(&profiles), "unhomed.yaml");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let e = build_with(&dir, &["--printer", "unhomed.yaml"]).unwrap_err();
    assert!(
        e.contains("start_gcode line 7")
            && e.contains("SET_KINEMATIC_POSITION redefined Z and no G28 homes it again"),
        "{e}"
    );
}
