//! Object labels: each object named for the host's cancel-object (a
//! recipe's objects are its parts; a plate's, its objects: each a whole
//! recipe, all its parts).
//!
//! Every file gets PrusaSlicer's `; printing object NAME` / `; stop
//! printing object NAME` comments around each object (OctoPrint's Cancel
//! Objects and Moonraker's object processing read them); with
//! `object_labels` (Klipper's default) also Klipper's own commands:
//! `EXCLUDE_OBJECT_DEFINE NAME=… CENTER=x,y POLYGON=[[x,y],…]` for every
//! object in the header, its polygon the convex hull of the object's points
//! in machine XY, and `EXCLUDE_OBJECT_START/END NAME=…` around its moves.
//!
//! Klipper reads a command's parameters with `shlex` after cutting the line
//! at `;`, `#` or `*`, takes `NAME=` case-insensitively and upper-cases it:
//! a name keeps ASCII letters, digits, `_`, `-` and `.` only (anything else,
//! spaces included, becomes `_`; OrcaSlicer #2027), and names equal up to
//! case get `_2`, `_3`… so each stays its own.

use glam::DVec2;

use crate::base::toolpath::Toolpath;
use crate::machine::Printer;

/// Largest number of corners of a polygon (a hull with more loses its
/// flattest corners first: the polygon stays convex and inside the hull).
const MAX_CORNERS: usize = 64;

/// Columns the hull's points are gathered in (see [`hull`]).
const COLUMNS: usize = 4096;

/// Part names made safe for Klipper's parser and unique up to case.
pub(crate) fn names<'a>(parts: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for name in parts {
        let mut base: String = name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        if base.is_empty() {
            base = "part".to_string();
        }
        let taken = |n: &str| out.iter().any(|o| o.eq_ignore_ascii_case(n));
        let mut n = base.clone();
        let mut k = 2;
        while taken(&n) {
            n = format!("{base}_{k}");
            k += 1;
        }
        out.push(n);
    }
    out
}

/// The convex hull of a part's points in machine XY, counter-clockwise, of
/// at most [`MAX_CORNERS`] corners. The points are first gathered in
/// [`COLUMNS`] columns across the part's width, each keeping its lowest and
/// highest point (and the leftmost and rightmost points kept whole): one pass
/// over millions of points, and a hull within one column's width of the
/// exact one (inside it), which a host draws and picks from.
#[cfg(test)]
pub(crate) fn hull(tp: &Toolpath, printer: &Printer) -> Vec<DVec2> {
    hull_of(std::slice::from_ref(tp), printer)
}

/// [`hull`] of the points of several parts together (an object's).
pub(crate) fn hull_of(parts: &[Toolpath], printer: &Printer) -> Vec<DVec2> {
    let o = DVec2::new(printer.origin[0], printer.origin[1]);
    let pts = || parts.iter().flat_map(|t| t.points.iter());
    let (mut x0, mut x1) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in pts() {
        x0 = x0.min(p.x);
        x1 = x1.max(p.x);
    }
    if x0 > x1 {
        return Vec::new();
    }
    let width = (x1 - x0).max(1e-9);
    let scale = (COLUMNS - 1) as f64 / width;
    let mut low = vec![None::<DVec2>; COLUMNS];
    let mut high = vec![None::<DVec2>; COLUMNS];
    for p in pts() {
        let q = p.truncate();
        let c = (((q.x - x0) * scale) as usize).min(COLUMNS - 1);
        if low[c].is_none_or(|l| q.y < l.y) {
            low[c] = Some(q);
        }
        if high[c].is_none_or(|h| q.y > h.y) {
            high[c] = Some(q);
        }
    }
    let mut cand: Vec<DVec2> = low.into_iter().chain(high).flatten().collect();
    cand.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    cand.dedup();
    let mut h = monotone_chain(&cand);
    simplify(&mut h, MAX_CORNERS);
    h.into_iter().map(|p| p + o).collect()
}

