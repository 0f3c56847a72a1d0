//! A recipe resolved: printer, material and parts whose primitives and steps
//! have every number evaluated and every expression compiled. The YAML edge
//! ([`crate::recipe`]) makes it; the stages after it only read it.

use crate::error::{Error, Result};
use crate::expr::Params;
use crate::machine::{Material, Printer};
use crate::primitive::{CaHelix, Primitive};
use crate::step::Step;
use crate::threads::Threads;
use crate::toolpath::Toolpath;

/// The default limit on strings in one part (a recipe may change it).
pub const DEFAULT_MAX_STRINGS: u64 = 50_000_000;

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

/// Makes a part's strings: its primitive, then each step in order, on up to
/// `threads` threads.
pub fn make_part(recipe: &Recipe, k: usize, threads: Threads) -> Result<Toolpath> {
    let part = &recipe.parts[k];
    let mut tp = part.primitive.build(part.cross_section, part.speed);
    tp.name = part.name.clone();
    for (j, step) in part.steps.iter().enumerate() {
        step.apply(&mut tp, recipe.max_strings, threads)
            .map_err(|e| e.under(&format!("parts[{k}].steps[{j}].{}", step.key())))?;
    }
    Ok(tp)
}

/// The PNG of `--pattern`: the cell array of the recipe's one `ca_helix` part.
pub fn pattern_png(recipe: &Recipe) -> Result<Vec<u8>> {
    let models: Vec<&CaHelix> = recipe
        .parts
        .iter()
        .filter_map(|p| match &p.primitive {
            Primitive::CaHelix(h) => Some(h),
            _ => None,
        })
        .collect();
    match models.as_slice() {
        [h] => h
            .model
            .run()
            .to_png()
            .map_err(|e| e.under("--pattern")),
        _ => Err(Error::input(
            "--pattern",
            format!(
                "the recipe has {} `ca_helix` parts; --pattern writes the cell array of exactly one",
                models.len()
            ),
        )),
    }
}
