//! A template parsed into its tree: text, legacy `[name]`s, and the code
//! of `{…}` blocks — statements, `if` blocks and expressions — each node
//! with the byte where it starts. The shared operators are
//! `base::grammar`'s; the arithmetic, the unary operators and the
//! functions are C's, as PrusaSlicer's placeholder parser reads them.

use std::collections::HashMap;

use super::lex::{is_ident, shown, Lexer, Lines, Tok};
use super::{MacroError, Value};
use crate::base::grammar::{self, Bin, Expected, Host, Sym};

/// Deepest tree accepted: nested brackets, calls, `if` blocks and the
/// length of one operator chain all count (a template is a few dozen
/// lines; a hostile one must not exhaust the stack).
pub(super) const MAX_DEPTH: usize = 100;

/// Most distinct `/patterns/` of one template (each one compiled once).
pub(super) const MAX_PATTERNS: usize = 64;

/// Largest compiled pattern and its lazy automaton's cache, bytes: with
/// [`MAX_PATTERNS`], a bound on the memory of one template's patterns.
pub(super) const PATTERN_SIZE: usize = 256 << 10;

/// A node of a template.
#[derive(Clone, Debug)]
pub(super) enum Node {
    /// Text written as it is.
    Text(String),
    /// `[name]`, `[name[index]]`, `[name_N]`.
    Legacy(String, Option<LegacyIndex>, usize),
    /// A statement of a `{…}` block.
    Stmt(Stmt),
    /// `{if c}…{elsif c}…{else}…{endif}` (or `if c then …`): the arms,
    /// then the `else` (empty without one).
    If(Vec<(Expr, Vec<Node>)>, Vec<Node>),
}

/// The index of a legacy `[name[index]]`.
#[derive(Clone, Debug)]
pub(super) enum LegacyIndex {
    Number(usize),
    Var(String),
}

/// A statement of a `{…}` block.
#[derive(Clone, Debug)]
pub(super) enum Stmt {
    /// An expression: its value is written.
    Output(Expr),
    /// `local name = …` or `global name = …`.
    New {
        global: bool,
        name: String,
        init: Init,
        at: usize,
    },
    /// `name = …` or `name[index] = …` of a variable made by a statement.
    Assign {
        name: String,
        index: Option<Expr>,
        init: Init,
        at: usize,
    },
}

/// The right side of a new variable or an assignment.
#[derive(Clone, Debug)]
pub(super) enum Init {
    /// An expression (a vector variable named alone is copied).
    Expr(Expr),
    /// `(a, b, …)`: a vector.
    List(Vec<Expr>, usize),
    /// `repeat(n, value)`: a vector of n copies.
    Repeat(Expr, Expr),
}

/// An expression and the byte it starts at.
#[derive(Clone, Debug)]
pub(super) struct Expr {
    pub(super) kind: Kind,
    pub(super) at: usize,
    /// Nodes on the longest path down from this one.
    height: u16,
}

/// What an expression is.
#[derive(Clone, Debug)]
pub(super) enum Kind {
    Lit(Value),
    Var(String),
    Index(String, Box<Expr>),
    Neg(Box<Expr>),
    Not(Box<Expr>),
    Arith(Arith, Box<Expr>, Box<Expr>),
    Logic(Bin, Box<Expr>, Box<Expr>),
    Cond(Box<Expr>, Box<Expr>, Box<Expr>),
    /// `a =~ /re/` (negated for `!~`): the pattern's number in the template.
    Match(Box<Expr>, usize, bool),
    Call(Func, Vec<Expr>),
    /// `one_of(s, …)`: strings, `/patterns/` and `~"patterns"`.
    OneOf(Box<Expr>, Vec<Choice>),
    /// `interpolate_table(x, (x0, y0), …)`.
    Table(Box<Expr>, Vec<(Expr, Expr)>),
}

/// An arithmetic operator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Arith {
    Add,
    Sub,
    Mul,
    Div,
    Mod,
}

