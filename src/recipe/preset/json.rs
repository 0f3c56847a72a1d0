//! OrcaSlicer and Bambu Studio `.json` printer presets (`"type":
//! "machine"`): one preset a file, every value a string or a list of
//! strings, `inherits` naming the parent preset (`"from": "system"` or
//! `"User"` alike), found beside the file or in `--profiles DIR` (a
//! slicer's `resources/profiles/VENDOR`, whose presets are under
//! `machine/`): as `NAME.json`, or as the file whose `"name"` it is.

use std::path::{Path, PathBuf};

use serde_json::{Map, Value};

use super::{Format, Preset, Setting};
use crate::base::error::{Error, Result};
use crate::base::input::Reads;

/// Deepest chain of `inherits` followed.
const MAX_DEPTH: usize = 32;

/// Most files of a folder read to find a parent by its `"name"`.
const MAX_SCAN: usize = 4000;

/// One parsed preset file: its keys.
fn object(text: &str, file: &str) -> Result<Map<String, Value>> {
    let v: Value = serde_json::from_str(text).map_err(|e| {
        let mut err = Error::input("", format!("is not a slicer preset (JSON): {e}")).in_file(file);
        err.line = Some((e.line(), e.column()));
        err
    })?;
    match v {
        Value::Object(m) => Ok(m),
        _ => Err(Error::input("", "is not a slicer preset: expected a JSON object").in_file(file)),
    }
}

fn str_of<'a>(m: &'a Map<String, Value>, key: &str) -> Option<&'a str> {
    m.get(key).and_then(Value::as_str)
}

/// The preset's name: its `"name"`, or the file's.
pub(crate) fn name_of(text: &str, file: &str, stem: &str) -> Result<String> {
    let m = object(text, file)?;
    check_type(&m, file)?;
    Ok(str_of(&m, "name").unwrap_or(stem).to_string())
}

fn check_type(m: &Map<String, Value>, file: &str) -> Result<()> {
    match str_of(m, "type") {
        None | Some("machine") | Some("machine_model") => Ok(()),
        Some(t) => Err(Error::input(
            "type",
            format!("is a `{t}` preset; expected a printer preset (`\"type\": \"machine\"`)"),
        )
        .in_file(file)),
    }
}

/// The preset of `text` (read from `path`) with its `inherits` chain
/// resolved through `path`'s folder and `profiles`; every file read noted
/// in `reads`.
pub(crate) fn preset(
    text: &str,
    path: &Path,
    profiles: Option<&Path>,
    reads: &Reads,
) -> Result<Preset> {
    let file = path.display().to_string();
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let own = object(text, &file)?;
    check_type(&own, &file)?;
    let name = str_of(&own, "name").unwrap_or(&stem).to_string();
    let mut dirs: Vec<PathBuf> = Vec::new();
    if let Some(d) = path.parent() {
        dirs.push(if d.as_os_str().is_empty() {
            PathBuf::from(".")
        } else {
            d.to_path_buf()
        });
    }
    if let Some(p) = profiles {
        dirs.push(p.to_path_buf());
        dirs.push(p.join("machine"));
    }
    let mut chain = vec![name.clone()];
    let mut layers = vec![own];
    while let Some(parent) = layers
        .last()
        .and_then(|m| str_of(m, "inherits"))
        .filter(|p| !p.is_empty())
    {
        let parent = parent.to_string();
        if chain.contains(&parent) || chain.len() > MAX_DEPTH {
            chain.push(parent);
            return Err(Error::input(
                "inherits",
                format!("an inherits cycle: {}", chain.join(" → ")),
            )
            .in_file(&file));
        }
        let child = chain.last().cloned().unwrap_or_default();
        let Some((found, m)) = find(&parent, &dirs, reads)? else {
            let looked: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
            return Err(Error::input(
                "inherits",
                format!(
                    "`{child}` inherits `{parent}`, found in none of {} (give the slicer's profile folder with --profiles DIR)",
                    looked.join(", ")
                ),
            )
            .in_file(&file));
        };
        check_type(&m, &found)?;
        chain.push(parent);
        layers.push(m);
    }
    let mut values = std::collections::BTreeMap::new();
    for m in layers.into_iter().rev() {
        for (k, v) in m {
            if k != "inherits" {
                values.insert(k, Setting::Json(v));
            }
        }
    }
    Ok(Preset {
        name,
        file,
        format: Format::Json,
        values,
    })
}

/// The preset named `name` in one of `dirs`: `NAME.json`, else the file
/// whose `"name"` it is (at most [`MAX_SCAN`] files a folder).
fn find(
    name: &str,
    dirs: &[PathBuf],
    reads: &Reads,
) -> Result<Option<(String, Map<String, Value>)>> {
    let named = |m: &Map<String, Value>| str_of(m, "name") == Some(name);
    let safe = !name.contains(['/', '\\']) && name != "." && name != "..";
    for d in dirs {
        let p = d.join(format!("{name}.json"));
        if safe && p.is_file() {
            let shown = p.display().to_string();
            let m = object(&reads.read_plain(&p, "printer preset")?, &shown)?;
            if named(&m) || str_of(&m, "name").is_none() {
                return Ok(Some((shown, m)));
            }
        }
    }
    for d in dirs {
        let Ok(entries) = std::fs::read_dir(d) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "json") && p.is_file())
            .take(MAX_SCAN)
            .collect();
        files.sort();
        for p in files {
            let Ok(text) = crate::base::input::read_plain(&p, "printer preset") else {
                continue;
            };
            let shown = p.display().to_string();
            if let Ok(m) = object(&text, &shown) {
                if named(&m) {
                    reads.note(&p);
                    return Ok(Some((shown, m)));
                }
            }
        }
    }
    Ok(None)
}
