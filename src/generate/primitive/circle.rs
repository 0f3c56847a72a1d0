//! `circle`: one closed circle of `segments` strings.

use glam::DVec3;

use super::on_circle;
use crate::base::toolpath::Toolpath;

/// One closed circle at height `center.z`, starting at angle 0, counter-clockwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Circle {
    /// Radius, mm.
    pub(crate) radius: f64,
    /// Centre.
    pub(crate) center: DVec3,
    /// Number of strings.
    pub(crate) segments: u32,
}

impl Circle {
    /// Number of strings: `segments`.
    pub(crate) fn string_count(&self) -> u64 {
        self.segments as u64
    }

    /// Makes the strings; the last point is exactly the first.
    pub(crate) fn build(&self, c: f64, v: f64) -> Toolpath {
        let at = |k: u64| {
            let (x, y) = on_circle(self.radius, k, self.segments);
            self.center + DVec3::new(x, y, 0.0)
        };
        let mut t = Toolpath::with_capacity(at(0), self.segments as usize);
        for k in 1..=self.segments as u64 {
            t.draw(at(k), c, v);
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_and_on_the_circle() {
        let circle = Circle {
            radius: 10.0,
            center: DVec3::new(1.0, 2.0, 3.0),
            segments: 72,
        };
        let t = circle.build(0.2, 30.0);
        assert_eq!(t.len(), 72);
        assert_eq!(t.points[0], t.points[72]);
        for p in &t.points {
            assert!(((*p - circle.center).length() - 10.0).abs() < 1e-12);
            assert_eq!(p.z, 3.0);
        }
    }
}
