//! The print-time estimate: a trapezoidal-velocity planner with look-ahead,
//! modelled on the firmware's own (Marlin's junction deviation, Klipper's
//! square-corner velocity and minimum cruise ratio).
//!
//! Each written move is a *block*: its length (3D, Z included; for a move of E
//! alone, its filament length), an acceleration `a` and a nominal speed
//!
//! ```text
//! v_nom = min(F, max_velocity, max_z_velocity · L/|dz|)
//! ```
//!
//! (`max_velocity` does not cap E-only moves, which run at their own F, under
//! Klipper at most `max_extrude_only_velocity` and accelerating at most at
//! `max_extrude_only_accel`; a move with Z accelerates at most at
//! `max_z_acceleration · L/|dz|`), then slowed by Marlin's minimum segment
//! time while its buffer drains (see [`Planner::slowdown`]). The
//! head starts and ends at rest. Between two XYZ blocks the speed may not
//! exceed the *junction speed* of the corner (see [`Planner::junction_v2`]),
//! nor either block's nominal speed; around an E-only block (a retraction) the
//! head is at rest, as in Klipper. Then, in v² units, with `e_i` the entry v²
//! of block i:
//!
//! - backward pass, from the end at rest: `e_i = min(j_i, e_{i+1} + 2·a_i·L_i)`
//!   (every block can decelerate to what follows);
//!   under Klipper the junction is also held to (icv / |Δr|)² where r is the
//!   filament per mm of path (`instantaneous_corner_velocity`: G1 ↔ G0);
//! - forward pass, from the start at rest: `e_i = min(e_i, e_{i-1} + 2·a_{i-1}·L_{i-1})`
//!   (every block can be reached by accelerating);
//! - each block is a trapezoid: it accelerates at `a` from its entry speed,
//!   cruises at `v_nom` when it gets there, and decelerates to its exit speed
//!   (a triangle when the block is too short to reach `v_nom`).
//!
//! Under Klipper the forward limit is applied as the blocks come and the
//! passes are Klipper's own, with its `minimum_cruise_ratio` (see
//! `klipper_passes`).
//!
//! This is the firmware's look-ahead with an unbounded buffer: the passes run
//! over the whole print at [`Planner::finish`]. A firmware's buffer (16 moves
//! for Marlin, about 1 s of moves for Klipper) is long enough for the short
//! strings of p3dp's recipes that this differs little; with long moves at high
//! speed a short buffer would plan slower than this.
//!
//! Everything is + − × ÷ and `sqrt` (IEEE-exact), plus `libm::asin`, so the
//! estimate is the same on every machine.

mod clock;
mod junction;
mod klipper;
mod marlin;

pub(crate) use clock::{place, Marks, Progress, Timeline};

use glam::DVec3;

use junction::Turn;
use klipper::{klipper_passes, Mcr};
use marlin::{Queue, SETTLE};

#[cfg(test)]
use crate::machine::kinematics::Kinematics;
pub(crate) use crate::machine::kinematics::Limits;

/// What a move is, which chooses its acceleration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MoveKind {
    /// An extruding move (G1 with E): `max_acceleration`.
    Extrude,
    /// A travel move (G0): `travel_acceleration`.
    Travel,
}

/// Times of a print or of one part, s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Times {
    /// Planned: with acceleration, junction speeds and speed limits.
    pub(crate) planned: f64,
    /// Σ L / F: the time the G-code asks for, as if every move ran at its F.
    pub(crate) ideal: f64,
    /// Σ L / v_nom: F capped by `max_velocity` and `min_segment_time`, no acceleration.
    pub(crate) nominal: f64,
}

impl Times {
    /// Time lost to acceleration, deceleration and corners: planned − nominal.
    pub(crate) fn lost_to_acceleration(&self) -> f64 {
        self.planned - self.nominal
    }

    /// Time lost to the speed limits: nominal − ideal.
    pub(crate) fn lost_to_speed_limits(&self) -> f64 {
        self.nominal - self.ideal
    }

    /// All time lost against the G-code's speeds: planned − ideal.
    pub(crate) fn lost(&self) -> f64 {
        self.planned - self.ideal
    }
}

/// One part's times.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PartTimes {
    /// Part name.
    pub(crate) name: String,
    /// Its times, s.
    pub(crate) times: Times,
}

/// The planner's answer: the whole print's times, and each part's.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Estimate {
    /// All moves.
    pub(crate) total: Times,
    /// Each part begun with [`Planner::begin_part`], in order.
    pub(crate) parts: Vec<PartTimes>,
}

/// One move, as the passes need it (32 bytes: 2M moves take 64 MB).
#[derive(Clone, Copy, Debug)]
struct Block {
    len: f64,
    accel: f64,
    /// Cruise v²: v_nom².
    cruise_v2: f64,
    /// Highest entry v² (junction limit; under Klipper also what the blocks
    /// before can reach), then the planned entry v².
    entry_v2: f64,
}

/// The last XYZ block, for the next junction.
#[derive(Clone, Copy, Debug)]
struct Last {
    dir: DVec3,
    len: f64,
    accel: f64,
    cruise_v2: f64,
    /// Filament per mm of path (0 for travel), for Klipper's extruder corner.
    e_per_mm: f64,
    /// Its acceleration over its kind's nominal one (below 1 when the Z axis
    /// limits it): Klipper's junction deviation scales with it.
    accel_share: f64,
}

/// What a move to a point is before the planner's state matters: its own
/// geometry and limits and its corner with the move before (the square
/// roots and divisions of [`Planner::move_to`] that do not wait on the
/// queue or the junction before it, worked out for a run of moves first).
#[derive(Clone, Copy, Debug)]
enum Step {
    /// The first move: it only sets the position.
    First,
    /// No motion (an E-only move when it feeds filament).
    Still,
    /// A move of `len` mm along `dir`.
    Moves(Geo),
}

/// A move's geometry (see [`Step`]).
#[derive(Clone, Copy, Debug)]
struct Geo {
    len: f64,
    dir: DVec3,
    /// Its kind's acceleration, and its own (lower when the Z axis limits it).
    base: f64,
    accel: f64,
    /// The Z axis's cap on its speed.
    cap: f64,
    /// The corner from the move before that moved (None for the first).
    turn: Option<Turn>,
}

/// Calls replayed at a time in [`Planner::replay`]: their [`Step`]s
/// stay in the fastest cache.
const STEPS: usize = 256;

struct Part {
    name: String,
    first: usize,
    ideal: f64,
    nominal: f64,
    dwell: f64,
}

/// Collects the moves of a print and plans them (see the module comment).
pub(crate) struct Planner {
    limits: Limits,
    blocks: Vec<Block>,
    /// Under Klipper's model, each block's [`Mcr`]; empty under Marlin's.
    mcr: Vec<Mcr>,
    pos: Option<DVec3>,
    last: Option<Last>,
    parts: Vec<Part>,
    /// Before any part: (ideal, nominal, dwell).
    pre: (f64, f64, f64),
    queue: Queue,
    /// 1 / `command_rate`, s a line: the same division done once, not per move.
    line_time: f64,
    /// The direction of the last move that moved (whatever came after it).
    prev_dir: Option<DVec3>,
    /// The steps of the calls being replayed (see [`Planner::replay`]).
    steps: Vec<Step>,
    /// Under Marlin's model, blocks planned already (their times summed in
    /// `planned`) and no longer kept: `blocks` starts with block `done`.
    done: usize,
    /// Whether `blocks[0]` is planned in both passes (a block kept from the
    /// last [`Planner::plan_settled`]: its entry is final).
    head_planned: bool,
    /// The planned time so far before the parts, then of each part.
    planned: Vec<f64>,
    /// The range the next planned block belongs to (0: before any part).
    slot: usize,
    /// The block count at which to look for settled blocks next.
    next_settle: usize,
    /// Each block's planned time in order, when asked for
    /// ([`Planner::recording`]): the timeline of `M73` progress.
    timeline: Option<Vec<f32>>,
    /// The accelerations last asked for (print, travel, retract: `M204`),
    /// before the per-axis caps (`M201`) hold them.
    asked: [f64; 3],
    /// The per-axis acceleration caps (`M201`), mm/s²: of X and Y (the
    /// lower of the two), which hold moves of the head, and of E, which
    /// holds a retraction (a move of E alone).
    accel_cap: [f64; 2],
}

