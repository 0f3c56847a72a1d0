//! The slicers' macro language of start and end G-code templates: the
//! placeholder language of PrusaSlicer, which SuperSlicer, OrcaSlicer and
//! Bambu Studio share, written anew from its documentation (help.prusa3d.com,
//! "Macros") and checked against what PrusaSlicer writes.
//!
//! A template is text with three constructs:
//! - `[name]`, `[name[index]]`, `[name_N]`: a variable as the slicer writes
//!   it (a list's element at the current extruder, 0, unless indexed);
//! - `{expression}`: a value or an expression (below);
//! - `{if c}…{elsif c}…{else}…{endif}`: the text of the first true branch.
//!
//! Expressions: numbers (`3` is an integer, `3.0` a real), `"strings"`,
//! `true`/`false`, variables and `name[expression]`, `+ - * / %` (integer
//! division of two integers, as C's; `+` joins strings), comparisons
//! `< > <= >= == != <>`, the regular-expression match `=~ /re/` and `!~`,
//! `not`/`!`, `and`/`&&`, `or`/`||`, `c ? a : b`, and the functions `min`,
//! `max`, `int` (toward zero), `round` (half away from zero), `digits(x, n,
//! d)` and `zdigits(x, n, d)` (`d` decimals, padded to `n` characters with
//! spaces or zeros). A real is written as C++'s `ostream` writes a double
//! (six significant digits, no trailing zeros: `0.2`, `215`, `1.23457e+06`).
//!
//! Pure: text and variables in, text out. An unknown variable, a type that
//! does not fit or a syntax error is a [`MacroError`] naming the template's
//! line; nothing is left unexpanded or silently empty.

use std::collections::BTreeMap;

/// A variable's or an expression's value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
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
}

/// The variables of a template, by name.
pub(crate) type Vars = BTreeMap<String, Value>;

/// Why a template could not be expanded: its 1-based line and what went wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct MacroError {
    /// Line of the template, 1-based.
    pub line: usize,
    /// What went wrong, naming the variable or construct.
    pub message: String,
}

/// Deepest nesting of expressions and `{if}` blocks accepted (a template is
/// a few dozen lines; a hostile one must not exhaust the stack).
const MAX_DEPTH: usize = 64;

