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
//!
//! As careful as a package manager with what it sends and what it prints:
//!
//! - **Redirects.** None is followed by the HTTP client. A question (a
//!   GET) follows at most [`MAX_REDIRECTS`] redirects within the origin
//!   `--to` names (scheme, host and port), never to another with the key;
//!   an upload follows none: a 3xx is an error naming the status and the
//!   `Location` (a client that follows a 302 turns the upload into a GET
//!   without its body, and the host "takes" nothing).
//! - **Credentials.** A user and password in `--to` are sent (HTTP basic
//!   authentication) but never printed: every address shown is
//!   [`Address::shown`], and every text printed has them and the API key
//!   masked.
//! - **A host's text** (an error body, the file name it answers, a
//!   `Location`) is read at most [`ANSWER_BYTES`] and made printable by
//!   [`printable`] before it reaches a terminal.
//! - **Time.** `--timeout` bounds each silence (resolving, connecting, each
//!   write of the upload, the wait for the answer and its reading); a
//!   question is bounded whole. At most [`MAX_TIMEOUT_S`].
//! - **The file** is streamed from disk, never read whole: a 2 GB upload
//!   costs a buffer, not 2 GB.

use std::io::{self, Read, Seek};
use std::time::Duration;

use crate::base::error::{Error, Result};

/// Longest `--timeout`, s (an hour): past it a host is not answering.
pub(crate) const MAX_TIMEOUT_S: u64 = 3600;

/// Most redirects a question follows within its origin.
pub(crate) const MAX_REDIRECTS: usize = 5;

/// Most bytes of a host's answer read (the rest is never read).
pub(crate) const ANSWER_BYTES: u64 = 64 << 10;

/// Most lines, and characters a line, of a host's text printed.
const SHOWN_LINES: usize = 20;
const SHOWN_LINE_CHARS: usize = 200;

/// Shortest secret masked in what is printed: a shorter one would mask
/// ordinary text.
const MIN_SECRET_CHARS: usize = 3;

/// What replaces a secret in anything printed.
const MASK: &str = "********";

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

/// The host's base URL, `http://[USER:PASSWORD@]HOST[:PORT][/PATH]`, taken
/// apart so that its credentials are sent and never shown.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Address {
    /// `HOST[:PORT]` as given (no credentials).
    authority: String,
    /// The host, lower case, for comparing origins.
    host: String,
    /// The port (80 when not given).
    port: u16,
    /// The base path, no trailing `/` (`""` or `/octoprint`).
    path: String,
    /// `USER:PASSWORD` when given.
    userinfo: Option<String>,
}

/// `text` (a URL the user gave) with anything between `://` and `@`
/// masked, one line: safe to print in an error about it.
pub(crate) fn redact(text: &str) -> String {
    let (scheme, rest) = match text.split_once("://") {
        Some((scheme, rest)) => (format!("{scheme}://"), rest),
        None => (String::new(), text),
    };
    let end = rest.find(['/', '?', '#']).unwrap_or(rest.len());
    let shown = match rest[..end].rfind('@') {
        Some(at) => format!("{scheme}{MASK}@{}", &rest[at + 1..]),
        None => text.to_string(),
    };
    crate::base::safe_text::one_line(&shown).into_owned()
}

impl Address {
    /// Parses `--to`: plain HTTP, a host, an optional port and base path,
    /// no query; an error shows the text with its credentials masked.
    pub(crate) fn parse(text: &str) -> Result<Address> {
        let bad = |why: &str| {
            Error::input(
                "--to",
                format!(
                    "`{}` {why}; expected http://HOST[:PORT] (a base path may follow)",
                    redact(text)
                ),
            )
        };
        if text.starts_with("https://") {
            return Err(Error::input(
                "--to",
                "p3dp speaks plain HTTP only (printer hosts on a local network); expected http://HOST[:PORT]",
            ));
        }
        if !text.starts_with("http://") {
            return Err(bad("is not a URL"));
        }
        let uri: ureq::http::Uri = text.parse().map_err(|_| bad("is not a URL"))?;
        let (Some(auth), Some(host)) = (uri.authority(), uri.host()) else {
            return Err(bad("names no host"));
        };
        if host.is_empty() {
            return Err(bad("names no host"));
        }
        if uri.query().is_some() {
            return Err(bad("has a query (`?…`)"));
        }
        let (userinfo, authority) = match auth.as_str().rsplit_once('@') {
            Some((u, a)) => (Some(u.to_string()), a.to_string()),
            None => (None, auth.as_str().to_string()),
        };
        Ok(Address {
            authority,
            host: host.to_ascii_lowercase(),
            port: uri.port_u16().unwrap_or(80),
            path: uri.path().trim_end_matches('/').to_string(),
            userinfo,
        })
    }

