//! Batch builds and lock files: --sweep, -j, summary.csv, hash --lock / --check.

use crate::common::*;

fn ok(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "exit {:?}\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn hash_of(dir: &std::path::Path, args: &[&str]) -> String {
    let out = p3dp(dir, args);
    ok(&out);
    String::from_utf8(out.stdout)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .to_string()
}

fn sha_file(path: &std::path::Path) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(std::fs::read(path).unwrap())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[test]
fn sweep_builds_the_cartesian_product_named_by_values() {
    let dir = tmp("sweep");
    let sphere = recipe("sphere.yaml");
    let s = sphere.to_str().unwrap();
    let out = p3dp(
        &dir,
        &[
            "build",
            s,
            "--sweep",
            "radius=20,25",
            "--sweep",
            "pitch=0.2..0.3:0.1",
            "-o",
            "out",
            "-j",
            "2",
        ],
    );
    ok(&out);
    let names = [("20", "0.2"), ("20", "0.3"), ("25", "0.2"), ("25", "0.3")];
    for (r, p) in names {
        let file = dir.join(format!("out/sphere_radius-{r}_pitch-{p}.gcode"));
        assert!(file.is_file(), "{} missing", file.display());
        // the same bytes as --set, which are the same as editing by hand (tests/cli.rs)
        let set_r = format!("radius={r}");
        let set_p = format!("pitch={p}");
        let h = hash_of(&dir, &["hash", s, "--set", &set_r, "--set", &set_p]);
        assert_eq!(sha_file(&file), h, "{}", file.display());
    }
    // one summary line per variant
    let report = String::from_utf8(out.stdout).unwrap();
    assert_eq!(report.lines().count(), 4, "{report}");
    // summary.csv: a header and one row per variant, with the hash of each file
    let csv = std::fs::read_to_string(dir.join("out/summary.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(
        rows[0],
        "file,recipe,radius,pitch,filament_mm,filament_g,print_time_s,warnings,sha256,error"
    );
    assert_eq!(rows.len(), 5);
    for row in &rows[1..] {
        let cols: Vec<&str> = row.split(',').collect();
        assert_eq!(cols.len(), 10, "{row}");
        assert_eq!(sha_file(&dir.join("out").join(cols[0])), cols[8]);
        assert!(cols[4].parse::<f64>().unwrap() > 100.0);
    }
}

#[test]
fn thread_count_does_not_change_the_bytes() {
    let dir = tmp("threads");
    let (a, b) = (recipe("sphere.yaml"), recipe("globe.yaml"));
    let args = |j: &'static str, o: &'static str| {
        vec![
            "build".to_string(),
            a.to_str().unwrap().to_string(),
            b.to_str().unwrap().to_string(),
            "--sweep".into(),
            "radius=20,25,30".into(),
            "-j".into(),
            j.into(),
            "-o".into(),
            o.into(),
        ]
    };
    for (j, o) in [("1", "one"), ("2", "two")] {
        let v = args(j, o);
        let refs: Vec<&str> = v.iter().map(String::as_str).collect();
        ok(&p3dp(&dir, &refs));
    }
    let mut n = 0;
    for e in std::fs::read_dir(dir.join("one")).unwrap() {
        let name = e.unwrap().file_name();
        assert_eq!(
            std::fs::read(dir.join("one").join(&name)).unwrap(),
            std::fs::read(dir.join("two").join(&name)).unwrap(),
            "{name:?}"
        );
        n += 1;
    }
    assert_eq!(n, 7); // 2 recipes × 3 radii + summary.csv
}

#[test]
fn lock_check_names_the_recipe_whose_default_changed() {
    let dir = tmp("lock");
    let text = std::fs::read_to_string(recipe("sphere.yaml")).unwrap();
    std::fs::write(dir.join("sphere.yaml"), &text).unwrap();
    std::fs::write(
        dir.join("other.yaml"),
        text.replace("name: sphere", "name: other"),
    )
    .unwrap();
    ok(&p3dp(
        &dir,
        &["hash", "--lock", "p3dp.lock", "sphere.yaml", "other.yaml"],
    ));
    let check = p3dp(&dir, &["hash", "--check", "p3dp.lock"]);
    ok(&check);
    let stdout = String::from_utf8_lossy(&check.stdout);
    // an unchanged lock says so in one line
    assert_eq!(stdout, "2 entries, unchanged\n");
    let sha = |name: &str| -> String {
        let lock = std::fs::read_to_string(dir.join("p3dp.lock")).unwrap();
        let at = lock.find(&format!("recipe: {name}")).unwrap();
        let line = lock[at..].lines().find(|l| l.contains("sha256: ")).unwrap();
        line.trim().trim_start_matches("sha256: ").to_string()
    };
    let old = sha("sphere.yaml");
    // change one param default of one recipe
    std::fs::write(
        dir.join("sphere.yaml"),
        text.replace("  lift: 0.4", "  lift: 0.5"),
    )
    .unwrap();
    let check = p3dp(&dir, &["hash", "--check", "p3dp.lock"]);
    assert_eq!(check.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&check.stdout);
    let stderr = String::from_utf8_lossy(&check.stderr);
    // only the entry that changed, with its old and new hashes whole
    // (issue 41)
    let new = String::from_utf8_lossy(&p3dp(&dir, &["hash", "sphere.yaml"]).stdout)
        .split_whitespace()
        .next()
        .unwrap()
        .to_string();
    assert_eq!((old.len(), new.len()), (64, 64));
    assert_eq!(
        stdout,
        format!("CHANGED  sphere.yaml\n         was {old}\n         now {new}\n2 entries: 1 changed, 1 unchanged\n")
    );
    assert!(
        stderr.contains(&format!("sha256 was {old}, now {new}")),
        "{stderr}"
    );
    assert!(
        stderr.contains("sphere.yaml") && !stderr.contains("other.yaml"),
        "{stderr}"
    );
    // it points at the first difference: the param comment in the header
    assert!(stderr.contains("lines 1–"), "{stderr}");
    // the changed param's line is quoted, not only the block's first line
    assert!(stderr.contains("`; param lift = 0.5`"), "{stderr}");
    assert!(stderr.contains("G-code changed"), "{stderr}");
}

#[test]
fn lock_keeps_set_values_and_points_at_the_exact_line_of_short_outputs() {
    let dir = tmp("lock-set");
    let text = "p3dp: 1\nname: ring\nparams:\n  size: 10\nparts:\n  - primitive: {circle: {radius: size, center: [0, 0, 0.2], segments: 36}}\n";
    std::fs::write(dir.join("ring.yaml"), text).unwrap();
    ok(&p3dp(
        &dir,
        &["hash", "--lock", "l.lock", "ring.yaml", "--set", "size=12"],
    ));
    let lock = std::fs::read_to_string(dir.join("l.lock")).unwrap();
    assert!(lock.contains("size=12"), "{lock}");
    ok(&p3dp(&dir, &["hash", "--check", "l.lock"]));
    std::fs::write(
        dir.join("ring.yaml"),
        text.replace("segments: 36", "segments: 37"),
    )
    .unwrap();
    let check = p3dp(&dir, &["hash", "--check", "l.lock"]);
    assert_eq!(check.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&check.stderr);
    // fewer than 512 lines: one line per block, so the exact line is named
    assert!(stderr.contains("first differing line"), "{stderr}");
}

#[test]
fn batch_lines_count_findings_by_severity() {
    // the pine tree's branch loops bridge short gaps: notes, not warnings
    let dir = tmp("batch-severity");
    let (pine, cup) = (recipe("pine-tree.yaml"), recipe("cup.yaml"));
    let out = p3dp(
        &dir,
        &[
            "build",
            pine.to_str().unwrap(),
            cup.to_str().unwrap(),
            "-o",
            "out/",
        ],
    );
    ok(&out);
    let report = String::from_utf8_lossy(&out.stdout);
    let line = |name: &str| {
        report
            .lines()
            .find(|l| l.contains(name))
            .unwrap()
            .to_string()
    };
    assert!(
        line("pine-tree.yaml").contains(", 0 warnings, 0 errors, 1 note, sha256"),
        "{report}"
    );
    assert!(
        line("cup.yaml").contains(", 0 warnings, 0 errors, sha256"),
        "{report}"
    );
}

#[test]
fn lock_keeps_the_printer_and_paths_outside_its_folder() {
    let dir = tmp("lock-printer");
    std::fs::create_dir_all(dir.join("ci")).unwrap();
    // a repository: the lock in ci/ may name the project's files above it
    std::fs::create_dir_all(dir.join(".git")).unwrap();
    let text = "p3dp: 1\nname: ring\nparts:\n  - primitive: {circle: {radius: 10, center: [0, 0, 0.2], segments: 36}}\n";
    std::fs::write(dir.join("ring.yaml"), text).unwrap();
    std::fs::write(
        dir.join("mine.yaml"),
        "inherits: prusa-mk4\nname: mine\nnozzle_diameter: 0.6\n",
    )
    .unwrap();
    for (n, (printer, want)) in [
        ("voron-350", "printer: voron-350"),
        ("mine.yaml", "printer: ../mine.yaml"),
    ]
    .into_iter()
    .enumerate()
    {
        let args = [
            "hash",
            "--lock",
            "ci/l.lock",
            "ring.yaml",
            "--printer",
            printer,
        ];
        ok(&p3dp(&dir, &args));
        let lock = std::fs::read_to_string(dir.join("ci/l.lock")).unwrap();
        assert!(lock.contains("recipe: ../ring.yaml"), "{lock}");
        assert!(lock.contains(want), "{lock}");
        // the hash is that of the build for that printer, not the recipe's own
        let own = p3dp(&dir, &["hash", "ring.yaml"]);
        let own = String::from_utf8_lossy(&own.stdout)
            .split_whitespace()
            .next()
            .unwrap()
            .to_string();
        assert!(
            !lock.contains(&own),
            "{printer}: the lock has the recipe's own printer's hash"
        );
        // checked from anywhere, the entry is rebuilt for the same printer
        let check = p3dp(&dir.join("ci"), &["hash", "--check", "l.lock"]);
        ok(&check);
        let stdout = String::from_utf8_lossy(&check.stdout);
        // the second printer's entry joins the first's
        let entries = ["1 entry", "2 entries"][n];
        assert_eq!(stdout, format!("{entries}, unchanged\n"));
    }
}

#[test]
fn the_projects_recipes_match_the_committed_lock() {
    let out = p3dp(&root(), &["hash", "--check", "p3dp.lock"]);
    assert!(
        out.status.success(),
        "recipes changed output; if intended, run `p3dp hash --lock p3dp.lock recipes/*.yaml` and say why in the commit\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    // every recipe of recipes/ is in the lock
    let lock = std::fs::read_to_string(root().join("p3dp.lock")).unwrap();
    for e in std::fs::read_dir(root().join("recipes")).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().to_string();
        if name.ends_with(".yaml") {
            assert!(
                lock.contains(&format!("recipe: recipes/{name}")),
                "{name} is not locked"
            );
        }
    }
}

#[test]
fn example_script_makes_the_same_files_as_the_sweep() {
    let dir = tmp("example-script");
    let script = root().join("examples/plate-variants.sh");
    let out = std::process::Command::new("bash")
        .arg(&script)
        .arg(dir.join("loop"))
        .env("P3DP", env!("CARGO_BIN_EXE_p3dp"))
        .env("CYCLES", "3 4")
        .env("AMPLITUDES", "1 1.5")
        .output()
        .unwrap();
    ok(&out);
    let plate = recipe("plate.yaml");
    ok(&p3dp(
        &dir,
        &[
            "build",
            plate.to_str().unwrap(),
            "--sweep",
            "cycles=3,4",
            "--sweep",
            "amplitude=1..1.5:0.5",
            "-o",
            "sweep",
        ],
    ));
    for c in ["3", "4"] {
        for a in ["1", "1.5"] {
            let name = format!("plate_cycles-{c}_amplitude-{a}.gcode");
            let (l, s) = (dir.join("loop").join(&name), dir.join("sweep").join(&name));
            assert!(
                std::fs::read(&l).unwrap() == std::fs::read(&s).unwrap(),
                "{name} differs"
            );
        }
    }
}

/// `check --sweep` keeps no variant's plan once it is checked (each was kept
/// until the end, so the peak grew with the variants); the lines come out
/// in the variants' order all the same.
#[test]
fn a_checked_sweep_lets_each_variant_go() {
    let dir = tmp("sweep-memory");
    std::fs::write(
        dir.join("big.yaml"),
        "p3dp: 1\nname: big\nprinter: generic-220\nmaterial: pla\nparams: {rad: 10}\nparts:\n  - primitive:\n      helix: { radius: rad, height: 30, pitch: 0.2 }\n",
    )
    .unwrap();
    let (out, peak) = p3dp_peak(
        &dir,
        &[
            "check",
            "big.yaml",
            "--sweep",
            "rad=10..10.299:0.001",
            "-j",
            "2",
        ],
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let labels: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("big.yaml ["))
        .collect();
    assert_eq!(labels.len(), 300, "{text}");
    assert!(labels[0].starts_with("big.yaml [rad=10]:"), "{}", labels[0]);
    assert!(
        labels[299].starts_with("big.yaml [rad=10.299]:"),
        "{}",
        labels[299]
    );
    assert!(peak > 0 && peak < 60_000, "peak {peak} kB");
}
