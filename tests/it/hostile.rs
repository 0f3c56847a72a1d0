//! Hostile input (issue 17): no G-code injection, no clobbered files, no
//! panics, bounded machines. Each test runs the real binary.

use std::path::{Path, PathBuf};

use crate::common::*;

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
        // a start_gcode placeholder's braces: filled in no name (a part's
        // name may hold `{EXPR}` over the params, so the expression here is one)
        "{pi}",
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

// ---------------------------------------------------------------------------
// Defect 2: special files as targets; a closed pipe.

#[cfg(unix)]
fn file_type(p: &Path) -> std::fs::FileType {
    std::fs::symlink_metadata(p).unwrap().file_type()
}

#[cfg(unix)]
fn is_root() -> bool {
    std::process::Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

#[cfg(unix)]
#[test]
fn a_fifo_a_symlink_and_a_device_stay_what_they_are() {
    use std::os::unix::fs::FileTypeExt;
    use std::sync::mpsc;
    use std::time::Duration;
    let dir = tmp("special-targets");
    let r = recipe("sphere.yaml");
    let r = r.to_str().unwrap();

    // a FIFO: written to directly, a reader gets the G-code
    let fifo = dir.join("pipe.gcode");
    let st = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(st.success());
    let (tx, rx) = mpsc::channel();
    let reader = fifo.clone();
    std::thread::spawn(move || {
        let _ = tx.send(std::fs::read(reader));
    });
    let out = p3dp(&dir, &["build", r, "-o", "pipe.gcode"]);
    assert_eq!(code(&out), Some(0), "{}", describe(&out));
    assert!(file_type(&fifo).is_fifo(), "the FIFO was replaced");
    let got = rx
        .recv_timeout(Duration::from_secs(20))
        .expect("the FIFO's reader got nothing")
        .unwrap();
    assert!(String::from_utf8_lossy(&got).contains("; generated by p3dp"));

    // a symlink: its target is replaced, the link stays a link
    std::fs::create_dir_all(dir.join("real")).unwrap();
    std::fs::write(dir.join("real/target.gcode"), "old").unwrap();
    std::os::unix::fs::symlink("real/target.gcode", dir.join("link.gcode")).unwrap();
    std::os::unix::fs::symlink("real/new.json", dir.join("dangling.json")).unwrap();
    let out = p3dp(
        &dir,
        &[
            "build",
            r,
            "-o",
            "link.gcode",
            "--stats-json",
            "dangling.json",
        ],
    );
    assert_eq!(code(&out), Some(0), "{}", describe(&out));
    assert!(file_type(&dir.join("link.gcode")).is_symlink());
    assert!(file_type(&dir.join("dangling.json")).is_symlink());
    let text = std::fs::read_to_string(dir.join("real/target.gcode")).unwrap();
    assert!(text.starts_with("; generated by p3dp"), "{text}");
    assert!(std::fs::read_to_string(dir.join("real/new.json"))
        .unwrap()
        .contains("gcode_sha256"));

    // a folder as a file is refused
    std::fs::create_dir_all(dir.join("folder.json")).unwrap();
    let out = p3dp(
        &dir,
        &["build", r, "-o", "x.gcode", "--stats-json", "folder.json"],
    );
    assert_eq!(code(&out), Some(2), "{}", describe(&out));
    assert!(stderr(&out).contains("folder.json"), "{}", describe(&out));
    assert!(!dir.join("x.gcode").exists());

    // a character device (made with mknod as root): written to, not replaced
    if is_root() {
        let null = dir.join("null");
        let st = std::process::Command::new("mknod")
            .args([null.to_str().unwrap(), "c", "1", "3"])
            .status()
            .unwrap();
        if st.success() {
            let out = p3dp(&dir, &["build", r, "-o", "null", "--stats-json", "null"]);
            assert_eq!(code(&out), Some(0), "{}", describe(&out));
            assert!(file_type(&null).is_char_device(), "the device was replaced");
        }
    }
    let temps: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(".p3dp-"))
        .collect();
    assert!(temps.is_empty(), "temp files left: {temps:?}");
}

#[test]
fn standard_output_closed_early_ends_quietly() {
    use std::io::BufRead;
    let dir = tmp("closed-pipe");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_p3dp"))
        .args(["build", recipe("vase.yaml").to_str().unwrap(), "-o", "-"])
        .current_dir(&dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.starts_with("; generated by p3dp"), "{first}");
    // the reader goes away, like `| head -1`
    let out = child.wait_with_output().unwrap();
    assert_eq!(code(&out), Some(0), "{}", describe(&out));
    assert!(stderr(&out).is_empty(), "{}", describe(&out));
}

#[test]
fn reports_into_a_closed_pipe_end_quietly() {
    // `p3dp check r.yaml | true`: println! panicked with exit 101
    let dir = tmp("closed-report");
    let globe = recipe("globe.yaml");
    let out_file = dir.join("g.gcode");
    let cases: Vec<Vec<&str>> = vec![
        vec!["check", globe.to_str().unwrap()],
        vec![
            "build",
            globe.to_str().unwrap(),
            "-o",
            out_file.to_str().unwrap(),
        ],
        vec!["printers"],
        vec!["schema"],
        vec!["completions", "bash"],
        vec!["hash", globe.to_str().unwrap()],
    ];
    for args in cases {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_p3dp"))
            .args(&args)
            .current_dir(&dir)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // the reader is gone before the command writes a byte
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        assert!(
            matches!(code(&out), Some(0 | 1)),
            "{args:?}: {}",
            describe(&out)
        );
        assert!(
            !stderr(&out).contains("panicked"),
            "{args:?}: {}",
            describe(&out)
        );
    }
}

