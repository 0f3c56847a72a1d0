//! `include:`: other files' params and templates, so a library of parts can
//! be shared between recipes; and a part's `include:`, a whole recipe as a
//! part ([`load_part_includes`]).
//!
//! Paths are relative to the including file. Included files come first, in
//! the order listed (each after its own includes); a file included twice is
//! read once; a file that includes itself, directly or not, is refused with
//! the chain of files. A param or template defined in two files is an error
//! naming both.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use indexmap::IndexMap;

use crate::base::error::{Error, Result};
use crate::base::expr::Params;
use crate::base::input::Reads;
use crate::recipe::eval::key;
use crate::recipe::schema::RawParam;
use crate::recipe::schema::{RawLibrary, RawPart, RawRecipe, RawTemplate};
use crate::recipe::yaml::parse_yaml;

/// Largest file `include:` reads, bytes.
pub(super) const MAX_INCLUDE_BYTES: u64 = 1 << 20;
/// Most files one recipe may include, directly or not.
pub(super) const MAX_INCLUDES: usize = 64;

/// A template and where it was written.
#[derive(Clone, Debug)]
pub(crate) struct Template {
    /// As written.
    pub(crate) raw: RawTemplate,
    /// The included file that defines it, as shown in messages; `None` for
    /// the recipe itself.
    pub(crate) file: Option<String>,
    /// That file's folder (its relative paths start there).
    pub(crate) dir: PathBuf,
}

/// The params and templates of a recipe and the files it includes.
#[derive(Clone, Debug, Default)]
pub(crate) struct Library {
    /// Every param in evaluation order (included files first), with the
    /// included file that defines it (`None`: the recipe).
    pub(crate) params: IndexMap<String, (RawParam, Option<String>)>,
    /// Every template by name.
    pub(crate) templates: IndexMap<String, Template>,
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

/// A whole recipe a part includes (`include: pot.yaml` on a part), read once.
#[derive(Debug)]
pub(crate) struct Included {
    /// As written.
    pub(crate) raw: RawRecipe,
    /// Its params and templates (and those of the files it includes).
    pub(crate) library: Library,
    /// Its folder (its relative paths start there).
    pub(crate) dir: PathBuf,
    /// The file as shown in messages.
    pub(crate) shown: String,
}

/// Every whole recipe the parts include, directly or through templates and
/// other included recipes, by the path a use names (its folder joined
/// with the file); a file named twice is read once.
pub(crate) type Includes = IndexMap<PathBuf, Arc<Included>>;

/// Reads the recipes the parts of `raw` (the recipe at `file`, in `dir`,
/// with its library `lib`) include as parts, and theirs in turn; a recipe
/// that includes itself, directly or not, is refused with the chain.
pub(crate) fn load_part_includes(
    raw: &RawRecipe,
    file: Option<&Path>,
    dir: &Path,
    lib: &Library,
    reads: &Reads,
) -> Result<Includes> {
    let mut w = PartIncludes {
        reads,
        out: Includes::new(),
        canon: IndexMap::new(),
        stack: Vec::new(),
    };
    if let Some(f) = file {
        let canon = std::fs::canonicalize(f).unwrap_or_else(|_| f.to_path_buf());
        w.stack.push((canon, f.display().to_string()));
    }
    w.recipe(&raw.parts, dir, lib, None)?;
    Ok(w.out)
}

struct PartIncludes<'r> {
    reads: &'r Reads,
    out: Includes,
    /// Each file read, by canonical path.
    canon: IndexMap<PathBuf, Arc<Included>>,
    /// The chain of recipes being read: canonical path and shown name.
    stack: Vec<(PathBuf, String)>,
}

impl PartIncludes<'_> {
    /// The includes of a recipe's `parts` (in `dir`) and of its templates.
    fn recipe(
        &mut self,
        parts: &[RawPart],
        dir: &Path,
        lib: &Library,
        from: Option<&str>,
    ) -> Result<()> {
        for (k, p) in parts.iter().enumerate() {
            self.part(p, dir, &format!("{}[{k}]", key!(RawRecipe, parts)), from)?;
        }
        for (name, t) in &lib.templates {
            let place = format!(
                "{}.{name}.{}",
                key!(RawRecipe, templates),
                key!(RawTemplate, part)
            );
            let shown = t.file.as_deref().or(from);
            self.part(&t.raw.part, &t.dir, &place, shown)?;
        }
        Ok(())
    }

    /// The includes of part `p` (at `place` of the file `from`) and its children.
    fn part(&mut self, p: &RawPart, dir: &Path, place: &str, from: Option<&str>) -> Result<()> {
        if let Some(inc) = &p.include {
            self.file(inc, dir, &format!("{place}.{}", key!(p.include)), from)?;
        }
        for (k, c) in p.parts.iter().flatten().enumerate() {
            self.part(c, dir, &format!("{place}.{}[{k}]", key!(p.parts)), from)?;
        }
        Ok(())
    }

    /// Reads the recipe `inc` names (relative to `dir`), once, and its includes.
    fn file(&mut self, inc: &str, dir: &Path, place: &str, from: Option<&str>) -> Result<()> {
        let here = |e: Error| match from {
            Some(f) => e.in_file(f),
            None => e,
        };
        let path = dir.join(inc);
        if self.out.contains_key(&path) {
            return Ok(());
        }
        let shown = path.display().to_string();
        let at = |e: Error| {
            if e.file.is_none() {
                here(e.under(place))
            } else {
                e
            }
        };
        self.reads.reach(&path, "included recipe").map_err(at)?;
        let canon = std::fs::canonicalize(&path).map_err(|e| {
            here(Error::input(
                place,
                format!("cannot read the included recipe `{inc}` ({shown}): {e}"),
            ))
        })?;
        if let Some(k) = self.stack.iter().position(|(c, _)| *c == canon) {
            let mut chain: Vec<&str> = self.stack[k..].iter().map(|(_, s)| s.as_str()).collect();
            chain.push(&shown);
            return Err(here(Error::input(
                place,
                format!(
                    "include cycle: {}; expected recipes that do not include each other",
                    chain.join(" → ")
                ),
            )));
        }
        if let Some(done) = self.canon.get(&canon) {
            let done = done.clone();
            self.out.insert(path, done);
            return Ok(());
        }
        if self.canon.len() >= MAX_INCLUDES {
            return Err(here(Error::input(
                place,
                format!("more than {MAX_INCLUDES} included recipes; expected fewer"),
            )));
        }
        let text = self
            .reads
            .read_reached(&path, "included recipe", MAX_INCLUDE_BYTES)
            .map_err(at)?;
        let raw: RawRecipe = parse_yaml(&text, &shown)?;
        let mine = |e: Error| e.in_file(&shown);
        if raw.p3dp != 1 {
            return Err(mine(Error::input(
                "p3dp",
                format!("format version {} is not known; expected 1", raw.p3dp),
            )));
        }
        if raw.plate.is_some() {
            return Err(here(Error::input(
                place,
                format!("`{inc}` is a plate, which is printed on its own; expected a recipe with `parts`"),
            )));
        }
        let sub = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let library = load_library(&raw, Some(&path), &sub, self.reads)?;
        self.stack.push((canon.clone(), shown.clone()));
        self.recipe(&raw.parts, &sub, &library, Some(&shown))?;
        self.stack.pop();
        let included = Arc::new(Included {
            raw,
            library,
            dir: sub,
            shown,
        });
        self.canon.insert(canon, included.clone());
        self.out.insert(path, included);
        Ok(())
    }
}
