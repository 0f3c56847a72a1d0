//! Parts a param switches, copies named by their group, whole recipes as
//! parts and template params of every kind (issue 41), as the loader
//! resolves them: which parts there are and what they are named, and the
//! places its errors name.
//!
//! Past the public face: `recipe::{parse_yaml, RawRecipe}`,
//! `recipe::load`, `recipe::resolve`, `Recipe::parts`. Home: beside
//! `recipe::expand`.

use std::path::Path;

use crate::base::testing::tmp;
use crate::generate::model::Recipe;
use crate::recipe::{parse_yaml, RawRecipe};

/// The part names of recipe `text` resolved with `sets`, or its error.
fn names(text: &str, sets: &[(&str, &str)]) -> Result<Vec<String>, String> {
    let raw: RawRecipe = parse_yaml(text, "t.yaml").map_err(|e| e.to_string())?;
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(n, v)| (n.to_string(), v.to_string()))
        .collect();
    crate::recipe::resolve(&raw, &sets, None, Path::new("."))
        .map(|r| r.parts.iter().map(|p| p.name.clone()).collect())
        .map_err(|e| e.to_string())
}

const RING: &str = "{circle: {radius: 5, center: [0, 0, 0.2]}}";

#[test]
fn if_switches_a_part_and_its_children_in_each_copy() {
    let text = format!(
        "p3dp: 1\nname: t\nparams: {{saucer: false}}\nparts:\n  - {{name: saucer, if: saucer, primitive: {RING}}}\n  - {{name: \"r-{{k}}\", for: {{k: \"1..3\"}}, if: \"k != 2\", primitive: {RING}}}\n  - {{name: g, if: \"not saucer\", parts: [{{name: a, primitive: {RING}}}]}}\n"
    );
    assert_eq!(names(&text, &[]).unwrap(), ["r-1", "r-3", "a"]);
    assert_eq!(
        names(&text, &[("saucer", "true")]).unwrap(),
        ["saucer", "r-1", "r-3"]
    );
    // an `if` that is no expression names its key
    let e = names(&text.replace("if: saucer", "if: \"saucer +\""), &[]).unwrap_err();
    assert!(e.contains("parts[0].if"), "{e}");
}

#[test]
fn empty_ranges_and_lists_make_no_copy() {
    let text = format!(
        "p3dp: 1\nname: t\nparams: {{count: 0}}\nparts:\n  - {{name: a, for: {{k: \"1..count\"}}, primitive: {RING}}}\n  - {{name: b, for: {{k: []}}, primitive: {RING}}}\n  - {{name: c, primitive: {RING}}}\n"
    );
    assert_eq!(names(&text, &[]).unwrap(), ["c"]);
    assert_eq!(
        names(&text, &[("count", "2")]).unwrap(),
        ["a-0", "a-1", "c"]
    );
    let none =
        format!("p3dp: 1\nname: t\nparts:\n  - {{name: a, for: {{k: []}}, primitive: {RING}}}\n");
    assert!(names(&none, &[])
        .unwrap_err()
        .contains("every part is switched off"));
}

#[test]
fn a_copied_named_group_names_its_parts_by_the_copy() {
    let group =
        format!("parts: [{{name: bottom, primitive: {RING}}}, {{name: wall, primitive: {RING}}}]");
    let text = format!(
        "p3dp: 1\nname: t\ntemplates:\n  pot: {{part: {{{group}}}}}\nparts:\n  - {{name: \"pot-{{k}}\", for: {{k: \"1..2\"}}, {group}}}\n  - {{template: pot, name: \"tpl-{{k}}\", for: {{k: \"3..3\"}}}}\n  - {{name: row, for: {{k: \"0..1\"}}, {group}}}\n  - {{for: {{k: \"0..0\"}}, {group}}}\n  - {{name: one, {group}}}\n"
    );
    assert_eq!(
        names(&text, &[]).unwrap(),
        [
            "pot-1/bottom",
            "pot-1/wall",
            "pot-2/bottom",
            "pot-2/wall",
            "tpl-3/bottom",
            "tpl-3/wall",
            "row-0/bottom",
            "row-0/wall",
            "row-1/bottom",
            "row-1/wall",
            // an unnamed copied group suffixes its parts; an uncopied one
            // leaves their names alone
            "bottom-0",
            "wall-0",
            "bottom",
            "wall",
        ]
    );
}

