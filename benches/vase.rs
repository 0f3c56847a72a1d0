//! Benchmark of issue 2: build the 2,000,000-string vase of `benches/vase-2m.yaml`
//! (recipe → strings → deform_cylinder → checks → G-code written to a file),
//! several times, and report wall time and peak memory.
//!
//!     cargo bench --bench vase
//!
//! Targets on the project's 2-core machine: under 1.5 s wall and under 300 MB
//! peak resident memory per build, release build.

use std::path::Path;
use std::time::Instant;

use p3dp::threads::Threads;

fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn main() {
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/vase-2m.yaml");
    let out = std::env::temp_dir().join(format!("p3dp-bench-vase-{}.gcode", std::process::id()));
    let runs = 5;
    let mut times = Vec::new();
    let mut hashes = Vec::new();
    let mut strings = 0;
    for _ in 0..runs {
        let t0 = Instant::now();
        let plan = p3dp::build::plan(&recipe, &p3dp::build::Options::default()).expect("plan");
        strings = plan.paths.iter().map(|p| p.len()).sum::<usize>();
        let file = std::fs::File::create(&out).expect("temp file");
        let stats = plan.render(file).expect("render");
        drop(plan);
        times.push(t0.elapsed().as_secs_f64());
        hashes.push(stats.gcode_sha256);
    }
    let _ = std::fs::remove_file(&out);
    assert!(
        hashes.windows(2).all(|w| w[0] == w[1]),
        "output not deterministic"
    );
    times.sort_by(f64::total_cmp);
    let median = times[runs / 2];
    let peak = peak_rss_mb().map_or("unknown".to_string(), |m| format!("{m:.0} MB"));
    println!("vase-2m: {strings} strings, {runs} builds");
    println!(
        "  wall: min {:.3} s, median {median:.3} s (target < 1.5 s)",
        times[0]
    );
    println!("  peak resident memory: {peak} (target < 300 MB)");
    println!("  sha256 {}", hashes[0]);
    checks_against_generation(&recipe, runs);
}

/// Issue 7: the support and collision checks on the same vase must take less
/// time than generating its strings (primitive and steps).
fn checks_against_generation(path: &Path, runs: usize) {
    let recipe = p3dp::recipe::Recipe::load(path, &[], None).expect("recipe");
    let (mut gen, mut sup, mut col) = (Vec::new(), Vec::new(), Vec::new());
    let mut found = 0;
    for _ in 0..runs {
        let t0 = Instant::now();
        let part = p3dp::build::make_part(&recipe, 0, Threads::available()).expect("part");
        gen.push(t0.elapsed().as_secs_f64());
        let refs = [&part];
        let mut out = Vec::new();
        let t1 = Instant::now();
        p3dp::check::support::check(&recipe, &refs, &mut out);
        sup.push(t1.elapsed().as_secs_f64());
        let t2 = Instant::now();
        p3dp::check::collision::check(&recipe, &refs, &mut out);
        col.push(t2.elapsed().as_secs_f64());
        found = out.len();
    }
    for v in [&mut gen, &mut sup, &mut col] {
        v.sort_by(f64::total_cmp);
    }
    let (g, s, c) = (gen[runs / 2], sup[runs / 2], col[runs / 2]);
    println!("  checks (median of {runs}): generating the strings {g:.3} s; support {s:.3} s, collision {c:.3} s ({found} findings)");
    println!(
        "  support + collision = {:.0} % of generation (target < 100 %)",
        100.0 * (s + c) / g
    );
}
