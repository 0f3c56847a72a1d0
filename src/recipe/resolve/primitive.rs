//! Resolving the primitives as written: every number evaluated, SVG files
//! read, errors naming `KIND.KEY` (KIND the primitive's key, KEY the field's
//! own name, see [`crate::recipe::eval`]).

use crate::base::input::Reads;
use crate::recipe::context::Context;
use std::path::Path;
use std::sync::Arc;

use crate::base::error::Result;
use crate::base::svg::{self, Outline, Subpath};
use crate::generate::primitive::outline::drawing_commands;
use crate::generate::primitive::turtle::Env;
use crate::generate::primitive::{
    Arc as ArcPrimitive, Circle, Cylinder, Direction, Helix, Primitive, Spiral,
};
use crate::recipe::eval::{at, key, At, Scope};
use crate::recipe::schema::Num;
use crate::recipe::schema::{
    RawArc, RawCircle, RawCylinder, RawDirection, RawHelix, RawOutline, RawPath, RawPrimitive,
    RawSpiral,
};

/// Resolves the primitive in `scope`; a turtle runs now, starting from
/// `env` (the part's cross-section and speed). Errors name `KIND.KEY`.
/// SVG files are read relative to `dir`, noted in `cx`, whose lent
/// z-buffers a solid starts from.
pub(super) fn resolve(
    raw: &RawPrimitive,
    scope: &Scope,
    env: &Env,
    dir: &Path,
    cx: &Context,
    gcode: super::GcodeCheck,
) -> Result<Primitive> {
    let files = Files {
        dir,
        max_strings: env.max_strings,
        reads: &cx.reads,
    };
    let s = scope.under(raw.key());
    Ok(match raw {
        RawPrimitive::Path(p) => path(p, &s, files, env, gcode)?,
        RawPrimitive::Circle(p) => Primitive::Circle(circle(p, &s)?),
        RawPrimitive::Arc(p) => Primitive::Arc(arc(p, &s)?),
        RawPrimitive::Spiral(p) => Primitive::Spiral(spiral(p, &s, files)?),
        RawPrimitive::Helix(p) => Primitive::Helix(helix(p, &s, files)?),
        RawPrimitive::Cylinder(p) => Primitive::Cylinder(cylinder(p, &s, files)?),
        RawPrimitive::PatternHelix(p) => {
            Primitive::PatternHelix(super::pattern::pattern_helix(p, &s)?)
        }
        RawPrimitive::CaHelix(p) => Primitive::CaHelix(super::pattern::ca_helix(p, &s)?),
        RawPrimitive::Solid(p) => {
            Primitive::Solid(super::solid::resolve(p, &s, cx.zbuffers.as_ref())?)
        }
        RawPrimitive::Turtle(t) => {
            Primitive::Turtle(Box::new(super::turtle::resolve(t, &s, env, gcode)?))
        }
        RawPrimitive::Label(p) => Primitive::Label(label(p, &s)?),
    })
}

/// `label:`; `s` is under `label`.
fn label(
    raw: &crate::recipe::schema::RawLabel,
    s: &Scope,
) -> Result<crate::generate::primitive::Label> {
    use crate::generate::primitive::label::{segments, CHARSET};
    let text = crate::recipe::expand::fill_name(&raw.text, s.params, &s.place("text"))?;
    crate::base::safe_text::check(&s.place("text"), &text)?;
    if text.trim().is_empty() || text.chars().count() > 32 {
        return Err(s.error("text", format!("{text:?}: expected 1 to 32 characters")));
    }
    if let Some(c) = text.chars().find(|c| segments(*c).is_none()) {
        return Err(s.error(
            "text",
            format!("{text:?} holds {c:?}, which the seven-segment font cannot draw; expected {CHARSET}"),
        ));
    }
    Ok(crate::generate::primitive::Label {
        text,
        center: s.center(at!(raw.center))?,
        height: s.positive_or(at!(raw.height), 5.0)?,
        layers: match at!(raw.layers).some() {
            Some(n) => s.whole_max(n, 1, 1000)?,
            None => 1,
        },
        layer_height: s.positive_or(at!(raw.layer_height), 0.2)?,
        angle: match at!(raw.angle).some() {
            Some(n) => s.num(n)?,
            None => 0.0,
        },
    })
}

