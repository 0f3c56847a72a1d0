//! Arc fitting: runs of extruding strings that lie on a circle (or a helix,
//! the circle rising linearly with the angle) become single `G2`/`G3` moves.
//!
//! A candidate arc from point i to point j is the circle through the XY of
//! three of its points (first, middle, last). It is accepted when
//!
//! - every point lies within the tolerance of the arc: radial error
//!   `| |p − c| − R |` and height error (z against the arc's z, linear in
//!   the angle swept from the start) give `sqrt(er² + ez²) ≤ tol`;
//! - every string's chord stays within the tolerance of the arc between its
//!   ends: the sagitta `R·(1 − cos(Δθ/2))` plus the largest radial and height
//!   errors of its ends is at most `tol` (the arc's XY is at most the sagitta
//!   from the chord of two points on it, and the ends' errors add at most their
//!   larger value in between, since both z and the radius are interpolated
//!   linearly);
//! - the angle turns one way only, at most [`MAX_STEP`] a string and
//!   [`MAX_SWEEP`] in all (never a full turn, whose end would meet its start),
//!   and the radius lies in [[`MIN_RADIUS`], [`MAX_RADIUS`]] (a nearly
//!   straight run stays lines);
//! - the firmware's own chords of the arc (see [`Firmware`]) stay within the
//!   tolerance of it too, so a small arc that a firmware would cut into one
//!   or two straight moves stays strings.
//!
//! The fit is greedy: from each start the longest acceptable arc is found by
//! doubling its length, then bisecting; a start with no arc of at least
//! [`MIN_STRINGS`] strings stays a line and the next point is tried.
//! Everything is + − × ÷, `sqrt` and libm, so the same on every machine.

use glam::{DVec2, DVec3};

use crate::base::toolpath::Toolpath;

/// Fewest strings an arc replaces.
pub(crate) const MIN_STRINGS: usize = 3;
/// Largest angle of one string on an arc, radians.
pub(crate) const MAX_STEP: f64 = std::f64::consts::PI / 8.0;
/// Largest angle one arc sweeps, radians (three quarters of a turn).
pub(crate) const MAX_SWEEP: f64 = 1.5 * std::f64::consts::PI;
/// Smallest arc radius at any tolerance, mm.
pub(crate) const MIN_RADIUS: f64 = 0.3;

/// How a firmware cuts a `G2`/`G3` into straight moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Firmware {
    /// Longest chord, mm (Marlin's MAX_ARC_SEGMENT_MM, Klipper's
    /// `[gcode_arcs] resolution`).
    pub(crate) max_chord: f64,
    /// At least this many chords a full turn (Marlin's MIN_CIRCLE_SEGMENTS;
    /// 0 for no minimum).
    pub(crate) min_circle_segments: u32,
}

impl Firmware {
    /// How far the firmware's chords leave a circle of radius `r`: the
    /// sagitta `r·(1 − cos(α/2))` of the chord angle α, the smaller of
    /// `2·asin(max_chord / 2r)` and a turn over `min_circle_segments`
    /// (about max_chord²/(8r) for large r).
    pub(crate) fn sagitta(&self, r: f64) -> f64 {
        use std::f64::consts::PI;
        let mut alpha = 2.0 * libm::asin((self.max_chord / (2.0 * r)).min(1.0));
        if self.min_circle_segments > 0 {
            alpha = alpha.min(2.0 * PI / self.min_circle_segments as f64);
        }
        r * (1.0 - libm::cos(alpha / 2.0))
    }
}
/// Largest arc radius, mm.
pub(crate) const MAX_RADIUS: f64 = 1000.0;
/// Strings on one arc differ in cross-section and in speed by at most this
/// factor from the run's first string (a larger change starts a new move).
pub(crate) const RATE_TOLERANCE: f64 = 1.01;

/// An arc (or helix turn) through points `start..=end` of a polyline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Arc {
    /// Index of the first point.
    pub(crate) start: usize,
    /// Index of the last point (the arc replaces strings `start..end`).
    pub(crate) end: usize,
    /// Centre, XY.
    pub(crate) center: DVec2,
    /// Radius, mm.
    pub(crate) radius: f64,
    /// Counter-clockwise seen from above (`G3`); clockwise is `G2`.
    pub(crate) ccw: bool,
    /// Angle of the start point round the centre, radians.
    pub(crate) theta0: f64,
    /// Angle swept, radians (> 0).
    pub(crate) sweep: f64,
    /// Height at the start, mm.
    pub(crate) z0: f64,
    /// Height at the end, mm.
    pub(crate) z1: f64,
}

