//! p3dp: procedural 3D printing. A YAML recipe describes the path of the
//! nozzle itself (Kanada's draw3dp); p3dp turns it into G-code and stats.
//!
//! The crate's face is small: load a recipe and build its plan
//! ([`prepare`], [`plan`]: the parts made into strings and, for `plan`,
//! checked), run the stages inside one pool of threads ([`pipeline`]:
//! checks, G-code, stats, previews), read what came out ([`Plan`]'s
//! findings, [`Stats`], [`Finding`]). Everything else is the crate's own
//! (the integration tests, benches and fuzz targets reach further through
//! the hidden `testing` module, feature `testing`).
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
// `pub` means reachable from the face or from `testing`: the lint holds the
// crate to it where both exist (the tests' builds, `cargo clippy
// --all-targets`). Without `testing` the items only it exports are
// unreachable, so the compiler's dead-code check sees what the tests alone use.
#![cfg_attr(feature = "testing", warn(unreachable_pub))]

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
pub use app::prepare::{plan, prepare, Options};
pub use base::error::{Error, Kind, Result};
pub use base::finding::{Finding, Severity, CODES, SAFETY};
pub use recipe::preset::Source;

/// The command line, for the `p3dp` binary: parse [`cli::Cli`], [`cli::run`]
/// it, print each error with [`cli::print_error`].
pub mod cli {
    pub use crate::app::cli::{run, Cli};

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

/// The crate's insides the integration tests (`tests/it/`), the benches and
/// the fuzz targets reach: feature `testing` only, not part of the face.
#[cfg(feature = "testing")]
#[doc(hidden)]
pub mod testing {
    pub use crate::analyse::check::first_layer::Footprint;
    pub use crate::app::command::new::STARTERS;
    pub use crate::app::fuzzing as fuzz;
    pub use crate::app::prepare::prepare_in;
    pub use crate::base::input::Reads;
    pub use crate::base::toolpath::{Event, Toolpath};
    pub use crate::generate::assembly::make_parts;
    pub use crate::generate::model::{make_part, Recipe};
    pub use crate::machine::printer::{Bed, Flavor, Printer};
    pub use crate::recipe::context::Context;
    pub use crate::recipe::profile::built_in_names as printers;
    pub use crate::recipe::{load as load_recipe, load_in as load_recipe_in};
    pub use crate::Plan;

    /// Prusa's binary G-code read back: the blocks of a `.bgcode` file, each
    /// checksum checked.
    pub mod bgcode {
        pub use crate::output::host::bgcode::{decode, Block};
    }

    /// Printer profiles: built in, from a file, from a slicer's preset.
    pub mod profile {
        pub use crate::recipe::profile::{built_in, from_file, from_preset};
    }

    /// Slicer presets (PrusaSlicer-family `.ini`, OrcaSlicer/Bambu Studio
    /// `.json`) read as p3dp printer profiles and materials.
    pub mod presets {
        pub use crate::recipe::preset::map::{import, Imported};
        pub use crate::recipe::preset::{
            list, list_of, load, load_filament, Kind, Preset, Setting, Source,
        };
    }

    /// A plan's insides: its recipe and its strings, to read and to change.
    pub trait Insides {
        /// The resolved recipe.
        fn recipe(&self) -> &Recipe;
        /// The resolved recipe, to change before writing.
        fn recipe_mut(&mut self) -> &mut Recipe;
        /// Skirt, then parts, in print order.
        fn paths(&self) -> &[Toolpath];
        /// Puts `paths` (skirt, then parts) in place of the strings, and
        /// measures again what the plan derives from them (the extent, the
        /// start and end G-code); the checks' findings are cleared.
        fn set_paths(&mut self, paths: Vec<Toolpath>) -> crate::Result<()>;
        /// Where each part holds on to the bed, as the checks measured it.
        fn footprints(&self) -> &[Footprint];
        /// The start G-code as it is written, expanded.
        fn start_gcode(&self) -> String;
        /// The end G-code as it is written, expanded.
        fn end_gcode(&self) -> String;
    }

    impl Insides for Plan {
        fn recipe(&self) -> &Recipe {
            &self.recipe
        }
        fn recipe_mut(&mut self) -> &mut Recipe {
            &mut self.recipe
        }
        fn paths(&self) -> &[Toolpath] {
            &self.paths
        }
        fn set_paths(&mut self, paths: Vec<Toolpath>) -> crate::Result<()> {
            *self = Plan::new(self.path.clone(), self.recipe.clone(), paths)?;
            Ok(())
        }
        fn footprints(&self) -> &[Footprint] {
            &self.footprints
        }
        fn start_gcode(&self) -> String {
            self.frame.start_text()
        }
        fn end_gcode(&self) -> String {
            self.frame.end_text()
        }
    }
}