// ---------------------------------------------------------------------------
// Defects 5 and 7: outputs over each other or over inputs; all or nothing;
// temp files of a stopped run.

/// Names of the entries of `dir`, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn two_outputs_that_are_one_file_are_refused_before_writing() {
    let dir = tmp("same-output");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink("out.gcode", dir.join("alias.json")).unwrap();
    let r = recipe("sphere.yaml");
    let r = r.to_str().unwrap();
    let mut cases = vec![
        vec!["--stats-json", "out.gcode", "-o", "out.gcode"],
        vec!["-o", "out.gcode", "--stats-json", "sub/../out.gcode"],
        vec![
            "-o",
            "out.gcode",
            "--preview",
            "./out.gcode.png",
            "--stats-json",
            "out.gcode.png",
        ],
    ];
    #[cfg(unix)]
    cases.push(vec!["-o", "out.gcode", "--stats-json", "alias.json"]);
    for args in cases {
        let mut full = vec!["build", r];
        full.extend(&args);
        let out = p3dp(&dir, &full);
        assert_eq!(code(&out), Some(2), "{args:?}: {}", describe(&out));
        assert!(
            stderr(&out).contains("expected a different file for each output"),
            "{args:?}: {}",
            describe(&out)
        );
        let mut left = entries(&dir);
        left.retain(|e| e != "sub" && e != "alias.json");
        assert!(left.is_empty(), "{args:?}: wrote {left:?}");
    }
}

#[test]
fn no_output_may_be_an_input() {
    let dir = tmp("output-is-input");
    let text = std::fs::read_to_string(recipe("sphere.yaml")).unwrap();
    std::fs::write(dir.join("r.yaml"), &text).unwrap();
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let cases: [&[&str]; 5] = [
        &["build", "r.yaml", "-o", "r.yaml"],
        &["build", "r.yaml", "--stats-json", "sub/../r.yaml"],
        &["hash", "r.yaml", "--lock", "r.yaml"],
        &["build", "r.yaml", "--printer", "p.yaml", "-o", "p.yaml"],
        &[
            "hash",
            "r.yaml",
            "--printer",
            "./p.yaml",
            "--lock",
            "p.yaml",
        ],
    ];
    std::fs::write(dir.join("p.yaml"), "inherits: generic-220\n").unwrap();
    for args in cases {
        let out = p3dp(&dir, args);
        assert_eq!(code(&out), Some(2), "{args:?}: {}", describe(&out));
        assert!(
            stderr(&out).contains("which this command reads"),
            "{args:?}: {}",
            describe(&out)
        );
        assert_eq!(std::fs::read_to_string(dir.join("r.yaml")).unwrap(), text);
        assert_eq!(
            std::fs::read_to_string(dir.join("p.yaml")).unwrap(),
            "inherits: generic-220\n"
        );
    }
}

#[test]
fn a_failing_preview_or_pattern_leaves_no_gcode() {
    let dir = tmp("all-or-nothing");
    // a folder where the preview goes: the preview cannot be written
    std::fs::create_dir_all(dir.join("p.png")).unwrap();
    let out = p3dp(
        &dir,
        &[
            "build",
            recipe("sphere.yaml").to_str().unwrap(),
            "-o",
            "out.gcode",
            "--stats-json",
            "s.json",
            "--preview",
            "p.png",
        ],
    );
    assert_eq!(code(&out), Some(2), "{}", describe(&out));
    assert_eq!(entries(&dir), ["p.png"], "{}", describe(&out));
    std::fs::remove_dir(dir.join("p.png")).unwrap();
    std::fs::create_dir_all(dir.join("c.png")).unwrap();
    let out = p3dp(
        &dir,
        &[
            "build",
            recipe("ca-stripes.yaml").to_str().unwrap(),
            "-o",
            "out.gcode",
            "--pattern",
            "c.png",
        ],
    );
    assert_eq!(code(&out), Some(2), "{}", describe(&out));
    assert_eq!(entries(&dir), ["c.png"], "{}", describe(&out));
}

#[test]
fn two_recipes_of_one_name_into_one_folder_write_nothing() {
    let dir = tmp("same-name");
    let text = std::fs::read_to_string(recipe("sphere.yaml")).unwrap();
    std::fs::write(dir.join("a.yaml"), &text).unwrap();
    std::fs::write(dir.join("b.yaml"), &text).unwrap();
    let out = p3dp(&dir, &["build", "a.yaml", "b.yaml", "-o", "out/"]);
    assert_eq!(code(&out), Some(2), "{}", describe(&out));
    assert!(
        stderr(&out).contains("would both write"),
        "{}",
        describe(&out)
    );
    assert!(
        entries(&dir.join("out")).is_empty(),
        "{:?}",
        entries(&dir.join("out"))
    );
}

#[test]
fn empty_output_names_name_the_option() {
    let dir = tmp("empty-output");
    let r = recipe("sphere.yaml");
    for opt in ["-o", "--stats-json", "--preview", "--pattern"] {
        let out = p3dp(&dir, &["build", r.to_str().unwrap(), opt, ""]);
        assert_eq!(code(&out), Some(2), "{opt}: {}", describe(&out));
        // clap itself refuses an empty path; `-o` (a file, a folder or `-`) is ours
        let e = stderr(&out);
        assert!(
            e.starts_with(&format!("error: {opt}: an empty file name"))
                || e.contains(&format!("a value is required for '{opt} ")),
            "{opt}: {}",
            describe(&out)
        );
    }
    assert!(entries(&dir).is_empty(), "{:?}", entries(&dir));
}

