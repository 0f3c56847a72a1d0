//! Boundary pieces: straight segments and circular arcs, with their exact
//! intersections (the paper's section 4: line–line, line–circle, and here also
//! circle–circle), distances and areas.
//!
//! A cross-section of boxes and vertical cylinders is bounded by nothing else,
//! and neither is its inward offset (offset lines stay lines, offset arcs stay
//! arcs, reflex corners become arcs), so these two kinds carry every loop
//! until the very end, when arcs become short strings.

use std::f64::consts::{PI, TAU};

use glam::DVec2;

/// z-component of the cross product `a × b`.
#[inline]
pub(crate) fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// `v` turned a quarter turn counter-clockwise.
#[inline]
pub(crate) fn perp(v: DVec2) -> DVec2 {
    DVec2::new(-v.y, v.x)
}

/// The point at angle `phi` on the circle (`c`, `r`).
#[inline]
pub(crate) fn on_circle(c: DVec2, r: f64, phi: f64) -> DVec2 {
    c + r * DVec2::new(libm::cos(phi), libm::sin(phi))
}

/// An arc of the circle (`c`, `r`): from angle `a0`, turning by `sweep`
/// (counter-clockwise when positive, |sweep| ≤ 2π), from `p0` to `p1`.
///
/// The end points are kept as given (not recomputed from the angles), so two
/// pieces that meet share exactly the same coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Arc {
    /// Centre.
    pub(crate) c: DVec2,
    /// Radius, > 0.
    pub(crate) r: f64,
    /// Angle of the start point, radians.
    pub(crate) a0: f64,
    /// Signed angle turned from start to end, radians.
    pub(crate) sweep: f64,
    /// Start point.
    pub(crate) p0: DVec2,
    /// End point.
    pub(crate) p1: DVec2,
}

impl Arc {
    /// A whole circle from angle 0, counter-clockwise or clockwise.
    pub(crate) fn circle(c: DVec2, r: f64, ccw: bool) -> Arc {
        let p = c + DVec2::new(r, 0.0);
        Arc {
            c,
            r,
            a0: 0.0,
            sweep: if ccw { TAU } else { -TAU },
            p0: p,
            p1: p,
        }
    }

    /// +1 for counter-clockwise, -1 for clockwise.
    #[inline]
    pub(crate) fn dir(&self) -> f64 {
        if self.sweep >= 0.0 {
            1.0
        } else {
            -1.0
        }
    }

    /// Whether this is a whole circle.
    #[inline]
    pub(crate) fn is_full(&self) -> bool {
        self.sweep.abs() >= TAU
    }

    /// How far (radians, in the arc's direction, in [0, 2π)) angle `phi` lies
    /// from the start; within `tol` of a whole turn counts as 0.
    pub(crate) fn offset_of(&self, phi: f64, tol: f64) -> f64 {
        let t = ((phi - self.a0) * self.dir()).rem_euclid(TAU);
        if TAU - t <= tol {
            0.0
        } else {
            t
        }
    }

    /// The point `theta` radians along the arc from its start.
    #[inline]
    pub(crate) fn at(&self, theta: f64) -> DVec2 {
        on_circle(self.c, self.r, self.a0 + self.dir() * theta)
    }
}

/// One piece of a boundary loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Piece {
    /// A segment from the first point to the second.
    Line(DVec2, DVec2),
    /// A circular arc.
    Arc(Arc),
}

impl Piece {
    /// Start point.
    #[inline]
    pub(crate) fn start(&self) -> DVec2 {
        match self {
            Piece::Line(a, _) => *a,
            Piece::Arc(k) => k.p0,
        }
    }

    /// End point.
    #[inline]
    pub(crate) fn end(&self) -> DVec2 {
        match self {
            Piece::Line(_, b) => *b,
            Piece::Arc(k) => k.p1,
        }
    }

    /// Whether this is a whole circle (a loop by itself).
    pub(crate) fn is_full(&self) -> bool {
        matches!(self, Piece::Arc(k) if k.is_full())
    }

    /// The same piece run the other way.
    pub(crate) fn reversed(&self) -> Piece {
        match *self {
            Piece::Line(a, b) => Piece::Line(b, a),
            Piece::Arc(k) => Piece::Arc(Arc {
                a0: k.a0 + k.sweep,
                sweep: -k.sweep,
                p0: k.p1,
                p1: k.p0,
                ..k
            }),
        }
    }

    /// The same piece with its end points replaced (by the shared vertex
    /// coordinates they were snapped to).
    pub(crate) fn with_ends(&self, a: DVec2, b: DVec2) -> Piece {
        match *self {
            Piece::Line(..) => Piece::Line(a, b),
            Piece::Arc(k) => Piece::Arc(Arc { p0: a, p1: b, ..k }),
        }
    }

