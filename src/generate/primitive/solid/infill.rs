//! Infill: parallel scanlines clipped exactly to a region.
//!
//! Scanline k is the line p·n = k·spacing (n the unit normal of the infill
//! direction), so lines sit at the same places on every layer of the same
//! direction and in every island. Its crossings with the region's loops come
//! from exact line–segment and line–circle intersections
//! ([`crate::base::geom::region::crossings`], which also carries the paper's
//! odd-intersection rule); sorted along the line, crossings 1–2, 3–4, … bound
//! the spans inside the region (even–odd). Spans that meet end to end (a line
//! through a reflex corner, or touching one) are joined, so no gap opens at a
//! corner; spans shorter than `min_span` (the zero-length ones of a line that
//! only touches a corner or is tangent to an arc, and any sliver) are dropped,
//! so no stray string is printed.

use glam::DVec2;

use crate::base::geom::region::{crossings, monotone, Region};

/// Unit vector of the infill direction `deg` degrees counter-clockwise from
/// +x. Multiples of 45° are exact (±1/√2 with the same bits in both
/// coordinates), so a 45° line through a square's corner meets its opposite
/// corner exactly.
pub(crate) fn direction(deg: f64) -> DVec2 {
    let k = deg / 45.0;
    if k.fract() == 0.0 && k.abs() < 1e15 {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        return match (k as i64).rem_euclid(8) {
            0 => DVec2::new(1.0, 0.0),
            1 => DVec2::new(h, h),
            2 => DVec2::new(0.0, 1.0),
            3 => DVec2::new(-h, h),
            4 => DVec2::new(-1.0, 0.0),
            5 => DVec2::new(-h, -h),
            6 => DVec2::new(0.0, -1.0),
            _ => DVec2::new(h, -h),
        };
    }
    let a = deg.to_radians();
    DVec2::new(libm::cos(a), libm::sin(a))
}

/// Range of scanline numbers k that may cross `region` for direction `u`.
pub(crate) fn scanline_range(region: &Region, u: DVec2, spacing: f64) -> Option<(i64, i64)> {
    let n = DVec2::new(-u.y, u.x);
    let monos = monotone(&region.loops, n);
    let lo = monos
        .iter()
        .map(|m| m.f0.min(m.f1))
        .fold(f64::INFINITY, f64::min);
    let hi = monos
        .iter()
        .map(|m| m.f0.max(m.f1))
        .fold(f64::NEG_INFINITY, f64::max);
    if lo > hi {
        return None;
    }
    Some((
        libm::ceil(lo / spacing) as i64,
        libm::floor(hi / spacing) as i64,
    ))
}

/// The infill spans of `region` along direction `u` (unit), `spacing` apart,
/// in scanline order, each running along +u. See the module comment.
pub(crate) fn spans(region: &Region, u: DVec2, spacing: f64, min_span: f64) -> Vec<(DVec2, DVec2)> {
    let n = DVec2::new(-u.y, u.x);
    let monos = monotone(&region.loops, n);
    let Some((k0, k1)) = scanline_range(region, u, spacing) else {
        return Vec::new();
    };
    let eps = region.eps();
    let mut out = Vec::new();
    for k in k0..=k1 {
        let s = k as f64 * spacing;
        let xs = crossings(&monos, n, s);
        let mut line: Vec<(DVec2, DVec2)> = Vec::with_capacity(xs.len() / 2);
        for pair in xs.chunks_exact(2) {
            let (a, b) = (pair[0].1, pair[1].1);
            match line.last_mut() {
                Some(last) if last.1.distance(a) <= eps => last.1 = b,
                _ => line.push((a, b)),
            }
        }
        out.extend(line.into_iter().filter(|(a, b)| a.distance(*b) >= min_span));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::geom::region::{boolean, Op, Shape};
    use std::f64::consts::PI;

    #[test]
    fn diagonals_are_exact() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert_eq!(direction(45.0), DVec2::new(h, h));
        assert_eq!(direction(-45.0), DVec2::new(h, -h));
        assert_eq!(direction(90.0), DVec2::new(0.0, 1.0));
        let d = direction(30.0);
        assert!((d - DVec2::new(3f64.sqrt() / 2.0, 0.5)).length() < 1e-15);
    }

    #[test]
    fn a_line_through_two_corners_is_one_whole_string() {
        let sq = boolean(&[(
            Some(Shape::Rect {
                min: DVec2::new(-2.0, -2.0),
                max: DVec2::new(2.0, 2.0),
            }),
            Op::Union,
        )]);
        let sp = spans(&sq, direction(45.0), 0.5, 0.1);
        // the diagonal (k = 0) runs corner to corner, with no gap
        let diag: Vec<_> = sp
            .iter()
            .filter(|(a, b)| a.x - a.y == 0.0 && b.x - b.y == 0.0)
            .collect();
        assert_eq!(diag.len(), 1);
        assert_eq!(*diag[0], (DVec2::new(-2.0, -2.0), DVec2::new(2.0, 2.0)));
        // the lines through the two other corners touch them only: nothing there
        for (a, b) in &sp {
            assert!(a.distance(*b) > 0.1);
        }
        let total: f64 = sp.iter().map(|(a, b)| a.distance(*b)).sum();
        assert!((total * 0.5 - 16.0).abs() / 16.0 < 0.03, "{}", total * 0.5);
    }

    #[test]
    fn a_tangent_line_prints_nothing_and_the_disc_is_filled() {
        let c = boolean(&[(
            Some(Shape::Disc {
                c: DVec2::ZERO,
                r: 4.0,
            }),
            Op::Union,
        )]);
        // horizontal lines 0.5 apart: k = ±8 are tangent at (0, ±4)
        let sp = spans(&c, direction(0.0), 0.5, 0.1);
        assert!(sp.iter().all(|(a, _)| a.y.abs() < 4.0 - 0.25));
        assert_eq!(sp.len(), 15);
        for (a, b) in &sp {
            assert!((a.length() - 4.0).abs() < 1e-12 && (b.length() - 4.0).abs() < 1e-12);
            assert!(a.x < b.x);
        }
        let total: f64 = sp.iter().map(|(a, b)| a.distance(*b)).sum();
        assert!((total * 0.5 - PI * 16.0).abs() / (PI * 16.0) < 0.03);
    }
}
