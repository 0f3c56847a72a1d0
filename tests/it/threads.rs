//! One thread budget: a build gives the same bytes whatever the pipeline's
//! pool (and `-j`) allows, on a vase large enough that its deform step is
//! split among threads.

use crate::common::*;
use p3dp::pipeline::{self, Threads};
use p3dp::testing::Insides;
use p3dp::{plan, prepare};

/// A scaled-down `benches/vase-2m.yaml`: 60 turns of 1000 strings, so the
/// deform step (60,000 points and strings) is well above `PAR_MIN` (8,192).
const VASE: &str = r#"p3dp: 1
name: vase-60k
printer: generic-220
material: pla
params:
  radius: 30
  height: 6
  lobes: 6
defaults:
  cross_section: 0.08
  speed: 40
parts:
  - name: vase
    primitive:
      helix: { radius: radius, height: height, pitch: 0.1, segments: 1000, center: [0, 0, 0.2] }
    steps:
      - deform_cylinder:
          position: ["r*(0.8 + 0.2*sin(pi*z/height)) + 2*sin(lobes*theta + z/20)", theta, z]
          cross_section: "c*(1.2 - 0.4*z/height)"
"#;

#[test]
fn the_vase_is_the_same_bytes_on_1_2_and_4_threads() {
    let dir = tmp("threads-vase");
    let path = dir.join("vase.yaml");
    std::fs::write(&path, VASE).unwrap();
    let build = |n: usize| {
        pipeline::run(Threads::new(n), || {
            let mut p = plan(&path, &Default::default()).unwrap();
            assert!(p.paths().iter().map(|t| t.len()).sum::<usize>() > 50_000);
            let mut out = Vec::new();
            let stats = pipeline::write(&mut p, &hashed(None), &mut out)
                .unwrap()
                .stats;
            (out, stats)
        })
    };
    // the pipelined build: checks beside the writer (two threads: the
    // planner between checks; four: a thread of its own)
    let piped = |n: usize| {
        pipeline::run(Threads::new(n), || {
            let mut p = prepare(&path, &Default::default()).unwrap();
            let mut out = Vec::new();
            let job = hashed(Some(pipeline::Stop::Never));
            let stats = pipeline::write(&mut p, &job, &mut out).unwrap().stats;
            (out, stats)
        })
    };
    let one = build(1);
    assert!(
        one.0.len() > 1_000_000,
        "a real build: {} bytes",
        one.0.len()
    );
    for n in [1, 2, 4] {
        for (how, other) in [("plan + render", build(n)), ("check_and_render", piped(n))] {
            assert!(one.0 == other.0, "{how} on {n} threads changed the G-code");
            // the whole stats: hash, moves, times, findings, footprints
            assert_eq!(one.1, other.1, "{how} on {n} threads changed the stats");
        }
    }
    // and through the binary: -j 1, 2 and 4 write the same G-code and stats
    let built = |j: &str| {
        let (g, s) = (format!("vase-{j}.gcode"), format!("vase-{j}.json"));
        let o = p3dp(
            &dir,
            &["build", "-j", j, "vase.yaml", "-o", &g, "--stats-json", &s],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let g = std::fs::read(dir.join(g)).unwrap();
        let s = std::fs::read_to_string(dir.join(s)).unwrap();
        (g, s)
    };
    let j1 = built("1");
    assert!(j1.0 == one.0, "the binary writes what the library renders");
    for j in ["2", "4"] {
        let other = built(j);
        assert!(j1.0 == other.0, "-j {j} changed the G-code");
        assert_eq!(j1.1, other.1, "-j {j} changed the stats");
    }
    let hash = |j: &str| {
        let o = p3dp(&dir, &["hash", "-j", j, "vase.yaml"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap()
    };
    assert_eq!(hash("1"), hash("4"));
    assert!(hash("2").starts_with(&one.1.gcode_sha256));
}

/// The G-code is written while the checks run, to a temp file: a check that
/// fails must still leave nothing behind, on any thread count, and the error
/// is the check's.
#[test]
fn a_failed_check_writes_nothing_whatever_the_threads() {
    let dir = tmp("threads-vase-fails");
    // 60 turns up to z = 300: above the printer's 250 mm
    let tall = VASE
        .replace("height: 6", "height: 300")
        .replace("pitch: 0.1", "pitch: 5");
    std::fs::write(dir.join("tall.yaml"), tall).unwrap();
    for j in ["1", "2", "4"] {
        let o = p3dp(&dir, &["build", "-j", j, "tall.yaml", "-o", "tall.gcode"]);
        assert_eq!(o.status.code(), Some(1), "-j {j}: a failed check");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("above-max-z"), "-j {j}: {err}");
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(left, ["tall.yaml"], "-j {j} left files behind");
    }
}

/// A build the checks refuse gives up writing (`pipeline::check_and_write`):
/// on one thread nothing is written at all; on more, the writer stops once
/// the checks have failed, or (when it was quicker) has written the whole
/// G-code, never a prefix passed off as done; the findings are the same.
#[test]
fn a_refused_build_stops_writing_and_keeps_its_findings() {
    let dir = tmp("threads-vase-stops");
    let tall = VASE
        .replace("height: 6", "height: 300")
        .replace("pitch: 0.1", "pitch: 5");
    let path = dir.join("tall.yaml");
    std::fs::write(&path, tall).unwrap();
    let prepared = || prepare(&path, &Default::default()).unwrap();
    // the whole G-code, as `--force` writes it
    let mut forced = prepared();
    let mut full = Vec::new();
    pipeline::run(Threads::new(2), || {
        pipeline::write(&mut forced, &hashed(Some(pipeline::Stop::Never)), &mut full).unwrap();
    });
    assert!(!forced.failing(false).is_empty(), "the tall vase fails");
    assert!(full.len() > 100_000);
    for n in [1, 2, 4] {
        let mut p = prepared();
        let mut out = Vec::new();
        let r = pipeline::run(Threads::new(n), || {
            let job = hashed(Some(pipeline::Stop::Failing { strict: false }));
            pipeline::write(&mut p, &job, &mut out).map(|w| w.stats)
        });
        assert_eq!(p.findings, forced.findings, "{n} threads: other findings");
        match r {
            Err(e) => assert!(e.to_string().contains("stopped"), "{n} threads: {e}"),
            Ok(_) => assert!(out == full, "{n} threads: a prefix passed off as done"),
        }
        if n == 1 {
            assert!(out.is_empty(), "one thread: checks first, nothing written");
        }
        assert!(out.len() <= full.len() && full.starts_with(&out));
    }
}

/// The costly checks are tasks any thread may take (`pipeline`): on
/// every recipe of `tests/checks/` (a finding of each kind), 1 to 4 threads
/// give the same findings in the same order, the same footprints and the
/// same G-code (written whatever the checks say, as `--force` does).
#[test]
fn the_checks_find_the_same_whichever_thread_runs_them() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/checks");
    let mut recipes: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    recipes.sort();
    assert!(recipes.len() >= 10, "the check recipes are there");
    let mut kinds = std::collections::BTreeSet::new();
    for path in &recipes {
        let run = |n: usize| {
            pipeline::run(Threads::new(n), || {
                let mut p = prepare(path, &Default::default()).unwrap();
                let mut out = Vec::new();
                let job = hashed(Some(pipeline::Stop::Never));
                pipeline::write(&mut p, &job, &mut out).unwrap();
                (p.findings.clone(), p.footprints().to_vec(), out)
            })
        };
        let one = run(1);
        kinds.extend(one.0.iter().map(|f| f.code));
        for n in [2, 3, 4] {
            let other = run(n);
            let name = path.display();
            assert_eq!(one.0, other.0, "{name}: other findings on {n} threads");
            assert_eq!(one.1, other.1, "{name}: other footprints on {n} threads");
            assert!(one.2 == other.2, "{name}: other G-code on {n} threads");
        }
    }
    // the costly checks' own findings are among them
    for code in [
        "unsupported",
        "bridge",
        "nozzle-collision",
        "first-layer",
        "starvation",
    ] {
        assert!(
            kinds.contains(code),
            "no `{code}` finding in tests/checks: {kinds:?}"
        );
    }
}

/// A hashed build, checked (stopping as `stop` says) or not.
fn hashed(stop: Option<pipeline::Stop>) -> pipeline::Job<'static> {
    pipeline::Job {
        check: stop.map(|s| (&[][..], s)),
        hash: true,
        ..Default::default()
    }
}
