//! The one place that decides what runs where.
//!
//! A command runs inside one pool of `-j` threads ([`run`]): the domain
//! code's own data parallelism (`base::par`: a helix's points, a deform's
//! chunks, the previews' bands) and everything scheduled here share it, and
//! no other thread computes. The stages of a build are plain functions —
//! the checks (`analyse::check::tasks`: which tasks there are and
//! how their findings merge is theirs to say), the emitter
//! (`output::gcode`: the plan's strings into typed commands, each
//! written once and followed by the firmware's state) and the planner
//! (`Planner`: moves into times). This module runs them side by side and
//! puts their results together in one fixed order, so the bytes never
//! depend on the threads.
//!
//! [`write()`] is the one entry of a build: a [`Job`] says whether to check
//! (and when to give up: [`Stop`]), how the G-code is stamped, and whether
//! it is hashed. On two threads or more, this thread writes while a second
//! takes the checks one task at a time, planning the moves recorded so far
//! between them; the writer plans too when the backlog grows, and once
//! everything is written it takes the checks not yet taken. A G-code with
//! progress lines (`M73`, Bambu's header) needs the print's time before its
//! first line: it is formatted once into a scratch file while its moves are
//! planned and `Marks` keeps where progress lines may go, then copied to
//! the output with the lines put in from the planned times
//! (`progressive`), each piece hashed on the second thread while this one
//! makes and writes the next (`copied`).

use std::collections::VecDeque;
use std::io::{self, Write};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, MutexGuard};

use crate::analyse::check::first_layer::Footprint;
use crate::analyse::check::tasks::{Task, Tasks};
use crate::analyse::plan::Plan;
use crate::analyse::planner::{
    place, Both, Call, Estimate, Marks, MoveKind, Moves, Planner, Timeline,
};
use crate::analyse::stats::{MoveStats, Stats};
use crate::base::error::{Error, Result};
use crate::base::finding::Finding;
use crate::output::file::{HashWriter, Scratch};
use crate::output::gcode::metadata::{Ahead, Options};
use crate::output::gcode::{Head, WithProgress};
use crate::output::preview;

/// How many threads a command may use; at least 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Threads(usize);

impl Threads {
    /// One thread: everything runs in turn.
    pub const ONE: Threads = Threads(1);

    /// A budget of `n` threads (0 is taken as 1).
    pub fn new(n: usize) -> Threads {
        Threads(n.max(1))
    }

    /// Most threads per core a budget may have: more only add the cost of
    /// starting them and of smaller shares of work.
    pub const PER_CORE_MAX: usize = 4;

    /// A budget of `n` threads asked for (`-j N`), at most
    /// [`Threads::PER_CORE_MAX`] per core.
    pub fn asked(n: usize) -> Threads {
        Threads::new(n.min(Threads::available().get() * Threads::PER_CORE_MAX))
    }

    /// One thread per core the machine offers (1 when that is unknown).
    pub fn available() -> Threads {
        Threads::new(std::thread::available_parallelism().map_or(1, |n| n.get()))
    }

    /// The number of threads, ≥ 1.
    pub fn get(self) -> usize {
        self.0
    }
}

impl Default for Threads {
    /// [`Threads::available`].
    fn default() -> Threads {
        Threads::available()
    }
}

/// Runs `f` inside a pool of `threads` threads, on one of them: all the
/// parallel work `f` starts shares that pool.
pub fn run<R: Send>(threads: Threads, f: impl FnOnce() -> R + Send) -> R {
    match rayon::ThreadPoolBuilder::new()
        .num_threads(threads.get())
        .thread_name(|k| format!("p3dp-{k}"))
        .build()
    {
        Ok(pool) => pool.install(f),
        // no thread could be started: the work runs here, in turn
        Err(_) => f(),
    }
}

/// Whether the pool has a second thread for work beside this one's.
fn parallel() -> bool {
    rayon::current_num_threads() >= 2
}