#[test]
fn stale_temp_files_of_ours_are_swept_and_no_others() {
    let dir = tmp("stale-temps");
    let old = std::time::SystemTime::now() - std::time::Duration::from_secs(2 * 3600);
    for name in [
        ".p3dp-abc123.tmp",
        ".p3dp-fresh1.tmp",
        ".p3dp-toolong1.tmp",
        "keep.tmp",
    ] {
        std::fs::write(dir.join(name), "x").unwrap();
        if name != ".p3dp-fresh1.tmp" {
            let f = std::fs::File::options()
                .write(true)
                .open(dir.join(name))
                .unwrap();
            f.set_modified(old).unwrap();
        }
    }
    let out = p3dp(
        &dir,
        &[
            "build",
            recipe("sphere.yaml").to_str().unwrap(),
            "-o",
            "x.gcode",
        ],
    );
    assert_eq!(code(&out), Some(0), "{}", describe(&out));
    assert_eq!(
        entries(&dir),
        [
            ".p3dp-fresh1.tmp",
            ".p3dp-toolong1.tmp",
            "keep.tmp",
            "x.gcode"
        ]
    );
}

/// SIGTERM while the outputs are being written removes the temp files.
#[cfg(unix)]
#[test]
fn a_terminated_build_leaves_no_temp_file() {
    use std::time::{Duration, Instant};
    let dir = tmp("sigterm");
    std::fs::create_dir_all(dir.join("out")).unwrap();
    // the preview is a FIFO nobody reads: opening it waits, with the G-code
    // already in its temp file
    let st = std::process::Command::new("mkfifo")
        .arg(dir.join("wait.png"))
        .status()
        .unwrap();
    assert!(st.success());
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_p3dp"))
        .args([
            "build",
            recipe("sphere.yaml").to_str().unwrap(),
            "-o",
            "out/x.gcode",
            "--preview",
            "wait.png",
        ])
        .current_dir(&dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let mut seen = false;
    while start.elapsed() < Duration::from_secs(60) {
        if entries(&dir.join("out"))
            .iter()
            .any(|e| e.starts_with(".p3dp-"))
        {
            seen = true;
            break;
        }
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(200));
    let _ = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    let status = child.wait().unwrap();
    // unblock nothing: the FIFO stays; only the out folder is checked
    assert!(seen, "no temp file was seen while the build waited");
    assert_eq!(status.code(), Some(128 + 15), "{status:?}");
    assert!(
        entries(&dir.join("out")).is_empty(),
        "{:?}",
        entries(&dir.join("out"))
    );
}

// ---------------------------------------------------------------------------
// Defect 3: panics and stack overflows.

/// No panic, no abort: exit 2 with the place named.
fn refused(out: &std::process::Output, place: &str) {
    assert_eq!(code(out), Some(2), "{}", describe(out));
    let e = stderr(out);
    assert!(!e.contains("panicked") && !e.contains("overflow"), "{e}");
    assert!(e.contains(place), "expected `{place}` in: {e}");
}

#[test]
fn sweeps_that_panicked_or_built_nothing_are_refused() {
    let dir = tmp("bad-sweeps");
    let r = recipe("sphere.yaml");
    let r = r.to_str().unwrap();
    for (sweep, says) in [
        ("x=1:..2", "a range is written a..b:step"),
        ("radius=0..1:1e-320", "values; expected at most 10000"),
        (
            "radius=1e20..1.00000000000001e20:100",
            "too small to tell the values apart",
        ),
    ] {
        let out = p3dp(&dir, &["build", r, "--sweep", sweep, "-o", "out/"]);
        refused(&out, &format!("--sweep {sweep}: "));
        assert!(stderr(&out).contains(says), "{sweep}: {}", describe(&out));
    }
    // three sweeps of 1000 values: 1e9 builds, refused before any is made
    let thousand: Vec<String> = (0..1000).map(|k| k.to_string()).collect();
    let s = |n: &str| format!("{n}={}", thousand.join(","));
    let (a, b, c) = (s("a"), s("b"), s("c"));
    let out = p3dp(
        &dir,
        &[
            "build", r, "--sweep", &a, "--sweep", &b, "--sweep", &c, "-o", "out/",
        ],
    );
    refused(
        &out,
        "--sweep: 1 recipe(s) × 1000 × 1000 × 1000 values make 1000000000 builds",
    );
    assert!(entries(&dir).is_empty(), "{:?}", entries(&dir));
}

#[test]
fn long_and_deep_expressions_are_refused_not_overflowing() {
    let dir = tmp("deep-expr");
    let cases = [
        (
            "terms",
            (0..50_000).map(|_| "x").collect::<Vec<_>>().join("+"),
        ),
        ("minus", format!("{}x", "-".repeat(50_000))),
        (
            "calls",
            format!("{}x{}", "abs(".repeat(50_000), ")".repeat(50_000)),
        ),
        (
            "parens",
            format!("{}x{}", "(".repeat(50_000), ")".repeat(50_000)),
        ),
        ("minus-short", format!("{}x", "-".repeat(4000))),
        (
            "terms-short",
            (0..2000).map(|_| "x").collect::<Vec<_>>().join("+"),
        ),
    ];
    for (tag, e) in cases {
        let text = format!(
            "p3dp: 1\nname: deep\nparts:\n  - primitive: {{helix: {{radius: 10, height: 2, pitch: 0.5}}}}\n    steps:\n      - deform_xyz: {{position: [\"{e}\", y, z]}}\n"
        );
        std::fs::write(dir.join(format!("{tag}.yaml")), text).unwrap();
        let out = p3dp(&dir, &["check", &format!("{tag}.yaml")]);
        refused(
            &out,
            "parts[0].steps[0].deform_xyz.position[0]: the expression",
        );
    }
}

/// A lock with one entry for `sphere.yaml`, its fields as given.
fn lock_text(version: &str, sha: &str, lines: &str, block_lines: &str, blocks: &str) -> String {
    format!(
        "p3dp_lock: {version}\nentries:\n- recipe: r.yaml\n  sha256: {sha}\n  lines: {lines}\n  block_lines: {block_lines}\n  blocks: {blocks}\n"
    )
}

#[test]
fn every_broken_lock_is_refused_with_its_place() {
    let dir = tmp("bad-locks");
    std::fs::copy(recipe("sphere.yaml"), dir.join("r.yaml")).unwrap();
    let out = p3dp(&dir, &["hash", "r.yaml", "--lock", "good.lock"]);
    assert_eq!(code(&out), Some(0), "{}", describe(&out));
    let good = std::fs::read_to_string(dir.join("good.lock")).unwrap();
    let field = |k: &str| {
        good.lines()
            .find_map(|l| l.trim().strip_prefix(&format!("{k}: ")))
            .unwrap()
            .to_string()
    };
    let (sha, lines, bl, blocks) = (
        field("sha256"),
        field("lines"),
        field("block_lines"),
        field("blocks"),
    );
    let other = "0".repeat(64);
    let cases = [
        (
            lock_text("1", "abc", &lines, &bl, &blocks),
            "entries[0].sha256",
        ),
        (
            lock_text("1", "ééééééé", &lines, &bl, &blocks),
            "entries[0].sha256",
        ),
        (
            lock_text("1", &other, &lines, "0", &blocks),
            "entries[0].block_lines",
        ),
        (
            lock_text(
                "1",
                &other,
                "18446744073709551615",
                "36028797018963968",
                &blocks,
            ),
            "entries[0].lines",
        ),
        (
            lock_text("1", &other, &lines, &bl, "zz"),
            "entries[0].blocks",
        ),
        (
            lock_text("7", &sha, &lines, &bl, &blocks),
            "p3dp_lock: lock format version 7",
        ),
        (
            "p3dp_lock: 1\nentries: []\n".to_string(),
            "entries: no entries",
        ),
        (
            lock_text("1", &sha, &lines, &bl, &blocks).replace("r.yaml", "missing.yaml"),
            "entries[0].recipe: no recipe file at `missing.yaml`",
        ),
        (
            lock_text("1", &sha, &lines, &bl, &blocks)
                .replace("  sha256", "  printer: nope.yaml\n  sha256"),
            "entries[0].printer",
        ),
    ];
    for (k, (text, place)) in cases.iter().enumerate() {
        let f = format!("bad{k}.lock");
        std::fs::write(dir.join(&f), text).unwrap();
        let out = p3dp(&dir, &["hash", "--check", &f]);
        refused(&out, &format!("{f}: {place}"));
    }
    // the good lock still checks, and a changed one names the change
    let out = p3dp(&dir, &["hash", "--check", "good.lock"]);
    assert_eq!(code(&out), Some(0), "{}", describe(&out));
    std::fs::write(dir.join("changed.lock"), good.replace(&sha, &other)).unwrap();
    let out = p3dp(&dir, &["hash", "--check", "changed.lock"]);
    assert_eq!(code(&out), Some(1), "{}", describe(&out));
}

/// Issue 42: a lock's entries are confined as any file reached through a
/// key. A lock naming a file outside its project (by `..`, an absolute
/// path, a symlink, or as its printer) is refused before the file is
/// opened, and the error names the entry and nothing of the file: before,
/// the file was built and its fake key quoted into the error.
#[test]
fn lock_entries_outside_the_locks_project_are_refused_unread() {
    let dir = tmp("lock-confined");
    let secret = "AKIAFAKEKEY0123456789";
    std::fs::write(
        dir.join("secret.yaml"),
        format!("p3dp: 1\nname: x\naws_secret_access_key: {secret}\nparts: []\n"),
    )
    .unwrap();
    let proj = dir.join("proj");
    std::fs::create_dir_all(&proj).unwrap();
    std::fs::copy(recipe("sphere.yaml"), proj.join("r.yaml")).unwrap();
    std::os::unix::fs::symlink(dir.join("secret.yaml"), proj.join("link.yaml")).unwrap();
    let out = p3dp(&proj, &["hash", "r.yaml", "--lock", "good.lock"]);
    assert_eq!(code(&out), Some(0), "{}", describe(&out));
    let good = std::fs::read_to_string(proj.join("good.lock")).unwrap();
    let abs = dir.join("secret.yaml").display().to_string();
    let cases = [
        (
            "recipe: r.yaml",
            "recipe: ../secret.yaml",
            "entries[0].recipe",
            "../secret.yaml",
        ),
        (
            "recipe: r.yaml",
            "recipe: link.yaml",
            "entries[0].recipe",
            "link.yaml",
        ),
        (
            "recipe: r.yaml",
            &format!("recipe: {abs}"),
            "entries[0].recipe",
            &abs,
        ),
        // missing or not, a file outside gets the same answer
        (
            "recipe: r.yaml",
            "recipe: ../nothing.yaml",
            "entries[0].recipe",
            "../nothing.yaml",
        ),
        (
            "  sha256",
            "  printer: ../secret.yaml\n  sha256",
            "entries[0].printer",
            "../secret.yaml",
        ),
    ];
    for (k, (from, to, place, name)) in cases.iter().enumerate() {
        let f = format!("out{k}.lock");
        std::fs::write(proj.join(&f), good.replacen(from, to, 1)).unwrap();
        let out = p3dp(&proj, &["hash", "--check", &f]);
        refused(&out, &format!("{f}: {place}: the "));
        let e = stderr(&out);
        assert!(
            e.contains(&format!("`{name}` is outside the folders a lock may name")),
            "{e}"
        );
        assert!(!e.contains(secret) && !e.contains("aws_secret"), "{e}");
    }
    // --allow-read lets the lock reach the folder above (the user's choice)
    let out = p3dp(
        &proj,
        &["hash", "--check", "out0.lock", "--allow-read", ".."],
    );
    assert!(
        !stderr(&out).contains("outside the folders"),
        "{}",
        describe(&out)
    );
    // and no lock is written that --check would refuse
    std::fs::copy(recipe("sphere.yaml"), dir.join("top.yaml")).unwrap();
    let out = p3dp(&proj, &["hash", "../top.yaml", "--lock", "new.lock"]);
    refused(
        &out,
        "--lock: the recipe `../top.yaml` is outside the folders",
    );
    assert!(!proj.join("new.lock").exists());
}

/// `s` as a YAML double-quoted string, every character outside printable
/// ASCII written as an escape (`\U0000FFFE`), so YAML reads any of them.
fn yaml_escaped(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' | '\\' => {
                out.push('\\');
                out.push(c);
            }
            ' '..='~' => out.push(c),
            c => out.push_str(&format!("\\U{:08X}", c as u32)),
        }
    }
    out.push('"');
    out
}

