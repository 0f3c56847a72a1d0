//! Resolution: params evaluated in order (with `--set`), every number
//! evaluated and every expression compiled, images loaded, each error naming
//! its key path (derived from the raw forms' field names, see
//! [`crate::recipe::eval`]).
//!
//! Here the recipe's top level; a part in `part.rs`, its primitives in
//! `primitive.rs` (`pattern.rs`, `solid.rs`, `turtle.rs` for the larger
//! ones), steps in `step.rs`, an inline material in `material.rs`.

mod material;
mod part;
mod pattern;
pub(crate) mod plate;
mod primitive;
mod solid;
pub(crate) mod step;
mod turtle;

use std::path::Path;

use super::context::Context;
use super::eval::{at, join, key, Scope};
use super::expand::Expansion;
use super::schema::{RawPart, RawRecipe};
use super::yaml::parse_yaml;
use crate::base::error::{Error, Result};
use crate::generate::model::{
    Group, Part, Recipe, Skirt, DEFAULT_CROSS_SECTION, DEFAULT_MAX_STRINGS, DEFAULT_SPEED,
};
use crate::machine::{Material, Printer};

pub(crate) use material::from_filament;

/// Evaluates numbers of one recipe: its params, and where images and a
/// turtle's limits come from.
/// The check of a recipe's own printer command (`gcode:`, `gcode_at:`) for
/// the recipe's printer and material: `Err` says why it is refused.
pub(super) type GcodeCheck<'a> = &'a dyn Fn(&str) -> std::result::Result<(), String>;

struct Ctx<'a> {
    scope: Scope<'a>,
    /// The check of the recipe's own printer commands.
    gcode: GcodeCheck<'a>,
    dir: &'a Path,
    /// The load's files read and z-buffers lent.
    cx: &'a Context,
    /// Filament area (mm²) and max_strings, for a turtle (set once known).
    turtle: (f64, u64),
}

impl<'a> std::ops::Deref for Ctx<'a> {
    type Target = Scope<'a>;
    fn deref(&self) -> &Scope<'a> {
        &self.scope
    }
}

/// Reads and resolves a recipe file. `printer` overrides the recipe's printer.
#[cfg(any(test, feature = "testing"))]
pub fn load(path: &Path, sets: &[(String, String)], printer: Option<&Printer>) -> Result<Recipe> {
    load_in(path, sets, printer, &Context::default())
}

/// [`load`] in the context `cx`: every file read noted there, the
/// z-buffers it lends used.
pub fn load_in(
    path: &Path,
    sets: &[(String, String)],
    printer: Option<&Printer>,
    cx: &Context,
) -> Result<Recipe> {
    load_with(path, sets, printer, None, cx)
}

/// [`load_in`], `material` (a filament preset's, `--filament`)
/// overriding the recipe's material.
pub(crate) fn load_with(
    path: &Path,
    sets: &[(String, String)],
    printer: Option<&Printer>,
    material: Option<&Material>,
    cx: &Context,
) -> Result<Recipe> {
    let raw = read_raw(path, cx)?;
    from_raw_in(&raw, path, sets, (printer, material), cx)
}

/// The recipe file at `path` as written (a recipe or a plate), read in
/// the context `cx`.
pub(crate) fn read_raw(path: &Path, cx: &Context) -> Result<RawRecipe> {
    let shown = path.display().to_string();
    let text = cx.reads.read_text(path, "recipe")?;
    let raw: RawRecipe = parse_yaml(&text, &shown)?;
    if raw.parts.is_empty() && raw.plate.is_none() {
        // neither key: named where the top-level map starts, as a
        // missing key is
        #[derive(serde::Deserialize)]
        struct Parts {
            #[allow(dead_code)]
            parts: serde::de::IgnoredAny,
        }
        if let Err(e) = parse_yaml::<Parts>(&text, &shown) {
            return Err(Error {
                message: "missing field `parts`; expected `parts` (the parts to print) or `plate` (the recipes a plate puts on the bed)".into(),
                ..e
            });
        }
    }
    Ok(raw)
}

/// [`load_in`] of the recipe `raw` read from `path`, with the
/// command line's printer and material (`--filament`) if given.
pub(crate) fn from_raw_in(
    raw: &RawRecipe,
    path: &Path,
    sets: &[(String, String)],
    given: (Option<&Printer>, Option<&Material>),
    cx: &Context,
) -> Result<Recipe> {
    let shown = path.display().to_string();
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    resolve_in(raw, sets, given, &dir, Some(path), cx).map_err(|e| e.in_file(&shown))
}

/// Resolves a parsed recipe; relative paths are taken from `dir`.
#[cfg(any(test, feature = "testing"))]
pub(crate) fn resolve(
    raw: &RawRecipe,
    sets: &[(String, String)],
    printer: Option<&Printer>,
    dir: &Path,
) -> Result<Recipe> {
    resolve_in(raw, sets, (printer, None), dir, None, &Context::default())
}

