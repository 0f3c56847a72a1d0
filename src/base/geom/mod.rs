//! Geometry shared by several stages: arc fitting (G2/G3 output and its
//! checks), the exact 2D pieces, regions and offsets of the feature-based
//! solids (paper 003), one spatial grid of segments for the checks and the
//! previews, and the index of a path's passes that gives a string its width
//! (the previews and the mesh).

pub mod arc;
pub mod grid;
pub mod offset;
pub mod passes;
pub mod piece;
pub mod region;
