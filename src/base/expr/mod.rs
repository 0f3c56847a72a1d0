//! Math expressions of a recipe, compiled once and evaluated per point or string.
//!
//! Parsing is one pass (`parse`): the operators the recipe shares with the
//! slicers' macros (comparisons, `and`/`or`/`not`, `?:`) by
//! [`crate::base::grammar`]'s table, the arithmetic between them by meval's
//! shunting-yard (reverse Polish notation); we then resolve every name to a
//! variable slot, a param constant or a function pointer, fold constant
//! sub-expressions, and run the result on a small fixed stack. Every transcendental function goes
//! through the `libm` crate, so a recipe gives bit-identical numbers on every
//! machine (std's `sin` may call the platform's libm, which differs).

mod params;
mod parse;

use meval::tokenizer::{Operation, Token};

use parse::HOLE;

use crate::base::error::Error;
pub(crate) use params::{short, Kind, Params};

/// What is wrong with an expression, for a caller that must tell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ExprErrorKind {
    /// The text does not parse.
    Syntax,
    /// A name is unknown or not available here (the message lists those that are).
    Name,
    /// A function is unknown or given the wrong number of arguments.
    Function,
    /// The expression is nested too deeply to run.
    TooDeep,
    /// A constant expression evaluates to NaN or infinity.
    NotFinite,
}

/// An expression that cannot be compiled or evaluated: a sentence naming it
/// and what is wrong with it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct ExprError {
    /// What kind of problem.
    pub(crate) kind: ExprErrorKind,
    /// The sentence.
    pub(crate) message: String,
}

impl ExprError {
    /// An error of `kind` saying `message`.
    fn new(kind: ExprErrorKind, message: impl Into<String>) -> ExprError {
        ExprError {
            kind,
            message: message.into(),
        }
    }

    /// The input error at key path `place` (empty for none).
    pub(crate) fn at(self, place: impl Into<String>) -> Error {
        Error::input(place, self.message)
    }
}

impl std::fmt::Display for ExprError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for ExprError {}

/// Slot of each per-point / per-string variable in the value array.
pub(crate) mod var {
    /// x coordinate (mm).
    pub(crate) const X: usize = 0;
    /// y coordinate (mm).
    pub(crate) const Y: usize = 1;
    /// z coordinate (mm).
    pub(crate) const Z: usize = 2;
    /// distance from the z axis (mm).
    pub(crate) const R: usize = 3;
    /// angle around the z axis, in [0, 2·pi).
    pub(crate) const THETA: usize = 4;
    /// cross-section of the string (mm²).
    pub(crate) const C: usize = 5;
    /// head speed of the string (mm/s).
    pub(crate) const V: usize = 6;
    /// index of the point or string in the part.
    pub(crate) const I: usize = 7;
    /// number of points or strings in the part.
    pub(crate) const N: usize = 8;
    /// i / (n - 1), 0 to 1 along the part.
    pub(crate) const T: usize = 9;
    /// arc-length fraction 0..1 along an `outline:` (the `s` of issue 20).
    pub(crate) const S: usize = 10;
    /// how many slots there are.
    pub(crate) const COUNT: usize = 11;
}

/// Names of the variable slots, indexed by [`var`].
pub(crate) const VAR_NAMES: [&str; var::COUNT] =
    ["x", "y", "z", "r", "theta", "c", "v", "i", "n", "t", "s"];

/// Variables added after recipe v1, whose names a param, template param or
/// loop variable may still take: such a param shadows the variable.
pub(crate) const SHADOWABLE: [&str; 1] = ["s"];

/// The values an expression sees for one point or string.
pub(crate) type Vars = [f64; var::COUNT];

/// Names that params may not take: the variables (less [`SHADOWABLE`]) and
/// the constants.
pub(crate) fn is_reserved(name: &str) -> bool {
    (VAR_NAMES.contains(&name) && !SHADOWABLE.contains(&name)) || name == "pi" || name == "e"
}

const STACK: usize = 32;

/// Longest expression text, in bytes: a bound on the work of compiling one.
pub(crate) const MAX_LEN: usize = 4096;

/// Deepest expression tree (operations and calls inside one another):
/// compiling and evaluating recurse this deep.
pub(crate) const MAX_DEPTH: u32 = 256;

type F1 = fn(f64) -> f64;
type F2 = fn(f64, f64) -> f64;
type F3 = fn(f64, f64, f64) -> f64;

#[derive(Clone, Copy, Debug)]
enum Op {
    Num(f64),
    Var(u8),
    Neg,
    Add,
    Sub,
    Mul,
    Div,
    Rem,
    Pow,
    F1(F1),
    F2(F2),
    F3(F3),
    /// `eca(rule, width, row, col)`, its rows kept in the evaluation's [`Memo`].
    Eca,
    Min(u8),
    Max(u8),
    /// A value of the extra slots of [`Expr::compile_ext`].
    Ext(u16),
    /// `name[k]` of a list param: value k (from the end when negative) of
    /// the `len` values from `off` in the expression's data; NaN for k not
    /// a whole number in −len..len.
    At {
        off: u32,
        len: u32,
    },
}

/// A compiled expression.
#[derive(Clone, Debug)]
pub(crate) struct Expr {
    src: String,
    ops: Vec<Op>,
    /// The values of the list params it reads ([`Op::At`]).
    data: Vec<f64>,
    used: u32,
    /// `rand()` calls, read from the extra slots after the named ones.
    rands: u16,
}

// The functions recipe authors may call, beyond meval's operators.
fn f_mod(a: f64, b: f64) -> f64 {
    // floored modulo: the result has the sign of b, so mod(-1, 360) = 359
    a - b * libm::floor(a / b)
}
fn f_clamp(x: f64, lo: f64, hi: f64) -> f64 {
    x.max(lo).min(hi)
}
fn f_step(edge: f64, x: f64) -> f64 {
    // GLSL's step: 0 below the edge, 1 from it on
    if x < edge {
        0.0
    } else {
        1.0
    }
}
fn f_smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = f_clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}
fn f_mix(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}
fn f_sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}
fn f_sqrt(x: f64) -> f64 {
    x.sqrt() // IEEE 754 correctly rounded: portable
}
fn f_abs(x: f64) -> f64 {
    x.abs()
}
fn f_fract(x: f64) -> f64 {
    x - libm::floor(x)
}
fn f_radians(x: f64) -> f64 {
    x * (std::f64::consts::PI / 180.0)
}
fn f_degrees(x: f64) -> f64 {
    x * (180.0 / std::f64::consts::PI)
}
/// 1 or 0: the values of comparisons and logic (any number but 0 is true,
/// NaN included, as in Python).
fn truth(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}
fn f_lt(a: f64, b: f64) -> f64 {
    truth(a < b)
}
fn f_le(a: f64, b: f64) -> f64 {
    truth(a <= b)
}
fn f_gt(a: f64, b: f64) -> f64 {
    truth(a > b)
}
fn f_ge(a: f64, b: f64) -> f64 {
    truth(a >= b)
}
fn f_eq(a: f64, b: f64) -> f64 {
    truth(a == b)
}
fn f_ne(a: f64, b: f64) -> f64 {
    truth(a != b)
}
fn f_and(a: f64, b: f64) -> f64 {
    truth(a != 0.0 && b != 0.0)
}
fn f_or(a: f64, b: f64) -> f64 {
    truth(a != 0.0 || b != 0.0)
}
fn f_not(a: f64) -> f64 {
    truth(a == 0.0)
}
/// `if(c, a, b)`: a when c is true (not 0), else b. Both are computed (an
/// expression has no side effects), only one is kept.
fn f_if(c: f64, a: f64, b: f64) -> f64 {
    if c != 0.0 {
        a
    } else {
        b
    }
}

