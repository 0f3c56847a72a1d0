//! A step resolved: its expressions compiled over the variables it may
//! read, its image loaded. Places are `KIND.KEY` (KIND the step's key).

use std::path::PathBuf;

use super::Ctx;
use crate::base::error::{Error, Result};
use crate::base::expr::var;
use crate::generate::step::{Bitmap, Deform, Keep, Modulate, ModulateMap, Step};
use crate::recipe::eval::{at, At, Scope};
use crate::recipe::schema::{Num, RawDeform, RawKeep, RawStep};

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
    })
}

fn keep(k: &Option<RawKeep>) -> Keep {
    match k {
        Some(RawKeep::Speed) => Keep::Speed,
        _ => Keep::Flow,
    }
}

/// `deform_xyz` or `deform_cylinder`; `s` is under its key.
fn deform(s: &Scope, d: &RawDeform, cylinder: bool) -> Result<Deform> {
    let position = match at!(d.position).some() {
        Some(p) => {
            let ps = s.under(p.key);
            let n = p.value;
            Some([
                ps.expr(At::new(&n[0], "[0]"), POINT_VARS)?,
                ps.expr(At::new(&n[1], "[1]"), POINT_VARS)?,
                ps.expr(At::new(&n[2], "[2]"), POINT_VARS)?,
            ])
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
pub fn load_bitmap(
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
