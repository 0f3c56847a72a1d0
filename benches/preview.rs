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
//! HTML viewer in 1.5 s. With more than one thread a preview keeps both
//! cores busy nearly throughout, so its wall time on a quiet machine is
//! about its CPU time over two; the CPU time is printed too, as it moves
//! far less than the wall time when the machine is loaded.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// One run's figures: wall s, peak RSS MB and CPU s (user + system; both
/// from /usr/bin/time, when there is one).
struct Run {
    wall: f64,
    rss: Option<f64>,
    cpu: Option<f64>,
}

/// One run under /usr/bin/time, and the preview it wrote.
fn run(bin: &Path, recipe: &Path, out: &Path) -> (Run, Vec<u8>) {
    let t0 = Instant::now();
    let timed = Path::new("/usr/bin/time").is_file();
    let output = if timed {
        Command::new("/usr/bin/time")
            .args(["-f", "P3DP-RSS %M %U %S"])
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
    let fields: Vec<f64> = err
        .lines()
        .find_map(|l| l.strip_prefix("P3DP-RSS "))
        .map(|l| {
            l.split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect()
        })
        .unwrap_or_default();
    let run = Run {
        wall,
        rss: fields.first().map(|kb| kb / 1024.0),
        cpu: (fields.len() == 3).then(|| fields[1] + fields[2]),
    };
    (run, std::fs::read(out).expect("the preview"))
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
        let mut cpus = Vec::new();
        let mut peak: Option<f64> = None;
        let mut first: Option<Vec<u8>> = None;
        for _ in 0..runs {
            let (Run { wall, rss, cpu }, bytes) = run(&bin, &recipe, &out);
            walls.push(wall);
            cpus.extend(cpu);
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
        // CPU time moves far less than wall time on a loaded machine
        cpus.sort_by(f64::total_cmp);
        if let Some(c) = cpus.get(cpus.len() / 2) {
            println!("  CPU (user + system): median {c:.2} s");
        }
        let peak = peak.map_or("unknown (no /usr/bin/time)".to_string(), |m| {
            format!("{m:.0} MB")
        });
        match mem_target {
            Some(t) => println!("  peak resident memory: {peak} (target ≤ {t} MB)"),
            None => println!("  peak resident memory: {peak}"),
        }
    }
}
