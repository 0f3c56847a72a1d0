//! A step resolved: its expressions compiled over the variables it may
//! read, its image loaded. Places are `KIND.KEY` (KIND the step's key).

use std::path::PathBuf;

use super::Ctx;
use crate::base::error::{Error, Result};
use crate::base::expr::{var, Expr};
use crate::base::gcode::named::{Key, Named, SHAPER_TYPE};
use crate::base::gcode::Shaper;
use crate::generate::step::{Bitmap, Deform, Keep, Modulate, ModulateMap, Set, Step};
use crate::recipe::eval::{at, join, At, Scope};
use crate::recipe::schema::{Num, RawAxis, RawDeform, RawKeep, RawSet, RawStep};
use glam::{DAffine3, DVec3};

/// What a point's expressions may read: its place, index, and the part's
/// size (`modulate_map`'s u and v, `deform_*`'s position).
const POINT_VARS: &[usize] = &[
    var::X,
    var::Y,
    var::Z,
    var::R,
    var::THETA,
    var::I,
    var::N,
    var::T,
    var::S,
];
/// What a string's expressions may read: a point's, and its cross-section
/// and speed.
const STRING_VARS: &[usize] = &[
    var::X,
    var::Y,
    var::Z,
    var::R,
    var::THETA,
    var::C,
    var::V,
    var::I,
    var::N,
    var::T,
    var::S,
];

/// A step; its places start with its key (`deform_xyz.position[2]`).
pub(super) fn resolve(ctx: &Ctx, step: &RawStep) -> Result<Step> {
    let s = ctx.under(step.key());
    Ok(match step {
        RawStep::DeformXyz(d) => Step::DeformXyz(deform(&s, d, false)?),
        RawStep::DeformCylinder(d) => Step::DeformCylinder(deform(&s, d, true)?),
        RawStep::ModulateCylinder { factor, keep: k } => Step::ModulateCylinder(Modulate {
            factor: s.expr(at!(factor), STRING_VARS)?,
            keep: keep(k),
        }),
        RawStep::ModulateMap { .. } => Step::ModulateMap(modulate_map(ctx, &s, step)?),
        RawStep::Subdivide { max_length } => Step::Subdivide(s.positive(at!(max_length))?),
        RawStep::Translate(d) => Step::Translate(ctx.point(At::new(d, step.key()))?),
        RawStep::Rotate { angle, center } => {
            let o = s.center(at!(center))?;
            let a = s.num(at!(angle))?;
            Step::Place("rotate", about(o, DAffine3::from_rotation_z(a)))
        }
        RawStep::Scale { factor, center } => {
            let o = s.center(at!(center))?;
            let f = s.point(at!(factor))?;
            if f.x == 0.0 || f.y == 0.0 || f.z == 0.0 || !f.is_finite() {
                return Err(s.error(
                    "factor",
                    format!("[{}, {}, {}] flattens the part; expected three finite non-zero factors (negative ones mirror)", f.x, f.y, f.z),
                ));
            }
            Step::Place("scale", about(o, DAffine3::from_scale(f)))
        }
        RawStep::Mirror { axis, at } => {
            let c = match at {
                Some(n) => s.num(At::new(n, "at"))?,
                None => 0.0,
            };
            let (flip, o) = match axis {
                RawAxis::X => (DVec3::new(-1.0, 1.0, 1.0), DVec3::new(c, 0.0, 0.0)),
                RawAxis::Y => (DVec3::new(1.0, -1.0, 1.0), DVec3::new(0.0, c, 0.0)),
                RawAxis::Z => (DVec3::new(1.0, 1.0, -1.0), DVec3::new(0.0, 0.0, c)),
            };
            Step::Place("mirror", about(o, DAffine3::from_scale(flip)))
        }
        RawStep::GcodeAt { z, gcode } => Step::GcodeAt(s.num(at!(z))?, gcode_at(ctx, &s, gcode)?),
        RawStep::Set(raw) => Step::Set(Box::new(set(&s, raw)?)),
    })
}

/// `gcode_at`'s line, `s` under its key: each `{expr}` replaced by its
/// value over the params, then checked as a literal line is.
fn gcode_at(ctx: &Ctx, s: &Scope, text: &str) -> Result<std::sync::Arc<str>> {
    use crate::base::format::{fmt_value, pieces, Piece};
    let cut = pieces(text).map_err(|m| s.error("gcode", m))?;
    let mut line = String::with_capacity(text.len());
    for c in &cut {
        match c {
            Piece::Text(t) => line.push_str(t),
            Piece::Expr(src) => {
                let n = Num::Expr((*src).into());
                let v = s.num(At::new(&n, "gcode"))?;
                line.push_str(&fmt_value(crate::recipe::eval::finite(
                    v,
                    &s.place("gcode"),
                )?));
            }
        }
    }
    (ctx.gcode)(&line).map_err(|m| {
        if line == text {
            s.error("gcode", m)
        } else {
            s.error(
                "gcode",
                format!("the line `{}` made here: {m}", line.trim()),
            )
        }
    })?;
    Ok(line.trim().into())
}

