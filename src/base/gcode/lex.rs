//! A G-code line cut into its code and parameters the way the firmware's
//! own parser cuts it, so that what p3dp checks is what the printer runs.
//!
//! - **Marlin** (Marlin 2's `GCodeParser::parse` with its default
//!   `FASTER_GCODE_PARSER` and `GCODE_CASE_INSENSITIVE`; Prusa's Buddy and
//!   Bambu's firmware are Marlin's): a `;` ends the code, `*` a checksum; a
//!   leading `N<number>` is a line number; the command is `G`, `M` or `T`,
//!   spaces allowed before its number (`M 104` is `M104`) and a point
//!   after it giving a subcode (`M104.1` runs as `M104`); then every letter
//!   is a parameter, its value the number that follows (spaces allowed
//!   between), letters inside quotes included (`G1 X1 "Y5"` moves Y), a
//!   letter ending a number (`X1E3` is `X1 E3`). A repeated parameter: the
//!   last one counts. `M23`, `M28`, `M30`, `M117`, `M118`, `M928` and
//!   `M810`–`M819` take the rest of the line as text.
//! - **Klipper** (`klippy/gcode.py`): the code (before `;`) is upper-cased
//!   and split at each run of letters and `_` (and at `*`); the command is
//!   the first run and the text to the next (`M 104` is `M104`, `M104.1` is
//!   a command of its own); each later run is a key whose value is the text
//!   up to the next run, stripped, read as Python's `float` reads it when
//!   the command asks (otherwise the command fails). An extended command
//!   (`SET_HEATER_TEMPERATURE`, a macro) takes `KEY=VALUE` words split as
//!   `shlex` splits them, quotes removed, up to a `#`, `*` or `;`. A
//!   repeated key: the last one counts.
//! - **RepRapFirmware**: as Marlin, but text in quotes is a string value,
//!   never parameters.
//!
//! Anything outside printable ASCII in a command (a comment may hold any
//! text) is refused: firmwares read such bytes differently (Python's `float`
//! takes full-width digits), so no reading of them is safe.

/// Whose parser reads a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Grammar {
    /// Marlin's (Prusa's Buddy firmware and Bambu's too).
    Marlin,
    /// Klipper's.
    Klipper,
    /// RepRapFirmware's.
    Reprap,
}

/// A command's code as the firmware dispatches it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Code {
    /// A letter (`G`, `M`, `T`) and its number; `sub` is the number after a
    /// point (`M862.3`), `None` without one.
    Number {
        /// `b'G'`, `b'M'` or `b'T'`.
        letter: u8,
        /// The command's number.
        number: u32,
        /// The subcode.
        sub: Option<u32>,
    },
    /// A named command (Klipper's extended commands and macros), upper case.
    Name(String),
}

impl Code {
    /// Whether this is `letter` `number` (any subcode).
    pub(crate) fn is(&self, l: u8, n: u32) -> bool {
        matches!(*self, Code::Number { letter, number, .. } if letter == l && number == n)
    }

    /// The code as written back: `M104`, `M862.3`, `SET_PIN`.
    pub(crate) fn shown(&self) -> String {
        match self {
            Code::Number {
                letter,
                number,
                sub: None,
            } => format!("{}{number}", *letter as char),
            Code::Number {
                letter,
                number,
                sub: Some(s),
            } => format!("{}{number}.{s}", *letter as char),
            Code::Name(n) => n.clone(),
        }
    }
}

/// A parameter's value as the line holds it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value<'a> {
    /// No value (`G28 X`).
    None,
    /// A number, read as the firmware reads it.
    Number(f64),
    /// Text: a string value, or one the firmware could not read as a number.
    Text(&'a str),
}

/// One parameter: its key (a letter, or Klipper's `KEY`), upper case.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Param<'a> {
    /// The key.
    pub(crate) key: String,
    /// The value.
    pub(crate) value: Value<'a>,
}

/// A line of G-code, cut (see the module comment).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Line<'a> {
    /// The command; `None` for a blank or comment-only line.
    pub(crate) code: Option<Code>,
    /// Every parameter, in order, repeated ones included.
    pub(crate) params: Vec<Param<'a>>,
    /// The text argument of a command that takes the rest of the line
    /// (`M117 Printing…`), or a line's raw words after a named command.
    pub(crate) text: Option<&'a str>,
    /// The comment after `;`, if any.
    pub(crate) comment: Option<&'a str>,
}

