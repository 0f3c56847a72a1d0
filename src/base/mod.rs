//! Layer 1, the bottom: plain types, geometry and expressions that every
//! layer above uses, with no knowledge of printers, recipes or files of the
//! project's own formats.

pub(crate) mod error;
pub(crate) mod expr;
pub(crate) mod finding;
pub(crate) mod format;
pub(crate) mod gcode;
pub(crate) mod geom;
pub(crate) mod grammar;
pub(crate) mod input;
pub(crate) mod mem;
pub(crate) mod par;
pub(crate) mod rng;
pub(crate) mod safe_text;
pub(crate) mod slicer_macro;
pub(crate) mod svg;
pub(crate) mod toolpath;
pub(crate) mod xml;

#[cfg(test)]
pub(crate) mod testing;
