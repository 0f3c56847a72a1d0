//! Recipes: the YAML format of `../shared/spec/recipe-v1.md`, loaded and resolved.
//!
//! Loading is two stages. [`parse_yaml`] reads the text into the raw schema
//! (`Raw*` types, every number still a number-or-expression), reporting the
//! line and key path of any syntax error, unknown key or wrong type. Then
//! [`Recipe::resolve`] evaluates params (with `--set` overrides), every number,
//! compiles step expressions and loads images, naming the key path of any
//! problem.

use std::fmt;
use std::path::{Path, PathBuf};

use glam::DVec3;
use indexmap::IndexMap;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::expr::{self, var, Expr, Params};
use crate::primitive::{Arc, Circle, Cylinder, Direction, Helix, PathCmd, Primitive, Spiral};
use crate::printer::{Material, Printer};
use crate::step::{Bitmap, Deform, Keep, Modulate, ModulateMap, Step};

/// The default limit on strings in one part (a recipe may change it).
pub const DEFAULT_MAX_STRINGS: u64 = 50_000_000;

/// Deserializes YAML into `T`, with errors naming `file`, line, column and key path.
///
/// Enums are written as one-key maps (`{helix: {…}}`), as the spec does.
pub fn parse_yaml<T: de::DeserializeOwned>(text: &str, file: &str) -> Result<T> {
    let de = serde_yaml::Deserializer::from_str(text);
    let mut track = serde_path_to_error::Track::new();
    let tracked = serde_path_to_error::Deserializer::new(de, &mut track);
    serde_yaml::with::singleton_map_recursive::deserialize(tracked).map_err(|e| {
        // a syntax error leaves `?` segments where the parser lost track
        let mut path = track.path().to_string();
        while let Some(p) = path.strip_suffix(".?").or(path.strip_suffix("?")) {
            path = p.to_string();
        }
        let mut msg = e.to_string();
        if let Some(loc) = e.location() {
            let suffix = format!(" at line {} column {}", loc.line(), loc.column());
            if let Some(k) = msg.find(&suffix) {
                msg.replace_range(k..k + suffix.len(), "");
            }
        }
        // serde_yaml prefixes the parent's path; we give the exact one.
        if let Some((pre, rest)) = msg.split_once(": ") {
            if !pre.is_empty() && !pre.contains(' ') {
                msg = rest.to_string();
            }
        }
        let mut err = Error::input(
            if path == "." { String::new() } else { path },
            shorten_quoted(&msg),
        );
        err.file = Some(file.to_string());
        err.line = e.location().map(|l| (l.line(), l.column()));
        if err.line.is_none() && msg.contains("more than one document") {
            // serde_yaml gives no place: the second `---` is where it begins
            err.line = second_document(text).map(|l| (l, 1));
            err.message = "a second YAML document begins here; expected one document".into();
        }
        err
    })
}

/// The line (1-based) of the `---` that starts a second YAML document.
fn second_document(text: &str) -> Option<usize> {
    let mut content = false;
    for (k, line) in text.lines().enumerate() {
        let t = line.trim_end();
        if t == "---" || t.starts_with("--- ") {
            if content {
                return Some(k + 1);
            }
            content = true;
        } else if !t.is_empty() && !t.starts_with('#') {
            content = true;
        }
    }
    None
}

/// Cuts each quoted text of a message to 40 characters: an error about a
/// file that is no recipe (`/etc/passwd`) names it, not prints it.
fn shorten_quoted(msg: &str) -> String {
    const KEEP: usize = 40;
    // a whole file read as one string (a text file that is no YAML map):
    // say what it is, not what it says
    if let Some(rest) = msg.strip_prefix("invalid type: string \"") {
        if let Some(k) = rest.rfind("\", expected") {
            return format!("invalid type: text{}", &rest[k + 1..]);
        }
    }
    let mut out = String::with_capacity(msg.len().min(400));
    let mut rest = msg;
    while let Some(open) = rest.find('"') {
        out.push_str(&rest[..=open]);
        let after = &rest[open + 1..];
        let close = after.find('"').unwrap_or(after.len());
        let inner = &after[..close];
        if inner.chars().count() > KEEP {
            out.extend(inner.chars().take(KEEP));
            out.push('…');
        } else {
            out.push_str(inner);
        }
        rest = &after[close..];
        if let Some(r) = rest.strip_prefix('"') {
            out.push('"');
            rest = r;
        }
    }
    out.push_str(rest);
    if out.chars().count() > 400 {
        out = out.chars().take(400).collect::<String>() + "…";
    }
    out
}

/// Deserializes a map that refuses a key given twice (an `IndexMap` would
/// silently keep the last), as struct fields are refused.
fn unique_map<'de, D: Deserializer<'de>>(
    d: D,
) -> std::result::Result<IndexMap<String, Num>, D::Error> {
    struct V;
    impl<'de> Visitor<'de> for V {
        type Value = IndexMap<String, Num>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a map of param names to numbers or expressions")
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
                let v: Num = m.next_value()?;
                out.insert(k, v);
            }
            Ok(out)
        }
    }
    d.deserialize_map(V)
}

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
pub type Num3 = [Num; 3];

