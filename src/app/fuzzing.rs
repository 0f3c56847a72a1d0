//! The fuzz targets' entry points (`fuzz/`, run by hand with cargo-fuzz):
//! each takes the fuzzer's bytes through one of p3dp's readers, as the
//! command line would, and must never panic. Built only with the `fuzzing`
//! feature, so the crate's face stays small.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::base::expr::{eval_const, var, Expr, Memo, Params};
use crate::base::input::{check_nesting, decode, Reads, MAX_IMAGE_PIXELS};
use crate::base::slicer_macro::{Template, Value, Vars};
use crate::base::svg::{parse, Options, Outline};
use crate::base::toolpath::Toolpath;
use crate::generate::model::make_part;
use crate::output::lock::{first_difference, LineHashes, Lock};
use crate::recipe::schema::Num;
use crate::recipe::{parse_yaml, RawRecipe};

/// Parts of at most this many strings are built and checked too.
const BUILD_STRINGS: u64 = 20_000;

/// A scratch folder of this process for one target, marked as a project.
fn scratch(target: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("p3dp-fuzz-{target}-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let _ = std::fs::write(dir.join("p3dp.lock"), "p3dp_lock: 1\nentries: []\n");
    dir
}

/// Recipe text → load and resolve (relative paths from `recipes`), then
/// build and check it when small.
pub fn recipe(data: &[u8], recipes: &Path) {
    // as recipe::load reads a file: UTF-8 without a BOM, nesting capped
    let Ok(text) = decode(data.to_vec()) else {
        return;
    };
    if check_nesting(&text).is_err() {
        return;
    }
    let Ok(raw) = parse_yaml::<RawRecipe>(&text, "fuzz.yaml") else {
        return;
    };
    // a bound on the work of one input: the fuzzer wants many fast runs
    let raw = RawRecipe {
        max_strings: raw.max_strings.or(Some(Num::Value(200_000.0))),
        ..raw
    };
    let Ok(recipe) = crate::recipe::resolve(&raw, &[], None, recipes) else {
        return;
    };
    if recipe.string_count() > BUILD_STRINGS {
        return;
    }
    let mut paths = Vec::new();
    for k in 0..recipe.parts.len() {
        match make_part(&recipe, k) {
            Ok(tp) => paths.push(tp),
            Err(_) => return,
        }
    }
    let refs: Vec<&Toolpath> = paths.iter().collect();
    let _ = crate::analyse::check::run(&recipe, &refs, &recipe.allow);
}

/// Included library text → a recipe that includes it and uses its template
/// `cup` (the gallery's `cup.yaml` is the seed), loaded through files.
pub fn include(data: &[u8]) {
    const RECIPE: &str =
        "p3dp: 1\nname: f\ninclude: [lib.yaml]\nmax_strings: 200000\nparts:\n  - template: cup\n";
    let dir = scratch("include");
    let recipe = dir.join("r.yaml");
    if std::fs::write(&recipe, RECIPE).is_err()
        || std::fs::write(dir.join("lib.yaml"), data).is_err()
    {
        return;
    }
    let _ = crate::recipe::load(&recipe, &[], None);
}

/// Expression text → compiled and evaluated at ordinary and extreme values.
pub fn expr(data: &[u8]) {
    let Ok(src) = std::str::from_utf8(data) else {
        return;
    };
    let mut params = Params::new();
    params.insert("radius".into(), 30.0);
    params.insert("height".into(), 100.0);
    let _ = eval_const(src, &params);
    let all: Vec<usize> = (0..var::COUNT).collect();
    if let Ok(e) = Expr::compile(src, &params, &all) {
        for vars in [
            [0.0; var::COUNT],
            [1.0, -2.0, 3.5, 4.0, 0.5, 0.2, 40.0, 7.0, 100.0, 0.07, 0.25],
            [
                1e300,
                -1e300,
                f64::MIN_POSITIVE,
                1e-300,
                6.25,
                1e9,
                1e-9,
                1e6,
                1e6,
                1.0,
                0.999,
            ],
        ] {
            let _ = e.eval(&vars);
        }
    }
    if let Ok(e) = Expr::compile_ext(src, &params, &all, &["len", "depth"]) {
        let ext = vec![0.5; 2 + e.rands()];
        let _ = e.eval_ext(&[1.0; var::COUNT], &ext, &mut Memo::default());
    }
}

/// Slicer macro text → a template parsed, its variables listed, and
/// expanded twice over a few typical variables (the same bytes both times:
/// `random` is seeded by the text), within the output cap.
pub fn slicer_macro(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(t) = Template::parse(text) else {
        return;
    };
    let _ = t.variables();
    let mut vars = Vars::new();
    let list = |v: Vec<Value>| Value::List(v);
    vars.insert("layer_height".into(), Value::Float(0.2));
    vars.insert("initial_tool".into(), Value::Int(0));
    vars.insert("printer_model".into(), Value::Str("MK4S".into()));
    vars.insert("has_wipe_tower".into(), Value::Bool(false));
    vars.insert(
        "temperature".into(),
        list(vec![Value::Int(215), Value::Nil]),
    );
    vars.insert("bed_shape".into(), list(vec![Value::Str("0x0".into()); 4]));
    vars.insert("park".into(), Value::Shown(12.3, "12.300".into()));
    let a = t.expand(&vars);
    let b = t.expand(&vars);
    assert_eq!(a, b, "the same template, the same bytes");
    if let Ok(out) = a {
        assert!(out.len() <= 4 << 20, "the output cap");
    }
}

/// Image bytes → a `modulate_map` bitmap, within the pixel cap.
pub fn image(data: &[u8]) {
    let dir = scratch("image");
    let file = dir.join("map.png");
    if std::fs::write(&file, data).is_err() {
        return;
    }
    let reads = Reads::default();
    reads.allow(&dir);
    if let Ok(b) = crate::recipe::resolve::step::load_bitmap(&file, "map.png", &reads) {
        assert!(b.width as u64 * b.height as u64 <= MAX_IMAGE_PIXELS);
    }
}

/// Lock text → validated, its entries compared with a small G-code's.
pub fn lock(data: &[u8]) {
    let Ok(text) = decode(data.to_vec()) else {
        return;
    };
    if check_nesting(&text).is_err() {
        return;
    }
    let Ok(lock) = parse_yaml::<Lock>(&text, "fuzz.lock") else {
        return;
    };
    if lock.validate().is_err() {
        return;
    }
    let mut lines = LineHashes::default();
    let _ = lines.write_all(b"G1 X1\nG1 X2\n; end\n");
    for e in &lock.entries {
        let new = lines.blocks(e.block_lines);
        let _ = first_difference(&e.blocks, &new);
        let _ = &e.sha256[..12];
    }
}

/// Printer profile text → a profile loaded from a file.
pub fn printer(data: &[u8]) {
    let dir = scratch("printer");
    let file = dir.join("profile.yaml");
    if std::fs::write(&file, data).is_err() {
        return;
    }
    let _ = crate::recipe::profile::from_file(&file);
}

/// SVG text → an outline, sampled.
pub fn svg(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let opt = Options {
        id: None,
        scale: 1.0,
        tolerance: 0.01,
        max_points: 200_000,
    };
    if let Ok(subpaths) = parse(text, &opt) {
        if let Ok(o) = Outline::from_subpaths(&subpaths) {
            let _ = o.fractions(240);
            let _ = o.point_at(0.5);
        }
    }
}

/// A fixed parent and template beside a fuzzed `.json` preset, so its
/// `inherits` and `include` chains are followed.
const JSON_PARENT: &str = r#"{"type": "machine", "name": "base", "printable_area": ["0x0", "200x0", "200x200", "0x200"], "printable_height": "200", "nozzle_diameter": ["0.4", "0.4"], "machine_start_gcode": "G28 ; [printer_preset]", "machine_end_gcode": "M84"}"#;
const JSON_TEMPLATE: &str = r#"{"name": "tpl", "machine_start_gcode": "M104 S{nozzle_temperature_initial_layer[initial_no_support_extruder]}\nG28"}"#;
const JSON_FILAMENT: &str = r#"{"type": "filament", "name": "fil", "nozzle_temperature": ["210"], "hot_plate_temp": ["60"], "filament_density": ["1.24"]}"#;

/// One preset of `kind` loaded: a printer mapped to a profile, its YAML
/// read back as the same value, loaded as a profile; a filament made a
/// material. Errors are fine; a panic or a YAML that reads back otherwise
/// is a finding.
fn preset_one(kind: crate::recipe::preset::Kind, src: &crate::recipe::preset::Source) {
    use crate::recipe::preset::{self, map, Kind};
    let reads = Reads::default();
    let Ok(p) = preset::load_kind(kind, src, &reads) else {
        return;
    };
    match kind {
        Kind::Printer => {
            let Ok(imported) = map::import(&p) else {
                return;
            };
            let yaml = imported.yaml();
            let back: crate::recipe::schema::RawPrinter = parse_yaml(&yaml, "fuzz.yaml")
                .unwrap_or_else(|e| panic!("the import's YAML does not load: {e}\n{yaml}"));
            assert!(
                back == imported.raw,
                "the import's YAML reads back otherwise:\n{yaml}"
            );
            let _ = crate::recipe::profile::from_raw(back, "fuzz.yaml");
        }
        Kind::Filament => {
            let _ = crate::recipe::resolve::from_filament(src, &reads);
        }
    }
}

/// `.ini` preset text → every printer and filament preset of it (at most
/// eight of each) loaded, mapped, written and read back.
pub fn preset_ini(data: &[u8]) {
    use crate::recipe::preset::{self, Kind, Source};
    let dir = scratch("preset-ini");
    let file = dir.join("bundle.ini");
    if std::fs::write(&file, data).is_err() {
        return;
    }
    for kind in [Kind::Printer, Kind::Filament] {
        let Ok(names) = preset::list_of(kind, &file, &Reads::default()) else {
            continue;
        };
        for name in names.into_iter().take(8) {
            let src = Source {
                file: file.clone(),
                preset: Some(name),
                profiles: None,
            };
            preset_one(kind, &src);
        }
        // a missed name: the did-you-mean search
        let src = Source {
            file: file.clone(),
            preset: Some("no such preset".into()),
            profiles: None,
        };
        preset_one(kind, &src);
    }
}

/// `.json` preset text (beside a parent `base`, a template `tpl` and a
/// filament `fil` it may inherit or include) → loaded as a printer and as a
/// filament, mapped, written and read back.
pub fn preset_json(data: &[u8]) {
    use crate::recipe::preset::{Kind, Source};
    let dir = scratch("preset-json");
    let machine = dir.join("machine");
    let _ = std::fs::create_dir_all(&machine);
    for (name, text) in [
        ("base.json", JSON_PARENT),
        ("tpl.json", JSON_TEMPLATE),
        ("fil.json", JSON_FILAMENT),
    ] {
        let _ = std::fs::write(machine.join(name), text);
    }
    let file = machine.join("fuzz.json");
    if std::fs::write(&file, data).is_err() {
        return;
    }
    let src = Source {
        file,
        preset: None,
        profiles: None,
    };
    preset_one(Kind::Printer, &src);
    preset_one(Kind::Filament, &src);
}

/// A G-code line → read as each firmware reads it (no panic, whatever the
/// bytes); every command read is written back by the one writer as lines
/// the same firmware reads again.
pub fn gcode_line(data: &[u8]) {
    use crate::machine::firmware::{read, write};
    use crate::machine::Flavor;
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for flavor in Flavor::ALL {
        let Ok(r) = read::read(flavor, text) else {
            continue;
        };
        // object labels on where the firmware has them (Klipper's
        // EXCLUDE_OBJECT): a label read is written as the command, not as
        // the comment written when they are off
        let d = write::Dialect {
            flavor,
            object_labels: flavor == Flavor::Klipper,
            prusa_8bit: false,
        };
        for c in &r.commands {
            if write::refusal(d, c).is_some() {
                continue;
            }
            let mut chunk = crate::base::format::Chunk::new();
            write::write(d, c, "", &mut chunk);
            let written = std::str::from_utf8(chunk.bytes()).expect("the writer writes ASCII");
            // a command may take more than one line (RepRapFirmware waits
            // for a heater with `M116` after `M104`): each reads again
            assert!(!written.contains('\r'), "{written:?}");
            let mut read_again = 0;
            for line in written.lines() {
                let again = read::read(flavor, line)
                    .unwrap_or_else(|e| panic!("{flavor:?}: {line:?} written, not read: {e}"));
                read_again += again.commands.len();
            }
            assert!(read_again >= 1, "{flavor:?}: {text:?} → {written:?}");
        }
    }
}
