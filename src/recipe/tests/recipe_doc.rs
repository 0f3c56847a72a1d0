//! `docs/recipe.md` cannot drift from the code: every key the loader knows
//! (found by asking the loader itself: an unknown key `__probe__` at each
//! place makes it list the keys it takes there), every variable and every
//! expression function must appear in the reference as a code span.
//!
//! Past the public face: the loader's raw form (`recipe::parse_yaml`,
//! `RawRecipe`) and the expression language's names (`base::expr::VAR_NAMES`,
//! `FUNCTIONS`). Home: beside `recipe::schema` (the keys) and `base::expr`.

use crate::recipe::{parse_yaml, RawRecipe};

/// The names the loader lists for the place where `__probe__` stands in
/// `yaml`, or none when it takes no map there.
fn listed(yaml: &str) -> Vec<String> {
    let e = match parse_yaml::<RawRecipe>(yaml, "probe.yaml") {
        Ok(_) => return Vec::new(),
        Err(e) => e.message,
    };
    let list = match e.split_once("expected one of ") {
        Some((_, list)) => list.to_string(),
        // serde says `expected `a` or `b`` for two and `expected `a`` for one
        None if e.contains("unknown") => match e.split_once(", expected ") {
            Some((_, list)) => list.replace(" or ", ", "),
            None => return Vec::new(),
        },
        None => return Vec::new(),
    };
    list.split(", ")
        .map(|k| {
            k.split(';')
                .next()
                .unwrap_or(k)
                .trim()
                .trim_matches('`')
                .to_string()
        })
        .filter(|k| !k.is_empty() && !k.contains(' '))
        .collect()
}

const HEAD: &str = "p3dp: 1\nname: probe\n";

/// Every key and kind the loader takes, with where it was found.
fn loader_names() -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut add = |place: &str, names: Vec<String>| {
        for n in names {
            out.push((place.to_string(), n));
        }
    };
    let part = |inner: &str| format!("{HEAD}parts:\n  - {inner}\n");
    add(
        "top level",
        listed(&format!("{HEAD}__probe__: 1\nparts: []\n")),
    );
    add(
        "material",
        listed(&format!("{HEAD}material: {{__probe__: 1}}\nparts: []\n")),
    );
    add(
        "defaults",
        listed(&format!("{HEAD}defaults: {{__probe__: 1}}\nparts: []\n")),
    );
    add(
        "skirt",
        listed(&format!("{HEAD}skirt: {{__probe__: 1}}\nparts: []\n")),
    );
    add(
        "allow",
        listed(&format!("{HEAD}allow: [{{__probe__: 1}}]\nparts: []\n")),
    );
    add(
        "templates",
        listed(&format!(
            "{HEAD}templates: {{t: {{__probe__: 1}}}}\nparts: []\n"
        )),
    );
    add("part", listed(&part("{__probe__: 1}")));
    add(
        "plate entry",
        listed(&format!(
            "{HEAD}plate: [{{recipe: a.yaml, __probe__: 1}}]\n"
        )),
    );
    add(
        "for",
        listed(&part(
            "{for: {k: {__probe__: 1}}, primitive: {circle: {radius: 1}}}",
        )),
    );
    add("brim", listed(&part("{brim: {__probe__: 1}}")));
    add("stand", listed(&part("{stand: {__probe__: 1}}")));
    let prim = |p: &str, inner: &str| part(&format!("{{primitive: {{{p}: {inner}}}}}"));
    add(
        "path commands",
        listed(&prim("path", "{commands: [{__probe__: 1}]}")),
    );
    add(
        "solid infill",
        listed(&prim("solid", "{infill: {__probe__: 1}}")),
    );
    let features = listed(&prim("solid", "{features: [{__probe__: {}}]}"));
    for f in &features {
        add(
            &format!("solid feature {f}"),
            listed(&prim(
                "solid",
                &format!("{{features: [{{{f}: {{__probe__: 1}}}}]}}"),
            )),
        );
    }
    add("solid features", features);
    add(
        "turtle start",
        listed(&prim("turtle", "{start: {__probe__: 1}}")),
    );
    add(
        "turtle commands",
        listed(&prim("turtle", "{program: [{__probe__: 1}]}")),
    );
    let primitives = listed(&part("{primitive: {__probe__: {}}}"));
    for p in &primitives {
        add(
            &format!("primitive {p}"),
            listed(&part(&format!("{{primitive: {{{p}: {{__probe__: 1}}}}}}"))),
        );
    }
    add("primitive", primitives);
    let steps = listed(&part("{steps: [{__probe__: {}}]}"));
    for s in &steps {
        add(
            &format!("step {s}"),
            listed(&part(&format!("{{steps: [{{{s}: {{__probe__: 1}}}}]}}"))),
        );
    }
    add("step", steps);
    out
}