/// The text of entry `name` of the zip `file`.
fn zip_text(file: &Path, name: &str) -> String {
    let bytes = std::fs::read(file).unwrap();
    let mut z = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
    let mut s = String::new();
    std::io::Read::read_to_string(&mut z.by_name(name).unwrap(), &mut s).unwrap();
    s
}

/// A lock's own text (an entry's recipe name) reaches the terminal escaped:
/// no escape sequence of a hostile lock is printed raw by `hash --check`.
#[test]
fn a_changed_entrys_name_is_printed_escaped() {
    let dir = tmp("lock-escape");
    let name = "a\u{1b}]0;owned\u{7}b.yaml";
    std::fs::copy(recipe("sphere.yaml"), dir.join(name)).unwrap();
    let out = p3dp(&dir, &["hash", name, "--lock", "l.lock"]);
    assert_eq!(code(&out), Some(0), "{}", describe(&out));
    let lock = std::fs::read_to_string(dir.join("l.lock")).unwrap();
    let sha = lock
        .lines()
        .find_map(|l| l.trim().strip_prefix("sha256: "))
        .unwrap()
        .to_string();
    std::fs::write(dir.join("l.lock"), lock.replace(&sha, &"0".repeat(64))).unwrap();
    let out = p3dp(&dir, &["hash", "--check", "l.lock"]);
    assert_eq!(code(&out), Some(1), "{}", describe(&out));
    let all = format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr(&out));
    assert!(!all.contains(['\u{1b}', '\u{7}']), "{all:?}");
    assert!(
        all.contains("CHANGED  a\\u{1b}]0;owned\\u{7}b.yaml"),
        "{all}"
    );
}

