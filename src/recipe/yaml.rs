//! YAML read with places: every error names the file, line, column and key path.

use serde::de;

use crate::error::{Error, Result};

/// Deserializes YAML into `T`, with errors naming `file`, line, column and key path.
///
/// Enums are written as one-key maps (`{helix: {…}}`), as the spec does.
pub fn parse_yaml<T: de::DeserializeOwned>(text: &str, file: &str) -> Result<T> {
    let de = serde_yaml::Deserializer::from_str(text);
    let mut track = serde_path_to_error::Track::new();
    let tracked = serde_path_to_error::Deserializer::new(de, &mut track);
    serde_yaml::with::singleton_map_recursive::deserialize(tracked).map_err(|e| {
        // a syntax error leaves `?` segments where the parser lost track
        let mut path = track.path().to_string();
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
            err.line = second_document(text).map(|l| (l, 1));
            err.message = "a second YAML document begins here; expected one document".into();
        }
        err
    })
}

/// The line (1-based) of the `---` that starts a second YAML document.
fn second_document(text: &str) -> Option<usize> {
    let mut content = false;
    for (k, line) in text.lines().enumerate() {
        let t = line.trim_end();
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
