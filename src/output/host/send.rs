//! Uploads to the software that runs a printer, by each one's published
//! HTTP API:
//!
//! - Moonraker (Klipper's, behind Mainsail and Fluidd): `POST
//!   /server/files/upload`, a multipart form with `root=gcodes`, `print`
//!   and the file; it answers `201` and whether the print started.
//! - OctoPrint: `POST /api/files/local`, a multipart form with the file,
//!   `select` and `print`; its API keys belong to users (`X-Api-Key`). A
//!   POST with a wrong key fails its CSRF check: `400 CSRF validation
//!   failed`, not `401`.
//! - PrusaLink (Prusa's MK4, XL, MINI, Core One): `PUT
//!   /api/v1/files/usb/NAME` with the bytes as the body, `Print-After-Upload`
//!   and `Overwrite-File: ?0` (its OpenAPI description; no PrusaLink server
//!   runs in the tests).
//!
//! Which one answers is found by asking Moonraker's `/server/info` first,
//! then `/api/version`, whose `text` names OctoPrint or PrusaLink. Hosts
//! write an upload to a temporary file and move it into place only once it
//! is whole, so a transfer that fails leaves no partial file behind.

use std::io::{self, Read};
use std::time::Duration;

use crate::base::error::{Error, Result};

/// The host software at the other end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Host {
    /// Moonraker (Klipper).
    Moonraker,
    /// OctoPrint.
    OctoPrint,
    /// PrusaLink.
    PrusaLink,
}

impl Host {
    /// The host's name as the command line spells it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Host::Moonraker => "moonraker",
            Host::OctoPrint => "octoprint",
            Host::PrusaLink => "prusalink",
        }
    }

    /// The host a `--host` name means.
    pub(crate) fn of_name(name: &str) -> Option<Host> {
        [Host::Moonraker, Host::OctoPrint, Host::PrusaLink]
            .into_iter()
            .find(|h| h.name().eq_ignore_ascii_case(name))
    }
}

/// Where and how to send.
#[derive(Clone, Debug)]
pub(crate) struct Target {
    /// The host's base URL (`http://printer.local`, `http://10.0.0.5:7125`).
    pub url: String,
    /// Its API key (`X-Api-Key`), when it asks for one.
    pub key: Option<String>,
    /// How long a request may take, connecting included.
    pub timeout: Duration,
}

/// What a host said to an upload.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Sent {
    /// The file's path on the host.
    pub path: String,
    /// Whether the host says the print started (or was queued).
    pub printing: bool,
}

impl Target {
    fn agent(&self) -> ureq::Agent {
        ureq::Agent::config_builder()
            .timeout_global(Some(self.timeout))
            .http_status_as_error(false)
            .build()
            .into()
    }

    fn at(&self, path: &str) -> String {
        format!("{}{path}", self.url.trim_end_matches('/'))
    }

    /// A request failure as the user's error: the cause named.
    fn failed(&self, e: ureq::Error) -> Error {
        let why = match &e {
            ureq::Error::Timeout(_) => format!(
                "the host did not answer within {} s (--timeout sets the limit)",
                self.timeout.as_secs()
            ),
            ureq::Error::HostNotFound => "the host name does not resolve".to_string(),
            ureq::Error::ConnectionFailed => {
                "nothing answers there (connection refused): is the host running, and are the address and port right?".to_string()
            }
            ureq::Error::Io(io) if io.kind() == io::ErrorKind::ConnectionRefused => {
                "nothing answers there (connection refused): is the host running, and are the address and port right?".to_string()
            }
            ureq::Error::Io(io) if io.kind() == io::ErrorKind::TimedOut => format!(
                "the host did not answer within {} s (--timeout sets the limit)",
                self.timeout.as_secs()
            ),
            ureq::Error::Io(io)
                if matches!(io.kind(), io::ErrorKind::BrokenPipe | io::ErrorKind::ConnectionReset) =>
            {
                "the host closed the connection before the file was whole (hosts do so for a wrong API key or a file they refuse); it keeps no part of it".to_string()
            }
            ureq::Error::BadUri(u) => format!("`{u}` is not a URL; expected http://HOST[:PORT]"),
            other => format!("the request failed: {other}"),
        };
        Error::io(self.url.clone(), why)
    }

