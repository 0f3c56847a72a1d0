//! `p3dp send` against a real Moonraker and a real OctoPrint (issue 31),
//! each started here on loopback with a throwaway data folder from the
//! virtual environments `.ci/run` makes (`P3DP_HOST_VENV`,
//! `P3DP_OCTOPRINT_VENV`; skipped with a note when absent, a failure under
//! CI). The uploaded file must be byte-identical and listed with its
//! metadata; a wrong key, a closed port are refused with a clear message
//! and exit status 2, leaving nothing on the host.

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::common::tmp;
use crate::hosts::{build, num, venv, with_thumbnails};

/// A server this test started, stopped (by its own id) when dropped.
struct Server(Child);

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A loopback port nothing listens on (for a moment).
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// GET `url` with an optional API key: status and body.
fn get(url: &str, key: Option<&str>) -> Option<(u16, String)> {
    let agent: ureq::Agent = ureq::Agent::config_builder()
        .timeout_global(Some(Duration::from_secs(5)))
        .http_status_as_error(false)
        .build()
        .into();
    let mut req = agent.get(url);
    if let Some(k) = key {
        req = req.header("X-Api-Key", k);
    }
    let mut resp = req.call().ok()?;
    let body = resp.body_mut().read_to_string().unwrap_or_default();
    Some((resp.status().as_u16(), body))
}

