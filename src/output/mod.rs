//! Layer 5, output: what a plan becomes on disk: G-code, previews, meshes,
//! lock files, all written whole or not at all.

pub mod file;
pub mod gcode;
pub mod host;
pub mod lock;
pub mod mesh;
pub mod preview;
