//! A part as written: its keys, `brim:` and `stand:`, `for:` loops
//! (issue 15), and `primitive:` one primitive or a list of them. Each type
//! reads as `crate::recipe::parse_yaml` does (enums as one-key maps, exact
//! key paths).

use std::fmt;

use indexmap::IndexMap;
use serde::de::{self, DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;

use super::num::Num;
use super::param::RawParam;
use super::primitive::RawPrimitive;
use super::step::RawStep;

/// One part.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPart {
    /// Name for reports.
    #[serde(default)]
    pub(crate) name: Option<String>,
    /// mm², overrides defaults.
    #[serde(default)]
    pub(crate) cross_section: Option<Num>,
    /// mm/s, overrides defaults.
    #[serde(default)]
    pub(crate) speed: Option<Num>,
    /// One primitive, or a list whose strings follow each other.
    #[serde(default)]
    pub(crate) primitive: Option<RawPrimitives>,
    /// Steps in order.
    #[serde(default)]
    pub(crate) steps: Vec<RawStep>,
    /// Loops on the bed round the part's first contact, printed first.
    #[serde(default)]
    pub(crate) brim: Option<RawBrim>,
    /// A short printed tube under the part's first contact, printed first.
    #[serde(default)]
    pub(crate) stand: Option<RawStand>,
    /// Child parts, making this part a group (see [`super::expand`]).
    #[serde(default)]
    pub(crate) parts: Option<Vec<RawPart>>,
    /// A template to use instead of `primitive` or `parts`.
    #[serde(default)]
    pub(crate) template: Option<String>,
    /// A whole recipe file whose parts this part is (a group), instead of
    /// `primitive`, `parts` or `template`.
    #[serde(default)]
    pub(crate) include: Option<String>,
    /// The template's (or the included recipe's) params for this use: a
    /// number or expression, true or false, a list, or one of a choice's
    /// strings.
    #[serde(default)]
    pub(crate) with: IndexMap<String, RawParam>,
    /// Repeat the part once per value of each name (`for:` in a recipe).
    #[serde(default, rename = "for")]
    pub(crate) repeat: IndexMap<String, RawLoop>,
    /// The part is made only when this is non-zero (`if:` in a recipe).
    #[serde(default, rename = "if")]
    pub(crate) when: Option<Num>,
}

/// `brim:` of a part: loops on the bed round its first contact.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBrim {
    /// Number of loops.
    pub(crate) loops: Num,
    /// Width of a loop and the step between loops, mm (0.45).
    #[serde(default)]
    pub(crate) line_width: Option<Num>,
    /// Height of the loops' bead, mm (0.2).
    #[serde(default)]
    pub(crate) layer_height: Option<Num>,
    /// mm/s (the part's speed).
    #[serde(default)]
    pub(crate) speed: Option<Num>,
}

/// `stand:` of a part: a short printed tube round its first contact, its top
/// just under where the part passes over it.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawStand {
    /// Radius of the outer wall's centre line, mm, about the middle of the
    /// part's first contact.
    pub(crate) radius: Num,
    /// Number of walls, `line_width` apart, from `radius` inwards (2).
    #[serde(default)]
    pub(crate) walls: Option<Num>,
    /// Height, mm, in whole layers (as tall as the part leaves room for: no
    /// higher than the nozzle where the part passes over the walls).
    #[serde(default)]
    pub(crate) height: Option<Num>,
    /// Width of a wall, mm (0.45).
    #[serde(default)]
    pub(crate) line_width: Option<Num>,
    /// Height of a layer, mm (0.2).
    #[serde(default)]
    pub(crate) layer_height: Option<Num>,
    /// mm/s (the part's speed).
    #[serde(default)]
    pub(crate) speed: Option<Num>,
}

