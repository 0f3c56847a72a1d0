//! The bed of a slicer's printer preset: its corners (`bed_shape`,
//! `printable_area`) as a rectangle, a circle on the origin, or, for a
//! convex polygon, the largest rectangle or circle inside it.

use super::{Format, Preset};
use crate::base::error::{Error, Result};
use crate::recipe::schema::RawBed;

/// The corners of the bed setting `key`, `XxY` each; `None` when the
/// setting holds no corners at all (OrcaSlicer's legacy `bed_shape =
/// rectangular`, its `printable_area` being the bed).
fn corners(p: &Preset, key: &str) -> Result<Option<Vec<(f64, f64)>>> {
    let mut pts = Vec::new();
    let list = p.list(key).unwrap_or_default();
    if list.iter().all(|s| !s.contains(['x', 'X'])) {
        return Ok(None);
    }
    for s in list {
        let parsed = s
            .split_once(['x', 'X'])
            .and_then(|(x, y)| Some((x.trim().parse::<f64>().ok()?, y.trim().parse::<f64>().ok()?)))
            .filter(|(x, y)| x.is_finite() && y.is_finite());
        match parsed {
            Some(xy) => pts.push(xy),
            None => {
                return Err(
                    Error::input(key, format!("`{s}` is not a corner; expected XxY"))
                        .in_file(&p.file),
                )
            }
        }
    }
    Ok(Some(pts))
}