/// `material:` a built-in name or an inline map.
#[derive(Clone, Debug, PartialEq)]
pub enum RawMaterial {
    /// `pla`, `abs` or `petg`.
    Named(String),
    /// `{filament_diameter, density, nozzle_temp, bed_temp}`.
    Inline(InlineMaterial),
}

/// An inline material.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InlineMaterial {
    /// Name for reports.
    #[serde(default)]
    pub name: Option<String>,
    /// mm; the printer's when absent.
    #[serde(default)]
    pub filament_diameter: Option<Num>,
    /// g/cm³.
    pub density: Num,
    /// °C.
    pub nozzle_temp: Num,
    /// °C.
    pub bed_temp: Num,
    /// Hottest safe nozzle, °C; `nozzle_temp` + 25 when absent.
    #[serde(default)]
    pub max_nozzle_temp: Option<Num>,
    /// Part-cooling fan, 0 to 1, above `fan_start_z`; 0 (off) when absent.
    #[serde(default)]
    pub fan_speed: Option<Num>,
    /// Height above which the fan turns on, mm; 0.5 when absent.
    #[serde(default)]
    pub fan_start_z: Option<Num>,
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
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawDefaults {
    /// mm².
    #[serde(default)]
    pub cross_section: Option<Num>,
    /// mm/s.
    #[serde(default)]
    pub speed: Option<Num>,
}

/// `skirt:`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawSkirt {
    /// mm outside the parts' footprint.
    pub distance: Num,
    /// Number of loops.
    pub loops: Num,
}

/// The top level of a recipe file.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawRecipe {
    /// Format version; must be 1.
    pub p3dp: u32,
    /// Recipe name.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// Built-in profile name or a path.
    #[serde(default)]
    pub printer: Option<String>,
    /// Built-in material or inline map.
    #[serde(default)]
    pub material: Option<RawMaterial>,
    /// Named params in order.
    #[serde(default, deserialize_with = "unique_map")]
    pub params: IndexMap<String, Num>,
    /// Default cross-section and speed.
    #[serde(default)]
    pub defaults: RawDefaults,
    /// Optional skirt.
    #[serde(default)]
    pub skirt: Option<RawSkirt>,
    /// The parts, printed in order.
    pub parts: Vec<RawPart>,
    /// Most strings one part, and all parts together, may have (default 50 million).
    #[serde(default)]
    pub max_strings: Option<Num>,
    /// Check codes silenced for this recipe (see [`crate::check::CODES`]).
    #[serde(default)]
    pub allow: Vec<RawAllow>,
}

/// An `allow:` entry: a check code, or `{code, reason}`.
#[derive(Clone, Debug, PartialEq)]
pub enum RawAllow {
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
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AllowMap {
    code: String,
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

impl RawAllow {
    /// The check code.
    pub fn code(&self) -> &str {
        match self {
            RawAllow::Code(c) | RawAllow::WithReason { code: c, .. } => c,
        }
    }
}

/// One part.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawPart {
    /// Name for reports.
    #[serde(default)]
    pub name: Option<String>,
    /// mm², overrides defaults.
    #[serde(default)]
    pub cross_section: Option<Num>,
    /// mm/s, overrides defaults.
    #[serde(default)]
    pub speed: Option<Num>,
    /// Exactly one primitive.
    pub primitive: RawPrimitive,
    /// Steps in order.
    #[serde(default)]
    pub steps: Vec<RawStep>,
}

/// A primitive as written.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
#[allow(missing_docs)]
pub enum RawPrimitive {
    Path {
        commands: Vec<RawCmd>,
    },
    Circle {
        radius: Num,
        #[serde(default)]
        center: Option<Num3>,
        #[serde(default)]
        segments: Option<Num>,
    },
    Arc {
        radius: Num,
        start: Num,
        end: Num,
        #[serde(default)]
        center: Option<Num3>,
        #[serde(default)]
        segments: Option<Num>,
        #[serde(default)]
        rise: Option<Num>,
    },
    Spiral {
        radius: Num,
        pitch: Num,
        #[serde(default)]
        center: Option<Num3>,
        #[serde(default)]
        segments: Option<Num>,
        #[serde(default)]
        inner_radius: Option<Num>,
        #[serde(default)]
        direction: Option<RawDirection>,
    },
    Helix {
        radius: Num,
        height: Num,
        pitch: Num,
        #[serde(default)]
        center: Option<Num3>,
        #[serde(default)]
        segments: Option<Num>,
    },
    Cylinder {
        radius: Num,
        height: Num,
        vpitch: Num,
        hpitch: Num,
        #[serde(default)]
        center: Option<Num3>,
        #[serde(default)]
        segments: Option<Num>,
    },
    PatternHelix(crate::primitive::pattern::RawPatternHelix),
    CaHelix(crate::primitive::ca::RawCaHelix),
    Solid(crate::primitive::solid::RawSolid),
    Turtle(crate::primitive::turtle::RawTurtle),
}

/// `direction:` of a spiral.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum RawDirection {
    Outward,
    Inward,
}