/// [`resolve`] for the recipe read from `file` (so that an
/// include cycle through it is named).
fn resolve_in(
    raw: &RawRecipe,
    sets: &[(String, String)],
    (printer, given): (Option<&Printer>, Option<&Material>),
    dir: &Path,
    file: Option<&Path>,
    cx: &Context,
) -> Result<Recipe> {
    check_top(raw)?;
    if file.is_none() {
        // a recipe given as parsed YAML reads in the project of `dir`
        cx.reads.allow(&crate::base::input::project_root(dir));
    }
    let library = super::expand::load_library(raw, file, dir, &cx.reads)?;
    let params = library.eval_params(sets)?;
    let top = Scope::new(&params);
    let printer = match printer {
        Some(p) => p.clone(),
        None => {
            let spec = raw.printer.as_deref().unwrap_or("generic-220");
            crate::recipe::profile::resolve(spec, dir, &cx.reads)?
        }
    };
    let material = match given {
        Some(m) => m.clone(),
        None => material::resolve(&top.under(key!(raw.material)), raw.material.as_ref())?,
    };
    let mut printer = printer;
    if let Some(q) = material.max_volumetric_speed {
        // the filament's own flow limit, where it is below the hot end's
        printer.max_flow = printer.max_flow.min(q);
    }
    let defaults = &raw.defaults;
    let ds = top.under(key!(raw.defaults));
    let c0 = ds.positive_or(at!(defaults.cross_section), DEFAULT_CROSS_SECTION)?;
    let v0 = ds.positive_or(at!(defaults.speed), DEFAULT_SPEED)?;
    let skirt = match &raw.skirt {
        Some(s) => {
            let ss = top.under(key!(raw.skirt));
            Some(Skirt {
                distance: ss.non_negative(at!(s.distance))?,
                loops: ss.whole_max(at!(s.loops), 1, 1000)?,
            })
        }
        None => None,
    };
    let max_strings = match at!(raw.max_strings).some() {
        Some(n) => top.whole(n, 1)? as u64,
        None => DEFAULT_MAX_STRINGS,
    };
    let d = material
        .filament_diameter
        .unwrap_or(printer.filament_diameter);
    let turtle = (std::f64::consts::PI * (d / 2.0) * (d / 2.0), max_strings);
    // templates, loops, groups and recipes included whole expanded into
    // leaf parts; those that turn out empty (a turtle whose every move
    // an `if` skips) dropped
    let includes = super::expand::load_part_includes(raw, file, dir, &library, &cx.reads)?;
    let expansion = super::expand::expand(&raw.parts, &library.templates, &params, dir, &includes)?;
    let check = |t: &str| crate::analyse::check::gcode::command(t, &printer, &material).map(|_| ());
    let (parts, kept) = leaves(&expansion, turtle, (c0, v0), max_strings, cx, &check)?;
    if parts.is_empty() {
        return Err(Error::input(
            key!(raw.parts),
            "every part is switched off (by `if`, an empty `for` or a path that moves nowhere): nothing to print; expected at least one part",
        ));
    }
    let groups = groups(&expansion, &kept, turtle, cx, &check)?;
    let allow: Vec<String> = raw.allow.iter().map(|a| a.code().to_string()).collect();
    let allow_key = key!(raw.allow);
    crate::base::finding::validate_allow(&allow, |i| format!("{allow_key}[{i}]"))?;
    Ok(Recipe {
        name: raw.name.clone(),
        params,
        printer,
        material,
        skirt,
        parts,
        max_strings,
        allow,
        groups,
        objects: Vec::new(),
    })
}

/// The top level's own checks: the format version, a name, some parts.
fn check_top(raw: &RawRecipe) -> Result<()> {
    if raw.p3dp != 1 {
        return Err(Error::input(
            key!(raw.p3dp),
            format!("format version {} is not known; expected 1", raw.p3dp),
        ));
    }
    if raw.name.trim().is_empty() {
        return Err(Error::input(key!(raw.name), "expected a non-empty name"));
    }
    // names reach G-code comments: one line each, no control characters
    crate::base::safe_text::check(key!(raw.name), &raw.name)?;
    if let Some(d) = &raw.description {
        // a block scalar's final line break is no line of its own
        crate::base::safe_text::check(key!(raw.description), d.trim_end_matches(['\n', '\r']))?;
    }
    if raw.plate.is_some() {
        return Err(Error::input(
            key!(raw.plate),
            "a plate is built on its own (`p3dp build`), not read as a recipe",
        ));
    }
    if raw.parts.is_empty() {
        return Err(Error::input(key!(raw.parts), "expected at least one part"));
    }
    Ok(())
}

