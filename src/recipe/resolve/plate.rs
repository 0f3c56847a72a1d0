//! A plate: whole recipes put on one bed, each printed complete before the
//! next. A plate file is a recipe whose top level lists `plate:` entries
//! instead of `parts:` ([`PlateSpec::from_raw`]); `p3dp plate RECIPE*N …`
//! makes the same [`PlateSpec`] from the command line, so the same plate
//! gives the same bytes either way.
//!
//! [`make`] loads every object (an entry's recipe with its `set:` values,
//! once per combination of its `sweep:` values, `copies` times), builds its
//! strings as a build of that recipe alone would (steps, groups, brims,
//! stands, its skirt first), arranges the objects on the bed
//! ([`crate::generate::plate`]) and returns one recipe of all their parts,
//! named `OBJECT/PART`, with the objects in print order.

use std::path::{Path, PathBuf};

use glam::DVec2;

use super::material;
use crate::base::error::{Error, Result};
use crate::base::expr::{Kind, Params};
use crate::base::toolpath::Toolpath;
use crate::generate::model::{Object, Recipe, DEFAULT_MAX_STRINGS};
use crate::generate::plate::{self as arrange, Area, Item, Refusal, Shadow};
use crate::machine::Printer;
use crate::recipe::context::Context;
use crate::recipe::eval::{key, Scope};
use crate::recipe::params::{format_value, parse_sweep};
use crate::recipe::schema::{
    Num, RawDefaults, RawMaterial, RawParam, RawPlateItem, RawRecipe, RawSweep,
};

/// Most copies of one entry.
pub(crate) const MAX_COPIES: u32 = 200;
/// Most objects on one plate (the arrangement's work grows as the cube of
/// their number; a bed holds far fewer with the head's reach between them).
pub(crate) const MAX_OBJECTS: usize = 200;

/// A plate as the build takes it, from a plate file or the command line.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct PlateSpec {
    /// The plate's name: the G-code's and the output file's.
    pub(crate) name: String,
    /// `printer:`, a built-in or a file relative to `dir`; `None`: the
    /// first object's recipe's.
    pub(crate) printer: Option<String>,
    /// `material:`; `None`: the first object's.
    pub(crate) material: Option<RawMaterial>,
    /// Check codes silenced on the whole plate.
    pub(crate) allow: Vec<String>,
    /// What goes on the bed, in order.
    pub(crate) entries: Vec<PlateEntry>,
    /// Where relative paths start.
    pub(crate) dir: PathBuf,
    /// The recipes were named on the command line (read wherever they
    /// lie), not reached through a plate file's keys (read in its project).
    pub(crate) named: bool,
}

/// One entry: a recipe, its params, its variants and copies, maybe a place.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct PlateEntry {
    /// The recipe file.
    pub(crate) recipe: PathBuf,
    /// The objects' name; `None`: the recipe's.
    pub(crate) name: Option<String>,
    /// Copies of each variant.
    pub(crate) copies: u32,
    /// Its params, as `--set` gives them.
    pub(crate) sets: Vec<(String, String)>,
    /// Its variants, as `--sweep` gives them.
    pub(crate) sweeps: Vec<(String, Vec<String>)>,
    /// A fixed place for its (0, 0), recipe coordinates.
    pub(crate) at: Option<[f64; 2]>,
    /// Where it is written (`plate[1]`; on the command line, the argument).
    pub(crate) place: String,
}

impl PlateSpec {
    /// The plate of a plate file `raw` read from `path`.
    pub(crate) fn from_raw(raw: &RawRecipe, path: &Path) -> Result<PlateSpec> {
        let shown = path.display().to_string();
        let items = raw.plate.as_deref().unwrap_or_default();
        only_plate_keys(raw).map_err(|e| e.in_file(&shown))?;
        if items.is_empty() {
            return Err(Error::input(
                key!(raw.plate),
                "expected at least one entry, e.g. `- {recipe: pot.yaml}`",
            )
            .in_file(&shown));
        }
        let mut entries = Vec::with_capacity(items.len());
        for (k, item) in items.iter().enumerate() {
            let place = format!("{}[{k}]", key!(raw.plate));
            entries.push(entry(item, &place).map_err(|e| e.in_file(&shown))?);
        }
        Ok(PlateSpec {
            name: raw.name.clone(),
            printer: raw.printer.clone(),
            material: raw.material.clone(),
            allow: raw.allow.iter().map(|a| a.code().to_string()).collect(),
            entries,
            dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
            named: false,
        })
    }
}