/// Waits (at most a minute) until `url` answers 200.
fn wait_for(url: &str, key: Option<&str>, server: &mut Server) {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(60) {
        if let Some((200, _)) = get(url, key) {
            return;
        }
        if let Ok(Some(status)) = server.0.try_wait() {
            panic!("the server stopped ({status}) before answering {url}");
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    panic!("{url} did not answer within a minute");
}

/// `p3dp send ARGS` with `P3DP_API_KEY` set to `key` (or unset).
fn send(dir: &Path, key: Option<&str>, args: &[&str]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_p3dp"));
    c.arg("send")
        .args(args)
        .current_dir(dir)
        .env_remove("P3DP_API_KEY");
    if let Some(k) = key {
        c.env("P3DP_API_KEY", k);
    }
    c.output().expect("run p3dp send")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn moonraker_takes_the_file_byte_for_byte_and_lists_its_metadata() {
    let Some(py) = venv("P3DP_HOST_VENV", "the Moonraker server") else {
        return;
    };
    let dir = tmp("send-moonraker");
    let stats = build(&dir, &with_thumbnails(&dir, "voron-350"), "vase.gcode");
    let data = dir.join("moonraker");
    std::fs::create_dir_all(data.join("config")).unwrap();
    let port = free_port();
    // loopback is trusted, so the key is Moonraker's own (read back below);
    // a wrong key is still refused
    let conf = format!(
        "[server]\nhost: 127.0.0.1\nport: {port}\nklippy_uds_address: {}\n\n[authorization]\ntrusted_clients:\n  127.0.0.0/8\n",
        data.join("klippy.sock").display()
    );
    std::fs::write(data.join("config/moonraker.conf"), conf).unwrap();
    let mut server = Server(
        Command::new(py.with_file_name("moonraker"))
            .args(["-d", data.to_str().unwrap(), "-n"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start moonraker"),
    );
    let url = format!("http://127.0.0.1:{port}");
    wait_for(&format!("{url}/server/info"), None, &mut server);
    let (_, key) = get(&format!("{url}/access/api_key"), None).unwrap();
    let key: String = serde_json::from_str::<Value>(&key).unwrap()["result"]
        .as_str()
        .unwrap()
        .to_string();

    let wrong = send(&dir, Some("not-the-key"), &["vase.gcode", "--to", &url]);
    assert_eq!(wrong.status.code(), Some(2), "{}", stderr(&wrong));
    assert!(
        stderr(&wrong).contains("refused the API key (HTTP 401)"),
        "{}",
        stderr(&wrong)
    );
    assert!(!data.join("gcodes/vase.gcode").exists());
    assert!(
        !stderr(&wrong).contains("not-the-key"),
        "the key is never printed"
    );

    let ok = send(&dir, Some(&key), &["vase.gcode", "--to", &url]);
    assert!(ok.status.success(), "{}", stderr(&ok));
    let said = String::from_utf8_lossy(&ok.stdout);
    assert!(
        said.contains("sent to moonraker") && !said.contains(&key),
        "{said}"
    );
    let sent = std::fs::read(dir.join("vase.gcode")).unwrap();
    assert_eq!(std::fs::read(data.join("gcodes/vase.gcode")).unwrap(), sent);
    let meta = format!("{url}/server/files/metadata?filename=vase.gcode");
    let (status, body) = get(&meta, Some(&key)).unwrap();
    assert_eq!(status, 200, "{body}");
    let m = &serde_json::from_str::<Value>(&body).unwrap()["result"];
    assert_eq!(m["slicer"], "p3dp", "{m}");
    assert!(
        (num(m, "estimated_time") - num(&stats, "print_time_s")).abs() <= 1.0,
        "{m}"
    );
    assert_eq!(num(m, "size") as usize, sent.len());
    assert!(!m["thumbnails"].as_array().unwrap().is_empty(), "{m}");

    let port = free_port();
    let closed = send(
        &dir,
        None,
        &["vase.gcode", "--to", &format!("http://127.0.0.1:{port}")],
    );
    assert_eq!(closed.status.code(), Some(2));
    assert!(
        stderr(&closed).contains("connection refused"),
        "{}",
        stderr(&closed)
    );
}

/// An OctoPrint data folder with one admin user whose API key is `key`
/// (OctoPrint's keys belong to users; the global key is deprecated).
fn octoprint_base(py: &Path, base: &Path, key: &str) {
    let octoprint = py.with_file_name("octoprint");
    let out = Command::new(&octoprint)
        .args(["--basedir", base.to_str().unwrap(), "user", "add"])
        .args(["--password", "p3dp-test-password", "--admin", "tester"])
        .output()
        .expect("octoprint user add");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let users = base.join("users.yaml");
    let text = std::fs::read_to_string(&users).unwrap();
    assert!(text.contains("apikey: null"), "{text}");
    std::fs::write(
        &users,
        text.replace("apikey: null", &format!("apikey: {key}")),
    )
    .unwrap();
    // a headless server for one upload: the bundled plugins the file API
    // does not use left off, and the web assets unbundled (its start takes
    // ~1.2 s instead of ~4.9 s here; the upload and files API are the core's)
    let mut config = std::fs::read_to_string(base.join("config.yaml")).unwrap_or_default();
    config.push_str(concat!(
        "server:\n  firstRun: false\n  onlineCheck:\n    enabled: false\n  pluginBlacklist:\n    enabled: false\n",
        "plugins:\n  tracking:\n    enabled: false\n  announcements:\n    enabled: false\n",
        "  _disabled: [achievements, action_command_notification, action_command_prompt, announcements,",
        " backup, classicwebcam, corewizard, customcontrolmanager, discovery, errortracking, eventmanager,",
        " gcodeviewer, health_check, logging, pluginmanager, softwareupdate, tracking, virtual_printer]\n",
        "devel:\n  webassets:\n    bundle: false\n    minify: false\n",
    ));
    std::fs::write(base.join("config.yaml"), config).unwrap();
}

#[test]
fn octoprint_takes_the_file_byte_for_byte_and_refuses_a_wrong_key() {
    let Some(py) = venv("P3DP_OCTOPRINT_VENV", "the OctoPrint server") else {
        return;
    };
    let dir = tmp("send-octoprint");
    build(&dir, Path::new("prusa-mk4"), "vase.gcode");
    let base: PathBuf = dir.join("octoprint");
    let key = "P3DPTESTKEY0123456789ABCDEF";
    octoprint_base(&py, &base, key);
    let port = free_port();
    let mut server = Server(
        Command::new(py.with_file_name("octoprint"))
            .args([
                "--basedir",
                base.to_str().unwrap(),
                "serve",
                "--iknowwhatimdoing",
            ])
            .args(["--host", "127.0.0.1", "--port", &port.to_string()])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start octoprint"),
    );
    let url = format!("http://127.0.0.1:{port}");
    wait_for(&format!("{url}/api/version"), Some(key), &mut server);

    // a wrong key: OctoPrint answers /api/version 403, a POST 400 (CSRF)
    let wrong = send(&dir, Some("WRONG"), &["vase.gcode", "--to", &url]);
    assert_eq!(wrong.status.code(), Some(2), "{}", stderr(&wrong));
    assert!(
        stderr(&wrong).contains("refused the API key (HTTP 403)"),
        "{}",
        stderr(&wrong)
    );
    let args = ["vase.gcode", "--to", &url, "--host", "octoprint"];
    let wrong = send(&dir, Some("WRONG"), &args);
    assert_eq!(wrong.status.code(), Some(2), "{}", stderr(&wrong));
    assert!(
        stderr(&wrong).contains("CSRF validation failed"),
        "{}",
        stderr(&wrong)
    );
    assert!(!base.join("uploads/vase.gcode").exists());

    let ok = send(&dir, Some(key), &["vase.gcode", "--to", &url]);
    assert!(ok.status.success(), "{}", stderr(&ok));
    assert!(String::from_utf8_lossy(&ok.stdout).contains("sent to octoprint"));
    let sent = std::fs::read(dir.join("vase.gcode")).unwrap();
    assert_eq!(
        std::fs::read(base.join("uploads/vase.gcode")).unwrap(),
        sent
    );
    let (status, body) = get(&format!("{url}/api/files/local/vase.gcode"), Some(key)).unwrap();
    assert_eq!(status, 200, "{body}");
    let f: Value = serde_json::from_str(&body).unwrap();
    assert_eq!(f["name"], "vase.gcode");
    assert_eq!(num(&f, "size") as usize, sent.len());
}

/// What a stand-in host saw of one request: the body's first and last
/// bytes (at most 1 MB and 64 bytes) and its length.
struct Seen {
    method: String,
    url: String,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
    tail: Vec<u8>,
    len: u64,
}

impl Seen {
    fn header(&self, k: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(h, _)| h.eq_ignore_ascii_case(k))
            .map(|(_, v)| v.as_str())
    }
}

/// A stand-in's answer: status, headers, body.
type Reply = (u16, Vec<(&'static str, String)>, Vec<u8>);

/// A stand-in host on loopback, answering each request by `answer`; what
/// it saw comes back from [`StandIn::seen`], which stops it.
struct StandIn {
    url: String,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: std::thread::JoinHandle<Vec<Seen>>,
}

impl StandIn {
    fn start(answer: impl Fn(&Seen) -> Reply + Send + 'static) -> StandIn {
        use std::sync::atomic::{AtomicBool, Ordering};
        let server = tiny_http::Server::http("127.0.0.1:0").unwrap();
        let url = format!("http://{}", server.server_addr().to_ip().unwrap());
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        let stopped = stop.clone();
        let thread = std::thread::spawn(move || {
            let mut seen = Vec::new();
            while !stopped.load(Ordering::Relaxed) {
                let Ok(Some(mut req)) = server.recv_timeout(Duration::from_millis(50)) else {
                    continue;
                };
                let s = read_request(&mut req);
                let (code, headers, body) = answer(&s);
                let mut resp = tiny_http::Response::from_data(body).with_status_code(code);
                for (k, v) in headers {
                    resp.add_header(tiny_http::Header::from_bytes(k, v.as_bytes()).unwrap());
                }
                let _ = req.respond(resp);
                seen.push(s);
            }
            seen
        });
        StandIn { url, stop, thread }
    }

    /// Stops the host: every request it saw, in order.
    fn seen(self) -> Vec<Seen> {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        self.thread.join().unwrap()
    }
}

/// A request read whole, its body streamed through (never held whole).
fn read_request(req: &mut tiny_http::Request) -> Seen {
    let mut body = Vec::new();
    let mut tail = Vec::new();
    let mut len = 0u64;
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let n = match req.as_reader().read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => n,
        };
        len += n as u64;
        let room = (1usize << 20).saturating_sub(body.len());
        body.extend_from_slice(&buf[..n.min(room)]);
        // the last 64 bytes: of this read alone when it has as many
        let last = &buf[n.saturating_sub(64)..n];
        tail.extend_from_slice(last);
        let cut = tail.len().saturating_sub(64);
        tail.drain(..cut);
    }
    Seen {
        method: req.method().to_string(),
        url: req.url().to_string(),
        headers: req
            .headers()
            .iter()
            .map(|h| (h.field.to_string(), h.value.to_string()))
            .collect(),
        body,
        tail,
        len,
    }
}

/// A PrusaLink answer to `/api/version` (and 404 to Moonraker's question).
fn prusalink_question(s: &Seen) -> Option<Reply> {
    match s.url.as_str() {
        "/server/info" => Some((404, vec![], b"not found".to_vec())),
        "/api/version" => Some((
            200,
            vec![],
            br#"{"api":"2.0.0","server":"2.1.2","text":"PrusaLink"}"#.to_vec(),
        )),
        _ => None,
    }
}

/// A stand-in for PrusaLink (no real one runs here: its published API):
/// answers `/api/version` as PrusaLink does, then each upload with
/// `status` and `body`.
fn fake_prusalink_saying(status: u16, body: &'static [u8]) -> StandIn {
    StandIn::start(move |s| prusalink_question(s).unwrap_or((status, vec![], body.to_vec())))
}

fn fake_prusalink(status: u16) -> StandIn {
    fake_prusalink_saying(status, b"")
}

#[test]
fn prusalink_gets_a_put_of_the_bytes_and_a_conflict_is_named() {
    let dir = tmp("send-prusalink");
    std::fs::write(dir.join("a b.bgcode"), b"GCDE\x01\x00\x00\x00 not really").unwrap();
    let server = fake_prusalink(201);
    let ok = send(
        &dir,
        Some("link-key"),
        &["a b.bgcode", "--to", &server.url, "--print"],
    );
    assert!(ok.status.success(), "{}", stderr(&ok));
    let seen = server.seen();
    let put = seen.last().unwrap();
    assert_eq!(
        (put.method.as_str(), put.url.as_str()),
        ("PUT", "/api/v1/files/usb/a%20b.bgcode")
    );
    assert_eq!(put.body, std::fs::read(dir.join("a b.bgcode")).unwrap());
    assert_eq!(put.header("X-Api-Key"), Some("link-key"));
    assert_eq!(put.header("Print-After-Upload"), Some("?1"));
    assert_eq!(put.header("Overwrite-File"), Some("?0"));
    assert!(String::from_utf8_lossy(&ok.stdout).contains("sent to prusalink"));

    let server = fake_prusalink(409);
    let taken = send(&dir, Some("link-key"), &["a b.bgcode", "--to", &server.url]);
    server.seen();
    assert_eq!(taken.status.code(), Some(2));
    assert!(
        stderr(&taken).contains("409 Conflict"),
        "{}",
        stderr(&taken)
    );
}

#[test]
fn a_host_that_never_answers_times_out_by_name() {
    let dir = tmp("send-timeout");
    std::fs::write(dir.join("x.gcode"), "G28\n").unwrap();
    // accepts the connection, never answers
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}", listener.local_addr().unwrap());
    let out = send(&dir, None, &["x.gcode", "--to", &url, "--timeout", "1"]);
    drop(listener);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("did not answer within 1 s"),
        "{}",
        stderr(&out)
    );
}

// ---------------------------------------------------------------------------
// Issue 42: `send` as careful as a package manager, against hostile hosts.

const KEY: &str = "KEY-p3dp-0123456789";

fn gcode_in(dir: &Path) {
    std::fs::write(dir.join("x.gcode"), "G28\nG1 X10 Y10\n").unwrap();
}

#[test]
fn a_redirect_to_another_origin_is_refused_and_never_carries_the_key() {
    let dir = tmp("send-redirect-away");
    gcode_in(&dir);
    // the other origin records anything that reaches it
    let other = StandIn::start(|_| (200, vec![], b"{}".to_vec()));
    let away = format!("{}/steal", other.url);
    let to = away.clone();
    let host = StandIn::start(move |_| (302, vec![("Location", to.clone())], Vec::new()));
    let out = send(&dir, Some(KEY), &["x.gcode", "--to", &host.url]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(&format!(
            "redirects /server/info to another address, `{away}` (HTTP 302)"
        )),
        "{}",
        stderr(&out)
    );
    // an upload answered by a redirect: an error naming it, nothing followed
    let out = send(
        &dir,
        Some(KEY),
        &["x.gcode", "--to", &host.url, "--host", "moonraker"],
    );
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(&format!(
            "the upload with HTTP 302 (a redirect, to `{away}`)"
        )),
        "{}",
        stderr(&out)
    );
    assert!(!String::from_utf8_lossy(&out.stdout).contains("sent"));
    let asked = host.seen();
    assert_eq!(asked.len(), 2, "one question, one upload, no second try");
    assert_eq!(asked[1].method, "POST");
    assert!(other.seen().is_empty(), "the other origin heard nothing");
}

#[test]
fn an_upload_answered_by_a_redirect_within_the_host_is_not_sent() {
    let dir = tmp("send-redirect-upload");
    gcode_in(&dir);
    let host = StandIn::start(|s| {
        prusalink_question(s).unwrap_or((302, vec![("Location", "/login".to_string())], Vec::new()))
    });
    let out = send(&dir, Some(KEY), &["x.gcode", "--to", &host.url]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("HTTP 302 (a redirect, to `/login`)"),
        "{}",
        stderr(&out)
    );
    assert!(String::from_utf8_lossy(&out.stdout).is_empty());
    let asked = host.seen();
    // not turned into a body-less GET of /login
    assert!(asked.iter().all(|s| s.url != "/login"), "followed");
    assert_eq!(asked.last().unwrap().method, "PUT");
}

#[test]
fn a_redirect_within_the_host_is_followed_for_a_question() {
    let dir = tmp("send-redirect-within");
    gcode_in(&dir);
    let host = StandIn::start(|s| match s.url.as_str() {
        "/server/info" => (404, vec![], Vec::new()),
        "/api/version" => (
            301,
            vec![("Location", "/api/version/".to_string())],
            Vec::new(),
        ),
        "/api/version/" => (200, vec![], br#"{"text":"PrusaLink"}"#.to_vec()),
        _ => (201, vec![], Vec::new()),
    });
    let out = send(&dir, Some(KEY), &["x.gcode", "--to", &host.url]);
    assert!(out.status.success(), "{}", stderr(&out));
    let asked = host.seen();
    let followed = asked.iter().find(|s| s.url == "/api/version/").unwrap();
    assert_eq!(followed.header("X-Api-Key"), Some(KEY));
    assert_eq!(asked.last().unwrap().method, "PUT");
}

#[test]
fn credentials_in_the_url_are_sent_but_never_printed() {
    let dir = tmp("send-credentials");
    gcode_in(&dir);
    let password = "pw-S3CRET-99";
    let host = fake_prusalink(201);
    let port = host.url.rsplit(':').next().unwrap().to_string();
    let to = format!("http://maker:{password}@127.0.0.1:{port}");
    let out = send(&dir, None, &["x.gcode", "--to", &to]);
    assert!(out.status.success(), "{}", stderr(&out));
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains(&format!(
            "sent to prusalink at http://127.0.0.1:{port} as usb/x.gcode"
        )),
        "{said}"
    );
    let (o, e) = (said.to_string(), stderr(&out));
    for text in [&o, &e] {
        assert!(
            !text.contains(password) && !text.contains("maker"),
            "{text}"
        );
    }
    assert!(
        e.contains("warning: --to holds a user name and password") && e.contains("P3DP_API_KEY"),
        "{e}"
    );
    let put = host.seen().pop().unwrap();
    // basic authentication: base64 of maker:pw-S3CRET-99
    assert_eq!(
        put.header("Authorization"),
        Some("Basic bWFrZXI6cHctUzNDUkVULTk5")
    );
    // a host echoing both secrets back in an error, a closed port, a bad URL
    let echo: &'static [u8] = b"denied for maker:pw-S3CRET-99 with key KEY-p3dp-0123456789";
    let host = fake_prusalink_saying(500, echo);
    let port = host.url.rsplit(':').next().unwrap().to_string();
    let to = format!("http://maker:{password}@127.0.0.1:{port}");
    let out = send(&dir, Some(KEY), &["x.gcode", "--to", &to]);
    host.seen();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("HTTP 500: denied for ******** with key ********"),
        "{}",
        stderr(&out)
    );
    let closed = format!("http://maker:{password}@127.0.0.1:{}", free_port());
    for to in [
        closed.as_str(),
        "http://maker:pw-S3CRET-99@",
        "http://maker:pw-S3CRET-99@h:x",
    ] {
        let out = send(&dir, Some(KEY), &["x.gcode", "--to", to]);
        assert_eq!(out.status.code(), Some(2), "{to}");
        let e = stderr(&out);
        assert!(!e.contains(password) && !e.contains(KEY), "{e}");
    }
}

