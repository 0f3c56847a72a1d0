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

use std::path::Path;

use indexmap::IndexMap;

pub(crate) use include::{load_library, Library, Template};

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
    pub part: &'a RawPart,
    /// The recipe's params plus the template params and loop variables in scope.
    pub params: Params,
    /// Where it is written, through templates and loops.
    pub place: String,
    /// Its name with placeholders filled and copy suffixes added; `None`
    /// when neither the part nor a template use names it.
    pub name: Option<String>,
    /// The folder of the file that wrote it (relative paths start there).
    pub dir: &'a Path,
}

/// The steps of a group (or of a template use), to run on leaves `first..end`.
#[derive(Clone, Debug)]
pub(crate) struct GroupSpec<'a> {
    /// First leaf of the group.
    pub first: usize,
    /// One past its last leaf.
    pub end: usize,
    /// The steps as written.
    pub steps: &'a [RawStep],
    /// The params in scope where the steps are written.
    pub params: Params,
    /// Where the group is written.
    pub place: String,
    /// The folder of the file that wrote it.
    pub dir: &'a Path,
}

/// A recipe's parts expanded: leaves in print order, and group steps in the
/// order they run (inner groups before the groups around them).
#[derive(Clone, Debug, Default)]
pub(crate) struct Expansion<'a> {
    /// The leaf parts, in print order.
    pub leaves: Vec<Leaf<'a>>,
    /// The group steps, innermost first.
    pub groups: Vec<GroupSpec<'a>>,
}

/// Expands `parts` (written in the folder `dir`) with the recipe's evaluated
/// `params` and the `templates` of the recipe and its includes.
pub(crate) fn expand<'a>(
    parts: &'a [RawPart],
    templates: &'a IndexMap<String, Template>,
    params: &'a Params,
    dir: &'a Path,
) -> Result<Expansion<'a>> {
    let mut w = Walker {
        templates,
        global: params,
        out: Expansion::default(),
    };
    let scope = Scope {
        params: params.clone(),
        suffix: String::new(),
        stack: Vec::new(),
        depth: 0,
        dir,
    };
    for (k, p) in parts.iter().enumerate() {
        w.part(p, &scope, &format!("{}[{k}]", key!(RawRecipe, parts)), None)?;
    }
    Ok(w.out)
}

/// What a part sees: constants, the copy suffix for names, the templates
/// being expanded (to refuse recursion), the nesting depth, its file's folder.
#[derive(Clone)]
struct Scope<'a> {
    params: Params,
    suffix: String,
    stack: Vec<&'a str>,
    depth: usize,
    dir: &'a Path,
}

