//! The plan of one build: a recipe resolved, its parts made into strings
//! (skirt first) and checked, ready to write.

use crate::analyse::check::{self, Finding};
use crate::analyse::frame::Frame;
use crate::base::error::{Error, Result};
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;

/// A recipe made into strings and checked, ready to write.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The recipe file as given.
    pub path: String,
    /// The resolved recipe.
    pub(crate) recipe: Recipe,
    /// Skirt, then parts, in print order.
    pub(crate) paths: Vec<Toolpath>,
    /// What the checks found.
    pub findings: Vec<Finding>,
    /// Each part's hold on the bed, as the first-layer check measured it.
    pub(crate) footprints: Vec<check::first_layer::Footprint>,
    /// The start and end G-code, expanded and checked: what the writer writes.
    pub(crate) frame: Frame,
    /// Why the start or end G-code is unsafe or cannot be expanded, if it
    /// is: raised by [`Plan::frame_ok`] when the G-code is written or the
    /// checks pass, so that the recipe's own findings come first (a
    /// material hotter than the printer allows is its check's finding
    /// before it is the start G-code's `M104`).
    pub(crate) frame_error: Option<crate::base::error::Error>,
    /// The heights and the first layer of the strings, measured once.
    pub(crate) extent: crate::analyse::frame::Extent,
}

impl Plan {
    /// A plan of `paths` (skirt first) of `recipe`, read from `path`, its
    /// checks not yet run; the profile's start and end G-code expanded and
    /// checked now (see `analyse::frame`): an error if unsafe,
    /// kept in `frame_error` (see [`Plan::frame_ok`]).
    pub(crate) fn new(path: String, recipe: Recipe, paths: Vec<Toolpath>) -> Result<Plan> {
        one_value_a_line(&paths).map_err(|e| e.in_file(&path))?;
        let extent = crate::analyse::frame::extent(&recipe, &paths);
        let (frame, frame_error) = match crate::analyse::frame::frame(&recipe, &extent) {
            Ok(f) => (f, None),
            Err(e) => (Frame::default(), Some(e)),
        };
        Ok(Plan {
            path,
            recipe,
            paths,
            findings: Vec::new(),
            footprints: Vec::new(),
            frame,
            frame_error,
            extent,
        })
    }

    /// The start and end G-code's error, if any: nothing may be written
    /// from a plan whose frame failed.
    pub(crate) fn frame_ok(&self) -> Result<()> {
        match &self.frame_error {
            Some(e) => Err(e.clone()),
            None => Ok(()),
        }
    }

    /// The codes silenced: the recipe's `allow`, then the command line's.
    pub(crate) fn allowed(&self, allow: &[String]) -> Vec<String> {
        self.recipe.allow.iter().chain(allow).cloned().collect()
    }

    /// Marks the findings of the codes the recipe and `allow` silence (and,
    /// on a plate, the codes each object's recipe silences in its own parts).
    pub(crate) fn silence(&self, findings: &mut Vec<Finding>, allow: &[String]) {
        check::apply_allow(findings, &self.recipe.allow);
        check::apply_allow(findings, allow);
        for o in self.recipe.objects.iter().filter(|o| !o.allow.is_empty()) {
            let mine = |f: &Finding| {
                f.part
                    .as_deref()
                    .is_some_and(|n| self.paths[o.paths.clone()].iter().any(|t| t.name == n))
            };
            findings.retain(|f| !(o.allow.iter().any(|a| a == f.code) && mine(f)));
        }
    }

    /// The objects of the print, each a name and its paths `first..end` in
    /// print order: a plate's objects, or each path of a recipe on its own
    /// (the hosts' object labels, a package's object list).
    pub(crate) fn objects(&self) -> Vec<(String, std::ops::Range<usize>)> {
        if self.recipe.objects.is_empty() {
            return (0..self.paths.len())
                .map(|k| (self.paths[k].name.clone(), k..k + 1))
                .collect();
        }
        self.recipe
            .objects
            .iter()
            .map(|o| (o.name.clone(), o.paths.clone()))
            .collect()
    }

    /// The findings that fail the build: errors, and warnings when `strict`.
    pub fn failing(&self, strict: bool) -> Vec<&Finding> {
        check::failing(&self.findings, strict)
    }
}

/// Refuses a line test whose line `k` (a `set` with `band: k`) is given two
/// values: the report's bands and `calibrate apply --band k` name one value
/// a line. The same value again (a line drawn in two parts) is the same band.
fn one_value_a_line(paths: &[Toolpath]) -> Result<()> {
    use crate::base::toolpath::Event;
    let mut seen: std::collections::HashMap<u32, (f64, &str)> = Default::default();
    for tp in paths {
        for (_, e) in &tp.events {
            let (Event::Set { band: Some(b), .. } | Event::Band { band: b, .. }) = e else {
                continue;
            };
            if b.z.is_some() {
                continue; // a height band
            }
            let (v, part) = *seen.entry(b.index).or_insert((b.value, &tp.name));
            if v.to_bits() != b.value.to_bits() {
                return Err(Error::input(
                    "set.band",
                    format!(
                        "line {} of the line test is given {} (part `{part}`) and {} (part `{}`); expected each line its own `band` (a different k for each value)",
                        b.index, v, b.value, tp.name
                    ),
                ));
            }
        }
    }
    Ok(())
}
