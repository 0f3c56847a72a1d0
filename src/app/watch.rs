//! `p3dp watch`: the HTML viewer served on loopback, rebuilt on every save.
//!
//! The recipe is built as `preview` builds it (a recipe that fails its
//! checks is shown too, its findings listed) and the viewer page served at
//! `http://127.0.0.1:PORT/`. Every file the build read or tried to read
//! (the recipe, its `include:`s, images, printer profiles and what they
//! `inherits`; the [`crate::recipe::context::Context`] of its load) is followed by watching its
//! folder (so an editor that saves by writing a new file and renaming it
//! over the old one is seen too). A save starts a new build at once, with no
//! settling delay: a write is taken as done by its own last event (the file
//! closed after writing, or renamed into place), and the events already
//! queued when a build starts are covered by it (a burst builds once, from
//! the last state). Only a change that no such event ends (a file system
//! that reports no closes) waits for the files to be quiet for
//! [`UNCLOSED`].
//!
//! The page follows `/events` (server-sent events): `model` swaps the
//! geometry in place (the camera stays) as soon as it is drawn, while the
//! checks still run beside it; `checks` then gives their findings and the
//! moves they flag; `build-error` shows an error, rendered as in the
//! terminal, beside the last good model.
//!
//! What a build made is kept for the next, in the loading context
//! ([`crate::recipe::context::Context`]): the `solid` parts' z-buffers
//! ([`crate::generate::primitive::solid::Reusing`]: an edited feature
//! re-slices only the layers it reaches) and every part's toolpath
//! ([`crate::generate::assembly::Parts`]: a part whose resolved form is
//! unchanged is not made again); the build line says how much was made.
//!
//! The server binds 127.0.0.1 only and answers only requests addressed to
//! it by that name or `localhost`. Nothing is written to disk. The first
//! SIGINT, SIGTERM or SIGHUP stops it cleanly (status 0); a second one exits
//! at once.

use std::collections::BTreeSet;
use std::io::Write;
use std::net::{Ipv4Addr, SocketAddr, TcpListener};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use crate::app::http;
use crate::app::prepare::{prepare_in, Options as BuildOptions};
use crate::base::error::{Error, Result};
use crate::generate::assembly::{Parts, PartsMade};
use crate::generate::primitive::solid::Reusing;
use crate::output::file::identity;
use crate::recipe::context::Context;

/// The port `p3dp watch` serves on unless `--port` says otherwise.
pub(crate) const DEFAULT_PORT: u16 = 8430;

/// How long the files must stay quiet after a change that no close or
/// rename ends before a build starts (a file system that reports no closes;
/// a file written through a memory map).
pub(crate) const UNCLOSED: Duration = Duration::from_millis(100);

/// How often an idle event stream gets a comment (finds closed pages).
const KEEP_ALIVE: Duration = Duration::from_secs(15);

/// Most pages following the events at once.
const MAX_STREAMS: usize = 32;

/// What `p3dp watch` is asked to do.
#[derive(Clone, Debug)]
pub(crate) struct Options {
    /// The recipe file.
    pub(crate) recipe: PathBuf,
    /// `--set`, `--printer`, `--allow` of each build.
    pub(crate) build: BuildOptions,
    /// `-j`: the threads of each build.
    pub(crate) threads: crate::app::pipeline::Threads,
    /// `--port`: 0 takes any free port.
    pub(crate) port: u16,
    /// `--open`: open the page in the system's browser.
    pub(crate) open: bool,
}

/// The newest model and the newest failure, as the pages are told them.
#[derive(Default)]
struct State {
    /// The number of the newest build finished.
    build: u64,
    /// The last good build: its number, the viewer's data and the event.
    model: Option<(u64, Arc<Value>, Arc<String>)>,
    /// The checks of a build drawn: its number, the findings (as the
    /// viewer lists them) and the event.
    checks: Option<(u64, Arc<Value>, Arc<String>)>,
    /// The newest build when it failed: its number, text and the event.
    error: Option<(u64, Arc<String>, Arc<String>)>,
    /// The newest build drawn and how long it took to draw.
    drawn: (u64, Duration),
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
    /// A build's model is drawn (its checks still run).
    Drawn(Box<Drawn>),
    /// A build finished.
    Built(Box<Outcome>),
    /// A signal: stop.
    Stop,
}

