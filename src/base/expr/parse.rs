//! The one parse of a recipe expression into the tree [`super::Compiler`]
//! compiles: the shared operators (`c ? a : b`, `or`/`||`, `and`/`&&`,
//! `not`/`!`, the comparisons) by `base::grammar`'s table, the arithmetic
//! between them by meval's shunting-yard (its tokens: numbers, names,
//! `+ - * / % ^` and the unary signs), and the rest of the language —
//! calls, brackets, a list param's `name[k]`, `len(name)`, a choice's
//! quoted string, `rand()` — as operands of the arithmetic, each parsed
//! where it stands. Every token keeps its byte span in the text as
//! written, so every error points at the user's own characters; nothing is
//! rewritten as text.
//!
//! Precedence, loosest first: `?:`, `or`, `and`, `not`, one comparison (a
//! chain `a < b < c` is refused), then meval's arithmetic (`+ -`, `* / %`,
//! unary `-`, `^` and `**`, right to left).

use meval::tokenizer::{Operation, Token};

use super::{ExprError, ExprErrorKind, Node, Op, MAX_DEPTH};
use crate::base::grammar::{self, Bin, Cmp, Expected, Host, Sym};

/// A token of a recipe expression.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Ident,
    /// A quoted string, its text without the quotes.
    Str(String),
    Open,
    Close,
    LBracket,
    RBracket,
    Comma,
    /// One of meval's arithmetic operators (`**` is `^`).
    Arith(Operation),
    /// A shared operator.
    Sym(Sym),
    End,
}

/// A token and its bytes in the text.
#[derive(Clone, Debug)]
struct Lexeme {
    tok: Tok,
    start: usize,
    end: usize,
}

/// `cannot read the expression …: {what} at character N`.
pub(super) fn syntax(src: &str, at: usize, what: &str) -> ExprError {
    ExprError::new(
        ExprErrorKind::Syntax,
        format!(
            "cannot read the expression `{src}`: {what} at character {}",
            src[..at.min(src.len())].chars().count() + 1
        ),
    )
}

/// meval's words for a token it cannot take at `at`: `unexpected `…``.
fn unexpected(src: &str, at: usize) -> ExprError {
    let rest: String = src.get(at..).unwrap_or("").chars().take(12).collect();
    syntax(src, at, &format!("unexpected `{rest}`"))
}

/// The length of the number at the start of `b` as meval reads one
/// (digits, an optional `.` and digits, an optional exponent).
fn number_len(b: &[u8]) -> usize {
    let digits = |k: usize| b[k..].iter().take_while(|c| c.is_ascii_digit()).count();
    let mut n = digits(0);
    if b.get(n) == Some(&b'.') {
        n += 1 + digits(n + 1);
    }
    if matches!(b.get(n), Some(b'e' | b'E')) {
        let sign = usize::from(matches!(b.get(n + 1), Some(b'+' | b'-')));
        let d = digits(n + 1 + sign);
        if d > 0 {
            n += 1 + sign + d;
        }
    }
    n
}