/// Value `k` of `list` as `name[k]` reads it: from the end when negative
/// (Python's), NaN for k not a whole number in −len..len.
fn list_at(list: &[f64], k: f64) -> f64 {
    let n = list.len() as f64;
    if k.fract() != 0.0 || !(-n..n).contains(&k) {
        return f64::NAN;
    }
    let k = if k < 0.0 { k + n } else { k };
    list[k as usize]
}

fn lookup1(name: &str) -> Option<F1> {
    Some(match name {
        "sin" => libm::sin,
        "cos" => libm::cos,
        "tan" => libm::tan,
        "asin" => libm::asin,
        "acos" => libm::acos,
        "atan" => libm::atan,
        "sinh" => libm::sinh,
        "cosh" => libm::cosh,
        "tanh" => libm::tanh,
        "asinh" => libm::asinh,
        "acosh" => libm::acosh,
        "atanh" => libm::atanh,
        "sqrt" => f_sqrt,
        "cbrt" => libm::cbrt,
        "exp" => libm::exp,
        "ln" | "log" => libm::log,
        "log10" => libm::log10,
        "log2" => libm::log2,
        "abs" => f_abs,
        "floor" => libm::floor,
        "ceil" => libm::ceil,
        "round" => libm::round,
        "trunc" | "int" => libm::trunc,
        "sign" | "signum" => f_sign,
        "fract" => f_fract,
        "radians" => f_radians,
        "degrees" => f_degrees,
        _ => return None,
    })
}

fn lookup2(name: &str) -> Option<F2> {
    Some(match name {
        "atan2" => libm::atan2,
        "hypot" => libm::hypot,
        "pow" => libm::pow,
        "mod" => f_mod,
        "step" => f_step,
        _ => return None,
    })
}

/// Rows between two rows [`eca`] keeps, so any row is at most this many
/// steps from a known one.
const ECA_STRIDE: u64 = 256;

/// The rows of one automaton computed so far.
#[derive(Clone, Debug)]
struct EcaCache {
    /// Rule and ring width.
    key: (u8, u32),
    /// Rows 0, ECA_STRIDE, 2·ECA_STRIDE, … computed so far.
    kept: Vec<u64>,
    /// The last row asked for, and its cells.
    last: (u64, u64),
}

/// What the evaluations of one pass over many points remember between
/// points: the rows of the automaton `eca` has computed. Only a shortcut:
/// every value is the same with a fresh one.
#[derive(Clone, Debug, Default)]
pub(crate) struct Memo {
    eca: Option<EcaCache>,
}

/// One generation of the elementary automaton `rule` on a ring of cells
/// (`mask` has the ring's `w` bits set): cell i's next state is bit
/// (left·4 + self·2 + right) of the rule.
fn eca_next(rule: u8, w: u32, mask: u64, cells: u64) -> u64 {
    let left = (cells << 1 | cells >> (w - 1)) & mask;
    let right = (cells >> 1 | cells << (w - 1)) & mask;
    let mut next = 0u64;
    for k in 0..8u64 {
        if rule >> k & 1 == 1 {
            let l = if k & 4 != 0 { left } else { !left };
            let c = if k & 2 != 0 { cells } else { !cells };
            let r = if k & 1 != 0 { right } else { !right };
            next |= l & c & r;
        }
    }
    next & mask
}

#[cfg(test)]
/// `eca(rule, width, row, col)`: the cell (0 or 1) at `row` and `col` of
/// Wolfram's elementary cellular automaton `rule` (0–255) on a ring of
/// `width` cells (1–64) whose row 0 has one live cell, at column 0; columns
/// wrap around the ring. NaN for arguments out of range (rows up to 10⁶).
pub(crate) fn eca(rule: f64, width: f64, row: f64, col: f64) -> f64 {
    Memo::default().eca(rule, width, row, col)
}

impl Memo {
    /// [`eca`], going on from the rows this memo has kept.
    pub(crate) fn eca(&mut self, rule: f64, width: f64, row: f64, col: f64) -> f64 {
        let whole = |x: f64, hi: f64| x.fract() == 0.0 && (0.0..=hi).contains(&x);
        if !whole(rule, 255.0) || !whole(width, 64.0) || width < 1.0 || !whole(row, 1e6) {
            return f64::NAN;
        }
        if !col.is_finite() || col.fract() != 0.0 {
            return f64::NAN;
        }
        let (rule, w, row) = (rule as u8, width as u32, row as u64);
        let mask = if w == 64 { u64::MAX } else { (1u64 << w) - 1 };
        // An expression evaluated per point asks for rows in any order (from
        // row 0 each time, n points of row r would cost n·r generations):
        // keep every ECA_STRIDE-th row, so a row costs at most ECA_STRIDE
        // generations once the rows up to it have been computed, and go on
        // from the last row when it is near.
        let cache = match &mut self.eca {
            Some(c) if c.key == (rule, w) => c,
            slot => slot.insert(EcaCache {
                key: (rule, w),
                kept: vec![1],
                last: (0, 1),
            }),
        };
        let at = ((row / ECA_STRIDE) as usize).min(cache.kept.len() - 1);
        let (mut from, mut cells) = (at as u64 * ECA_STRIDE, cache.kept[at]);
        if cache.last.0 <= row && cache.last.0 > from {
            (from, cells) = cache.last;
        }
        for r in from..row {
            cells = eca_next(rule, w, mask, cells);
            if (r + 1) % ECA_STRIDE == 0 && (r + 1) / ECA_STRIDE == cache.kept.len() as u64 {
                cache.kept.push(cells);
            }
        }
        cache.last = (row, cells);
        let c = f_mod(col, width) as u32;
        (cells >> c & 1) as f64
    }
}

/// The functions of four arguments: `eca` alone (see [`Op::Eca`]).
fn lookup4(name: &str) -> Option<()> {
    (name == "eca").then_some(())
}

fn lookup3(name: &str) -> Option<F3> {
    Some(match name {
        "clamp" => f_clamp,
        "smoothstep" => f_smoothstep,
        "mix" | "lerp" => f_mix,
        "if" => f_if,
        _ => return None,
    })
}

