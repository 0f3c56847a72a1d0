//! Printer profiles read from YAML: the built-in ones (embedded in the
//! binary, parsed by the same code as a user's file), a user's file, and
//! `inherits:` chains merged key by key.

use std::path::Path;

use serde::Deserialize;

use super::yaml::parse_yaml;
use crate::base::error::{Error, Result};
use crate::machine::Printer;

const BUILT_IN: &[(&str, &str)] = &[
    (
        "generic-220",
        include_str!("../machine/printers/generic-220.yaml"),
    ),
    ("ender3", include_str!("../machine/printers/ender3.yaml")),
    (
        "prusa-mk3s",
        include_str!("../machine/printers/prusa-mk3s.yaml"),
    ),
    (
        "prusa-mk4",
        include_str!("../machine/printers/prusa-mk4.yaml"),
    ),
    (
        "voron-350",
        include_str!("../machine/printers/voron-350.yaml"),
    ),
    (
        "rostock-max",
        include_str!("../machine/printers/rostock-max.yaml"),
    ),
];

/// Names of the built-in printer profiles.
pub fn built_in_names() -> Vec<&'static str> {
    BUILT_IN.iter().map(|(n, _)| *n).collect()
}

/// A built-in profile by name.
pub fn built_in(name: &str) -> Option<Printer> {
    let (_, text) = BUILT_IN.iter().find(|(n, _)| *n == name)?;
    let p: Printer = parse_yaml(text, name).expect("built-in profiles parse");
    Some(p)
}

impl Printer {
    /// A built-in profile by name.
    pub fn built_in(name: &str) -> Option<Printer> {
        built_in(name)
    }

    /// A profile from a YAML file. With `inherits: NAME|FILE` the file's keys
    /// override those of a built-in profile or another file (maps merged key
    /// by key, see [`merge_yaml`]); a file without it is parsed on its own.
    pub fn from_file(path: &Path) -> Result<Printer> {
        let shown = path.display().to_string();
        let text = crate::base::input::read_text(path, "printer profile")?;
        let value: serde_yaml::Value = parse_yaml(&text, &shown)?;
        let p: Printer = if value.get("inherits").is_some() {
            let named = value.get("name").is_some();
            let mut seen = vec![path.canonicalize().unwrap_or_else(|_| path.to_path_buf())];
            let mut merged = inherit(value, path, &mut seen).map_err(|e| e.in_file(&shown))?;
            if !named {
                // a profile named after its file, not after its base
                let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned());
                if let (Some(m), Some(stem)) = (merged.as_mapping_mut(), stem) {
                    m.insert("name".into(), stem.into());
                }
            }
            from_value(merged, &shown)?
        } else {
            parse_yaml(&text, &shown)?
        };
        p.validate().map_err(|e| e.in_file(&shown))?;
        Ok(p)
    }

    /// A built-in name, or else a path (relative paths from `base`).
    pub fn resolve(spec: &str, base: &Path) -> Result<Printer> {
        if let Some(p) = Printer::built_in(spec) {
            return Ok(p);
        }
        if !names_a_file(spec) {
            return Err(unknown_printer("printer", spec));
        }
        // relative to the recipe's folder, or to the working one for --printer
        let path = if base == Path::new(".") || base.as_os_str().is_empty() {
            Path::new(spec).to_path_buf()
        } else {
            base.join(spec)
        };
        crate::base::input::note_read(&path);
        if !path.is_file() {
            let at = if path == Path::new(spec) {
                String::new()
            } else {
                format!(" ({})", path.display())
            };
            return Err(Error::input(
                "printer",
                format!(
                    "no printer profile at `{spec}`{at}; built-in printers are {}",
                    built_in_names().join(", ")
                ),
            ));
        }
        Printer::from_file(&path)
    }
}

/// Whether a printer name that is not built in is meant as a file: it has a
/// `/` or ends in `.yaml` / `.yml` (anything else is a misspelt name).
fn names_a_file(spec: &str) -> bool {
    spec.contains('/') || spec.ends_with(".yaml") || spec.ends_with(".yml")
}

