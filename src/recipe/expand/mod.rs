//! Procedural recipes (issue 15): templates, `for` loops, groups and
//! included libraries, expanded into a flat list of leaf parts.
//!
//! Kanada's draw3dp builds parts by procedures: a `Trace` accumulates several
//! primitives, a combination of parts is deformed as one, and functions of
//! part assembly "become generation functions of complex parts" (paper 000,
//! §3.3–3.4). In a recipe these are:
//!
//! - `primitive:` a list (see [`crate::recipe::schema::RawPrimitives`]): one
//!   part, several primitives;
//! - `parts:` on a part: a group, whose `steps` run after its children's own
//!   steps on all their strings (see [`crate::generate::assembly`]);
//! - `templates:` named part trees with `params:` defaults, used by
//!   `template: NAME` with `with:` values;
//! - `for: {NAME: RANGE_OR_LIST}` on any part: one copy per value;
//! - `include:` other files' `params` and `templates` (see [`load_library`]).
//!
//! Expansion is pure and happens on the raw schema: it only decides which
//! raw leaf part is resolved with which constants. Template params and loop
//! variables are constants of one instance, so each leaf gets the recipe's
//! params extended by them (lexically: a template's body sees the recipe's
//! params and its own, not its caller's loop variables) and is then resolved
//! exactly as a v1 part is. The tree is bounded ([`MAX_PARTS`] leaves,
//! [`MAX_DEPTH`] levels) and a `for` is measured before it is expanded, so no
//! recipe can make expansion hang or exhaust memory.
//!
//! Every place is written through the chain that made it:
//! `parts[1].parts[0] (template ring, k = 3).steps[0]` is step 0 of the
//! template `ring`'s part in its copy with k = 3, used at `parts[1].parts[0]`.

mod include;
mod with;

use std::path::Path;
use std::sync::Arc;

use indexmap::IndexMap;

pub(crate) use include::{load_library, load_part_includes, Includes, Library, Template};

use crate::base::error::{Error, Result};
use crate::base::expr::{self, Params};
use crate::recipe::eval::{join, key};
use crate::recipe::params::is_identifier;
use crate::recipe::schema::Num;
use crate::recipe::schema::{RawLoop, RawPart, RawRecipe, RawStep, RawTemplate};

/// Most leaf parts a recipe may expand to.
pub(crate) const MAX_PARTS: usize = 10_000;

/// Most names one `for` may loop over.
pub(crate) const MAX_LOOP_NAMES: usize = 64;
/// Deepest nesting of groups and template uses.
pub(crate) const MAX_DEPTH: usize = 32;

/// A leaf part of the expanded recipe, to be resolved as a v1 part.
#[derive(Clone, Debug)]
pub(crate) struct Leaf<'a> {
    /// The part as written (it has a `primitive`).
    pub(crate) part: &'a RawPart,
    /// The recipe's params plus the template params and loop variables in scope.
    pub(crate) params: Params,
    /// Where it is written, through templates and loops.
    pub(crate) place: String,
    /// Its name with placeholders filled and copy suffixes added; `None`
    /// when neither the part nor a template use names it.
    pub(crate) name: Option<String>,
    /// The folder of the file that wrote it (relative paths start there).
    pub(crate) dir: &'a Path,
    /// The cross-section and speed of its recipe's `defaults` when it comes
    /// from a recipe included as a part; `None`: the recipe's own.
    pub(crate) defaults: Option<(f64, f64)>,
}

/// The steps of a group (or of a template use), to run on leaves `first..end`.
#[derive(Clone, Debug)]
pub(crate) struct GroupSpec<'a> {
    /// First leaf of the group.
    pub(crate) first: usize,
    /// One past its last leaf.
    pub(crate) end: usize,
    /// The steps as written.
    pub(crate) steps: &'a [RawStep],
    /// The params in scope where the steps are written.
    pub(crate) params: Params,
    /// Where the group is written.
    pub(crate) place: String,
    /// The folder of the file that wrote it.
    pub(crate) dir: &'a Path,
}

/// A recipe's parts expanded: leaves in print order, and group steps in the
/// order they run (inner groups before the groups around them).
#[derive(Clone, Debug, Default)]
pub(crate) struct Expansion<'a> {
    /// The leaf parts, in print order.
    pub(crate) leaves: Vec<Leaf<'a>>,
    /// The group steps, innermost first.
    pub(crate) groups: Vec<GroupSpec<'a>>,
}

