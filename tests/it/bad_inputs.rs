//! Broken recipes fail cleanly: the right exit status, an error naming the
//! file and the place in it, no panic, and nothing written.
//!
//! Every `tests/bad/*.yaml` starts with a `#` line saying what is wrong and
//! carries a line
//!
//! ```text
//! # expect: exit=N place=SUBSTRING
//! ```
//!
//! where `N` is the exit status (2 unusable input, 1 a failed check) and
//! `SUBSTRING` (the rest of the line) must appear in standard error: a key path
//! like `parts[0].primitive.helix.pitch` or a line like `:4:`.
//!
//! Set `P3DP_BAD=word` to run only the corpus files whose name contains `word`.

use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_p3dp");
/// A broken recipe must fail fast; a hang is a failure too.
const TIMEOUT: Duration = Duration::from_secs(120);

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn corpus_dir() -> PathBuf {
    root().join("tests").join("bad")
}

/// A fresh, empty folder under the system temp dir, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::SeqCst);
        let safe: String = tag
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        let dir =
            std::env::temp_dir().join(format!("p3dp-bad-inputs-{}-{n}-{safe}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).expect("create a temp dir");
        TempDir(dir)
    }

    fn sub(&self, name: &str) -> PathBuf {
        let d = self.0.join(name);
        fs::create_dir_all(&d).expect("create a temp sub dir");
        d
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

struct Run {
    status: Option<ExitStatus>,
    stdout: String,
    stderr: String,
    timed_out: bool,
}

impl Run {
    fn code(&self) -> Option<i32> {
        self.status.and_then(|s| s.code())
    }

    fn describe(&self) -> String {
        format!(
            "status {}{}\n--- stderr ---\n{}\n--- stdout ---\n{}",
            match self.status {
                Some(s) => s.to_string(),
                None => "none".into(),
            },
            if self.timed_out {
                format!(" (killed after {TIMEOUT:?})")
            } else {
                String::new()
            },
            self.stderr.trim_end(),
            self.stdout.trim_end()
        )
    }
}

/// Runs `p3dp ARGS` in `cwd`, killing it after [`TIMEOUT`].
fn p3dp(cwd: &Path, args: &[&str]) -> Run {
    let mut child = Command::new(BIN)
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run p3dp");
    let drain = |r: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            if let Some(mut r) = r {
                let _ = r.read_to_end(&mut buf);
            }
            String::from_utf8_lossy(&buf).into_owned()
        })
    };
    let out = drain(
        child
            .stdout
            .take()
            .map(|r| Box::new(r) as Box<dyn Read + Send>),
    );
    let err = drain(
        child
            .stderr
            .take()
            .map(|r| Box::new(r) as Box<dyn Read + Send>),
    );
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        match child.try_wait().expect("wait for p3dp") {
            Some(s) => break Some(s),
            None if start.elapsed() > TIMEOUT => {
                timed_out = true;
                let _ = child.kill();
                break child.wait().ok();
            }
            None => std::thread::sleep(Duration::from_millis(20)),
        }
    };
    Run {
        status,
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
        timed_out,
    }
}