/// When a checked build gives up writing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Stop {
    /// Never: everything is written whatever the checks find (`--force`).
    #[default]
    Never,
    /// As soon as the checks fail, warnings counting when `strict`: the
    /// caller refuses the build, so the rest of the G-code would be waste.
    Failing {
        /// Warnings fail too (`--strict`).
        strict: bool,
    },
}

/// What a build does besides writing (see [`write()`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Job<'a> {
    /// Run the checks first or beside the writing, silencing these codes
    /// and stopping as said; `None`: write unchecked.
    pub check: Option<(&'a [String], Stop)>,
    /// How the G-code is stamped (the date, Bambu's package).
    pub stamp: Options,
    /// Hash the G-code (the stats' `gcode_sha256`; empty when not).
    pub hash: bool,
    /// A preview's draft: written even when the profile's start or end
    /// G-code failed its checks, with no progress lines.
    pub draft: bool,
}

/// What a build wrote: the output back, the moves' figures and the stats.
pub struct Written<W> {
    /// The output, flushed.
    pub out: W,
    /// The stats report.
    pub stats: Stats,
    /// What the written moves add up to (for packages).
    pub(crate) moves: MoveStats,
}

/// Runs every check of `plan` and keeps what they found; the costly checks
/// side by side when the pool allows.
pub fn check(plan: &mut Plan, allow: &[String]) {
    (plan.findings, plan.footprints) = checked(plan, allow);
}

/// What every check of `plan` finds (silenced as `allow` says) and each
/// part's hold on the bed, the plan left as it is: for a caller that reads
/// the plan meanwhile (`p3dp watch` draws it while it is checked).
pub(crate) fn checked(plan: &Plan, allow: &[String]) -> (Vec<Finding>, Vec<Footprint>) {
    let tasks = Tasks::new(
        &plan.recipe,
        plan.paths.iter().collect(),
        plan.allowed(allow),
    );
    let queue = Queue::new(&tasks);
    rayon::in_place_scope(|s| {
        if parallel() {
            s.spawn(|_| while queue.run_next() {});
        }
        while queue.run_next() {}
    });
    let (mut findings, footprints) = tasks.merged();
    plan.silence(&mut findings, allow);
    (findings, footprints)
}

/// The one entry of a build: `plan`'s G-code written to `out` as `job`
/// says (see the module comment). With checks, their findings are in the
/// plan whatever the result, and the caller must look at them first: with
/// checks that fail, `out` holds G-code that must not be committed (so
/// `out` should be a temp file, never standard output); under
/// [`Stop::Failing`] the writing gives up early, its error "stopped". The
/// bytes are those of the checks then the writing, on any thread count.
pub fn write<W: Write>(plan: &mut Plan, job: &Job, out: W) -> Result<Written<W>> {
    let out = Hashing::new(out, job.hash);
    let (out, moves) = match job.check {
        Some((allow, stop)) if !parallel() => {
            check(plan, allow);
            if let Stop::Failing { strict } = stop {
                if !plan.failing(strict).is_empty() {
                    return Err(Error::check(&plan.path, "stopped: the checks failed"));
                }
            }
            written(plan, job, out, None)?
        }
        Some((allow, stop)) => checked_beside(plan, job, allow, stop, out)?,
        None => written(plan, job, out, None)?,
    };
    let (out, digest, bytes) = out.finish();
    let stats = Stats::of(plan, &moves, digest, bytes);
    Ok(Written { out, stats, moves })
}

/// Whether the G-code needs the print's time before it is written: `M73`
/// progress, Bambu's header block.
fn ahead(plan: &Plan, job: &Job) -> bool {
    !job.draft && (plan.recipe.printer.progress || job.stamp.bambu)
}

