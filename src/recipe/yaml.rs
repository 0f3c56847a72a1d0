//! YAML read with places: every error names the file, line, column and key
//! path. The one module that knows the YAML library: the rest of the crate
//! reads through [`parse_yaml`] and, to merge profiles, [`Tree`].

use serde::de;

use crate::base::error::{Error, Result};

/// Deserializes YAML into `T`, with errors naming `file`, line, column and key path.
///
/// Enums are written as one-key maps (`{helix: {…}}`), as the spec does.
pub(crate) fn parse_yaml<T: de::DeserializeOwned>(text: &str, file: &str) -> Result<T> {
    let de = serde_yaml::Deserializer::from_str(text);
    let mut track = serde_path_to_error::Track::new();
    let tracked = serde_path_to_error::Deserializer::new(de, &mut track);
    serde_yaml::with::singleton_map_recursive::deserialize(tracked).map_err(|e| {
        // a syntax error leaves `?` segments where the parser lost track
        let segments = track.path();
        let mut path = segments.to_string();
        while let Some(p) = path.strip_suffix(".?").or(path.strip_suffix("?")) {
            path = p.to_string();
        }
        let mut msg = e.to_string();
        if let Some(loc) = e.location() {
            let suffix = format!(" at line {} column {}", loc.line(), loc.column());
            if let Some(k) = msg.find(&suffix) {
                msg.replace_range(k..k + suffix.len(), "");
            }
        }
        // serde_yaml prefixes the parent's path; we give the exact one.
        if let Some((pre, rest)) = msg.split_once(": ") {
            if !pre.is_empty() && !pre.contains(' ') {
                msg = rest.to_string();
            }
        }
        let mut err = Error::input(
            if path == "." { String::new() } else { path },
            shorten_quoted(&msg),
        );
        err.file = Some(file.to_string());
        err.line = e.location().map(|l| (l.line(), l.column()));
        if err.line.is_none() && msg.contains("more than one document") {
            // serde_yaml gives no place: the second `---` is where it begins
            let at = second_document(text);
            err.line = at.map(|l| (l, 1));
            err.message = match at.and_then(|l| text.lines().nth(l - 1)) {
                Some(l) if l.contains('\u{feff}') => "a byte-order mark (U+FEFF) here starts a second YAML document; expected one document (remove the mark)".into(),
                _ => "a second YAML document begins here; expected one document".into(),
            };
        }
        if err.message.contains("expected map with a single key") {
            if let Some((variant, extra, line)) = extra_key(text, &segments, err.line) {
                err.message = format!(
                    "`{extra}` beside `{variant}`: this map takes the one key `{variant}`; is `{extra}` indented too little?"
                );
                err = err.with_help(format!(
                    "if `{extra}` belongs to `{variant}`, indent it as far as the keys under `{variant}`"
                ));
                err.line = line.or(err.line);
            }
        }
        if let Some(help) = misplaced_key(text, &segments, &err.message) {
            err = err.with_help(help);
        }
        explain(err, text)
    })
}

/// A YAML document held as a tree, to be merged with another (a printer
/// profile's `inherits:`) before it is read into a type.
#[derive(Clone, Debug)]
pub(crate) struct Tree(serde_yaml::Value);

impl Tree {
    /// Parses `text`, errors as [`parse_yaml`]'s (naming `file`).
    pub(crate) fn parse(text: &str, file: &str) -> Result<Tree> {
        parse_yaml(text, file).map(Tree)
    }

    /// Whether the top-level map has `key`.
    pub(crate) fn has(&self, key: &str) -> bool {
        self.0.get(key).is_some()
    }

    /// Takes `key` out of the top-level map.
    pub(crate) fn remove(&mut self, key: &str) -> Option<Tree> {
        self.0.as_mapping_mut()?.remove(key).map(Tree)
    }

    /// The text, when the tree is a string.
    pub(crate) fn as_str(&self) -> Option<&str> {
        self.0.as_str()
    }

    /// Sets `key` of the top-level map (when it is a map) to `value`.
    pub(crate) fn set_str(&mut self, key: &str, value: String) {
        if let Some(m) = self.0.as_mapping_mut() {
            m.insert(key.into(), value.into());
        }
    }

    /// Deep merge: keys of `over` replace those of `base`, maps are merged
    /// key by key, except two maps whose `tag` key differs (a round bed
    /// replacing a rectangle: `shape`), where `over` replaces `base` whole.
    pub(crate) fn merge(base: Tree, over: Tree, tag: &str) -> Tree {
        Tree(merge(base.0, over.0, tag))
    }

    /// Reads the tree into `T`, naming the key path of any error (and
    /// `file`; a merged tree has no lines).
    pub(crate) fn read<T: de::DeserializeOwned>(self, file: &str) -> Result<T> {
        let mut track = serde_path_to_error::Track::new();
        let tracked = serde_path_to_error::Deserializer::new(self.0, &mut track);
        T::deserialize(tracked).map_err(|e| {
            let path = track.path().to_string();
            let mut err = Error::input(
                if path == "." { String::new() } else { path },
                e.to_string(),
            );
            err.file = Some(file.to_string());
            err
        })
    }
}

