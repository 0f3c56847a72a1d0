//! The primitives as written: one key naming the kind (`{helix: {…}}`) and
//! its map. `solid:` and `turtle:` have files of their own.

use serde::Deserialize;

use super::num::{Num, Num3};
use super::solid::RawSolid;
use super::turtle::{RawCommand, RawTurtle};

/// A primitive as written: one key naming its kind.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) enum RawPrimitive {
    Path(RawPath),
    Circle(RawCircle),
    Arc(RawArc),
    Spiral(RawSpiral),
    Helix(RawHelix),
    Cylinder(RawCylinder),
    PatternHelix(RawPatternHelix),
    CaHelix(RawCaHelix),
    Solid(RawSolid),
    Turtle(RawTurtle),
    Label(RawLabel),
}

impl RawPrimitive {
    /// The primitive's key (`helix`, `pattern_helix`): the variant's name as
    /// serde reads it (snake_case), the first segment of its key paths.
    pub(crate) fn key(&self) -> &'static str {
        match self {
            RawPrimitive::Path(_) => "path",
            RawPrimitive::Circle(_) => "circle",
            RawPrimitive::Arc(_) => "arc",
            RawPrimitive::Spiral(_) => "spiral",
            RawPrimitive::Helix(_) => "helix",
            RawPrimitive::Cylinder(_) => "cylinder",
            RawPrimitive::PatternHelix(_) => "pattern_helix",
            RawPrimitive::CaHelix(_) => "ca_helix",
            RawPrimitive::Solid(_) => "solid",
            RawPrimitive::Turtle(_) => "turtle",
            RawPrimitive::Label(_) => "label",
        }
    }
}

/// `path:` as written: commands (the program language of `turtle:`, with
/// `move` and `draw`), or an SVG drawing. A list in place of the map is
/// its `commands`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct RawPath(PathMap, bool);

impl RawPath {
    /// Whether it was written as the list of commands itself (its key
    /// paths are then `path[k]`, not `path.commands[k]`).
    pub(crate) fn is_list(&self) -> bool {
        self.1
    }
}

impl schemars::JsonSchema for RawPath {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RawPath".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let map = g.subschema_for::<PathMap>();
        let cmd = g.subschema_for::<RawCommand>();
        schemars::json_schema!({
            "description": "A path: {commands: […]} or {svg: FILE, …}, or the list of commands itself.",
            "anyOf": [map, {"type": "array", "items": cmd}]
        })
    }
}

/// The map form of `path:`.
#[derive(Clone, Debug, Default, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct PathMap {
    /// The commands, in order.
    #[serde(default)]
    pub(crate) commands: Option<Vec<RawCommand>>,
    /// An SVG file whose paths are drawn as strings (instead of `commands`).
    #[serde(default)]
    pub(crate) svg: Option<String>,
    /// Only the SVG element with this id.
    #[serde(default)]
    pub(crate) id: Option<String>,
    /// Factor on the SVG's drawn size (mm).
    #[serde(default)]
    pub(crate) scale: Option<Num>,
    /// Chord tolerance of flattened curves, mm.
    #[serde(default)]
    pub(crate) tolerance: Option<Num>,
    /// Where the centre of the drawing's bounding box goes.
    #[serde(default)]
    pub(crate) center: Option<Num3>,
}

impl std::ops::Deref for RawPath {
    type Target = PathMap;
    fn deref(&self) -> &PathMap {
        &self.0
    }
}

impl<'de> Deserialize<'de> for RawPath {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<RawPath, D::Error> {
        use serde::de::{self, MapAccess, SeqAccess, Visitor};
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawPath;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a map {commands: […]} or {svg: FILE}, or the list of commands itself")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, s: A) -> Result<RawPath, A::Error> {
                let cmds =
                    Vec::<RawCommand>::deserialize(de::value::SeqAccessDeserializer::new(s))?;
                Ok(RawPath(
                    PathMap {
                        commands: Some(cmds),
                        ..PathMap::default()
                    },
                    true,
                ))
            }
            fn visit_map<A: MapAccess<'de>>(self, m: A) -> Result<RawPath, A::Error> {
                PathMap::deserialize(de::value::MapAccessDeserializer::new(m))
                    .map(|p| RawPath(p, false))
            }
        }
        d.deserialize_any(V)
    }
}

