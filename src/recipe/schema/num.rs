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

/// A point of a program's command: `[x, y, z]`, or a map of some of `x`,
/// `y`, `z` whose missing coordinates stay where the head is (FullControl's
/// `Point(z=…)`).
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
}

impl RawPoint {
    /// The three coordinates, `None` for those that stay.
    pub(crate) fn coords(&self) -> [Option<&Num>; 3] {
        match self {
            RawPoint::Full([x, y, z]) => [Some(x), Some(y), Some(z)],
            RawPoint::Partial { x, y, z } => [x.as_ref(), y.as_ref(), z.as_ref()],
        }
    }
}

impl<'de> Deserialize<'de> for RawPoint {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<RawPoint, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawPoint;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a point [x, y, z], or a map of some of x, y, z")
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
                if p.x.is_none() && p.y.is_none() && p.z.is_none() {
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
            "description": "A point [x, y, z], or a map of some of x, y, z (the others stay where the head is).",
            "anyOf": [{"type": "array", "items": num, "minItems": 3, "maxItems": 3}, partial]
        })
    }
}