/// Refuses a plate file's keys that belong to recipes (a plate's objects
/// bring their own), and checks its name.
fn only_plate_keys(raw: &RawRecipe) -> Result<()> {
    if raw.p3dp != 1 {
        return Err(Error::input(
            key!(raw.p3dp),
            format!("format version {} is not known; expected 1", raw.p3dp),
        ));
    }
    if raw.name.trim().is_empty() {
        return Err(Error::input(key!(raw.name), "expected a non-empty name"));
    }
    crate::base::safe_text::check(key!(raw.name), &raw.name)?;
    if let Some(d) = &raw.description {
        crate::base::safe_text::check(key!(raw.description), d.trim_end_matches(['\n', '\r']))?;
    }
    for (key, given) in [
        (key!(raw.parts), !raw.parts.is_empty()),
        (key!(raw.params), !raw.params.is_empty()),
        (key!(raw.templates), !raw.templates.is_empty()),
        (key!(raw.include), !raw.include.is_empty()),
        (key!(raw.defaults), raw.defaults != RawDefaults::default()),
        (key!(raw.skirt), raw.skirt.is_some()),
        (key!(raw.max_strings), raw.max_strings.is_some()),
    ] {
        if given {
            return Err(Error::input(
                key,
                format!("a plate takes no `{key}`: its objects' recipes bring their own; expected `plate` entries (recipe, name, copies, set, sweep, at) beside p3dp, name, description, printer, material and allow"),
            ));
        }
    }
    Ok(())
}

/// One entry of `plate:`, at `place`.
fn entry(item: &RawPlateItem, place: &str) -> Result<PlateEntry> {
    let at = |key: &str| format!("{place}.{key}");
    let none = Params::new();
    let copies = match &item.copies {
        Some(n) => {
            let v = crate::recipe::eval::eval(n, &none, &at(key!(item.copies)))?;
            if v.fract() != 0.0 || !(1.0..=MAX_COPIES as f64).contains(&v) {
                return Err(Error::input(
                    at(key!(item.copies)),
                    format!(
                        "{v} is not allowed; expected a whole number of copies, 1 to {MAX_COPIES}"
                    ),
                ));
            }
            v as u32
        }
        None => 1,
    };
    let mut sets = Vec::with_capacity(item.set.len());
    for (name, v) in &item.set {
        sets.push((
            name.clone(),
            set_text(v, &format!("{}.{name}", at(key!(item.set))))?,
        ));
    }
    let mut sweeps = Vec::with_capacity(item.sweep.len());
    for (name, v) in &item.sweep {
        let here = format!("{}.{name}", at(key!(item.sweep)));
        let values = match v {
            RawSweep::Text(t) => {
                parse_sweep(&format!("{name}={t}"))
                    .map_err(|e| Error {
                        place: Some(here.clone()),
                        ..e
                    })?
                    .1
            }
            RawSweep::List(v) if v.is_empty() => {
                return Err(Error::input(here, "expected at least one value"))
            }
            RawSweep::List(v) => v.iter().map(num_text).collect(),
        };
        sweeps.push((name.clone(), values));
    }
    let fixed = match &item.at {
        Some([x, y]) => {
            let place = at(key!(item.at));
            let x = crate::recipe::eval::eval(x, &none, &format!("{place}[0]"))?;
            let y = crate::recipe::eval::eval(y, &none, &format!("{place}[1]"))?;
            Some([
                crate::recipe::eval::finite(x, &place)?,
                crate::recipe::eval::finite(y, &place)?,
            ])
        }
        None => None,
    };
    if let Some(n) = &item.name {
        crate::base::safe_text::check(&at(key!(item.name)), n)?;
    }
    Ok(PlateEntry {
        recipe: PathBuf::from(&item.recipe),
        name: item.name.clone(),
        copies,
        sets,
        sweeps,
        at: fixed,
        place: place.to_string(),
    })
}

