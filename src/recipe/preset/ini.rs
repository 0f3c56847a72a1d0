//! PrusaSlicer-family `.ini` presets (PrusaSlicer, SuperSlicer, Slic3r): a
//! vendor or user bundle of `[printer:NAME]` sections (`inherits = a; b`
//! resolved inside the bundle, the parents applied left to right and the
//! section's own keys last; abstract `*name*` sections are bases only), or
//! an exported config, one preset of `key = value` lines with no section.

use std::collections::BTreeMap;

use super::{Format, Preset, Setting};
use crate::base::error::{Error, Result};

/// Deepest chain of `inherits` followed.
const MAX_DEPTH: usize = 32;

/// A parsed `.ini` file: its printer sections in order, or its one preset.
pub(crate) struct Ini {
    /// `[printer:NAME]` sections, in the file's order.
    pub printers: Vec<(String, BTreeMap<String, String>)>,
    /// The keys before any section (an exported config's whole).
    pub top: BTreeMap<String, String>,
    /// Whether the file has sections at all.
    pub sectioned: bool,
}

/// Parses `text` (`file` names it in errors): sections, `key = value`
/// lines, `#` and `;` comment lines.
pub(crate) fn parse(text: &str, file: &str) -> Result<Ini> {
    let mut ini = Ini {
        printers: Vec::new(),
        top: BTreeMap::new(),
        sectioned: false,
    };
    // where `key = value` lines go: the top, a printer section, or nowhere
    // (another kind of section)
    enum Into {
        Top,
        Printer(usize),
        Skip,
    }
    let mut into = Into::Top;
    for (k, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with(';') {
            continue;
        }
        if let Some(head) = line.strip_prefix('[') {
            let Some(head) = head.strip_suffix(']') else {
                return Err(at(file, k, "a section header without its `]`"));
            };
            ini.sectioned = true;
            into = match head.split_once(':') {
                Some(("printer", name)) => {
                    ini.printers
                        .push((name.trim().to_string(), BTreeMap::new()));
                    Into::Printer(ini.printers.len() - 1)
                }
                _ => Into::Skip,
            };
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            return Err(at(
                file,
                k,
                "expected `key = value`, a `[section]` or a comment; this is not a slicer preset file",
            ));
        };
        let (key, value) = (key.trim().to_string(), value.trim().to_string());
        match into {
            Into::Top => {
                ini.top.insert(key, value);
            }
            Into::Printer(i) => {
                ini.printers[i].1.insert(key, value);
            }
            Into::Skip => {}
        }
    }
    Ok(ini)
}

fn at(file: &str, k: usize, message: &str) -> Error {
    let mut e = Error::input("", message).in_file(file);
    e.line = Some((k + 1, 1));
    e
}

impl Ini {
    /// The printer presets a user may pick: every section but the abstract
    /// `*name*` ones (an exported config: its one preset).
    pub(crate) fn names(&self, stem: &str) -> Vec<String> {
        if !self.sectioned {
            return vec![self.single_name(stem)];
        }
        self.printers
            .iter()
            .map(|(n, _)| n.clone())
            .filter(|n| !is_abstract(n))
            .collect()
    }

    /// An exported config's name: its `printer_settings_id`, or the file's.
    fn single_name(&self, stem: &str) -> String {
        match self.top.get("printer_settings_id") {
            Some(id) if !id.is_empty() => id.clone(),
            _ => stem.to_string(),
        }
    }

    /// The preset `name` (or the only one) with its `inherits` resolved.
    pub(crate) fn preset(&self, name: Option<&str>, file: &str, stem: &str) -> Result<Preset> {
        if !self.sectioned {
            if self.top.is_empty() {
                return Err(Error::input(
                    "",
                    "holds no settings; expected a slicer's printer preset",
                )
                .in_file(file));
            }
            return Ok(preset(self.single_name(stem), &self.top, file));
        }
        let names = self.names(stem);
        let name = match name {
            Some(n) => n.to_string(),
            None if names.len() == 1 => names[0].clone(),
            None if names.is_empty() => {
                return Err(Error::input("", "holds no printer preset (no `[printer:NAME]` section)").in_file(file))
            }
            None => {
                return Err(Error::input(
                    "",
                    format!(
                        "holds {} printer presets; pick one: `p3dp printers import {file} --preset NAME -o OUT.yaml` (`p3dp printers list {file}` lists them)",
                        names.len()
                    ),
                )
                .in_file(file))
            }
        };
        if is_abstract(&name) && self.find(&name).is_some() {
            return Err(Error::input(
                "--preset",
                format!("`{name}` is an abstract preset, a base for others; pick one of those"),
            )
            .in_file(file));
        }
        let mut chain = Vec::new();
        let values = self.resolve(&name, &mut chain, file)?;
        Ok(preset(name, &values, file))
    }

    fn find(&self, name: &str) -> Option<&BTreeMap<String, String>> {
        self.printers
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    }

