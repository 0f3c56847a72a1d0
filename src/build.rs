//! The pipeline: recipe → parts of strings → steps → checks → G-code and stats.

use std::io::{self, Write};
use std::path::Path;

use sha2::{Digest, Sha256};

use crate::check::{self, Finding};
use crate::error::{Error, Result};
use crate::gcode::{Emitter, MoveStats};
use crate::printer::Printer;
use crate::recipe::Recipe;
use crate::stats::{PartStats, Stats};
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
}

/// Makes a part's strings: its primitive, then each step in order.
pub fn make_part(recipe: &Recipe, k: usize) -> Result<Toolpath> {
    make_part_within(recipe, k, recipe.max_strings)
}

/// Makes a part as [`make_part`] does, its steps refused past `budget`
/// strings (what the recipe's limit leaves after the parts before it).
fn make_part_within(recipe: &Recipe, k: usize, budget: u64) -> Result<Toolpath> {
    let part = &recipe.parts[k];
    let mut tp = part.primitive.build(part.cross_section, part.speed);
    tp.name = part.name.clone();
    for (j, step) in part.steps.iter().enumerate() {
        step.apply(&mut tp, budget)
            .map_err(|m| Error::input(format!("parts[{k}].steps[{j}].{}", step.key()), m))?;
    }
    Ok(tp)
}

/// Loads, builds and checks a recipe.
pub fn plan(path: &Path, opts: &Options) -> Result<Plan> {
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
    let mut parts: Vec<Toolpath> = Vec::with_capacity(recipe.parts.len());
    let mut used = 0u64;
    for k in 0..recipe.parts.len() {
        // max_strings bounds the whole recipe: each part's steps get what is left
        let budget = recipe.max_strings.saturating_sub(used);
        let tp = make_part_within(&recipe, k, budget).map_err(|e| e.in_file(&shown))?;
        used = used.saturating_add(tp.len() as u64);
        parts.push(tp);
    }
    let mut paths = Vec::with_capacity(parts.len() + 1);
    if let Some(s) = &recipe.skirt {
        let cv = (recipe.parts[0].cross_section, recipe.parts[0].speed);
        let spacing = recipe.printer.nozzle_diameter;
        match crate::skirt::make(s, &parts, spacing, cv, recipe.max_strings) {
            Ok(Some(sk)) => paths.push(sk),
            Ok(None) => {}
            Err(m) => return Err(Error::input("skirt", m).in_file(&shown)),
        }
    }
    paths.extend(parts);
    let refs: Vec<&Toolpath> = paths.iter().collect();
    let allowed: Vec<String> = recipe.allow.iter().chain(&opts.allow).cloned().collect();
    let (mut findings, footprints) = check::run_allowing(&recipe, &refs, &allowed);
    check::apply_allow(&mut findings, &recipe.allow);
    check::apply_allow(&mut findings, &opts.allow);
    Ok(Plan {
        path: shown,
        recipe,
        paths,
        findings,
        footprints,
    })
}

impl Plan {
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

    /// Writes the G-code to `out`.
    pub fn write_gcode<W: Write>(&self, out: W) -> Result<(W, MoveStats)> {
        let io = |e: io::Error| Error::io(&self.path, format!("cannot write the G-code: {e}"));
        let top = self.top_z();
        let mut em = Emitter::new(out, &self.recipe);
        em.thumbnails = crate::preview::thumbnail::blocks(self)?;
        let fan_events = |t: &Toolpath| {
            t.events
                .iter()
                .any(|(_, e)| matches!(e, crate::toolpath::Event::Fan { .. }))
        };
        if self.paths.iter().any(fan_events) {
            em.manual_fan();
        }
        em.start(&self.recipe, top)?;
        for tp in &self.paths {
            em.part(tp).map_err(io)?;
        }
        em.finish(&self.recipe, top)
    }

    /// Writes the G-code to `out`, hashing it, and returns the stats.
    pub fn render<W: Write>(&self, out: W) -> Result<Stats> {
        let (hw, moves) = self.write_gcode(HashWriter::new(out))?;
        let (digest, bytes) = hw.finish();
        let parts = self
            .paths
            .iter()
            .zip(&moves.estimate.parts)
            .map(|(t, pt)| PartStats {
                name: t.name.clone(),
                strings: t.len(),
                print_time_s: pt.times.planned,
                time_lost_s: pt.times.lost(),
            })
            .collect();
        let mut stats = Stats::new(
            &self.path,
            &self.recipe,
            &moves,
            parts,
            digest,
            bytes,
            self.findings.clone(),
        );
        stats.first_layer = self.footprints.clone();
        Ok(stats)
    }
}

/// A writer that hashes and counts what passes through it.
pub struct HashWriter<W: Write> {
    inner: io::BufWriter<W>,
    hasher: Sha256,
    bytes: u64,
}

impl<W: Write> HashWriter<W> {
    /// Wraps `inner` (buffered).
    pub fn new(inner: W) -> HashWriter<W> {
        HashWriter {
            inner: io::BufWriter::with_capacity(1 << 16, inner),
            hasher: Sha256::new(),
            bytes: 0,
        }
    }

    /// The SHA-256 in hex and the byte count.
    pub fn finish(self) -> (String, u64) {
        let (hex, bytes, _) = self.finish_into();
        (hex, bytes)
    }

    /// The SHA-256 in hex, the byte count and the inner writer.
    pub fn finish_into(self) -> (String, u64, W) {
        let d = self.hasher.finalize();
        let hex: String = d.iter().map(|b| format!("{b:02x}")).collect();
        let inner = self
            .inner
            .into_inner()
            .unwrap_or_else(|e| panic!("flushed before: {e}"));
        (hex, self.bytes, inner)
    }
}

impl<W: Write> Write for HashWriter<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

// moved to `crate::output` (special files, symlinks, signals); re-exported
// here for the callers that import them from `build`
pub use crate::output::{write_atomic, AtomicFile};