impl Arc {
    /// The point at angle `phi` (0 to `sweep`) from the start: z is linear in
    /// the angle, as the firmware interpolates a helical `G2`/`G3`.
    pub(crate) fn point_at(&self, phi: f64) -> DVec3 {
        let a = if self.ccw {
            self.theta0 + phi
        } else {
            self.theta0 - phi
        };
        DVec3::new(
            self.center.x + self.radius * libm::cos(a),
            self.center.y + self.radius * libm::sin(a),
            self.z0 + (self.z1 - self.z0) * phi / self.sweep,
        )
    }

    /// The points that bound the arc's sweep: its ends, the points where x
    /// or y is extreme (angles 0, π/2, π, 3π/2 when the sweep passes them)
    /// and the point farthest from `from` (at the angle of centre − `from`,
    /// when swept). A rectangle, or a disc round `from`, holds the whole arc
    /// exactly when it holds these points.
    pub(crate) fn bounding_points(&self, from: DVec2) -> Vec<DVec3> {
        use std::f64::consts::{FRAC_PI_2, PI, TAU};
        let away = self.center - from;
        let mut angles = vec![0.0, FRAC_PI_2, PI, -FRAC_PI_2];
        if away.length_squared() > 0.0 {
            angles.push(libm::atan2(away.y, away.x));
        }
        let mut out = vec![self.point_at(0.0), self.point_at(self.sweep)];
        for a in angles {
            // the angle travelled from the start to `a`, in [0, 2π)
            let d = if self.ccw {
                a - self.theta0
            } else {
                self.theta0 - a
            };
            let phi = d - TAU * libm::floor(d / TAU);
            if phi <= self.sweep {
                out.push(self.point_at(phi));
            }
        }
        out
    }

    /// Length of the helix, mm: sqrt((R·sweep)² + Δz²).
    pub(crate) fn length(&self) -> f64 {
        let xy = self.radius * self.sweep;
        let dz = self.z1 - self.z0;
        (xy * xy + dz * dz).sqrt()
    }
}

/// The circle through three points: centre and radius, `None` when they are
/// (nearly) on a line. The centre is where the perpendicular bisectors of
/// a→b and a→c meet: with u = centre − a, `2 u·ab = |ab|²` and `2 u·ac = |ac|²`,
/// solved by Cramer's rule.
pub(crate) fn circle(a: DVec2, b: DVec2, c: DVec2) -> Option<(DVec2, f64)> {
    let ab = b - a;
    let ac = c - a;
    let d = 2.0 * (ab.x * ac.y - ab.y * ac.x);
    let (ab2, ac2) = (ab.length_squared(), ac.length_squared());
    // NaN (a non-finite point) counts as collinear
    if d.abs().is_nan() || d.abs() <= 1e-12 * (ab2 * ac2).sqrt() {
        return None;
    }
    let u = DVec2::new((ac.y * ab2 - ab.y * ac2) / d, (ab.x * ac2 - ac.x * ab2) / d);
    Some((a + u, u.length()))
}

/// `x` wrapped into (−π, π].
fn wrap(x: f64) -> f64 {
    use std::f64::consts::PI;
    let mut x = x;
    while x > PI {
        x -= 2.0 * PI;
    }
    while x <= -PI {
        x += 2.0 * PI;
    }
    x
}

