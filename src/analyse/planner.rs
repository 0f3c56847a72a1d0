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

use glam::DVec3;

use crate::base::threads::Threads;

pub use crate::machine::kinematics::{
    Kinematics, Limits, KLIPPER_MINIMUM_CRUISE_RATIO, MARLIN_JUNCTION_DEVIATION,
    MARLIN_MIN_SEGMENT_TIME,
};

/// What a move is, which chooses its acceleration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MoveKind {
    /// An extruding move (G1 with E): `max_acceleration`.
    Extrude,
    /// A travel move (G0): `travel_acceleration`.
    Travel,
}

/// Times of a print or of one part, s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Times {
    /// Planned: with acceleration, junction speeds and speed limits.
    pub planned: f64,
    /// Σ L / F: the time the G-code asks for, as if every move ran at its F.
    pub ideal: f64,
    /// Σ L / v_nom: F capped by `max_velocity` and `min_segment_time`, no acceleration.
    pub nominal: f64,
}

impl Times {
    /// Time lost to acceleration, deceleration and corners: planned − nominal.
    pub fn lost_to_acceleration(&self) -> f64 {
        self.planned - self.nominal
    }

    /// Time lost to the speed limits: nominal − ideal.
    pub fn lost_to_speed_limits(&self) -> f64 {
        self.nominal - self.ideal
    }

    /// All time lost against the G-code's speeds: planned − ideal.
    pub fn lost(&self) -> f64 {
        self.planned - self.ideal
    }
}

/// One part's times.
#[derive(Clone, Debug, PartialEq)]
pub struct PartTimes {
    /// Part name.
    pub name: String,
    /// Its times, s.
    pub times: Times,
}

/// The planner's answer: the whole print's times, and each part's.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    /// All moves.
    pub total: Times,
    /// Each part begun with [`Planner::begin_part`], in order.
    pub parts: Vec<PartTimes>,
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

/// A block's minimum-cruise-ratio profile, kept beside it under Klipper's
/// model only (Marlin's has none: 16 bytes a move saved).
#[derive(Clone, Copy, Debug)]
struct Mcr {
    /// The highest entry v² in the minimum-cruise-ratio profile.
    entry_v2: f64,
    /// The v² this block can gain in that profile, 2·L·a_mcr.
    delta_v2: f64,
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

/// The shape of the corner between two moves of unit directions `a` and
/// `b`, which depends on nothing else (see [`Planner::junction_v2`]).
#[derive(Clone, Copy, Debug, Default)]
struct Turn {
    /// |a − b|² = 4·cos²(θ/2), at most 4: 0 straight on.
    w: f64,
    /// cos²(θ/2).
    cos_half2: f64,
    /// sin(θ/2): 0 a full reversal.
    sin_half: f64,
    /// The junction circle's radius over δ: sin/(1 − sin) of θ/2.
    r: f64,
    /// cos(θ/2).
    x: f64,
}

impl Turn {
    /// The corner from direction `a` into direction `b`.
    fn new(a: DVec3, b: DVec3) -> Turn {
        // w = |u1 − u2|² = 2·(1 − cos φ) = 4·cos²(θ/2): stable for small turns
        let w = (a - b).length_squared().min(4.0);
        let mut t = Turn {
            w,
            ..Turn::default()
        };
        if w <= 0.0 {
            return t; // straight on
        }
        t.cos_half2 = 0.25 * w; // cos²(θ/2)
        t.sin_half = (1.0 - t.cos_half2).max(0.0).sqrt(); // sin(θ/2)
        if t.sin_half <= 0.0 {
            return t; // a full reversal
        }
        // sin/(1 − sin) = sin·(1 + sin)/cos², exact where sin is near 1
        t.r = t.sin_half * (1.0 + t.sin_half) / t.cos_half2;
        t.x = t.cos_half2.sqrt();
        t
    }
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

/// Calls replayed at a time in [`Planner::replay_batch`]: their [`Step`]s
/// stay in the fastest cache.
const STEPS: usize = 256;

/// Marlin's block buffer as the SD reader fills it and the steppers empty it
/// (see [`Planner::slowdown`]): times in s from the first move.
#[derive(Clone, Debug, Default)]
struct Queue {
    /// When the reader has the next line ready.
    read: f64,
    /// When the last queued block finishes.
    busy_until: f64,
    /// End times of the blocks in the buffer, oldest first.
    ends: std::collections::VecDeque<f64>,
}

struct Part {
    name: String,
    first: usize,
    ideal: f64,
    nominal: f64,
    dwell: f64,
}

/// Collects the moves of a print and plans them (see the module comment).
pub struct Planner {
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
    /// The steps of the calls being replayed (see [`Planner::replay_batch`]).
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
}

/// Blocks queued between two looks for settled blocks (see
/// [`Planner::plan_settled`]): 256 KB of them.
const SETTLE: usize = 8192;

impl Planner {
    /// A planner with these limits, the head at an unknown place.
    pub fn new(limits: Limits) -> Planner {
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
            limits,
        }
    }

