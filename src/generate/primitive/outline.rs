//! Primitives over SVG sources: `path: {svg: …}` (a drawing as strings)
//! and `outline: {svg: …}` of `helix`, `spiral` and `cylinder` (a closed
//! outline in place of the circle). Parsing and flattening are
//! [`crate::base::svg`]'s; reading the files is the recipe's
//! (`crate::recipe::resolve`).

use glam::{DVec2, DVec3};

use super::path::PathCmd;
use crate::base::svg::{Outline, Subpath};
use crate::base::toolpath::Toolpath;

/// The points of one turn along `o`, at the arc fractions `f`.
pub(crate) fn turn_points(o: &Outline, f: &[f64]) -> Vec<DVec2> {
    f.iter().map(|&s| o.point_at(s)).collect()
}

/// A helix or spiral over an outline: point j sits at global step
/// g = first + j, on turn k = g div m at arc fraction f[g mod m] (m =
/// f.len(), Euclidean division), so at turns u = k + f[g mod m], placed by
/// `at(u, pts[g mod m])`. The path carries u in [`Toolpath::turns`].
pub(crate) fn along(
    f: &[f64],
    pts: &[DVec2],
    first: i64,
    n: u64,
    c: f64,
    v: f64,
    at: impl Fn(f64, DVec2) -> DVec3,
) -> Toolpath {
    let m = f.len() as i64;
    let point = |j: u64| {
        let g = first + j as i64;
        let q = g.rem_euclid(m) as usize;
        let u = g.div_euclid(m) as f64 + f[q];
        (u, at(u, pts[q]))
    };
    let (u0, p0) = point(0);
    let mut t = Toolpath::with_capacity(p0, n as usize);
    let mut turns = Vec::with_capacity(n as usize + 1);
    turns.push(u0);
    for j in 1..=n {
        let (u, p) = point(j);
        t.draw(p, c, v);
        turns.push(u);
    }
    t.turns = Some(turns);
    t
}

/// The drawing `sub` as `path` commands: each subpath a `move` to its start
/// and a `draw` to each further point (back to the start when it is
/// closed), the centre of the drawing's bounding box at `center`, all at
/// `center.z`.
pub(crate) fn drawing_commands(sub: &[Subpath], center: DVec3) -> Vec<PathCmd> {
    let all = sub.iter().flat_map(|p| &p.points);
    let (lo, hi) = all.fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let shift = center.truncate() - (lo + hi) * 0.5;
    let at = |p: DVec2| (p + shift).extend(center.z);
    let mut cmds = Vec::new();
    for p in sub {
        cmds.push(PathCmd::Move(at(p.points[0])));
        cmds.extend(p.points[1..].iter().map(|&q| PathCmd::Draw(at(q))));
        if p.closed {
            cmds.push(PathCmd::Draw(at(p.points[0])));
        }
    }
    cmds
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn along_counts_turns_from_the_first_step_euclidean() {
        // a unit square's fractions with 4 steps a turn: 0, 1/4, 1/2, 3/4
        let sq = [
            DVec2::new(1.0, -1.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(-1.0, 1.0),
            DVec2::new(-1.0, -1.0),
        ];
        let o = Outline::new(&sq).unwrap();
        let f = o.fractions(4);
        assert_eq!(f.len(), 8, "4 steps and 4 corners: {f:?}");
        let pts = turn_points(&o, &f);
        // starting 3 steps before turn 0: u = -1 + f[5], -1 + f[6], -1 + f[7], 0, …
        let t = along(&f, &pts, -3, 4, 0.1, 10.0, |u, p| p.extend(u));
        let u = t.turns.as_ref().unwrap();
        assert_eq!(u.len(), 5);
        assert_eq!(u[3], 0.0);
        assert_eq!(u[0], -1.0 + f[5]);
        assert_eq!(u[4], f[1]);
        for (p, uj) in t.points.iter().zip(u) {
            assert_eq!(p.z, *uj);
            assert_eq!(p.truncate(), o.point_at(*uj));
        }
    }
}