    /// The address as printed: no credentials.
    pub(crate) fn shown(&self) -> String {
        crate::base::safe_text::one_line(&format!("http://{}{}", self.authority, self.path))
            .into_owned()
    }

    /// Whether `--to` carries a user and password.
    pub(crate) fn has_credentials(&self) -> bool {
        self.userinfo.is_some()
    }

    /// `http://[CREDENTIALS@]AUTHORITY` followed by `path_and_query`: what
    /// is requested, never shown.
    fn url(&self, path_and_query: &str) -> String {
        match &self.userinfo {
            Some(u) => format!("http://{u}@{}{path_and_query}", self.authority),
            None => format!("http://{}{path_and_query}", self.authority),
        }
    }

    /// The secrets of the address: the credentials, the password alone,
    /// and each percent-decoded.
    fn secrets(&self) -> Vec<String> {
        let Some(u) = &self.userinfo else {
            return Vec::new();
        };
        let mut v = vec![u.clone()];
        if let Some((_, pw)) = u.split_once(':') {
            v.push(pw.to_string());
        }
        let decoded: Vec<String> = v.iter().map(|s| percent_decode(s)).collect();
        v.extend(decoded);
        v
    }

    /// The path and query of a redirect's `location`, seen from `from` (a
    /// path and query), when it stays within this origin; `None` when it
    /// leaves it (another scheme, host or port) or is no URL.
    fn within(&self, from: &str, location: &str) -> Option<String> {
        let loc = location.trim();
        if loc.is_empty() || loc.chars().any(|c| c.is_control() || c.is_whitespace()) {
            return None;
        }
        let absolute = if let Some(rest) = loc.strip_prefix("//") {
            Some(format!("http://{rest}"))
        } else if loc.contains("://") {
            Some(loc.to_string())
        } else {
            None
        };
        if let Some(abs) = absolute {
            let uri: ureq::http::Uri = abs.parse().ok()?;
            let same = uri.scheme_str() == Some("http")
                && uri.host().map(str::to_ascii_lowercase) == Some(self.host.clone())
                && uri.port_u16().unwrap_or(80) == self.port;
            return same.then(|| {
                uri.path_and_query()
                    .map_or("/".to_string(), |p| p.as_str().to_string())
            });
        }
        if loc.starts_with('/') {
            return Some(loc.to_string());
        }
        // relative to the folder of the path asked
        let path = from.split(['?', '#']).next().unwrap_or("");
        let dir = &path[..path.rfind('/').map_or(0, |k| k + 1)];
        Some(format!("{dir}{loc}"))
    }
}

/// `%XX` sequences decoded (as a server reads credentials), others kept.
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut k = 0;
    while k < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[k] == b'%' && k + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[k + 1]), hex(b[k + 2])) {
                out.push((h * 16 + l) as u8);
                k += 3;
                continue;
            }
        }
        out.push(b[k]);
        k += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// A host's text made safe and readable for a terminal, as lines: terminal
