//! `p3dp watch`: the HTML viewer served on loopback, rebuilt on every save.
//!
//! The recipe is built as `preview` builds it (a recipe that fails its
//! checks is shown too, its findings listed) and the viewer page served at
//! `http://127.0.0.1:PORT/`. Every file the build read or tried to read
//! (the recipe, its `include:`s, images, printer profiles and what they
//! `inherits`; the [`crate::recipe::context::Context`] of its load) is followed by watching its
//! folder (so an editor that saves by writing a new file and renaming it
//! over the old one is seen too); a change, settled for [`SETTLE`], starts a
//! new build. The page follows `/events` (server-sent events): `model` swaps
//! the geometry in place (the camera stays), `build-error` shows the error,
//! rendered as in the terminal, beside the last good model.
//! The `solid` parts' z-buffers are kept from one build to the next
//! ([`crate::generate::primitive::solid::Reusing`]): an edited feature re-slices only
//! the layers it reaches, and the build line says how many.
//!
//! The server binds 127.0.0.1 only and answers only requests addressed to
//! it by that name or `localhost`. Nothing is written to disk. The first
//! SIGINT, SIGTERM or SIGHUP stops it cleanly (status 0); a second one exits
//! at once.

use std::collections::BTreeSet;
use std::io::Write;
use std::net::{Ipv4Addr, SocketAddr, TcpListener};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use crate::app::http;
use crate::app::prepare::{prepare_in, Options as BuildOptions};
use crate::base::error::{Error, Result};
use crate::generate::primitive::solid::Reusing;
use crate::output::file::identity;
use crate::recipe::context::Context;

/// The port `p3dp watch` serves on unless `--port` says otherwise.
pub(crate) const DEFAULT_PORT: u16 = 8430;

/// How long the files must stay unchanged after a change before a build
/// starts (an editor's save may be several writes and a rename).
pub(crate) const SETTLE: Duration = Duration::from_millis(100);

/// The longest a stream of changes delays a build.
const SETTLE_AT_MOST: Duration = Duration::from_secs(1);

/// How often an idle event stream gets a comment (finds closed pages).
const KEEP_ALIVE: Duration = Duration::from_secs(15);

/// Most pages following the events at once.
const MAX_STREAMS: usize = 32;

/// What `p3dp watch` is asked to do.
#[derive(Clone, Debug)]
pub(crate) struct Options {
    /// The recipe file.
    pub recipe: PathBuf,
    /// `--set`, `--printer`, `--allow` of each build.
    pub build: BuildOptions,
    /// `-j`: the threads of each build.
    pub threads: crate::app::pipeline::Threads,
    /// `--port`: 0 takes any free port.
    pub port: u16,
    /// `--open`: open the page in the system's browser.
    pub open: bool,
}

/// The newest model and the newest failure, as the pages are told them.
#[derive(Default)]
struct State {
    /// The number of the newest build finished.
    build: u64,
    /// The last good build: its number, the viewer's data and the event.
    model: Option<(u64, Arc<Value>, Arc<String>)>,
    /// The newest build when it failed: its number, text and the event.
    error: Option<(u64, Arc<String>, Arc<String>)>,
    /// Bumped on every change, so a stream knows it has news.
    seq: u64,
    /// Set when the server stops.
    stop: bool,
    /// Event streams open now.
    streams: usize,
}