/// The G-code of `plan`, unchecked, in one pass: the planner beside the
/// writer when the pool allows; with progress lines, formatted into a
/// scratch file first ([`progressive`]). `failed` (the checks refused the
/// build) stops the writing.
fn written<W: Write>(
    plan: &Plan,
    job: &Job,
    out: Hashing<W>,
    failed: Option<&AtomicBool>,
) -> Result<(Hashing<W>, MoveStats)> {
    let never = AtomicBool::new(false);
    let failed = failed.unwrap_or(&never);
    let thumbnails = crate::output::preview::thumbnail::blocks(plan)?;
    let head = Head {
        options: job.stamp,
        ahead: None,
        thumbnails,
        draft: job.draft,
    };
    let limits = plan.recipe.printer.limits();
    if ahead(plan, job) {
        let feed = Feed::new(Planner::recording(limits));
        return rayon::in_place_scope(|s| {
            if parallel() {
                s.spawn(|_| feed.plan_to_end());
            }
            progressive(plan, head, &feed, failed, out)
        });
    }
    let out = Until { out, failed };
    let done = if !parallel() {
        let planner = Planner::new(limits);
        crate::output::gcode::write(plan, head, out, planner, finish_planner)
    } else {
        let feed = Feed::new(Planner::new(limits));
        rayon::in_place_scope(|s| {
            s.spawn(|_| feed.plan_to_end());
            let sink = Batches::new(&feed);
            crate::output::gcode::write(plan, head, out, sink, |b| b.end())
        })
    };
    done.map(|(w, m)| (w.out, m))
}

/// A G-code with progress lines (see the module comment): formatted once
/// into a scratch file while its moves go to `feed` (a recording planner)
/// and [`Marks`] keeps where progress lines may go; then, the moves
/// planned, copied to `out` with the lines put in ([`place`]).
fn progressive<W: Write>(
    plan: &Plan,
    head: Head,
    feed: &Feed,
    failed: &AtomicBool,
    out: Hashing<W>,
) -> Result<(Hashing<W>, MoveStats)> {
    let io = |e: io::Error| Error::io_from(&plan.path, format!("cannot write the G-code: {e}"), &e);
    let scratch = Until {
        out: Scratch::new(),
        failed,
    };
    let sink = Both(Batches::new(feed), Marks::default());
    let mut marks = Marks::default();
    let (scratch, moves) = crate::output::gcode::write(plan, head.clone(), scratch, sink, |b| {
        marks = std::mem::take(&mut b.1);
        b.0.end()
    })?;
    let lines = place(&marks, feed.timeline(), &moves.estimate);
    drop(marks);
    let ahead = Ahead::of(&moves);
    let text = scratch.out.into_reader().map_err(io)?;
    let mut copy = WithProgress::new(plan, &head, &ahead, text, &lines);
    let mut out = out;
    copied(&mut copy, &mut out, failed).map_err(io)?;
    Ok((out, moves))
}

/// Bytes of G-code a piece of [`copied`] holds.
const PIECE: usize = 1 << 18;

/// Writes out every piece of `copy` to `out` (see [`WithProgress`]); with
/// a hash and a second thread, each piece is hashed there while this one
/// makes the next and writes it (the SHA-256 is the copy's longest part).
/// `failed` stops it as [`Until`] does.
fn copied<R: io::Read + Send, W: Write>(
    copy: &mut WithProgress<'_, R>,
    out: &mut Hashing<W>,
    failed: &AtomicBool,
) -> io::Result<()> {
    let (sink, mut hasher, bytes) = out.parts()?;
    let (mut cur, mut prev) = (
        Vec::with_capacity(PIECE + 256),
        Vec::with_capacity(PIECE + 256),
    );
    let mut more = copy.fill(&mut cur, PIECE)?;
    while !cur.is_empty() {
        if failed.load(Ordering::Relaxed) {
            return Err(io::Error::other("stopped: the checks failed"));
        }
        std::mem::swap(&mut cur, &mut prev);
        cur.clear();
        let mut next = || -> io::Result<()> {
            if more {
                more = copy.fill(&mut cur, PIECE)?;
            }
            sink.write_all(&prev)
        };
        match hasher.as_deref_mut() {
            Some(h) if parallel() => {
                let prev = &prev;
                rayon::in_place_scope(|s| {
                    s.spawn(move |_| sha2::Digest::update(h, prev));
                    next()
                })?;
            }
            Some(h) => {
                sha2::Digest::update(h, &prev);
                next()?;
            }
            None => next()?,
        }
        *bytes += prev.len() as u64;
    }
    sink.flush()
}

