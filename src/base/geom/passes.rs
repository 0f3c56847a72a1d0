//! The passes of a polyline, found in space: for a string, the nearest point
//! of another pass (the next turn of a helix, the next ring of a spiral),
//! and from it the surface the string lies in and the spacing between
//! passes, which give a string its width (the previews draw it, the mesh
//! sweeps it).
//!
//! Neighbour. A point p at arc length s_p has as neighbour the closest point
//! q of a string within one cell of p, q at arc length s_q, with
//! |s_q − s_p| > 3·|p − q| (much farther along the path than in space), so
//! that p's own string and the strings next to it on its pass never count;
//! ties go to the lower string. Every search here returns that one point,
//! however the index is cut or searched.
//!
//! Width. A string of cross-section c laid h from the next pass fills those
//! h along the surface and is c / h thick across it; a string with no
//! neighbouring pass is round, of diameter 2·sqrt(c/π) ([`round_diameter`]).

use glam::DVec3;

use crate::base::geom::grid::{closest, cube, CellMap, SegGrid};
use crate::base::par;

/// The strings of a polyline in the shared segment grid
/// ([`crate::base::geom::grid::SegGrid`]), to find the nearest point of another
/// pass: one much farther along the path than in space (path distance over
/// 3 × straight distance), so that a point's own neighbours on its string do
/// not count.
pub(crate) struct Grid<'t> {
    points: &'t [DVec3],
    /// Arc length along the path at each point, mm.
    s: Vec<f64>,
    cell: f64,
    /// String k runs from point k to point k + 1; the strings in runs (the
    /// id of each run's first, and the run's grid, which numbers them from 0).
    strings: Vec<(usize, SegGrid)>,
}

