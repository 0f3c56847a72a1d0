//! What the printer's own software reads in p3dp's files (issue 31):
//! Moonraker's metadata extractor (Mainsail, Fluidd), Prusa's
//! `gcode-metadata` (PrusaLink, Prusa Connect), libbgcode (Prusa's binary
//! G-code library, through its Python binding) and bambox (a `.gcode.3mf`
//! validator), each run from the virtual environment `.ci/run` makes and
//! names in `P3DP_HOST_VENV`. Without it these are skipped with a note;
//! under CI (`CI` set) they fail instead. The checks that need no host
//! (progress, labels, the packages read back by hand) always run.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

use md5::Digest;
use serde_json::Value;

use crate::common::{p3dp, recipe, tmp};

/// The Python of the hosts' virtual environment, or None (with a note)
/// when there is none here; a failure under CI, whose `.ci/run` makes it.
fn python(what: &str) -> Option<PathBuf> {
    venv("P3DP_HOST_VENV", what)
}

/// The `bin/python` of the virtual environment the variable `var` names,
/// or None (with a note) when it is not set here; a failure under CI.
pub(crate) fn venv(var: &str, what: &str) -> Option<PathBuf> {
    match std::env::var_os(var) {
        Some(v) => {
            let py = PathBuf::from(v).join("bin").join("python");
            assert!(py.exists(), "{var} has no bin/python: {}", py.display());
            Some(py)
        }
        None => {
            assert!(
                std::env::var_os("CI").is_none(),
                "{var} is not set, and CI must run {what} (.ci/run makes the venv)"
            );
            eprintln!("note: {var} is not set; {what} is skipped");
            None
        }
    }
}

/// Runs `python ARGS`, asserting success; its standard output.
fn run_python(py: &Path, args: &[&str]) -> String {
    let out = Command::new(py).args(args).output().expect("run python");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "python {args:?} failed:\n{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    text
}

/// A built-in printer with thumbnails in all three formats, as a profile
/// file in `dir`.
pub(crate) fn with_thumbnails(dir: &Path, printer: &str) -> PathBuf {
    let f = dir.join(format!("{printer}-thumbs.yaml"));
    let yaml = format!(
        "inherits: {printer}\nname: {printer}\nthumbnails: [\"16x16/QOI\", \"300x300/PNG\", \"64x48/JPG\"]\n"
    );
    std::fs::write(&f, yaml).unwrap();
    f
}

/// Builds the gallery's vase for `printer` (a profile file) into
/// `dir/out`; its stats.
pub(crate) fn build(dir: &Path, printer: &Path, out: &str) -> Value {
    let json = format!("{out}.json");
    let o = p3dp(
        dir,
        &[
            "build",
            recipe("vase.yaml").to_str().unwrap(),
            "--printer",
            printer.to_str().unwrap(),
            "-o",
            out,
            "--stats-json",
            &json,
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&std::fs::read(dir.join(json)).unwrap()).unwrap()
}

pub(crate) fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("no number `{key}` in {v}"))
}

/// The commands of G-code text, comments and spacing left out.
fn commands(text: &str) -> Vec<String> {
    text.lines()
        .map(|l| {
            l.split(';')
                .next()
                .unwrap()
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ")
        })
        .filter(|c| !c.is_empty())
        .collect()
}

#[test]
fn progress_counts_every_percent_down_to_100_0() {
    let dir = tmp("hosts-m73");
    let stats = build(&dir, Path::new("prusa-mk4"), "v.gcode");
    let text = std::fs::read_to_string(dir.join("v.gcode")).unwrap();
    let m73: Vec<(u32, u32)> = text
        .lines()
        .filter_map(|l| l.strip_prefix("M73 P"))
        .map(|r| {
            let (p, r) = r.split_once(" R").unwrap();
            (p.parse().unwrap(), r.parse().unwrap())
        })
        .collect();
    assert_eq!(m73.first().unwrap().0, 0);
    let minutes = num(&stats, "print_time_s") / 60.0;
    assert!(
        (f64::from(m73[0].1) - minutes).abs() <= 1.0,
        "{:?} against {minutes} min",
        m73[0]
    );
    assert_eq!(*m73.last().unwrap(), (100, 0));
    for w in m73.windows(2) {
        assert!(w[1].0 >= w[0].0 && w[1].1 <= w[0].1, "not monotone: {w:?}");
    }
    for p in 0..=100 {
        assert!(m73.iter().any(|m| m.0 == p), "no M73 P{p}");
    }
}