/// What one build keeps for the next (lent to each in its [`Context`]):
/// the solids' z-buffers ([`crate::generate::primitive::solid::Reusing`])
/// and the parts made ([`Parts`]).
#[derive(Default)]
struct Kept {
    zbuffers: crate::generate::primitive::solid::Cache,
    parts: Parts,
}

/// A build's model, drawn before its checks finish.
struct Drawn {
    number: u64,
    /// The viewer's data (its findings empty: the checks are still running).
    data: Value,
    took: Duration,
}

/// One build's result.
struct Outcome {
    number: u64,
    result: Result<Built>,
    /// Per solid: its layers and how many were recomputed.
    solids: Vec<crate::generate::primitive::solid::Reuse>,
    /// How many parts were made anew, of how many.
    parts: PartsMade,
    /// The files the build read or tried to read.
    inputs: Vec<PathBuf>,
    took: Duration,
}

/// What a good build gives the page and the terminal once checked.
struct Built {
    /// The findings as the viewer lists them.
    findings: Value,
    /// The moves they flag, by index.
    flagged: Vec<u32>,
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
    let kept = Arc::new(Mutex::new(Kept::default()));
    let mut number = 0;
    // a build is wanted (the first, or a change); one is running
    let (mut wanted, mut building) = (true, false);
    // when the newest change that no close or rename ended was seen
    let mut unclosed: Option<Instant> = None;
    loop {
        let wake = if wanted && !building {
            // the events queued already belong to this build (both halves
            // of a rename, a burst of saves): it reads the files after them
            match rx.try_recv() {
                Ok(w) => Some(w),
                Err(TryRecvError::Empty) => {
                    (wanted, building, unclosed) = (false, true, None);
                    number += 1;
                    start_build(opts, number, tx, &kept);
                    continue;
                }
                Err(TryRecvError::Disconnected) => return Ok(()),
            }
        } else if let Some(t) = unclosed {
            match rx.recv_timeout((t + UNCLOSED).saturating_duration_since(Instant::now())) {
                Ok(w) => Some(w),
                Err(RecvTimeoutError::Timeout) => None,
                Err(RecvTimeoutError::Disconnected) => return Ok(()),
            }
        } else {
            match rx.recv() {
                Ok(w) => Some(w),
                Err(_) => return Ok(()),
            }
        };
        match wake {
            Some(Wake::Stop) => return Ok(()),
            Some(Wake::Files(Ok(ev))) => match files.change(&ev) {
                Change::Done => (wanted, unclosed) = (true, None),
                Change::Begun => unclosed = Some(Instant::now()),
                Change::None => {}
            },
            Some(Wake::Files(Err(e))) => crate::tellln!("note: watching files: {e}"),
            Some(Wake::Drawn(d)) => publish_model(shared, *d),
            Some(Wake::Built(out)) => {
                building = false;
                files.update(&mut watcher, &opts.recipe, &out.inputs);
                publish(shared, *out);
            }
            None => (wanted, unclosed) = (true, None),
        }
    }
}