/// [`write`] with checks beside the writing (see the module comment).
fn checked_beside<W: Write>(
    plan: &mut Plan,
    job: &Job,
    allow: &[String],
    stop: Stop,
    out: Hashing<W>,
) -> Result<(Hashing<W>, MoveStats)> {
    let this = &*plan;
    let tasks = Tasks::new(
        &this.recipe,
        this.paths.iter().collect(),
        this.allowed(allow),
    );
    let queue = Queue::new(&tasks);
    let limits = this.recipe.printer.limits();
    let two_passes = ahead(this, job);
    let feed = Feed::new(if two_passes {
        Planner::recording(limits)
    } else {
        Planner::new(limits)
    });
    let failed = AtomicBool::new(false);
    let (queue, feed, failed) = (&queue, &feed, &failed);
    // drawn before the checks' side begins (on both threads: the pictures
    // split their work over the pool): that side plans until the writer's
    // side ends the feed, which a refused thumbnail would never do
    let thumbnails = crate::output::preview::thumbnail::blocks(this)?;
    let written = rayon::in_place_scope(|s| {
        // the checks' side: every task it can take, planning between them;
        // then, unless they refuse the build, the planning that is left
        s.spawn(move |_| {
            while queue.run_next() {
                feed.catch_up();
            }
            let refused = queue.all_done()
                && matches!(stop, Stop::Failing { strict } if queue.tasks.fail(strict));
            failed.store(refused, Ordering::Relaxed);
            if !refused {
                feed.plan_to_end();
            }
        });
        let written = written_beside(this, job, two_passes, feed, failed, thumbnails, out);
        if written.is_ok() {
            // the checks not yet taken (the other side may not have begun)
            while queue.run_next() {}
        }
        written
    });
    let (mut findings, footprints) = tasks.merged();
    plan.silence(&mut findings, allow);
    (plan.findings, plan.footprints) = (findings, footprints);
    written
}

/// The writer's side of [`checked_beside`]: the G-code written with its
/// moves sent to `feed` (which the checks' thread plans between checks),
/// with progress lines through a scratch file ([`progressive`]).
fn written_beside<W: Write>(
    plan: &Plan,
    job: &Job,
    progress: bool,
    feed: &Feed,
    failed: &AtomicBool,
    thumbnails: String,
    out: Hashing<W>,
) -> Result<(Hashing<W>, MoveStats)> {
    let head = Head {
        options: job.stamp,
        thumbnails,
        ..Head::default()
    };
    if progress {
        return progressive(plan, head, feed, failed, out);
    }
    let out = Until { out, failed };
    let sink = Batches::new(feed);
    crate::output::gcode::write(plan, head, out, sink, |b| b.end()).map(|(w, m)| (w.out, m))
}

/// A preview of `plan` for `out` (PNG or HTML by its extension): the
/// G-code written as a draft for its stats (and, for a viewer, its moves)
/// beside the drawing when the pool allows; the same preview either way.
pub(crate) fn preview(
    plan: &Plan,
    out: &Path,
    opts: &preview::Options,
) -> Result<preview::Finished> {
    crate::analyse::check::within_reach(&plan.recipe, &plan.paths, plan.extent.points, "preview")
        .map_err(|e| e.in_file(&plan.path))?;
    let job = preview::Job::new(plan, out, opts)?;
    let mut reader = job.reader();
    let render = |reader: &mut preview::Reader| -> Result<Stats> { view(plan, reader) };
    let (stats, drawing) = if parallel() {
        rayon::join(|| render(&mut reader), || job.draw())
    } else {
        // in turn, the G-code first, so that its memory is let go before
        // the drawing takes its own
        let stats = render(&mut reader);
        (stats, job.draw())
    };
    Ok(job.finish(drawing, reader, &stats?))
}

