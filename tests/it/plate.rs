//! Plates (issue 41): whole recipes on one bed, arranged and printed one
//! after another, built by the real binary from a plate file and from the
//! command line; and the language that switches parts, names copies and
//! takes whole recipes as parts. Each test reads the G-code back.

use crate::common::*;
use std::path::{Path, PathBuf};

/// `recipes/plates/NAME`.
fn plates(name: &str) -> PathBuf {
    root().join("recipes/plates").join(name)
}

/// Builds `args` in `dir`, asserting success; the G-code written to `out`.
fn build(dir: &Path, args: &[&str], out: &str) -> (String, String) {
    let o = p3dp(dir, args);
    assert!(
        o.status.success(),
        "{args:?}:\n{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let report = String::from_utf8_lossy(&o.stdout).into_owned();
    (std::fs::read_to_string(dir.join(out)).unwrap(), report)
}

/// A printer profile's `head.box` and `head.gantry` (height, y band).
fn head_of(printer: &str) -> ([f64; 4], Option<(f64, [f64; 2])>) {
    let path = root().join(format!("src/machine/printers/{printer}.yaml"));
    let y: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let b: Vec<f64> = y["head"]["box"]
        .as_sequence()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let g = &y["head"]["gantry"];
    let gantry = g.as_mapping().map(|_| {
        let band: Vec<f64> = g["y"]
            .as_sequence()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        (g["height"].as_f64().unwrap(), [band[0], band[1]])
    });
    ([b[0], b[1], b[2], b[3]], gantry)
}

/// One object as the G-code prints it: its name, the rectangle of its
/// extruding moves (machine XY), its top and its lowest nozzle height.
#[derive(Debug)]
struct Printed {
    name: String,
    lo: [f64; 2],
    hi: [f64; 2],
    top: f64,
    bottom: f64,
}

/// The objects of a plate's G-code in print order, each from the moves of
/// its parts (`OBJECT/PART`); asserts that each object's moves are one run
/// and that its labels enclose exactly its parts.
fn objects(gcode: &str) -> Vec<Printed> {
    let g = parse(gcode);
    let object_of = |part: usize| g.parts[part].split('/').next().unwrap().to_string();
    let mut out: Vec<Printed> = Vec::new();
    for m in &g.moves {
        if m.part == 0 || m.de <= 0.0 || m.g == 0 {
            continue;
        }
        let name = object_of(m.part);
        if out.last().is_none_or(|o| o.name != name) {
            assert!(
                out.iter().all(|o| o.name != name),
                "the moves of `{name}` are not contiguous"
            );
            out.push(Printed {
                name,
                lo: [f64::INFINITY; 2],
                hi: [f64::NEG_INFINITY; 2],
                top: f64::NEG_INFINITY,
                bottom: f64::INFINITY,
            });
        }
        let o = out.last_mut().unwrap();
        for [x, y, z] in [m.from, m.to] {
            o.lo = [o.lo[0].min(x), o.lo[1].min(y)];
            o.hi = [o.hi[0].max(x), o.hi[1].max(y)];
            o.top = o.top.max(z);
            o.bottom = o.bottom.min(z);
        }
    }
    // the labels: `; printing object X` … `; stop printing object X`
    // around X's parts only, each object once, in print order
    let mut labelled = Vec::new();
    let mut open: Option<String> = None;
    for l in gcode.lines() {
        if let Some(n) = l.strip_prefix("; printing object ") {
            assert!(open.is_none(), "{n} opens inside {open:?}");
            open = Some(n.to_string());
            labelled.push(n.to_string());
        } else if let Some(n) = l.strip_prefix("; stop printing object ") {
            assert_eq!(open.take().as_deref(), Some(n));
        } else if let Some(p) = l.strip_prefix("; part: ") {
            let obj = p.split('/').next().unwrap();
            assert_eq!(open.as_deref(), Some(obj), "part {p} outside its label");
        }
    }
    let names: Vec<&str> = out.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(labelled, names, "each object labelled, in print order");
    out
}

/// Asserts that every object printed after another keeps the earlier one
/// outside its own rectangle grown by the head's box, and, when the earlier
/// one rises above the gantry over the later one's lowest nozzle height,
/// outside the gantry's band over it.
fn clear_of_the_head(objs: &[Printed], printer: &str) {
    let (b, gantry) = head_of(printer);
    for (i, a) in objs.iter().enumerate() {
        for later in &objs[i + 1..] {
            let boxed = a.hi[0] <= later.lo[0] + b[0]
                || a.lo[0] >= later.hi[0] + b[1]
                || a.hi[1] <= later.lo[1] + b[2]
                || a.lo[1] >= later.hi[1] + b[3];
            assert!(
                boxed,
                "`{}` is within the head's reach of `{}`",
                a.name, later.name
            );
            if let Some((h, band)) = gantry {
                if a.top > later.bottom + h {
                    assert!(
                        a.hi[1] <= later.lo[1] + band[0] || a.lo[1] >= later.hi[1] + band[1],
                        "`{}` stands under the gantry over `{}`",
                        a.name,
                        later.name
                    );
                }
            }
        }
    }
}

#[test]
fn four_pots_on_an_a1_mini_are_arranged_clear_of_the_head_and_labelled() {
    let dir = tmp("plate-pots");
    let plate = plates("pots.yaml");
    let (gcode, report) = build(
        &dir,
        &[
            "build",
            plate.to_str().unwrap(),
            "-o",
            "pots.gcode",
            "--stats-json",
            "s.json",
        ],
        "pots.gcode",
    );
    let objs = objects(&gcode);
    let names: Vec<&str> = objs.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["pot-1", "pot-2", "pot-3", "pot-4"]);
    // the stats: each object's time and filament, adding up to the print's
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    let per: Vec<&serde_json::Value> = stats["objects"].as_array().unwrap().iter().collect();
    assert_eq!(per.len(), 4);
    let sum = |k: &str| per.iter().map(|o| o[k].as_f64().unwrap()).sum::<f64>();
    let total = stats["print_time_s"].as_f64().unwrap();
    assert!(
        (sum("print_time_s") - total).abs() < 1e-6 * total,
        "{} {total}",
        sum("print_time_s")
    );
    let filament = stats["filament_length_mm"].as_f64().unwrap();
    assert!(
        (sum("filament_length_mm") - filament).abs() < 0.01 * filament,
        "{filament}"
    );
    // the taller round pot takes longer than the shorter one
    assert!(per[3]["print_time_s"].as_f64() > per[2]["print_time_s"].as_f64());
    // `p3dp hash` of the plate file: the bytes `build` wrote
    let o = p3dp(&dir, &["hash", plate.to_str().unwrap()]);
    assert!(o.status.success());
    let sha = stats["gcode_sha256"].as_str().unwrap();
    assert!(String::from_utf8_lossy(&o.stdout).starts_with(sha));
    clear_of_the_head(&objs, "bambu-a1-mini");
    // every object on the 180 mm bed
    for o in &objs {
        assert!(
            o.lo[0] >= 0.0 && o.lo[1] >= 0.0 && o.hi[0] <= 180.0 && o.hi[1] <= 180.0,
            "{o:?}"
        );
    }
    // the checks (the collision check over the real filament) find nothing
    assert!(report.contains("0 warnings, 0 errors"), "{report}");
    // the report: each part by its object, and each object's time and filament
    assert!(report.contains("    pot-2/wall: "), "{report}");
    for n in names {
        let line = report
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{n}: ")) && l.contains("filament"))
            .unwrap_or_else(|| panic!("no line for {n}:\n{report}"));
        assert!(line.contains(" g"), "{line}");
    }
}