#[test]
fn template_params_take_every_kind_and_refuse_the_wrong_one() {
    let text = format!(
        "p3dp: 1\nname: t\ntemplates:\n  ring:\n    params: {{shape: {{choices: [round, star], default: round}}, on: true, rs: [1, 2]}}\n    part: {{name: \"{{if(shape == 'star', 1, 0)}}-{{on}}-{{rs[1]}}\", primitive: {RING}}}\nparts:\n  - {{template: ring}}\n  - {{template: ring, with: {{shape: star, on: false, rs: [3, 4]}}}}\n"
    );
    assert_eq!(names(&text, &[]).unwrap(), ["0-1-2", "1-0-4"]);
    let e = names(&text.replace("shape: star", "shape: square"), &[]).unwrap_err();
    assert!(e.contains("parts[1].with.shape"), "{e}");
    assert!(e.contains("expected one of round, star"), "{e}");
    let e = names(&text.replace("rs: [3, 4]", "rs: 3"), &[]).unwrap_err();
    assert!(e.contains("parts[1].with.rs"), "{e}");
}

/// Writes `files` (name, text) in a fresh project and loads `main`.
fn load(tag: &str, files: &[(&str, &str)], main: &str) -> Result<Recipe, String> {
    let dir = tmp(tag);
    std::fs::write(dir.join("p3dp.lock"), "p3dp_lock: 1\nentries: []\n").unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    crate::recipe::load(&dir.join(main), &[], None).map_err(|e| e.to_string())
}

const CUP: &str = "p3dp: 1\nname: cup\nparams: {rad: 5, kind: {choices: [low, high], default: low}}\ndefaults: {cross_section: 0.1}\nparts:\n  - {name: ring, primitive: {helix: {radius: rad, height: \"if(kind == 'high', 4, 1)\", pitch: 0.5, center: [0, 0, 0.2]}}}\n";

#[test]
fn a_whole_recipe_is_a_group_of_its_parts_with_its_params_given() {
    let main = "p3dp: 1\nname: m\nparams: {size: 7}\nparts:\n  - {include: cup.yaml, with: {rad: \"size\", kind: high}, for: {k: \"1..2\"}, name: \"c-{k}\", steps: [{translate: [\"20*k\", 0, 0]}]}\n  - {include: cup.yaml}\n";
    let r = load("whole", &[("cup.yaml", CUP), ("m.yaml", main)], "m.yaml").unwrap();
    let names: Vec<&str> = r.parts.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["c-1/ring", "c-2/ring", "cup/ring"]);
    // its params from `with:` (over the caller's params), its own defaults
    let radius = |k: usize| match &r.parts[k].primitive {
        crate::generate::primitive::Primitive::Helix(h) => (h.radius, h.height),
        other => panic!("{other:?}"),
    };
    assert_eq!(radius(0), (7.0, 4.0));
    assert_eq!(radius(2), (5.0, 1.0));
    assert_eq!(r.parts[0].cross_section, 0.1);
    // its group's steps run on its parts
    assert_eq!(r.groups.len(), 2);
}

#[test]
fn a_whole_recipe_is_refused_when_it_cannot_be_one() {
    let cycle_a = "p3dp: 1\nname: a\nparts: [{include: b.yaml}]\n";
    let cycle_b = "p3dp: 1\nname: b\nparts: [{include: a.yaml}]\n";
    let e = load(
        "cycle",
        &[("a.yaml", cycle_a), ("b.yaml", cycle_b)],
        "a.yaml",
    )
    .unwrap_err();
    assert!(e.contains("include cycle") && e.contains("b.yaml"), "{e}");
    let main = "p3dp: 1\nname: m\nparts: [{include: cup.yaml, with: {radius: 3}}]\n";
    let e = load("unknown", &[("cup.yaml", CUP), ("m.yaml", main)], "m.yaml").unwrap_err();
    assert!(e.contains("parts[0].with.radius"), "{e}");
    assert!(
        e.contains("the recipe `cup.yaml` has no param `radius`; its params are rad, kind"),
        "{e}"
    );
    let plate = "p3dp: 1\nname: p\nplate: [{recipe: cup.yaml}]\n";
    let main = "p3dp: 1\nname: m\nparts: [{include: p.yaml}]\n";
    let e = load(
        "plate",
        &[("cup.yaml", CUP), ("p.yaml", plate), ("m.yaml", main)],
        "m.yaml",
    )
    .unwrap_err();
    assert!(e.contains("is a plate"), "{e}");
    let main = "p3dp: 1\nname: m\nparts: [{include: cup.yaml, template: x}]\n";
    let e = load("both", &[("cup.yaml", CUP), ("m.yaml", main)], "m.yaml").unwrap_err();
    assert!(
        e.contains("parts[0].include: `include` beside `template`"),
        "{e}"
    );
}
