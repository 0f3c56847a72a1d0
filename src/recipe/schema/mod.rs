//! The recipe format as written (`Raw*`: every number still a
//! number-or-expression), deserialised from YAML with key paths in errors,
//! and the JSON Schema made from the same types ([`json_schema`]).
//!
//! Here: the top level of a file (a recipe, [`RawRecipe`], or a library it
//! includes, [`RawLibrary`]) and its keys; a part's keys in `part.rs`, the
//! primitives in `primitive.rs` (`solid:` and `turtle:` in `solid.rs` and
//! `turtle.rs`), the steps in `step.rs`; a printer profile in `profile.rs`.

mod curve;
mod num;
mod param;
mod part;
mod plate;
mod primitive;
mod profile;
mod solid;
mod step;
mod turtle;

use std::fmt;

use indexmap::IndexMap;
use serde::de::{self, Deserializer, IgnoredAny, MapAccess, Visitor};
use serde::Deserialize;

pub(crate) use num::{Num, Num3, RawPoint};
pub(crate) use param::{RawChoice, RawEach, RawParam};
pub(crate) use part::{RawBrim, RawLoop, RawPart, RawPrimitiveItem, RawStand};
pub(crate) use plate::{RawPlateItem, RawSweep};
pub(crate) use primitive::{
    RawArc, RawCaHelix, RawCircle, RawCylinder, RawDirection, RawHelix, RawInitial, RawLabel,
    RawLayout, RawOutline, RawPath, RawPatternHelix, RawPrimitive, RawRule, RawSpiral,
};
pub(crate) use profile::{
    RawBed, RawExtrusion, RawFlavor, RawHead, RawKinematics, RawPrinter, RawRetraction, RawVariable,
};
pub(crate) use solid::{RawFeature, RawInfill, RawOp, RawPattern, RawSolid};
pub(crate) use step::{RawAxis, RawDeform, RawKeep, RawSet, RawStep};
pub(crate) use turtle::{RawCommand, RawLsystem, RawProcedure, RawTurtle};

/// `material:` a built-in name or an inline map.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum RawMaterial {
    /// `pla`, `abs` or `petg`.
    Named(String),
    /// `{filament_diameter, density, nozzle_temp, bed_temp}`.
    Inline(InlineMaterial),
}

/// An inline material.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct InlineMaterial {
    /// Name for reports.
    #[serde(default)]
    pub(crate) name: Option<String>,
    /// mm; the printer's when absent.
    #[serde(default)]
    pub(crate) filament_diameter: Option<Num>,
    /// g/cm³.
    pub(crate) density: Num,
    /// °C.
    pub(crate) nozzle_temp: Num,
    /// °C.
    pub(crate) bed_temp: Num,
    /// Hottest safe nozzle, °C; `nozzle_temp` + 25 when absent.
    #[serde(default)]
    pub(crate) max_nozzle_temp: Option<Num>,
    /// Part-cooling fan, 0 to 1, above `fan_start_z`; 0 (off) when absent.
    #[serde(default)]
    pub(crate) fan_speed: Option<Num>,
    /// Height above which the fan turns on, mm; 0.5 when absent.
    #[serde(default)]
    pub(crate) fan_start_z: Option<Num>,
    /// Filament colour `#rrggbb` (the 3MF of `p3dp mesh`); `#FA8F29` when absent.
    #[serde(default)]
    pub(crate) color: Option<String>,
}

impl<'de> Deserialize<'de> for RawMaterial {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<RawMaterial, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawMaterial;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a material name (pla, abs, petg) or a map {filament_diameter, density, nozzle_temp, bed_temp}")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<RawMaterial, E> {
                Ok(RawMaterial::Named(v.to_string()))
            }
            fn visit_map<A: MapAccess<'de>>(
                self,
                m: A,
            ) -> std::result::Result<RawMaterial, A::Error> {
                InlineMaterial::deserialize(de::value::MapAccessDeserializer::new(m))
                    .map(RawMaterial::Inline)
            }
        }
        d.deserialize_any(V)
    }
}

