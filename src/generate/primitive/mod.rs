//! Primitives: the shapes a part starts from (Kanada's Fig. 3 "parts assembly").
//!
//! Each primitive knows how many strings it will make before it makes them,
//! so an impossible recipe is refused before it allocates. The primitives
//! as written and their resolution into these types are the recipe's
//! (`crate::recipe::schema`, `crate::recipe::resolve`).

mod arc;
/// Kanada's cellular-automaton model of self-organised printing: `ca_helix`.
pub(crate) mod ca;
mod circle;
mod cylinder;
mod helix;
pub(crate) mod label;
/// Primitives over SVG sources: `path: {svg: …}` and the `outline:` of helix, spiral, cylinder.
pub(crate) mod outline;
mod path;
/// The constant-flow helix of self-organised patterns: `pattern_helix`.
pub(crate) mod pattern;
/// Feature-based solids printed from a z-buffer of loops: `solid`.
pub(crate) mod solid;
mod spiral;
/// A 3D turtle that prints as it walks (turtle.py, ExtruderTurtle): `turtle`.
pub(crate) mod turtle;

pub(crate) use arc::Arc;
pub(crate) use ca::CaHelix;
pub(crate) use circle::Circle;
pub(crate) use cylinder::Cylinder;
pub(crate) use helix::Helix;
pub(crate) use label::Label;
pub(crate) use path::PathCmd;
pub(crate) use pattern::PatternHelix;
pub(crate) use solid::Solid;
pub(crate) use spiral::{Direction, Spiral};
pub(crate) use turtle::Turtle;

use crate::base::toolpath::Toolpath;

/// A primitive with every value resolved to a number.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Primitive {
    /// The papers' low-level API: move, draw, cross_section, speed.
    Path(Vec<PathCmd>),
    /// One closed circle.
    Circle(Circle),
    /// Part of a circle, optionally rising.
    Arc(Arc),
    /// A flat spiral.
    Spiral(Spiral),
    /// A single-wall helix with no seam.
    Helix(Helix),
    /// A filled cylinder of stacked spirals.
    Cylinder(Cylinder),
    /// Boxes and cylinders combined, printed layer by layer from exact loops.
    Solid(Solid),
    /// Kanada's self-organised pattern print: a constant-flow helix.
    PatternHelix(PatternHelix),
    /// Kanada's cellular-automaton model of those patterns, as G-code.
    CaHelix(CaHelix),
    /// A 3D turtle program, run when the recipe was resolved.
    Turtle(Box<Turtle>),
    /// Digits and short words as strokes (band labels).
    Label(Label),
}

impl Primitive {
    /// How many strings `build` will make.
    pub(crate) fn string_count(&self) -> u64 {
        match self {
            Primitive::Path(cmds) => path::string_count(cmds),
            Primitive::Circle(p) => p.string_count(),
            Primitive::Arc(p) => p.string_count(),
            Primitive::Spiral(p) => p.string_count(),
            Primitive::Helix(p) => p.string_count(),
            Primitive::Cylinder(p) => p.string_count(),
            Primitive::Solid(p) => p.string_count(),
            Primitive::PatternHelix(p) => p.string_count(),
            Primitive::CaHelix(p) => p.string_count(),
            Primitive::Turtle(p) => p.string_count(),
            Primitive::Label(p) => p.string_count(),
        }
    }

    /// Makes the strings, with cross-section `c` and speed `v` where the
    /// primitive sets none of its own.
    /// A primitive that splits its points (a helix) makes the same strings
    /// whatever the threads.
    pub(crate) fn build(&self, c: f64, v: f64) -> Toolpath {
        match self {
            Primitive::Path(cmds) => path::build(cmds, c, v),
            Primitive::Circle(p) => p.build(c, v),
            Primitive::Arc(p) => p.build(c, v),
            Primitive::Spiral(p) => p.build(c, v),
            Primitive::Helix(p) => p.build(c, v),
            Primitive::Cylinder(p) => p.build(c, v),
            Primitive::Solid(p) => p.build(c, v),
            Primitive::PatternHelix(p) => p.build(c, v),
            Primitive::CaHelix(p) => p.build(c, v),
            // the part's c and v were the turtle's starting values
            Primitive::Turtle(p) => p.build(),
            Primitive::Label(p) => p.build(c, v),
        }
    }
}

/// Below this many points a primitive is made on one thread (as steps:
/// a thread costs ~50 µs).
pub(crate) const PAR_MIN: usize = 8_192;

/// The point at angle `k / segments` of a turn on a circle of radius `r`.
///
/// The angle is reduced to one turn first (`k mod segments`) so every turn of
/// a helix or spiral uses exactly the same sines and cosines.
#[inline]
pub(crate) fn on_circle(r: f64, k: u64, segments: u32) -> (f64, f64) {
    let a = std::f64::consts::TAU * (k % segments as u64) as f64 / segments as f64;
    (r * libm::cos(a), r * libm::sin(a))
}

/// [`on_circle`] for points 0..=`last`, its sines and cosines computed once
/// per angle of a turn (a 2M-string helix of 1000 segments needs 1000, not
/// 2M): point k is entry `k mod segments`, the very values `on_circle` gives.
pub(crate) struct TurnTable {
    points: Vec<(f64, f64)>,
}

impl TurnTable {
    /// The table for radius `r` and `segments` a turn, up to point `last`.
    pub(crate) fn new(r: f64, segments: u32, last: u64) -> TurnTable {
        let len = (segments as u64).min(last.saturating_add(1));
        TurnTable {
            points: (0..len).map(|k| on_circle(r, k, segments)).collect(),
        }
    }

    /// `on_circle(r, k, segments)`.
    #[inline]
    pub(crate) fn at(&self, k: u64) -> (f64, f64) {
        self.points[(k % self.points.len() as u64) as usize]
    }

    /// The points `at(k)`, `at(k + 1)`, … in turn, without a division each.
    pub(crate) fn walk_from(&self, k: u64) -> TurnWalk<'_> {
        TurnWalk {
            points: &self.points,
            j: (k % self.points.len() as u64) as usize,
        }
    }
}

/// [`TurnTable::walk`]: the table's entries in order, round and round.
pub(crate) struct TurnWalk<'a> {
    points: &'a [(f64, f64)],
    j: usize,
}

impl TurnWalk<'_> {
    /// The next point: `at(k)` for the k-th call (from 0).
    #[inline]
    pub(crate) fn next_point(&mut self) -> (f64, f64) {
        let p = self.points[self.j];
        self.j += 1;
        if self.j == self.points.len() {
            self.j = 0;
        }
        p
    }
}