/// The state shared by the builds and the pages.
struct Shared {
    state: Mutex<State>,
    changed: Condvar,
    /// Told to each page, so that it can tell a new server from the same one.
    run: String,
    /// The recipe as given (shown in the page).
    recipe: String,
    /// The recipe's file name (the page's name before the first model).
    name: String,
    /// The port served.
    port: u16,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// What wakes the main loop.
enum Wake {
    /// A file event from the watcher.
    Files(notify::Result<notify::Event>),
    /// A build finished.
    Built(Box<Outcome>),
    /// A signal: stop.
    Stop,
}

/// The solids' z-buffers kept between builds (lent to each, see [`crate::generate::primitive::solid::Reusing`]).
type Buffers = Arc<Mutex<crate::generate::primitive::solid::Cache>>;

/// One build's result.
struct Outcome {
    number: u64,
    result: Result<Built>,
    /// Per solid: its layers and how many were recomputed.
    solids: Vec<crate::generate::primitive::solid::Reuse>,
    /// The files the build read or tried to read.
    inputs: Vec<PathBuf>,
    took: Duration,
}

/// What a good build gives the page and the terminal.
struct Built {
    data: Value,
    /// `2 warnings, 0 errors · 100.0 × 100.0 × 50.0 mm`.
    summary: String,
}

/// Runs `p3dp watch` until a signal stops it: the URL served is printed
/// first, then a line for each build (errors on standard error).
pub(crate) fn run(opts: &Options) -> Result<()> {
    let shown = opts.recipe.display().to_string();
    // a recipe that is not there now is a mistake of the command line; one
    // that goes later is shown in the page until it comes back
    match std::fs::metadata(&opts.recipe) {
        Err(e) => {
            return Err(Error::io_from(
                &shown,
                format!("cannot read the recipe: {e}"),
                &e,
            ))
        }
        Ok(m) if !m.is_file() => {
            return Err(
                Error::input("", "is not a file; expected a recipe file (YAML)").in_file(&shown),
            )
        }
        Ok(_) => {}
    }
    crate::analyse::check::validate_allow(&opts.build.allow, |i| {
        format!("--allow {}", opts.build.allow[i])
    })?;
    let listener = bind(opts.port)?;
    let port = listener.local_addr().map(|a| a.port()).unwrap_or(opts.port);
    let name = opts
        .recipe
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let shared = Arc::new(Shared {
        state: Mutex::new(State::default()),
        changed: Condvar::new(),
        run: run_id(),
        recipe: shown.clone(),
        name,
        port,
    });
    let (tx, rx) = mpsc::channel::<Wake>();
    {
        let tx = tx.clone();
        crate::output::file::stop_on_signals(Box::new(move |_| tx.send(Wake::Stop).is_ok()));
    }
    let http = {
        let shared = Arc::clone(&shared);
        let handle: Arc<dyn Fn(&http::Request) -> http::Answer + Send + Sync> = {
            let shared = Arc::clone(&shared);
            Arc::new(move |req: &http::Request| answer(req, &shared))
        };
        std::thread::Builder::new()
            .name("p3dp-serve".into())
            .spawn(move || http::serve(listener, handle, || shared.lock().stop))
            .map_err(|e| Error::io("p3dp watch", format!("cannot start the server: {e}")))?
    };
    let url = format!("http://127.0.0.1:{port}/");
    crate::sayln!("p3dp watch: {shown} on {url} (loopback only; Ctrl-C stops)");
    let _ = std::io::stdout().flush();
    if opts.open {
        if let Err(e) = opener::open(&url) {
            crate::tellln!("note: cannot open a browser ({e}); open {url} yourself");
        }
    }
    let result = follow(opts, &shared, &tx, &rx);
    // stop: the pages' streams end, the server thread returns, the socket closes
    shared.lock().stop = true;
    shared.changed.notify_all();
    // a page still being sent to a stalled client is not waited for long
    let until = Instant::now() + Duration::from_millis(500);
    while !http.is_finished() && Instant::now() < until {
        std::thread::sleep(Duration::from_millis(5));
    }
    if http.is_finished() {
        let _ = http.join();
    }
    result
}

/// The listening socket on 127.0.0.1 (`port` 0: any free one).
fn bind(port: u16) -> Result<TcpListener> {
    let at = SocketAddr::from((Ipv4Addr::LOCALHOST, port));
    TcpListener::bind(at).map_err(|e| {
        let place = format!("--port {port}");
        if e.kind() == std::io::ErrorKind::AddrInUse {
            Error::input(
                place,
                format!("port {port} of 127.0.0.1 is in use (another p3dp watch?); expected a free port: give another with --port N, or --port 0 for any free one"),
            )
        } else {
            Error::io_from(
                place,
                format!("cannot listen on 127.0.0.1:{port}: {e}"),
                &e,
            )
        }
    })
}

/// A token of this run of the server: the page tells a restarted server by it.
fn run_id() -> String {
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    format!("{:x}-{}", t, std::process::id())
}

/// The main loop: builds, watches, rebuilds on changes until [`Wake::Stop`].
fn follow(
    opts: &Options,
    shared: &Arc<Shared>,
    tx: &Sender<Wake>,
    rx: &Receiver<Wake>,
) -> Result<()> {
    let watch_tx = tx.clone();
    let mut watcher = notify::recommended_watcher(move |ev| {
        let _ = watch_tx.send(Wake::Files(ev));
    })
    .map_err(|e| Error::io("p3dp watch", format!("cannot watch files: {e}")))?;
    let mut files = Files::default();
    // the recipe's folder from the start: a save during the first build counts
    files.update(&mut watcher, &opts.recipe, &[]);
    let buffers = Buffers::default();
    let mut number = 1;
    start_build(opts, number, tx, &buffers);
    let mut building = true;
    let mut again = false;
    // the first change not yet built, and the newest
    let mut pending: Option<(Instant, Instant)> = None;
    loop {
        let wake = match pending {
            Some((first, last)) => {
                let due = (last + SETTLE).min(first + SETTLE_AT_MOST);
                match rx.recv_timeout(due.saturating_duration_since(Instant::now())) {
                    Ok(w) => Some(w),
                    Err(RecvTimeoutError::Timeout) => None,
                    Err(RecvTimeoutError::Disconnected) => return Ok(()),
                }
            }
            None => match rx.recv() {
                Ok(w) => Some(w),
                Err(_) => return Ok(()),
            },
        };
        match wake {
            Some(Wake::Stop) => return Ok(()),
            Some(Wake::Files(Ok(ev))) => {
                if files.touches(&ev) {
                    let now = Instant::now();
                    pending = Some(pending.map_or((now, now), |(first, _)| (first, now)));
                }
            }
            Some(Wake::Files(Err(e))) => crate::tellln!("note: watching files: {e}"),
            Some(Wake::Built(out)) => {
                building = false;
                files.update(&mut watcher, &opts.recipe, &out.inputs);
                publish(shared, *out);
                if again {
                    again = false;
                    number += 1;
                    start_build(opts, number, tx, &buffers);
                    building = true;
                }
            }
            None => {
                // the files have settled
                pending = None;
                if building {
                    again = true;
                } else {
                    number += 1;
                    start_build(opts, number, tx, &buffers);
                    building = true;
                }
            }
        }
    }
}

/// Builds on a thread of its own (a signal is answered mid-build), telling
/// the main loop the outcome; the solids start from the z-buffers of the
/// build before, so an edited feature re-slices only the layers it reaches.
fn start_build(opts: &Options, number: u64, tx: &Sender<Wake>, buffers: &Buffers) {
    let (opts, to_main, buffers) = (opts.clone(), tx.clone(), Arc::clone(buffers));
    let spawned = std::thread::Builder::new()
        .name(format!("p3dp-build-{number}"))
        .spawn(move || {
            let t0 = Instant::now();
            // a bug in a stage must not leave the loop waiting for this build
            let mut kept = buffers.lock().unwrap_or_else(|e| e.into_inner());
            let cx = Context {
                zbuffers: Some(Reusing::new(std::mem::take(&mut *kept))),
                ..Context::default()
            };
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| build(&opts, &cx)))
                .unwrap_or_else(|_| {
                    Err(Error::io(
                        "p3dp watch",
                        "the build stopped on an internal error (a bug of p3dp; please report it with the recipe)",
                    ))
                });
            let inputs = cx.reads.files();
            let cache = cx.zbuffers.map(Reusing::finish).unwrap_or_default();
            let solids = cache.last.clone();
            *kept = cache;
            drop(kept);
            let _ = to_main.send(Wake::Built(Box::new(Outcome {
                number,
                result,
                solids,
                inputs,
                took: t0.elapsed(),
            })));
        });
    if let Err(e) = spawned {
        let _ = tx.send(Wake::Built(Box::new(Outcome {
            number,
            result: Err(Error::io(
                "p3dp watch",
                format!("cannot start a build: {e}"),
            )),
            solids: Vec::new(),
            inputs: Vec::new(),
            took: Duration::ZERO,
        })));
    }
}

