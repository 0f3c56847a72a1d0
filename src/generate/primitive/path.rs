//! `path`: the papers' low-level API (`move`, `draw`, `setCrossSection`, `setVelocity`).

use glam::DVec3;

use crate::base::toolpath::Toolpath;
use serde::Deserialize;

use crate::base::error::{Error, Result};
use crate::base::num::{Num, Num3, Scope};

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
pub fn string_count(cmds: &[PathCmd]) -> u64 {
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
pub fn build(cmds: &[PathCmd], c0: f64, v0: f64) -> Toolpath {
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

/// A `path` command as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum RawCmd {
    Move(Num3),
    Draw(Num3),
    CrossSection(Num),
    Speed(Num),
}

/// `path:` as written: commands, or an SVG drawing.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawPath {
    /// The commands, in order.
    #[serde(default)]
    pub commands: Option<Vec<RawCmd>>,
    /// An SVG file whose paths are drawn as strings (instead of `commands`).
    #[serde(default)]
    pub svg: Option<String>,
    /// Only the SVG element with this id.
    #[serde(default)]
    pub id: Option<String>,
    /// Factor on the SVG's drawn size (mm).
    #[serde(default)]
    pub scale: Option<Num>,
    /// Chord tolerance of flattened curves, mm.
    #[serde(default)]
    pub tolerance: Option<Num>,
    /// Where the centre of the drawing's bounding box goes.
    #[serde(default)]
    pub center: Option<Num3>,
}

impl RawPath {
    /// Evaluates every command (or reads the SVG drawing); errors name
    /// `path.commands[k].KEY` or `path.KEY`.
    pub fn resolve(&self, s: &Scope, files: super::outline::Files) -> Result<Vec<PathCmd>> {
        let svg_only = [
            ("id", self.id.is_some()),
            ("scale", self.scale.is_some()),
            ("tolerance", self.tolerance.is_some()),
            ("center", self.center.is_some()),
        ];
        let commands = match (&self.commands, &self.svg) {
            (Some(c), None) => {
                if let Some((k, _)) = svg_only.iter().find(|(_, set)| *set) {
                    return Err(Error::input(
                        format!("path.{k}"),
                        "this key belongs with `svg`; expected it only when the path draws an SVG file",
                    ));
                }
                c
            }
            (None, Some(file)) => {
                return super::outline::drawing_commands(
                    s,
                    files,
                    file,
                    self.id.as_deref(),
                    &self.scale,
                    &self.tolerance,
                    &self.center,
                )
            }
            _ => {
                return Err(Error::input(
                    "path",
                    "expected exactly one of `commands` (move, draw, …) and `svg` (an SVG file to draw)",
                ))
            }
        };
        let mut cmds = Vec::with_capacity(commands.len());
        for (k, c) in commands.iter().enumerate() {
            let place = format!("path.commands[{k}]");
            cmds.push(match c {
                RawCmd::Move(n) => PathCmd::Move(s.point(n, &format!("{place}.move"))?),
                RawCmd::Draw(n) => PathCmd::Draw(s.point(n, &format!("{place}.draw"))?),
                RawCmd::CrossSection(n) => {
                    PathCmd::CrossSection(s.positive(n, &format!("{place}.cross_section"))?)
                }
                RawCmd::Speed(n) => PathCmd::Speed(s.positive(n, &format!("{place}.speed"))?),
            });
        }
        if !cmds.iter().any(|c| matches!(c, PathCmd::Draw(_))) {
            return Err(Error::input(
                "path.commands",
                "expected at least one `draw` command (a path that extrudes nothing prints nothing)",
            ));
        }
        Ok(cmds)
    }
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