/// The arc through points `i..=j` of `pts` when it passes the tests of the
/// module comment.
pub(crate) fn try_arc(pts: &[DVec3], i: usize, j: usize, tol: f64, fw: Firmware) -> Option<Arc> {
    if j < i + MIN_STRINGS || j >= pts.len() {
        return None;
    }
    let m = (i + j) / 2;
    let (center, radius) = circle(pts[i].truncate(), pts[m].truncate(), pts[j].truncate())?;
    if !(MIN_RADIUS..=MAX_RADIUS).contains(&radius) || fw.sagitta(radius) > tol {
        return None;
    }
    let angle = |p: DVec3| libm::atan2(p.y - center.y, p.x - center.x);
    // swept angle at each point, unwrapped, turning one way only
    let mut phis = Vec::with_capacity(j - i + 1);
    phis.push(0.0);
    let mut prev = angle(pts[i]);
    let theta0 = prev;
    let mut sign = 0.0;
    for p in &pts[i + 1..=j] {
        let a = angle(*p);
        let d = wrap(a - prev);
        if d.abs() < 1e-9 || d.abs() > MAX_STEP {
            return None;
        }
        let s = d.signum();
        if sign == 0.0 {
            sign = s;
        } else if s != sign {
            return None;
        }
        phis.push(phis.last().unwrap() + d.abs());
        prev = a;
    }
    let sweep = *phis.last().unwrap();
    if sweep > MAX_SWEEP + 1e-9 {
        return None;
    }
    let (z0, z1) = (pts[i].z, pts[j].z);
    // radial and height errors of each point
    let err = |k: usize| {
        let p = pts[i + k];
        let er = ((p.truncate() - center).length() - radius).abs();
        let ez = (p.z - (z0 + (z1 - z0) * phis[k] / sweep)).abs();
        (er, ez)
    };
    let mut last = err(0);
    for k in 1..phis.len() {
        let e = err(k);
        if (e.0 * e.0 + e.1 * e.1).sqrt() > tol {
            return None;
        }
        let step = phis[k] - phis[k - 1];
        let sagitta = radius * (1.0 - libm::cos(step / 2.0));
        if sagitta + e.0.max(last.0) + e.1.max(last.1) > tol {
            return None;
        }
        last = e;
    }
    Some(Arc {
        start: i,
        end: j,
        center,
        radius,
        ccw: sign > 0.0,
        theta0,
        sweep,
        z0,
        z1,
    })
}

/// Fits arcs to the polyline `pts` (see the module comment): the arcs found,
/// in order, not overlapping; the points between them stay lines.
pub(crate) fn fit(pts: &[DVec3], tol: f64, fw: Firmware) -> Vec<Arc> {
    let mut arcs = Vec::new();
    if pts.len() <= MIN_STRINGS {
        return arcs;
    }
    let last = pts.len() - 1;
    let mut i = 0;
    while i + MIN_STRINGS <= last {
        let Some(mut best) = try_arc(pts, i, i + MIN_STRINGS, tol, fw) else {
            i += 1;
            continue;
        };
        // double the length while it fits, then bisect between fit and misfit
        let mut bad = None;
        while best.end < last {
            let cand = (i + 2 * (best.end - i)).min(last);
            match try_arc(pts, i, cand, tol, fw) {
                Some(a) => best = a,
                None => {
                    bad = Some(cand);
                    break;
                }
            }
        }
        if let Some(mut hi) = bad {
            while hi - best.end > 1 {
                let mid = (best.end + hi) / 2;
                match try_arc(pts, i, mid, tol, fw) {
                    Some(a) => best = a,
                    None => hi = mid,
                }
            }
        }
        i = best.end;
        arcs.push(best);
    }
    arcs
}

