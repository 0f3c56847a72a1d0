//! Errors rendered like rustc's: the first line as ever
//! (`error: FILE:LINE:COL: PATH: message`), then the recipe's own line with
//! the place underlined, and a `help:` line where one is known.
//!
//! The place is the error's line and column when the YAML reader gave one,
//! else its key path looked up in the file (`parts[0].steps[1].position[2]`),
//! narrowed to the token an expression error names. The rendering is
//! `annotate-snippets`' (rustc's own renderer), coloured only when asked.

use std::io::IsTerminal;

use annotate_snippets::{AnnotationKind, Group, Level, Renderer, Snippet};

use crate::base::error::{Error, Kind};

/// A span on one line: 1-based line, 0-based byte columns `start..end`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Span {
    /// Line, 1-based.
    pub(crate) line: usize,
    /// First byte of the span in the line.
    pub(crate) start: usize,
    /// One past its last byte.
    pub(crate) end: usize,
}

/// Whether standard error takes colour: a terminal, and `NO_COLOR` unset.
pub(crate) fn stderr_color() -> bool {
    std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty()) && std::io::stderr().is_terminal()
}

/// Renders `e` with the text of its file read from disk (when there is one).
///
/// The file is read as every input is (bounded: `/dev/zero` is no text), and
/// shown only where it was read as YAML: a file that is no recipe at all (a
/// system file given by mistake) is named, never printed.
pub(crate) fn render(e: &Error, color: bool) -> String {
    let not_yaml = e.message.starts_with("invalid type: text");
    let text = e
        .file
        .as_deref()
        .filter(|_| !not_yaml)
        .filter(|f| std::path::Path::new(f).is_file())
        .and_then(|f| crate::base::input::read_text(std::path::Path::new(f), "file").ok());
    render_with(e, text.as_deref(), color)
}

/// Renders `e` given the text of its file.
pub(crate) fn render_with(e: &Error, text: Option<&str>, color: bool) -> String {
    let title = format!("{e}");
    let span = text.and_then(|t| place(e, t).map(|s| (t, s)));
    let help = e
        .help
        .as_deref()
        .map(str::to_string)
        .or_else(|| check_help(e));
    if span.is_none() {
        return match help {
            Some(h) => format!("error: {title}\nhelp: {h}\n"),
            None => format!("error: {title}\n"),
        };
    }
    let renderer = if color {
        Renderer::styled()
    } else {
        Renderer::plain()
    };
    let mut group = Group::with_title(Level::ERROR.primary_title(title.as_str()));
    if let (Some((t, s)), Some(file)) = (span, e.file.as_deref()) {
        let line = t.lines().nth(s.line - 1).unwrap_or("");
        let label = e.place.as_deref().unwrap_or("here");
        group = group.element(
            Snippet::source(line)
                .line_start(s.line)
                .path(file)
                .annotation(AnnotationKind::Primary.span(s.start..s.end).label(label)),
        );
    }
    let mut report: Vec<Group> = vec![group];
    if let Some(h) = &help {
        report.push(Group::with_title(Level::HELP.secondary_title(h.as_str())));
    }
    let mut out = renderer.render(&report);
    out.push('\n');
    out
}

/// A `help:` where the remedy is known from the message: a failed check, a
/// misspelt name in an expression, a missing image.
pub(crate) fn check_help(e: &Error) -> Option<String> {
    let m = &e.message;
    if e.kind == Kind::Check {
        return m.contains("[out-of-bed]").then(|| {
            "move the part onto the bed (a `translate` step or smaller params), or give a larger printer with --printer; `p3dp printers` lists them".into()
        });
    }
    if let Some(rest) = m
        .strip_prefix("cannot read the expression `")
        .and_then(|r| r.split_once("`: unexpected `"))
        .map(|(_, r)| r)
    {
        return Some(if rest.starts_with(|c: char| c.is_alphabetic()) {
            "numbers carry no units in a recipe (lengths are mm, speeds mm/s): write `10`, not `10 mm`; between two values put an operator (+ - * / ^)".into()
        } else {
            "an expression is arithmetic (+ - * / ^ and parentheses) over numbers, params, the variables and functions of docs/recipe.md".into()
        });
    }
    if m.contains("invalid type: sequence, expected a number") {
        return Some("one number (or an expression in quotes) goes here, not a list; to build several values, use --sweep NAME=v1,v2,…".into());
    }
    if m.starts_with("cannot open the image") {
        return Some(
            "an image's path is taken from the recipe's folder; check its name there".into(),
        );
    }
    if let Some((name, rest)) = m
        .strip_prefix("unknown name `")
        .and_then(|r| r.split_once('`'))
    {
        let known = rest
            .split_once("it may use ")?
            .1
            .replace(" and the params ", ", ");
        let names: Vec<&str> = known.split(", ").map(str::trim).collect();
        return Some(closest(name, &names).map_or_else(
            || format!("a name here is one of {}", names.join(", ")),
            |k| {
                format!(
                    "did you mean `{k}`? a name here is one of {}",
                    names.join(", ")
                )
            },
        ));
    }
    if let Some((name, rest)) = m
        .strip_prefix("unknown function `")
        .and_then(|r| r.split_once('`'))
    {
        let list = rest.split_once("functions are: ")?.1;
        let names: Vec<&str> = list
            .split(' ')
            .map(|f| f.split('(').next().unwrap_or(f))
            .collect();
        return Some(closest(name, &names).map_or_else(
            || "docs/recipe.md describes each function".to_string(),
            |k| format!("did you mean `{k}`?"),
        ));
    }
    None
}

