//! The authoring loop: plain-worded errors for a newcomer's mistakes.

mod common;

use common::*;
use std::path::Path;
use std::process::Output;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
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
fn a_sweep_range_without_a_step_asks_for_one() {
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
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("--sweep cycles=3..5"), "{e}");
    assert!(e.contains("a range needs a step"), "{e}");
    assert!(e.contains("cycles=3..5:1"), "{e}");
    assert!(!e.contains("--set"), "{e}");
    assert!(!dir.join("out").exists());
}