    /// The keys of `name` over those of its parents; `chain` holds the
    /// presets being resolved (a cycle is an error naming them).
    fn resolve(
        &self,
        name: &str,
        chain: &mut Vec<String>,
        file: &str,
    ) -> Result<BTreeMap<String, String>> {
        let Some(own) = self.find(name) else {
            let msg = match chain.last() {
                Some(child) => format!("`{child}` inherits `{name}`, which is not in this file"),
                None => super::no_such(name, &self.names(""), file),
            };
            return Err(Error::input("inherits", msg).in_file(file));
        };
        if chain.iter().any(|n| n == name) || chain.len() > MAX_DEPTH {
            chain.push(name.to_string());
            return Err(Error::input(
                "inherits",
                format!("an inherits cycle: {}", chain.join(" → ")),
            )
            .in_file(file));
        }
        chain.push(name.to_string());
        let mut out = BTreeMap::new();
        if let Some(parents) = own.get("inherits") {
            for parent in parents.split(';').map(str::trim).filter(|p| !p.is_empty()) {
                out.extend(self.resolve(parent, chain, file)?);
            }
        }
        chain.pop();
        out.extend(
            own.iter()
                .filter(|(k, _)| *k != "inherits")
                .map(|(k, v)| (k.clone(), v.clone())),
        );
        Ok(out)
    }
}

fn is_abstract(name: &str) -> bool {
    name.len() >= 2 && name.starts_with('*') && name.ends_with('*')
}

fn preset(name: String, values: &BTreeMap<String, String>, file: &str) -> Preset {
    Preset {
        name,
        file: file.to_string(),
        format: Format::Ini,
        values: values
            .iter()
            .map(|(k, v)| (k.clone(), Setting::Ini(v.clone())))
            .collect(),
    }
}

/// A string option as PrusaSlicer stores it: `\n` a line feed, `\r` a
/// carriage return, `\` before any other character that character.
pub(crate) fn unescape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        match chars.next() {
            Some('n') => out.push('\n'),
            Some('r') => out.push('\r'),
            Some(other) => out.push(other),
            None => out.push('\\'),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const BUNDLE: &str = "# a bundle\n[vendor]\nname = V\n[printer:*common*]\nbed_shape = 0x0,200x0,200x200,0x200\nretract_length = 1\n[printer:*fast*]\nmachine_max_feedrate_x = 300\nretract_length = 2\n[printer:A]\ninherits = *common*; *fast*\nprinter_model = A1\n[printer:B]\ninherits = A\nretract_length = 3\n[print:x]\nlayer_height = 0.2\n";

    #[test]
    fn inherits_left_to_right_then_own() {
        let ini = parse(BUNDLE, "v.ini").unwrap();
        assert_eq!(ini.names("v"), ["A", "B"]);
        let a = ini.preset(Some("A"), "v.ini", "v").unwrap();
        assert_eq!(a.text("retract_length").as_deref(), Some("2"));
        assert_eq!(
            a.text("bed_shape").as_deref(),
            Some("0x0,200x0,200x200,0x200")
        );
        let b = ini.preset(Some("B"), "v.ini", "v").unwrap();
        assert_eq!(b.text("retract_length").as_deref(), Some("3"));
        assert_eq!(b.text("printer_model").as_deref(), Some("A1"));
        assert!(b.text("layer_height").is_none());
    }

    #[test]
    fn cycles_missing_parents_and_choices_are_named() {
        let cyc = "[printer:A]\ninherits = B\n[printer:B]\ninherits = A\n";
        let e = parse(cyc, "c.ini")
            .unwrap()
            .preset(Some("A"), "c.ini", "c")
            .unwrap_err();
        assert!(e.to_string().contains("cycle: A → B → A"), "{e}");
        let missing = "[printer:A]\ninherits = *gone*\n";
        let e = parse(missing, "m.ini")
            .unwrap()
            .preset(None, "m.ini", "m")
            .unwrap_err();
        assert!(
            e.to_string()
                .contains("`A` inherits `*gone*`, which is not in this file"),
            "{e}"
        );
        let e = parse(BUNDLE, "v.ini")
            .unwrap()
            .preset(None, "v.ini", "v")
            .unwrap_err();
        assert!(e.to_string().contains("holds 2 printer presets"), "{e}");
        let e = parse(BUNDLE, "v.ini")
            .unwrap()
            .preset(Some("*fast*"), "v.ini", "v")
            .unwrap_err();
        assert!(e.to_string().contains("abstract"), "{e}");
        assert!(parse("just text\n", "t.ini").is_err());
    }

    #[test]
    fn strings_unescape_as_prusaslicer_writes_them() {
        assert_eq!(
            unescape(r#"M862.3 P \"[printer_model]\"\nG28"#),
            "M862.3 P \"[printer_model]\"\nG28"
        );
        assert_eq!(unescape(r"a\\nb"), "a\\nb");
    }
}
