//! The one place that decides what runs where.
//!
//! A command runs inside one pool of `-j` threads ([`run`]): the domain
//! code's own data parallelism (`base::par`: a helix's points, a deform's
//! chunks, the previews' bands) and everything scheduled here share it, and
//! no other thread computes. The stages of a build are plain functions —
//! the checks ([`crate::analyse::check`]) from the parts to findings, the
//! G-code writer ([`crate::output::gcode::write`]) from the parts to bytes
//! and moves, the planner ([`Planner`]) from moves to times — and this
//! module runs them side by side and puts their results together in one
//! fixed order, so the bytes never depend on the threads.
//!
//! A checked build on two threads or more ([`check_and_write`]): this
//! thread writes the G-code, its moves recorded in batches for the planner;
//! a second takes the cheap checks, then the costly ones one at a time,
//! planning the moves recorded so far after each; the writer plans too when
//! the backlog grows (so it stays small), and once everything is written it
//! plans what is left and takes the checks not yet taken. With one thread
//! the checks run first, then the writer with the planner inline.

use std::collections::VecDeque;
use std::io::{self, Write};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, MutexGuard, OnceLock};

use crate::analyse::check::{self, first_layer, Cheap, Costly, Finding};
use crate::analyse::plan::Plan;
use crate::analyse::planner::{Call, Clock, Estimate, MoveKind, Moves, Planner, Timeline};
use crate::analyse::stats::{MoveStats, Stats};
use crate::base::error::{Error, Result};
use crate::base::toolpath::Toolpath;
use crate::output::file::HashWriter;
use crate::output::gcode::metadata::{Ahead, Options};
use crate::output::gcode::Head;
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

/// Runs every check of `plan` and keeps what they found; the costly checks
/// side by side when the pool allows.
pub fn check(plan: &mut Plan, allow: &[String]) {
    let refs: Vec<&Toolpath> = plan.paths.iter().collect();
    let tasks = CheckTasks::new(plan, &refs, allow);
    rayon::in_place_scope(|s| {
        if parallel() {
            s.spawn(|_| while tasks.run_next() {});
        }
        while tasks.run_next() {}
    });
    (plan.findings, plan.footprints) = tasks.finish(plan, allow);
}

/// The G-code of `plan` written to `out` (its thumbnails made first), and
/// what its moves add up to; the print-time planner runs beside the writer
/// when the pool allows.
pub fn write<W: Write>(plan: &Plan, out: W) -> Result<(W, MoveStats)> {
    write_with(plan, &Options::default(), out)
}

/// [`write`], stamped as `options` say (the date, Bambu's package).
pub fn write_with<W: Write>(plan: &Plan, options: &Options, out: W) -> Result<(W, MoveStats)> {
    let thumbnails = crate::output::preview::thumbnail::blocks(plan)?;
    written(plan, options, thumbnails, out, None, false)
}

/// Whether the G-code needs the print's time before it is written: `M73`
/// progress, Bambu's header block.
fn ahead(plan: &Plan, options: &Options) -> bool {
    plan.recipe.printer.progress || options.bambu
}

/// The G-code of `plan`, in one pass (the planner beside the writer when
/// the pool allows), or, when it needs the print's time ahead ([`ahead`]),
/// in two: the moves planned first with their times ([`plan_first`]), then
/// the G-code written with a [`Clock`] reading them. `failed` (the checks
/// refused the build) stops the writing.
fn written<W: Write>(
    plan: &Plan,
    options: &Options,
    thumbnails: String,
    out: W,
    failed: Option<&AtomicBool>,
    draft: bool,
) -> Result<(W, MoveStats)> {
    let never = AtomicBool::new(false);
    let failed = failed.unwrap_or(&never);
    let out = Until { out, failed };
    let mut head = Head {
        options: *options,
        ahead: None,
        thumbnails,
        draft,
    };
    // a draft (a preview) needs no progress lines: one pass
    let done = if !draft && ahead(plan, options) {
        let (estimate, timeline, stats) = plan_first(plan, options, failed, draft)?;
        head.ahead = Some(Ahead::of(&stats));
        let clock = Clock::new(timeline, estimate);
        crate::output::gcode::write(plan, head, out, clock, |c| c.estimate())
    } else if !parallel() {
        let planner = Planner::new(plan.recipe.printer.limits());
        crate::output::gcode::write(plan, head, out, planner, finish_planner)
    } else {
        let feed = Feed::new(Planner::new(plan.recipe.printer.limits()));
        rayon::in_place_scope(|s| {
            s.spawn(|_| feed.plan_to_end());
            let sink = Batches::new(&feed);
            crate::output::gcode::write(plan, head, out, sink, |b| b.end())
        })
    };
    done.map(|(w, m)| (w.out, m))
}