/// The G-code of `plan` written as a draft (counted, not kept), its moves
/// handed to the planner and to `viewer`: the stats. The viewer's
/// consumer of the command stream, for previews and `p3dp watch`.
pub(crate) fn view(plan: &Plan, viewer: impl Moves) -> Result<Stats> {
    let head = Head {
        thumbnails: crate::output::preview::thumbnail::blocks(plan)?,
        draft: true,
        ..Head::default()
    };
    let out = Counted {
        out: io::sink(),
        bytes: 0,
    };
    let sink = Both(Planner::new(plan.recipe.printer.limits()), viewer);
    let (out, moves) =
        crate::output::gcode::write(plan, head, out, sink, |b| finish_planner(&mut b.0))?;
    Ok(Stats::of(plan, &moves, String::new(), out.bytes))
}

/// The planner's estimate once every move is in.
fn finish_planner(p: &mut Planner) -> Estimate {
    let limits = p.limits().clone();
    std::mem::replace(p, Planner::new(limits)).finish()
}

/// The tasks of one plan's checks, taken one at a time by whichever thread
/// asks, in [`Task::ORDER`]: a geometric task waits for the cheap checks'
/// verdict first.
struct Queue<'a> {
    tasks: &'a Tasks<'a>,
    /// The next task to take (an index into [`Task::ORDER`]).
    next: AtomicUsize,
    /// How many tasks have finished.
    finished: AtomicUsize,
    /// Whether the cheap checks are done; `done` wakes a task waiting on them.
    cheap: (Mutex<bool>, Condvar),
}

impl<'a> Queue<'a> {
    fn new(tasks: &'a Tasks<'a>) -> Queue<'a> {
        Queue {
            tasks,
            next: AtomicUsize::new(0),
            finished: AtomicUsize::new(0),
            cheap: (Mutex::new(false), Condvar::new()),
        }
    }

    /// Takes the next task and runs it on the caller's thread; false when
    /// none is left to take.
    fn run_next(&self) -> bool {
        let k = self.next.fetch_add(1, Ordering::Relaxed);
        let Some(&task) = Task::ORDER.get(k) else {
            return false;
        };
        let (lock, cond) = &self.cheap;
        if task.geometric() {
            let mut done = relock(lock.lock());
            while !*done {
                done = relock(cond.wait(done));
            }
        }
        self.tasks.run(task);
        if task == Task::Cheap {
            *relock(lock.lock()) = true;
            cond.notify_all();
        }
        self.finished.fetch_add(1, Ordering::Release);
        true
    }

    /// Whether every task has finished (on whichever thread).
    fn all_done(&self) -> bool {
        self.finished.load(Ordering::Acquire) == Task::ORDER.len()
    }
}

/// A lock's guard, a poisoned lock taken as it is (a panic elsewhere is
/// raised when its scope ends).
fn relock<T>(r: std::sync::LockResult<T>) -> T {
    r.unwrap_or_else(|e| e.into_inner())
}

/// The output of a build, hashed as it goes when asked, and counted.
enum Hashing<W: Write> {
    /// SHA-256 and size.
    Hashed(HashWriter<W>),
    /// Size alone.
    Counted(Counted<W>),
}

impl<W: Write> Hashing<W> {
    fn new(out: W, hash: bool) -> Hashing<W> {
        if hash {
            Hashing::Hashed(HashWriter::new(out))
        } else {
            Hashing::Counted(Counted { out, bytes: 0 })
        }
    }

