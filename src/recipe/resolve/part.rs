//! A leaf part resolved: its primitives (each maybe with its own
//! cross-section and speed), steps, brim and stand. Places are relative to
//! the part (the caller puts them under its place).

use super::Ctx;
use crate::base::error::{Error, Result};
use crate::generate::model::{Brim, Part, Piece, Stand};
use crate::generate::primitive::turtle::Env;
use crate::generate::primitive::Primitive;
use crate::recipe::eval::{at, join, key, Scope};
use crate::recipe::schema::{RawBrim, RawPart, RawPrimitiveItem, RawStand};

/// Leaf part `k`; `c0` and `v0` are the defaults' cross-section and speed.
pub(super) fn resolve(ctx: &Ctx, p: &RawPart, c0: f64, v0: f64, k: usize) -> Result<Part> {
    let cross_section = ctx.positive_or(at!(p.cross_section), c0)?;
    let speed = ctx.positive_or(at!(p.speed), v0)?;
    // one primitive or a list, each maybe with its own c and v
    let items = p
        .primitive
        .as_ref()
        .map(|x| x.items(key!(p.primitive)))
        .unwrap_or_default();
    if items.is_empty() {
        return Err(ctx.error(key!(p.primitive), "expected at least one primitive"));
    }
    let mut pieces = Vec::with_capacity(items.len());
    for (key, item) in items {
        pieces.push(piece(ctx, p, item, &key, (cross_section, speed))?);
    }
    let first = pieces.remove(0);
    let mut steps = Vec::with_capacity(p.steps.len());
    for (j, s) in p.steps.iter().enumerate() {
        let at = join(key!(p.steps), &format!("[{j}]"));
        steps.push(super::step::resolve(ctx, s).map_err(|e| e.under(&at))?);
    }
    Ok(Part {
        name: p.name.clone().unwrap_or_else(|| format!("part {}", k + 1)),
        cross_section: first.cross_section,
        speed: first.speed,
        primitive: first.primitive,
        steps,
        more: pieces,
        place: format!("parts[{k}]"),
        brim: match &p.brim {
            Some(b) => Some(brim(&ctx.under(key!(p.brim)), b, speed)?),
            None => None,
        },
        stand: match &p.stand {
            Some(st) => Some(stand(&ctx.under(key!(p.stand)), st, speed)?),
            None => None,
        },
    })
}

/// Puts the key paths a turtle's or path's settings name under `prefix`,
/// as the errors of its resolution are.
pub(super) fn settings_under(p: &mut Primitive, prefix: &str) {
    if let Primitive::Turtle(t) = p {
        t.place_under(prefix);
    }
}

/// One primitive of part `p`, written at `key` (`primitive`,
/// `primitive[k]`), with its own cross-section and speed or the part's
/// (`cv`).
fn piece(
    ctx: &Ctx,
    p: &RawPart,
    item: &RawPrimitiveItem,
    key: &str,
    cv: (f64, f64),
) -> Result<Piece> {
    let s = ctx.under(key);
    let c = s.positive_or(at!(item.cross_section), cv.0)?;
    let v = s.positive_or(at!(item.speed), cv.1)?;
    // a turtle runs now: its strings start with the part's c and v
    let env = Env {
        cross_section: c,
        speed: v,
        filament_area: ctx.turtle.0,
        max_strings: ctx.turtle.1,
    };
    let mut primitive = super::primitive::resolve(
        &item.primitive,
        &ctx.scope,
        &env,
        ctx.dir,
        ctx.cx,
        ctx.gcode,
    )
    .map_err(|e| e.under(key))?;
    settings_under(&mut primitive, key);
    // a solid's beads are layer_height × line_width: a cross_section the
    // recipe gives for it would be silently ignored, so refuse it
    if let Primitive::Solid(sol) = &primitive {
        let bead = sol.layer_height * sol.line_width;
        let given = item.cross_section.is_some() || p.cross_section.is_some();
        if given && (c - bead).abs() > 1e-9 * bead {
            let at = if item.cross_section.is_some() {
                s.place(key!(item.cross_section))
            } else {
                ctx.place(key!(p.cross_section))
            };
            return Err(Error::input(
                at,
                format!(
                    "{c} is not used by a solid: its beads are layer_height × line_width = {} mm² (infill squeezed to its spacing); remove cross_section or set it to {}",
                    crate::base::format::fmt_num(bead),
                    crate::base::format::fmt_num(bead)
                ),
            ));
        }
    }
    Ok(Piece {
        primitive,
        cross_section: c,
        speed: v,
    })
}

/// `brim:`; `s` is under `brim`.
fn brim(s: &Scope, b: &RawBrim, speed: f64) -> Result<Brim> {
    Ok(Brim {
        loops: {
            let n = s.positive(at!(b.loops))?;
            if n.fract() != 0.0 || n > 1000.0 {
                return Err(s.error(
                    key!(b.loops),
                    format!("{n} is not allowed; expected a whole number of loops, 1 to 1000"),
                ));
            }
            n as u32
        },
        line_width: s.positive_or(at!(b.line_width), 0.45)?,
        layer_height: s.positive_or(at!(b.layer_height), 0.2)?,
        speed: s.positive_or(at!(b.speed), speed)?,
    })
}

/// `stand:`; `s` is under `stand`.
fn stand(s: &Scope, st: &RawStand, speed: f64) -> Result<Stand> {
    let radius = s.positive(at!(st.radius))?;
    if radius > 1000.0 {
        return Err(s.error(
            key!(st.radius),
            format!("{radius} mm is not allowed; expected at most 1000 mm"),
        ));
    }
    let walls = match at!(st.walls).some() {
        Some(w) => {
            let n = s.positive(w)?;
            if n.fract() != 0.0 || n > 100.0 {
                return Err(s.error(
                    w.key,
                    format!("{n} is not allowed; expected a whole number of walls, 1 to 100"),
                ));
            }
            n as u32
        }
        None => 2,
    };
    Ok(Stand {
        radius,
        walls,
        height: at!(st.height).some().map(|n| s.positive(n)).transpose()?,
        line_width: s.positive_or(at!(st.line_width), 0.45)?,
        layer_height: s.positive_or(at!(st.layer_height), 0.2)?,
        speed: s.positive_or(at!(st.speed), speed)?,
    })
}