/// The first of two passes ([`written`]): the writer's moves alone (its
/// text thrown away), planned by a recording planner beside it when the
/// pool allows; the estimate, each block's time and the totals.
fn plan_first(
    plan: &Plan,
    options: &Options,
    failed: &AtomicBool,
    draft: bool,
) -> Result<(Estimate, Timeline, MoveStats)> {
    let head = Head {
        options: *options,
        draft,
        ..Head::default()
    };
    let discard = Until {
        out: io::sink(),
        failed,
    };
    let planner = Planner::recording(plan.recipe.printer.limits());
    let mut timeline = Timeline::default();
    let (_, mut stats) = if !parallel() {
        crate::output::gcode::write(plan, head, discard, planner, |p| {
            let (e, t) = take_planner(p).finish_timed();
            timeline = t;
            e
        })?
    } else {
        let feed = Feed::new(planner);
        let r = rayon::in_place_scope(|s| {
            s.spawn(|_| feed.plan_to_end());
            let sink = Batches::new(&feed);
            crate::output::gcode::write(plan, head, discard, sink, |b| b.end())
        })?;
        timeline = feed.timeline();
        r
    };
    let estimate = std::mem::take(&mut stats.estimate);
    Ok((estimate, timeline, stats))
}

/// [`write_with`] through a hashing writer: the stats.
pub fn render_with<W: Write>(plan: &Plan, options: &Options, out: W) -> Result<Stats> {
    let (hw, moves) = write_with(plan, options, HashWriter::new(out))?;
    let (digest, bytes) = hw.finish();
    Ok(Stats::of(plan, &moves, digest, bytes))
}

/// [`write`] through a hashing writer: the stats.
pub fn render<W: Write>(plan: &Plan, out: W) -> Result<Stats> {
    let (hw, moves) = write(plan, HashWriter::new(out))?;
    let (digest, bytes) = hw.finish();
    Ok(Stats::of(plan, &moves, digest, bytes))
}

/// [`render`] without the SHA-256 of the G-code (its `gcode_sha256` is
/// empty; the size is counted): for the previews, which show neither.
/// Written as a draft: a profile's start or end G-code that failed its
/// checks does not stop a picture of the print.
pub fn render_unhashed<W: Write>(plan: &Plan, out: W) -> Result<Stats> {
    let thumbnails = crate::output::preview::thumbnail::blocks(plan)?;
    let out = Counted { out, bytes: 0 };
    let (counted, moves) = written(plan, &Options::default(), thumbnails, out, None, true)?;
    Ok(Stats::of(plan, &moves, String::new(), counted.bytes))
}

/// A preview of `plan` for `out` (PNG or HTML by its extension): the
/// G-code written for its stats (and, for a viewer, its moves) beside the
/// drawing when the pool allows; the same preview either way.
pub fn preview(plan: &Plan, out: &Path, opts: &preview::Options) -> Result<preview::Finished> {
    crate::analyse::check::within_reach(&plan.recipe, &plan.paths, "preview")
        .map_err(|e| e.in_file(&plan.path))?;
    let job = preview::Job::new(plan, out, opts)?;
    let mut reader = job.reader();
    let (stats, drawing) = if parallel() {
        rayon::join(|| render_unhashed(plan, &mut reader), || job.draw())
    } else {
        // in turn, the G-code first, so that its memory is let go before
        // the drawing takes its own
        let stats = render_unhashed(plan, &mut reader);
        (stats, job.draw())
    };
    Ok(job.finish(drawing, reader, &stats?))
}

