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