impl Planner {
    /// A planner with these limits, the head at an unknown place.
    pub(crate) fn new(limits: Limits) -> Planner {
        Planner {
            blocks: Vec::new(),
            mcr: Vec::new(),
            pos: None,
            last: None,
            parts: Vec::new(),
            pre: (0.0, 0.0, 0.0),
            queue: Queue::default(),
            line_time: 1.0 / limits.command_rate,
            prev_dir: None,
            steps: Vec::new(),
            done: 0,
            head_planned: false,
            planned: vec![0.0],
            slot: 0,
            next_settle: SETTLE,
            timeline: None,
            asked: [
                limits.max_acceleration,
                limits.travel_acceleration,
                limits.retract_acceleration,
            ],
            accel_cap: [f64::INFINITY; 2],
            limits,
        }
    }

    /// A setting the firmware follows from here on, as it does: `M204`'s
    /// accelerations (a move of the head held to `M201`'s caps of X and Y, the
    /// lower of the two), the speed limits (`M203`, Klipper's
    /// `VELOCITY`), the junction deviation, classic jerk (as Marlin's
    /// conversion, 0.4·jerk²/acceleration), the square-corner velocity and
    /// minimum cruise ratio of Klipper's model. A setting of the other
    /// firmware's model, or one that does not change times (temperatures,
    /// pressure advance, input shaping), changes nothing.
    pub(crate) fn setting(&mut self, s: &crate::base::gcode::Setting) {
        use crate::base::gcode::Setting as S;
        let l = &mut self.limits;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        match *s {
            S::Acceleration {
                print,
                travel,
                retract,
            } => {
                for (k, v) in [print, travel, retract].into_iter().enumerate() {
                    if let Some(a) = v.filter(|&a| positive(a)) {
                        self.asked[k] = a;
                    }
                }
                self.hold_accelerations();
            }
            S::MaxAcceleration { axes } => {
                let xy = [axes[0], axes[1]]
                    .into_iter()
                    .flatten()
                    .filter(|&a| positive(a));
                if let Some(cap) = xy.reduce(f64::min) {
                    self.accel_cap[0] = cap;
                }
                if let Some(ce) = axes[3].filter(|&a| positive(a)) {
                    self.accel_cap[1] = ce;
                }
                self.hold_accelerations();
                if let Some(az) = axes[2].filter(|&a| positive(a)) {
                    self.limits.max_z_acceleration = Some(az);
                }
            }
            S::SpeedLimit { velocity } if positive(velocity) => l.max_velocity = velocity,
            S::MaxFeedrate { axes } => {
                let xy = [axes[0], axes[1]]
                    .into_iter()
                    .flatten()
                    .filter(|&v| positive(v));
                if let Some(v) = xy.reduce(f64::min) {
                    l.max_velocity = v;
                }
                if let Some(vz) = axes[2].filter(|&v| positive(v)) {
                    l.max_z_velocity = Some(vz);
                }
            }
            S::JunctionDeviation(j) if positive(j) && l.junction_deviation.is_some() => {
                l.junction_deviation = Some(j);
            }
            S::Jerk(j) if positive(j) && l.junction_deviation.is_some() => {
                l.junction_deviation = Some(0.4 * j * j / l.max_acceleration);
            }
            S::SquareCornerVelocity(v) if v >= 0.0 && l.square_corner_velocity.is_some() => {
                l.square_corner_velocity = Some(v);
            }
            S::MinimumCruiseRatio(r)
                if (0.0..1.0).contains(&r) && l.square_corner_velocity.is_some() =>
            {
                l.minimum_cruise_ratio = r;
            }
            _ => {}
        }
    }

    /// The accelerations asked for, each held to its per-axis cap (a move
    /// of the head to X's and Y's, a retraction to E's).
    fn hold_accelerations(&mut self) {
        let [c, ce] = self.accel_cap;
        self.limits.max_acceleration = self.asked[0].min(c);
        self.limits.travel_acceleration = self.asked[1].min(c);
        self.limits.retract_acceleration = self.asked[2].min(ce);
    }

    /// A planner that also keeps each block's planned time
    /// ([`Planner::finish_timed`]).
    pub(crate) fn recording(limits: Limits) -> Planner {
        Planner {
            timeline: Some(Vec::new()),
            ..Planner::new(limits)
        }
    }

    /// The limits in use.
    pub(crate) fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Moves from now on belong to part `name` (parts are consecutive).
    pub(crate) fn begin_part(&mut self, name: &str) {
        self.parts.push(Part {
            name: name.to_string(),
            first: self.done + self.blocks.len(),
            ideal: 0.0,
            nominal: 0.0,
            dwell: 0.0,
        });
    }

    /// Counts a move of `len` mm asked at `feed` mm/s and planned at a
    /// nominal `v`: its ideal time at the feed (at `v` when the feed is not a
    /// speed) and its nominal time.
    fn add_move(&mut self, len: f64, feed: f64, v: f64) {
        let ideal = if feed.is_finite() && feed > 0.0 {
            len / feed
        } else {
            len / v
        };
        self.add(ideal, len / v, 0.0);
    }

    fn add(&mut self, ideal: f64, nominal: f64, dwell: f64) {
        match self.parts.last_mut() {
            Some(p) => {
                p.ideal += ideal;
                p.nominal += nominal;
                p.dwell += dwell;
            }
            None => {
                self.pre.0 += ideal;
                self.pre.1 += nominal;
                self.pre.2 += dwell;
            }
        }
    }

    /// The head comes to rest here (a pause, a wait, a dwell): the next move
    /// starts from rest.
    pub(crate) fn stop(&mut self) {
        self.last = None;
        self.drain(0.0);
    }

    /// The head stands still for `seconds` (e.g. `G4`): counted in every time.
    pub(crate) fn dwell(&mut self, seconds: f64) {
        self.last = None;
        self.drain(seconds.max(0.0));
        if seconds > 0.0 {
            self.add(seconds, seconds, seconds);
        }
    }

    /// Nominal speed: F capped by `max_velocity` (XYZ moves) and by
    /// `cap`, then by `min_segment_time` (see [`Planner::slowdown`]).
    fn nominal(&mut self, len: f64, feed: f64, xyz: bool, cap: f64) -> f64 {
        let mut v = if feed.is_finite() && feed > 0.0 {
            feed
        } else {
            self.limits.max_velocity
        };
        if xyz {
            v = v.min(self.limits.max_velocity);
        }
        v = v.min(cap);
        self.slowdown(len, v)
    }

