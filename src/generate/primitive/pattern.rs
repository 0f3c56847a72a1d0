//! `pattern_helix`: the print of Kanada's self-organised patterns
//! ("Self-organized 3D-printing Patterns Simulated by Cellular Automata",
//! section 2, Figs. 2 and 3).
//!
//! The head runs a helix (pseudo-layers: layer transitions would leave edges)
//! of 72 strings per turn at constant speed, extruding constantly and far too
//! little for a wall (c much less than 0.2 mm², layers 0.1 to 0.3 mm high), so
//! that the filament itself decides where it sticks: chunks stack into stripes
//! that lean, split, merge and die out. Only the first turn differs: it is
//! filled and slow, the all-ones initial layer of the automaton. After it,
//! every string has the same cross-section and speed; any change would print
//! an artefact (the vertical bars of Fig. 8b come from speed changes).
//!
//! The checks warn when a value lies outside what the paper reports patterns
//! for (section 2: layer height 0.1 to 0.3 mm, head speed 40 to 150 mm/s,
//! 72 strings per turn, nozzle 0.3 to 0.5 mm, PLA at 180 to 220 °C or ABS at
//! 220 to 260 °C; Figs. 3, 10 and 12: c from 0.02 to 0.045 mm²), and when a
//! step has made the strings after the first turn differ.

use glam::DVec3;

use super::TurnTable;
use crate::base::toolpath::Toolpath;

/// The filled, slow first turn when a recipe names none: a normal string, slowly.
pub(crate) const FIRST_LAYER: FirstLayer = FirstLayer {
    cross_section: 0.2,
    speed: 15.0,
};

/// Cross-section and speed of the first turn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FirstLayer {
    /// mm².
    pub(crate) cross_section: f64,
    /// mm/s.
    pub(crate) speed: f64,
}

/// A constant-flow helix of `layers` turns of `segments` strings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PatternHelix {
    /// Radius, mm.
    pub(crate) radius: f64,
    /// Turns, the first one included.
    pub(crate) layers: u32,
    /// Rise per turn, mm.
    pub(crate) layer_height: f64,
    /// Strings per turn.
    pub(crate) segments: u32,
    /// Cross-section after the first turn, mm²; the part's when `None`.
    pub(crate) cross_section: Option<f64>,
    /// Head speed after the first turn, mm/s; the part's when `None`.
    pub(crate) speed: Option<f64>,
    /// The first turn.
    pub(crate) first_layer: FirstLayer,
    /// Centre; the helix starts at height `center.z`.
    pub(crate) center: DVec3,
}

impl PatternHelix {
    /// `layers × segments`.
    pub(crate) fn string_count(&self) -> u64 {
        self.layers as u64 * self.segments as u64
    }

    /// Point k at angle 2·pi·k/segments and height `layer_height·k/segments`:
    /// the first `segments` strings at the first layer's c and v, every later
    /// one at exactly `c` and `v` (the primitive's own, else the part's).
    pub(crate) fn build(&self, c: f64, v: f64) -> Toolpath {
        let (c, v) = (self.cross_section.unwrap_or(c), self.speed.unwrap_or(v));
        let n = self.string_count();
        let seg = self.segments as u64;
        let circle = TurnTable::new(self.radius, self.segments, n);
        let at = |k: u64| {
            let (x, y) = circle.at(k);
            let z = self.layer_height * k as f64 / seg as f64;
            self.center + DVec3::new(x, y, z)
        };
        let mut t = Toolpath::with_capacity(at(0), n as usize);
        let first = self.first_layer;
        for k in 1..=n {
            if k <= seg {
                t.draw(at(k), first.cross_section, first.speed);
            } else {
                t.draw(at(k), c, v);
            }
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn helix() -> PatternHelix {
        PatternHelix {
            radius: 20.0,
            layers: 150,
            layer_height: 0.2,
            segments: 72,
            cross_section: Some(0.045),
            speed: Some(60.0),
            first_layer: FIRST_LAYER,
            center: DVec3::new(0.0, 0.0, 0.2),
        }
    }

    #[test]
    fn constant_after_the_first_turn() {
        let t = helix().build(0.196, 40.0);
        assert_eq!(t.len(), 150 * 72);
        for (k, s) in t.strings.iter().enumerate() {
            let want = if k < 72 { (0.2, 15.0) } else { (0.045, 60.0) };
            assert_eq!((s.c, s.v), want, "string {k}");
            assert!(!s.travel);
        }
        for k in 0..t.len() - 72 {
            let (a, b) = (t.points[k], t.points[k + 72]);
            assert!(a.x == b.x && a.y == b.y, "point {k}");
            assert!((b.z - a.z - 0.2).abs() < 1e-9, "point {k}");
        }
        assert_eq!(t.points[0], DVec3::new(20.0, 0.0, 0.2));
        // without its own c and v the part's are used
        let t = PatternHelix {
            cross_section: None,
            speed: None,
            ..helix()
        }
        .build(0.03, 50.0);
        assert_eq!((t.strings[100].c, t.strings[100].v), (0.03, 50.0));
    }
}
