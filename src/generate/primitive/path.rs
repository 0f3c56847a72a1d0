//! `path`: the papers' low-level API (`move`, `draw`, `setCrossSection`, `setVelocity`).

use glam::DVec3;

use crate::base::toolpath::Toolpath;

/// One command of a `path` primitive, with numbers resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathCmd {
    /// Travel to the point without extruding.
    Move(DVec3),
    /// Extrude a string to the point.
    Draw(DVec3),
    /// Cross-section from now on, mm².
    CrossSection(f64),
    /// Speed from now on, mm/s.
    Speed(f64),
}

/// Number of strings: one per `move` or `draw`, less a leading `move`.
pub(super) fn string_count(cmds: &[PathCmd]) -> u64 {
    let moves = cmds
        .iter()
        .filter(|c| matches!(c, PathCmd::Move(_) | PathCmd::Draw(_)))
        .count() as u64;
    moves - starts_with_move(cmds) as u64
}

fn starts_with_move(cmds: &[PathCmd]) -> bool {
    cmds.iter()
        .find(|c| matches!(c, PathCmd::Move(_) | PathCmd::Draw(_)))
        .is_some_and(|c| matches!(c, PathCmd::Move(_)))
}

/// Runs the commands. The first point is the first `move` when one comes
/// before any `draw`, else the origin.
pub(super) fn build(cmds: &[PathCmd], c0: f64, v0: f64) -> Toolpath {
    let (mut c, mut v) = (c0, v0);
    let mut rest = cmds;
    let mut start = DVec3::ZERO;
    if starts_with_move(cmds) {
        let k = cmds
            .iter()
            .position(|c| matches!(c, PathCmd::Move(_)))
            .unwrap();
        // commands before the first move only set c and v
        for cmd in &cmds[..k] {
            match *cmd {
                PathCmd::CrossSection(x) => c = x,
                PathCmd::Speed(x) => v = x,
                _ => {}
            }
        }
        if let PathCmd::Move(p) = cmds[k] {
            start = p;
        }
        rest = &cmds[k + 1..];
    }
    let mut t = Toolpath::with_capacity(start, rest.len());
    for cmd in rest {
        match *cmd {
            PathCmd::Move(p) => t.travel(p, v),
            PathCmd::Draw(p) => t.draw(p, c, v),
            PathCmd::CrossSection(x) => c = x,
            PathCmd::Speed(x) => v = x,
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn move_draw_and_settings() {
        let cmds = [
            PathCmd::Speed(10.0),
            PathCmd::Move(DVec3::new(1.0, 0.0, 0.2)),
            PathCmd::Draw(DVec3::new(2.0, 0.0, 0.2)),
            PathCmd::CrossSection(0.3),
            PathCmd::Draw(DVec3::new(2.0, 1.0, 0.2)),
            PathCmd::Move(DVec3::new(5.0, 1.0, 0.2)),
        ];
        let t = build(&cmds, 0.1, 40.0);
        assert_eq!(t.points[0], DVec3::new(1.0, 0.0, 0.2));
        assert_eq!(t.len() as u64, string_count(&cmds));
        assert_eq!(t.len(), 3);
        assert_eq!(t.strings[0].c, 0.1);
        assert_eq!(t.strings[0].v, 10.0);
        assert_eq!(t.strings[1].c, 0.3);
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
