//! Writing a plan: its G-code (with the printer's thumbnails), hashed as it
//! goes, and the stats of what was written.

use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;

use crate::analyse::check;
pub use crate::analyse::plan::{Checked, Plan};
use crate::analyse::planner::Background;
use crate::analyse::stats::{PartStats, Stats};
pub use crate::app::prepare::{plan, prepare, Options};
use crate::base::error::{Error, Result};
use crate::base::finding;
use crate::base::threads::Threads;
use crate::base::toolpath::Toolpath;
pub use crate::generate::model::make_part;
use crate::output::file::HashWriter;
use crate::output::gcode::{Emitter, MoveStats};

impl Plan {
    /// Writes the G-code to `out`.
    pub fn write_gcode<W: Write>(&self, out: W) -> Result<(W, MoveStats)> {
        let planner = Background::new(self.recipe.printer.limits(), self.threads);
        self.write_gcode_with(out, planner)
    }

    /// Writes the G-code to `out`, its moves planned by `planner`.
    fn write_gcode_with<W: Write>(&self, out: W, planner: Background) -> Result<(W, MoveStats)> {
        let io =
            |e: io::Error| Error::io_from(&self.path, format!("cannot write the G-code: {e}"), &e);
        let top = self.top_z();
        let mut em = Emitter::with_planner(out, &self.recipe, planner);
        em.thumbnails = crate::output::preview::thumbnail::blocks(self)?;
        let fan_events = |t: &Toolpath| {
            t.events
                .iter()
                .any(|(_, e)| matches!(e, crate::base::toolpath::Event::Fan { .. }))
        };
        if self.paths.iter().any(fan_events) {
            em.manual_fan();
        }
        em.start(&self.recipe, top)?;
        for tp in &self.paths {
            em.part(tp).map_err(io)?;
        }
        em.finish(&self.recipe, top)
    }

    /// Writes the G-code to `out`, hashing it, and returns the stats.
    pub fn render<W: Write>(&self, out: W) -> Result<Stats> {
        let (hw, moves) = self.write_gcode(HashWriter::new(out))?;
        let (digest, bytes) = hw.finish();
        Ok(self.stats(&moves, digest, bytes))
    }

    /// [`Plan::render`] without the SHA-256 of the G-code (its
    /// `gcode_sha256` is empty; the size is counted): for the previews,
    /// which show neither, and need the stats only (hashing the vase's 67 MB
    /// was a tenth of the writing).
    pub fn render_unhashed<W: Write>(&self, out: W) -> Result<Stats> {
        // the planner inline: the previews draw on the other threads meanwhile
        let planner = Background::new(self.recipe.printer.limits(), Threads::ONE);
        let (counted, moves) = self.write_gcode_with(Counted { out, bytes: 0 }, planner)?;
        Ok(self.stats(&moves, String::new(), counted.bytes))
    }

    /// Checks the plan (as [`Plan::check`]) and writes its G-code to `out`
    /// (as [`Plan::write_gcode`]) at the same time, within the plan's thread
    /// budget; with one thread, or when the G-code depends on the findings
    /// (thumbnails mark them), one after the other. The findings are in the
    /// plan whatever the G-code's result, and the caller must look at them
    /// first: with checks that fail, `out` holds G-code that must not be
    /// committed (so `out` should be a temp file, never standard output).
    /// The bytes are those of `check` then `write_gcode`.
    ///
    /// With two threads the G-code is written (and hashed, by `out`) on the
    /// caller's thread while the other runs the checks, then the print-time
    /// planner on the moves recorded meanwhile; with three or more the
    /// planner has a thread of its own and the checks the rest.
    pub fn check_and_write<W: Write>(
        &mut self,
        allow: &[String],
        out: W,
    ) -> Result<(W, MoveStats)> {
        self.check_and_write_until(allow, None, out)
    }

    /// [`Plan::check_and_write`], and with `stop = Some(strict)` the writing
    /// given up as soon as the checks fail at that strictness (the caller
    /// refuses the build, so the rest of the G-code would be wasted work; a
    /// 8M-string vase over the printer's height wrote all 270 MB of it
    /// first). The writer's error is then "stopped": the caller reports the
    /// findings instead. `None` (a `--force` build) always writes everything.
    pub fn check_and_write_until<W: Write>(
        &mut self,
        allow: &[String],
        stop: Option<bool>,
        out: W,
    ) -> Result<(W, MoveStats)> {
        let n = self.threads.get();
        if n == 1 || !self.recipe.printer.thumbnails.is_empty() {
            self.wake();
            self.check(allow);
            if stop.is_some_and(|strict| !self.failing(strict).is_empty()) {
                return Err(Error::check(&self.path, "stopped: the checks failed"));
            }
            return self.write_gcode(out);
        }
        let limits = self.recipe.printer.limits();
        if n == 2 {
            return self.check_and_write_on_two(allow, stop, out, limits);
        }
        let planner = Background::new(limits, Threads::new(2));
        let check_threads = Threads::new(n - 2);
        let this = &*self;
        let failed = AtomicBool::new(false);
        let failed = &failed;
        let (checked, written) = std::thread::scope(|s| {
            let checks = s.spawn(move || {
                let c = this.checks(allow, check_threads);
                let yes = stop.is_some_and(|strict| !finding::failing(&c.0, strict).is_empty());
                failed.store(yes, Ordering::Relaxed);
                c
            });
            let out = Until { out, failed };
            let written = this.write_gcode_with(out, planner).map(|(w, m)| (w.out, m));
            let checked = checks
                .join()
                .unwrap_or_else(|e| std::panic::resume_unwind(e));
            (checked, written)
        });
        (self.findings, self.footprints) = checked;
        written
    }

