//! p3dp: procedural 3D printing. A YAML recipe describes the path of the
//! nozzle itself (Kanada's draw3dp); p3dp turns it into G-code and stats.
//!
//! Data flows one way, in layers that never import from a layer above
//! (`docs/ARCHITECTURE.md`; `tests/layers.rs` checks it):
//!
//! 1. plain types and utilities: [`error`], [`threads`], [`toolpath`],
//!    [`expr`], [`num`], [`finding`], [`format`], [`rng`], [`geom`];
//! 2. the machine model: [`machine`];
//! 3. generation: [`primitive`], [`step`], [`model`], [`assembly`], [`skirt`];
//! 4. analysis and output: [`planner`], [`gcode`], [`check`], [`stats`];
//! 5. the YAML edge: [`recipe`];
//! 6. orchestration: [`output`], [`plan`], [`preview`], [`build`],
//!    [`batch`], [`lock`], [`diagnostic`], [`watch`], [`cli`].

#![warn(missing_docs)]
// print!/println! panic on a closed pipe (`p3dp check r.yaml | head -1`):
// the library writes through `say!`/`tell!` (src/output.rs) instead
#![deny(clippy::print_stdout, clippy::print_stderr)]

pub mod analyse;
pub mod app;
pub mod base;
pub mod generate;
pub mod machine;
pub mod output;
pub mod recipe;

pub use base::error::{Error, Result};
