//! The slicers' macro language of start and end G-code templates: the
//! placeholder language of PrusaSlicer, which SuperSlicer, OrcaSlicer and
//! Bambu Studio share, written anew from its documentation (help.prusa3d.com,
//! "Macros") and PrusaSlicer 2.9's grammar, and checked against what the
//! makers' current presets use.
//!
//! A template is text with three constructs:
//! - `[name]`, `[name[index]]`, `[name_N]`: a variable as the slicer writes
//!   it (a list's element at the current extruder, 0, unless indexed);
//! - `{code}`: statements separated by `;` — an expression (its value is
//!   written), `local name = …` and `global name = …` (a new variable of
//!   this expansion, or of every later one given the same globals), an
//!   assignment `name = …` or `name[i] = …` to one of those, or
//!   `name[i] = number` to one of the slicer's output vectors
//!   (`e_retracted`, `e_restart_extra`, `position`, `e_position`, which it
//!   reads back); a right side may be a vector `(a, b, …)` or
//!   `repeat(n, value)`;
//! - `{if c}…{elsif c}…{else}…{endif}`: the text of the first true branch,
//!   anywhere in the text or inside code (`{if c then …; else …; endif}`,
//!   `{local t = 1; if t > 0}…{endif}`).
//!
//! Expressions: numbers (`3` is an integer, `3.0` a real), `"strings"`,
//! `true`/`false`, variables, `name[expression]` (an index past a vector's
//! end reads its first element, as PrusaSlicer's parser does), `+ - * / %` (integer
//! division of two integers, as C's; `+` joins strings), the comparisons
//! `< > <= >= == != <>` (reals equal within 1e-8, a string compared with
//! anything as text), the match `=~ /re/` and `!~` (the whole string),
//! `not`/`!`, `and`/`&&`, `or`/`||`, `c ? a : b` — the shared operators of
//! [`crate::base::grammar`] — and the functions `min(a, b)`, `max(a, b)`,
//! `int` (toward zero), `round` (half away from zero), `digits(x, n[, d])`
//! and `zdigits` (`x` in `n` characters, spaces or zeros before it, `d`
//! decimals or rounded to an integer), `random(lo, hi)` (an integer in
//! lo..=hi when both are, else a real in [lo, hi)), `is_nil(v)`,
//! `size(v)`, `empty(v)`, `one_of(s, "a", /re/, ~"re", …)` and
//! `interpolate_table(x, (x0, y0), (x1, y1), …)`. A real is written as
//! C++'s `ostream` writes a double (six significant digits, no trailing
//! zeros: `0.2`, `215`, `1.23457e+06`).
//!
//! `random` is deterministic: SplitMix64 seeded with the FNV-1a hash of the
//! template's text, its numbers drawn in the order the expansion meets the
//! calls, so the same template gives the same bytes on every run.
//!
//! Pure and bounded: text and variables in, text out. An unknown variable,
//! a type that does not fit or a syntax error is a [`MacroError`] naming
//! the template's line and column; nothing is left unexpanded or silently
//! empty. Parsing is linear in the text; the tree is at most
//! `parse::MAX_DEPTH` deep however the text nests or chains; each distinct
//! pattern is compiled once, at most 64 of them per template, each capped
//! in size; an expansion writes at most 4 MiB and takes at most
//! `eval::MAX_WORK` steps.

mod eval;
mod lex;
mod parse;
#[cfg(test)]
mod tests;

use std::collections::BTreeMap;

/// A variable's or an expression's value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    /// `true` or `false` (a legacy `[name]` writes `1` or `0`, as slicers do).
    Bool(bool),
    /// An integer.
    Int(i64),
    /// A real number.
    Float(f64),
    /// A real number written as the given text when it stands alone (a
    /// value p3dp formats itself, e.g. a position with three decimals); in
    /// arithmetic, the number.
    Shown(f64, String),
    /// Text.
    Str(String),
    /// A list (one element per extruder, or a point's coordinates).
    List(Vec<Value>),
    /// An optional setting left undefined (PrusaSlicer's `nil`), which
    /// `is_nil` tells.
    Nil,
}

/// The variables of a template, by name.
pub(crate) type Vars = BTreeMap<String, Value>;

/// Why a template could not be expanded: its 1-based line and column and
/// what went wrong.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct MacroError {
    /// Line of the template, 1-based.
    pub(crate) line: usize,
    /// Column of the line, in characters, 1-based.
    pub(crate) column: usize,
    /// What went wrong, naming the variable or construct, and the column.
    pub(crate) message: String,
}