/// `primitive:` one primitive, or a list whose strings follow each other in
/// order (draw3dp's `Trace`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum RawPrimitives {
    /// `primitive: {helix: {…}}`, as in v1.
    One(Box<RawPrimitiveItem>),
    /// `primitive: [{spiral: {…}}, {helix: {…}}]`.
    List(Vec<RawPrimitiveItem>),
}

impl RawPrimitives {
    /// The primitives in order, each with its key path below the part: `key`
    /// (the part's key for them, `primitive`) for one, `key[k]` in a list.
    pub(crate) fn items(&self, key: &str) -> Vec<(String, &RawPrimitiveItem)> {
        match self {
            RawPrimitives::One(p) => vec![(key.to_string(), &**p)],
            RawPrimitives::List(v) => v
                .iter()
                .enumerate()
                .map(|(k, p)| (format!("{key}[{k}]"), p))
                .collect(),
        }
    }
}

/// One primitive, with an optional `cross_section` and `speed` beside its key
/// that replace the part's for this primitive's strings
/// (`{cylinder: {…}, cross_section: 0.1, speed: 25}`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RawPrimitiveItem {
    /// The primitive.
    pub(crate) primitive: RawPrimitive,
    /// mm², the part's when absent.
    pub(crate) cross_section: Option<Num>,
    /// mm/s, the part's when absent.
    pub(crate) speed: Option<Num>,
}

impl<'de> Deserialize<'de> for RawPrimitives {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<RawPrimitives, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawPrimitives;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a primitive such as {helix: {…}}, or a list of them")
            }
            fn visit_map<A: MapAccess<'de>>(self, m: A) -> Result<RawPrimitives, A::Error> {
                item_from_map(m).map(|p| RawPrimitives::One(Box::new(p)))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<RawPrimitives, A::Error> {
                let mut v = Vec::new();
                while let Some(item) = s.next_element::<RawPrimitiveItem>()? {
                    v.push(item);
                }
                Ok(RawPrimitives::List(v))
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for RawPrimitiveItem {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<RawPrimitiveItem, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawPrimitiveItem;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a primitive such as {helix: {…}}")
            }
            fn visit_map<A: MapAccess<'de>>(self, m: A) -> Result<RawPrimitiveItem, A::Error> {
                item_from_map(m)
            }
        }
        d.deserialize_any(V)
    }
}

impl schemars::JsonSchema for RawPrimitives {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RawPrimitives".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let item = g.subschema_for::<RawPrimitiveItem>();
        schemars::json_schema!({
            "description": "One primitive such as {helix: {…}}, or a list of them whose strings follow each other.",
            "anyOf": [item, {"type": "array", "items": item}]
        })
    }
}

impl schemars::JsonSchema for RawPrimitiveItem {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RawPrimitiveItem".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        // the primitive's one key beside an optional cross_section and speed
        let variants = <RawPrimitive as schemars::JsonSchema>::json_schema(g);
        let mut properties = serde_json::Map::new();
        let mut one_of = Vec::new();
        for v in variants
            .get("oneOf")
            .and_then(|v| v.as_array())
            .into_iter()
            .flatten()
        {
            if let Some(p) = v.get("properties").and_then(|p| p.as_object()) {
                for (k, s) in p {
                    properties.insert(k.clone(), s.clone());
                    one_of.push(serde_json::json!({"required": [k]}));
                }
            }
        }
        let num = serde_json::to_value(g.subschema_for::<Num>()).unwrap_or_default();
        properties.insert("cross_section".into(), num.clone());
        properties.insert("speed".into(), num);
        schemars::json_schema!({
            "description": "One primitive: its key, and optionally `cross_section` and `speed` for its strings.",
            "type": "object",
            "properties": properties,
            "additionalProperties": false,
            "oneOf": one_of
        })
    }
}

/// The primitives' keys, for messages.
const PRIMITIVES: [&str; 10] = [
    "path",
    "circle",
    "arc",
    "spiral",
    "helix",
    "cylinder",
    "pattern_helix",
    "ca_helix",
    "solid",
    "turtle",
];

