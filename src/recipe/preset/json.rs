//! OrcaSlicer and Bambu Studio `.json` presets: printers (`"type":
//! "machine"`) and filaments (`"type": "filament"`), one preset a file,
//! every value a string or a list of strings. `inherits` names the parent
//! preset; Bambu Studio's `include` names template presets whose keys (the
//! start and end G-code) it takes, applied over the parent's and under the
//! preset's own. A named preset is found as `NAME.json` beside the file, in
//! `--profiles DIR` (a slicer's `resources/profiles/VENDOR`) or its
//! `machine/` (`filament/`) folder, or as the file whose `"name"` it is in
//! those folders and their sub-folders (Elegoo keeps parents in a sibling
//! folder such as `machine/ECC/`) — the folders scanned once a load, at
//! most [`MAX_SCAN`] files and [`MAX_SCAN_BYTES`] bytes, each file read
//! once however many links lead to it. Every file a chain reaches lies
//! inside the preset's project or slicer folder or `--profiles`, symlinks
//! resolved, as a YAML profile's `inherits` does.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use serde_json::{Map, Value};

use super::{Format, Kind, Preset, Setting};
use crate::base::error::{Error, Result};
use crate::base::input::Reads;

/// Deepest chain of `inherits` followed.
const MAX_DEPTH: usize = 32;

/// Most files the folders are scanned for, to find a preset by its `"name"`.
const MAX_SCAN: usize = 4000;

/// Most bytes read while scanning the folders.
const MAX_SCAN_BYTES: u64 = 64 << 20;

/// Deepest sub-folder scanned.
const MAX_SCAN_DEPTH: usize = 3;

/// Most templates one preset includes.
const MAX_INCLUDES: usize = 32;

/// Keys that describe a preset file, not a setting.
const META: &[&str] = &[
    "inherits",
    "include",
    "name",
    "type",
    "from",
    "instantiation",
    "setting_id",
    "filament_id",
    "version",
    "description",
];

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
pub(crate) fn name_of(text: &str, file: &str, stem: &str, kind: Kind) -> Result<String> {
    let m = object(text, file)?;
    check_type(&m, file, kind)?;
    Ok(str_of(&m, "name").unwrap_or(stem).to_string())
}

fn check_type(m: &Map<String, Value>, file: &str, kind: Kind) -> Result<()> {
    let ok = match (kind, str_of(m, "type")) {
        (_, None) => true,
        (Kind::Printer, Some(t)) => t == "machine" || t == "machine_model",
        (Kind::Filament, Some(t)) => t == "filament",
    };
    if ok {
        return Ok(());
    }
    let t = str_of(m, "type").unwrap_or_default();
    let expected = match kind {
        Kind::Printer => "a printer preset (`\"type\": \"machine\"`)",
        Kind::Filament => "a filament preset (`\"type\": \"filament\"`)",
    };
    Err(Error::input("type", format!("is a `{t}` preset; expected {expected}")).in_file(file))
}

/// The preset of `text` (read from `path`) with its `inherits` chain and
/// its `include`s resolved through `path`'s folder, its slicer folder and
/// `profiles`; every file read noted in `reads`.
pub(crate) fn preset(
    text: &str,
    path: &Path,
    profiles: Option<&Path>,
    reads: &Reads,
    kind: Kind,
) -> Result<Preset> {
    let file = path.display().to_string();
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let own = object(text, &file)?;
    check_type(&own, &file, kind)?;
    let name = str_of(&own, "name").unwrap_or(&stem).to_string();
    let mut finder = Finder::new(path, profiles, reads, kind);
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
        let Some((found, m)) = finder.find(&parent)? else {
            return Err(Error::input(
                "inherits",
                format!("`{child}` inherits `{parent}`, {}", finder.not_found()),
            )
            .in_file(&file));
        };
        check_type(&m, &found, kind)?;
        chain.push(parent);
        layers.push(m);
    }
    let mut values = std::collections::BTreeMap::new();
    for (k, m) in layers.into_iter().enumerate().rev() {
        // a layer's templates over its parents' keys, its own keys last
        for (inc, t) in includes(&m, &chain[k], &mut finder, &file)? {
            for (key, v) in t {
                if !META.contains(&key.as_str()) {
                    values.insert(key, Setting::Json(v));
                }
            }
            let _ = inc;
        }
        for (key, v) in m {
            if key != "inherits" && key != "include" {
                values.insert(key, Setting::Json(v));
            }
        }
    }
    Ok(Preset {
        name,
        file,
        format: Format::Json,
        kind,
        values,
    })
}