struct Walker<'a> {
    templates: &'a IndexMap<String, Template>,
    global: &'a Params,
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
                format!("parts are nested more than {MAX_DEPTH} deep here (groups and template uses); expected a shallower tree"),
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
        let carrier = match &p.template {
            _ if name.is_some() => name.as_deref(),
            Some(t) => p.name.as_deref().or_else(|| {
                self.templates
                    .get(t)
                    .and_then(|tpl| tpl.raw.part.name.as_deref())
            }),
            None => p.name.as_deref(),
        };
        let suffixed = !carrier.unwrap_or("").contains('{');
        let mut index = vec![0usize; loops.len()];
        for _ in 0..copies {
            let mut s = scope.clone();
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

    /// One copy of a part: a template use, a group or a leaf.
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
        if let Some(t) = &p.template {
            return self.template_use(p, t, scope, place, &here, copy, name);
        }
        if !p.with.is_empty() {
            return Err(Error::input(
                join(&here, key!(p.with)),
                "`with` gives a template's params; expected `template: NAME` beside it",
            ));
        }
        match (&p.primitive, &p.parts) {
            (Some(_), Some(_)) => Err(Error::input(
                here,
                "both `primitive` and `parts` are given; expected one: `primitive` for a part, `parts` for a group of parts",
            )),
            (None, None) => Err(Error::input(
                here,
                "expected `primitive` (one or a list), `parts` (a group of parts) or `template`",
            )),
            (Some(_), None) => self.leaf(p, scope, here, name),
            (None, Some(children)) => self.group_part(p, children, scope, here),
        }
    }

    /// A leaf part at `here`: its name filled and suffixed, then recorded.
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
        }
        .map(|n| n + &scope.suffix);
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
        });
        Ok(())
    }

    /// A group at `here`: its `children` one level deeper, then its steps.
    fn group_part(
        &mut self,
        p: &'a RawPart,
        children: &'a [RawPart],
        scope: &Scope<'a>,
        here: String,
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
        if let Some(n) = &p.name {
            check_name(
                &fill_name(n, &scope.params, &join(&here, key!(p.name)))?,
                &join(&here, key!(p.name)),
            )?;
        }
        let inner = Scope {
            depth: scope.depth + 1,
            ..scope.clone()
        };
        let first = self.out.leaves.len();
        for (j, c) in children.iter().enumerate() {
            let at = format!("{}[{j}]", join(&here, key!(p.parts)));
            self.part(c, &inner, &at, None)?;
        }
        self.group(first, &p.steps, scope, here);
        Ok(())
    }

    /// `template: t` with `with:` values, at `place` (`here` with its copy).
    #[allow(clippy::too_many_arguments)]
    fn template_use(
        &mut self,
        p: &'a RawPart,
        t: &'a str,
        scope: &Scope<'a>,
        place: &str,
        here: &str,
        copy: Option<String>,
        name: Option<String>,
    ) -> Result<()> {
        only_use_fields(p, here)?;
        let tpl = self.template(p, t, here)?;
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
        with_known(p, t, tpl, here)?;
        let params = self.template_params(p, t, tpl, scope, here)?;
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
            suffix: scope.suffix.clone(),
            stack,
            depth: scope.depth + 1,
            dir: &tpl.dir,
        };
        let first = self.out.leaves.len();
        self.part(&tpl.raw.part, &inner, &body, name)?;
        self.group(first, &p.steps, scope, here.to_string());
        Ok(())
    }

    /// The template `t` a use at `here` names, or an error listing the known ones.
    fn template(&self, p: &RawPart, t: &str, here: &str) -> Result<&'a Template> {
        let Some(tpl) = self.templates.get(t) else {
            let known: Vec<&str> = self.templates.keys().map(String::as_str).collect();
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

    /// The params a use of `tpl` gives its body: the recipe's params, then
    /// each template param in order, from `with:` (evaluated where the use
    /// is) or its default (evaluated in the params before it).
    fn template_params(
        &self,
        p: &RawPart,
        t: &str,
        tpl: &Template,
        scope: &Scope<'a>,
        here: &str,
    ) -> Result<Params> {
        // the template's body sees the recipe's params and its own
        let mut params = self.global.clone();
        for (pn, default) in &tpl.raw.params {
            let def_place =
                [key!(RawRecipe, templates), t, key!(RawTemplate, params), pn].join(".");
            let in_def = |e: Error| match &tpl.file {
                Some(f) => e.in_file(f),
                None => e,
            };
            if !is_identifier(pn) || expr::is_reserved(pn) {
                return Err(in_def(Error::input(
                    def_place,
                    format!("`{pn}` cannot name a template param; expected letters, digits and `_`, not a name expressions already use ({})", reserved_names()),
                )));
            }
            let v = match p.with.get(pn) {
                Some(n) => eval(n, &scope.params, &[here, key!(p.with), pn].join("."))?,
                None => eval(default, &params, &def_place).map_err(in_def)?,
            };
            params.insert(pn.clone(), v);
        }
        Ok(params)
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

/// Refuses the fields a template use at `here` cannot have beside `template`.
fn only_use_fields(p: &RawPart, here: &str) -> Result<()> {
    for (key, given) in [
        (key!(p.primitive), p.primitive.is_some()),
        (key!(p.parts), p.parts.is_some()),
        (key!(p.cross_section), p.cross_section.is_some()),
        (key!(p.speed), p.speed.is_some()),
    ] {
        if given {
            return Err(Error::input(
                join(here, key),
                format!("`{key}` beside `template`; a template use takes only `name`, `with`, `for` and `steps` (steps run after the template's own)"),
            ));
        }
    }
    Ok(())
}

/// Refuses a `with:` key at `here` that is not a param of the template `t`.
fn with_known(p: &RawPart, t: &str, tpl: &Template, here: &str) -> Result<()> {
    for key in p.with.keys() {
        if !tpl.raw.params.contains_key(key) {
            let known: Vec<&str> = tpl.raw.params.keys().map(String::as_str).collect();
            return Err(Error::input(
                [here, key!(p.with), key].join("."),
                if known.is_empty() {
                    format!("template `{t}` has no params")
                } else {
                    format!(
                        "template `{t}` has no param `{key}`; its params are {}",
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
                if v.is_empty() {
                    return Err(Error::input(at, "expected at least one value"));
                }
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

/// The values of `"a..b"` or `"a..b:step"`: a, a + step, … up to b
/// included (within 1e-9 of a step, so 0..1:0.1 ends at 1).
fn range(s: &str, params: &Params, place: &str) -> Result<Vec<f64>> {
    let not_range = || {
        Error::input(place, format!("`{s}` is not a range; expected \"a..b\" or \"a..b:step\" (b included), or a list [v1, v2, …]"))
    };
    let (a, rest) = s.split_once("..").ok_or_else(not_range)?;
    let (b, step) = match rest.split_once(':') {
        Some((b, st)) => (b, Some(st)),
        None => (rest, None),
    };
    if a.trim().is_empty() || b.trim().is_empty() {
        return Err(not_range());
    }
    let a = expr::eval_const(a, params).map_err(|e| e.at(place))?;
    let b = expr::eval_const(b, params).map_err(|e| e.at(place))?;
    let step = match step {
        Some(st) => expr::eval_const(st, params).map_err(|e| e.at(place))?,
        None => 1.0,
    };
    if step == 0.0 {
        return Err(Error::input(
            place,
            format!("the step of `{s}` is 0; expected a step that moves from a to b"),
        ));
    }
    let span = (b - a) / step;
    if span < -1e-9 {
        return Err(Error::input(place, format!(
            "`{s}` is empty: from {} the step {} never reaches {}; expected a step with the sign of b - a",
            fmt_value(a),
            fmt_value(step),
            fmt_value(b)
        )));
    }
    let n = libm::floor(span + 1e-9 * span.abs().max(1.0)) + 1.0;
    if !n.is_finite() || n > MAX_PARTS as f64 {
        return Err(Error::input(place, format!(
            "`{s}` has {} values, more than the limit of {MAX_PARTS} parts in a recipe; expected a shorter range or a larger step",
            if n.is_finite() { format!("{n}") } else { "endless".into() }
        )));
    }
    Ok((0..n as usize).map(|k| a + k as f64 * step).collect())
}

/// A number of a template's `with:` or a loop's list, evaluated in `params`.
fn eval(n: &Num, params: &Params, place: &str) -> Result<f64> {
    let v = crate::recipe::eval::eval(n, params, place)?;
    crate::recipe::eval::finite(v, place)
}

/// `name` with each `{EXPR}` replaced by the expression's value in `params`
/// (integers without decimals, others with up to 6).
pub(crate) fn fill_name(name: &str, params: &Params, place: &str) -> Result<String> {
    let mut out = String::with_capacity(name.len());
    let mut rest = name;
    while let Some(open) = rest.find('{') {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let close = after.find('}').ok_or_else(|| {
            Error::input(
                place,
                format!(
                    "the name {name:?} has a `{{` without its `}}`; expected `{{EXPR}}`, e.g. `ring-{{k}}`"
                ),
            )
        })?;
        let src = &after[..close];
        let v = expr::eval_const(src, params)
            .map_err(|m| Error::input(place, format!("in the name {name:?}: {m}")))?;
        out.push_str(&fmt_value(v));
        rest = &after[close + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

/// Refuses names that would break the G-code comment they are written into.
pub(crate) fn check_name(name: &str, place: &str) -> Result<()> {
    crate::base::safe_text::check(place, name)
}

/// A value in a name or a place: integers without decimals, others with up
/// to 6, never `-0`.
pub(crate) fn fmt_value(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        let s = format!("{v:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".into()
        } else {
            s.to_string()
        }
    }
}

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
        assert!(range("3..1", &p, "for.k")
            .unwrap_err()
            .message
            .contains("empty"));
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