/// escape sequences (CSI `ESC [ … final`, OSC `ESC ] … BEL|ST`, DCS, SOS,
/// PM and APC strings up to ST, their C1 forms, two-character escapes)
/// removed; every other control character and bidirectional override
/// removed, a tab made a space; every kind of line break (CR LF, CR, NEL,
/// U+2028, U+2029, VT, FF) a new line; each secret (≥ 3 characters) masked
/// after that (so escapes cannot split one); blank lines at the ends
/// dropped; at most 20 lines of 200 characters, the cut said.
pub(crate) fn printable(text: &str, secrets: &[String]) -> Vec<String> {
    let mut clean = strip_terminal(text);
    let mut secrets: Vec<&str> = secrets
        .iter()
        .map(String::as_str)
        .filter(|s| s.chars().count() >= MIN_SECRET_CHARS)
        .collect();
    // longest first: a secret holding another is masked whole
    secrets.sort_by_key(|s| std::cmp::Reverse(s.len()));
    for s in secrets {
        clean = clean.replace(s, MASK);
    }
    let lines: Vec<&str> = clean.split('\n').map(str::trim_end).collect();
    let first = lines.iter().position(|l| !l.trim().is_empty());
    let last = lines.iter().rposition(|l| !l.trim().is_empty());
    let (Some(first), Some(last)) = (first, last) else {
        return Vec::new();
    };
    let lines = &lines[first..=last];
    let mut out: Vec<String> = lines
        .iter()
        .take(SHOWN_LINES)
        .map(|l| {
            let n = l.chars().count();
            if n > SHOWN_LINE_CHARS {
                let cut: String = l.chars().take(SHOWN_LINE_CHARS).collect();
                format!("{cut}… ({} more characters)", n - SHOWN_LINE_CHARS)
            } else {
                l.to_string()
            }
        })
        .collect();
    if lines.len() > SHOWN_LINES {
        out.push(format!("… ({} more lines)", lines.len() - SHOWN_LINES));
    }
    out
}

/// [`printable`] as one line: its lines joined by ` ⏎ `.
pub(crate) fn printable_line(text: &str, secrets: &[String]) -> String {
    printable(text, secrets).join(" ⏎ ")
}

/// `lines` after `lead`: on the same line when there is one, else each on
/// a line of its own, indented by four spaces.
fn block(lead: &str, lines: &[String]) -> String {
    match lines {
        [] => lead.to_string(),
        [one] => format!("{lead}: {one}"),
        many => format!("{lead}:\n    {}", many.join("\n    ")),
    }
}

/// Whether `c` reorders text on a terminal (bidirectional embeddings,
/// overrides and isolates, the marks), which could make a host's text read
/// other than it is.
fn is_bidi(c: char) -> bool {
    matches!(c, '\u{061c}' | '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

/// `text` without terminal escape sequences and control characters, its
/// line breaks made `\n` (see [`printable`]).
fn strip_terminal(text: &str) -> String {
    let mut out = String::with_capacity(text.len().min(1 << 16));
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\r' => {
                if chars.peek() == Some(&'\n') {
                    chars.next();
                }
                out.push('\n');
            }
            '\n' | '\u{0b}' | '\u{0c}' | '\u{85}' | '\u{2028}' | '\u{2029}' => out.push('\n'),
            '\t' => out.push(' '),
            '\u{1b}' => match chars.next() {
                Some('[') => skip_csi(&mut chars),
                Some(']' | 'P' | 'X' | '^' | '_') => skip_string(&mut chars),
                // a two-character escape (or a lone one at the end)
                _ => {}
            },
            '\u{9b}' => skip_csi(&mut chars),
            '\u{9d}' | '\u{90}' | '\u{98}' | '\u{9e}' | '\u{9f}' => skip_string(&mut chars),
            c if c.is_control() || is_bidi(c) => {}
            c => out.push(c),
        }
    }
    out
}

/// Skips a CSI sequence's parameters and intermediates up to its final
/// byte (`@`–`~`), or to the text's end.
fn skip_csi(chars: &mut std::iter::Peekable<std::str::Chars>) {
    for c in chars.by_ref() {
        if ('@'..='~').contains(&c) {
            break;
        }
    }
}

