//! The skirt: loops around the parts' footprint, printed first to prime the
//! nozzle (Kanada's Fig. 9 prints one at r = 30 around the r = 25 sphere).
//!
//! The footprint is the convex hull of the parts' extruding points seen from
//! above; loop k is that hull offset outwards by `distance + k·w` (w the
//! nozzle diameter), corners rounded with arcs, at the parts' lowest height.

use glam::{DVec2, DVec3};

use crate::error::{Error, Result};
use crate::model::Skirt;
use crate::toolpath::Toolpath;

/// Convex hull of `pts`, counter-clockwise, by Andrew's monotone chain.
pub fn convex_hull(mut pts: Vec<DVec2>) -> Vec<DVec2> {
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
pub fn make(
    skirt: &Skirt,
    parts: &[Toolpath],
    spacing: f64,
    (c, v): (f64, f64),
    max_strings: u64,
) -> Result<Option<Toolpath>> {
    let mut pts = Vec::new();
    let mut z = f64::INFINITY;
    for tp in parts {
        // a string's start is the string before's end: pushed once (the
        // hull's sort and dedup would drop the copy anyway)
        let mut pushed_end = false;
        for k in 0..tp.len() {
            if tp.strings[k].travel {
                pushed_end = false;
                continue;
            }
            let (a, b) = tp.ends(k);
            if !pushed_end {
                pts.push(a.truncate());
            }
            pts.push(b.truncate());
            pushed_end = true;
            z = z.min(a.z).min(b.z);
        }
    }
    if pts.is_empty() {
        return Ok(None);
    }
    let hull = convex_hull(pts);
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