/// Builds on a thread of its own (a signal is answered mid-build), telling
/// the main loop the model as soon as it is drawn, then the outcome; the
/// build starts from what the build before kept.
fn start_build(opts: &Options, number: u64, tx: &Sender<Wake>, kept: &Arc<Mutex<Kept>>) {
    let (opts, to_main, kept) = (opts.clone(), tx.clone(), Arc::clone(kept));
    let spawned = std::thread::Builder::new()
        .name(format!("p3dp-build-{number}"))
        .spawn(move || {
            let t0 = Instant::now();
            let mut kept = kept.lock().unwrap_or_else(|e| e.into_inner());
            let cx = Context {
                zbuffers: Some(Reusing::new(std::mem::take(&mut kept.zbuffers))),
                parts: Some(std::mem::take(&mut kept.parts)),
                ..Context::default()
            };
            let drawn = |data: Value| {
                let took = t0.elapsed();
                let d = Drawn { number, data, took };
                let _ = to_main.send(Wake::Drawn(Box::new(d)));
            };
            // a bug in a stage must not leave the loop waiting for this build
            let result =
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| build(&opts, &cx, &drawn)))
                    .unwrap_or_else(|_| {
                        Err(Error::io(
                            "p3dp watch",
                            "the build stopped on an internal error (a bug of p3dp; please report it with the recipe)",
                        ))
                    });
            let inputs = cx.reads.files();
            let cache = cx.zbuffers.map(Reusing::finish).unwrap_or_default();
            let solids = cache.last.clone();
            let parts = cx.parts.unwrap_or_default();
            let made = parts.finish(result.is_err());
            (kept.zbuffers, kept.parts) = (cache, parts);
            drop(kept);
            let _ = to_main.send(Wake::Built(Box::new(Outcome {
                number,
                result,
                solids,
                parts: made,
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
            parts: PartsMade::default(),
            inputs: Vec::new(),
            took: Duration::ZERO,
        })));
    }
}

/// One build in the loading context `cx`: the plan, refused when it
/// reaches far beyond the machine (as `preview` refuses it); then its
/// model drawn (G-code written in memory, handed to `drawn`) while its
/// checks run beside, when the pool has a second thread; then what the
/// checks found.
fn build(opts: &Options, cx: &Context, drawn: &(dyn Fn(Value) + Sync)) -> Result<Built> {
    use crate::output::preview::html;
    crate::app::pipeline::run(opts.threads, || {
        let mut p = prepare_in(&opts.recipe, &opts.build, cx)?;
        crate::analyse::check::within_reach(&p.recipe, &p.paths, p.extent.points, "preview")
            .map_err(|e| e.in_file(&p.path))?;
        // the viewer's moves read from the G-code beside the passes' spacing
        let draw = || -> Result<[f64; 3]> {
            let read = || -> Result<_> {
                let mut viewer = html::reader(&p);
                let stats = crate::app::pipeline::view(&p, &mut viewer)?;
                Ok((viewer, stats))
            };
            let view = crate::output::preview::Options::default();
            let (read, drawing) = rayon::join(read, || html::draw(&p, &view));
            let (viewer, stats) = read?;
            drawn(html::finish(drawing, viewer, &stats).to_value());
            Ok([0, 1, 2].map(|k| stats.bbox.max[k] - stats.bbox.min[k]))
        };
        let check = || crate::app::pipeline::checked(&p, &opts.build.allow);
        let (size, (findings, footprints)) = rayon::join(draw, check);
        let size = size?;
        (p.findings, p.footprints) = (findings, footprints);
        let (findings, flagged) =
            html::checked(&p, |r| crate::app::pipeline::view(&p, r).map(drop))?;
        let size = size.map(|x| format!("{x:.1}"));
        Ok(Built {
            findings: Value::Array(findings),
            flagged,
            summary: format!(
                "{} · {} mm",
                crate::base::finding::summary(&p.findings),
                size.join(" × ")
            ),
        })
    })
}

/// Tells the pages a build's model, drawn before its checks are done.
fn publish_model(shared: &Shared, d: Drawn) {
    let mut st = shared.lock();
    st.build = st.build.max(d.number);
    let event = json!({"run": shared.run, "build": d.number, "model": d.data, "pending": "checks"});
    st.model = Some((d.number, Arc::new(d.data), Arc::new(event.to_string())));
    st.drawn = (d.number, d.took);
    st.error = None;
    st.seq += 1;
    drop(st);
    shared.changed.notify_all();
}

