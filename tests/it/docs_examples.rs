//! Every example of the README, the guide, the recipe reference and the
//! checks' page runs:
//! the fenced blocks of those pages are read and executed, so a wrong word
//! about a command or a key fails the tests.
//!
//! - Every fenced block carries a language: `sh` and `yaml` blocks run,
//!   `text` (output, error messages) and others are shown only.
//! - A `yaml` block that is a whole recipe (`p3dp: 1`) is written as
//!   `NAME.yaml` and checked: it loads, builds and has no finding at all
//!   (`0 warnings, 0 errors`, no note). One that is a printer profile
//!   (`inherits:` or `flavor:`) is given to `p3dp check` as `--printer`.
//!   Any other is a fragment: it is set in a recipe round it where its shape
//!   says (top-level keys, a part, steps, turtle commands, a solid's
//!   features), which must load (its checks may fail: it is a piece); one
//!   that includes other files is only parsed.
//! - In a `sh` block every line that starts with `p3dp` runs (through `sh`,
//!   the test's binary first on `PATH`) and must succeed; other commands
//!   (`cargo …`) are the project's and are left alone, as is `p3dp watch`,
//!   which serves until stopped (the `watch::` tests run it).
//!
//! Each page runs in a fresh folder of its own, its blocks in order (a
//! recipe written by one block is built by the next), with `recipes/`,
//! `maps/` (copied) and `docs/` (linked) of the repository, so the commands
//! read as they would from the repository's root.

use crate::common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A fenced block: its page, first line, language and text.
struct Block {
    page: String,
    line: usize,
    lang: String,
    text: String,
}

/// The fenced blocks of `page` (a path from the crate root).
fn blocks(page: &str) -> Vec<Block> {
    let page = page.trim_start_matches("./");
    let text = std::fs::read_to_string(root().join(page)).unwrap();
    let mut out = Vec::new();
    let mut open: Option<(usize, String, String)> = None;
    for (k, l) in text.lines().enumerate() {
        let fence = l.trim_start().strip_prefix("```");
        match (&mut open, fence) {
            (None, Some(info)) => open = Some((k + 1, info.trim().to_string(), String::new())),
            (Some(_), Some(_)) => {
                let (line, lang, text) = open.take().unwrap();
                out.push(Block {
                    page: page.to_string(),
                    line,
                    lang,
                    text,
                });
            }
            (Some((_, _, t)), None) => {
                t.push_str(l);
                t.push('\n');
            }
            (None, None) => {}
        }
    }
    assert!(open.is_none(), "{page}: a fence is not closed");
    out
}

