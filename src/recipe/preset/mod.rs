//! Slicer presets imported: PrusaSlicer's family of `.ini` files ([`ini`])
//! and OrcaSlicer's and Bambu Studio's `.json` ones ([`json`]), read
//! through the project's input rules (bounded, UTF-8, noted in the load's
//! reads, a `.json` chain's files held to the folders the build may read),
//! their `inherits` (and Bambu Studio's `include`) resolved, each preset
//! once. A printer preset is mapped into a profile's terms and units as the
//! profile's own raw type ([`map`]): `--printer FILE.ini|FILE.json` builds
//! with it directly, `p3dp printers import` writes it as YAML. A filament
//! preset (`--filament FILE [--filament-preset NAME]`) gives the material
//! and the filament's template variables (see
//! `crate::recipe::resolve::material`).

mod bed;
pub(crate) mod ini;
pub(crate) mod json;
pub(crate) mod map;
mod reach;
mod write;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::base::error::{Error, Result};
use crate::base::input::Reads;

/// The preset file's family.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Format {
    /// PrusaSlicer, SuperSlicer, Slic3r: `key = value` text.
    Ini,
    /// OrcaSlicer, Bambu Studio: JSON strings and lists of strings.
    Json,
}

impl Format {
    /// The family's name in notes.
    pub(crate) fn describe(self) -> &'static str {
        match self {
            Format::Ini => "a PrusaSlicer-family .ini preset",
            Format::Json => "an OrcaSlicer/Bambu Studio .json preset",
        }
    }
}

/// What a preset describes: a printer (`[printer:NAME]`, `"type":
/// "machine"`) or a filament (`[filament:NAME]`, `"type": "filament"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Kind {
    /// A printer preset.
    Printer,
    /// A filament preset.
    Filament,
}

impl Kind {
    /// The kind's name in messages: `printer`, `filament`.
    pub(crate) fn word(self) -> &'static str {
        match self {
            Kind::Printer => "printer",
            Kind::Filament => "filament",
        }
    }

    /// The option that picks a preset of this kind in a bundle.
    pub(crate) fn option(self) -> &'static str {
        match self {
            Kind::Printer => "--preset",
            Kind::Filament => "--filament-preset",
        }
    }
}

/// One setting as the preset file holds it.
#[derive(Clone, Debug, PartialEq)]
pub enum Setting {
    /// An `.ini` value: text, a list comma-separated, a string C-escaped.
    Ini(String),
    /// A `.json` value: a string or a list of strings.
    Json(serde_json::Value),
}

/// A preset, its `inherits` resolved: every key it and its parents set.
#[derive(Clone, Debug, PartialEq)]
pub struct Preset {
    /// The preset's name.
    pub(crate) name: String,
    /// The file it was read from, as the user named it.
    pub(crate) file: String,
    /// The file's family.
    pub(crate) format: Format,
    /// A printer's or a filament's.
    pub kind: Kind,
    /// Every setting, by key.
    pub values: BTreeMap<String, Setting>,
}

impl Preset {
    /// Whether `key` is set (and not empty).
    pub(crate) fn has(&self, key: &str) -> bool {
        self.text(key).is_some_and(|t| !t.is_empty())
    }

    /// A string setting (`.ini` escapes undone; a `.json` list's first element).
    /// A `.json` string has its C escapes undone too, as OrcaSlicer and
    /// Bambu Studio read one (`ConfigBase::load_from_json` deserialises a
    /// string option with `unescape_string_cstyle`: Snapmaker's U1 writes
    /// its G-code on one line with `\n` between the commands); a list's
    /// elements are taken as they are (escaped and unescaped again there).
    pub fn text(&self, key: &str) -> Option<String> {
        match self.values.get(key)? {
            Setting::Ini(s) => Some(ini::unescape(s)),
            Setting::Json(serde_json::Value::String(s)) => Some(ini::unescape(s)),
            Setting::Json(serde_json::Value::Array(a)) => a.first().map(json_text),
            Setting::Json(v) => Some(json_text(v)),
        }
    }