/// Tells the terminal and the pages how a build went: its checks' findings
/// when it drew a model, else its error.
fn publish(shared: &Shared, out: Outcome) {
    let secs = out.took.as_secs_f64();
    let mut st = shared.lock();
    st.build = st.build.max(out.number);
    match out.result {
        Ok(b) => {
            let drawn = match st.drawn {
                (n, t) if n == out.number => format!(" (drawn in {:.2} s)", t.as_secs_f64()),
                _ => String::new(),
            };
            crate::sayln!(
                "build {}: ok in {secs:.2} s{drawn} · {}{}{} · watching {} file{}",
                out.number,
                b.summary,
                made(&out.parts),
                resliced(&out.solids),
                out.inputs.len(),
                if out.inputs.len() == 1 { "" } else { "s" }
            );
            let event = json!({"run": shared.run, "build": out.number,
                "findings": b.findings, "flagged": b.flagged});
            st.checks = Some((
                out.number,
                Arc::new(b.findings),
                Arc::new(event.to_string()),
            ));
        }
        Err(e) => {
            let kept = match &st.model {
                Some((n, _, _)) if *n != out.number => format!("the page keeps build {n}'s model"),
                Some(_) => "its model stays on the page".to_string(),
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

/// ` · parts made: 1 of 2` (made anew, of all), or nothing without parts.
fn made(parts: &PartsMade) -> String {
    if parts.parts == 0 {
        return String::new();
    }
    format!(" · parts made: {} of {}", parts.made, parts.parts)
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
    /// The tracker of the last rename seen by its new name.
    renamed: Option<usize>,
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

    /// What a file event says of the files followed (or of a missing
    /// folder on the way to one): reading is no change; a write ends when
    /// the file is closed, or renamed into place.
    fn change(&mut self, ev: &notify::Event) -> Change {
        use notify::event::{AccessKind, AccessMode, CreateKind, ModifyKind, RenameMode};
        use notify::EventKind;
        // a rename told twice (its new name, then both names) is one change
        if let EventKind::Modify(ModifyKind::Name(mode)) = ev.kind {
            let told = ev.tracker().is_some() && ev.tracker() == self.renamed;
            if mode == RenameMode::To {
                self.renamed = ev.tracker();
            }
            if mode == RenameMode::Both && told {
                return Change::None;
            }
        }
        let kind = match ev.kind {
            EventKind::Access(AccessKind::Close(AccessMode::Write)) => Change::Done,
            EventKind::Access(_) => return Change::None,
            // the new file in place (a rename's own half, or one reported whole)
            EventKind::Modify(ModifyKind::Name(
                RenameMode::To | RenameMode::Both | RenameMode::Any,
            )) => Change::Done,
            // gone, or a missing folder made: nothing more will come
            EventKind::Remove(_) | EventKind::Create(CreateKind::Folder) => Change::Done,
            // written or made, not yet closed (or renamed away, a new one to come)
            _ => Change::Begun,
        };
        // a rename reported whole names where from, then where to
        let paths = match ev.kind {
            EventKind::Modify(ModifyKind::Name(RenameMode::Both)) => {
                ev.paths.last().into_iter().collect()
            }
            _ => ev.paths.iter().collect::<Vec<_>>(),
        };
        let followed = paths.into_iter().any(|p| {
            let id = identity(p);
            self.files.iter().any(|f| *f == id || f.starts_with(&id))
        });
        if followed {
            kind
        } else {
            Change::None
        }
    }
}

/// What a file event means for the build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Change {
    /// Nothing followed changed.
    None,
    /// A followed file is being written (or renamed away): its close or
    /// rename ends the change.
    Begun,
    /// A followed file's change is complete: build.
    Done,
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
    let mut data = st
        .model
        .as_ref()
        .map_or(Value::Null, |(_, d, _)| (**d).clone());
    // the model's checks, once done (their flags come with the stream)
    if let (Some((n, _, _)), Some((c, findings, _))) = (&st.model, &st.checks) {
        if n == c {
            data["findings"] = (**findings).clone();
        }
    }
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
    let (mut sent_model, mut sent_checks, mut sent_error) = (0u64, 0u64, 0u64);
    let mut seen = u64::MAX;
    loop {
        let (model, checks, error) = {
            let st = shared.lock();
            let (st, timeout) = shared
                .changed
                .wait_timeout_while(st, KEEP_ALIVE, |s| s.seq == seen && !s.stop)
                .unwrap_or_else(|e| e.into_inner());
            if st.stop {
                return;
            }
            if timeout.timed_out() {
                (None, None, None)
            } else {
                seen = st.seq;
                let model = st
                    .model
                    .as_ref()
                    .filter(|(n, _, _)| *n != sent_model)
                    .map(|(n, _, e)| (*n, Arc::clone(e)));
                let checks = st
                    .checks
                    .as_ref()
                    .filter(|(n, _, _)| *n != sent_checks)
                    .map(|(n, _, e)| (*n, Arc::clone(e)));
                let error = st
                    .error
                    .as_ref()
                    .filter(|(n, _, _)| *n != sent_error)
                    .map(|(n, _, e)| (*n, Arc::clone(e)));
                (model, checks, error)
            }
        };
        let mut msg = String::new();
        if let Some((n, e)) = model {
            sent_model = n;
            msg.push_str(&format!("event: model\nid: {n}\ndata: {e}\n\n"));
        }
        if let Some((n, e)) = checks {
            sent_checks = n;
            msg.push_str(&format!("event: checks\nid: {n}\ndata: {e}\n\n"));
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
    fn a_write_is_done_when_closed_or_renamed_into_place_reads_are_nothing() {
        let dir = std::env::temp_dir();
        let mut files = Files::default();
        let recipe = dir.join("p3dp-watch-unit.yaml");
        files.files.insert(identity(&recipe));
        files
            .files
            .insert(identity(&dir.join("p3dp-no-such-dir/map.png")));
        let ev = |kind, p: PathBuf| notify::Event::new(kind).add_path(p);
        use notify::event::{
            AccessKind, AccessMode, CreateKind, DataChange, ModifyKind, RenameMode,
        };
        use notify::EventKind;
        let data = EventKind::Modify(ModifyKind::Data(DataChange::Any));
        let close = EventKind::Access(AccessKind::Close(AccessMode::Write));
        // written in place: begun by the writes, done when closed
        assert_eq!(files.change(&ev(data, recipe.clone())), Change::Begun);
        assert_eq!(files.change(&ev(close, recipe.clone())), Change::Done);
        // a new file renamed over it: done at the rename
        let to = EventKind::Modify(ModifyKind::Name(RenameMode::To));
        assert_eq!(files.change(&ev(to, recipe.clone())), Change::Done);
        let tmp = dir.join("p3dp-watch-unit.yaml.tmp");
        let both = notify::Event::new(EventKind::Modify(ModifyKind::Name(RenameMode::Both)))
            .add_path(tmp.clone())
            .add_path(recipe.clone());
        assert_eq!(files.change(&both), Change::Done);
        // the same rename told by its new name, then by both: one change
        let to = ev(to, recipe.clone()).set_tracker(7);
        assert_eq!(files.change(&to), Change::Done);
        assert_eq!(files.change(&both.clone().set_tracker(7)), Change::None);
        assert_eq!(files.change(&both.set_tracker(8)), Change::Done);
        // renamed away (an editor's backup): a new one is to come
        let away = notify::Event::new(EventKind::Modify(ModifyKind::Name(RenameMode::Both)))
            .add_path(recipe.clone())
            .add_path(dir.join("p3dp-watch-unit.yaml~"));
        assert_eq!(files.change(&away), Change::None);
        let from = EventKind::Modify(ModifyKind::Name(RenameMode::From));
        assert_eq!(files.change(&ev(from, recipe.clone())), Change::Begun);
        // reading is no change; others' files neither
        let read = EventKind::Access(AccessKind::Any);
        assert_eq!(files.change(&ev(read, recipe.clone())), Change::None);
        assert_eq!(files.change(&ev(close, tmp)), Change::None);
        assert_eq!(
            files.change(&ev(
                EventKind::Create(CreateKind::File),
                dir.join("p3dp-watch-unit.yaml.swp")
            )),
            Change::None
        );
        // the missing folder made: the image may be there now
        assert_eq!(
            files.change(&ev(
                EventKind::Create(CreateKind::Folder),
                dir.join("p3dp-no-such-dir")
            )),
            Change::Done
        );
    }
}