#[test]
fn a_hosts_text_reaches_the_terminal_as_short_clean_lines() {
    let dir = tmp("send-hostile-text");
    gcode_in(&dir);
    let mut body = b"\x1b]0;owned\x07\x1b[2J\x1b[31mfirst line\x1b[0m\r\nsecond line, key KEY-p3dp-\x1b[0m0123456789\n\xc2\x9b6n\xe2\x80\xaeend".to_vec();
    body.extend(std::iter::repeat_n(b'z', 1 << 20));
    let body: &'static [u8] = Box::leak(body.into_boxed_slice());
    let host = fake_prusalink_saying(500, body);
    let out = send(&dir, Some(KEY), &["x.gcode", "--to", &host.url]);
    host.seen();
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    assert!(
        e.contains("the host answered HTTP 500:\n    first line\n    second line, key ********\n    endzzz"),
        "{e}"
    );
    assert!(
        !e.contains(['\u{1b}', '\u{7}', '\u{9b}', '\u{202e}']),
        "{e:?}"
    );
    assert!(!e.contains(KEY) && !e.contains("\\u{"), "{e}");
    assert!(e.len() < 2000, "{} bytes: capped", e.len());
    // the file name a host answers with is made printable too
    let host = StandIn::start(|s| {
        match s.url.as_str() {
        "/server/info" => (200, vec![], br#"{"result":{"klippy_state":"ready"}}"#.to_vec()),
        _ => (
            201,
            vec![],
            br#"{"item":{"path":"\u001b[2J\u001b]0;x\u0007evil\nname.gcode"},"print_started":false}"#.to_vec(),
        ),
    }
    });
    let out = send(&dir, Some(KEY), &["x.gcode", "--to", &host.url]);
    host.seen();
    assert!(out.status.success(), "{}", stderr(&out));
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains(" as evil ⏎ name.gcode ("), "{said:?}");
    assert!(!said.contains('\u{1b}'), "{said:?}");
}

