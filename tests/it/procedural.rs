//! Procedural recipes (issue 15) through the real binary: templates, loops,
//! groups and includes expand to the same moves as the recipe written out by
//! hand, and an include's errors name both files. What expansion resolves
//! to, part by part, is checked in `internals::procedural`.

use crate::common;

use std::path::{Path, PathBuf};

use crate::common::{p3dp, recipe, root, tmp};

pub(crate) fn fixture(name: &str) -> PathBuf {
    root().join("tests/fixtures/procedural").join(name)
}

/// Builds `path` (with `--force`: only the moves matter here) and returns the
/// G-code text.
fn gcode(path: &Path, dir: &Path, out: &str) -> String {
    let o = p3dp(
        dir,
        &["build", path.to_str().unwrap(), "-o", out, "--force"],
    );
    assert!(
        o.status.success(),
        "{}: {}",
        path.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::read_to_string(dir.join(out)).unwrap()
}

/// The G-code's commands without comments (the part names, stats, thumbnails).
fn commands(text: &str) -> Vec<&str> {
    text.lines()
        .map(|l| l.split(';').next().unwrap().trim_end())
        .filter(|l| !l.is_empty())
        .collect()
}

#[test]
fn expansion_is_pure_templates_loops_groups_and_includes_give_the_flat_moves() {
    let dir = tmp("procedural-pure");
    for name in ["nested-loops", "template-in-group", "include"] {
        let a = gcode(&fixture(&format!("{name}.yaml")), &dir, "a.gcode");
        let b = gcode(&fixture(&format!("{name}-flat.yaml")), &dir, "b.gcode");
        let (ca, cb) = (commands(&a), commands(&b));
        assert!(ca.len() > 1000, "{name}: {} commands", ca.len());
        assert_eq!(ca.len(), cb.len(), "{name}");
        if let Some(k) = (0..ca.len()).find(|&k| ca[k] != cb[k]) {
            panic!("{name}: command {k} differs: `{}` vs `{}`", ca[k], cb[k]);
        }
        // and the parts are named as the flat recipe names them
        let parts =
            |t: &str| -> Vec<String> { common::parse(t).parts.into_iter().skip(1).collect() };
        assert_eq!(parts(&a), parts(&b), "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn olympic_rings_with_templates_are_byte_identical_to_the_hand_written_pieces() {
    let dir = tmp("procedural-olympic");
    let a = gcode(&recipe("olympic-rings.yaml"), &dir, "a.gcode");
    let b = gcode(
        &root().join("tests/fixtures/olympic-rings-flat.yaml"),
        &dir,
        "b.gcode",
    );
    assert!(a == b, "the G-code differs");
    let text = std::fs::read_to_string(recipe("olympic-rings.yaml")).unwrap();
    let flat =
        std::fs::read_to_string(root().join("tests/fixtures/olympic-rings-flat.yaml")).unwrap();
    assert!(2 * text.lines().count() < flat.lines().count() - 4);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn include_errors_name_both_files_and_the_missing_one() {
    let dir = tmp("procedural-include");
    std::fs::create_dir_all(dir.join("lib")).unwrap();
    std::fs::write(
        dir.join("lib/a.yaml"),
        "p3dp: 1\nparams: {size: 4}\ntemplates:\n  dot:\n    part: {primitive: {circle: {radius: size, center: [0, 0, 0.2]}}}\n",
    )
    .unwrap();
    let main = |extra: &str| {
        format!("p3dp: 1\nname: m\ninclude: [lib/a.yaml]\n{extra}parts:\n  - {{template: dot}}\n")
    };
    let run = |text: &str| {
        std::fs::write(dir.join("m.yaml"), text).unwrap();
        let o = p3dp(&dir, &["build", "m.yaml", "-o", "m.gcode"]);
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    // the library's param and template, and --set reaches the param
    let (code, err) = run(&main(""));
    assert_eq!(code, Some(0), "{err}");
    let o = p3dp(
        &dir,
        &["build", "m.yaml", "-o", "m.gcode", "--set", "size=6"],
    );
    assert!(o.status.success());
    let g = common::parse(&std::fs::read_to_string(dir.join("m.gcode")).unwrap());
    let far = g
        .moves
        .iter()
        .filter(|m| m.de > 0.0)
        .map(|m| (m.to[0] - 110.0).hypot(m.to[1] - 110.0))
        .fold(0.0, f64::max);
    assert!((far - 6.0).abs() < 1e-3, "{far}");
    let (code, err) = run(&main("params: {size: 5}\n"));
    assert_eq!(code, Some(2));
    assert!(
        err.contains("m.yaml: params.size: the param `size` is also defined in lib/a.yaml"),
        "{err}"
    );
    let (code, err) = run(&main(
        "templates:\n  dot: {part: {primitive: {circle: {radius: 1}}}}\n",
    ));
    assert_eq!(code, Some(2));
    assert!(
        err.contains("templates.dot: the template `dot` is also defined in lib/a.yaml"),
        "{err}"
    );
    let (code, err) = run(&main("").replace("lib/a.yaml", "lib/nope.yaml"));
    assert_eq!(code, Some(2));
    assert!(
        err.contains("m.yaml: include[0]: cannot read the included file `lib/nope.yaml`"),
        "{err}"
    );
    std::fs::write(dir.join("lib/a.yaml"), "p3dp: 1\nparams: {size: \"2*q\"}\n").unwrap();
    let (code, err) = run(&main(""));
    assert_eq!(code, Some(2));
    assert!(
        err.contains("lib/a.yaml: params.size: unknown name `q`"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