    /// Length, mm.
    pub(crate) fn length(&self) -> f64 {
        match self {
            Piece::Line(a, b) => a.distance(*b),
            Piece::Arc(k) => k.r * k.sweep.abs(),
        }
    }

    /// The point halfway along.
    pub(crate) fn midpoint(&self) -> DVec2 {
        match self {
            Piece::Line(a, b) => (*a + *b) * 0.5,
            Piece::Arc(k) => k.at(0.5 * k.sweep.abs()),
        }
    }

    /// Unit tangent at parameter `theta` of an arc.
    fn arc_tangent(k: &Arc, theta: f64) -> DVec2 {
        let phi = k.a0 + k.dir() * theta;
        k.dir() * DVec2::new(-libm::sin(phi), libm::cos(phi))
    }

    /// Unit direction of travel at the start.
    pub(crate) fn tangent_start(&self) -> DVec2 {
        match self {
            Piece::Line(a, b) => (*b - *a).normalize_or_zero(),
            Piece::Arc(k) => Self::arc_tangent(k, 0.0),
        }
    }

    /// Unit direction of travel at the end.
    pub(crate) fn tangent_end(&self) -> DVec2 {
        match self {
            Piece::Line(a, b) => (*b - *a).normalize_or_zero(),
            Piece::Arc(k) => Self::arc_tangent(k, k.sweep.abs()),
        }
    }

    /// Unit direction of travel halfway along.
    pub(crate) fn tangent_mid(&self) -> DVec2 {
        match self {
            Piece::Line(a, b) => (*b - *a).normalize_or_zero(),
            Piece::Arc(k) => Self::arc_tangent(k, 0.5 * k.sweep.abs()),
        }
    }

    /// Signed curvature: 0 for a line, +1/r turning left, -1/r turning right.
    pub(crate) fn curvature(&self) -> f64 {
        match self {
            Piece::Line(..) => 0.0,
            Piece::Arc(k) => k.dir() / k.r,
        }
    }

    /// Twice the signed area the piece adds to its loop, ∮ (x dy − y dx).
    ///
    /// A segment adds the shoelace term `a × b`; an arc adds the shoelace term
    /// of its chord plus twice the circular segment between chord and arc,
    /// r²(Δ − sin Δ) with Δ the signed sweep. Both are exact formulas, so the
    /// area of a loop of lines and arcs is exact up to rounding.
    pub(crate) fn area2(&self) -> f64 {
        match self {
            Piece::Line(a, b) => cross(*a, *b),
            Piece::Arc(k) => cross(k.p0, k.p1) + k.r * k.r * (k.sweep - libm::sin(k.sweep)),
        }
    }

    /// Distance from `p` to the piece.
    pub(crate) fn distance(&self, p: DVec2) -> f64 {
        match self {
            Piece::Line(a, b) => {
                let d = *b - *a;
                let l2 = d.length_squared();
                if l2 == 0.0 {
                    return p.distance(*a);
                }
                let t = ((p - *a).dot(d) / l2).clamp(0.0, 1.0);
                p.distance(*a + d * t)
            }
            Piece::Arc(k) => {
                let v = p - k.c;
                let rho = v.length();
                if k.is_full() {
                    return (rho - k.r).abs();
                }
                if rho > 0.0 {
                    let th = k.offset_of(libm::atan2(v.y, v.x), 0.0);
                    if th <= k.sweep.abs() {
                        return (rho - k.r).abs();
                    }
                }
                p.distance(k.p0).min(p.distance(k.p1))
            }
        }
    }

    /// Bounding box `[min, max]` (of the whole circle for an arc), grown by `pad`.
    pub(crate) fn bbox(&self, pad: f64) -> [DVec2; 2] {
        let (lo, hi) = match self {
            Piece::Line(a, b) => (a.min(*b), a.max(*b)),
            Piece::Arc(k) => (k.c - DVec2::splat(k.r), k.c + DVec2::splat(k.r)),
        };
        [lo - DVec2::splat(pad), hi + DVec2::splat(pad)]
    }