/// A number or expression as `--set` writes it.
fn num_text(n: &Num) -> String {
    match n {
        Num::Value(v) => format_value(*v),
        Num::Expr(s) => s.clone(),
    }
}

/// A `set:` value as `--set` writes it: a number or expression, `true` or
/// `false`, a list `[a, b]`, or a choice's string.
fn set_text(v: &RawParam, place: &str) -> Result<String> {
    Ok(match v {
        RawParam::Num(n) => num_text(n),
        RawParam::Bool(b) => b.to_string(),
        RawParam::List(items) => {
            let v: Vec<String> = items.iter().map(num_text).collect();
            format!("[{}]", v.join(", "))
        }
        RawParam::Choice(_) | RawParam::Each(_) => {
            return Err(Error::input(
                place,
                "expected a value (a number or expression, true or false, a list, or a choice's string), not a choice's or a loop's declaration",
            ))
        }
    })
}

/// An object loaded: its entry, its recipe and its strings (skirt first),
/// in its own coordinates.
struct Loaded {
    entry: usize,
    recipe: std::sync::Arc<Recipe>,
    paths: std::sync::Arc<Vec<Toolpath>>,
}

/// Makes the plate `spec` with the command line's `sets` (given to every
/// object after its own) and `printer` (in place of the plate's): one recipe
/// of every object's parts and their paths, arranged, in print order.
pub(crate) fn make(
    spec: &PlateSpec,
    sets: &[(String, String)],
    printer: Option<&Printer>,
    cx: &Context,
) -> Result<(Recipe, Vec<Toolpath>)> {
    let printer = match printer {
        Some(p) => p.clone(),
        None => plate_printer(spec, cx)?,
    };
    let loaded = load_objects(spec, sets, &printer, cx)?;
    let names = names(spec, &loaded)?;
    let material = plate_material(spec, &loaded, &names)?;
    let mut items = Vec::with_capacity(loaded.len());
    for (o, name) in loaded.iter().zip(&names) {
        let shadow = Shadow::of(&o.paths).ok_or_else(|| {
            Error::input(
                &spec.entries[o.entry].place,
                format!("object `{name}` prints nothing; expected a recipe that extrudes"),
            )
        })?;
        let at = spec.entries[o.entry].at.map(DVec2::from_array);
        items.push(Item { shadow, at });
    }
    let order = arrange::arrange(&items, &printer.head, &Area::of(&printer))
        .map_err(|r| refused(r, spec, &loaded, &names, &items, &printer))?;
    compose(spec, &loaded, &names, &order, printer, material)
}

/// The printer of a plate without `--printer`: its `printer:`, else the
/// first object's recipe's, else the default.
fn plate_printer(spec: &PlateSpec, cx: &Context) -> Result<Printer> {
    if let Some(p) = &spec.printer {
        return crate::recipe::profile::resolve(p, &spec.dir, &cx.reads);
    }
    let first = &spec.entries[0];
    let path = spec.dir.join(&first.recipe);
    reach(spec, first, &path, cx)?;
    let raw = super::read_raw(&path, cx)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let p = raw.printer.as_deref().unwrap_or("generic-220");
    crate::recipe::profile::resolve(p, &dir, &cx.reads)
        .map_err(|e| e.in_file(&path.display().to_string()))
}

/// Refuses a recipe a plate file names outside the folders it may read
/// (the command line's recipes may lie anywhere).
fn reach(spec: &PlateSpec, e: &PlateEntry, path: &Path, cx: &Context) -> Result<()> {
    if spec.named {
        return Ok(());
    }
    cx.reads
        .reach(path, "recipe")
        .map_err(|err| err.under(&format!("{}.recipe", e.place)))
}

