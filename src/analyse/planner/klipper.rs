//! Klipper's model: the look-ahead as the moves are queued (`calc_junction`)
//! and its flush with the minimum cruise ratio.

use super::{trapezoid_time, Block, Planner};

/// A block's minimum-cruise-ratio profile, kept beside it under Klipper's
/// model only (Marlin's has none: 16 bytes a move saved).
#[derive(Clone, Copy, Debug)]
pub(super) struct Mcr {
    /// The highest entry v² in the minimum-cruise-ratio profile.
    pub(super) entry_v2: f64,
    /// The v² this block can gain in that profile, 2·L·a_mcr.
    pub(super) delta_v2: f64,
}

impl Planner {
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
    pub(super) fn klipper_entry(
        &self,
        entry_v2: &mut f64,
        base: f64,
        accel: f64,
        len: f64,
    ) -> (f64, f64) {
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
pub(super) fn klipper_passes(
    b: &[Block],
    mcr: &[Mcr],
    ends: &[usize],
    mut timeline: Option<&mut Vec<f32>>,
) -> Vec<f64> {
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
        let mut t = 0.0;
        if c > 0.0 {
            t = trapezoid_time(b[i].len, b[i].accel, start.min(c), exit.min(c), c);
            planned[slot] += t;
        }
        if let Some(tl) = timeline.as_deref_mut() {
            tl.push(t as f32);
        }
        prev_cruise = c;
    }
    planned
}