/// Checks `plan` (as [`check`]) and writes its G-code to `out` (as
/// [`write`]) at the same time; with one thread, or when the G-code depends
/// on the findings (thumbnails mark them), one after the other. The
/// findings are in the plan whatever the G-code's result, and the caller
/// must look at them first: with checks that fail, `out` holds G-code that
/// must not be committed (so `out` should be a temp file, never standard
/// output). The bytes are those of `check` then `write`.
///
/// With `stop = Some(strict)` the writing is given up as soon as the
/// checks fail at that strictness (the caller refuses the build, so the
/// rest of the G-code would be wasted work): the writer's error is then
/// "stopped", and the caller reports the findings instead. `None` (a
/// `--force` build) always writes everything.
pub fn check_and_write<W: Write>(
    plan: &mut Plan,
    allow: &[String],
    stop: Option<bool>,
    out: W,
) -> Result<(W, MoveStats)> {
    check_and_write_with(plan, allow, stop, &Options::default(), out)
}

/// [`check_and_write`], stamped as `options` say.
pub fn check_and_write_with<W: Write>(
    plan: &mut Plan,
    allow: &[String],
    stop: Option<bool>,
    options: &Options,
    out: W,
) -> Result<(W, MoveStats)> {
    if !parallel() || !plan.recipe.printer.thumbnails.is_empty() {
        check(plan, allow);
        if stop.is_some_and(|strict| !plan.failing(strict).is_empty()) {
            return Err(Error::check(&plan.path, "stopped: the checks failed"));
        }
        return write_with(plan, options, out);
    }
    let this = &*plan;
    let refs: Vec<&Toolpath> = this.paths.iter().collect();
    let all = CheckTasks::new(this, &refs, allow);
    let limits = this.recipe.printer.limits();
    let two_passes = ahead(this, options);
    let feed = Feed::new(if two_passes {
        Planner::recording(limits)
    } else {
        Planner::new(limits)
    });
    let failed = AtomicBool::new(false);
    let (tasks, feed, failed) = (&all, &feed, &failed);
    let written = rayon::in_place_scope(|s| {
        // the checks' side: every task it can take, planning between them;
        // then, unless they refuse the build, the planning that is left
        s.spawn(move |_| {
            while tasks.run_next() {
                feed.catch_up();
            }
            let refused = tasks.all_done() && stop.is_some_and(|strict| tasks.fail(strict));
            failed.store(refused, Ordering::Relaxed);
            if !refused {
                feed.plan_to_end();
            }
        });
        let written = written_beside(this, options, two_passes, feed, failed, out);
        if written.is_ok() {
            // the checks not yet taken (the other side may not have begun)
            while tasks.run_next() {}
        }
        written
    });
    let checked = all.finish(this, allow);
    (plan.findings, plan.footprints) = checked;
    written
}

/// [`check_and_write`] through a hashing writer: the stats.
pub fn check_and_render<W: Write>(
    plan: &mut Plan,
    allow: &[String],
    stop: Option<bool>,
    out: W,
) -> Result<Stats> {
    check_and_render_with(plan, allow, stop, &Options::default(), out)
}

/// [`check_and_render`], stamped as `options` say.
pub fn check_and_render_with<W: Write>(
    plan: &mut Plan,
    allow: &[String],
    stop: Option<bool>,
    options: &Options,
    out: W,
) -> Result<Stats> {
    let (hw, moves) = check_and_write_with(plan, allow, stop, options, HashWriter::new(out))?;
    let (digest, bytes) = hw.finish();
    Ok(Stats::of(plan, &moves, digest, bytes))
}

/// The planner's estimate once every move is in.
fn finish_planner(p: &mut Planner) -> Estimate {
    take_planner(p).finish()
}