    /// The parameter of `x` (a point on the piece's line or circle): 0..1
    /// along a segment, 0..|sweep| radians along an arc; `None` when `x` lies
    /// more than `eps` beyond the piece's ends.
    pub(crate) fn locate(&self, x: DVec2, eps: f64) -> Option<f64> {
        match self {
            Piece::Line(a, b) => {
                if x == *a {
                    return Some(0.0);
                }
                if x == *b {
                    return Some(1.0);
                }
                let d = *b - *a;
                let l2 = d.length_squared();
                let t = (x - *a).dot(d) / l2;
                let tol = eps / l2.sqrt();
                (t >= -tol && t <= 1.0 + tol).then(|| t.clamp(0.0, 1.0))
            }
            Piece::Arc(k) => {
                if x == k.p0 {
                    return Some(0.0);
                }
                if x == k.p1 && !k.is_full() {
                    return Some(k.sweep.abs());
                }
                let tol = eps / k.r;
                let th = k.offset_of(libm::atan2(x.y - k.c.y, x.x - k.c.x), tol);
                let end = k.sweep.abs();
                (th <= end + tol).then(|| th.min(end))
            }
        }
    }

    /// The part of the piece from parameter `s0` (at point `x0`) to `s1` (at `x1`).
    pub(crate) fn sub(&self, s0: f64, x0: DVec2, s1: f64, x1: DVec2) -> Piece {
        match self {
            Piece::Line(..) => Piece::Line(x0, x1),
            Piece::Arc(k) => Piece::Arc(Arc {
                a0: k.a0 + k.dir() * s0,
                sweep: k.dir() * (s1 - s0),
                p0: x0,
                p1: x1,
                ..*k
            }),
        }
    }

    /// Parameter tolerance matching a distance `eps`.
    pub(crate) fn param_tol(&self, eps: f64) -> f64 {
        match self {
            Piece::Line(a, b) => eps / a.distance(*b).max(eps),
            Piece::Arc(k) => eps / k.r,
        }
    }

    /// Parameter of the end.
    pub(crate) fn end_param(&self) -> f64 {
        match self {
            Piece::Line(..) => 1.0,
            Piece::Arc(k) => k.sweep.abs(),
        }
    }
}

/// Where the lines through segments `ab` and `cd` meet (the paper's eq. 5);
/// for parallel segments on one line, their four end points (the caller
/// keeps those that lie on both). Axis-aligned pairs, the edges of boxes,
/// meet at exactly (x of the vertical, y of the horizontal).
fn line_line(a: DVec2, b: DVec2, c: DVec2, d: DVec2, eps: f64) -> Vec<DVec2> {
    let d1 = b - a;
    let d2 = d - c;
    let den = cross(d1, d2);
    let l1 = d1.length();
    let l2 = d2.length();
    if den.abs() <= 1e-12 * l1 * l2 {
        if l1 == 0.0 || (cross(d1, c - a) / l1).abs() > eps {
            return Vec::new();
        }
        return vec![a, b, c, d];
    }
    if d1.y == 0.0 && d2.x == 0.0 {
        return vec![DVec2::new(c.x, a.y)];
    }
    if d1.x == 0.0 && d2.y == 0.0 {
        return vec![DVec2::new(a.x, c.y)];
    }
    let t = cross(c - a, d2) / den;
    vec![a + d1 * t]
}

/// Where the line through `ab` meets the circle (`c`, `r`) (the paper's
/// eq. 6–7, solved from the foot of the perpendicular from the centre, which
/// loses no precision when the line passes near the centre): none, one point
/// when the line is tangent within `eps`, or two.
fn line_circle(a: DVec2, b: DVec2, c: DVec2, r: f64, eps: f64) -> Vec<DVec2> {
    let d = b - a;
    let l = d.length();
    if l == 0.0 {
        return Vec::new();
    }
    let u = d / l;
    // exact feet for axis-aligned lines
    let foot = if d.y == 0.0 {
        DVec2::new(c.x, a.y)
    } else if d.x == 0.0 {
        DVec2::new(a.x, c.y)
    } else {
        a + u * (c - a).dot(u)
    };
    let dist = foot.distance(c);
    if dist > r + eps {
        return Vec::new();
    }
    if (r - dist).abs() <= eps {
        return vec![foot];
    }
    let h = ((r - dist) * (r + dist)).sqrt();
    vec![foot - u * h, foot + u * h]
}

/// Where two circles meet: none, one point when they touch within `eps`, or
/// two; for one circle given twice, the arcs' end points (each may split the
/// other).
fn circle_circle(k: &Arc, m: &Arc, eps: f64) -> Vec<DVec2> {
    let dv = m.c - k.c;
    let dd = dv.length();
    if dd <= eps {
        if (k.r - m.r).abs() <= eps {
            let mut v = Vec::new();
            for a in [k, m] {
                if !a.is_full() {
                    v.push(a.p0);
                    v.push(a.p1);
                }
            }
            return v;
        }
        return Vec::new();
    }
    let (r1, r2) = (k.r, m.r);
    if dd > r1 + r2 + eps || dd < (r1 - r2).abs() - eps {
        return Vec::new();
    }
    // distance from k's centre to the chord through the meeting points
    let along = ((dd * dd + r1 * r1 - r2 * r2) / (2.0 * dd)).clamp(-r1, r1);
    let base = k.c + dv * (along / dd);
    if (dd - (r1 + r2)).abs() <= eps || (dd - (r1 - r2).abs()).abs() <= eps {
        return vec![base];
    }
    let h = ((r1 - along) * (r1 + along)).max(0.0).sqrt();
    let n = perp(dv / dd);
    vec![base + n * h, base - n * h]
}