fn lex(src: &str) -> Result<Vec<Lexeme>, ExprError> {
    let b = src.as_bytes();
    let mut out = Vec::new();
    let mut k = 0;
    while k < b.len() {
        let c = b[k];
        let two = |s: &[u8]| b[k..].starts_with(s);
        let (tok, len) = match c {
            b' ' | b'\t' | b'\n' | b'\r' => {
                k += 1;
                continue;
            }
            b'(' => (Tok::Open, 1),
            b')' => (Tok::Close, 1),
            b'[' => (Tok::LBracket, 1),
            b']' => (Tok::RBracket, 1),
            b',' => (Tok::Comma, 1),
            b'\'' | b'"' => {
                let end = b[k + 1..]
                    .iter()
                    .position(|&x| x == c)
                    .ok_or_else(|| syntax(src, k, "a quoted string without its closing quote"))?;
                (Tok::Str(src[k + 1..k + 1 + end].to_string()), end + 2)
            }
            b'*' if two(b"**") => (Tok::Arith(Operation::Pow), 2),
            b'+' => (Tok::Arith(Operation::Plus), 1),
            b'-' => (Tok::Arith(Operation::Minus), 1),
            b'*' => (Tok::Arith(Operation::Times), 1),
            b'/' => (Tok::Arith(Operation::Div), 1),
            b'%' => (Tok::Arith(Operation::Rem), 1),
            b'^' => (Tok::Arith(Operation::Pow), 1),
            b'<' if two(b"<=") => (Tok::Sym(Sym::Cmp(Cmp::Le)), 2),
            b'<' => (Tok::Sym(Sym::Cmp(Cmp::Lt)), 1),
            b'>' if two(b">=") => (Tok::Sym(Sym::Cmp(Cmp::Ge)), 2),
            b'>' => (Tok::Sym(Sym::Cmp(Cmp::Gt)), 1),
            b'=' if two(b"==") => (Tok::Sym(Sym::Cmp(Cmp::Eq)), 2),
            b'!' if two(b"!=") => (Tok::Sym(Sym::Cmp(Cmp::Ne)), 2),
            b'!' => (Tok::Sym(Sym::Not), 1),
            b'&' if two(b"&&") => (Tok::Sym(Sym::And), 2),
            b'|' if two(b"||") => (Tok::Sym(Sym::Or), 2),
            b'?' => (Tok::Sym(Sym::Question), 1),
            b':' => (Tok::Sym(Sym::Colon), 1),
            b'=' => return Err(syntax(src, k, "`=` alone (compare with `==`)")),
            b'&' | b'|' => {
                return Err(syntax(
                    src,
                    k,
                    "a single `&` or `|` (write `and`/`&&`, `or`/`||`)",
                ))
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let n = b[k..]
                    .iter()
                    .position(|x| !(x.is_ascii_alphanumeric() || *x == b'_'))
                    .unwrap_or(b.len() - k);
                let tok = match &src[k..k + n] {
                    "and" => Tok::Sym(Sym::And),
                    "or" => Tok::Sym(Sym::Or),
                    "not" => Tok::Sym(Sym::Not),
                    _ => Tok::Ident,
                };
                (tok, n)
            }
            c if c.is_ascii_digit() => {
                let n = number_len(&b[k..]);
                let v = src[k..k + n].parse().map_err(|_| unexpected(src, k))?;
                (Tok::Num(v), n)
            }
            _ => return Err(unexpected(src, k)),
        };
        out.push(Lexeme {
            tok,
            start: k,
            end: k + len,
        });
        k += len;
    }
    out.push(Lexeme {
        tok: Tok::End,
        start: b.len(),
        end: b.len(),
    });
    Ok(out)
}

/// The prefix of the name that stands for an operand parsed apart (a
/// call, a bracket, a list read) in the tokens given to meval: no name of
/// the text can start with it.
pub(super) const HOLE: char = '\u{1}';

/// Parses `src` into its tree with `c`'s names, params and functions.
pub(super) fn parse<'a>(src: &'a str, c: &mut super::Compiler<'a>) -> Result<Node, ExprError> {
    let toks = lex(src)?;
    let mut p = Parser {
        src,
        toks,
        k: 0,
        depth: 0,
        c,
    };
    let root = grammar::expression(&mut p, &grammar::RECIPE)?;
    let t = &p.toks[p.k];
    let what = match t.tok {
        Tok::End => return Ok(root.0),
        Tok::Close | Tok::RBracket => "a closing bracket without its opening one",
        Tok::Comma => "a `,` outside a function's arguments",
        Tok::Sym(Sym::Colon) => "a `:` without its `?`",
        _ => return Err(unexpected(src, t.start)),
    };
    Err(syntax(src, t.start, what))
}

/// A node and its height (nodes on the longest path down).
type Tall = (Node, u32);