impl<'a> Line<'a> {
    /// The value the firmware uses for `key`: the last one given.
    pub(crate) fn get(&self, key: &str) -> Option<&Value<'a>> {
        self.params
            .iter()
            .rev()
            .find(|p| p.key == key)
            .map(|p| &p.value)
    }

    /// Whether `key` is given at all.
    pub(crate) fn has(&self, key: &str) -> bool {
        self.params.iter().any(|p| p.key == key)
    }

    /// Every value given for `key`, in order.
    pub(crate) fn all(&self, key: &str) -> impl Iterator<Item = &Value<'a>> {
        let key = key.to_string();
        self.params
            .iter()
            .filter(move |p| p.key == key)
            .map(|p| &p.value)
    }

    /// The number the firmware uses for `key`: `Ok(None)` when it is not
    /// given or has no value, an error when the firmware cannot read it.
    pub(crate) fn number(&self, key: &str) -> Result<Option<f64>, String> {
        match self.get(key) {
            None | Some(Value::None) => Ok(None),
            Some(Value::Number(v)) => Ok(Some(*v)),
            Some(Value::Text(t)) => Err(format!(
                "cannot read `{key}`'s value `{t}` as a number (the firmware could not either)"
            )),
        }
    }

    /// Every number given for `key` (a value that is no number is an error).
    pub(crate) fn numbers(&self, key: &str) -> Result<Vec<f64>, String> {
        self.all(key)
            .filter_map(|v| match v {
                Value::None => None,
                Value::Number(x) => Some(Ok(*x)),
                Value::Text(t) => Some(Err(format!(
                    "cannot read `{key}`'s value `{t}` as a number (the firmware could not either)"
                ))),
            })
            .collect()
    }

    /// Text of a named command's `KEY=VALUE` word (Klipper), the last one.
    pub(crate) fn word(&self, key: &str) -> Option<&'a str> {
        match self.get(key)? {
            Value::Text(t) => Some(t),
            _ => None,
        }
    }
}

/// Longest line read, bytes: a G-code line is short; a longer one is no
/// command a firmware's buffer (96 bytes in Marlin) would take whole.
pub(crate) const MAX_LINE: usize = 4096;

/// Cuts `line` as `grammar`'s firmware does (see the module comment); an
/// error says why the line cannot be read safely.
pub(crate) fn lex(grammar: Grammar, line: &str) -> Result<Line<'_>, String> {
    if line.len() > MAX_LINE {
        return Err(format!(
            "a line of {} bytes; expected at most {MAX_LINE}",
            line.len()
        ));
    }
    let (code, comment) = match line.find(';') {
        Some(k) => (&line[..k], Some(line[k + 1..].trim())),
        None => (line, None),
    };
    if let Some(c) = code
        .chars()
        .find(|c| !(c.is_ascii_graphic() || *c == ' ' || *c == '\t'))
    {
        return Err(format!(
            "the command holds {c:?} (U+{:04X}); expected printable ASCII before any `;` comment (firmwares read other characters differently)",
            c as u32
        ));
    }
    let mut out = Line {
        comment,
        ..Line::default()
    };
    // a checksum `*NN` ends the code (Marlin and RepRapFirmware; Klipper
    // makes `*` a key of its own, which no command reads)
    let code = code.split('*').next().unwrap_or("");
    let code = skip_line_number(code.trim_matches([' ', '\t']));
    if code.is_empty() {
        return Ok(out);
    }
    if skip_line_number(code) != code {
        // each firmware skips one line number; the second is read as a
        // command `N…` that none has (Marlin and Klipper answer "unknown
        // command"), and no line written for it reads back as it
        return Err(format!(
            "`{code}` starts with a second line number; expected at most one `N<number>` before the command"
        ));
    }
    match grammar {
        Grammar::Klipper => klipper(code, &mut out)?,
        Grammar::Marlin | Grammar::Reprap => marlin(code, grammar == Grammar::Reprap, &mut out)?,
    }
    Ok(out)
}

/// `code` without a leading line number `N<digits>` (and the spaces after).
fn skip_line_number(code: &str) -> &str {
    let b = code.as_bytes();
    let signed = |c: u8| c.is_ascii_digit() || c == b'-' || c == b'+';
    if b.len() >= 2 && b[0].eq_ignore_ascii_case(&b'N') && signed(b[1]) {
        let rest = &code[2..];
        let k = rest
            .find(|c: char| !c.is_ascii_digit())
            .unwrap_or(rest.len());
        return rest[k..].trim_start_matches([' ', '\t']);
    }
    code
}