/// Expands `parts` (written in the folder `dir`) with the recipe's evaluated
/// `params`, the `templates` of the recipe and its includes, and the
/// recipes its parts include whole (`includes`).
pub(crate) fn expand<'a>(
    parts: &'a [RawPart],
    templates: &'a IndexMap<String, Template>,
    params: &'a Params,
    dir: &'a Path,
    includes: &'a Includes,
) -> Result<Expansion<'a>> {
    let mut w = Walker {
        includes,
        out: Expansion::default(),
    };
    let scope = Scope {
        params: params.clone(),
        suffix: String::new(),
        prefix: String::new(),
        copied: false,
        stack: Vec::new(),
        depth: 0,
        dir,
        lib: Lib {
            templates,
            global: Arc::new(params.clone()),
            defaults: None,
        },
    };
    for (k, p) in parts.iter().enumerate() {
        w.part(p, &scope, &format!("{}[{k}]", key!(RawRecipe, parts)), None)?;
    }
    Ok(w.out)
}

/// The templates and params a recipe's parts see: the recipe's, or those of
/// a recipe included as a part.
#[derive(Clone)]
struct Lib<'a> {
    templates: &'a IndexMap<String, Template>,
    /// What a template's body sees besides its own params.
    global: Arc<Params>,
    /// An included recipe's defaults (cross-section, speed).
    defaults: Option<(f64, f64)>,
}

/// What a part sees: constants, the copy suffix and the copies' prefix for
/// names, whether it is a copy itself, the templates being expanded (to
/// refuse recursion), the nesting depth, its file's folder, its recipe's
/// templates and params.
#[derive(Clone)]
struct Scope<'a> {
    params: Params,
    suffix: String,
    /// `pot-2/`: the names of the copies (and included recipes) around.
    prefix: String,
    /// This part is one copy of a `for` (its own or a template use's).
    copied: bool,
    stack: Vec<&'a str>,
    depth: usize,
    dir: &'a Path,
    lib: Lib<'a>,
}

struct Walker<'a> {
    includes: &'a Includes,
    out: Expansion<'a>,
}

impl<'a> Walker<'a> {
    /// A part written at `place`, once or once per value of its `for`.
    /// `name` is a name given by a template use, replacing the part's own.
    fn part(
        &mut self,
        p: &'a RawPart,
        scope: &Scope<'a>,
        place: &str,
        name: Option<String>,
    ) -> Result<()> {
        if scope.depth >= MAX_DEPTH {
            return Err(Error::input(
                place,
                format!("parts are nested more than {MAX_DEPTH} deep here (groups, template uses and included recipes); expected a shallower tree"),
            ));
        }
        if p.repeat.is_empty() {
            return self.instance(p, scope, place, None, name);
        }
        let loops = loop_values(p, &scope.params, place)?;
        let copies = loops
            .iter()
            .fold(1usize, |n, (_, v)| n.saturating_mul(v.len()));
        let before = self.out.leaves.len();
        if copies > MAX_PARTS || before + copies > MAX_PARTS {
            let sizes: Vec<String> = loops.iter().map(|(_, v)| v.len().to_string()).collect();
            return Err(Error::input(
                // the field `repeat` is read as `for`
                format!("{place}.for"),
                format!(
                    "this `for` makes {} copies{}{}, more than the limit of {MAX_PARTS} parts in a recipe; expected fewer values",
                    if copies == usize::MAX { "too many".to_string() } else { copies.to_string() },
                    if sizes.len() > 1 { format!(" ({})", sizes.join(" × ")) } else { String::new() },
                    if before > 0 { format!(" after {before} parts") } else { String::new() },
                ),
            ));
        }
        // a name with a `{…}` placeholder names the copies itself
        let carrier = match (&p.template, &p.include) {
            _ if name.is_some() => name.as_deref(),
            (Some(t), _) => p.name.as_deref().or_else(|| {
                scope
                    .lib
                    .templates
                    .get(t)
                    .and_then(|tpl| tpl.raw.part.name.as_deref())
            }),
            (None, Some(_)) => p.name.as_deref().or(Some("")),
            (None, None) => p.name.as_deref(),
        };
        let suffixed = !carrier.unwrap_or("").contains('{');
        let mut index = vec![0usize; loops.len()];
        for _ in 0..copies {
            let mut s = scope.clone();
            s.copied = true;
            let mut desc = Vec::with_capacity(loops.len());
            for (j, (var, values)) in loops.iter().enumerate() {
                let v = values[index[j]];
                s.params.insert(var.to_string(), v);
                desc.push(format!("{var} = {}", fmt_value(v)));
                if suffixed {
                    s.suffix.push_str(&format!("-{}", index[j]));
                }
            }
            self.instance(p, &s, place, Some(desc.join(", ")), name.clone())?;
            // the odometer: the last name turns fastest
            for j in (0..loops.len()).rev() {
                index[j] += 1;
                if index[j] < loops[j].1.len() {
                    break;
                }
                index[j] = 0;
            }
        }
        Ok(())
    }

