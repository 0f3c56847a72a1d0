//! The pre-pass that gives meval's arithmetic the rest of the language:
//! comparisons (`< <= == != >= >`), `and`/`&&`, `or`/`||`, `not`/`!`,
//! quoted strings (a choice param's strings), and list params read as
//! `name[k]` and `len(name)`.
//!
//! meval's tokenizer knows only `+ - * / % ^`, so the text is rewritten into
//! calls it can read before it sees it: `a < b` becomes `__lt(a, b)`,
//! `a and b` `__and(a, b)`, `not a` `__not(a)`, `name[k]` `__at_name(k)`,
//! `'wing_nut'` and `len(name)` the numbers they stand for. Precedence, from
//! loosest: `or`, `and`, `not`, one comparison (a chain `a < b < c` is
//! refused), then meval's arithmetic. Text without any of these is handed
//! on unchanged. Every byte of the rewritten text remembers the byte of the
//! source it comes from, so meval's errors point into the text as written.

use super::{ExprError, ExprErrorKind, Params};

/// The rewritten text and, per byte of it, the byte of the source it came from.
pub(super) struct Lowered {
    pub text: String,
    pub from: Vec<usize>,
}

/// Prefix of the call a list index becomes: `__at_NAME(k)`.
pub(super) const AT: &str = "__at_";

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    /// Arithmetic the pre-pass copies as it is (numbers, names, `+ - * / % ^`).
    Text,
    Ident,
    Str(String),
    Open,
    Close,
    LBracket,
    RBracket,
    Comma,
    Cmp(&'static str),
    And,
    Or,
    Not,
}

struct Token {
    tok: Tok,
    start: usize,
    end: usize,
}

fn syntax(src: &str, at: usize, what: &str) -> ExprError {
    ExprError {
        kind: ExprErrorKind::Syntax,
        message: format!(
            "cannot read the expression `{src}`: {what} at character {}",
            at + 1
        ),
    }
}

/// The length of the number or arithmetic at byte `k` of `b`: up to the
/// next byte the pre-pass itself reads, a number's exponent (`1e-3`) with it.
fn text_len(b: &[u8], k: usize) -> usize {
    let n = b[k..]
        .iter()
        .position(|x| b" \t\n\r()[],'\"<>=!&|".contains(x) || x.is_ascii_alphabetic() || *x == b'_')
        .unwrap_or(b.len() - k);
    let mut n = n.max(1);
    while k + n < b.len()
        && (b[k + n] == b'e' || b[k + n] == b'E')
        && b[k..k + n].iter().all(|x| x.is_ascii_digit() || *x == b'.')
    {
        let m = b[k + n + 1..]
            .iter()
            .position(|x| !(x.is_ascii_digit() || *x == b'+' || *x == b'-'))
            .unwrap_or(b.len() - k - n - 1);
        n += 1 + m;
    }
    n
}

fn tokens(src: &str) -> Result<Vec<Token>, ExprError> {
    let b = src.as_bytes();
    let mut out = Vec::new();
    let mut k = 0;
    while k < b.len() {
        let c = b[k];
        let start = k;
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
                let s = &src[k + 1..k + 1 + end];
                (Tok::Str(s.to_string()), end + 2)
            }
            b'<' if two(b"<=") => (Tok::Cmp("__le"), 2),
            b'<' => (Tok::Cmp("__lt"), 1),
            b'>' if two(b">=") => (Tok::Cmp("__ge"), 2),
            b'>' => (Tok::Cmp("__gt"), 1),
            b'=' if two(b"==") => (Tok::Cmp("__eq"), 2),
            b'!' if two(b"!=") => (Tok::Cmp("__ne"), 2),
            b'!' => (Tok::Not, 1),
            b'&' if two(b"&&") => (Tok::And, 2),
            b'|' if two(b"||") => (Tok::Or, 2),
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
                    "and" => Tok::And,
                    "or" => Tok::Or,
                    "not" => Tok::Not,
                    _ => Tok::Ident,
                };
                (tok, n)
            }
            _ => (Tok::Text, text_len(b, k)),
        };
        k += len;
        out.push(Token {
            tok,
            start,
            end: start + len,
        });
    }
    Ok(out)
}

/// Whether `src` uses anything of this pre-pass: if not it goes to meval as it is.
fn needs_lowering(toks: &[Token], src: &str, params: &Params) -> bool {
    toks.iter().enumerate().any(|(k, t)| match t.tok {
        Tok::Text | Tok::Open | Tok::Close | Tok::Comma => false,
        Tok::Ident => {
            let name = &src[t.start..t.end];
            name == "len" && toks.get(k + 1).is_some_and(|n| n.tok == Tok::Open)
                || params.list(name).is_some()
        }
        _ => true,
    })
}