#[test]
fn nine_vases_on_an_x1c_are_arranged_clear_of_the_head_and_packaged_as_objects() {
    let dir = tmp("plate-vases");
    let plate = plates("vases.yaml");
    let (gcode, report) = build(
        &dir,
        &["build", plate.to_str().unwrap(), "-o", "vases.gcode"],
        "vases.gcode",
    );
    let objs = objects(&gcode);
    assert_eq!(objs.len(), 9);
    clear_of_the_head(&objs, "bambu-x1c");
    assert!(report.contains("0 warnings, 0 errors"), "{report}");
    // Bambu's package: nine objects, printed by object
    let o = p3dp(
        &dir,
        &["build", plate.to_str().unwrap(), "-o", "vases.gcode.3mf"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(dir.join("vases.gcode.3mf")).unwrap();
    let mut z = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
    let mut read = |name: &str| {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut z.by_name(name).unwrap(), &mut s).unwrap();
        s
    };
    let info = read("Metadata/slice_info.config");
    for k in 1..=9 {
        assert!(info.contains(&format!("name=\"bud-vase-{k}\"")), "{info}");
    }
    assert_eq!(info.matches("<object ").count(), 9, "{info}");
    let json: serde_json::Value = serde_json::from_str(&read("Metadata/plate_1.json")).unwrap();
    assert_eq!(json["is_seq_print"], true);
    assert_eq!(json["bbox_objects"].as_array().unwrap().len(), 9);
}

#[test]
fn klipper_labels_each_object_with_its_outline() {
    let dir = tmp("plate-klipper");
    let plate = plates("pots.yaml");
    let (gcode, _) = build(
        &dir,
        &[
            "build",
            plate.to_str().unwrap(),
            "--printer",
            "voron-350",
            "-o",
            "p.gcode",
        ],
        "p.gcode",
    );
    let objs = objects(&gcode);
    assert_eq!(objs.len(), 4);
    for o in &objs {
        let define = gcode
            .lines()
            .find(|l| l.starts_with(&format!("EXCLUDE_OBJECT_DEFINE NAME={} ", o.name)))
            .unwrap_or_else(|| panic!("no define of {}", o.name));
        // its polygon is round the object's own moves
        let poly = define.split("POLYGON=").nth(1).unwrap();
        let nums: Vec<f64> = poly
            .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().unwrap())
            .collect();
        for xy in nums.chunks(2) {
            assert!(xy[0] >= o.lo[0] - 1.0 && xy[0] <= o.hi[0] + 1.0, "{define}");
            assert!(xy[1] >= o.lo[1] - 1.0 && xy[1] <= o.hi[1] + 1.0, "{define}");
        }
        assert_eq!(
            gcode
                .matches(&format!("EXCLUDE_OBJECT_START NAME={}\n", o.name))
                .count(),
            1
        );
        assert_eq!(
            gcode
                .matches(&format!("EXCLUDE_OBJECT_END NAME={}\n", o.name))
                .count(),
            1
        );
    }
}

