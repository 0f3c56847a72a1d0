//! Progress from the planner's own time (`M73 P… R…`), placed the way
//! slicers place it: the G-code is formatted once, while its moves are
//! planned, and the progress lines are put in when it is copied to its
//! output, from the planned times.
//!
//! A printer shows how far a print is and how long is left from the `M73`
//! lines in its G-code, so their values need the print's total time, known
//! only once every move is planned. As the G-code is written, [`Marks`]
//! follows the writer's moves as a consumer of the command stream: it
//! counts the planner's blocks as [`Planner::move_to`](super::Planner::move_to)
//! and [`Planner::extrude_only`](super::Planner::extrude_only) make them (a
//! move of no length or of nothing makes none), and keeps, for each block,
//! where in the G-code the next line a progress line may precede begins
//! (each move's line, and the start and the end of the print), with the
//! dwells and the parts' beginnings between them. Once the planner has the
//! times of its blocks (a [`Timeline`]), [`place`] walks them as a clock
//! would: a progress line is due at each whole percent reached and at each
//! part, and goes at the next such place; the last, 100 % and 0 min,
//! before the end G-code.

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
    pub(crate) percent: u32,
    /// Planned minutes left, rounded to the nearest minute.
    pub(crate) minutes_left: u64,
}

/// Something between blocks that moves the clock (see [`Marks`]).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Event {
    /// The first place a progress line may go (0 % is due at once).
    First,
    /// The head stood this many seconds.
    Dwell(f64),
    /// A part begins: its progress line is due whatever the percent.
    Part,
    /// Every move is written: 100 % before the end G-code.
    Done,
}

/// Where progress lines may go in a G-code being written, and what moves
/// the clock between them (see the module comment).
#[derive(Clone, Debug, Default)]
pub(crate) struct Marks {
    /// The head's position as the planner knows it.
    pos: Option<DVec3>,
    /// Per block, the offset of the next place after it, as the step from
    /// the previous block's (the first from 0), each an unsigned LEB128
    /// varint: a step is mostly one line, under 128 bytes, so one byte per
    /// block (the blocks after the last place have none: step 0).
    steps: Vec<u8>,
    /// The blocks so far.
    blocks: usize,
    /// Blocks since the last place, waiting for its offset.
    waiting: usize,
    /// The offset the last block's place was at.
    last: u64,
    /// Events: the number of blocks before each, its place's offset (0
    /// until that place comes) and what it is.
    events: Vec<(usize, u64, Event)>,
    /// Events since the last place, waiting for its offset.
    events_waiting: usize,
}

impl Marks {
    /// A place a progress line may go, at byte `offset` of the G-code.
    pub(crate) fn place(&mut self, offset: u64) {
        if self.waiting > 0 {
            // the first waiting block carries the step; the rest are at
            // the same place
            leb128(&mut self.steps, offset - self.last);
            self.steps.resize(self.steps.len() + self.waiting - 1, 0);
            self.last = offset;
            self.waiting = 0;
        }
        let n = self.events.len();
        for e in &mut self.events[n - self.events_waiting..] {
            e.1 = offset;
        }
        self.events_waiting = 0;
    }

    /// The first place (before the start G-code), at `offset`.
    pub(crate) fn first(&mut self, offset: u64) {
        self.event(Event::First);
        self.place(offset);
    }

    /// The last place (before the end G-code), at `offset`: 100 %.
    pub(crate) fn done(&mut self, offset: u64) {
        self.event(Event::Done);
        self.place(offset);
    }

    fn event(&mut self, e: Event) {
        self.events.push((self.blocks, 0, e));
        self.events_waiting += 1;
    }

    /// One block.
    fn block(&mut self) {
        self.blocks += 1;
        self.waiting += 1;
    }
}

