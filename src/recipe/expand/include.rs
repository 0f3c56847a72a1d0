//! `include:`: other files' params and templates, so a library of parts can
//! be shared between recipes.
//!
//! Paths are relative to the including file. Included files come first, in
//! the order listed (each after its own includes); a file included twice is
//! read once; a file that includes itself, directly or not, is refused with
//! the chain of files. A param or template defined in two files is an error
//! naming both.

use std::path::{Path, PathBuf};

use indexmap::IndexMap;

use crate::base::error::{Error, Result};
use crate::base::expr::Params;
use crate::base::input::Reads;
use crate::recipe::eval::key;
use crate::recipe::schema::RawParam;
use crate::recipe::schema::{RawLibrary, RawRecipe, RawTemplate};
use crate::recipe::yaml::parse_yaml;

/// Largest file `include:` reads, bytes.
pub(super) const MAX_INCLUDE_BYTES: u64 = 1 << 20;
/// Most files one recipe may include, directly or not.
pub(super) const MAX_INCLUDES: usize = 64;

/// A template and where it was written.
#[derive(Clone, Debug)]
pub(crate) struct Template {
    /// As written.
    pub raw: RawTemplate,
    /// The included file that defines it, as shown in messages; `None` for
    /// the recipe itself.
    pub file: Option<String>,
    /// That file's folder (its relative paths start there).
    pub dir: PathBuf,
}

/// The params and templates of a recipe and the files it includes.
#[derive(Clone, Debug, Default)]
pub(crate) struct Library {
    /// Every param in evaluation order (included files first), with the
    /// included file that defines it (`None`: the recipe).
    pub params: IndexMap<String, (RawParam, Option<String>)>,
    /// Every template by name.
    pub templates: IndexMap<String, Template>,
}

/// Reads the includes of `raw` (the recipe at `file`, when known, in `dir`)
/// and gathers its params and templates after theirs.
pub(crate) fn load_library(
    raw: &RawRecipe,
    file: Option<&Path>,
    dir: &Path,
    reads: &Reads,
) -> Result<Library> {
    let mut lib = Library::default();
    let mut loader = Loader {
        seen: Vec::new(),
        stack: Vec::new(),
        reads,
    };
    if let Some(f) = file {
        let canon = std::fs::canonicalize(f).unwrap_or_else(|_| f.to_path_buf());
        loader.stack.push((canon, f.display().to_string()));
    }
    loader.includes(&mut lib, &raw.include, dir, None)?;
    lib.add(&raw.params, &raw.templates, None, dir)?;
    Ok(lib)
}

impl Library {
    /// Evaluates every param in order, with `--set` overrides (see
    /// [`crate::recipe::eval_params`]); an error in an included param names
    /// that file.
    pub(crate) fn eval_params(&self, sets: &[(String, String)]) -> Result<Params> {
        let raw: IndexMap<String, RawParam> = self
            .params
            .iter()
            .map(|(k, (n, _))| (k.clone(), n.clone()))
            .collect();
        crate::recipe::params::eval_params(&raw, sets).map_err(|e| {
            let params = format!("{}.", key!(RawRecipe, params));
            let name = e.place.as_deref().and_then(|p| p.strip_prefix(&params));
            match name.and_then(|n| self.params.get(n)) {
                Some((_, Some(f))) => e.in_file(f),
                _ => e,
            }
        })
    }

    /// Adds one file's params and templates (`file` as shown, `None` for the recipe).
    fn add(
        &mut self,
        params: &IndexMap<String, RawParam>,
        templates: &IndexMap<String, RawTemplate>,
        file: Option<&str>,
        dir: &Path,
    ) -> Result<()> {
        let here = |e: Error| match file {
            Some(f) => e.in_file(f),
            None => e,
        };
        let twice = |what: &str, name: &str, other: &Option<String>| {
            here(Error::input(
                format!("{what}s.{name}"),
                format!(
                    "the {what} `{name}` is also defined in {}; expected each name defined once across a recipe and its includes",
                    other.as_deref().unwrap_or("the recipe")
                ),
            ))
        };
        for (name, n) in params {
            if let Some((_, other)) = self.params.get(name) {
                return Err(twice("param", name, other));
            }
            self.params
                .insert(name.clone(), (n.clone(), file.map(str::to_string)));
        }
        for (name, t) in templates {
            if let Some(other) = self.templates.get(name) {
                return Err(twice("template", name, &other.file));
            }
            self.templates.insert(
                name.clone(),
                Template {
                    raw: t.clone(),
                    file: file.map(str::to_string),
                    dir: dir.to_path_buf(),
                },
            );
        }
        Ok(())
    }
}

struct Loader<'a> {
    /// Files read so far (canonical paths).
    seen: Vec<PathBuf>,
    /// The chain of files being included: canonical path and shown name.
    stack: Vec<(PathBuf, String)>,
    /// Where every file read is noted.
    reads: &'a Reads,
}

impl Loader<'_> {
    /// Reads `list` (written in the file `from`, `None`: the recipe, in `dir`).
    fn includes(
        &mut self,
        lib: &mut Library,
        list: &[String],
        dir: &Path,
        from: Option<&str>,
    ) -> Result<()> {
        let here = |e: Error| match from {
            Some(f) => e.in_file(f),
            None => e,
        };
        for (k, inc) in list.iter().enumerate() {
            let place = format!("{}[{k}]", key!(RawRecipe, include));
            // an error in the included file's text stays there; any other
            // is at the key that names it
            let at = |e: Error| {
                if e.file.is_none() {
                    here(e.under(&place))
                } else {
                    e
                }
            };
            let path = dir.join(inc);
            let shown = path.display().to_string();
            self.reads.reach(&path, "included file").map_err(at)?;
            let canon = std::fs::canonicalize(&path).map_err(|e| {
                here(Error::input(
                    &place,
                    format!("cannot read the included file `{inc}` ({shown}): {e}"),
                ))
            })?;
            if let Some(at) = self.stack.iter().position(|(c, _)| *c == canon) {
                let mut chain: Vec<&str> =
                    self.stack[at..].iter().map(|(_, s)| s.as_str()).collect();
                chain.push(&shown);
                return Err(here(Error::input(
                    &place,
                    format!(
                        "include cycle: {}; expected files that do not include each other",
                        chain.join(" → ")
                    ),
                )));
            }
            if self.seen.contains(&canon) {
                continue;
            }
            if self.seen.len() >= MAX_INCLUDES {
                return Err(here(Error::input(
                    &place,
                    format!("more than {MAX_INCLUDES} included files; expected fewer"),
                )));
            }
            let text = self
                .reads
                .read_reached(&path, "included file", MAX_INCLUDE_BYTES)
                .map_err(at)?;
            let raw: RawLibrary = parse_yaml(&text, &shown)?;
            if raw.p3dp != 1 {
                return Err(Error::input(
                    "p3dp",
                    format!("format version {} is not known; expected 1", raw.p3dp),
                )
                .in_file(&shown));
            }
            self.seen.push(canon.clone());
            self.stack.push((canon, shown.clone()));
            let sub = path.parent().map(Path::to_path_buf).unwrap_or_default();
            self.includes(lib, &raw.include, &sub, Some(&shown))?;
            self.stack.pop();
            lib.add(&raw.params, &raw.templates, Some(&shown), &sub)?;
        }
        Ok(())
    }
}
