//! A param as written: a number or expression, a boolean, a list (written
//! out, or made by a loop), or a choice among strings (FullControl's
//! `part_type = 'wing_nut'`).

use std::fmt;

use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;

use indexmap::IndexMap;

use super::num::Num;
use super::part::RawLoop;

/// One param of `params:`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum RawParam {
    /// A number or an expression over the params before it.
    Num(Num),
    /// `true` or `false`: 1 or 0 in expressions.
    Bool(bool),
    /// A list of numbers or expressions, read as `name[k]` and `len(name)`.
    List(Vec<Num>),
    /// One of a declared set of strings.
    Choice(RawChoice),
    /// A list made by a loop: `{for: {k: "0..3"}, value: "k^2"}`.
    Each(RawEach),
}

/// `{for: {k: RANGE}, value: EXPR}`: a list param holding EXPR's value for
/// each value of `k` (a range `"a..b"`/`"a..b:step"` or a list), over the
/// params before it and `k`.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawEach {
    /// One name and its values.
    #[serde(rename = "for")]
    pub(crate) each: IndexMap<String, RawLoop>,
    /// Each element's value.
    pub(crate) value: Num,
}

/// A param written as a map: a choice's or a loop's keys.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMapParam {
    choices: Option<Vec<String>>,
    default: Option<String>,
    #[serde(rename = "for")]
    each: Option<IndexMap<String, RawLoop>>,
    value: Option<Num>,
}

/// `{choices: [a, b, c], default: b}`: a param that is one of these strings.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawChoice {
    /// The strings it may be (letters, digits and `_`).
    pub(crate) choices: Vec<String>,
    /// The one it is unless `--set` says otherwise.
    pub(crate) default: String,
}

impl<'de> Deserialize<'de> for RawParam {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<RawParam, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawParam;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, an expression string, true or false, a list [a, b, …], {for: {k: \"0..3\"}, value: EXPR} or {choices: [a, b], default: a}")
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<RawParam, E> {
                Ok(RawParam::Bool(v))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<RawParam, E> {
                Ok(RawParam::Num(Num::Value(v)))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<RawParam, E> {
                Ok(RawParam::Num(Num::Value(v as f64)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<RawParam, E> {
                Ok(RawParam::Num(Num::Value(v as f64)))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<RawParam, E> {
                Ok(RawParam::Num(Num::Expr(v.to_string())))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<RawParam, A::Error> {
                let mut v = Vec::new();
                while let Some(n) = s.next_element::<Num>()? {
                    v.push(n);
                }
                Ok(RawParam::List(v))
            }
            fn visit_map<A: MapAccess<'de>>(self, m: A) -> Result<RawParam, A::Error> {
                let raw = RawMapParam::deserialize(de::value::MapAccessDeserializer::new(m))?;
                match raw {
                    RawMapParam {
                        choices: Some(choices),
                        default: Some(default),
                        each: None,
                        value: None,
                    } => Ok(RawParam::Choice(RawChoice { choices, default })),
                    RawMapParam {
                        choices: None,
                        default: None,
                        each: Some(each),
                        value: Some(value),
                    } => Ok(RawParam::Each(RawEach { each, value })),
                    _ => Err(de::Error::custom(
                        "expected {choices: [a, b], default: a} (a choice) or {for: {k: \"0..3\"}, value: EXPR} (a list made by a loop)",
                    )),
                }
            }
        }
        d.deserialize_any(V)
    }
}

impl schemars::JsonSchema for RawParam {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RawParam".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let num = g.subschema_for::<Num>();
        let choice = g.subschema_for::<RawChoice>();
        let each = g.subschema_for::<RawEach>();
        schemars::json_schema!({
            "description": "A number or an expression over the params before it; true or false; a list of numbers [a, b, …] (read as name[k], len(name), sum(name)), or one made by a loop {for: {k: \"0..3\"}, value: EXPR}; or {choices: [a, b], default: a}, one of a set of strings (compared as name == 'a').",
            "anyOf": [num, {"type": "boolean"}, {"type": "array", "items": num}, each, choice]
        })
    }
}