#[test]
fn klipper_labels_wrap_each_part_once_defined() {
    let dir = tmp("hosts-labels");
    build(&dir, Path::new("voron-350"), "v.gcode");
    let text = std::fs::read_to_string(dir.join("v.gcode")).unwrap();
    let defined: Vec<&str> = text
        .lines()
        .filter_map(|l| l.strip_prefix("EXCLUDE_OBJECT_DEFINE NAME="))
        .map(|l| l.split(' ').next().unwrap())
        .collect();
    assert_eq!(defined, ["skirt", "bottom", "wall"]);
    let (mut open, mut started, mut spans) = (None, false, 0);
    for l in text.lines() {
        if let Some(n) = l.strip_prefix("EXCLUDE_OBJECT_START NAME=") {
            assert!(
                open.is_none() && defined.contains(&n),
                "{l} inside {open:?}"
            );
            (open, started) = (Some(n), true);
            spans += 1;
        } else if let Some(n) = l.strip_prefix("EXCLUDE_OBJECT_END NAME=") {
            assert_eq!(open.take(), Some(n));
        } else if started && l.starts_with("G1 X") && l.contains(" E") && !l.contains("E-") {
            // every extruding move after the start G-code is inside a part
            assert!(open.is_some(), "{l} outside every object");
        }
    }
    assert!(open.is_none() && spans >= 3);
}

#[test]
fn moonraker_reads_p3dp_its_time_filament_layers_and_thumbnails() {
    let Some(py) = python("Moonraker's metadata extractor") else {
        return;
    };
    let site = run_python(
        &py,
        &["-c", "import importlib.util as u; print(u.find_spec('moonraker').submodule_search_locations[0])"],
    );
    let script = PathBuf::from(site.trim()).join("components/file_manager/metadata.py");
    let dir = tmp("hosts-moonraker");
    for (printer, bed) in [("voron-350", 60.0), ("prusa-mk4", 60.0), ("ender3", 60.0)] {
        let file = format!("{printer}.gcode");
        let stats = build(&dir, &with_thumbnails(&dir, printer), &file);
        // `-o`: object processing, which turns "; printing object" comments
        // into Klipper's labels for files that have none
        let args = [
            script.to_str().unwrap(),
            "-p",
            dir.to_str().unwrap(),
            "-f",
            &file,
            "-o",
        ];
        let out = run_python(&py, &args);
        let v: Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
        let m = &v["metadata"];
        assert_eq!(m["slicer"], "p3dp", "{printer}: {m}");
        assert_eq!(m["slicer_version"], env!("CARGO_PKG_VERSION"));
        let t = num(&stats, "print_time_s");
        assert!(
            (num(m, "estimated_time") - t).abs() <= 1.0,
            "{printer}: {m} against {t} s"
        );
        assert!((num(m, "filament_total") - num(&stats, "filament_length_mm")).abs() < 0.01);
        assert!((num(m, "filament_weight_total") - num(&stats, "filament_mass_g")).abs() < 0.01);
        let bbox = &stats["bbox"];
        let (lo, hi) = (
            bbox["min"][2].as_f64().unwrap(),
            bbox["max"][2].as_f64().unwrap(),
        );
        assert!(
            (num(m, "first_layer_height") - lo).abs() < 1e-3,
            "{printer}: {m}"
        );
        assert!(
            (num(m, "object_height") - hi).abs() < 1e-3,
            "{printer}: {m} against {hi}"
        );
        assert_eq!(num(m, "nozzle_diameter"), 0.4);
        // the print's temperatures, not the MK4's probing 170 °C
        assert_eq!(num(m, "first_layer_extr_temp"), 210.0, "{printer}");
        assert_eq!(num(m, "first_layer_bed_temp"), bed);
        // ours (the QOI decoded to PNG), and a 32 px one Moonraker makes
        let thumbs = m["thumbnails"].as_array().unwrap();
        for wh in [[16, 16], [300, 300], [64, 48]] {
            let found = thumbs
                .iter()
                .any(|t| t["width"] == wh[0] && t["height"] == wh[1]);
            assert!(found, "{printer}: no {wh:?} thumbnail in {m}");
        }
        for th in thumbs {
            let f = dir.join(th["relative_path"].as_str().unwrap());
            assert_eq!(
                std::fs::metadata(&f).unwrap().len(),
                th["size"].as_u64().unwrap()
            );
        }
        let text = std::fs::read_to_string(dir.join(&file)).unwrap();
        for part in ["skirt", "bottom", "wall"] {
            assert!(
                text.contains(&format!("EXCLUDE_OBJECT_DEFINE NAME={part} ")),
                "{printer}: {part}"
            );
        }
    }
}