struct Parser<'a, 'c> {
    src: &'a str,
    toks: Vec<Lexeme>,
    k: usize,
    depth: u32,
    c: &'c mut super::Compiler<'a>,
}

impl Parser<'_, '_> {
    fn tok(&self) -> &Lexeme {
        &self.toks[self.k]
    }

    /// A node over `args` (heights known), folded; refused past
    /// [`MAX_DEPTH`].
    fn node(&self, node: Node, args: &[u32]) -> Result<Tall, ExprError> {
        let h = 1 + args.iter().copied().max().unwrap_or(0);
        self.c.check_depth(h)?;
        Ok((super::fold(node), h))
    }

    /// An operand of the arithmetic: a number, a name, or a part parsed
    /// apart (a bracket, a call, a list read, a string).
    fn atom(&mut self, holes: &mut Vec<Tall>) -> Result<Option<Token>, ExprError> {
        let t = self.tok().clone();
        let hole = |holes: &mut Vec<Tall>, n: Tall| {
            holes.push(n);
            Token::Var(format!("{HOLE}{}", holes.len() - 1))
        };
        Ok(Some(match t.tok {
            Tok::Num(v) => {
                self.k += 1;
                Token::Number(v)
            }
            Tok::Str(s) => {
                self.k += 1;
                let v = self.c.symbol(&s, t.start)?;
                hole(holes, (Node::Num(v), 1))
            }
            Tok::Open => {
                self.k += 1;
                let e = self.nested(t.start)?;
                self.expect(Tok::Close)?;
                hole(holes, e)
            }
            Tok::Ident => {
                let name = &self.src[t.start..t.end];
                self.k += 1;
                match self.tok().tok {
                    Tok::Open => hole(holes, self.call(name, t.start)?),
                    Tok::LBracket if self.c.is_list(name) => hole(holes, self.list(name, t.start)?),
                    Tok::LBracket => {
                        let at = self.tok().start;
                        return Err(syntax(
                            self.src,
                            at,
                            "a `[` after something that is not a list param",
                        ));
                    }
                    _ => Token::Var(name.to_string()),
                }
            }
            Tok::Sym(Sym::Not) => {
                return Err(syntax(
                    self.src,
                    t.start,
                    "`not` inside arithmetic (put it in parentheses: `(not a)`)",
                ))
            }
            Tok::End => {
                return Err(ExprError::new(
                    ExprErrorKind::Syntax,
                    format!(
                        "cannot read the expression `{}`: it ends where a value was expected",
                        self.src
                    ),
                ))
            }
            Tok::Sym(_) | Tok::Comma | Tok::Close | Tok::RBracket => {
                return Err(syntax(self.src, t.start, "a value is missing"))
            }
            _ => return Ok(None),
        }))
    }

    /// A full expression one level deeper (inside brackets).
    fn nested(&mut self, at: usize) -> Result<Tall, ExprError> {
        self.enter(at)?;
        let e = grammar::expression(self, &grammar::RECIPE)?;
        self.leave();
        Ok(e)
    }

    fn expect(&mut self, tok: Tok) -> Result<(), ExprError> {
        if self.tok().tok == tok {
            self.k += 1;
            return Ok(());
        }
        let t = self.tok().clone();
        Err(match (tok, &t.tok) {
            (Tok::Close, Tok::End) => ExprError::new(
                ExprErrorKind::Syntax,
                format!(
                    "cannot read the expression `{}`: 1 closing parenthesis missing",
                    self.src
                ),
            ),
            (Tok::Close, Tok::Comma) => {
                syntax(self.src, t.start, "a `,` outside a function's arguments")
            }
            (Tok::RBracket, _) => syntax(self.src, t.start, "`]` expected"),
            _ => unexpected(self.src, t.start),
        })
    }

