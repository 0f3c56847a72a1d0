//! One rule for every file a build reads (issue 33): a file reached through
//! a key is a regular file inside the recipe's project, read bounded, and
//! no output of the command may replace any file the build read.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use crate::common::*;

/// A recipe of four parts that reaches every kind of file: an include, a
/// profile inheriting from another, an SVG, an image; a solid for the
/// z-buffer. Returns its folder.
fn project(name: &str) -> crate::common::Tmp {
    let dir = tmp(name);
    let w = |f: &str, t: &[u8]| std::fs::write(dir.join(f), t).unwrap();
    w("lib.yaml", b"p3dp: 1\nparams: {rr: 8}\n");
    // a library named like a mesh, for `mesh -o` to aim at
    w("more.3mf", b"p3dp: 1\nparams: {h: 1}\n");
    w("base.yaml", b"inherits: generic-220\nname: base\n");
    w("p.yaml", b"inherits: base.yaml\nname: mine\n");
    w(
        "c.svg",
        b"<svg xmlns='http://www.w3.org/2000/svg' viewBox='0 0 20 20'><circle id='c' cx='10' cy='10' r='8'/></svg>",
    );
    let mut png = Vec::new();
    image::GrayImage::from_fn(4, 4, |x, y| image::Luma([((x + y) * 30) as u8]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    w("m.png", &png);
    w("r.yaml", RECIPE.as_bytes());
    dir
}

const RECIPE: &str = "p3dp: 1\nname: r\nprinter: p.yaml\nmaterial: pla\ninclude: [lib.yaml, more.3mf]\nparts:\n  - name: ring\n    primitive: {helix: {radius: rr, height: 1, pitch: 0.5, center: [-40, 0, 0.2]}}\n    steps:\n      - modulate_map: {image: m.png, u: \"theta/(2*pi)\", v: \"z\"}\n  - name: shape\n    primitive: {path: {svg: c.svg}}\n  - name: solid\n    primitive:\n      solid: {layer_height: 0.2, line_width: 0.45, features: [{box: {center: [40, 0, 0.4], size: [6, 6, 0.8]}}]}\n";

fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    files.sort();
    files
}

#[test]
fn the_project_builds_when_no_output_is_an_input() {
    let dir = project("inputs-ok");
    let out = p3dp(&dir, &["build", "r.yaml", "-o", "r.gcode", "--force"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let g = std::fs::read_to_string(dir.join("r.gcode")).unwrap();
    assert!(g.contains("; part: shape"), "the SVG part is drawn");
}

#[test]
fn outputs_over_every_kind_of_input_are_refused_and_nothing_is_written() {
    let dir = project("inputs-clobber");
    std::os::unix::fs::symlink("p.yaml", dir.join("link.stl")).unwrap();
    let cases: &[&[&str]] = &[
        &["build", "r.yaml", "-o", "lib.yaml", "--force"],
        &[
            "build",
            "r.yaml",
            "-o",
            "x.gcode",
            "--stats-json",
            "lib.yaml",
            "--force",
        ],
        &["build", "r.yaml", "-o", "p.yaml", "--force"],
        &["build", "r.yaml", "-o", "base.yaml", "--force"],
        &[
            "build",
            "r.yaml",
            "-o",
            "x.gcode",
            "--preview",
            "m.png",
            "--force",
        ],
        &[
            "build",
            "r.yaml",
            "-o",
            "x.gcode",
            "--pattern",
            "m.png",
            "--force",
        ],
        &["build", "r.yaml", "-o", "c.svg", "--force"],
        &[
            "build",
            "r.yaml",
            "-o",
            "x.gcode",
            "--zbuffer-svg",
            "c.svg",
            "--force",
        ],
        &["hash", "r.yaml", "--lock", "lib.yaml", "--force"],
        &["preview", "r.yaml", "-o", "m.png"],
        &["mesh", "r.yaml", "-o", "more.3mf"],
        &["mesh", "r.yaml", "-o", "link.stl"],
    ];
    let before = snapshot(&dir);
    for args in cases {
        let out = p3dp(&dir, args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(
            stderr(&out).contains("which this command reads"),
            "{args:?}: {}",
            stderr(&out)
        );
        assert!(snapshot(&dir) == before, "{args:?} wrote or changed a file");
    }
}

/// Runs `p3dp ARGS` in `dir`, killed after `limit`: its output, or `None`
/// when it had to be killed (it hung).
fn run_bounded(dir: &Path, args: &[&str], limit: Duration) -> Option<Output> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_p3dp"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t = Instant::now();
    while t.elapsed() < limit {
        if child.try_wait().unwrap().is_some() {
            return Some(child.wait_with_output().unwrap());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn fifos_and_devices_through_every_file_key_are_refused_quickly() {
    let dir = project("inputs-fifo");
    let fifo = dir.join("ff");
    let made = Command::new("mkfifo").arg(&fifo).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
    let lock = |recipe: &str, printer: &str| {
        format!("p3dp_lock: 1\nentries:\n- recipe: {recipe}\n{printer}  sha256: 0000000000000000000000000000000000000000000000000000000000000000\n  lines: 1\n  block_lines: 1\n  blocks: '00000000'\n")
    };
    std::fs::write(dir.join("l1.lock"), lock("ff", "")).unwrap();
    std::fs::write(dir.join("l2.lock"), lock("r.yaml", "  printer: ff\n")).unwrap();
    // (what replaces what in the recipe, or a lock; what the error says)
    let cases: Vec<(String, &str)> = vec![
        ("include: [ff]".into(), "FIFO"),
        ("include: [/dev/zero]".into(), "/dev/zero"),
        ("printer: ./ff".into(), "FIFO"),
        ("svg: ff".into(), "FIFO"),
        ("svg: /dev/zero".into(), "/dev/zero"),
        ("image: ff".into(), "FIFO"),
        ("image: /dev/urandom".into(), "/dev/urandom"),
        ("inherits: ./ff".into(), "FIFO"),
        ("l1.lock".into(), "FIFO"),
        ("l2.lock".into(), "FIFO"),
    ];
    for (case, says) in &cases {
        let args: Vec<String> = if case.ends_with(".lock") {
            vec!["hash".into(), "--check".into(), case.clone()]
        } else if let Some(base) = case.strip_prefix("inherits: ") {
            std::fs::write(dir.join("p.yaml"), format!("inherits: {base}\n")).unwrap();
            vec!["check".into(), "r.yaml".into()]
        } else {
            let (key, _) = case.split_once(": ").unwrap();
            let text = RECIPE
                .lines()
                .map(|l| {
                    let t = l.trim_start();
                    if (key == "include" || key == "printer") && t.starts_with(&format!("{key}:")) {
                        case.clone()
                    } else if (key == "svg" || key == "image") && t.contains(&format!("{key}: ")) {
                        let old = if key == "svg" {
                            "svg: c.svg"
                        } else {
                            "image: m.png"
                        };
                        l.replace(old, case)
                    } else {
                        l.to_string()
                    }
                })
                .collect::<Vec<_>>()
                .join("\n");
            std::fs::write(dir.join("f.yaml"), text).unwrap();
            vec!["check".into(), "f.yaml".into()]
        };
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = run_bounded(&dir, &args, Duration::from_secs(10))
            .unwrap_or_else(|| panic!("{case}: hung on the FIFO"));
        assert_eq!(out.status.code(), Some(2), "{case}: {}", stderr(&out));
        assert!(stderr(&out).contains(says), "{case}: {}", stderr(&out));
    }
}

#[test]
fn a_recipe_reads_only_inside_its_project() {
    let top = tmp("inputs-confine");
    let dir = top.join("proj");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let secret = "API_KEY: sk-live-0123456789\n";
    std::fs::write(top.join("secret.yaml"), secret).unwrap();
    std::fs::write(dir.join("lib.yaml"), "p3dp: 1\nparams: {rr: 8}\n").unwrap();
    let recipe = |inc: &str| {
        format!("p3dp: 1\nname: r\ninclude: [{inc}]\nparts:\n  - primitive: {{helix: {{radius: 8, height: 1, pitch: 0.5, center: [0, 0, 0.2]}}}}\n")
    };
    let abs = top.join("secret.yaml").display().to_string();
    for inc in [
        "../secret.yaml",
        abs.as_str(),
        "/proc/self/environ",
        "/etc/passwd",
    ] {
        std::fs::write(dir.join("r.yaml"), recipe(inc)).unwrap();
        let out = p3dp(&dir, &["check", "r.yaml"]);
        let e = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{inc}: {e}");
        assert!(e.contains("include[0]"), "{inc}: the key is named: {e}");
        assert!(!e.contains("sk-live"), "{inc}: no text of the file: {e}");
        assert!(!e.contains("root:"), "{inc}: no text of the file: {e}");
    }
    // the folder tree of the recipe: `..` from a subfolder stays inside
    std::fs::write(dir.join("sub/r.yaml"), recipe("../lib.yaml")).unwrap();
    std::fs::write(dir.join("p3dp.lock"), "p3dp_lock: 1\nentries: []\n").unwrap();
    let out = p3dp(&dir, &["check", "sub/r.yaml"]);
    assert_ne!(out.status.code(), Some(2), "{}", stderr(&out));
    // the explicit option lets a build read outside
    std::fs::write(dir.join("r.yaml"), recipe("../secret.yaml")).unwrap();
    let out = p3dp(&dir, &["check", "r.yaml", "--allow-read", ".."]);
    // read now: the file is no library (a key p3dp does not know)
    assert!(
        !stderr(&out).contains("outside the folders"),
        "{}",
        stderr(&out)
    );
}
