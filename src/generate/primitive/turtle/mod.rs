//! `turtle`: a 3D turtle that prints as it walks (Kanada's turtle.py, the
//! ExtruderTurtle library of Pezzuti Dyer and Buechley, TEI '22).
//!
//! A program of commands moves a turtle with a position and a frame
//! (heading, left, up: [`frame`]); with the pen down each move is an
//! extruding string, with the pen up a travel move after a retraction.
//! Settings (`extrude_rate`, `cross_section`, `speed`) apply to the strings
//! that follow; `dwell`, `pause`, temperatures, the fan and `extrude` in place
//! become [`Event`](crate::base::toolpath::Event)s between strings. Structure: `repeat` (with a counter),
//! `if`, procedures with parameters, and L-systems ([`lsystem`]).
//!
//! The program is compiled (into a [`program`], by the recipe's resolution)
//! and run ([`interp`], [`run`]) when the recipe is resolved, so every
//! problem, including one that only shows while running (a value that is
//! not finite, recursion without end, a program over the `max_strings`
//! limit), is an input error naming its key path.

pub(crate) mod frame;
pub(crate) mod interp;
pub(crate) mod lsystem;
pub(crate) mod program;
pub(crate) mod shapes;

pub(crate) use frame::Frame;

use crate::base::error::{Error, Result};
use crate::base::toolpath::Toolpath;

/// What a turtle needs from its part and recipe.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Env {
    /// The part's cross-section, mm² (until the program sets one).
    pub(crate) cross_section: f64,
    /// The part's speed, mm/s (until the program sets one).
    pub(crate) speed: f64,
    /// Filament cross-section area, mm² (turns `extrude_rate` into mm²).
    pub(crate) filament_area: f64,
    /// The recipe's `max_strings`: most strings plus events.
    pub(crate) max_strings: u64,
}

/// A turtle's program, already run: its strings and events.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Turtle {
    /// The strings and events the program made.
    pub(crate) path: Toolpath,
}

impl Turtle {
    /// How many strings it made.
    pub(crate) fn string_count(&self) -> u64 {
        self.path.len() as u64
    }

    /// Its strings (the part's c and v were applied when it ran).
    pub(crate) fn build(&self) -> Toolpath {
        self.path.clone()
    }

    /// Puts the key paths its settings name under `prefix`, as
    /// [`Error::under`] does with an error's place (the program's places
    /// are relative to `turtle` or to a path's commands).
    pub(crate) fn place_under(&mut self, prefix: &str) {
        for (_, e) in &mut self.path.events {
            if let crate::base::toolpath::Event::Set {
                place: Some(place), ..
            } = e
            {
                *place = crate::base::error::place_under(prefix, place).into();
            }
        }
    }
}

/// Runs a compiled program from `env` (the part's cross-section and speed,
/// the recipe's limits), `check` holding the `gcode` lines it makes to the
/// printer; errors name key paths relative to `turtle`.
pub(crate) fn run(prog: &interp::Program, env: &Env, check: interp::Check) -> Result<Turtle> {
    let limits = interp::Limits {
        max_strings: env.max_strings,
        max_steps: env.max_strings.saturating_mul(8).saturating_add(1_000_000),
    };
    // the interpreter keeps its own stack of tasks (blocks, calls, L-system
    // derivations) on the heap, so it runs here, on the caller's thread
    let cvs = (env.cross_section, env.speed, env.filament_area);
    let path = prog.run(cvs, limits, check)?;
    // a program that makes no move at all (every move behind an `if` that
    // is 0) makes no part: the part is left out, as one switched off
    if !path.strings.is_empty() && path.strings.iter().all(|s| s.travel) {
        return Err(Error::input(
            "program",
            "the program extrudes nothing; expected at least one move with the pen down",
        ));
    }
    Ok(Turtle { path })
}
