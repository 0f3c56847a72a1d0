//! The tokens of a macro's code (inside `{…}`), read once each: the lexer
//! keeps the one token looked at ahead, so parsing is linear in the text.

use super::{MacroError, Value};
use crate::base::grammar::{Cmp, Sym};

/// A token of a macro's code.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Tok {
    /// An integer or a real literal.
    Num(Value),
    /// A `"string"`, its escapes resolved.
    Str(String),
    /// A name or a keyword.
    Ident(String),
    /// An operator or a bracket.
    Sym(&'static str),
    /// The `}` that ends the code.
    Close,
    /// The end of the text.
    End,
}

/// Operators and brackets, longest first where one starts another.
const SYMBOLS: [&str; 27] = [
    "==", "!=", "<>", "<=", ">=", "=~", "!~", "&&", "||", "<", ">", "+", "-", "*", "/", "%", "(",
    ")", "[", "]", ",", "?", ":", "!", ";", "=", "~",
];

/// Where each line of a template starts, to turn a byte offset into a line
/// and column in O(log lines).
#[derive(Clone, Debug)]
pub(super) struct Lines {
    starts: Vec<usize>,
}

impl Lines {
    /// The line starts of `text`.
    pub(super) fn new(text: &str) -> Lines {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(k, _)| k + 1));
        Lines { starts }
    }

    /// The 1-based line and character column of byte `at` of `text`.
    pub(super) fn locate(&self, text: &str, at: usize) -> (usize, usize) {
        let at = at.min(text.len());
        let k = self.starts.partition_point(|&s| s <= at) - 1;
        let start = self.starts[k];
        let column = text
            .get(start..at)
            .map_or(at - start, |s| s.chars().count());
        (k + 1, column + 1)
    }
}

/// The lexer of a template's code, over its whole text.
pub(super) struct Lexer<'a> {
    pub(super) src: &'a str,
    s: &'a [u8],
    /// Byte offset of the next unread byte.
    pub(super) pos: usize,
    /// The token looked at ahead, its start and end.
    ahead: Option<(Tok, usize, usize)>,
    lines: &'a Lines,
}