    /// The output, its hasher (when hashed) and the size counted so far,
    /// to be written, hashed and counted apart (see [`HashWriter::parts`]).
    fn parts(&mut self) -> io::Result<(&mut W, Option<&mut sha2::Sha256>, &mut u64)> {
        match self {
            Hashing::Hashed(h) => h.parts().map(|(w, s, n)| (w, Some(s), n)),
            Hashing::Counted(c) => Ok((&mut c.out, None, &mut c.bytes)),
        }
    }

    /// The output, the SHA-256 (empty when not hashed) and the size.
    fn finish(self) -> (W, String, u64) {
        match self {
            Hashing::Hashed(h) => {
                let (digest, bytes, out) = h.finish_into();
                (out, digest, bytes)
            }
            Hashing::Counted(c) => (c.out, String::new(), c.bytes),
        }
    }
}

impl<W: Write> Write for Hashing<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self {
            Hashing::Hashed(h) => h.write(buf),
            Hashing::Counted(c) => c.write(buf),
        }
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        match self {
            Hashing::Hashed(h) => h.write_all(buf),
            Hashing::Counted(c) => c.write_all(buf),
        }
    }
    fn flush(&mut self) -> io::Result<()> {
        match self {
            Hashing::Hashed(h) => h.flush(),
            Hashing::Counted(c) => c.flush(),
        }
    }
}

/// Calls recorded at a time before they go to the [`Feed`].
const BATCH: usize = 4096;

/// Recorded batches the writer lets wait before it plans them itself.
const BACKLOG: usize = 8;

/// The planner fed by the writer's [`Batches`], run by whichever thread is
/// free: one lock keeps the calls in order, so the estimate is the one
/// planner's, whoever replayed what.
struct Feed {
    /// The planner, and its estimate (and the blocks' times, when it
    /// records them) once every call is in.
    planner: Mutex<Planned>,
    /// Batches recorded and not yet planned, and whether the writer has
    /// ended; `arrived` wakes a thread waiting for them.
    queue: Mutex<(VecDeque<Vec<Call>>, bool)>,
    arrived: Condvar,
    /// Planned batches, emptied, for the writer to fill again.
    spare: Mutex<Vec<Vec<Call>>>,
}

impl Feed {
    fn new(planner: Planner) -> Feed {
        Feed {
            planner: Mutex::new((Some(planner), None)),
            queue: Mutex::new((VecDeque::new(), false)),
            arrived: Condvar::new(),
            spare: Mutex::new(Vec::new()),
        }
    }

    /// Queues a batch of calls.
    fn send(&self, batch: Vec<Call>) -> usize {
        let mut q = relock(self.queue.lock());
        q.0.push_back(batch);
        self.arrived.notify_one();
        q.0.len()
    }

    /// The writer has ended: no more batches.
    fn close(&self) {
        relock(self.queue.lock()).1 = true;
        self.arrived.notify_all();
    }

    /// The next batch, waiting for one unless `wait` is false; None once
    /// the queue is empty and (when waiting) the writer has ended.
    fn next(&self, wait: bool) -> Option<Vec<Call>> {
        let mut q = relock(self.queue.lock());
        loop {
            if let Some(b) = q.0.pop_front() {
                return Some(b);
            }
            if !wait || q.1 {
                return None;
            }
            q = relock(self.arrived.wait(q));
        }
    }

    /// Replays `batch` and keeps it to be filled again.
    fn replay(&self, planner: &mut Planner, mut batch: Vec<Call>) {
        planner.replay(&batch);
        batch.clear();
        let mut spare = relock(self.spare.lock());
        if spare.len() < 2 * BACKLOG {
            spare.push(batch);
        }
    }

    /// Plans the batches queued so far, unless another thread is planning.
    fn catch_up(&self) {
        let Ok(mut guard) = self.planner.try_lock() else {
            return;
        };
        self.drain(&mut guard, false);
    }

    /// Plans every batch until the writer has ended, then finishes.
    fn plan_to_end(&self) {
        let mut guard = relock(self.planner.lock());
        self.drain(&mut guard, true);
    }