    /// One copy of a part: a template use, an included recipe, a group or a
    /// leaf; nothing when its `if` is 0.
    fn instance(
        &mut self,
        p: &'a RawPart,
        scope: &Scope<'a>,
        place: &str,
        copy: Option<String>,
        name: Option<String>,
    ) -> Result<()> {
        let here = match &copy {
            Some(d) => format!("{place} ({d})"),
            None => place.to_string(),
        };
        if let Some(w) = &p.when {
            // the field `when` is read as `if`
            if eval(w, &scope.params, &join(&here, "if"))? == 0.0 {
                return Ok(());
            }
        }
        if let Some(t) = &p.template {
            return self.template_use(p, t, scope, (place, &here), copy, name);
        }
        if let Some(inc) = &p.include {
            return self.include_use(p, inc, scope, (place, &here), copy, name);
        }
        if !p.with.is_empty() {
            return Err(Error::input(
                join(&here, key!(p.with)),
                "`with` gives the params of a template or an included recipe; expected `template: NAME` or `include: FILE` beside it",
            ));
        }
        match (&p.primitive, &p.parts) {
            (Some(_), Some(_)) => Err(Error::input(
                here,
                "both `primitive` and `parts` are given; expected one: `primitive` for a part, `parts` for a group of parts",
            )),
            (None, None) => Err(Error::input(
                here,
                "expected `primitive` (one or a list), `parts` (a group of parts), `template` or `include` (a whole recipe)",
            )),
            (Some(_), None) => self.leaf(p, scope, here, name),
            (None, Some(children)) => self.group_part(p, children, scope, here, name),
        }
    }

    /// A leaf part at `here`: its name filled, prefixed and suffixed, then recorded.
    fn leaf(
        &mut self,
        p: &'a RawPart,
        scope: &Scope<'a>,
        here: String,
        name: Option<String>,
    ) -> Result<()> {
        let name = match name {
            Some(n) => Some(n),
            None => match &p.name {
                Some(n) => Some(fill_name(n, &scope.params, &join(&here, key!(p.name)))?),
                None => None,
            },
        };
        let name = match name {
            Some(n) => Some(format!("{}{n}{}", scope.prefix, scope.suffix)),
            // an unnamed part of a named copy: `pot-2/part 5`
            None if !scope.prefix.is_empty() => Some(format!(
                "{}part {}",
                scope.prefix,
                self.out.leaves.len() + 1
            )),
            None => None,
        };
        if let Some(n) = &name {
            check_name(n, &join(&here, key!(p.name)))?;
        }
        if self.out.leaves.len() >= MAX_PARTS {
            return Err(Error::input(
                here,
                format!("the recipe would have more than {MAX_PARTS} parts; expected fewer copies"),
            ));
        }
        self.out.leaves.push(Leaf {
            part: p,
            params: scope.params.clone(),
            place: here,
            name,
            dir: scope.dir,
            defaults: scope.lib.defaults,
        });
        Ok(())
    }