    /// A move to `to` (machine coordinates, mm) at `feed` mm/s, feeding `e` mm
    /// of filament. The first move, from an unknown place, only sets the
    /// position; a move of E alone (`to` where the head is, `e` > 0) is an
    /// E-only block at `feed` with `retract_acceleration`, from rest to rest;
    /// a move of nothing is skipped.
    pub(crate) fn move_to(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
        let step = self.step(to, kind);
        self.take(step, e, feed, kind);
    }

    /// The first half of [`Planner::move_to`]: the move's geometry, from the
    /// position alone (which it updates, with the last direction). The
    /// rest of the planner's state plays no part, so the steps of a run of
    /// calls can be worked out before any of them is taken.
    fn step(&mut self, to: DVec3, kind: MoveKind) -> Step {
        let Some(from) = self.pos else {
            self.pos = Some(to);
            return Step::First;
        };
        let d = to - from;
        let len = d.length();
        let moves = len > 0.0; // not when NaN
        if !moves {
            return Step::Still;
        }
        let base = match kind {
            MoveKind::Extrude => self.limits.max_acceleration,
            MoveKind::Travel => self.limits.travel_acceleration,
        };
        let mut accel = base;
        // the Z axis's own limits, scaled to the move as both firmwares
        // do (Klipper's cartesian check_move: z_ratio = L / |dz|)
        let mut cap = f64::INFINITY;
        if d.z != 0.0 {
            let z_ratio = len / d.z.abs();
            if let Some(vz) = self.limits.max_z_velocity {
                cap = vz * z_ratio;
            }
            if let Some(az) = self.limits.max_z_acceleration {
                accel = accel.min(az * z_ratio);
            }
        }
        let dir = d / len;
        let turn = self.prev_dir.map(|p| Turn::new(p, dir));
        self.prev_dir = Some(dir);
        self.pos = Some(to);
        Step::Moves(Geo {
            len,
            dir,
            base,
            accel,
            cap,
            turn,
        })
    }

    /// The second half of [`Planner::move_to`]: the move taken, its step
    /// worked out.
    fn take(&mut self, step: Step, e: f64, feed: f64, kind: MoveKind) {
        let g = match step {
            Step::First => return,
            Step::Still => {
                if e > 0.0 {
                    self.extrude_only(e, feed);
                }
                return;
            }
            Step::Moves(g) => g,
        };
        let Geo {
            len,
            dir,
            base,
            accel,
            cap,
            turn,
        } = g;
        let v = self.nominal(len, feed, true, cap);
        let cruise_v2 = v * v;
        // the extruder's corner (e_per_mm) and the acceleration's share
        // are read under Klipper's limits only: Marlin's skip the divisions
        let icv = self.limits.instantaneous_corner_velocity;
        let e_per_mm = if kind == MoveKind::Extrude && icv.is_some() {
            e / len
        } else {
            0.0
        };
        let accel_share = if self.limits.square_corner_velocity.is_some() {
            accel / base
        } else {
            1.0
        };
        let mut entry_v2 = match self.last {
            Some(prev) => {
                // the last block is the last move that moved: its turn
                let t = turn.unwrap_or_else(|| Turn::new(prev.dir, dir));
                let mut j = self.junction_v2(&prev, &t, len, accel, accel_share, cruise_v2);
                // Klipper's extruder.py calc_junction: the E speed may
                // change at once by at most instantaneous_corner_velocity
                if let Some(icv) = icv {
                    let dr = (e_per_mm - prev.e_per_mm).abs();
                    if dr > 0.0 {
                        j = j.min((icv / dr) * (icv / dr));
                    }
                }
                j
            }
            None => 0.0,
        };
        let (mcr_entry_v2, mcr_delta_v2) = self.klipper_entry(&mut entry_v2, base, accel, len);
        self.push(
            Block {
                len,
                accel,
                cruise_v2,
                entry_v2,
            },
            mcr_entry_v2,
            mcr_delta_v2,
        );
        self.last = Some(Last {
            dir,
            len,
            accel,
            cruise_v2,
            e_per_mm,
            accel_share,
        });
        self.add_move(len, feed, v);
    }

    /// Replays recorded calls in order, as one call at a time would: each
    /// run of [`STEPS`] calls has its moves' steps worked out first (a loop
    /// whose moves do not wait on each other, so the processor overlaps
    /// their square roots and divisions), then is taken. The same
    /// operations on the same values, so the same estimate.
    pub(crate) fn replay(&mut self, calls: &[Call]) {
        let mut steps = std::mem::take(&mut self.steps);
        // a setting changes the limits the steps are worked out with: the
        // runs end at each one
        let runs = calls
            .split_inclusive(|c| matches!(c, Call::Setting(_)))
            .flat_map(|r| r.chunks(STEPS));
        for run in runs {
            steps.clear();
            for c in run {
                if let Call::MoveTo(to, _, _, kind) = *c {
                    steps.push(self.step(to, kind));
                }
            }
            let mut next = steps.iter();
            for c in run {
                match *c {
                    Call::MoveTo(_, e, feed, kind) => {
                        let step = *next.next().expect("a step for every move");
                        self.take(step, e, feed, kind);
                    }
                    _ => self.call(c),
                }
            }
        }
        self.steps = steps;
    }

    /// A move of E alone (retraction, unretraction), `length` mm of filament
    /// at `feed` mm/s: from rest to rest, as Klipper plans extrude-only moves.
    pub(crate) fn extrude_only(&mut self, length: f64, feed: f64) {
        let length = length.abs();
        if length <= 0.0 || !length.is_finite() {
            return;
        }
        // Klipper's extruder.py check_move: an extrude-only move is held to
        // max_extrude_only_velocity and max_extrude_only_accel
        let cap = self
            .limits
            .max_extrude_only_velocity
            .unwrap_or(f64::INFINITY);
        let accel = match self.limits.max_extrude_only_accel {
            Some(a) => a.min(self.limits.retract_acceleration),
            None => self.limits.retract_acceleration,
        };
        let v = self.nominal(length, feed, false, cap);
        self.last = None;
        let mut entry_v2 = 0.0;
        let base = self.limits.max_acceleration;
        let (mcr_entry_v2, mcr_delta_v2) = self.klipper_entry(&mut entry_v2, base, accel, length);
        self.push(
            Block {
                len: length,
                accel,
                cruise_v2: v * v,
                entry_v2,
            },
            mcr_entry_v2,
            mcr_delta_v2,
        );
        self.add_move(length, feed, v);
    }

    /// Queues a block, with its minimum-cruise-ratio profile under Klipper's model.
    fn push(&mut self, b: Block, mcr_entry_v2: f64, mcr_delta_v2: f64) {
        self.blocks.push(b);
        if self.limits.square_corner_velocity.is_none() && self.blocks.len() >= self.next_settle {
            self.plan_settled();
        }
        if self.limits.square_corner_velocity.is_some() {
            self.mcr.push(Mcr {
                entry_v2: mcr_entry_v2,
                delta_v2: mcr_delta_v2,
            });
        }
    }

    /// Plans every move (the passes of the module comment) and sums the times.
    pub(crate) fn finish(self) -> Estimate {
        self.finish_timed().0
    }

    /// [`Planner::finish`], and each block's planned time when the planner
    /// was [`Planner::recording`] (empty otherwise).
    pub(crate) fn finish_timed(mut self) -> (Estimate, Timeline) {
        if self.limits.square_corner_velocity.is_some() {
            let mut ends: Vec<usize> = self.parts.iter().map(|p| p.first).collect();
            ends.push(self.blocks.len());
            let mut timeline = self.timeline.take();
            let planned = klipper_passes(&self.blocks, &self.mcr, &ends, timeline.as_mut());
            return (self.estimate(&planned), Timeline::new(timeline));
        }
        // the head ends at rest: the backward pass from 0 after the last block
        let n = self.blocks.len();
        self.backward(n, 0.0);
        self.forward(n, true);
        let mut planned = std::mem::take(&mut self.planned);
        planned.resize(self.parts.len() + 1, 0.0);
        let timeline = Timeline::new(self.timeline.take());
        (self.estimate(&planned), timeline)
    }

