//! Hostile input (issue 17): no G-code injection, no clobbered files, no
//! panics, bounded machines. Each test runs the real binary.

mod common;

use std::path::{Path, PathBuf};

use common::*;

fn code(out: &std::process::Output) -> Option<i32> {
    out.status.code()
}

fn describe(out: &std::process::Output) -> String {
    format!(
        "status {:?}\n--- stderr ---\n{}\n--- stdout ---\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr),
        String::from_utf8_lossy(&out.stdout)
    )
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A YAML double-quoted string holding `s` exactly (control characters escaped).
fn yaml_str(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() || c == '\u{2028}' || c == '\u{2029}' => {
                out.push_str(&format!("\\U{:08X}", c as u32))
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A two-part recipe whose recipe, part and material names are `name`, on a
/// profile (written beside it) named `name` too.
fn named_recipe(dir: &Path, file: &str, name: &str) -> PathBuf {
    let q = yaml_str(name);
    let profile = dir.join(format!("{file}.printer.yaml"));
    std::fs::write(&profile, format!("inherits: generic-220\nname: {q}\n")).unwrap();
    let text = format!(
        "p3dp: 1\nname: {q}\ndescription: {q}\nprinter: {}\nmaterial: {{name: {q}, density: 1.24, nozzle_temp: 210, bed_temp: 60}}\nparts:\n  - name: {q}\n    primitive: {{helix: {{radius: 10, height: 2, pitch: 0.5}}}}\n  - name: {q}\n    primitive: {{helix: {{radius: 4, height: 2, pitch: 0.5}}}}\n",
        profile.file_name().unwrap().to_str().unwrap()
    );
    let p = dir.join(file);
    std::fs::write(&p, text).unwrap();
    p
}

/// The lines of G-code that are not comments.
fn commands(text: &str) -> Vec<&str> {
    text.split('\n')
        .filter(|l| !l.trim_start().starts_with(';'))
        .collect()
}

#[test]
fn hostile_names_never_make_a_gcode_line() {
    let dir = tmp("hostile-names");
    let base = named_recipe(&dir, "plain.yaml", "plain");
    let out = p3dp(
        &dir,
        &[
            "build",
            base.to_str().unwrap(),
            "-o",
            "plain.gcode",
            "--force",
        ],
    );
    assert_eq!(code(&out), Some(0), "{}", describe(&out));
    let plain = std::fs::read_to_string(dir.join("plain.gcode")).unwrap();
    let want = commands(&plain);
    // text that is refused: every control character and line separator
    let refused = [
        "x\nM109 S450",
        "x\rM109 S450",
        "x\r\nM109 S450",
        "\nG28",
        "x\u{0b}M104 S450",
        "x\u{0c}M104 S450",
        "x\u{85}M104 S450",
        "x\u{2028}M104 S450",
        "x\u{2029}M104 S450",
        "x\u{0}M104",
        "x\u{1b}[2J",
        "tab\there",
        "x\u{7f}",
    ];
    for (k, name) in refused.iter().enumerate() {
        let r = named_recipe(&dir, &format!("refused-{k}.yaml"), name);
        let o = format!("refused-{k}.gcode");
        let out = p3dp(&dir, &["build", r.to_str().unwrap(), "-o", &o, "--force"]);
        assert_eq!(code(&out), Some(2), "{name:?}: {}", describe(&out));
        let e = stderr(&out);
        assert!(
            e.contains("name: contains") || e.contains("description: contains"),
            "{name:?}: {e}"
        );
        assert!(!dir.join(&o).exists(), "{name:?}: a file was written");
    }
    // text that is accepted: it stays inside its comment
    let accepted = [
        "; M109 S450",
        "M109 S450",
        "x ; G28",
        "%",
        "(M104 S450)",
        "N10 G28*42",
        "\\nM109 S450 (a backslash and an n)",
        "ünïcode 🔥 名前",
        "{nozzle_temp}",
        "\u{200b}zero\u{feff}width",
    ];
    for (k, name) in accepted.iter().enumerate() {
        let r = named_recipe(&dir, &format!("accepted-{k}.yaml"), name);
        let o = format!("accepted-{k}.gcode");
        let out = p3dp(&dir, &["build", r.to_str().unwrap(), "-o", &o, "--force"]);
        assert_eq!(code(&out), Some(0), "{name:?}: {}", describe(&out));
        let text = std::fs::read_to_string(dir.join(&o)).unwrap();
        assert!(
            !text.contains('\r'),
            "{name:?}: a carriage return was written"
        );
        assert_eq!(
            commands(&text),
            want,
            "{name:?}: the name changed a line that is not a comment"
        );
        assert!(
            text.contains(name),
            "{name:?} is not in the G-code comments"
        );
    }
}

#[test]
fn printer_name_with_a_line_break_is_refused_naming_the_profile() {
    let dir = tmp("hostile-printer-name");
    let profile = root().join("tests/fixtures/printers/hostile-name.yaml");
    let out = p3dp(
        &dir,
        &[
            "build",
            recipe("vase.yaml").to_str().unwrap(),
            "--printer",
            profile.to_str().unwrap(),
            "-o",
            "v.gcode",
        ],
    );
    assert_eq!(code(&out), Some(2), "{}", describe(&out));
    let e = stderr(&out);
    assert!(
        e.contains("hostile-name.yaml: name: contains a line break"),
        "{e}"
    );
    assert!(!dir.join("v.gcode").exists());
}