/// Every object: each entry's recipe loaded once per variant (its sweeps'
/// combinations), its strings made once, `copies` times.
fn load_objects(
    spec: &PlateSpec,
    sets: &[(String, String)],
    printer: &Printer,
    cx: &Context,
) -> Result<Vec<Loaded>> {
    let mut out = Vec::new();
    for (i, e) in spec.entries.iter().enumerate() {
        let path = spec.dir.join(&e.recipe);
        reach(spec, e, &path, cx)?;
        let shown = path.display().to_string();
        // counted before any is made: sweeps multiply
        let count = e
            .sweeps
            .iter()
            .fold(e.copies as usize, |n, (_, v)| n.saturating_mul(v.len()));
        if out.len().saturating_add(count) > MAX_OBJECTS {
            return Err(Error::input(
                &e.place,
                format!("{} objects with the ones before, more than {MAX_OBJECTS} on one plate; expected fewer copies or variants", out.len().saturating_add(count)),
            ));
        }
        for variant in variants(&e.sweeps) {
            let mut s = e.sets.clone();
            s.extend(variant.iter().cloned());
            s.extend(sets.iter().cloned());
            let recipe = super::load_in(&path, &s, Some(printer), cx)
                .map_err(|err| own_values(err, spec, e, &variant))?;
            let paths = arrange::made(&recipe).map_err(|err| err.in_file(&shown))?;
            let (recipe, paths) = (std::sync::Arc::new(recipe), std::sync::Arc::new(paths));
            for _ in 0..e.copies {
                out.push(Loaded {
                    entry: i,
                    recipe: recipe.clone(),
                    paths: paths.clone(),
                });
            }
        }
    }
    Ok(out)
}

/// An object's load error about a value its entry gave (the params read
/// each as a `--set`) named where it was given: a plate file's
/// `plate[k].set.NAME` or `plate[k].sweep.NAME` (in the plate file), the
/// command line's `--sweep NAME=VALUE`.
fn own_values(err: Error, spec: &PlateSpec, e: &PlateEntry, variant: &[(String, String)]) -> Error {
    let given =
        |(n, v): &&(String, String)| err.place.as_deref() == Some(&format!("--set {n}={v}"));
    let (what, (name, value)) = match (variant.iter().find(given), e.sets.iter().find(given)) {
        (Some(nv), _) => ("sweep", nv),
        (None, Some(nv)) => ("set", nv),
        (None, None) => return err,
    };
    if spec.named {
        return Error {
            place: Some(format!("--{what} {name}={value}")),
            ..err
        };
    }
    Error {
        file: None,
        line: None,
        place: Some(format!("{}.{what}.{name}", e.place)),
        ..err
    }
}

/// Every combination of the sweeps' values (the first sweep outermost), as
/// `--set` values; one empty combination without sweeps.
pub(crate) fn variants(sweeps: &[(String, Vec<String>)]) -> Vec<Vec<(String, String)>> {
    let mut combos: Vec<Vec<(String, String)>> = vec![Vec::new()];
    for (name, values) in sweeps {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push((name.clone(), v.clone()));
                    c
                })
            })
            .collect();
    }
    combos
}

/// The objects' names: each entry's `name:` or its recipe's, numbered
/// `NAME-1`, `NAME-2`… in plate order when several objects share it; two
/// objects of one name are refused.
fn names(spec: &PlateSpec, loaded: &[Loaded]) -> Result<Vec<String>> {
    let base: Vec<&str> = loaded
        .iter()
        .map(|o| {
            spec.entries[o.entry]
                .name
                .as_deref()
                .unwrap_or(&o.recipe.name)
        })
        .collect();
    let mut seen: indexmap::IndexMap<&str, usize> = indexmap::IndexMap::new();
    let mut out = Vec::with_capacity(loaded.len());
    for b in &base {
        let n = base.iter().filter(|x| *x == b).count();
        let k = seen.entry(b).or_insert(0);
        *k += 1;
        out.push(if n > 1 {
            format!("{b}-{k}")
        } else {
            b.to_string()
        });
    }
    for (k, n) in out.iter().enumerate() {
        if out[..k].contains(n) {
            return Err(Error::input(
                &spec.entries[loaded[k].entry].place,
                format!(
                    "two objects are named `{n}`; expected each its own name (`name:` on an entry)"
                ),
            ));
        }
    }
    Ok(out)
}