/// The points where pieces `p` and `q` meet, each with its parameter on `p`
/// and on `q` (see [`Piece::locate`]). A point within `eps` of an end point of
/// either piece is snapped to that end point.
pub(crate) fn intersect(p: &Piece, q: &Piece, eps: f64) -> Vec<(DVec2, f64, f64)> {
    let raw = match (p, q) {
        (Piece::Line(a, b), Piece::Line(c, d)) => line_line(*a, *b, *c, *d, eps),
        (Piece::Line(a, b), Piece::Arc(k)) | (Piece::Arc(k), Piece::Line(a, b)) => {
            line_circle(*a, *b, k.c, k.r, eps)
        }
        (Piece::Arc(k), Piece::Arc(m)) => circle_circle(k, m, eps),
    };
    let ends = [p.start(), p.end(), q.start(), q.end()];
    let mut out: Vec<(DVec2, f64, f64)> = Vec::with_capacity(raw.len());
    for mut x in raw {
        if let Some(e) = ends.iter().find(|e| x.distance(**e) <= eps) {
            x = *e;
        }
        if let (Some(s), Some(t)) = (p.locate(x, eps), q.locate(x, eps)) {
            if !out.iter().any(|(y, _, _)| *y == x) {
                out.push((x, s, t));
            }
        }
    }
    out
}

/// Splits `piece` at the points `hits` (parameter, point) lying on it.
/// Points within `eps` of an end or of each other count once; a whole circle
/// is cut into arcs between consecutive points (none: it stays whole).
pub(crate) fn split(piece: &Piece, hits: &mut [(f64, DVec2)], eps: f64) -> Vec<Piece> {
    hits.sort_by(|a, b| a.0.total_cmp(&b.0));
    let tol = piece.param_tol(eps);
    let end = piece.end_param();
    let mut cuts: Vec<(f64, DVec2)> = Vec::with_capacity(hits.len());
    for &(s, x) in hits.iter() {
        if let Some(last) = cuts.last() {
            if s - last.0 <= tol || x.distance(last.1) <= eps {
                continue;
            }
        }
        cuts.push((s, x));
    }
    if piece.is_full() {
        // cyclic: a cut near a whole turn is the cut at 0
        if cuts.len() > 1 {
            let (s0, x0) = cuts[0];
            let (sl, xl) = *cuts.last().unwrap();
            if s0 + end - sl <= tol || xl.distance(x0) <= eps {
                cuts.pop();
            }
        }
        let k = cuts.len();
        if k == 0 {
            return vec![*piece];
        }
        let mut out = Vec::with_capacity(k);
        for i in 0..k {
            let (s0, x0) = cuts[i];
            let (s1, x1) = if i + 1 < k {
                cuts[i + 1]
            } else {
                (cuts[0].0 + end, cuts[0].1)
            };
            out.push(piece.sub(s0, x0, s1, x1));
        }
        return out;
    }
    let (a, b) = (piece.start(), piece.end());
    cuts.retain(|&(s, x)| s > tol && s < end - tol && x.distance(a) > eps && x.distance(b) > eps);
    if cuts.is_empty() {
        return vec![*piece];
    }
    let mut out = Vec::with_capacity(cuts.len() + 1);
    let mut prev = (0.0, a);
    for &c in &cuts {
        out.push(piece.sub(prev.0, prev.1, c.0, c.1));
        prev = c;
    }
    out.push(piece.sub(prev.0, prev.1, end, b));
    out
}

