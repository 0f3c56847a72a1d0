//! p3dp: procedural 3D printing. A YAML recipe describes the path of the
//! nozzle itself (Kanada's draw3dp); p3dp turns it into G-code and stats.
//!
//! The crate's face is small: load a recipe and build its plan
//! ([`prepare`], [`plan`]: the parts made into strings and, for `plan`,
//! checked), run the stages inside one pool of threads ([`pipeline`]:
//! checks, G-code, stats, previews), read what came out ([`Plan`],
//! [`Stats`], [`Finding`]). Everything else is the crate's own.
//!
//! Inside, data flows one way, one folder per layer, and no layer imports
//! from one above it (`docs/ARCHITECTURE.md`; `tests/it/layers.rs` checks
//! it): `base` (plain types, geometry, expressions), `machine` (the
//! printer), `generate` (primitives and steps into strings), `analyse`
//! (checks, planner, stats), `output` (G-code, files, previews, meshes,
//! locks), `recipe` (the YAML edge) and `app` (the pipeline and the
//! commands).

#![warn(missing_docs)]
// print!/println! panic on a closed pipe (`p3dp check r.yaml | head -1`):
// the library writes through `say!`/`tell!` (output::file::stdout) instead
#![deny(clippy::print_stdout, clippy::print_stderr)]
#![warn(unreachable_pub)]

mod analyse;
mod app;
mod base;
mod generate;
mod machine;
mod output;
mod recipe;

pub use analyse::plan::Plan;
pub use analyse::stats::Stats;
pub use app::pipeline;
pub use app::prepare::{plan, prepare, prepare_in, Options};
pub use base::error::{Error, Kind, Result};
pub use base::finding::{Finding, Severity, CODES, SAFETY};
pub use base::input::Reads;
pub use base::toolpath::{Event, Toolpath};
pub use generate::assembly::make_parts;
pub use generate::model::{make_part, Recipe};
pub use machine::printer::{Bed, Flavor, Printer};
pub use recipe::context::Context;
pub use recipe::profile::built_in_names as printers;

/// Prusa's binary G-code read back: the blocks of a `.bgcode` file, each
/// checksum checked.
pub mod bgcode {
    pub use crate::output::host::bgcode::{decode, Block};
}

/// Slicer presets (PrusaSlicer-family `.ini`, OrcaSlicer/Bambu Studio
/// `.json`) read as p3dp printer profiles and materials.
pub mod presets {
    pub use crate::recipe::preset::map::{import, Imported};
    pub use crate::recipe::preset::{
        list, list_of, load, load_filament, Kind, Preset, Setting, Source,
    };
}

/// The fuzz targets' entry points (`fuzz/`; the `fuzzing` feature only).
#[cfg(feature = "fuzzing")]
#[doc(hidden)]
pub use app::fuzzing;

/// The command line, for the `p3dp` binary: parse [`cli::Cli`], [`cli::run`]
/// it, print each error with [`cli::print_error`].
pub mod cli {
    pub use crate::app::cli::{run, Cli};
    pub use crate::app::command::new::STARTERS;

    /// Prints an error to standard error as the command line shows it
    /// (rustc-style, in colour on a terminal).
    pub fn print_error(e: &crate::Error) {
        crate::tell!("{}", crate::app::cli::render_error(e));
    }

    /// Removes the temporary files of outputs not yet committed when the
    /// process is interrupted (SIGINT, SIGTERM, SIGHUP).
    pub fn remove_temp_files_on_signals() {
        crate::output::file::remove_temp_files_on_signals();
    }
}
