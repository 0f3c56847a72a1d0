//! `helix`: the single wall with no layers and no seam (Kanada, Fig. 4b).

use std::sync::Arc;

use glam::DVec3;

use super::outline::{along, turn_points};
use super::{TurnTable, PAR_MIN};
use crate::base::svg::Outline;
use crate::base::toolpath::Toolpath;

/// A helix rising continuously from `center.z` to `center.z + height`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Helix {
    /// Radius, mm (with an outline: its farthest distance from its centroid).
    pub(crate) radius: f64,
    /// Total rise, mm.
    pub(crate) height: f64,
    /// Vertical rise per turn, mm.
    pub(crate) pitch: f64,
    /// Centre of the bottom.
    pub(crate) center: DVec3,
    /// Strings per turn.
    pub(crate) segments: u32,
    /// A closed outline in place of the circle, centroid at the origin.
    pub(crate) outline: Option<Arc<Outline>>,
}

impl Helix {
    /// `round(height / pitch * segments)`, as the spec says (with an
    /// outline, segments plus the outline's corners per turn).
    pub(crate) fn string_count(&self) -> u64 {
        let m = match &self.outline {
            Some(o) => o.fractions(self.segments).len(),
            None => self.segments as usize,
        };
        libm::round(self.height / self.pitch * m as f64).max(1.0) as u64
    }

    /// Over an outline: point j is on turn k = j div m at arc fraction
    /// s = f[j mod m] (the `segments` even steps and the corners, the same
    /// every turn), at height (k + s)·pitch: every turn is the outline,
    /// rising one pitch over it. The top is within one string's rise of
    /// `height`.
    fn build_outline(&self, o: &Outline, c: f64, v: f64) -> Toolpath {
        let f = o.fractions(self.segments);
        let pts = turn_points(o, &f);
        along(&f, &pts, 0, self.string_count(), c, v, |u, p| {
            self.center + DVec3::new(p.x, p.y, u * self.pitch)
        })
    }

    /// Point k is at angle 2·pi·k/segments and height `height·k/n`, so the
    /// angle steps are uniform and the last point sits exactly at `height`.
    /// The points are computed in chunks, each the same whatever the split.
    pub(crate) fn build(&self, c: f64, v: f64) -> Toolpath {
        if let Some(o) = &self.outline {
            return self.build_outline(o, c, v);
        }
        let n = self.string_count();
        let circle = TurnTable::new(self.radius, self.segments, n);
        // the turn's table walked in step (k mod segments without a division
        // per point); the points written in place in chunks, then the
        // strings likewise
        let points = crate::base::par::fill_vec_with(n as usize + 1, PAR_MIN, |start| {
            let mut turn = circle.walk_from(start as u64);
            let mut k = start as u64;
            move || {
                let (x, y) = turn.next_point();
                let z = if k == n {
                    self.height
                } else {
                    self.height * k as f64 / n as f64
                };
                k += 1;
                self.center + DVec3::new(x, y, z)
            }
        });
        Toolpath::uniform(points, c, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rises_to_exactly_height_with_segments_per_turn() {
        let h = Helix {
            radius: 20.0,
            height: 10.0,
            pitch: 0.3,
            center: DVec3::new(0.0, 0.0, 0.2),
            segments: 72,
            outline: None,
        };
        let t = h.build(0.1, 20.0);
        assert_eq!(t.len() as u64, (10.0f64 / 0.3 * 72.0).round() as u64);
        assert_eq!(t.head().z, 10.2);
        assert_eq!(t.points[0], DVec3::new(20.0, 0.0, 0.2));
        // one turn later the point is straight above the start, one pitch up
        let p = t.points[72];
        assert!(p.x == 20.0 && p.y == 0.0);
        assert!((p.z - 0.2 - 0.3).abs() < 1e-3);
        // z never decreases
        assert!(t.points.windows(2).all(|w| w[1].z > w[0].z));
    }

    #[test]
    fn built_in_one_go_as_point_by_point() {
        // the walked table and `Toolpath::uniform` give the bits of
        // `on_circle` per point and `draw` per string
        let h = Helix {
            radius: 7.5,
            height: 3.0,
            pitch: 0.2,
            center: DVec3::new(1.0, -2.0, 0.3),
            segments: 37,
            outline: None,
        };
        let t = h.build(0.2, 30.0);
        let n = h.string_count();
        let at = |k: u64| {
            let (x, y) = super::super::on_circle(h.radius, k, h.segments);
            let z = if k == n {
                h.height
            } else {
                h.height * k as f64 / n as f64
            };
            h.center + DVec3::new(x, y, z)
        };
        let mut want = Toolpath::new(at(0));
        for k in 1..=n {
            want.draw(at(k), 0.2, 30.0);
        }
        assert_eq!(t, want);
        // split over threads (above PAR_MIN points): the same again
        let big = Helix {
            height: 60.0,
            ..h.clone()
        };
        assert!(big.string_count() as usize > PAR_MIN);
        let one = big.build(0.2, 30.0);
        for threads in [2, 3, 4] {
            let on = crate::base::par::on_threads(threads, || big.build(0.2, 30.0));
            assert_eq!(on, one);
        }
    }
}
