//! Exact plane regions bounded by loops of segments and arcs: booleans of
//! feature cross-sections, areas, point tests, islands and scanline crossings.
//!
//! Every region here is made by one procedure, the *overlay*: take every
//! curve that might bound the result (the features' edges and circles for a
//! boolean, offset curves for an offset), split each at every point where it
//! meets another (closed-form intersections, [`super::piece::intersect`]),
//! classify each split piece by its midpoint (is the result on its left, on
//! its right, or on both or neither sides?), keep the pieces with the result
//! on exactly one side, turned so that it lies on their left, and chain them
//! into closed loops. Outer loops then run counter-clockwise, holes clockwise,
//! and the signed areas add up to the region's area.

use glam::DVec2;

use super::piece::{cross, intersect, perp, split, Arc, Piece};

/// A closed loop of pieces, the region on its left.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Loop {
    /// The pieces in order; each ends where the next starts.
    pub(crate) pieces: Vec<Piece>,
}

impl Loop {
    /// Signed area: positive for an outer loop (counter-clockwise), negative
    /// for a hole (clockwise).
    pub(crate) fn area(&self) -> f64 {
        self.pieces.iter().map(Piece::area2).sum::<f64>() * 0.5
    }

    /// Length, mm.
    pub(crate) fn length(&self) -> f64 {
        self.pieces.iter().map(Piece::length).sum()
    }

    /// The loop as a closed polyline (last point = first point), each arc cut
    /// into chords that stray at most `tol` from it (see [`super::piece::chords`]).
    pub(crate) fn discretise(&self, tol: f64) -> Vec<DVec2> {
        let mut pts = Vec::new();
        for p in &self.pieces {
            pts.push(p.start());
            if let Piece::Arc(k) = p {
                let n = super::piece::chords(k.r, k.sweep, tol);
                for i in 1..n {
                    pts.push(k.at(k.sweep.abs() * i as f64 / n as f64));
                }
            }
        }
        if let Some(&first) = pts.first() {
            pts.push(first);
        }
        pts
    }

    /// Whether `p` lies inside this loop alone (crossing parity).
    pub(crate) fn encloses(&self, p: DVec2) -> bool {
        let n = DVec2::new(0.0, 1.0);
        let monos = monotone(std::slice::from_ref(self), n);
        crossings(&monos, n, p.y)
            .iter()
            .filter(|c| c.0 > p.x)
            .count()
            % 2
            == 1
    }
}

/// A region: outer loops counter-clockwise, holes clockwise, none crossing.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Region {
    /// The loops.
    pub(crate) loops: Vec<Loop>,
}

impl Region {
    /// Area, mm² (outer loops minus holes).
    pub(crate) fn area(&self) -> f64 {
        self.loops.iter().map(Loop::area).sum()
    }

    /// Whether the region is empty.
    pub(crate) fn is_empty(&self) -> bool {
        self.loops.is_empty()
    }

    /// Whether `p` lies inside (crossing parity over all loops).
    pub(crate) fn contains(&self, p: DVec2) -> bool {
        let n = DVec2::new(0.0, 1.0);
        let monos = monotone(&self.loops, n);
        crossings(&monos, n, p.y)
            .iter()
            .filter(|c| c.0 > p.x)
            .count()
            % 2
            == 1
    }

    /// Distance tolerance for this region's geometry: 1e-9 of its size.
    pub(crate) fn eps(&self) -> f64 {
        eps_for(self.loops.iter().flat_map(|l| l.pieces.iter()))
    }