fn merge(base: serde_yaml::Value, over: serde_yaml::Value, tag: &str) -> serde_yaml::Value {
    use serde_yaml::Value;
    match (base, over) {
        (Value::Mapping(mut b), Value::Mapping(o)) => {
            let tagged = |m: &serde_yaml::Mapping| m.get(tag).cloned();
            if tagged(&o).is_some() && tagged(&b).is_some() && tagged(&o) != tagged(&b) {
                return Value::Mapping(o);
            }
            for (k, v) in o {
                let merged = match b.remove(&k) {
                    Some(old) => merge(old, v, tag),
                    None => v,
                };
                b.insert(k, merged);
            }
            Value::Mapping(b)
        }
        (_, over) => over,
    }
}

/// A line and column, 1-based.
type LineCol = (usize, usize);

/// Where a one-key map (`{deform_xyz: {…}}`) met a second key: the first key,
/// the second, and the second's line and column.
fn extra_key(
    text: &str,
    path: &serde_path_to_error::Path,
    near: Option<(usize, usize)>,
) -> Option<(String, String, Option<LineCol>)> {
    let chain = node_chain(text, path)?;
    let map = chain.last()?.1.as_mapping()?;
    let mut keys = map.keys().filter_map(serde_yaml::Value::as_str);
    let (variant, extra) = (keys.next()?.to_string(), keys.next()?.to_string());
    let near = near.map_or(0, |(l, _)| l);
    let line = key_lines(text, &extra).min_by_key(|(l, _)| (l.abs_diff(near), *l > near));
    Some((variant, extra, line))
}

/// The lines and columns where `key:` is written, 1-based.
fn key_lines<'a>(text: &'a str, key: &'a str) -> impl Iterator<Item = (usize, usize)> + 'a {
    text.lines().enumerate().filter_map(move |(k, l)| {
        let t = l.trim_start();
        let t = t.strip_prefix("- ").unwrap_or(t).trim_start();
        let rest = t.strip_prefix(key)?;
        rest.trim_start()
            .starts_with(':')
            .then(|| (k + 1, l.len() - t.len() + 1))
    })
}

/// The YAML nodes along a key path, each with its name, the document first.
fn node_chain(
    text: &str,
    path: &serde_path_to_error::Path,
) -> Option<Vec<(String, serde_yaml::Value)>> {
    use serde_path_to_error::Segment;
    let mut node: serde_yaml::Value = serde_yaml::from_str(text).ok()?;
    let mut chain = vec![("the top level".to_string(), node.clone())];
    for seg in path.iter() {
        let (name, next) = match seg {
            Segment::Seq { index } => (format!("[{index}]"), node.get(*index)?),
            Segment::Map { key } | Segment::Enum { variant: key } => {
                (format!("`{key}`"), node.get(key.as_str())?)
            }
            Segment::Unknown => return None,
        };
        node = next.clone();
        chain.push((name, node.clone()));
    }
    Some(chain)
}

/// A help for a key that is missing where it was expected but written at an
/// outer level (indented too little), or unknown beside a primitive.
fn misplaced_key(text: &str, path: &serde_path_to_error::Path, message: &str) -> Option<String> {
    let quoted = |after: &str| -> Option<String> {
        let rest = message.split_once(after)?.1;
        Some(rest.split('`').next()?.to_string())
    };
    if let Some(key) = quoted("unknown key `").filter(|_| message.contains("beside the primitive"))
    {
        return Some(format!(
            "if `{key}` belongs to the primitive, indent it as far as the primitive's own keys"
        ));
    }
    let key = quoted("missing field `")?;
    let chain = node_chain(text, path)?;
    let (here, _) = chain.last()?;
    let outer = chain[..chain.len() - 1]
        .iter()
        .rev()
        .find(|(_, n)| n.get(key.as_str()).is_some())?;
    Some(format!(
        "`{key}:` is written under {} instead of {here}: indent it as far as the keys of {here}",
        outer.0
    ))
}

/// For ``unknown field `pich`, expected one of `radius`, `pitch` `` (or an
/// unknown variant): `did you mean `pitch`?` when a key is close, and the
/// allowed keys.
fn did_you_mean(message: &str) -> Option<String> {
    let (head, allowed) = message.split_once(", expected one of ")?;
    let wrong = head
        .strip_prefix("unknown field `")
        .or_else(|| head.strip_prefix("unknown variant `"))?
        .strip_suffix('`')?;
    let keys: Vec<&str> = allowed.split(", ").map(|k| k.trim_matches('`')).collect();
    let best = keys
        .iter()
        .map(|k| (strsim::damerau_levenshtein(wrong, k), *k))
        .filter(|(d, k)| *d <= 2.max(k.len() / 3) && *d < k.len())
        .min();
    let list = keys
        .iter()
        .map(|k| format!("`{k}`"))
        .collect::<Vec<_>>()
        .join(", ");
    Some(match best {
        Some((_, k)) => format!("did you mean `{k}`? the keys allowed here are {list}"),
        None => format!("the keys allowed here are {list}"),
    })
}