    /// A group at `here` (named `name` by a template use, else by itself):
    /// its `children` one level deeper, then its steps. A named group that
    /// is a copy names its children `COPY/CHILD`.
    fn group_part(
        &mut self,
        p: &'a RawPart,
        children: &'a [RawPart],
        scope: &Scope<'a>,
        here: String,
        name: Option<String>,
    ) -> Result<()> {
        for (key, given) in [
            (key!(p.cross_section), p.cross_section.is_some()),
            (key!(p.speed), p.speed.is_some()),
        ] {
            if given {
                return Err(Error::input(
                    join(&here, key),
                    format!("a group has no strings of its own; expected `{key}` on its parts (or in `defaults`)"),
                ));
            }
        }
        if children.is_empty() {
            return Err(Error::input(
                join(&here, key!(p.parts)),
                "expected at least one part in a group",
            ));
        }
        let name = match name {
            Some(n) => Some(n),
            None => match &p.name {
                Some(n) => Some(fill_name(n, &scope.params, &join(&here, key!(p.name)))?),
                None => None,
            },
        };
        if let Some(n) = &name {
            check_name(n, &join(&here, key!(p.name)))?;
        }
        let mut inner = Scope {
            depth: scope.depth + 1,
            copied: false,
            ..scope.clone()
        };
        if let (true, Some(n)) = (scope.copied, &name) {
            inner.prefix = format!("{}{n}{}/", scope.prefix, scope.suffix);
            inner.suffix.clear();
        }
        let first = self.out.leaves.len();
        for (j, c) in children.iter().enumerate() {
            let at = format!("{}[{j}]", join(&here, key!(p.parts)));
            self.part(c, &inner, &at, None)?;
        }
        self.group(first, &p.steps, scope, here);
        Ok(())
    }

    /// `template: t` with `with:` values, at `place` (`here` with its copy).
    fn template_use(
        &mut self,
        p: &'a RawPart,
        t: &'a str,
        scope: &Scope<'a>,
        (place, here): (&str, &str),
        copy: Option<String>,
        name: Option<String>,
    ) -> Result<()> {
        only_use_fields(p, here, key!(p.template))?;
        let tpl = self.template(p, t, scope, here)?;
        if scope.stack.contains(&t) {
            let mut chain: Vec<&str> = scope.stack.clone();
            chain.push(t);
            return Err(Error::input(
                join(here, key!(p.template)),
                format!(
                    "template `{t}` uses itself: {}; expected templates that end",
                    chain.join(" → ")
                ),
            ));
        }
        with_known(p, &format!("template `{t}`"), tpl.raw.params.keys(), here)?;
        let params = template_params(p, t, tpl, scope, here)?;
        // a name given where the template is used wins over the one inside it
        let name = match (name, &p.name) {
            (Some(n), _) => Some(n),
            (None, Some(n)) => Some(fill_name(n, &scope.params, &join(here, key!(p.name)))?),
            (None, None) => None,
        };
        let from = match &tpl.file {
            Some(f) => format!(" from {f}"),
            None => String::new(),
        };
        let body = match &copy {
            Some(d) => format!("{place} (template {t}{from}, {d})"),
            None => format!("{place} (template {t}{from})"),
        };
        let mut stack = scope.stack.clone();
        stack.push(t);
        let inner = Scope {
            params,
            stack,
            depth: scope.depth + 1,
            dir: &tpl.dir,
            ..scope.clone()
        };
        let first = self.out.leaves.len();
        self.part(&tpl.raw.part, &inner, &body, name)?;
        self.group(first, &p.steps, scope, here.to_string());
        Ok(())
    }