#[test]
fn prusa_gcode_metadata_reads_time_model_nozzle_and_thumbnails() {
    let Some(py) = python("Prusa's gcode-metadata") else {
        return;
    };
    let dir = tmp("hosts-prusalink");
    let stats = build(&dir, &with_thumbnails(&dir, "prusa-mk4"), "mk4.gcode");
    let script = "import sys, json, gcode_metadata as g\n\
        m = g.get_metadata(sys.argv[1], save_cache=False)\n\
        d = dict(m.data)\n\
        d['seconds'] = g.estimated_to_seconds(d['estimated printing time (normal mode)'])\n\
        d['thumbnails'] = sorted(m.thumbnails)\n\
        print(json.dumps(d))";
    let out = run_python(
        &py,
        &["-c", script, dir.join("mk4.gcode").to_str().unwrap()],
    );
    let m: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(m["printer_model"], "MK4", "{m}");
    assert!(
        (num(&m, "seconds") - num(&stats, "print_time_s")).abs() <= 1.0,
        "{m}"
    );
    assert_eq!(num(&m, "nozzle_diameter"), 0.4);
    assert_eq!(m["filament_type"], "PLA");
    assert_eq!(num(&m, "temperature"), 210.0);
    assert_eq!(m["normal_percent_present"], true, "M73 progress: {m}");
    let thumbs: Vec<&str> = m["thumbnails"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_str().unwrap())
        .collect();
    assert_eq!(thumbs, ["16x16_QOI", "300x300_PNG", "64x48_JPG"]);
}

#[test]
fn bgcode_blocks_read_back_to_the_same_commands() {
    let dir = tmp("hosts-bgcode");
    let printer = with_thumbnails(&dir, "prusa-mk4");
    build(&dir, &printer, "v.gcode");
    build(&dir, &printer, "v.bgcode");
    let ascii = std::fs::read_to_string(dir.join("v.gcode")).unwrap();
    let binary = std::fs::read(dir.join("v.bgcode")).unwrap();
    assert!(
        binary.len() < ascii.len() / 2,
        "{} of {}",
        binary.len(),
        ascii.len()
    );
    // our reader, from the specification: every checksum and block
    let blocks = ::p3dp::testing::bgcode::decode(&binary).expect("a valid .bgcode");
    let kinds: Vec<u16> = blocks.iter().map(|b| b.kind).collect();
    assert_eq!(
        kinds[..7],
        [0, 3, 5, 5, 5, 4, 2],
        "file, printer, 3 thumbnails, print, slicer"
    );
    let Some(py) = python("libbgcode's binding") else {
        return;
    };
    let (file, back) = (dir.join("v.bgcode"), dir.join("back.gcode"));
    let script = "import sys, json, pybgcode as b\n\
        f = b.open(sys.argv[1], 'rb'); out = b.open(sys.argv[2], 'w')\n\
        r = b.from_binary_to_ascii(f, out, True); b.close(f); b.close(out)\n\
        f = b.open(sys.argv[1], 'rb'); meta = b.read_metadata(f, 'printer'); b.close(f)\n\
        f = b.open(sys.argv[1], 'rb'); th = [[t['meta'].width, t['meta'].height, len(t['bytes'])] for t in b.read_thumbnails(f)]; b.close(f)\n\
        print(json.dumps({'result': b.translate_result(r), 'printer': meta, 'thumbnails': th}))";
    let args = ["-c", script, file.to_str().unwrap(), back.to_str().unwrap()];
    let out = run_python(&py, &args);
    let v: Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    assert_eq!(v["result"], "Success", "{v}");
    assert_eq!(v["printer"]["printer_model"], "MK4");
    let sizes: Vec<[u64; 3]> = blocks
        .iter()
        .filter(|b| b.kind == 5)
        .map(|b| {
            let wh = |k: usize| u64::from(u16::from_le_bytes([b.params[k], b.params[k + 1]]));
            [wh(2), wh(4), b.data.len() as u64]
        })
        .collect();
    assert_eq!(v["thumbnails"], serde_json::json!(sizes));
    assert_eq!(
        sizes[..2].iter().map(|s| [s[0], s[1]]).collect::<Vec<_>>(),
        [[16, 16], [300, 300]]
    );
    let decoded = std::fs::read_to_string(back).unwrap();
    assert_eq!(
        commands(&decoded),
        commands(&ascii),
        "libbgcode's G-code is the .gcode build's"
    );
}