    /// The connected pieces, in the order their outer loops were found: each
    /// outer loop with the holes inside it (a hole belongs to the smallest
    /// outer loop around it).
    pub(crate) fn islands(&self) -> Vec<Region> {
        let outers: Vec<(usize, f64)> = self
            .loops
            .iter()
            .enumerate()
            .filter(|(_, l)| l.area() > 0.0)
            .map(|(k, l)| (k, l.area()))
            .collect();
        let mut out: Vec<Region> = outers
            .iter()
            .map(|&(k, _)| Region {
                loops: vec![self.loops[k].clone()],
            })
            .collect();
        // smallest outer first, to find the innermost one around a hole
        let mut by_size: Vec<usize> = (0..outers.len()).collect();
        by_size.sort_by(|&a, &b| outers[a].1.total_cmp(&outers[b].1).then(a.cmp(&b)));
        for hole in self.loops.iter().filter(|l| l.area() <= 0.0) {
            let probe = hole.pieces[0].midpoint();
            if let Some(&i) = by_size
                .iter()
                .find(|&&i| self.loops[outers[i].0].encloses(probe))
            {
                out[i].loops.push(hole.clone());
            }
        }
        out
    }
}

/// 1e-9 of the size of some geometry (at least 1e-9 mm): the distance under
/// which two computed points are the same point. Rounding in the closed-form
/// intersections is about 1e-15 of the size, far below it; features are
/// never meant to be closer than it.
pub(crate) fn eps_for<'a>(pieces: impl Iterator<Item = &'a Piece>) -> f64 {
    let mut s: f64 = 1.0;
    for p in pieces {
        let [lo, hi] = p.bbox(0.0);
        s = s.max(lo.abs().max_element()).max(hi.abs().max_element());
    }
    1e-9 * s
}

/// What to do with a split piece: keep it as it runs, keep it reversed, or drop it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Keep {
    /// The result lies on its left.
    Forward,
    /// The result lies on its right.
    Reverse,
    /// The result lies on both sides or neither.
    Drop,
}

/// The overlay (see the module comment): splits `candidates` at their mutual
/// intersections, keeps each split piece as `classify` says, and chains the
/// kept pieces into loops.
pub(crate) fn overlay(candidates: &[Piece], eps: f64, classify: impl Fn(&Piece) -> Keep) -> Region {
    let n = candidates.len();
    let boxes: Vec<[DVec2; 2]> = candidates.iter().map(|p| p.bbox(eps)).collect();
    let mut hits: Vec<Vec<(f64, DVec2)>> = vec![Vec::new(); n];
    for i in 0..n {
        for j in i + 1..n {
            let (a, b) = (boxes[i], boxes[j]);
            if a[1].x < b[0].x || b[1].x < a[0].x || a[1].y < b[0].y || b[1].y < a[0].y {
                continue;
            }
            for (x, s, t) in intersect(&candidates[i], &candidates[j], eps) {
                hits[i].push((s, x));
                hits[j].push((t, x));
            }
        }
    }
    let mut kept = Vec::new();
    for (p, h) in candidates.iter().zip(hits.iter_mut()) {
        for sub in split(p, h, eps) {
            match classify(&sub) {
                Keep::Forward => kept.push(sub),
                Keep::Reverse => kept.push(sub.reversed()),
                Keep::Drop => {}
            }
        }
    }
    chain(kept, eps)
}

/// Chains oriented pieces into closed loops.
///
/// End points within `eps` become one vertex, and every piece takes that
/// vertex's exact coordinates, so neighbouring pieces share their end points
/// bit for bit (the scanline rule in [`crossings`] relies on it). Pieces of
/// zero length go; a piece given twice counts once; a piece and its reverse
/// (a zero-width sliver) cancel. Where several pieces leave one vertex (two
/// loops touching at a point), the walk takes the sharpest left turn, which
/// keeps each loop around one wedge of the region, so loops never cross.
/// Loops thinner than 10·eps (area / length) are slivers and go.
pub(crate) fn chain(pieces: Vec<Piece>, eps: f64) -> Region {
    let (items, nverts) = snap_ends(pieces, eps);
    let alive = survivors(&items, eps);
    let mut out: Vec<usize> = Vec::new();
    let mut outgoing: Vec<Vec<usize>> = vec![Vec::new(); nverts];
    let mut loops = Vec::new();
    for (k, (p, s, _)) in items.iter().enumerate() {
        if !alive[k] {
            continue;
        }
        if p.is_full() {
            loops.push(Loop { pieces: vec![*p] });
        } else {
            outgoing[*s].push(k);
            out.push(k);
        }
    }
    let mut used = vec![false; items.len()];
    for &first in &out {
        if used[first] {
            continue;
        }
        used[first] = true;
        if let Some(pieces) = walk_loop(&items, &outgoing, &mut used, first) {
            loops.push(Loop { pieces });
        }
    }
    loops.retain(|l| l.area().abs() > 10.0 * eps * l.length());
    Region { loops }
}

