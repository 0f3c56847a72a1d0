//! The operators the recipe's expressions (`base::expr`) and the slicers'
//! macros (`base::slicer_macro`) share — the ternary `c ? a : b`, `or`,
//! `and`, `not`, the comparisons and the macros' pattern match — in one
//! precedence table and one parser over it. Each language brings its own
//! tokens and operands through [`Host`]: its lexer says which token is
//! which shared operator, and everything that binds tighter than a
//! comparison (the arithmetic: meval's for a recipe, C's for a macro) is
//! the host's operand.
//!
//! The table, loosest first (the C grammar's, as PrusaSlicer's placeholder
//! parser has it):
//!
//! | level | operators | associativity |
//! |---|---|---|
//! | ternary | `c ? a : b` | right |
//! | or | `or`, `\|\|` | left |
//! | and | `and`, `&&` | left |
//! | not (recipe only) | `not`, `!` | prefix |
//! | equality | `==`, `!=`, `<>`, `=~ /re/`, `!~ /re/` | left |
//! | relational | `<`, `<=`, `>`, `>=` | left |
//!
//! What the two languages do differently is one row of [`Dialect`] each:
//! a recipe's `not` binds looser than a comparison (`not x == 1` is
//! `not (x == 1)`, as in Python) and a second comparison in a row is
//! refused (`a < b < c` would not mean what it says); a macro's `not` is
//! a unary operator of its operands (C's `!`), and comparisons chain as C's.
//!
//! The parser recurses once per level and once per nested ternary or `not`
//! (the host's [`Host::enter`] counts the latter), and builds every chain
//! of one level in a loop: the host's node constructors see each node and
//! refuse a tree deeper than its cap, so no input can exhaust the stack.

/// A comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Cmp {
    /// `==`
    Eq,
    /// `!=`, `<>`
    Ne,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
}

impl Cmp {
    /// Whether it is of the equality level (`==`, `!=`), else relational.
    fn is_equality(self) -> bool {
        matches!(self, Cmp::Eq | Cmp::Ne)
    }

    /// Whether `a op b` holds for an ordering of a and b.
    pub(crate) fn holds(self, ord: std::cmp::Ordering) -> bool {
        use std::cmp::Ordering::*;
        match self {
            Cmp::Eq => ord == Equal,
            Cmp::Ne => ord != Equal,
            Cmp::Lt => ord == Less,
            Cmp::Le => ord != Greater,
            Cmp::Gt => ord == Greater,
            Cmp::Ge => ord != Less,
        }
    }
}

/// A shared operator, as a language's lexer reads it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Sym {
    /// `?` of the ternary.
    Question,
    /// `:` of the ternary.
    Colon,
    /// `or`, `||`
    Or,
    /// `and`, `&&`
    And,
    /// `not`, `!`
    Not,
    /// A comparison.
    Cmp(Cmp),
    /// `=~` (or `!~`, negated): the right side is a pattern the host reads.
    Match {
        /// `!~`
        negated: bool,
    },
}

/// A binary node of the shared grammar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Bin {
    /// `or`
    Or,
    /// `and`
    And,
    /// A comparison.
    Cmp(Cmp),
}

/// What one language does differently in the table (see the module's text).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Dialect {
    /// `not` binds looser than the comparisons (else the host reads it as a
    /// unary operator of its operands).
    pub(crate) loose_not: bool,
    /// A comparison may take another comparison as its operand.
    pub(crate) chains: bool,
}

/// The recipe's expressions: Python's `not`, one comparison at a time.
pub(crate) const RECIPE: Dialect = Dialect {
    loose_not: true,
    chains: false,
};

/// The slicers' macros: C's `!`, comparisons chain.
pub(crate) const MACRO: Dialect = Dialect {
    loose_not: false,
    chains: true,
};

/// What the shared parser expected and did not find.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Expected {
    /// The `:` of a ternary whose `?` is at the place.
    Colon,
    /// One comparison only (the place is the second's).
    OneComparison,
}