/// The planner, a fresh one left in its place.
fn take_planner(p: &mut Planner) -> Planner {
    let limits = p.limits().clone();
    std::mem::replace(p, Planner::new(limits))
}

/// The writer's side of [`check_and_write`]: the G-code written with its
/// moves sent to `feed` (which the checks' thread plans between checks);
/// with `two_passes`, those moves written first with their text thrown
/// away, then the G-code with a [`Clock`] over the feed's timeline.
fn written_beside<W: Write>(
    plan: &Plan,
    options: &Options,
    two_passes: bool,
    feed: &Feed,
    failed: &AtomicBool,
    out: W,
) -> Result<(W, MoveStats)> {
    let head = Head {
        options: *options,
        ..Head::default()
    };
    let sink = Batches::new(feed);
    if !two_passes {
        let out = Until { out, failed };
        return crate::output::gcode::write(plan, head, out, sink, |b| b.end())
            .map(|(w, m)| (w.out, m));
    }
    let discard = Until {
        out: io::sink(),
        failed,
    };
    let (_, mut stats) = crate::output::gcode::write(plan, head, discard, sink, |b| b.end())?;
    let estimate = std::mem::take(&mut stats.estimate);
    let head = Head {
        options: *options,
        ahead: Some(Ahead::of(&stats)),
        thumbnails: String::new(),
        draft: false,
    };
    let clock = Clock::new(feed.timeline(), estimate);
    let out = Until { out, failed };
    crate::output::gcode::write(plan, head, out, clock, |c| c.estimate()).map(|(w, m)| (w.out, m))
}

/// The checks of one plan as tasks that any thread may take, one at a time,
/// in any interleaving: the cheap checks first (the costly ones run only if
/// they allow), then the costly ones, the longest first, each writing its
/// findings to its own slot; [`CheckTasks::finish`] puts them together in
/// the one fixed order of [`check::merge`].
struct CheckTasks<'a> {
    recipe: &'a crate::generate::model::Recipe,
    paths: &'a [&'a Toolpath],
    allowed: Vec<String>,
    cheap: OnceLock<Cheap>,
    /// The next task to take (an index into [`CheckTasks::ORDER`]).
    next: AtomicUsize,
    /// How many tasks have finished.
    finished: AtomicUsize,
    starvation: OnceLock<Vec<Finding>>,
    support: OnceLock<Vec<Finding>>,
    collision: OnceLock<Vec<Finding>>,
    /// The first layer's strings on the bed, found by whichever half comes
    /// first, and the halves' results.
    bed: OnceLock<first_layer::Bed>,
    contacts: OnceLock<Vec<Option<first_layer::Contact>>>,
    areas: OnceLock<Vec<u64>>,
    /// Tasks waiting for the cheap checks: taken only once they are done.
    cheap_done: (Mutex<bool>, Condvar),
}

/// A task of [`CheckTasks`].
#[derive(Clone, Copy)]
enum Task {
    Cheap,
    Support,
    FirstLayerArea,
    Collision,
    FirstLayerContacts,
    Starvation,
}

impl<'a> CheckTasks<'a> {
    /// The order tasks are taken in: the cheap checks (the others wait for
    /// them), then the longest first, so the last to finish is a short one;
    /// the first layer in two halves, each shorter than the support check.
    const ORDER: [Task; 6] = [
        Task::Cheap,
        Task::Support,
        Task::FirstLayerArea,
        Task::Collision,
        Task::FirstLayerContacts,
        Task::Starvation,
    ];

