//! Resolving `solid:`: numbers evaluated, the z-buffer computed.

use glam::DVec3;

use crate::base::error::{Error, Result};
use crate::generate::primitive::solid::{Body, Feature, Infill, Op, Pattern, Solid};
use crate::recipe::schema::{Num, Num3};
use crate::recipe::schema::{RawFeature, RawOp, RawPattern, RawSolid};

/// Resolves `solid:`; `num` evaluates a number (or expression) at a key path.
/// Places are relative to the primitive (`solid.features[1].cylinder.radius`).
pub fn resolve(raw: &RawSolid, num: &dyn Fn(&Num, &str) -> Result<f64>) -> Result<Solid> {
    let positive = |n: &Num, place: &str| -> Result<f64> {
        let v = num(n, place)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(Error::input(
                place,
                format!("{v} is not allowed; expected a number > 0"),
            ))
        }
    };
    let opt = |n: &Option<Num>, place: &str, default: f64| match n {
        Some(n) => positive(n, place),
        None => Ok(default),
    };
    let point = |n: &Num3, place: &str| -> Result<DVec3> {
        Ok(DVec3::new(
            num(&n[0], &format!("{place}[0]"))?,
            num(&n[1], &format!("{place}[1]"))?,
            num(&n[2], &format!("{place}[2]"))?,
        ))
    };
    let layer_height = opt(&raw.layer_height, "solid.layer_height", 0.2)?;
    let line_width = opt(&raw.line_width, "solid.line_width", 0.45)?;
    let chord_tolerance = opt(&raw.chord_tolerance, "solid.chord_tolerance", 0.01)?;
    let perimeters = match &raw.perimeters {
        Some(n) => {
            let v = num(n, "solid.perimeters")?;
            if v.fract() != 0.0 || !(0.0..=1000.0).contains(&v) {
                return Err(Error::input(
                    "solid.perimeters",
                    format!("{v} is not allowed; expected a whole number from 0 to 1000"),
                ));
            }
            v as u32
        }
        None => 2,
    };
    let infill = match &raw.infill {
        Some(i) => {
            let pattern = match i.pattern {
                None | Some(RawPattern::Lines) => Pattern::Lines,
                Some(RawPattern::Grid) => Pattern::Grid,
            };
            // a grid lays two directions: each at twice the width is solid
            let solid_spacing = match pattern {
                Pattern::Lines => line_width,
                Pattern::Grid => 2.0 * line_width,
            };
            Infill {
                angle: match &i.angle {
                    Some(n) => num(n, "solid.infill.angle")?,
                    None => 45.0,
                },
                spacing: opt(&i.spacing, "solid.infill.spacing", solid_spacing)?,
                alternate: i.alternate.unwrap_or(true),
                pattern,
                connect: i.connect.unwrap_or(false),
            }
        }
        None => Infill {
            angle: 45.0,
            spacing: line_width,
            alternate: true,
            pattern: Pattern::Lines,
            connect: false,
        },
    };
    if raw.features.is_empty() {
        return Err(Error::input(
            "solid.features",
            "expected at least one feature (`box` or `cylinder`)",
        ));
    }
    let mut features = Vec::with_capacity(raw.features.len());
    for (k, f) in raw.features.iter().enumerate() {
        let (key, op) = match f {
            RawFeature::Box(b) => ("box", b.op),
            RawFeature::Cylinder(c) => ("cylinder", c.op),
        };
        let place = format!("solid.features[{k}].{key}");
        let body = match f {
            RawFeature::Box(b) => {
                let size = point(&b.size, &format!("{place}.size"))?;
                for i in 0..3 {
                    if size[i] <= 0.0 {
                        return Err(Error::input(
                            format!("{place}.size[{i}]"),
                            format!("{} is not allowed; expected a number > 0", size[i]),
                        ));
                    }
                }
                Body::Box {
                    center: point(&b.center, &format!("{place}.center"))?,
                    size,
                }
            }
            RawFeature::Cylinder(c) => Body::Cylinder {
                center: point(&c.center, &format!("{place}.center"))?,
                radius: positive(&c.radius, &format!("{place}.radius"))?,
                height: positive(&c.height, &format!("{place}.height"))?,
            },
        };
        let op = match op {
            None | Some(RawOp::Union) => Op::Union,
            Some(RawOp::Subtract) => Op::Subtract,
            Some(RawOp::Intersect) => Op::Intersect,
        };
        if k == 0 && op != Op::Union {
            return Err(Error::input(
                format!("{place}.op"),
                "the first feature must be a union: there is nothing yet to subtract from or intersect with",
            ));
        }
        features.push(Feature { body, op });
    }
    Solid::new(
        layer_height,
        perimeters,
        line_width,
        chord_tolerance,
        infill,
        features,
    )
}