    /// An answer other than success as the user's error.
    fn refused(&self, status: u16, body: &str) -> Error {
        let short: String = crate::base::safe_text::one_line(body.trim())
            .chars()
            .take(200)
            .collect();
        let why = match status {
            400 if body.contains("CSRF") => "the host refused the API key (OctoPrint's 400 \"CSRF validation failed\": a wrong or missing key); set P3DP_API_KEY to a key of a user of this host".to_string(),
            401 | 403 => format!("the host refused the API key (HTTP {status}); set P3DP_API_KEY to a valid key of this host"),
            409 => "a file of that name is on the host already, or it is printing it, and the host refused to replace it (HTTP 409 Conflict)".to_string(),
            413 => "the host refused the file as too large (HTTP 413)".to_string(),
            415 => "the host does not take this kind of file (HTTP 415)".to_string(),
            507 => "the host has no room for the file (HTTP 507)".to_string(),
            _ => format!("the host answered HTTP {status}: {short}"),
        };
        Error::io(self.url.clone(), why)
    }

    /// A GET of `path`: its status and body (empty when unreadable).
    fn get(&self, path: &str) -> Result<(u16, String)> {
        let mut req = self.agent().get(self.at(path));
        if let Some(k) = &self.key {
            req = req.header("X-Api-Key", k);
        }
        let mut resp = req.call().map_err(|e| self.failed(e))?;
        let body = resp.body_mut().read_to_string().unwrap_or_default();
        Ok((resp.status().as_u16(), body))
    }

    /// Which host answers at the URL.
    pub(crate) fn detect(&self) -> Result<Host> {
        let (status, body) = self.get("/server/info")?;
        let json: Option<serde_json::Value> = serde_json::from_str(&body).ok();
        let moonraker = json.as_ref().is_some_and(|j| {
            j.get("result")
                .is_some_and(|r| r.get("klippy_state").is_some())
                || j.pointer("/error/code").is_some()
        });
        if moonraker && status == 200 {
            return Ok(Host::Moonraker);
        }
        if moonraker && (status == 401 || status == 403) {
            // refused before an upload whose body it would not read
            return Err(self.refused(status, &body));
        }
        let (status, body) = self.get("/api/version")?;
        let text = serde_json::from_str::<serde_json::Value>(&body)
            .ok()
            .and_then(|j| j.get("text").and_then(|t| t.as_str()).map(str::to_string))
            .unwrap_or_default();
        if status == 200 && text.contains("OctoPrint") {
            return Ok(Host::OctoPrint);
        }
        if status == 200 && text.contains("PrusaLink") {
            return Ok(Host::PrusaLink);
        }
        if status == 401 || status == 403 {
            return Err(self
                .refused(status, &body)
                .with_help("p3dp asked /api/version which host this is; name it with --host octoprint|prusalink|moonraker"));
        }
        Err(Error::io(
            self.url.clone(),
            format!("neither Moonraker, OctoPrint nor PrusaLink answers here (/api/version: HTTP {status})"),
        )
        .with_help("give the host's base URL, e.g. http://printer.local:7125 for Moonraker, or name it with --host"))
    }

    /// Uploads `bytes` as `name` to `host`, starting the print if `print`;
    /// `progress` hears the bytes sent so far.
    pub(crate) fn upload(
        &self,
        host: Host,
        name: &str,
        bytes: &[u8],
        print: bool,
        progress: &mut dyn FnMut(u64),
    ) -> Result<Sent> {
        let flag = if print { "true" } else { "false" };
        let (req, body, ctype) = match host {
            Host::Moonraker => {
                let fields = [("root", "gcodes"), ("print", flag)];
                let (body, ctype) = multipart(&fields, name, bytes);
                (
                    self.agent().post(self.at("/server/files/upload")),
                    body,
                    ctype,
                )
            }
            Host::OctoPrint => {
                let fields = [("select", flag), ("print", flag)];
                let (body, ctype) = multipart(&fields, name, bytes);
                (self.agent().post(self.at("/api/files/local")), body, ctype)
            }
            Host::PrusaLink => {
                let path = format!("/api/v1/files/usb/{}", percent(name));
                let req = self
                    .agent()
                    .put(self.at(&path))
                    .header("Print-After-Upload", if print { "?1" } else { "?0" })
                    .header("Overwrite-File", "?0");
                (req, bytes.to_vec(), "application/octet-stream".to_string())
            }
        };
        let mut req = req
            .header("Content-Type", ctype)
            .header("Content-Length", body.len().to_string());
        if let Some(k) = &self.key {
            req = req.header("X-Api-Key", k);
        }
        let mut reader = Counting {
            inner: &body[..],
            done: 0,
            progress,
        };
        let mut resp = req
            .send(ureq::SendBody::from_reader(&mut reader))
            .map_err(|e| self.failed(e))?;
        let status = resp.status().as_u16();
        let text = resp.body_mut().read_to_string().unwrap_or_default();
        if !(200..300).contains(&status) {
            return Err(self.refused(status, &text));
        }
        Ok(answer(host, name, print, &text))
    }
}

