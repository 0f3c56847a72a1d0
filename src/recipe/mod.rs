//! The YAML edge: recipes in the format of `docs/recipe.md` (which keeps every
//! key of the v1 contract) and printer profiles, read and resolved.
//!
//! Loading is two stages. [`yaml::parse_yaml`] reads the text into the raw
//! schema ([`schema`]: `Raw*` types, every number still a
//! number-or-expression), reporting the line and key path of any syntax
//! error, unknown key or wrong type. Then [`recipe::resolve`] evaluates params
//! (with `--set` overrides), every number, compiles step expressions and
//! loads images, naming the key path of any problem; the result is a
//! [`crate::generate::model::Recipe`].
//!
//! The modules, each using only those before it: [`yaml`] (the one that
//! knows the YAML library), [`schema`] (every serde form: the recipe, its
//! primitives and steps, printer profiles; the JSON Schema), [`eval`]
//! (numbers evaluated, key paths derived from field names), [`params`],
//! [`expand`] (templates, loops, groups, includes), [`profile`] (printer
//! profiles loaded into [`crate::machine::Printer`]) and [`resolve`] (the raw
//! forms into generation's types; a turtle's program compiled and run).

pub(crate) mod context;
pub(crate) mod eval;
pub(crate) mod expand;
pub(crate) mod params;
pub(crate) mod preset;
pub(crate) mod profile;
pub(crate) mod resolve;
pub(crate) mod schema;
pub(crate) mod yaml;

pub(crate) use params::parse_set;
#[cfg(any(test, feature = "testing"))]
pub use resolve::load;
#[cfg(any(test, feature = "testing"))]
pub use resolve::load_in;
#[cfg(any(test, feature = "testing"))]
pub(crate) use resolve::resolve;
pub(crate) use resolve::{from_raw_in, read_raw};
pub(crate) use schema::RawRecipe;
pub(crate) use yaml::parse_yaml;

#[cfg(test)]
mod tests;
