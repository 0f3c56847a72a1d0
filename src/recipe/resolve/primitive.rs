//! Resolving the primitives as written: every number evaluated, SVG files
//! read, errors naming `KIND.KEY`.

use std::path::Path;
use std::sync::Arc;

use crate::base::error::{Error, Result};
use crate::base::svg::{self, Outline, Subpath};
use crate::generate::primitive::outline::drawing_commands;
use crate::generate::primitive::turtle::Env;
use crate::generate::primitive::{
    Arc as ArcPrimitive, Circle, Cylinder, Direction, Helix, PathCmd, Primitive, Spiral,
};
use crate::recipe::eval::Scope;
use crate::recipe::schema::{Num, Num3};
use crate::recipe::schema::{
    RawArc, RawCircle, RawCmd, RawCylinder, RawDirection, RawHelix, RawOutline, RawPath,
    RawPrimitive, RawSpiral,
};

impl RawPrimitive {
    /// Resolves the primitive in `scope`; a turtle runs now, starting from
    /// `env` (the part's cross-section and speed). Errors name `KIND.KEY`.
    /// SVG files are read relative to `dir`.
    pub fn resolve(&self, scope: &Scope, env: &Env, dir: &std::path::Path) -> Result<Primitive> {
        let num = |n: &Num, place: &str| scope.num(n, place);
        let files = Files {
            dir,
            max_strings: env.max_strings,
        };
        Ok(match self {
            RawPrimitive::Path(p) => Primitive::Path(p.resolve(scope, files)?),
            RawPrimitive::Circle(p) => Primitive::Circle(p.resolve(scope)?),
            RawPrimitive::Arc(p) => Primitive::Arc(p.resolve(scope)?),
            RawPrimitive::Spiral(p) => Primitive::Spiral(p.resolve(scope, files)?),
            RawPrimitive::Helix(p) => Primitive::Helix(p.resolve(scope, files)?),
            RawPrimitive::Cylinder(p) => Primitive::Cylinder(p.resolve(scope, files)?),
            RawPrimitive::PatternHelix(p) => Primitive::PatternHelix(p.resolve(&num)?),
            RawPrimitive::CaHelix(p) => Primitive::CaHelix(p.resolve(&num)?),
            RawPrimitive::Solid(s) => Primitive::Solid(super::solid::resolve(s, &num)?),
            RawPrimitive::Turtle(t) => {
                Primitive::Turtle(Box::new(super::turtle::resolve(t, scope.params, env)?))
            }
        })
    }
}

/// Where a primitive reads files and how many points it may make.
#[derive(Clone, Copy, Debug)]
pub struct Files<'a> {
    /// The folder file names are relative to (the recipe's).
    pub dir: &'a Path,
    /// The recipe's `max_strings`: most points a drawing may flatten to.
    pub max_strings: u64,
}