/// Skips a control string (OSC, DCS, SOS, PM, APC) up to its terminator:
/// BEL, ST (`ESC \` or U+009C), or the text's end.
fn skip_string(chars: &mut std::iter::Peekable<std::str::Chars>) {
    while let Some(c) = chars.next() {
        match c {
            '\u{7}' | '\u{9c}' => break,
            '\u{1b}' => {
                if chars.peek() == Some(&'\\') {
                    chars.next();
                }
                break;
            }
            _ => {}
        }
    }
}

/// Where and how to send.
#[derive(Clone, Debug)]
pub(crate) struct Target {
    /// The host's base URL.
    pub(crate) address: Address,
    /// Its API key (`X-Api-Key`), when it asks for one.
    pub(crate) key: Option<String>,
    /// How long the host may stay silent (see the module's notes).
    pub(crate) timeout: Duration,
}

/// What a host said to an upload.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Sent {
    /// The file's path on the host, printable.
    pub(crate) path: String,
    /// Whether the host says the print started (or was queued).
    pub(crate) printing: bool,
}

/// A host's answer: its status, `Location` and at most [`ANSWER_BYTES`]
/// of its body.
struct Answer {
    status: u16,
    location: Option<String>,
    body: String,
}

impl Answer {
    fn of(mut resp: ureq::http::Response<ureq::Body>) -> Answer {
        let location = resp
            .headers()
            .get("location")
            .map(|v| String::from_utf8_lossy(v.as_bytes()).into_owned());
        let mut buf = Vec::new();
        // an unreadable or cut answer is what was read of it
        let _ = resp
            .body_mut()
            .as_reader()
            .take(ANSWER_BYTES)
            .read_to_end(&mut buf);
        Answer {
            status: resp.status().as_u16(),
            location,
            body: String::from_utf8_lossy(&buf).into_owned(),
        }
    }

    fn redirects(&self) -> bool {
        (300..400).contains(&self.status) && self.status != 304
    }
}

impl Target {
    /// An HTTP client that follows no redirect and bounds every wait by the
    /// timeout (a question also as a whole).
    fn agent(&self, question: bool) -> ureq::Agent {
        let t = Some(self.timeout);
        ureq::Agent::config_builder()
            .http_status_as_error(false)
            .max_redirects(0)
            .timeout_global(if question { t } else { None })
            .timeout_resolve(t)
            .timeout_connect(t)
            .timeout_send_request(t)
            .timeout_per_write(t)
            .timeout_per_read(t)
            .timeout_recv_response(t)
            .timeout_recv_body(t)
            .build()
            .into()
    }

    /// Everything printed is masked of these.
    fn secrets(&self) -> Vec<String> {
        let mut v = self.address.secrets();
        v.extend(self.key.clone());
        v
    }

    /// A host's text as printable lines.
    fn printable(&self, text: &str) -> Vec<String> {
        printable(text, &self.secrets())
    }

    /// An error about the host: its address shown, no credentials.
    fn error(&self, why: String) -> Error {
        Error::io(self.address.shown(), why)
    }

    /// A request failure as the user's error: the cause named.
    fn failed(&self, e: ureq::Error) -> Error {
        let silent = || {
            format!(
                "the host did not answer within {} s (--timeout sets the limit)",
                self.timeout.as_secs()
            )
        };
        let refused = "nothing answers there (connection refused): is the host running, and are the address and port right?";
        let why = match &e {
            ureq::Error::Timeout(_) => silent(),
            ureq::Error::HostNotFound => "the host name does not resolve".to_string(),
            ureq::Error::ConnectionFailed => refused.to_string(),
            ureq::Error::Io(io) if io.kind() == io::ErrorKind::ConnectionRefused => {
                refused.to_string()
            }
            ureq::Error::Io(io) if io.kind() == io::ErrorKind::TimedOut => silent(),
            ureq::Error::Io(io)
                if matches!(io.kind(), io::ErrorKind::BrokenPipe | io::ErrorKind::ConnectionReset) =>
            {
                "the host closed the connection before the file was whole (hosts do so for a wrong API key or a file they refuse); it keeps no part of it".to_string()
            }
            ureq::Error::BadUri(_) => format!(
                "`{}` is not a URL; expected http://HOST[:PORT]",
                self.address.shown()
            ),
            other => format!(
                "the request failed: {}",
                printable_line(&other.to_string(), &self.secrets())
            ),
        };
        self.error(why)
    }

