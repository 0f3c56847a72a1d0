//! Making a plan: a recipe loaded (with the command line's `--set`,
//! `--printer` and `--allow`), its parts made into strings, skirt first.

use std::path::Path;

use crate::analyse::check;
use crate::analyse::plan::Plan;
use crate::base::error::{Error, Result};
use crate::generate::model::Recipe;
use crate::machine::Printer;
use crate::recipe::context::Context;

/// What the command line says about one build.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// `--set NAME=VALUE` overrides, in order.
    pub sets: Vec<(String, String)>,
    /// `--printer NAME|FILE` overrides the recipe's printer.
    pub printer: Option<String>,
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
    // the command line's own mistakes name the option, not the recipe
    check::validate_allow(&opts.allow, |i| format!("--allow {}", opts.allow[i]))?;
    for dir in &opts.allow_read {
        cx.reads.allow(dir);
    }
    let printer = match &opts.printer {
        Some(spec) => Some({
            // a profile named on the command line may inherit from its own project
            cx.reads.name(Path::new(spec));

            Printer::resolve(spec, Path::new("."), &cx.reads).map_err(|e| {
                if e.file.is_none() && e.place.as_deref() == Some("printer") {
                    Error {
                        place: Some(format!("--printer {spec}")),
                        ..e
                    }
                } else {
                    e
                }
            })?
        }),
        None => None,
    };
    let recipe = Recipe::load_in(path, &opts.sets, printer.as_ref(), cx)?;
    // each part with its own steps, then the steps of groups
    let parts = crate::generate::assembly::make_parts_in(&recipe, cx.parts.as_ref())
        .map_err(|e| e.in_file(&shown))?;
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
    Plan::new(shown, recipe, paths)
}