/// The plate's material: its `material:`, else the first object's; every
/// object's recipe must print in it (one filament for the plate).
fn plate_material(
    spec: &PlateSpec,
    loaded: &[Loaded],
    names: &[String],
) -> Result<crate::machine::Material> {
    let none = Params::new();
    let material = match &spec.material {
        Some(m) => material::resolve(&Scope::new(&none).under("material"), Some(m))?,
        None => loaded[0].recipe.material.clone(),
    };
    for (o, name) in loaded.iter().zip(names) {
        if o.recipe.material != material {
            return Err(Error::input(
                &spec.entries[o.entry].place,
                format!(
                    "object `{name}` is printed in `{}`, the plate in `{}`: one plate takes one filament; expected the same material (or another plate)",
                    o.recipe.material.name, material.name
                ),
            ));
        }
    }
    Ok(material)
}

/// The error of an arrangement refused, naming the object and the reason.
fn refused(
    r: Refusal,
    spec: &PlateSpec,
    loaded: &[Loaded],
    names: &[String],
    items: &[Item],
    printer: &Printer,
) -> Error {
    let place = |k: usize| spec.entries[loaded[k].entry].place.clone();
    let size = |k: usize| {
        let s = items[k].shadow.size();
        format!("{:.1} × {:.1} mm", s.x, s.y)
    };
    let r4 = printer.head.reach();
    let keep = format!(
        "each object is kept {}…{} mm in x and {}…{} mm in y (the head's reach, head.box) and {} mm more from the one printed before",
        r4[0], r4[1], r4[2], r4[3], arrange::MARGIN
    );
    let bed = printer.bed.describe();
    match r {
        Refusal::TooBig(k) => Error::input(
            place(k),
            format!("object `{}` ({} seen from above, with its brim and skirt) does not fit on the bed ({bed}, less {} mm at the edges); expected a smaller object or a larger printer", names[k], size(k), arrange::MARGIN),
        ),
        Refusal::Off(k) => Error::input(
            format!("{}.at", place(k)),
            format!("object `{}` ({}) at this place reaches off the bed ({bed}, less {} mm at the edges); expected a place on the bed", names[k], size(k), arrange::MARGIN),
        ),
        Refusal::Fixed(a, b) => Error::input(
            format!("{}.at", place(b)),
            format!("object `{}` at this place is too close to `{}`, printed before it: {keep}; expected places farther apart", names[b], names[a]),
        ),
        Refusal::Gantry(k, j) => {
            let g = printer.head.gantry.map_or(0.0, |g| g.height);
            Error::input(
                place(k),
                format!("object `{}` is {:.1} mm tall, more than the gantry's {g} mm over the nozzle (head.gantry.height), and so is `{}`: one of them can print last, and no place on the bed keeps the other out of the gantry's way; expected one of them on another plate", names[k], items[k].shadow.top, names[j]),
            )
        }
        Refusal::Full(k) => Error::input(
            place(k),
            format!("object `{}` ({}) finds no place on the bed ({bed}) clear of the {} objects before it: {keep}; expected fewer or smaller objects, or a larger printer", names[k], size(k), k),
        ),
    }
}