/// Every function name an expression may call, for error messages.
pub(crate) const FUNCTIONS: &str =
    "sin cos tan asin acos atan atan2(y,x) sinh cosh tanh asinh acosh atanh \
sqrt cbrt exp ln log log10 log2 pow(a,b) abs sign signum floor ceil round trunc fract \
mod(a,b) int min(a,b,…) max(a,b,…) clamp(x,lo,hi) step(edge,x) smoothstep(e0,e1,x) \
mix(a,b,t) lerp(a,b,t) if(c,a,b) hypot(x,y) radians degrees eca(rule,width,row,col) len(list) \
sum(list[,a,b])";

#[derive(Clone, Debug)]
enum Node {
    Num(f64),
    Var(u8),
    Ext(u16),
    Neg(Box<Node>),
    Bin(Op, Box<Node>, Box<Node>),
    Call(Op, Vec<Node>),
}

impl Node {
    fn num(&self) -> Option<f64> {
        match self {
            Node::Num(v) => Some(*v),
            _ => None,
        }
    }
    fn depth(&self) -> usize {
        match self {
            Node::Num(_) | Node::Var(_) | Node::Ext(_) => 1,
            Node::Neg(a) => a.depth(),
            Node::Bin(_, a, b) => a.depth().max(1 + b.depth()),
            Node::Call(_, args) => args
                .iter()
                .enumerate()
                .map(|(k, a)| k + a.depth())
                .max()
                .unwrap_or(1),
        }
    }
    fn emit(&self, out: &mut Vec<Op>) {
        match self {
            Node::Num(v) => out.push(Op::Num(*v)),
            Node::Var(s) => out.push(Op::Var(*s)),
            Node::Ext(s) => out.push(Op::Ext(*s)),
            Node::Neg(a) => {
                a.emit(out);
                out.push(Op::Neg);
            }
            Node::Bin(op, a, b) => {
                a.emit(out);
                b.emit(out);
                out.push(*op);
            }
            Node::Call(op, args) => {
                for a in args {
                    a.emit(out);
                }
                out.push(*op);
            }
        }
    }
}

/// The value of a constant's name: `pi`, `e`, `tau` (2·pi), `true` (1),
/// `false` (0). A param of the same name comes first (all but `pi` and `e`
/// were added after recipe v1).
fn constant(name: &str) -> Option<f64> {
    Some(match name {
        "pi" => std::f64::consts::PI,
        "e" => std::f64::consts::E,
        "tau" => std::f64::consts::TAU,
        "true" => 1.0,
        "false" => 0.0,
        _ => return None,
    })
}

/// Runs `ops` on a stack; the one evaluator used for folding and at run time.
#[inline]
fn run(ops: &[Op], data: &[f64], vars: &Vars, ext: &[f64], memo: &mut Memo) -> f64 {
    let mut st = [0.0f64; STACK];
    let mut sp = 0usize;
    for op in ops {
        match *op {
            Op::At { off, len } => {
                let list = &data[off as usize..(off + len) as usize];
                st[sp - 1] = list_at(list, st[sp - 1]);
            }
            Op::Num(v) => {
                st[sp] = v;
                sp += 1;
            }
            Op::Var(s) => {
                st[sp] = vars[s as usize];
                sp += 1;
            }
            Op::Ext(s) => {
                st[sp] = ext[s as usize];
                sp += 1;
            }
            Op::Neg => st[sp - 1] = -st[sp - 1],
            Op::F1(f) => st[sp - 1] = f(st[sp - 1]),
            Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Rem | Op::Pow | Op::F2(_) => {
                sp -= 1;
                let (a, b) = (st[sp - 1], st[sp]);
                st[sp - 1] = match *op {
                    Op::Add => a + b,
                    Op::Sub => a - b,
                    Op::Mul => a * b,
                    Op::Div => a / b,
                    Op::Rem => libm::fmod(a, b),
                    Op::Pow => libm::pow(a, b),
                    Op::F2(f) => f(a, b),
                    _ => unreachable!(),
                };
            }
            Op::F3(f) => {
                sp -= 2;
                st[sp - 1] = f(st[sp - 1], st[sp], st[sp + 1]);
            }
            Op::Eca => {
                sp -= 3;
                st[sp - 1] = memo.eca(st[sp - 1], st[sp], st[sp + 1], st[sp + 2]);
            }
            Op::Min(k) | Op::Max(k) => {
                let k = k as usize;
                let args = &st[sp - k..sp];
                let mut m = args[0];
                for &a in &args[1..] {
                    m = if matches!(op, Op::Min(_)) {
                        m.min(a)
                    } else {
                        m.max(a)
                    };
                }
                sp -= k;
                st[sp] = m;
                sp += 1;
            }
        }
    }
    st[0]
}

/// Points one pass of [`Expr::eval_many`] evaluates together.
pub(crate) const LANES: usize = 64;

/// The working state of [`Expr::eval_many_in`] over many points: its stack
/// (one value per point in each slot) and what the evaluations remember
/// between points ([`Memo`]).
pub(crate) struct Lanes {
    stack: Box<[[f64; LANES]; STACK]>,
    memo: Memo,
}

impl Lanes {
    /// A stack for [`Expr::eval_many_in`].
    pub(crate) fn new() -> Lanes {
        Lanes {
            stack: Box::new([[0.0; LANES]; STACK]),
            memo: Memo::default(),
        }
    }
}

impl Default for Lanes {
    /// [`Lanes::new`].
    fn default() -> Lanes {
        Lanes::new()
    }
}

/// [`run`] on up to [`LANES`] points: each stack slot holds one value per
/// point, and every instruction is applied to all of them before the next.
// the calls of 3, 4 and k arguments read several slots of one lane at once
#[allow(clippy::needless_range_loop)]
fn run_lanes(ops: &[Op], data: &[f64], vars: &[Vars], out: &mut [f64], lanes: &mut Lanes) {
    let (st, memo) = (&mut *lanes.stack, &mut lanes.memo);
    let n = vars.len();
    let mut sp = 0usize;
    for op in ops {
        match *op {
            Op::At { off, len } => {
                let list = &data[off as usize..(off + len) as usize];
                for a in &mut st[sp - 1][..n] {
                    *a = list_at(list, *a);
                }
            }
            Op::Num(v) => {
                st[sp][..n].fill(v);
                sp += 1;
            }
            Op::Var(s) => {
                for (d, v) in st[sp][..n].iter_mut().zip(vars) {
                    *d = v[s as usize];
                }
                sp += 1;
            }
            Op::Ext(s) => {
                // as `eval`: no extra slots
                let ext: &[f64] = &[];
                st[sp][..n].fill(ext[s as usize]);
                sp += 1;
            }
            Op::Neg => {
                for a in &mut st[sp - 1][..n] {
                    *a = -*a;
                }
            }
            Op::F1(f) => {
                for a in &mut st[sp - 1][..n] {
                    *a = f(*a);
                }
            }
            Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Rem | Op::Pow | Op::F2(_) => {
                sp -= 1;
                let (left, right) = st.split_at_mut(sp);
                let (a, b) = (&mut left[sp - 1][..n], &right[0][..n]);
                let pairs = a.iter_mut().zip(b);
                match *op {
                    Op::Add => pairs.for_each(|(x, y)| *x += *y),
                    Op::Sub => pairs.for_each(|(x, y)| *x -= *y),
                    Op::Mul => pairs.for_each(|(x, y)| *x *= *y),
                    Op::Div => pairs.for_each(|(x, y)| *x /= *y),
                    Op::Rem => pairs.for_each(|(x, y)| *x = libm::fmod(*x, *y)),
                    Op::Pow => pairs.for_each(|(x, y)| *x = libm::pow(*x, *y)),
                    Op::F2(f) => pairs.for_each(|(x, y)| *x = f(*x, *y)),
                    _ => unreachable!(),
                }
            }
            Op::F3(f) => {
                sp -= 2;
                for j in 0..n {
                    st[sp - 1][j] = f(st[sp - 1][j], st[sp][j], st[sp + 1][j]);
                }
            }
            Op::Eca => {
                sp -= 3;
                for j in 0..n {
                    let (a, b, c, d) = (st[sp - 1][j], st[sp][j], st[sp + 1][j], st[sp + 2][j]);
                    st[sp - 1][j] = memo.eca(a, b, c, d);
                }
            }
            Op::Min(k) | Op::Max(k) => {
                sp = lanes_min_max(st, sp, k as usize, n, matches!(op, Op::Min(_)));
            }
        }
    }
    out.copy_from_slice(&st[0][..n]);
}