/// A function of expressions (those of a variable reference take a
/// [`Kind::Var`] or [`Kind::Index`] argument).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Func {
    Min,
    Max,
    Int,
    Round,
    Digits,
    Zdigits,
    Random,
    IsNil,
    Size,
    Empty,
}

/// One alternative of `one_of`.
#[derive(Clone, Debug)]
pub(super) enum Choice {
    /// A string to equal.
    Equal(Expr),
    /// A `/pattern/` (its number) to match.
    Pattern(usize),
    /// `~expr`: a pattern computed.
    Computed(Expr),
}

impl Expr {
    /// The variables the expression reads, each with its byte.
    pub(super) fn walk(&self, add: &mut impl FnMut(&str, usize)) {
        match &self.kind {
            Kind::Lit(_) => {}
            Kind::Var(n) => add(n, self.at),
            Kind::Index(n, i) => {
                add(n, self.at);
                i.walk(add);
            }
            Kind::Neg(a) | Kind::Not(a) | Kind::Match(a, ..) => a.walk(add),
            Kind::Arith(_, a, b) | Kind::Logic(_, a, b) => {
                a.walk(add);
                b.walk(add);
            }
            Kind::Cond(c, a, b) => {
                c.walk(add);
                a.walk(add);
                b.walk(add);
            }
            Kind::Call(_, args) => args.iter().for_each(|a| a.walk(add)),
            Kind::OneOf(s, choices) => {
                s.walk(add);
                for c in choices {
                    if let Choice::Equal(e) | Choice::Computed(e) = c {
                        e.walk(add);
                    }
                }
            }
            Kind::Table(x, pts) => {
                x.walk(add);
                for (a, b) in pts {
                    a.walk(add);
                    b.walk(add);
                }
            }
        }
    }
}

/// The parser of a whole template.
pub(super) struct Parser<'a> {
    pub(super) lex: Lexer<'a>,
    depth: usize,
    /// The template's patterns, each compiled once, and their numbers.
    pub(super) patterns: Vec<regex::Regex>,
    known: HashMap<String, usize>,
}

/// Compiles `/pattern/` as the slicers match it (the whole subject), its
/// size and its automaton's cache capped.
pub(super) fn compile_pattern(pattern: &str) -> Result<regex::Regex, String> {
    regex::RegexBuilder::new(&format!("^(?:{pattern})$"))
        .size_limit(PATTERN_SIZE)
        .dfa_size_limit(PATTERN_SIZE)
        .build()
        .map_err(|e| format!("bad regular expression: {e}"))
}