/// The templates the preset `m` (named `name`) includes, in its order: each
/// found as a parent is, or refused naming it.
fn includes(
    m: &Map<String, Value>,
    name: &str,
    finder: &mut Finder,
    file: &str,
) -> Result<Vec<(String, Map<String, Value>)>> {
    let names: Vec<String> = match m.get("include") {
        None => return Ok(Vec::new()),
        Some(Value::String(s)) => vec![s.clone()],
        Some(Value::Array(a)) => a
            .iter()
            .map(|v| {
                v.as_str().map(str::to_string).ok_or_else(|| {
                    Error::input("include", "expected the names of template presets").in_file(file)
                })
            })
            .collect::<Result<_>>()?,
        Some(_) => {
            return Err(
                Error::input("include", "expected the names of template presets").in_file(file),
            )
        }
    };
    if names.len() > MAX_INCLUDES {
        return Err(Error::input(
            "include",
            format!(
                "`{name}` includes {} templates; at most {MAX_INCLUDES} are read",
                names.len()
            ),
        )
        .in_file(file));
    }
    let mut out = Vec::new();
    for inc in names.into_iter().filter(|n| !n.is_empty()) {
        let Some((found, t)) = finder.find(&inc)? else {
            return Err(Error::input(
                "include",
                format!("`{name}` includes `{inc}`, {}", finder.not_found()),
            )
            .in_file(file));
        };
        for nested in ["inherits", "include"] {
            if t.get(nested)
                .is_some_and(|v| v != "" && v != &Value::Array(vec![]))
            {
                return Err(Error::input(
                    nested,
                    format!("the template `{inc}` that `{name}` includes has its own `{nested}`; p3dp reads templates of plain settings only"),
                )
                .in_file(&found));
            }
        }
        out.push((found, t));
    }
    Ok(out)
}

/// Finds presets by name for one load: `NAME.json` in the folders first,
/// else an index of every file's `"name"` in the folder trees, built once.
struct Finder<'a> {
    /// Folders searched for `NAME.json`, in order.
    dirs: Vec<PathBuf>,
    /// Folder trees scanned for a file whose `"name"` is NAME.
    trees: Vec<PathBuf>,
    /// `"name"` (and file stem) → file, once scanned.
    index: Option<HashMap<String, PathBuf>>,
    /// Whether the scan stopped at its cap on files or bytes.
    capped: bool,
    /// Where the chain's files may lie (the preset's project or slicer
    /// folder, `--profiles`), symlinks resolved.
    roots: Reads,
    /// The load's reads, where every file read is noted.
    reads: &'a Reads,
    /// `printer preset` or `filament preset`, in messages.
    what: String,
}

