//! p3dp: procedural 3D printing. A YAML recipe describes the path of the
//! nozzle itself (Kanada's draw3dp); p3dp turns it into G-code and stats.
//!
//! Data flows one way: [`recipe`] → parts of strings ([`toolpath`], made by
//! [`primitive`]) → [`step`]s → [`check`]s → [`gcode`] and [`stats`];
//! [`build`] runs the pipeline and [`cli`] the commands.

#![warn(missing_docs)]

pub mod arc;
pub mod batch;
pub mod build;
pub mod check;
pub mod cli;
pub mod error;
pub mod expr;
pub mod flavor;
pub mod gcode;
pub mod input;
pub mod limits;
pub mod lock;
pub mod output;
pub mod planner;
pub mod preview;
pub mod primitive;
pub mod printer;
pub mod recipe;
pub mod safe_text;
pub mod skirt;
pub mod stats;
pub mod step;
pub mod toolpath;

pub use error::{Error, Result};