#[test]
fn the_command_line_and_the_plate_file_give_the_same_bytes() {
    let dir = tmp("plate-cli");
    std::fs::write(dir.join("p3dp.lock"), "p3dp_lock: 1\nentries: []\n").unwrap();
    std::fs::copy(plates("pot.yaml"), dir.join("pot.yaml")).unwrap();
    std::fs::copy(plates("bud-vase.yaml"), dir.join("bud-vase.yaml")).unwrap();
    std::fs::write(
        dir.join("mixed.yaml"),
        "p3dp: 1\nname: mixed\nprinter: bambu-x1c\nplate:\n  - {recipe: pot.yaml, copies: 2, sweep: {height: \"16, 22\"}}\n  - {recipe: bud-vase.yaml, sweep: {height: \"16, 22\"}}\n",
    )
    .unwrap();
    let (file, _) = build(
        &dir,
        &["build", "mixed.yaml", "-o", "file.gcode"],
        "file.gcode",
    );
    let (cli, report) = build(
        &dir,
        &[
            "plate",
            "pot.yaml*2",
            "bud-vase.yaml",
            "--sweep",
            "height=16,22",
            "--name",
            "mixed",
            "--printer",
            "bambu-x1c",
            "-o",
            "cli.gcode",
        ],
        "cli.gcode",
    );
    assert!(
        file == cli,
        "the command line's plate differs from the file's"
    );
    assert_eq!(objects(&cli).len(), 6);
    assert!(report.starts_with("mixed → cli.gcode"), "{report}");
    // the default file is the plate's name
    let o = p3dp(&dir, &["plate", "pot.yaml", "--name", "one"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("one.gcode").is_file());
}

/// A plate of `entries` in a fresh project with the gallery's pot, its
/// failed `p3dp check`: exit status and message.
fn refused(entries: &str, printer: &str) -> (i32, String) {
    let dir = tmp("plate-refused");
    std::fs::write(dir.join("p3dp.lock"), "p3dp_lock: 1\nentries: []\n").unwrap();
    std::fs::copy(plates("pot.yaml"), dir.join("pot.yaml")).unwrap();
    std::fs::write(
        dir.join("bad.yaml"),
        format!("p3dp: 1\nname: bad\nprinter: {printer}\nplate:\n{entries}"),
    )
    .unwrap();
    let o = p3dp(&dir, &["check", "bad.yaml"]);
    (
        o.status.code().unwrap(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn an_object_that_cannot_fit_is_refused_by_name() {
    // too wide for the A1 mini's 180 mm bed, even alone
    let (code, e) = refused(
        "  - {recipe: pot.yaml, name: basin, set: {radius: 95}}\n",
        "bambu-a1-mini",
    );
    assert_eq!(code, 2, "{e}");
    assert!(e.contains("bad.yaml") && e.contains("plate[0]"), "{e}");
    assert!(
        e.contains("object `basin`") && e.contains("does not fit on the bed"),
        "{e}"
    );
    // five more pots than the bed holds with the head's reach between them
    let (code, e) = refused("  - {recipe: pot.yaml, copies: 12}\n", "bambu-a1-mini");
    assert_eq!(code, 2, "{e}");
    assert!(e.contains("finds no place on the bed"), "{e}");
    assert!(e.contains("object `pot-"), "{e}");
    // two pots taller than the gantry: one can print last, not both
    let (code, e) = refused(
        "  - {recipe: pot.yaml, copies: 5, set: {height: 40}}\n",
        "bambu-a1-mini",
    );
    assert_eq!(code, 2, "{e}");
    assert!(e.contains("more than the gantry's 25 mm"), "{e}");
    // a fixed place off the bed, named at its key
    let (code, e) = refused("  - {recipe: pot.yaml, at: [80, 0]}\n", "bambu-a1-mini");
    assert_eq!(code, 2, "{e}");
    assert!(
        e.contains("plate[0].at") && e.contains("reaches off the bed"),
        "{e}"
    );
}

#[test]
fn one_object_too_tall_for_the_gantry_prints_last() {
    let dir = tmp("plate-tall");
    std::fs::write(dir.join("p3dp.lock"), "p3dp_lock: 1\nentries: []\n").unwrap();
    std::fs::copy(plates("pot.yaml"), dir.join("pot.yaml")).unwrap();
    std::fs::write(
        dir.join("tall.yaml"),
        "p3dp: 1\nname: tall\nprinter: bambu-a1-mini\nplate:\n  - {recipe: pot.yaml, name: tower, set: {height: 45}}\n  - {recipe: pot.yaml, copies: 3}\n",
    )
    .unwrap();
    let (gcode, report) = build(&dir, &["build", "tall.yaml", "-o", "t.gcode"], "t.gcode");
    let objs = objects(&gcode);
    assert_eq!(objs.last().unwrap().name, "tower");
    assert!(objs.last().unwrap().top > 45.0);
    clear_of_the_head(&objs, "bambu-a1-mini");
    assert!(report.contains("0 warnings, 0 errors"), "{report}");
}

#[test]
fn a_part_switched_off_by_a_param_is_absent() {
    let dir = tmp("plate-switch");
    let pot = plates("pot.yaml");
    let (off, report) = build(
        &dir,
        &["build", pot.to_str().unwrap(), "-o", "off.gcode"],
        "off.gcode",
    );
    let g = parse(&off);
    assert_eq!(g.parts[1..], ["bottom".to_string(), "wall".to_string()]);
    assert!(!report.contains("saucer"), "{report}");
    // nothing is extruded on the bed beyond the pot's foot
    let r_max = g
        .moves
        .iter()
        .filter(|m| m.de > 0.0 && m.to[2] < 0.3 && m.part > 0)
        .map(|m| ((m.to[0] - 90.0).powi(2) + (m.to[1] - 90.0).powi(2)).sqrt())
        .fold(0.0, f64::max);
    assert!(r_max < 15.5, "{r_max}");
    let (on, _) = build(
        &dir,
        &[
            "build",
            pot.to_str().unwrap(),
            "--set",
            "saucer=true",
            "-o",
            "on.gcode",
        ],
        "on.gcode",
    );
    let g = parse(&on);
    assert_eq!(g.parts[1], "saucer");
    let r_max = g
        .moves
        .iter()
        .filter(|m| m.de > 0.0 && m.part == 1)
        .map(|m| ((m.to[0] - 90.0).powi(2) + (m.to[1] - 90.0).powi(2)).sqrt())
        .fold(0.0, f64::max);
    assert!((r_max - 21.0).abs() < 0.5, "{r_max}");
}

/// Writes `recipe` as `NAME.yaml` in a fresh project beside the gallery's
/// pot and builds it; its G-code and report.
fn built(name: &str, recipe: &str) -> (String, String) {
    let dir = tmp(&format!("plate-{name}"));
    std::fs::write(dir.join("p3dp.lock"), "p3dp_lock: 1\nentries: []\n").unwrap();
    std::fs::copy(plates("pot.yaml"), dir.join("pot.yaml")).unwrap();
    std::fs::write(dir.join(format!("{name}.yaml")), recipe).unwrap();
    let file = format!("{name}.yaml");
    build(&dir, &["build", &file, "-o", "out.gcode"], "out.gcode")
}

#[test]
fn template_params_may_be_choices_booleans_and_lists() {
    let (gcode, _) = built(
        "choices",
        "p3dp: 1\nname: choices\ntemplates:\n  ring:\n    params:\n      shape: {choices: [round, star], default: round}\n      flat: false\n      radii: [10, 20]\n    part:\n      name: ring\n      primitive: {helix: {radius: \"radii[1]\", height: \"if(flat, 1, 4)\", pitch: 0.25, center: [0, 0, 0.2]}}\n      steps:\n        - deform_cylinder: {position: [\"r - if(shape == 'star', 2*(1 - cos(5*theta)), 0)\", theta, z]}\nparts:\n  - {template: ring, name: round, steps: [{translate: [-30, 0, 0]}]}\n  - {template: ring, name: star, with: {shape: star, flat: true, radii: [5, 15]}, steps: [{translate: [30, 0, 0]}]}\n",
    );
    let g = parse(&gcode);
    // radius of each part's points round its own centre
    let radii = |part: &str, cx: f64| -> (f64, f64, f64) {
        let k = g.parts.iter().position(|p| p == part).unwrap();
        g.moves.iter().filter(|m| m.part == k && m.de > 0.0).fold(
            (f64::INFINITY, 0.0, 0.0),
            |(lo, hi, top), m| {
                let r = ((m.to[0] - 110.0 - cx).powi(2) + (m.to[1] - 110.0).powi(2)).sqrt();
                (lo.min(r), hi.max(r), f64::max(top, m.to[2]))
            },
        )
    };
    let (lo, hi, top) = radii("round", -30.0);
    assert!(
        (lo - 20.0).abs() < 0.05 && (hi - 20.0).abs() < 0.05,
        "{lo} {hi}"
    );
    assert!((top - 4.2).abs() < 0.01, "{top}");
    // the star: the list's 15 mm, pulled in by up to 4 mm, one mm tall
    let (lo, hi, top) = radii("star", 30.0);
    assert!(
        (hi - 15.0).abs() < 0.05 && (lo - 11.0).abs() < 0.1,
        "{lo} {hi}"
    );
    assert!((top - 1.2).abs() < 0.01, "{top}");
}

#[test]
fn copies_of_a_named_group_name_their_parts_by_the_copy() {
    let recipe = "p3dp: 1\nname: copies\nprinter: bambu-a1-mini\ntemplates:\n  pot:\n    params: {h: 6}\n    part:\n      parts:\n        - {name: bottom, primitive: {cylinder: {radius: 8, height: 0.4, vpitch: 0.2, hpitch: 0.45, center: [0, 0, 0.2]}}, cross_section: 0.1, speed: 25}\n        - {name: wall, primitive: {helix: {radius: 8, height: h, pitch: 0.25, center: [0, 0, 0.4]}}}\nparts:\n  - {template: pot, name: \"pot-{k}\", for: {k: \"1..2\"}, with: {h: \"4 + 2*k\"}, steps: [{translate: [\"50*k - 75\", 0, 0]}]}\n  - {template: pot, name: crowded, steps: [{translate: [-5, 30, 0]}]}\n";
    let (gcode, report) = built("copies", recipe);
    let g = parse(&gcode);
    assert_eq!(
        g.parts[1..],
        [
            "pot-1/bottom",
            "pot-1/wall",
            "pot-2/bottom",
            "pot-2/wall",
            "bottom",
            "wall"
        ]
        .map(String::from)
    );
    assert!(report.contains("    pot-2/wall: "), "{report}");
    // a finding in a copy names the copy: the third pot stands within the
    // head's reach of the first two
    let finding = report
        .lines()
        .find(|l| l.contains("[head-collision]"))
        .unwrap_or_else(|| panic!("{report}"));
    assert!(
        finding.contains("filament of part `pot-1/wall`")
            || finding.contains("filament of part `pot-2/wall`"),
        "{finding}"
    );
}

#[test]
fn empty_loops_and_moveless_paths_make_nothing_and_no_error() {
    let (gcode, _) = built(
        "empty",
        "p3dp: 1\nname: empty\nparams: {saucer: 0}\nparts:\n  - {name: ring, for: {k: \"1..saucer\"}, primitive: {circle: {radius: 20, center: [0, 0, 0.2]}}}\n  - {name: none, for: {k: []}, primitive: {circle: {radius: 20, center: [0, 0, 0.2]}}}\n  - name: turtle\n    primitive: {turtle: {start: {position: [0, 0, 0.2]}, program: [{if: saucer, do: [{forward: 10}]}]}}\n  - {name: cup, primitive: {helix: {radius: 10, height: 2, pitch: 0.25, center: [0, 0, 0.2]}}}\n",
    );
    assert_eq!(parse(&gcode).parts[1..], ["cup".to_string()]);
    // every part switched off: nothing to print, said so
    let dir = tmp("plate-nothing");
    std::fs::write(
        dir.join("n.yaml"),
        "p3dp: 1\nname: n\nparams: {on: false}\nparts:\n  - {if: on, primitive: {circle: {radius: 20, center: [0, 0, 0.2]}}}\n",
    )
    .unwrap();
    let o = p3dp(&dir, &["check", "n.yaml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("every part is switched off"));
}

#[test]
fn a_whole_recipe_is_a_part_with_its_params_overridden() {
    let (gcode, report) = built(
        "whole",
        "p3dp: 1\nname: whole\nparts:\n  - {include: pot.yaml, name: tall, with: {height: 30, shape: star}, steps: [{translate: [-40, 0, 0]}]}\n  - {include: pot.yaml, with: {saucer: true}, steps: [{translate: [40, 0, 0]}]}\n",
    );
    let g = parse(&gcode);
    assert_eq!(
        g.parts[1..],
        [
            "tall/bottom",
            "tall/wall",
            "pot/saucer",
            "pot/bottom",
            "pot/wall"
        ]
        .map(String::from)
    );
    assert!(report.contains("0 warnings, 0 errors"), "{report}");
    // the tall one is 30 mm high (its `with:`), the other the recipe's 20
    let top = |name: &str| {
        let k = g.parts.iter().position(|p| p == name).unwrap();
        g.moves
            .iter()
            .filter(|m| m.part == k && m.de > 0.0)
            .map(|m| m.to[2])
            .fold(0.0, f64::max)
    };
    assert!(
        (top("tall/wall") - 30.6).abs() < 0.01,
        "{}",
        top("tall/wall")
    );
    assert!((top("pot/wall") - 20.6).abs() < 0.01, "{}", top("pot/wall"));
}

/// The hosts read a plate's objects (run with `P3DP_HOST_VENV`, as
/// `tests/it/hosts.rs`; skipped with a note without it): Moonraker's object
/// processing makes Klipper's labels of the `; printing object` comments,
/// one object per pot, and bambox finds the vases' package valid.
#[test]
fn the_hosts_read_a_plates_objects() {
    let Some(py) = crate::hosts::venv("P3DP_HOST_VENV", "the hosts' readers of a plate") else {
        return;
    };
    let dir = tmp("plate-hosts");
    let pots = plates("pots.yaml");
    build(
        &dir,
        &["build", pots.to_str().unwrap(), "-o", "pots.gcode"],
        "pots.gcode",
    );
    let site = std::process::Command::new(&py)
        .args(["-c", "import importlib.util as u; print(u.find_spec('moonraker').submodule_search_locations[0])"])
        .output()
        .unwrap();
    let script = PathBuf::from(String::from_utf8_lossy(&site.stdout).trim())
        .join("components/file_manager/metadata.py");
    let out = std::process::Command::new(&py)
        .arg(&script)
        .args(["-p", dir.to_str().unwrap(), "-f", "pots.gcode", "-o"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("pots.gcode")).unwrap();
    let defined: Vec<&str> = text
        .lines()
        .filter_map(|l| l.strip_prefix("EXCLUDE_OBJECT_DEFINE NAME="))
        .map(|l| l.split(' ').next().unwrap())
        .collect();
    assert_eq!(defined.len(), 4, "{defined:?}");
    for n in &defined {
        assert!(n.to_ascii_lowercase().starts_with("pot"), "{n}");
        assert_eq!(
            text.matches(&format!("EXCLUDE_OBJECT_START NAME={n}\n"))
                .count(),
            1,
            "{n}"
        );
    }
    // Bambu's package of the nine vases, as bambox validates it
    let vases = plates("vases.yaml");
    let o = p3dp(
        &dir,
        &["build", vases.to_str().unwrap(), "-o", "v.gcode.3mf"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = std::process::Command::new(py.with_file_name("bambox"))
        .args(["validate", "--strict", "--json"])
        .arg(dir.join("v.gcode.3mf"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let json = &text[text.find('{').unwrap_or(0)..];
    let v: serde_json::Value = serde_json::from_str(json).unwrap_or_else(|e| panic!("{e}: {text}"));
    assert_eq!(v["valid"], true, "{v}");
    assert_eq!(v["errors"], serde_json::json!([]), "{v}");
    assert_eq!(v["warnings"], serde_json::json!([]), "{v}");
}

/// The `.gcode.3mf`'s top and pick pictures are drawn from above, the
/// whole bed in the picture as Bambu Studio frames them (a 256 mm bed on
/// 512 px: 2 px/mm, y up the bed is up the picture): each object's pixels
/// lie over its footprint (its box in `plate_1.json`) and nowhere else, the
/// objects apart; the pick picture gives each object one flat opaque
/// colour that numbers it, r + 256 g + 65536 b = its `identify_id` in
/// `slice_info.config`, and no pixel mixes two (no blending).
#[test]
fn the_packages_top_and_pick_pictures_show_each_object_from_above() {
    let dir = tmp("plate-pictures");
    let (pot, vase) = (plates("pot.yaml"), plates("bud-vase.yaml"));
    let o = p3dp(
        &dir,
        &[
            "plate",
            pot.to_str().unwrap(),
            vase.to_str().unwrap(),
            "--printer",
            "bambu-a1",
            "-o",
            "two.gcode.3mf",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(dir.join("two.gcode.3mf")).unwrap();
    let mut z = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
    let mut read = |name: &str| {
        let mut v = Vec::new();
        std::io::Read::read_to_end(&mut z.by_name(name).unwrap(), &mut v).unwrap();
        v
    };
    let json: serde_json::Value = serde_json::from_slice(&read("Metadata/plate_1.json")).unwrap();
    let info = String::from_utf8(read("Metadata/slice_info.config")).unwrap();
    let png = |v: Vec<u8>| {
        image::load_from_memory_with_format(&v, image::ImageFormat::Png)
            .unwrap()
            .to_rgba8()
    };
    let (iso, top, pick) = (
        read("Metadata/plate_1.png"),
        read("Metadata/top_1.png"),
        read("Metadata/pick_1.png"),
    );
    assert_ne!(top, iso, "the top picture is its own view");
    let (top, pick) = (png(top), png(pick));
    assert_eq!((top.width(), top.height()), (512, 512));
    assert_eq!((pick.width(), pick.height()), (512, 512));
    // each object's box on the bed, in pixels (2 px/mm, y flipped), grown
    // by 2 px for the strings' width and the edge pixels
    let boxes: Vec<(u32, [f64; 4])> = json["bbox_objects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| {
            let b: Vec<f64> = o["bbox"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            let id = o["id"].as_u64().unwrap() as u32;
            (
                id,
                [
                    2.0 * b[0] - 2.0,
                    512.0 - 2.0 * b[3] - 2.0,
                    2.0 * b[2] + 2.0,
                    512.0 - 2.0 * b[1] + 2.0,
                ],
            )
        })
        .collect();
    assert_eq!(boxes.len(), 2);
    for (id, _) in &boxes {
        assert!(info.contains(&format!("identify_id=\"{id}\"")), "{info}");
    }
    // the boxes apart: a gap of transparent pixels between them
    let (a, b) = (boxes[0].1, boxes[1].1);
    assert!(
        a[2] < b[0] || b[2] < a[0] || a[3] < b[1] || b[3] < a[1],
        "{a:?} {b:?}"
    );
    let inside = |x: u32, y: u32| {
        boxes
            .iter()
            .find(|(_, r)| {
                (x as f64) >= r[0] && (x as f64) <= r[2] && (y as f64) >= r[1] && (y as f64) <= r[3]
            })
            .map(|(id, _)| *id)
    };
    let mut top_in = [0usize; 2];
    let mut pick_in = [0usize; 2];
    for (x, y, p) in top.enumerate_pixels() {
        if p[3] > 0 {
            let id = inside(x, y).unwrap_or_else(|| panic!("top: ({x}, {y}) lies on no object"));
            top_in[id as usize - 1] += 1;
        }
    }
    for (x, y, p) in pick.enumerate_pixels() {
        match p[3] {
            0 => {}
            255 => {
                let id = p[0] as u32 + 256 * p[1] as u32 + 65536 * p[2] as u32;
                assert_eq!(inside(x, y), Some(id), "pick: ({x}, {y}) has id {id}");
                pick_in[id as usize - 1] += 1;
            }
            a => panic!("pick: ({x}, {y}) is blended (alpha {a})"),
        }
    }
    // each object covers most of its box's disc from above (a pot's and a
    // vase's bottoms are filled): π/4 of a 30 mm box is ~2800 px
    for k in 0..2 {
        assert!(
            top_in[k] > 2000,
            "top: object {} has {} px",
            k + 1,
            top_in[k]
        );
        assert!(
            pick_in[k] > 2000,
            "pick: object {} has {} px",
            k + 1,
            pick_in[k]
        );
    }
}