    /// `name(args…)` at `at`, its `(` next: `len(list)`, `rand()`, a
    /// function of no arguments of the caller's, or a function.
    fn call(&mut self, name: &str, at: usize) -> Result<Tall, ExprError> {
        let open = self.tok().start;
        self.k += 1;
        if self.tok().tok == Tok::Close {
            if let Some(n) = self.c.call0(name) {
                self.k += 1;
                return Ok((n, 1));
            }
        }
        if name == "len" {
            let t = self.tok().clone();
            let list = self.src[t.start..t.end].to_string();
            if t.tok == Tok::Ident
                && self.toks[self.k + 1].tok == Tok::Close
                && self.c.is_list(&list)
            {
                self.k += 2;
                return Ok((Node::Num(self.c.list_len(&list) as f64), 1));
            }
            return Err(syntax(
                self.src,
                at,
                "`len` takes the name of a list param, as `len(name)`",
            ));
        }
        if name == "sum" {
            return self.sum(at, open);
        }
        let mut args = Vec::new();
        if self.tok().tok == Tok::Close {
            self.k += 1;
        } else {
            loop {
                args.push(self.nested(open)?);
                if self.tok().tok == Tok::Comma {
                    self.k += 1;
                    continue;
                }
                self.expect(Tok::Close)?;
                break;
            }
        }
        let op = super::function_op(name, args.len(), self.src)?;
        let heights: Vec<u32> = args.iter().map(|a| a.1).collect();
        let node = Node::Call(op, args.into_iter().map(|a| a.0).collect());
        self.node(node, &heights)
    }

    /// `sum(list)` or `sum(list, a, b)` at `at`, after its `(` at `open`:
    /// the list param's values k = a..b (b included; 0 when b < a), summed
    /// in order. The bounds must be known when the expression is read
    /// (numbers, params, a list param's loop name), so the sum is a number.
    fn sum(&mut self, at: usize, open: usize) -> Result<Tall, ExprError> {
        let usage = "`sum` takes the name of a list param and, optionally, the first and last index: `sum(name)`, `sum(name, a, b)`";
        let t = self.tok().clone();
        let list = self.src[t.start..t.end].to_string();
        if t.tok != Tok::Ident || !self.c.is_list(&list) {
            return Err(syntax(self.src, at, usage));
        }
        self.k += 1;
        let values = self.c.list_values(&list);
        let (a, b) = if self.tok().tok == Tok::Comma {
            self.k += 1;
            let a = self.nested(open)?;
            if self.tok().tok != Tok::Comma {
                return Err(syntax(self.src, at, usage));
            }
            self.k += 1;
            let b = self.nested(open)?;
            let (Some(a), Some(b)) = (a.0.num(), b.0.num()) else {
                return Err(syntax(
                    self.src,
                    at,
                    "`sum(name, a, b)`'s a and b must be known before the print (numbers or params), not values of the path",
                ));
            };
            (a, b)
        } else {
            (0.0, values.len() as f64 - 1.0)
        };
        self.expect(Tok::Close)?;
        Ok((
            Node::Num(
                sum_of(&values, a, b)
                    .map_err(|m| syntax(self.src, at, &format!("`{list}`: {m}")))?,
            ),
            1,
        ))
    }

    /// `list[k]` at `at`, its `[` next.
    fn list(&mut self, name: &str, at: usize) -> Result<Tall, ExprError> {
        self.k += 1;
        let k = self.nested(at)?;
        self.expect(Tok::RBracket)?;
        let node = self.c.list_at(name, k.0)?;
        self.node(node, &[k.1])
    }