/// Whether `c` separates words (Marlin skips spaces; a tab is taken as one
/// too, which reads more of the line, never less).
fn space(c: u8) -> bool {
    c == b' ' || c == b'\t'
}

/// Marlin's reading (RepRapFirmware's with `quoted`: text in quotes is a
/// string value).
fn marlin<'a>(code: &'a str, quoted: bool, out: &mut Line<'a>) -> Result<(), String> {
    let b = code.as_bytes();
    let letter = b[0].to_ascii_uppercase();
    if !(b[0].is_ascii_alphanumeric() || b[0] == b'_' || b.iter().any(u8::is_ascii_digit)) {
        // no letter first and no number anywhere (a maker's banner that lost
        // its `;`, Bambu's `==== record data ====`): Marlin takes no command
        // letter from it and answers "unknown command"; read as a named
        // command of its first word, which the checks name
        let first = code.split([' ', '\t']).next().unwrap_or(code);
        out.code = Some(Code::Name(first.to_string()));
        let rest = code[first.len()..].trim_matches([' ', '\t']);
        out.text = (!rest.is_empty()).then_some(rest);
        return Ok(());
    }
    if !matches!(letter, b'G' | b'M' | b'T') {
        // not a command Marlin runs (it answers "unknown command"); read as
        // a named one so that the checks can say so, or a flavour's table
        // can know it
        return named(code, out);
    }
    let mut i = 1;
    while i < b.len() && space(b[i]) {
        i += 1;
    }
    let start = i;
    while i < b.len() && b[i].is_ascii_digit() {
        i += 1;
    }
    if i == start {
        return named(code, out);
    }
    let number = code[start..i]
        .parse::<u32>()
        .map_err(|_| format!("the command number `{}` is too large", &code[start..i]))?;
    let mut sub = None;
    if i < b.len() && b[i] == b'.' {
        let s = i + 1;
        i = s;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        sub = Some(code[s..i].parse::<u32>().unwrap_or(0));
    }
    out.code = Some(Code::Number {
        letter,
        number,
        sub,
    });
    let rest = &code[i..];
    if letter == b'M' && takes_text(number) {
        let t = rest.trim_matches([' ', '\t']);
        out.text = (!t.is_empty()).then_some(t);
        return Ok(());
    }
    marlin_params(rest, quoted, out)
}

/// M codes whose parameters are the rest of the line as text: file names,
/// messages, macros.
fn takes_text(n: u32) -> bool {
    matches!(n, 23 | 28 | 30 | 117 | 118 | 928 | 810..=819)
}

/// Marlin's parameter loop: each letter a key, its value the number after it.
fn marlin_params<'a>(rest: &'a str, quoted: bool, out: &mut Line<'a>) -> Result<(), String> {
    let b = rest.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if quoted && c == b'{' {
            return Err("an expression in braces: RepRapFirmware evaluates it when it runs the line, so p3dp cannot check its value".into());
        }
        if quoted && c == b'"' {
            // a string value of the parameter before, or a stray string
            let end = rest[i + 1..].find('"').map_or(b.len(), |k| i + 1 + k);
            if let Some(p) = out.params.last_mut() {
                if p.value == Value::None {
                    p.value = Value::Text(&rest[i + 1..end]);
                }
            }
            i = (end + 1).min(b.len());
            continue;
        }
        if !c.is_ascii_alphabetic() {
            i += 1;
            continue;
        }
        let key = (c.to_ascii_uppercase() as char).to_string();
        i += 1;
        let mut j = i;
        while j < b.len() && space(b[j]) {
            j += 1;
        }
        let value = match marlin_number(&b[j..]) {
            Some((v, len)) => {
                i = j + len;
                Value::Number(v)
            }
            None => Value::None,
        };
        out.params.push(Param { key, value });
    }
    Ok(())
}

