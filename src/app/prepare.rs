//! Making a plan: a recipe loaded (with the command line's `--set`,
//! `--printer` and `--allow`), its parts made into strings, skirt first.

use std::path::Path;

use crate::analyse::check;
use crate::analyse::plan::Plan;
use crate::base::error::{Error, Result};
use crate::base::threads::{Awake, Threads};
use crate::generate::model::Recipe;
use crate::machine::Printer;

/// What the command line says about one build.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// `--set NAME=VALUE` overrides, in order.
    pub sets: Vec<(String, String)>,
    /// `--printer NAME|FILE` overrides the recipe's printer.
    pub printer: Option<String>,
    /// `--allow CODE`: check codes silenced for this build.
    pub allow: Vec<String>,
    /// How many threads the build may use (default: one per core).
    pub threads: Threads,
}

/// Loads, builds and checks a recipe.
pub fn plan(path: &Path, opts: &Options) -> Result<Plan> {
    let mut p = prepare(path, opts)?;
    p.check(&opts.allow);
    Ok(p)
}

/// Loads and builds a recipe without checking it: no findings until
/// [`Plan::check`] (or [`Plan::checks`]) has run.
pub fn prepare(path: &Path, opts: &Options) -> Result<Plan> {
    let shown = path.display().to_string();
    // the command line's own mistakes name the option, not the recipe
    check::validate_allow(&opts.allow, |i| format!("--allow {}", opts.allow[i]))?;
    let printer = match &opts.printer {
        Some(spec) => Some(Printer::resolve(spec, Path::new(".")).map_err(|e| {
            if e.file.is_none() && e.place.as_deref() == Some("printer") {
                Error {
                    place: Some(format!("--printer {spec}")),
                    ..e
                }
            } else {
                e
            }
        })?),
        None => None,
    };
    let recipe = Recipe::load(path, &opts.sets, printer.as_ref())?;
    // each part with its own steps, then the steps of groups
    let parts = crate::generate::assembly::make_parts(&recipe, opts.threads)
        .map_err(|e| e.in_file(&shown))?;
    // the brims and skirt are made on this thread alone: a worker kept
    // awake meanwhile starts the checks at once
    let awake = Awake::keep(opts.threads).map(std::sync::Arc::new);
    let mut paths = Vec::with_capacity(parts.len() + 1);
    if let Some(s) = &recipe.skirt {
        let cv = (recipe.parts[0].cross_section, recipe.parts[0].speed);
        let spacing = recipe.printer.nozzle_diameter;
        match crate::generate::skirt::make(s, &parts, spacing, cv, recipe.max_strings) {
            Ok(Some(sk)) => paths.push(sk),
            Ok(None) => {}
            Err(e) => return Err(e.under("skirt").in_file(&shown)),
        }
    }
    paths.extend(parts);
    Ok(Plan {
        path: shown,
        recipe,
        paths,
        findings: Vec::new(),
        footprints: Vec::new(),
        threads: opts.threads,
        awake,
    })
}