/// A piece of [`chain`] and the vertices it starts and ends at.
type Edge = (Piece, usize, usize);

/// The pieces with their end points merged into vertices (an end within
/// `eps` of a vertex met before is that vertex) and moved onto them
/// exactly, less the pieces of zero length; and how many vertices there are.
fn snap_ends(pieces: Vec<Piece>, eps: f64) -> (Vec<Edge>, usize) {
    let mut verts: Vec<DVec2> = Vec::new();
    let mut vid = |p: DVec2| -> usize {
        if let Some(k) = verts.iter().position(|v| v.distance(p) <= eps) {
            k
        } else {
            verts.push(p);
            verts.len() - 1
        }
    };
    let mut items: Vec<Edge> = Vec::with_capacity(pieces.len());
    for p in pieces {
        let (s, e) = (vid(p.start()), vid(p.end()));
        if s == e && !p.is_full() {
            continue;
        }
        if p.length() <= eps {
            continue;
        }
        items.push((p, s, e));
    }
    let items = items
        .into_iter()
        .map(|(p, s, e)| (p.with_ends(verts[s], verts[e]), s, e))
        .collect();
    (items, verts.len())
}

/// Which of `items` stay: of two pieces between the same vertices whose
/// midpoints lie within 10·eps, the second goes when both run the same way
/// (a duplicate), and both go when they run opposite ways (a sliver).
fn survivors(items: &[Edge], eps: f64) -> Vec<bool> {
    let mut alive = vec![true; items.len()];
    for i in 0..items.len() {
        if !alive[i] {
            continue;
        }
        for j in i + 1..items.len() {
            if !alive[j] {
                continue;
            }
            let (pi, si, ei) = &items[i];
            let (pj, sj, ej) = &items[j];
            let same_ends = (si == sj && ei == ej) || (si == ej && ei == sj);
            if !same_ends || pi.midpoint().distance(pj.midpoint()) > 10.0 * eps {
                continue;
            }
            if pi.tangent_mid().dot(pj.tangent_mid()) > 0.0 {
                alive[j] = false;
            } else {
                alive[i] = false;
                alive[j] = false;
                break;
            }
        }
    }
    alive
}

/// Follows the pieces from `first` (the unused ones leaving each vertex,
/// `outgoing`), taking the sharpest left turn at each, until the walk comes
/// back to `first`: the loop's pieces, marked `used`; None for a chain that
/// does not close (numerically inconsistent; dropped).
fn walk_loop(
    items: &[Edge],
    outgoing: &[Vec<usize>],
    used: &mut [bool],
    first: usize,
) -> Option<Vec<Piece>> {
    let mut chain = vec![first];
    loop {
        let cur = *chain.last().unwrap();
        let v = items[cur].2;
        let tin = items[cur].0.tangent_end();
        // candidates: unused pieces leaving v, and closing the loop
        let leaving = outgoing[v].iter().copied().filter(|&k| !used[k]);
        let closing = (v == items[first].1).then_some(first);
        match sharpest_left(items, tin, leaving.chain(closing)) {
            Some(k) if k == first => return Some(chain.iter().map(|&k| items[k].0).collect()),
            Some(k) => {
                used[k] = true;
                chain.push(k);
            }
            None => return None,
        }
    }
}

