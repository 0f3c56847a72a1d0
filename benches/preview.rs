//! Benchmark of issue 21: the previews of the 2,000,000-string vase of
//! `benches/vase-2m.yaml`, PNG and HTML, each through the release binary as a
//! user runs it (a fresh process per run, so each peak of resident memory is
//! that run's own), several times; reports the wall median and the peak RSS.
//!
//!     cargo bench --bench preview
//!
//! The same from the command line, one run:
//!
//!     /usr/bin/time -v target/release/p3dp preview benches/vase-2m.yaml -o /tmp/vase.png
//!     /usr/bin/time -v target/release/p3dp preview benches/vase-2m.yaml -o /tmp/vase.html
//!
//! Targets on the project's 2-core machine: the PNG in 1 s and 250 MB, the
//! HTML viewer in 1.5 s.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// One run under /usr/bin/time -f "%e %M": wall s and peak RSS MB.
fn run(bin: &Path, recipe: &Path, out: &Path) -> (f64, Option<f64>, Vec<u8>) {
    let t0 = Instant::now();
    let timed = Path::new("/usr/bin/time").is_file();
    let output = if timed {
        Command::new("/usr/bin/time")
            .args(["-f", "P3DP-RSS %M"])
            .arg(bin)
            .arg("preview")
            .arg(recipe)
            .arg("-o")
            .arg(out)
            .output()
    } else {
        Command::new(bin)
            .arg("preview")
            .arg(recipe)
            .arg("-o")
            .arg(out)
            .output()
    }
    .expect("run p3dp");
    let wall = t0.elapsed().as_secs_f64();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let err = String::from_utf8_lossy(&output.stderr);
    let rss = err
        .lines()
        .find_map(|l| l.strip_prefix("P3DP-RSS "))
        .and_then(|kb| kb.trim().parse::<f64>().ok())
        .map(|kb| kb / 1024.0);
    (wall, rss, std::fs::read(out).expect("the preview"))
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let recipe = root.join("benches/vase-2m.yaml");
    // cargo builds the binary for its benches, in the same profile
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_p3dp"));
    let runs = 5;
    for (ext, wall_target, mem_target) in [("png", 1.0, Some(250.0)), ("html", 1.5, None)] {
        let out =
            std::env::temp_dir().join(format!("p3dp-bench-preview-{}.{ext}", std::process::id()));
        let mut walls = Vec::new();
        let mut peak: Option<f64> = None;
        let mut first: Option<Vec<u8>> = None;
        for _ in 0..runs {
            let (wall, rss, bytes) = run(&bin, &recipe, &out);
            walls.push(wall);
            peak = match (peak, rss) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
            match &first {
                None => first = Some(bytes),
                Some(f) => assert!(*f == bytes, "{ext}: output not deterministic"),
            }
        }
        let _ = std::fs::remove_file(&out);
        walls.sort_by(f64::total_cmp);
        let median = walls[runs / 2];
        let size = first.map_or(0, |b| b.len());
        println!(
            "vase-2m preview → {ext}: {runs} runs, {} kB",
            (size + 512) / 1024
        );
        println!(
            "  wall: min {:.3} s, median {median:.3} s (target ≤ {wall_target} s)",
            walls[0]
        );
        let peak = peak.map_or("unknown (no /usr/bin/time)".to_string(), |m| {
            format!("{m:.0} MB")
        });
        match mem_target {
            Some(t) => println!("  peak resident memory: {peak} (target ≤ {t} MB)"),
            None => println!("  peak resident memory: {peak}"),
        }
    }
}