    /// The arithmetic from here to the next shared operator, `,` or closing
    /// bracket: its tokens in meval's reverse Polish order, compiled.
    fn arithmetic(&mut self) -> Result<Tall, ExprError> {
        let mut run: Vec<Token> = Vec::new();
        let mut holes: Vec<Tall> = Vec::new();
        loop {
            // a value, after any unary signs
            while let Tok::Arith(op @ (Operation::Plus | Operation::Minus)) = self.tok().tok {
                run.push(Token::Unary(op));
                self.k += 1;
            }
            let t = self.tok().clone();
            match self.atom(&mut holes)? {
                Some(tok) => run.push(tok),
                None => return Err(unexpected(self.src, t.start)),
            }
            // then an operator, or the end of the arithmetic
            match self.tok().tok {
                Tok::Arith(op) => {
                    run.push(Token::Binary(op));
                    self.k += 1;
                }
                _ => break,
            }
        }
        let rpn = meval::shunting_yard::to_rpn(&run).map_err(|e| {
            ExprError::new(
                ExprErrorKind::Syntax,
                format!("cannot read the expression `{}`: {e}", self.src),
            )
        })?;
        self.c.run(rpn, holes)
    }
}

impl Host for Parser<'_, '_> {
    type Node = Tall;
    type Error = ExprError;

    fn peek_sym(&mut self) -> Result<Option<(Sym, usize)>, ExprError> {
        let t = self.tok();
        Ok(match t.tok {
            Tok::Sym(s) => Some((s, t.start)),
            _ => None,
        })
    }

    fn bump(&mut self) {
        self.k += 1;
    }

    fn operand(&mut self) -> Result<Tall, ExprError> {
        self.arithmetic()
    }

    fn matches(&mut self, _: Tall, _: bool, at: usize) -> Result<Tall, ExprError> {
        Err(unexpected(self.src, at))
    }

    fn binary(&mut self, op: Bin, a: Tall, b: Tall, _: usize) -> Result<Tall, ExprError> {
        let f: super::F2 = match op {
            Bin::Or => super::f_or,
            Bin::And => super::f_and,
            Bin::Cmp(Cmp::Eq) => super::f_eq,
            Bin::Cmp(Cmp::Ne) => super::f_ne,
            Bin::Cmp(Cmp::Lt) => super::f_lt,
            Bin::Cmp(Cmp::Le) => super::f_le,
            Bin::Cmp(Cmp::Gt) => super::f_gt,
            Bin::Cmp(Cmp::Ge) => super::f_ge,
        };
        self.node(Node::Call(Op::F2(f), vec![a.0, b.0]), &[a.1, b.1])
    }

    fn not(&mut self, a: Tall, _: usize) -> Result<Tall, ExprError> {
        self.node(Node::Call(Op::F1(super::f_not), vec![a.0]), &[a.1])
    }

    fn ternary(&mut self, c: Tall, a: Tall, b: Tall, _: usize) -> Result<Tall, ExprError> {
        let h = [c.1, a.1, b.1];
        self.node(Node::Call(Op::F3(super::f_if), vec![c.0, a.0, b.0]), &h)
    }

    fn enter(&mut self, _: usize) -> Result<(), ExprError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.c.too_deep());
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth -= 1;
    }

    fn expected(&mut self, what: Expected, at: usize) -> ExprError {
        match what {
            Expected::Colon => syntax(self.src, at, "a `?` without its `:`"),
            Expected::OneComparison => syntax(
                self.src,
                at,
                "a second comparison (write `a < b and b < c`)",
            ),
        }
    }
}

/// The sum of `values[a..=b]` in order (0 when b < a): a and b whole
/// numbers, within the list when the range is not empty.
fn sum_of(values: &[f64], a: f64, b: f64) -> Result<f64, String> {
    if a.fract() != 0.0 || b.fract() != 0.0 {
        return Err(format!(
            "the first and last index must be whole numbers, not {a} and {b}"
        ));
    }
    if b < a {
        return Ok(0.0);
    }
    let n = values.len() as f64;
    if a < 0.0 || b >= n {
        return Err(format!(
            "the list has {} value{}: indices 0 to {}, not {a} to {b}",
            values.len(),
            if values.len() == 1 { "" } else { "s" },
            n - 1.0
        ));
    }
    Ok(values[a as usize..=b as usize].iter().sum())
}

#[cfg(test)]
mod tests {
    use super::super::{var, Expr, Params};