    /// The estimate from the planned time before the parts and of each part.
    fn estimate(&self, planned: &[f64]) -> Estimate {
        let mut est = Estimate {
            total: Times {
                planned: planned[0] + self.pre.2,
                ideal: self.pre.0,
                nominal: self.pre.1,
            },
            parts: Vec::with_capacity(self.parts.len()),
        };
        for (k, p) in self.parts.iter().enumerate() {
            let t = Times {
                planned: planned[k + 1] + p.dwell,
                ideal: p.ideal,
                nominal: p.nominal,
            };
            est.total.planned += t.planned;
            est.total.ideal += t.ideal;
            est.total.nominal += t.nominal;
            est.parts.push(PartTimes {
                name: p.name.clone(),
                times: t,
            });
        }
        est
    }
}

/// Time of one block of length `len` at acceleration `a`, entering at v0²,
/// leaving at v1², cruising at most at vc² (all reachable: |v1² − v0²| ≤ 2aL).
///
/// The highest speed the block can reach is the peak of a triangle,
/// vp² = (v0² + v1² + 2aL)/2 (from v² = v0² + 2a·x, Klipper's key look-ahead
/// formula). When vp ≤ vc it is a triangle: (vp − v0)/a + (vp − v1)/a;
/// otherwise a trapezoid: (vc − v0)/a + (vc − v1)/a plus the cruise
/// L − (2vc² − v0² − v1²)/(2a) = (vp² − vc²)/a long at vc. Differences of
/// speeds are written as differences of squares over sums, exact when close.
pub(crate) fn trapezoid_time(len: f64, a: f64, v0_2: f64, v1_2: f64, vc_2: f64) -> f64 {
    if len <= 0.0 {
        return 0.0;
    }
    let vp_2 = 0.5 * (v0_2 + v1_2 + 2.0 * a * len);
    let (v0, v1) = (v0_2.sqrt(), v1_2.sqrt());
    let ramp = |top_2: f64, top: f64| {
        (top_2 - v0_2).max(0.0) / (a * (top + v0)) + (top_2 - v1_2).max(0.0) / (a * (top + v1))
    };
    if vp_2 <= vc_2 {
        ramp(vp_2, vp_2.sqrt())
    } else {
        let vc = vc_2.sqrt();
        ramp(vc_2, vc) + (vp_2 - vc_2) / (a * vc)
    }
}

/// Where the G-code writer's moves go, in the order it writes them: a
/// [`Planner`], or a [`Call`] list that one replays later (elsewhere).
pub(crate) trait Moves {
    /// See [`Planner::begin_part`].
    fn begin_part(&mut self, name: &str);
    /// See [`Planner::stop`].
    fn stop(&mut self);
    /// See [`Planner::dwell`].
    fn dwell(&mut self, seconds: f64);
    /// See [`Planner::move_to`].
    fn move_to(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind);
    /// See [`Planner::extrude_only`].
    fn extrude_only(&mut self, length: f64, feed: f64);
    /// A setting the firmware follows from here on (accelerations, speed
    /// limits, corners): see [`Planner::setting`].
    #[inline]
    fn setting(&mut self, _s: &crate::base::gcode::Setting) {}
    /// A move of a profile's own G-code (its start or end sequence): not
    /// p3dp's, so not planned (the estimate is of p3dp's moves), but drawn
    /// by a viewer.
    #[inline]
    fn profile_move(&mut self, _to: DVec3, _e: f64, _feed: f64, _kind: MoveKind) {}
    /// A place a progress line may go, at byte `offset` of the G-code
    /// (before a move's line): only [`Marks`] keeps them.
    #[inline]
    fn place(&mut self, _offset: u64) {}
    /// The first place (before the start G-code).
    #[inline]
    fn first_place(&mut self, _offset: u64) {}
    /// The last place (before the end G-code).
    #[inline]
    fn last_place(&mut self, _offset: u64) {}
}

impl<T: Moves + ?Sized> Moves for &mut T {
    fn begin_part(&mut self, name: &str) {
        (**self).begin_part(name)
    }
    fn stop(&mut self) {
        (**self).stop()
    }
    fn dwell(&mut self, seconds: f64) {
        (**self).dwell(seconds)
    }
    fn move_to(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
        (**self).move_to(to, e, feed, kind)
    }
    fn extrude_only(&mut self, length: f64, feed: f64) {
        (**self).extrude_only(length, feed)
    }
    fn setting(&mut self, s: &crate::base::gcode::Setting) {
        (**self).setting(s)
    }
    fn profile_move(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
        (**self).profile_move(to, e, feed, kind)
    }
    fn place(&mut self, offset: u64) {
        (**self).place(offset)
    }
    fn first_place(&mut self, offset: u64) {
        (**self).first_place(offset)
    }
    fn last_place(&mut self, offset: u64) {
        (**self).last_place(offset)
    }
}

/// Two consumers of the same moves, in turn.
pub(crate) struct Both<A, B>(pub(crate) A, pub(crate) B);

impl<A: Moves, B: Moves> Moves for Both<A, B> {
    fn begin_part(&mut self, name: &str) {
        self.0.begin_part(name);
        self.1.begin_part(name);
    }
    fn stop(&mut self) {
        self.0.stop();
        self.1.stop();
    }
    fn dwell(&mut self, seconds: f64) {
        self.0.dwell(seconds);
        self.1.dwell(seconds);
    }
    fn move_to(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
        self.0.move_to(to, e, feed, kind);
        self.1.move_to(to, e, feed, kind);
    }
    fn extrude_only(&mut self, length: f64, feed: f64) {
        self.0.extrude_only(length, feed);
        self.1.extrude_only(length, feed);
    }
    fn setting(&mut self, s: &crate::base::gcode::Setting) {
        self.0.setting(s);
        self.1.setting(s);
    }
    fn profile_move(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
        self.0.profile_move(to, e, feed, kind);
        self.1.profile_move(to, e, feed, kind);
    }
    fn place(&mut self, offset: u64) {
        self.0.place(offset);
        self.1.place(offset);
    }
    fn first_place(&mut self, offset: u64) {
        self.0.first_place(offset);
        self.1.first_place(offset);
    }
    fn last_place(&mut self, offset: u64) {
        self.0.last_place(offset);
        self.1.last_place(offset);
    }
}

impl Moves for Planner {
    fn begin_part(&mut self, name: &str) {
        Planner::begin_part(self, name)
    }
    fn stop(&mut self) {
        Planner::stop(self)
    }
    fn dwell(&mut self, seconds: f64) {
        Planner::dwell(self, seconds)
    }
    fn move_to(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
        Planner::move_to(self, to, e, feed, kind)
    }
    fn extrude_only(&mut self, length: f64, feed: f64) {
        Planner::extrude_only(self, length, feed)
    }
    fn setting(&mut self, s: &crate::base::gcode::Setting) {
        Planner::setting(self, s)
    }
}