/// A `set` step; `s` is under its key.
fn set(s: &Scope, raw: &RawSet) -> Result<Set> {
    use crate::base::toolpath::Pace;
    use crate::generate::step::set::{Bands, NAMES, VARS};
    let bands = match (&raw.every, &raw.band) {
        (Some(_), Some(_)) => {
            return Err(s.error(
                "band",
                "a `set` step has height bands (`every`) or is one line's band (`band`), not both; expected one of them",
            ))
        }
        (Some(_), None) => Bands::Height {
            from: match &raw.from {
                Some(n) => s.num(At::new(n, "from"))?,
                None => 0.0,
            },
            every: s.positive(at!(raw.every).some().expect("given"))?,
        },
        (None, Some(_)) => Bands::Line(s.whole(at!(raw.band).some().expect("given"), 0)?),
        (None, None) => {
            if raw.from.is_some() {
                return Err(s.error("from", "`from` is where height bands begin; expected `every` beside it"));
            }
            Bands::Once
        }
    };
    let compile = |key: &str, n: &Num| {
        let e =
            Expr::compile_ext(&n.src(), s.params, VARS, NAMES).map_err(|e| e.at(s.place(key)))?;
        if e.rands() > 0 {
            return Err(s.error(key, "`rand()` would set another value on every build of the same band; expected an expression of the position and `band`"));
        }
        Ok(e)
    };
    let pace =
        match raw.paces().as_slice() {
            [] => None,
            [(key, n)] => {
                let kind = if *key == "speed" {
                    Pace::Speed
                } else {
                    Pace::Volumetric
                };
                Some((kind, compile(key, n)?))
            }
            _ => return Err(s.error(
                "volumetric_speed",
                "`speed` and `volumetric_speed` both set the strings' speed; expected one of them",
            )),
        };
    let named = named(raw, s.here(), compile)?;
    Ok(Set { bands, named, pace })
}