    /// An answer other than success as the user's error, the host's own
    /// text printable.
    fn refused(&self, status: u16, body: &str) -> Error {
        let why = match status {
            400 if body.contains("CSRF") => "the host refused the API key (OctoPrint's 400 \"CSRF validation failed\": a wrong or missing key); set P3DP_API_KEY to a key of a user of this host".to_string(),
            401 | 403 => format!("the host refused the API key (HTTP {status}); set P3DP_API_KEY to a valid key of this host"),
            409 => "a file of that name is on the host already, or it is printing it, and the host refused to replace it (HTTP 409 Conflict)".to_string(),
            413 => "the host refused the file as too large (HTTP 413)".to_string(),
            415 => "the host does not take this kind of file (HTTP 415)".to_string(),
            507 => "the host has no room for the file (HTTP 507)".to_string(),
            _ => block(&format!("the host answered HTTP {status}"), &self.printable(body)),
        };
        self.error(why)
    }

    /// The `Location` of a redirect, printable.
    fn location(&self, a: &Answer) -> String {
        printable_line(a.location.as_deref().unwrap_or(""), &self.secrets())
    }

    /// A GET of `path`, following redirects within the origin only.
    fn get(&self, path: &str) -> Result<Answer> {
        let mut at = format!("{}{path}", self.address.path);
        for _ in 0..=MAX_REDIRECTS {
            let mut req = self.agent(true).get(self.address.url(&at));
            if let Some(k) = &self.key {
                req = req.header("X-Api-Key", k);
            }
            let a = Answer::of(req.call().map_err(|e| self.failed(e))?);
            let Some(loc) = a.location.as_deref().filter(|_| a.redirects()) else {
                return Ok(a);
            };
            at = self.address.within(&at, loc).ok_or_else(|| {
                self.error(format!(
                    "the host redirects {path} to another address, `{}` (HTTP {}); p3dp follows a redirect only within the address --to names, never to another with the API key: give --to that address if it is the printer's",
                    self.location(&a),
                    a.status
                ))
            })?;
        }
        Err(self.error(format!(
            "the host redirects {path} more than {MAX_REDIRECTS} times; expected an answer"
        )))
    }

    /// Which host answers at the URL.
    pub(crate) fn detect(&self) -> Result<Host> {
        let a = self.get("/server/info")?;
        let json: Option<serde_json::Value> = serde_json::from_str(&a.body).ok();
        let moonraker = json.as_ref().is_some_and(|j| {
            j.get("result")
                .is_some_and(|r| r.get("klippy_state").is_some())
                || j.pointer("/error/code").is_some()
        });
        if moonraker && a.status == 200 {
            return Ok(Host::Moonraker);
        }
        if moonraker && (a.status == 401 || a.status == 403) {
            // refused before an upload whose body it would not read
            return Err(self.refused(a.status, &a.body));
        }
        let a = self.get("/api/version")?;
        let text = serde_json::from_str::<serde_json::Value>(&a.body)
            .ok()
            .and_then(|j| j.get("text").and_then(|t| t.as_str()).map(str::to_string))
            .unwrap_or_default();
        if a.status == 200 && text.contains("OctoPrint") {
            return Ok(Host::OctoPrint);
        }
        if a.status == 200 && text.contains("PrusaLink") {
            return Ok(Host::PrusaLink);
        }
        if a.status == 401 || a.status == 403 {
            return Err(self
                .refused(a.status, &a.body)
                .with_help("p3dp asked /api/version which host this is; name it with --host octoprint|prusalink|moonraker"));
        }
        Err(self.error(format!(
            "neither Moonraker, OctoPrint nor PrusaLink answers here (/api/version: HTTP {})",
            a.status
        ))
        .with_help("give the host's base URL, e.g. http://printer.local:7125 for Moonraker, or name it with --host"))
    }