/// `min` (or `max`) of the top `k` stack rows of `n` lanes into the lowest
/// of them; the new stack height.
fn lanes_min_max(st: &mut [[f64; LANES]], sp: usize, k: usize, n: usize, min: bool) -> usize {
    assert!(k > 0, "min and max take at least one argument");
    let (low, rest) = st[sp - k..sp].split_at_mut(1);
    for row in rest.iter() {
        for (m, &a) in low[0][..n].iter_mut().zip(&row[..n]) {
            *m = if min { m.min(a) } else { m.max(a) };
        }
    }
    sp - (k - 1)
}

fn allowed_names(allowed: &[usize], params: &Params) -> String {
    let mut names: Vec<&str> = allowed.iter().map(|&k| VAR_NAMES[k]).collect();
    names.extend(["pi", "e", "tau", "true", "false"]);
    let mut s = names.join(", ");
    if !params.is_empty() {
        let p: Vec<&str> = params.keys().map(String::as_str).collect();
        s.push_str(" and the params ");
        s.push_str(&p.join(", "));
    }
    s
}

impl Expr {
    /// Compiles `src`, resolving params to constants and only the `allowed`
    /// variable slots (see [`var`]) to variables. The error is a sentence
    /// naming the expression and what is wrong with it.
    pub(crate) fn compile(
        src: &str,
        params: &Params,
        allowed: &[usize],
    ) -> Result<Expr, ExprError> {
        Expr::compile_inner(src, params, allowed, None)
    }

    /// Compiles `src` as [`Expr::compile`] does, with `names` as extra
    /// variables (they shadow nothing: a caller keeps them apart from params;
    /// a name `f()` is a function of no arguments, called as `f()`)
    /// and `rand()` allowed: name k reads extra slot k, and the j-th `rand()`
    /// of the text reads slot `names.len() + j`, which the caller fills with a
    /// fresh random number before each [`Expr::eval_ext`] (see [`Expr::rands`]).
    pub(crate) fn compile_ext(
        src: &str,
        params: &Params,
        allowed: &[usize],
        names: &[&str],
    ) -> Result<Expr, ExprError> {
        Expr::compile_inner(src, params, allowed, Some(names))
    }

    fn compile_inner(
        src: &str,
        params: &Params,
        allowed: &[usize],
        names: Option<&[&str]>,
    ) -> Result<Expr, ExprError> {
        check_text(src)?;
        let mut c = Compiler {
            src,
            params,
            allowed,
            names,
            stack: Vec::new(),
            heights: Vec::new(),
            holes: Vec::new(),
            used: 0,
            rands: 0,
            data: Vec::new(),
        };
        let root = parse::parse(src, &mut c)?;
        c.finish(root)
    }

    /// Evaluates with the given variable values (for a few points: a pass
    /// over many keeps one [`Memo`] for all, see [`Expr::eval_in`]).
    #[inline]
    pub(crate) fn eval(&self, vars: &Vars) -> f64 {
        run(&self.ops, &self.data, vars, &[], &mut Memo::default())
    }

    /// [`Expr::eval`] going on from what `memo` kept of the points before.
    #[inline]
    pub(crate) fn eval_in(&self, vars: &Vars, memo: &mut Memo) -> f64 {
        run(&self.ops, &self.data, vars, &[], memo)
    }

    /// Evaluates at many points at once: `out[j] = self.eval(&vars[j])`,
    /// bit for bit. The program runs one instruction at a time over
    /// [`LANES`] points (a loop per instruction instead of one dispatch per
    /// instruction and point); each point sees exactly the operations of
    /// [`Expr::eval`], in the same order.
    #[cfg(test)]
    pub(crate) fn eval_many(&self, vars: &[Vars], out: &mut [f64]) {
        let mut lanes = Lanes::new();
        self.eval_many_in(vars, out, &mut lanes);
    }

    /// [`Expr::eval_many`] on the stack `lanes` (made once for many calls:
    /// it is 16 KiB, more to clear than a few points are to evaluate).
    pub(crate) fn eval_many_in(&self, vars: &[Vars], out: &mut [f64], lanes: &mut Lanes) {
        assert_eq!(vars.len(), out.len(), "one result per point");
        for (v, o) in vars.chunks(LANES).zip(out.chunks_mut(LANES)) {
            run_lanes(&self.ops, &self.data, v, o, lanes);
        }
    }

    /// Evaluates an expression of [`Expr::compile_ext`]: `ext` holds the
    /// named extra values, then [`Expr::rands`] random numbers.
    #[inline]
    pub(crate) fn eval_ext(&self, vars: &Vars, ext: &[f64], memo: &mut Memo) -> f64 {
        run(&self.ops, &self.data, vars, ext, memo)
    }

    /// How many `rand()` calls the expression makes per evaluation.
    pub(crate) fn rands(&self) -> usize {
        self.rands as usize
    }

    /// The value when the expression uses no variable.
    pub(crate) fn constant(&self) -> Option<f64> {
        match self.ops.as_slice() {
            [Op::Num(v)] => Some(*v),
            _ => None,
        }
    }

    /// Whether the expression reads extra slot `k` of [`Expr::compile_ext`].
    pub(crate) fn uses_ext(&self, k: usize) -> bool {
        self.ops
            .iter()
            .any(|o| matches!(o, Op::Ext(s) if *s as usize == k))
    }

    /// Whether the expression reads variable slot `k`.
    pub(crate) fn uses(&self, k: usize) -> bool {
        self.used & (1 << k) != 0
    }