/// Two recipes whose part and material are named `name`: `file`, a helix,
/// and `solid-FILE`, the cup with a solid base.
fn xml_named(dir: &Path, file: &str, name: &str) {
    let q = yaml_escaped(name);
    let text = format!(
        "p3dp: 1\nname: n\nmaterial: {{name: {q}, density: 1.24, nozzle_temp: 210, bed_temp: 60}}\nparts:\n  - name: {q}\n    primitive: {{helix: {{radius: 10, height: 2, pitch: 0.5}}}}\n"
    );
    std::fs::write(dir.join(file), text).unwrap();
    let solid = std::fs::read_to_string(recipe("cup-solid-base.yaml"))
        .unwrap()
        .replace("  - name: base\n", &format!("  - name: {q}\n"));
    std::fs::write(dir.join(format!("solid-{file}")), solid).unwrap();
}

/// Issue 42: every XML p3dp writes (the `.gcode.3mf`'s metadata, the mesh's
/// 3MF, the z-buffer's SVG) reads back in a real XML parser with a hostile
/// name whole.
#[test]
fn xml_outputs_hold_hostile_names_whole() {
    let dir = tmp("xml-names");
    let name = "a <b> & \"c\" 'd' ]]> \u{202e}x 🐢";
    xml_named(&dir, "ok.yaml", name);
    let args = [
        "build",
        "ok.yaml",
        "--printer",
        "bambu-x1c",
        "-o",
        "ok.gcode.3mf",
    ];
    let built = p3dp(&dir, &args);
    assert_eq!(code(&built), Some(0), "{}", describe(&built));
    let info = zip_text(&dir.join("ok.gcode.3mf"), "Metadata/slice_info.config");
    let doc = roxmltree::Document::parse(&info).unwrap_or_else(|e| panic!("{e}: {info}"));
    let names: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("object"))
        .filter_map(|n| n.attribute("name"))
        .collect();
    assert_eq!(names, [name]);
    let meshed = p3dp(&dir, &["mesh", "ok.yaml", "-o", "ok.3mf"]);
    assert_eq!(code(&meshed), Some(0), "{}", describe(&meshed));
    let model = zip_text(&dir.join("ok.3mf"), "3D/3dmodel.model");
    let doc = roxmltree::Document::parse(&model).unwrap();
    let base = doc.descendants().find(|n| n.has_tag_name("base")).unwrap();
    assert_eq!(base.attribute("name"), Some(name));
    let args = [
        "build",
        "solid-ok.yaml",
        "-o",
        "s.gcode",
        "--zbuffer-svg",
        "z.svg",
    ];
    let svg = p3dp(&dir, &args);
    assert_eq!(code(&svg), Some(0), "{}", describe(&svg));
    let svg = std::fs::read_to_string(dir.join("z.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{e}: {svg}"));
    let title = doc.descendants().find(|n| n.has_tag_name("title")).unwrap();
    assert!(title.text().unwrap().starts_with(name), "{svg}");
}

