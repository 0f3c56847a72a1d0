//! Layer 1, the bottom: plain types, geometry and expressions that every
//! layer above uses, with no knowledge of printers, recipes or files of the
//! project's own formats.

pub mod error;
pub mod expr;
pub mod finding;
pub mod format;
pub mod geom;
pub mod input;
pub mod mem;
pub mod par;
pub mod rng;
pub mod safe_text;
pub mod slicer_macro;
pub mod svg;
pub mod toolpath;