/// One recipe of the objects' parts in print order, their paths moved to
/// their places and named `OBJECT/PART`.
fn compose(
    spec: &PlateSpec,
    loaded: &[Loaded],
    names: &[String],
    order: &[(usize, DVec2)],
    printer: Printer,
    material: crate::machine::Material,
) -> Result<(Recipe, Vec<Toolpath>)> {
    let mut parts = Vec::new();
    let mut paths = Vec::new();
    let mut objects = Vec::with_capacity(order.len());
    let mut params = Params::new();
    let mut total = 0u64;
    for &(k, d) in order {
        let (o, name) = (&loaded[k], &names[k]);
        let mut ps = (*o.paths).clone();
        arrange::translate(&mut ps, d);
        for tp in &mut ps {
            tp.name = format!("{name}/{}", tp.name);
            total = total.saturating_add(tp.len() as u64);
        }
        let (first_path, first_part) = (paths.len(), parts.len());
        for part in &o.recipe.parts {
            let mut p = part.clone();
            p.name = format!("{name}/{}", p.name);
            parts.push(p);
        }
        paths.extend(ps);
        objects.push(Object {
            name: name.clone(),
            paths: first_path..paths.len(),
            parts: first_part..parts.len(),
            allow: o.recipe.allow.clone(),
        });
        object_params(&mut params, name, &o.recipe.params);
    }
    if total > DEFAULT_MAX_STRINGS {
        return Err(Error::input(
            key!(RawRecipe, plate),
            format!("the objects together have {total} strings, more than the limit of {DEFAULT_MAX_STRINGS} for a plate; expected fewer or smaller objects"),
        ));
    }
    crate::base::finding::validate_allow(&spec.allow, |i| format!("allow[{i}]"))?;
    let recipe = Recipe {
        name: spec.name.clone(),
        params,
        printer,
        material,
        skirt: None,
        parts,
        max_strings: DEFAULT_MAX_STRINGS,
        allow: spec.allow.clone(),
        groups: Vec::new(),
        objects,
    };
    Ok((recipe, paths))
}

/// Each param of object `name`'s recipe as `name/PARAM`, as it reads.
fn object_params(out: &mut Params, name: &str, params: &Params) {
    for (k, v) in params.iter() {
        let key = format!("{name}/{k}");
        out.insert(key.clone(), *v);
        if let Some(kind) = params.kind(k) {
            if !matches!(kind, Kind::List) {
                out.set_kind(&key, kind.clone());
            }
        }
    }
    for k in params.list_names() {
        if let Some(v) = params.list(k) {
            out.insert_list(&format!("{name}/{k}"), v.to_vec());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recipe::yaml::parse_yaml;

    #[test]
    fn a_plate_file_gives_its_entries_as_the_command_line_would() {
        let raw: RawRecipe = parse_yaml(
            "p3dp: 1\nname: pots\nplate:\n  - {recipe: pot.yaml, copies: 2, set: {shape: star, h: 40}}\n  - {recipe: pot.yaml, sweep: {height: \"40, 60\", r: [1, 2.5]}, at: [30, -40]}\n",
            "t",
        )
        .unwrap();
        let spec = PlateSpec::from_raw(&raw, Path::new("d/pots.yaml")).unwrap();
        assert_eq!(spec.dir, PathBuf::from("d"));
        let e = &spec.entries;
        assert_eq!(e[0].copies, 2);
        assert_eq!(
            e[0].sets,
            [("shape".into(), "star".into()), ("h".into(), "40".into())]
        );
        assert_eq!(
            e[1].sweeps[0],
            ("height".into(), vec!["40".into(), "60".into()])
        );
        assert_eq!(e[1].sweeps[1], ("r".into(), vec!["1".into(), "2.5".into()]));
        assert_eq!(e[1].at, Some([30.0, -40.0]));
        assert_eq!(variants(&e[1].sweeps).len(), 4);
    }

    #[test]
    fn a_plate_refuses_a_recipes_keys_and_bad_entries() {
        let bad = |yaml: &str| {
            let raw: RawRecipe = parse_yaml(yaml, "t").unwrap();
            PlateSpec::from_raw(&raw, Path::new("p.yaml")).unwrap_err()
        };
        let e = bad("p3dp: 1\nname: p\nparams: {a: 1}\nplate: [{recipe: a.yaml}]\n");
        assert_eq!(e.place.as_deref(), Some("params"), "{e}");
        let e = bad("p3dp: 1\nname: p\nplate: [{recipe: a.yaml, copies: 0}]\n");
        assert_eq!(e.place.as_deref(), Some("plate[0].copies"), "{e}");
        let e = bad("p3dp: 1\nname: p\nplate: [{recipe: a.yaml, sweep: {h: \"3..1\"}}]\n");
        assert_eq!(e.place.as_deref(), Some("plate[0].sweep.h"), "{e}");
        let e = bad("p3dp: 1\nname: p\nplate: []\n");
        assert_eq!(e.place.as_deref(), Some("plate"), "{e}");
    }
}