/// The name in `names` nearest to `wrong` by edit distance, if near enough.
fn closest<'a>(wrong: &str, names: &[&'a str]) -> Option<&'a str> {
    names
        .iter()
        .map(|k| (strsim::damerau_levenshtein(wrong, k), *k))
        .filter(|(d, k)| *d <= 2.max(k.len() / 3) && *d < k.len())
        .min()
        .map(|(_, k)| k)
}

/// Where in `text` the error is: its line and column, else its key path,
/// else the part a failed check names; narrowed to an expression's token.
fn place(e: &Error, text: &str) -> Option<Span> {
    let lines: Vec<&str> = text.lines().collect();
    let mut span = match (e.line, e.place.as_deref()) {
        (Some((l, c)), _) => {
            let line = lines.get(l.checked_sub(1)?)?;
            let start = char_col(line, c.saturating_sub(1));
            Some(Span {
                line: l,
                start,
                end: word_end(line, start),
            })
        }
        (None, Some(path)) => locate(text, path),
        (None, None) => None,
    };
    if span.is_none() {
        span = part_by_name(&lines, &e.message);
    }
    let mut span = span?;
    if let Some(narrow) = expression_token(lines[span.line - 1], span, &e.message) {
        span = narrow;
    }
    Some(span)
}

/// Byte offset of the `c`-th character (0-based) of `line`.
fn char_col(line: &str, c: usize) -> usize {
    line.char_indices().nth(c).map_or(line.len(), |(k, _)| k)
}

/// End of the token starting at `start`: a word, a quoted string, a flow
/// collection, or one character.
fn word_end(line: &str, start: usize) -> usize {
    let rest = &line[start.min(line.len())..];
    let Some(first) = rest.chars().next() else {
        return start;
    };
    let len = match first {
        '"' | '\'' => rest[1..].find(first).map_or(rest.len(), |k| k + 2),
        '{' | '[' => flow_end(rest),
        // a plain scalar or a key: up to `: `, a flow separator or a comment
        c if c.is_alphanumeric() || c == '_' || c == '-' || c == '.' => {
            let stop = [": ", ",", "}", "]", " #"]
                .iter()
                .filter_map(|p| rest.find(p))
                .min()
                .unwrap_or(rest.len());
            let token = rest[..stop].trim_end();
            token.strip_suffix(':').unwrap_or(token).len()
        }
        c => c.len_utf8(),
    };
    start + len.max(1).min(rest.len())
}

/// Length of the flow collection at the start of `s` (to its closing bracket
/// on this line, or the line's end).
fn flow_end(s: &str) -> usize {
    let mut depth = 0;
    let mut quote = None;
    for (k, c) in s.char_indices() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '{' | '[') => depth += 1,
            (None, '}' | ']') => {
                depth -= 1;
                if depth == 0 {
                    return k + 1;
                }
            }
            _ => {}
        }
    }
    s.len()
}

/// One step of a key path.
#[derive(Debug, PartialEq)]
enum Seg {
    Key(String),
    Index(usize),
}