    /// Whether the expression is exactly variable `k` (an identity mapping).
    pub(crate) fn is_var(&self, k: usize) -> bool {
        matches!(self.ops.as_slice(), [Op::Var(s)] if *s as usize == k)
    }

    /// The source text as written in the recipe.
    pub(crate) fn src(&self) -> &str {
        &self.src
    }
}

/// Refuses a text too long or blank.
fn check_text(src: &str) -> Result<(), ExprError> {
    if src.len() > MAX_LEN {
        return Err(ExprError::new(
            ExprErrorKind::TooDeep,
            format!(
                "the expression `{}…` is {} characters long; expected at most {MAX_LEN}",
                src.chars().take(24).collect::<String>(),
                src.len()
            ),
        ));
    }
    if src.trim().is_empty() {
        return Err(ExprError::new(
            ExprErrorKind::Syntax,
            "an empty expression; expected a number or an expression",
        ));
    }
    Ok(())
}

/// The state of [`Expr::compile_inner`]: the names, params and functions
/// an expression may use, and what the parse has met; it turns each run
/// of arithmetic, in meval's reverse Polish order, into a tree.
struct Compiler<'a> {
    /// The expression as written, for error messages.
    src: &'a str,
    /// The recipe's params, folded in as constants.
    params: &'a Params,
    /// The variable slots the expression may read.
    allowed: &'a [usize],
    /// The extra names of [`Expr::compile_ext`], if any.
    names: Option<&'a [&'a str]>,
    /// The trees built so far: the operands of the tokens to come.
    stack: Vec<Node>,
    /// The height of each tree on `stack`, to refuse one nested too deeply.
    heights: Vec<u32>,
    /// The operands of the current run parsed apart (calls, brackets, list
    /// reads), which its tokens name `HOLE` and their number.
    holes: Vec<Option<(Node, u32)>>,
    /// Bit k set when variable slot k is read.
    used: u32,
    /// `rand()` calls met so far.
    rands: u16,
    /// The values of the list params read so far ([`Op::At`]).
    data: Vec<f64>,
}

impl Compiler<'_> {
    /// The tree of one run of arithmetic: `rpn`, meval's reverse Polish
    /// tokens, over the operands `holes` parsed apart; with its height.
    fn run(&mut self, rpn: Vec<Token>, holes: Vec<(Node, u32)>) -> Result<(Node, u32), ExprError> {
        self.holes = holes.into_iter().map(Some).collect();
        for tok in rpn {
            self.push(tok)?;
        }
        if self.stack.len() != 1 {
            let n = self.stack.len();
            return Err(ExprError::new(
                ExprErrorKind::Syntax,
                format!(
                    "cannot read the expression `{}`: expected one value, found {n}",
                    self.src
                ),
            ));
        }
        let h = self.heights.pop().unwrap_or(1);
        self.heights.clear();
        Ok((self.stack.pop().expect("one tree"), h))
    }

    /// Takes one token: checks the depth, builds its node from the operands
    /// on the stack, and pushes it folded.
    fn push(&mut self, tok: Token) -> Result<(), ExprError> {
        if let Token::Var(name) = &tok {
            if let Some(k) = name.strip_prefix(HOLE) {
                let hole = k
                    .parse::<usize>()
                    .ok()
                    .and_then(|k| self.holes.get_mut(k)?.take());
                let (node, h) = hole.expect("each hole is named once");
                self.heights.push(h);
                self.stack.push(node);
                return Ok(());
            }
        }
        self.check_height(&tok)?;
        let node = match tok {
            Token::Number(v) => Node::Num(v),
            Token::Var(name) => self.name(name)?,
            Token::Unary(Operation::Minus) => Node::Neg(Box::new(self.pop()?)),
            Token::Unary(_) => self.pop()?,
            Token::Binary(op) => {
                let b = self.pop()?;
                let a = self.pop()?;
                Node::Bin(binary_op(op), Box::new(a), Box::new(b))
            }
            Token::Func(name, nargs) => self.call(name, nargs)?,
            other => {
                return Err(ExprError::new(
                    ExprErrorKind::Syntax,
                    format!(
                        "cannot read the expression `{}`: unexpected {other:?}",
                        self.src
                    ),
                ))
            }
        };
        self.stack.push(fold(node));
        Ok(())
    }

    /// Records the height of the tree `tok` makes (one more than its
    /// highest operand's) and refuses one over [`MAX_DEPTH`].
    fn check_height(&mut self, tok: &Token) -> Result<(), ExprError> {
        let takes = match tok {
            Token::Unary(_) => 1,
            Token::Binary(_) => 2,
            Token::Func(_, n) => n.unwrap_or(0),
            _ => 0,
        };
        let below = self.heights.len().saturating_sub(takes);
        let height = 1 + self.heights.drain(below..).max().unwrap_or(0);
        self.check_depth(height)?;
        self.heights.push(height);
        Ok(())
    }

    /// Refuses a tree `height` nodes high, over [`MAX_DEPTH`].
    fn check_depth(&self, height: u32) -> Result<(), ExprError> {
        if height > MAX_DEPTH {
            return Err(self.too_deep());
        }
        Ok(())
    }

    /// The error of an expression nested too deeply.
    fn too_deep(&self) -> ExprError {
        ExprError::new(
            ExprErrorKind::TooDeep,
            format!(
                "the expression `{}…` nests operations and calls more than {MAX_DEPTH} deep; expected a simpler expression",
                self.src.chars().take(24).collect::<String>()
            ),
        )
    }

    /// A call of no arguments `name()` the caller gives: `rand()` (a fresh
    /// slot each) or a name `name()` of [`Expr::compile_ext`].
    fn call0(&mut self, name: &str) -> Option<Node> {
        let names = self.names?;
        if let Some(k) = names
            .iter()
            .position(|n| n.strip_suffix("()") == Some(name))
        {
            return Some(Node::Ext(k as u16));
        }
        if name != "rand" {
            return None;
        }
        self.rands += 1;
        Some(Node::Ext((names.len() + self.rands as usize - 1) as u16))
    }

    /// Whether `name` is a list param.
    fn is_list(&self, name: &str) -> bool {
        self.params.list(name).is_some()
    }

    /// The values of list param `name`.
    fn list_values(&self, name: &str) -> Vec<f64> {
        self.params
            .list(name)
            .map_or_else(Vec::new, <[f64]>::to_vec)
    }

    /// How many values list param `name` has.
    fn list_len(&self, name: &str) -> usize {
        self.params.list(name).map_or(0, <[f64]>::len)
    }

    /// The number a quoted string at byte `at` stands for: one of the
    /// declared choices.
    fn symbol(&self, s: &str, at: usize) -> Result<f64, ExprError> {
        if let Some(v) = self.params.symbol(s) {
            return Ok(v);
        }
        let known: Vec<String> = self.params.symbols().map(|s| format!("'{s}'")).collect();
        Err(ExprError::new(
            ExprErrorKind::Name,
            if known.is_empty() {
                format!(
                    "the string '{s}' in `{}` (character {}) is no choice: this recipe declares no param with `choices`",
                    self.src,
                    self.src[..at].chars().count() + 1
                )
            } else {
                format!(
                    "the string '{s}' in `{}` is not one of the declared choices; expected one of {}",
                    self.src,
                    known.join(", ")
                )
            },
        ))
    }

    /// The operand on top of the stack.
    fn pop(&mut self) -> Result<Node, ExprError> {
        self.stack.pop().ok_or_else(|| {
            ExprError::new(
                ExprErrorKind::Syntax,
                format!(
                    "cannot read the expression `{}`: an operand is missing",
                    self.src
                ),
            )
        })
    }

    /// What `name` stands for, first match wins: an extra name, a param shadowing a later variable, an allowed variable, a param,
    /// `pi`, `e`.
    fn name(&mut self, name: String) -> Result<Node, ExprError> {
        let (src, params, allowed, names) = (self.src, self.params, self.allowed, self.names);
        let ext = names.and_then(|ns| ns.iter().position(|n| *n == name));
        Ok(if let Some(k) = ext {
            Node::Ext(k as u16)
        } else if let Some(v) = params
            .get(&name)
            .filter(|_| SHADOWABLE.contains(&name.as_str()))
        {
            // a param named like a later variable shadows it
            Node::Num(*v)
        } else if let Some(k) = VAR_NAMES.iter().position(|n| *n == name) {
            if !allowed.contains(&k) {
                return Err(ExprError::new(
                    ExprErrorKind::Name,
                    format!(
                        "`{name}` is not available in `{src}` here; it may use {}",
                        allowed_names(allowed, params)
                    ),
                ));
            }
            self.used |= 1 << k;
            Node::Var(k as u8)
        } else if let Some(v) = params.get(&name) {
            Node::Num(*v)
        } else if let Some(v) = constant(&name) {
            Node::Num(v)
        } else if params.list(&name).is_some() {
            return Err(ExprError::new(
                ExprErrorKind::Name,
                format!(
                    "`{name}` in `{src}` is a list; read one of its values as `{name}[k]` (k from 0), its length as `len({name})`"
                ),
            ));
        } else {
            return Err(ExprError::new(
                ExprErrorKind::Name,
                format!(
                    "unknown name `{name}` in `{src}`; it may use {}",
                    allowed_names(allowed, params)
                ),
            ));
        })
    }

    /// The call of `name` on the top `nargs` trees of the stack.
    fn call(&mut self, name: String, nargs: Option<usize>) -> Result<Node, ExprError> {
        let k = nargs.unwrap_or(0);
        let op = function_op(&name, k, self.src)?;
        if self.stack.len() < k {
            return Err(ExprError::new(
                ExprErrorKind::Syntax,
                format!(
                    "cannot read the expression `{}`: `{name}` lacks arguments",
                    self.src
                ),
            ));
        }
        let args = self.stack.split_off(self.stack.len() - k);
        Ok(Node::Call(op, args))
    }

    /// `list[k]`: the value when k is known, else the read of the list's
    /// values at run time.
    fn list_at(&mut self, name: &str, k: Node) -> Result<Node, ExprError> {
        let values = self.params.list(name).unwrap_or(&[]);
        if let Some(k) = k.num() {
            let v = list_at(values, k);
            if v.is_nan() && !values.iter().any(|x| x.is_nan()) {
                let n = values.len();
                return Err(ExprError::new(
                    ExprErrorKind::NotFinite,
                    format!(
                        "`{name}[{}]` in `{}`: the list has {n} value{}, read by whole numbers from 0 to {} (or from the end, -1 to -{n})",
                        short(k),
                        self.src,
                        if n == 1 { "" } else { "s" },
                        n as i64 - 1
                    ),
                ));
            }
            return Ok(Node::Num(v));
        }
        let off = self.data.len() as u32;
        self.data.extend_from_slice(values);
        let op = Op::At {
            off,
            len: values.len() as u32,
        };
        Ok(Node::Call(op, vec![k]))
    }

    /// The compiled expression: the tree, shallow enough for the
    /// run-time stack, emitted in reverse Polish order.
    fn finish(self, root: Node) -> Result<Expr, ExprError> {
        let src = self.src;
        if root.depth() > STACK {
            return Err(ExprError::new(
                ExprErrorKind::TooDeep,
                format!("the expression `{src}` is nested too deeply"),
            ));
        }
        let mut ops = Vec::new();
        root.emit(&mut ops);
        Ok(Expr {
            src: src.to_string(),
            ops,
            data: self.data,
            used: self.used,
            rands: self.rands,
        })
    }
}