    fn new(plan: &'a Plan, paths: &'a [&'a Toolpath], allow: &[String]) -> CheckTasks<'a> {
        CheckTasks {
            recipe: &plan.recipe,
            paths,
            allowed: plan.allowed(allow),
            cheap: OnceLock::new(),
            next: AtomicUsize::new(0),
            finished: AtomicUsize::new(0),
            starvation: OnceLock::new(),
            support: OnceLock::new(),
            collision: OnceLock::new(),
            bed: OnceLock::new(),
            contacts: OnceLock::new(),
            areas: OnceLock::new(),
            cheap_done: (Mutex::new(false), Condvar::new()),
        }
    }

    /// Whether the costly geometric checks run: waits for the cheap ones.
    fn geometric(&self) -> bool {
        let (lock, cond) = &self.cheap_done;
        let mut done = relock(lock.lock());
        while !*done {
            done = relock(cond.wait(done));
        }
        self.cheap.get().is_some_and(|c| c.geometric)
    }

    /// Takes the next task and runs it on the caller's thread; false when
    /// none is left to take.
    fn run_next(&self) -> bool {
        let k = self.next.fetch_add(1, Ordering::Relaxed);
        let Some(&task) = Self::ORDER.get(k) else {
            return false;
        };
        let (recipe, paths) = (self.recipe, self.paths);
        let nozzle = recipe.printer.nozzle_diameter;
        match task {
            Task::Cheap => {
                let _ = self.cheap.set(check::cheap(recipe, paths, &self.allowed));
                let (lock, cond) = &self.cheap_done;
                *relock(lock.lock()) = true;
                cond.notify_all();
            }
            Task::Starvation => {
                let _ = self.starvation.set(check::starvation::check(recipe, paths));
            }
            _ if !self.geometric() => {}
            Task::Support => {
                let _ = self.support.set(check::support::check(recipe, paths));
            }
            Task::Collision => {
                let _ = self.collision.set(check::collision::check(recipe, paths));
            }
            Task::FirstLayerContacts => {
                let bed = self.bed.get_or_init(|| first_layer::Bed::of(paths, nozzle));
                let min_h = first_layer::min_height(recipe);
                let _ = self.contacts.set(bed.contacts(paths, min_h));
            }
            Task::FirstLayerArea => {
                let bed = self.bed.get_or_init(|| first_layer::Bed::of(paths, nozzle));
                let _ = self.areas.set(bed.areas(paths, nozzle));
            }
        }
        self.finished.fetch_add(1, Ordering::Release);
        true
    }

    /// Whether every task has finished (on whichever thread).
    fn all_done(&self) -> bool {
        self.finished.load(Ordering::Acquire) == Self::ORDER.len()
    }

    /// Whether the findings, every task done, fail a build at this
    /// strictness (the codes the recipe and the command line allow
    /// silenced).
    fn fail(&self, strict: bool) -> bool {
        let (mut all, _) = self.merged();
        check::apply_allow(&mut all, &self.allowed);
        !check::failing(&all, strict).is_empty()
    }

    /// The findings in the one fixed order, and the footprints; every task
    /// must have run.
    fn merged(&self) -> (Vec<Finding>, Vec<first_layer::Footprint>) {
        let cheap = self.cheap.get().expect("the cheap checks ran");
        let cheap = Cheap {
            findings: cheap.findings.clone(),
            pattern: cheap.pattern.clone(),
            geometric: cheap.geometric,
        };
        let take = |s: &OnceLock<Vec<Finding>>| s.get().cloned().unwrap_or_default();
        let mut costly = Costly {
            starvation: take(&self.starvation),
            support: take(&self.support),
            collision: take(&self.collision),
            ..Costly::default()
        };
        if let (Some(c), Some(a)) = (self.contacts.get(), self.areas.get()) {
            (costly.first_layer, costly.footprints) =
                first_layer::findings(self.recipe, self.paths, c, a);
        }
        check::merge(cheap, costly)
    }

    /// Every finding and the footprints, the codes `plan`'s recipe and
    /// `allow` silence marked.
    fn finish(self, plan: &Plan, allow: &[String]) -> (Vec<Finding>, Vec<first_layer::Footprint>) {
        let (mut findings, footprints) = self.merged();
        plan.silence(&mut findings, allow);
        (findings, footprints)
    }
}

/// A lock's guard, a poisoned lock taken as it is (a panic elsewhere is
/// raised when its scope ends).
fn relock<T>(r: std::sync::LockResult<T>) -> T {
    r.unwrap_or_else(|e| e.into_inner())
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