/// `parts[0].steps[1].position[2]` as steps; `None` for a place that is not
/// a key path (`--set …`, `-o -`).
fn segments(path: &str) -> Option<Vec<Seg>> {
    let mut out = Vec::new();
    for word in path.split('.') {
        let (key, mut rest) = word.split_once('[').map_or((word, ""), |(k, r)| (k, r));
        if !key.is_empty() {
            if !key.chars().all(|c| c.is_alphanumeric() || c == '_') {
                return None;
            }
            out.push(Seg::Key(key.to_string()));
        }
        while !rest.is_empty() {
            let (n, r) = rest.split_once(']')?;
            out.push(Seg::Index(n.parse().ok()?));
            rest = r.strip_prefix('[').unwrap_or(r);
        }
    }
    (!out.is_empty()).then_some(out)
}

/// A node of the YAML text: a block of lines `start..end` (0-based) whose
/// entries start at column `col` (on line `start` after any `- `), or a value
/// on one line.
#[derive(Clone, Copy, Debug)]
enum Node {
    Block {
        start: usize,
        end: usize,
        col: usize,
    },
    Inline(Span),
}

/// Indentation and content of a line, the content starting after any `- `.
fn content(line: &str) -> (usize, &str) {
    let t = line.trim_start_matches(' ');
    (line.len() - t.len(), t)
}

fn is_blank(line: &str) -> bool {
    let t = line.trim();
    t.is_empty() || t.starts_with('#')
}

/// Looks a key path up in the text: the span of the deepest node found (the
/// value of the last key, or the key itself when its value is a block).
pub(crate) fn locate(text: &str, path: &str) -> Option<Span> {
    let segs = segments(path)?;
    let lines: Vec<&str> = text.lines().collect();
    let mut node = Node::Block {
        start: 0,
        end: lines.len(),
        col: 0,
    };
    let mut found: Option<Span> = None;
    for seg in &segs {
        let next = match node {
            Node::Block { start, end, col } => block_child(&lines, start, end, col, seg),
            Node::Inline(s) => flow_child(lines[s.line - 1], s, seg).map(|s| (Node::Inline(s), s)),
        };
        match next {
            Some((n, s)) => {
                node = n;
                found = Some(s);
            }
            None => break,
        }
    }
    found
}

/// The child `seg` of the block `start..end` whose entries start at `col`:
/// its node and the span to show (its value, or its key).
fn block_child(
    lines: &[&str],
    start: usize,
    end: usize,
    col: usize,
    seg: &Seg,
) -> Option<(Node, Span)> {
    let mut items = 0;
    for k in start..end.min(lines.len()) {
        let line = lines[k];
        if is_blank(line) {
            continue;
        }
        let (at, rest) = entry_column(line, k == start, col);
        if at != col {
            continue;
        }
        match seg {
            Seg::Index(n) => {
                let Some(after) = rest.strip_prefix('-') else {
                    continue;
                };
                if !(after.is_empty() || after.starts_with(' ')) {
                    continue;
                }
                if items == *n {
                    return item_child(lines, k, end, at, after);
                }
                items += 1;
            }
            Seg::Key(key) => {
                if let Some(child) = key_child(lines, k, end, at, rest, key) {
                    return Some(child);
                }
            }
        }
    }
    None
}

/// Where the entry of `line` starts, and its text from there: its indent,
/// or on the block's `first` line, past the `- ` of the sequence items that
/// open it, up to the block's column `col`.
fn entry_column(line: &str, first: bool, col: usize) -> (usize, &str) {
    let (indent, mut rest) = content(line);
    let mut at = indent;
    if first && at < col {
        // the first line of a sequence item: `- key: …`
        while at < col {
            let Some(r) = rest.strip_prefix('-') else {
                break;
            };
            let r2 = r.trim_start_matches(' ');
            at += 1 + r.len() - r2.len();
            rest = r2;
        }
    }
    (at, rest)
}

/// The sequence item whose `-` is on line `k` at column `at`, `after` the
/// text after its `-`, in a block ending at `end`: a block below it, a
/// value on its line, or a block of entries starting on its line.
fn item_child(
    lines: &[&str],
    k: usize,
    end: usize,
    at: usize,
    after: &str,
) -> Option<(Node, Span)> {
    let line = lines[k];
    let item_end = block_end(lines, k + 1, end, at);
    let inner = after.trim_start_matches(' ');
    let inner_col = at + 1 + after.len() - inner.len();
    let dash = Span {
        line: k + 1,
        start: at,
        end: at + 1,
    };
    if inner.is_empty() {
        let c = next_col(lines, k + 1, item_end)?;
        let node = Node::Block {
            start: k + 1,
            end: item_end,
            col: c,
        };
        return Some((node, dash));
    }
    if inner.starts_with(['{', '[', '"', '\'']) || !has_key(inner) {
        let s = Span {
            line: k + 1,
            start: inner_col,
            end: word_end(line, inner_col),
        };
        return Some((Node::Inline(s), s));
    }
    let node = Node::Block {
        start: k,
        end: item_end,
        col: inner_col,
    };
    Some((node, dash))
}

