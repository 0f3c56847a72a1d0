//! `p3dp new`: a commented starter recipe that builds as it is.

use std::io::Write;
use std::path::PathBuf;

use super::{file_stem, make_parent};
use crate::base::error::{Error, Result};

/// The starter recipes of `p3dp new --from KIND`: each kind and its text,
/// with `__NAME__` where the recipe's name goes.
pub const STARTERS: &[(&str, &str)] = &[
    ("sphere", include_str!("../starters/sphere.yaml")),
    ("globe", include_str!("../starters/globe.yaml")),
    ("plate", include_str!("../starters/plate.yaml")),
    ("turtle", include_str!("../starters/turtle.yaml")),
    ("solid", include_str!("../starters/solid.yaml")),
];

/// The text of starter `from` for a recipe called `name`, built from `file`.
pub(crate) fn starter_text(name: &str, from: &str, file: &str) -> Result<String> {
    let text = STARTERS
        .iter()
        .find(|(k, _)| *k == from)
        .map(|(_, t)| *t)
        .ok_or_else(|| {
            let kinds: Vec<&str> = STARTERS.iter().map(|(k, _)| *k).collect();
            Error::input(
                format!("--from {from}"),
                format!("no starter `{from}`; expected one of {}", kinds.join(", ")),
            )
        })?;
    let plain = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c));
    let yaml_name = if plain {
        name.to_string()
    } else {
        serde_json::to_string(name).expect("a string serialises")
    };
    Ok(text
        .replace("__NAME__.yaml", file)
        .replace("__NAME__.gcode", &format!("{}.gcode", file_stem(name)))
        .replace("name: __NAME__", &format!("name: {yaml_name}"))
        .replace("__NAME__", name))
}

/// `p3dp new NAME [--from KIND]`: writes the starter recipe `NAME.yaml` (or
/// NAME itself when it ends in `.yaml`/`.yml`), never over an existing file;
/// returns the line to print.
pub(crate) fn write(name: &str, from: &str) -> Result<String> {
    let path = if name.ends_with(".yaml") || name.ends_with(".yml") {
        PathBuf::from(name)
    } else {
        PathBuf::from(format!("{name}.yaml"))
    };
    let shown = path.display().to_string();
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.trim().is_empty())
        .ok_or_else(|| Error::input(format!("new {name}"), "expected a recipe name"))?;
    let text = starter_text(&stem, from, &shown)?;
    make_parent(&path)?;
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&path)
        .map_err(|e| {
            let why = if e.kind() == std::io::ErrorKind::AlreadyExists {
                "already exists; not overwritten (choose another name or remove it)".to_string()
            } else {
                format!("cannot create the recipe: {e}")
            };
            Error::io_from(&shown, why, &e)
        })?;
    file.write_all(text.as_bytes())
        .map_err(|e| Error::io_from(&shown, format!("cannot write the recipe: {e}"), &e))?;
    Ok(format!(
        "wrote {shown} (a {from} to start from); build it with: p3dp build {shown}"
    ))
}