#[test]
fn gcode_3mf_holds_its_g_code_md5_and_bambu_markers() {
    let dir = tmp("hosts-bambu");
    let printer = dir.join("x1c.yaml");
    let yaml = "inherits: generic-220\nname: x1c\nprinter_model: X1C\nbed: { shape: rectangle, size: [256, 256], max_z: 250 }\norigin: [128, 128, 0]\n";
    std::fs::write(&printer, yaml).unwrap();
    let stats = build(&dir, &printer, "v.gcode.3mf");
    let bytes = std::fs::read(dir.join("v.gcode.3mf")).unwrap();
    build(&dir, &printer, "again.gcode.3mf");
    assert_eq!(
        bytes,
        std::fs::read(dir.join("again.gcode.3mf")).unwrap(),
        "deterministic zip"
    );
    let mut z = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
    let mut read = |n: &str| {
        let mut s = Vec::new();
        z.by_name(n)
            .unwrap_or_else(|_| panic!("no {n}"))
            .read_to_end(&mut s)
            .unwrap();
        s
    };
    let gcode = read("Metadata/plate_1.gcode");
    let md5: String = md5::Md5::digest(&gcode)
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect();
    assert_eq!(
        String::from_utf8(read("Metadata/plate_1.gcode.md5")).unwrap(),
        md5
    );
    let text = String::from_utf8(gcode).unwrap();
    let layers: u32 = text
        .lines()
        .find_map(|l| l.strip_prefix("; total layer number: "))
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(
        text.lines().filter(|l| l.starts_with("M73 L")).count() as u32,
        layers
    );
    assert_eq!(
        text.lines().filter(|l| l.starts_with("M991 S0 P")).count() as u32,
        layers
    );
    let info = String::from_utf8(read("Metadata/slice_info.config")).unwrap();
    assert!(
        info.contains(r#"key="printer_model_id" value="BL-P001""#),
        "{info}"
    );
    let secs = format!(
        r#"key="prediction" value="{}""#,
        num(&stats, "print_time_s").round()
    );
    assert!(info.contains(&secs), "{info}");
    assert!(read("Metadata/plate_1.png").starts_with(b"\x89PNG"));
    let Some(py) = python("bambox's validator") else {
        return;
    };
    let bambox = py.with_file_name("bambox");
    let out = Command::new(bambox)
        .args(["validate", "--strict", "--json"])
        .arg(dir.join("v.gcode.3mf"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let json = &text[text.find('{').unwrap_or(0)..];
    let v: Value = serde_json::from_str(json).unwrap_or_else(|e| panic!("{e}: {text}"));
    assert_eq!(v["valid"], true, "{v}");
    assert_eq!(v["errors"], serde_json::json!([]), "{v}");
    assert_eq!(v["warnings"], serde_json::json!([]), "{v}");
}

/// The built-ins' own thumbnails (issue 39), read by the printers' software:
/// Prusa's `gcode-metadata` (PrusaLink, Prusa Connect) in the MK4S's and
/// the CORE One's G-code, libbgcode in their `.bgcode`, each in the sizes
/// and formats PrusaSlicer's preset writes.
#[test]
fn prusa_hosts_read_the_built_ins_thumbnails() {
    let dir = tmp("hosts-prusa-thumbs");
    let want = ["16x16_QOI", "313x173_QOI", "380x285_PNG", "480x240_QOI"];
    let blocks = [[16, 16, 2], [313, 173, 2], [480, 240, 2], [380, 285, 0]];
    for (printer, model) in [("prusa-mk4s", "MK4S"), ("prusa-core-one", "COREONE")] {
        build(&dir, Path::new(printer), &format!("{printer}.gcode"));
        build(&dir, Path::new(printer), &format!("{printer}.bgcode"));
        let Some(py) = python("Prusa's gcode-metadata and libbgcode") else {
            return;
        };
        let script = "import sys, json, gcode_metadata as g, pybgcode as b\n\
            m = g.get_metadata(sys.argv[1], save_cache=False)\n\
            f = b.open(sys.argv[2], 'rb'); th = [[t['meta'].width, t['meta'].height, int(t['meta'].format)] for t in b.read_thumbnails(f)]; b.close(f)\n\
            print(json.dumps({'model': m.data.get('printer_model'), 'thumbnails': sorted(m.thumbnails), 'bgcode': th}))";
        let gcode = dir.join(format!("{printer}.gcode"));
        let bgcode = dir.join(format!("{printer}.bgcode"));
        let out = run_python(
            &py,
            &[
                "-c",
                script,
                gcode.to_str().unwrap(),
                bgcode.to_str().unwrap(),
            ],
        );
        let v: Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
        assert_eq!(v["model"], model, "{printer}: {v}");
        assert_eq!(v["thumbnails"], serde_json::json!(want), "{printer}: {v}");
        assert_eq!(v["bgcode"], serde_json::json!(blocks), "{printer}: {v}");
    }
}

/// Moonraker (Mainsail, Fluidd) reads the Klipper built-ins' own thumbnails:
/// Creality Print's 96 and 300 px for the K1 and the Ender-3 V3,
/// OrcaSlicer's 48 and 300 px for the Voron.
#[test]
fn moonraker_reads_the_klipper_built_ins_thumbnails() {
    let Some(py) = python("Moonraker's metadata extractor") else {
        return;
    };
    let site = run_python(
        &py,
        &["-c", "import importlib.util as u; print(u.find_spec('moonraker').submodule_search_locations[0])"],
    );
    let script = PathBuf::from(site.trim()).join("components/file_manager/metadata.py");
    let dir = tmp("hosts-moonraker-built-ins");
    for (printer, sizes) in [
        ("creality-k1", [96, 300]),
        ("ender3-v3", [96, 300]),
        ("voron-350", [48, 300]),
    ] {
        let file = format!("{printer}.gcode");
        build(&dir, Path::new(printer), &file);
        let args = [
            script.to_str().unwrap(),
            "-p",
            dir.to_str().unwrap(),
            "-f",
            &file,
        ];
        let out = run_python(&py, &args);
        let v: Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
        let thumbs = v["metadata"]["thumbnails"].as_array().unwrap();
        for px in sizes {
            let found = thumbs.iter().any(|t| t["width"] == px && t["height"] == px);
            assert!(found, "{printer}: no {px} px thumbnail in {v}");
        }
        for th in thumbs {
            let f = dir.join(th["relative_path"].as_str().unwrap());
            let img = image::open(&f).unwrap_or_else(|e| panic!("{printer}: {e}"));
            assert_eq!(
                (u64::from(img.width()), u64::from(img.height())),
                (
                    th["width"].as_u64().unwrap(),
                    th["height"].as_u64().unwrap()
                )
            );
        }
    }
}

/// A Bambu built-in's `.gcode.3mf` carries the plate pictures Bambu Studio
/// writes (512 px, and 128 px for the printer's list) and its G-code no
/// thumbnail, as Bambu Studio's for a Bambu printer; bambox finds it valid.
#[test]
fn a_bambu_built_in_s_package_carries_bambu_studio_s_pictures() {
    let dir = tmp("hosts-bambu-built-in");
    build(&dir, Path::new("bambu-x1c"), "v.gcode.3mf");
    let bytes = std::fs::read(dir.join("v.gcode.3mf")).unwrap();
    let mut z = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
    let mut read = |n: &str| {
        let mut s = Vec::new();
        z.by_name(n).unwrap().read_to_end(&mut s).unwrap();
        s
    };
    for (name, px) in [
        ("Metadata/plate_1.png", 512),
        ("Metadata/plate_1_small.png", 128),
    ] {
        let img =
            image::load_from_memory_with_format(&read(name), image::ImageFormat::Png).unwrap();
        assert_eq!((img.width(), img.height()), (px, px), "{name}");
    }
    let gcode = String::from_utf8(read("Metadata/plate_1.gcode")).unwrap();
    assert!(
        !gcode.contains("; thumbnail"),
        "Bambu Studio writes none in the G-code"
    );
    let Some(py) = python("bambox's validator") else {
        return;
    };
    let out = Command::new(py.with_file_name("bambox"))
        .args(["validate", "--strict", "--json"])
        .arg(dir.join("v.gcode.3mf"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let json = &text[text.find('{').unwrap_or(0)..];
    let v: Value = serde_json::from_str(json).unwrap_or_else(|e| panic!("{e}: {text}"));
    assert_eq!(v["valid"], true, "{v}");
    assert_eq!(v["warnings"], serde_json::json!([]), "{v}");
}

/// The E values of relative-E G-code after its start G-code (from the
/// first part on), added up.
fn net_e_of_parts(text: &str) -> f64 {
    let from = text.find("\n; part: ").unwrap();
    text[from..]
        .lines()
        .filter(|l| l.starts_with("G1 ") || l.starts_with("G2 ") || l.starts_with("G3 "))
        .flat_map(|l| l.split(';').next().unwrap().split_whitespace())
        .filter_map(|w| w.strip_prefix('E'))
        .map(|v| v.parse::<f64>().unwrap())
        .sum()
}

#[test]
fn no_empty_moves_and_filament_counted_net() {
    let dir = tmp("hosts-faults");
    // the oracle's faults: `G1 E0.00000` in cup-solid-base (a line the
    // firmware ignores but a planner stops for), and hairs' final
    // retraction counted as filament used
    for (name, printer) in [("cup-solid-base", "voron-350"), ("hairs", "voron-350")] {
        let out = format!("{name}.gcode");
        let p = p3dp(
            &dir,
            &[
                "build",
                recipe(&format!("{name}.yaml")).to_str().unwrap(),
                "--printer",
                printer,
                "-o",
                &out,
                "--stats-json",
                "s.json",
            ],
        );
        assert!(p.status.success(), "{}", String::from_utf8_lossy(&p.stderr));
        let text = std::fs::read_to_string(dir.join(&out)).unwrap();
        for l in text.lines() {
            let cmd = l.split(';').next().unwrap().trim();
            assert!(
                cmd != "G1 E0.00000" && cmd != "G1 E-0.00000",
                "{name}: an empty move `{l}`"
            );
        }
        let stats: Value =
            serde_json::from_slice(&std::fs::read(dir.join("s.json")).unwrap()).unwrap();
        let net = net_e_of_parts(&text);
        let counted = num(&stats, "filament_length_mm");
        assert!(
            (counted - net).abs() < 1e-4,
            "{name}: {counted} mm counted, {net} mm net in the G-code"
        );
    }
}

#[test]
fn the_date_is_the_epochs_unless_source_date_epoch_and_hash_follows_build() {
    let dir = tmp("hosts-date");
    let sphere = recipe("sphere.yaml");
    let run = |env: Option<&str>, args: &[&str]| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_p3dp"));
        c.args(args)
            .current_dir(&dir)
            .env_remove("SOURCE_DATE_EPOCH");
        if let Some(v) = env {
            c.env("SOURCE_DATE_EPOCH", v);
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap()
    };
    for (env, date) in [
        (None, "1970-01-01 at 00:00:00"),
        (Some("1700000000"), "2023-11-14 at 22:13:20"),
    ] {
        run(env, &["build", sphere.to_str().unwrap(), "-o", "s.gcode"]);
        let bytes = std::fs::read(dir.join("s.gcode")).unwrap();
        let first = String::from_utf8_lossy(&bytes)
            .lines()
            .next()
            .unwrap()
            .to_string();
        let want = format!(
            "; generated by p3dp {} on {date} UTC",
            env!("CARGO_PKG_VERSION")
        );
        assert_eq!(first, want);
        let sha: String = sha2::Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        let hashed = run(env, &["hash", sphere.to_str().unwrap()]);
        assert!(
            hashed.starts_with(&sha),
            "hash {hashed} against the file's {sha}"
        );
    }
}
