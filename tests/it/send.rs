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
    let mut config = std::fs::read_to_string(base.join("config.yaml")).unwrap_or_default();
    config.push_str(
        "server:\n  firstRun: false\n  onlineCheck:\n    enabled: false\n  pluginBlacklist:\n    enabled: false\nplugins:\n  tracking:\n    enabled: false\n  announcements:\n    enabled: false\n",
    );
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

/// What a stand-in PrusaLink saw of one request.
struct Seen {
    method: String,
    url: String,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

/// A stand-in for PrusaLink (no real one runs here: its published API):
/// answers `/api/version` as PrusaLink does, then each upload with
/// `status`; what it saw comes back when the thread ends.
fn fake_prusalink(status: u16, uploads: usize) -> (String, std::thread::JoinHandle<Vec<Seen>>) {
    let server = tiny_http::Server::http("127.0.0.1:0").unwrap();
    let url = format!("http://{}", server.server_addr().to_ip().unwrap());
    let thread = std::thread::spawn(move || {
        let mut seen = Vec::new();
        let mut left = uploads;
        while left > 0 {
            let mut req = server.recv().unwrap();
            let mut body = Vec::new();
            req.as_reader().read_to_end(&mut body).unwrap();
            let path = req.url().to_string();
            let (code, text) = match path.as_str() {
                "/server/info" => (404, String::from("not found")),
                "/api/version" => (
                    200,
                    r#"{"api":"2.0.0","server":"2.1.2","text":"PrusaLink"}"#.to_string(),
                ),
                _ => {
                    left -= 1;
                    (status, String::new())
                }
            };
            seen.push(Seen {
                method: req.method().to_string(),
                url: path,
                headers: req
                    .headers()
                    .iter()
                    .map(|h| (h.field.to_string(), h.value.to_string()))
                    .collect(),
                body,
            });
            req.respond(tiny_http::Response::from_string(text).with_status_code(code))
                .unwrap();
        }
        seen
    });
    (url, thread)
}

#[test]
fn prusalink_gets_a_put_of_the_bytes_and_a_conflict_is_named() {
    let dir = tmp("send-prusalink");
    std::fs::write(dir.join("a b.bgcode"), b"GCDE\x01\x00\x00\x00 not really").unwrap();
    let (url, server) = fake_prusalink(201, 1);
    let ok = send(
        &dir,
        Some("link-key"),
        &["a b.bgcode", "--to", &url, "--print"],
    );
    assert!(ok.status.success(), "{}", stderr(&ok));
    let seen = server.join().unwrap();
    let put = seen.last().unwrap();
    assert_eq!(
        (put.method.as_str(), put.url.as_str()),
        ("PUT", "/api/v1/files/usb/a%20b.bgcode")
    );
    assert_eq!(put.body, std::fs::read(dir.join("a b.bgcode")).unwrap());
    let header = |k: &str| {
        put.headers
            .iter()
            .find(|(h, _)| h.eq_ignore_ascii_case(k))
            .map(|(_, v)| v.as_str())
    };
    assert_eq!(header("X-Api-Key"), Some("link-key"));
    assert_eq!(header("Print-After-Upload"), Some("?1"));
    assert_eq!(header("Overwrite-File"), Some("?0"));
    assert!(String::from_utf8_lossy(&ok.stdout).contains("sent to prusalink"));

    let (url, server) = fake_prusalink(409, 1);
    let taken = send(&dir, Some("link-key"), &["a b.bgcode", "--to", &url]);
    server.join().unwrap();
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