/// Reads `{KIND: {…}, cross_section: c, speed: v}`: exactly one primitive key.
fn item_from_map<'de, A: MapAccess<'de>>(mut m: A) -> Result<RawPrimitiveItem, A::Error> {
    let (mut primitive, mut cross_section, mut speed) = (None, None, None);
    while let Some(key) = m.next_key::<String>()? {
        match key.as_str() {
            "cross_section" => cross_section = Some(m.next_value::<Num>()?),
            "speed" => speed = Some(m.next_value::<Num>()?),
            _ => {
                if primitive.is_some() {
                    return Err(de::Error::custom(if PRIMITIVES.contains(&key.as_str()) {
                        format!("a second primitive `{key}` here; expected one primitive per entry (give several as a list)")
                    } else {
                        format!("unknown key `{key}` beside the primitive; expected `cross_section` or `speed`")
                    }));
                }
                primitive = Some(RawPrimitive::deserialize(KeyedEnum { key, map: &mut m })?);
            }
        }
    }
    match primitive {
        Some(primitive) => Ok(RawPrimitiveItem {
            primitive,
            cross_section,
            speed,
        }),
        None => Err(de::Error::custom(
            "no primitive here; expected a primitive such as {helix: {…}}",
        )),
    }
}

/// The enum whose variant is a map key already read and whose content is
/// that key's value: lets a map hold one variant beside other keys.
struct KeyedEnum<'m, A> {
    key: String,
    map: &'m mut A,
}

impl<'de, A: MapAccess<'de>> Deserializer<'de> for KeyedEnum<'_, A> {
    type Error = A::Error;

    fn deserialize_any<V: Visitor<'de>>(self, v: V) -> Result<V::Value, A::Error> {
        v.visit_enum(self)
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, A::Error> {
        v.visit_enum(self)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf option unit unit_struct newtype_struct seq tuple
        tuple_struct map struct identifier ignored_any
    }
}

impl<'de, 'm, A: MapAccess<'de>> de::EnumAccess<'de> for KeyedEnum<'m, A> {
    type Error = A::Error;
    type Variant = Content<'m, A>;

    fn variant_seed<S: DeserializeSeed<'de>>(
        self,
        seed: S,
    ) -> Result<(S::Value, Content<'m, A>), A::Error> {
        let key: de::value::StringDeserializer<A::Error> =
            de::IntoDeserializer::into_deserializer(self.key);
        Ok((seed.deserialize(key)?, Content(self.map)))
    }
}

/// The value of a [`KeyedEnum`]'s key, read as the variant's content.
struct Content<'m, A>(&'m mut A);

impl<'de, A: MapAccess<'de>> de::VariantAccess<'de> for Content<'_, A> {
    type Error = A::Error;

    fn unit_variant(self) -> Result<(), A::Error> {
        self.0.next_value::<IgnoredAny>().map(|_| ())
    }

    fn newtype_variant_seed<S: DeserializeSeed<'de>>(self, seed: S) -> Result<S::Value, A::Error> {
        self.0.next_value_seed(seed)
    }

    fn tuple_variant<V: Visitor<'de>>(self, len: usize, v: V) -> Result<V::Value, A::Error> {
        struct Seed<V>(usize, V);
        impl<'de, V: Visitor<'de>> DeserializeSeed<'de> for Seed<V> {
            type Value = V::Value;
            fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<V::Value, D::Error> {
                d.deserialize_tuple(self.0, self.1)
            }
        }
        self.0.next_value_seed(Seed(len, v))
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, A::Error> {
        struct Seed<V>(&'static [&'static str], V);
        impl<'de, V: Visitor<'de>> DeserializeSeed<'de> for Seed<V> {
            type Value = V::Value;
            fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<V::Value, D::Error> {
                d.deserialize_struct("", self.0, self.1)
            }
        }
        self.0.next_value_seed(Seed(fields, v))
    }
}

