//! A number as a recipe writes it: a literal, or an expression string over
//! the params (evaluated by `crate::recipe::eval`).

use std::fmt;

use serde::de::{self, Deserializer, Visitor};
use serde::Deserialize;

/// A number, or an expression over params written as a string.
#[derive(Clone, Debug, PartialEq)]
pub enum Num {
    /// A literal number.
    Value(f64),
    /// An expression string, e.g. `"pi/2*radius"`.
    Expr(String),
}

impl Num {
    /// The expression text (a literal number becomes its decimal text).
    pub fn src(&self) -> String {
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