/// `v` appended as an unsigned LEB128 varint: 7 bits a byte, low first,
/// the high bit set on every byte but the last.
fn leb128(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// The varint [`leb128`] wrote at `*at`, `*at` moved past it; 0 past the end.
fn unleb128(bytes: &[u8], at: &mut usize) -> u64 {
    let mut v = 0u64;
    let mut shift = 0;
    while let Some(&b) = bytes.get(*at) {
        *at += 1;
        v |= u64::from(b & 0x7f) << shift;
        if b < 0x80 {
            break;
        }
        shift += 7;
    }
    v
}

impl Moves for Marks {
    fn place(&mut self, offset: u64) {
        Marks::place(self, offset)
    }
    fn first_place(&mut self, offset: u64) {
        self.first(offset)
    }
    fn last_place(&mut self, offset: u64) {
        self.done(offset)
    }
    fn begin_part(&mut self, _name: &str) {
        self.event(Event::Part);
    }
    fn stop(&mut self) {}
    fn dwell(&mut self, seconds: f64) {
        if seconds > 0.0 {
            self.event(Event::Dwell(seconds));
        }
    }
    fn move_to(&mut self, to: DVec3, e: f64, _feed: f64, _kind: MoveKind) {
        let Some(from) = self.pos else {
            self.pos = Some(to);
            return;
        };
        // as Planner::step: a move of length > 0 (not NaN) is a block;
        // otherwise the position stays and filament fed alone is one
        // (|d|² > 0 exactly when |d| > 0: no square root needed)
        if (to - from).length_squared() > 0.0 {
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
}

/// The clock that reads each block's time off a [`Timeline`]: a progress
/// line is due at each whole percent and at each part.
struct Clock {
    timeline: Timeline,
    /// The whole print's planned time, s.
    total: f64,
    /// A time below which the percent cannot exceed the last shown (a
    /// margin under the exact step): [`Clock::check`] works the percent out
    /// only from there.
    below: f64,
    /// Blocks taken so far.
    next: usize,
    /// Planned time so far, s.
    elapsed: f64,
    /// The last percent handed out.
    shown: Option<u32>,
    /// A progress line due at the next place.
    due: Option<Progress>,
}

impl Clock {
    /// Progress at the time so far (never 100 % before the end).
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
        if self.elapsed < self.below {
            return;
        }
        let p = self.now();
        if self.shown.is_none_or(|s| p.percent > s) {
            self.shown = Some(p.percent);
            self.due = Some(p);
        }
        self.below = self.next_step();
    }

    /// Just under the time at which the percent passes the last shown: the
    /// step's exact time less a relative 1e-9 (far more than the rounding
    /// of `100·elapsed/total`), so the exact test decides at every block
    /// near it.
    fn next_step(&self) -> f64 {
        match self.shown {
            Some(s) if self.total > 0.0 => f64::from(s + 1) * self.total / 100.0 * (1.0 - 1e-9),
            _ => f64::NEG_INFINITY,
        }
    }

    fn event(&mut self, e: Event) {
        match e {
            Event::First => {
                self.due = Some(self.now());
                self.shown = Some(0);
                self.below = self.next_step();
            }
            Event::Dwell(s) => {
                self.elapsed += s;
                self.check();
            }
            Event::Part => {
                let p = self.now();
                self.shown = Some(self.shown.map_or(p.percent, |s| s.max(p.percent)));
                self.due = Some(p);
                self.below = self.next_step();
            }
            Event::Done => {
                self.due = Some(Progress {
                    percent: 100,
                    minutes_left: 0,
                });
            }
        }
    }
}

/// The progress lines of a G-code whose places are `marks`, from the
/// blocks' planned times and the print's `estimate`: each line's byte
/// offset (the line it goes before) and its values, in order.
///
/// The blocks and events run through the clock in the order they came,
/// each with the place that followed it; a place holds a line when the
/// clock has one due there (the last thing before it moved the clock).
pub(crate) fn place(
    marks: &Marks,
    timeline: Timeline,
    estimate: &Estimate,
) -> Vec<(u64, Progress)> {
    let mut clock = Clock {
        total: estimate.total.planned,
        below: f64::NEG_INFINITY,
        timeline,
        next: 0,
        elapsed: 0.0,
        shown: None,
        due: None,
    };
    let mut out = Vec::new();
    let mut items = items(marks).peekable();
    while let Some((item, at)) = items.next() {
        match item {
            None => clock.block(),
            Some(e) => clock.event(e),
        }
        if items.peek().is_none_or(|&(_, next)| next != at) {
            if let Some(p) = clock.due.take() {
                out.push((at, p));
            }
        }
    }
    out
}

/// The blocks (`None`) and events of `marks` in the order they came, each
/// with the offset of the place after it.
fn items(marks: &Marks) -> impl Iterator<Item = (Option<Event>, u64)> + '_ {
    let mut events = marks.events.iter().peekable();
    let mut offset = 0u64;
    let mut b = 0usize;
    let mut at = 0usize;
    std::iter::from_fn(move || {
        if let Some(&&(before, at, e)) = events.peek() {
            if before <= b {
                events.next();
                return Some((Some(e), at));
            }
        }
        if b == marks.blocks {
            return None;
        }
        b += 1;
        offset += unleb128(&marks.steps, &mut at);
        Some((None, offset))
    })
}

#[cfg(test)]
mod tests {
    use super::super::tests::{klipper, long_print, marlin};
    use super::super::Planner;
    use super::*;

    #[test]
    fn steps_read_back_as_written() {
        let values = [
            0u64,
            1,
            127,
            128,
            300,
            16_383,
            16_384,
            u32::MAX as u64 + 7,
            u64::MAX,
        ];
        let mut bytes = Vec::new();
        for &v in &values {
            leb128(&mut bytes, v);
        }
        // one byte below 128, two below 2^14
        assert_eq!(bytes.len(), 1 + 1 + 1 + 2 + 2 + 2 + 3 + 5 + 10);
        let mut at = 0;
        for &v in &values {
            assert_eq!(unleb128(&bytes, &mut at), v);
        }
        assert_eq!(unleb128(&bytes, &mut at), 0, "past the end: 0");
    }

    /// The clock as it ran beside the writer: every call in order, a
    /// progress line written at each place when one is due.
    struct Reference {
        clock: Clock,
        lines: Vec<(u64, Progress)>,
        pos: Option<DVec3>,
    }

    impl Reference {
        fn at(&mut self, offset: u64) {
            if let Some(p) = self.clock.due.take() {
                self.lines.push((offset, p));
            }
        }
    }

    /// A writer of the calls: a place before each move's line (30 bytes),
    /// a part's comment and a dwell's line (20 bytes) with none.
    struct Writer {
        marks: Marks,
        reference: Reference,
        offset: u64,
    }

    impl Writer {
        fn line(&mut self, place: bool, len: u64) {
            if place {
                self.marks.place(self.offset);
                self.reference.at(self.offset);
            }
            self.offset += len;
        }
    }

    impl Moves for Writer {
        fn begin_part(&mut self, name: &str) {
            self.line(false, 20);
            self.marks.begin_part(name);
            self.reference.clock.event(Event::Part);
        }
        fn stop(&mut self) {}
        fn dwell(&mut self, seconds: f64) {
            self.line(false, 20);
            self.marks.dwell(seconds);
            if seconds > 0.0 {
                self.reference.clock.event(Event::Dwell(seconds));
            }
        }
        fn move_to(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
            self.line(true, 30);
            self.marks.move_to(to, e, feed, kind);
            let r = &mut self.reference;
            match r.pos {
                None => r.pos = Some(to),
                Some(from) if (to - from).length() > 0.0 => {
                    r.pos = Some(to);
                    r.clock.block();
                }
                Some(_) if e > 0.0 => r.clock.block(),
                Some(_) => {}
            }
        }
        fn extrude_only(&mut self, length: f64, feed: f64) {
            self.line(true, 30);
            self.marks.extrude_only(length, feed);
            if length.abs() > 0.0 {
                self.reference.clock.block();
            }
        }
    }

    #[test]
    fn progress_lines_go_where_a_clock_beside_the_writer_put_them() {
        for limits in [
            marlin(1000.0, 0.013, 300.0),
            klipper(3000.0, 5.0, 300.0, 0.5),
        ] {
            let mut p = Planner::recording(limits);
            long_print(&mut p);
            let (est, timeline) = p.finish_timed();
            assert!(timeline.len() > 30_000);
            let clock = Clock {
                total: est.total.planned,
                below: f64::NEG_INFINITY,
                timeline: timeline.clone(),
                next: 0,
                elapsed: 0.0,
                shown: None,
                due: None,
            };
            let mut w = Writer {
                marks: Marks::default(),
                reference: Reference {
                    clock,
                    lines: Vec::new(),
                    pos: None,
                },
                offset: 100,
            };
            w.marks.first(w.offset);
            w.reference.clock.event(Event::First);
            w.reference.at(w.offset);
            long_print(&mut w);
            w.marks.done(w.offset);
            w.reference.clock.event(Event::Done);
            w.reference.at(w.offset);
            let lines = place(&w.marks, timeline, &est);
            assert_eq!(lines, w.reference.lines);
            // 0 % first, whole percents in order, minutes counting down, 100 % last
            assert_eq!(
                lines[0],
                (
                    100,
                    Progress {
                        percent: 0,
                        minutes_left: libm::round(est.total.planned / 60.0) as u64
                    }
                )
            );
            let (last, p) = lines[lines.len() - 1];
            assert_eq!((last, p.percent, p.minutes_left), (w.offset, 100, 0));
            assert!(lines
                .windows(2)
                .all(|x| x[0].0 < x[1].0 && x[0].1.percent <= x[1].1.percent));
            assert!(lines
                .windows(2)
                .all(|x| x[0].1.minutes_left >= x[1].1.minutes_left));
            assert!(lines.len() > 95, "{}", lines.len());
            // the reference's clock took every block of the timeline
            assert_eq!(w.reference.clock.next, w.reference.clock.timeline.len());
        }
    }
}