    /// A list setting: an `.ini` value split at commas, a `.json` list.
    pub(crate) fn list(&self, key: &str) -> Option<Vec<String>> {
        match self.values.get(key)? {
            Setting::Ini(s) => Some(split(s)),
            Setting::Json(serde_json::Value::Array(a)) => Some(a.iter().map(json_text).collect()),
            Setting::Json(serde_json::Value::String(s)) => Some(split(s)),
            Setting::Json(v) => Some(vec![json_text(v)]),
        }
    }

    /// The first number of a setting; an error names the key when it is
    /// set but no number.
    pub(crate) fn number(&self, key: &str) -> Result<Option<f64>> {
        let Some(first) = self.list(key).and_then(|l| l.into_iter().next()) else {
            return Ok(None);
        };
        let t = first.trim().trim_end_matches('%');
        if t.is_empty() || t == "nil" {
            return Ok(None);
        }
        match t.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(Error::input(key, format!("`{first}` is not a number")).in_file(&self.file)),
        }
    }

    /// The first of `keys` that is set, as text.
    pub(crate) fn first_text(&self, keys: &[&str]) -> Option<(String, String)> {
        keys.iter().find_map(|k| {
            self.text(k)
                .filter(|t| !t.is_empty())
                .map(|t| (k.to_string(), t))
        })
    }

    /// The first number of the first of `keys` that is set.
    pub(crate) fn first_number(&self, keys: &[&str]) -> Result<Option<f64>> {
        for k in keys {
            if let Some(v) = self.number(k)? {
                return Ok(Some(v));
            }
        }
        Ok(None)
    }
}

/// The refusal of preset `p` at `key`: p3dp cannot import `what`.
pub(crate) fn refuse(p: &Preset, key: &str, what: String) -> Error {
    Error::input(
        key,
        format!("preset `{}`: p3dp cannot import {what}", p.name),
    )
    .in_file(&p.file)
}

fn json_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

fn split(s: &str) -> Vec<String> {
    s.split(',').map(|x| x.trim().to_string()).collect()
}

/// Where a preset comes from: its file, the preset picked, the folder its
/// parents are found in.
#[derive(Clone, Debug, Default)]
pub struct Source {
    /// The preset file.
    pub file: PathBuf,
    /// `--preset NAME` (`--filament-preset NAME`): the preset of a bundle.
    pub preset: Option<String>,
    /// `--profiles DIR`: where `.json` parents (and nothing else) are found.
    pub profiles: Option<PathBuf>,
}

/// Whether `path` names a slicer preset file (`.ini` or `.json`).
pub(crate) fn is_preset_file(path: &str) -> bool {
    let lower = path.to_ascii_lowercase();
    lower.ends_with(".ini") || lower.ends_with(".json")
}

fn format_of(path: &Path, text: &str) -> Format {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("json") => Format::Json,
        Some("ini") => Format::Ini,
        _ if text.trim_start().starts_with('{') => Format::Json,
        _ => Format::Ini,
    }
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The printer presets `file` holds, in its order.
#[cfg(any(test, feature = "testing"))]
pub fn list(file: &Path, reads: &Reads) -> Result<Vec<String>> {
    list_of(Kind::Printer, file, reads)
}

/// The presets of `kind` that `file` holds, in its order.
pub fn list_of(kind: Kind, file: &Path, reads: &Reads) -> Result<Vec<String>> {
    let shown = file.display().to_string();
    let text = reads.read_plain(file, &format!("{} preset", kind.word()))?;
    match format_of(file, &text) {
        Format::Ini => Ok(ini::parse(&text, &shown)?.names(kind, &stem(file))),
        Format::Json => Ok(vec![json::name_of(&text, &shown, &stem(file), kind)?]),
    }
}

/// The printer preset `src` names, its `inherits` resolved.
pub fn load(src: &Source, reads: &Reads) -> Result<Preset> {
    load_kind(Kind::Printer, src, reads)
}

/// The filament preset `src` names, its `inherits` resolved.
pub fn load_filament(src: &Source, reads: &Reads) -> Result<Preset> {
    load_kind(Kind::Filament, src, reads)
}