    /// Uploads `size` bytes of `file` (from its start) as `name` to `host`,
    /// streamed, starting the print if `print`; `progress` hears the bytes
    /// sent so far of `total` (the body's length, returned first).
    pub(crate) fn upload<F: Read + Seek>(
        &self,
        host: Host,
        name: &str,
        (file, size): (&mut F, u64),
        print: bool,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<Sent> {
        let (req, head, tail) = self.upload_request(host, name, file, print)?;
        let total = head.len() as u64 + size + tail.len() as u64;
        let mut req = req.header("Content-Length", total.to_string());
        if let Some(k) = &self.key {
            req = req.header("X-Api-Key", k);
        }
        file.rewind()
            .map_err(|e| Error::io_from(name, format!("cannot read: {e}"), &e))?;
        let body = io::Cursor::new(head)
            .chain(Exactly {
                inner: file.take(size),
                left: size,
            })
            .chain(io::Cursor::new(tail));
        let mut reader = Counting {
            inner: body,
            done: 0,
            total,
            progress,
        };
        let resp = req
            .send(ureq::SendBody::from_reader(&mut reader))
            .map_err(|e| self.failed(e))?;
        let a = Answer::of(resp);
        if a.redirects() || (300..400).contains(&a.status) {
            return Err(self.error(format!(
                "the host answered the upload with HTTP {} (a redirect, to `{}`) instead of taking the file; p3dp follows no redirect for an upload (a client that does sends the next request without the file): give --to the address the host names, if it is the printer's",
                a.status,
                self.location(&a)
            )));
        }
        if !(200..300).contains(&a.status) {
            return Err(self.refused(a.status, &a.body));
        }
        let mut sent = answer(host, name, print, &a.body);
        sent.path = printable_line(&sent.path, &self.secrets());
        Ok(sent)
    }
}

impl Target {
    /// The request an upload of `file` as `name` to `host` makes, and what
    /// its body holds before and after the file's bytes (a multipart
    /// frame, or nothing for PrusaLink's PUT).
    fn upload_request<F: Read + Seek>(
        &self,
        host: Host,
        name: &str,
        file: &mut F,
        print: bool,
    ) -> Result<(
        ureq::RequestBuilder<ureq::typestate::WithBody>,
        Vec<u8>,
        Vec<u8>,
    )> {
        let flag = if print { "true" } else { "false" };
        if host == Host::PrusaLink {
            let path = format!("{}/api/v1/files/usb/{}", self.address.path, percent(name));
            let req = self
                .agent(false)
                .put(self.address.url(&path))
                .header("Print-After-Upload", if print { "?1" } else { "?0" })
                .header("Overwrite-File", "?0")
                .header("Content-Type", "application/octet-stream");
            return Ok((req, Vec::new(), Vec::new()));
        }
        let boundary = boundary_for(file)
            .map_err(|e| Error::io_from(name, format!("cannot read: {e}"), &e))?;
        let (path, fields) = if host == Host::Moonraker {
            (
                "/server/files/upload",
                [("root", "gcodes"), ("print", flag)],
            )
        } else {
            ("/api/files/local", [("select", flag), ("print", flag)])
        };
        let (head, tail) = multipart(&fields, name, &boundary);
        let req = self
            .agent(false)
            .post(self.address.url(&format!("{}{path}", self.address.path)))
            .header(
                "Content-Type",
                format!("multipart/form-data; boundary={boundary}"),
            );
        Ok((req, head, tail))
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

/// A reader of exactly `left` bytes: one that ends sooner (a file cut
/// while it is sent) is an error, not a short body.
struct Exactly<R> {
    inner: R,
    left: u64,
}

impl<R: Read> Read for Exactly<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        if n == 0 && self.left > 0 && !buf.is_empty() {
            return Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                format!(
                    "the file ended {} bytes early (changed while sent?)",
                    self.left
                ),
            ));
        }
        self.left -= n as u64;
        Ok(n)
    }
}

/// A reader that reports how much of it was read.
struct Counting<'p, R> {
    inner: R,
    done: u64,
    total: u64,
    progress: &'p mut dyn FnMut(u64, u64),
}