fn doc() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/recipe.md");
    std::fs::read_to_string(path).expect("docs/recipe.md")
}

/// Whether `name` appears in the doc as a code span (alone, or starting one
/// like `` `name: …` `` or `` `name(a, b)` ``).
fn mentioned(doc: &str, name: &str) -> bool {
    [
        format!("`{name}`"),
        format!("`{name}:"),
        format!("`{name}("),
    ]
    .iter()
    .any(|p| doc.contains(p.as_str()))
}

#[test]
fn the_probe_finds_the_loader_s_keys() {
    let names = loader_names();
    let has = |place: &str, n: &str| names.iter().any(|(p, k)| p == place && k == n);
    assert!(has("top level", "parts"), "{names:?}");
    assert!(has("top level", "plate"), "{names:?}");
    assert!(has("plate entry", "copies"), "{names:?}");
    assert!(has("part", "if"), "{names:?}");
    assert!(has("primitive helix", "pitch"), "{names:?}");
    assert!(has("step", "modulate_map"), "{names:?}");
    assert!(has("turtle commands", "forward"), "{names:?}");
    assert!(names.len() > 100, "{}", names.len());
}

#[test]
fn every_key_of_the_loader_is_in_the_reference() {
    let doc = doc();
    let missing: Vec<String> = loader_names()
        .into_iter()
        .filter(|(_, n)| !mentioned(&doc, n))
        .map(|(place, n)| format!("{place}: `{n}`"))
        .collect();
    assert!(
        missing.is_empty(),
        "docs/recipe.md does not mention these keys the loader takes:\n{}",
        missing.join("\n")
    );
}

#[test]
fn every_variable_and_function_is_in_the_reference() {
    let doc = doc();
    let mut missing = Vec::new();
    for v in crate::base::expr::VAR_NAMES.iter().chain(&["pi", "e"]) {
        if !mentioned(&doc, v) {
            missing.push(format!("variable `{v}`"));
        }
    }
    for f in crate::base::expr::FUNCTIONS.split_whitespace() {
        let name = f.split('(').next().unwrap();
        if !mentioned(&doc, name) {
            missing.push(format!("function `{name}`"));
        }
    }
    assert!(
        missing.is_empty(),
        "docs/recipe.md does not mention:\n{}",
        missing.join("\n")
    );
}

/// A recipe resolved from `text` (relative paths from the crate root).
fn resolved(text: &str) -> crate::generate::model::Recipe {
    let raw: RawRecipe = parse_yaml(text, "doc.yaml").unwrap();
    crate::recipe::resolve(&raw, &[], None, std::path::Path::new(".")).unwrap()
}

