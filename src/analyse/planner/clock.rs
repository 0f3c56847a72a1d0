//! Progress from the planner's own time (`M73 P… R…`), known before the
//! G-code is written.
//!
//! A printer shows how far a print is and how long is left from the `M73`
//! lines in its G-code, so their values must be known as the lines are
//! written: the print's total time first. The build plans the moves once
//! with a [`Planner::recording`](super::Planner::recording) planner (the
//! writer's moves alone, its text thrown away), which keeps each block's
//! planned time, the [`Timeline`]; then writes the G-code with a [`Clock`]
//! as its moves' sink: the same calls in the same order, so the clock makes
//! the same blocks the planner made (a move of no length or of nothing makes
//! none, exactly as [`Planner::move_to`](super::Planner::move_to) and
//! [`Planner::extrude_only`](super::Planner::extrude_only) decide) and
//! adds their times up as the writer goes, dwells included. The writer asks
//! it after each line whether a progress line is due ([`Moves::due`]).

use glam::DVec3;

use super::{Estimate, MoveKind, Moves};

/// Each block's planned time, s, in the order the blocks were queued.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Timeline {
    times: Vec<f32>,
}

impl Timeline {
    /// The times a recording planner kept (none when it kept none).
    pub(super) fn new(times: Option<Vec<f32>>) -> Timeline {
        Timeline {
            times: times.unwrap_or_default(),
        }
    }

    #[cfg(test)]
    /// The number of blocks.
    pub(crate) fn len(&self) -> usize {
        self.times.len()
    }
}

/// What a printer's screen is told: percent done and minutes left.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Progress {
    /// Whole percent of the print's planned time done, 0 to 100.
    pub percent: u32,
    /// Planned minutes left, rounded to the nearest minute.
    pub minutes_left: u64,
}

/// The moves' sink that reads the time of each block off a [`Timeline`]
/// (see the module comment): a progress line is due at each whole percent
/// and at each part, and [`Moves::done`] gives the last, 100 % and 0 min.
#[derive(Clone, Debug)]
pub(crate) struct Clock {
    timeline: Timeline,
    estimate: Estimate,
    /// The whole print's planned time, s.
    total: f64,
    /// Blocks taken so far.
    next: usize,
    /// Planned time so far, s.
    elapsed: f64,
    /// The head's position as the planner knows it.
    pos: Option<DVec3>,
    /// The last percent handed out.
    shown: Option<u32>,
    /// A progress line due before the next line.
    due: Option<Progress>,
}

impl Clock {
    /// A clock over `timeline`, the print's `estimate` (what the writer's
    /// summary reports); the first progress line (0 %) is due at once.
    pub(crate) fn new(timeline: Timeline, estimate: Estimate) -> Clock {
        let total = estimate.total.planned;
        let mut c = Clock {
            timeline,
            estimate,
            total,
            next: 0,
            elapsed: 0.0,
            pos: None,
            shown: None,
            due: None,
        };
        c.due = Some(c.now());
        c.shown = Some(0);
        c
    }

    /// The estimate the clock was made with.
    pub(crate) fn estimate(&self) -> Estimate {
        self.estimate.clone()
    }

    /// Progress at the time so far (never 100 % before [`Moves::done`]).
    fn now(&self) -> Progress {
        let frac = if self.total > 0.0 {
            self.elapsed / self.total
        } else {
            0.0
        };
        let percent = libm::floor(100.0 * frac).clamp(0.0, 99.0) as u32;
        let left = (self.total - self.elapsed).max(0.0);
        Progress {
            percent,
            minutes_left: libm::round(left / 60.0) as u64,
        }
    }

    /// One block taken: its time added, and a progress line due when a new
    /// whole percent is reached.
    fn block(&mut self) {
        if let Some(&t) = self.timeline.times.get(self.next) {
            self.elapsed += f64::from(t);
        }
        self.next += 1;
        self.check();
    }