/// Andrew's monotone chain over points sorted by x then y: the hull,
/// counter-clockwise, without collinear points.
fn monotone_chain(p: &[DVec2]) -> Vec<DVec2> {
    if p.len() < 3 {
        return p.to_vec();
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut h: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        h.pop(); // the last point starts the other chain
    }
    h
}

/// Drops the corner whose triangle with its neighbours is smallest until
/// at most `max` are left (Visvalingam): a convex polygon stays convex.
fn simplify(h: &mut Vec<DVec2>, max: usize) {
    while h.len() > max.max(3) {
        let n = h.len();
        let area = |i: usize| {
            let (a, b, c) = (h[(i + n - 1) % n], h[i], h[(i + 1) % n]);
            (b - a).perp_dot(c - a).abs()
        };
        let k = (0..n)
            .min_by(|&i, &j| area(i).total_cmp(&area(j)))
            .expect("a polygon has corners");
        h.remove(k);
    }
}

/// A number of a label's coordinates: µm, trailing zeros dropped.
fn num(v: f64) -> String {
    crate::base::format::fmt_num(v)
}

/// `EXCLUDE_OBJECT_DEFINE` for a part named `name` with hull `hull`.
pub(crate) fn define(name: &str, hull: &[DVec2]) -> String {
    let centre = if hull.is_empty() {
        DVec2::ZERO
    } else {
        let (lo, hi) = hull.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        (lo + hi) / 2.0
    };
    let poly: Vec<String> = hull
        .iter()
        .map(|p| format!("[{},{}]", num(p.x), num(p.y)))
        .collect();
    format!(
        "EXCLUDE_OBJECT_DEFINE NAME={name} CENTER={},{} POLYGON=[{}]\n",
        num(centre.x),
        num(centre.y),
        poly.join(",")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_safe_and_unique_up_to_case() {
        let n = names(["cup", "Cup", "my part #1", "", "a;b", "cup"]);
        assert_eq!(n, ["cup", "Cup_2", "my_part__1", "part", "a_b", "cup_3"]);
    }

    #[test]
    fn hull_of_a_square_and_its_inside() {
        let mut pts = vec![];
        for i in 0..=10 {
            for j in 0..=10 {
                pts.push(glam::DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let tp = Toolpath::uniform(pts, 0.1, 10.0);
        let printer = crate::recipe::profile::built_in("generic-220").unwrap();
        let h = hull(&tp, &printer);
        assert_eq!(h.len(), 4, "{h:?}");
        for c in [
            [110.0, 110.0],
            [120.0, 110.0],
            [120.0, 120.0],
            [110.0, 120.0],
        ] {
            assert!(h.contains(&DVec2::from_array(c)), "{h:?}");
        }
        let line = define("SQ", &h);
        assert!(line.starts_with("EXCLUDE_OBJECT_DEFINE NAME=SQ CENTER=115,115 POLYGON=[["));
        assert!(!line.trim_end().contains(' ') || line.split(' ').count() == 4);
    }

    #[test]
    fn a_big_hull_keeps_its_corners_few_and_convex() {
        let pts: Vec<glam::DVec3> = (0..100_000)
            .map(|k| {
                let t = k as f64 * 0.01;
                glam::DVec3::new(30.0 * t.cos(), 30.0 * t.sin(), 0.0)
            })
            .collect();
        let tp = Toolpath::uniform(pts, 0.1, 10.0);
        let printer = crate::recipe::profile::built_in("generic-220").unwrap();
        let h = hull(&tp, &printer);
        assert!(h.len() <= MAX_CORNERS && h.len() > 16);
        for k in 0..h.len() {
            let (a, b, c) = (h[k], h[(k + 1) % h.len()], h[(k + 2) % h.len()]);
            assert!((b - a).perp_dot(c - b) > 0.0, "not convex at {k}");
            assert!(((b - DVec2::splat(110.0)).length() - 30.0).abs() < 0.05);
        }
    }
}
