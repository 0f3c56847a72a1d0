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
    /// Loops on the bed round its first contact, printed first.
    pub brim: Option<Brim>,
}

/// A part's brim: `loops` closed circles on the bed round the part's first
/// contact, from the outside in, then the part (a remedy for a part that
/// stands on a small contact, as Kanada's sphere and globe on their poles).
#[derive(Clone, Debug, PartialEq)]
pub struct Brim {
    /// Number of loops.
    pub loops: u32,
    /// Width of a loop and the step between loops, mm.
    pub line_width: f64,
    /// Height of the loops (their nozzle height over the bed), mm.
    pub layer_height: f64,
    /// Speed, mm/s.
    pub speed: f64,
}

impl Brim {
    /// Longest chord of a brim loop, mm.
    const CHORD: f64 = 0.5;

    /// The brim round `tp`'s first contact, then `tp`: the contact is the
    /// extruding strings within one brim layer of the part's lowest; the
    /// loops are circles about the middle of their bounding rectangle, the
    /// innermost 0.9 × line_width outside the farthest contact point (its
    /// bead overlaps the part's), each next one line_width further out,
    /// printed outermost first so the head ends inside, next to the part.
    pub fn around(&self, tp: &Toolpath) -> Toolpath {
        if tp.is_empty() || self.loops == 0 {
            return tp.clone();
        }
        let drawn = || {
            (0..tp.len())
                .filter(|&k| !tp.strings[k].travel)
                .flat_map(|k| {
                    let (a, b) = tp.ends(k);
                    [a, b]
                })
        };
        let z0 = drawn().map(|p| p.z).fold(f64::INFINITY, f64::min);
        let (mut lo, mut hi) = (
            glam::DVec2::splat(f64::INFINITY),
            glam::DVec2::splat(f64::NEG_INFINITY),
        );
        for p in drawn().filter(|p| p.z <= z0 + self.layer_height) {
            lo = lo.min(p.truncate());
            hi = hi.max(p.truncate());
        }
        if !lo.is_finite() {
            let p = tp.points[0].truncate();
            (lo, hi) = (p, p);
        }
        let centre = (lo + hi) * 0.5;
        let reach = drawn()
            .filter(|p| p.z <= z0 + self.layer_height)
            .map(|p| p.truncate().distance(centre))
            .fold(0.0, f64::max);
        let (w, h) = (self.line_width, self.layer_height);
        let c = w * h;
        let r_in = reach + 0.9 * w;
        let on_circle = |r: f64, t: f64| {
            glam::DVec3::new(centre.x + r * libm::cos(t), centre.y + r * libm::sin(t), h)
        };
        let r_out = r_in + (self.loops - 1) as f64 * w;
        let mut out = Toolpath::new(on_circle(r_out, 0.0));
        out.name = tp.name.clone();
        for k in (0..self.loops).rev() {
            let r = r_in + k as f64 * w;
            let n = (libm::ceil(std::f64::consts::TAU * r / Self::CHORD) as usize).max(24);
            if k + 1 < self.loops {
                out.travel(on_circle(r, 0.0), self.speed);
            }
            for i in 1..=n {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                out.draw(on_circle(r, if i == n { 0.0 } else { t }), c, self.speed);
            }
        }
        out.append(tp, self.speed);
        out
    }
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

/// Makes a part's strings (without its brim, which
/// [`crate::assembly::make_parts`] adds last): its primitives, then each of its own steps in
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

#[cfg(test)]
mod brim_tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn a_brim_circles_the_first_contact_outside_in_then_prints_the_part() {
        let mut tp = Toolpath::new(DVec3::new(0.0, 0.0, 0.2));
        tp.name = "pole".into();
        tp.draw(DVec3::new(1.0, 0.0, 0.2), 0.1, 30.0);
        tp.draw(DVec3::new(1.0, 0.0, 5.0), 0.1, 30.0);
        let b = Brim {
            loops: 3,
            line_width: 0.5,
            layer_height: 0.2,
            speed: 20.0,
        };
        let out = b.around(&tp);
        assert_eq!(out.name, "pole");
        // the contact: the first string (within 0.2 of the lowest), centre
        // (0.5, 0), reach 0.5; loops at 0.5 + 0.45 + k·0.5, outermost first
        let centre = glam::DVec2::new(0.5, 0.0);
        let r_of = |p: DVec3| p.truncate().distance(centre);
        assert!((r_of(out.points[0]) - (0.95 + 1.0)).abs() < 1e-12);
        let drawn: Vec<usize> = (0..out.len()).filter(|&k| !out.strings[k].travel).collect();
        let last_brim = drawn[drawn.len() - 3]; // before the part's two strings
        assert!((r_of(out.ends(last_brim).1) - 0.95).abs() < 1e-12);
        for &k in &drawn[..drawn.len() - 2] {
            let (a, c) = (out.ends(k), out.strings[k].c);
            assert!((a.0.z - 0.2).abs() < 1e-12 && (c - 0.1).abs() < 1e-12);
        }
        // the part follows whole
        assert_eq!(out.points[out.points.len() - 1], DVec3::new(1.0, 0.0, 5.0));
        assert!(out.volume() > tp.volume() + 0.1 * std::f64::consts::TAU * 3.0 * 0.95);
    }
}
