//! Marlin's model: its block buffer as the SD reader fills it and the
//! steppers empty it (the minimum segment time's slowdown), and its
//! look-ahead passes run over the blocks the moves to come can no longer
//! change.

use super::{trapezoid_time, Part, Planner};

/// Marlin's block buffer as the SD reader fills it and the steppers empty it
/// (see [`Planner::slowdown`]): times in s from the first move.
#[derive(Clone, Debug, Default)]
pub(super) struct Queue {
    /// When the reader has the next line ready.
    read: f64,
    /// When the last queued block finishes.
    busy_until: f64,
    /// End times of the blocks in the buffer, oldest first.
    ends: std::collections::VecDeque<f64>,
}

/// Blocks queued between two looks for settled blocks (see
/// [`Planner::plan_settled`]): 256 KB of them.
pub(super) const SETTLE: usize = 8192;

impl Planner {
    /// The buffer empties (the firmware waits for its moves, then `seconds`
    /// more) before the reader goes on.
    pub(super) fn drain(&mut self, seconds: f64) {
        let q = &mut self.queue;
        q.read = q.read.max(q.busy_until) + seconds;
        q.busy_until = q.read;
        q.ends.clear();
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
    pub(super) fn slowdown(&mut self, len: f64, v: f64) -> f64 {
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
    pub(super) fn plan_settled(&mut self) {
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
    pub(super) fn backward(&mut self, end: usize, mut next: f64) {
        for j in (1..end).rev() {
            let e = self.cap(j).min(next + self.reach(j));
            self.blocks[j].entry_v2 = e;
            next = e;
        }
    }

    /// The forward pass over `blocks[..end]` and their times, summed per
    /// range in order; with `last` the last of them ends at rest, else each
    /// leaves at the entry of the block after it (in `blocks`).
    pub(super) fn forward(&mut self, end: usize, last: bool) {
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
            let t = trapezoid_time(b.len, b.accel, b.entry_v2, exit, b.cruise_v2);
            self.planned[slot] += t;
            if let Some(tl) = self.timeline.as_mut() {
                tl.push(t as f32);
            }
        }
        self.slot = slot;
    }
}
