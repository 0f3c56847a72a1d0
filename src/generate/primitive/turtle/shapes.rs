//! The points of a program's curves (FullControl's `arcXY`, `spiralXY`,
//! `helixZ`, `bezier` and `rectangleXY`), first to last.

use glam::DVec3;

/// `n` + 1 points of an arc about `o`: point k at angle a0 + da·k/n,
/// radius r0 + (r1 − r0)·k/n, height o.z + dz·k/n.
pub(crate) fn arc(o: DVec3, r0: f64, r1: f64, a0: f64, da: f64, dz: f64, n: usize) -> Vec<DVec3> {
    (0..=n)
        .map(|k| {
            let t = k as f64 / n as f64;
            let (a, r) = (a0 + da * t, r0 + (r1 - r0) * t);
            DVec3::new(o.x + r * libm::cos(a), o.y + r * libm::sin(a), o.z + dz * t)
        })
        .collect()
}

/// `n` + 1 points of the Bézier curve of `ctrl` (at least two control
/// points) at t = k/n: Σ C(m, i)·(1 − t)^(m−i)·t^i·P_i, m + 1 points.
pub(crate) fn bezier(ctrl: &[DVec3], n: usize) -> Vec<DVec3> {
    let m = ctrl.len().saturating_sub(1);
    // the binomial coefficients C(m, i), exact in f64 for any practical m
    let mut binom = vec![1.0f64; m + 1];
    for i in 1..=m {
        binom[i] = binom[i - 1] * (m + 1 - i) as f64 / i as f64;
    }
    (0..=n)
        .map(|k| {
            let t = k as f64 / n as f64;
            ctrl.iter().enumerate().fold(DVec3::ZERO, |acc, (i, p)| {
                let b = binom[i] * libm::pow(1.0 - t, (m - i) as f64) * libm::pow(t, i as f64);
                acc + *p * b
            })
        })
        .collect()
}

/// The five corners of FullControl's `rectangleXY`: `c`, then along x (or
/// along y when `clockwise`), the opposite corner, the other side, `c`.
pub(crate) fn rectangle(c: DVec3, dx: f64, dy: f64, clockwise: bool) -> Vec<DVec3> {
    let (x, y) = (DVec3::new(dx, 0.0, 0.0), DVec3::new(0.0, dy, 0.0));
    let (first, third) = if clockwise { (y, x) } else { (x, y) };
    vec![c, c + first, c + x + y, c + third, c]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curves_pass_their_ends() {
        let a = arc(
            DVec3::new(1.0, 2.0, 3.0),
            2.0,
            4.0,
            0.0,
            std::f64::consts::PI,
            1.0,
            4,
        );
        assert_eq!(a.len(), 5);
        assert!((a[0] - DVec3::new(3.0, 2.0, 3.0)).length() < 1e-12);
        assert!((a[4] - DVec3::new(-3.0, 2.0, 4.0)).length() < 1e-12);
        let ctrl = [
            DVec3::ZERO,
            DVec3::new(1.0, 2.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
        ];
        let b = bezier(&ctrl, 2);
        assert_eq!(b[0], ctrl[0]);
        assert!((b[1] - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-12);
        assert!((b[2] - ctrl[2]).length() < 1e-12);
        let r = rectangle(DVec3::ZERO, 2.0, 1.0, true);
        assert_eq!(r[1], DVec3::new(0.0, 1.0, 0.0));
        assert_eq!(r[2], DVec3::new(2.0, 1.0, 0.0));
        assert_eq!(r[4], DVec3::ZERO);
    }
}