/// Of the pieces `candidates`, in order, the one that turns most to the
/// left from the incoming tangent `tin`: the largest turn
/// atan2(tin × tout, tin · tout) by more than 1e-9, or within 1e-9 of it,
/// the more curved piece; the first of equals.
fn sharpest_left(
    items: &[Edge],
    tin: DVec2,
    candidates: impl Iterator<Item = usize>,
) -> Option<usize> {
    let mut best: Option<(usize, f64, f64)> = None;
    for k in candidates {
        let p = &items[k].0;
        let tout = p.tangent_start();
        let turn = libm::atan2(cross(tin, tout), tin.dot(tout));
        let curv = p.curvature();
        let better = match best {
            None => true,
            Some((_, bt, bc)) => turn > bt + 1e-9 || ((turn - bt).abs() <= 1e-9 && curv > bc),
        };
        if better {
            best = Some((k, turn, curv));
        }
    }
    best.map(|(k, _, _)| k)
}

/// A piece along which f(p) = p·n only rises or only falls, with f at its ends.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mono {
    /// The piece.
    pub(crate) piece: Piece,
    /// f at the start.
    pub(crate) f0: f64,
    /// f at the end.
    pub(crate) f1: f64,
}

/// The loops' pieces cut where f(p) = p·n (n a unit vector) is extreme, so
/// that every piece is monotone in f: segments already are; an arc is cut at
/// c + r·n and c − r·n, the points where its tangent is parallel to the
/// scanlines f = const.
pub(crate) fn monotone(loops: &[Loop], n: DVec2) -> Vec<Mono> {
    let mut out = Vec::new();
    let alpha = libm::atan2(n.y, n.x);
    for l in loops {
        for p in &l.pieces {
            match p {
                Piece::Line(a, b) => out.push(Mono {
                    piece: *p,
                    f0: a.dot(n),
                    f1: b.dot(n),
                }),
                Piece::Arc(k) => {
                    let tol = 1e-12;
                    let end = k.sweep.abs();
                    let mut cuts: Vec<(f64, DVec2)> = [
                        (alpha, k.c + n * k.r),
                        (alpha + std::f64::consts::PI, k.c - n * k.r),
                    ]
                    .iter()
                    .map(|&(phi, x)| (k.offset_of(phi, tol), x))
                    .filter(|&(t, _)| t > tol && t < end - tol)
                    .collect();
                    cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
                    let mut prev = (0.0, k.p0);
                    cuts.push((end, k.p1));
                    for c in cuts {
                        let q = p.sub(prev.0, prev.1, c.0, c.1);
                        out.push(Mono {
                            piece: q,
                            f0: prev.1.dot(n),
                            f1: c.1.dot(n),
                        });
                        prev = c;
                    }
                }
            }
        }
    }
    out
}

