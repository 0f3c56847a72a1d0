//! The skirt: loops around the parts' footprint, printed first to prime the
//! nozzle (Kanada's Fig. 9 prints one at r = 30 around the r = 25 sphere).
//!
//! The footprint is the convex hull of the parts' extruding points seen from
//! above; loop k is that hull offset outwards by `distance + k·w` (w the
//! nozzle diameter), corners rounded with arcs, at the parts' lowest height.

use glam::{DVec2, DVec3};

use crate::base::error::{Error, Result};
use crate::base::toolpath::Toolpath;
use crate::generate::model::Skirt;

#[cfg(test)]
/// Convex hull of `pts`, counter-clockwise, by Andrew's monotone chain.
pub(crate) fn convex_hull(pts: Vec<DVec2>) -> Vec<DVec2> {
    hull_of(near_outline(|| pts.iter().copied()))
}

/// [`convex_hull`] of all of `pts`.
fn hull_of(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    // unstable is the same order: two points equal under `total_cmp` on
    // both axes have the same bits
    pts.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::with_capacity(pts.len() + 1);
    let n = pts.len();
    for pass in 0..2 {
        let start = hull.len();
        for i in 0..n {
            // the lower chain left to right, then the upper right to left
            let p = pts[if pass == 0 { i } else { n - 1 - i }];
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// The points of `points()` (called twice: it gives the same points each
/// time) that do not lie well inside the octagon of its extreme points (the
/// largest and smallest x, y, x + y and x − y): no point well inside is a
/// corner of the hull, so the hull of those left is the same, and sorting
/// them (the points near the outline) is the hull's cost (Akl and
/// Toussaint's heuristic; the sphere's skirt sorted all 15,000 points, and
/// gathering them into a list first was as slow again). "Well inside" is
/// more than 1e-9 × the octagon's size from each of its sides, far more
/// than the rounding of the sides' cross products.
fn near_outline<I: Iterator<Item = DVec2>>(points: impl Fn() -> I) -> Vec<DVec2> {
    let Some((score, best, n)) = extremes(points()) else {
        return Vec::new();
    };
    if n < 64 || !score.iter().all(|s| s.is_finite()) {
        return points().collect();
    }
    let Some(octagon) = Octagon::new(&best) else {
        return points().collect();
    };
    points().filter(|&p| !octagon.well_inside(p)).collect()
}

/// A point's coordinate along the directions 0°, 45°, …, 315°.
fn along(p: DVec2) -> [f64; 8] {
    [
        p.x,
        p.x + p.y,
        p.y,
        p.y - p.x,
        -p.x,
        -p.x - p.y,
        -p.y,
        p.x - p.y,
    ]
}

/// The largest coordinate of `points` along each direction of [`along`],
/// the first point that reaches it (the octagon's corners, counter-clockwise;
/// two may be the same point), and how many points there are; None for none.
fn extremes(mut points: impl Iterator<Item = DVec2>) -> Option<([f64; 8], [DVec2; 8], usize)> {
    let first = points.next()?;
    let mut score = along(first);
    let mut best = [first; 8];
    let mut n = 1;
    for p in points {
        let v = along(p);
        for k in 0..8 {
            if v[k] > score[k] {
                (score[k], best[k]) = (v[k], p);
            }
        }
        n += 1;
    }
    Some((score, best, n))
}

/// The octagon of a point set's extreme points (see [`near_outline`]),
/// shrunk by a margin of 1e-9 × its size.
struct Octagon {
    /// Each side as (start, direction, the least cross product of a point
    /// well inside: its length times the margin).
    sides: Vec<(DVec2, DVec2, f64)>,
    /// A box well inside, between the west, east, south and north corners:
    /// a first, cheaper test.
    inner: Option<(DVec2, DVec2)>,
}

impl Octagon {
    /// The octagon of the extreme points `best` (in the order of [`along`]);
    /// None when fewer than 3 of them differ.
    fn new(best: &[DVec2; 8]) -> Option<Octagon> {
        let mut corners: Vec<DVec2> = Vec::with_capacity(8);
        for &p in best {
            if corners.last() != Some(&p) {
                corners.push(p);
            }
        }
        while corners.len() > 1 && corners.first() == corners.last() {
            corners.pop();
        }
        if corners.len() < 3 {
            return None;
        }
        let size = (best[0].x - best[4].x).max(best[2].y - best[6].y);
        let margin = size * 1e-9;
        let sides = (0..corners.len())
            .map(|i| {
                let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
                (a, b - a, (b - a).length() * margin)
            })
            .collect();
        let mut octagon = Octagon { sides, inner: None };
        // the box is taken only when its corners are well inside (so all
        // of it is: the octagon less its margin is convex)
        let (lo, hi) = (
            DVec2::new(
                best[3].x.max(best[4].x).max(best[5].x),
                best[5].y.max(best[6].y).max(best[7].y),
            ) + margin,
            DVec2::new(
                best[7].x.min(best[0].x).min(best[1].x),
                best[1].y.min(best[2].y).min(best[3].y),
            ) - margin,
        );
        let boxed = lo.cmplt(hi).all()
            && [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)]
                .into_iter()
                .all(|p| octagon.inside(p));
        if boxed {
            octagon.inner = Some((lo, hi));
        }
        Some(octagon)
    }

    /// Whether `p` lies well inside every side: left of it by more than
    /// the side's least cross product.
    fn inside(&self, p: DVec2) -> bool {
        self.sides
            .iter()
            .all(|&(a, d, least)| d.perp_dot(p - a) > least)
    }

    /// Whether `p` lies well inside: in the inner box, or inside every side.
    fn well_inside(&self, p: DVec2) -> bool {
        let in_box = self
            .inner
            .is_some_and(|(lo, hi)| p.cmpgt(lo).all() && p.cmplt(hi).all());
        in_box || self.inside(p)
    }
}

/// The hull offset outwards by `d`, corners as arcs of at most 10°.
fn offset(hull: &[DVec2], d: f64) -> Vec<DVec2> {
    let step = 10f64.to_radians();
    if hull.len() == 1 {
        let n = 36;
        return (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                hull[0] + DVec2::new(libm::cos(a), libm::sin(a)) * d
            })
            .collect();
    }
    let n = hull.len();
    let normal = |a: DVec2, b: DVec2| {
        let t = (b - a).normalize();
        DVec2::new(t.y, -t.x) // outward for a counter-clockwise hull
    };
    let mut out = Vec::new();
    for i in 0..n {
        let (prev, cur, next) = (hull[(i + n - 1) % n], hull[i], hull[(i + 1) % n]);
        let a0 = normal(prev, cur).to_angle();
        let mut a1 = normal(cur, next).to_angle();
        while a1 < a0 {
            a1 += std::f64::consts::TAU;
        }
        let k = ((a1 - a0) / step).ceil().max(1.0) as usize;
        for j in 0..=k {
            let a = a0 + (a1 - a0) * j as f64 / k as f64;
            out.push(cur + DVec2::new(libm::cos(a), libm::sin(a)) * d);
        }
    }
    out.dedup_by(|a, b| a.distance(*b) < 1e-9);
    out
}

/// The skirt around `parts`, or `None` when they extrude nothing; an error
/// (with no place: the caller names the key) when it would have more than
/// `max_strings` strings.
pub(crate) fn make(
    skirt: &Skirt,
    parts: &[Toolpath],
    spacing: f64,
    (c, v): (f64, f64),
    max_strings: u64,
) -> Result<Option<Toolpath>> {
    // the extruding strings' ends (a string's start is the string before's
    // end: given once), seen from above, and their heights
    let ends = || {
        parts.iter().flat_map(|tp| {
            (0..tp.len())
                .filter(|&k| !tp.strings[k].travel)
                .flat_map(move |k| {
                    let joined = k > 0 && !tp.strings[k - 1].travel;
                    let (a, b) = tp.ends(k);
                    (!joined).then_some(a).into_iter().chain([b])
                })
        })
    };
    let (z, any) = ends().fold((f64::INFINITY, false), |(z, _), p| (z.min(p.z), true));
    if !any {
        return Ok(None);
    }
    let near = near_outline(|| ends().map(|p| p.truncate()));
    let hull = hull_of(near);
    // every loop has about as many strings as the first
    let per_loop = offset(&hull, skirt.distance.max(spacing)).len() as u64 + 1;
    if per_loop * skirt.loops as u64 > max_strings {
        return Err(Error::input(
            "",
            format!(
                "{} loops of about {per_loop} strings each exceed the limit of {max_strings} strings; expected fewer loops",
                skirt.loops
            ),
        ));
    }
    let mut tp: Option<Toolpath> = None;
    for k in 0..skirt.loops {
        let d = skirt.distance + spacing * k as f64;
        let ring = if d > 0.0 {
            offset(&hull, d)
        } else {
            hull.clone()
        };
        let at = |p: DVec2| DVec3::new(p.x, p.y, z);
        let t = tp.get_or_insert_with(|| Toolpath::new(at(ring[0])));
        if k > 0 {
            t.travel(at(ring[0]), v);
        }
        for p in ring.iter().skip(1).chain(std::iter::once(&ring[0])) {
            t.draw(at(*p), c, v);
        }
    }
    let Some(mut tp) = tp else { return Ok(None) };
    tp.name = "skirt".into();
    Ok(Some(tp))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_square_with_inside_points() {
        let pts = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
            DVec2::new(0.5, 0.5),
        ];
        let h = convex_hull(pts);
        assert_eq!(h.len(), 4);
    }

    #[test]
    fn dropping_inner_points_keeps_the_hull() {
        let mut rng = crate::base::rng::SplitMix64::new(21);
        let mut u = || rng.uniform();
        let clouds: Vec<Vec<DVec2>> = vec![
            // a disc, a helix seen from above, a thin sliver, a square grid
            // (many points on the octagon's sides), a segment
            (0..5000)
                .map(|_| DVec2::new(u() - 0.5, u() - 0.5) * 80.0)
                .collect(),
            (0..20000)
                .map(|k| {
                    let a = k as f64 * 0.0123;
                    DVec2::new(libm::cos(a), libm::sin(a)) * (25.0 - k as f64 * 1e-3)
                })
                .collect(),
            (0..3000)
                .map(|_| DVec2::new(u() * 100.0, 50.0 + (u() - 0.5) * 1e-3))
                .collect(),
            (0..4096)
                .map(|k| DVec2::new((k % 64) as f64, (k / 64) as f64) * 0.5)
                .collect(),
            (0..100).map(|k| DVec2::splat(k as f64)).collect(),
            // thinner than the margin: nothing is dropped
            (0..3000)
                .map(|_| DVec2::new(u() * 100.0, 50.0 + (u() - 0.5) * 1e-8))
                .collect(),
        ];
        for (i, pts) in clouds.into_iter().enumerate() {
            let kept = near_outline(|| pts.iter().copied());
            assert!(
                i >= 4 || kept.len() < pts.len(),
                "cloud {i} dropped nothing"
            );
            assert_eq!(hull_of(kept), hull_of(pts), "cloud {i}");
        }
    }

    #[test]
    fn skirt_keeps_its_distance() {
        let mut part = Toolpath::new(DVec3::new(-5.0, -5.0, 0.3));
        part.draw(DVec3::new(5.0, -5.0, 0.3), 0.1, 10.0);
        part.draw(DVec3::new(5.0, 5.0, 0.3), 0.1, 10.0);
        part.draw(DVec3::new(-5.0, 5.0, 0.3), 0.1, 10.0);
        let sk = Skirt {
            distance: 3.0,
            loops: 2,
        };
        // two loops of about 40 strings do not fit in 10
        assert!(make(&sk, &[part.clone()], 0.4, (0.1, 20.0), 10).is_err());
        let s = make(&sk, &[part], 0.4, (0.1, 20.0), 1000).unwrap().unwrap();
        // every skirt point is 3 or 3.4 mm from the square
        for p in &s.points {
            let q = DVec2::new(p.x.abs() - 5.0, p.y.abs() - 5.0);
            let d = q.max(DVec2::ZERO).length() + q.x.max(q.y).min(0.0);
            assert!((d - 3.0).abs() < 1e-9 || (d - 3.4).abs() < 1e-9, "{d}");
            assert_eq!(p.z, 0.3);
        }
        assert_eq!(s.strings.iter().filter(|s| s.travel).count(), 1);
    }
}