/// One build in the loading context `cx`: the plan, its G-code (in
/// memory) and the viewer's data.
fn build(opts: &Options, cx: &Context) -> Result<Built> {
    let (p, stats, viewer) = crate::app::pipeline::run(opts.threads, || {
        let mut p = prepare_in(&opts.recipe, &opts.build, cx)?;
        crate::app::pipeline::check(&mut p, &opts.build.allow);
        crate::analyse::check::within_reach(&p.recipe, &p.paths, "preview")
            .map_err(|e| e.in_file(&p.path))?;
        let mut viewer = crate::output::preview::html::reader(&p);
        let stats = crate::app::pipeline::view(&p, &mut viewer)?;
        Ok::<_, Error>((p, stats, viewer))
    })?;
    let view = crate::output::preview::Options::default();
    let (data, _) = crate::output::preview::html::data(&p, viewer, &stats, &view);
    let size = [0, 1, 2].map(|k| format!("{:.1}", stats.bbox.max[k] - stats.bbox.min[k]));
    Ok(Built {
        data,
        summary: format!(
            "{} · {} mm",
            crate::base::finding::summary(&p.findings),
            size.join(" × ")
        ),
    })
}

/// Tells the terminal and the pages how a build went.
fn publish(shared: &Shared, out: Outcome) {
    let secs = out.took.as_secs_f64();
    let mut st = shared.lock();
    st.build = st.build.max(out.number);
    match out.result {
        Ok(b) => {
            crate::sayln!(
                "build {}: ok in {secs:.2} s · {}{} · watching {} file{}",
                out.number,
                b.summary,
                resliced(&out.solids),
                out.inputs.len(),
                if out.inputs.len() == 1 { "" } else { "s" }
            );
            let event = json!({"run": shared.run, "build": out.number, "model": b.data});
            st.model = Some((out.number, Arc::new(b.data), Arc::new(event.to_string())));
            st.error = None;
        }
        Err(e) => {
            let kept = match &st.model {
                Some((n, _, _)) => format!("the page keeps build {n}'s model"),
                None => "no model to show yet".to_string(),
            };
            crate::tellln!("build {} failed in {secs:.2} s ({kept}):", out.number);
            crate::tell!(
                "{}",
                crate::app::diagnostic::render(&e, crate::app::diagnostic::stderr_color())
            );
            let text = crate::app::diagnostic::render(&e, false);
            let event = json!({"run": shared.run, "build": out.number, "error": text});
            st.error = Some((out.number, Arc::new(text), Arc::new(event.to_string())));
        }
    }
    let _ = std::io::stdout().flush();
    st.seq += 1;
    drop(st);
    shared.changed.notify_all();
}