impl<R: Read> Read for Counting<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.done += n as u64;
        (self.progress)(self.done, self.total);
        Ok(n)
    }
}

/// A multipart boundary (RFC 2046 §5.1.1) for `file`, read once in
/// 64 kB pieces: `p3dp-` and the file's MD5 in hex (no text can hold its
/// own MD5 by design), lengthened with `x` in the rare file that holds it
/// anyway; the file is read again only if it holds `p3dp-` at all.
fn boundary_for<F: Read + Seek>(file: &mut F) -> io::Result<String> {
    use md5::Digest;
    const PREFIX: &[u8] = b"p3dp-";
    let mut md5 = md5::Md5::new();
    let mut seen = false;
    scan(file, PREFIX.len(), |window, fresh| {
        md5.update(fresh);
        seen = seen || window.windows(PREFIX.len()).any(|w| w == PREFIX);
    })?;
    let hex: String = md5.finalize().iter().map(|b| format!("{b:02x}")).collect();
    let mut boundary = format!("p3dp-{hex}");
    // only a file holding `p3dp-` can hold the boundary: read it again
    while seen {
        let b = boundary.as_bytes().to_vec();
        seen = false;
        scan(file, b.len(), |window, _| {
            seen = seen || window.windows(b.len()).any(|w| w == b.as_slice());
        })?;
        if seen {
            boundary.push('x');
        }
    }
    Ok(boundary)
}

