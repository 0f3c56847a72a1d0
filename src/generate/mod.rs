//! Layer 3, generation: a resolved recipe made into strings (Kanada's
//! S_i = (start, end, c, v)): primitives, steps, parts and groups, the skirt.

pub mod assembly;
pub mod model;
pub mod primitive;
pub mod skirt;
pub mod step;
