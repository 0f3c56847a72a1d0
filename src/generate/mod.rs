//! Layer 3, generation: a resolved recipe made into strings (Kanada's
//! S_i = (start, end, c, v)): primitives, steps, parts and groups, the skirt.

pub(crate) mod assembly;
pub(crate) mod model;
pub(crate) mod plate;
pub(crate) mod primitive;
pub(crate) mod skirt;
pub(crate) mod step;

#[cfg(test)]
mod tests;