/// The arcs of a part, with indices into `tp.points`: fitted to each run of
/// extruding strings with no event inside and with cross-section and speed
/// within [`RATE_TOLERANCE`] of the run's first string.
pub(crate) fn fit_part(tp: &Toolpath, tol: f64, fw: Firmware) -> Vec<Arc> {
    let n = tp.len();
    let mut arcs = Vec::new();
    let mut k = 0;
    let mut events = tp.events.iter().map(|(at, _)| *at).peekable();
    while k < n {
        if tp.strings[k].travel {
            k += 1;
            continue;
        }
        let first = tp.strings[k];
        let near = |a: f64, b: f64| a > 0.0 && b > 0.0 && a.max(b) <= b.min(a) * RATE_TOLERANCE;
        let mut end = k + 1;
        while events.next_if(|at| *at <= k).is_some() {}
        let next_event = events.peek().copied().unwrap_or(usize::MAX);
        while end < n
            && end < next_event
            && !tp.strings[end].travel
            && near(tp.strings[end].c, first.c)
            && near(tp.strings[end].v, first.v)
        {
            end += 1;
        }
        // strings k..end: points k..=end
        for mut a in fit(&tp.points[k..=end], tol, fw) {
            a.start += k;
            a.end += k;
            arcs.push(a);
        }
        k = end;
    }
    arcs
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const FW: Firmware = Firmware {
        max_chord: 1.0,
        min_circle_segments: 72,
    };

    fn helix(r: f64, pitch: f64, per_turn: usize, n: usize) -> Vec<DVec3> {
        (0..=n)
            .map(|k| {
                let a = 2.0 * PI * k as f64 / per_turn as f64;
                DVec3::new(
                    5.0 + r * libm::cos(a),
                    -3.0 + r * libm::sin(a),
                    pitch * a / (2.0 * PI),
                )
            })
            .collect()
    }

    #[test]
    fn circle_through_three_points() {
        let (c, r) = circle(
            DVec2::new(1.0, 0.0),
            DVec2::new(0.0, 1.0),
            DVec2::new(-1.0, 0.0),
        )
        .unwrap();
        assert!(c.length() < 1e-12 && (r - 1.0).abs() < 1e-12);
        assert!(circle(DVec2::ZERO, DVec2::X, DVec2::X * 2.0).is_none());
    }

    #[test]
    fn a_helix_becomes_few_arcs_within_tolerance() {
        let pts = helix(20.0, 0.2, 300, 900);
        let arcs = fit(&pts, 0.01, FW);
        // three turns, at most three quarters of a turn per arc
        assert_eq!(arcs.len(), 4, "{arcs:?}");
        assert_eq!(arcs[0].start, 0);
        assert_eq!(arcs.last().unwrap().end, 900);
        for a in &arcs {
            assert!(a.ccw && (a.radius - 20.0).abs() < 1e-6);
            // every original point lies on the arc
            let step = a.sweep / (a.end - a.start) as f64;
            for (k, p) in pts.iter().enumerate().take(a.end + 1).skip(a.start) {
                let q = a.point_at(step * (k - a.start) as f64);
                assert!(q.distance(*p) < 1e-6, "{k}");
            }
        }
        // contiguous
        for w in arcs.windows(2) {
            assert_eq!(w[0].end, w[1].start);
        }
    }

    #[test]
    fn clockwise_and_coarse_circles() {
        let mut pts = helix(10.0, 0.0, 72, 36);
        pts.reverse();
        let arcs = fit(&pts, 0.01, FW);
        assert_eq!(arcs.len(), 1);
        assert!(!arcs[0].ccw);
        // 20 segments a turn: the chords leave the circle by 0.12 mm
        let coarse = helix(10.0, 0.0, 20, 12);
        assert!(fit(&coarse, 0.01, FW).is_empty());
        // but the points are on a circle, so a loose tolerance takes them
        assert_eq!(fit(&coarse, 1.0, FW).len(), 1);
    }

    #[test]
    fn small_arcs_need_a_firmware_that_keeps_them_round() {
        let klipper = Firmware {
            max_chord: 1.0,
            min_circle_segments: 0,
        };
        // 1 mm chords leave a 5 mm circle by 1/40 mm
        assert!((klipper.sagitta(5.0) - 0.025).abs() < 1e-4);
        // Marlin's 72 chords a turn keep a small circle round
        assert!(FW.sagitta(2.0) < 0.002);
        let small = helix(2.0, 0.0, 100, 60);
        assert_eq!(fit(&small, 0.01, FW).len(), 1);
        assert!(fit(&small, 0.01, klipper).is_empty());
    }

    #[test]
    fn arcs_stop_at_events_travel_and_rate_changes() {
        use crate::base::toolpath::Event;
        let pts = helix(20.0, 0.2, 300, 300);
        let mut tp = Toolpath::new(pts[0]);
        for (k, p) in pts.iter().enumerate().skip(1) {
            if k == 60 {
                tp.event(Event::Pause);
            }
            if k == 150 {
                tp.travel(*p, 100.0);
                continue;
            }
            // the speed steps by 5 % at string 200, drifts by 0.5 % before
            let v = if k > 200 {
                31.5
            } else {
                30.0 + 0.15 * k as f64 / 200.0
            };
            tp.draw(*p, 0.1, v);
        }
        let arcs = fit_part(&tp, 0.01, FW);
        // the pause comes before string 59, string 149 travels, string 200
        // is the first at the new speed
        for cut in [59, 149, 150, 200] {
            assert!(
                arcs.iter().all(|a| a.start >= cut || a.end <= cut),
                "{cut}: {arcs:?}"
            );
        }
        let covered: usize = arcs.iter().map(|a| a.end - a.start).sum();
        assert!(covered > 280, "{covered}");
    }

    #[test]
    fn lines_and_zigzags_stay_lines() {
        let line: Vec<DVec3> = (0..20).map(|k| DVec3::new(k as f64, 0.0, 0.0)).collect();
        assert!(fit(&line, 0.01, FW).is_empty());
        let zig: Vec<DVec3> = (0..20)
            .map(|k| DVec3::new(k as f64, (k % 2) as f64, 0.0))
            .collect();
        assert!(fit(&zig, 0.01, FW).is_empty());
    }

    #[test]
    fn a_bump_breaks_the_arc() {
        let mut pts = helix(20.0, 0.0, 300, 200);
        pts[100].x += 0.05;
        let arcs = fit(&pts, 0.01, FW);
        assert!(arcs.iter().all(|a| !(a.start < 100 && a.end > 100)));
    }
}