/// Where the scanline f(p) = p·n = s crosses the monotone pieces, as
/// (position along u = n turned clockwise, point), sorted along the line.
///
/// The paper counts a scanline's intersections and, when the count is odd,
/// looks for the profile corner the line passes through, to join the points
/// "in such a way that gaps and this point are avoided". Here the count is
/// even by construction (symbolic perturbation): a point with f = s counts as
/// lying above the line, so a piece crosses exactly when its two ends fall on
/// different sides. A line through a corner where the boundary passes across
/// it crosses once there (one piece ends on it, the next starts on it, only
/// one changes side); a corner or an arc that only touches the line gives two
/// crossings at the same point (a zero-length span, dropped by the caller) or
/// none. Neighbouring pieces share their end points bit for bit, so the two
/// sides of a corner always agree.
pub(crate) fn crossings(monos: &[Mono], n: DVec2, s: f64) -> Vec<(f64, DVec2)> {
    let u = DVec2::new(n.y, -n.x);
    let mut out = Vec::new();
    for m in monos {
        let (above0, above1) = (m.f0 >= s, m.f1 >= s);
        if above0 == above1 {
            continue;
        }
        let (a, b) = (m.piece.start(), m.piece.end());
        // a vertex on the line is taken as it is; otherwise the point is
        // s·n + t·u, on the scanline by construction (exactly, when the lines
        // are axis-parallel), with t from the paper's eq. 5 or eq. 7
        let x = if m.f0 == s {
            a
        } else if m.f1 == s {
            b
        } else {
            let t = match m.piece {
                Piece::Line(..) => {
                    let (ta, tb) = (a.dot(u), b.dot(u));
                    ta + (tb - ta) * ((s - m.f0) / (m.f1 - m.f0))
                }
                Piece::Arc(k) => arc_crossing(&k, n, u, s),
            };
            n * s + u * t
        };
        out.push((x.dot(u), x));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// Where a monotone arc meets the scanline p = s·n + t·u: on its circle,
/// (s − c·n)² + (t − c·u)² = r², so t = c·u ± √(r² − (s − c·n)²); the sign
/// is the side of the centre (along u) the arc lies on.
fn arc_crossing(k: &Arc, n: DVec2, u: DVec2, s: f64) -> f64 {
    let q = s - k.c.dot(n);
    let h = ((k.r - q) * (k.r + q)).max(0.0).sqrt();
    let mid = Piece::Arc(*k).midpoint();
    if (mid - k.c).dot(u) >= 0.0 {
        k.c.dot(u) + h
    } else {
        k.c.dot(u) - h
    }
}

/// A feature's cross-section in one horizontal plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Shape {
    /// An axis-aligned rectangle.
    Rect {
        /// Lowest corner.
        min: DVec2,
        /// Highest corner.
        max: DVec2,
    },
    /// A disc.
    Disc {
        /// Centre.
        c: DVec2,
        /// Radius.
        r: f64,
    },
}

/// How a feature combines with the features before it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Op {
    /// Adds material.
    Union,
    /// Removes material.
    Subtract,
    /// Keeps only the material also inside this feature.
    Intersect,
}

impl Shape {
    /// Its boundary, counter-clockwise (inside on the left).
    pub(crate) fn boundary(&self) -> Vec<Piece> {
        match *self {
            Shape::Rect { min, max } => {
                let c = [min, DVec2::new(max.x, min.y), max, DVec2::new(min.x, max.y)];
                (0..4).map(|k| Piece::Line(c[k], c[(k + 1) % 4])).collect()
            }
            Shape::Disc { c, r } => vec![Piece::Arc(Arc::circle(c, r, true))],
        }
    }

    /// Whether the shape holds the points just left and just right of a
    /// piece passing through `m` with left normal `nl`. Off the boundary
    /// (farther than `eps`), both sides agree; on it, the side the shape's
    /// inward normal points to is inside.
    fn sides(&self, m: DVec2, nl: DVec2, eps: f64) -> (bool, bool) {
        let (g, inward) = match *self {
            Shape::Rect { min, max } => {
                let c = (min + max) * 0.5;
                let h = (max - min) * 0.5;
                let d = m - c;
                let gx = d.x.abs() - h.x;
                let gy = d.y.abs() - h.y;
                let inward = if gx > gy {
                    DVec2::new(-d.x.signum(), 0.0)
                } else {
                    DVec2::new(0.0, -d.y.signum())
                };
                (gx.max(gy), inward)
            }
            Shape::Disc { c, r } => {
                let v = c - m;
                let l = v.length();
                (l - r, if l > 0.0 { v / l } else { DVec2::ZERO })
            }
        };
        if g < -eps {
            (true, true)
        } else if g > eps {
            (false, false)
        } else {
            let d = nl.dot(inward);
            if d > 1e-9 {
                (true, false)
            } else if d < -1e-9 {
                (false, true)
            } else {
                // across the boundary at its midpoint: cannot happen once
                // pieces are split at every meeting point; count it outside
                (false, false)
            }
        }
    }
}