/// Reads `file` from its start in pieces; `each` sees every window of
/// the last `overlap - 1` bytes and a fresh piece, and the fresh piece.
fn scan<F: Read + Seek>(
    file: &mut F,
    overlap: usize,
    mut each: impl FnMut(&[u8], &[u8]),
) -> io::Result<()> {
    file.rewind()?;
    let keep = overlap.saturating_sub(1);
    let mut window: Vec<u8> = Vec::with_capacity(keep + (64 << 10));
    let mut buf = vec![0u8; 64 << 10];
    loop {
        let n = match file.read(&mut buf) {
            Ok(0) => return Ok(()),
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        window.extend_from_slice(&buf[..n]);
        each(&window, &buf[..n]);
        let cut = window.len().saturating_sub(keep);
        window.drain(..cut);
    }
}

/// The `multipart/form-data` frame (RFC 7578) of text `fields` and a file
/// named `name`: what goes before the file's bytes and after them.
fn multipart(fields: &[(&str, &str)], name: &str, boundary: &str) -> (Vec<u8>, Vec<u8>) {
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
    let mut head = String::with_capacity(512);
    for (k, v) in fields {
        head.push_str(&format!(
            "--{boundary}\r\nContent-Disposition: form-data; name=\"{k}\"\r\n\r\n{v}\r\n"
        ));
    }
    head.push_str(&format!(
        "--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"{file_name}\"\r\nContent-Type: application/octet-stream\r\n\r\n"
    ));
    let tail = format!("\r\n--{boundary}--\r\n");
    (head.into_bytes(), tail.into_bytes())
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
    fn multipart_frames_the_file_with_a_boundary_it_does_not_hold() {
        let (head, tail) = multipart(&[("root", "gcodes")], "a\"b.gcode", "p3dp-x");
        let text = String::from_utf8([head, b"G28\r\n".to_vec(), tail].concat()).unwrap();
        assert!(text.starts_with("--p3dp-x\r\n"));
        assert!(text.ends_with("\r\n--p3dp-x--\r\n"));
        assert!(text.contains("filename=\"a_b.gcode\""));
        assert!(text.contains("\r\n\r\nG28\r\n\r\n--"));
        assert_eq!(percent("a b/ü.gcode"), "a%20b%2F%C3%BC.gcode");
        assert_eq!(Host::of_name("OctoPrint"), Some(Host::OctoPrint));
        // the boundary is the file's MD5 (RFC 1321's "abc")
        let mut f = io::Cursor::new(b"abc".to_vec());
        assert_eq!(
            boundary_for(&mut f).unwrap(),
            "p3dp-900150983cd24fb0d6963f7d28e17f72"
        );
        // a file holding its boundary (across a 64 kB piece) gets a longer one
        let mut bytes = vec![b'.'; (64 << 10) - 10];
        bytes.extend_from_slice(b"p3dp-");
        let b = boundary_for(&mut io::Cursor::new(bytes.clone())).unwrap();
        bytes.extend_from_slice(&b.as_bytes()[5..]);
        let longer = boundary_for(&mut io::Cursor::new(bytes.clone())).unwrap();
        assert!(!bytes.windows(longer.len()).any(|w| w == longer.as_bytes()));
    }

    #[test]
    fn addresses_keep_credentials_out_of_what_is_shown() {
        let a = Address::parse("http://me:s3cr%40t@Printer.local:7125/octo/").unwrap();
        assert_eq!(a.shown(), "http://Printer.local:7125/octo");
        assert!(a.has_credentials());
        assert_eq!(
            a.url("/api/version"),
            "http://me:s3cr%40t@Printer.local:7125/api/version"
        );
        let secrets = a.secrets();
        assert!(secrets.contains(&"s3cr@t".to_string()), "{secrets:?}");
        for bad in [
            "http://me:pw@",
            "ftp://me:pw@host",
            "http://me:pw@host/?q=1",
            "me:pw@host",
        ] {
            let e = Address::parse(bad).unwrap_err();
            assert!(!e.message.contains("pw"), "{e}");
        }
        assert_eq!(redact("http://u:p@h:1/x"), "http://********@h:1/x");
        assert_eq!(redact("u:p@h/x@y"), "********@h/x@y");
        assert!(Address::parse("https://h").is_err());
    }

    #[test]
    fn redirects_stay_within_the_origin() {
        let a = Address::parse("http://10.0.0.5:7125").unwrap();
        let within = |loc: &str| a.within("/api/version", loc);
        assert_eq!(within("/login?next=1"), Some("/login?next=1".into()));
        assert_eq!(within("version/"), Some("/api/version/".into()));
        assert_eq!(within("http://10.0.0.5:7125/x"), Some("/x".into()));
        for other in [
            "http://10.0.0.5:7126/x",
            "http://10.0.0.6:7125/x",
            "//evil.example/x",
            "https://10.0.0.5:7125/x",
            "http://10.0.0.5/x",
            "/x\r\nX-Evil: 1",
        ] {
            assert_eq!(within(other), None, "{other}");
        }
    }

    #[test]
    fn a_hosts_text_prints_as_indented_lines_without_escapes_or_secrets() {
        let key = "KEY-0123456789".to_string();
        let hostile = "\u{1b}]0;owned\u{7}\u{1b}[31mred\u{1b}[0m line one\r\nline two KEY-0123\u{1b}[0m456789\n\u{9b}2J\u{202e}gnp.exe\u{0}\ttab\u{2028}last";
        let lines = printable(hostile, std::slice::from_ref(&key));
        assert_eq!(
            lines,
            ["red line one", "line two ********", "gnp.exe tab", "last"]
        );
        assert_eq!(
            block("the host answered HTTP 500", &lines),
            "the host answered HTTP 500:\n    red line one\n    line two ********\n    gnp.exe tab\n    last"
        );
        assert_eq!(block("x", &printable("one", &[])), "x: one");
        // length-capped: lines and characters
        let long = format!("{}\n", "a".repeat(5000)).repeat(100);
        let lines = printable(&long, &[]);
        assert_eq!(lines.len(), SHOWN_LINES + 1);
        assert!(
            lines[0].ends_with("… (4800 more characters)"),
            "{}",
            lines[0]
        );
        assert_eq!(lines[SHOWN_LINES], "… (80 more lines)");
        // an unterminated sequence ends the text, never more
        assert_eq!(printable("ok\u{1b}]52;c;aGk=", &[]), ["ok"]);
        assert_eq!(printable_line("a\nb", &[]), "a ⏎ b");
    }
}