/// Issue 42: a name XML cannot hold (U+FFFE, U+FFFF) is refused by name
/// with nothing written: it made `slice_info.config` malformed with exit 0.
#[test]
fn xml_outputs_refuse_names_xml_forbids() {
    let dir = tmp("xml-bad-names");
    for (bad, code_point) in [("a\u{fffe}b", "U+FFFE"), ("a\u{ffff}", "U+FFFF")] {
        xml_named(&dir, "bad.yaml", bad);
        let package = [
            "build",
            "bad.yaml",
            "--printer",
            "bambu-x1c",
            "-o",
            "bad.gcode.3mf",
        ];
        let svg = [
            "build",
            "solid-bad.yaml",
            "-o",
            "b.gcode",
            "--zbuffer-svg",
            "b.svg",
        ];
        let runs: [(&[&str], &str); 3] = [
            (&package, "bad.gcode.3mf"),
            (&["mesh", "bad.yaml", "-o", "bad.3mf"], "bad.3mf"),
            (&svg, "b.svg"),
        ];
        for (args, out) in runs {
            let o = p3dp(&dir, args);
            assert_eq!(code(&o), Some(2), "{args:?}: {}", describe(&o));
            let e = stderr(&o);
            assert!(
                e.contains(&format!("{code_point} at character")) && e.contains("XML 1.0"),
                "{e}"
            );
            assert!(!dir.join(out).exists(), "{out} written");
        }
    }
}

// ---------------------------------------------------------------------------
// Defect 4: machine and material values outside a sane range.

#[test]
fn profiles_outside_physical_ranges_are_refused_with_the_key() {
    let dir = tmp("profile-ranges");
    let cases = [
        (
            "filament_diameter: 1e-9",
            "filament_diameter: 0.000000001 mm is not allowed; expected 1 to 3.5 mm",
        ),
        (
            "nozzle_diameter: 5",
            "nozzle_diameter: 5 mm is not allowed; expected 0.1 to 2 mm",
        ),
        (
            "max_nozzle_temp: 1000",
            "max_nozzle_temp: 1000 °C is not allowed; expected at most 500 °C",
        ),
        ("max_bed_temp: 300", "max_bed_temp: 300 °C is not allowed"),
        (
            "travel_speed: 1e9",
            "travel_speed: 1000000000 mm/s is not allowed; expected at most 2000 mm/s",
        ),
        (
            "max_speed: 1e9",
            "max_speed: 1000000000 mm/s is not allowed",
        ),
        (
            "retraction: {length: 1e6, speed: 35}",
            "retraction.length: 1000000 mm is not allowed; expected at most 20 mm",
        ),
        (
            "kinematics: {max_acceleration: 1e9}",
            "kinematics.max_acceleration: 1000000000 mm/s² is not allowed",
        ),
        (
            "max_flow: 1e12",
            "max_flow: 1000000000000 mm³/s is not allowed",
        ),
        (
            "bed: {shape: rectangle, size: [1e9, 220], max_z: 250}",
            "bed.size[0]",
        ),
    ];
    for (k, (line, says)) in cases.iter().enumerate() {
        let f = format!("p{k}.yaml");
        std::fs::write(dir.join(&f), format!("inherits: generic-220\n{line}\n")).unwrap();
        let out = p3dp(
            &dir,
            &[
                "build",
                recipe("sphere.yaml").to_str().unwrap(),
                "--printer",
                &f,
                "-o",
                "x.gcode",
            ],
        );
        refused(&out, &format!("{f}: {says}"));
        assert!(!dir.join("x.gcode").exists(), "{line}: G-code written");
    }
}

// ---------------------------------------------------------------------------
// Defects 6 and 8: bounded reads and parsing, places in every error.

