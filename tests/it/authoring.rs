//! The authoring loop: plain-worded errors for a newcomer's mistakes, starter
//! recipes that build, shell completions and the manual page.

use crate::common::*;
use std::path::Path;
use std::process::Output;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Writes `text` as `name` in `dir` and runs `p3dp check` on it.
fn check_text(dir: &Path, name: &str, text: &str) -> Output {
    std::fs::write(dir.join(name), text).unwrap();
    p3dp(dir, &["check", name])
}

#[test]
fn an_empty_file_says_it_is_empty() {
    let dir = tmp("authoring-empty");
    for (name, text) in [("empty.yaml", ""), ("blank.yaml", "\n  \n")] {
        let o = check_text(&dir, name, text);
        assert_eq!(o.status.code(), Some(2));
        let e = stderr(&o);
        assert!(
            e.contains(&format!("error: {name}: the file is empty")),
            "{e}"
        );
        assert!(!e.contains("missing field"), "{e}");
    }
    let o = check_text(&dir, "comments.yaml", "# nothing yet\n");
    let e = stderr(&o);
    assert!(e.contains("the file has only comments"), "{e}");
}

#[test]
fn a_tab_is_called_a_tab() {
    let dir = tmp("authoring-tab");
    let o = check_text(
        &dir,
        "tab.yaml",
        "p3dp: 1\nname: t\nparts:\n  - name: wall\n\tprimitive:\n      helix: { radius: 10, height: 2, pitch: 0.5 }\n",
    );
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("tab.yaml:5:"), "{e}");
    assert!(e.contains("a tab"), "{e}");
    assert!(e.contains("use spaces"), "{e}");
}

#[test]
fn wrong_indentation_names_the_extra_key() {
    let dir = tmp("authoring-indent");
    let o = check_text(
        &dir,
        "indent.yaml",
        "p3dp: 1\nname: t\nparts:\n  - name: wall\n    primitive:\n      helix:\n        radius: 10\n        height: 2\n      pitch: 0.5\n",
    );
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("`pitch`"), "{e}");
    assert!(e.contains("`helix`"), "{e}");
    assert!(e.contains("indent"), "{e}");
    assert!(!e.contains("expected map with a single key"), "{e}");
    let o = check_text(
        &dir,
        "indent-step.yaml",
        "p3dp: 1\nname: t\nparts:\n  - primitive:\n      helix: { radius: 10, height: 2, pitch: 0.5 }\n    steps:\n      - deform_xyz:\n          position: [x, y, z]\n        speed: 3\n",
    );
    let e = stderr(&o);
    assert!(e.contains("`speed`"), "{e}");
    assert!(e.contains("`deform_xyz`"), "{e}");
    assert!(e.contains("indent-step.yaml:9:"), "{e}");
}

#[test]
fn a_sweep_range_without_a_step_steps_by_one_as_for_does() {
    let dir = tmp("authoring-sweep");
    let plate = recipe("plate.yaml");
    let o = p3dp(
        &dir,
        &[
            "build",
            plate.to_str().unwrap(),
            "--sweep",
            "cycles=3..5",
            "-o",
            "out/",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let mut names: Vec<String> = std::fs::read_dir(dir.join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".gcode"))
        .collect();
    names.sort();
    assert_eq!(names.len(), 3, "{names:?}");
    for c in ["3", "4", "5"] {
        assert!(
            names.iter().any(|n| n.contains(&format!("cycles-{c}"))),
            "{names:?}"
        );
    }
}

#[test]
fn every_starter_builds_clean_on_the_default_printer() {
    let dir = tmp("authoring-new");
    let kinds: Vec<&str> = p3dp::testing::STARTERS.iter().map(|(k, _)| *k).collect();
    assert!(kinds.len() >= 5, "{kinds:?}");
    for kind in kinds {
        let name = format!("my-{kind}");
        let o = p3dp(&dir, &["new", &name, "--from", kind]);
        assert!(o.status.success(), "new --from {kind}: {}", stderr(&o));
        let file = format!("{name}.yaml");
        let text = std::fs::read_to_string(dir.join(&file)).unwrap();
        assert!(text.contains(&format!("name: {name}")), "{text}");
        assert!(!text.contains("__NAME__"), "{text}");
        assert!(
            text.lines().filter(|l| l.contains('#')).count() > 5,
            "commented"
        );
        let c = p3dp(&dir, &["check", &file]);
        assert!(
            c.status.success(),
            "check {file}: {}{}",
            stdout(&c),
            stderr(&c)
        );
        // a newcomer's first build shows no warning (and no note)
        assert!(
            stdout(&c).contains(&format!("{file}: 0 warnings, 0 errors\n")),
            "check {file}: {}",
            stdout(&c)
        );
        let b = p3dp(&dir, &["build", &file]);
        assert!(b.status.success(), "build {file}: {}", stderr(&b));
        assert!(dir.join(format!("{name}.gcode")).is_file());
    }
    // never over an existing file
    let o = p3dp(&dir, &["new", "my-sphere"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("already exists"), "{}", stderr(&o));
    // an unknown kind is refused by the argument parser, naming the kinds
    let o = p3dp(&dir, &["new", "x", "--from", "cube"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("turtle"), "{}", stderr(&o));
}

#[test]
fn completions_and_the_manual_name_the_subcommands() {
    let dir = tmp("authoring-completions");
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let o = p3dp(&dir, &["completions", shell]);
        assert!(o.status.success(), "{shell}: {}", stderr(&o));
        let text = stdout(&o);
        for sub in [
            "build",
            "check",
            "hash",
            "preview",
            "mesh",
            "watch",
            "new",
            "explain",
            "completions",
        ] {
            assert!(text.contains(sub), "{shell} completions lack {sub}");
        }
    }
    let o = p3dp(&dir, &["man"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let man = stdout(&o);
    assert!(man.starts_with(".ie") || man.contains(".TH"), "{man}");
    for sub in [
        "build", "check", "hash", "preview", "mesh", "watch", "new", "man",
    ] {
        assert!(man.contains(sub), "the manual lacks {sub}");
    }
}
