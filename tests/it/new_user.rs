//! The faults a new user met (issue 32), each mended: a `deform_xyz`
//! written in cylinder coordinates, `--sweep a..b`, sweep names and
//! summaries, `hash --lock` with one variant, a lock mismatch naming the
//! part, the summary of a path over nothing, a runaway L-system.

use crate::common::{p3dp, tmp};

fn run(dir: &std::path::Path, args: &[&str]) -> (Option<i32>, String) {
    let out = p3dp(dir, args);
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code(), text)
}

#[test]
fn deform_xyz_refuses_cylinder_coordinates_naming_the_key() {
    let dir = tmp("deform-xyz-r");
    std::fs::write(
        dir.join("r.yaml"),
        "p3dp: 1\nname: twist\nparts:\n  - primitive: {helix: {radius: 10, height: 5, pitch: 0.25}}\n    steps:\n      - deform_xyz:\n          position: [r, \"theta + z/10\", z]\n",
    )
    .unwrap();
    let (code, text) = run(&dir, &["build", "r.yaml", "-o", "r.gcode"]);
    assert_eq!(code, Some(2), "{text}");
    assert!(
        text.contains("deform_xyz.position") && text.contains("deform_cylinder"),
        "{text}"
    );
    assert!(!dir.join("r.gcode").exists());
    // the point's angle in a Cartesian position is a wave round the part: fine
    std::fs::write(
        dir.join("w.yaml"),
        "p3dp: 1\nname: wave\nparts:\n  - primitive: {helix: {radius: 10, height: 5, pitch: 0.25}}\n    steps:\n      - deform_xyz:\n          position: [x, y, \"z + 0.2 + 0.1*cos(6*theta)\"]\n",
    )
    .unwrap();
    let (code, text) = run(&dir, &["build", "w.yaml", "-o", "w.gcode"]);
    assert_eq!(code, Some(0), "{text}");
}