#[cfg(unix)]
#[test]
fn endless_inputs_are_refused_not_read_until_memory_runs_out() {
    let dir = tmp("dev-zero");
    std::fs::write(dir.join("p.yaml"), "inherits: /dev/zero\n").unwrap();
    let text = std::fs::read_to_string(recipe("sphere.yaml")).unwrap();
    std::fs::write(dir.join("r.yaml"), text).unwrap();
    std::fs::write(
        dir.join("z.lock"),
        "p3dp_lock: 1\nentries:\n- recipe: /dev/zero\n  sha256: 0000000000000000000000000000000000000000000000000000000000000000\n  lines: 1\n  block_lines: 1\n  blocks: '00000000'\n",
    )
    .unwrap();
    let cases: [(&[&str], &str); 5] = [
        (
            &["check", "/dev/zero"],
            "/dev/zero: the recipe is larger than 16 MB",
        ),
        (
            &["check", "r.yaml", "--printer", "p.yaml"],
            "the printer profile `/dev/zero` is a system file",
        ),
        (
            &["hash", "--check", "/dev/zero"],
            "/dev/zero: the lock file is larger than 16 MB",
        ),
        (
            &["hash", "--check", "z.lock"],
            "entries[0].recipe: the recipe `/dev/zero` is outside the folders a lock may name",
        ),
        (
            &["build", "/dev/zero", "-o", "x.gcode"],
            "/dev/zero: the recipe is larger than 16 MB",
        ),
    ];
    for (args, says) in cases {
        let out = p3dp(&dir, args);
        refused(&out, says);
    }
    assert!(!dir.join("x.gcode").exists());
}

#[test]
fn a_byte_order_mark_is_no_part_of_the_first_key() {
    let dir = tmp("bom");
    // the first key right after the mark (a comment first hid the problem)
    let text =
        "name: bom\np3dp: 1\nparts:\n  - primitive: {helix: {radius: 10, height: 2, pitch: 0.5}}\n";
    std::fs::write(dir.join("bom.yaml"), format!("\u{feff}{text}")).unwrap();
    std::fs::write(dir.join("plain.yaml"), text).unwrap();
    let a = p3dp(&dir, &["build", "bom.yaml", "-o", "a.gcode", "--force"]);
    assert_eq!(code(&a), Some(0), "{}", describe(&a));
    let b = p3dp(&dir, &["build", "plain.yaml", "-o", "b.gcode", "--force"]);
    assert_eq!(code(&b), Some(0), "{}", describe(&b));
    assert_eq!(
        std::fs::read(dir.join("a.gcode")).unwrap(),
        std::fs::read(dir.join("b.gcode")).unwrap()
    );
}

#[test]
fn unreadable_text_and_deep_yaml_name_a_line_and_column() {
    let dir = tmp("bad-text");
    std::fs::write(
        dir.join("latin1.yaml"),
        b"p3dp: 1\nname: caf\xe9\nparts: []\n",
    )
    .unwrap();
    let out = p3dp(&dir, &["check", "latin1.yaml"]);
    refused(&out, "latin1.yaml:2:10: byte 0xe9 is not UTF-8");
    let deep = format!(
        "p3dp: 1\nname: {}1{}\n",
        "[".repeat(200_000),
        "]".repeat(200_000)
    );
    std::fs::write(dir.join("deep.yaml"), deep).unwrap();
    let t = std::time::Instant::now();
    let out = p3dp(&dir, &["check", "deep.yaml"]);
    refused(&out, "deep.yaml:2:71: brackets nest more than 64 deep");
    assert!(t.elapsed().as_secs() < 10, "took {:?}", t.elapsed());
    let long = "A".repeat(20_000);
    std::fs::write(
        dir.join("text.yaml"),
        format!("p3dp: 1\nname: t\nparts:\n  - primitive: {{helix: {{radius: 10, height: 2, pitch: 0.5}}}}\n    steps:\n      - modulate_map: {{text: \"{long}\", u: \"theta\", v: z}}\n"),
    )
    .unwrap();
    let out = p3dp(&dir, &["check", "text.yaml"]);
    refused(&out, "parts[0].steps[0].modulate_map.text: the text has 20000 characters; expected at most 10000");
}

#[cfg(unix)]
#[test]
fn an_error_about_a_system_file_names_it_without_printing_it() {
    let dir = tmp("system-file");
    std::fs::write(
        dir.join("etc.lock"),
        "p3dp_lock: 1\nentries:\n- recipe: /etc/passwd\n  sha256: 0000000000000000000000000000000000000000000000000000000000000000\n  lines: 1\n  block_lines: 1\n  blocks: '00000000'\n",
    )
    .unwrap();
    let passwd = std::fs::read_to_string("/etc/passwd").unwrap_or_default();
    let first = passwd.lines().next().unwrap_or("root:x:0:0");
    for args in [
        &["hash", "--check", "etc.lock"][..],
        &["check", "/etc/passwd"][..],
    ] {
        let out = p3dp(&dir, args);
        assert_eq!(code(&out), Some(2), "{}", describe(&out));
        let e = stderr(&out);
        assert!(e.contains("/etc/passwd"), "{e}");
        let head: String = first.chars().take(12).collect();
        assert!(!e.contains(&head), "the error prints the file: {e}");
    }
}

/// Runs `p3dp ARGS` in `dir`, killed after `secs`; `None` when it was killed.
fn p3dp_within(dir: &Path, args: &[&str], secs: u64) -> Option<std::process::Output> {
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_p3dp"))
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let id = child.id();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    match rx.recv_timeout(std::time::Duration::from_secs(secs)) {
        Ok(out) => Some(out.unwrap()),
        Err(_) => {
            let _ = std::process::Command::new("kill")
                .args(["-KILL", &id.to_string()])
                .status();
            None
        }
    }
}