/// A language as the shared parser sees it: its tokens, operands and nodes.
pub(crate) trait Host {
    /// A node of the language's tree.
    type Node;
    /// The language's error.
    type Error;
    /// The next token and its byte offset when it is a shared operator
    /// (not consumed); `None` for any other token.
    fn peek_sym(&mut self) -> Result<Option<(Sym, usize)>, Self::Error>;
    /// Consumes the token [`Host::peek_sym`] returned.
    fn bump(&mut self);
    /// An operand: all that binds tighter than a comparison.
    fn operand(&mut self) -> Result<Self::Node, Self::Error>;
    /// `left =~ pattern` (or `!~`), the `=~` consumed at byte `at`: reads
    /// the pattern and makes the node.
    fn matches(
        &mut self,
        left: Self::Node,
        negated: bool,
        at: usize,
    ) -> Result<Self::Node, Self::Error>;
    /// The node `a op b`, the operator at byte `at`.
    fn binary(
        &mut self,
        op: Bin,
        a: Self::Node,
        b: Self::Node,
        at: usize,
    ) -> Result<Self::Node, Self::Error>;
    /// The node `not a`.
    fn not(&mut self, a: Self::Node, at: usize) -> Result<Self::Node, Self::Error>;
    /// The node `c ? a : b`.
    fn ternary(
        &mut self,
        c: Self::Node,
        a: Self::Node,
        b: Self::Node,
        at: usize,
    ) -> Result<Self::Node, Self::Error>;
    /// One level deeper of nesting (a ternary's branch, a `not`'s operand,
    /// or the host's own brackets), refused past the host's cap at `at`.
    fn enter(&mut self, at: usize) -> Result<(), Self::Error>;
    /// Back one level.
    fn leave(&mut self);
    /// The error for what was `expected` at byte `at`.
    fn expected(&mut self, what: Expected, at: usize) -> Self::Error;
}

/// An expression of the shared grammar: a ternary, or an `or` chain.
pub(crate) fn expression<H: Host>(h: &mut H, d: &Dialect) -> Result<H::Node, H::Error> {
    let c = or(h, d)?;
    let Some((Sym::Question, at)) = h.peek_sym()? else {
        return Ok(c);
    };
    h.bump();
    h.enter(at)?;
    let a = expression(h, d)?;
    if !matches!(h.peek_sym()?, Some((Sym::Colon, _))) {
        return Err(h.expected(Expected::Colon, at));
    }
    h.bump();
    let b = expression(h, d)?;
    h.leave();
    h.ternary(c, a, b, at)
}

/// `a or b or …`, left to right.
fn or<H: Host>(h: &mut H, d: &Dialect) -> Result<H::Node, H::Error> {
    let mut a = and(h, d)?;
    while let Some((Sym::Or, at)) = h.peek_sym()? {
        h.bump();
        let b = and(h, d)?;
        a = h.binary(Bin::Or, a, b, at)?;
    }
    Ok(a)
}

/// `a and b and …`, left to right.
fn and<H: Host>(h: &mut H, d: &Dialect) -> Result<H::Node, H::Error> {
    let mut a = not(h, d)?;
    while let Some((Sym::And, at)) = h.peek_sym()? {
        h.bump();
        let b = not(h, d)?;
        a = h.binary(Bin::And, a, b, at)?;
    }
    Ok(a)
}

/// `not a` where `not` binds looser than comparisons; else a comparison.
fn not<H: Host>(h: &mut H, d: &Dialect) -> Result<H::Node, H::Error> {
    if d.loose_not {
        if let Some((Sym::Not, at)) = h.peek_sym()? {
            h.bump();
            h.enter(at)?;
            let a = not(h, d)?;
            h.leave();
            return h.not(a, at);
        }
    }
    Ok(equality(h, d)?.0)
}

/// `a == b`, `a != b`, `a =~ /re/`, …, left to right; with whether the
/// node is a comparison (for [`Dialect::chains`]).
fn equality<H: Host>(h: &mut H, d: &Dialect) -> Result<(H::Node, bool), H::Error> {
    let (mut a, mut compared) = relational(h, d)?;
    loop {
        let (op, at) = match h.peek_sym()? {
            Some((Sym::Cmp(c), at)) if c.is_equality() => (c, at),
            Some((Sym::Match { negated }, at)) => {
                h.bump();
                a = h.matches(a, negated, at)?;
                compared = true;
                continue;
            }
            _ => return Ok((a, compared)),
        };
        if compared && !d.chains {
            return Err(h.expected(Expected::OneComparison, at));
        }
        h.bump();
        let (b, right) = relational(h, d)?;
        if right && !d.chains {
            return Err(h.expected(Expected::OneComparison, at));
        }
        a = h.binary(Bin::Cmp(op), a, b, at)?;
        compared = true;
    }
}