/// Where a primitive reads files and how many points it may make.
#[derive(Clone, Copy, Debug)]
pub(super) struct Files<'a> {
    /// The folder file names are relative to (the recipe's).
    pub(crate) dir: &'a Path,
    /// The recipe's `max_strings`: most points a drawing may flatten to.
    pub(crate) max_strings: u64,
    /// Where every file read is noted.
    pub(crate) reads: &'a Reads,
}

/// `path:` its commands run (or the SVG drawing read); `s` is under `path`.
fn path(
    raw: &RawPath,
    s: &Scope,
    files: Files,
    env: &Env,
    gcode: super::GcodeCheck,
) -> Result<Primitive> {
    let svg_only = [
        (key!(raw.id), raw.id.is_some()),
        (key!(raw.scale), raw.scale.is_some()),
        (key!(raw.tolerance), raw.tolerance.is_some()),
        (key!(raw.center), raw.center.is_some()),
    ];
    let commands = match (&raw.commands, &raw.svg) {
        (Some(c), None) => {
            if let Some((k, _)) = svg_only.iter().find(|(_, set)| *set) {
                return Err(s.error(
                    k,
                    "this key belongs with `svg`; expected it only when the path draws an SVG file",
                ));
            }
            c
        }
        (None, Some(file)) => {
            let center = s.center(at!(raw.center))?;
            let svg = At::new(file, key!(raw.svg));
            let sub = read(
                s,
                files,
                svg,
                at!(raw.id),
                at!(raw.scale),
                at!(raw.tolerance),
            )?;
            return Ok(Primitive::Path(drawing_commands(&sub, center)));
        }
        _ => return Err(s.error(
            "",
            "expected exactly one of `commands` (move, draw, …) and `svg` (an SVG file to draw)",
        )),
    };
    // the turtle's language, run now: a path starts where its first
    // travel goes, and its `move` and `draw` make a string each (v1)
    let key = if raw.is_list() {
        ""
    } else {
        key!(raw.commands)
    };
    let t = super::turtle::resolve_path(commands, key, s, env, gcode)?;
    Ok(Primitive::Turtle(Box::new(t)))
}

fn circle(raw: &RawCircle, s: &Scope) -> Result<Circle> {
    Ok(Circle {
        radius: s.positive(at!(raw.radius))?,
        center: s.center(at!(raw.center))?,
        segments: s.segments(at!(raw.segments))?,
    })
}

fn arc(raw: &RawArc, s: &Scope) -> Result<ArcPrimitive> {
    let (start, end) = (s.num(at!(raw.start))?, s.num(at!(raw.end))?);
    if start == end {
        return Err(s.error(key!(raw.end), "expected an end angle other than start"));
    }
    Ok(ArcPrimitive {
        radius: s.positive(at!(raw.radius))?,
        center: s.center(at!(raw.center))?,
        start,
        end,
        segments: s.segments(at!(raw.segments))?,
        rise: match at!(raw.rise).some() {
            Some(n) => s.num(n)?,
            None => 0.0,
        },
    })
}

fn spiral(raw: &RawSpiral, s: &Scope, files: Files) -> Result<Spiral> {
    let (radius, outline) = radius_or_outline(s, files, at!(raw.radius), at!(raw.outline))?;
    let inner = match at!(raw.inner_radius).some() {
        Some(n) => s.non_negative(n)?,
        None => 0.0,
    };
    if inner >= radius {
        return Err(s.error(
            key!(raw.inner_radius),
            format!("{inner} is not allowed; expected less than radius {radius}"),
        ));
    }
    Ok(Spiral {
        radius,
        pitch: s.positive(at!(raw.pitch))?,
        center: s.center(at!(raw.center))?,
        segments: s.segments(at!(raw.segments))?,
        inner_radius: inner,
        direction: match raw.direction {
            Some(RawDirection::Inward) => Direction::Inward,
            _ => Direction::Outward,
        },
        outline,
    })
}