    fn check(&mut self) {
        let p = self.now();
        if self.shown.is_none_or(|s| p.percent > s) {
            self.shown = Some(p.percent);
            self.due = Some(p);
        }
    }
}

impl Moves for Clock {
    fn begin_part(&mut self, _name: &str) {
        let p = self.now();
        self.shown = Some(self.shown.map_or(p.percent, |s| s.max(p.percent)));
        self.due = Some(p);
    }
    fn stop(&mut self) {}
    fn dwell(&mut self, seconds: f64) {
        if seconds > 0.0 {
            self.elapsed += seconds;
            self.check();
        }
    }
    fn move_to(&mut self, to: DVec3, e: f64, _feed: f64, _kind: MoveKind) {
        let Some(from) = self.pos else {
            self.pos = Some(to);
            return;
        };
        // as Planner::step: a move of length > 0 (not NaN) is a block;
        // otherwise the position stays and filament fed alone is one
        if (to - from).length() > 0.0 {
            self.pos = Some(to);
            self.block();
        } else if e > 0.0 {
            self.extrude_only(e, 0.0);
        }
    }
    fn extrude_only(&mut self, length: f64, _feed: f64) {
        let length = length.abs();
        if length > 0.0 && length.is_finite() {
            self.block();
        }
    }
    #[inline]
    fn due(&mut self) -> Option<Progress> {
        self.due.take()
    }
    fn done(&mut self) -> Option<Progress> {
        self.due = None;
        Some(Progress {
            percent: 100,
            minutes_left: 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{klipper, long_print, marlin};
    use super::super::Planner;
    use super::*;

    #[test]
    fn the_clock_takes_the_planners_blocks_and_ends_at_its_total() {
        for limits in [
            marlin(1000.0, 0.013, 300.0),
            klipper(3000.0, 5.0, 300.0, 0.5),
        ] {
            clock_over(limits);
        }
    }

    fn clock_over(limits: crate::analyse::planner::Limits) {
        let mut p = Planner::recording(limits);
        long_print(&mut p);
        let (est, timeline) = p.finish_timed();
        assert!(timeline.len() > 30_000);
        let mut c = Clock::new(timeline, est.clone());
        assert_eq!(c.due().map(|p| p.percent), Some(0));
        let mut shown = vec![];
        long_print(&mut RecordDue(&mut c, &mut shown));
        // every block of the timeline taken, no more
        assert_eq!(c.next, c.timeline.len());
        let rel = (c.elapsed - est.total.planned).abs() / est.total.planned;
        assert!(rel < 1e-5, "{} vs {}", c.elapsed, est.total.planned);
        // whole percents in order, each once (parts repeat the current one)
        let mut last = 0;
        for p in &shown {
            assert!(p.percent >= last && p.percent <= 99, "{shown:?}");
            last = p.percent;
        }
        assert!(last >= 98, "{last}");
        let left: Vec<u64> = shown.iter().map(|p| p.minutes_left).collect();
        assert!(left.windows(2).all(|w| w[0] >= w[1]), "{left:?}");
        assert_eq!(
            c.done().map(|p| (p.percent, p.minutes_left)),
            Some((100, 0))
        );
    }

    /// Passes the calls on to a clock and keeps each progress line due.
    struct RecordDue<'a>(&'a mut Clock, &'a mut Vec<Progress>);

    impl Moves for RecordDue<'_> {
        fn begin_part(&mut self, name: &str) {
            self.0.begin_part(name);
            self.1.extend(self.0.due());
        }
        fn stop(&mut self) {
            self.0.stop();
        }
        fn dwell(&mut self, s: f64) {
            self.0.dwell(s);
            self.1.extend(self.0.due());
        }
        fn move_to(&mut self, to: DVec3, e: f64, f: f64, k: MoveKind) {
            self.0.move_to(to, e, f, k);
            self.1.extend(self.0.due());
        }
        fn extrude_only(&mut self, l: f64, f: f64) {
            self.0.extrude_only(l, f);
            self.1.extend(self.0.due());
        }
    }
}
