//! The loader checked on real recipes and on its own reference.

mod procedural;
mod recipe_doc;
mod settings;
mod switches;