/// Puts the parser's terse messages in plain words: an empty file, a tab, a
/// misspelt key.
fn explain(mut err: Error, text: &str) -> Error {
    if err.help.is_none() {
        if let Some(h) = did_you_mean(&err.message) {
            err = err.with_help(h);
        }
    }
    let blank = text
        .lines()
        .all(|l| l.trim().is_empty() || l.trim_start().starts_with('#'));
    if blank {
        err.place = None;
        err.line = None;
        err.message = if text.trim().is_empty() {
            "the file is empty; expected YAML keys (a recipe starts with `p3dp: 1`)".into()
        } else {
            "the file has only comments; expected YAML keys (a recipe starts with `p3dp: 1`)".into()
        };
        return err.with_help(
            "a recipe starts with `p3dp: 1`, `name:` and `parts:`; `p3dp new NAME` writes a starter to edit",
        );
    }
    if let Some((l, c)) = err.line {
        let at = |l: usize| text.lines().nth(l.wrapping_sub(1)).unwrap_or("");
        // the tab is where the parser stopped, or indents that line or the one before
        let tab_at = at(l).chars().nth(c.saturating_sub(1)) == Some('\t');
        let indent_tab = |line: &str| line[..line.len() - line.trim_start().len()].contains('\t');
        let tab_line = if tab_at || indent_tab(at(l)) {
            Some(l)
        } else if l > 1 && indent_tab(at(l - 1)) {
            Some(l - 1)
        } else {
            None
        };
        if let Some(t) = tab_line {
            if t != l {
                err.line = Some((t, at(t).find('\t').map_or(1, |k| k + 1)));
            }
            err.place = None;
            err.message = "a tab in the indentation; YAML indents with spaces only".into();
            err = err.with_help("tabs are not allowed in YAML indentation; use spaces");
        }
    }
    err
}

/// The line (1-based) of the `---` (or of the `...` that ends the first,
/// or of a byte-order mark, which YAML takes as a new stream's start) that
/// starts a second YAML document.
fn second_document(text: &str) -> Option<usize> {
    let mut content = false;
    // the indentation of the first content line: a line indented less ends
    // the first document too (YAML reads it as a second)
    let mut first_indent: Option<usize> = None;
    for (k, line) in text.lines().enumerate() {
        let t = line.trim_end();
        let indent = line.len() - line.trim_start().len();
        let blank = t.trim_start().is_empty() || t.trim_start().starts_with('#');
        if let Some(i) = first_indent.filter(|_| !blank) {
            if indent < i {
                return Some(k + 1);
            }
        }
        if !blank && first_indent.is_none() && !t.starts_with("---") {
            first_indent = Some(indent);
        }
        if content && (t.contains('\u{feff}') || t == "..." || t.starts_with("... ")) {
            return Some(k + 1);
        }
        if t == "---" || t.starts_with("--- ") {
            if content {
                return Some(k + 1);
            }
            content = true;
        } else if !t.is_empty() && !t.starts_with('#') {
            content = true;
        }
    }
    None
}

/// Cuts each quoted text of a message to 40 characters: an error about a
/// file that is no recipe (`/etc/passwd`) names it, not prints it.
fn shorten_quoted(msg: &str) -> String {
    const KEEP: usize = 40;
    // a whole file read as one string (a text file that is no YAML map):
    // say what it is, not what it says
    if let Some(rest) = msg.strip_prefix("invalid type: string \"") {
        if let Some(k) = rest.rfind("\", expected") {
            return format!("invalid type: text{}", &rest[k + 1..]);
        }
    }
    let mut out = String::with_capacity(msg.len().min(400));
    let mut rest = msg;
    while let Some(open) = rest.find('"') {
        out.push_str(&rest[..=open]);
        let after = &rest[open + 1..];
        let close = after.find('"').unwrap_or(after.len());
        let inner = &after[..close];
        if inner.chars().count() > KEEP {
            out.extend(inner.chars().take(KEEP));
            out.push('…');
        } else {
            out.push_str(inner);
        }
        rest = &after[close..];
        if let Some(r) = rest.strip_prefix('"') {
            out.push('"');
            rest = r;
        }
    }
    out.push_str(rest);
    if out.chars().count() > 400 {
        out = out.chars().take(400).collect::<String>() + "…";
    }
    out
}
/// `value` as YAML text (for the files p3dp writes in YAML: lock files).
pub(crate) fn to_yaml<T: serde::Serialize>(value: &T) -> String {
    serde_yaml::to_string(value).expect("p3dp's own values serialise")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_document_is_placed_where_it_begins() {
        for (text, line, says) in [
            ("a: 1\n---\nb: 2\n", 2, "second YAML document"),
            ("a: 1\n...\nb: 2\n", 2, "second YAML document"),
            ("# c\n  a: 1\nb: 2\n", 3, "second YAML document"),
        ] {
            let e = parse_yaml::<serde_yaml::Value>(text, "f.yaml").unwrap_err();
            assert_eq!(e.line.map(|l| l.0), Some(line), "{text:?}: {e}");
            assert!(e.message.contains(says), "{text:?}: {e}");
        }
    }
}