impl MacroError {
    /// The error `what` at `line` and `column`.
    fn new(line: usize, column: usize, what: String) -> MacroError {
        MacroError {
            line,
            column,
            message: format!("{what} (column {column})"),
        }
    }
}

impl Value {
    /// The number in a numeric value.
    fn number(&self) -> Option<f64> {
        match *self {
            Value::Int(i) => Some(i as f64),
            Value::Float(f) | Value::Shown(f, _) => Some(f),
            _ => None,
        }
    }

    /// The type's name in messages.
    fn kind(&self) -> &'static str {
        match self {
            Value::Bool(_) => "a boolean",
            Value::Int(_) => "an integer",
            Value::Float(_) | Value::Shown(..) => "a real number",
            Value::Str(_) => "a string",
            Value::List(_) => "a list",
            Value::Nil => "nil",
        }
    }

    /// The value as `{…}` writes it.
    pub(crate) fn text(&self) -> String {
        match self {
            Value::Bool(b) => b.to_string(),
            Value::Int(i) => i.to_string(),
            Value::Float(f) => fmt_g(*f),
            Value::Shown(_, s) | Value::Str(s) => s.clone(),
            Value::List(v) => v.iter().map(Value::text).collect::<Vec<_>>().join(","),
            Value::Nil => "nil".into(),
        }
    }

    /// The value as a legacy `[name]` writes it (a boolean as `1` or `0`).
    fn legacy_text(&self) -> String {
        match self {
            Value::Bool(b) => if *b { "1" } else { "0" }.to_string(),
            v => v.text(),
        }
    }
}

/// `x` as C++'s default `ostream << double` writes it (`%g`: six significant
/// digits, trailing zeros dropped, an exponent outside 1e-4 ≤ |x| < 1e6).
pub(crate) fn fmt_g(x: f64) -> String {
    if !x.is_finite() {
        return if x.is_nan() {
            "nan".into()
        } else if x > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        };
    }
    if x == 0.0 {
        return if x.is_sign_negative() { "-0" } else { "0" }.into();
    }
    // the exponent after rounding to six significant digits
    let sci = format!("{x:.5e}");
    let (mant, exp) = sci.split_once('e').expect("`e` formatting has an exponent");
    let exp: i32 = exp.parse().expect("an integer exponent");
    let strip = |s: &str| {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s.to_string()
        }
    };
    if !(-4..6).contains(&exp) {
        let sign = if exp < 0 { '-' } else { '+' };
        format!("{}e{sign}{:02}", strip(mant), exp.abs())
    } else {
        let decimals = (5 - exp).max(0) as usize;
        strip(&format!("{x:.decimals$}"))
    }
}

/// A parsed template.
#[derive(Clone, Debug)]
pub(crate) struct Template {
    nodes: Vec<parse::Node>,
    /// The `/patterns/` of the template, compiled once each.
    patterns: Vec<regex::Regex>,
    src: String,
    lines: lex::Lines,
    /// The seed of `random`: the FNV-1a hash of the text.
    seed: u64,
}

