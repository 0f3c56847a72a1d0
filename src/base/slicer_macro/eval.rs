//! A parsed template expanded: its text written, its statements run, its
//! expressions evaluated as PrusaSlicer's placeholder parser evaluates
//! them, within bounds on the output, the values and the work.

use std::collections::HashMap;

use super::parse::{Arith, Choice, Expr, Func, Init, Kind, LegacyIndex, Node, Stmt};
use super::{fmt_g, MacroError, Template, Value, Vars};
use crate::base::grammar::{Bin, Cmp};
use crate::base::rng::SplitMix64;

/// Largest expansion, bytes (a maker's start G-code is a few tens of KB).
pub(super) const MAX_OUTPUT: usize = 4 << 20;

/// Longest string value and most elements of a vector value.
pub(super) const MAX_VALUE: usize = 1 << 20;

/// Most steps of one expansion: nodes evaluated, plus the bytes and
/// elements of the values made (no loop exists, but values can be copied
/// and joined).
pub(super) const MAX_WORK: u64 = 50_000_000;

/// Two reals within this are equal to `==` (PrusaSlicer's tolerance).
const EQUAL_WITHIN: f64 = 1e-8;

/// How far outside an `interpolate_table`'s range a value still takes the
/// end's value (PrusaSlicer's EPSILON).
const TABLE_SLACK: f64 = 1e-4;

/// The slicer's variables a template may assign, element by element, which
/// the slicer reads back after it (PrusaSlicer's `output_config`, its
/// `PlaceholderParserIntegration`): where the head is, E's position, and
/// the filament each extruder has retracted (`e_retracted`) and will push
/// back beyond it at the next unretraction (`e_restart_extra`). Every other
/// setting is read-only.
pub(super) const OUTPUTS: [&str; 4] = ["position", "e_position", "e_retracted", "e_restart_extra"];

/// The state of one expansion.
pub(super) struct Run<'t> {
    t: &'t Template,
    vars: &'t Vars,
    globals: &'t mut Vars,
    locals: Vars,
    /// The slicer's output variables the template assigned ([`OUTPUTS`]),
    /// copied from `vars` at the first assignment.
    pub(super) outputs: Vars,
    pub(super) out: String,
    rng: SplitMix64,
    work: u64,
    /// The patterns `one_of`'s `~expr` computed, compiled once each.
    computed: HashMap<String, regex::Regex>,
}

type R<T> = Result<T, MacroError>;