/// The error for `spec` at key `key`: neither a built-in printer nor a file.
fn unknown_printer(key: &str, spec: &str) -> Error {
    Error::input(
        key,
        format!(
            "unknown printer `{spec}`; built-in printers are {} (or give a path to a printer YAML)",
            built_in_names().join(", ")
        ),
    )
}

/// Deepest chain of `inherits` followed.
const MAX_INHERITS: usize = 16;

/// Resolves the `inherits:` of a profile file's YAML `value` (read from
/// `path`): the base (a built-in name, or a file relative to `path`, itself
/// resolved) with `value`'s keys merged over it. `seen` holds the files of
/// the chain so far, to refuse cycles.
fn inherit(
    mut value: serde_yaml::Value,
    path: &Path,
    seen: &mut Vec<std::path::PathBuf>,
) -> Result<serde_yaml::Value> {
    let Some(spec) = value.as_mapping_mut().and_then(|m| m.remove("inherits")) else {
        return Ok(value);
    };
    let Some(spec) = spec.as_str().map(str::to_string) else {
        return Err(Error::input(
            "inherits",
            "expected the name of a built-in printer or the path of a printer YAML",
        ));
    };
    if seen.len() > MAX_INHERITS {
        return Err(Error::input(
            "inherits",
            format!("more than {MAX_INHERITS} profiles inherit one from another"),
        ));
    }
    let base = if let Some((_, text)) = BUILT_IN.iter().find(|(n, _)| *n == spec) {
        serde_yaml::from_str(text).expect("built-in profiles parse")
    } else if names_a_file(&spec) {
        let rel = spec.trim_start_matches("./");
        let file = match path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() && dir != Path::new(".") => dir.join(rel),
            _ => Path::new(rel).to_path_buf(),
        };
        crate::base::input::note_read(&file);
        let canon = file.canonicalize().map_err(|e| {
            Error::input(
                "inherits",
                format!(
                    "cannot read the printer profile `{spec}` ({}): {e}",
                    file.display()
                ),
            )
        })?;
        if seen.contains(&canon) {
            return Err(Error::input(
                "inherits",
                format!("`{spec}` inherits, directly or not, from itself"),
            ));
        }
        seen.push(canon);
        let shown = file.display().to_string();
        let text = crate::base::input::read_text(&file, "printer profile")?;
        let v: serde_yaml::Value = parse_yaml(&text, &shown)?;
        inherit(v, &file, seen).map_err(|e| e.in_file(&shown))?
    } else {
        return Err(unknown_printer("inherits", &spec));
    };
    Ok(merge_yaml(base, value))
}

/// Deep merge: keys of `over` replace those of `base`, maps are merged key by
/// key, except two maps whose `shape` differs (a round bed replacing a
/// rectangle), where `over` replaces `base` whole.
pub fn merge_yaml(base: serde_yaml::Value, over: serde_yaml::Value) -> serde_yaml::Value {
    use serde_yaml::Value;
    match (base, over) {
        (Value::Mapping(mut b), Value::Mapping(o)) => {
            let shape = |m: &serde_yaml::Mapping| m.get("shape").cloned();
            if shape(&o).is_some() && shape(&b).is_some() && shape(&o) != shape(&b) {
                return Value::Mapping(o);
            }
            for (k, v) in o {
                let merged = match b.remove(&k) {
                    Some(old) => merge_yaml(old, v),
                    None => v,
                };
                b.insert(k, merged);
            }
            Value::Mapping(b)
        }
        (_, over) => over,
    }
}

/// Deserialises a merged profile, naming the key path of any error.
fn from_value(value: serde_yaml::Value, file: &str) -> Result<Printer> {
    let mut track = serde_path_to_error::Track::new();
    let tracked = serde_path_to_error::Deserializer::new(value, &mut track);
    Printer::deserialize(tracked).map_err(|e| {
        let path = track.path().to_string();
        let mut err = Error::input(
            if path == "." { String::new() } else { path },
            e.to_string(),
        );
        err.file = Some(file.to_string());
        err
    })
}