    /// Replays queued batches (waiting for the writer's when `to_end`, then
    /// finishing the estimate).
    fn drain(&self, guard: &mut MutexGuard<'_, Planned>, to_end: bool) {
        let (planner, estimate) = &mut **guard;
        let Some(p) = planner.as_mut() else {
            return; // finished already
        };
        while let Some(b) = self.next(to_end) {
            self.replay(p, b);
        }
        if to_end {
            *estimate = planner.take().map(Planner::finish_timed);
        }
    }

    /// The estimate, once the writer has ended: plans what is left first.
    fn estimate(&self) -> Estimate {
        let mut guard = relock(self.planner.lock());
        self.drain(&mut guard, true);
        match guard.1.as_mut() {
            Some((e, _)) => std::mem::take(e),
            None => Estimate::default(),
        }
    }

    /// The blocks' times of a recording planner, once the writer has
    /// ended and its estimate was taken.
    fn timeline(&self) -> Timeline {
        let mut guard = relock(self.planner.lock());
        self.drain(&mut guard, true);
        guard.1.take().map(|(_, t)| t).unwrap_or_default()
    }
}

/// A [`Feed`]'s planner and, once finished, its estimate and timeline.
type Planned = (Option<Planner>, Option<(Estimate, Timeline)>);

/// The writer's side of a [`Feed`]: moves recorded in batches of
/// [`BATCH`]; when the backlog passes [`BACKLOG`] batches the writer plans
/// some itself, if no other thread is at it.
struct Batches<'a> {
    feed: &'a Feed,
    batch: Vec<Call>,
}

impl<'a> Batches<'a> {
    fn new(feed: &'a Feed) -> Batches<'a> {
        Batches {
            feed,
            batch: Vec::with_capacity(BATCH),
        }
    }

    fn push(&mut self, c: Call) {
        self.batch.push(c);
        if self.batch.len() >= BATCH {
            self.send();
        }
    }

    fn send(&mut self) {
        let fresh = relock(self.feed.spare.lock())
            .pop()
            .unwrap_or_else(|| Vec::with_capacity(BATCH));
        let batch = std::mem::replace(&mut self.batch, fresh);
        if self.feed.send(batch) > BACKLOG {
            self.feed.catch_up();
        }
    }

    /// Sends what is left and returns the estimate.
    fn end(&mut self) -> Estimate {
        self.send();
        self.feed.close();
        self.feed.estimate()
    }
}

impl Drop for Batches<'_> {
    /// A writer that stops on an error ends the feed too: a thread waiting
    /// for its batches goes on.
    fn drop(&mut self) {
        self.feed.close();
    }
}

impl Moves for Batches<'_> {
    fn begin_part(&mut self, name: &str) {
        self.push(Call::BeginPart(name.to_string()));
    }
    fn stop(&mut self) {
        self.push(Call::Stop);
    }
    fn dwell(&mut self, seconds: f64) {
        self.push(Call::Dwell(seconds));
    }
    fn move_to(&mut self, to: glam::DVec3, e: f64, feed: f64, kind: MoveKind) {
        self.push(Call::MoveTo(to, e, feed, kind));
    }
    fn extrude_only(&mut self, length: f64, feed: f64) {
        self.push(Call::ExtrudeOnly(length, feed));
    }
    fn setting(&mut self, s: &crate::base::gcode::Setting) {
        self.push(Call::Setting(Box::new(*s)));
    }
}

/// A writer that counts the bytes through it.
struct Counted<W> {
    out: W,
    bytes: u64,
}

impl<W: Write> Write for Counted<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.out.write(buf)?;
        self.bytes += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

/// A writer that fails once `failed` is set: the G-code of a build the
/// checks refuse is not written on (see [`check_and_write`]).
struct Until<'a, W> {
    out: W,
    failed: &'a AtomicBool,
}

impl<W: Write> Write for Until<'_, W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.failed.load(Ordering::Relaxed) {
            return Err(io::Error::other("stopped: the checks failed"));
        }
        self.out.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}