    /// `include: inc`, a whole recipe as a group, its params from `with:`,
    /// at `place` (`here` with its copy). Its parts are named `NAME/PART`:
    /// NAME the use's name (or the recipe's), with the copy's number.
    fn include_use(
        &mut self,
        p: &'a RawPart,
        inc: &'a str,
        scope: &Scope<'a>,
        (place, here): (&str, &str),
        copy: Option<String>,
        name: Option<String>,
    ) -> Result<()> {
        only_use_fields(p, here, key!(p.include))?;
        let Some(r) = self.includes.get(&scope.dir.join(inc)) else {
            return Err(Error::input(
                join(here, key!(p.include)),
                format!("the included recipe `{inc}` was not read"),
            ));
        };
        let lib = &r.library;
        with_known(p, &format!("the recipe `{inc}`"), lib.params.keys(), here)?;
        let mut sets = Vec::with_capacity(p.with.len());
        for (k, g) in &p.with {
            let at = [here, key!(p.with), k].join(".");
            let target = &lib.params[k].0;
            sets.push((
                k.clone(),
                with::value(g, target, &scope.params, &at)?.text(),
            ));
        }
        let params = lib.eval_params(&sets).map_err(|e| e.in_file(&r.shown))?;
        let defaults = included_defaults(&r.raw, &params).map_err(|e| e.in_file(&r.shown))?;
        let name = match (name, &p.name) {
            (Some(n), _) => n,
            (None, Some(n)) => fill_name(n, &scope.params, &join(here, key!(p.name)))?,
            (None, None) => r.raw.name.clone(),
        };
        check_name(&name, &join(here, key!(p.name)))?;
        let body = match &copy {
            Some(d) => format!("{place} (include {inc}, {d})"),
            None => format!("{place} (include {inc})"),
        };
        let inner = Scope {
            params: params.clone(),
            suffix: String::new(),
            prefix: format!("{}{name}{}/", scope.prefix, scope.suffix),
            copied: false,
            stack: Vec::new(),
            depth: scope.depth + 1,
            dir: &r.dir,
            lib: Lib {
                templates: &lib.templates,
                global: Arc::new(params),
                defaults: Some(defaults),
            },
        };
        let first = self.out.leaves.len();
        for (j, c) in r.raw.parts.iter().enumerate() {
            let at = format!("{body}.{}[{j}]", key!(RawRecipe, parts));
            self.part(c, &inner, &at, None)?;
        }
        self.group(first, &p.steps, scope, here.to_string());
        Ok(())
    }

    /// The template `t` a use at `here` names, or an error listing the known ones.
    fn template(
        &self,
        p: &RawPart,
        t: &str,
        scope: &Scope<'a>,
        here: &str,
    ) -> Result<&'a Template> {
        let templates = scope.lib.templates;
        let Some(tpl) = templates.get(t) else {
            let known: Vec<&str> = templates.keys().map(String::as_str).collect();
            return Err(Error::input(
                join(here, key!(p.template)),
                if known.is_empty() {
                    format!("unknown template `{t}`; this recipe defines no templates (add them under `templates:` or `include:` a file that has them)")
                } else {
                    format!(
                        "unknown template `{t}`; the templates are {}",
                        known.join(", ")
                    )
                },
            ));
        };
        Ok(tpl)
    }

    /// Records `steps` (when there are any) to run on the leaves from `first` on.
    fn group(&mut self, first: usize, steps: &'a [RawStep], scope: &Scope<'a>, place: String) {
        if !steps.is_empty() {
            self.out.groups.push(GroupSpec {
                first,
                end: self.out.leaves.len(),
                steps,
                params: scope.params.clone(),
                place,
                dir: scope.dir,
            });
        }
    }
}

/// The params a use of `tpl` (template `t`, at `here`) gives its body: the
/// recipe's params, then each template param in order, from `with:`
/// (evaluated where the use is) or its default (evaluated in the params
/// before it).
fn template_params(
    p: &RawPart,
    t: &str,
    tpl: &Template,
    scope: &Scope,
    here: &str,
) -> Result<Params> {
    let def_place =
        |pn: &str| [key!(RawRecipe, templates), t, key!(RawTemplate, params), pn].join(".");
    let in_def = |e: Error| match &tpl.file {
        Some(f) => e.in_file(f),
        None => e,
    };
    let mut given = IndexMap::new();
    for (pn, target) in &tpl.raw.params {
        if !is_identifier(pn) || expr::is_reserved(pn) {
            return Err(in_def(Error::input(
                def_place(pn),
                format!("`{pn}` cannot name a template param; expected letters, digits and `_`, not a name expressions already use ({})", reserved_names()),
            )));
        }
        if let Some(g) = p.with.get(pn) {
            let at = [here, key!(p.with), pn].join(".");
            given.insert(pn.clone(), with::value(g, target, &scope.params, &at)?);
        }
    }
    // the template's body sees the recipe's params and its own
    with::template_params(&scope.lib.global, &tpl.raw.params, &given, &def_place).map_err(in_def)
}

/// The cross-section and speed of an included recipe's `defaults`.
fn included_defaults(raw: &RawRecipe, params: &Params) -> Result<(f64, f64)> {
    use crate::generate::model::{DEFAULT_CROSS_SECTION, DEFAULT_SPEED};
    use crate::recipe::eval::{at, Scope};
    let d = &raw.defaults;
    let s = Scope::new(params).under(key!(raw.defaults));
    Ok((
        s.positive_or(at!(d.cross_section), DEFAULT_CROSS_SECTION)?,
        s.positive_or(at!(d.speed), DEFAULT_SPEED)?,
    ))
}