#[test]
fn timeouts_past_an_hour_are_refused_not_a_panic() {
    let dir = tmp("send-timeout-cap");
    gcode_in(&dir);
    for t in ["18446744073709551615", "3601", "0"] {
        let out = send(
            &dir,
            None,
            &["x.gcode", "--to", "http://127.0.0.1:9", "--timeout", t],
        );
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert!(
            stderr(&out).contains(&format!(
                "--timeout: {t} s is not allowed; expected 1 to 3600 s"
            )),
            "{}",
            stderr(&out)
        );
        assert!(!stderr(&out).contains("panicked"));
    }
}

/// `p3dp send ARGS` in `dir`, its process id told to `pid` as soon as it
/// starts; killed (and `None`) after `secs`.
fn send_within(
    dir: &Path,
    args: &[&str],
    pid: &std::sync::atomic::AtomicU32,
    secs: u64,
) -> Option<Output> {
    let child = Command::new(env!("CARGO_BIN_EXE_p3dp"))
        .arg("send")
        .args(args)
        .current_dir(dir)
        .env_remove("P3DP_API_KEY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let id = child.id();
    pid.store(id, std::sync::atomic::Ordering::SeqCst);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    match rx.recv_timeout(Duration::from_secs(secs)) {
        Ok(out) => Some(out.unwrap()),
        Err(_) => {
            let _ = Command::new("kill")
                .args(["-KILL", &id.to_string()])
                .status();
            None
        }
    }
}

/// The peak resident memory of process `pid`, kB (`VmHWM`).
fn peak_kb(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

#[test]
fn a_fifo_is_refused_unopened() {
    use std::sync::atomic::AtomicU32;
    let dir = tmp("send-fifo");
    gcode_in(&dir);
    let made = Command::new("mkfifo").arg(dir.join("pipe.gcode")).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
    let host = fake_prusalink(201);
    let pid = AtomicU32::new(0);
    // no writer ever opens the FIFO: reading it would hang
    let out = send_within(
        &dir,
        &["x.gcode", "pipe.gcode", "--to", &host.url],
        &pid,
        30,
    )
    .expect("a FIFO hung `send`");
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("pipe.gcode` is a FIFO; expected a regular file"),
        "{}",
        stderr(&out)
    );
    assert!(
        host.seen().is_empty(),
        "nothing is sent when one file is refused"
    );
}

/// The upload's whole point is its size (2 GB through loopback, seconds of
/// both cores): an ignored test, which CI runs (`.ci/run`, README).
#[test]
#[ignore = "heavy: CI runs it, see README"]
fn a_2_gb_file_is_streamed() {
    use std::io::{Seek, SeekFrom, Write};
    use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
    use std::sync::Arc;
    let dir = tmp("send-streamed");

    // 2 GiB and 5 bytes, sparse, marked at both ends
    let size: u64 = (2 << 30) + 5;
    let mut f = std::fs::File::create(dir.join("big.gcode")).unwrap();
    f.write_all(b";head").unwrap();
    f.seek(SeekFrom::Start(size - 5)).unwrap();
    f.write_all(b";tail").unwrap();
    drop(f);
    let pid = Arc::new(AtomicU32::new(0));
    let peak = Arc::new(AtomicU64::new(0));
    let (p, k) = (pid.clone(), peak.clone());
    let host = StandIn::start(move |s| {
        prusalink_question(s).unwrap_or_else(|| {
            // the whole body is in: p3dp waits for the answer
            k.store(peak_kb(p.load(Ordering::SeqCst)), Ordering::SeqCst);
            (201, vec![], Vec::new())
        })
    });
    let out = send_within(&dir, &["big.gcode", "--to", &host.url], &pid, 300)
        .expect("a 2 GB upload within 5 minutes");
    assert!(out.status.success(), "{}", stderr(&out));
    let put = host.seen().pop().unwrap();
    assert_eq!(put.len, size);
    assert_eq!(
        put.header("Content-Length"),
        Some(size.to_string().as_str())
    );
    assert!(put.body.starts_with(b";head") && put.tail.ends_with(b";tail"));
    let peak = peak.load(Ordering::SeqCst);
    assert!(
        peak > 0 && peak < 256 << 10,
        "peak memory {peak} kB: not streamed"
    );
    // sparse, but no test leaves a 2 GB file behind
    std::fs::remove_file(dir.join("big.gcode")).unwrap();
}