/// Marlin's `valid_float` and `strtof` on the value: an optional sign,
/// digits, a point, digits (at least one digit, or a point and a digit,
/// after the sign), read up to the first character that is none of
/// `0-9 . + -` (the whole run is skipped, as Marlin skips it); `None` when
/// there is no value.
fn marlin_number(b: &[u8]) -> Option<(f64, usize)> {
    let numeric = |k: usize| b.get(k).is_some_and(u8::is_ascii_digit);
    let decimal = |k: usize| numeric(k) || b.get(k) == Some(&b'.');
    let valid = numeric(0)
        || (b.first() == Some(&b'.') && numeric(1))
        || (matches!(b.first(), Some(b'-' | b'+')) && decimal(1));
    if !valid {
        return None;
    }
    let run = b
        .iter()
        .position(|c| !(c.is_ascii_digit() || matches!(c, b'.' | b'+' | b'-')))
        .unwrap_or(b.len());
    // strtof reads the longest prefix of [sign] digits [. digits]
    let mut k = usize::from(matches!(b[0], b'-' | b'+'));
    while k < run && b[k].is_ascii_digit() {
        k += 1;
    }
    if k < run && b[k] == b'.' {
        k += 1;
        while k < run && b[k].is_ascii_digit() {
            k += 1;
        }
    }
    let text = std::str::from_utf8(&b[..k]).unwrap_or("");
    // "-." and "+." read as 0 (strtof converts nothing)
    let v = text.parse::<f64>().unwrap_or(0.0);
    Some((v, run))
}

/// A named command: its name, and `KEY=VALUE` words after it (Klipper's
/// extended command syntax; for other firmware only to name the command).
fn named<'a>(code: &'a str, out: &mut Line<'a>) -> Result<(), String> {
    let end = code
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(code.len());
    if end == 0 {
        return Err(format!(
            "`{code}` does not start with a command; expected a letter"
        ));
    }
    out.code = Some(Code::Name(code[..end].to_ascii_uppercase()));
    let args = code[end..].trim_matches([' ', '\t']);
    out.text = (!args.is_empty()).then_some(args);
    for w in shlex_words(args)? {
        let (key, value) = match w.split_once('=') {
            Some((k, v)) => {
                let v = unquote(v).ok_or_else(|| format!("`{w}`: a quote inside a word"))?;
                let value = match python_float(v) {
                    Some(x) => Value::Number(x),
                    None => Value::Text(v),
                };
                (k, value)
            }
            None => (
                unquote(w).ok_or_else(|| format!("`{w}`: a quote inside a word"))?,
                Value::None,
            ),
        };
        out.params.push(Param {
            key: key.to_ascii_uppercase(),
            value,
        });
    }
    Ok(())
}

/// Words split at white space outside quotes, as Python's `shlex.split`
/// splits them (the quotes are removed by [`unquote`]); the quotes must close.
fn shlex_words(args: &str) -> Result<Vec<&str>, String> {
    let mut out = Vec::new();
    let b = args.as_bytes();
    let mut i = 0;
    while i < b.len() {
        while i < b.len() && space(b[i]) {
            i += 1;
        }
        if i == b.len() {
            break;
        }
        let start = i;
        let mut quote: Option<u8> = None;
        while i < b.len() && (quote.is_some() || !space(b[i])) {
            match (quote, b[i]) {
                (None, q @ (b'"' | b'\'')) => quote = Some(q),
                (Some(q), c) if c == q => quote = None,
                _ => {}
            }
            i += 1;
        }
        if quote.is_some() {
            return Err("a quote that does not close".into());
        }
        out.push(&args[start..i]);
    }
    Ok(out)
}

/// `s` without one pair of quotes round all of it; `None` when a quote
/// stands elsewhere in it (shlex would join the pieces: no key a check
/// reads is written so, and refusing is the safe reading).
fn unquote(s: &str) -> Option<&str> {
    let b = s.as_bytes();
    if b.len() >= 2 && (b[0] == b'"' || b[0] == b'\'') && b[b.len() - 1] == b[0] {
        let inner = &s[1..s.len() - 1];
        return (!inner.contains(['"', '\''])).then_some(inner);
    }
    (!s.contains(['"', '\''])).then_some(s)
}