/// The instruction of meval's binary operator `op`.
fn binary_op(op: Operation) -> Op {
    match op {
        Operation::Plus => Op::Add,
        Operation::Minus => Op::Sub,
        Operation::Times => Op::Mul,
        Operation::Div => Op::Div,
        Operation::Rem => Op::Rem,
        Operation::Pow => Op::Pow,
    }
}

/// The instruction calling function `name` with `k` arguments, or the error
/// saying how many it takes or that it is unknown.
fn function_op(name: &str, k: usize, src: &str) -> Result<Op, ExprError> {
    Ok(match (name, k) {
        ("min", 1..=255) => Op::Min(k as u8),
        ("max", 1..=255) => Op::Max(k as u8),
        ("min" | "max", _) => {
            return Err(ExprError::new(
                ExprErrorKind::Function,
                format!("`{name}` takes 1 to 255 arguments but is given {k} in `{src}`"),
            ))
        }
        (n, 1) if lookup1(n).is_some() => Op::F1(lookup1(n).unwrap()),
        (n, 2) if lookup2(n).is_some() => Op::F2(lookup2(n).unwrap()),
        (n, 3) if lookup3(n).is_some() => Op::F3(lookup3(n).unwrap()),
        (n, 4) if lookup4(n).is_some() => Op::Eca,
        (n, _) => return Err(arity_error(n, k, src)),
    })
}

/// The error for function `n` given `k` arguments, which no function of
/// that name takes: how many it does take, or that it is unknown.
fn arity_error(n: &str, k: usize, src: &str) -> ExprError {
    let arity = if lookup1(n).is_some() {
        Some(1)
    } else if lookup2(n).is_some() {
        Some(2)
    } else if lookup3(n).is_some() {
        Some(3)
    } else if lookup4(n).is_some() {
        Some(4)
    } else {
        None
    };
    ExprError::new(
        ExprErrorKind::Function,
        match arity {
            Some(a) => format!(
                "`{n}` takes {a} argument{} but is given {k} in `{src}`",
                if a == 1 { "" } else { "s" }
            ),
            None => format!("unknown function `{n}` in `{src}`; functions are: {FUNCTIONS}"),
        },
    )
}