/// ` · solid layers re-sliced: 20 of 70` (each solid's count, `+`-joined),
/// or nothing without solids.
fn resliced(solids: &[crate::generate::primitive::solid::Reuse]) -> String {
    if solids.is_empty() {
        return String::new();
    }
    let each: Vec<String> = solids
        .iter()
        .map(|r| format!("{} of {}", r.recomputed, r.layers))
        .collect();
    format!(" · solid layers re-sliced: {}", each.join(", "))
}

/// The files followed, by identity, and the folders watched for them.
#[derive(Default)]
struct Files {
    files: BTreeSet<PathBuf>,
    dirs: BTreeSet<PathBuf>,
}

impl Files {
    /// Follows `inputs` (and the recipe, always) from now on: their folders
    /// watched (the nearest that exists, for a file in a missing folder).
    fn update(&mut self, watcher: &mut impl notify::Watcher, recipe: &Path, inputs: &[PathBuf]) {
        let mut files = BTreeSet::new();
        let mut dirs = BTreeSet::new();
        for f in std::iter::once(recipe).chain(inputs.iter().map(PathBuf::as_path)) {
            let id = identity(f);
            let mut dir = id.parent().map(Path::to_path_buf);
            while let Some(d) = dir {
                if d.is_dir() {
                    dirs.insert(d);
                    break;
                }
                dir = d.parent().map(Path::to_path_buf);
            }
            files.insert(id);
        }
        for gone in self.dirs.difference(&dirs) {
            let _ = watcher.unwatch(gone);
        }
        for new in dirs.difference(&self.dirs) {
            if let Err(e) = watcher.watch(new, notify::RecursiveMode::NonRecursive) {
                crate::tellln!("note: cannot watch {}: {e}", new.display());
            }
        }
        self.files = files;
        self.dirs = dirs;
    }