/// `circle:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawCircle {
    pub(crate) radius: Num,
    #[serde(default)]
    pub(crate) center: Option<Num3>,
    #[serde(default)]
    pub(crate) segments: Option<Num>,
}

/// `label:` as written: a short text in a seven-segment font; `{EXPR}` in
/// `text` is replaced by the expression's value.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawLabel {
    pub(crate) text: String,
    #[serde(default)]
    pub(crate) center: Option<Num3>,
    #[serde(default)]
    pub(crate) height: Option<Num>,
    #[serde(default)]
    pub(crate) layers: Option<Num>,
    #[serde(default)]
    pub(crate) layer_height: Option<Num>,
    #[serde(default)]
    pub(crate) angle: Option<Num>,
}

/// `arc:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawArc {
    pub(crate) radius: Num,
    pub(crate) start: Num,
    pub(crate) end: Num,
    #[serde(default)]
    pub(crate) center: Option<Num3>,
    #[serde(default)]
    pub(crate) segments: Option<Num>,
    #[serde(default)]
    pub(crate) rise: Option<Num>,
}

/// `direction:` of a spiral as written.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub(crate) enum RawDirection {
    Outward,
    Inward,
}

/// `spiral:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawSpiral {
    #[serde(default)]
    pub(crate) radius: Option<Num>,
    pub(crate) pitch: Num,
    #[serde(default)]
    pub(crate) center: Option<Num3>,
    #[serde(default)]
    pub(crate) segments: Option<Num>,
    #[serde(default)]
    pub(crate) inner_radius: Option<Num>,
    #[serde(default)]
    pub(crate) direction: Option<RawDirection>,
    #[serde(default)]
    pub(crate) outline: Option<RawOutline>,
}

/// `helix:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawHelix {
    #[serde(default)]
    pub(crate) radius: Option<Num>,
    pub(crate) height: Num,
    pub(crate) pitch: Num,
    #[serde(default)]
    pub(crate) center: Option<Num3>,
    #[serde(default)]
    pub(crate) segments: Option<Num>,
    #[serde(default)]
    pub(crate) outline: Option<RawOutline>,
}

/// `cylinder:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawCylinder {
    #[serde(default)]
    pub(crate) radius: Option<Num>,
    pub(crate) height: Num,
    pub(crate) vpitch: Num,
    pub(crate) hpitch: Num,
    #[serde(default)]
    pub(crate) center: Option<Num3>,
    #[serde(default)]
    pub(crate) segments: Option<Num>,
    #[serde(default)]
    pub(crate) outline: Option<RawOutline>,
}

/// `outline:` as written: a closed SVG outline.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawOutline {
    pub(crate) svg: String,
    #[serde(default)]
    pub(crate) id: Option<String>,
    #[serde(default)]
    pub(crate) scale: Option<Num>,
    #[serde(default)]
    pub(crate) tolerance: Option<Num>,
}

/// `pattern_helix:` as written in a recipe. Required: `radius`, `layers`
/// (turns, the first included), `layer_height`; optional (default):
/// `segments` (72), `cross_section` and `speed` (the part's), `first_layer:
/// {cross_section, speed}` ({0.2, 15}), `center` ([0, 0, layer_height]).
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawPatternHelix {
    pub(crate) radius: Num,
    pub(crate) layers: Num,
    pub(crate) layer_height: Num,
    #[serde(default)]
    pub(crate) segments: Option<Num>,
    #[serde(default)]
    pub(crate) cross_section: Option<Num>,
    #[serde(default)]
    pub(crate) speed: Option<Num>,
    #[serde(default)]
    pub(crate) first_layer: Option<RawFirstLayer>,
    #[serde(default)]
    pub(crate) center: Option<Num3>,
}

/// `first_layer:` of a `pattern_helix`.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawFirstLayer {
    #[serde(default)]
    pub(crate) cross_section: Option<Num>,
    #[serde(default)]
    pub(crate) speed: Option<Num>,
}