#[test]
fn a_sweep_names_and_summarises_the_values_it_gives() {
    let dir = tmp("sweep-values");
    std::fs::write(
        dir.join("ring.yaml"),
        "p3dp: 1\nname: ring\nparams:\n  k: 1\n  size: 5\nparts:\n  - primitive: {circle: {radius: size, center: [0, 0, 0.2]}}\n",
    )
    .unwrap();
    let (code, text) = run(
        &dir,
        &[
            "build",
            "ring.yaml",
            "--sweep",
            "k=1..2",
            "--sweep",
            "size=5 + k/2",
            "-o",
            "out/",
        ],
    );
    assert_eq!(code, Some(0), "{text}");
    for f in ["ring_k-1_size-5.5.gcode", "ring_k-2_size-6.gcode"] {
        assert!(dir.join("out").join(f).exists(), "{f}: {text}");
    }
    let csv = std::fs::read_to_string(dir.join("out/summary.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert!(rows[0].starts_with("file,recipe,k,size,"), "{csv}");
    assert!(
        rows[1].contains(",1,5.5,") && rows[2].contains(",2,6,"),
        "{csv}"
    );
}

#[test]
fn hash_lock_merges_and_a_mismatch_names_the_part() {
    let dir = tmp("lock-merge");
    let text = "p3dp: 1\nname: ring\nparams:\n  size: 10\nparts:\n  - name: rim\n    primitive: {circle: {radius: size, center: [0, 0, 0.2], segments: 36}}\n";
    std::fs::write(dir.join("ring.yaml"), text).unwrap();
    for set in ["size=10", "size=12", "size=14"] {
        let (code, out) = run(
            &dir,
            &["hash", "--lock", "l.lock", "ring.yaml", "--set", set],
        );
        assert_eq!(code, Some(0), "{out}");
    }
    // three variants locked one at a time: three entries; size=12 again replaces its own
    let (code, out) = run(
        &dir,
        &["hash", "--lock", "l.lock", "ring.yaml", "--set", "size=12"],
    );
    assert_eq!(code, Some(0), "{out}");
    let lock = std::fs::read_to_string(dir.join("l.lock")).unwrap();
    assert_eq!(lock.matches("- recipe: ring.yaml").count(), 3, "{lock}");
    let order: Vec<usize> = ["size=10", "size=12", "size=14"]
        .iter()
        .map(|s| lock.find(s).unwrap())
        .collect();
    assert!(order.windows(2).all(|w| w[0] < w[1]), "{lock}");
    let (code, out) = run(&dir, &["hash", "--check", "l.lock"]);
    assert_eq!(code, Some(0), "{out}");
    // a changed geometry is named by its part
    std::fs::write(
        dir.join("ring.yaml"),
        text.replace("segments: 36", "segments: 37"),
    )
    .unwrap();
    let (code, out) = run(&dir, &["hash", "--check", "l.lock"]);
    assert_eq!(code, Some(1), "{out}");
    assert!(out.contains("in part `rim` at about string"), "{out}");
    // a file that is not a lock is refused, not overwritten
    std::fs::write(dir.join("notes.txt"), "my notes\n").unwrap();
    let (code, out) = run(&dir, &["hash", "--lock", "notes.txt", "ring.yaml"]);
    assert_eq!(code, Some(2), "{out}");
    assert!(out.contains("remove it to start a new lock"), "{out}");
    assert_eq!(
        std::fs::read_to_string(dir.join("notes.txt")).unwrap(),
        "my notes\n"
    );
}

#[test]
fn a_part_mostly_over_gaps_is_a_warning_in_the_summary() {
    let dir = tmp("bridged-share");
    // two rails 9 mm apart, two layers high, then 21 crossings between them
    // a layer up, 1 mm apart: each gap short, most of the path over them
    let recipe = "p3dp: 1\nname: grate\nparts:\n  - primitive:\n      path:\n        - for: {h: \"1..2\"}\n          do:\n            - move: [0, 0, \"0.3*h\"]\n            - draw: [0, 21, \"0.3*h\"]\n            - move: [9, 21, \"0.3*h\"]\n            - draw: [9, 0, \"0.3*h\"]\n        - move: [0, 0, 0.9]\n        - for: {k: \"0..20\"}\n          do:\n            - draw: [\"9*(k % 2 == 0)\", k, 0.9]\n            - draw: [\"9*(k % 2 == 0)\", \"k + 1\", 0.9]\n";
    std::fs::write(dir.join("g.yaml"), recipe).unwrap();
    let (code, text) = run(&dir, &["check", "g.yaml"]);
    assert!(
        text.contains("warning [bridge]")
            && text.contains("% of the print's path hanging over gaps"),
        "{text}"
    );
    assert!(text.contains("1 warning, 0 errors"), "{code:?} {text}");
}

#[test]
fn a_runaway_lsystem_is_refused_by_its_size_before_it_runs() {
    let dir = tmp("lsystem-runaway");
    // 26 doublings: 2^26 = 67 million strings, past the 50 million of
    // max_strings (and under the steps limit)
    let recipe = |n: u32| {
        format!("p3dp: 1\nname: koch\nparts:\n  - primitive:\n      turtle:\n        start: {{position: [-50, 0, 0.2]}}\n        program:\n          - lsystem:\n              axiom: F\n              rules: {{F: \"F+F\"}}\n              iterations: {n}\n              commands:\n                F: [{{forward: 0.001}}]\n                \"+\": [{{left: 90}}]\n                \"-\": [{{right: 90}}]\n")
    };
    std::fs::write(dir.join("k.yaml"), recipe(26)).unwrap();
    let start = std::time::Instant::now();
    let (code, text) = run(&dir, &["check", "k.yaml"]);
    assert_eq!(code, Some(2), "{text}");
    assert!(
        text.contains("67108864 strings") && text.contains("lsystem"),
        "{text}"
    );
    // refused before any of them is made, not after running up to the limit
    assert!(
        start.elapsed() < std::time::Duration::from_secs(2),
        "{:?}",
        start.elapsed()
    );
    std::fs::write(dir.join("k.yaml"), recipe(3)).unwrap();
    let (code, text) = run(&dir, &["check", "k.yaml"]);
    assert_eq!(code, Some(0), "{text}");
}

#[test]
fn a_filament_change_at_a_height() {
    let dir = tmp("gcode-at");
    let recipe = |cmd: &str| {
        format!("p3dp: 1\nname: tube\nparts:\n  - primitive: {{helix: {{radius: 10, height: 4, pitch: 0.2, center: [0, 0, 0.2]}}}}\n    steps:\n      - gcode_at: {{z: 2, gcode: \"{cmd}\"}}\n")
    };
    std::fs::write(dir.join("t.yaml"), recipe("M600")).unwrap();
    let (code, text) = run(&dir, &["build", "t.yaml", "-o", "t.gcode"]);
    assert_eq!(code, Some(0), "{text}");
    let g = crate::common::parse(&std::fs::read_to_string(dir.join("t.gcode")).unwrap());
    let at = g
        .lines
        .iter()
        .position(|l| l.trim() == "M600")
        .expect("M600 written");
    // the moves before it stay below 2 mm, the first extruding one after reaches it
    let z_before = g
        .moves
        .iter()
        .filter(|m| m.de > 0.0 && !m.to[2].is_nan())
        .map(|m| m.to[2]);
    assert!(z_before.clone().any(|z| z >= 2.0));
    let lines_before: Vec<&String> = g.lines[..at]
        .iter()
        .filter(|l| l.starts_with("G1 X") || l.starts_with("G1 Y"))
        .collect();
    let last_z = g.lines[..at].iter().rev().find_map(|l| {
        l.split_whitespace()
            .find_map(|w| w.strip_prefix('Z'))
            .and_then(|v| v.parse::<f64>().ok())
    });
    assert!(
        !lines_before.is_empty() && last_z.unwrap() < 2.0,
        "{last_z:?}"
    );
    // a command that moves the head is refused, naming the key
    std::fs::write(dir.join("t.yaml"), recipe("G28")).unwrap();
    let (code, text) = run(&dir, &["build", "t.yaml", "-o", "u.gcode"]);
    assert_eq!(code, Some(2), "{text}");
    assert!(
        text.contains("steps[0].gcode_at.gcode") && text.contains("G28"),
        "{text}"
    );
}