/// The settings of a `set` step or command written at `place` (its bands
/// aside), each value made by `compile` (given the key and the value as
/// written): the one reading of a settings map, which a step and a
/// turtle's or path's command share.
pub(super) fn named<T>(
    raw: &RawSet,
    place: &str,
    mut compile: impl FnMut(&'static str, &Num) -> Result<T>,
) -> Result<Named<T>> {
    let error = |key: &str, m: String| Error::input(join(place, key), m);
    let mut values = Vec::new();
    for (key, n) in raw.values() {
        values.push((Key::of(key).expect("a setting's key"), compile(key, n)?));
    }
    let shaper = match &raw.input_shaper_type {
        Some(t) => Some(Shaper::parse(t).ok_or_else(|| {
            error(
                SHAPER_TYPE,
                format!("unknown input shaper `{t}`; expected one of zv, mzv, zvd, ei, 2hump_ei, 3hump_ei"),
            )
        })?),
        None => None,
    };
    if values.is_empty() && shaper.is_none() && raw.paces().is_empty() {
        return Err(error("", "`set` sets nothing; expected a setting such as `nozzle_temperature: \"start + band*step\"` (see docs/recipe.md)".into()));
    }
    if raw.wait.is_some() && raw.nozzle_temperature.is_none() {
        return Err(error(
            "wait",
            "`wait` waits for `nozzle_temperature`; expected it beside that key".into(),
        ));
    }
    Ok(Named {
        values,
        wait: raw.wait.unwrap_or(false),
        shaper,
    })
}

/// `map` applied about `o` instead of the origin.
fn about(o: DVec3, map: DAffine3) -> DAffine3 {
    DAffine3::from_translation(o) * map * DAffine3::from_translation(-o)
}

fn keep(k: &Option<RawKeep>) -> Keep {
    match k {
        Some(RawKeep::Speed) => Keep::Speed,
        _ => Keep::Flow,
    }
}

/// `deform_xyz` reads `r` and `theta` as the point's cylinder coordinates
/// (`z + cos(6*theta)` is a wave round the part), but a position written
/// as a cylinder one, `[r, f(theta), …]`, maps x to the radius and y to the
/// angle: a column off to one side without a word. That one is refused.
fn cartesian_only(n: &[Num; 3], e: &[Expr], s: &Scope) -> Result<()> {
    let bare_r = matches!(&n[0], Num::Expr(t) if t.trim() == "r");
    let angle_y = e[1].uses(var::THETA) && !e[1].uses(var::X) && !e[1].uses(var::Y);
    if bare_r && angle_y {
        return Err(s.error(
            "",
            "[r, …(theta), …] is a cylinder position, but deform_xyz maps [x, y, z] (it would put x at the radius and y at the angle); expected deform_cylinder: {position: [r, theta, z]} for cylinder coordinates",
        ));
    }
    Ok(())
}

/// `deform_xyz` or `deform_cylinder`; `s` is under its key.
fn deform(s: &Scope, d: &RawDeform, cylinder: bool) -> Result<Deform> {
    let position = match at!(d.position).some() {
        Some(p) => {
            let ps = s.under(p.key);
            let n = p.value;
            let mut out = Vec::with_capacity(3);
            for (n, key) in n.iter().zip(["[0]", "[1]", "[2]"]) {
                out.push(ps.expr(At::new(n, key), POINT_VARS)?);
            }
            if !cylinder {
                cartesian_only(n, &out, &ps)?;
            }
            Some(out.try_into().expect("three coordinates"))
        }
        None => None,
    };
    Ok(Deform {
        cylinder,
        position,
        cross_section: at!(d.cross_section)
            .some()
            .map(|n| s.expr(n, STRING_VARS))
            .transpose()?,
        speed: at!(d.speed)
            .some()
            .map(|n| s.expr(n, STRING_VARS))
            .transpose()?,
    })
}

/// `modulate_map`; `s` is under its key, images are read from `ctx.dir`.
fn modulate_map(ctx: &Ctx, s: &Scope, step: &RawStep) -> Result<ModulateMap> {
    let RawStep::ModulateMap {
        image,
        text,
        u,
        v,
        dark,
        light,
        threshold,
        keep: k,
    } = step
    else {
        unreachable!("resolve sends only modulate_map here")
    };
    let factor = |n: At<Option<Num>>| match n.some() {
        Some(n) => s.positive(n),
        None => Ok(1.0),
    };
    let threshold = match at!(threshold).some() {
        Some(n) => {
            let t = s.num(n)?;
            if !(0.0..=1.0).contains(&t) {
                return Err(s.error(
                    n.key,
                    format!("{t} is not allowed; expected a number from 0 to 1"),
                ));
            }
            t
        }
        None => 0.5,
    };
    let (image_key, text_key) = (at!(image).key, at!(text).key);
    let bitmap = match (image, text) {
        (Some(image), None) => load_bitmap(&ctx.dir.join(image), image, &ctx.cx.reads)
            .map_err(|e| e.under(&s.place(image_key)))?,
        (None, Some(text)) => Bitmap::from_text(text).map_err(|e| e.under(&s.place(text_key)))?,
        _ => {
            return Err(s.error(
                "",
                "expected exactly one of `image` (a picture file) and `text` (letters)",
            ))
        }
    };
    Ok(ModulateMap {
        image: bitmap,
        u: s.expr(at!(u), POINT_VARS)?,
        v: s.expr(at!(v), POINT_VARS)?,
        dark: factor(at!(dark))?,
        light: factor(at!(light))?,
        threshold,
        keep: keep(k),
    })
}

/// Loads an image as grey levels 0..1; the error names the image as written
/// (an input error with no place: the caller names the key; an I/O failure
/// keeps its [`std::io::ErrorKind`]).
pub(crate) fn load_bitmap(
    path: &PathBuf,
    shown: &str,
    reads: &crate::base::input::Reads,
) -> Result<Bitmap> {
    let io = |message: String, e: &std::io::Error| Error {
        io_kind: Some(e.kind()),
        ..Error::input("", message)
    };
    reads.reach(path, "image")?;
    if let Err(e) = std::fs::metadata(path) {
        let m = format!("cannot open the image `{shown}` ({}): {e}", path.display());
        return Err(io(m, &e));
    }
    // a regular file only (never a FIFO or device), bounded
    let file = crate::base::input::open_regular(path, "image")?;
    let bytes = crate::base::input::read_bounded(file, crate::base::input::MAX_IMAGE_BYTES)
        .map_err(|e| io(format!("cannot read the image `{shown}`: {e}"), &e))?
        .ok_or_else(|| {
            Error::input(
                "",
                format!(
                    "the image `{shown}` is larger than {} MB; expected a smaller file",
                    crate::base::input::MAX_IMAGE_BYTES >> 20
                ),
            )
        })?;
    let open = || {
        image::ImageReader::new(std::io::Cursor::new(&bytes[..]))
            .with_guessed_format()
            .map_err(|e| io(format!("cannot read the image `{shown}`: {e}"), &e))
    };
    // the header's size first: a small file may declare a huge image
    let (w, h) = open()?.into_dimensions().map_err(|e| {
        Error::input(
            "",
            format!("`{shown}` is not an image p3dp can read (PNG, JPEG, BMP, GIF): {e}"),
        )
    })?;
    crate::base::input::check_image_size(w, h)
        .map_err(|m| Error::input("", format!("the image `{shown}` {m}")))?;
    let mut reader = open()?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w.max(1));
    limits.max_image_height = Some(h.max(1));
    limits.max_alloc = Some(crate::base::input::MAX_IMAGE_PIXELS * 8);
    reader.limits(limits);
    let img = reader.decode().map_err(|e| {
        Error::input(
            "",
            format!("`{shown}` is not an image p3dp can read (PNG, JPEG, BMP, GIF): {e}"),
        )
    })?;
    let grey = img.to_luma8();
    let (w, h) = grey.dimensions();
    if w == 0 || h == 0 {
        return Err(Error::input("", format!("the image `{shown}` is empty")));
    }
    Ok(Bitmap {
        width: w as usize,
        height: h as usize,
        pixels: grey.as_raw().iter().map(|&p| p as f32 / 255.0).collect(),
    })
}