/// A number as Python's `float` reads it after `strip`, for the ASCII text a
/// command holds: a sign, digits with an optional point (or a point and
/// digits), an optional exponent, `inf`/`infinity`/`nan` in any case;
/// `None` for anything else (an underscore between digits, which Python
/// takes, is refused too: the safe reading of a value no maker writes).
pub(crate) fn python_float(s: &str) -> Option<f64> {
    let t = s.trim_matches(|c: char| c.is_ascii_whitespace());
    let body = t.strip_prefix(['+', '-']).unwrap_or(t);
    let lower = body.to_ascii_lowercase();
    if matches!(lower.as_str(), "inf" | "infinity" | "nan") {
        let neg = t.starts_with('-');
        return Some(match (lower.as_str(), neg) {
            ("nan", _) => f64::NAN,
            (_, true) => f64::NEG_INFINITY,
            _ => f64::INFINITY,
        });
    }
    let digits = |s: &str| s.bytes().all(|c| c.is_ascii_digit());
    let (mant, exp) = match lower.split_once('e') {
        Some((m, e)) => (m, Some(e)),
        None => (lower.as_str(), None),
    };
    let ok_mant = match mant.split_once('.') {
        Some((a, b)) => digits(a) && digits(b) && !(a.is_empty() && b.is_empty()),
        None => !mant.is_empty() && digits(mant),
    };
    let ok_exp = exp.is_none_or(|e| {
        let e = e.strip_prefix(['+', '-']).unwrap_or(e);
        !e.is_empty() && digits(e)
    });
    if !(ok_mant && ok_exp) {
        return None;
    }
    t.parse::<f64>().ok()
}

/// Klipper's reading (see the module comment).
fn klipper<'a>(code: &'a str, out: &mut Line<'a>) -> Result<(), String> {
    let up = code.to_ascii_uppercase();
    let first = up.find(|c: char| c.is_ascii_uppercase() || c == '_');
    let Some(0) = first else {
        return Err(format!(
            "`{code}` does not start with a command; expected a letter"
        ));
    };
    // the first run of letters and `_`, and the text to the next run
    let run = |from: usize| {
        up[from..]
            .find(|c: char| !(c.is_ascii_uppercase() || c == '_'))
            .map_or(up.len(), |k| from + k)
    };
    let next_key = |from: usize| {
        up[from..]
            .find(|c: char| c.is_ascii_uppercase() || c == '_' || c == '*')
            .map_or(up.len(), |k| from + k)
    };
    let e1 = run(0);
    let e2 = next_key(e1);
    let name = &up[..e1];
    if name == "N" {
        // a line number, whatever follows the `N` up to the next letters
        // (gcode.py: `parts[1] == 'N'` makes the command parts[3] + parts[4]);
        // a second one would be a command `N…` Klipper does not have
        let rest = code[e2..].trim_start_matches([' ', '\t']);
        if rest.is_empty() || rest.starts_with('*') {
            return Ok(());
        }
        let at = up.len() - rest.len();
        if &up[at..run(at)] == "N" {
            return Err(format!(
                "`{code}` starts with a second line number; expected at most one `N<number>` before the command"
            ));
        }
        return klipper(rest, out);
    }
    let num = up[e1..e2].trim();
    let traditional = name.len() == 1 && num.starts_with(|c: char| c.is_ascii_digit());
    if !traditional {
        // an extended command: `NAME KEY=VALUE …` (Klipper's extended_r:
        // the arguments stop at `#`, `*` or `;`)
        let args_end = code.find(['#', '*']).unwrap_or(code.len());
        return named(&code[..args_end], out);
    }
    let code_now = klipper_code(name, num);
    let text_command =
        matches!(code_now, Code::Number { letter: b'M', number, .. } if takes_text(number));
    out.code = Some(code_now);
    if text_command {
        // M117/M118 …: the raw text after the command
        let t = code[e1..].trim_start_matches([' ', '\t']);
        let t = t
            .trim_start_matches(|c: char| c.is_ascii_digit())
            .trim_matches([' ', '\t']);
        out.text = (!t.is_empty()).then_some(t);
        return Ok(());
    }
    let mut at = e2;
    while at < up.len() {
        let ke = if &up[at..at + 1] == "*" {
            at + 1
        } else {
            run(at)
        };
        let ve = next_key(ke);
        let key = up[at..ke].to_string();
        let raw = code[ke..ve].trim();
        let value = if raw.is_empty() {
            Value::Text(raw)
        } else {
            match python_float(raw) {
                Some(v) => Value::Number(v),
                None => Value::Text(raw),
            }
        };
        out.params.push(Param { key, value });
        at = ve;
    }
    Ok(())
}

/// A traditional Klipper command's code: the letter and the text after it
/// (`M104.1` is a command of its own, kept as a name when it has a point).
fn klipper_code(letter: &str, num: &str) -> Code {
    match num.parse::<u32>() {
        Ok(number) if num.bytes().all(|c| c.is_ascii_digit()) => Code::Number {
            letter: letter.as_bytes()[0],
            number,
            sub: None,
        },
        _ => Code::Name(format!("{letter}{num}")),
    }
}