/// `a < b`, `a >= b`, …, left to right.
fn relational<H: Host>(h: &mut H, d: &Dialect) -> Result<(H::Node, bool), H::Error> {
    let mut a = h.operand()?;
    let mut compared = false;
    while let Some((Sym::Cmp(op), at)) = h.peek_sym()? {
        if op.is_equality() {
            break;
        }
        if compared && !d.chains {
            return Err(h.expected(Expected::OneComparison, at));
        }
        h.bump();
        let b = h.operand()?;
        a = h.binary(Bin::Cmp(op), a, b, at)?;
        compared = true;
    }
    Ok((a, compared))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A toy language: single letters are operands, written back with
    /// brackets showing the tree.
    struct Toy {
        toks: Vec<(char, usize)>,
        k: usize,
        depth: usize,
    }

    impl Toy {
        fn new(s: &str) -> Toy {
            let toks = s
                .char_indices()
                .filter(|(_, c)| !c.is_whitespace())
                .map(|(k, c)| (c, k))
                .collect();
            Toy {
                toks,
                k: 0,
                depth: 0,
            }
        }
    }

    impl Host for Toy {
        type Node = String;
        type Error = String;
        fn peek_sym(&mut self) -> Result<Option<(Sym, usize)>, String> {
            Ok(self.toks.get(self.k).and_then(|&(c, at)| {
                let s = match c {
                    '?' => Sym::Question,
                    ':' => Sym::Colon,
                    '|' => Sym::Or,
                    '&' => Sym::And,
                    '!' => Sym::Not,
                    '=' => Sym::Cmp(Cmp::Eq),
                    '<' => Sym::Cmp(Cmp::Lt),
                    '~' => Sym::Match { negated: false },
                    _ => return None,
                };
                Some((s, at))
            }))
        }
        fn bump(&mut self) {
            self.k += 1;
        }
        fn operand(&mut self) -> Result<String, String> {
            match self.toks.get(self.k) {
                Some(&(c, _)) if c.is_ascii_alphabetic() => {
                    self.k += 1;
                    Ok(c.to_string())
                }
                Some(&(c, at)) => Err(format!("`{c}` at {at}")),
                None => Err("end".into()),
            }
        }
        fn matches(&mut self, left: String, _: bool, _: usize) -> Result<String, String> {
            let p = self.operand()?;
            Ok(format!("({left}~{p})"))
        }
        fn binary(&mut self, op: Bin, a: String, b: String, _: usize) -> Result<String, String> {
            let o = match op {
                Bin::Or => "|",
                Bin::And => "&",
                Bin::Cmp(Cmp::Eq) => "=",
                Bin::Cmp(_) => "<",
            };
            Ok(format!("({a}{o}{b})"))
        }
        fn not(&mut self, a: String, _: usize) -> Result<String, String> {
            Ok(format!("!{a}"))
        }
        fn ternary(&mut self, c: String, a: String, b: String, _: usize) -> Result<String, String> {
            Ok(format!("({c}?{a}:{b})"))
        }
        fn enter(&mut self, at: usize) -> Result<(), String> {
            self.depth += 1;
            if self.depth > 8 {
                return Err(format!("too deep at {at}"));
            }
            Ok(())
        }
        fn leave(&mut self) {
            self.depth -= 1;
        }
        fn expected(&mut self, what: Expected, at: usize) -> String {
            format!("{what:?} at {at}")
        }
    }

    fn parse(s: &str, d: &Dialect) -> String {
        let mut t = Toy::new(s);
        let r = expression(&mut t, d).unwrap_or_else(|e| e);
        if t.k < t.toks.len() {
            return format!("{r} then {:?}", &t.toks[t.k..]);
        }
        r
    }

    #[test]
    fn the_table_binds_as_documented() {
        for d in [&RECIPE, &MACRO] {
            assert_eq!(parse("a | b & c", d), "(a|(b&c))");
            assert_eq!(parse("a & b | c & d", d), "((a&b)|(c&d))");
            assert_eq!(parse("a = b & c < d", d), "((a=b)&(c<d))");
            assert_eq!(parse("a | b ? c : d ? e : f", d), "((a|b)?c:(d?e:f))");
            assert_eq!(parse("a ~ b | c", d), "((a~b)|c)");
            assert_eq!(parse("a ? b c", d), "Colon at 2 then [('c', 6)]");
        }
        // a recipe's `not` takes a comparison; a macro's is its host's
        assert_eq!(parse("! a = b", &RECIPE), "!(a=b)");
        assert!(parse("! a = b", &MACRO).starts_with("`!` at 0"));
        // chains: C's for macros, refused for recipes
        assert_eq!(parse("a = b < c", &MACRO), "(a=(b<c))");
        assert_eq!(parse("a < b < c", &MACRO), "((a<b)<c)");
        assert!(parse("a < b < c", &RECIPE).starts_with("OneComparison at 6"));
        assert!(parse("a = b < c", &RECIPE).starts_with("OneComparison at 2"));
        assert!(parse("a = b = c", &RECIPE).starts_with("OneComparison at 6"));
    }

    #[test]
    fn nesting_is_counted() {
        let deep = "!".repeat(20) + "a";
        assert!(parse(&deep, &RECIPE).starts_with("too deep"));
        let ternaries = "a?".repeat(20) + "b" + &":c".repeat(20);
        assert!(parse(&ternaries, &MACRO).starts_with("too deep"));
    }
}
