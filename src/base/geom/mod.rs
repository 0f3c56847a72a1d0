//! Geometry shared by several stages: arc fitting (G2/G3 output and its
//! checks), the exact 2D pieces, regions and offsets of the feature-based
//! solids (paper 003), one spatial grid of segments for the checks and the
//! previews, and the index of a path's passes that gives a string its width
//! (the previews and the mesh).

pub(crate) mod arc;
pub(crate) mod grid;
pub(crate) mod offset;
pub(crate) mod passes;
pub(crate) mod piece;
pub(crate) mod region;