/// The entry `key:` if line `k`'s entry at column `at`, `rest` its text,
/// is one, in a block ending at `end`: its value on the line, or the block
/// below it (shown by its key); None when the entry is another.
fn key_child(
    lines: &[&str],
    k: usize,
    end: usize,
    at: usize,
    rest: &str,
    key: &str,
) -> Option<(Node, Span)> {
    let line = lines[k];
    let after = rest.strip_prefix(key)?;
    let after_colon = after.trim_start_matches(' ');
    let value = after_colon.strip_prefix(':')?;
    let key_span = Span {
        line: k + 1,
        start: at,
        end: at + key.len(),
    };
    let v = value.trim_start_matches(' ');
    let v_col = line.len() - v.len();
    if !is_blank(v) {
        let s = Span {
            line: k + 1,
            start: v_col,
            end: word_end(line, v_col),
        };
        return Some((Node::Inline(s), s));
    }
    let child_end = block_end(lines, k + 1, end, at);
    let c = next_col(lines, k + 1, child_end).unwrap_or(at + 2);
    let node = Node::Block {
        start: k + 1,
        end: child_end,
        col: c,
    };
    Some((node, key_span))
}

/// Whether a line's content is a `key: …` entry.
fn has_key(s: &str) -> bool {
    s.find(':').is_some_and(|k| {
        s[..k]
            .chars()
            .all(|c| c.is_alphanumeric() || c == '_' || c == '-')
            && s[k + 1..].chars().next().is_none_or(|c| c == ' ')
    })
}

/// The end (exclusive) of the block after line `from - 1` indented beyond `col`
/// (or a sequence at `col` under a key).
fn block_end(lines: &[&str], from: usize, end: usize, col: usize) -> usize {
    let mut k = from;
    while k < end.min(lines.len()) {
        let line = lines[k];
        if !is_blank(line) {
            let (indent, rest) = content(line);
            if indent < col || (indent == col && !rest.starts_with("- ") && rest != "-") {
                break;
            }
        }
        k += 1;
    }
    k
}

/// Column of the first entry in lines `from..end`.
fn next_col(lines: &[&str], from: usize, end: usize) -> Option<usize> {
    (from..end.min(lines.len()))
        .find(|&k| !is_blank(lines[k]))
        .map(|k| content(lines[k]).0)
}

/// The child `seg` of a flow collection (`{a: 1, b: [x, y]}`) at `s`.
fn flow_child(line: &str, s: Span, seg: &Seg) -> Option<Span> {
    let text = &line[s.start..s.end];
    let close = match text.chars().next()? {
        '{' => '}',
        '[' => ']',
        _ => return None,
    };
    let inner_start = s.start + 1;
    let inner_end = if text.ends_with(close) && text.len() > 1 {
        s.end - 1
    } else {
        s.end
    };
    // top-level entries split at commas
    let mut entries = Vec::new();
    let (mut depth, mut quote, mut from) = (0i32, None, inner_start);
    for (k, c) in line[inner_start..inner_end].char_indices() {
        let k = k + inner_start;
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '{' | '[') => depth += 1,
            (None, '}' | ']') => depth -= 1,
            (None, ',') if depth == 0 => {
                entries.push((from, k));
                from = k + 1;
            }
            _ => {}
        }
    }
    entries.push((from, inner_end));
    let trim = |(a, b): (usize, usize)| -> Option<Span> {
        let t = &line[a..b];
        let lead = t.len() - t.trim_start().len();
        let body = t.trim();
        (!body.is_empty()).then(|| Span {
            line: s.line,
            start: a + lead,
            end: a + lead + body.len(),
        })
    };
    match seg {
        Seg::Index(n) => trim(*entries.get(*n)?),
        Seg::Key(key) => entries.into_iter().find_map(|(a, b)| {
            let e = trim((a, b))?;
            let t = &line[e.start..e.end];
            let rest = t.strip_prefix(key.as_str())?.trim_start();
            let v = rest.strip_prefix(':')?;
            let lead = v.len() - v.trim_start().len();
            let start = e.end - v.len() + lead;
            Some(Span {
                line: s.line,
                start,
                end: start + word_end(&line[start..e.end], 0),
            })
        }),
    }
}