#[test]
fn cheap_checks_refuse_before_expensive_ones_run() {
    let dir = tmp("cheap-first");
    let cases = [
        (
            "wide.yaml",
            "  - primitive: {helix: {radius: 1e4, height: 2, pitch: 0.5}}\n",
            "[out-of-bed]",
        ),
        (
            "thick.yaml",
            "  - cross_section: 1e7\n    primitive: {helix: {radius: 10, height: 2, pitch: 0.5}}\n",
            "[over-extrusion]",
        ),
    ];
    for (f, part, code_) in cases {
        std::fs::write(dir.join(f), format!("p3dp: 1\nname: big\nparts:\n{part}")).unwrap();
        // 42 s and 5 GB before (debug build)
        let out = p3dp_within(&dir, &["check", f], 10)
            .unwrap_or_else(|| panic!("{f}: still running after 10 s"));
        assert_eq!(code(&out), Some(1), "{f}: {}", describe(&out));
        assert!(
            String::from_utf8_lossy(&out.stdout).contains(code_),
            "{f}: {}",
            describe(&out)
        );
    }
}

#[test]
fn an_automaton_a_million_rows_deep_per_point_is_computed_once() {
    let dir = tmp("eca-rows");
    std::fs::write(
        dir.join("eca.yaml"),
        "p3dp: 1\nname: eca\nparts:\n  - primitive: {helix: {radius: 10, height: 50, pitch: 0.2, segments: 288}}\n    steps:\n      - deform_cylinder: {position: [\"r + 0.2 * eca(30, 64, 1000000, i)\", theta, z]}\n",
    )
    .unwrap();
    let out = p3dp_within(&dir, &["check", "eca.yaml"], 20)
        .expect("still running after 20 s (minutes before)");
    assert!(matches!(code(&out), Some(0 | 1)), "{}", describe(&out));
    // rows going down, from a million: every point started again from row
    // 0 before (72,000 × a million generations)
    std::fs::write(
        dir.join("down.yaml"),
        "p3dp: 1\nname: down\nparts:\n  - primitive: {helix: {radius: 10, height: 50, pitch: 0.2, segments: 288}}\n    steps:\n      - deform_cylinder: {position: [\"r + 0.2 * eca(30, 64, 1000000 - i, i)\", theta, z]}\n",
    )
    .unwrap();
    let out = p3dp_within(&dir, &["check", "down.yaml"], 20)
        .expect("still running after 20 s (hours before)");
    assert!(matches!(code(&out), Some(0 | 1)), "{}", describe(&out));
}

#[test]
fn a_line_retraced_a_million_times_is_checked_in_linear_time() {
    // the first-layer check scanned every earlier copy of the line (newest
    // first) for the one it kept, and painted each copy's footprint again,
    // and the support check scanned the whole pile under every sample above
    // it: over 5 minutes for 2M strings (1.4 s now, release)
    let dir = tmp("pile");
    std::fs::write(
        dir.join("pile.yaml"),
        "p3dp: 1\nname: pile\nprinter: generic-220\nmaterial: pla\nparts:\n  - name: pile\n    primitive:\n      turtle:\n        start: {position: [0, 0, 0.2]}\n        program:\n          - repeat: 300000\n            do: [{forward: 10}, {backward: 10}]\n  - name: over\n    primitive:\n      turtle:\n        start: {position: [-20, 0.3, 1.2]}\n        program:\n          - repeat: 100\n            do: [{forward: 50}, {backward: 50}]\n",
    )
    .unwrap();
    let out = p3dp_within(&dir, &["check", "pile.yaml"], 30).expect("still running after 30 s");
    assert!(matches!(code(&out), Some(0 | 1)), "{}", describe(&out));
    // the pile's contact is one line's footprint, however often retraced
    let area = |repeat: &str| {
        let text = std::fs::read_to_string(dir.join("pile.yaml")).unwrap();
        std::fs::write(dir.join("p.yaml"), text.replace("repeat: 300000", repeat)).unwrap();
        let out = p3dp_within(
            &dir,
            &[
                "build",
                "p.yaml",
                "-o",
                "p.gcode",
                "--stats-json",
                "p.json",
                "--force",
            ],
            30,
        )
        .expect("still running after 30 s");
        assert!(matches!(code(&out), Some(0 | 1)), "{}", describe(&out));
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("p.json")).unwrap()).unwrap();
        json.pointer("/first_layer/0/contact_area_mm2")
            .and_then(|v| v.as_f64())
            .unwrap()
    };
    let (many, once) = (area("repeat: 300000"), area("repeat: 1"));
    assert!(once > 10.0 * 0.4 && many == once, "{many} vs {once}");
}

#[test]
fn a_turtle_that_works_without_drawing_is_stopped_early() {
    // a procedure calling itself twice, 60 deep, drawing nothing: 2^61
    // steps; the absolute step limit (400 million) stopped it after 44 s
    let dir = tmp("turtle-idle");
    std::fs::write(
        dir.join("tree.yaml"),
        "p3dp: 1\nname: tree\nparts:\n  - primitive:\n      turtle:\n        procedures:\n          tree:\n            params: [d]\n            do:\n              - if: d\n                do:\n                  - {call: tree, args: [\"d - 1\"]}\n                  - {call: tree, args: [\"d - 1\"]}\n        program:\n          - {call: tree, args: [60]}\n",
    )
    .unwrap();
    let out = p3dp_within(&dir, &["check", "tree.yaml"], 20).expect("still running after 20 s");
    assert_eq!(code(&out), Some(2), "{}", describe(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("tree.yaml")
            && err.contains("procedures.tree.do[0]")
            && err.contains("made only 0 strings"),
        "{err}"
    );
}