/// `defaults:`.
#[derive(Clone, Debug, Default, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDefaults {
    /// mm².
    #[serde(default)]
    pub(crate) cross_section: Option<Num>,
    /// mm/s.
    #[serde(default)]
    pub(crate) speed: Option<Num>,
}

/// `skirt:`.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSkirt {
    /// mm outside the parts' footprint.
    pub(crate) distance: Num,
    /// Number of loops.
    pub(crate) loops: Num,
}

/// The top level of a recipe file.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRecipe {
    /// Format version; must be 1.
    pub(crate) p3dp: u32,
    /// Recipe name.
    pub(crate) name: String,
    /// Free text.
    #[serde(default)]
    pub(crate) description: Option<String>,
    /// Built-in profile name or a path.
    #[serde(default)]
    pub(crate) printer: Option<String>,
    /// Built-in material or inline map.
    #[serde(default)]
    pub(crate) material: Option<RawMaterial>,
    /// Named params in order.
    #[serde(default, deserialize_with = "unique_map")]
    pub(crate) params: IndexMap<String, RawParam>,
    /// Default cross-section and speed.
    #[serde(default)]
    pub(crate) defaults: RawDefaults,
    /// Optional skirt.
    #[serde(default)]
    pub(crate) skirt: Option<RawSkirt>,
    /// The parts, printed in order (a plate has `plate` instead).
    #[serde(default)]
    pub(crate) parts: Vec<RawPart>,
    /// What goes on the bed, instead of `parts`: whole recipes, each
    /// printed complete, one after another (see `docs/recipe.md`, Plates).
    #[serde(default)]
    pub(crate) plate: Option<Vec<RawPlateItem>>,
    /// Most strings one part may have (default 50 million).
    #[serde(default)]
    pub(crate) max_strings: Option<Num>,
    /// Check codes silenced for this recipe (the codes a finding names).
    #[serde(default)]
    pub(crate) allow: Vec<RawAllow>,
    /// Named, parameterised part trees (see [`super::expand`]).
    #[serde(default)]
    pub(crate) templates: IndexMap<String, RawTemplate>,
    /// Files whose params and templates this recipe uses, relative to it.
    #[serde(default)]
    pub(crate) include: Vec<String>,
}

/// A named, parameterised part tree (draw3dp's part-assembly functions).
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTemplate {
    /// The params and their defaults, in order, as a recipe's params are
    /// (numbers, true/false, lists, choices); a default may use the
    /// recipe's params and the template params before it.
    #[serde(default, deserialize_with = "unique_map")]
    pub(crate) params: IndexMap<String, RawParam>,
    /// The part (or group) it makes.
    pub(crate) part: RawPart,
}

/// An included file: a recipe or a library of params and templates. Only
/// `params`, `templates` and `include` are taken; a recipe's other keys are
/// allowed and ignored, so any recipe can serve as a library.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawLibrary {
    /// Format version; must be 1.
    pub(crate) p3dp: u32,
    #[serde(default)]
    pub(crate) name: Option<IgnoredAny>,
    #[serde(default)]
    pub(crate) description: Option<IgnoredAny>,
    #[serde(default)]
    pub(crate) printer: Option<IgnoredAny>,
    #[serde(default)]
    pub(crate) material: Option<IgnoredAny>,
    #[serde(default)]
    pub(crate) defaults: Option<IgnoredAny>,
    #[serde(default)]
    pub(crate) skirt: Option<IgnoredAny>,
    #[serde(default)]
    pub(crate) parts: Option<IgnoredAny>,
    #[serde(default)]
    pub(crate) max_strings: Option<IgnoredAny>,
    #[serde(default)]
    pub(crate) allow: Option<IgnoredAny>,
    #[serde(default)]
    pub(crate) plate: Option<IgnoredAny>,
    /// Params, in order.
    #[serde(default, deserialize_with = "unique_map")]
    pub(crate) params: IndexMap<String, RawParam>,
    /// Templates.
    #[serde(default)]
    pub(crate) templates: IndexMap<String, RawTemplate>,
    /// Files it includes in turn.
    #[serde(default)]
    pub(crate) include: Vec<String>,
}