/// Every file (not folder) under `dir`, recursively, relative to `dir`.
fn files_under(dir: &Path) -> Vec<String> {
    fn walk(base: &Path, dir: &Path, out: &mut Vec<String>) {
        let Ok(entries) = fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(base, &p, out);
            } else {
                out.push(p.strip_prefix(base).unwrap_or(&p).display().to_string());
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// Every entry (file or folder) directly in `dir`.
fn entries_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[derive(Debug)]
struct Expect {
    exit: i32,
    place: String,
}

/// Reads the leading comment and the `# expect: exit=N place=SUBSTRING` line.
fn expectation(text: &str) -> Result<Expect, String> {
    let first = text.lines().next().unwrap_or("");
    if !first.starts_with('#') || first.trim_start_matches('#').trim().is_empty() {
        return Err("the first line must be a `#` comment saying what is wrong".into());
    }
    let line = text
        .lines()
        .take_while(|l| l.starts_with('#'))
        .find_map(|l| l.trim_start_matches('#').trim().strip_prefix("expect:"))
        .ok_or("no `# expect: exit=N place=SUBSTRING` line in the leading comments")?
        .trim();
    let rest = line
        .strip_prefix("exit=")
        .ok_or("the expect line must start with `exit=`")?;
    let (n, rest) = rest
        .split_once(' ')
        .ok_or("expected ` place=` after the exit status")?;
    let exit = n
        .parse()
        .map_err(|_| format!("`{n}` is not an exit status"))?;
    let place = rest
        .trim_start()
        .strip_prefix("place=")
        .ok_or("expected `place=SUBSTRING` after the exit status")?
        .trim()
        .to_string();
    if place.is_empty() {
        return Err("`place=` is empty".into());
    }
    Ok(Expect { exit, place })
}

fn corpus() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = fs::read_dir(corpus_dir())
        .expect("read tests/bad")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    files.sort();
    files
}

/// Builds one corpus file; returns what is wrong with the outcome, if anything.
fn check_case(path: &Path) -> Result<(), String> {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let text = fs::read_to_string(path).map_err(|e| format!("cannot read: {e}"))?;
    let want = expectation(&text)?;
    let tmp = TempDir::new(&name);
    let cwd = tmp.sub("cwd");
    let out = tmp.sub("out");
    let gcode = out.join("out.gcode");
    let stats = out.join("s.json");
    let run = p3dp(
        &cwd,
        &[
            "build",
            path.to_str().unwrap(),
            "-o",
            gcode.to_str().unwrap(),
            "--stats-json",
            stats.to_str().unwrap(),
        ],
    );
    let mut problems = Vec::new();
    if run.timed_out {
        problems.push(format!("did not finish within {TIMEOUT:?}"));
    }
    if run.code() != Some(want.exit) {
        problems.push(format!(
            "exit status {:?}, expected {}",
            run.code(),
            want.exit
        ));
    }
    if run.stderr.contains("panicked") {
        problems.push("p3dp panicked".into());
    }
    if !run.stderr.contains(&name) {
        problems.push(format!("stderr does not name the file `{name}`"));
    }
    if !run.stderr.contains(&want.place) {
        problems.push(format!("stderr does not name the place `{}`", want.place));
    }
    let left = files_under(&out);
    if !left.is_empty() {
        problems.push(format!("files left in the output folder: {left:?}"));
    }
    let left = files_under(&cwd);
    if !left.is_empty() {
        problems.push(format!("files left in the current folder: {left:?}"));
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{}\ncommand: cd {} && {BIN} build {} -o {} --stats-json {}\n{}",
            problems.join("; "),
            cwd.display(),
            path.display(),
            gcode.display(),
            stats.display(),
            run.describe()
        ))
    }
}

#[test]
fn corpus_has_at_least_15_recipes_each_with_an_expectation() {
    let files = corpus();
    assert!(
        files.len() >= 15,
        "tests/bad holds {} recipes, expected at least 15",
        files.len()
    );
    for f in &files {
        let text = fs::read_to_string(f).unwrap();
        let e = expectation(&text).unwrap_or_else(|m| panic!("{}: {m}", f.display()));
        assert!(
            e.exit == 1 || e.exit == 2,
            "{}: a broken recipe exits 1 or 2, not {}",
            f.display(),
            e.exit
        );
    }
}