/// One call on a [`Planner`], recorded to [`Planner::replay`] later: the
/// same calls in the same order give the same estimate.
#[derive(Clone, Debug)]
pub(crate) enum Call {
    /// [`Planner::begin_part`].
    BeginPart(String),
    /// [`Planner::stop`].
    Stop,
    /// [`Planner::dwell`].
    Dwell(f64),
    /// [`Planner::move_to`].
    MoveTo(DVec3, f64, f64, MoveKind),
    /// [`Planner::extrude_only`].
    ExtrudeOnly(f64, f64),
    /// [`Planner::setting`] (boxed: settings are rare, and a call stays
    /// the size of a move).
    Setting(Box<crate::base::gcode::Setting>),
}

impl Moves for Vec<Call> {
    fn begin_part(&mut self, name: &str) {
        self.push(Call::BeginPart(name.to_string()));
    }
    fn stop(&mut self) {
        self.push(Call::Stop);
    }
    fn dwell(&mut self, seconds: f64) {
        self.push(Call::Dwell(seconds));
    }
    fn move_to(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
        self.push(Call::MoveTo(to, e, feed, kind));
    }
    fn extrude_only(&mut self, length: f64, feed: f64) {
        self.push(Call::ExtrudeOnly(length, feed));
    }
    fn setting(&mut self, s: &crate::base::gcode::Setting) {
        self.push(Call::Setting(Box::new(*s)));
    }
}

