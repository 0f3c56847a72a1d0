//! `spiral`: a flat Archimedean spiral (Kanada, Fig. 4a).

use std::sync::Arc;

use glam::DVec3;

use super::outline::{along, turn_points};
use crate::base::svg::Outline;
use crate::base::toolpath::Toolpath;

/// Which way a spiral runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Direction {
    /// From `inner_radius` out to `radius`, ending at angle 0.
    Outward,
    /// The outward spiral reversed: from `radius` at angle 0 in to `inner_radius`.
    Inward,
}

/// A flat spiral whose outer end sits at angle 0, where a helix of the same
/// radius starts, so that the helix continues it without a seam.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Spiral {
    /// Outer radius, mm (with an outline: its farthest distance from its centroid).
    pub(crate) radius: f64,
    /// Horizontal distance between turns, mm.
    pub(crate) pitch: f64,
    /// Centre.
    pub(crate) center: DVec3,
    /// Strings per turn.
    pub(crate) segments: u32,
    /// Where the spiral starts (outward), mm.
    pub(crate) inner_radius: f64,
    /// Outward or inward.
    pub(crate) direction: Direction,
    /// A closed outline in place of the circle, centroid at the origin.
    pub(crate) outline: Option<Arc<Outline>>,
}

impl Spiral {
    /// Number of turns, (radius - inner_radius) / pitch.
    pub(crate) fn turns(&self) -> f64 {
        (self.radius - self.inner_radius) / self.pitch
    }

    /// `round(turns · segments)`, at least 1 (with an outline, segments
    /// plus the outline's corners per turn).
    pub(crate) fn string_count(&self) -> u64 {
        let m = match &self.outline {
            Some(o) => o.fractions(self.segments).len(),
            None => self.segments as usize,
        };
        libm::round(self.turns() * m as f64).max(1.0) as u64
    }

    /// Over an outline: the outward spiral's last point is the outline's
    /// start (u = 0); point j sits n − j steps before it, at turns u ≤ 0 and
    /// arc fraction s = u − floor(u), on the outline scaled about its
    /// centroid by (radius + u·pitch) / radius, so the turns are `pitch`
    /// apart where the outline is farthest from its centroid (`radius`)
    /// and the first is `inner_radius` / `radius` of the outline's size.
    fn build_outline(&self, o: &Outline, c: f64, v: f64) -> Toolpath {
        let f = o.fractions(self.segments);
        let pts = turn_points(o, &f);
        let n = self.string_count();
        let mut t = along(&f, &pts, -(n as i64), n, c, v, |u, p| {
            let k = ((self.radius + u * self.pitch) / self.radius).max(0.0);
            self.center + DVec3::new(p.x * k, p.y * k, 0.0)
        });
        if self.direction == Direction::Inward {
            t.points.reverse();
            if let Some(u) = &mut t.turns {
                u.reverse();
            }
        }
        t
    }

    /// r(s) = inner + (radius − inner)·s and angle 2·pi·turns·(s − 1) for
    /// s = k/n: r grows by `pitch` a turn and the outer end is at angle 0.
    pub(crate) fn build(&self, c: f64, v: f64) -> Toolpath {
        if let Some(o) = &self.outline {
            return self.build_outline(o, c, v);
        }
        let n = self.string_count();
        let turns = self.turns();
        let at = |k: u64| {
            let k = match self.direction {
                Direction::Outward => k,
                Direction::Inward => n - k,
            };
            if k == n {
                return self.center + DVec3::new(self.radius, 0.0, 0.0);
            }
            let s = k as f64 / n as f64;
            let r = self.inner_radius + (self.radius - self.inner_radius) * s;
            let a = std::f64::consts::TAU * turns * (s - 1.0);
            self.center + DVec3::new(r * libm::cos(a), r * libm::sin(a), 0.0)
        };
        let mut t = Toolpath::with_capacity(at(0), n as usize);
        for k in 1..=n {
            t.draw(at(k), c, v);
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spiral(direction: Direction) -> Spiral {
        Spiral {
            radius: 10.0,
            pitch: 0.5,
            center: DVec3::new(0.0, 0.0, 0.2),
            segments: 72,
            inner_radius: 2.0,
            direction,
            outline: None,
        }
    }

    #[test]
    fn outward_ends_where_a_helix_starts() {
        let t = spiral(Direction::Outward).build(0.2, 20.0);
        assert_eq!(t.len(), 16 * 72);
        assert_eq!(t.head(), DVec3::new(10.0, 0.0, 0.2));
        assert!((t.points[0].truncate().length() - 2.0).abs() < 1e-12);
        // the radius grows by one pitch per turn
        let r = |p: DVec3| p.truncate().length();
        assert!((r(t.points[72]) - r(t.points[0]) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn inward_is_outward_reversed() {
        let o = spiral(Direction::Outward).build(0.2, 20.0);
        let i = spiral(Direction::Inward).build(0.2, 20.0);
        let mut rev = o.points.clone();
        rev.reverse();
        for (a, b) in rev.iter().zip(&i.points) {
            assert!((*a - *b).length() < 1e-12);
        }
    }
}
