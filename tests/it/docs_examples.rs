//! Every example of the README, the guide and the recipe reference runs:
//! the fenced blocks of those pages are read and executed, so a wrong word
//! about a command or a key fails the tests.
//!
//! - Every fenced block carries a language: `sh` and `yaml` blocks run,
//!   `text` (output, error messages) and others are shown only.
//! - A `yaml` block that is a whole recipe (`p3dp: 1`) is written as
//!   `NAME.yaml` and checked: it loads, builds and has no finding at all
//!   (`0 warnings, 0 errors`, no note). One that is a printer profile
//!   (`inherits:` or `flavor:`) is given to `p3dp check` as `--printer`.
//!   Any other is a fragment: it must be valid YAML.
//! - In a `sh` block every line that starts with `p3dp` runs (through `sh`,
//!   the test's binary first on `PATH`) and must succeed; other commands
//!   (`cargo …`) are the project's and are left alone, as is `p3dp watch`,
//!   which serves until stopped (the `watch::` tests run it).
//!
//! Each page runs in a fresh folder of its own, its blocks in order (a
//! recipe written by one block is built by the next), with `recipes/`,
//! `maps/` and `docs/` of the repository linked in, so the commands read
//! as they would from the repository's root.

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
    let mut v = vec!["README.md".to_string(), "docs/recipe.md".to_string()];
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

/// A fresh folder with the repository's `recipes/`, `maps/` and `docs/`
/// linked in.
fn workspace(tag: &str) -> PathBuf {
    let dir = tmp(&format!("docs-{tag}"));
    for d in ["recipes", "maps", "docs"] {
        #[cfg(unix)]
        std::os::unix::fs::symlink(root().join(d), dir.join(d)).unwrap();
        #[cfg(not(unix))]
        let _ = d;
    }
    dir
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

/// Runs every example of `page` in order; returns how many ran.
fn run_page(page: &str) -> usize {
    let tag = page.replace(['/', '.'], "-");
    let dir = workspace(&tag);
    let mut ran = 0;
    for b in blocks(page) {
        let at = format!("{}:{}", b.page, b.line);
        match b.lang.as_str() {
            "yaml" => {
                ran += 1;
                run_yaml(&dir, &at, &b.text);
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
    let _ = std::fs::remove_dir_all(&dir);
    ran
}

/// A `yaml` block: a recipe checked clean, a printer profile used, or a
/// fragment parsed.
fn run_yaml(dir: &Path, at: &str, text: &str) {
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
    } else if top("inherits") || top("flavor") {
        let file = format!("profile-{}.yaml", at.rsplit(':').next().unwrap());
        std::fs::write(dir.join(&file), text).unwrap();
        let o = p3dp(dir, &["check", "recipes/sphere.yaml", "--printer", &file]);
        assert!(
            o.status.success(),
            "{at}: the profile is refused:\n{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
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