    /// Whether a file event concerns a file followed (or a missing folder on
    /// the way to one). Reading a file is no change; closing one written is
    /// (the last event of a slow write).
    fn touches(&self, ev: &notify::Event) -> bool {
        use notify::event::{AccessKind, AccessMode};
        use notify::EventKind;
        if matches!(ev.kind, EventKind::Access(a) if a != AccessKind::Close(AccessMode::Write)) {
            return false;
        }
        ev.paths.iter().any(|p| {
            let id = identity(p);
            self.files.iter().any(|f| *f == id || f.starts_with(&id))
        })
    }
}

/// Whether the request names this server: `127.0.0.1`, `localhost` or
/// `[::1]`, with this port or none (refuses a page of another site that a
/// DNS name rebound to 127.0.0.1 would let read the model).
fn host_ok(host: &str, port: u16) -> bool {
    ["127.0.0.1", "localhost", "[::1]"]
        .iter()
        .any(|name| host == *name || host == format!("{name}:{port}"))
}

/// A short plain-text answer.
fn text(status: u16, body: &str) -> http::Answer {
    let kind = "text/plain; charset=utf-8";
    http::Answer::Whole(status, kind, Vec::new(), body.as_bytes().to_vec())
}

/// Answers one request: `/` the page, `/events` the stream.
fn answer(req: &http::Request, shared: &Arc<Shared>) -> http::Answer {
    if !host_ok(&req.host, shared.port) {
        return text(
            403,
            "p3dp watch answers only requests addressed to 127.0.0.1 or localhost\n",
        );
    }
    if req.method != "GET" {
        return text(405, "p3dp watch answers GET only\n");
    }
    match req.path.as_str() {
        "/" | "/index.html" => http::Answer::Whole(
            200,
            "text/html; charset=utf-8",
            vec![("Cache-Control", "no-store".to_string())],
            page(shared).into_bytes(),
        ),
        "/events" => {
            {
                let mut st = shared.lock();
                if st.streams >= MAX_STREAMS {
                    return text(503, "too many pages follow this p3dp watch\n");
                }
                st.streams += 1;
            }
            let shared = Arc::clone(shared);
            http::Answer::Stream(Box::new(move |sock| {
                stream(Box::new(sock), &shared);
                shared.lock().streams -= 1;
            }))
        }
        _ => text(404, "not found; p3dp watch serves / and /events\n"),
    }
}

/// The viewer page as it stands: the last good model and the newest state.
fn page(shared: &Shared) -> String {
    let st = shared.lock();
    let data = st
        .model
        .as_ref()
        .map_or(Value::Null, |(_, d, _)| (**d).clone());
    let live = json!({
        "run": shared.run,
        "build": st.build,
        "model_build": st.model.as_ref().map_or(0, |(n, _, _)| *n),
        "error": st.error.as_ref().map(|(_, t, _)| t.as_str()),
        "recipe": shared.recipe,
        "name": shared.name,
    });
    drop(st);
    let title = data["name"].as_str().unwrap_or(&shared.name).to_string();
    crate::output::preview::html::page_with(&title, &data, &live)
}

