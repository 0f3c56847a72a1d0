//! A plate as written: the entries of `plate:`, each a recipe file put on
//! the bed (its copies, its params, its variants, maybe a fixed place).

use std::fmt;

use indexmap::IndexMap;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;

use super::num::Num;
use super::param::RawParam;

/// One entry of `plate:`: a recipe, printed whole, once or more.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPlateItem {
    /// The recipe file, relative to the plate.
    pub(crate) recipe: String,
    /// The objects' name (default: the recipe's), numbered when there are several.
    #[serde(default)]
    pub(crate) name: Option<String>,
    /// How many of each variant (1).
    #[serde(default)]
    pub(crate) copies: Option<Num>,
    /// The recipe's params for these objects, as `--set` gives them: a
    /// number or expression, true or false, a list, one of a choice's strings.
    #[serde(default)]
    pub(crate) set: IndexMap<String, RawParam>,
    /// Variants: every combination of these values, each its own object(s),
    /// as `--sweep` makes them (`"40, 60"`, `"1..3:0.5"` or a list).
    #[serde(default)]
    pub(crate) sweep: IndexMap<String, RawSweep>,
    /// A fixed place: where the recipe's (0, 0) goes on the bed, `[x, y]`
    /// from the bed's centre, mm (default: arranged).
    #[serde(default)]
    pub(crate) at: Option<[Num; 2]>,
}

/// The values of one name of a `sweep:`: a `--sweep` text or a list.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum RawSweep {
    /// `"v1, v2"`, `"a..b"` or `"a..b:step"`.
    Text(String),
    /// `[v1, v2, …]`.
    List(Vec<Num>),
}

impl<'de> Deserialize<'de> for RawSweep {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<RawSweep, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawSweep;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("values \"v1, v2\", a range \"a..b:step\", or a list [v1, v2, …]")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<RawSweep, E> {
                Ok(RawSweep::Text(v.to_string()))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<RawSweep, E> {
                Ok(RawSweep::List(vec![Num::Value(v)]))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<RawSweep, E> {
                Ok(RawSweep::List(vec![Num::Value(v as f64)]))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<RawSweep, E> {
                Ok(RawSweep::List(vec![Num::Value(v as f64)]))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<RawSweep, A::Error> {
                let mut v = Vec::new();
                while let Some(n) = s.next_element::<Num>()? {
                    v.push(n);
                }
                Ok(RawSweep::List(v))
            }
        }
        d.deserialize_any(V)
    }
}

impl schemars::JsonSchema for RawSweep {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RawSweep".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let num = g.subschema_for::<Num>();
        schemars::json_schema!({
            "description": "Values as --sweep takes them (\"v1, v2\", \"a..b:step\"), or a list.",
            "anyOf": [{"type": "string"}, {"type": "number"}, {"type": "array", "items": num}]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recipe::yaml::parse_yaml;

    #[test]
    fn a_plate_entry_reads_its_keys() {
        let e: RawPlateItem = parse_yaml(
            "{recipe: pot.yaml, copies: 2, set: {shape: star, h: 40, round: true}, sweep: {height: \"40, 60\", r: [1, 2]}, at: [30, -40]}",
            "t",
        )
        .unwrap();
        assert_eq!(e.recipe, "pot.yaml");
        assert_eq!(e.copies, Some(Num::Value(2.0)));
        assert_eq!(e.set["shape"], RawParam::Num(Num::Expr("star".into())));
        assert_eq!(e.set["round"], RawParam::Bool(true));
        assert_eq!(e.sweep["height"], RawSweep::Text("40, 60".into()));
        assert_eq!(
            e.sweep["r"],
            RawSweep::List(vec![Num::Value(1.0), Num::Value(2.0)])
        );
        assert_eq!(e.at, Some([Num::Value(30.0), Num::Value(-40.0)]));
        let e = parse_yaml::<RawPlateItem>("{recipe: a.yaml, copy: 2}", "t").unwrap_err();
        assert_eq!(e.place.as_deref(), Some("copy"), "{e}");
    }
}
