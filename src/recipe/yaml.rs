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
        let mut err = Error::input(if path == "." { String::new() } else { path }, msg);
        err.file = Some(file.to_string());
        err.line = e.location().map(|l| (l.line(), l.column()));
        err
    })
}
