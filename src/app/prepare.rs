//! Making a plan: a recipe loaded (with the command line's `--set`,
//! `--printer` and `--allow`), its parts made into strings, skirt first.

use std::path::Path;

use crate::analyse::check;
use crate::analyse::plan::Plan;
use crate::base::error::{Error, Result};
use crate::machine::Printer;
use crate::recipe::context::Context;

/// What the command line says about one build.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// `--set NAME=VALUE` overrides, in order.
    pub sets: Vec<(String, String)>,
    /// `--printer NAME|FILE` overrides the recipe's printer.
    pub printer: Option<String>,
    /// `--filament FILE [--filament-preset NAME]`: a slicer's filament
    /// preset overrides the recipe's material.
    pub filament: Option<crate::recipe::preset::Source>,
    /// `--allow CODE`: check codes silenced for this build.
    pub allow: Vec<String>,
    /// `--allow-read DIR`: folders the recipe may read in besides its project.
    pub allow_read: Vec<std::path::PathBuf>,
}

/// Loads, builds and checks a recipe (on the pool it runs in, if any).
pub fn plan(path: &Path, opts: &Options) -> Result<Plan> {
    let mut p = prepare(path, opts)?;
    crate::app::pipeline::check(&mut p, &opts.allow);
    Ok(p)
}

/// Loads and builds a recipe without checking it: no findings until the
/// checks have run ([`crate::app::pipeline::check`]).
pub fn prepare(path: &Path, opts: &Options) -> Result<Plan> {
    prepare_in(path, opts, &Context::default())
}

/// [`prepare`] in the loading context `cx` (the files read noted there,
/// its lent z-buffers and kept parts used).
pub fn prepare_in(path: &Path, opts: &Options, cx: &Context) -> Result<Plan> {
    let shown = path.display().to_string();
    let printer = command_line(opts, cx)?;
    let raw = crate::recipe::read_raw(path, cx)?;
    if raw.plate.is_some() {
        // a plate: whole recipes arranged on the bed, printed one after another
        let spec = crate::recipe::resolve::plate::PlateSpec::from_raw(&raw, path)?;
        return prepare_plate(&spec, &shown, opts, printer.as_ref(), cx);
    }
    let material = filament(opts, cx)?;
    let given = (printer.as_ref(), material.as_ref());
    let recipe = crate::recipe::from_raw_in(&raw, path, &opts.sets, given, cx)?;
    // each part with its own steps, then the steps of groups; the skirt first
    let paths = crate::generate::plate::made_in(&recipe, cx.parts.as_ref())
        .map_err(|e| e.in_file(&shown))?;
    Plan::new(shown, recipe, paths)
}

/// What [`prepare_in`] does before it makes any string: the command line
/// read, the recipe resolved (its params with `opts.sets`, every key and
/// value); a plate is made whole (its objects are recipes built and
/// arranged). A batch resolves every variant so before it builds any.
pub(crate) fn resolve_in(path: &Path, opts: &Options, cx: &Context) -> Result<()> {
    let printer = command_line(opts, cx)?;
    let raw = crate::recipe::read_raw(path, cx)?;
    if raw.plate.is_some() {
        let spec = crate::recipe::resolve::plate::PlateSpec::from_raw(&raw, path)?;
        let shown = path.display().to_string();
        return prepare_plate(&spec, &shown, opts, printer.as_ref(), cx).map(drop);
    }
    let material = filament(opts, cx)?;
    let given = (printer.as_ref(), material.as_ref());
    crate::recipe::from_raw_in(&raw, path, &opts.sets, given, cx).map(drop)
}

/// [`prepare_in`] of the plate `spec` the command line describes (`p3dp
/// plate`), reported as `shown`.
pub(crate) fn prepare_plate_in(
    spec: &crate::recipe::resolve::plate::PlateSpec,
    shown: &str,
    opts: &Options,
    cx: &Context,
) -> Result<Plan> {
    let printer = command_line(opts, cx)?;
    prepare_plate(spec, shown, opts, printer.as_ref(), cx)
}

/// What the command line gives every build: its `--allow` codes checked,
/// its `--allow-read` folders, and its `--printer` read.
fn command_line(opts: &Options, cx: &Context) -> Result<Option<Printer>> {
    // the command line's own mistakes name the option, not the recipe
    check::validate_allow(&opts.allow, |i| format!("--allow {}", opts.allow[i]))?;
    for dir in &opts.allow_read {
        cx.reads.allow(dir);
    }
    match &opts.printer {
        Some(spec) => {
            // a profile named on the command line may inherit from its own project
            cx.reads.name(Path::new(spec));
            crate::recipe::profile::resolve(spec, Path::new("."), &cx.reads)
                .map(Some)
                .map_err(|e| {
                    if e.file.is_none() && e.place.as_deref() == Some("printer") {
                        Error {
                            place: Some(format!("--printer {spec}")),
                            ..e
                        }
                    } else {
                        e
                    }
                })
        }
        None => Ok(None),
    }
}

/// The command line's `--filament` preset as the material.
fn filament(opts: &Options, cx: &Context) -> Result<Option<crate::machine::Material>> {
    let Some(src) = &opts.filament else {
        return Ok(None);
    };
    cx.reads.name(&src.file);
    crate::recipe::resolve::from_filament(src, &cx.reads)
        .map(Some)
        .map_err(|e| {
            if e.file.is_none() {
                e.under("--filament")
            } else {
                e
            }
        })
}

/// The plan of a plate (`shown` as reports name it): its objects loaded
/// with the command line's `--set` and `--printer`, arranged.
pub(crate) fn prepare_plate(
    spec: &crate::recipe::resolve::plate::PlateSpec,
    shown: &str,
    opts: &Options,
    printer: Option<&Printer>,
    cx: &Context,
) -> Result<Plan> {
    if opts.filament.is_some() {
        return Err(Error::input(
            "--filament",
            "a plate's objects keep their recipes' materials; expected --filament with a recipe, not a plate",
        ));
    }
    let (recipe, paths) = crate::recipe::resolve::plate::make(spec, &opts.sets, printer, cx)
        .map_err(|e| e.in_file(shown))?;
    Plan::new(shown.to_string(), recipe, paths)
}