/// What a host's success answer says: the file's path and whether it prints.
fn answer(host: Host, name: &str, print: bool, text: &str) -> Sent {
    let j: serde_json::Value = serde_json::from_str(text).unwrap_or_default();
    let s = |p: &str| j.pointer(p).and_then(|v| v.as_str()).map(str::to_string);
    let b = |p: &str| j.pointer(p).and_then(|v| v.as_bool()).unwrap_or(false);
    match host {
        Host::Moonraker => Sent {
            path: s("/item/path").unwrap_or_else(|| name.to_string()),
            printing: b("/print_started") || b("/print_queued"),
        },
        Host::OctoPrint => Sent {
            path: s("/files/local/path").unwrap_or_else(|| name.to_string()),
            printing: b("/effectivePrint"),
        },
        // PrusaLink answers 201 with no body: the print starts as asked
        Host::PrusaLink => Sent {
            path: format!("usb/{name}"),
            printing: print,
        },
    }
}

/// A reader that reports how much of it was read.
struct Counting<'a, 'p> {
    inner: &'a [u8],
    done: u64,
    progress: &'p mut dyn FnMut(u64),
}

impl Read for Counting<'_, '_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.done += n as u64;
        (self.progress)(self.done);
        Ok(n)
    }
}

/// A `multipart/form-data` body (RFC 7578) of text `fields` and the file:
/// the body and its content type. The boundary is made of the file's MD5,
/// lengthened until it is found nowhere in the file.
fn multipart(fields: &[(&str, &str)], name: &str, bytes: &[u8]) -> (Vec<u8>, String) {
    use md5::Digest;
    let mut boundary: String = md5::Md5::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    boundary.insert_str(0, "p3dp-");
    while bytes
        .windows(boundary.len())
        .any(|w| w == boundary.as_bytes())
    {
        boundary.push('x');
    }
    let file_name: String = name
        .chars()
        .map(|c| {
            if c == '"' || c == '\\' || c.is_control() {
                '_'
            } else {
                c
            }
        })
        .collect();
    let mut body = Vec::with_capacity(bytes.len() + 512);
    for (k, v) in fields {
        body.extend_from_slice(
            format!("--{boundary}\r\nContent-Disposition: form-data; name=\"{k}\"\r\n\r\n{v}\r\n")
                .as_bytes(),
        );
    }
    body.extend_from_slice(
        format!(
            "--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"{file_name}\"\r\nContent-Type: application/octet-stream\r\n\r\n"
        )
        .as_bytes(),
    );
    body.extend_from_slice(bytes);
    body.extend_from_slice(format!("\r\n--{boundary}--\r\n").as_bytes());
    (body, format!("multipart/form-data; boundary={boundary}"))
}

/// `s` with every byte but RFC 3986's unreserved ones percent-encoded.
fn percent(s: &str) -> String {
    s.bytes()
        .map(|b| {
            if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
                (b as char).to_string()
            } else {
                format!("%{b:02X}")
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn multipart_bodies_frame_the_file() {
        let (body, ctype) = multipart(&[("root", "gcodes")], "a\"b.gcode", b"G28\r\n");
        let boundary = ctype
            .strip_prefix("multipart/form-data; boundary=")
            .unwrap();
        let text = String::from_utf8(body).unwrap();
        assert!(text.starts_with(&format!("--{boundary}\r\n")));
        assert!(text.ends_with(&format!("\r\n--{boundary}--\r\n")));
        assert!(text.contains("filename=\"a_b.gcode\""));
        assert!(text.contains("\r\n\r\nG28\r\n\r\n--"));
        assert_eq!(percent("a b/ü.gcode"), "a%20b%2F%C3%BC.gcode");
        assert_eq!(Host::of_name("OctoPrint"), Some(Host::OctoPrint));
    }
}