impl<'a> Parser<'a> {
    /// A parser of `src`.
    pub(super) fn new(src: &'a str, lines: &'a Lines) -> Parser<'a> {
        Parser {
            lex: Lexer::new(src, lines),
            depth: 0,
            patterns: Vec::new(),
            known: HashMap::new(),
        }
    }

    fn error(&self, at: usize, message: impl Into<String>) -> MacroError {
        self.lex.error(at, message)
    }

    fn deeper(&mut self, at: usize) -> Result<(), MacroError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.error(at, format!("nested more than {MAX_DEPTH} deep")));
        }
        Ok(())
    }

    /// A node of `kind` at `at` over `children`: refused when the tree
    /// would be deeper than [`MAX_DEPTH`] (a flat chain of 20,000 `+`
    /// counts as deep as it is: evaluating it recurses that far).
    fn node(&self, kind: Kind, at: usize) -> Result<Expr, MacroError> {
        let below = |e: &Expr| e.height;
        let h = match &kind {
            Kind::Lit(_) | Kind::Var(_) => 0,
            Kind::Index(_, a) | Kind::Neg(a) | Kind::Not(a) | Kind::Match(a, ..) => below(a),
            Kind::Arith(_, a, b) | Kind::Logic(_, a, b) => below(a).max(below(b)),
            Kind::Cond(c, a, b) => below(c).max(below(a)).max(below(b)),
            Kind::Call(_, args) => args.iter().map(below).max().unwrap_or(0),
            Kind::OneOf(s, cs) => cs
                .iter()
                .map(|c| match c {
                    Choice::Equal(e) | Choice::Computed(e) => below(e),
                    Choice::Pattern(_) => 0,
                })
                .fold(below(s), u16::max),
            Kind::Table(x, pts) => pts
                .iter()
                .map(|(a, b)| below(a).max(below(b)))
                .fold(below(x), u16::max),
        } + 1;
        if h as usize > MAX_DEPTH {
            return Err(self.error(
                at,
                format!("an expression nested more than {MAX_DEPTH} deep (operators, brackets and calls inside one another)"),
            ));
        }
        Ok(Expr {
            kind,
            at,
            height: h,
        })
    }

    /// The number of `/pattern/` in the template, compiled once.
    fn pattern(&mut self, text: String, at: usize) -> Result<usize, MacroError> {
        if let Some(&k) = self.known.get(&text) {
            return Ok(k);
        }
        if self.patterns.len() >= MAX_PATTERNS {
            return Err(self.error(
                at,
                format!("more than {MAX_PATTERNS} different patterns in one template"),
            ));
        }
        let re = compile_pattern(&text).map_err(|m| self.error(at, m))?;
        self.patterns.push(re);
        self.known.insert(text, self.patterns.len() - 1);
        Ok(self.patterns.len() - 1)
    }

    /// Nodes up to the end or to an `{elsif}`, `{else}` or `{endif}`,
    /// returned with the keyword and its `{` (consumed up to the keyword).
    #[allow(clippy::type_complexity)]
    pub(super) fn block(
        &mut self,
    ) -> Result<(Vec<Node>, Option<(&'static str, usize)>), MacroError> {
        let s = self.lex.src.as_bytes();
        let mut nodes = Vec::new();
        loop {
            let start = self.lex.pos;
            let k = s[start..]
                .iter()
                .position(|b| matches!(b, b'[' | b'{'))
                .map_or(s.len(), |k| start + k);
            if k > start {
                nodes.push(Node::Text(self.lex.src[start..k].to_string()));
            }
            self.lex.pos = k;
            if k >= s.len() {
                return Ok((nodes, None));
            }
            self.lex.pos += 1;
            if s[k] == b'[' {
                nodes.push(self.legacy(k)?);
                continue;
            }
            let save = self.lex.pos;
            self.lex.skip_space();
            let word = self.lex.ident();
            if let Some(w) = ["elsif", "else", "endif"].into_iter().find(|w| *w == word) {
                return Ok((nodes, Some((w, k))));
            }
            self.lex.pos = save;
            self.code(k, &mut nodes)?;
        }
    }

    /// The code of a `{…}` whose `{` is at `open`, up to and with its `}`:
    /// statements separated by `;` and `if` blocks.
    fn code(&mut self, open: usize, nodes: &mut Vec<Node>) -> Result<(), MacroError> {
        loop {
            if self.lex.eat(";")? {
                continue;
            }
            let (t, at) = self.lex.peek()?;
            match t {
                Tok::Close => {
                    self.lex.next()?;
                    return Ok(());
                }
                Tok::End => return Err(self.error(open, "a `{` without its `}`")),
                Tok::Ident(w) if w == "if" => {
                    self.lex.next()?;
                    self.deeper(at)?;
                    let node = self.if_block(at)?;
                    self.depth -= 1;
                    nodes.push(node);
                    continue;
                }
                _ => {}
            }
            nodes.push(Node::Stmt(self.statement()?));
            match self.lex.peek()? {
                (Tok::Sym(";") | Tok::Close, _) => {}
                (t, at) => {
                    let t = shown(t);
                    return Err(self.error(
                        at,
                        format!("expected `;` or `}}` after a statement, found {t}"),
                    ));
                }
            }
        }
    }

    /// An `if` block after its `if`, up to its `endif` (the `}` after it is
    /// the enclosing code's).
    fn if_block(&mut self, open: usize) -> Result<Node, MacroError> {
        let mut arms = Vec::new();
        loop {
            let cond = self.expression()?;
            let (body, end) = self.arm_body(open, &["elsif", "else", "endif"])?;
            arms.push((cond, body));
            match end {
                "elsif" => continue,
                "else" => {
                    let (other, end) = self.arm_body(open, &["endif"])?;
                    debug_assert_eq!(end, "endif");
                    return Ok(Node::If(arms, other));
                }
                _ => return Ok(Node::If(arms, Vec::new())),
            }
        }
    }

    /// The body of one arm, as text (`}…{`) or as code (`then …` in the
    /// `if`; straight on after `else`), up to one of the keywords `ends`,
    /// consumed, which is returned.
    fn arm_body(
        &mut self,
        open: usize,
        ends: &[&'static str],
    ) -> Result<(Vec<Node>, &'static str), MacroError> {
        let mut body = Vec::new();
        if matches!(self.lex.peek()?.0, Tok::Close) {
            self.lex.next()?;
            let (nodes, end) = self.block()?;
            let Some((word, at)) = end else {
                return Err(self.error(open, "an `{if}` without `{endif}`"));
            };
            let Some(&w) = ends.iter().find(|e| **e == word) else {
                return Err(self.error(at, format!("`{{{word}}}` after `{{else}}`")));
            };
            return Ok((nodes, w));
        }
        self.lex.eat("then")?;
        loop {
            if self.lex.eat(";")? {
                continue;
            }
            let (t, at) = self.lex.peek()?;
            match t {
                Tok::Ident(w) => {
                    if let Some(&e) = ends.iter().find(|e| **e == w) {
                        self.lex.next()?;
                        return Ok((body, e));
                    }
                    if ["elsif", "else", "endif"].contains(&w.as_str()) {
                        let w = w.clone();
                        return Err(self.error(at, format!("`{w}` after `else`")));
                    }
                    if w == "if" {
                        self.lex.next()?;
                        self.deeper(at)?;
                        body.push(self.if_block(at)?);
                        self.depth -= 1;
                        continue;
                    }
                }
                Tok::End | Tok::Close => {
                    return Err(self.error(open, "an `{if}` without `{endif}`"))
                }
                _ => {}
            }
            body.push(Node::Stmt(self.statement()?));
        }
    }

    /// A statement: `local`/`global` name `=` …, an assignment, or an
    /// expression.
    fn statement(&mut self) -> Result<Stmt, MacroError> {
        let (t, at) = self.lex.peek()?;
        if let Tok::Ident(w) = t {
            if w == "local" || w == "global" {
                let global = w == "global";
                self.lex.next()?;
                let (name, _) = self.name()?;
                if !self.lex.eat("=")? {
                    let a = self.lex.at()?;
                    return Err(self.error(a, format!("expected `=` after `{name}`")));
                }
                let init = self.init()?;
                return Ok(Stmt::New {
                    global,
                    name,
                    init,
                    at,
                });
            }
        }
        let e = self.expression()?;
        if !self.lex.eat("=")? {
            return Ok(Stmt::Output(e));
        }
        let (name, index) = match e.kind {
            Kind::Var(n) => (n, None),
            Kind::Index(n, i) => (n, Some(*i)),
            _ => return Err(self.error(at, "only a variable can be assigned to")),
        };
        let init = self.init()?;
        Ok(Stmt::Assign {
            name,
            index,
            init,
            at,
        })
    }

    /// A name, its start.
    fn name(&mut self) -> Result<(String, usize), MacroError> {
        match self.lex.next()? {
            (Tok::Ident(w), at) => Ok((w, at)),
            (t, at) => Err(self.error(at, format!("expected a name, found {}", shown(&t)))),
        }
    }

    /// The right side of `=`: `(a, b, …)`, `repeat(n, v)` or an expression.
    fn init(&mut self) -> Result<Init, MacroError> {
        let (t, at) = self.lex.peek()?;
        if *t == Tok::Sym("(") {
            self.lex.next()?;
            let mut items = Vec::new();
            if !self.lex.eat(")")? {
                loop {
                    items.push(self.expression()?);
                    if self.lex.eat(")")? {
                        break;
                    }
                    self.expect(",")?;
                }
            }
            return Ok(Init::List(items, at));
        }
        if matches!(t, Tok::Ident(w) if w == "repeat") {
            self.lex.next()?;
            self.expect("(")?;
            let n = self.expression()?;
            self.expect(",")?;
            let v = self.expression()?;
            self.expect(")")?;
            return Ok(Init::Repeat(n, v));
        }
        Ok(Init::Expr(self.expression()?))
    }

    fn expect(&mut self, sym: &str) -> Result<(), MacroError> {
        if self.lex.eat(sym)? {
            return Ok(());
        }
        let (t, at) = self.lex.peek()?;
        let t = shown(t);
        Err(self.error(at, format!("expected `{sym}`, found {t}")))
    }

    /// An expression of the shared grammar over this language's operands.
    pub(super) fn expression(&mut self) -> Result<Expr, MacroError> {
        grammar::expression(self, &grammar::MACRO)
    }

    /// `a + b - …`, left to right.
    fn additive(&mut self) -> Result<Expr, MacroError> {
        let mut a = self.term()?;
        loop {
            let op = match self.lex.peek()? {
                (Tok::Sym("+"), _) => Arith::Add,
                (Tok::Sym("-"), _) => Arith::Sub,
                _ => return Ok(a),
            };
            let (_, at) = self.lex.next()?;
            let b = self.term()?;
            a = self.node(Kind::Arith(op, Box::new(a), Box::new(b)), at)?;
        }
    }

    /// `a * b / c % …`, left to right.
    fn term(&mut self) -> Result<Expr, MacroError> {
        let mut a = self.unary()?;
        loop {
            let op = match self.lex.peek()? {
                (Tok::Sym("*"), _) => Arith::Mul,
                (Tok::Sym("/"), _) => Arith::Div,
                (Tok::Sym("%"), _) => Arith::Mod,
                _ => return Ok(a),
            };
            let (_, at) = self.lex.next()?;
            let b = self.unary()?;
            a = self.node(Kind::Arith(op, Box::new(a), Box::new(b)), at)?;
        }
    }

    /// `-a`, `+a`, `!a`, `not a`, or a factor.
    fn unary(&mut self) -> Result<Expr, MacroError> {
        let (t, at) = self.lex.peek()?;
        let kind: fn(Box<Expr>) -> Kind = match t {
            Tok::Sym("-") => Kind::Neg,
            Tok::Sym("!") => Kind::Not,
            Tok::Ident(w) if w == "not" => Kind::Not,
            Tok::Sym("+") => {
                self.lex.next()?;
                self.deeper(at)?;
                let e = self.unary()?;
                self.depth -= 1;
                return Ok(e);
            }
            _ => return self.factor(),
        };
        self.lex.next()?;
        self.deeper(at)?;
        let a = self.unary()?;
        self.depth -= 1;
        self.node(kind(Box::new(a)), at)
    }

    fn factor(&mut self) -> Result<Expr, MacroError> {
        let (t, at) = self.lex.next()?;
        match t {
            Tok::Num(v) => self.node(Kind::Lit(v), at),
            Tok::Str(s) => self.node(Kind::Lit(Value::Str(s)), at),
            Tok::Sym("(") => {
                self.deeper(at)?;
                let e = self.expression()?;
                self.depth -= 1;
                if !self.lex.eat(")")? {
                    return Err(self.error(at, "a `(` without its `)`"));
                }
                Ok(e)
            }
            Tok::Ident(w) => self.named(w, at),
            t => Err(self.error(at, format!("expected a value, found {}", shown(&t)))),
        }
    }

    /// What a name starts: a literal, a function's call, or a variable.
    fn named(&mut self, w: String, at: usize) -> Result<Expr, MacroError> {
        let lit = match w.as_str() {
            "true" => Some(Value::Bool(true)),
            "false" => Some(Value::Bool(false)),
            _ => None,
        };
        if let Some(v) = lit {
            return self.node(Kind::Lit(v), at);
        }
        let func = match w.as_str() {
            "min" => Some((Func::Min, 2, 2)),
            "max" => Some((Func::Max, 2, 2)),
            "int" => Some((Func::Int, 1, 1)),
            "round" => Some((Func::Round, 1, 1)),
            "digits" => Some((Func::Digits, 2, 3)),
            "zdigits" => Some((Func::Zdigits, 2, 3)),
            "random" => Some((Func::Random, 2, 2)),
            "is_nil" => Some((Func::IsNil, 1, 1)),
            "size" => Some((Func::Size, 1, 1)),
            "empty" => Some((Func::Empty, 1, 1)),
            "one_of" | "interpolate_table" => None,
            _ => return self.variable(w, at),
        };
        if !matches!(self.lex.peek()?.0, Tok::Sym("(")) {
            return self.variable(w, at);
        }
        self.lex.next()?;
        self.deeper(at)?;
        let e = match func {
            None if w == "one_of" => self.one_of(at)?,
            None => self.table(at)?,
            Some((f, lo, hi)) => {
                let args = self.args(&w, lo, hi, at)?;
                if matches!(f, Func::IsNil | Func::Size | Func::Empty)
                    && !matches!(args[0].kind, Kind::Var(_) | Kind::Index(..))
                {
                    return Err(self.error(args[0].at, format!("`{w}` takes a variable")));
                }
                self.node(Kind::Call(f, args), at)?
            }
        };
        self.depth -= 1;
        Ok(e)
    }

    /// The arguments of `w(` up to its `)`: `lo` to `hi` of them.
    fn args(&mut self, w: &str, lo: usize, hi: usize, at: usize) -> Result<Vec<Expr>, MacroError> {
        let mut args = vec![self.expression()?];
        while self.lex.eat(",")? {
            args.push(self.expression()?);
        }
        if !self.lex.eat(")")? {
            return Err(self.error(at, format!("`{w}(` without its `)`")));
        }
        if !(lo..=hi).contains(&args.len()) {
            let n = if lo == hi {
                lo.to_string()
            } else {
                format!("{lo} or {hi}")
            };
            let s = if hi == 1 { "" } else { "s" };
            return Err(self.error(
                at,
                format!("`{w}` takes {n} argument{s}, not {}", args.len()),
            ));
        }
        Ok(args)
    }

    /// `name` or `name[index]`.
    fn variable(&mut self, w: String, at: usize) -> Result<Expr, MacroError> {
        if self.lex.eat("[")? {
            self.deeper(at)?;
            let i = self.expression()?;
            self.depth -= 1;
            if !self.lex.eat("]")? {
                return Err(self.error(at, format!("`{w}[` without its `]`")));
            }
            return self.node(Kind::Index(w, Box::new(i)), at);
        }
        self.node(Kind::Var(w), at)
    }

    /// `one_of(s, "a", /re/, ~expr, …)` after its `(`.
    fn one_of(&mut self, at: usize) -> Result<Expr, MacroError> {
        let s = self.expression()?;
        let mut choices = Vec::new();
        while self.lex.eat(",")? {
            if let Some((p, pat)) = self.lex.pattern()? {
                choices.push(Choice::Pattern(self.pattern(p, pat)?));
            } else if self.lex.eat("~")? {
                choices.push(Choice::Computed(self.expression()?));
            } else {
                choices.push(Choice::Equal(self.expression()?));
            }
        }
        self.expect(")")?;
        self.node(Kind::OneOf(Box::new(s), choices), at)
    }

    /// `interpolate_table(x, (x0, y0), …)` after its `(`.
    fn table(&mut self, at: usize) -> Result<Expr, MacroError> {
        let x = self.expression()?;
        let mut pts = Vec::new();
        while self.lex.eat(",")? {
            self.expect("(")?;
            let a = self.expression()?;
            self.expect(",")?;
            let b = self.expression()?;
            self.expect(")")?;
            pts.push((a, b));
        }
        self.expect(")")?;
        if pts.is_empty() {
            return Err(self.error(at, "`interpolate_table` takes a value and (x, y) points"));
        }
        self.node(Kind::Table(Box::new(x), pts), at)
    }

    /// A legacy `[name]`, `[name[index]]` after its `[` at `open`.
    fn legacy(&mut self, open: usize) -> Result<Node, MacroError> {
        let s = self.lex.src.as_bytes();
        let bad = |p: &Parser| {
            p.error(
                open,
                "a `[` that starts no variable; expected `[name]` or `[name[index]]`",
            )
        };
        let name = self.lex.ident().to_string();
        if name.is_empty() {
            return Err(bad(self));
        }
        let mut index = None;
        if s.get(self.lex.pos) == Some(&b'[') {
            self.lex.pos += 1;
            let i = self.lex.ident().to_string();
            index = Some(if i.is_empty() {
                let start = self.lex.pos;
                while s.get(self.lex.pos).is_some_and(u8::is_ascii_digit) {
                    self.lex.pos += 1;
                }
                let n = self.lex.src[start..self.lex.pos]
                    .parse()
                    .map_err(|_| bad(self))?;
                LegacyIndex::Number(n)
            } else {
                LegacyIndex::Var(i)
            });
            if s.get(self.lex.pos) != Some(&b']') {
                return Err(bad(self));
            }
            self.lex.pos += 1;
        }
        if s.get(self.lex.pos) != Some(&b']') {
            return Err(bad(self));
        }
        self.lex.pos += 1;
        debug_assert!(is_ident(name.as_bytes()[0], false));
        Ok(Node::Legacy(name, index, open))
    }
}

impl Host for Parser<'_> {
    type Node = Expr;
    type Error = MacroError;

    fn peek_sym(&mut self) -> Result<Option<(Sym, usize)>, MacroError> {
        self.lex.sym()
    }

    fn bump(&mut self) {
        let _ = self.lex.next();
    }

    fn operand(&mut self) -> Result<Expr, MacroError> {
        self.additive()
    }

    fn matches(&mut self, left: Expr, negated: bool, at: usize) -> Result<Expr, MacroError> {
        let Some((p, pat)) = self.lex.pattern()? else {
            let m = if negated { "!~" } else { "=~" };
            let a = self.lex.at()?;
            return Err(self.error(a, format!("expected /regex/ after `{m}`")));
        };
        let k = self.pattern(p, pat)?;
        self.node(Kind::Match(Box::new(left), k, negated), at)
    }

    fn binary(&mut self, op: Bin, a: Expr, b: Expr, at: usize) -> Result<Expr, MacroError> {
        self.node(Kind::Logic(op, Box::new(a), Box::new(b)), at)
    }

    fn not(&mut self, a: Expr, at: usize) -> Result<Expr, MacroError> {
        self.node(Kind::Not(Box::new(a)), at)
    }

    fn ternary(&mut self, c: Expr, a: Expr, b: Expr, at: usize) -> Result<Expr, MacroError> {
        self.node(Kind::Cond(Box::new(c), Box::new(a), Box::new(b)), at)
    }

    fn enter(&mut self, at: usize) -> Result<(), MacroError> {
        self.deeper(at)
    }

    fn leave(&mut self) {
        self.depth -= 1;
    }

    fn expected(&mut self, what: Expected, at: usize) -> MacroError {
        match what {
            Expected::Colon => self.error(at, "a `?` without its `:`"),
            Expected::OneComparison => self.error(at, "a second comparison"),
        }
    }
}