fn helix(raw: &RawHelix, s: &Scope, files: Files) -> Result<Helix> {
    let (radius, outline) = radius_or_outline(s, files, at!(raw.radius), at!(raw.outline))?;
    Ok(Helix {
        radius,
        outline,
        height: s.positive(at!(raw.height))?,
        pitch: s.positive(at!(raw.pitch))?,
        center: s.center(at!(raw.center))?,
        segments: s.segments(at!(raw.segments))?,
    })
}

fn cylinder(raw: &RawCylinder, s: &Scope, files: Files) -> Result<Cylinder> {
    let (radius, outline) = radius_or_outline(s, files, at!(raw.radius), at!(raw.outline))?;
    Ok(Cylinder {
        radius,
        outline,
        height: s.positive(at!(raw.height))?,
        vpitch: s.positive(at!(raw.vpitch))?,
        hpitch: s.positive(at!(raw.hpitch))?,
        center: s.center(at!(raw.center))?,
        segments: s.segments(at!(raw.segments))?,
    })
}

/// Reads the SVG file `svg` (relative to `files.dir`), only the element
/// `id` when given, at `scale` and `tolerance`; errors name those keys in `s`.
fn read(
    s: &Scope,
    files: Files,
    svg: At<String>,
    id: At<Option<String>>,
    scale: At<Option<Num>>,
    tolerance: At<Option<Num>>,
) -> Result<Vec<Subpath>> {
    let scale = s.positive_or(scale, 1.0)?;
    let tolerance = s.positive_or(tolerance, svg::DEFAULT_TOLERANCE)?;
    let file = svg.value.as_str();
    crate::base::safe_text::check(&s.place(svg.key), file)?;
    let opt = svg::Options {
        id: id.value.as_deref(),
        scale,
        tolerance,
        max_points: files.max_strings,
    };
    svg::load(&files.dir.join(file), file, &opt, files.reads)
        .map_err(|e| e.under(&s.place(svg.key)))
}

/// `outline:` the closed outline, centroid at the origin; `s` is under
/// `KIND.outline`.
fn outline(raw: &RawOutline, s: &Scope, files: Files) -> Result<Arc<Outline>> {
    let svg = at!(raw.svg);
    let sub = read(
        s,
        files,
        svg,
        at!(raw.id),
        at!(raw.scale),
        at!(raw.tolerance),
    )?;
    let o = Outline::from_subpaths(&sub).map_err(|m| {
        let what = match &raw.id {
            Some(id) => format!("the element with id=\"{id}\" of `{}`", raw.svg),
            None => format!("the SVG file `{}`", raw.svg),
        };
        s.error(svg.key, format!("{what} {m}"))
    })?;
    Ok(Arc::new(o))
}

/// A radius or an outline, as `helix`, `spiral` and `cylinder` take them:
/// exactly one; with an outline, the radius is its farthest distance from
/// its centroid.
fn radius_or_outline(
    s: &Scope,
    files: Files,
    radius: At<Option<Num>>,
    outline_at: At<Option<RawOutline>>,
) -> Result<(f64, Option<Arc<Outline>>)> {
    match (radius.some(), outline_at.some()) {
        (Some(r), None) => Ok((s.positive(r)?, None)),
        (None, Some(o)) => {
            let o = outline(o.value, &s.under(o.key), files)?;
            Ok((o.max_radius(), Some(o)))
        }
        (None, None) => Err(s.error(
            "",
            "expected `radius` (a circle) or `outline` (a closed SVG outline)",
        )),
        (Some(_), Some(_)) => Err(s.error(
            radius.key,
            "expected either `radius` or `outline`, not both (an outline keeps its drawn size times `scale`)",
        )),
    }
}
