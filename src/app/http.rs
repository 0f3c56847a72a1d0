//! The small HTTP/1.1 server of `p3dp watch`: one thread per connection,
//! each bounded, so that no client can hold the others up or grow the
//! process.
//!
//! - A request head is at most [`MAX_HEAD`] bytes (431 past it), and must
//!   arrive within [`IO_TIMEOUT`]; a write that a client does not take within
//!   [`IO_TIMEOUT`] ends its connection, and an answer must be taken whole
//!   within [`ANSWER_TIME`].
//! - At most [`MAX_CONNECTIONS`] connections are served at once; one more
//!   closes the oldest that has not yet sent its request (idle connections
//!   never lock fresh ones out), or is closed itself when none is idle.
//! - Every answer is `Connection: close`: a thread ends with its connection.
//!
//! Only `GET` is parsed; the handler sees the method, the path and the
//! `Host` header ([`Request`]) and answers with [`Answer`].

use std::io::{Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Longest request head (request line and headers), bytes.
pub(crate) const MAX_HEAD: usize = 16 << 10;
/// Longest wait for a client's bytes, or for a client to take a write.
pub(crate) const IO_TIMEOUT: Duration = Duration::from_secs(5);
/// Longest time a client may take to take a whole answer.
pub(crate) const ANSWER_TIME: Duration = Duration::from_secs(30);
/// Most connections served at once.
pub(crate) const MAX_CONNECTIONS: usize = 64;

/// A request as the handler sees it.
pub(crate) struct Request {
    /// `GET`, `POST`…
    pub(crate) method: String,
    /// The path, without its query.
    pub(crate) path: String,
    /// The `Host` header, lower case ("" when there is none).
    pub(crate) host: String,
}

/// What the handler does with a request.
pub(crate) enum Answer {
    /// A whole answer: status, content type, extra headers, body.
    Whole(u16, &'static str, Vec<(&'static str, String)>, Vec<u8>),
    /// The connection handed over (for a stream of events), with the
    /// write timeout set; the handler's thread is the connection's.
    Stream(Box<dyn FnOnce(TcpStream) + Send>),
}

/// The connections open: an id, a handle to close it, and whether it is
/// still reading its request.
#[derive(Default)]
struct Open {
    next: u64,
    list: Vec<(u64, TcpStream, bool)>,
}

fn lock(open: &Mutex<Open>) -> std::sync::MutexGuard<'_, Open> {
    open.lock().unwrap_or_else(|e| e.into_inner())
}

/// Serves `listener` with `handle` until `stop()` is true (checked every
/// few milliseconds); then closes every connection still open.
pub(crate) fn serve(
    listener: TcpListener,
    handle: Arc<dyn Fn(&Request) -> Answer + Send + Sync>,
    stop: impl Fn() -> bool,
) {
    let open = Arc::new(Mutex::new(Open::default()));
    if listener.set_nonblocking(true).is_err() {
        return;
    }
    while !stop() {
        let sock = match listener.accept() {
            Ok((sock, _)) => sock,
            Err(_) => {
                std::thread::sleep(Duration::from_millis(10));
                continue;
            }
        };
        let Some(id) = admit(&open, &sock) else {
            let _ = sock.shutdown(Shutdown::Both);
            continue;
        };
        let (open2, handle) = (Arc::clone(&open), Arc::clone(&handle));
        let spawned = std::thread::Builder::new()
            .name("p3dp-http".into())
            .spawn(move || {
                connection(sock, id, &open2, handle.as_ref());
                lock(&open2).list.retain(|(k, _, _)| *k != id);
            });
        if spawned.is_err() {
            lock(&open).list.retain(|(k, _, _)| *k != id);
        }
    }
    for (_, s, _) in lock(&open).list.drain(..) {
        let _ = s.shutdown(Shutdown::Both);
    }
}

/// Notes a new connection, closing the oldest idle one when all places are
/// taken; `None` when none is idle (the new one is refused).
fn admit(open: &Mutex<Open>, sock: &TcpStream) -> Option<u64> {
    let handle = sock.try_clone().ok()?;
    let mut o = lock(open);
    if o.list.len() >= MAX_CONNECTIONS {
        let k = o.list.iter().position(|(_, _, reading)| *reading)?;
        let (_, old, _) = o.list.remove(k);
        let _ = old.shutdown(Shutdown::Both);
    }
    o.next += 1;
    let id = o.next;
    o.list.push((id, handle, true));
    Some(id)
}