/// A `path` command.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum RawCmd {
    Move(Num3),
    Draw(Num3),
    CrossSection(Num),
    Speed(Num),
}

/// `keep:` of a modulation.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum RawKeep {
    Flow,
    Speed,
}

/// The keys of `deform_xyz` and `deform_cylinder`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct RawDeform {
    #[serde(default)]
    pub position: Option<Num3>,
    #[serde(default)]
    pub cross_section: Option<Num>,
    #[serde(default)]
    pub speed: Option<Num>,
}

/// A step as written.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
#[allow(missing_docs)]
pub enum RawStep {
    DeformXyz(RawDeform),
    DeformCylinder(RawDeform),
    ModulateCylinder {
        factor: Num,
        #[serde(default)]
        keep: Option<RawKeep>,
    },
    ModulateMap {
        #[serde(default)]
        image: Option<String>,
        #[serde(default)]
        text: Option<String>,
        u: Num,
        v: Num,
        #[serde(default)]
        dark: Option<Num>,
        #[serde(default)]
        light: Option<Num>,
        #[serde(default)]
        threshold: Option<Num>,
        #[serde(default)]
        keep: Option<RawKeep>,
    },
    Subdivide {
        max_length: Num,
    },
    Translate(Num3),
}

/// `skirt:` resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Skirt {
    /// mm outside the parts' footprint.
    pub distance: f64,
    /// Number of loops.
    pub loops: u32,
}

/// A part resolved: numbers evaluated, expressions compiled.
#[derive(Clone, Debug)]
pub struct Part {
    /// Name for reports (`part 1` when the recipe gives none).
    pub name: String,
    /// Cross-section, mm².
    pub cross_section: f64,
    /// Speed, mm/s.
    pub speed: f64,
    /// The primitive.
    pub primitive: Primitive,
    /// The steps.
    pub steps: Vec<Step>,
}

/// A recipe resolved and ready to build.
#[derive(Clone, Debug)]
pub struct Recipe {
    /// Recipe name.
    pub name: String,
    /// Param values after `--set`.
    pub params: Params,
    /// Printer profile.
    pub printer: Printer,
    /// Material.
    pub material: Material,
    /// Optional skirt.
    pub skirt: Option<Skirt>,
    /// Parts in print order.
    pub parts: Vec<Part>,
    /// Most strings one part may have.
    pub max_strings: u64,
    /// Check codes the recipe silences (`allow:`).
    pub allow: Vec<String>,
}

/// Default cross-section when a recipe gives none: Kanada's 0.196 mm² (Fig. 9).
pub const DEFAULT_CROSS_SECTION: f64 = 0.196;
/// Default speed when a recipe gives none: Kanada's 40 mm/s (Fig. 9).
pub const DEFAULT_SPEED: f64 = 40.0;

/// Evaluates numbers of one recipe against its params.
struct Ctx<'a> {
    params: &'a Params,
    dir: &'a Path,
    /// Filament area (mm²) and max_strings, for a turtle (set once known).
    turtle: (f64, u64),
}

impl Ctx<'_> {
    fn num(&self, n: &Num, place: &str) -> Result<f64> {
        match n {
            Num::Value(v) => finite(*v, place),
            Num::Expr(s) => expr::eval_const(s, self.params).map_err(|m| Error::input(place, m)),
        }
    }

    fn positive(&self, n: &Num, place: &str) -> Result<f64> {
        let v = self.num(n, place)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(Error::input(
                place,
                format!("{v} is not allowed; expected a number > 0"),
            ))
        }
    }

    fn non_negative(&self, n: &Num, place: &str) -> Result<f64> {
        let v = self.num(n, place)?;
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(Error::input(
                place,
                format!("{v} is not allowed; expected a number ≥ 0"),
            ))
        }
    }

    fn whole(&self, n: &Num, place: &str, min: u32) -> Result<u32> {
        let v = self.num(n, place)?;
        if v.fract() != 0.0 || v < min as f64 || v > 1e7 {
            return Err(Error::input(
                place,
                format!("{v} is not allowed; expected a whole number from {min} to 10000000"),
            ));
        }
        Ok(v as u32)
    }

    fn whole_max(&self, n: &Num, place: &str, min: u32, max: u32) -> Result<u32> {
        let v = self.num(n, place)?;
        if v.fract() != 0.0 || v < min as f64 || v > max as f64 {
            return Err(Error::input(
                place,
                format!("{v} is not allowed; expected a whole number from {min} to {max}"),
            ));
        }
        Ok(v as u32)
    }

    fn segments(&self, n: &Option<Num>, place: &str) -> Result<u32> {
        match n {
            Some(n) => self.whole(n, &format!("{place}.segments"), 3),
            None => Ok(72),
        }
    }

    fn point(&self, n: &Num3, place: &str) -> Result<DVec3> {
        Ok(DVec3::new(
            self.num(&n[0], &format!("{place}[0]"))?,
            self.num(&n[1], &format!("{place}[1]"))?,
            self.num(&n[2], &format!("{place}[2]"))?,
        ))
    }

    fn center(&self, n: &Option<Num3>, place: &str) -> Result<DVec3> {
        match n {
            Some(n) => self.point(n, &format!("{place}.center")),
            None => Ok(DVec3::ZERO),
        }
    }

    fn expr(&self, n: &Num, allowed: &[usize], place: &str) -> Result<Expr> {
        Expr::compile(&n.src(), self.params, allowed).map_err(|m| Error::input(place, m))
    }
}