/// The defaults and units `docs/recipe.md` states are the loader's: each
/// row below is text the reference holds, beside the value the loader
/// gives when the key is left out (or the unit the G-code shows).
#[test]
fn stated_defaults_and_units_are_the_loaders() {
    let doc = std::fs::read_to_string(crate::base::testing::root().join("docs/recipe.md")).unwrap();
    let plain = resolved(
        "p3dp: 1\nname: d\nmaterial: {density: 1.24, nozzle_temp: 215, bed_temp: 60}\nparts:\n  - primitive: {circle: {radius: 10}}\n",
    );
    let tp = crate::generate::model::make_part(&plain, 0).unwrap();
    let m = &plain.material;
    let extras = resolved(
        "p3dp: 1\nname: e\nparts:\n  - speed: 33\n    brim: {loops: 3}\n    stand: {radius: 7}\n    primitive: {circle: {radius: 10, center: [0, 0, 5]}}\n",
    );
    let brim = extras.parts[0].brim.as_ref().unwrap();
    let stand = extras.parts[0].stand.as_ref().unwrap();
    let rows: Vec<(&str, bool)> = vec![
        (
            "`line_width` (0.45 mm, also the step between loops), `layer_height` (0.2 mm), `speed` (the part's)",
            brim.line_width == 0.45 && brim.layer_height == 0.2 && brim.speed == 33.0,
        ),
        (
            "`walls` concentric circles (2), `line_width` apart (0.45 mm)",
            stand.walls == 2 && stand.line_width == 0.45,
        ),
        (
            "in layers of `layer_height` (0.2 mm; the first at that nozzle height) at `speed` (the part's)",
            stand.layer_height == 0.2 && stand.speed == 33.0 && stand.height.is_none(),
        ),
        (
            "| `printer` | `generic-220` |",
            plain.printer.name == "generic-220",
        ),
        (
            "| `max_strings` | 50 000 000 |",
            plain.max_strings == 50_000_000,
        ),
        (
            "| `defaults.cross_section` | 0.196 | mm²",
            tp.strings.iter().all(|s| s.c == 0.196),
        ),
        (
            "| `defaults.speed` | 40 | mm/s",
            tp.strings.iter().all(|s| s.v == 40.0),
        ),
        (
            "`segments` the strings per turn (default 72)",
            tp.strings.iter().filter(|s| !s.travel).count() == 72,
        ),
        (
            "| `max_nozzle_temp` | `nozzle_temp` + 25 |",
            m.max_nozzle_temp == 215.0 + 25.0,
        ),
        ("| `fan_speed` | 0 (off) |", m.fan_speed == 0.0),
        ("| `fan_start_z` | 0.5 |", m.fan_start_z == 0.5),
        (
            "| `color` | `#FA8F29` (orange) |",
            m.color == [0xFA, 0x8F, 0x29],
        ),
        ("| `name` | `part N` |", plain.parts[0].name == "part 1"),
    ];
    for (text, holds) in rows {
        assert!(doc.contains(text), "docs/recipe.md no longer says {text}");
        assert!(holds, "docs/recipe.md says {text}, the loader disagrees");
    }
}

/// `dwell` waits milliseconds, as the reference says: `{dwell: 500}` is
/// `G4 P500`, half a second in the print-time estimate.
#[test]
fn dwell_is_milliseconds() {
    let doc = std::fs::read_to_string(crate::base::testing::root().join("docs/recipe.md")).unwrap();
    assert!(
        doc.contains("wait, in **milliseconds** (`G4 P<ms>`"),
        "docs/recipe.md"
    );
    let dir = crate::base::testing::tmp("doc-dwell");
    let recipe = |ms: u32| {
        format!(
            "p3dp: 1\nname: w{ms}\nparts:\n  - primitive:\n      turtle:\n        start: {{position: [0, 0, 0.2]}}\n        program:\n          - {{forward: 10}}\n          - {{dwell: {ms}}}\n          - {{forward: 10}}\n"
        )
    };
    let mut times = Vec::new();
    for ms in [0u32, 500] {
        std::fs::write(dir.join(format!("w{ms}.yaml")), recipe(ms)).unwrap();
        let o = crate::app::testing::p3dp(
            &dir,
            &[
                "build",
                &format!("w{ms}.yaml"),
                "-o",
                &format!("w{ms}.gcode"),
                "--stats-json",
                &format!("w{ms}.json"),
            ],
        );
        assert!(o.success(), "{}", o.stderr);
        let gcode = std::fs::read_to_string(dir.join(format!("w{ms}.gcode"))).unwrap();
        assert!(
            gcode.contains(&format!("\nG4 P{ms} ")),
            "no G4 P{ms} in the G-code"
        );
        let stats: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(format!("w{ms}.json"))).unwrap(),
        )
        .unwrap();
        times.push(stats["print_time_s"].as_f64().unwrap());
    }
    let waited = times[1] - times[0];
    assert!(
        (waited - 0.5).abs() < 1e-6,
        "a 500 ms dwell added {waited} s"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