/// Refuses the fields a use at `here` (of a template, or a recipe
/// included whole: `what` is `template` or `include`) cannot have beside it.
fn only_use_fields(p: &RawPart, here: &str, what: &str) -> Result<()> {
    for (key, given) in [
        (key!(p.primitive), p.primitive.is_some()),
        (key!(p.parts), p.parts.is_some()),
        (key!(p.cross_section), p.cross_section.is_some()),
        (key!(p.speed), p.speed.is_some()),
        (
            key!(p.include),
            what != key!(p.include) && p.include.is_some(),
        ),
    ] {
        if given {
            return Err(Error::input(
                join(here, key),
                format!("`{key}` beside `{what}`; a use of a template or an included recipe takes only `name`, `with`, `for`, `if` and `steps` (steps run after its own)"),
            ));
        }
    }
    Ok(())
}

/// Refuses a `with:` key at `here` that is not one of `known`, the params
/// of `what` (`template `ring``, `the recipe `pot.yaml``).
fn with_known<'k>(
    p: &RawPart,
    what: &str,
    known: impl Iterator<Item = &'k String>,
    here: &str,
) -> Result<()> {
    let known: Vec<&str> = known.map(String::as_str).collect();
    for key in p.with.keys() {
        if !known.contains(&key.as_str()) {
            return Err(Error::input(
                [here, key!(p.with), key].join("."),
                if known.is_empty() {
                    format!("{what} has no params")
                } else {
                    format!(
                        "{what} has no param `{key}`; its params are {}",
                        known.join(", ")
                    )
                },
            ));
        }
    }
    Ok(())
}

/// The values of each name of `p`'s `for`, evaluated in `params`.
fn loop_values<'p>(
    p: &'p RawPart,
    params: &Params,
    place: &str,
) -> Result<Vec<(&'p str, Vec<f64>)>> {
    if p.repeat.len() > MAX_LOOP_NAMES {
        return Err(Error::input(
            format!("{place}.for"),
            format!(
                "{} loop names, more than {MAX_LOOP_NAMES}; expected fewer",
                p.repeat.len()
            ),
        ));
    }
    let mut out = Vec::with_capacity(p.repeat.len());
    let mut copies = 1usize;
    for (var, l) in &p.repeat {
        if copies > MAX_PARTS {
            // too many copies already: the caller refuses them, and the
            // values of the names left are never made
            break;
        }
        // the field `repeat` is read as `for`
        let at = format!("{place}.for.{var}");
        if !is_identifier(var) || expr::is_reserved(var) {
            return Err(Error::input(
                at,
                format!("`{var}` cannot name a loop variable; expected letters, digits and `_`, not a name expressions already use ({})", reserved_names()),
            ));
        }
        let values = match l {
            RawLoop::List(v) => {
                if v.len() > MAX_PARTS {
                    return Err(Error::input(
                        at,
                        format!(
                            "{} values, more than the limit of {MAX_PARTS} parts in a recipe",
                            v.len()
                        ),
                    ));
                }
                let mut vals = Vec::with_capacity(v.len());
                for (k, n) in v.iter().enumerate() {
                    vals.push(eval(n, params, &format!("{at}[{k}]"))?);
                }
                vals
            }
            RawLoop::Range(s) => range(s, params, &at)?,
        };
        copies = copies.saturating_mul(values.len());
        out.push((var.as_str(), values));
    }
    Ok(out)
}

/// The values of a `for` range (see [`params::range`]), at most
/// [`MAX_PARTS`].
fn range(s: &str, params: &Params, place: &str) -> Result<Vec<f64>> {
    crate::recipe::params::range(s, params, place, MAX_PARTS, "parts in a recipe")
}

/// A number of a template's `with:` or a loop's list, evaluated in `params`.
fn eval(n: &Num, params: &Params, place: &str) -> Result<f64> {
    let v = crate::recipe::eval::eval(n, params, place)?;
    crate::recipe::eval::finite(v, place)
}