/// Writes server-sent events to one page until it goes or the server stops:
/// the last good model and the newest error at once, then every change.
fn stream(mut out: Box<dyn Write + Send>, shared: &Shared) {
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream; charset=utf-8\r\n\
                Cache-Control: no-store\r\nConnection: close\r\n\r\nretry: 1000\n\n";
    if out
        .write_all(head.as_bytes())
        .and_then(|_| out.flush())
        .is_err()
    {
        return;
    }
    let (mut sent_model, mut sent_error) = (0u64, 0u64);
    let mut seen = u64::MAX;
    loop {
        let (model, error) = {
            let st = shared.lock();
            let (st, timeout) = shared
                .changed
                .wait_timeout_while(st, KEEP_ALIVE, |s| s.seq == seen && !s.stop)
                .unwrap_or_else(|e| e.into_inner());
            if st.stop {
                return;
            }
            if timeout.timed_out() {
                (None, None)
            } else {
                seen = st.seq;
                let model = st
                    .model
                    .as_ref()
                    .filter(|(n, _, _)| *n != sent_model)
                    .map(|(n, _, e)| (*n, Arc::clone(e)));
                let error = st
                    .error
                    .as_ref()
                    .filter(|(n, _, _)| *n != sent_error)
                    .map(|(n, _, e)| (*n, Arc::clone(e)));
                (model, error)
            }
        };
        let mut msg = String::new();
        if let Some((n, e)) = model {
            sent_model = n;
            msg.push_str(&format!("event: model\nid: {n}\ndata: {e}\n\n"));
        }
        if let Some((n, e)) = error {
            sent_error = n;
            msg.push_str(&format!("event: build-error\nid: {n}\ndata: {e}\n\n"));
        }
        if msg.is_empty() {
            msg.push_str(": keep-alive\n\n");
        }
        if out
            .write_all(msg.as_bytes())
            .and_then(|_| out.flush())
            .is_err()
        {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_busy_port_is_an_input_error_naming_the_option() {
        let held = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
        let port = held.local_addr().unwrap().port();
        let e = bind(port).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert_eq!(e.place.as_deref(), Some(format!("--port {port}").as_str()));
        assert!(e.message.contains("in use"), "{e}");
        // port 0: any free one, on loopback only
        let l = bind(0).unwrap();
        assert!(l.local_addr().unwrap().ip().is_loopback());
    }

    #[test]
    fn events_of_followed_files_count_reads_do_not() {
        let dir = std::env::temp_dir();
        let mut files = Files::default();
        let recipe = dir.join("p3dp-watch-unit.yaml");
        files.files.insert(identity(&recipe));
        files
            .files
            .insert(identity(&dir.join("p3dp-no-such-dir/map.png")));
        let ev = |kind, p: PathBuf| notify::Event::new(kind).add_path(p);
        use notify::event::{AccessKind, CreateKind, ModifyKind, RenameMode};
        assert!(files.touches(&ev(
            notify::EventKind::Modify(ModifyKind::Name(RenameMode::To)),
            recipe.clone()
        )));
        assert!(!files.touches(&ev(
            notify::EventKind::Access(AccessKind::Any),
            recipe.clone()
        )));
        assert!(files.touches(&ev(
            notify::EventKind::Access(AccessKind::Close(notify::event::AccessMode::Write)),
            recipe.clone()
        )));
        assert!(!files.touches(&ev(
            notify::EventKind::Create(CreateKind::File),
            dir.join("p3dp-watch-unit.yaml.swp")
        )));
        // the missing folder made: the image may be there now
        assert!(files.touches(&ev(
            notify::EventKind::Create(CreateKind::Folder),
            dir.join("p3dp-no-such-dir")
        )));
    }
}