impl<'t> Run<'t> {
    /// An expansion of `t` over `vars` and the `globals` of earlier ones.
    pub(super) fn new(t: &'t Template, vars: &'t Vars, globals: &'t mut Vars) -> Run<'t> {
        Run {
            t,
            vars,
            globals,
            locals: Vars::new(),
            outputs: Vars::new(),
            out: String::new(),
            rng: SplitMix64::new(t.seed),
            work: 0,
            computed: HashMap::new(),
        }
    }

    fn error(&self, at: usize, message: impl Into<String>) -> MacroError {
        let (line, column) = self.t.lines.locate(&self.t.src, at);
        MacroError::new(line, column, message.into())
    }

    /// Counts `n` steps of work at byte `at`.
    fn step(&mut self, n: usize, at: usize) -> R<()> {
        self.work += n as u64;
        if self.work > MAX_WORK {
            return Err(self.error(
                at,
                format!("the template takes more than {MAX_WORK} steps to expand"),
            ));
        }
        Ok(())
    }

    fn write(&mut self, s: &str, at: usize) -> R<()> {
        if self.out.len() + s.len() > MAX_OUTPUT {
            return Err(self.error(
                at,
                format!("the expansion is longer than {MAX_OUTPUT} bytes"),
            ));
        }
        self.out.push_str(s);
        Ok(())
    }

    /// Runs `nodes`.
    pub(super) fn nodes(&mut self, nodes: &'t [Node]) -> R<()> {
        for n in nodes {
            match n {
                Node::Text(s) => self.write(s, 0)?,
                Node::Legacy(name, idx, at) => {
                    let s = self.legacy(name, idx, *at)?;
                    self.write(&s, *at)?;
                }
                Node::Stmt(s) => self.statement(s)?,
                Node::If(arms, other) => {
                    let mut taken = other;
                    for (c, body) in arms {
                        if self.truth(c)? {
                            taken = body;
                            break;
                        }
                    }
                    self.nodes(taken)?;
                }
            }
        }
        Ok(())
    }

    /// A variable by name: a local, a global, then the template's.
    fn lookup(&self, name: &str, at: usize) -> R<&Value> {
        self.locals
            .get(name)
            .or_else(|| self.globals.get(name))
            .or_else(|| self.outputs.get(name))
            .or_else(|| self.vars.get(name))
            .ok_or_else(|| self.error(at, format!("unknown variable `{name}`")))
    }

    fn statement(&mut self, s: &Stmt) -> R<()> {
        match s {
            Stmt::Output(e) => {
                let v = self.eval(e)?;
                if let Value::Nil = v {
                    return Err(self.error(
                        e.at,
                        "a nil value (a setting left undefined) cannot be written",
                    ));
                }
                self.write(&v.text(), e.at)
            }
            Stmt::New {
                global,
                name,
                init,
                at,
            } => {
                let v = self.init(init, *at)?;
                if *global {
                    self.globals.insert(name.clone(), v);
                } else {
                    self.locals.insert(name.clone(), v);
                }
                Ok(())
            }
            Stmt::Assign {
                name,
                index,
                init,
                at,
            } => self.assign(name, index.as_ref(), init, *at),
        }
    }

    fn assign(&mut self, name: &str, index: Option<&Expr>, init: &Init, at: usize) -> R<()> {
        let i = match index {
            Some(e) => Some(self.index(e)?),
            None => None,
        };
        let v = self.init(init, at)?;
        let local = self.locals.contains_key(name);
        if !local && !self.globals.contains_key(name) {
            return self.assign_output(name, i, v, at);
        }
        let slot = if local {
            self.locals.get_mut(name)
        } else {
            self.globals.get_mut(name)
        }
        .expect("checked above");
        let Some(i) = i else {
            *slot = v;
            return Ok(());
        };
        match slot {
            Value::List(items) if i < items.len() => {
                items[i] = v;
                Ok(())
            }
            Value::List(items) => {
                let n = items.len();
                Err(self.error(at, format!("`{name}` has {n} elements, no index {i}")))
            }
            _ => Err(self.error(
                at,
                format!("`{name}` is not a vector; it cannot be indexed"),
            )),
        }
    }

    /// `name[i] = v` for one of the slicer's [`OUTPUTS`]: an element of a
    /// vector the slicer gave, a number (PrusaSlicer's
    /// `vector_variable_element_assign_scalar`); the vector keeps its size.
    fn assign_output(&mut self, name: &str, i: Option<usize>, v: Value, at: usize) -> R<()> {
        let given = self.vars.get(name);
        if !OUTPUTS.contains(&name) || given.is_none() {
            return Err(self.error(
                at,
                format!("`{name}` is no variable of `local` or `global`; a slicer's setting cannot be assigned (only {} can)", OUTPUTS.map(|o| format!("`{o}`")).join(", ")),
            ));
        }
        let Some(i) = i else {
            return Err(self.error(
                at,
                format!("`{name}` is a vector the slicer reads back: assign its elements (`{name}[0] = …`), not the whole"),
            ));
        };
        let Some(x) = v.number() else {
            return Err(self.error(
                at,
                format!("`{name}[{i}]` takes a number, not {}", v.kind()),
            ));
        };
        if !self.outputs.contains_key(name) {
            let copy = given.cloned().unwrap_or(Value::Nil);
            self.outputs.insert(name.to_string(), copy);
        }
        match self.outputs.get_mut(name) {
            Some(Value::List(items)) if i < items.len() => {
                items[i] = Value::Float(x);
                Ok(())
            }
            Some(Value::List(items)) => {
                let n = items.len();
                Err(self.error(at, format!("`{name}` has {n} elements, no index {i}")))
            }
            _ => Err(self.error(
                at,
                format!("`{name}` is not a vector; it cannot be indexed"),
            )),
        }
    }

    /// The value of a right side of `=`.
    fn init(&mut self, init: &Init, at: usize) -> R<Value> {
        match init {
            Init::Expr(Expr {
                kind: Kind::Var(n),
                at,
                ..
            }) => match self.lookup(n, *at)? {
                Value::List(items) => {
                    let v = Value::List(items.clone());
                    self.step(items.len(), *at)?;
                    Ok(v)
                }
                v => Ok(v.clone()),
            },
            Init::Expr(e) => self.eval(e),
            Init::List(items, at) => {
                let vals = items.iter().map(|e| self.eval(e)).collect::<R<Vec<_>>>()?;
                self.vector(vals, *at)
            }
            Init::Repeat(n, v) => {
                let count = match self.eval(n)? {
                    Value::Int(k) if (0..=MAX_VALUE as i64).contains(&k) => k as usize,
                    other => {
                        return Err(self.error(
                            n.at,
                            format!(
                                "`repeat` takes a count of 0 to {MAX_VALUE}, not {}",
                                other.text()
                            ),
                        ))
                    }
                };
                let v = self.eval(v)?;
                self.step(count, at)?;
                Ok(Value::List(vec![v; count]))
            }
        }
    }

    /// A vector of `vals` as PrusaSlicer types one: strings if any is a
    /// string, reals if any is real, else all booleans or all integers.
    fn vector(&mut self, vals: Vec<Value>, at: usize) -> R<Value> {
        let has = |f: fn(&Value) -> bool| vals.iter().any(f);
        if vals.is_empty() {
            return Err(self.error(at, "an empty vector: its type cannot be known"));
        }
        self.step(vals.len(), at)?;
        if has(|v| matches!(v, Value::Str(_))) {
            return Ok(Value::List(
                vals.iter().map(|v| Value::Str(v.text())).collect(),
            ));
        }
        let bools = has(|v| matches!(v, Value::Bool(_)));
        if bools && has(|v| v.number().is_some()) {
            return Err(self.error(at, "a vector mixing numbers and booleans"));
        }
        if let Some(v) = vals
            .iter()
            .find(|v| matches!(v, Value::List(_) | Value::Nil))
        {
            return Err(self.error(at, format!("{} inside a vector", v.kind())));
        }
        if has(|v| matches!(v, Value::Float(_) | Value::Shown(..))) {
            let f = vals.iter().map(|v| Value::Float(v.number().unwrap_or(0.0)));
            return Ok(Value::List(f.collect()));
        }
        Ok(Value::List(vals))
    }

    /// A legacy `[name]`: a list's element at the index (0 by default), as
    /// the slicer writes the option; `[name_N]` when `name_N` is no variable.
    fn legacy(&self, name: &str, idx: &Option<LegacyIndex>, at: usize) -> R<String> {
        let found = self.lookup(name, at).ok();
        let (value, index) = match (found, idx) {
            (Some(v), None) => (v, 0),
            (Some(v), Some(LegacyIndex::Number(i))) => (v, *i),
            (Some(v), Some(LegacyIndex::Var(iv))) => {
                let i = self.lookup(iv, at)?;
                (v, self.as_index(i, iv, at)?)
            }
            (None, None) => {
                // `[temperature_1]`: the list `temperature` at 1
                let split = name
                    .rsplit_once('_')
                    .and_then(|(n, i)| Some((n, i.parse::<usize>().ok()?)));
                match split.and_then(|(n, i)| Some((self.lookup(n, at).ok()?, i))) {
                    Some(found) => found,
                    None => return Err(self.error(at, format!("unknown variable `{name}`"))),
                }
            }
            (None, Some(_)) => return Err(self.error(at, format!("unknown variable `{name}`"))),
        };
        let v = match value {
            // past the end: the first element, as the slicer serialises it
            Value::List(items) => items.get(index).or_else(|| items.first()).ok_or_else(|| {
                self.error(
                    at,
                    format!("`{name}` is an empty vector: it has no element {index}"),
                )
            })?,
            v if idx.is_none() || index == 0 => v,
            _ => {
                return Err(self.error(at, format!("`{name}` is not a list; it cannot be indexed")))
            }
        };
        if let Value::Nil = v {
            return Err(self.error(at, format!("`{name}` is nil (left undefined)")));
        }
        Ok(v.legacy_text())
    }

    fn as_index(&self, v: &Value, what: &str, at: usize) -> R<usize> {
        match *v {
            Value::Int(i) if i >= 0 => Ok(i as usize),
            _ => Err(self.error(
                at,
                format!(
                    "the index `{what}` is {}, expected an integer ≥ 0",
                    v.kind()
                ),
            )),
        }
    }

    /// The value of an index expression.
    fn index(&mut self, e: &Expr) -> R<usize> {
        let v = self.eval(e)?;
        self.as_index(&v, "", e.at).map_err(|_| {
            self.error(
                e.at,
                format!("an index is {}, expected an integer ≥ 0", v.kind()),
            )
        })
    }

    fn truth(&mut self, e: &Expr) -> R<bool> {
        match self.eval(e)? {
            Value::Bool(b) => Ok(b),
            v => Err(self.error(
                e.at,
                format!("a condition is {}, expected a boolean", v.kind()),
            )),
        }
    }

    /// The value of `e`.
    pub(super) fn eval(&mut self, e: &Expr) -> R<Value> {
        self.step(1, e.at)?;
        let at = e.at;
        match &e.kind {
            Kind::Lit(v) => Ok(v.clone()),
            Kind::Var(name) => match self.lookup(name, at)? {
                // a list where one value is wanted: the current extruder's (0)
                Value::List(items) => items
                    .first()
                    .cloned()
                    .ok_or_else(|| self.error(at, format!("`{name}` is an empty list"))),
                v => Ok(v.clone()),
            },
            Kind::Index(name, index) => self.element(name, index, at),
            Kind::Not(a) => Ok(Value::Bool(!self.truth(a)?)),
            Kind::Neg(a) => match self.eval(a)? {
                Value::Int(i) => i
                    .checked_neg()
                    .map(Value::Int)
                    .ok_or_else(|| self.error(at, "an integer overflow in `-`")),
                v => match v.number() {
                    Some(f) => Ok(Value::Float(-f)),
                    None => Err(self.error(at, format!("cannot negate {}", v.kind()))),
                },
            },
            Kind::Arith(op, a, b) => {
                let (x, y) = (self.eval(a)?, self.eval(b)?);
                self.arithmetic(*op, &x, &y, at)
            }
            Kind::Logic(Bin::And, a, b) => Ok(Value::Bool(self.truth(a)? && self.truth(b)?)),
            Kind::Logic(Bin::Or, a, b) => Ok(Value::Bool(self.truth(a)? || self.truth(b)?)),
            Kind::Logic(Bin::Cmp(op), a, b) => {
                let (x, y) = (self.eval(a)?, self.eval(b)?);
                self.compare(*op, &x, &y, at)
            }
            Kind::Cond(c, a, b) => {
                if self.truth(c)? {
                    self.eval(a)
                } else {
                    self.eval(b)
                }
            }
            Kind::Match(a, k, negated) => match self.eval(a)? {
                Value::Str(s) => Ok(Value::Bool(self.t.patterns[*k].is_match(&s) != *negated)),
                v => Err(self.error(at, format!("`=~` matches a string, not {}", v.kind()))),
            },
            Kind::Call(f, args) => self.call(*f, args, at),
            Kind::OneOf(s, choices) => self.one_of(s, choices),
            Kind::Table(x, pts) => self.table(x, pts, at),
        }
    }

    /// `name[index]`: an index past the end reads the first element, as
    /// PrusaSlicer's parser reads a vector (its `vector_element_to_expr`:
    /// a template written for five tools reads tool 0's value on a machine
    /// with fewer); an empty vector has no element to read.
    fn element(&mut self, name: &str, index: &Expr, at: usize) -> R<Value> {
        let i = self.index(index)?;
        match self.lookup(name, at)? {
            Value::List(items) => {
                items
                    .get(i)
                    .or_else(|| items.first())
                    .cloned()
                    .ok_or_else(|| {
                        self.error(
                            at,
                            format!("`{name}` is an empty vector: it has no element {i}"),
                        )
                    })
            }
            v if i == 0 => Ok(v.clone()),
            _ => Err(self.error(at, format!("`{name}` is not a list; it cannot be indexed"))),
        }
    }

    fn compare(&self, op: Cmp, x: &Value, y: &Value, at: usize) -> R<Value> {
        let ord = match (x, y) {
            (Value::Bool(a), Value::Bool(b)) if matches!(op, Cmp::Eq | Cmp::Ne) => a.cmp(b),
            _ if x.number().is_some() && y.number().is_some() => {
                if let (Value::Int(a), Value::Int(b)) = (x, y) {
                    a.cmp(b)
                } else {
                    let (a, b) = (x.number().unwrap_or(0.0), y.number().unwrap_or(0.0));
                    if matches!(op, Cmp::Eq | Cmp::Ne) {
                        // PrusaSlicer's: reals within 1e-8 are equal
                        let eq = (a - b).abs() < EQUAL_WITHIN;
                        return Ok(Value::Bool(eq == (op == Cmp::Eq)));
                    }
                    a.partial_cmp(&b).ok_or_else(|| {
                        self.error(at, "a comparison with a number that is not one")
                    })?
                }
            }
            // a string with anything written as text: the texts compared
            (Value::Str(_), v) | (v, Value::Str(_))
                if !matches!(v, Value::List(_) | Value::Nil) =>
            {
                x.text().cmp(&y.text())
            }
            _ => {
                return Err(self.error(at, format!("cannot compare {} with {}", x.kind(), y.kind())))
            }
        };
        Ok(Value::Bool(op.holds(ord)))
    }

    fn arithmetic(&mut self, op: Arith, x: &Value, y: &Value, at: usize) -> R<Value> {
        let sym = match op {
            Arith::Add => "+",
            Arith::Sub => "-",
            Arith::Mul => "*",
            Arith::Div => "/",
            Arith::Mod => "%",
        };
        if op == Arith::Add && (matches!(x, Value::Str(_)) || matches!(y, Value::Str(_))) {
            let (a, b) = (x.text(), y.text());
            if a.len() + b.len() > MAX_VALUE {
                return Err(self.error(at, format!("a string longer than {MAX_VALUE} bytes")));
            }
            self.step(a.len() + b.len(), at)?;
            return Ok(Value::Str(a + &b));
        }
        let bad = || {
            self.error(
                at,
                format!("cannot apply `{sym}` to {} and {}", x.kind(), y.kind()),
            )
        };
        if let (Value::Int(a), Value::Int(b)) = (x, y) {
            let (a, b) = (*a, *b);
            if matches!(op, Arith::Div | Arith::Mod) && b == 0 {
                return Err(self.error(at, "division by zero"));
            }
            return match op {
                Arith::Add => a.checked_add(b),
                Arith::Sub => a.checked_sub(b),
                Arith::Mul => a.checked_mul(b),
                Arith::Div => a.checked_div(b),
                Arith::Mod => a.checked_rem(b),
            }
            .map(Value::Int)
            .ok_or_else(|| self.error(at, format!("an integer overflow in `{sym}`")));
        }
        let (a, b) = (x.number().ok_or_else(bad)?, y.number().ok_or_else(bad)?);
        if matches!(op, Arith::Div | Arith::Mod) && b == 0.0 {
            return Err(self.error(at, "division by zero"));
        }
        Ok(Value::Float(match op {
            Arith::Add => a + b,
            Arith::Sub => a - b,
            Arith::Mul => a * b,
            Arith::Div => a / b,
            Arith::Mod => libm::fmod(a, b),
        }))
    }

    /// The value a variable reference (`name`, `name[i]`) names, or `None`
    /// for the whole vector of a `name` that is one.
    fn reference(&mut self, e: &Expr) -> R<Result<Value, Vec<Value>>> {
        match &e.kind {
            Kind::Var(n) => match self.lookup(n, e.at)? {
                Value::List(items) => Ok(Err(items.clone())),
                v => Ok(Ok(v.clone())),
            },
            _ => Ok(Ok(self.eval(e)?)),
        }
    }

    fn call(&mut self, f: Func, args: &[Expr], at: usize) -> R<Value> {
        match f {
            Func::IsNil => {
                return Ok(Value::Bool(match self.reference(&args[0])? {
                    Ok(v) => v == Value::Nil,
                    Err(items) => items.first() == Some(&Value::Nil),
                }))
            }
            Func::Size | Func::Empty => {
                let Err(items) = self.reference(&args[0])? else {
                    return Err(self.error(args[0].at, "`size` and `empty` take a vector variable"));
                };
                return Ok(if f == Func::Size {
                    Value::Int(items.len() as i64)
                } else {
                    Value::Bool(items.is_empty())
                });
            }
            _ => {}
        }
        let vals = args.iter().map(|a| self.eval(a)).collect::<R<Vec<_>>>()?;
        let num = |k: usize| {
            vals[k].number().ok_or_else(|| {
                self.error(
                    args[k].at,
                    format!(
                        "argument {} is {}, expected a number",
                        k + 1,
                        vals[k].kind()
                    ),
                )
            })
        };
        let real = vals
            .iter()
            .any(|v| matches!(v, Value::Float(_) | Value::Shown(..)));
        match f {
            Func::Min | Func::Max => {
                let (a, b) = (num(0)?, num(1)?);
                let first = (a < b) == (f == Func::Min);
                if let (Value::Int(x), Value::Int(y)) = (&vals[0], &vals[1]) {
                    return Ok(Value::Int(if first { *x } else { *y }));
                }
                Ok(Value::Float(if first { a } else { b }))
            }
            Func::Int => Ok(Value::Int(self.to_int(libm::trunc(num(0)?), at)?)),
            Func::Round => Ok(Value::Int(self.to_int(libm::round(num(0)?), at)?)),
            Func::Digits | Func::Zdigits => self.digits(f == Func::Zdigits, &vals, args, at),
            Func::Random => {
                let (lo, hi) = (num(0)?, num(1)?);
                if lo.partial_cmp(&hi).is_none_or(|o| o.is_gt()) {
                    return Err(self.error(at, "`random(lo, hi)` takes lo ≤ hi"));
                }
                if !real {
                    // Lemire's multiply-shift: a uniform integer in [lo, hi]
                    let (a, b) = (lo as i64, hi as i64);
                    let span = (b as i128 - a as i128 + 1) as u128;
                    let k = (self.rng.next_u64() as u128 * span) >> 64;
                    return Ok(Value::Int((a as i128 + k as i128) as i64));
                }
                Ok(Value::Float(lo + (hi - lo) * self.rng.uniform()))
            }
            Func::IsNil | Func::Size | Func::Empty => unreachable!("handled above"),
        }
    }

    /// `digits(x, n[, d])`, `zdigits`: `x` in `n` characters (spaces or
    /// zeros before it), with `d` decimals, or rounded to an integer
    /// without `d` (C's `%*.*f` and `%*d`, PrusaSlicer's).
    fn digits(&self, zeros: bool, vals: &[Value], args: &[Expr], at: usize) -> R<Value> {
        let x = vals[0].number().ok_or_else(|| {
            self.error(
                args[0].at,
                format!("`digits` formats a number, not {}", vals[0].kind()),
            )
        })?;
        let int = |k: usize| match vals.get(k) {
            Some(Value::Int(i)) => Ok(Some((*i).clamp(0, 64) as usize)),
            Some(v) => Err(self.error(
                args[k].at,
                format!("`digits` takes integer widths, not {}", v.kind()),
            )),
            None => Ok(None),
        };
        let w = int(1)?.unwrap_or(0);
        Ok(Value::Str(match (int(2)?, zeros) {
            (Some(d), true) => format!("{x:0w$.d$}"),
            (Some(d), false) => format!("{x:w$.d$}"),
            (None, z) => {
                let i = self.to_int(libm::round(x), at)?;
                if z {
                    format!("{i:0w$}")
                } else {
                    format!("{i:w$}")
                }
            }
        }))
    }

    fn to_int(&self, x: f64, at: usize) -> R<i64> {
        if x.is_finite() && x.abs() < 9.0e18 {
            Ok(x as i64)
        } else {
            Err(self.error(at, format!("{} is no integer", fmt_g(x))))
        }
    }

    fn one_of(&mut self, s: &Expr, choices: &[Choice]) -> R<Value> {
        let subject = match self.eval(s)? {
            Value::Str(x) => x,
            v => {
                return Err(self.error(s.at, format!("`one_of` matches a string, not {}", v.kind())))
            }
        };
        for c in choices {
            let hit = match c {
                Choice::Pattern(k) => self.t.patterns[*k].is_match(&subject),
                Choice::Equal(e) | Choice::Computed(e) => {
                    let Value::Str(p) = self.eval(e)? else {
                        return Err(self.error(e.at, "`one_of` takes strings and patterns"));
                    };
                    match c {
                        Choice::Computed(_) => self.computed(&p, e.at)?.is_match(&subject),
                        _ => p == subject,
                    }
                }
            };
            if hit {
                return Ok(Value::Bool(true));
            }
        }
        Ok(Value::Bool(false))
    }

    /// A pattern computed at run time, compiled once, within the template's
    /// cap on patterns.
    fn computed(&mut self, p: &str, at: usize) -> R<&regex::Regex> {
        if !self.computed.contains_key(p) {
            if self.t.patterns.len() + self.computed.len() >= super::parse::MAX_PATTERNS {
                return Err(self.error(
                    at,
                    format!(
                        "more than {} different patterns in one template",
                        super::parse::MAX_PATTERNS
                    ),
                ));
            }
            let re = super::parse::compile_pattern(p).map_err(|m| self.error(at, m))?;
            self.computed.insert(p.to_string(), re);
        }
        Ok(&self.computed[p])
    }

    /// `interpolate_table(x, (x0, y0), …)`: y on the polyline through the
    /// points (increasing x), linearly between two; outside, an error.
    fn table(&mut self, x: &Expr, pts: &[(Expr, Expr)], at: usize) -> R<Value> {
        let num = |r: &mut Run, e: &Expr| -> R<f64> {
            let v = r.eval(e)?;
            v.number().ok_or_else(|| {
                r.error(
                    e.at,
                    format!("`interpolate_table` takes numbers, not {}", v.kind()),
                )
            })
        };
        let xv = num(self, x)?;
        let mut table = Vec::with_capacity(pts.len());
        for (a, b) in pts {
            table.push((num(self, a)?, num(self, b)?, a.at));
        }
        for w in table.windows(2) {
            if w[0].0 > w[1].0 {
                return Err(self.error(w[1].2, "the x values of the table must increase"));
            }
        }
        for w in table.windows(2) {
            let ((x0, y0, _), (x1, y1, _)) = (w[0], w[1]);
            if xv >= x0 && xv <= x1 {
                return Ok(Value::Float(if xv == x0 {
                    y0
                } else if xv == x1 {
                    y1
                } else {
                    // linear interpolation between the two points
                    y0 + (y1 - y0) * ((xv - x0) / (x1 - x0))
                }));
            }
        }
        let (first, last) = (table[0], table[table.len() - 1]);
        if (xv - first.0).abs() < TABLE_SLACK {
            return Ok(Value::Float(first.1));
        }
        if (xv - last.0).abs() < TABLE_SLACK {
            return Ok(Value::Float(last.1));
        }
        Err(self.error(
            at,
            format!(
                "{} is outside the table ({} to {})",
                fmt_g(xv),
                fmt_g(first.0),
                fmt_g(last.0)
            ),
        ))
    }
}