/// The JSON Schema (draft 2020-12) of a recipe, made from the same `Raw*`
/// types the loader reads (so it cannot drift from them), for editors:
/// `# yaml-language-server: $schema=…` at the top of a recipe.
pub(crate) fn json_schema() -> serde_json::Value {
    let mut s = serde_json::to_value(schemars::schema_for!(RawRecipe)).unwrap_or_default();
    if let Some(o) = s.as_object_mut() {
        // a recipe has `parts`, a plate `plate`: one of them
        o.insert(
            "oneOf".into(),
            serde_json::json!([{"required": ["parts"]}, {"required": ["plate"]}]),
        );
        o.insert("title".into(), "p3dp recipe (format version 1)".into());
        o.insert(
            "description".into(),
            "A p3dp recipe: the nozzle's path as primitives and steps. Reference: docs/recipe.md."
                .into(),
        );
    }
    s
}

/// An `allow:` entry: a check code, or `{code, reason}`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum RawAllow {
    /// Just the code.
    Code(String),
    /// The code and why it is allowed.
    WithReason {
        /// The check code.
        code: String,
        /// Why the finding is accepted.
        reason: Option<String>,
    },
}

/// `{code, reason}` of an `allow:` entry.
#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct AllowMap {
    /// The check code.
    code: String,
    /// Why the finding is accepted.
    #[serde(default)]
    reason: Option<String>,
}

impl<'de> Deserialize<'de> for RawAllow {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<RawAllow, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawAllow;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a check code, or a map {code, reason}")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<RawAllow, E> {
                Ok(RawAllow::Code(v.to_string()))
            }
            fn visit_map<A: MapAccess<'de>>(self, m: A) -> std::result::Result<RawAllow, A::Error> {
                let a = AllowMap::deserialize(de::value::MapAccessDeserializer::new(m))?;
                Ok(RawAllow::WithReason {
                    code: a.code,
                    reason: a.reason,
                })
            }
        }
        d.deserialize_any(V)
    }
}

impl schemars::JsonSchema for RawMaterial {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RawMaterial".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let inline = g.subschema_for::<InlineMaterial>();
        schemars::json_schema!({
            "description": "A built-in material (pla, abs, petg) or an inline map.",
            "anyOf": [{"type": "string", "examples": ["pla", "abs", "petg"]}, inline]
        })
    }
}

impl schemars::JsonSchema for RawAllow {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RawAllow".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let map = g.subschema_for::<AllowMap>();
        schemars::json_schema!({
            "description": "A check code to silence, or {code, reason}.",
            "anyOf": [{"type": "string"}, map]
        })
    }
}

impl RawAllow {
    /// The check code.
    pub(crate) fn code(&self) -> &str {
        match self {
            RawAllow::Code(c) | RawAllow::WithReason { code: c, .. } => c,
        }
    }
}

/// Deserializes a map that refuses a key given twice (an `IndexMap` would
/// silently keep the last), as struct fields are refused.
fn unique_map<'de, D: Deserializer<'de>>(
    d: D,
) -> std::result::Result<IndexMap<String, RawParam>, D::Error> {
    struct V;
    impl<'de> Visitor<'de> for V {
        type Value = IndexMap<String, RawParam>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a map of param names to numbers, expressions, booleans, lists or choices")
        }
        fn visit_map<A: MapAccess<'de>>(
            self,
            mut m: A,
        ) -> std::result::Result<Self::Value, A::Error> {
            let mut out = IndexMap::new();
            while let Some(k) = m.next_key::<String>()? {
                if out.contains_key(&k) {
                    return Err(de::Error::custom(format!(
                        "duplicate param `{k}`; expected each param once"
                    )));
                }
                let v: RawParam = m.next_value()?;
                out.insert(k, v);
            }
            Ok(out)
        }
    }
    d.deserialize_map(V)
}
