//! `cylinder`: a filled cylinder of flat spirals (Kanada's `cylinder`).

use std::sync::Arc;

use glam::DVec3;

use super::spiral::{Direction, Spiral};
use crate::base::svg::Outline;
use crate::base::toolpath::Toolpath;

/// Flat spirals every `vpitch`, `hpitch` apart, alternately outward and
/// inward, so each layer starts where the last one ended, one `vpitch` up.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Cylinder {
    /// Radius, mm (with an outline: its farthest distance from its centroid).
    pub(crate) radius: f64,
    /// Height, mm.
    pub(crate) height: f64,
    /// Distance between layers, mm.
    pub(crate) vpitch: f64,
    /// Distance between the turns of a layer's spiral, mm.
    pub(crate) hpitch: f64,
    /// Centre of the bottom layer.
    pub(crate) center: DVec3,
    /// Strings per turn.
    pub(crate) segments: u32,
    /// A closed outline in place of the circle (each layer a spiral of it).
    pub(crate) outline: Option<Arc<Outline>>,
}

impl Cylinder {
    /// Number of layers: `round(height / vpitch)`, at least 1.
    pub(crate) fn layers(&self) -> u64 {
        libm::round(self.height / self.vpitch).max(1.0) as u64
    }

    fn layer(&self, j: u64) -> Spiral {
        Spiral {
            radius: self.radius,
            pitch: self.hpitch,
            center: self.center + DVec3::new(0.0, 0.0, self.vpitch * j as f64),
            segments: self.segments,
            inner_radius: 0.0,
            direction: if j.is_multiple_of(2) {
                Direction::Outward
            } else {
                Direction::Inward
            },
            outline: self.outline.clone(),
        }
    }

    /// Spiral strings of every layer plus one vertical step between layers.
    pub(crate) fn string_count(&self) -> u64 {
        // saturating: a huge height must reach the string limit, not wrap
        let l = self.layers();
        l.saturating_mul(self.layer(0).string_count())
            .saturating_add(l - 1)
    }

    /// Makes the layers; the step up between two layers is a travel string
    /// (a Z move that extrudes nothing).
    pub(crate) fn build(&self, c: f64, v: f64) -> Toolpath {
        let mut t = self.layer(0).build(c, v);
        t.strings.reserve(self.string_count() as usize - t.len());
        for j in 1..self.layers() {
            let layer = self.layer(j).build(c, v);
            t.append(&layer, v);
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_alternate_and_join_without_travel_in_xy() {
        let cyl = Cylinder {
            radius: 5.0,
            height: 0.6,
            vpitch: 0.2,
            hpitch: 0.5,
            center: DVec3::new(0.0, 0.0, 0.2),
            segments: 36,
            outline: None,
        };
        let t = cyl.build(0.1, 20.0);
        assert_eq!(t.len() as u64, cyl.string_count());
        assert_eq!(cyl.layers(), 3);
        let travels: Vec<usize> = (0..t.len()).filter(|&k| t.strings[k].travel).collect();
        assert_eq!(travels.len(), 2);
        for k in travels {
            let (a, b) = t.ends(k);
            // straight up by one vpitch
            assert_eq!(a.truncate(), b.truncate());
            assert!((b.z - a.z - 0.2).abs() < 1e-12);
        }
        // the top layer (outward) ends at the rim, angle 0
        assert!((t.head() - DVec3::new(5.0, 0.0, 0.6)).length() < 1e-12);
    }
}
