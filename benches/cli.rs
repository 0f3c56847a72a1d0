//! The sphere (`recipes/sphere.yaml`, 59k points) and the 2,000,000-string
//! vase (`benches/vase-2m.yaml`) built through the release binary as a user
//! runs it, a fresh process per run: wall, CPU and peak memory per thread
//! budget; every run of a case must write the same bytes. Then a batch:
//! `check --sweep` of 10,000 variants of a 2 mm helix
//! (`benches/sweep-helix.yaml`), and a `check` of 49 million strings
//! (`benches/check-49m.yaml`): its peak memory against the budget.
//!
//!     cargo bench --bench cli
//!     P3DP_BASELINE=/path/to/older/p3dp cargo bench --bench cli
//!
//! With `P3DP_BASELINE` the older binary runs the same cases, alternately
//! with this one, and the ratio of the medians is printed (figures and
//! targets: docs/performance.md).

mod common;

use std::path::Path;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let sphere = root.join("recipes/sphere.yaml");
    let vase = root.join("benches/vase-2m.yaml");
    // the outputs in a folder of their own, as a project's: a build sweeps
    // its output folder of stale temp files
    let dir = std::env::temp_dir().join(format!("p3dp-bench-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a folder for the outputs");
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("{cores} cores");
    for (name, recipe, jobs, runs) in [
        ("sphere", &sphere, "2", 41),
        ("sphere", &sphere, "1", 21),
        ("vase-2m", &vase, "2", 9),
        ("vase-2m", &vase, "1", 5),
    ] {
        let out = dir.join(format!("{name}.gcode"));
        let first = std::cell::RefCell::new(std::collections::HashMap::new());
        common::compare(
            &format!("{name} -j {jobs}"),
            &[
                "build",
                recipe.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "-j",
                jobs,
            ],
            &dir,
            runs,
            // a new file each run: replacing an existing big file costs
            // the file system its old pages inside the rename
            || {
                let _ = std::fs::remove_file(&out);
            },
            |bin| {
                let bytes = std::fs::read(&out).expect("the G-code");
                let mut seen = first.borrow_mut();
                let f = seen.entry(bin.to_string()).or_insert_with(|| bytes.clone());
                assert!(
                    *f == bytes,
                    "{name} [{bin}]: not the same bytes on every run"
                );
            },
        );
    }
    // a batch: 10,000 variants of a 2 mm helix checked (target: 20 s on
    // 2 cores, issue 42)
    let sweep = root.join("benches/sweep-helix.yaml");
    common::compare(
        "check --sweep b=1..10000",
        &["check", sweep.to_str().unwrap(), "--sweep", "b=1..10000"],
        &dir,
        3,
        || {},
        |_| {},
    );
    // 49 million strings checked: the memory budget (issue 42: 1.5 GB;
    // figures in docs/performance.md)
    let big = root.join("benches/check-49m.yaml");
    common::compare(
        "check of 49M strings",
        &["check", big.to_str().unwrap()],
        &dir,
        1,
        || {},
        |_| {},
    );
    let _ = std::fs::remove_dir_all(&dir);
}
