//! `p3dp watch`, run as the real binary: the page on loopback, its event
//! stream following edits of the recipe and of a file it includes, errors
//! shown beside the last good model, a clean stop on SIGINT. HTTP by hand
//! over `std::net::TcpStream` (no client crate).

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

use crate::common::*;

const RECIPE: &str = "p3dp: 1
name: watched
printer: generic-220
material: pla
include: [lib.yaml]
parts:
  - primitive:
      helix: { radius: 10, height: h, pitch: 0.5 }
";

const LIB: &str = "p3dp: 1\nparams: {h: 2}\n";

/// The running server, killed if a test fails half way.
struct Server {
    child: Child,
    port: u16,
    stdout: Receiver<String>,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `p3dp watch ARGS --port 0` in `dir` and reads the URL it prints.
fn start(dir: &Path, args: &[&str]) -> Server {
    let mut child = Command::new(env!("CARGO_BIN_EXE_p3dp"))
        .arg("watch")
        .args(args)
        .args(["--port", "0", "-j", "1"])
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run p3dp watch");
    let (tx, stdout) = mpsc::channel();
    let out = child.stdout.take().unwrap();
    std::thread::spawn(move || {
        for line in BufReader::new(out).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    // stderr is drained so the server never blocks on it
    let err = child.stderr.take().unwrap();
    std::thread::spawn(move || {
        let mut s = String::new();
        let _ = BufReader::new(err).read_to_string(&mut s);
        eprint!("{s}");
    });
    let line = stdout
        .recv_timeout(Duration::from_secs(10))
        .expect("p3dp watch prints its URL");
    let port: u16 = line
        .split("http://127.0.0.1:")
        .nth(1)
        .and_then(|r| r.split('/').next())
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("no URL in {line:?}"));
    Server {
        child,
        port,
        stdout,
    }
}

/// GET `path` with `host` as the Host header: (status, body).
fn get(port: u16, path: &str, host: &str) -> (u16, String) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let body = text.split_once("\r\n\r\n").map_or("", |(_, b)| b);
    (status, body.to_string())
}

/// The server-sent events of `/events`, each (event name, data as JSON).
fn events(port: u16) -> Receiver<(String, serde_json::Value)> {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    write!(
        s,
        "GET /events HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nAccept: text/event-stream\r\n\r\n"
    )
    .unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut lines = BufReader::new(s).lines().map_while(Result::ok);
        let status = lines.next().unwrap_or_default();
        assert!(status.contains(" 200 "), "{status}");
        let mut head = Vec::new();
        for l in lines.by_ref() {
            if l.is_empty() {
                break;
            }
            head.push(l.to_ascii_lowercase());
        }
        assert!(
            head.iter()
                .any(|h| h.starts_with("content-type: text/event-stream")),
            "{head:?}"
        );
        let (mut name, mut data) = (String::new(), String::new());
        for l in lines {
            if l.is_empty() {
                if !data.is_empty() {
                    let v = serde_json::from_str(&data).expect("event data is JSON");
                    if tx.send((std::mem::take(&mut name), v)).is_err() {
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
    rx
}

/// The next event named `name` within `within`, skipping others.
fn next(
    rx: &Receiver<(String, serde_json::Value)>,
    name: &str,
    within: Duration,
) -> serde_json::Value {
    let end = Instant::now() + within;
    loop {
        let left = end.saturating_duration_since(Instant::now());
        match rx.recv_timeout(left) {
            Ok((n, v)) if n == name => return v,
            Ok(_) => {}
            Err(_) => panic!("no `{name}` event within {within:?}"),
        }
    }
}

/// The extent of a model event's bounding box along x, y and z.
fn size(model: &serde_json::Value) -> [f64; 3] {
    let b = &model["model"]["bbox"];
    [0, 1, 2].map(|k| b["max"][k].as_f64().unwrap() - b["min"][k].as_f64().unwrap())
}

/// Saves as editors do: a new file renamed over the old one.
fn save(path: &Path, text: &str) {
    let tmp = path.with_extension("yaml.editor-tmp");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

#[test]
fn the_page_follows_edits_errors_and_stops_on_sigint() {
    let dir = tmp("watch");
    let recipe = dir.join("recipe.yaml");
    std::fs::write(&recipe, RECIPE).unwrap();
    std::fs::write(dir.join("lib.yaml"), LIB).unwrap();
    let mut server = start(&dir, &["recipe.yaml"]);
    let port = server.port;

    // the page: the viewer, live; only for requests addressed to loopback names
    let (status, page) = get(port, "/", &format!("127.0.0.1:{port}"));
    assert_eq!(status, 200);
    assert!(page.contains("<canvas id=\"gl\">") && page.contains("id=\"p3dp-live\""));
    assert!(page.contains("new EventSource(\"/events\")"));
    assert_eq!(get(port, "/", &format!("localhost:{port}")).0, 200);
    assert_eq!(get(port, "/", "evil.example:80").0, 403);
    assert_eq!(get(port, "/nothing", &format!("127.0.0.1:{port}")).0, 404);

    let ev = events(port);
    let first = next(&ev, "model", Duration::from_secs(10));
    let s = size(&first);
    assert!(
        (s[0] - 20.0).abs() < 0.5 && (s[2] - 2.0).abs() < 0.3,
        "{s:?}"
    );
    // the model comes before its checks are done; their findings follow,
    // for the same build, with the moves they flag
    assert_eq!(first["pending"], "checks", "{}", first["pending"]);
    let checks = next(&ev, "checks", Duration::from_secs(10));
    assert_eq!(checks["build"], first["build"]);
    assert!(checks["flagged"].is_array(), "{checks}");
    let findings = checks["findings"].as_array().unwrap();
    for f in findings {
        for k in ["code", "severity", "message"] {
            assert!(f[k].is_string(), "{f}");
        }
    }

    // a radius changed: a new model within 2 s, 30 mm across
    let edited = RECIPE.replace("radius: 10", "radius: 15");
    let t0 = Instant::now();
    save(&recipe, &edited);
    let m = next(&ev, "model", Duration::from_secs(2));
    let s = size(&m);
    assert!((s[0] - 30.0).abs() < 0.5, "{s:?} after {:?}", t0.elapsed());
    assert!(m["build"].as_u64() > first["build"].as_u64());

    // the included file changed: the height follows
    std::fs::write(dir.join("lib.yaml"), "p3dp: 1\nparams: {h: 4}\n").unwrap();
    let m = next(&ev, "model", Duration::from_secs(2));
    assert!((size(&m)[2] - 4.0).abs() < 0.3, "{:?}", size(&m));

    // a misspelt key: the error, rustc-style, naming it; the page keeps the model
    save(&recipe, &edited.replace("radius: 15", "radious: 15"));
    let e = next(&ev, "build-error", Duration::from_secs(2));
    let text = e["error"].as_str().unwrap();
    assert!(text.contains("radious") && text.contains("help:"), "{text}");
    assert!(text.contains("recipe.yaml:8:"), "{text}");
    let (_, page) = get(port, "/", &format!("127.0.0.1:{port}"));
    assert!(page.contains("radious") && page.contains("\"model_build\":"));
    assert!(
        !page.contains("id=\"p3dp-data\">null<"),
        "the last model stays"
    );

    // fixed: a model again
    save(&recipe, &edited.replace("radius: 15", "radius: 12"));
    let m = next(&ev, "model", Duration::from_secs(2));
    assert!((size(&m)[0] - 24.0).abs() < 0.5, "{:?}", size(&m));

    // Ctrl-C: status 0 within a second, the port closed, no temp files
    let lines: Vec<String> = server.stdout.try_iter().collect();
    assert!(lines.iter().any(|l| l.contains(": ok in ")), "{lines:?}");
    let pid = server.child.id().to_string();
    assert!(Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap()
        .success());
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = server.child.try_wait().unwrap() {
            break s;
        }
        assert!(
            t0.elapsed() < Duration::from_millis(1500),
            "still running after SIGINT"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(status.code(), Some(0), "{status:?}");
    assert!(TcpStream::connect(("127.0.0.1", port)).is_err());
    for f in std::fs::read_dir(&dir).unwrap() {
        let name = f.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.starts_with(".p3dp-"), "{name} left behind");
    }
}

#[test]
fn a_busy_port_or_a_missing_recipe_is_refused_at_once() {
    let dir = tmp("watch-refused");
    std::fs::write(dir.join("recipe.yaml"), RECIPE).unwrap();
    let held = std::net::TcpListener::bind(("127.0.0.1", 0)).unwrap();
    let port = held.local_addr().unwrap().port().to_string();
    let out = p3dp(&dir, &["watch", "recipe.yaml", "--port", &port]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("--port {port}")) && err.contains("in use"),
        "{err}"
    );
    assert!(err.contains("--port 0"), "{err}");

    let out = p3dp(&dir, &["watch", "missing.yaml", "--port", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.yaml"));
}

/// The files `p3dp watch` follows are those the build read or tried:
/// recipe, includes, images, a printer profile and what it inherits.
#[test]
fn a_build_records_every_file_it_reads_missing_ones_too() {
    let dir = tmp("watch-inputs");
    std::fs::create_dir_all(dir.join("printers")).unwrap();
    for f in ["child-user.yaml", "base-user.yaml"] {
        std::fs::copy(
            root().join("tests/fixtures/printers").join(f),
            dir.join("printers").join(f),
        )
        .unwrap();
    }
    std::fs::copy(root().join("maps/world-300x150.png"), dir.join("map.png")).unwrap();
    std::fs::write(dir.join("lib.yaml"), LIB).unwrap();
    let text = |image: &str| {
        format!(
            "p3dp: 1
name: inputs
printer: printers/child-user.yaml
material: pla
include: [lib.yaml]
parts:
  - primitive:
      helix: {{ radius: 10, height: h, pitch: 0.5 }}
    steps:
      - modulate_map: {{ image: {image}, u: \"theta/(2*pi)\", v: \"z/h\", dark: 1, light: 0.8 }}
"
        )
    };
    let recipe = dir.join("recipe.yaml");
    std::fs::write(&recipe, text("map.png")).unwrap();
    let opts = p3dp::Options::default();
    let cx = p3dp::testing::Context::default();
    let built = p3dp::testing::prepare_in(&recipe, &opts, &cx);
    let files = cx.reads.files();
    if let Err(e) = built {
        panic!("{e}");
    }
    let ids: Vec<_> = files.iter().map(|f| f.canonicalize().unwrap()).collect();
    for f in [
        "recipe.yaml",
        "lib.yaml",
        "map.png",
        "printers/child-user.yaml",
        "printers/base-user.yaml",
    ] {
        let want = dir.join(f).canonicalize().unwrap();
        assert!(ids.contains(&want), "{f} not among {files:?}");
    }
    // a missing image fails the build, and is followed: making it is a change
    std::fs::write(&recipe, text("later.png")).unwrap();
    let cx = p3dp::testing::Context::default();
    let built = p3dp::testing::prepare_in(&recipe, &opts, &cx);
    let files = cx.reads.files();
    assert!(built.is_err());
    assert!(files.iter().any(|f| f.ends_with("later.png")), "{files:?}");
}

/// The next line of `p3dp watch` containing `what`, within `wait`.
fn line_with(server: &Server, what: &str, wait: Duration) -> String {
    let t0 = Instant::now();
    loop {
        let left = wait.saturating_sub(t0.elapsed());
        match server.stdout.recv_timeout(left) {
            Ok(l) if l.contains(what) => return l,
            Ok(_) => {}
            Err(_) => panic!("no line with {what:?} within {wait:?}"),
        }
    }
}

#[test]
fn an_edited_feature_re_slices_only_its_layers() {
    let dir = tmp("watch-solid");
    let recipe = dir.join("solid.yaml");
    let text = "p3dp: 1\nname: solid\nprinter: generic-220\nmaterial: pla\nparts:\n  - name: solid\n    speed: 40\n    primitive:\n      solid: {layer_height: 0.2, perimeters: 2, infill: {spacing: 0.8}, features: [{box: {center: [0, 0, 5], size: [40, 30, 10]}}, {cylinder: {center: [0, 0, 0], radius: 8, height: 10, op: subtract}}, {cylinder: {center: [15, 0, 10], radius: 5, height: 6}}]}\n";
    std::fs::write(&recipe, text).unwrap();
    let server = start(&dir, &["solid.yaml"]);
    // the first build slices every layer
    let l = line_with(&server, ": ok in ", Duration::from_secs(20));
    assert!(l.contains("solid layers re-sliced: 80 of 80"), "{l}");
    // the boss (z 10 … 16) made 4 mm tall: its 20 remaining layers only
    save(
        &recipe,
        &text.replace("radius: 5, height: 6", "radius: 5, height: 4"),
    );
    let l = line_with(&server, ": ok in ", Duration::from_secs(20));
    assert!(l.contains("solid layers re-sliced: 20 of 70"), "{l}");
}

/// A line of `/proc/PID/status` as a number (`Threads`, `VmHWM` in kB).
fn proc_status(pid: u32, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = text.lines().find(|l| l.starts_with(&format!("{key}:")))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[test]
fn hostile_clients_never_hold_a_fresh_get_up() {
    let dir = tmp("watch-hostile");
    std::fs::write(dir.join("r.yaml"), RECIPE).unwrap();
    std::fs::write(dir.join("lib.yaml"), LIB).unwrap();
    let server = start(&dir, &["r.yaml"]);
    let (port, pid) = (server.port, server.child.id());
    let host = format!("127.0.0.1:{port}");
    // a header of up to 64 MB: refused past 16 kB, never held in memory
    let mut big = TcpStream::connect(("127.0.0.1", port)).unwrap();
    big.set_write_timeout(Some(Duration::from_secs(5))).unwrap();
    let _ = write!(big, "GET / HTTP/1.1\r\nHost: {host}\r\nX-Big: ");
    let chunk = vec![b'a'; 1 << 20];
    for _ in 0..64 {
        if big.write_all(&chunk).is_err() {
            break;
        }
    }
    // pages and streams asked for and never read, and 500 connections idle
    let mut held = Vec::new();
    for k in 0..80 {
        let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
        let path = if k % 2 == 0 { "/" } else { "/events" };
        write!(s, "GET {path} HTTP/1.1\r\nHost: {host}\r\n\r\n").unwrap();
        held.push(s);
    }
    for _ in 0..500 {
        held.push(TcpStream::connect(("127.0.0.1", port)).unwrap());
    }
    std::thread::sleep(Duration::from_millis(200));
    let t = Instant::now();
    let (status, body) = get(port, "/", &host);
    assert_eq!(status, 200);
    assert!(body.contains("<html"), "the page");
    assert!(t.elapsed() < Duration::from_secs(1), "{:?}", t.elapsed());
    let threads = proc_status(pid, "Threads").unwrap_or(0);
    assert!(threads < 120, "{threads} threads");
    let peak = proc_status(pid, "VmHWM").unwrap_or(0);
    assert!(peak < 300_000, "{peak} kB at most");
    drop(held);
    drop(server);
}

/// Two parts, one edited: only that one is made again; the other is the
/// build before's toolpath (the build line says how many were made).
#[test]
fn an_edited_part_is_made_again_alone() {
    let dir = tmp("watch-parts");
    let recipe = dir.join("two.yaml");
    let text = "p3dp: 1\nname: two\nprinter: generic-220\nmaterial: pla\nparams: {rad: 10, h: 2}\nparts:\n  - name: left\n    primitive:\n      helix: { radius: rad, height: h, pitch: 0.5 }\n    steps: [{translate: [-30, 0, 0]}]\n  - name: right\n    primitive:\n      helix: { radius: 8, height: 3, pitch: 0.5 }\n    steps: [{translate: [30, 0, 0]}]\n";
    std::fs::write(&recipe, text).unwrap();
    let server = start(&dir, &["two.yaml"]);
    let l = line_with(&server, ": ok in ", Duration::from_secs(20));
    assert!(l.contains("parts made: 2 of 2"), "{l}");
    // the right part's helix taller: the left one is taken back
    save(&recipe, &text.replace("height: 3", "height: 4"));
    let l = line_with(&server, ": ok in ", Duration::from_secs(20));
    assert!(l.contains("parts made: 1 of 2"), "{l}");
    // a param the left part reads: that one only
    save(
        &recipe,
        &text
            .replace("height: 3", "height: 4")
            .replace("rad: 10", "rad: 11"),
    );
    let l = line_with(&server, ": ok in ", Duration::from_secs(20));
    assert!(l.contains("parts made: 1 of 2"), "{l}");
    // a comment: nothing made
    save(
        &recipe,
        &format!(
            "{}# a note\n",
            text.replace("height: 3", "height: 4")
                .replace("rad: 10", "rad: 11")
        ),
    );
    let l = line_with(&server, ": ok in ", Duration::from_secs(20));
    assert!(l.contains("parts made: 0 of 2"), "{l}");
}

/// A model far beyond the machine is refused as `preview` refuses it (its
/// drawing would take minutes and gigabytes), named in the page's error;
/// the page keeps the last model.
#[test]
fn a_model_far_beyond_the_machine_is_refused() {
    let dir = tmp("watch-far");
    let recipe = dir.join("far.yaml");
    std::fs::write(&recipe, RECIPE).unwrap();
    std::fs::write(dir.join("lib.yaml"), LIB).unwrap();
    let server = start(&dir, &["far.yaml"]);
    let ev = events(server.port);
    let first = next(&ev, "model", Duration::from_secs(10));
    save(&recipe, &RECIPE.replace("radius: 10", "radius: 100000000"));
    let e = next(&ev, "build-error", Duration::from_secs(10));
    let text = e["error"].as_str().unwrap();
    assert!(
        text.contains("farther than")
            && text.contains("a preview is drawn of what lies near the machine"),
        "{text}"
    );
    assert!(e["build"].as_u64() > first["build"].as_u64());
}