/// The bed and the XY point of its centre (where recipe (0, 0) lands).
pub(super) fn bed(p: &Preset, max_z: f64, notes: &mut Vec<String>) -> Result<(RawBed, [f64; 2])> {
    // PrusaSlicer's bed is bed_shape; OrcaSlicer's and Bambu's printable_area
    let order: [&str; 2] = match p.format {
        Format::Ini => ["bed_shape", "printable_area"],
        Format::Json => ["printable_area", "bed_shape"],
    };
    let mut found = None;
    for key in order {
        if p.has(key) {
            if let Some(pts) = corners(p, key)? {
                found = Some((key, pts));
                break;
            }
        }
    }
    let Some((key, pts)) = found else {
        return Err(super::refuse(
            p,
            order[0],
            "a preset without a bed (no bed_shape or printable_area corners)".into(),
        ));
    };
    let (xs, ys): (Vec<f64>, Vec<f64>) = pts.iter().copied().unzip();
    let (x0, x1) = (
        xs.iter().copied().fold(f64::INFINITY, f64::min),
        xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let (y0, y1) = (
        ys.iter().copied().fold(f64::INFINITY, f64::min),
        ys.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let on = |v: f64, a: f64, b: f64| (v - a).abs() < 1e-6 || (v - b).abs() < 1e-6;
    if pts.len() == 4
        && pts.iter().all(|&(x, y)| on(x, x0, x1) && on(y, y0, y1))
        && x1 > x0
        && y1 > y0
    {
        let bed = RawBed::Rectangle {
            size: [x1 - x0, y1 - y0],
            min: [x0, y0],
            max_z,
        };
        return Ok((bed, [(x0 + x1) / 2.0, (y0 + y1) / 2.0]));
    }
    if pts.len() >= 8 {
        let k = pts.len() as f64;
        let (cx, cy) = (xs.iter().sum::<f64>() / k, ys.iter().sum::<f64>() / k);
        let radii: Vec<f64> = pts.iter().map(|&(x, y)| (x - cx).hypot(y - cy)).collect();
        let r = radii.iter().sum::<f64>() / k;
        let round = r > 0.0 && radii.iter().all(|q| (q - r).abs() <= 0.005 * r);
        if round && cx.hypot(cy) <= 0.01 * r {
            let d = libm::round(2.0 * r * 1000.0) / 1000.0;
            return Ok((RawBed::Circle { diameter: d, max_z }, [0.0, 0.0]));
        }
        if round {
            return Err(super::refuse(
                p,
                key,
                "a round bed whose centre is not the origin".into(),
            ));
        }
    }
    match inscribed(&pts) {
        Some((bed, centre, how)) => {
            notes.push(format!(
                "the bed ({key}) is a polygon of {} corners: p3dp keeps to the {how} inside it",
                pts.len()
            ));
            Ok((with_height(bed, max_z), centre))
        }
        None => Err(super::refuse(
            p,
            key,
            format!(
                "a bed of {} corners that is neither a rectangle, a circle nor a convex polygon",
                pts.len()
            ),
        )),
    }
}

fn with_height(bed: RawBed, z: f64) -> RawBed {
    match bed {
        RawBed::Rectangle { size, min, .. } => RawBed::Rectangle {
            size,
            min,
            max_z: z,
        },
        RawBed::Circle { diameter, .. } => RawBed::Circle { diameter, max_z: z },
    }
}

/// Whether the polygon `pts` is convex (its turns all one way, straight
/// runs allowed) and not degenerate.
fn convex(pts: &[(f64, f64)]) -> bool {
    let n = pts.len();
    if n < 3 {
        return false;
    }
    let (mut pos, mut neg) = (false, false);
    for k in 0..n {
        let (a, b, c) = (pts[k], pts[(k + 1) % n], pts[(k + 2) % n]);
        let cross = (b.0 - a.0) * (c.1 - b.1) - (b.1 - a.1) * (c.0 - b.0);
        pos |= cross > 1e-9;
        neg |= cross < -1e-9;
    }
    pos != neg
}

/// Whether `q` lies inside the convex polygon `pts` (its edges included).
fn inside(pts: &[(f64, f64)], q: (f64, f64)) -> bool {
    let n = pts.len();
    let (mut pos, mut neg) = (false, false);
    for k in 0..n {
        let (a, b) = (pts[k], pts[(k + 1) % n]);
        let cross = (b.0 - a.0) * (q.1 - a.1) - (b.1 - a.1) * (q.0 - a.0);
        pos |= cross > 1e-9;
        neg |= cross < -1e-9;
    }
    !(pos && neg)
}

/// A bed p3dp can hold to inside a convex polygon bed: the largest
/// rectangle of the polygon's proportions centred on its corners' mean
/// (found by halving the scale), or, for a polygon about the origin (a
/// delta's), the largest circle on the origin if it is larger; with the
/// bed's centre and what it is, in words. Every point of either lies inside
/// the polygon, so no move p3dp allows leaves the maker's bed.
fn inscribed(pts: &[(f64, f64)]) -> Option<(RawBed, [f64; 2], &'static str)> {
    if !convex(pts) {
        return None;
    }
    let k = pts.len() as f64;
    let c = (
        pts.iter().map(|p| p.0).sum::<f64>() / k,
        pts.iter().map(|p| p.1).sum::<f64>() / k,
    );
    let (w, h) = (
        pts.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max)
            - pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min),
        pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max)
            - pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min),
    );
    let fits = |s: f64| {
        let (dx, dy) = (s * w / 2.0, s * h / 2.0);
        [(-dx, -dy), (dx, -dy), (dx, dy), (-dx, dy)]
            .iter()
            .all(|&(x, y)| inside(pts, (c.0 + x, c.1 + y)))
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..50 {
        let mid = (lo + hi) / 2.0;
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    // whole hundredths of a millimetre, rounded inwards
    let down = |v: f64| libm::floor(v * 100.0) / 100.0;
    let (rw, rh) = (down(lo * w), down(lo * h));
    // a circle on the origin: the distance to the nearest edge's line
    let n = pts.len();
    let origin_inside = inside(pts, (0.0, 0.0)) && c.0.hypot(c.1) <= 0.01 * w.max(h);
    let r = (0..n)
        .map(|k| {
            let (a, b) = (pts[k], pts[(k + 1) % n]);
            let len = (b.0 - a.0).hypot(b.1 - a.1);
            if len > 0.0 {
                ((b.0 - a.0) * a.1 - (b.1 - a.1) * a.0).abs() / len
            } else {
                f64::INFINITY
            }
        })
        .fold(f64::INFINITY, f64::min);
    if origin_inside && std::f64::consts::PI * r * r > rw * rh && r > 0.0 {
        let d = down(2.0 * r);
        return Some((
            RawBed::Circle {
                diameter: d,
                max_z: 0.0,
            },
            [0.0, 0.0],
            "largest circle",
        ));
    }
    if rw <= 0.0 || rh <= 0.0 {
        return None;
    }
    let min = [c.0 - rw / 2.0, c.1 - rh / 2.0];
    Some((
        RawBed::Rectangle {
            size: [rw, rh],
            min,
            max_z: 0.0,
        },
        [c.0, c.1],
        "largest rectangle of its proportions",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygon_beds_are_held_inside() {
        let hex = [
            (-69.0, -120.0),
            (-138.0, 0.0),
            (-69.0, 120.0),
            (69.0, 120.0),
            (138.0, 0.0),
            (69.0, -120.0),
        ];
        let (b, c, _) = inscribed(&hex).unwrap();
        assert_eq!(c, [0.0, 0.0]);
        let RawBed::Circle { diameter, .. } = b else {
            panic!("{b:?}")
        };
        // the apothem of the slanted edges: 138·120 / √(69² + 120²)
        assert!(
            (diameter / 2.0 - 138.0 * 120.0 / 69f64.hypot(120.0)).abs() < 0.01,
            "{diameter}"
        );
        // a rounded rectangle, off the origin: a rectangle inside it
        let mut round: Vec<(f64, f64)> = Vec::new();
        for q in 0..4 {
            let (cx, cy) = [(190.0, 190.0), (10.0, 190.0), (10.0, 10.0), (190.0, 10.0)][q];
            for k in 0..=8 {
                let a = (q as f64 + k as f64 / 8.0) * std::f64::consts::FRAC_PI_2;
                round.push((cx + 10.0 * a.cos(), cy + 10.0 * a.sin()));
            }
        }
        let (b, c, _) = inscribed(&round).unwrap();
        let RawBed::Rectangle { size, min, .. } = b else {
            panic!("{b:?}")
        };
        assert!((c[0] - 100.0).abs() < 1e-9 && (c[1] - 100.0).abs() < 1e-9);
        for (x, y) in [(min[0], min[1]), (min[0] + size[0], min[1] + size[1])] {
            assert!(inside(&round, (x, y)));
        }
        assert!(size[0] > 190.0, "{size:?}");
        // Folgertech's typo 20x0 for 200x0 is convex but no rectangle: held inside too;
        // a non-convex bed is refused
        assert!(inscribed(&[
            (0.0, 0.0),
            (100.0, 0.0),
            (50.0, 10.0),
            (100.0, 100.0),
            (0.0, 100.0)
        ])
        .is_none());
    }
}
