//! `docs/gallery.md` and its pictures: every recipe of `recipes/` has its
//! preview (made by `docs/make-previews.sh`) and its line in the gallery,
//! and the pictures are current. They are deterministic, so "current" is
//! tested without drawing all of them: `docs/previews/SOURCES` holds the
//! hash of the G-code each was drawn from and must agree with `p3dp.lock`
//! (which another test holds to the code: `batch::`), and a few cheap ones
//! are drawn again and compared byte for byte (a change of the renderer
//! changes every picture).

use crate::common::*;
use std::collections::BTreeMap;

/// The recipes of `recipes/`, by name.
fn recipe_names() -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(root().join("recipes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The script's list: name → (colour, view).
fn script_list() -> BTreeMap<String, (String, String)> {
    let script = std::fs::read_to_string(root().join("docs/make-previews.sh")).unwrap();
    let list = script
        .split("<<'LIST'\n")
        .nth(1)
        .and_then(|s| s.split("\nLIST").next())
        .expect("the script's LIST");
    list.lines()
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(w.len(), 3, "{l}");
            (w[0].to_string(), (w[1].to_string(), w[2].to_string()))
        })
        .collect()
}

#[test]
fn every_recipe_has_its_picture_and_its_line() {
    let names = recipe_names();
    assert!(names.len() >= 39, "{names:?}");
    let list = script_list();
    let gallery = std::fs::read_to_string(root().join("docs/gallery.md")).unwrap();
    for n in &names {
        assert!(
            list.contains_key(n),
            "docs/make-previews.sh does not draw {n}"
        );
        assert!(
            root().join(format!("docs/previews/{n}.png")).is_file(),
            "no docs/previews/{n}.png: run docs/make-previews.sh"
        );
        let line = format!("| ![{n}](previews/{n}.png) | [`{n}`](../recipes/{n}.yaml) | ");
        assert_eq!(gallery.matches(&line).count(), 1, "docs/gallery.md: {line}");
    }
    // nothing drawn or shown that is not a recipe
    for n in list.keys() {
        assert!(
            names.contains(n),
            "the script draws {n}, which is no recipe"
        );
    }
    for e in std::fs::read_dir(root().join("docs/previews")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|e| e == "png") {
            let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
            assert!(
                names.contains(&stem),
                "{} is no recipe's picture",
                p.display()
            );
        }
    }
}

#[test]
fn the_pictures_were_drawn_from_the_locked_gcode() {
    let lock: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(root().join("p3dp.lock")).unwrap()).unwrap();
    let mut locked = BTreeMap::new();
    for e in lock["entries"].as_sequence().unwrap() {
        if e.get("set").is_none() && e.get("printer").is_none() {
            locked.insert(
                e["recipe"].as_str().unwrap().to_string(),
                e["sha256"].as_str().unwrap().to_string(),
            );
        }
    }
    let sources = std::fs::read_to_string(root().join("docs/previews/SOURCES")).unwrap();
    let mut drawn = BTreeMap::new();
    for l in sources.lines() {
        let (sha, recipe) = l.split_once("  ").expect("SHA256  RECIPE");
        drawn.insert(recipe.to_string(), sha.to_string());
    }
    for n in recipe_names() {
        let r = format!("recipes/{n}.yaml");
        let (Some(d), Some(l)) = (drawn.get(&r), locked.get(&r)) else {
            panic!("{r}: not in docs/previews/SOURCES and p3dp.lock both");
        };
        assert_eq!(
            d, l,
            "{r}: its G-code changed since its picture was drawn; run docs/make-previews.sh"
        );
    }
}

#[test]
fn a_few_pictures_drawn_again_are_the_same_bytes() {
    let list = script_list();
    let dir = tmp("gallery-docs");
    for n in ["hex-prism", "cardioid"] {
        let (color, view) = &list[n];
        let out = dir.join(format!("{n}.png"));
        let recipe = root().join(format!("recipes/{n}.yaml"));
        let o = p3dp(
            &dir,
            &[
                "preview",
                recipe.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--size",
                "600x450",
                "--color",
                color,
                "--view",
                view,
            ],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let committed = std::fs::read(root().join(format!("docs/previews/{n}.png"))).unwrap();
        assert!(
            std::fs::read(&out).unwrap() == committed,
            "docs/previews/{n}.png is not what `p3dp preview` draws now: run docs/make-previews.sh"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
