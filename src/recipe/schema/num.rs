//! A number as a recipe writes it: a literal, or an expression string over
//! the params (evaluated by `crate::recipe::eval`).

use std::fmt;

use serde::de::{self, Deserializer, Visitor};
use serde::Deserialize;

/// A number, or an expression over params written as a string.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Num {
    /// A literal number.
    Value(f64),
    /// An expression string, e.g. `"pi/2*radius"`.
    Expr(String),
}

impl Num {
    /// The expression text (a literal number becomes its decimal text).
    pub(crate) fn src(&self) -> String {
        match self {
            Num::Value(v) => format!("{v}"),
            Num::Expr(s) => s.clone(),
        }
    }
}

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Num, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Num;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an expression string")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Num, E> {
                Ok(Num::Value(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Num, E> {
                Ok(Num::Value(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Num, E> {
                Ok(Num::Value(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<Num, E> {
                Ok(Num::Expr(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

/// A point or vector of three numbers.
pub(crate) type Num3 = [Num; 3];

impl schemars::JsonSchema for Num {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Num".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "A number, or an expression string over the params before it (e.g. \"pi/2*radius\").",
            "type": ["number", "string"]
        })
    }
}

/// A point of a program's command: `[x, y, z]`, a map of some of `x`,
/// `y`, `z` whose missing coordinates stay where the head is (FullControl's
/// `Point(z=…)`), or `{polar: [cx, cy, cz], radius, angle}` (FullControl's
/// `polar_to_point`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum RawPoint {
    /// `[x, y, z]`.
    Full(Num3),
    /// `{x: …, z: …}`: only these coordinates change.
    Partial {
        /// x, mm.
        x: Option<Num>,
        /// y, mm.
        y: Option<Num>,
        /// z, mm.
        z: Option<Num>,
    },
    /// `{polar: [cx, cy, cz], radius: r, angle: a}`: (cx + r·cos a,
    /// cy + r·sin a, cz), a in radians counter-clockwise from +x.
    Polar {
        /// The centre.
        center: Num3,
        /// The distance from it, mm.
        radius: Num,
        /// Radians from +x, counter-clockwise seen from above.
        angle: Num,
    },
}

/// The map form of [`RawPoint`].
#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct PartialPoint {
    /// x, mm (the head's when absent).
    #[serde(default)]
    x: Option<Num>,
    /// y, mm (the head's when absent).
    #[serde(default)]
    y: Option<Num>,
    /// z, mm (the head's when absent).
    #[serde(default)]
    z: Option<Num>,
    /// The centre of a point given by `radius` and `angle` (instead of x, y, z).
    #[serde(default)]
    polar: Option<Num3>,
    /// The polar point's distance from `polar`, mm.
    #[serde(default)]
    radius: Option<Num>,
    /// The polar point's angle, radians counter-clockwise from +x.
    #[serde(default)]
    angle: Option<Num>,
}

impl RawPoint {
    /// The three coordinates, `None` for those that stay; a polar point's
    /// as expressions (`cx + (r)*cos(a)`, `cy + (r)*sin(a)`, `cz`).
    pub(crate) fn coords(&self) -> [Option<Num>; 3] {
        match self {
            RawPoint::Full([x, y, z]) => [Some(x.clone()), Some(y.clone()), Some(z.clone())],
            RawPoint::Partial { x, y, z } => [x.clone(), y.clone(), z.clone()],
            RawPoint::Polar {
                center: [cx, cy, cz],
                radius,
                angle,
            } => {
                let (cx, cy, r, a) = (text(cx), text(cy), text(radius), text(angle));
                [
                    Some(Num::Expr(format!("{cx} + {r}*cos({a})"))),
                    Some(Num::Expr(format!("{cy} + {r}*sin({a})"))),
                    Some(cz.clone()),
                ]
            }
        }
    }
}

/// A number or expression as a bracketed expression text.
fn text(n: &Num) -> String {
    match n {
        Num::Value(v) => format!("({v})"),
        Num::Expr(s) => format!("({s})"),
    }
}

impl<'de> Deserialize<'de> for RawPoint {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<RawPoint, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawPoint;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a point [x, y, z], a map of some of x, y, z, or {polar: [cx, cy, cz], radius, angle}")
            }
            fn visit_seq<A: de::SeqAccess<'de>>(
                self,
                s: A,
            ) -> std::result::Result<RawPoint, A::Error> {
                Num3::deserialize(de::value::SeqAccessDeserializer::new(s)).map(RawPoint::Full)
            }
            fn visit_map<A: de::MapAccess<'de>>(
                self,
                m: A,
            ) -> std::result::Result<RawPoint, A::Error> {
                let p = PartialPoint::deserialize(de::value::MapAccessDeserializer::new(m))?;
                let xyz = p.x.is_some() || p.y.is_some() || p.z.is_some();
                match (xyz, p.polar, p.radius, p.angle) {
                    (false, Some(center), Some(radius), Some(angle)) => {
                        return Ok(RawPoint::Polar {
                            center,
                            radius,
                            angle,
                        })
                    }
                    (_, None, None, None) => {}
                    _ => {
                        return Err(de::Error::custom(
                            "a polar point is {polar: [cx, cy, cz], radius: r, angle: a} (all three, no x, y, z); expected that or some of x, y, z",
                        ))
                    }
                }
                if !xyz {
                    return Err(de::Error::custom(
                        "an empty point; expected at least one of x, y, z",
                    ));
                }
                Ok(RawPoint::Partial {
                    x: p.x,
                    y: p.y,
                    z: p.z,
                })
            }
        }
        d.deserialize_any(V)
    }
}

impl schemars::JsonSchema for RawPoint {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RawPoint".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let num = g.subschema_for::<Num>();
        let partial = g.subschema_for::<PartialPoint>();
        schemars::json_schema!({
            "description": "A point [x, y, z], a map of some of x, y, z (the others stay where the head is), or {polar: [cx, cy, cz], radius: r, angle: a} (radians from +x).",
            "anyOf": [{"type": "array", "items": num, "minItems": 3, "maxItems": 3}, partial]
        })
    }
}