/// Largest compiled regular expression of `=~`, bytes.
const REGEX_SIZE: usize = 1 << 20;

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
        }
    }

    /// The value as `{…}` writes it.
    pub fn text(&self) -> String {
        match self {
            Value::Bool(b) => b.to_string(),
            Value::Int(i) => i.to_string(),
            Value::Float(f) => fmt_g(*f),
            Value::Shown(_, s) | Value::Str(s) => s.clone(),
            Value::List(v) => v.iter().map(Value::text).collect::<Vec<_>>().join(","),
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
pub struct Template {
    nodes: Vec<Node>,
}

#[derive(Clone, Debug)]
enum Node {
    Text(String),
    /// `{expression}`
    Expr(Expr),
    /// `[name]`, `[name[index]]`, `[name_N]`
    Legacy(String, Option<LegacyIndex>, usize),
    /// `{if}` arms, then `{else}` (empty without it)
    If(Vec<(Expr, Vec<Node>)>, Vec<Node>),
}

#[derive(Clone, Debug)]
enum LegacyIndex {
    Number(usize),
    Var(String),
}

#[derive(Clone, Debug)]
enum Expr {
    Lit(Value),
    Var(String, usize),
    Index(String, Box<Expr>, usize),
    Not(Box<Expr>, usize),
    Neg(Box<Expr>, usize),
    Bin(Op, Box<Expr>, Box<Expr>, usize),
    Cond(Box<Expr>, Box<Expr>, Box<Expr>, usize),
    Match(Box<Expr>, regex::Regex, bool, usize),
    Call(Func, Vec<Expr>, usize),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Or,
    And,
    Eq,
    Ne,
    Lt,
    Gt,
    Le,
    Ge,
    Add,
    Sub,
    Mul,
    Div,
    Mod,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Func {
    Min,
    Max,
    Int,
    Round,
    Digits,
    Zdigits,
}

impl Template {
    /// Parses `text`; a syntax error names its line.
    pub fn parse(text: &str) -> Result<Template, MacroError> {
        let mut p = Parser {
            s: text.as_bytes(),
            src: text,
            pos: 0,
            depth: 0,
        };
        let (nodes, end) = p.block()?;
        match end {
            None => Ok(Template { nodes }),
            Some((word, at)) => Err(p.error_at(at, format!("`{{{word}}}` without an `{{if}}`"))),
        }
    }

    /// The text with every construct expanded from `vars`.
    pub fn expand(&self, vars: &Vars) -> Result<String, MacroError> {
        let mut out = String::new();
        expand_nodes(&self.nodes, vars, &mut out)?;
        Ok(out)
    }

    /// Every variable the template names, in any branch, with the line of
    /// its first use, in order of appearance.
    pub fn variables(&self) -> Vec<(String, usize)> {
        let mut out: Vec<(String, usize)> = Vec::new();
        let mut add = |name: &str, line: usize| {
            if !out.iter().any(|(n, _)| n == name) {
                out.push((name.to_string(), line));
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

fn walk_nodes(nodes: &[Node], add: &mut impl FnMut(&str, usize)) {
    for n in nodes {
        match n {
            Node::Text(_) => {}
            Node::Expr(e) => walk_expr(e, add),
            Node::Legacy(name, idx, line) => {
                add(name, *line);
                if let Some(LegacyIndex::Var(v)) = idx {
                    add(v, *line);
                }
            }
            Node::If(arms, other) => {
                for (c, body) in arms {
                    walk_expr(c, add);
                    walk_nodes(body, add);
                }
                walk_nodes(other, add);
            }
        }
    }
}

fn walk_expr(e: &Expr, add: &mut impl FnMut(&str, usize)) {
    match e {
        Expr::Lit(_) => {}
        Expr::Var(n, line) => add(n, *line),
        Expr::Index(n, i, line) => {
            add(n, *line);
            walk_expr(i, add);
        }
        Expr::Not(a, _) | Expr::Neg(a, _) | Expr::Match(a, ..) => walk_expr(a, add),
        Expr::Bin(_, a, b, _) => {
            walk_expr(a, add);
            walk_expr(b, add);
        }
        Expr::Cond(c, a, b, _) => {
            walk_expr(c, add);
            walk_expr(a, add);
            walk_expr(b, add);
        }
        Expr::Call(_, args, _) => args.iter().for_each(|a| walk_expr(a, add)),
    }
}

fn expand_nodes(nodes: &[Node], vars: &Vars, out: &mut String) -> Result<(), MacroError> {
    for n in nodes {
        match n {
            Node::Text(t) => out.push_str(t),
            Node::Expr(e) => out.push_str(&eval(e, vars)?.text()),
            Node::Legacy(name, idx, line) => out.push_str(&legacy(name, idx, *line, vars)?),
            Node::If(arms, other) => {
                let mut taken = None;
                for (c, body) in arms {
                    if truth(c, vars)? {
                        taken = Some(body);
                        break;
                    }
                }
                expand_nodes(taken.unwrap_or(other), vars, out)?;
            }
        }
    }
    Ok(())
}

fn unknown(name: &str, line: usize) -> MacroError {
    MacroError {
        line,
        message: format!("unknown variable `{name}`"),
    }
}

fn lookup<'v>(name: &str, line: usize, vars: &'v Vars) -> Result<&'v Value, MacroError> {
    vars.get(name).ok_or_else(|| unknown(name, line))
}

/// A legacy `[name]`: a list's element at the index (0 by default), as
/// the slicer writes the option; `[name_N]` when `name_N` is no variable.
fn legacy(
    name: &str,
    idx: &Option<LegacyIndex>,
    line: usize,
    vars: &Vars,
) -> Result<String, MacroError> {
    let (value, index) = match (vars.get(name), idx) {
        (Some(v), None) => (v, 0),
        (Some(v), Some(LegacyIndex::Number(i))) => (v, *i),
        (Some(v), Some(LegacyIndex::Var(iv))) => {
            let i = lookup(iv, line, vars)?;
            (v, as_index(i, iv, line)?)
        }
        (None, None) => {
            // `[temperature_1]`: the list `temperature` at 1
            let split = name
                .rsplit_once('_')
                .and_then(|(n, i)| Some((n, i.parse::<usize>().ok()?)));
            match split.and_then(|(n, i)| Some((vars.get(n)?, i))) {
                Some(found) => found,
                None => return Err(unknown(name, line)),
            }
        }
        (None, Some(_)) => return Err(unknown(name, line)),
    };
    match value {
        Value::List(items) => items
            .get(index)
            .map(Value::legacy_text)
            .ok_or_else(|| MacroError {
                line,
                message: format!(
                    "`{name}` has {} element{}, no index {index}",
                    items.len(),
                    if items.len() == 1 { "" } else { "s" }
                ),
            }),
        v if idx.is_none() || index == 0 => Ok(v.legacy_text()),
        _ => Err(MacroError {
            line,
            message: format!("`{name}` is not a list; it cannot be indexed"),
        }),
    }
}

fn as_index(v: &Value, what: &str, line: usize) -> Result<usize, MacroError> {
    match *v {
        Value::Int(i) if i >= 0 => Ok(i as usize),
        _ => Err(MacroError {
            line,
            message: format!(
                "the index `{what}` is {}, expected an integer ≥ 0",
                v.kind()
            ),
        }),
    }
}

fn truth(e: &Expr, vars: &Vars) -> Result<bool, MacroError> {
    match eval(e, vars)? {
        Value::Bool(b) => Ok(b),
        v => Err(MacroError {
            line: e.line(),
            message: format!("a condition is {}, expected a boolean", v.kind()),
        }),
    }
}

impl Expr {
    fn line(&self) -> usize {
        match self {
            Expr::Lit(_) => 0,
            Expr::Var(_, l)
            | Expr::Index(_, _, l)
            | Expr::Not(_, l)
            | Expr::Neg(_, l)
            | Expr::Bin(_, _, _, l)
            | Expr::Cond(_, _, _, l)
            | Expr::Match(_, _, _, l)
            | Expr::Call(_, _, l) => *l,
        }
    }
}

fn type_error(line: usize, message: String) -> MacroError {
    MacroError { line, message }
}

fn eval(e: &Expr, vars: &Vars) -> Result<Value, MacroError> {
    match e {
        Expr::Lit(v) => Ok(v.clone()),
        Expr::Var(name, line) => match lookup(name, *line, vars)? {
            // a list where one value is wanted: the current extruder's (0)
            Value::List(items) => items
                .first()
                .cloned()
                .ok_or_else(|| type_error(*line, format!("`{name}` is an empty list"))),
            v => Ok(v.clone()),
        },
        Expr::Index(name, index, line) => {
            let i = eval(index, vars)?;
            let i = as_index(&i, name, *line)?;
            match lookup(name, *line, vars)? {
                Value::List(items) => items.get(i).cloned().ok_or_else(|| {
                    type_error(
                        *line,
                        if items.len() == 1 {
                            // the per-extruder lists: p3dp gives tool 0 only
                            format!("`{name}[{i}]`: `{name}` is a value per extruder and p3dp drives one (index 0 only); a preset for several extruders or a filament changer needs its single-extruder variant")
                        } else {
                            format!("`{name}` has {} elements, no index {i}", items.len())
                        },
                    )
                }),
                v if i == 0 => Ok(v.clone()),
                _ => Err(type_error(
                    *line,
                    format!("`{name}` is not a list; it cannot be indexed"),
                )),
            }
        }
        Expr::Not(a, _) => Ok(Value::Bool(!truth(a, vars)?)),
        Expr::Neg(a, line) => match eval(a, vars)? {
            Value::Int(i) => Ok(Value::Int(i.wrapping_neg())),
            v => match v.number() {
                Some(f) => Ok(Value::Float(-f)),
                None => Err(type_error(*line, format!("cannot negate {}", v.kind()))),
            },
        },
        Expr::Bin(op, a, b, line) => binary(*op, a, b, *line, vars),
        Expr::Cond(c, a, b, _) => {
            if truth(c, vars)? {
                eval(a, vars)
            } else {
                eval(b, vars)
            }
        }
        Expr::Match(a, re, negate, line) => match eval(a, vars)? {
            Value::Str(s) => Ok(Value::Bool(re.is_match(&s) != *negate)),
            v => Err(type_error(
                *line,
                format!("`=~` matches a string, not {}", v.kind()),
            )),
        },
        Expr::Call(f, args, line) => call(*f, args, *line, vars),
    }
}

fn binary(op: Op, a: &Expr, b: &Expr, line: usize, vars: &Vars) -> Result<Value, MacroError> {
    // `and` and `or` look at their right side only when they must
    match op {
        Op::And => return Ok(Value::Bool(truth(a, vars)? && truth(b, vars)?)),
        Op::Or => return Ok(Value::Bool(truth(a, vars)? || truth(b, vars)?)),
        _ => {}
    }
    let (x, y) = (eval(a, vars)?, eval(b, vars)?);
    match op {
        Op::Eq | Op::Ne | Op::Lt | Op::Gt | Op::Le | Op::Ge => compare(op, &x, &y, line),
        Op::Add if matches!(x, Value::Str(_)) || matches!(y, Value::Str(_)) => {
            Ok(Value::Str(x.text() + &y.text()))
        }
        _ => arithmetic(op, &x, &y, line),
    }
}

fn compare(op: Op, x: &Value, y: &Value, line: usize) -> Result<Value, MacroError> {
    let ord = match (x, y) {
        (Value::Str(a), Value::Str(b)) => a.cmp(b),
        (Value::Bool(a), Value::Bool(b)) if matches!(op, Op::Eq | Op::Ne) => a.cmp(b),
        _ => match (x.number(), y.number()) {
            (Some(a), Some(b)) => a.partial_cmp(&b).ok_or_else(|| {
                type_error(line, "a comparison with a number that is not one".into())
            })?,
            _ => {
                return Err(type_error(
                    line,
                    format!("cannot compare {} with {}", x.kind(), y.kind()),
                ))
            }
        },
    };
    use std::cmp::Ordering::*;
    Ok(Value::Bool(match op {
        Op::Eq => ord == Equal,
        Op::Ne => ord != Equal,
        Op::Lt => ord == Less,
        Op::Gt => ord == Greater,
        Op::Le => ord != Greater,
        _ => ord != Less,
    }))
}

fn arithmetic(op: Op, x: &Value, y: &Value, line: usize) -> Result<Value, MacroError> {
    let sym = match op {
        Op::Add => "+",
        Op::Sub => "-",
        Op::Mul => "*",
        Op::Div => "/",
        _ => "%",
    };
    let bad = || {
        type_error(
            line,
            format!("cannot apply `{sym}` to {} and {}", x.kind(), y.kind()),
        )
    };
    if let (Value::Int(a), Value::Int(b)) = (x, y) {
        let (a, b) = (*a, *b);
        if matches!(op, Op::Div | Op::Mod) && b == 0 {
            return Err(type_error(line, "division by zero".into()));
        }
        return match op {
            Op::Add => a.checked_add(b),
            Op::Sub => a.checked_sub(b),
            Op::Mul => a.checked_mul(b),
            Op::Div => a.checked_div(b),
            _ => a.checked_rem(b),
        }
        .map(Value::Int)
        .ok_or_else(|| type_error(line, format!("an integer overflow in `{sym}`")));
    }
    let (a, b) = (x.number().ok_or_else(bad)?, y.number().ok_or_else(bad)?);
    if matches!(op, Op::Div | Op::Mod) && b == 0.0 {
        return Err(type_error(line, "division by zero".into()));
    }
    Ok(Value::Float(match op {
        Op::Add => a + b,
        Op::Sub => a - b,
        Op::Mul => a * b,
        Op::Div => a / b,
        _ => libm::fmod(a, b),
    }))
}

fn call(f: Func, args: &[Expr], line: usize, vars: &Vars) -> Result<Value, MacroError> {
    let vals = args
        .iter()
        .map(|a| eval(a, vars))
        .collect::<Result<Vec<_>, _>>()?;
    let num = |k: usize| {
        vals[k].number().ok_or_else(|| {
            type_error(
                line,
                format!(
                    "argument {} is {}, expected a number",
                    k + 1,
                    vals[k].kind()
                ),
            )
        })
    };
    match f {
        Func::Min | Func::Max => {
            let (a, b) = (num(0)?, num(1)?);
            let first = (a < b) == (f == Func::Min);
            if let (Value::Int(x), Value::Int(y)) = (&vals[0], &vals[1]) {
                return Ok(Value::Int(if first { *x } else { *y }));
            }
            Ok(Value::Float(if first { a } else { b }))
        }
        Func::Int => Ok(Value::Int(to_int(libm::trunc(num(0)?), line)?)),
        Func::Round => Ok(Value::Int(to_int(libm::round(num(0)?), line)?)),
        Func::Digits | Func::Zdigits => {
            let x = num(0)?;
            let width = num(1)?;
            let decimals = if vals.len() > 2 { num(2)? } else { 0.0 };
            if !(0.0..=64.0).contains(&width) || !(0.0..=20.0).contains(&decimals) {
                return Err(type_error(
                    line,
                    "digits() takes a width of 0 to 64 and 0 to 20 decimals".into(),
                ));
            }
            let (w, d) = (width as usize, decimals as usize);
            Ok(Value::Str(if f == Func::Zdigits {
                format!("{x:0w$.d$}")
            } else {
                format!("{x:w$.d$}")
            }))
        }
    }
}

fn to_int(x: f64, line: usize) -> Result<i64, MacroError> {
    if x.is_finite() && x.abs() < 9.0e18 {
        Ok(x as i64)
    } else {
        Err(type_error(line, format!("{} is no integer", fmt_g(x))))
    }
}

/// The template parser: text, `[…]` and `{…}` over bytes (every construct
/// starts and ends at an ASCII byte, so slices stay on char boundaries).
struct Parser<'a> {
    s: &'a [u8],
    src: &'a str,
    pos: usize,
    depth: usize,
}

/// A token of an expression.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(Value),
    Str(String),
    Ident(String),
    Sym(&'static str),
    Close,
    End,
}

const SYMBOLS: [&str; 24] = [
    "==", "!=", "<>", "<=", ">=", "=~", "!~", "&&", "||", "<", ">", "+", "-", "*", "/", "%", "(",
    ")", "[", "]", ",", "?", ":", "!",
];

impl<'a> Parser<'a> {
    fn line_at(&self, at: usize) -> usize {
        1 + self.s[..at.min(self.s.len())]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }

    fn error_at(&self, at: usize, message: String) -> MacroError {
        MacroError {
            line: self.line_at(at),
            message,
        }
    }

    fn deeper(&mut self) -> Result<(), MacroError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.error_at(self.pos, format!("nested more than {MAX_DEPTH} deep")));
        }
        Ok(())
    }

    /// Nodes up to the end or to an `{elsif}`, `{else}` or `{endif}`, which
    /// is returned with its place (the `{`), not consumed past its keyword.
    #[allow(clippy::type_complexity)]
    fn block(&mut self) -> Result<(Vec<Node>, Option<(&'static str, usize)>), MacroError> {
        self.deeper()?;
        let mut nodes = Vec::new();
        loop {
            let start = self.pos;
            while self.pos < self.s.len() && !matches!(self.s[self.pos], b'[' | b'{') {
                self.pos += 1;
            }
            if self.pos > start {
                nodes.push(Node::Text(self.src[start..self.pos].to_string()));
            }
            if self.pos >= self.s.len() {
                self.depth -= 1;
                return Ok((nodes, None));
            }
            let open = self.pos;
            if self.s[open] == b'[' {
                self.pos += 1;
                nodes.push(self.legacy(open)?);
                continue;
            }
            self.pos += 1;
            let save = self.pos;
            match self.keyword() {
                Some("if") => nodes.push(self.if_block(open)?),
                Some(k @ ("elsif" | "else" | "endif")) => {
                    self.depth -= 1;
                    return Ok((nodes, Some((k, open))));
                }
                _ => {
                    self.pos = save;
                    let line = self.line_at(open);
                    let e = self.expr(line)?;
                    self.expect_close(open)?;
                    nodes.push(Node::Expr(e));
                }
            }
        }
    }

    /// `if`, `elsif`, `else` or `endif` after a `{` (and spaces), consumed
    /// with the spaces after it; `None` (nothing consumed) otherwise.
    fn keyword(&mut self) -> Option<&'static str> {
        let save = self.pos;
        self.skip_space();
        let start = self.pos;
        while self.pos < self.s.len() && is_ident(self.s[self.pos], self.pos > start) {
            self.pos += 1;
        }
        let word = &self.src[start..self.pos];
        for k in ["if", "elsif", "else", "endif"] {
            if word == k {
                self.skip_space();
                return Some(k);
            }
        }
        self.pos = save;
        None
    }

    /// An `{if …}` block from its condition to its `{endif}`.
    fn if_block(&mut self, open: usize) -> Result<Node, MacroError> {
        let mut arms = Vec::new();
        let mut cond_at = open;
        loop {
            let line = self.line_at(cond_at);
            let cond = self.expr(line)?;
            self.expect_close(cond_at)?;
            let (body, end) = self.block()?;
            arms.push((cond, body));
            match end {
                Some(("elsif", at)) => cond_at = at,
                Some(("else", at)) => {
                    self.expect_close(at)?;
                    let (other, end) = self.block()?;
                    return match end {
                        Some(("endif", at)) => {
                            self.expect_close(at)?;
                            Ok(Node::If(arms, other))
                        }
                        Some((k, at)) => {
                            Err(self.error_at(at, format!("`{{{k}}}` after `{{else}}`")))
                        }
                        None => Err(self.error_at(open, "an `{if}` without `{endif}`".into())),
                    };
                }
                Some((_, at)) => {
                    self.expect_close(at)?;
                    return Ok(Node::If(arms, Vec::new()));
                }
                None => return Err(self.error_at(open, "an `{if}` without `{endif}`".into())),
            }
        }
    }

    fn expect_close(&mut self, open: usize) -> Result<(), MacroError> {
        match self.token(false)? {
            Tok::Close => Ok(()),
            t => Err(self.error_at(
                open,
                format!("expected `}}` to close the `{{` here, found {}", shown(&t)),
            )),
        }
    }

    /// A legacy `[name]`, `[name[index]]` after its `[`.
    fn legacy(&mut self, open: usize) -> Result<Node, MacroError> {
        let line = self.line_at(open);
        let name = self.ident();
        let bad = |p: &Parser| {
            p.error_at(
                open,
                "a `[` that starts no variable; expected `[name]` or `[name[index]]`".into(),
            )
        };
        if name.is_empty() {
            return Err(bad(self));
        }
        let mut index = None;
        if self.s.get(self.pos) == Some(&b'[') {
            self.pos += 1;
            let i = self.ident();
            index = Some(if i.is_empty() {
                let start = self.pos;
                while self.s.get(self.pos).is_some_and(u8::is_ascii_digit) {
                    self.pos += 1;
                }
                let n = self.src[start..self.pos].parse().map_err(|_| bad(self))?;
                LegacyIndex::Number(n)
            } else {
                LegacyIndex::Var(i)
            });
            if self.s.get(self.pos) != Some(&b']') {
                return Err(bad(self));
            }
            self.pos += 1;
        }
        if self.s.get(self.pos) != Some(&b']') {
            return Err(bad(self));
        }
        self.pos += 1;
        Ok(Node::Legacy(name, index, line))
    }

    fn ident(&mut self) -> String {
        let start = self.pos;
        while self.pos < self.s.len() && is_ident(self.s[self.pos], self.pos > start) {
            self.pos += 1;
        }
        self.src[start..self.pos].to_string()
    }

    fn skip_space(&mut self) {
        while self.s.get(self.pos).is_some_and(u8::is_ascii_whitespace) {
            self.pos += 1;
        }
    }

    /// The next token; `regex` reads a `/…/` literal as a string.
    fn token(&mut self, regex: bool) -> Result<Tok, MacroError> {
        self.skip_space();
        let Some(&c) = self.s.get(self.pos) else {
            return Ok(Tok::End);
        };
        let at = self.pos;
        if c == b'}' {
            self.pos += 1;
            return Ok(Tok::Close);
        }
        if c == b'"' || (regex && c == b'/') {
            return self.quoted(c, at);
        }
        if c.is_ascii_digit() || (c == b'.' && self.s.get(at + 1).is_some_and(u8::is_ascii_digit)) {
            return self.number(at);
        }
        if is_ident(c, false) {
            return Ok(Tok::Ident(self.ident()));
        }
        for sym in SYMBOLS {
            if self.s[at..].starts_with(sym.as_bytes()) {
                self.pos += sym.len();
                return Ok(Tok::Sym(sym));
            }
        }
        let ch = self.src[at..].chars().next().unwrap_or('?');
        Err(self.error_at(at, format!("unexpected `{ch}` in an expression")))
    }

    /// A `"string"` (`\` escapes the next character) or a `/regex/` (`\/`
    /// is a slash; other escapes are the pattern's).
    fn quoted(&mut self, q: u8, at: usize) -> Result<Tok, MacroError> {
        self.pos += 1;
        let mut out = String::new();
        loop {
            let Some(ch) = self.src[self.pos..].chars().next() else {
                return Err(self.error_at(at, "a string or pattern is never closed".into()));
            };
            self.pos += ch.len_utf8();
            if ch as u32 == q as u32 {
                return Ok(Tok::Str(out));
            }
            if ch == '\\' {
                let Some(next) = self.src[self.pos..].chars().next() else {
                    continue;
                };
                self.pos += next.len_utf8();
                if q == b'/' && next != '/' {
                    out.push('\\');
                }
                out.push(next);
            } else {
                out.push(ch);
            }
        }
    }

    fn number(&mut self, at: usize) -> Result<Tok, MacroError> {
        let digits = |p: &mut Parser| {
            while p.s.get(p.pos).is_some_and(u8::is_ascii_digit) {
                p.pos += 1;
            }
        };
        digits(self);
        let mut real = false;
        if self.s.get(self.pos) == Some(&b'.') {
            real = true;
            self.pos += 1;
            digits(self);
        }
        if matches!(self.s.get(self.pos), Some(b'e' | b'E')) {
            let save = self.pos;
            self.pos += 1;
            if matches!(self.s.get(self.pos), Some(b'+' | b'-')) {
                self.pos += 1;
            }
            if self.s.get(self.pos).is_some_and(u8::is_ascii_digit) {
                real = true;
                digits(self);
            } else {
                self.pos = save;
            }
        }
        let text = &self.src[at..self.pos];
        let bad = |p: &Parser| p.error_at(at, format!("`{text}` is no number"));
        if real {
            Ok(Tok::Num(Value::Float(text.parse().map_err(|_| bad(self))?)))
        } else {
            Ok(Tok::Num(Value::Int(text.parse().map_err(|_| bad(self))?)))
        }
    }

    fn peek(&mut self, regex: bool) -> Result<Tok, MacroError> {
        let save = self.pos;
        let t = self.token(regex);
        self.pos = save;
        t
    }

    /// Consumes the symbol `sym` if it is next.
    fn eat(&mut self, sym: &str) -> Result<bool, MacroError> {
        let save = self.pos;
        match self.token(false)? {
            Tok::Sym(s) if s == sym => Ok(true),
            Tok::Ident(w) if w == sym => Ok(true),
            _ => {
                self.pos = save;
                Ok(false)
            }
        }
    }

    /// `c ? a : b`, or an `or` expression.
    fn expr(&mut self, line: usize) -> Result<Expr, MacroError> {
        self.deeper()?;
        let c = self.or(line)?;
        let e = if self.eat("?")? {
            let a = self.expr(line)?;
            if !self.eat(":")? {
                return Err(self.error_at(self.pos, "a `?` without its `:`".into()));
            }
            let b = self.expr(line)?;
            Expr::Cond(Box::new(c), Box::new(a), Box::new(b), line)
        } else {
            c
        };
        self.depth -= 1;
        Ok(e)
    }

    fn or(&mut self, line: usize) -> Result<Expr, MacroError> {
        let mut a = self.and(line)?;
        while self.eat("or")? || self.eat("||")? {
            let b = self.and(line)?;
            a = Expr::Bin(Op::Or, Box::new(a), Box::new(b), line);
        }
        Ok(a)
    }

    fn and(&mut self, line: usize) -> Result<Expr, MacroError> {
        let mut a = self.equality(line)?;
        while self.eat("and")? || self.eat("&&")? {
            let b = self.equality(line)?;
            a = Expr::Bin(Op::And, Box::new(a), Box::new(b), line);
        }
        Ok(a)
    }

    fn equality(&mut self, line: usize) -> Result<Expr, MacroError> {
        let mut a = self.relational(line)?;
        loop {
            let op = match self.peek(false)? {
                Tok::Sym("==") => Op::Eq,
                Tok::Sym("!=" | "<>") => Op::Ne,
                Tok::Sym(m @ ("=~" | "!~")) => {
                    self.token(false)?;
                    let at = self.pos;
                    let Tok::Str(pattern) = self.token(true)? else {
                        return Err(self.error_at(at, format!("expected /regex/ after `{m}`")));
                    };
                    let re = regex::RegexBuilder::new(&format!("^(?:{pattern})$"))
                        .size_limit(REGEX_SIZE)
                        .build()
                        .map_err(|e| self.error_at(at, format!("bad regular expression: {e}")))?;
                    a = Expr::Match(Box::new(a), re, m == "!~", line);
                    continue;
                }
                _ => return Ok(a),
            };
            self.token(false)?;
            let b = self.relational(line)?;
            a = Expr::Bin(op, Box::new(a), Box::new(b), line);
        }
    }

    fn relational(&mut self, line: usize) -> Result<Expr, MacroError> {
        let mut a = self.additive(line)?;
        loop {
            let op = match self.peek(false)? {
                Tok::Sym("<") => Op::Lt,
                Tok::Sym(">") => Op::Gt,
                Tok::Sym("<=") => Op::Le,
                Tok::Sym(">=") => Op::Ge,
                _ => return Ok(a),
            };
            self.token(false)?;
            let b = self.additive(line)?;
            a = Expr::Bin(op, Box::new(a), Box::new(b), line);
        }
    }

    fn additive(&mut self, line: usize) -> Result<Expr, MacroError> {
        let mut a = self.term(line)?;
        loop {
            let op = match self.peek(false)? {
                Tok::Sym("+") => Op::Add,
                Tok::Sym("-") => Op::Sub,
                _ => return Ok(a),
            };
            self.token(false)?;
            let b = self.term(line)?;
            a = Expr::Bin(op, Box::new(a), Box::new(b), line);
        }
    }

    fn term(&mut self, line: usize) -> Result<Expr, MacroError> {
        let mut a = self.unary(line)?;
        loop {
            let op = match self.peek(false)? {
                Tok::Sym("*") => Op::Mul,
                Tok::Sym("/") => Op::Div,
                Tok::Sym("%") => Op::Mod,
                _ => return Ok(a),
            };
            self.token(false)?;
            let b = self.unary(line)?;
            a = Expr::Bin(op, Box::new(a), Box::new(b), line);
        }
    }

    fn unary(&mut self, line: usize) -> Result<Expr, MacroError> {
        self.deeper()?;
        let e = if self.eat("!")? || self.eat("not")? {
            Expr::Not(Box::new(self.unary(line)?), line)
        } else if self.eat("-")? {
            Expr::Neg(Box::new(self.unary(line)?), line)
        } else if self.eat("+")? {
            self.unary(line)?
        } else {
            self.factor(line)?
        };
        self.depth -= 1;
        Ok(e)
    }

    fn factor(&mut self, line: usize) -> Result<Expr, MacroError> {
        let at = self.pos;
        match self.token(false)? {
            Tok::Num(v) => Ok(Expr::Lit(v)),
            Tok::Str(s) => Ok(Expr::Lit(Value::Str(s))),
            Tok::Sym("(") => {
                let e = self.expr(line)?;
                if !self.eat(")")? {
                    return Err(self.error_at(at, "a `(` without its `)`".into()));
                }
                Ok(e)
            }
            Tok::Ident(w) => self.name(w, line, at),
            t => Err(self.error_at(at, format!("expected a value, found {}", shown(&t)))),
        }
    }

    /// What follows an identifier: a function's call, an index, or nothing.
    fn name(&mut self, w: String, line: usize, at: usize) -> Result<Expr, MacroError> {
        match w.as_str() {
            "true" => return Ok(Expr::Lit(Value::Bool(true))),
            "false" => return Ok(Expr::Lit(Value::Bool(false))),
            _ => {}
        }
        let func = match w.as_str() {
            "min" => Some((Func::Min, 2..=2)),
            "max" => Some((Func::Max, 2..=2)),
            "int" => Some((Func::Int, 1..=1)),
            "round" => Some((Func::Round, 1..=1)),
            "digits" => Some((Func::Digits, 2..=3)),
            "zdigits" => Some((Func::Zdigits, 2..=3)),
            _ => None,
        };
        if let Some((f, arity)) = func {
            if self.eat("(")? {
                let mut args = vec![self.expr(line)?];
                while self.eat(",")? {
                    args.push(self.expr(line)?);
                }
                if !self.eat(")")? {
                    return Err(self.error_at(at, format!("`{w}(` without its `)`")));
                }
                if !arity.contains(&args.len()) {
                    return Err(self.error_at(
                        at,
                        format!(
                            "`{w}` takes {} argument{}, not {}",
                            if arity.start() == arity.end() {
                                arity.start().to_string()
                            } else {
                                format!("{} or {}", arity.start(), arity.end())
                            },
                            if *arity.end() == 1 { "" } else { "s" },
                            args.len()
                        ),
                    ));
                }
                return Ok(Expr::Call(f, args, line));
            }
        }
        if self.eat("[")? {
            let i = self.expr(line)?;
            if !self.eat("]")? {
                return Err(self.error_at(at, format!("`{w}[` without its `]`")));
            }
            return Ok(Expr::Index(w, Box::new(i), line));
        }
        Ok(Expr::Var(w, line))
    }
}

fn is_ident(c: u8, later: bool) -> bool {
    c == b'_' || c.is_ascii_alphabetic() || (later && c.is_ascii_digit())
}

fn shown(t: &Tok) -> String {
    match t {
        Tok::Num(v) => format!("`{}`", v.text()),
        Tok::Str(s) => format!("\"{s}\""),
        Tok::Ident(w) => format!("`{w}`"),
        Tok::Sym(s) => format!("`{s}`"),
        Tok::Close => "`}`".into(),
        Tok::End => "the end of the text".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vars() -> Vars {
        let mut v = Vars::new();
        let f = |x: f64| Value::Float(x);
        v.insert(
            "first_layer_temperature".into(),
            Value::List(vec![f(215.0), f(230.0)]),
        );
        v.insert(
            "first_layer_bed_temperature".into(),
            Value::List(vec![f(60.0)]),
        );
        v.insert("layer_height".into(), f(0.2));
        v.insert("max_layer_z".into(), f(10.4));
        v.insert("max_print_height".into(), f(210.0));
        v.insert("z_offset".into(), f(0.0));
        v.insert("initial_tool".into(), Value::Int(0));
        v.insert("has_wipe_tower".into(), Value::Bool(false));
        v.insert("printer_model".into(), Value::Str("MK3S".into()));
        v.insert(
            "filament_settings_id".into(),
            Value::List(vec![Value::Str("Prusament PA11 Carbon".into())]),
        );
        v.insert("park".into(), Value::Shown(12.3, "12.300".into()));
        v
    }

    fn x(t: &str) -> String {
        expand(t, &vars()).unwrap_or_else(|e| panic!("{t}: {e:?}"))
    }

    #[test]
    fn legacy_and_braced_variables() {
        assert_eq!(x("M104 S[first_layer_temperature]"), "M104 S215");
        assert_eq!(x("M104 S[first_layer_temperature_1]"), "M104 S230");
        assert_eq!(
            x("M104 S[first_layer_temperature[initial_tool]]"),
            "M104 S215"
        );
        assert_eq!(x("M140 S{first_layer_bed_temperature[0]}"), "M140 S60");
        assert_eq!(x("M862.3 P \"[printer_model]\""), "M862.3 P \"MK3S\"");
        assert_eq!(x("[has_wipe_tower] {has_wipe_tower}"), "0 false");
        assert_eq!(x("G1 Z{park}"), "G1 Z12.300");
        assert_eq!(x("G1 Z{park + 1}"), "G1 Z13.3");
    }

    #[test]
    fn arithmetic_and_functions() {
        assert_eq!(
            x("G1 Z{z_offset+min(max_layer_z+1, max_print_height)}"),
            "G1 Z11.4"
        );
        assert_eq!(x("{7/2} {7.0/2} {7%3} {-3/2}"), "3 3.5 1 -1");
        assert_eq!(
            x("{int(2.7)} {round(2.5)} {round(-2.5)} {max(1, 2)}"),
            "2 3 -3 2"
        );
        assert_eq!(
            x("{digits(3.14159, 6, 2)}|{zdigits(3.1, 6, 2)}"),
            "  3.14|003.10"
        );
        assert_eq!(x("{first_layer_temperature[0] * 2/3}"), "143.333");
        assert_eq!(
            x("{1000000.0} {0.0001} {1e-5} {0.1+0.2}"),
            "1e+06 0.0001 1e-05 0.3"
        );
        assert_eq!(x("{\"a\" + 1}"), "a1");
    }

    #[test]
    fn conditions_and_matches() {
        let t = "{if filament_settings_id[initial_tool]=~/.*Prusament PA11.*/}\nA\n{elsif layer_height < 0.1}B{else}\nC\n{endif}\nD";
        assert_eq!(x(t), "\nA\n\nD");
        assert_eq!(
            x("M221 S{if layer_height<0.075}100{else}95{endif}"),
            "M221 S95"
        );
        assert_eq!(
            x("{if not has_wipe_tower and (layer_height > 0.1 or false)}y{endif}"),
            "y"
        );
        assert_eq!(x("{(layer_height > 0.1 ? 230 : 200)}"), "230");
        assert_eq!(x("{layer_height > 0.1 ? \"a\" : \"b\"}"), "a");
        assert_eq!(
            x("{if printer_model == \"MK3S\"}m{endif}{if printer_model != \"MK3S\"}n{endif}"),
            "m"
        );
        assert_eq!(x("{if printer_model !~ /MK.*/}m{else}k{endif}"), "k");
        assert_eq!(x("{if 1 <> 2 && 2 >= 2 || false}t{endif}"), "t");
    }

    #[test]
    fn errors_name_the_line_and_the_variable() {
        let e = expand("G28\nM104 S{hot_end_temp}\n", &vars()).unwrap_err();
        assert_eq!(e.line, 2);
        assert!(e.message.contains("`hot_end_temp`"), "{e:?}");
        let e = expand("G28\n\nM104 S[bed_type]", &vars()).unwrap_err();
        assert_eq!(
            (e.line, e.message.as_str()),
            (3, "unknown variable `bed_type`")
        );
        for bad in [
            "{if layer_height}x{endif}",
            "{if true}x",
            "{else}",
            "{1 +}",
            "M117 [not a var]",
            "{layer_height + \"a\" * 2}",
            "{first_layer_temperature[5]}",
            "{1/0}",
            "{\"abc}",
        ] {
            assert!(expand(bad, &vars()).is_err(), "{bad}");
        }
        // an unknown variable in a branch not taken is still named
        let t = Template::parse("{if false}{bed_type}{endif}[printer_model]").unwrap();
        assert_eq!(t.expand(&vars()).unwrap(), "MK3S");
        let names: Vec<String> = t.variables().into_iter().map(|(n, _)| n).collect();
        assert_eq!(names, ["bed_type", "printer_model"]);
    }

    #[test]
    fn hostile_nesting_is_refused() {
        let deep = format!("{{{}1{}}}", "(".repeat(10_000), ")".repeat(10_000));
        assert!(expand(&deep, &vars()).is_err());
        let ifs = "{if true}".repeat(10_000);
        assert!(expand(&ifs, &vars()).is_err());
    }

    #[test]
    fn reals_print_like_ostream() {
        for (v, s) in [
            (215.0, "215"),
            (0.2, "0.2"),
            (1234567.0, "1.23457e+06"),
            (123456.0, "123456"),
            (0.000012345, "1.2345e-05"),
            (-3.5, "-3.5"),
            (2.0 / 3.0, "0.666667"),
            (999999.5, "1e+06"),
        ] {
            assert_eq!(fmt_g(v), s, "{v}");
        }
    }
}
