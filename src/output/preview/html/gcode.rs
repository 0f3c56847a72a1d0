//! The viewer's moves, taken from the command stream as the G-code is
//! written ([`Reader`] is a consumer of the firmware's motion, like the
//! planner): per move only what the viewer draws, never the text.

use std::collections::HashSet;

use glam::DVec3;

use crate::analyse::planner::{MoveKind, Moves};

/// What the viewer keeps of the moves of one print.
pub(crate) struct Reader {
    /// Where recipe (0, 0, 0) lands in machine coordinates.
    origin: DVec3,
    /// The part the next move belongs to (0: before the first).
    part: usize,
    /// Per path, the strings the checks flagged (as [`Scene::flagged`]),
    /// kept for the scene.
    ///
    /// [`Scene::flagged`]: crate::output::preview::Scene
    pub(super) flags: Vec<Vec<bool>>,
    /// The machine end points (µm) of the flagged strings.
    flagged_ends: HashSet<[i64; 3]>,
    /// Filament cross-section, mm².
    area: f64,
    pub(super) to: Vec<DVec3>,
    /// Each move's feed, mm/min.
    pub(super) feed: Vec<f64>,
    /// Kinds (0 travel, 1 extrude, 2 flagged, 3 dry).
    pub(super) kind: Vec<u8>,
    /// The cross-section each move lays, mm².
    pub(super) c: Vec<f64>,
    /// (part number, first move) of each run of moves of one part.
    pub(super) parts: Vec<(usize, usize)>,
    pub(super) bmin: DVec3,
    pub(super) bmax: DVec3,
}

impl Reader {
    pub(super) fn new(origin: DVec3, flagged_ends: HashSet<[i64; 3]>, area: f64) -> Reader {
        Reader {
            origin,
            part: 0,
            flags: Vec::new(),
            flagged_ends,
            area,
            to: Vec::new(),
            feed: Vec::new(),
            kind: Vec::new(),
            c: Vec::new(),
            parts: Vec::new(),
            bmin: DVec3::splat(f64::INFINITY),
            bmax: DVec3::splat(f64::NEG_INFINITY),
        }
    }

    /// A move to machine point `to` feeding `de` mm of filament at `feed`
    /// mm/s.
    fn take(&mut self, to: DVec3, de: f64, feed: f64, kind: MoveKind) {
        let k = self.to.len();
        if self.parts.last().is_none_or(|p| p.0 != self.part) {
            self.parts.push((self.part, k));
        }
        let p = to - self.origin;
        let prev = self.to.last().copied();
        let extrudes = kind == MoveKind::Extrude;
        let kind = match kind {
            MoveKind::Travel => 0u8,
            MoveKind::Extrude if !self.flagged_ends.is_empty() => {
                let um = to.to_array().map(|x| libm::round(x * 1e3) as i64);
                if self.flagged_ends.contains(&um) {
                    2
                } else {
                    1
                }
            }
            MoveKind::Extrude => 1,
        };
        let mut c = 0.0;
        if extrudes {
            // the cross-section the move lays: filament volume over length
            let len = prev.map_or(0.0, |q| q.distance(p));
            if len > 0.0 {
                c = de.max(0.0) * self.area / len;
            }
            let prev = prev.unwrap_or(p);
            self.bmin = self.bmin.min(prev).min(p);
            self.bmax = self.bmax.max(prev).max(p);
        }
        self.to.push(p);
        self.feed.push(feed * 60.0);
        self.kind.push(kind);
        self.c.push(c);
    }
}

impl Moves for Reader {
    fn begin_part(&mut self, _name: &str) {
        self.part += 1;
    }
    fn stop(&mut self) {}
    fn dwell(&mut self, _seconds: f64) {}
    fn move_to(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
        // a move to where the head is draws nothing
        if self.to.last().is_some_and(|&q| q == to - self.origin) {
            return;
        }
        self.take(to, e, feed, kind);
    }
    fn extrude_only(&mut self, _length: f64, _feed: f64) {}
    fn profile_move(&mut self, to: DVec3, e: f64, feed: f64, kind: MoveKind) {
        self.move_to(to, e, feed, kind);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_are_kept_in_recipe_coordinates_with_their_kind_and_cross_section() {
        let origin = DVec3::new(110.0, 110.0, 0.0);
        let flagged: HashSet<[i64; 3]> = [[111_000, 111_000, 200]].into_iter().collect();
        let mut r = Reader::new(origin, flagged, 2.0);
        r.move_to(DVec3::new(110.0, 110.0, 0.2), 0.0, 120.0, MoveKind::Travel);
        r.begin_part("a");
        r.move_to(DVec3::new(111.0, 110.0, 0.2), 0.05, 30.0, MoveKind::Extrude);
        r.move_to(DVec3::new(111.0, 111.0, 0.2), 0.05, 30.0, MoveKind::Extrude);
        // nowhere to go: nothing drawn
        r.move_to(DVec3::new(111.0, 111.0, 0.2), 0.0, 30.0, MoveKind::Extrude);
        assert_eq!(r.to[0], DVec3::new(0.0, 0.0, 0.2));
        assert_eq!(r.kind, [0, 1, 2]);
        assert_eq!(r.parts, [(0, 0), (1, 1)]);
        assert_eq!(r.feed, [7200.0, 1800.0, 1800.0]);
        // 0.05 mm of filament of 2 mm² over 1 mm
        assert!((r.c[1] - 0.1).abs() < 1e-12, "{:?}", r.c);
    }
}