impl<'a> Finder<'a> {
    fn new(path: &Path, profiles: Option<&Path>, reads: &'a Reads, kind: Kind) -> Finder<'a> {
        let sub = match kind {
            Kind::Printer => "machine",
            Kind::Filament => "filament",
        };
        let roots = Reads::default();
        roots.name(path);
        let mut dirs: Vec<PathBuf> = Vec::new();
        let mut trees: Vec<PathBuf> = Vec::new();
        let own = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        dirs.push(own.clone());
        trees.push(own);
        if let Some(p) = profiles {
            roots.allow(p);
            dirs.push(p.to_path_buf());
            dirs.push(p.join(sub));
            trees.push(p.to_path_buf());
        }
        if let Some(vendor) = vendor_folder(path) {
            roots.allow(&vendor);
            dirs.push(vendor.join(sub));
            trees.push(vendor.join(sub));
            // OrcaSlicer's filaments inherit its library's generic ones
            let library = vendor.with_file_name("OrcaFilamentLibrary");
            if kind == Kind::Filament && library.is_dir() && library != vendor {
                roots.allow(&library);
                dirs.push(library.join(sub));
                trees.push(library.join(sub));
            }
        }
        Finder {
            dirs,
            trees,
            index: None,
            capped: false,
            roots,
            reads,
            what: format!("{} preset", kind.word()),
        }
    }

    /// Reads and parses the preset file `p`, held to the chain's folders.
    fn read(&self, p: &Path) -> Result<(String, Map<String, Value>)> {
        self.reads.note(p);
        self.roots.reach(p, &self.what)?;
        let shown = p.display().to_string();
        let m = object(&self.reads.read_plain(p, &self.what)?, &shown)?;
        Ok((shown, m))
    }

    /// The preset named `name`, or `None`.
    fn find(&mut self, name: &str) -> Result<Option<(String, Map<String, Value>)>> {
        let named = |m: &Map<String, Value>| str_of(m, "name").is_none_or(|n| n == name);
        let safe = !name.contains(['/', '\\', '\0']) && name != "." && name != "..";
        if safe {
            for d in &self.dirs {
                let p = d.join(format!("{name}.json"));
                if p.is_file() {
                    let (shown, m) = self.read(&p)?;
                    if named(&m) {
                        return Ok(Some((shown, m)));
                    }
                }
            }
        }
        if self.index.is_none() {
            self.scan();
        }
        match self.index.as_ref().and_then(|i| i.get(name)).cloned() {
            Some(p) => self.read(&p).map(Some),
            None => Ok(None),
        }
    }

    /// Indexes the trees once: each file's `"name"` (and stem), the first
    /// file in sorted order winning; each real file read once.
    fn scan(&mut self) {
        let mut files = Vec::new();
        let mut seen_dirs = HashSet::new();
        for t in self.trees.clone() {
            walk(&t, 0, &mut files, &mut seen_dirs, &mut self.capped);
        }
        let mut index = HashMap::new();
        let mut seen = HashSet::new();
        let mut bytes = 0u64;
        for p in files {
            let Ok(real) = p.canonicalize() else { continue };
            if !seen.insert(real.clone()) || self.roots.reach(&p, &self.what).is_err() {
                continue;
            }
            let size = std::fs::metadata(&real).map(|m| m.len()).unwrap_or(0);
            if bytes + size > MAX_SCAN_BYTES {
                self.capped = true;
                break;
            }
            bytes += size;
            let Ok(text) = crate::base::input::read_plain(&p, &self.what) else {
                continue;
            };
            if let Ok(Value::Object(m)) = serde_json::from_str::<Value>(&text) {
                if let Some(n) = str_of(&m, "name") {
                    index.entry(n.to_string()).or_insert_with(|| p.clone());
                }
            }
            if let Some(s) = p.file_stem() {
                index
                    .entry(s.to_string_lossy().into_owned())
                    .or_insert_with(|| p.clone());
            }
        }
        self.index = Some(index);
    }

    /// The end of a message for a preset found nowhere.
    fn not_found(&self) -> String {
        let looked: Vec<String> = self.dirs.iter().map(|d| d.display().to_string()).collect();
        let capped = if self.capped {
            format!(
                " (the scan stopped at its cap of {MAX_SCAN} files, {} MiB)",
                MAX_SCAN_BYTES >> 20
            )
        } else {
            String::new()
        };
        format!(
            "found in none of {} or their sub-folders{capped} (give the slicer's profile folder with --profiles DIR)",
            looked.join(", ")
        )
    }
}

/// The `.json` files under `dir`, sorted, at most [`MAX_SCAN`] in all and
/// [`MAX_SCAN_DEPTH`] folders deep; a folder met twice (a link) walked once.
fn walk(
    dir: &Path,
    depth: usize,
    out: &mut Vec<PathBuf>,
    seen: &mut HashSet<PathBuf>,
    capped: &mut bool,
) {
    let Ok(real) = dir.canonicalize() else { return };
    if depth > MAX_SCAN_DEPTH || !seen.insert(real) {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut paths: Vec<PathBuf> = Vec::new();
    for e in entries.flatten() {
        if paths.len() >= MAX_SCAN {
            *capped = true;
            break;
        }
        paths.push(e.path());
    }
    paths.sort();
    let mut sub = Vec::new();
    for p in paths {
        if p.is_dir() {
            sub.push(p);
        } else if p.extension().is_some_and(|x| x == "json") && p.is_file() {
            if out.len() >= MAX_SCAN {
                *capped = true;
                return;
            }
            out.push(p);
        }
    }
    for d in sub {
        walk(&d, depth + 1, out, seen, capped);
    }
}

/// The slicer's vendor folder of a preset file: the folder above the
/// nearest `machine`, `filament` or `process` folder holding it (at most
/// three levels up), as OrcaSlicer and Bambu Studio lay out
/// `resources/profiles/VENDOR`.
fn vendor_folder(path: &Path) -> Option<PathBuf> {
    let mut at = path.parent()?;
    for _ in 0..3 {
        let name = at.file_name()?.to_string_lossy();
        if matches!(name.as_ref(), "machine" | "filament" | "process") {
            return at.parent().map(Path::to_path_buf);
        }
        at = at.parent()?;
    }
    None
}
