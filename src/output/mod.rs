//! Layer 5, output: what a plan becomes on disk: G-code, previews, meshes,
//! lock files, all written whole or not at all.

pub(crate) mod file;
pub(crate) mod gcode;
pub(crate) mod host;
pub(crate) mod lock;
pub(crate) mod mesh;
pub(crate) mod preview;