const POINT_VARS: &[usize] = &[
    var::X,
    var::Y,
    var::Z,
    var::R,
    var::THETA,
    var::I,
    var::N,
    var::T,
];
const STRING_VARS: &[usize] = &[
    var::X,
    var::Y,
    var::Z,
    var::R,
    var::THETA,
    var::C,
    var::V,
    var::I,
    var::N,
    var::T,
];

fn finite(v: f64, place: &str) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::input(
            place,
            format!("{v} is not allowed; expected a finite number"),
        ))
    }
}

fn is_identifier(s: &str) -> bool {
    let mut cs = s.chars();
    matches!(cs.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && cs.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Evaluates params in order, each over the ones before it; `sets` replaces
/// a param's expression (`--set NAME=VALUE`).
pub fn eval_params(raw: &IndexMap<String, Num>, sets: &[(String, String)]) -> Result<Params> {
    let mut params = Params::new();
    for (name, value) in raw {
        let place = format!("params.{name}");
        if !is_identifier(name) {
            return Err(Error::input(
                place,
                "a param name must be letters, digits and `_`, not starting with a digit",
            ));
        }
        if expr::is_reserved(name) {
            return Err(Error::input(
                place,
                format!("`{name}` is a name expressions already use; choose another param name"),
            ));
        }
        let v = match sets.iter().rev().find(|(n, _)| n == name) {
            Some((_, s)) => expr::eval_const(s, &params)
                .map_err(|m| Error::input(format!("--set {name}={s}"), m))?,
            None => match value {
                Num::Value(v) => finite(*v, &place)?,
                Num::Expr(s) => {
                    expr::eval_const(s, &params).map_err(|m| Error::input(&place, m))?
                }
            },
        };
        params.insert(name.clone(), v);
    }
    for (name, s) in sets {
        if !raw.contains_key(name) {
            let known: Vec<&str> = raw.keys().map(String::as_str).collect();
            return Err(Error::input(
                format!("--set {name}={s}"),
                if known.is_empty() {
                    format!("unknown param `{name}`; this recipe has no params")
                } else {
                    format!(
                        "unknown param `{name}`; the recipe's params are {}",
                        known.join(", ")
                    )
                },
            ));
        }
    }
    Ok(params)
}

/// Parses a `NAME=VALUE` of `--set`.
pub fn parse_set(s: &str) -> Result<(String, String)> {
    match s.split_once('=') {
        Some((n, v)) if !n.trim().is_empty() && !v.trim().is_empty() => {
            Ok((n.trim().to_string(), v.trim().to_string()))
        }
        _ => Err(Error::input(
            format!("--set {s}"),
            "expected NAME=VALUE, e.g. --set radius=30",
        )),
    }
}

impl Recipe {
    /// Reads and resolves a recipe file. `printer` overrides the recipe's printer.
    pub fn load(
        path: &Path,
        sets: &[(String, String)],
        printer: Option<&Printer>,
    ) -> Result<Recipe> {
        let shown = path.display().to_string();
        let text = crate::input::read_text(path, "recipe")?;
        let raw: RawRecipe = parse_yaml(&text, &shown)?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Recipe::resolve(&raw, sets, printer, &dir).map_err(|e| e.in_file(&shown))
    }

    /// Resolves a parsed recipe; relative paths are taken from `dir`.
    pub fn resolve(
        raw: &RawRecipe,
        sets: &[(String, String)],
        printer: Option<&Printer>,
        dir: &Path,
    ) -> Result<Recipe> {
        if raw.p3dp != 1 {
            return Err(Error::input(
                "p3dp",
                format!("format version {} is not known; expected 1", raw.p3dp),
            ));
        }
        if raw.name.trim().is_empty() {
            return Err(Error::input("name", "expected a non-empty name"));
        }
        // names reach G-code comments: one line each, no control characters
        crate::safe_text::check("name", &raw.name)?;
        if let Some(d) = &raw.description {
            // a block scalar's final line break is no line of its own
            crate::safe_text::check("description", d.trim_end_matches(['\n', '\r']))?;
        }
        for (k, p) in raw.parts.iter().enumerate() {
            if let Some(n) = &p.name {
                crate::safe_text::check(&format!("parts[{k}].name"), n)?;
            }
        }
        if raw.parts.is_empty() {
            return Err(Error::input("parts", "expected at least one part"));
        }
        let params = eval_params(&raw.params, sets)?;
        let ctx = Ctx {
            params: &params,
            dir,
            turtle: (0.0, DEFAULT_MAX_STRINGS),
        };
        let printer = match printer {
            Some(p) => p.clone(),
            None => Printer::resolve(raw.printer.as_deref().unwrap_or("generic-220"), dir)?,
        };
        let material = resolve_material(&ctx, raw.material.as_ref())?;
        let c0 = match &raw.defaults.cross_section {
            Some(n) => ctx.positive(n, "defaults.cross_section")?,
            None => DEFAULT_CROSS_SECTION,
        };
        let v0 = match &raw.defaults.speed {
            Some(n) => ctx.positive(n, "defaults.speed")?,
            None => DEFAULT_SPEED,
        };
        let skirt = match &raw.skirt {
            Some(s) => Some(Skirt {
                distance: ctx.non_negative(&s.distance, "skirt.distance")?,
                loops: ctx.whole_max(&s.loops, "skirt.loops", 1, 1000)?,
            }),
            None => None,
        };
        let max_strings = match &raw.max_strings {
            Some(n) => ctx.whole(n, "max_strings", 1)? as u64,
            None => DEFAULT_MAX_STRINGS,
        };
        let d = material
            .filament_diameter
            .unwrap_or(printer.filament_diameter);
        let ctx = Ctx {
            turtle: (std::f64::consts::PI * (d / 2.0) * (d / 2.0), max_strings),
            ..ctx
        };
        let mut parts = Vec::with_capacity(raw.parts.len());
        let mut total = 0u64;
        for (k, p) in raw.parts.iter().enumerate() {
            let place = format!("parts[{k}]");
            let part = resolve_part(&ctx, p, c0, v0, k).map_err(|e| e.under(&place))?;
            let n = part.primitive.string_count();
            // the limit holds for all parts together too (YAML aliases repeat a part)
            total = total.saturating_add(n);
            if n <= max_strings && total > max_strings {
                return Err(Error::input(
                    format!("{place}.primitive"),
                    format!(
                        "the parts up to this one make {total} strings, more than the limit of {max_strings} for the whole recipe; expected fewer or smaller parts (or raise max_strings)"
                    ),
                ));
            }
            if n > max_strings {
                return Err(Error::input(
                    format!("{place}.primitive"),
                    format!(
                        "this primitive would make {n} strings, more than the limit of {max_strings}; expected a larger pitch or fewer segments (or raise max_strings)"
                    ),
                ));
            }
            parts.push(part);
        }
        let allow: Vec<String> = raw.allow.iter().map(|a| a.code().to_string()).collect();
        crate::check::validate_allow(&allow, |i| format!("allow[{i}]"))?;
        Ok(Recipe {
            name: raw.name.clone(),
            params,
            printer,
            material,
            skirt,
            parts,
            max_strings,
            allow,
        })
    }
}

fn resolve_material(ctx: &Ctx, m: Option<&RawMaterial>) -> Result<Material> {
    match m {
        None => Ok(Material::built_in("pla").unwrap()),
        Some(RawMaterial::Named(n)) => Material::built_in(n).ok_or_else(|| {
            Error::input(
                "material",
                format!("unknown material `{n}`; built-in materials are pla, abs, petg (or give an inline map)"),
            )
        }),
        Some(RawMaterial::Inline(m)) => {
            if let Some(n) = &m.name {
                crate::safe_text::check("material.name", n)?;
            }
            let nozzle_temp = ctx.positive(&m.nozzle_temp, "material.nozzle_temp")?;
            let material = Material {
                name: m.name.clone().unwrap_or_else(|| "custom".into()),
                filament_diameter: match &m.filament_diameter {
                    Some(n) => Some(ctx.positive(n, "material.filament_diameter")?),
                    None => None,
                },
                density: ctx.positive(&m.density, "material.density")?,
                nozzle_temp,
                bed_temp: ctx.non_negative(&m.bed_temp, "material.bed_temp")?,
                max_nozzle_temp: match &m.max_nozzle_temp {
                    Some(n) => ctx.positive(n, "material.max_nozzle_temp")?,
                    None => nozzle_temp + 25.0,
                },
                fan_speed: match &m.fan_speed {
                    Some(n) => {
                        let f = ctx.non_negative(n, "material.fan_speed")?;
                        if f > 1.0 {
                            return Err(Error::input(
                                "material.fan_speed",
                                format!("{f} is not allowed; expected a fraction of full speed from 0 to 1"),
                            ));
                        }
                        f
                    }
                    None => 0.0,
                },
                fan_start_z: match &m.fan_start_z {
                    Some(n) => ctx.non_negative(n, "material.fan_start_z")?,
                    None => crate::printer::FAN_START_Z,
                },
            };
            material_ranges(&material)?;
            Ok(material)
        }
    }
}

/// Refuses an inline material's values outside what a machine can do (see
/// [`crate::limits`]); the nozzle temperature against the printer's own
/// limit is the `nozzle-temp` check's (a failed check, not unusable input).
fn material_ranges(m: &Material) -> Result<()> {
    use crate::limits::*;
    if let Some(d) = m.filament_diameter {
        range("material.filament_diameter", d, FILAMENT_DIAMETER, "mm")?;
    }
    range("material.density", m.density, DENSITY, "g/cm³")?;
    at_most("material.nozzle_temp", m.nozzle_temp, NOZZLE_TEMP_MAX, "°C")?;
    at_most(
        "material.max_nozzle_temp",
        m.max_nozzle_temp,
        NOZZLE_TEMP_MAX,
        "°C",
    )?;
    at_most("material.bed_temp", m.bed_temp, BED_TEMP_MAX, "°C")?;
    at_most(
        "material.fan_start_z",
        m.fan_start_z,
        MACHINE_LENGTH_MAX,
        "mm",
    )
}

fn resolve_part(ctx: &Ctx, p: &RawPart, c0: f64, v0: f64, k: usize) -> Result<Part> {
    let cross_section = match &p.cross_section {
        Some(n) => ctx.positive(n, "cross_section")?,
        None => c0,
    };
    let speed = match &p.speed {
        Some(n) => ctx.positive(n, "speed")?,
        None => v0,
    };
    let primitive = match &p.primitive {
        // a turtle runs now: its strings start with the part's c and v
        RawPrimitive::Turtle(t) => {
            let env = crate::primitive::turtle::Env {
                cross_section,
                speed,
                filament_area: ctx.turtle.0,
                max_strings: ctx.turtle.1,
            };
            crate::primitive::turtle::resolve(t, ctx.params, &env)
                .map(|t| Primitive::Turtle(Box::new(t)))
        }
        other => resolve_primitive(ctx, other),
    }
    .map_err(|e| e.under("primitive"))?;
    let mut steps = Vec::with_capacity(p.steps.len());
    for (j, s) in p.steps.iter().enumerate() {
        steps.push(resolve_step(ctx, s).map_err(|e| e.under(&format!("steps[{j}]")))?);
    }
    Ok(Part {
        name: p.name.clone().unwrap_or_else(|| format!("part {}", k + 1)),
        cross_section,
        speed,
        primitive,
        steps,
    })
}

fn resolve_primitive(ctx: &Ctx, p: &RawPrimitive) -> Result<Primitive> {
    Ok(match p {
        RawPrimitive::Path { commands } => {
            let mut cmds = Vec::with_capacity(commands.len());
            for (k, c) in commands.iter().enumerate() {
                let place = format!("path.commands[{k}]");
                cmds.push(match c {
                    RawCmd::Move(n) => PathCmd::Move(ctx.point(n, &format!("{place}.move"))?),
                    RawCmd::Draw(n) => PathCmd::Draw(ctx.point(n, &format!("{place}.draw"))?),
                    RawCmd::CrossSection(n) => {
                        PathCmd::CrossSection(ctx.positive(n, &format!("{place}.cross_section"))?)
                    }
                    RawCmd::Speed(n) => PathCmd::Speed(ctx.positive(n, &format!("{place}.speed"))?),
                });
            }
            if !cmds.iter().any(|c| matches!(c, PathCmd::Draw(_))) {
                return Err(Error::input(
                    "path.commands",
                    "expected at least one `draw` command (a path that extrudes nothing prints nothing)",
                ));
            }
            Primitive::Path(cmds)
        }
        RawPrimitive::Circle {
            radius,
            center,
            segments,
        } => Primitive::Circle(Circle {
            radius: ctx.positive(radius, "circle.radius")?,
            center: ctx.center(center, "circle")?,
            segments: ctx.segments(segments, "circle")?,
        }),
        RawPrimitive::Arc {
            radius,
            start,
            end,
            center,
            segments,
            rise,
        } => {
            let (start, end) = (ctx.num(start, "arc.start")?, ctx.num(end, "arc.end")?);
            if start == end {
                return Err(Error::input(
                    "arc.end",
                    "expected an end angle other than start",
                ));
            }
            Primitive::Arc(Arc {
                radius: ctx.positive(radius, "arc.radius")?,
                center: ctx.center(center, "arc")?,
                start,
                end,
                segments: ctx.segments(segments, "arc")?,
                rise: match rise {
                    Some(n) => ctx.num(n, "arc.rise")?,
                    None => 0.0,
                },
            })
        }
        RawPrimitive::Spiral {
            radius,
            pitch,
            center,
            segments,
            inner_radius,
            direction,
        } => {
            let radius = ctx.positive(radius, "spiral.radius")?;
            let inner = match inner_radius {
                Some(n) => ctx.non_negative(n, "spiral.inner_radius")?,
                None => 0.0,
            };
            if inner >= radius {
                return Err(Error::input(
                    "spiral.inner_radius",
                    format!("{inner} is not allowed; expected less than radius {radius}"),
                ));
            }
            Primitive::Spiral(Spiral {
                radius,
                pitch: ctx.positive(pitch, "spiral.pitch")?,
                center: ctx.center(center, "spiral")?,
                segments: ctx.segments(segments, "spiral")?,
                inner_radius: inner,
                direction: match direction {
                    Some(RawDirection::Inward) => Direction::Inward,
                    _ => Direction::Outward,
                },
            })
        }
        RawPrimitive::Helix {
            radius,
            height,
            pitch,
            center,
            segments,
        } => Primitive::Helix(Helix {
            radius: ctx.positive(radius, "helix.radius")?,
            height: ctx.positive(height, "helix.height")?,
            pitch: ctx.positive(pitch, "helix.pitch")?,
            center: ctx.center(center, "helix")?,
            segments: ctx.segments(segments, "helix")?,
        }),
        RawPrimitive::Cylinder {
            radius,
            height,
            vpitch,
            hpitch,
            center,
            segments,
        } => Primitive::Cylinder(Cylinder {
            radius: ctx.positive(radius, "cylinder.radius")?,
            height: ctx.positive(height, "cylinder.height")?,
            vpitch: ctx.positive(vpitch, "cylinder.vpitch")?,
            hpitch: ctx.positive(hpitch, "cylinder.hpitch")?,
            center: ctx.center(center, "cylinder")?,
            segments: ctx.segments(segments, "cylinder")?,
        }),
        RawPrimitive::PatternHelix(p) => {
            Primitive::PatternHelix(p.resolve(&|n: &Num, place: &str| ctx.num(n, place))?)
        }
        RawPrimitive::CaHelix(p) => {
            Primitive::CaHelix(p.resolve(&|n: &Num, place: &str| ctx.num(n, place))?)
        }
        RawPrimitive::Solid(s) => Primitive::Solid(crate::primitive::solid::resolve(
            s,
            &|n: &Num, place: &str| ctx.num(n, place),
        )?),
        RawPrimitive::Turtle(_) => unreachable!("a turtle is resolved by resolve_part"),
    })
}

fn keep(k: &Option<RawKeep>) -> Keep {
    match k {
        Some(RawKeep::Speed) => Keep::Speed,
        _ => Keep::Flow,
    }
}

fn resolve_deform(ctx: &Ctx, d: &RawDeform, key: &str, cylinder: bool) -> Result<Deform> {
    let position = match &d.position {
        Some(p) => Some([
            ctx.expr(&p[0], POINT_VARS, &format!("{key}.position[0]"))?,
            ctx.expr(&p[1], POINT_VARS, &format!("{key}.position[1]"))?,
            ctx.expr(&p[2], POINT_VARS, &format!("{key}.position[2]"))?,
        ]),
        None => None,
    };
    Ok(Deform {
        cylinder,
        position,
        cross_section: match &d.cross_section {
            Some(n) => Some(ctx.expr(n, STRING_VARS, &format!("{key}.cross_section"))?),
            None => None,
        },
        speed: match &d.speed {
            Some(n) => Some(ctx.expr(n, STRING_VARS, &format!("{key}.speed"))?),
            None => None,
        },
    })
}

fn resolve_step(ctx: &Ctx, s: &RawStep) -> Result<Step> {
    Ok(match s {
        RawStep::DeformXyz(d) => Step::DeformXyz(resolve_deform(ctx, d, "deform_xyz", false)?),
        RawStep::DeformCylinder(d) => {
            Step::DeformCylinder(resolve_deform(ctx, d, "deform_cylinder", true)?)
        }
        RawStep::ModulateCylinder { factor, keep: k } => Step::ModulateCylinder(Modulate {
            factor: ctx.expr(factor, STRING_VARS, "modulate_cylinder.factor")?,
            keep: keep(k),
        }),
        RawStep::ModulateMap {
            image,
            text,
            u,
            v,
            dark,
            light,
            threshold,
            keep: k,
        } => {
            let key = "modulate_map";
            let factor = |n: &Option<Num>, name: &str| match n {
                Some(n) => ctx.positive(n, &format!("{key}.{name}")),
                None => Ok(1.0),
            };
            let threshold = match threshold {
                Some(n) => ctx.num(n, &format!("{key}.threshold"))?,
                None => 0.5,
            };
            if !(0.0..=1.0).contains(&threshold) {
                return Err(Error::input(
                    format!("{key}.threshold"),
                    format!("{threshold} is not allowed; expected a number from 0 to 1"),
                ));
            }
            let bitmap = match (image, text) {
                (Some(image), None) => load_bitmap(&ctx.dir.join(image), image)
                    .map_err(|m| Error::input(format!("{key}.image"), m))?,
                (None, Some(text)) => {
                    Bitmap::from_text(text).map_err(|m| Error::input(format!("{key}.text"), m))?
                }
                _ => {
                    return Err(Error::input(
                        key,
                        "expected exactly one of `image` (a picture file) and `text` (letters)",
                    ))
                }
            };
            Step::ModulateMap(ModulateMap {
                image: bitmap,
                u: ctx.expr(u, POINT_VARS, &format!("{key}.u"))?,
                v: ctx.expr(v, POINT_VARS, &format!("{key}.v"))?,
                dark: factor(dark, "dark")?,
                light: factor(light, "light")?,
                threshold,
                keep: keep(k),
            })
        }
        RawStep::Subdivide { max_length } => {
            Step::Subdivide(ctx.positive(max_length, "subdivide.max_length")?)
        }
        RawStep::Translate(d) => Step::Translate(ctx.point(d, "translate")?),
    })
}

/// Loads an image as grey levels 0..1; the error names the image as written.
pub fn load_bitmap(path: &PathBuf, shown: &str) -> std::result::Result<Bitmap, String> {
    let open = || {
        image::ImageReader::open(path)
            .map_err(|e| format!("cannot open the image `{shown}` ({}): {e}", path.display()))?
            .with_guessed_format()
            .map_err(|e| format!("cannot read the image `{shown}`: {e}"))
    };
    // the header's size first: a small file may declare a huge image
    let (w, h) = open()?.into_dimensions().map_err(|e| {
        format!("`{shown}` is not an image p3dp can read (PNG, JPEG, BMP, GIF): {e}")
    })?;
    crate::input::check_image_size(w, h).map_err(|m| format!("the image `{shown}` {m}"))?;
    let mut reader = open()?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w.max(1));
    limits.max_image_height = Some(h.max(1));
    limits.max_alloc = Some(crate::input::MAX_IMAGE_PIXELS * 8);
    reader.limits(limits);
    let img = reader.decode().map_err(|e| {
        format!("`{shown}` is not an image p3dp can read (PNG, JPEG, BMP, GIF): {e}")
    })?;
    let grey = img.to_luma8();
    let (w, h) = grey.dimensions();
    if w == 0 || h == 0 {
        return Err(format!("the image `{shown}` is empty"));
    }
    Ok(Bitmap {
        width: w as usize,
        height: h as usize,
        pixels: grey.as_raw().iter().map(|&p| p as f32 / 255.0).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Result<Recipe> {
        let raw: RawRecipe = parse_yaml(text, "t.yaml")?;
        Recipe::resolve(&raw, &[], None, Path::new("."))
    }

    const HELIX: &str = "p3dp: 1\nname: h\nparams:\n  radius: 10\n  height: \"2*radius\"\nparts:\n  - primitive: {helix: {radius: radius, height: height, pitch: 0.5}}\n";

    #[test]
    fn params_chain_and_set_overrides() {
        let r = load(HELIX).unwrap();
        assert_eq!(r.params["height"], 20.0);
        let raw: RawRecipe = parse_yaml(HELIX, "t.yaml").unwrap();
        let r = Recipe::resolve(
            &raw,
            &[("radius".into(), "3*4".into())],
            None,
            Path::new("."),
        )
        .unwrap();
        assert_eq!(r.params["height"], 24.0);
        let e = Recipe::resolve(&raw, &[("radios".into(), "3".into())], None, Path::new("."))
            .unwrap_err();
        assert!(e.to_string().contains("unknown param `radios`"), "{e}");
    }

    #[test]
    fn unknown_key_names_the_path_and_line() {
        let e = load(&HELIX.replace("pitch: 0.5", "pitch: 0.5, pich: 1")).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("parts[0].primitive.helix.pich"));
        assert_eq!(e.line.map(|l| l.0), Some(7));
        assert!(e.message.contains("expected one of"), "{e}");
    }

    #[test]
    fn bad_values_name_the_key() {
        let e = load(&HELIX.replace("pitch: 0.5", "pitch: -1")).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("parts[0].primitive.helix.pitch"));
        let e = load(&HELIX.replace("pitch: 0.5", "pitch: 0.5, segments: 2.5")).unwrap_err();
        assert_eq!(
            e.place.as_deref(),
            Some("parts[0].primitive.helix.segments")
        );
        let e = load(&HELIX.replace("pitch: 0.5", "pitch: 0.0000001")).unwrap_err();
        assert!(e.message.contains("more than the limit"), "{e}");
    }

    #[test]
    fn step_expressions_compile_with_places() {
        let text = format!(
            "{HELIX}    steps:\n      - deform_cylinder: {{position: [r, theta, \"z + \"]}}\n"
        );
        let e = load(&text).unwrap_err();
        assert_eq!(
            e.place.as_deref(),
            Some("parts[0].steps[0].deform_cylinder.position[2]")
        );
        assert!(e.message.contains("z + "), "{e}");
    }

    #[test]
    fn materials() {
        let r = load(&HELIX.replace("name: h", "name: h\nmaterial: petg")).unwrap();
        assert_eq!(r.material.name, "petg");
        let r = load(&HELIX.replace(
            "name: h",
            "name: h\nmaterial: {filament_diameter: 2.85, density: 1.2, nozzle_temp: 200, bed_temp: 50}",
        ))
        .unwrap();
        assert_eq!(r.material.filament_diameter, Some(2.85));
        let e = load(&HELIX.replace("name: h", "name: h\nmaterial: wood")).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("material"));
    }
}