/// The leaf parts resolved, each with the params in its scope; `c0` and
/// `v0` are the defaults' cross-section and speed (a recipe included as a
/// part brings its own). Each part, and all of them together, must stay
/// within `max_strings`. A part whose primitives make no string at all (a
/// turtle or path whose every move an `if` skips) is left out: with the
/// parts, for each leaf its index among them (`None`: left out).
fn leaves(
    expansion: &Expansion,
    turtle: (f64, u64),
    (c0, v0): (f64, f64),
    max_strings: u64,
    cx: &Context,
    gcode: GcodeCheck,
) -> Result<(Vec<Part>, Vec<Option<usize>>)> {
    // the limit holds for all parts together too (YAML aliases, loops)
    let total_limit = max_strings;
    let mut total = 0u64;
    let mut parts = Vec::with_capacity(expansion.leaves.len());
    let mut kept = Vec::with_capacity(expansion.leaves.len());
    for (k, leaf) in expansion.leaves.iter().enumerate() {
        let place = &leaf.place;
        let ctx = Ctx {
            gcode,
            scope: Scope::new(&leaf.params),
            dir: leaf.dir,
            cx,
            turtle,
        };
        let raw = leaf.part;
        let (c0, v0) = leaf.defaults.unwrap_or((c0, v0));
        let mut part = part::resolve(&ctx, raw, c0, v0, k).map_err(|e| e.under(place))?;
        part::settings_under(&mut part.primitive, place);
        for piece in &mut part.more {
            part::settings_under(&mut piece.primitive, place);
        }
        if part.primitives().all(|p| p.string_count() == 0) {
            kept.push(None);
            continue;
        }
        kept.push(Some(parts.len()));
        if let Some(name) = &leaf.name {
            part.name.clone_from(name);
        }
        part.place.clone_from(place);
        crate::base::safe_text::check(&join(place, key!(raw.name)), &part.name)?;
        let n = part.string_count();
        let at = join(place, key!(raw.primitive));
        if n > max_strings {
            return Err(Error::input(
                at,
                format!(
                    "this primitive would make {n} strings, more than the limit of {max_strings}; expected a larger pitch or fewer segments (or raise max_strings)"
                ),
            ));
        }
        total = total.saturating_add(n);
        if total > total_limit {
            return Err(Error::input(
                at,
                format!(
                    "the parts up to this one make {total} strings, more than the limit of {total_limit} for the whole recipe (all parts together); expected fewer or smaller parts (or raise max_strings)"
                ),
            ));
        }
        parts.push(part);
    }
    Ok((parts, kept))
}

/// The groups' steps resolved, each with the params where it is written;
/// `kept` maps each leaf to its part (see [`leaves`]). A group whose parts
/// were all left out has nothing to run on.
fn groups(
    expansion: &Expansion,
    kept: &[Option<usize>],
    turtle: (f64, u64),
    cx: &Context,
    gcode: GcodeCheck,
) -> Result<Vec<Group>> {
    let mut groups = Vec::with_capacity(expansion.groups.len());
    for g in &expansion.groups {
        // the parts the group's leaves became
        let mut made = kept[g.first..g.end].iter().flatten();
        let Some(&first) = made.next() else {
            continue;
        };
        let end = made.last().map_or(first, |&k| k) + 1;
        let ctx = Ctx {
            gcode,
            scope: Scope::new(&g.params),
            dir: g.dir,
            cx,
            turtle,
        };
        let mut steps = Vec::with_capacity(g.steps.len());
        for (j, s) in g.steps.iter().enumerate() {
            let at = join(key!(RawPart, steps), &format!("[{j}]"));
            steps.push(step::resolve(&ctx, s).map_err(|e| e.under(&at).under(&g.place))?);
        }
        groups.push(Group {
            first,
            end,
            steps,
            place: g.place.clone(),
        });
    }
    Ok(groups)
}
#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Result<Recipe> {
        let raw: RawRecipe = parse_yaml(text, "t.yaml")?;
        super::resolve(&raw, &[], None, Path::new("."))
    }

    const HELIX: &str = "p3dp: 1\nname: h\nparams:\n  radius: 10\n  height: \"2*radius\"\nparts:\n  - primitive: {helix: {radius: radius, height: height, pitch: 0.5}}\n";

    #[test]
    fn params_chain_and_set_overrides() {
        let r = load(HELIX).unwrap();
        assert_eq!(r.params["height"], 20.0);
        let raw: RawRecipe = parse_yaml(HELIX, "t.yaml").unwrap();
        let r = super::resolve(
            &raw,
            &[("radius".into(), "3*4".into())],
            None,
            Path::new("."),
        )
        .unwrap();
        assert_eq!(r.params["height"], 24.0);
        let e = super::resolve(&raw, &[("radios".into(), "3".into())], None, Path::new("."))
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
