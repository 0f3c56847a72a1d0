//! Edit → see: `p3dp watch` timed from a save to the page's event, for
//! every gallery recipe and the vase (issue 38).
//!
//!     cargo bench --bench watch
//!     P3DP_BASELINE=/path/to/an/older/p3dp cargo bench --bench watch
//!     cargo bench --bench watch -- sphere vase      # only these recipes
//!
//! The gallery (`recipes/` and the `maps/` it reads) is copied to a scratch
//! folder. For each recipe and binary, `p3dp watch RECIPE --port 0 -j 2`
//! runs there; the bench follows `/events` as the page does, waits for the
//! first model, then saves the recipe as an editor does (a new file renamed
//! over the old one) and times, from just before the save:
//!
//! - `model`: the next `model` event (the geometry on the page);
//! - `checked`: the next event that carries the checks' findings (a
//!   `checks` event, or the `model` event itself for a server that sends
//!   them together).
//!
//! Two edits, alternately, each saved `P3DP_WATCH_EDITS` times (7 unless
//! set): `param`, the first number of the recipe's top-level `params:`
//! changed and changed back (an integer ±1, a decimal ×1.01: every part
//! that reads it is rebuilt), and `comment`, a comment line added and
//! removed (nothing a part reads changes). A recipe without numeric params
//! gets the comment edit only. The medians are printed per recipe, with the
//! build time watch reports for its first build (figures:
//! docs/performance.md).

// the bench uses the binaries and the median of what the benches share
#[allow(dead_code)]
mod common;

use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