/// The preset of `kind` that `src` names, its `inherits` resolved; the
/// files a `.json` chain reaches read only inside the folders the build may
/// read (the preset's project or slicer folder, `--profiles`).
pub(crate) fn load_kind(kind: Kind, src: &Source, reads: &Reads) -> Result<Preset> {
    let shown = src.file.display().to_string();
    let text = reads.read_plain(&src.file, &format!("{} preset", kind.word()))?;
    match format_of(&src.file, &text) {
        Format::Ini => {
            ini::parse(&text, &shown)?.preset(kind, src.preset.as_deref(), &shown, &stem(&src.file))
        }
        Format::Json => {
            let p = json::preset(&text, &src.file, src.profiles.as_deref(), reads, kind)?;
            match &src.preset {
                Some(n) if *n != p.name => Err(Error::input(
                    kind.option(),
                    format!(
                        "the file holds the {} preset `{}`, not `{n}`",
                        kind.word(),
                        p.name
                    ),
                )
                .in_file(&shown)),
                _ => Ok(p),
            }
        }
    }
}

/// Characters of a name the did-you-mean search compares: the start of a
/// long name tells it apart, and a bound keeps thousands of long names quick.
const CLOSE_CHARS: usize = 64;

/// Most names the did-you-mean search looks at.
const CLOSE_NAMES: usize = 20_000;

/// The message for a `kind` preset `name` not in `file`, which holds
/// `names` (the closest names offered; the search bounded in names and in
/// characters a name).
pub(crate) fn no_such(kind: Kind, name: &str, names: &[String], file: &str) -> String {
    let cut = |s: &str| {
        s.chars()
            .take(CLOSE_CHARS)
            .collect::<String>()
            .to_lowercase()
    };
    let wanted = cut(name);
    let mut close: Vec<(f64, &String)> = names
        .iter()
        .take(CLOSE_NAMES)
        .map(|n| (strsim::normalized_levenshtein(&cut(n), &wanted), n))
        .filter(|(s, _)| *s > 0.5)
        .collect();
    close.sort_by(|a, b| b.0.total_cmp(&a.0));
    let shown = crate::base::safe_text::one_line(name);
    let mut msg = format!("no {} preset `{shown}` in {file}", kind.word());
    if !close.is_empty() {
        let shown: Vec<String> = close
            .iter()
            .take(3)
            .map(|(_, n)| format!("`{}`", crate::base::safe_text::one_line(n)))
            .collect();
        msg.push_str(&format!("; did you mean {}?", shown.join(", ")));
    } else {
        msg.push_str(&format!(
            "; `p3dp printers list {file}` lists its printer presets"
        ));
    }
    msg
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `.json` string's C escapes are undone as OrcaSlicer undoes them (a
    /// G-code written on one line with `\n`); a list's elements are not.
    #[test]
    fn json_strings_are_unescaped_as_orcaslicer_reads_them() {
        let j = |v: serde_json::Value| Setting::Json(v);
        let p = Preset {
            name: "U".into(),
            file: "u.json".into(),
            format: Format::Json,
            kind: Kind::Printer,
            values: [
                (
                    "one".to_string(),
                    j(serde_json::json!(
                        r#"G28\nM117 \"a\"\n{if x==\"b\"}T0{endif}"#
                    )),
                ),
                ("real".to_string(), j(serde_json::json!("G28\nG1 Z5"))),
                ("list".to_string(), j(serde_json::json!([r"a\nb"]))),
            ]
            .into_iter()
            .collect(),
        };
        assert_eq!(
            p.text("one").unwrap(),
            "G28\nM117 \"a\"\n{if x==\"b\"}T0{endif}"
        );
        assert_eq!(p.text("real").unwrap(), "G28\nG1 Z5");
        assert_eq!(p.text("list").unwrap(), r"a\nb");
    }

    /// A missed name among thousands of long ones is answered quickly: the
    /// search compares the first characters of each name only.
    #[test]
    fn did_you_mean_is_bounded() {
        let names: Vec<String> = (0..4000)
            .map(|k| format!("{k:04} {}", "long preset name ".repeat(60)))
            .collect();
        let t = std::time::Instant::now();
        let msg = no_such(
            Kind::Printer,
            &format!("0007 {}", "long preset name ".repeat(59)),
            &names,
            "b.ini",
        );
        assert!(msg.contains("did you mean `0007 long"), "{}", &msg[..200]);
        // unbounded, 4000 Levenshtein distances of 1000-character names
        // take tens of seconds
        assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
    }
}
