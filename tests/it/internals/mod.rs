//! Tests that reach past the crate's public face (loading a recipe,
//! planning it, writing G-code, reading stats and findings) into its
//! internals: a primitive's own model, the recipe's parts and steps, the
//! planner, the checks on strings changed by hand, the loader's raw form.
//!
//! Each module names, in its first comment, what it reaches for and the
//! module of `src/` it belongs beside; the modules outside `internals` use
//! the public face only. When the face shrinks (issue 29, part 7) these
//! move beside their code as unit tests, one module at a time.

mod bowl;
mod ca;
mod extruder_turtle;
mod gallery;
mod globe;
mod mutate;
mod planner;
mod preview;
mod procedural;
mod recipe_doc;
mod solid;
mod svg;