impl<'t> Grid<'t> {
    #[cfg(test)]
    /// Files the strings of the polyline `points` in cubes of `cell` mm.
    pub(crate) fn new(points: &'t [DVec3], cell: f64) -> Grid<'t> {
        Grid::new_on(points, cell, 1)
    }

    /// [`Grid::new`] in `parts` grids of a run of strings each, built side
    /// by side on the pool ([`par::map`]). A search looks in each; the
    /// nearest point (ties going to the lower string) is the same however
    /// they are cut.
    pub(crate) fn new_on(points: &'t [DVec3], cell: f64, parts: usize) -> Grid<'t> {
        let mut s = Vec::with_capacity(points.len());
        let mut acc = 0.0;
        for (k, p) in points.iter().enumerate() {
            if k > 0 {
                let d = p.distance(points[k - 1]);
                if d.is_finite() {
                    acc += d;
                }
            }
            s.push(acc);
        }
        let n = points.len().saturating_sub(1);
        let run = n.div_ceil(parts.max(1)).max(1);
        let build = |from: usize| {
            let to = (from + run).min(n);
            let g = SegGrid::build(to - from, cell, |k| {
                (points[from + k], points[from + k + 1])
            });
            (from, g)
        };
        // the runs' first strings (one run, from 0, when there are none)
        let froms: Vec<usize> = if n <= run {
            vec![0]
        } else {
            (0..n).step_by(run).collect()
        };
        let strings = par::map(&froms, |&from| build(from));
        Grid {
            points,
            s,
            cell,
            strings,
        }
    }

    /// A grid to find the passes next to a surface whose passes lie about
    /// `h` apart: cells big enough to reach the ends of the strings nearby
    /// (longer than `h` on a coarse helix).
    pub(crate) fn for_surface(points: &'t [DVec3], h: f64) -> Grid<'t> {
        Grid::for_surface_on(points, h, 1)
    }

    /// [`Grid::for_surface`] in `parts` grids built at once ([`Grid::new_on`]).
    pub(crate) fn for_surface_on(points: &'t [DVec3], h: f64, parts: usize) -> Grid<'t> {
        let step = (points.len() / 4096).max(1);
        let mut lens: Vec<f64> = (step..points.len())
            .step_by(step)
            .map(|k| points[k].distance(points[k - 1]))
            .filter(|l| l.is_finite())
            .collect();
        lens.sort_by(f64::total_cmp);
        let l90 = lens.get(lens.len() * 9 / 10).copied().unwrap_or(0.0);
        Grid::new_on(
            points,
            (3.0 * h).max(0.6 * l90 + 1.5 * h).clamp(0.3, 4.0),
            parts,
        )
    }

    /// Arc length at point k, mm.
    pub(crate) fn arc(&self, k: usize) -> f64 {
        self.s[k]
    }

    /// The nearest point of another pass to `p` (at arc length `sp`): the
    /// closest point of the strings within one cell of `p`, or `None` when
    /// none lies that near.
    pub(crate) fn nearest_other(&self, p: DVec3, sp: f64) -> Option<DVec3> {
        self.nearest_other_near(p, sp, None).map(|(q, _)| q)
    }

    /// [`Grid::nearest_other`], and the string the point lies on, looking
    /// first at the strings around `hint` (the answer for a point nearby).
    ///
    /// The answer is the same with or without the hint: the nearest
    /// qualifying point, ties going to the lower string. The hint only
    /// narrows the search: a qualifying point d away from `p` bounds the
    /// answer's distance by d, so only the cubes within d of `p` (not within
    /// a whole cell) can hold it.
    pub(crate) fn nearest_other_near(
        &self,
        p: DVec3,
        sp: f64,
        hint: Option<usize>,
    ) -> Option<(DVec3, usize)> {
        self.nearest(p, sp, hint, false)
    }

    #[cfg(test)]
    /// The point [`Grid::nearest_other_near`] finds, or, when a string
    /// within [`HINT_REACH`] of `hint` qualifies, the nearest point of those
    /// alone: a pass followed along (the next pass of a helix stays the next
    /// pass), the whole grid searched only when it is lost.
    pub(crate) fn follow_other(&self, p: DVec3, sp: f64, hint: usize) -> Option<(DVec3, usize)> {
        self.nearest(p, sp, Some(hint), true)
    }

    fn nearest(
        &self,
        p: DVec3,
        sp: f64,
        hint: Option<usize>,
        follow: bool,
    ) -> Option<(DVec3, usize)> {
        if !p.is_finite() {
            return None;
        }
        let mut best: Option<(f64, usize, DVec3)> = None;
        let consider = |k: usize, best: &mut Option<(f64, usize, DVec3)>| {
            let (a, b) = (self.points[k], self.points[k + 1]);
            // the closest point of the string: a + f·(b − a)
            let f = closest(p, a, b);
            let q = a + (b - a) * f;
            // no root where the square shows it too far: d² beyond
            // bound²·(1 + 10⁻¹²) makes the rounded root d above the bound
            // (as far as the cell, or the best so far), which is refused below
            let bound = best.map_or(self.cell, |b| b.0.min(self.cell));
            let d2 = (p - q).length_squared();
            if d2 > bound * bound * (1.0 + 1e-12) {
                return;
            }
            let d = d2.sqrt(); // p.distance(q), bit for bit
            let sq = self.s[k] + f * (self.s[k + 1] - self.s[k]);
            // 1 µm: a point revisited (a closed loop) is no neighbour
            if d > 1e-3
                && d < self.cell
                && best.is_none_or(|b| (d, k) < (b.0, b.1))
                && (sq - sp).abs() > 3.0 * d
            {
                *best = Some((d, k, q));
            }
        };
        let n = self.points.len().saturating_sub(1);
        if let Some(h) = hint {
            for k in h.saturating_sub(HINT_REACH)..h.saturating_add(HINT_REACH + 1).min(n) {
                consider(k, &mut best);
            }
        }
        if !(follow && best.is_some()) {
            for (from, g) in &self.strings {
                let r = best.map_or(self.cell, |b| b.0);
                g.search(p, r, u32::MAX, |k| {
                    consider(from + k as usize, &mut best);
                    false
                });
            }
        }
        best.map(|(_, k, q)| (q, k))
    }

    #[cfg(test)]
    /// The surface a string from `a` to `b` lies in, told by the nearest
    /// other pass to its middle (arc length `sm`): see [`Local`].
    pub(crate) fn local(&self, a: DVec3, b: DVec3, sm: f64) -> Option<Local> {
        self.local_near(a, b, sm, None, false).map(|(l, _)| l)
    }

    /// The surface a string from `a` to `b` lies in, told by the nearest
    /// other pass to its middle (arc length `sm`, see [`Local`]), looked
    /// for first near string `hint` (see [`Grid::nearest_other_near`]: the
    /// same answer with or without it), and the neighbouring string it
    /// found; with `follow`, the neighbour [`Grid::follow_other`] finds.
    pub(crate) fn local_near(
        &self,
        a: DVec3,
        b: DVec3,
        sm: f64,
        hint: Option<usize>,
        follow: bool,
    ) -> Option<(Local, usize)> {
        let t = (b - a).normalize_or_zero();
        let m = (a + b) * 0.5;
        let (q, k) = self.nearest(m, sm, hint, follow)?;
        // the way across to the neighbour, less any part along the string
        let across = (q - m) - t * (q - m).dot(t);
        let normal = t.cross(across).normalize_or_zero();
        if t == DVec3::ZERO || normal == DVec3::ZERO {
            return None;
        }
        Some((
            Local {
                normal,
                spacing: across.length(),
            },
            k,
        ))
    }
}

/// How many strings either side of a hint [`Grid::nearest_other_near`] tries.
pub(crate) const HINT_REACH: usize = 2;

/// The wall around one string: it fills the `spacing` across to the next
/// pass along the surface, and is c / spacing thick along `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Local {
    /// Unit normal of the surface (either side).
    pub(crate) normal: DVec3,
    /// Distance across to the neighbouring pass, mm.
    pub(crate) spacing: f64,
}

/// The farthest [`pass_spacing`] looks for another pass, mm.
const REACH: f64 = 2.0;

/// Strings per piece of [`pass_spacing`]'s work.
const SPACING_PIECE: usize = 1 << 15;

/// The distance between neighbouring passes of a polyline (a helix's layer
/// height, a spiral's pitch), mm, or `None` when it has no such neighbours:
/// the median, over up to 1024 sampled points, of the distance to the nearest
/// point of another pass within [`REACH`] (as [`Grid::nearest_other`] finds
/// it), when at least 8 of them have one.
///
/// With so few points asked about, no grid of all the strings is built: the
/// cubes of 2 mm within 2.5 mm of a sampled point list it, and each string
/// is measured once against the points listed in the cubes of its pieces (at
/// most 1 mm long, so a string within 2 mm of a point has a piece whose
/// middle lies within 2.5 mm of it). The strings are measured in pieces of
/// [`SPACING_PIECE`] on the pool ([`par::map`]), each point's nearest of
/// every piece (distance, then string) the least of them all, so the same
/// however they are shared out.
pub(crate) fn pass_spacing(points: &[DVec3]) -> Option<f64> {
    let n = points.len();
    if n < 3 {
        return None;
    }
    let step = (n / 1024).max(1);
    let inv = 1.0 / REACH;
    let (samples, arcs) = spacing_samples(points, step);
    let near = Near::new(&samples, DVec3::splat(1.25 * REACH), inv);
    let firsts: Vec<usize> = (0..n - 1).step_by(SPACING_PIECE).collect();
    let pieces = par::map(&firsts, |&k0| {
        let k1 = (k0 + SPACING_PIECE).min(n - 1);
        nearest_of_piece(points, k0..k1, arcs[k0 / SPACING_PIECE], &samples, &near)
    });
    let mut best: Vec<Option<(f64, usize)>> = vec![None; samples.len()];
    for piece in pieces {
        for (slot, found) in best.iter_mut().zip(piece) {
            if let Some(x) = found.filter(|x| slot.is_none_or(|o| *x < o)) {
                *slot = Some(x);
            }
        }
    }
    let mut found: Vec<f64> = best.iter().flatten().map(|b| b.0).collect();
    if found.len() < 8 {
        return None;
    }
    found.sort_by(f64::total_cmp);
    Some(found[found.len() / 2])
}

/// Every `step`-th finite point of `points` with its arc length, and the
/// arc length at every [`SPACING_PIECE`]-th point (Σ of the finite string
/// lengths before it, summed in order).
fn spacing_samples(points: &[DVec3], step: usize) -> (Vec<(DVec3, f64)>, Vec<f64>) {
    let mut samples: Vec<(DVec3, f64)> = Vec::new();
    let mut arcs = Vec::new();
    let mut acc = 0.0;
    for (k, p) in points.iter().enumerate() {
        if k > 0 {
            let d = p.distance(points[k - 1]);
            if d.is_finite() {
                acc += d;
            }
        }
        if k.is_multiple_of(step) && p.is_finite() {
            samples.push((*p, acc));
        }
        if k.is_multiple_of(SPACING_PIECE) {
            arcs.push(acc);
        }
    }
    (samples, arcs)
}

/// Per sample, the nearest point of another pass among `strings` of
/// `points` (the first at arc length `sa`): (distance, string), the least
/// such pair, or `None`. A sample p at arc length s_p takes the closest point
/// q of a string within [`REACH`] when |s_q − s_p| > 3·|p − q| (as
/// [`Grid::nearest_other`] does) and |p − q| > 1 µm.
fn nearest_of_piece(
    points: &[DVec3],
    strings: std::ops::Range<usize>,
    mut sa: f64,
    samples: &[(DVec3, f64)],
    near: &Near,
) -> Vec<Option<(f64, usize)>> {
    let inv = 1.0 / REACH;
    let mut best: Vec<Option<(f64, usize)>> = vec![None; samples.len()];
    for k in strings {
        let (a, b) = (points[k], points[k + 1]);
        // the same sum as the samples' arc lengths: |b − a| = |a − b|, bit for bit
        let l = a.distance(b);
        let sb = if l.is_finite() { sa + l } else { sa };
        let pieces = (l * 2.0 * inv).clamp(0.0, 1e6) as usize + 1;
        let mut last = None;
        for j in 0..pieces {
            let c = cube(a.lerp(b, (j as f64 + 0.5) / pieces as f64), inv);
            if last == Some(c) {
                continue;
            }
            last = Some(c);
            for &i in near.get(c) {
                let (p, sp) = samples[i as usize];
                // as Grid::nearest_other: the closest point a + f·(b − a)
                let f = closest(p, a, b);
                let d = p.distance(a + (b - a) * f);
                let sq = sa + f * (sb - sa);
                let slot = &mut best[i as usize];
                if d > 1e-3
                    && d < REACH
                    && slot.is_none_or(|o| (d, k) < o)
                    && (sq - sp).abs() > 3.0 * d
                {
                    *slot = Some((d, k));
                }
            }
        }
        sa = sb;
    }
    best
}

/// The sampled points of [`pass_spacing`] listed (ascending) under every cube
/// within `r` of them: in an array over the cubes of their box when it has
/// at most [`Near::DENSE`] cubes (a look-up is then an index), else in a map.
enum Near {
    /// Cube (x, y, z) of the box from `lo` of `dims` cubes lists
    /// `items[starts[c]..starts[c + 1]]`, c = (x·dims[1] + y)·dims[2] + z
    /// relative to `lo`.
    Dense {
        lo: [i64; 3],
        dims: [i64; 3],
        starts: Vec<u32>,
        items: Vec<u32>,
    },
    Map(CellMap<[i64; 3], Vec<u32>>),
}

impl Near {
    /// The most cubes the array spans (2^22 + 1 starts of 4 bytes).
    const DENSE: i64 = 1 << 22;

    fn new(samples: &[(DVec3, f64)], r: DVec3, inv: f64) -> Near {
        let range = |p: DVec3| (cube(p - r, inv), cube(p + r, inv));
        let mut lo = [i64::MAX; 3];
        let mut hi = [i64::MIN; 3];
        for (p, _) in samples {
            let (a, b) = range(*p);
            for j in 0..3 {
                lo[j] = lo[j].min(a[j]);
                hi[j] = hi[j].max(b[j]);
            }
        }
        // cube coordinates are clamped to ±1e15, so these do not overflow
        let dims = [0, 1, 2].map(|j| (hi[j] - lo[j] + 1).max(0));
        let cubes = dims
            .iter()
            .try_fold(1i64, |acc, &d| acc.checked_mul(d))
            .filter(|&c| c <= Near::DENSE);
        let Some(cubes) = cubes.filter(|_| !samples.is_empty()) else {
            let mut map: CellMap<[i64; 3], Vec<u32>> = Default::default();
            for (i, (p, _)) in samples.iter().enumerate() {
                let (a, b) = range(*p);
                for x in a[0]..=b[0] {
                    for y in a[1]..=b[1] {
                        for z in a[2]..=b[2] {
                            map.entry([x, y, z]).or_default().push(i as u32);
                        }
                    }
                }
            }
            return Near::Map(map);
        };
        // counted, then filled in the order of the samples (as the map's lists)
        let mut starts = vec![0u32; cubes as usize + 1];
        let index = |x: i64, y: i64, z: i64| {
            (((x - lo[0]) * dims[1] + (y - lo[1])) * dims[2] + (z - lo[2])) as usize
        };
        let each = |f: &mut dyn FnMut(usize, usize)| {
            for (i, (p, _)) in samples.iter().enumerate() {
                let (a, b) = range(*p);
                for x in a[0]..=b[0] {
                    for y in a[1]..=b[1] {
                        for z in a[2]..=b[2] {
                            f(index(x, y, z), i);
                        }
                    }
                }
            }
        };
        each(&mut |c, _| starts[c + 1] += 1);
        for c in 1..starts.len() {
            starts[c] += starts[c - 1];
        }
        let mut items = vec![0u32; starts[cubes as usize] as usize];
        let mut next = starts.clone();
        each(&mut |c, i| {
            items[next[c] as usize] = i as u32;
            next[c] += 1;
        });
        Near::Dense {
            lo,
            dims,
            starts,
            items,
        }
    }

    /// The samples listed under cube `c`.
    #[inline]
    fn get(&self, c: [i64; 3]) -> &[u32] {
        match self {
            Near::Dense {
                lo,
                dims,
                starts,
                items,
            } => {
                let d = [0, 1, 2].map(|j| c[j] - lo[j]);
                if (0..3).any(|j| d[j] < 0 || d[j] >= dims[j]) {
                    return &[];
                }
                let k = ((d[0] * dims[1] + d[1]) * dims[2] + d[2]) as usize;
                &items[starts[k] as usize..starts[k + 1] as usize]
            }
            Near::Map(map) => map.get(&c).map_or(&[][..], |v| v),
        }
    }
}

/// The diameter of a round string of cross-section `c`, mm: how a string with
/// no neighbouring pass is drawn.
pub(crate) fn round_diameter(c: f64) -> f64 {
    2.0 * (c.max(0.0) / std::f64::consts::PI).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::toolpath::Toolpath;

    /// The median distance from every `step`-th of `points` to the nearest
    /// point of another pass, as grid `g` finds it.
    fn median_nearest(g: &Grid, points: &[DVec3], step: usize) -> f64 {
        let mut d: Vec<f64> = (0..points.len())
            .step_by(step)
            .filter_map(|i| {
                let p = points[i];
                g.nearest_other(p, g.arc(i)).map(|q| p.distance(q))
            })
            .collect();
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }

    #[test]
    fn helix_spacing_is_its_pitch() {
        // a helix of radius 10, pitch 0.3, 200 strings a turn, 20 turns
        let mut tp = Toolpath::new(DVec3::new(10.0, 0.0, 0.0));
        let n = 200 * 20;
        for i in 1..=n {
            let a = std::f64::consts::TAU * i as f64 / 200.0;
            let z = 0.3 * i as f64 / 200.0;
            tp.draw(DVec3::new(10.0 * a.cos(), 10.0 * a.sin(), z), 0.1, 30.0);
        }
        let h = pass_spacing(&tp.points).unwrap();
        assert!((h - 0.3).abs() < 0.01, "{h}");
        // the same median as asking a grid of all the strings
        let g = Grid::new(&tp.points, 2.0);
        let step = (tp.points.len() / 1024).max(1);
        assert_eq!(h, median_nearest(&g, &tp.points, step));
        // following a pass from a hint finds the nearest point too, here
        let (p, k) = (tp.points[2500], 2500);
        let exact = g.nearest_other_near(p, g.arc(k), None);
        assert_eq!(g.nearest_other_near(p, g.arc(k), Some(2300)), exact);
        let q = exact.unwrap();
        assert_eq!(g.follow_other(p, g.arc(k), q.1 + 1), exact);
        // a single straight line has no other pass
        let mut line = Toolpath::new(DVec3::ZERO);
        for i in 1..100 {
            line.draw(DVec3::new(i as f64 * 0.1, 0.0, 0.0), 0.1, 30.0);
        }
        assert_eq!(pass_spacing(&line.points), None);
        // the surface of the helix: a horizontal normal, spacing the pitch
        let g = Grid::new(&tp.points, 1.0);
        let k = 200 * 10;
        let l = g.local(tp.points[k], tp.points[k + 1], g.arc(k)).unwrap();
        assert!(l.normal.z.abs() < 1e-6, "{l:?}");
        assert!((l.spacing - 0.3).abs() < 0.01, "{l:?}");
    }

    #[test]
    fn spacing_is_measured_the_same_however_the_samples_are_listed() {
        // two helices of pitch 0.3 far apart: the samples' box spans more
        // cubes than the array takes, so they are listed in a map
        let mut tp = Toolpath::new(DVec3::new(10.0, 0.0, 0.0));
        for far in [0.0, 1e6] {
            for i in 1..=200 * 10 {
                let a = std::f64::consts::TAU * i as f64 / 200.0;
                let z = 0.3 * i as f64 / 200.0;
                tp.draw(
                    DVec3::new(far + 10.0 * a.cos(), 10.0 * a.sin(), z),
                    0.1,
                    30.0,
                );
            }
        }
        let step = (tp.points.len() / 1024).max(1);
        let samples: Vec<(DVec3, f64)> =
            tp.points.iter().step_by(step).map(|p| (*p, 0.0)).collect();
        let r = DVec3::splat(2.5);
        assert!(matches!(Near::new(&samples, r, 0.5), Near::Map(_)));
        assert!(matches!(
            Near::new(&samples[..10], r, 0.5),
            Near::Dense { .. }
        ));
        // the array lists what the map lists
        let Near::Map(map) = Near::new(&samples, r, 0.5) else {
            unreachable!()
        };
        let dense = Near::new(&samples[..500], r, 0.5);
        for (c, list) in &map {
            let want: Vec<u32> = list.iter().copied().filter(|&i| i < 500).collect();
            assert_eq!(dense.get(*c), &want[..], "{c:?}");
        }
        assert!(dense.get([1 << 40, 0, 0]).is_empty());
        // and the spacing is the median a grid of all the strings finds
        let h = pass_spacing(&tp.points).unwrap();
        assert!((h - 0.3).abs() < 0.01, "{h}");
        for parts in [1, 3] {
            let g = Grid::new_on(&tp.points, 2.0, parts);
            assert_eq!(h, median_nearest(&g, &tp.points, step));
        }
    }

    #[test]
    fn spacing_in_pieces_is_the_spacing_of_one_grid_on_any_pool() {
        // a helix of pitch 0.25 long enough for several pieces of strings
        let mut tp = Toolpath::new(DVec3::new(8.0, 0.0, 0.0));
        let n = 2 * SPACING_PIECE + 1234;
        for i in 1..=n {
            let a = std::f64::consts::TAU * i as f64 / 150.0;
            let z = 0.25 * i as f64 / 150.0;
            tp.draw(DVec3::new(8.0 * a.cos(), 8.0 * a.sin(), z), 0.1, 30.0);
        }
        let step = (tp.points.len() / 1024).max(1);
        let want = median_nearest(&Grid::new(&tp.points, 2.0), &tp.points, step);
        assert!((want - 0.25).abs() < 0.01, "{want}");
        for t in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap();
            assert_eq!(pool.install(|| pass_spacing(&tp.points)), Some(want), "{t}");
        }
    }

    #[test]
    fn a_hint_changes_where_the_search_starts_not_what_it_finds() {
        // a wavy helix: passes 0.2 mm apart whose spacing varies, and a
        // loop closed on itself at the top
        let mut tp = Toolpath::new(DVec3::new(5.0, 0.0, 0.0));
        for i in 1..=100 * 20 {
            let a = std::f64::consts::TAU * i as f64 / 100.0;
            let r = 5.0 + 0.3 * libm::sin(7.0 * a) + 0.05 * libm::sin(0.3 * a);
            let z = 0.2 * i as f64 / 100.0 + 0.03 * libm::sin(11.0 * a);
            tp.draw(DVec3::new(r * a.cos(), r * a.sin(), z), 0.1, 30.0);
        }
        let g = Grid::new(&tp.points, 0.6);
        let n = tp.points.len() - 1;
        let mut found = 0;
        for k in (0..n).step_by(3) {
            let (a, b) = (tp.points[k], tp.points[k + 1]);
            let sm = (g.arc(k) + g.arc(k + 1)) / 2.0;
            let want = g.local_near(a, b, sm, None, false);
            found += usize::from(want.is_some());
            // the neighbour itself, near it, the string's own, far away,
            // past the end
            let right = want.map_or(k, |(_, j)| j);
            for hint in [
                right,
                right + 1,
                right.saturating_sub(2),
                k,
                k + 1000,
                n + 5,
            ] {
                assert_eq!(
                    g.local_near(a, b, sm, Some(hint), false),
                    want,
                    "string {k}, hint {hint}"
                );
            }
        }
        // a neighbouring pass beside nearly every string
        assert!(found * 3 > n * 9 / 10, "{found} of {}", n / 3);
    }

    #[test]
    fn a_grid_in_parts_finds_what_one_grid_finds() {
        let mut tp = Toolpath::new(DVec3::new(5.0, 0.0, 0.0));
        for i in 1..=100 * 30 {
            let a = std::f64::consts::TAU * i as f64 / 100.0;
            tp.draw(
                DVec3::new(5.0 * a.cos(), 5.0 * a.sin(), 0.2 * i as f64 / 100.0),
                0.1,
                30.0,
            );
        }
        let one = Grid::new(&tp.points, 0.6);
        for parts in [2, 3, 7] {
            let many = Grid::new_on(&tp.points, 0.6, parts);
            for k in (0..tp.points.len() - 1).step_by(7) {
                let (a, b) = (tp.points[k], tp.points[k + 1]);
                let sm = (one.arc(k) + one.arc(k + 1)) / 2.0;
                for hint in [None, Some(k.saturating_sub(100))] {
                    assert_eq!(
                        one.local_near(a, b, sm, hint, false),
                        many.local_near(a, b, sm, hint, false),
                        "{parts} {k}"
                    );
                }
            }
        }
    }
}