    fn params() -> Params {
        let mut p = Params::new();
        p.insert_list("xs", vec![1.0, 2.0]);
        p.set_symbols(["a", "b", "é"]);
        p.insert("k".into(), 1.0);
        p
    }

    /// The value of `src` at x = 2, y = 3, or its error's message.
    fn val(src: &str) -> Result<f64, String> {
        let all: Vec<usize> = (0..var::COUNT).collect();
        let mut v = [0.0; var::COUNT];
        v[var::X] = 2.0;
        v[var::Y] = 3.0;
        Expr::compile(src, &params(), &all)
            .map(|e| e.eval(&v))
            .map_err(|e| e.message)
    }

    #[test]
    fn one_tree_for_logic_and_arithmetic() {
        assert_eq!(val("1 + 2*x"), Ok(5.0));
        assert_eq!(val("x < 1 and y > 2 or 1"), Ok(1.0));
        assert_eq!(val("not x == 1"), Ok(1.0));
        assert_eq!(val("!(x == 2 || y == 2) && 1"), Ok(0.0));
        assert_eq!(val("if(k == 'b', 1, 2)"), Ok(1.0));
        assert_eq!(val("xs[k - 1] * 2 + len(xs)"), Ok(4.0));
        assert_eq!(val("max(x != 0, 1e-3 <= y) + (y >= x) * 3"), Ok(4.0));
        // the ternary of the shared grammar, right to left
        assert_eq!(val("x > 2 ? 10 : y > 2 ? 20 : 30"), Ok(20.0));
        // meval's arithmetic: powers right to left, above the unary minus
        assert_eq!(val("-2^2 + 2**3**0"), Ok(-2.0));
        assert_eq!(val("2^-1"), Ok(0.5));
    }

    #[test]
    fn errors_point_at_the_characters_as_written() {
        let e = |s: &str| val(s).unwrap_err();
        assert!(e("x = 1").contains("`=` alone (compare with `==`) at character 3"));
        assert!(
            e("x < 1 < 2").contains("second comparison (write `a < b and b < c`) at character 7")
        );
        assert!(e("x == 1 < 2").contains("second comparison"));
        assert!(e("k == 'c'").contains("expected one of 'a', 'b', 'é'"));
        assert!(e("x & y").contains("single `&`"));
        assert!(e("'open").contains("closing quote at character 1"));
        assert!(e("y[1]").contains("not a list param at character 2"));
        assert!(e("x + not y")
            .contains("`not` inside arithmetic (put it in parentheses: `(not a)`) at character 5"));
        assert!(e("max(1, 2 +* 3)").contains("unexpected `* 3)` at character 11"));
        assert!(e("x ? 1").contains("`?` without its `:` at character 3"));
        assert!(e("1, 2").contains("`,` outside a function's arguments at character 2"));
        assert!(e("(x + 1").contains("1 closing parenthesis missing"));
        assert!(e("x )").contains("closing bracket without its opening one at character 3"));
        assert!(e("x <").contains("it ends where a value was expected"));
        // characters, not bytes: the column after a multi-byte letter
        assert!(
            e("'é' + * 2").contains("unexpected `* 2` at character 7"),
            "{}",
            e("'é' + * 2")
        );
        // the pre-pass's names are no longer functions of the language
        assert!(e("__lt(1, 2)").contains("unknown function `__lt`"));
    }

    #[test]
    fn nesting_is_refused_before_the_stack_runs_out() {
        let deep = format!("{}1{}", "(".repeat(2000), ")".repeat(2000));
        assert!(val(&deep)
            .unwrap_err()
            .contains("nests operations and calls more than 256 deep"));
        let nots = format!("{}1", "not ".repeat(1000));
        assert!(val(&nots).unwrap_err().contains("more than 256 deep"));
        let chain = format!("1{}", " or 1".repeat(700));
        assert!(val(&chain).unwrap_err().contains("more than 256 deep"));
    }
}