/// The `name: NAME` line of the part a failed check names (``part `NAME` ``).
fn part_by_name(lines: &[&str], message: &str) -> Option<Span> {
    let name = message.split_once("part `")?.1.split('`').next()?;
    lines.iter().enumerate().find_map(|(k, l)| {
        let (_, rest) = content(l);
        let rest = rest.strip_prefix("- ").unwrap_or(rest).trim_start();
        let v = rest.strip_prefix("name:")?.trim();
        let v = v.split(" #").next()?.trim().trim_matches(['"', '\'']);
        (v == name).then(|| {
            let start = l.find(name).unwrap_or(0);
            Span {
                line: k + 1,
                start,
                end: start + name.len(),
            }
        })
    })
}

/// Inside an expression's span, the token an expression error names: the
/// character a syntax error stopped at, or the unknown name or function.
fn expression_token(line: &str, s: Span, message: &str) -> Option<Span> {
    let value = line.get(s.start..s.end)?;
    let (body_start, body) = match value.chars().next()? {
        q @ ('"' | '\'') => (s.start + 1, value[1..].trim_end_matches(q)),
        _ => (s.start, value),
    };
    let quoted = |after: &str| -> Option<&str> { message.split_once(after)?.1.split('`').next() };
    if let Some(at) = message
        .split_once("` at character ")
        .and_then(|(_, r)| r.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|n| n.parse::<usize>().ok())
    {
        let k = char_col(body, at.checked_sub(1)?);
        let rest = &body[k..];
        let len = rest.trim_end().len().max(1);
        return Some(Span {
            line: s.line,
            start: body_start + k,
            end: body_start + k + len,
        });
    }
    let name = quoted("unknown name `")
        .or_else(|| quoted("unknown function `"))
        .or_else(|| {
            message
                .strip_prefix('`')
                .filter(|_| message.contains("` is not available"))
                .and_then(|r| r.split('`').next())
        })?;
    let k = find_word(body, name)?;
    Some(Span {
        line: s.line,
        start: body_start + k,
        end: body_start + k + name.len(),
    })
}

/// Offset of `word` in `s` standing alone (not inside a longer name).
fn find_word(s: &str, word: &str) -> Option<usize> {
    let is_name = |c: char| c.is_alphanumeric() || c == '_';
    s.match_indices(word).map(|(k, _)| k).find(|&k| {
        !s[..k].chars().next_back().is_some_and(is_name)
            && !s[k + word.len()..].chars().next().is_some_and(is_name)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const RECIPE: &str = "p3dp: 1\nname: t\nparts:\n  - name: wall\n    primitive:\n      helix: { radius: 10, height: 2, pitch: 0.5 }\n    steps:\n      - deform_cylinder: { position: [r, theta, \"z + * 2\"] }\n      - deform_xyz:\n          cross_section: \"c * q\"\n";

    fn text_at(s: Span) -> &'static str {
        &RECIPE.lines().nth(s.line - 1).unwrap()[s.start..s.end]
    }

    #[test]
    fn key_paths_are_found_in_block_and_flow_yaml() {
        let s = locate(RECIPE, "parts[0].primitive.helix.pitch").unwrap();
        assert_eq!((s.line, text_at(s)), (6, "0.5"));
        let s = locate(RECIPE, "parts[0].steps[0].deform_cylinder.position[2]").unwrap();
        assert_eq!((s.line, text_at(s)), (8, "\"z + * 2\""));
        let s = locate(RECIPE, "parts[0].steps[1].deform_xyz.cross_section").unwrap();
        assert_eq!((s.line, text_at(s)), (10, "\"c * q\""));
        let s = locate(RECIPE, "name").unwrap();
        assert_eq!(text_at(s), "t");
        assert_eq!(locate(RECIPE, "--set x=1"), None);
    }

    #[test]
    fn expression_errors_point_at_their_token() {
        let line = RECIPE.lines().nth(7).unwrap();
        let s = locate(RECIPE, "parts[0].steps[0].deform_cylinder.position[2]").unwrap();
        let t = expression_token(
            line,
            s,
            "cannot read the expression `z + * 2`: unexpected `* 2` at character 5",
        )
        .unwrap();
        assert_eq!(&line[t.start..t.end], "* 2");
        let line = RECIPE.lines().nth(9).unwrap();
        let s = locate(RECIPE, "parts[0].steps[1].deform_xyz.cross_section").unwrap();
        let t = expression_token(line, s, "unknown name `q` in `c * q`; it may use x").unwrap();
        assert_eq!(&line[t.start..t.end], "q");
    }
}
