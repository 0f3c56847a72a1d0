//! What the command-line benches share: a command timed as a whole process
//! (wall, CPU and peak memory from `/usr/bin/time` when there is one), and
//! the same command run by a second binary, alternately, when
//! `P3DP_BASELINE=/path/to/an/older/p3dp` is set, so the two are measured in
//! the same minutes (this machine's speed drifts over a day).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// One run's figures.
pub struct Run {
    /// Wall time, s.
    pub wall: f64,
    /// Peak resident memory, MB.
    pub rss: Option<f64>,
    /// User + system CPU time, s.
    pub cpu: Option<f64>,
}

/// The binaries to time: this build's, and the baseline when asked for.
pub fn binaries() -> Vec<(String, PathBuf)> {
    let mut v = vec![(
        "this".to_string(),
        PathBuf::from(env!("CARGO_BIN_EXE_p3dp")),
    )];
    if let Some(b) = std::env::var_os("P3DP_BASELINE") {
        v.push(("baseline".to_string(), PathBuf::from(b)));
    }
    v
}

/// Runs `bin ARGS` in `dir` once, timed; panics with its error output when
/// it fails.
pub fn run(bin: &Path, args: &[&str], dir: &Path) -> Run {
    let timed = Path::new("/usr/bin/time").is_file();
    let mut cmd = if timed {
        let mut c = Command::new("/usr/bin/time");
        c.args(["-f", "P3DP-RUN %M %U %S"]).arg(bin);
        c
    } else {
        Command::new(bin)
    };
    cmd.args(args).current_dir(dir);
    let t0 = Instant::now();
    let output = cmd.output().expect("run p3dp");
    let wall = t0.elapsed().as_secs_f64();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let err = String::from_utf8_lossy(&output.stderr);
    let fields: Vec<f64> = err
        .lines()
        .find_map(|l| l.strip_prefix("P3DP-RUN "))
        .map(|l| {
            l.split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect()
        })
        .unwrap_or_default();
    Run {
        wall,
        rss: fields.first().map(|kb| kb / 1024.0),
        cpu: (fields.len() == 3).then(|| fields[1] + fields[2]),
    }
}

/// The median of `v` (sorted in place).
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Times `args` `runs` times with each binary, alternately (after one
/// untimed run each, for the page cache), `prepare` run before every run
/// (untimed: removing the last output, say), and `check` given each run's
/// output folder after it (the bytes must be the same on every run); prints
/// a line per binary and, with a baseline, the ratio of the medians.
pub fn compare(
    label: &str,
    args: &[&str],
    dir: &Path,
    runs: usize,
    prepare: impl Fn(),
    check: impl Fn(&str),
) {
    let bins = binaries();
    for (_, b) in &bins {
        prepare();
        run(b, args, dir);
    }
    let mut walls = vec![Vec::new(); bins.len()];
    let mut cpus = vec![Vec::new(); bins.len()];
    let mut peaks = vec![0.0f64; bins.len()];
    for _ in 0..runs {
        for (k, (name, b)) in bins.iter().enumerate() {
            prepare();
            let r = run(b, args, dir);
            walls[k].push(r.wall);
            cpus[k].extend(r.cpu);
            peaks[k] = peaks[k].max(r.rss.unwrap_or(0.0));
            check(name);
        }
    }
    let mut medians = Vec::new();
    for (k, (name, _)) in bins.iter().enumerate() {
        let m = median(&mut walls[k]);
        medians.push(m);
        let cpu = if cpus[k].is_empty() {
            String::new()
        } else {
            format!(", CPU median {:.1} ms", 1e3 * median(&mut cpus[k]))
        };
        let mem = if peaks[k] > 0.0 {
            format!(", peak {:.0} MB", peaks[k])
        } else {
            String::new()
        };
        println!(
            "{label} [{name}]: median {:.1} ms, fastest {:.1} ms over {runs} runs{cpu}{mem}",
            1e3 * m,
            1e3 * walls[k][0]
        );
    }
    if medians.len() == 2 {
        println!("{label}: this / baseline = {:.3}", medians[0] / medians[1]);
    }
}
