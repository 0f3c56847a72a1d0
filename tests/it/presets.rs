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
use p3dp::presets as map;
use p3dp::presets::{self as preset, Source};
use p3dp::Reads;
use p3dp::{plan, Options};
use p3dp::{Bed, Flavor, Printer};

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
    Printer::from_preset(&src, &Reads::default())
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
    plan.recipe.printer.thumbnails.clear();
    let bytes = p3dp::pipeline::write(&mut plan, &p3dp::pipeline::Job::default(), Vec::new())?.out;
    let text = String::from_utf8(bytes).unwrap();
    Ok((text, plan.recipe.printer.clone(), plan.frame.end_text()))
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
            let imported = preset::load(&src, &Reads::default()).and_then(|p| map::to_yaml(&p));
            let yaml = match imported {
                Ok(i) => i.yaml,
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
    std::fs::write(&profile, map::to_yaml(&preset).unwrap().yaml).unwrap();
    let (text, _, _) = build_vase(&dir, &profile).unwrap();
    let opts = Options {
        printer: Some(profile.to_str().unwrap().into()),
        ..Default::default()
    };
    let ours = plan(&dir.join("vase.yaml"), &opts)
        .unwrap()
        .frame
        .start_text();
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
    let at = theirs
        .iter()
        .position(|l| *l == ours[0])
        .expect("PrusaSlicer's start G-code");
    assert_eq!(ours, theirs[at..at + ours.len()]);
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