/// Number of chords an arc of radius `r` turning by `sweep` needs so that
/// none strays more than `tol` from it: the sagitta of a chord spanning angle
/// θ is r·(1 − cos(θ/2)), so θ ≤ 2·acos(1 − tol/r) (at most a quarter turn
/// per chord, so a small circle still looks like one).
pub(crate) fn chords(r: f64, sweep: f64, tol: f64) -> u64 {
    let max = if tol < r {
        2.0 * libm::acos(1.0 - tol / r)
    } else {
        PI
    }
    .min(PI / 2.0);
    libm::ceil(sweep.abs() / max).max(1.0) as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    const EPS: f64 = 1e-9;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn axis_aligned_segments_meet_exactly() {
        let h = Piece::Line(v(-1.0, 0.3), v(2.0, 0.3));
        let w = Piece::Line(v(0.7, -5.0), v(0.7, 5.0));
        let x = intersect(&h, &w, EPS);
        assert_eq!(x.len(), 1);
        assert_eq!(x[0].0, v(0.7, 0.3));
        // collinear overlap: each splits at the other's ends
        let a = Piece::Line(v(0.0, 0.0), v(4.0, 0.0));
        let b = Piece::Line(v(1.0, 0.0), v(6.0, 0.0));
        let pts: Vec<DVec2> = intersect(&a, &b, EPS).iter().map(|h| h.0).collect();
        assert!(
            pts.contains(&v(4.0, 0.0)) && pts.contains(&v(1.0, 0.0)),
            "{pts:?}"
        );
    }

    #[test]
    fn line_circle_two_one_none() {
        let c = Piece::Arc(Arc::circle(v(0.0, 0.0), 5.0, true));
        let l = Piece::Line(v(-10.0, 3.0), v(10.0, 3.0));
        let x = intersect(&l, &c, EPS);
        assert_eq!(x.len(), 2);
        for (p, _, _) in &x {
            assert!((p.length() - 5.0).abs() < 1e-12);
            assert_eq!(p.y, 3.0);
        }
        // tangent: exactly one point
        let t = Piece::Line(v(-10.0, 5.0), v(10.0, 5.0));
        let x = intersect(&t, &c, EPS);
        assert_eq!(x.len(), 1);
        assert_eq!(x[0].0, v(0.0, 5.0));
        let far = Piece::Line(v(-10.0, 5.1), v(10.0, 5.1));
        assert!(intersect(&far, &c, EPS).is_empty());
    }

    #[test]
    fn circles_meet_and_touch() {
        let a = Piece::Arc(Arc::circle(v(0.0, 0.0), 5.0, true));
        let b = Piece::Arc(Arc::circle(v(6.0, 0.0), 5.0, true));
        let x = intersect(&a, &b, EPS);
        assert_eq!(x.len(), 2);
        for (p, _, _) in &x {
            assert!((p.x - 3.0).abs() < 1e-12 && (p.y.abs() - 4.0).abs() < 1e-12);
        }
        let touching = Piece::Arc(Arc::circle(v(10.0, 0.0), 5.0, true));
        let x = intersect(&a, &touching, EPS);
        assert_eq!(x.len(), 1);
        assert!((x[0].0 - v(5.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn arcs_split_and_keep_area() {
        let c = Piece::Arc(Arc::circle(v(1.0, 2.0), 3.0, true));
        let full = c.area2() / 2.0;
        assert!((full - PI * 9.0).abs() < 1e-12);
        let mut hits = vec![
            (1.0, on_circle(v(1.0, 2.0), 3.0, 1.0)),
            (4.0, on_circle(v(1.0, 2.0), 3.0, 4.0)),
        ];
        let parts = split(&c, &mut hits, EPS);
        assert_eq!(parts.len(), 2);
        let sum: f64 = parts.iter().map(|p| p.area2()).sum::<f64>() / 2.0;
        assert!((sum - full).abs() < 1e-12);
        assert_eq!(parts[0].end(), parts[1].start());
        assert_eq!(parts[1].end(), parts[0].start());
        // reversing negates the area
        assert!((parts[0].reversed().area2() + parts[0].area2()).abs() < 1e-12);
    }

    #[test]
    fn distance_to_arc_uses_the_ends_outside_its_angle() {
        let k = Arc {
            c: v(0.0, 0.0),
            r: 1.0,
            a0: 0.0,
            sweep: PI / 2.0,
            p0: v(1.0, 0.0),
            p1: v(0.0, 1.0),
        };
        let p = Piece::Arc(k);
        assert!((p.distance(v(2.0, 2.0)) - (8f64.sqrt() - 1.0)).abs() < 1e-12);
        assert!((p.distance(v(0.0, -1.0)) - 2f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn chord_count_meets_the_tolerance() {
        for &(r, tol) in &[(8.0, 0.01), (0.5, 0.01), (100.0, 0.001), (0.001, 0.01)] {
            let n = chords(r, TAU, tol);
            let theta = TAU / n as f64;
            let sag = r * (1.0 - libm::cos(theta / 2.0));
            assert!(
                sag <= tol * (1.0 + 1e-12),
                "r {r}: {n} chords, sagitta {sag}"
            );
            assert!(n >= 4);
        }
    }
}