/// How long one event may take before the bench gives up on a recipe.
const PATIENCE: Duration = Duration::from_secs(60);

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let only: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let edits: usize = std::env::var("P3DP_WATCH_EDITS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(7);
    let dir = std::env::temp_dir().join(format!("p3dp-bench-watch-{}", std::process::id()));
    copy_dir(&root.join("recipes"), &dir.join("recipes"));
    copy_dir(&root.join("maps"), &dir.join("maps"));
    // the scratch folder a project of its own (`globe` reads ../maps)
    std::fs::create_dir_all(dir.join(".git")).unwrap();
    let mut names: Vec<String> = std::fs::read_dir(dir.join("recipes"))
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".yaml"))
        .map(|n| n.trim_end_matches(".yaml").to_string())
        .filter(|n| only.is_empty() || only.contains(n))
        .collect();
    names.sort();
    let bins = common::binaries();
    println!(
        "{} edits of each kind; medians in ms (save → event on /events)",
        edits
    );
    println!(
        "{:<26} {:<9} {:>7} {:>8} {:>8} {:>8} {:>8}",
        "recipe", "binary", "build", "param", "checked", "comment", "checked"
    );
    for name in &names {
        let recipe = dir.join("recipes").join(format!("{name}.yaml"));
        let original = std::fs::read_to_string(&recipe).unwrap();
        for (label, bin) in &bins {
            let r = measure(bin, &recipe, &original, edits);
            std::fs::write(&recipe, &original).unwrap();
            let ms = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{:.0}", 1e3 * v));
            match r {
                Ok(f) => println!(
                    "{name:<26} {label:<9} {:>7} {:>8} {:>8} {:>8} {:>8}",
                    ms(f.build),
                    ms(f.param.0),
                    ms(f.param.1),
                    ms(f.comment.0),
                    ms(f.comment.1)
                ),
                Err(e) => println!("{name:<26} {label:<9} failed: {e}"),
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// One recipe's medians, s: the first build as watch reports it; per edit
/// kind, save → `model` and save → findings.
struct Figures {
    build: Option<f64>,
    param: (Option<f64>, Option<f64>),
    comment: (Option<f64>, Option<f64>),
}

/// The running server, killed when done.
struct Server {
    child: Child,
    stdout: Receiver<String>,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Times the edits of one recipe with one binary.
fn measure(bin: &Path, recipe: &Path, original: &str, edits: usize) -> Result<Figures, String> {
    let mut child = Command::new(bin)
        .arg("watch")
        .arg(recipe)
        .args(["--port", "0", "-j", "2"])
        .current_dir(recipe.parent().unwrap())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot run {}: {e}", bin.display()))?;
    let (tx, stdout) = mpsc::channel();
    let out = child.stdout.take().unwrap();
    std::thread::spawn(move || {
        for line in BufReader::new(out).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    let server = Server { child, stdout };
    let line = server
        .stdout
        .recv_timeout(Duration::from_secs(10))
        .map_err(|_| "no URL printed".to_string())?;
    let port: u16 = line
        .split("http://127.0.0.1:")
        .nth(1)
        .and_then(|r| r.split('/').next())
        .and_then(|p| p.parse().ok())
        .ok_or_else(|| format!("no URL in {line:?}"))?;
    let events = follow(port)?;
    let mut build = 0u64;
    // the first build: its model (and its findings, when they come apart)
    let (first, _) = next_build(&events, &mut build, Instant::now())?;
    let _ = first;
    let took = server
        .stdout
        .recv_timeout(Duration::from_secs(1))
        .ok()
        .and_then(|l| reported_time(&l));
    let edited = param_edit(original);
    let mut param = (Vec::new(), Vec::new());
    let mut comment = (Vec::new(), Vec::new());
    for k in 0..2 * edits {
        let flip = (k / 2) % 2 == 0;
        let (text, into) = match (&edited, k % 2) {
            (Some(e), 0) => (
                if flip {
                    e.clone()
                } else {
                    original.to_string()
                },
                &mut param,
            ),
            _ if flip => (format!("{original}\n# watch bench edit\n"), &mut comment),
            _ => (original.to_string(), &mut comment),
        };
        // settled: nothing pending before the save
        std::thread::sleep(Duration::from_millis(150));
        while events.try_recv().is_ok() {}
        let t0 = Instant::now();
        save(recipe, &text);
        let (model, checked) = next_build(&events, &mut build, t0)?;
        into.0.push(model);
        into.1.push(checked);
    }
    let med = |v: &mut Vec<f64>| (!v.is_empty()).then(|| common::median(v));
    Ok(Figures {
        build: took,
        param: (med(&mut param.0), med(&mut param.1)),
        comment: (med(&mut comment.0), med(&mut comment.1)),
    })
}

/// The seconds of watch's `build N: ok in S s` line.
fn reported_time(line: &str) -> Option<f64> {
    let rest = line.split(" ok in ").nth(1)?;
    rest.split(" s").next()?.parse().ok()
}

/// `original` with its first numeric top-level param changed (an integer
/// ±1, a decimal ×1.01), or None when it has none.
fn param_edit(original: &str) -> Option<String> {
    let mut lines: Vec<String> = original.lines().map(str::to_string).collect();
    let start = lines.iter().position(|l| l.trim_end() == "params:")?;
    for l in lines.iter_mut().skip(start + 1) {
        if !l.starts_with("  ") || l.starts_with("   ") {
            if l.trim().is_empty() || l.trim_start().starts_with('#') {
                continue;
            }
            return None;
        }
        let (key, rest) = l.split_once(':')?;
        let value = rest.split('#').next()?.trim();
        let new = if let Ok(i) = value.parse::<i64>() {
            format!("{}", if i > 1 { i - 1 } else { i + 1 })
        } else if let Ok(f) = value.parse::<f64>() {
            format!("{}", f * 1.01)
        } else {
            continue;
        };
        *l = format!("{key}: {new}");
        return Some(lines.join("\n") + "\n");
    }
    None
}

/// Saves as editors do: a new file renamed over the recipe.
fn save(recipe: &Path, text: &str) {
    let tmp = recipe.with_extension("yaml.tmp");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, recipe).unwrap();
}

/// One event: its name, its build number, and whether it carries findings.
struct Event {
    name: String,
    build: u64,
    findings: bool,
}

/// Waits for the next build's `model` event and for its findings: the
/// seconds from `t0` to each. A `build-error` is an error.
fn next_build(rx: &Receiver<Event>, build: &mut u64, t0: Instant) -> Result<(f64, f64), String> {
    let mut model = None;
    loop {
        let ev = rx
            .recv_timeout(PATIENCE)
            .map_err(|_| "no event".to_string())?;
        if ev.build <= *build {
            continue;
        }
        match ev.name.as_str() {
            "build-error" => return Err(format!("build {} failed", ev.build)),
            "model" if model.is_none() => {
                model = Some(t0.elapsed().as_secs_f64());
                if ev.findings {
                    *build = ev.build;
                    return Ok((model.unwrap(), model.unwrap()));
                }
            }
            "checks" if model.is_some() => {
                *build = ev.build;
                return Ok((model.unwrap(), t0.elapsed().as_secs_f64()));
            }
            _ => {}
        }
    }
}

/// The events of `/events`, read on a thread of their own.
fn follow(port: u16) -> Result<Receiver<Event>, String> {
    let mut s = TcpStream::connect(("127.0.0.1", port)).map_err(|e| e.to_string())?;
    write!(
        s,
        "GET /events HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nAccept: text/event-stream\r\n\r\n"
    )
    .map_err(|e| e.to_string())?;
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut lines = BufReader::new(s).lines().map_while(Result::ok);
        let (mut name, mut data) = (String::new(), String::new());
        for l in lines.by_ref() {
            if l.is_empty() {
                if !data.is_empty() {
                    let v: serde_json::Value = match serde_json::from_str(&data) {
                        Ok(v) => v,
                        Err(_) => return,
                    };
                    let ev = Event {
                        name: std::mem::take(&mut name),
                        build: v["build"].as_u64().unwrap_or(0),
                        findings: v["model"].get("findings").is_some()
                            && v.get("pending").is_none(),
                    };
                    if tx.send(ev).is_err() {
                        return;
                    }
                }
                data.clear();
            } else if let Some(n) = l.strip_prefix("event: ") {
                name = n.to_string();
            } else if let Some(d) = l.strip_prefix("data: ") {
                data.push_str(d);
            }
        }
    });
    Ok(rx)
}

/// Copies a folder's files (one level and below).
fn copy_dir(from: &Path, to: &PathBuf) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            copy_dir(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).unwrap();
        }
    }
}