/// Evaluates the features' boolean: in order, union adds, subtract removes,
/// intersect keeps the common part; `inside(k)` says whether feature k holds
/// the point.
pub(crate) fn evaluate(ops: &[Op], inside: impl Fn(usize) -> bool) -> bool {
    let mut r = false;
    for (k, op) in ops.iter().enumerate() {
        r = match op {
            Op::Union => r || inside(k),
            Op::Subtract => r && !inside(k),
            Op::Intersect => r && inside(k),
        };
    }
    r
}

/// The exact boolean of the shapes (a shape `None` is absent at this height
/// and holds no point), applied in order.
///
/// Classification of a split piece with midpoint m and left normal n: for
/// every shape, whether it holds the points m + δn and m − δn as δ → 0 (see
/// [`Shape::sides`]); the boolean on each side; the piece bounds the result
/// when the two differ. Pieces of two features that coincide (boxes sharing
/// an edge) are classified alike and kept once.
pub(crate) fn boolean(shapes: &[(Option<Shape>, Op)]) -> Region {
    let mut cands = Vec::new();
    for (s, _) in shapes {
        if let Some(s) = s {
            cands.extend(s.boundary());
        }
    }
    if cands.is_empty() {
        return Region::default();
    }
    let eps = eps_for(cands.iter());
    let ops: Vec<Op> = shapes.iter().map(|s| s.1).collect();
    overlay(&cands, eps, |p| {
        let m = p.midpoint();
        let nl = perp(p.tangent_mid());
        let sides: Vec<(bool, bool)> = shapes
            .iter()
            .map(|(s, _)| s.map_or((false, false), |s| s.sides(m, nl, eps)))
            .collect();
        let left = evaluate(&ops, |k| sides[k].0);
        let right = evaluate(&ops, |k| sides[k].1);
        match (left, right) {
            (true, false) => Keep::Forward,
            (false, true) => Keep::Reverse,
            _ => Keep::Drop,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Option<Shape> {
        Some(Shape::Rect {
            min: DVec2::new(x0, y0),
            max: DVec2::new(x1, y1),
        })
    }

    fn disc(x: f64, y: f64, r: f64) -> Option<Shape> {
        Some(Shape::Disc {
            c: DVec2::new(x, y),
            r,
        })
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1e-300)
    }

    #[test]
    fn box_minus_disc_is_exact() {
        let r = boolean(&[
            (rect(-20.0, -15.0, 20.0, 15.0), Op::Union),
            (disc(0.0, 0.0, 8.0), Op::Subtract),
        ]);
        assert_eq!(r.loops.len(), 2);
        assert!(rel(r.area(), 1200.0 - PI * 64.0) < 1e-12, "{}", r.area());
        assert_eq!(r.islands().len(), 1);
        assert!(r.contains(DVec2::new(15.0, 0.0)));
        assert!(!r.contains(DVec2::new(1.0, 1.0)));
        assert!(!r.contains(DVec2::new(25.0, 0.0)));
    }

    #[test]
    fn disc_crossing_the_edge_makes_a_notch_of_arc_and_lines() {
        // a disc centred on the box's right edge: half of it removed
        let r = boolean(&[
            (rect(0.0, 0.0, 10.0, 6.0), Op::Union),
            (disc(10.0, 3.0, 2.0), Op::Subtract),
        ]);
        assert_eq!(r.loops.len(), 1);
        assert!(rel(r.area(), 60.0 - PI * 2.0) < 1e-12);
        let arcs = r.loops[0]
            .pieces
            .iter()
            .filter(|p| matches!(p, Piece::Arc(_)))
            .count();
        assert_eq!(arcs, 1);
    }

    #[test]
    fn union_intersect_and_shared_edges() {
        // two boxes sharing an edge merge into one loop
        let r = boolean(&[
            (rect(0.0, 0.0, 1.0, 1.0), Op::Union),
            (rect(1.0, 0.0, 3.0, 1.0), Op::Union),
        ]);
        assert_eq!(r.loops.len(), 1);
        assert!(rel(r.area(), 3.0) < 1e-12);
        // a lens: two discs intersected
        let r = boolean(&[
            (disc(0.0, 0.0, 5.0), Op::Union),
            (disc(6.0, 0.0, 5.0), Op::Intersect),
        ]);
        let half = 25.0 * libm::acos(0.6) - 3.0 * 4.0;
        assert!(rel(r.area(), 2.0 * half) < 1e-12, "{}", r.area());
        // two discs united
        let r = boolean(&[
            (disc(0.0, 0.0, 5.0), Op::Union),
            (disc(6.0, 0.0, 5.0), Op::Union),
        ]);
        assert!(rel(r.area(), 2.0 * PI * 25.0 - 2.0 * half) < 1e-12);
        // identical boxes: union once, subtract to nothing
        let r = boolean(&[
            (rect(0.0, 0.0, 2.0, 2.0), Op::Union),
            (rect(0.0, 0.0, 2.0, 2.0), Op::Union),
        ]);
        assert_eq!(r.loops.len(), 1);
        assert!(rel(r.area(), 4.0) < 1e-12);
        let r = boolean(&[
            (rect(0.0, 0.0, 2.0, 2.0), Op::Union),
            (rect(0.0, 0.0, 2.0, 2.0), Op::Subtract),
        ]);
        assert!(r.is_empty());
    }

    #[test]
    fn boxes_touching_at_a_corner_stay_two_loops() {
        let r = boolean(&[
            (rect(0.0, 0.0, 1.0, 1.0), Op::Union),
            (rect(1.0, 1.0, 2.0, 2.0), Op::Union),
        ]);
        assert_eq!(r.loops.len(), 2);
        for l in &r.loops {
            assert!(rel(l.area(), 1.0) < 1e-12);
        }
        assert_eq!(r.islands().len(), 2);
    }

    #[test]
    fn absent_features_hold_nothing() {
        let r = boolean(&[(rect(0.0, 0.0, 4.0, 4.0), Op::Union), (None, Op::Intersect)]);
        assert!(r.is_empty());
        let r = boolean(&[(rect(0.0, 0.0, 4.0, 4.0), Op::Union), (None, Op::Subtract)]);
        assert!(rel(r.area(), 16.0) < 1e-12);
    }

    #[test]
    fn tangent_disc_inside_a_box() {
        // a hole touching the box's edge from inside: one loop pinched at a point
        let r = boolean(&[
            (rect(0.0, 0.0, 10.0, 10.0), Op::Union),
            (disc(5.0, 3.0, 3.0), Op::Subtract),
        ]);
        assert!(rel(r.area(), 100.0 - 9.0 * PI) < 1e-12, "{}", r.area());
        // a disc tangent to the outside of a box, united
        let r = boolean(&[
            (rect(0.0, 0.0, 10.0, 10.0), Op::Union),
            (disc(13.0, 5.0, 3.0), Op::Union),
        ]);
        assert!(rel(r.area(), 100.0 + 9.0 * PI) < 1e-12, "{}", r.area());
    }

    #[test]
    fn crossings_are_even_through_corners() {
        let r = boolean(&[(rect(-1.0, -1.0, 1.0, 1.0), Op::Union)]);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let n = DVec2::new(-h, h);
        let monos = monotone(&r.loops, n);
        // the diagonal through two corners
        let c = crossings(&monos, n, 0.0);
        assert_eq!(c.len(), 2);
        assert_eq!(c[0].1, DVec2::new(-1.0, -1.0));
        assert_eq!(c[1].1, DVec2::new(1.0, 1.0));
        // the line touching only the top-left corner: a zero-length pair or nothing
        let s = DVec2::new(-1.0, 1.0).dot(n);
        let c = crossings(&monos, n, s);
        assert!(c.is_empty() || (c.len() == 2 && c[0].1 == c[1].1), "{c:?}");
    }
}