impl Planner {
    /// Replays one recorded call.
    fn call(&mut self, c: &Call) {
        match *c {
            Call::BeginPart(ref name) => self.begin_part(name),
            Call::Stop => self.stop(),
            Call::Dwell(s) => self.dwell(s),
            Call::MoveTo(to, e, feed, kind) => self.move_to(to, e, feed, kind),
            Call::ExtrudeOnly(l, feed) => self.extrude_only(l, feed),
            Call::Setting(ref s) => self.setting(s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recorded_call_is_the_size_of_a_move() {
        // the batches between the writer and the planner hold millions of
        // calls: a setting (up to 4 optional values) must not widen them
        let mv = std::mem::size_of::<(DVec3, f64, f64, MoveKind)>();
        assert!(
            std::mem::size_of::<Call>() <= mv + 8,
            "{}",
            std::mem::size_of::<Call>()
        );
    }

    pub(super) fn marlin(accel: f64, jd: f64, vmax: f64) -> Limits {
        Limits {
            max_velocity: vmax,
            max_acceleration: accel,
            travel_acceleration: accel,
            retract_acceleration: accel,
            junction_deviation: Some(jd),
            square_corner_velocity: None,
            min_segment_time: 0.0,
            minimum_cruise_ratio: 0.0,
            max_z_velocity: None,
            max_z_acceleration: None,
            instantaneous_corner_velocity: None,
            max_extrude_only_velocity: None,
            max_extrude_only_accel: None,
            min_segment_time_floor: false,
            block_buffer_size: 16,
            command_rate: 500.0,
        }
    }

    pub(super) fn klipper(accel: f64, scv: f64, vmax: f64, ratio: f64) -> Limits {
        Limits {
            junction_deviation: None,
            square_corner_velocity: Some(scv),
            minimum_cruise_ratio: ratio,
            ..marlin(accel, 0.0, vmax)
        }
    }

    fn close(got: f64, want: f64, rel: f64) {
        assert!(
            ((got - want) / want).abs() <= rel,
            "got {got}, want {want} (relative error {:e})",
            ((got - want) / want).abs()
        );
    }

    /// The closed regular n-gon of radius `r` about the origin, n + 1 points.
    fn polygon(n: usize, r: f64) -> Vec<DVec3> {
        (0..=n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                DVec3::new(r * t.cos(), r * t.sin(), 0.0)
            })
            .collect()
    }

    /// Plans a path through `points` at `feed`, all extruding.
    fn plan(limits: Limits, points: &[DVec3], feed: f64) -> Estimate {
        let mut p = Planner::new(limits);
        p.move_to(points[0], 0.0, feed, MoveKind::Extrude);
        p.begin_part("p");
        for &q in &points[1..] {
            p.move_to(q, 0.1, feed, MoveKind::Extrude);
        }
        p.finish()
    }

    /// Feeds `p` a long varied print: 40,000 moves in four parts along a
    /// wobbling helix (corners of every size, Z, feeds from 5 to 250 mm/s,
    /// travels, retractions, a dwell and a stop, zero-length moves).
    pub(super) fn long_print(p: &mut impl Moves) {
        p.move_to(DVec3::ZERO, 0.0, 100.0, MoveKind::Travel);
        for k in 0..40_000usize {
            if k % 13_000 == 0 {
                p.begin_part(&format!("part {k}"));
            }
            let t = k as f64 * 0.05;
            let r = 20.0 + 3.0 * (7.0 * t).sin() + (k % 7) as f64 * 0.01;
            let to = DVec3::new(r * t.cos(), r * t.sin(), 0.2 + 0.0005 * k as f64);
            let feed = 5.0 + (k % 50) as f64 * 5.0;
            match k % 997 {
                0 => {
                    p.extrude_only(0.8, 35.0);
                    p.move_to(to, 0.0, 150.0, MoveKind::Travel);
                    p.extrude_only(0.8, 35.0);
                }
                1 => p.move_to(to, 0.0, feed, MoveKind::Extrude), // then again: no motion
                500 => p.dwell(0.5),
                600 => p.stop(),
                _ => p.move_to(to, 0.02, feed, MoveKind::Extrude),
            }
            if k % 997 == 1 {
                p.move_to(to, 0.0, feed, MoveKind::Extrude);
            }
        }
    }

    #[test]
    fn planning_settled_blocks_early_changes_nothing() {
        // Marlin's passes run as the moves come over the blocks that the
        // rest can no longer change, and forget them: the estimate is the
        // one of both passes over the whole print at the end, bit for bit
        for lim in [
            marlin(1000.0, 0.013, 300.0),
            Limits {
                min_segment_time: 0.02,
                max_z_velocity: Some(5.0),
                max_z_acceleration: Some(100.0),
                ..marlin(500.0, 0.05, 200.0)
            },
        ] {
            let mut early = Planner::new(lim.clone());
            long_print(&mut early);
            assert!(early.done > 30_000, "{} blocks settled", early.done);
            assert!(early.blocks.len() < 2 * SETTLE);
            let mut whole = Planner::new(lim);
            whole.next_settle = usize::MAX;
            long_print(&mut whole);
            assert_eq!(whole.done, 0);
            let (a, b) = (early.finish(), whole.finish());
            assert_eq!(a.parts.len(), 4);
            assert!(a.total.planned > a.total.nominal, "{a:?}");
            assert_eq!(a.total.planned.to_bits(), b.total.planned.to_bits());
            for (x, y) in a.parts.iter().zip(&b.parts) {
                assert_eq!(x.times.planned.to_bits(), y.times.planned.to_bits());
            }
            assert_eq!(a, b);
        }
    }

    #[test]
    fn one_long_move_is_a_trapezoid() {
        // 100 mm at 50 mm/s, a = 500: from rest to rest t = L/v + v/a
        let e = plan(
            marlin(500.0, 0.013, 300.0),
            &[DVec3::ZERO, DVec3::new(100.0, 0.0, 0.0)],
            50.0,
        );
        close(e.total.planned, 100.0 / 50.0 + 50.0 / 500.0, 1e-12);
        close(e.total.ideal, 2.0, 1e-12);
        close(e.total.lost_to_acceleration(), 0.1, 1e-9);
        assert_eq!(e.parts.len(), 1);
        assert_eq!(e.parts[0].times, e.total);
    }

    #[test]
    fn one_short_move_is_a_triangle() {
        // 2 mm at 100 mm/s, a = 1000: v² = aL = 2000 < 100², so t = 2·sqrt(L/a)
        let e = plan(
            marlin(1000.0, 0.013, 300.0),
            &[DVec3::ZERO, DVec3::new(0.0, 2.0, 0.0)],
            100.0,
        );
        close(e.total.planned, 2.0 * (2.0f64 / 1000.0).sqrt(), 1e-12);
        // a 3D move: the length includes Z
        let e = plan(
            marlin(1000.0, 0.013, 300.0),
            &[DVec3::ZERO, DVec3::new(1.0, 1.0, 1.0)],
            100.0,
        );
        close(e.total.planned, 2.0 * (3f64.sqrt() / 1000.0).sqrt(), 1e-12);
    }

    #[test]
    fn max_velocity_caps_the_feed() {
        let e = plan(
            marlin(1000.0, 0.013, 40.0),
            &[DVec3::ZERO, DVec3::new(100.0, 0.0, 0.0)],
            100.0,
        );
        close(e.total.planned, 100.0 / 40.0 + 40.0 / 1000.0, 1e-12);
        close(e.total.ideal, 1.0, 1e-12);
        close(e.total.nominal, 2.5, 1e-12);
    }

    /// Time from rest to rest through `n` equal segments of length `l` whose
    /// every inner corner allows `vj`, cruising at `v` where they can, by
    /// hand: the speed at corner i is what the junction, the acceleration
    /// from the start (v² = 2a·i·l) and the deceleration to the end
    /// (v² = 2a·(n − i)·l) allow, and each segment is a triangle or a
    /// trapezoid between its corner speeds.
    fn by_hand(n: usize, l: f64, a: f64, v: f64, vj: f64) -> f64 {
        let corner = |i: usize| {
            if i == 0 || i == n {
                0.0
            } else {
                (vj * vj)
                    .min(2.0 * a * i as f64 * l)
                    .min(2.0 * a * (n - i) as f64 * l)
                    .sqrt()
            }
        };
        let seg = |v0: f64, v1: f64| {
            let vp2 = (v0 * v0 + v1 * v1 + 2.0 * a * l) / 2.0;
            if vp2 <= v * v {
                let vp = vp2.sqrt();
                (vp - v0) / a + (vp - v1) / a
            } else {
                let d = (2.0 * v * v - v0 * v0 - v1 * v1) / (2.0 * a);
                (v - v0) / a + (v - v1) / a + (l - d) / v
            }
        };
        (0..n).map(|i| seg(corner(i), corner(i + 1))).sum()
    }

    #[test]
    fn square_with_junction_deviation() {
        // a 20 mm square at 60 mm/s, a = 1000, δ = 0.05: a 90° corner has
        // sin(θ/2) = √½, so v² = a·δ·√½/(1 − √½) = 50·(1 + √2) ≈ 120.7, v ≈ 11 mm/s
        let a = 1000.0;
        let vj = (a * 0.05 * (0.5f64.sqrt() / (1.0 - 0.5f64.sqrt()))).sqrt();
        close(vj, (50.0 * (1.0 + 2f64.sqrt())).sqrt(), 1e-12);
        let pts = [
            DVec3::ZERO,
            DVec3::new(20.0, 0.0, 0.0),
            DVec3::new(20.0, 20.0, 0.0),
            DVec3::new(0.0, 20.0, 0.0),
            DVec3::ZERO,
        ];
        let e = plan(marlin(a, 0.05, 300.0), &pts, 60.0);
        close(e.total.planned, by_hand(4, 20.0, a, 60.0, vj), 1e-12);
        // hand arithmetic, written out: ends 0→60→vj, inner vj→60→vj
        let ramp = |v0: f64| (60.0 - v0) / a;
        let dist = |v0: f64| (3600.0 - v0 * v0) / (2.0 * a);
        let end = ramp(0.0) + ramp(vj) + (20.0 - dist(0.0) - dist(vj)) / 60.0;
        let inner = 2.0 * ramp(vj) + (20.0 - 2.0 * dist(vj)) / 60.0;
        close(e.total.planned, 2.0 * end + 2.0 * inner, 1e-12);
    }

    #[test]
    fn square_with_square_corner_velocity() {
        // Klipper: a 90° corner is taken at exactly scv = 5 mm/s (no smoothing)
        let pts = [
            DVec3::ZERO,
            DVec3::new(30.0, 0.0, 0.0),
            DVec3::new(30.0, 30.0, 0.0),
            DVec3::new(0.0, 30.0, 0.0),
            DVec3::ZERO,
        ];
        let e = plan(klipper(3000.0, 5.0, 300.0, 0.0), &pts, 150.0);
        close(e.total.planned, by_hand(4, 30.0, 3000.0, 150.0, 5.0), 1e-12);
    }

    #[test]
    fn circle_where_the_junction_speed_limits() {
        // a 60-gon of radius 10 at 100 mm/s, a = 500, δ = 0.01: each string is
        // L = 2·10·sin(π/60) ≈ 1.047 mm (> 1 mm: no small-segment rule), the
        // turn φ = 6°, θ = 174°: v_j² = a·δ·sin 87°/(1 − sin 87°) ≈ 60.4²,
        // below 100 and below what a string can reach between two corners
        // (v² = v_j² + a·L ≈ 64.6²), so it limits every corner
        let n = 60;
        let r = 10.0;
        let pts = polygon(n, r);
        let l = 2.0 * r * (std::f64::consts::PI / n as f64).sin();
        let s = (87.0f64).to_radians().sin();
        let vj = (500.0 * 0.01 * s / (1.0 - s)).sqrt();
        assert!(l > 1.0 && vj < 100.0);
        let e = plan(marlin(500.0, 0.01, 300.0), &pts, 100.0);
        let want = by_hand(n, l, 500.0, 100.0, vj);
        close(e.total.planned, want, 1e-9);
        // and it is well over distance / speed (about 100/64 of it)
        assert!(e.total.planned > 1.4 * e.total.ideal);
    }

    #[test]
    fn circle_of_short_strings_uses_the_curvature_limit() {
        // 360 strings of radius 20: L ≈ 0.349 mm < 1 mm and φ = 1°, so Marlin's
        // small-segment rule v² ≤ a·L/φ = a·R·(2 sin(φ/2)/φ) ≈ a·R limits,
        // not δ; at a = 500, v ≈ 100 mm/s, below the 150 asked for
        let n = 360;
        let r = 20.0;
        let pts = polygon(n, r);
        let l = 2.0 * r * (std::f64::consts::PI / n as f64).sin();
        let phi = std::f64::consts::TAU / n as f64;
        let vj = (500.0 * l / phi).sqrt();
        let e = plan(marlin(500.0, 0.013, 300.0), &pts, 150.0);
        close(e.total.planned, by_hand(n, l, 500.0, 150.0, vj), 1e-9);
        // Klipper's centripetal limit from the move length: ½·L·a·tan(θ/2)
        let tan_half = (std::f64::consts::FRAC_PI_2 - phi / 2.0).tan();
        let vk = (0.5 * l * 500.0 * tan_half).sqrt();
        close(vk, vj, 1e-3); // the same circle, nearly the same speed
        let e = plan(klipper(500.0, 50.0, 300.0, 0.0), &pts, 150.0);
        close(e.total.planned, by_hand(n, l, 500.0, 150.0, vk), 1e-9);
    }

    #[test]
    fn min_segment_time_floor_caps_short_moves() {
        // 100 moves of 0.2 mm in a line at 40 mm/s take 5 ms each; Marlin's
        // 20 ms minimum slows them to 10 mm/s: no corners, so one trapezoid
        let pts: Vec<DVec3> = (0..=100)
            .map(|k| DVec3::new(0.2 * k as f64, 0.0, 0.0))
            .collect();
        let lim = Limits {
            min_segment_time: 0.02,
            min_segment_time_floor: true,
            ..marlin(1000.0, 0.013, 300.0)
        };
        let e = plan(lim, &pts, 40.0);
        close(e.total.planned, 20.0 / 10.0 + 10.0 / 1000.0, 1e-9);
        close(e.total.ideal, 0.5, 1e-12);
        close(e.total.nominal, 2.0, 1e-12);
    }

    /// `n` collinear moves of `l` mm along x, all at `feed`, extruding.
    fn line(n: usize, l: f64) -> Vec<DVec3> {
        (0..=n)
            .map(|k| DVec3::new(l * k as f64, 0.0, 0.0))
            .collect()
    }

    #[test]
    fn marlin_slowdown_only_while_the_buffer_drains() {
        // 30 moves of 0.2 mm at 40 mm/s (5 ms each), min segment time 20 ms
        let mst = 0.02;
        let t = 0.005;
        let base = Limits {
            min_segment_time: mst,
            ..marlin(1000.0, 0.013, 300.0)
        };
        // a reader far quicker than the moves: the buffer fills at once, so
        // block k sees k blocks queued; planner.cpp slows blocks with 2..=7
        // queued (BLOCK_BUFFER_SIZE 16) by 2·(mst − t)/k, none after
        let fast = Limits {
            command_rate: f64::INFINITY,
            ..base.clone()
        };
        let e = plan(fast, &line(30, 0.2), 40.0);
        let extra: f64 = (2..=7).map(|k| 2.0 * (mst - t) / k as f64).sum();
        close(e.total.nominal, 30.0 * t + extra, 1e-12);
        close(e.total.ideal, 30.0 * t, 1e-12);
        // a reader slower than the moves (10 ms a line): each block finds the
        // buffer empty, so nothing is slowed
        let slow = Limits {
            command_rate: 100.0,
            ..base.clone()
        };
        let e = plan(slow, &line(30, 0.2), 40.0);
        close(e.total.nominal, 30.0 * t, 1e-12);
        // moves longer than the minimum are never slowed
        let e = plan(
            Limits {
                command_rate: f64::INFINITY,
                ..base
            },
            &line(30, 1.0),
            40.0,
        );
        close(e.total.nominal, 30.0 * 0.025, 1e-12);
    }

    /// Time of a block of `l` mm at `a` from v0 to v1 cruising at `vc`, by
    /// hand (a trapezoid that reaches vc).
    fn trapezoid(l: f64, a: f64, v0: f64, v1: f64, vc: f64) -> f64 {
        let ramps = (vc - v0) / a + (vc - v1) / a;
        let ramp_len = (2.0 * vc * vc - v0 * v0 - v1 * v1) / (2.0 * a);
        assert!(ramp_len <= l);
        ramps + (l - ramp_len) / vc
    }

    #[test]
    fn klipper_instantaneous_corner_velocity_at_g1_g0_changes() {
        // a straight line of 10 mm moves alternating G1 (0.33 mm of filament:
        // r = 0.033 mm/mm) and G0 at 100 mm/s, a = 1000: Klipper's extruder
        // junction holds each change of r to v = icv / |Δr| = 1/0.033
        let lim = Limits {
            instantaneous_corner_velocity: Some(1.0),
            ..klipper(1000.0, 5.0, 300.0, 0.0)
        };
        let mut p = Planner::new(lim.clone());
        p.move_to(DVec3::ZERO, 0.0, 100.0, MoveKind::Travel);
        p.begin_part("p");
        let n = 6;
        for k in 1..=n {
            let to = DVec3::new(10.0 * k as f64, 0.0, 0.0);
            if k % 2 == 1 {
                p.move_to(to, 0.33, 100.0, MoveKind::Extrude);
            } else {
                p.move_to(to, 0.0, 100.0, MoveKind::Travel);
            }
        }
        let e = p.finish();
        let vj = 1.0 / 0.033;
        let want = trapezoid(10.0, 1000.0, 0.0, vj, 100.0)
            + (n - 2) as f64 * trapezoid(10.0, 1000.0, vj, vj, 100.0)
            + trapezoid(10.0, 1000.0, vj, 0.0, 100.0);
        close(e.total.planned, want, 1e-12);
        // without it the line is one trapezoid
        let plain = Limits {
            instantaneous_corner_velocity: None,
            ..lim
        };
        let e = plan(plain, &line(6, 10.0), 100.0);
        close(e.total.planned, 60.0 / 100.0 + 100.0 / 1000.0, 1e-12);
    }

    #[test]
    fn z_moves_keep_to_the_z_axis_limits() {
        let lim = Limits {
            max_z_velocity: Some(5.0),
            max_z_acceleration: Some(100.0),
            ..marlin(1000.0, 0.013, 300.0)
        };
        // a 2 mm hop asked at 120 mm/s runs at 5 mm/s, accelerating at 100
        let mut p = Planner::new(lim.clone());
        p.move_to(DVec3::ZERO, 0.0, 120.0, MoveKind::Travel);
        p.move_to(DVec3::new(0.0, 0.0, 2.0), 0.0, 120.0, MoveKind::Travel);
        close(p.finish().total.planned, 2.0 / 5.0 + 5.0 / 100.0, 1e-12);
        // a slanted move: the limits scale by L/|dz|
        let mut p = Planner::new(lim);
        p.move_to(DVec3::ZERO, 0.0, 120.0, MoveKind::Travel);
        p.move_to(DVec3::new(10.0, 0.0, 2.0), 0.0, 120.0, MoveKind::Travel);
        let l = 104f64.sqrt();
        let (v, a) = (5.0 * l / 2.0, 100.0 * l / 2.0);
        assert!(v * v < a * l);
        close(p.finish().total.planned, l / v + v / a, 1e-12);
    }

    #[test]
    fn klipper_extrude_only_limits() {
        // a 0.8 mm retraction at 35 mm/s with max_extrude_only_velocity 10
        // and max_extrude_only_accel 500: a trapezoid at 10 mm/s, a = 500
        let lim = Limits {
            max_extrude_only_velocity: Some(10.0),
            max_extrude_only_accel: Some(500.0),
            ..klipper(3000.0, 5.0, 300.0, 0.5)
        };
        let mut p = Planner::new(lim);
        p.extrude_only(0.8, 35.0);
        close(p.finish().total.planned, 0.8 / 10.0 + 10.0 / 500.0, 1e-12);
        // Klipper's defaults: 4·nozzle² over the filament's area, ≈ 0.266
        let r = crate::machine::kinematics::extrude_ratio(0.4, 1.75);
        close(r, 0.64 / (std::f64::consts::PI * 0.875 * 0.875), 1e-12);
        let k = Kinematics {
            square_corner_velocity: Some(5.0),
            max_acceleration: 3000.0,
            ..Kinematics::default()
        };
        let l = k.limits(300.0, r);
        close(l.max_extrude_only_accel.unwrap(), 3000.0 * r, 1e-12);
        close(l.max_extrude_only_velocity.unwrap(), 300.0 * r, 1e-12);
        assert_eq!(l.instantaneous_corner_velocity, Some(1.0));
        let m = Kinematics::default().limits(200.0, r);
        assert_eq!(m.instantaneous_corner_velocity, None);
        assert_eq!(m.max_extrude_only_accel, None);
    }

    #[test]
    fn minimum_cruise_ratio_slows_short_moves() {
        // Klipper's example: a standalone 1.5 mm move with ratio 0.5 cruises
        // at least 0.75 mm: peak v² = L·a·(1 − ratio) = 1.5·1000·0.5 = 750
        let e = plan(
            klipper(1000.0, 5.0, 300.0, 0.5),
            &[DVec3::ZERO, DVec3::new(1.5, 0.0, 0.0)],
            100.0,
        );
        let v = 750f64.sqrt();
        let accel_dist = 750.0 / 2000.0;
        close(1.5 - 2.0 * accel_dist, 0.75, 1e-12);
        close(e.total.planned, 2.0 * v / 1000.0 + 0.75 / v, 1e-12);
    }

    #[test]
    fn minimum_cruise_ratio_holds_for_a_run_of_moves() {
        // Klipper plans a run of moves as if it accelerated at a·(1 − ratio)
        // (the "pseudo" acceleration of its minimum-cruise-ratio check):
        // from rest to rest along D mm that profile peaks at v_p² = a·(1 − ratio)·D;
        // the head reaches v_p at a in (1 − ratio)·D/2, brakes in as much and
        // cruises ratio·D: t = 2·v_p/a + ratio·D/v_p, however D is cut into moves
        for (k, ratio) in [(1usize, 0.5), (5, 0.5), (5, 0.2), (40, 0.5), (7, 0.8)] {
            let (a, d): (f64, f64) = (1000.0, 5.0);
            let vp = (a * (1.0 - ratio) * d).sqrt();
            let want = 2.0 * vp / a + ratio * d / vp;
            let e = plan(
                klipper(a, 5.0, 1000.0, ratio),
                &line(k, d / k as f64),
                1000.0,
            );
            close(e.total.planned, want, 1e-12);
        }
        // where the feed caps the peak the ratio does not matter
        let e = plan(klipper(1000.0, 5.0, 1000.0, 0.5), &line(5, 1.0), 20.0);
        close(e.total.planned, 5.0 / 20.0 + 20.0 / 1000.0, 1e-12);
    }

    #[test]
    fn minimum_cruise_ratio_spares_moves_that_only_slow_down() {
        // 100 mm then 0.5 mm straight on, a = 1000, ratio 0.5: the short last
        // move only decelerates (to rest), as in Klipper it keeps its full
        // entry v² = 2·a·L = 1000, not the smoothed 2·a_d·L = 500
        let e = plan(
            klipper(1000.0, 5.0, 300.0, 0.5),
            &[
                DVec3::ZERO,
                DVec3::new(100.0, 0.0, 0.0),
                DVec3::new(100.5, 0.0, 0.0),
            ],
            100.0,
        );
        let v1 = 1000f64.sqrt();
        let first = 100.0 / 1000.0
            + (100.0 - v1) / 1000.0
            + (100.0 - 5.0 - (10000.0 - 1000.0) / 2000.0) / 100.0;
        close(e.total.planned, first + v1 / 1000.0, 1e-12);
    }

    #[test]
    fn retractions_are_e_only_moves_from_rest() {
        let mut p = Planner::new(marlin(1000.0, 0.013, 300.0));
        p.move_to(DVec3::ZERO, 0.0, 100.0, MoveKind::Travel);
        p.begin_part("a");
        p.move_to(DVec3::new(100.0, 0.0, 0.0), 1.0, 100.0, MoveKind::Extrude);
        p.extrude_only(0.8, 40.0); // retract
        p.move_to(DVec3::new(100.0, 100.0, 0.0), 0.0, 100.0, MoveKind::Travel);
        p.begin_part("b");
        p.extrude_only(0.8, 40.0); // unretract
        p.move_to(DVec3::new(0.0, 100.0, 0.0), 1.0, 100.0, MoveKind::Extrude);
        // E of 0 with no motion is skipped
        p.move_to(DVec3::new(0.0, 100.0, 0.0), 0.0, 100.0, MoveKind::Extrude);
        let e = p.finish();
        let long = 1.0 + 0.1;
        let retract = 2.0 * (0.8f64 / 1000.0).sqrt(); // triangle: 40² > a·L
        close(e.parts[0].times.planned, long + retract + long, 1e-12);
        close(e.parts[1].times.planned, retract + long, 1e-12);
        close(e.total.planned, 3.0 * long + 2.0 * retract, 1e-12);
        close(e.total.ideal, 3.0 + 2.0 * 0.8 / 40.0, 1e-12);
    }

    #[test]
    fn reversal_stops_and_straight_does_not() {
        let lim = marlin(1000.0, 0.013, 300.0);
        let line = [
            DVec3::ZERO,
            DVec3::new(50.0, 0.0, 0.0),
            DVec3::new(100.0, 0.0, 0.0),
        ];
        close(
            plan(lim.clone(), &line, 50.0).total.planned,
            2.0 + 0.05,
            1e-12,
        );
        let back = [DVec3::ZERO, DVec3::new(50.0, 0.0, 0.0), DVec3::ZERO];
        close(
            plan(lim, &back, 50.0).total.planned,
            2.0 * (1.0 + 0.05),
            1e-12,
        );
    }

    #[test]
    fn defaults_follow_the_junction_model() {
        let k = Kinematics::default();
        k.validate().unwrap();
        let l = k.limits(200.0, 0.266);
        assert_eq!(l.max_velocity, 200.0);
        assert_eq!(l.junction_deviation, Some(0.013));
        assert_eq!(l.min_segment_time, 0.02);
        assert_eq!(l.minimum_cruise_ratio, 0.0);
        let k = Kinematics {
            square_corner_velocity: Some(5.0),
            max_acceleration: 3000.0,
            ..Kinematics::default()
        };
        let l = k.limits(300.0, 0.266);
        assert_eq!(l.junction_deviation, None);
        assert_eq!(l.min_segment_time, 0.0);
        assert_eq!(l.minimum_cruise_ratio, 0.5);
        assert_eq!(l.travel_acceleration, 3000.0);
        let json = serde_json::to_value(&l).unwrap();
        assert!(json.get("junction_deviation").is_none());
        assert_eq!(json["square_corner_velocity"], 5.0);
        let both = Kinematics {
            junction_deviation: Some(0.02),
            ..k.clone()
        };
        assert!(both
            .validate()
            .unwrap_err()
            .to_string()
            .contains("give one of"));
        let bad = Kinematics {
            max_acceleration: -1.0,
            ..Kinematics::default()
        };
        let e = bad.validate().unwrap_err().to_string();
        assert!(e.contains("kinematics.max_acceleration"), "{e}");
        let bad = Kinematics {
            minimum_cruise_ratio: Some(1.0),
            ..Kinematics::default()
        };
        assert!(bad.validate().is_err());
    }

    #[test]
    fn dwell_and_stop() {
        let mut p = Planner::new(marlin(1000.0, 0.013, 300.0));
        p.move_to(DVec3::ZERO, 0.0, 50.0, MoveKind::Travel);
        p.begin_part("a");
        p.move_to(DVec3::new(50.0, 0.0, 0.0), 0.0, 50.0, MoveKind::Travel);
        p.dwell(2.0);
        p.move_to(DVec3::new(100.0, 0.0, 0.0), 0.0, 50.0, MoveKind::Travel);
        let e = p.finish();
        close(e.total.planned, 2.0 * (1.0 + 0.05) + 2.0, 1e-12);
        close(e.total.ideal, 4.0, 1e-12);
    }
}