/// One connection: its request read (bounded), answered, closed.
fn connection(
    mut sock: TcpStream,
    id: u64,
    open: &Mutex<Open>,
    handle: &(dyn Fn(&Request) -> Answer + Send + Sync),
) {
    let _ = sock.set_nonblocking(false);
    let _ = sock.set_read_timeout(Some(IO_TIMEOUT));
    let _ = sock.set_write_timeout(Some(IO_TIMEOUT));
    let head = match read_head(&mut sock) {
        Ok(h) => h,
        Err(Some(status)) => {
            let _ = write_whole(&mut sock, (status, "text/plain; charset=utf-8", &[], b""));
            return;
        }
        Err(None) => return,
    };
    if let Some(e) = lock(open).list.iter_mut().find(|(k, _, _)| *k == id) {
        e.2 = false;
    }
    let req = parse(&head);
    match handle(&req) {
        Answer::Whole(status, kind, headers, body) => {
            let _ = write_whole(&mut sock, (status, kind, &headers, &body));
        }
        Answer::Stream(f) => f(sock),
    }
}

/// The request head: bytes up to the blank line. `Err(Some(431))` when it
/// is too long, `Err(None)` when the client went or was too slow.
fn read_head(sock: &mut TcpStream) -> std::result::Result<Vec<u8>, Option<u16>> {
    let started = Instant::now();
    let mut head = Vec::with_capacity(1024);
    let mut buf = [0u8; 2048];
    loop {
        if started.elapsed() > IO_TIMEOUT {
            return Err(None);
        }
        let n = sock.read(&mut buf).map_err(|_| None)?;
        if n == 0 {
            return Err(None);
        }
        head.extend_from_slice(&buf[..n]);
        if let Some(end) = head.windows(4).position(|w| w == b"\r\n\r\n") {
            head.truncate(end);
            return Ok(head);
        }
        if head.len() > MAX_HEAD {
            return Err(Some(431));
        }
    }
}

/// The method, path and host of a request head.
fn parse(head: &[u8]) -> Request {
    let text = String::from_utf8_lossy(head);
    let mut lines = text.split("\r\n");
    let mut first = lines.next().unwrap_or("").split(' ');
    let method = first.next().unwrap_or("").to_string();
    let target = first.next().unwrap_or("");
    let path = target.split('?').next().unwrap_or("").to_string();
    let host = lines
        .filter_map(|l| l.split_once(':'))
        .find(|(name, _)| name.trim().eq_ignore_ascii_case("host"))
        .map(|(_, v)| v.trim().to_ascii_lowercase())
        .unwrap_or_default();
    Request { method, path, host }
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        431 => "Request Header Fields Too Large",
        503 => "Service Unavailable",
        _ => "",
    }
}

type Whole<'a> = (u16, &'a str, &'a [(&'static str, String)], &'a [u8]);

/// Writes a whole answer, in pieces, giving up past [`ANSWER_TIME`].
fn write_whole(sock: &mut TcpStream, (status, kind, headers, body): Whole) -> std::io::Result<()> {
    let mut head = format!(
        "HTTP/1.1 {status} {}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nConnection: close\r\n",
        reason(status),
        body.len()
    );
    for (name, value) in headers {
        head.push_str(&format!("{name}: {value}\r\n"));
    }
    head.push_str("\r\n");
    let started = Instant::now();
    for piece in std::iter::once(head.as_bytes()).chain(body.chunks(64 << 10)) {
        if started.elapsed() > ANSWER_TIME {
            return Err(std::io::Error::from(std::io::ErrorKind::TimedOut));
        }
        sock.write_all(piece)?;
    }
    sock.flush()?;
    let _ = sock.shutdown(Shutdown::Write);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_head_names_its_method_path_and_host() {
        let r = parse(b"GET /events?x=1 HTTP/1.1\r\nUser-Agent: t\r\nHOST: LocalHost:80");
        assert_eq!(r.method, "GET");
        assert_eq!(r.path, "/events");
        assert_eq!(r.host, "localhost:80");
        assert_eq!(parse(b"").host, "");
    }
}