/// `name` with each `{EXPR}` replaced by the expression's value in `params`
/// (integers without decimals, others with up to 6).
pub(crate) fn fill_name(name: &str, params: &Params, place: &str) -> Result<String> {
    use crate::base::format::{pieces, Piece};
    let pieces = pieces(name).map_err(|_| {
        Error::input(
            place,
            format!(
                "the name {name:?} has a `{{` without its `}}`; expected `{{EXPR}}`, e.g. `ring-{{k}}`"
            ),
        )
    })?;
    let mut out = String::with_capacity(name.len());
    for p in pieces {
        match p {
            Piece::Text(t) => out.push_str(t),
            Piece::Expr(src) => {
                let v = expr::eval_const(src, params)
                    .map_err(|m| Error::input(place, format!("in the name {name:?}: {m}")))?;
                out.push_str(&fmt_value(v));
            }
        }
    }
    Ok(out)
}

/// Refuses names that would break the G-code comment they are written into.
pub(crate) fn check_name(name: &str, place: &str) -> Result<()> {
    crate::base::safe_text::check(place, name)
}

/// A value in a name or a place: integers without decimals, others with up
/// to 6, never `-0`.
pub(crate) use crate::base::format::fmt_value;

fn reserved_names() -> String {
    let mut v: Vec<&str> = expr::VAR_NAMES
        .into_iter()
        .filter(|n| expr::is_reserved(n))
        .collect();
    v.extend(["pi", "e"]);
    v.join(", ")
}

/// The params of the recipe at `path` (its includes' first), read once:
/// [`Library::eval_params`] with a variant's `--set`s gives what a build
/// would evaluate them to, without building (a sweep's names and summary
/// show these values; its thousands of variants share one read).
pub(crate) fn param_library(path: &std::path::Path) -> crate::base::error::Result<Library> {
    let shown = path.display().to_string();
    let reads = crate::base::input::Reads::default();
    let text = reads.read_text(path, "recipe")?;
    let raw: crate::recipe::schema::RawRecipe = crate::recipe::yaml::parse_yaml(&text, &shown)?;
    let dir = path
        .parent()
        .map(std::path::Path::to_path_buf)
        .unwrap_or_default();
    load_library(&raw, Some(path), &dir, &reads)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_include_their_end() {
        let p = Params::new();
        assert_eq!(
            range("0..4", &p, "for.k").unwrap(),
            vec![0.0, 1.0, 2.0, 3.0, 4.0]
        );
        assert_eq!(range("1..2:0.5", &p, "for.k").unwrap(), vec![1.0, 1.5, 2.0]);
        assert_eq!(range("0..1:0.1", &p, "for.k").unwrap().len(), 11);
        assert_eq!(range("3..1:-1", &p, "for.k").unwrap(), vec![3.0, 2.0, 1.0]);
        assert_eq!(range("2..2", &p, "for.k").unwrap(), vec![2.0]);
        assert_eq!(range("3..1", &p, "for.k").unwrap(), Vec::<f64>::new());
        assert_eq!(range("1..0", &p, "for.k").unwrap(), Vec::<f64>::new());
        assert!(range("0..1:0", &p, "for.k")
            .unwrap_err()
            .message
            .contains("step"));
        assert!(range("k", &p, "for.k")
            .unwrap_err()
            .message
            .contains("not a range"));
        assert!(range("0..1e9", &p, "for.k")
            .unwrap_err()
            .message
            .contains("limit"));
        let mut q = Params::new();
        q.insert("m".into(), 3.0);
        assert_eq!(
            range("m..2*m", &q, "for.k").unwrap(),
            vec![3.0, 4.0, 5.0, 6.0]
        );
    }

    #[test]
    fn names_fill_placeholders() {
        let mut p = Params::new();
        p.insert("k".into(), 3.0);
        p.insert("a".into(), 0.25);
        assert_eq!(fill_name("ring-{k}", &p, "n").unwrap(), "ring-3");
        assert_eq!(fill_name("{k+1}/{a}", &p, "n").unwrap(), "4/0.25");
        assert_eq!(fill_name("plain", &p, "n").unwrap(), "plain");
        assert!(fill_name("bad-{k", &p, "n").is_err());
        assert!(fill_name("bad-{q}", &p, "n").is_err());
        assert!(check_name("a\nG28", "n").is_err());
        assert_eq!(fmt_value(-1e-9), "0");
    }
}
