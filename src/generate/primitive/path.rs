//! `path`: the papers' low-level API (`move`, `draw`), as outlines are drawn.

use glam::DVec3;

use crate::base::toolpath::Toolpath;

/// One command of a `path` primitive, with numbers resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum PathCmd {
    /// Travel to the point without extruding.
    Move(DVec3),
    /// Extrude a string to the point.
    Draw(DVec3),
}

/// Number of strings: one per `move` or `draw`, less a leading `move`.
pub(super) fn string_count(cmds: &[PathCmd]) -> u64 {
    (cmds.len() - matches!(cmds.first(), Some(PathCmd::Move(_))) as usize) as u64
}

/// Runs the commands. The first point is a leading `move`'s, else the origin.
pub(super) fn build(cmds: &[PathCmd], c: f64, v: f64) -> Toolpath {
    let (start, rest) = match cmds {
        [PathCmd::Move(p), rest @ ..] => (*p, rest),
        _ => (DVec3::ZERO, cmds),
    };
    let mut t = Toolpath::with_capacity(start, rest.len());
    for cmd in rest {
        match *cmd {
            PathCmd::Move(p) => t.travel(p, v),
            PathCmd::Draw(p) => t.draw(p, c, v),
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn move_then_draws() {
        let cmds = [
            PathCmd::Move(DVec3::new(1.0, 0.0, 0.2)),
            PathCmd::Draw(DVec3::new(2.0, 0.0, 0.2)),
            PathCmd::Draw(DVec3::new(2.0, 1.0, 0.2)),
            PathCmd::Move(DVec3::new(5.0, 1.0, 0.2)),
        ];
        let t = build(&cmds, 0.1, 40.0);
        assert_eq!(t.points[0], DVec3::new(1.0, 0.0, 0.2));
        assert_eq!(t.len() as u64, string_count(&cmds));
        assert_eq!(t.len(), 3);
        assert_eq!((t.strings[0].c, t.strings[0].v), (0.1, 40.0));
        assert!(t.strings[2].travel && !t.strings[1].travel);
    }

    #[test]
    fn starts_at_origin_without_a_leading_move() {
        let cmds = [PathCmd::Draw(DVec3::new(1.0, 0.0, 0.0))];
        let t = build(&cmds, 0.1, 40.0);
        assert_eq!(t.points[0], DVec3::ZERO);
        assert_eq!(t.len(), 1);
    }
}