#[test]
fn every_bad_recipe_fails_cleanly_and_writes_nothing() {
    let only = std::env::var("P3DP_BAD").ok();
    let files: Vec<PathBuf> = corpus()
        .into_iter()
        .filter(|f| {
            only.as_deref()
                .is_none_or(|w| f.file_name().unwrap().to_string_lossy().contains(w))
        })
        .collect();
    assert!(
        !files.is_empty(),
        "no corpus file matches P3DP_BAD={only:?}"
    );
    let mut failures = Vec::new();
    for f in &files {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        match check_case(f) {
            Ok(()) => println!("ok      {name}"),
            Err(m) => {
                println!("FAILED  {name}");
                failures.push(format!("=== {name}: {m}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} bad recipes were not refused cleanly:\n\n{}",
        failures.len(),
        files.len(),
        failures.join("\n\n")
    );
}

/// The harness's own control: the same command line on a good recipe does
/// write both files, so "nothing written" above means something.
#[test]
fn control_good_recipe_writes_gcode_and_stats() {
    let tmp = TempDir::new("control");
    let cwd = tmp.sub("cwd");
    let out = tmp.sub("out");
    let recipe = root().join("recipes").join("sphere.yaml");
    let run = p3dp(
        &cwd,
        &[
            "build",
            recipe.to_str().unwrap(),
            "-o",
            out.join("out.gcode").to_str().unwrap(),
            "--stats-json",
            out.join("s.json").to_str().unwrap(),
        ],
    );
    assert_eq!(run.code(), Some(0), "{}", run.describe());
    assert_eq!(files_under(&out), ["out.gcode", "s.json"]);
    assert!(files_under(&cwd).is_empty(), "{:?}", files_under(&cwd));
}

#[test]
fn unknown_set_param_exits_2_naming_the_flag() {
    let tmp = TempDir::new("set-nosuch");
    let cwd = tmp.sub("cwd");
    let out = tmp.sub("out");
    let recipe = root().join("recipes").join("sphere.yaml");
    let run = p3dp(
        &cwd,
        &[
            "build",
            recipe.to_str().unwrap(),
            "--set",
            "nosuch=3",
            "-o",
            out.join("out.gcode").to_str().unwrap(),
            "--stats-json",
            out.join("s.json").to_str().unwrap(),
        ],
    );
    assert_eq!(run.code(), Some(2), "{}", run.describe());
    assert!(run.stderr.contains("--set nosuch=3"), "{}", run.describe());
    assert!(run.stderr.contains("sphere.yaml"), "{}", run.describe());
    assert!(!run.stderr.contains("panicked"), "{}", run.describe());
    assert!(files_under(&out).is_empty(), "{:?}", files_under(&out));
    assert!(files_under(&cwd).is_empty(), "{:?}", files_under(&cwd));
}

#[test]
fn failed_build_into_a_missing_nested_folder_writes_no_file() {
    let tmp = TempDir::new("nested");
    let cwd = tmp.sub("cwd");
    let out = tmp.sub("out");
    let recipe = corpus_dir().join("zero-pitch.yaml");
    // -o as a file in a missing folder, and as a missing folder (trailing /)
    let targets = [
        out.join("nested").join("deeper").join("out.gcode"),
        PathBuf::from(format!("{}/", out.join("nested2").join("deeper").display())),
    ];
    for target in &targets {
        let run = p3dp(
            &cwd,
            &[
                "build",
                recipe.to_str().unwrap(),
                "-o",
                target.to_str().unwrap(),
                "--stats-json",
                out.join("nested").join("s.json").to_str().unwrap(),
            ],
        );
        assert_eq!(
            run.code(),
            Some(2),
            "-o {}: {}",
            target.display(),
            run.describe()
        );
        assert!(run.stderr.contains("zero-pitch.yaml"), "{}", run.describe());
        assert!(
            run.stderr.contains("parts[0].primitive.helix.pitch"),
            "{}",
            run.describe()
        );
        assert!(!run.stderr.contains("panicked"), "{}", run.describe());
        assert!(
            files_under(&out).is_empty(),
            "-o {}: files left: {:?}",
            target.display(),
            files_under(&out)
        );
        assert!(files_under(&cwd).is_empty(), "{:?}", files_under(&cwd));
    }
}

/// A failed build should not create the output folder either: `-o DIR/`
/// names a folder, and nothing is written into it.
#[test]
fn failed_build_creates_no_output_folder() {
    let tmp = TempDir::new("nested-folder");
    let cwd = tmp.sub("cwd");
    let out = tmp.sub("out");
    let recipe = corpus_dir().join("zero-pitch.yaml");
    let target = format!("{}/", out.join("nested").join("deeper").display());
    let run = p3dp(&cwd, &["build", recipe.to_str().unwrap(), "-o", &target]);
    assert_eq!(run.code(), Some(2), "{}", run.describe());
    assert!(
        entries_in(&out).is_empty(),
        "a failed build with -o {target} left {:?} in {}",
        entries_in(&out),
        out.display()
    );
}