/// FNV-1a, 64 bits: `h = (h xor byte) * 0x100000001b3` from 0xcbf29ce484222325.
fn fnv1a(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

impl Template {
    /// Parses `text`; a syntax error names its line and column.
    pub(crate) fn parse(text: &str) -> Result<Template, MacroError> {
        let lines = lex::Lines::new(text);
        let mut p = parse::Parser::new(text, &lines);
        let (nodes, end) = p.block()?;
        if let Some((word, at)) = end {
            return Err(p.lex.error(at, format!("`{{{word}}}` without an `{{if}}`")));
        }
        let patterns = std::mem::take(&mut p.patterns);
        Ok(Template {
            nodes,
            patterns,
            src: text.to_string(),
            lines,
            seed: fnv1a(text),
        })
    }

    /// The text with every construct expanded from `vars`.
    #[cfg(any(test, feature = "testing"))]
    pub(crate) fn expand(&self, vars: &Vars) -> Result<String, MacroError> {
        self.expand_with(vars, &mut Vars::new())
    }

    /// [`Template::expand`] with the `global` variables of the templates
    /// expanded before it (a start G-code's, for its end G-code), which it
    /// may read and add to.
    #[cfg(any(test, feature = "testing"))]
    pub(crate) fn expand_with(
        &self,
        vars: &Vars,
        globals: &mut Vars,
    ) -> Result<String, MacroError> {
        self.expand_io(vars, globals).map(|(out, _)| out)
    }

    /// [`Template::expand_with`], and the slicer's output variables the
    /// template assigned (`e_retracted`, `e_restart_extra`, `position`,
    /// `e_position`: PrusaSlicer reads them back after a custom G-code),
    /// each with every element, those not assigned as `vars` gave them.
    pub(crate) fn expand_io(
        &self,
        vars: &Vars,
        globals: &mut Vars,
    ) -> Result<(String, Vars), MacroError> {
        let mut run = eval::Run::new(self, vars, globals);
        run.nodes(&self.nodes)?;
        Ok((
            std::mem::take(&mut run.out),
            std::mem::take(&mut run.outputs),
        ))
    }

    /// The names the template's `global` statements make (a later template
    /// expanded with the same globals may read them).
    pub(crate) fn globals(&self) -> Vec<String> {
        fn walk(nodes: &[parse::Node], out: &mut Vec<String>) {
            for n in nodes {
                match n {
                    parse::Node::Stmt(parse::Stmt::New {
                        global: true, name, ..
                    }) if !out.contains(name) => out.push(name.clone()),
                    parse::Node::If(arms, other) => {
                        arms.iter().for_each(|(_, b)| walk(b, out));
                        walk(other, out);
                    }
                    _ => {}
                }
            }
        }
        let mut out = Vec::new();
        walk(&self.nodes, &mut out);
        out
    }

    /// Every variable the template reads from outside, in any branch, with
    /// the line of its first use, in order of appearance (those its own
    /// `local` and `global` statements make are its own).
    pub(crate) fn variables(&self) -> Vec<(String, usize)> {
        let mut own = std::collections::HashSet::new();
        own_names(&self.nodes, &mut own);
        let mut out: Vec<(String, usize)> = Vec::new();
        let mut seen = std::collections::HashSet::new();
        let mut add = |name: &str, at: usize| {
            if !own.contains(name) && seen.insert(name.to_string()) {
                out.push((name.to_string(), self.lines.locate(&self.src, at).0));
            }
        };
        walk_nodes(&self.nodes, &mut add);
        out
    }
}

#[cfg(test)]
/// Parses and expands `text` in one step.
pub(crate) fn expand(text: &str, vars: &Vars) -> Result<String, MacroError> {
    Template::parse(text)?.expand(vars)
}

/// The names `local` and `global` statements make, anywhere.
fn own_names(nodes: &[parse::Node], own: &mut std::collections::HashSet<String>) {
    for n in nodes {
        match n {
            parse::Node::Stmt(parse::Stmt::New { name, .. }) => {
                own.insert(name.clone());
            }
            parse::Node::If(arms, other) => {
                arms.iter().for_each(|(_, b)| own_names(b, own));
                own_names(other, own);
            }
            _ => {}
        }
    }
}

/// Each variable `nodes` read, with its byte.
fn walk_nodes(nodes: &[parse::Node], add: &mut impl FnMut(&str, usize)) {
    use parse::{Init, LegacyIndex, Node, Stmt};
    let init = |i: &Init, add: &mut dyn FnMut(&str, usize)| match i {
        Init::Expr(e) => e.walk(&mut |n: &str, a| add(n, a)),
        Init::List(items, _) => items
            .iter()
            .for_each(|e| e.walk(&mut |n: &str, a| add(n, a))),
        Init::Repeat(a, b) => {
            a.walk(&mut |n: &str, k| add(n, k));
            b.walk(&mut |n: &str, k| add(n, k));
        }
    };
    for n in nodes {
        match n {
            Node::Text(_) => {}
            Node::Legacy(name, idx, at) => {
                add(name, *at);
                if let Some(LegacyIndex::Var(v)) = idx {
                    add(v, *at);
                }
            }
            Node::Stmt(Stmt::Output(e)) => e.walk(add),
            Node::Stmt(Stmt::New { init: i, .. }) => init(i, add),
            Node::Stmt(Stmt::Assign { index, init: i, .. }) => {
                if let Some(e) = index {
                    e.walk(add);
                }
                init(i, add);
            }
            Node::If(arms, other) => {
                for (c, body) in arms {
                    c.walk(add);
                    walk_nodes(body, add);
                }
                walk_nodes(other, add);
            }
        }
    }
}
