//! Snapshots of rendered errors for the mistakes people make: each shows the
//! first line as ever (`error: FILE:LINE:COL: PATH: message`), the source line
//! with the place underlined, and a `help:` line where one is known.
//!
//! The expected texts are `tests/snapshots/errors/NAME.txt` (plain: standard
//! error is a pipe here). `UPDATE_SNAPSHOTS=1 cargo test --test it
//! error_snapshots::` rewrites them; review the diff before committing.

use crate::common::*;
use std::path::Path;

/// The recipes of the mistakes that are not in `tests/bad/`: (file, text).
const WRITTEN: &[(&str, &str)] = &[
    ("empty.yaml", ""),
    (
        "indent.yaml",
        "p3dp: 1\nname: t\nparts:\n  - primitive:\n      helix: { radius: 10, height: 2, pitch: 0.5 }\n    steps:\n      - deform_xyz:\n          position: [x, y, z]\n        speed: 3\n",
    ),
    (
        "string-for-number.yaml",
        "p3dp: 1\nname: t\nparts:\n  - primitive:\n      helix: { radius: 10 mm, height: 2, pitch: 0.5 }\n",
    ),
    (
        "misspelt-param.yaml",
        "p3dp: 1\nname: t\nparams:\n  radius: 10\nparts:\n  - primitive:\n      helix: { radius: radus, height: 2, pitch: 0.5 }\n",
    ),
];

/// (snapshot name, arguments of `p3dp`, run in `tests/` or in the scratch folder).
const CASES: &[(&str, &[&str], bool)] = &[
    (
        "misspelt-key",
        &["check", "bad/unknown-primitive-key.yaml"],
        true,
    ),
    (
        "unknown-top-key",
        &["check", "bad/unknown-top-key.yaml"],
        true,
    ),
    ("wrong-indentation", &["check", "indent.yaml"], false),
    ("tab", &["check", "bad/yaml-tab.yaml"], true),
    ("empty-file", &["check", "empty.yaml"], false),
    ("expression-typo", &["check", "bad/expr-syntax.yaml"], true),
    (
        "unknown-variable",
        &["check", "bad/expr-unknown-var.yaml"],
        true,
    ),
    ("misspelt-param", &["check", "misspelt-param.yaml"], false),
    (
        "unknown-function",
        &["check", "bad/expr-unknown-function.yaml"],
        true,
    ),
    (
        "string-for-number",
        &["check", "string-for-number.yaml"],
        false,
    ),
    (
        "list-for-number",
        &["check", "bad/list-for-number.yaml"],
        true,
    ),
    (
        "sweep-range-backwards",
        &["build", "bad/out-of-bed.yaml", "--sweep", "ripples=3..1"],
        true,
    ),
    ("missing-image", &["check", "bad/image-missing.yaml"], true),
    (
        "out-of-bed",
        &["build", "bad/out-of-bed.yaml", "-o", "-"],
        true,
    ),
];

#[test]
fn rendered_errors_match_their_snapshots() {
    let scratch = tmp("error-snapshots");
    for (file, text) in WRITTEN {
        std::fs::write(scratch.join(file), text).unwrap();
    }
    let tests = root().join("tests");
    let dir = tests.join("snapshots").join("errors");
    let update = std::env::var_os("UPDATE_SNAPSHOTS").is_some();
    let mut failed = Vec::new();
    for (name, args, in_tests) in CASES {
        let cwd: &Path = if *in_tests { &tests } else { &scratch };
        let out = p3dp(cwd, args);
        assert!(!out.status.success(), "{name}: expected a failure");
        let got = String::from_utf8(out.stderr).unwrap();
        assert!(!got.contains('\u{1b}'), "{name}: colour on a pipe:\n{got}");
        let file = dir.join(format!("{name}.txt"));
        if update {
            std::fs::write(&file, &got).unwrap();
            continue;
        }
        let want = std::fs::read_to_string(&file).unwrap_or_default();
        if got != want {
            failed.push(format!(
                "--- {name} (tests/snapshots/errors/{name}.txt) ---\nwant:\n{want}\ngot:\n{got}"
            ));
        }
        // every snapshot shows a source line (a `|` gutter) or a help
        assert!(
            got.contains(" | ") || got.contains("help: "),
            "{name}: neither a source line nor a help:\n{got}"
        );
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn no_color_and_pipes_stay_plain() {
    // NO_COLOR set: plain even if it were a terminal (here it is a pipe)
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_p3dp"))
        .args(["check", "bad/unknown-primitive-key.yaml"])
        .current_dir(root().join("tests"))
        .env("NO_COLOR", "1")
        .output()
        .unwrap();
    let e = String::from_utf8(out.stderr).unwrap();
    assert!(
        e.starts_with("error: bad/unknown-primitive-key.yaml:9:16: "),
        "{e}"
    );
    assert!(!e.contains('\u{1b}'), "{e}");
    assert!(e.contains("help: did you mean `radius`?"), "{e}");
}
