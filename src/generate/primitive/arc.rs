//! `arc`: part of a circle, optionally rising (a piece of a helix).
//!
//! Kanada's draw3dp has no arcs ("the programmer must describe them using the
//! low-level APIs"); split parts such as the Olympic rings of Fig. 5 need them.

use glam::DVec3;

use crate::base::toolpath::Toolpath;

/// An arc from angle `start` to `end` (radians, counter-clockwise when
/// `end > start`), rising by `rise` from start to end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Arc {
    /// Radius, mm.
    pub(crate) radius: f64,
    /// Centre; the arc starts at height `center.z`.
    pub(crate) center: DVec3,
    /// Start angle, radians.
    pub(crate) start: f64,
    /// End angle, radians.
    pub(crate) end: f64,
    /// Strings per full turn.
    pub(crate) segments: u32,
    /// Rise from start to end, mm.
    pub(crate) rise: f64,
}

impl Arc {
    /// `round(|end - start| / 2·pi · segments)`, at least 1.
    pub(crate) fn string_count(&self) -> u64 {
        let turns = (self.end - self.start).abs() / std::f64::consts::TAU;
        libm::round(turns * self.segments as f64).max(1.0) as u64
    }

    /// Makes the strings; the end points sit exactly at `start` and `end`.
    pub(crate) fn build(&self, c: f64, v: f64) -> Toolpath {
        let n = self.string_count();
        let at = |k: u64| {
            let s = k as f64 / n as f64;
            let a = self.start + (self.end - self.start) * s;
            let off = DVec3::new(
                self.radius * libm::cos(a),
                self.radius * libm::sin(a),
                self.rise * s,
            );
            self.center + off
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
    use std::f64::consts::PI;

    #[test]
    fn quarter_arc_ends_exactly() {
        let arc = Arc {
            radius: 10.0,
            center: DVec3::new(0.0, 0.0, 1.0),
            start: 0.0,
            end: PI / 2.0,
            segments: 72,
            rise: 2.0,
        };
        let t = arc.build(0.1, 20.0);
        assert_eq!(t.len(), 18);
        assert_eq!(t.points[0], DVec3::new(10.0, 0.0, 1.0));
        let e = t.head();
        assert!(e.x.abs() < 1e-12 && (e.y - 10.0).abs() < 1e-12 && e.z == 3.0);
        for p in &t.points {
            assert!((p.truncate().length() - 10.0).abs() < 1e-12);
        }
        // clockwise when end < start
        let cw = Arc {
            end: -PI / 2.0,
            ..arc
        }
        .build(0.1, 20.0);
        assert!(cw.points[1].y < 0.0);
    }
}