fn fold(node: Node) -> Node {
    let all_const = match &node {
        Node::Num(_) | Node::Var(_) | Node::Ext(_) => return node,
        // a list's values are the expression's own data, not at hand here
        Node::Call(Op::At { .. }, _) => return node,
        Node::Neg(a) => a.num().is_some(),
        Node::Bin(_, a, b) => a.num().is_some() && b.num().is_some(),
        Node::Call(_, args) => args.iter().all(|a| a.num().is_some()),
    };
    if !all_const || node.depth() > STACK {
        return node; // too deep to fold: compile reports it
    }
    let mut ops = Vec::new();
    node.emit(&mut ops);
    Node::Num(run(
        &ops,
        &[],
        &[0.0; var::COUNT],
        &[],
        &mut Memo::default(),
    ))
}

/// Evaluates an expression over params only (a number written as text).
pub(crate) fn eval_const(src: &str, params: &Params) -> Result<f64, ExprError> {
    let e = Expr::compile(src, params, &[])?;
    let v = e.eval(&[0.0; var::COUNT]);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ExprError::new(
            ExprErrorKind::NotFinite,
            format!("`{src}` evaluates to {v}, not a finite number"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eval_many_gives_the_bits_of_eval_at_every_point() {
        let all: Vec<usize> = (0..var::COUNT).collect();
        let srcs = [
            "r*(0.8 + 0.2*sin(pi*z/200)) + 2*sin(6*theta + z/20)",
            "c*(1.2 - 0.4*z/200)",
            "-x^2 + y % 3 - z/(i+1)",
            "min(x, y, z) + max(x, -y) + clamp(x, -1, 1) + atan2(y, x) + step(0, t)",
            "mod(i, 7) * 1e-3 + sqrt(abs(x*y)) - v",
        ];
        // 150 points: two full passes of LANES and a part, odd values in
        // every variable (negative, fractional, near zero)
        let vars: Vec<Vars> = (0..150)
            .map(|k| {
                let k = k as f64;
                let mut v = [0.0; var::COUNT];
                for (s, slot) in v.iter_mut().enumerate() {
                    *slot = (k * 0.37 + s as f64 * 1.1).sin() * (10.0 + k) - 0.5;
                }
                v
            })
            .collect();
        for src in srcs {
            let e = Expr::compile(src, &Params::new(), &all).unwrap();
            let mut out = vec![0.0; vars.len()];
            e.eval_many(&vars, &mut out);
            for (v, got) in vars.iter().zip(&out) {
                assert_eq!(got.to_bits(), e.eval(v).to_bits(), "{src} at {v:?}");
            }
        }
    }

    fn ev(src: &str, vars: &Vars) -> f64 {
        let all: Vec<usize> = (0..var::COUNT).collect();
        Expr::compile(src, &Params::new(), &all).unwrap().eval(vars)
    }

    #[test]
    fn arithmetic_and_precedence() {
        let v = [0.0; var::COUNT];
        assert_eq!(ev("1+2*3", &v), 7.0);
        assert_eq!(ev("2^3^2", &v), 512.0);
        assert_eq!(ev("2**3", &v), 8.0);
        assert_eq!(ev("-2+5", &v), 3.0);
        assert_eq!(ev("7 % 4", &v), 3.0);
    }

    #[test]
    fn variables_and_params() {
        let mut p = Params::new();
        p.insert("radius".into(), 25.0);
        let e = Expr::compile("radius*sin(pi*z/10)+r", &p, &[var::Z, var::R]).unwrap();
        let mut v = [0.0; var::COUNT];
        v[var::Z] = 5.0;
        v[var::R] = 1.0;
        assert_eq!(e.eval(&v), 26.0);
        assert!(e.uses(var::Z) && e.uses(var::R) && !e.uses(var::X));
    }

    #[test]
    fn comparisons_logic_and_if() {
        let mut v = [0.0; var::COUNT];
        v[var::X] = 2.0;
        v[var::Y] = 3.0;
        assert_eq!(ev("x > 1", &v), 1.0);
        assert_eq!(ev("x*x + y*y >= 13", &v), 1.0);
        assert_eq!(ev("x == 2 and y != 3", &v), 0.0);
        assert_eq!(ev("x < 1 || y < 4", &v), 1.0);
        assert_eq!(ev("not (x < 1)", &v), 1.0);
        assert_eq!(ev("if(x <= 2, 10, 1/0)", &v), 10.0);
        assert_eq!(ev("if(x > 2, 10, -1) + 1", &v), 0.0);
        assert_eq!(ev("int(-2.7) + tau/pi + true - false", &v), 1.0);
        // the same bits in many lanes as one by one
        let e = Expr::compile("if(x < 1.5, x, -y) * (y >= x)", &Params::new(), &[0, 1]).unwrap();
        let vars: Vec<Vars> = (0..70)
            .map(|k| {
                let mut w = [0.0; var::COUNT];
                w[var::X] = k as f64 * 0.05;
                w[var::Y] = 3.0 - k as f64 * 0.07;
                w
            })
            .collect();
        let mut out = vec![0.0; vars.len()];
        e.eval_many(&vars, &mut out);
        for (w, got) in vars.iter().zip(&out) {
            assert_eq!(got.to_bits(), e.eval(w).to_bits());
        }
        let e = Expr::compile("x = 4", &Params::new(), &[0]).unwrap_err();
        assert!(e.message.contains("`=` alone"), "{e}");
    }

    #[test]
    fn lists_and_choices() {
        let mut p = Params::new();
        p.insert_list("fr", vec![1.0, 0.5, 0.25]);
        p.set_symbols(["wing_nut", "wing_bolt"]);
        p.insert("part_type".into(), 1.0);
        let e = Expr::compile("fr[i] + len(fr) + fr[-1]", &p, &[var::I]).unwrap();
        let mut v = [0.0; var::COUNT];
        v[var::I] = 1.0;
        assert_eq!(e.eval(&v), 0.5 + 3.0 + 0.25);
        v[var::I] = 3.0;
        assert!(e.eval(&v).is_nan());
        let e = Expr::compile("if(part_type == 'wing_bolt', 7, 8)", &p, &[]).unwrap();
        assert_eq!(e.constant(), Some(7.0));
        let e = Expr::compile("fr[3]", &p, &[]).unwrap_err();
        assert!(e.message.contains("the list has 3 values"), "{e}");
        let e = Expr::compile("fr + 1", &p, &[]).unwrap_err();
        assert!(e.message.contains("is a list"), "{e}");
        let e = Expr::compile("part_type == 'threaded_tube'", &p, &[]).unwrap_err();
        assert!(e.message.contains("'wing_nut', 'wing_bolt'"), "{e}");
    }

    #[test]
    fn every_function_is_in_the_list_errors_give() {
        // the names the lookups match, read from this file's source
        let src = include_str!("mod.rs");
        let listed: Vec<&str> = FUNCTIONS
            .split_whitespace()
            .map(|f| f.split('(').next().unwrap())
            .collect();
        let mut found = 0;
        for body in src.split("\nfn lookup").skip(1) {
            let body = &body[..body.find("\n}\n").unwrap()];
            for arm in body.lines().filter(|l| l.trim_start().starts_with('"')) {
                for name in arm.split("=>").next().unwrap().split('|') {
                    let name = name.trim().trim_matches('"');
                    if name.is_empty() || name == "_" {
                        continue;
                    }
                    found += 1;
                    assert!(listed.contains(&name), "`{name}` is not in FUNCTIONS");
                }
            }
        }
        assert!(found > 30, "{found} names found");
        for extra in ["min", "max", "len", "sum", "lerp"] {
            assert!(listed.contains(&extra), "{extra}");
        }
    }

    #[test]
    fn added_functions() {
        let v = [0.0; var::COUNT];
        assert_eq!(ev("mod(-1, 360)", &v), 359.0);
        assert_eq!(ev("clamp(5, 0, 2)", &v), 2.0);
        assert_eq!(ev("step(1, 0.5)", &v), 0.0);
        assert_eq!(ev("step(1, 1)", &v), 1.0);
        assert_eq!(ev("hypot(3, 4)", &v), 5.0);
        assert_eq!(ev("atan2(1, 0)", &v), std::f64::consts::FRAC_PI_2);
        assert_eq!(ev("min(3, 1, 2)", &v), 1.0);
        assert_eq!(ev("max(3, 1, 2)", &v), 3.0);
    }

    #[test]
    fn constants_fold() {
        let e = Expr::compile("2*pi*3", &Params::new(), &[]).unwrap();
        assert_eq!(e.constant(), Some(2.0 * std::f64::consts::PI * 3.0));
        let id = Expr::compile("theta", &Params::new(), &[var::THETA]).unwrap();
        assert!(id.is_var(var::THETA));
    }

    #[test]
    fn transcendental_functions_are_libm() {
        // the same bits as libm on every machine
        let v = [0.0; var::COUNT];
        assert_eq!(ev("sin(1.234)", &v).to_bits(), libm::sin(1.234).to_bits());
        assert_eq!(ev("1.5^0.3", &v).to_bits(), libm::pow(1.5, 0.3).to_bits());
    }

    #[test]
    fn extra_names_and_rand_slots() {
        let p = Params::new();
        let e = Expr::compile_ext("k*10 + rand() + rand ( )", &p, &[], &["j", "k"]).unwrap();
        assert_eq!(e.rands(), 2);
        assert_eq!(
            e.eval_ext(
                &[0.0; var::COUNT],
                &[1.0, 2.0, 0.25, 0.5],
                &mut Memo::default()
            ),
            20.75
        );
        assert!(Expr::compile("rand()", &p, &[]).is_err());
        let e = Expr::compile_ext("operand(1)", &p, &[], &[]).unwrap_err();
        assert!(e.message.contains("operand"), "{e}");
    }

    #[test]
    fn elementary_automaton() {
        // Rule 30 from one cell, rows 0..3 around column 0 on a wide ring:
        // 1 / 111 / 11001 / 1101111
        let row = |r: f64| -> String {
            (-3..=3)
                .map(|c| {
                    if eca(30.0, 64.0, r, c as f64) == 1.0 {
                        '1'
                    } else {
                        '0'
                    }
                })
                .collect()
        };
        assert_eq!(row(0.0), "0001000");
        assert_eq!(row(1.0), "0011100");
        assert_eq!(row(2.0), "0110010");
        assert_eq!(row(3.0), "1101111");
        assert!(eca(30.0, 65.0, 1.0, 0.0).is_nan());
        assert!(eca(30.5, 8.0, 1.0, 0.0).is_nan());
        // wraps: column -1 is column width-1
        assert_eq!(eca(30.0, 8.0, 1.0, -1.0), eca(30.0, 8.0, 1.0, 7.0));
    }

    #[test]
    fn automaton_rows_in_any_order_agree_with_a_plain_simulation() {
        // a reference that knows nothing of the cache: a ring of bools
        // stepped from row 0 by the rule's table
        fn plain(rule: u8, w: usize, rows: usize) -> Vec<Vec<bool>> {
            let mut cur = vec![false; w];
            cur[0] = true;
            let mut all = vec![cur.clone()];
            for _ in 0..rows {
                cur = (0..w)
                    .map(|i| {
                        let l = cur[(i + w - 1) % w] as u8;
                        let c = cur[i] as u8;
                        let r = cur[(i + 1) % w] as u8;
                        rule >> (l * 4 + c * 2 + r) & 1 == 1
                    })
                    .collect();
                all.push(cur.clone());
            }
            all
        }
        for (rule, w) in [(30u8, 64usize), (110, 37), (90, 1), (184, 13)] {
            let want = plain(rule, w, 1200);
            // down, up, jumping across kept rows, and a new automaton between
            let order: Vec<usize> = (0..=1200)
                .rev()
                .step_by(7)
                .chain((0..=1200).step_by(13))
                .chain([1199, 3, 700, 256, 255, 512, 1024, 0, 1200])
                .collect();
            for (k, &r) in order.iter().enumerate() {
                if k % 50 == 0 {
                    eca(rule.wrapping_add(1) as f64, 8.0, 5.0, 0.0);
                }
                for c in [0, w / 2, w - 1] {
                    let got = eca(rule as f64, w as f64, r as f64, c as f64);
                    assert_eq!(
                        got, want[r][c] as u8 as f64,
                        "rule {rule} w {w} row {r} col {c}"
                    );
                }
            }
        }
    }

    #[test]
    fn blank_text_is_an_error_not_a_panic() {
        for s in [" ", "\t", "\n", " \n\t "] {
            let e = Expr::compile(s, &Params::new(), &[]).unwrap_err();
            assert!(e.message.contains("empty expression"), "{e}");
        }
    }

    #[test]
    fn errors_name_the_problem() {
        let p = Params::new();
        let e = Expr::compile("sin(", &p, &[]).unwrap_err();
        assert!(e.message.contains("sin("), "{e}");
        let e = Expr::compile("foo + 1", &p, &[var::X]).unwrap_err();
        assert!(
            e.message.contains("unknown name `foo`") && e.message.contains("x"),
            "{e}"
        );
        let e = Expr::compile("bar(1)", &p, &[]).unwrap_err();
        assert!(e.message.contains("unknown function `bar`"), "{e}");
        let many = format!("max({})", vec!["1"; 40].join(","));
        let e = Expr::compile(&many, &p, &[]).unwrap_err();
        assert!(e.message.contains("nested too deeply"), "{e}");
        let e = Expr::compile("atan2(1)", &p, &[]).unwrap_err();
        assert!(e.message.contains("takes 2 arguments"), "{e}");
        let e = Expr::compile("c*2", &p, &[var::X]).unwrap_err();
        assert!(e.message.contains("`c` is not available"), "{e}");
        assert_eq!(e.kind, ExprErrorKind::Name);
        assert_eq!(
            eval_const("1/0", &p).unwrap_err().kind,
            ExprErrorKind::NotFinite
        );
    }
}
