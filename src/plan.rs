//! The plan of one build: a recipe loaded, its parts made into strings (skirt
//! first) and checked, ready to write.

use std::path::Path;

use crate::check::{self, Finding};
use crate::error::{Error, Result};
use crate::machine::Printer;
use crate::model::Recipe;
use crate::threads::{Awake, Threads};
use crate::toolpath::Toolpath;

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

/// A recipe made into strings and checked, ready to write.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The recipe file as given.
    pub path: String,
    /// The resolved recipe.
    pub recipe: Recipe,
    /// Skirt, then parts, in print order.
    pub paths: Vec<Toolpath>,
    /// What the checks found.
    pub findings: Vec<Finding>,
    /// Each part's hold on the bed, as the first-layer check measured it.
    pub footprints: Vec<check::first_layer::Footprint>,
    /// How many threads making, checking and writing it may use.
    pub threads: Threads,
    /// A pool worker kept awake from the end of the steps until the checks
    /// start (see [`Awake`]).
    pub awake: Option<std::sync::Arc<Awake>>,
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
    let parts =
        crate::assembly::make_parts(&recipe, opts.threads).map_err(|e| e.in_file(&shown))?;
    // the brims and skirt are made on this thread alone: a worker kept
    // awake meanwhile starts the checks at once
    let awake = Awake::keep(opts.threads).map(std::sync::Arc::new);
    let mut paths = Vec::with_capacity(parts.len() + 1);
    if let Some(s) = &recipe.skirt {
        let cv = (recipe.parts[0].cross_section, recipe.parts[0].speed);
        let spacing = recipe.printer.nozzle_diameter;
        match crate::skirt::make(s, &parts, spacing, cv, recipe.max_strings) {
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

/// What the checks of a plan found: its findings (those `allow`ed already
/// marked) and the parts' footprints.
pub type Checked = (Vec<Finding>, Vec<check::first_layer::Footprint>);

impl Plan {
    /// Runs the checks on `threads` (any budget gives the same answer),
    /// `allow` (the command line's `--allow`) silencing codes beside the
    /// recipe's own; the plan is not changed: see [`Plan::check`].
    pub fn checks(&self, allow: &[String], threads: crate::threads::Threads) -> Checked {
        let refs: Vec<&Toolpath> = self.paths.iter().collect();
        let (mut findings, footprints) =
            check::run(&self.recipe, &refs, &self.allowed(allow), threads);
        self.silence(&mut findings, allow);
        (findings, footprints)
    }

    /// The codes silenced: the recipe's `allow`, then the command line's.
    pub fn allowed(&self, allow: &[String]) -> Vec<String> {
        self.recipe.allow.iter().chain(allow).cloned().collect()
    }

    /// Marks the findings of the codes the recipe and `allow` silence.
    pub fn silence(&self, findings: &mut Vec<Finding>, allow: &[String]) {
        check::apply_allow(findings, &self.recipe.allow);
        check::apply_allow(findings, allow);
    }

    /// Runs the checks on the plan's own budget and keeps what they found.
    pub fn check(&mut self, allow: &[String]) {
        self.wake();
        (self.findings, self.footprints) = self.checks(allow, self.threads);
    }

    /// Lets the worker kept awake go to the work now posted.
    pub fn wake(&self) {
        if let Some(a) = &self.awake {
            a.release();
        }
    }

    /// Highest point of any part, recipe coordinates.
    pub fn top_z(&self) -> f64 {
        self.paths
            .iter()
            .flat_map(|t| t.points.iter().map(|p| p.z))
            .fold(0.0, f64::max)
    }

    /// The findings that fail the build: errors, and warnings when `strict`.
    pub fn failing(&self, strict: bool) -> Vec<&Finding> {
        check::failing(&self.findings, strict)
    }
}