/// The values of one name of a `for`: a range string or a list.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum RawLoop {
    /// `"a..b"` or `"a..b:step"`, a and b (and step) expressions, b included.
    Range(String),
    /// `[v1, v2, …]`, numbers or expressions.
    List(Vec<Num>),
}

impl schemars::JsonSchema for RawLoop {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RawLoop".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let num = g.subschema_for::<Num>();
        schemars::json_schema!({
            "description": "A range \"a..b\" or \"a..b:step\" (b included), or a list of values.",
            "anyOf": [{"type": "string"}, {"type": "array", "items": num}]
        })
    }
}

impl<'de> Deserialize<'de> for RawLoop {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<RawLoop, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawLoop;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a range \"a..b\" or \"a..b:step\" (b included), or a list of values [v1, v2, …]")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<RawLoop, E> {
                Ok(RawLoop::Range(v.to_string()))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<RawLoop, A::Error> {
                let mut v = Vec::new();
                while let Some(n) = s.next_element::<Num>()? {
                    v.push(n);
                }
                Ok(RawLoop::List(v))
            }
        }
        d.deserialize_any(V)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recipe::yaml::parse_yaml;

    #[test]
    fn one_primitive_or_a_list_with_cross_section_and_speed_beside() {
        let one: RawPrimitives = parse_yaml("{circle: {radius: 5}}", "t").unwrap();
        assert!(matches!(one, RawPrimitives::One(ref p) if p.speed.is_none()));
        let list: RawPrimitives = parse_yaml(
            "- {spiral: {radius: 5, pitch: 0.4}, cross_section: 0.1, speed: 20}\n- helix: {radius: 5, height: 2, pitch: 0.3}\n",
            "t",
        )
        .unwrap();
        let items = list.items("primitive");
        assert_eq!(items[1].0, "primitive[1]");
        assert_eq!(items[0].1.cross_section, Some(Num::Value(0.1)));
        assert!(matches!(items[1].1.primitive, RawPrimitive::Helix { .. }));
        let e = parse_yaml::<RawPrimitives>("{circle: {radius: 5}, sped: 3}", "t").unwrap_err();
        assert!(e.message.contains("unknown key `sped`"), "{e}");
        let e = parse_yaml::<RawPrimitives>("{circle: {radius: 5}, helix: {}}", "t").unwrap_err();
        assert!(e.message.contains("a second primitive `helix`"), "{e}");
        let e = parse_yaml::<RawPrimitives>("[{helix: {radius: 5, height: 2, pich: 1}}]", "t")
            .unwrap_err();
        assert_eq!(e.place.as_deref(), Some("[0].helix.pich"));
    }

    #[test]
    fn the_primitive_keys_are_the_primitives() {
        for key in PRIMITIVES {
            let e = parse_yaml::<RawPrimitive>(&format!("{{{key}: 1}}"), "t").unwrap_err();
            assert!(!e.message.contains("unknown variant"), "{key}: {e}");
        }
        let e = parse_yaml::<RawPrimitive>("{blob: 1}", "t").unwrap_err();
        for key in PRIMITIVES {
            assert!(e.message.contains(&format!("`{key}`")), "{key}: {e}");
        }
    }

    #[test]
    fn a_loop_is_a_range_or_a_list() {
        assert_eq!(
            parse_yaml::<RawLoop>("\"0..4\"", "t").unwrap(),
            RawLoop::Range("0..4".into())
        );
        assert_eq!(
            parse_yaml::<RawLoop>("[1, \"2*a\"]", "t").unwrap(),
            RawLoop::List(vec![Num::Value(1.0), Num::Expr("2*a".into())])
        );
        let e = parse_yaml::<RawLoop>("5", "t").unwrap_err();
        assert!(e.message.contains("expected a range"), "{e}");
    }
}