    /// [`Plan::check_and_write_until`] on two threads. This one writes the
    /// G-code; the other (a pool worker) runs the cheap checks, then takes
    /// the costly ones one at a time ([`check::Tasks`], the longest first),
    /// planning the moves recorded so far between them. The writer, once it
    /// has written everything, plans what is left (the other thread's
    /// catching up stops at its next batch), writes the estimate at the end
    /// of the G-code, runs the cheap checks itself if the other thread has
    /// not started them, and takes the checks not yet taken: so neither
    /// thread waits while the other has work. The findings are put together
    /// in one fixed order.
    fn check_and_write_on_two<W: Write>(
        &mut self,
        allow: &[String],
        stop: Option<bool>,
        out: W,
        limits: crate::analyse::planner::Limits,
    ) -> Result<(W, MoveStats)> {
        let (planner, feed) = Background::fed(limits);
        let this = &*self;
        let refs: Vec<&Toolpath> = this.paths.iter().collect();
        let allowed = this.allowed(allow);
        let cell: OnceLock<check::Tasks> = OnceLock::new();
        let failed = AtomicBool::new(false);
        let (refs, allowed, tasks, failed, feed) = (&refs, &allowed, &cell, &failed, &feed);
        // the cheap checks, run by whichever thread comes first
        let between = move || feed.catch_up();
        let between = &between;
        let new_tasks = move || check::Tasks::new(&this.recipe, refs, allowed, between);
        // the checks on a pool worker (woken at once; a new thread could
        // wait milliseconds to start), the writing on this thread; the scope
        // ends when both have (a panic in the checks is raised then)
        let written = rayon::in_place_scope(|s| {
            s.spawn(move |_| {
                let t = tasks.get_or_init(new_tasks);
                while t.run_next() {
                    feed.catch_up();
                }
                // every check done here (none is on the writer's thread, which
                // takes one only after writing): give up the writing if they
                // refuse the build, else plan beside it until it is written
                let allows: [&[String]; 2] = [&this.recipe.allow, allow];
                let refused = t.all_done() && stop.is_some_and(|strict| t.fail(&allows, strict));
                failed.store(refused, Ordering::Relaxed);
                if !refused {
                    feed.run();
                }
            });
            this.wake();
            let out = Until { out, failed };
            let written = this.write_gcode_with(out, planner).map(|(w, m)| (w.out, m));
            if written.is_ok() {
                // the other thread may not have made the tasks yet, or even
                // started (its worker may be busy with another build's
                // checks): then this one makes them
                let t = tasks.get_or_init(new_tasks);
                while t.run_next() {}
            }
            written
        });
        let t = cell
            .into_inner()
            .expect("the checks' thread made its tasks");
        let (mut findings, footprints) = t.finish();
        self.silence(&mut findings, allow);
        (self.findings, self.footprints) = (findings, footprints);
        written
    }

    /// [`Plan::check_and_write`] through a hashing writer: the stats.
    pub fn check_and_render<W: Write>(&mut self, allow: &[String], out: W) -> Result<Stats> {
        self.check_and_render_until(allow, None, out)
    }

    /// [`Plan::check_and_write_until`] through a hashing writer: the stats.
    pub fn check_and_render_until<W: Write>(
        &mut self,
        allow: &[String],
        stop: Option<bool>,
        out: W,
    ) -> Result<Stats> {
        let (hw, moves) = self.check_and_write_until(allow, stop, HashWriter::new(out))?;
        let (digest, bytes) = hw.finish();
        Ok(self.stats(&moves, digest, bytes))
    }

    /// The stats of the G-code written with `moves`, its hash and size.
    fn stats(&self, moves: &MoveStats, digest: String, bytes: u64) -> Stats {
        let parts = self
            .paths
            .iter()
            .zip(&moves.estimate.parts)
            .map(|(t, pt)| PartStats {
                name: t.name.clone(),
                strings: t.len(),
                print_time_s: pt.times.planned,
                time_lost_s: pt.times.lost(),
            })
            .collect();
        let mut stats = Stats::new(
            &self.path,
            &self.recipe,
            moves,
            parts,
            digest,
            bytes,
            self.findings.clone(),
        );
        stats.first_layer = self.footprints.clone();
        stats
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
/// checks refuse is not written on (see [`Plan::check_and_write_until`]).
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
