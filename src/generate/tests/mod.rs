//! Generation checked on the gallery's real recipes: each module loads a recipe
//! and checks the geometry its comment or its paper figure promises.

mod bowl;
mod ca;
mod gallery;
mod globe;
mod solid;
mod svg;