impl RawPath {
    /// Evaluates every command (or reads the SVG drawing); errors name
    /// `path.commands[k].KEY` or `path.KEY`.
    pub fn resolve(&self, s: &Scope, files: Files) -> Result<Vec<PathCmd>> {
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
                return drawing(
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

impl RawCircle {
    /// Evaluates every number; errors name `circle.KEY`.
    pub fn resolve(&self, s: &Scope) -> Result<Circle> {
        Ok(Circle {
            radius: s.positive(&self.radius, "circle.radius")?,
            center: s.center(&self.center, "circle")?,
            segments: s.segments(&self.segments, "circle")?,
        })
    }
}

impl RawArc {
    /// Evaluates every number; errors name `arc.KEY`.
    pub fn resolve(&self, s: &Scope) -> Result<ArcPrimitive> {
        let (start, end) = (
            s.num(&self.start, "arc.start")?,
            s.num(&self.end, "arc.end")?,
        );
        if start == end {
            return Err(Error::input(
                "arc.end",
                "expected an end angle other than start",
            ));
        }
        Ok(ArcPrimitive {
            radius: s.positive(&self.radius, "arc.radius")?,
            center: s.center(&self.center, "arc")?,
            start,
            end,
            segments: s.segments(&self.segments, "arc")?,
            rise: match &self.rise {
                Some(n) => s.num(n, "arc.rise")?,
                None => 0.0,
            },
        })
    }
}

impl RawSpiral {
    /// Evaluates every number; errors name `spiral.KEY`.
    pub fn resolve(&self, s: &Scope, files: Files) -> Result<Spiral> {
        let (radius, outline) = radius_or_outline(s, files, "spiral", &self.radius, &self.outline)?;
        let inner = match &self.inner_radius {
            Some(n) => s.non_negative(n, "spiral.inner_radius")?,
            None => 0.0,
        };
        if inner >= radius {
            return Err(Error::input(
                "spiral.inner_radius",
                format!("{inner} is not allowed; expected less than radius {radius}"),
            ));
        }
        Ok(Spiral {
            radius,
            pitch: s.positive(&self.pitch, "spiral.pitch")?,
            center: s.center(&self.center, "spiral")?,
            segments: s.segments(&self.segments, "spiral")?,
            inner_radius: inner,
            direction: match self.direction {
                Some(RawDirection::Inward) => Direction::Inward,
                _ => Direction::Outward,
            },
            outline,
        })
    }
}

impl RawHelix {
    /// Evaluates every number; errors name `helix.KEY`.
    pub fn resolve(&self, s: &Scope, files: Files) -> Result<Helix> {
        let (radius, outline) = radius_or_outline(s, files, "helix", &self.radius, &self.outline)?;
        Ok(Helix {
            radius,
            outline,
            height: s.positive(&self.height, "helix.height")?,
            pitch: s.positive(&self.pitch, "helix.pitch")?,
            center: s.center(&self.center, "helix")?,
            segments: s.segments(&self.segments, "helix")?,
        })
    }
}

impl RawCylinder {
    /// Evaluates every number; errors name `cylinder.KEY`.
    pub fn resolve(&self, s: &Scope, files: Files) -> Result<Cylinder> {
        let (radius, outline) =
            radius_or_outline(s, files, "cylinder", &self.radius, &self.outline)?;
        Ok(Cylinder {
            radius,
            outline,
            height: s.positive(&self.height, "cylinder.height")?,
            vpitch: s.positive(&self.vpitch, "cylinder.vpitch")?,
            hpitch: s.positive(&self.hpitch, "cylinder.hpitch")?,
            center: s.center(&self.center, "cylinder")?,
            segments: s.segments(&self.segments, "cylinder")?,
        })
    }
}

/// Reads the SVG `file` (relative to `files.dir`); errors name `KEY.svg`,
/// `KEY.scale` or `KEY.tolerance` under `key`.
fn read(
    s: &Scope,
    files: Files,
    key: &str,
    file: &str,
    id: Option<&str>,
    scale: &Option<Num>,
    tolerance: &Option<Num>,
) -> Result<Vec<Subpath>> {
    let scale = s.positive_or(scale, &format!("{key}.scale"), 1.0)?;
    let tolerance = s.positive_or(
        tolerance,
        &format!("{key}.tolerance"),
        svg::DEFAULT_TOLERANCE,
    )?;
    crate::base::safe_text::check(&format!("{key}.svg"), file)?;
    let opt = svg::Options {
        id,
        scale,
        tolerance,
        max_points: files.max_strings,
    };
    svg::load(&files.dir.join(file), file, &opt).map_err(|e| e.under(&format!("{key}.svg")))
}

impl RawOutline {
    /// The outline, centroid at the origin; errors name `KEY.outline.…`.
    pub fn resolve(&self, s: &Scope, files: Files, key: &str) -> Result<Arc<Outline>> {
        let key = format!("{key}.outline");
        let sub = read(
            s,
            files,
            &key,
            &self.svg,
            self.id.as_deref(),
            &self.scale,
            &self.tolerance,
        )?;
        let o = Outline::from_subpaths(&sub).map_err(|m| {
            let what = match &self.id {
                Some(id) => format!("the element with id=\"{id}\" of `{}`", self.svg),
                None => format!("the SVG file `{}`", self.svg),
            };
            Error::input(format!("{key}.svg"), format!("{what} {m}"))
        })?;
        Ok(Arc::new(o))
    }
}

/// A radius or an outline, as `helix`, `spiral` and `cylinder` take them:
/// exactly one; with an outline, the radius is its farthest distance from
/// its centroid.
pub fn radius_or_outline(
    s: &Scope,
    files: Files,
    key: &str,
    radius: &Option<Num>,
    outline: &Option<RawOutline>,
) -> Result<(f64, Option<Arc<Outline>>)> {
    match (radius, outline) {
        (Some(r), None) => Ok((s.positive(r, &format!("{key}.radius"))?, None)),
        (None, Some(o)) => {
            let o = o.resolve(s, files, key)?;
            Ok((o.max_radius(), Some(o)))
        }
        (None, None) => Err(Error::input(
            key,
            "expected `radius` (a circle) or `outline` (a closed SVG outline)",
        )),
        (Some(_), Some(_)) => Err(Error::input(
            format!("{key}.radius"),
            "expected either `radius` or `outline`, not both (an outline keeps its drawn size times `scale`)",
        )),
    }
}

/// The SVG drawing `file` as `path` commands (see [`drawing_commands`]);
/// errors name `path.KEY`.
pub fn drawing(
    s: &Scope,
    files: Files,
    file: &str,
    id: Option<&str>,
    scale: &Option<Num>,
    tolerance: &Option<Num>,
    center: &Option<Num3>,
) -> Result<Vec<PathCmd>> {
    let center = s.center(center, "path")?;
    let sub = read(s, files, "path", file, id, scale, tolerance)?;
    Ok(drawing_commands(&sub, center))
}