impl<'a> Lexer<'a> {
    /// A lexer of `src` at byte 0.
    pub(super) fn new(src: &'a str, lines: &'a Lines) -> Lexer<'a> {
        Lexer {
            src,
            s: src.as_bytes(),
            pos: 0,
            ahead: None,
            lines,
        }
    }

    /// The error `message` at byte `at`.
    pub(super) fn error(&self, at: usize, message: impl Into<String>) -> MacroError {
        let (line, column) = self.lines.locate(self.src, at);
        MacroError::new(line, column, message.into())
    }

    /// The next token and its start, not consumed.
    pub(super) fn peek(&mut self) -> Result<(&Tok, usize), MacroError> {
        if self.ahead.is_none() {
            let t = self.read()?;
            self.ahead = Some(t);
        }
        let (t, start, _) = self.ahead.as_ref().expect("just read");
        Ok((t, *start))
    }

    /// The next token and its start, consumed.
    pub(super) fn next(&mut self) -> Result<(Tok, usize), MacroError> {
        match self.ahead.take() {
            Some((t, start, end)) => {
                self.pos = end;
                Ok((t, start))
            }
            None => {
                let (t, start, end) = self.read()?;
                self.pos = end;
                Ok((t, start))
            }
        }
    }

    /// Consumes the symbol or keyword `word` if it is next.
    pub(super) fn eat(&mut self, word: &str) -> Result<bool, MacroError> {
        let hit = match self.peek()?.0 {
            Tok::Sym(s) => *s == word,
            Tok::Ident(w) => w == word,
            _ => false,
        };
        if hit {
            self.next()?;
        }
        Ok(hit)
    }

    /// The start of the next token (white space skipped).
    pub(super) fn at(&mut self) -> Result<usize, MacroError> {
        Ok(self.peek()?.1)
    }

    /// The shared operator the next token is, if any.
    pub(super) fn sym(&mut self) -> Result<Option<(Sym, usize)>, MacroError> {
        let (t, at) = self.peek()?;
        let s = match t {
            Tok::Sym("?") => Sym::Question,
            Tok::Sym(":") => Sym::Colon,
            Tok::Sym("||") => Sym::Or,
            Tok::Sym("&&") => Sym::And,
            Tok::Ident(w) if w == "or" => Sym::Or,
            Tok::Ident(w) if w == "and" => Sym::And,
            Tok::Sym("==") => Sym::Cmp(Cmp::Eq),
            Tok::Sym("!=" | "<>") => Sym::Cmp(Cmp::Ne),
            Tok::Sym("<") => Sym::Cmp(Cmp::Lt),
            Tok::Sym("<=") => Sym::Cmp(Cmp::Le),
            Tok::Sym(">") => Sym::Cmp(Cmp::Gt),
            Tok::Sym(">=") => Sym::Cmp(Cmp::Ge),
            Tok::Sym("=~") => Sym::Match { negated: false },
            Tok::Sym("!~") => Sym::Match { negated: true },
            _ => return Ok(None),
        };
        Ok(Some((s, at)))
    }

    /// A `/pattern/` literal next (after `=~`, or in `one_of`): its text
    /// (`\/` a slash, other escapes the pattern's) and start.
    pub(super) fn pattern(&mut self) -> Result<Option<(String, usize)>, MacroError> {
        let (t, at) = self.peek()?;
        if *t != Tok::Sym("/") {
            return Ok(None);
        }
        self.ahead = None;
        self.pos = at;
        match self.quoted(b'/', at)? {
            Tok::Str(s) => Ok(Some((s, at))),
            _ => unreachable!("quoted gives a string"),
        }
    }

    /// Skips white space (the slicers' code allows spaces, tabs and line breaks).
    pub(super) fn skip_space(&mut self) {
        while self.s.get(self.pos).is_some_and(u8::is_ascii_whitespace) {
            self.pos += 1;
        }
    }

    /// Reads the token at `pos` (not moving it): the token, start, end.
    fn read(&mut self) -> Result<(Tok, usize, usize), MacroError> {
        let save = self.pos;
        self.skip_space();
        let at = self.pos;
        let t = self.token(at);
        let end = self.pos;
        self.pos = save;
        Ok((t?, at, end))
    }

    fn token(&mut self, at: usize) -> Result<Tok, MacroError> {
        let Some(&c) = self.s.get(at) else {
            return Ok(Tok::End);
        };
        if c == b'}' {
            self.pos += 1;
            return Ok(Tok::Close);
        }
        if c == b'"' {
            return self.quoted(c, at);
        }
        if c.is_ascii_digit() || (c == b'.' && self.s.get(at + 1).is_some_and(u8::is_ascii_digit)) {
            return self.number(at);
        }
        if is_ident(c, false) {
            return Ok(Tok::Ident(self.ident().to_string()));
        }
        for sym in SYMBOLS {
            if self.s[at..].starts_with(sym.as_bytes()) {
                self.pos += sym.len();
                return Ok(Tok::Sym(sym));
            }
        }
        let ch = self.src[at..].chars().next().unwrap_or('?');
        Err(self.error(at, format!("unexpected `{ch}` in an expression")))
    }

    /// A name at `pos`, consumed (empty if none).
    pub(super) fn ident(&mut self) -> &'a str {
        let start = self.pos;
        while self.pos < self.s.len() && is_ident(self.s[self.pos], self.pos > start) {
            self.pos += 1;
        }
        &self.src[start..self.pos]
    }

    /// A `"string"` (escapes `\"`, `\\`, `\n`, `\r`, others kept as the
    /// character) or a `/pattern/` (`\/` is a slash; other escapes are kept
    /// for the pattern).
    fn quoted(&mut self, q: u8, at: usize) -> Result<Tok, MacroError> {
        self.pos = at + 1;
        let mut out = String::new();
        loop {
            let Some(ch) = self.src[self.pos..].chars().next() else {
                return Err(self.error(at, "a string or pattern is never closed"));
            };
            self.pos += ch.len_utf8();
            if ch as u32 == q as u32 {
                return Ok(Tok::Str(out));
            }
            if ch != '\\' {
                out.push(ch);
                continue;
            }
            let Some(next) = self.src[self.pos..].chars().next() else {
                continue;
            };
            self.pos += next.len_utf8();
            match (q, next) {
                (b'/', '/') => out.push('/'),
                (b'/', c) => {
                    out.push('\\');
                    out.push(c);
                }
                (_, 'n') => out.push('\n'),
                (_, 'r') => out.push('\r'),
                (_, c) => out.push(c),
            }
        }
    }

    fn number(&mut self, at: usize) -> Result<Tok, MacroError> {
        self.pos = at;
        let digits = |p: &mut Lexer| {
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
        let bad = |p: &Lexer| p.error(at, format!("`{text}` is no number"));
        if real {
            Ok(Tok::Num(Value::Float(text.parse().map_err(|_| bad(self))?)))
        } else {
            Ok(Tok::Num(Value::Int(text.parse().map_err(|_| bad(self))?)))
        }
    }
}

/// Whether `c` may be in a name (`later`: not its first character).
pub(super) fn is_ident(c: u8, later: bool) -> bool {
    c == b'_' || c.is_ascii_alphabetic() || (later && c.is_ascii_digit())
}

/// A token as an error message shows it.
pub(super) fn shown(t: &Tok) -> String {
    match t {
        Tok::Num(v) => format!("`{}`", v.text()),
        Tok::Str(s) => format!("\"{s}\""),
        Tok::Ident(w) => format!("`{w}`"),
        Tok::Sym(s) => format!("`{s}`"),
        Tok::Close => "`}`".into(),
        Tok::End => "the end of the text".into(),
    }
}
