//! Planner starvation: a firmware plans a few moves ahead from a buffer that
//! the G-code stream fills one line at a time; a long run of moves each
//! quicker than a line takes to arrive and be planned (`checks.min_move_time`)
//! drains the buffer, and the firmware then stretches moves towards its
//! minimum segment time (Marlin's `M205 B`, the profile's
//! `kinematics.min_segment_time`): the head slows and stutters (the papers
//! warn that many very short strings make printing slow and unstable).
//!
//! The check sees the moves the G-code will have: strings shorter than the
//! printer's `min_string_length` are merged as [`crate::output::gcode`] merges them.
//! A run of at least `checks.planner_buffer` consecutive extruding moves,
//! each taking less than `min_move_time`, starves the planner; the time lost
//! is about Σ (max(min_segment_time, min_move_time) − L/v) over its moves.
//! One warning per part whose runs lose at least [`MIN_LOSS`] s and 1 % of
//! the print's time.

use glam::DVec3;

use super::{fmt_p, Finding, Severity};
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;

/// Losses below this (s) are not reported.
pub(crate) const MIN_LOSS: f64 = 1.0;

/// Runs of starving moves of one part.
#[derive(Default)]
struct Runs {
    /// Moves in the current run, its loss, where it starts.
    cur: (usize, f64, usize, DVec3),
    runs: usize,
    moves: usize,
    lost: f64,
    /// The run losing most: (moves, loss, first string, place).
    worst: Option<(usize, f64, usize, DVec3)>,
    time: f64,
}

impl Runs {
    fn close(&mut self, buffer: usize) {
        let (n, lost, k, at) = std::mem::take(&mut self.cur);
        if n >= buffer {
            self.runs += 1;
            self.moves += n;
            self.lost += lost;
            if self.worst.is_none_or(|w| lost > w.1) {
                self.worst = Some((n, lost, k, at));
            }
        }
    }

    fn add(&mut self, t: f64, lim: (f64, f64), k: usize, at: DVec3, buffer: usize) {
        self.time += t;
        if t < lim.0 {
            if self.cur.0 == 0 {
                self.cur.2 = k;
                self.cur.3 = at;
            }
            self.cur.0 += 1;
            self.cur.1 += lim.1 - t;
        } else {
            self.close(buffer);
        }
    }
}

/// The `starvation` warnings.
pub(crate) fn check(recipe: &Recipe, paths: &[&Toolpath]) -> Vec<Finding> {
    let mut out = Vec::new();
    scan(recipe, paths, &mut out);
    out
}

/// [`check`] into `out`.
fn scan(recipe: &Recipe, paths: &[&Toolpath], out: &mut Vec<Finding>) {
    let p = &recipe.printer;
    let t_min = p.checks.min_move_time;
    let stretch = p.limits().min_segment_time.max(t_min);
    let lim = (t_min, stretch);
    let buffer = p.checks.planner_buffer as usize;
    let min = p.min_string_length;
    let mut all = Vec::with_capacity(paths.len());
    for tp in paths {
        let mut r = Runs::default();
        // a pending merge: strings, path length, time, first string, start
        let mut pend: Option<(f64, f64, usize, DVec3)> = None;
        let flush = |pend: &mut Option<(f64, f64, usize, DVec3)>, r: &mut Runs| {
            if let Some((_, time, k, at)) = pend.take() {
                r.add(time, lim, k, at, buffer);
            }
        };
        for k in 0..tp.len() {
            let s = tp.strings[k];
            let (a, b) = tp.ends(k);
            if s.travel {
                flush(&mut pend, &mut r);
                r.close(buffer);
                continue;
            }
            let len = a.distance(b);
            let t = if s.v > 0.0 { len / s.v } else { 0.0 };
            if len >= min {
                flush(&mut pend, &mut r);
                r.add(t, lim, k, a, buffer);
                continue;
            }
            let e = pend.get_or_insert((0.0, 0.0, k, a));
            e.0 += len;
            e.1 += t;
            if e.0 >= min {
                flush(&mut pend, &mut r);
            }
        }
        flush(&mut pend, &mut r);
        r.close(buffer);
        all.push(r);
    }
    let total: f64 = all.iter().map(|r| r.time).sum();
    for (tp, r) in paths.iter().zip(all) {
        if r.lost < MIN_LOSS || r.lost < 0.01 * total {
            continue;
        }
        let Some((n, lost, k, at)) = r.worst else {
            continue;
        };
        out.push(Finding {
            code: "starvation",
            severity: Severity::Warning,
            message: format!(
                "part `{}` has {} run{} of moves ({} in all) each quicker than the {} ms the firmware takes to read and plan one (checks.min_move_time): the planner starves and stretches them towards {} ms, adding about {:.1} s to its {:.1} s; the worst run, {n} moves from string {k} at {}, loses {:.1} s (longer strings, or a lower speed there, avoid it)",
                tp.name,
                r.runs,
                if r.runs == 1 { "" } else { "s" },
                r.moves,
                t_min * 1000.0,
                stretch * 1000.0,
                r.lost,
                r.time,
                fmt_p(at),
                lost
            ),
            part: Some(tp.name.clone()),
            string: Some(k),
            at: Some(at.to_array()),
            strings: Vec::new(),
        });
    }
}
