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
    /// The primitive (the first, when the part has several).
    pub primitive: Primitive,
    /// The steps.
    pub steps: Vec<Step>,
    /// The primitives after the first, in order (see [`crate::assembly`]).
    pub more: Vec<Piece>,
    /// Where the part is written, through templates and loops
    /// (`parts[1].parts[0] (template ring, k = 3)`), for error places.
    pub place: String,
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
    /// Steps of groups of parts, in the order they run (see [`crate::assembly`]).
    pub groups: Vec<Group>,
}

/// Default cross-section when a recipe gives none: Kanada's 0.196 mm² (Fig. 9).
pub const DEFAULT_CROSS_SECTION: f64 = 0.196;
/// Default speed when a recipe gives none: Kanada's 40 mm/s (Fig. 9).
pub const DEFAULT_SPEED: f64 = 40.0;

/// A primitive after the first of a part, with its cross-section and speed.
#[derive(Clone, Debug)]
pub struct Piece {
    /// The primitive.
    pub primitive: Primitive,
    /// Cross-section of its strings where it sets none, mm².
    pub cross_section: f64,
    /// Speed of its strings where it sets none, mm/s.
    pub speed: f64,
}

/// The steps of a group, run on parts `first..end` of the recipe as one set.
#[derive(Clone, Debug)]
pub struct Group {
    /// First part of the group.
    pub first: usize,
    /// One past its last part.
    pub end: usize,
    /// The steps, in order.
    pub steps: Vec<Step>,
    /// Where the group is written (through templates and loops), for errors.
    pub place: String,
}

impl Part {
    /// The part's primitives in order: `primitive`, then `more`.
    pub fn primitives(&self) -> impl Iterator<Item = &Primitive> {
        std::iter::once(&self.primitive).chain(self.more.iter().map(|p| &p.primitive))
    }

    /// How many strings its primitives make, counting a joining travel
    /// between each two.
    pub fn string_count(&self) -> u64 {
        self.primitives()
            .map(Primitive::string_count)
            .fold(self.more.len() as u64, u64::saturating_add)
    }

    /// Builds the primitives in order, joined by travel strings where one
    /// ends away from the next one's start.
    pub fn build_primitives(&self) -> Toolpath {
        let mut tp = self.primitive.build(self.cross_section, self.speed);
        for p in &self.more {
            let next = p.primitive.build(p.cross_section, p.speed);
            tp.append(&next, p.speed);
        }
        tp
    }
}

/// Makes a part's strings: its primitives, then each of its own steps in
/// order (a group's steps are [`crate::assembly::make_parts`]'s), on up to
/// `threads` threads.
pub fn make_part(recipe: &Recipe, k: usize, threads: Threads) -> Result<Toolpath> {
    make_part_within(recipe, k, recipe.max_strings, threads)
}

/// Makes a part as [`make_part`] does, its steps refused past `budget`
/// strings (what the recipe's limits leave after the parts before it).
pub fn make_part_within(
    recipe: &Recipe,
    k: usize,
    budget: u64,
    threads: Threads,
) -> Result<Toolpath> {
    let part = &recipe.parts[k];
    let mut tp = part.build_primitives();
    tp.name = part.name.clone();
    for (j, step) in part.steps.iter().enumerate() {
        step.apply(&mut tp, budget, threads)
            .map_err(|e| e.under(&format!("{}.steps[{j}].{}", part.place, step.key())))?;
    }
    Ok(tp)
}

/// The PNG of `--pattern`: the cell array of the recipe's one `ca_helix` part.
pub fn pattern_png(recipe: &Recipe) -> Result<Vec<u8>> {
    let models: Vec<&CaHelix> = recipe
        .parts
        .iter()
        .flat_map(|p| p.primitives())
        .filter_map(|p| match p {
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