    /// The limits in use.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Moves from now on belong to part `name` (parts are consecutive).
    pub fn begin_part(&mut self, name: &str) {
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
    pub fn stop(&mut self) {
        self.last = None;
        self.drain(0.0);
    }

    /// The buffer empties (the firmware waits for its moves, then `seconds`
    /// more) before the reader goes on.
    fn drain(&mut self, seconds: f64) {
        let q = &mut self.queue;
        q.read = q.read.max(q.busy_until) + seconds;
        q.busy_until = q.read;
        q.ends.clear();
    }

    /// The head stands still for `seconds` (e.g. `G4`): counted in every time.
    pub fn dwell(&mut self, seconds: f64) {
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

    /// Marlin's minimum segment time, as `planner.cpp` (`_populate_block`,
    /// `#if ENABLED(SLOWDOWN)`) applies it: only while the buffer is draining,
    /// with `moves_queued` blocks in it and `2 ≤ moves_queued ≤
    /// BLOCK_BUFFER_SIZE/2 − 1`, a move of nominal time t < min_segment_time
    /// gets `t + 2·(min_segment_time − t)/moves_queued`; a full buffer (the
    /// reader keeping ahead) or an empty one slows nothing. The buffer is
    /// modelled as filled by a reader that makes a line ready every
    /// 1/`command_rate` s (when there is room: BLOCK_BUFFER_SIZE − 1 blocks)
    /// and emptied by the steppers at each block's nominal time (its
    /// acceleration is left out). With `min_segment_time_floor` every move
    /// lasts at least `min_segment_time` instead. Returns the speed.
    fn slowdown(&mut self, len: f64, v: f64) -> f64 {
        let lim = &self.limits;
        let m = lim.min_segment_time;
        if m <= 0.0 {
            return v;
        }
        if lim.min_segment_time_floor {
            return v.min(len / m);
        }
        let size = lim.block_buffer_size as usize;
        let q = &mut self.queue;
        let mut ready = q.read + self.line_time;
        while q.ends.front().is_some_and(|&e| e <= ready) {
            q.ends.pop_front();
        }
        if q.ends.len() + 1 >= size {
            // full: the reader waits for the oldest block to finish
            ready = ready.max(q.ends.pop_front().unwrap_or(ready));
            while q.ends.front().is_some_and(|&e| e <= ready) {
                q.ends.pop_front();
            }
        }
        let queued = q.ends.len();
        let mut t = len / v;
        if (2..size / 2).contains(&queued) && t < m {
            t += 2.0 * (m - t) / queued as f64;
        }
        q.read = ready;
        q.busy_until = q.busy_until.max(ready) + t;
        q.ends.push_back(q.busy_until);
        if t > 0.0 {
            len / t
        } else {
            v
        }
    }

    /// A move to `to` (machine coordinates, mm) at `feed` mm/s, feeding `e` mm
    /// of filament. The first move, from an unknown place, only sets the
    /// position; a move of E alone (`to` where the head is, `e` > 0) is an
    /// E-only block at `feed` with `retract_acceleration`, from rest to rest;
    /// a move of nothing is skipped.
    pub fn move_to(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
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
    fn replay_batch(&mut self, calls: &[Call]) {
        let mut steps = std::mem::take(&mut self.steps);
        for run in calls.chunks(STEPS) {
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
                    _ => replay(self, c),
                }
            }
        }
        self.steps = steps;
    }

    /// A move of E alone (retraction, unretraction), `length` mm of filament
    /// at `feed` mm/s: from rest to rest, as Klipper plans extrude-only moves.
    pub fn extrude_only(&mut self, length: f64, feed: f64) {
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

    /// Klipper's look-ahead at the time a block is queued (its
    /// `Move.calc_junction`): the block's highest entry v² `entry_v2` is also
    /// held to what the block before can reach, e_prev + 2·a_prev·L_prev (a
    /// forward pass as the moves come), and the same is done in the
    /// minimum-cruise-ratio profile, where every block gains at most
    /// 2·L·min(a_nom·(1 − ratio), a) of v² (`a_nom` the kind's acceleration,
    /// Klipper's `max_accel`; `a` the block's own, lower where the Z axis or
    /// the extruder limits it). Returns that profile's (entry v², gain); with
    /// no previous XYZ block the head is at rest. Marlin's model keeps the
    /// junction limit alone: (0, 0).
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

    fn klipper_entry(&self, entry_v2: &mut f64, base: f64, accel: f64, len: f64) -> (f64, f64) {
        if self.limits.square_corner_velocity.is_none() {
            return (0.0, 0.0);
        }
        let mcr_delta_v2 = 2.0 * len * (base * (1.0 - self.limits.minimum_cruise_ratio)).min(accel);
        let (prev, prev_mcr) = match (self.last, self.blocks.last(), self.mcr.last()) {
            (Some(_), Some(b), Some(m)) => (b, m),
            _ => {
                *entry_v2 = 0.0;
                return (0.0, mcr_delta_v2);
            }
        };
        *entry_v2 = entry_v2.min(prev.entry_v2 + 2.0 * prev.accel * prev.len);
        let mcr_entry_v2 = entry_v2.min(prev_mcr.entry_v2 + prev_mcr.delta_v2);
        (mcr_entry_v2, mcr_delta_v2)
    }

    /// Highest v² at the corner from `prev` into a block along `dir` of length
    /// `len`, acceleration `accel` (`accel_share` of its kind's) and cruise
    /// v² `cruise_v2` (never above either block's cruise v²).
    ///
    /// With θ the angle between the reversed incoming direction and the
    /// outgoing one (θ = 180° straight on, 90° a square corner, 0 a reversal),
    /// both firmwares use the "approximated centripetal acceleration" of
    /// Grbl (Marlin's junction deviation; Klipper's Kinematics document): a
    /// circle tangent to both moves whose closest approach to the corner is δ
    /// has radius R = δ·sin(θ/2) / (1 − sin(θ/2)), and the speed on it at
    /// acceleration a is v² = a·R.
    ///
    /// - Marlin: δ = `junction_deviation`, a the outgoing block's
    ///   acceleration. With `JD_HANDLE_SMALL_SEGMENTS` (on in Marlin's default
    ///   configuration) a block shorter than 1 mm turning by less than 45° is
    ///   taken as a chord of an arc of radius L / φ (φ = π − θ the turn), so
    ///   also v² ≤ a·L / φ. (Marlin approximates φ by a polynomial that never
    ///   goes below 0.033 rad; here φ is exact.)
    /// - Klipper: δ = scv²·(√2 − 1) / a_nom with a_nom its `max_accel`, and
    ///   v² = R·δ·a for each of the two moves' own a, so a 90° corner gets
    ///   exactly scv (less where the Z axis lowers a move's a); and the
    ///   circle must touch each move no further than its middle:
    ///   v² ≤ ½·L·a·tan(θ/2) for both moves.
    fn junction_v2(
        &self,
        prev: &Last,
        t: &Turn,
        len: f64,
        accel: f64,
        accel_share: f64,
        cruise_v2: f64,
    ) -> f64 {
        let both = cruise_v2.min(prev.cruise_v2);
        if t.w <= 0.0 {
            return both; // straight on
        }
        if t.sin_half <= 0.0 {
            return 0.0; // a full reversal stops the head
        }
        let (cos_half2, sin_half, r) = (t.cos_half2, t.sin_half, t.r);
        match (
            self.limits.square_corner_velocity,
            self.limits.junction_deviation,
        ) {
            (Some(scv), _) => {
                let share = accel_share.min(prev.accel_share);
                let jd_v2 = r * scv * scv * (std::f64::consts::SQRT_2 - 1.0) * share;
                let tan_half = sin_half / t.x; // t.x = √cos²(θ/2)
                let c_this = 0.5 * len * accel * tan_half;
                let c_prev = 0.5 * prev.len * prev.accel * tan_half;
                jd_v2.min(c_this).min(c_prev).min(both)
            }
            (None, Some(delta)) => {
                let mut v2 = r * accel * delta;
                // turn φ = π − θ = 2·asin(cos(θ/2)); φ < 45° ⇔ θ > 135°
                // ⇔ cos²(θ/2) < sin²(22.5°) = (1 − √½)/2
                const SMALL_TURN: f64 = 0.5 * (1.0 - std::f64::consts::FRAC_1_SQRT_2);
                let cap = v2.min(both);
                // 2x ≤ 2·asin x ≤ π·x: skip the asin when even the largest φ
                // leaves a limit above the others
                let x = t.x;
                if len < 1.0
                    && cos_half2 < SMALL_TURN
                    && len * accel < cap * std::f64::consts::PI * x
                {
                    let phi = 2.0 * libm::asin(x.min(1.0));
                    v2 = v2.min(len * accel / phi);
                }
                v2.min(both)
            }
            (None, None) => both,
        }
    }

    /// Plans every move (the passes of the module comment) and sums the times.
    pub fn finish(mut self) -> Estimate {
        if self.limits.square_corner_velocity.is_some() {
            let mut ends: Vec<usize> = self.parts.iter().map(|p| p.first).collect();
            ends.push(self.blocks.len());
            let planned = klipper_passes(&self.blocks, &self.mcr, &ends);
            return self.estimate(&planned);
        }
        // the head ends at rest: the backward pass from 0 after the last block
        let n = self.blocks.len();
        self.backward(n, 0.0);
        self.forward(n, true);
        let mut planned = std::mem::take(&mut self.planned);
        planned.resize(self.parts.len() + 1, 0.0);
        self.estimate(&planned)
    }

    /// Under Marlin's model, plans the blocks whose entries the blocks still
    /// to come can no longer change, and forgets them (2M moves kept 64 MB
    /// of blocks until the end).
    ///
    /// The backward pass is e_i = min(cap_i, e_{i+1} + 2·a_i·L_i), and each
    /// step (a rounded sum, then a min) never lowers its result when
    /// e_{i+1} grows. Whatever comes after the last block queued, its entry
    /// lies in [0, ∞]: run from both ends of that range, the pass gives
    /// bounds of every e_i, and where the two meet (bit for bit) e_i is the
    /// one the whole print's pass gives; below it the pass is the same
    /// operations on the same values. The forward pass and the times of the
    /// blocks before that one follow in order, so every sum is the same.
    fn plan_settled(&mut self) {
        let n = self.blocks.len();
        let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
        let mut settled = None;
        for j in (1..n).rev() {
            let t = self.reach(j);
            let cap = self.cap(j);
            lo = cap.min(lo + t);
            hi = cap.min(hi + t);
            if lo.to_bits() == hi.to_bits() {
                settled = Some((j, lo));
                break;
            }
        }
        match settled {
            Some((m, e)) => {
                self.blocks[m].entry_v2 = e;
                self.backward(m, e);
                self.forward(m, false);
                self.blocks.drain(..m);
                self.done += m;
                self.head_planned = true;
                self.next_settle = self.blocks.len() + SETTLE;
            }
            // nothing settled yet (moves so fast that 8192 of them cannot
            // stop): look again once the queue has doubled
            None => self.next_settle = 2 * n,
        }
    }

    /// 2·a·L of block j (of `blocks`): the v² it gains or loses.
    #[inline]
    fn reach(&self, j: usize) -> f64 {
        2.0 * self.blocks[j].accel * self.blocks[j].len
    }

    /// The highest entry v² of block j ≥ 1 (of `blocks`): its junction's,
    /// under both blocks' cruise v².
    #[inline]
    fn cap(&self, j: usize) -> f64 {
        let b = &self.blocks;
        b[j].entry_v2.min(b[j].cruise_v2).min(b[j - 1].cruise_v2)
    }

    /// The backward pass over `blocks[1..end]` from `next`, the entry v² of
    /// block `end`: entries the blocks after can brake from. (The first
    /// block of all enters at rest; a kept first block is planned already.)
    fn backward(&mut self, end: usize, mut next: f64) {
        for j in (1..end).rev() {
            let e = self.cap(j).min(next + self.reach(j));
            self.blocks[j].entry_v2 = e;
            next = e;
        }
    }

    /// The forward pass over `blocks[..end]` and their times, summed per
    /// range in order; with `last` the last of them ends at rest, else each
    /// leaves at the entry of the block after it (in `blocks`).
    fn forward(&mut self, end: usize, last: bool) {
        if end == 0 {
            return;
        }
        if !self.head_planned {
            // the first block of all: from rest
            self.blocks[0].entry_v2 = 0.0;
        }
        // ranges: before the parts (0), then part k (k + 1) from its first block
        if self.planned.len() <= self.parts.len() {
            self.planned.resize(self.parts.len() + 1, 0.0);
        }
        let first = |slot: usize, parts: &[Part]| parts.get(slot).map_or(usize::MAX, |p| p.first);
        let mut slot = self.slot;
        let mut bound = first(slot, &self.parts);
        // with `last` the last block leaves at rest, else at the next one's entry
        let blocks = &mut self.blocks[..end + usize::from(!last)];
        for i in 0..end {
            let g = self.done + i;
            while g >= bound {
                slot += 1;
                bound = first(slot, &self.parts);
            }
            let b = blocks[i];
            let exit = match blocks.get_mut(i + 1) {
                Some(nb) => {
                    let reach = b.entry_v2 + 2.0 * b.accel * b.len;
                    nb.entry_v2 = nb.entry_v2.min(reach);
                    nb.entry_v2
                }
                None => 0.0,
            };
            self.planned[slot] += trapezoid_time(b.len, b.accel, b.entry_v2, exit, b.cruise_v2);
        }
        self.slot = slot;
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

/// Klipper's look-ahead flush (`LookAheadQueue.flush`) over the whole print
/// and the blocks' times, summed per range as [`Planner::finish`] does.
///
/// Backward from rest at the end, each block gets its entry v²
/// s_i = min(e_i, s_{i+1} + 2·a_i·L_i) as in Marlin's model, and the same in
/// the minimum-cruise-ratio profile (entry limits `mcr_entry_v2` and gains
/// `mcr_delta_v2` of [`Planner::klipper_entry`], whose acceleration is
/// a·(1 − ratio)): m_i = min(me_i, m_{i+1} + d_i). A block with
/// m_i < m_{i+1} + d_i can speed up in that profile; the peak v² of the run of
/// such blocks is where the profile's triangle tops out, (m_i + m_{i+1} + d_i)/2,
/// taken at the block that can both speed up and slow down (or that
/// accelerates all along just before blocks that only slow down), and shared
/// by the blocks before it that accelerate all along. Such a block cruises at
/// most at that peak and at its own triangle's top (s_i + s_{i+1} + 2·a_i·L_i)/2.
/// Reaching the peak at a instead of a·(1 − ratio) takes (1 − ratio) of the
/// distance the profile's ramps take, which leaves at least `ratio` of a run
/// from rest to rest cruising. A block that can only slow down cruises at
/// the cruise of the block before it, or its own entry if lower. Then each
/// block is a trapezoid from min(s_i, c_i) to min(s_{i+1}, c_i) cruising at c_i.
fn klipper_passes(b: &[Block], mcr: &[Mcr], ends: &[usize]) -> Vec<f64> {
    let n = b.len();
    // (entry v², cruise v² if known, exit v²), filled backward
    let mut plan: Vec<(f64, Option<f64>, f64)> = vec![(0.0, None, 0.0); n];
    let (mut next, mut next_mcr, mut peak) = (0.0f64, 0.0f64, 0.0f64);
    let mut pending = 0usize;
    for i in (0..n).rev() {
        let reach = next + 2.0 * b[i].accel * b[i].len;
        let start = b[i].entry_v2.min(reach);
        pending += 1;
        let reach_mcr = next_mcr + mcr[i].delta_v2;
        let start_mcr = mcr[i].entry_v2.min(reach_mcr);
        let mut cruise = None;
        if start_mcr < reach_mcr {
            if start_mcr + mcr[i].delta_v2 > next_mcr || pending > 1 {
                peak = 0.5 * (start_mcr + reach_mcr);
            }
            cruise = Some(b[i].cruise_v2.min(0.5 * (start + reach)).min(peak));
            pending = 0;
        }
        plan[i] = (start, cruise, next);
        next = start;
        next_mcr = start_mcr;
    }
    let mut planned = vec![0.0f64; ends.len()];
    let mut slot = 0;
    let mut prev_cruise = 0.0f64;
    for (i, &(start, cruise, exit)) in plan.iter().enumerate() {
        while i >= ends[slot] {
            slot += 1;
        }
        let c = cruise.unwrap_or(prev_cruise.min(start));
        if c > 0.0 {
            planned[slot] += trapezoid_time(b[i].len, b[i].accel, start.min(c), exit.min(c), c);
        }
        prev_cruise = c;
    }
    planned
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
pub fn trapezoid_time(len: f64, a: f64, v0_2: f64, v1_2: f64, vc_2: f64) -> f64 {
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

/// One call on a [`Planner`], recorded to replay on another thread.
#[derive(Clone, Debug)]
enum Call {
    BeginPart(String),
    Stop,
    Dwell(f64),
    MoveTo(DVec3, f64, f64, MoveKind),
    ExtrudeOnly(f64, f64),
}

/// Calls sent to the planner's thread at a time.
const BATCH: usize = 4096;

/// Replays one recorded call on `planner`.
fn replay(planner: &mut Planner, call: &Call) {
    match *call {
        Call::BeginPart(ref name) => planner.begin_part(name),
        Call::Stop => planner.stop(),
        Call::Dwell(s) => planner.dwell(s),
        Call::MoveTo(to, e, feed, kind) => planner.move_to(to, e, feed, kind),
        Call::ExtrudeOnly(l, feed) => planner.extrude_only(l, feed),
    }
}

/// A [`Planner`] on its own thread: the same calls, recorded in batches and
/// replayed there in order while the G-code is written, so the estimate is
/// exactly the one planner's and costs the writer almost nothing. With a
/// budget of one thread it runs inline instead: the same calls, in the same
/// order, on the caller's thread.
pub struct Background {
    limits: Limits,
    batch: Vec<Call>,
    tx: Option<Tx>,
    worker: Option<std::thread::JoinHandle<Estimate>>,
    /// The planner itself when it runs inline (a budget of one thread).
    inline: Option<Planner>,
    /// The planner of a [`Feed`], shared with another thread.
    fed: Option<std::sync::Arc<std::sync::Mutex<Fed>>>,
    /// The feed's [`Feed::wanted`].
    wanted: std::sync::Arc<std::sync::atomic::AtomicBool>,
    /// The feed's [`Feed::sent`].
    sent: std::sync::Arc<std::sync::atomic::AtomicUsize>,
    /// Batches the planner has replayed, to fill again.
    pool: Pool,
}

/// Where recorded calls go: the planner's own thread (bounded: the writer
/// waits when it is too far ahead) or a [`Feed`] (unbounded: its thread may
/// have other work first).
enum Tx {
    Bounded(std::sync::mpsc::SyncSender<Vec<Call>>),
    Unbounded(std::sync::mpsc::Sender<Vec<Call>>),
}

/// The receiving end of [`Background::fed`]: a planner that a thread the
/// caller already has runs between and after its other work, replaying every
/// recorded call in order. The writer's thread takes over what is left once
/// it has written everything (see [`Background::finish`]), so whichever
/// thread is free plans; one lock keeps the calls in order, so the estimate
/// is the one planner's.
pub struct Feed {
    shared: std::sync::Arc<std::sync::Mutex<Fed>>,
    /// Set by the writer's thread when it has written everything and wants
    /// the planner: a catch-up stops at its next batch and lets it have it.
    wanted: std::sync::Arc<std::sync::atomic::AtomicBool>,
    /// How many batches the writer has sent so far.
    sent: std::sync::Arc<std::sync::atomic::AtomicUsize>,
}

/// A planner fed by a channel, and its estimate once the calls have ended.
struct Fed {
    planner: Option<Planner>,
    rx: std::sync::mpsc::Receiver<Vec<Call>>,
    /// How many batches it has taken from `rx`.
    received: usize,
    estimate: Option<Estimate>,
    pool: Pool,
}

/// Replayed batches handed back to the writer to fill again: a fresh
/// 196 KB batch each time cost the writer's thread page faults (2M moves:
/// ~100 MB of new pages, and as much unmapped on the other thread).
type Pool = std::sync::Arc<std::sync::Mutex<Vec<Vec<Call>>>>;

/// Batches a [`Pool`] keeps at most.
const POOL: usize = 16;

/// Hands `batch` back to `pool`, emptied (dropped when the pool is full).
fn recycle(pool: &Pool, mut batch: Vec<Call>) {
    batch.clear();
    if let Ok(mut p) = pool.lock() {
        if p.len() < POOL {
            p.push(batch);
        }
    }
}

/// An empty batch from `pool`, or a new one.
fn fresh(pool: &Pool) -> Vec<Call> {
    pool.lock()
        .ok()
        .and_then(|mut p| p.pop())
        .unwrap_or_else(|| Vec::with_capacity(BATCH))
}

impl Fed {
    /// Replays the first `until` batches (those sent so far), stopping
    /// early when `wanted` is set.
    fn catch_up(&mut self, until: usize, wanted: &std::sync::atomic::AtomicBool) {
        let Some(p) = &mut self.planner else { return };
        while self.received < until && !wanted.load(std::sync::atomic::Ordering::Relaxed) {
            let Ok(batch) = self.rx.try_recv() else { break };
            self.received += 1;
            p.replay_batch(&batch);
            recycle(&self.pool, batch);
        }
    }

    /// Replays the calls until the writer has sent the last and dropped its
    /// end (or is gone), then plans them.
    fn run(&mut self) {
        let Some(mut p) = self.planner.take() else {
            return;
        };
        while let Ok(batch) = self.rx.recv() {
            self.received += 1;
            p.replay_batch(&batch);
            recycle(&self.pool, batch);
        }
        self.estimate = Some(p.finish());
    }
}

/// The shared planner, even if a thread panicked while it held it (that
/// panic is raised where the scope joins it).
fn lock(m: &std::sync::Mutex<Fed>) -> std::sync::MutexGuard<'_, Fed> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Feed {
    /// Replays the calls recorded so far, not those recorded meanwhile (a
    /// writer faster than the planner kept this thread planning until it
    /// had written everything, the checks this thread had yet to start
    /// waiting); does nothing if the writer's thread is planning now, and
    /// stops as soon as it wants to (it has written everything: the rest is
    /// its to plan, while this thread goes on with its own work).
    pub fn catch_up(&self) {
        let until = self.sent.load(std::sync::atomic::Ordering::Acquire);
        if let Ok(mut fed) = self.shared.try_lock() {
            fed.catch_up(until, &self.wanted);
        }
    }

    /// Replays the calls until the writer finishes (unless its thread has
    /// done so already), and plans them.
    pub fn run(&self) {
        lock(&self.shared).run();
    }
}

impl Background {
    /// A planner with these limits, started on a thread of its own when
    /// `threads` allows a second one, else run inline.
    pub fn new(limits: Limits, threads: Threads) -> Background {
        let mut planner = Planner::new(limits.clone());
        if !threads.parallel() {
            return Background {
                limits,
                batch: Vec::new(),
                tx: None,
                worker: None,
                inline: Some(planner),
                fed: None,
                wanted: Default::default(),
                sent: Default::default(),
                pool: Default::default(),
            };
        }
        let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<Call>>(64);
        let pool = Pool::default();
        let back = pool.clone();
        let worker = std::thread::spawn(move || {
            for batch in rx {
                planner.replay_batch(&batch);
                recycle(&back, batch);
            }
            planner.finish()
        });
        Background {
            limits,
            batch: Vec::with_capacity(BATCH),
            tx: Some(Tx::Bounded(tx)),
            worker: Some(worker),
            inline: None,
            fed: None,
            wanted: Default::default(),
            sent: Default::default(),
            pool,
        }
    }

    /// A planner with these limits whose calls are recorded for the returned
    /// [`Feed`], which another thread runs when it is free: the same calls in
    /// the same order, so the same estimate. Calls wait in memory until then.
    pub fn fed(limits: Limits) -> (Background, Feed) {
        let wanted = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let sent = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let (tx, rx) = std::sync::mpsc::channel::<Vec<Call>>();
        let pool = Pool::default();
        let shared = std::sync::Arc::new(std::sync::Mutex::new(Fed {
            planner: Some(Planner::new(limits.clone())),
            rx,
            received: 0,
            estimate: None,
            pool: pool.clone(),
        }));
        let bg = Background {
            limits,
            batch: Vec::with_capacity(BATCH),
            tx: Some(Tx::Unbounded(tx)),
            worker: None,
            inline: None,
            fed: Some(shared.clone()),
            wanted: wanted.clone(),
            sent: sent.clone(),
            pool,
        };
        (
            bg,
            Feed {
                shared,
                wanted,
                sent,
            },
        )
    }

    fn call(&mut self, c: Call) {
        if let Some(p) = &mut self.inline {
            replay(p, &c);
            return;
        }
        self.batch.push(c);
        if self.batch.len() >= BATCH && self.tx.is_some() {
            self.send();
        }
    }

    fn send(&mut self) {
        let batch = std::mem::replace(&mut self.batch, fresh(&self.pool));
        // a send fails only if the worker died: its panic is raised at finish
        match &self.tx {
            Some(Tx::Bounded(tx)) => {
                let _ = tx.send(batch);
            }
            Some(Tx::Unbounded(tx)) if tx.send(batch).is_ok() => {
                self.sent.fetch_add(1, std::sync::atomic::Ordering::Release);
            }
            _ => {}
        }
    }

    /// The limits in use.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// See [`Planner::begin_part`].
    pub fn begin_part(&mut self, name: &str) {
        self.call(Call::BeginPart(name.to_string()));
    }

    /// See [`Planner::stop`].
    pub fn stop(&mut self) {
        self.call(Call::Stop);
    }

    /// See [`Planner::dwell`].
    pub fn dwell(&mut self, seconds: f64) {
        self.call(Call::Dwell(seconds));
    }

    /// See [`Planner::move_to`].
    pub fn move_to(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
        self.call(Call::MoveTo(to, e, feed, kind));
    }

    /// See [`Planner::extrude_only`].
    pub fn extrude_only(&mut self, length: f64, feed: f64) {
        self.call(Call::ExtrudeOnly(length, feed));
    }

    /// Sends what is left, waits for the thread and returns its estimate;
    /// calls after it are ignored.
    pub fn finish(&mut self) -> Estimate {
        if let Some(p) = self.inline.take() {
            return p.finish();
        }
        self.send();
        self.tx = None;
        if let Some(shared) = self.fed.take() {
            // every call is sent: plan what the feed's thread has not yet
            self.wanted
                .store(true, std::sync::atomic::Ordering::Relaxed);
            let mut fed = lock(&shared);
            fed.run();
            return fed
                .estimate
                .take()
                .unwrap_or_else(|| panic!("the planner's estimate was taken twice"));
        }
        let worker = self.worker.take().expect("finish is called once");
        worker
            .join()
            .unwrap_or_else(|e| std::panic::resume_unwind(e))
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        // an emitter dropped on an error: let the thread end, ignore its result
        self.tx = None;
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn marlin(accel: f64, jd: f64, vmax: f64) -> Limits {
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

    fn klipper(accel: f64, scv: f64, vmax: f64, ratio: f64) -> Limits {
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
    fn long_print(p: &mut Planner) {
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
            .contains("not both"));
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
