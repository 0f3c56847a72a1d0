//! Resolving `solid:`: numbers evaluated, the z-buffer computed.

use crate::base::error::Result;
use crate::generate::primitive::solid::Reusing;
use crate::generate::primitive::solid::{Body, Feature, Infill, Op, Pattern, Solid};
use crate::recipe::eval::{at, key, At, Scope};
use crate::recipe::schema::{RawFeature, RawInfill, RawOp, RawPattern, RawSolid};

/// Resolves `solid:`; `s` is under `solid`, so places read
/// `solid.features[1].cylinder.radius`.
pub(super) fn resolve(raw: &RawSolid, s: &Scope, reuse: Option<&Reusing>) -> Result<Solid> {
    let layer_height = s.positive_or(at!(raw.layer_height), 0.2)?;
    let line_width = s.positive_or(at!(raw.line_width), 0.45)?;
    let chord_tolerance = s.positive_or(at!(raw.chord_tolerance), 0.01)?;
    let perimeters = match at!(raw.perimeters).some() {
        Some(n) => s.whole_max(n, 0, 1000)?,
        None => 2,
    };
    let infill = match &raw.infill {
        Some(i) => infill(i, &s.under(key!(raw.infill)), line_width)?,
        None => Infill {
            angle: 45.0,
            spacing: line_width,
            alternate: true,
            pattern: Pattern::Lines,
            connect: false,
        },
    };
    if raw.features.is_empty() {
        return Err(s.error(
            key!(raw.features),
            "expected at least one feature (`box` or `cylinder`)",
        ));
    }
    let list = s.under(key!(raw.features));
    let mut features = Vec::with_capacity(raw.features.len());
    for (k, f) in raw.features.iter().enumerate() {
        features.push(feature(f, &list.under(&format!("[{k}]")), k == 0)?);
    }
    Solid::new(
        layer_height,
        perimeters,
        line_width,
        chord_tolerance,
        infill,
        features,
        reuse,
    )
}

/// `infill:`; `s` is under `solid.infill`.
fn infill(raw: &RawInfill, s: &Scope, line_width: f64) -> Result<Infill> {
    let pattern = match raw.pattern {
        None | Some(RawPattern::Lines) => Pattern::Lines,
        Some(RawPattern::Grid) => Pattern::Grid,
    };
    // a grid lays two directions: each at twice the width is solid
    let solid_spacing = match pattern {
        Pattern::Lines => line_width,
        Pattern::Grid => 2.0 * line_width,
    };
    Ok(Infill {
        angle: match at!(raw.angle).some() {
            Some(n) => s.num(n)?,
            None => 45.0,
        },
        spacing: s.positive_or(at!(raw.spacing), solid_spacing)?,
        alternate: raw.alternate.unwrap_or(true),
        pattern,
        connect: raw.connect.unwrap_or(false),
    })
}

/// Feature `[k]` of `features:`; `s` is under `solid.features[k]`. The
/// first must add material.
fn feature(raw: &RawFeature, s: &Scope, first: bool) -> Result<Feature> {
    // a feature is an enum's variant: its key is the variant's name
    let (s, op) = match raw {
        RawFeature::Box(b) => (s.under("box"), At::new(&b.op, key!(b.op))),
        RawFeature::Cylinder(c) => (s.under("cylinder"), At::new(&c.op, key!(c.op))),
    };
    let body = match raw {
        RawFeature::Box(b) => {
            let size = s.point(at!(b.size))?;
            for i in 0..3 {
                if size[i] <= 0.0 {
                    return Err(s.under(key!(b.size)).error(
                        &format!("[{i}]"),
                        format!("{} is not allowed; expected a number > 0", size[i]),
                    ));
                }
            }
            Body::Box {
                center: s.point(at!(b.center))?,
                size,
            }
        }
        RawFeature::Cylinder(c) => Body::Cylinder {
            center: s.point(at!(c.center))?,
            radius: s.positive(at!(c.radius))?,
            height: s.positive(at!(c.height))?,
        },
    };
    let op_key = op.key;
    let op = match op.value {
        None | Some(RawOp::Union) => Op::Union,
        Some(RawOp::Subtract) => Op::Subtract,
        Some(RawOp::Intersect) => Op::Intersect,
    };
    if first && op != Op::Union {
        return Err(s.error(
            op_key,
            "the first feature must be a union: there is nothing yet to subtract from or intersect with",
        ));
    }
    Ok(Feature { body, op })
}