/// `ca_helix:` as written in a recipe. Required: `radius`, `layers` (turns,
/// the first included), `layer_height`; optional (default): `cells` (288),
/// `rule` (`basic`), `layout` (`helix`), `p0` (0.99), `p1` (1), `consume` (0.5, split_merge only),
/// `e1` (0.3), `initial` (`ones`), `noise` (0.5, `initial: random` only),
/// `seed` (0), `center` ([0, 0, layer_height]). Filled cells are extruded at
/// the part's cross-section and speed.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub(crate) struct RawCaHelix {
    pub(crate) radius: Num,
    pub(crate) layers: Num,
    pub(crate) layer_height: Num,
    #[serde(default)]
    pub(crate) cells: Option<Num>,
    #[serde(default)]
    pub(crate) rule: Option<RawRule>,
    #[serde(default)]
    pub(crate) layout: Option<RawLayout>,
    #[serde(default)]
    pub(crate) p0: Option<Num>,
    #[serde(default)]
    pub(crate) p1: Option<Num>,
    #[serde(default)]
    pub(crate) consume: Option<Num>,
    #[serde(default)]
    pub(crate) e1: Option<Num>,
    #[serde(default)]
    pub(crate) initial: Option<RawInitial>,
    #[serde(default)]
    pub(crate) noise: Option<Num>,
    #[serde(default)]
    pub(crate) seed: Option<Num>,
    #[serde(default)]
    pub(crate) center: Option<Num3>,
}

/// Which of the paper's rules decides a cell.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
// serde's messages name the type ("expected enum Rule"), the schema too
#[serde(rename = "Rule", rename_all = "snake_case", expecting = "enum Rule")]
pub(crate) enum RawRule {
    /// Fig. 5: straight up at p0, else on the next cell (i + 1) at p1.
    Basic,
    /// Section 4.2: on i − 1, else on i + 1 at p1, else straight up at p0 using C.
    SplitMerge,
}

/// How the cells' turns are laid out: one helix, or one circle per layer.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(
    rename = "Layout",
    rename_all = "snake_case",
    expecting = "enum Layout"
)]
pub(crate) enum RawLayout {
    /// One helix, the paper's method (section 2): a cell's neighbours below
    /// run on across the seam into the turn being printed.
    Helix,
    /// Layered circles with a layer change, the "layered-circle-based
    /// (non-helical) algorithm in the previous study" of Fig. 11a: each
    /// layer is a ring of its own, so its neighbours below wrap round in the
    /// layer below.
    Layers,
}

/// `initial:` as written.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub(crate) enum RawInitial {
    /// Every cell of the first turn filled (the paper's usual start).
    Ones,
    /// Each cell of the first turn empty with probability `noise` (Fig. 11b).
    Random,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recipe::yaml::parse_yaml;

    #[test]
    fn each_primitive_knows_the_key_it_was_read_by() {
        for (key, map) in [
            ("path", "{commands: []}"),
            ("circle", "{radius: 1}"),
            ("arc", "{radius: 1, start: 0, end: 1}"),
            ("spiral", "{pitch: 1}"),
            ("helix", "{height: 1, pitch: 1}"),
            ("cylinder", "{height: 1, vpitch: 1, hpitch: 1}"),
            ("pattern_helix", "{radius: 1, layers: 1, layer_height: 1}"),
            ("ca_helix", "{radius: 1, layers: 1, layer_height: 1}"),
            ("solid", "{features: []}"),
            ("turtle", "{program: []}"),
        ] {
            let p: RawPrimitive = parse_yaml(&format!("{{{key}: {map}}}"), "t").unwrap();
            assert_eq!(p.key(), key);
        }
    }

    #[test]
    fn messages_name_the_types_as_before_the_raw_forms() {
        // the rule and layout were read straight into generation's types
        let e =
            parse_yaml::<RawCaHelix>("{radius: 1, layers: 2, layer_height: 0.2, rule: [1]}", "t")
                .unwrap_err();
        assert!(e.message.ends_with("expected enum Rule"), "{e}");
        let e =
            parse_yaml::<RawCaHelix>("{radius: 1, layers: 2, layer_height: 0.2, layout: 7}", "t")
                .unwrap_err();
        assert!(e.message.ends_with("expected enum Layout"), "{e}");
    }
}