/// Rewrites `src` for meval (see the module's text).
pub(super) fn lower(src: &str, params: &Params) -> Result<Lowered, ExprError> {
    let toks = tokens(src)?;
    if !needs_lowering(&toks, src, params) {
        return Ok(Lowered {
            text: src.to_string(),
            from: (0..src.len()).collect(),
        });
    }
    let mut p = Parser {
        src,
        params,
        toks,
        k: 0,
        out: Lowered {
            text: String::with_capacity(src.len() * 2),
            from: Vec::new(),
        },
    };
    p.or()?;
    if let Some(t) = p.toks.get(p.k) {
        let what = match t.tok {
            Tok::Close | Tok::RBracket => "a closing bracket without its opening one",
            Tok::Comma => "a `,` outside a function's arguments",
            Tok::Cmp(_) => "a second comparison (write `a < b and b < c`)",
            _ => "an unexpected token",
        };
        return Err(syntax(src, t.start, what));
    }
    Ok(p.out)
}

struct Parser<'a> {
    src: &'a str,
    params: &'a Params,
    toks: Vec<Token>,
    k: usize,
    out: Lowered,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.k).map(|t| &t.tok)
    }

    /// Appends `s`, every byte of it from source byte `at`.
    fn emit(&mut self, s: &str, at: usize) {
        self.out.text.push_str(s);
        self.out.from.extend(std::iter::repeat_n(at, s.len()));
    }

    /// Appends source bytes `a..b` as they are.
    fn copy(&mut self, a: usize, b: usize) {
        self.out.text.push_str(&self.src[a..b]);
        self.out.from.extend(a..b);
    }

    fn at(&self) -> usize {
        self.toks.get(self.k).map_or(self.src.len(), |t| t.start)
    }

    /// A binary level: `next` terms joined by `op`, folded into calls of `f`.
    fn chain(
        &mut self,
        op: Tok,
        f: &str,
        next: fn(&mut Self) -> Result<(), ExprError>,
    ) -> Result<(), ExprError> {
        let mark = self.out.text.len();
        let at = self.at();
        next(self)?;
        while self.peek() == Some(&op) {
            let op_at = self.at();
            self.k += 1;
            // wrap what is written so far: f(left, right)
            let left = self.out.text.split_off(mark);
            let left_from = self.out.from.split_off(mark);
            self.emit(&format!("{f}("), at);
            self.out.text.push_str(&left);
            self.out.from.extend(left_from);
            self.emit(",", op_at);
            next(self)?;
            self.emit(")", op_at);
        }
        Ok(())
    }

    fn or(&mut self) -> Result<(), ExprError> {
        self.chain(Tok::Or, "__or", Self::and)
    }

    fn and(&mut self) -> Result<(), ExprError> {
        self.chain(Tok::And, "__and", Self::not)
    }

    fn not(&mut self) -> Result<(), ExprError> {
        if self.peek() == Some(&Tok::Not) {
            let at = self.at();
            self.k += 1;
            self.emit("__not(", at);
            self.not()?;
            self.emit(")", at);
            return Ok(());
        }
        self.cmp()
    }

    fn cmp(&mut self) -> Result<(), ExprError> {
        let mark = self.out.text.len();
        let at = self.at();
        self.arith()?;
        if let Some(&Tok::Cmp(f)) = self.peek() {
            let op_at = self.at();
            self.k += 1;
            let left = self.out.text.split_off(mark);
            let left_from = self.out.from.split_off(mark);
            self.emit(&format!("{f}("), at);
            self.out.text.push_str(&left);
            self.out.from.extend(left_from);
            self.emit(",", op_at);
            self.arith()?;
            self.emit(")", op_at);
        }
        Ok(())
    }

    /// Arithmetic up to the next comparison, logic word, `,` or closing
    /// bracket at this depth: copied, with its brackets, strings and list
    /// reads rewritten.
    fn arith(&mut self) -> Result<(), ExprError> {
        let start = self.out.text.len();
        while let Some(t) = self.toks.get(self.k) {
            let (a, b) = (t.start, t.end);
            // the white space before a token stays, so positions read alike
            let gap = self.k.checked_sub(1).map_or(0, |j| self.toks[j].end);
            match t.tok.clone() {
                Tok::Cmp(_) | Tok::And | Tok::Or | Tok::Comma | Tok::Close | Tok::RBracket => break,
                Tok::Not => {
                    return Err(syntax(
                        self.src,
                        a,
                        "`not` inside arithmetic (put it in parentheses: `(not a)`)",
                    ))
                }
                Tok::Text => {
                    self.copy(gap, b);
                    self.k += 1;
                }
                Tok::Str(s) => {
                    self.copy(gap, a);
                    let v = self.string(&s, a)?;
                    self.emit(&format!("{v}"), a);
                    self.k += 1;
                }
                Tok::LBracket => {
                    return Err(syntax(
                        self.src,
                        a,
                        "a `[` after something that is not a list param",
                    ));
                }
                Tok::Open => {
                    self.copy(gap, b);
                    self.k += 1;
                    self.args(Tok::Close, ")")?;
                }
                Tok::Ident => self.ident(gap, a, b)?,
            }
        }
        if self.out.text.len() == start {
            return Err(syntax(self.src, self.at(), "a value is missing"));
        }
        Ok(())
    }

    /// A name: a list read `name[k]`, `len(name)`, or a name meval reads.
    fn ident(&mut self, gap: usize, a: usize, b: usize) -> Result<(), ExprError> {
        let name = &self.src[a..b];
        let next = self.toks.get(self.k + 1).map(|t| t.tok.clone());
        let is_list = self.params.list(name).is_some();
        if is_list && next == Some(Tok::LBracket) {
            self.copy(gap, a);
            self.emit(&format!("{AT}{name}("), a);
            self.k += 2;
            self.or()?;
            self.expect(Tok::RBracket, "]")?;
            self.emit(")", b);
            return Ok(());
        }
        if name == "len" && next == Some(Tok::Open) {
            let arg = self.toks.get(self.k + 2);
            let close = self.toks.get(self.k + 3).map(|t| &t.tok);
            if let (Some(arg), Some(Tok::Close)) = (arg, close) {
                if let Some(list) = self.params.list(&self.src[arg.start..arg.end]) {
                    let n = list.len();
                    self.copy(gap, a);
                    self.emit(&format!("{n}"), a);
                    self.k += 4;
                    return Ok(());
                }
            }
            return Err(syntax(
                self.src,
                a,
                "`len` takes the name of a list param, as `len(name)`",
            ));
        }
        self.copy(gap, b);
        self.k += 1;
        Ok(())
    }

    /// Comma-separated expressions up to the closing `close`.
    fn args(&mut self, close: Tok, text: &str) -> Result<(), ExprError> {
        if self.peek() == Some(&close) {
            let gap = self.toks[self.k - 1].end;
            self.copy(gap, self.toks[self.k].end);
            self.k += 1;
            return Ok(());
        }
        loop {
            self.or()?;
            match self.peek() {
                Some(Tok::Comma) => {
                    let (gap, end) = (self.toks[self.k - 1].end, self.toks[self.k].end);
                    self.copy(gap, end);
                    self.k += 1;
                }
                _ => return self.expect(close, text),
            }
        }
    }

    fn expect(&mut self, tok: Tok, text: &str) -> Result<(), ExprError> {
        if self.peek() == Some(&tok) {
            let gap = self.toks[self.k - 1].end;
            if tok == Tok::Close {
                self.copy(gap, self.toks[self.k].end);
            }
            self.k += 1;
            Ok(())
        } else {
            Err(syntax(self.src, self.at(), &format!("`{text}` expected")))
        }
    }

    /// The number a quoted string stands for: one of the declared choices.
    fn string(&self, s: &str, at: usize) -> Result<f64, ExprError> {
        if let Some(v) = self.params.symbol(s) {
            return Ok(v);
        }
        let known: Vec<String> = self.params.symbols().map(|s| format!("'{s}'")).collect();
        Err(ExprError {
            kind: ExprErrorKind::Name,
            message: if known.is_empty() {
                format!(
                    "the string '{s}' in `{}` (character {}) is no choice: this recipe declares no param with `choices`",
                    self.src,
                    at + 1
                )
            } else {
                format!(
                    "the string '{s}' in `{}` is not one of the declared choices; expected one of {}",
                    self.src,
                    known.join(", ")
                )
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rewritten text without its spaces (or the error's message).
    fn low(src: &str) -> String {
        let mut p = Params::new();
        p.insert_list("xs", vec![1.0, 2.0]);
        p.set_symbols(["a", "b"]);
        lower(src, &p)
            .map(|l| l.text.replace(' ', ""))
            .unwrap_or_else(|e| e.message)
    }

    #[test]
    fn rewrites_comparisons_logic_strings_and_lists() {
        assert_eq!(low("1 + 2*x"), "1+2*x");
        assert_eq!(low("x < 1"), "__lt(x,1)");
        assert_eq!(low("x+1 >= y*2"), "__ge(x+1,y*2)");
        assert_eq!(
            low("x < 1 and y > 2 or z"),
            "__or(__and(__lt(x,1),__gt(y,2)),z)"
        );
        assert_eq!(low("not x == 1"), "__not(__eq(x,1))");
        assert_eq!(low("if(k == 'b', 1, 2)"), "if(__eq(k,1),1,2)");
        assert_eq!(low("xs[i+1]*2"), "__at_xs(i+1)*2");
        assert_eq!(low("len(xs) - 1"), "2-1");
        assert_eq!(low("max(x != 0, 1e-3 <= y)"), "max(__ne(x,0),__le(1e-3,y))");
        assert_eq!(low("!(a || b) && c"), "__and(__not((__or(a,b))),c)");
    }

    #[test]
    fn the_rewritten_text_points_back_into_the_source() {
        let p = Params::new();
        let l = lower("x <= 1", &p).unwrap();
        // `1` of the output comes from character 6 of the source
        let k = l.text.find('1').unwrap();
        assert_eq!(l.from[k], 5);
        assert_eq!(l.from.len(), l.text.len());
    }

    #[test]
    fn mistakes_are_named() {
        assert!(low("x = 1").contains("`=` alone"));
        assert!(low("x < 1 < 2").contains("second comparison"));
        assert!(low("k == 'c'").contains("expected one of 'a', 'b'"));
        assert!(low("x & y").contains("single `&`"));
        assert!(low("'open").contains("closing quote"));
        assert!(low("y[1]").contains("not a list param"));
        assert!(low("x <").contains("value is missing"));
    }
}