/// The pages whose examples run.
fn pages() -> Vec<String> {
    let mut v = vec![
        "README.md".to_string(),
        "docs/recipe.md".to_string(),
        "docs/checks.md".to_string(),
    ];
    let mut guide: Vec<String> = std::fs::read_dir(root().join("docs/guide"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .map(|p| format!("docs/guide/{}", p.file_name().unwrap().to_string_lossy()))
        .collect();
    guide.sort();
    v.extend(guide);
    v
}

/// A fresh folder with the repository's `docs/` linked in and `maps/` and
/// `recipes/` copied (a recipe written there reads `../maps/…`, and a lock
/// written there names `recipes/…`, which must lie inside its project: the
/// folder is marked as one by a `.git` folder).
fn workspace(tag: &str) -> crate::common::Tmp {
    let dir = tmp(&format!("docs-{tag}"));
    std::fs::create_dir_all(dir.join(".git")).unwrap();
    copy_tree(&root().join("maps"), &dir.join("maps"));
    copy_tree(&root().join("recipes"), &dir.join("recipes"));
    std::fs::copy(root().join(".gitignore"), dir.join(".gitignore")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(root().join("docs"), dir.join("docs")).unwrap();
    dir
}

/// The files of `dir` git would call untracked, as the repository's
/// `.gitignore` (copied there) says; `None` without git on the `PATH`.
/// The folder is made a git repository the first time (its `.git` was
/// only a project's mark); nothing is ever added to it.
fn untracked(dir: &Path) -> Option<std::collections::BTreeSet<String>> {
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .current_dir(dir)
            .output()
            .ok()
    };
    if !dir.join(".git/HEAD").is_file() {
        git(&["init", "-q"]).filter(|o| o.status.success())?;
    }
    let o = git(&["status", "--porcelain", "--untracked-files=all"])?;
    assert!(
        o.status.success(),
        "git status: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    Some(
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter_map(|l| l.strip_prefix("?? "))
            .map(str::to_string)
            .collect(),
    )
}

/// Copies the folder `from` to `to`, its subfolders too.
fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_dir() {
            copy_tree(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

/// Runs `line` through `sh` in `dir`, the test's `p3dp` first on `PATH`.
fn shell(dir: &Path, line: &str) -> std::process::Output {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_p3dp"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    Command::new("sh")
        .args(["-c", line])
        .current_dir(dir)
        .env("PATH", path)
        .env_remove("P3DP_BASELINE")
        .output()
        .expect("run sh")
}

/// The commands of a `sh` block: continuation lines joined, comments
/// (after two spaces and `#`, or a whole line) dropped.
fn commands(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    for l in text.lines() {
        let l = match l.find("  #") {
            Some(k) => &l[..k],
            None => l,
        };
        let l = l.trim();
        if l.starts_with('#') {
            continue;
        }
        if let Some(head) = l.strip_suffix('\\') {
            cur.push_str(head);
            cur.push(' ');
            continue;
        }
        cur.push_str(l);
        if !cur.trim().is_empty() {
            out.push(cur.trim().to_string());
        }
        cur.clear();
    }
    out
}

/// Runs every example of `page` in order; returns how many ran. The
/// commands leave no file git would see as new in the repository, run
/// from its root as the pages say: what they write is ignored (a build's
/// G-code or package, the scratch folder `out/`, the reader's `my-*`
/// files; see `.gitignore`); the recipes and profiles this test saves
/// for the reader are the reader's to keep.
fn run_page(page: &str) -> usize {
    let tag = page.replace(['/', '.'], "-");
    let dir = workspace(&tag);
    let before = untracked(&dir);
    let mut saved = std::collections::BTreeSet::new();
    let mut ran = 0;
    for b in blocks(page) {
        let at = format!("{}:{}", b.page, b.line);
        match b.lang.as_str() {
            "yaml" => {
                ran += 1;
                saved.extend(run_yaml(&dir, &at, &b.text));
            }
            "sh" => {
                for c in commands(&b.text) {
                    if !c.starts_with("p3dp ") || c.starts_with("p3dp watch") {
                        continue;
                    }
                    ran += 1;
                    let o = shell(&dir, &c);
                    assert!(
                        o.status.success(),
                        "{at}: `{c}` failed ({:?}):\n{}{}",
                        o.status.code(),
                        String::from_utf8_lossy(&o.stdout),
                        String::from_utf8_lossy(&o.stderr)
                    );
                }
            }
            _ => {}
        }
    }
    match (before, untracked(&dir)) {
        (Some(before), Some(after)) => {
            let new: Vec<&String> = after
                .iter()
                .filter(|f| !before.contains(*f) && !saved.iter().any(|s| f.starts_with(s)))
                .collect();
            assert!(
                new.is_empty(),
                "{page}: its commands leave files git sees as new in the repository: {new:?}; write them to out/ or a name .gitignore ignores"
            );
        }
        _ => eprintln!("note: no git on the PATH: {page}'s files not looked at"),
    }
    let _ = std::fs::remove_dir_all(&dir);
    ran
}

/// A `yaml` block: a recipe checked clean, a printer profile used, or a
/// fragment parsed.
fn run_yaml(dir: &Path, at: &str, text: &str) -> Option<String> {
    let doc: serde_yaml::Value =
        serde_yaml::from_str(text).unwrap_or_else(|e| panic!("{at}: not YAML: {e}\n{text}"));
    let top = |k: &str| doc.as_mapping().is_some_and(|m| m.contains_key(k));
    if top("p3dp") {
        let name = doc["name"]
            .as_str()
            .unwrap_or_else(|| panic!("{at}: no name"));
        let file = format!("{name}.yaml");
        std::fs::write(dir.join(&file), text).unwrap();
        let o = p3dp(dir, &["check", &file]);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success() && out.contains(&format!("{file}: 0 warnings, 0 errors\n")),
            "{at}: the recipe does not check clean:\n{out}{}",
            String::from_utf8_lossy(&o.stderr)
        );
        Some(file)
    } else if top("inherits") || top("flavor") {
        let file = format!("profile-{}.yaml", at.rsplit(':').next().unwrap());
        std::fs::write(dir.join(&file), text).unwrap();
        let o = p3dp(dir, &["check", "recipes/sphere.yaml", "--printer", &file]);
        assert!(
            o.status.success(),
            "{at}: the profile is refused:\n{}",
            String::from_utf8_lossy(&o.stderr)
        );
        Some(file)
    } else if let Some(recipe) = in_a_recipe(&doc) {
        // a fragment, set in a recipe round it: the loader must take its
        // keys and expressions (its checks may fail: it is a piece)
        let sub = dir.join("fragments");
        std::fs::create_dir_all(&sub).unwrap();
        let file = format!("fragment-{}.yaml", at.rsplit(':').next().unwrap());
        let text = serde_yaml::to_string(&recipe).unwrap();
        std::fs::write(sub.join(&file), &text).unwrap();
        let o = p3dp(&sub, &["check", &file]);
        assert!(
            matches!(o.status.code(), Some(0 | 1)),
            "{at}: the fragment does not load in a recipe round it:\n{}\n{text}",
            String::from_utf8_lossy(&o.stderr)
        );
        Some("fragments/".to_string())
    } else {
        None
    }
}

/// The recipe a fragment is shown in: a sphere's helix with the params the
/// pages' fragments use, the fragment set where its shape says (top-level
/// keys, a part, a list of parts, of steps or of turtle commands, a
/// solid's features). None for one that reads other files by relative path
/// (`include:`) or has no place: those are parsed only.
fn in_a_recipe(doc: &serde_yaml::Value) -> Option<serde_yaml::Value> {
    use serde_yaml::Value;
    let mut recipe: Value = serde_yaml::from_str(
        "p3dp: 1\nname: fragment\nparams: {radius: 25, height: \"pi/2*radius\", lift: 0.4, sea: 0.65, thin: 0.65}\nparts:\n  - name: sphere\n    primitive: {helix: {radius: radius, height: height, pitch: 0.2}}\n",
    )
    .unwrap();
    let first_key = |v: &Value| -> Option<String> {
        let m = match v {
            Value::Sequence(s) => s.first()?.as_mapping()?,
            Value::Mapping(m) => m,
            _ => return None,
        };
        m.keys().next()?.as_str().map(str::to_string)
    };
    const STEPS: &[&str] = &[
        "deform_xyz",
        "deform_cylinder",
        "modulate_cylinder",
        "modulate_map",
        "subdivide",
        "translate",
    ];
    const TOP: &[&str] = &[
        "allow",
        "templates",
        "parts",
        "params",
        "defaults",
        "skirt",
        "material",
    ];
    let part = &mut recipe["parts"][0];
    let key = first_key(doc)?;
    match doc {
        Value::Mapping(m) if m.contains_key("include") => return None,
        Value::Mapping(m)
            if m.keys()
                .all(|k| k.as_str().is_some_and(|k| TOP.contains(&k))) =>
        {
            for (k, v) in m {
                recipe[k.as_str()?] = v.clone();
            }
        }
        Value::Mapping(m) if m.contains_key("steps") => part["steps"] = m["steps"].clone(),
        Value::Mapping(m) if m.contains_key("primitive") => {
            part["primitive"] = m["primitive"].clone()
        }
        Value::Mapping(m) if m.contains_key("features") => {
            part["primitive"] =
                serde_yaml::from_str("{solid: {layer_height: 0.2, line_width: 0.45}}").unwrap();
            part["primitive"]["solid"]["features"] = m["features"].clone();
            part["cross_section"] = Value::from(0.09);
        }
        Value::Sequence(_) if STEPS.contains(&key.as_str()) => part["steps"] = doc.clone(),
        Value::Sequence(s) if key == "name" || key == "primitive" => {
            recipe["parts"] = Value::Sequence(s.clone())
        }
        Value::Sequence(_) => {
            part["primitive"] =
                serde_yaml::from_str("{turtle: {start: {position: [0, 0, 0.2]}}}").unwrap();
            part["primitive"]["turtle"]["program"] = doc.clone();
        }
        _ => return None,
    }
    Some(recipe)
}

#[test]
fn every_fence_says_its_language() {
    let mut all = pages();
    for dir in ["docs", "."] {
        for e in std::fs::read_dir(root().join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|e| e == "md") {
                let rel = p
                    .strip_prefix(root())
                    .unwrap()
                    .to_string_lossy()
                    .into_owned();
                if !all.contains(&rel) {
                    all.push(rel);
                }
            }
        }
    }
    assert!(all.iter().any(|p| p == "SECURITY.md"), "{all:?}");
    for page in all {
        for b in blocks(&page) {
            assert!(
                !b.lang.is_empty(),
                "{}:{}: a fenced block without a language: `sh` and `yaml` run, `text` is shown",
                b.page,
                b.line
            );
        }
    }
}

#[test]
fn the_readme_is_short_and_its_examples_run() {
    let lines = std::fs::read_to_string(root().join("README.md"))
        .unwrap()
        .lines()
        .count();
    assert!(lines <= 300, "README.md has {lines} lines; at most 300");
    assert!(run_page("README.md") >= 6);
}

#[test]
fn the_recipe_reference_examples_run() {
    assert!(run_page("docs/recipe.md") >= 2);
}

#[test]
fn the_checks_page_examples_run() {
    assert!(run_page("docs/checks.md") >= 1);
}

#[test]
fn the_guide_examples_run() {
    let guide: Vec<String> = pages()
        .into_iter()
        .filter(|p| p.starts_with("docs/guide/"))
        .collect();
    assert!(guide.len() >= 11, "{guide:?}");
    // the chapters side by side: each in its own folder
    let ran: Vec<usize> = std::thread::scope(|s| {
        let hs: Vec<_> = guide.iter().map(|p| s.spawn(move || run_page(p))).collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (p, n) in guide.iter().zip(&ran) {
        if !p.ends_with("README.md") {
            assert!(*n >= 2, "{p}: only {n} examples");
        }
    }
}

#[test]
fn the_guide_recipes_build_clean_and_have_pictures() {
    let dir = root().join("docs/guide");
    let mut recipes = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_none_or(|e| e != "yaml") {
            continue;
        }
        let text = std::fs::read_to_string(&p).unwrap();
        if !text.contains("\np3dp: 1\n") {
            continue; // a printer profile
        }
        recipes += 1;
        let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
        assert!(
            dir.join(format!("{stem}.png")).is_file(),
            "no picture of {stem}"
        );
        let o = p3dp(&dir, &["check", &format!("{stem}.yaml")]);
        assert!(
            String::from_utf8_lossy(&o.stdout).contains("0 warnings, 0 errors\n"),
            "{stem}: {}",
            String::from_utf8_lossy(&o.stdout)
        );
        // its chapter shows it as it is, comments aside
        let body: String = text
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| format!("{l}\n"))
            .collect();
        let shown = pages()
            .iter()
            .filter(|p| p.starts_with("docs/guide/"))
            .flat_map(|p| blocks(p))
            .any(|b| b.text == body);
        assert!(shown, "{stem}.yaml is not shown whole in a chapter");
    }
    assert!(recipes >= 4);
}

/// The guide has its plates chapter (issue 41): listed in the guide's
/// contents, with a plate file the tests save and build, the same plate
/// by `p3dp plate`, and a package of a plate; its examples run with the
/// guide's (`the_guide_examples_run`).
#[test]
fn the_guide_has_a_plates_chapter() {
    let page = "docs/guide/11-plates.md";
    let contents = std::fs::read_to_string(root().join("docs/guide/README.md")).unwrap();
    assert!(contents.contains("[Plates](11-plates.md)"), "{contents}");
    let blocks = blocks(page);
    let plate_file = blocks.iter().find(|b| {
        b.lang == "yaml"
            && serde_yaml::from_str::<serde_yaml::Value>(&b.text)
                .is_ok_and(|d| d["p3dp"].is_number() && d["plate"].is_sequence())
    });
    assert!(plate_file.is_some(), "{page}: no plate file");
    let commands: Vec<String> = blocks
        .iter()
        .filter(|b| b.lang == "sh")
        .flat_map(|b| commands(&b.text))
        .collect();
    for wanted in ["p3dp plate ", ".gcode.3mf"] {
        assert!(
            commands.iter().any(|c| c.contains(wanted)),
            "{page}: no command with `{wanted}`: {commands:?}"
        );
    }
}
