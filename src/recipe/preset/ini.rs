//! PrusaSlicer-family `.ini` presets (PrusaSlicer, SuperSlicer, Slic3r): a
//! vendor or user bundle of `[printer:NAME]` and `[filament:NAME]` sections
//! (`inherits = a; b` resolved inside the bundle, the parents applied left
//! to right and the section's own keys last; abstract `*name*` sections are
//! bases only), or an exported config, one preset of `key = value` lines
//! with no section. Every section a preset's chain reaches is resolved once,
//! however often the chain meets it (a diamond of inherits stays linear).

use std::collections::{BTreeMap, HashMap};
use std::rc::Rc;

use super::{Format, Kind, Preset, Setting};
use crate::base::error::{Error, Result};

/// Deepest chain of `inherits` followed.
const MAX_DEPTH: usize = 32;

/// One `[kind:NAME]` section: its kind, name and own keys.
struct Section {
    kind: Kind,
    name: String,
    keys: BTreeMap<String, String>,
}

/// A parsed `.ini` file: its printer and filament sections in order, or its
/// one preset.
pub(crate) struct Ini {
    /// `[printer:NAME]` and `[filament:NAME]` sections, in the file's order.
    sections: Vec<Section>,
    /// Each section's place by kind and name (the first of a name).
    index: HashMap<(Kind, String), usize>,
    /// The keys before any section (an exported config's whole).
    pub(crate) top: BTreeMap<String, String>,
    /// Whether the file has sections at all.
    pub(crate) sectioned: bool,
}

/// Parses `text` (`file` names it in errors): sections, `key = value`
/// lines, `#` and `;` comment lines.
pub(crate) fn parse(text: &str, file: &str) -> Result<Ini> {
    let mut ini = Ini {
        sections: Vec::new(),
        index: HashMap::new(),
        top: BTreeMap::new(),
        sectioned: false,
    };
    // where `key = value` lines go: the top, a section, or nowhere
    // (another kind of section)
    enum Into {
        Top,
        Section(usize),
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
            let kind = match head.split_once(':') {
                Some(("printer", name)) => Some((Kind::Printer, name)),
                Some(("filament", name)) => Some((Kind::Filament, name)),
                _ => None,
            };
            into = match kind {
                Some((kind, name)) => {
                    let name = name.trim().to_string();
                    let at = ini.sections.len();
                    ini.index.entry((kind, name.clone())).or_insert(at);
                    ini.sections.push(Section {
                        kind,
                        name,
                        keys: BTreeMap::new(),
                    });
                    Into::Section(at)
                }
                None => Into::Skip,
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
            Into::Section(i) => {
                ini.sections[i].keys.insert(key, value);
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

/// The presets resolved so far in one load, by name.
type Resolved = HashMap<String, Rc<BTreeMap<String, String>>>;

impl Ini {
    /// The presets of `kind` a user may pick: every section but the
    /// abstract `*name*` ones (an exported config: its one preset).
    pub(crate) fn names(&self, kind: Kind, stem: &str) -> Vec<String> {
        if !self.sectioned {
            return vec![self.single_name(kind, stem)];
        }
        self.sections
            .iter()
            .filter(|s| s.kind == kind && !is_abstract(&s.name))
            .map(|s| s.name.clone())
            .collect()
    }

    /// An exported config's name: its `printer_settings_id` (or
    /// `filament_settings_id`), or the file's.
    fn single_name(&self, kind: Kind, stem: &str) -> String {
        let id = match kind {
            Kind::Printer => "printer_settings_id",
            Kind::Filament => "filament_settings_id",
        };
        match self.top.get(id) {
            Some(id) if !id.is_empty() => id.clone(),
            _ => stem.to_string(),
        }
    }

    /// The preset of `kind` named `name` (or the only one) with its
    /// `inherits` resolved.
    pub(crate) fn preset(
        &self,
        kind: Kind,
        name: Option<&str>,
        file: &str,
        stem: &str,
    ) -> Result<Preset> {
        if !self.sectioned {
            if self.top.is_empty() {
                return Err(Error::input(
                    "",
                    format!(
                        "holds no settings; expected a slicer's {} preset",
                        kind.word()
                    ),
                )
                .in_file(file));
            }
            return Ok(preset(self.single_name(kind, stem), kind, &self.top, file));
        }
        let name = self.pick(kind, name, file, stem)?;
        if is_abstract(&name) && self.index.contains_key(&(kind, name.clone())) {
            return Err(Error::input(
                kind.option(),
                format!("`{name}` is an abstract preset, a base for others; pick one of those"),
            )
            .in_file(file));
        }
        let mut chain = Vec::new();
        let mut done = Resolved::new();
        let values = self.resolve(kind, &name, &mut chain, &mut done, file)?;
        Ok(preset(name, kind, &values, file))
    }

    /// The name asked, or the bundle's only preset of `kind`.
    fn pick(&self, kind: Kind, name: Option<&str>, file: &str, stem: &str) -> Result<String> {
        let names = self.names(kind, stem);
        match name {
            Some(n) => Ok(n.to_string()),
            None if names.len() == 1 => Ok(names[0].clone()),
            None if names.is_empty() => Err(Error::input(
                "",
                format!(
                    "holds no {w} preset (no `[{w}:NAME]` section)",
                    w = kind.word()
                ),
            )
            .in_file(file)),
            None => Err(Error::input(
                "",
                format!(
                    "holds {} {} presets; pick one with {} NAME (`p3dp printers list {file}{}` lists them)",
                    names.len(),
                    kind.word(),
                    kind.option(),
                    if kind == Kind::Filament { " --filaments" } else { "" }
                ),
            )
            .in_file(file)),
        }
    }

    /// The keys of `name` over those of its parents; `chain` holds the
    /// presets being resolved (a cycle is an error naming them), `done`
    /// those resolved already in this load (each section resolved once).
    fn resolve(
        &self,
        kind: Kind,
        name: &str,
        chain: &mut Vec<String>,
        done: &mut Resolved,
        file: &str,
    ) -> Result<Rc<BTreeMap<String, String>>> {
        if let Some(v) = done.get(name) {
            return Ok(Rc::clone(v));
        }
        let Some(&at) = self.index.get(&(kind, name.to_string())) else {
            let msg = match chain.last() {
                Some(child) => format!("`{child}` inherits `{name}`, which is not in this file"),
                None => super::no_such(kind, name, &self.names(kind, ""), file),
            };
            return Err(Error::input("inherits", msg).in_file(file));
        };
        let own = &self.sections[at].keys;
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
                let p = self.resolve(kind, parent, chain, done, file)?;
                out.extend(p.iter().map(|(k, v)| (k.clone(), v.clone())));
            }
        }
        chain.pop();
        out.extend(
            own.iter()
                .filter(|(k, _)| *k != "inherits")
                .map(|(k, v)| (k.clone(), v.clone())),
        );
        let out = Rc::new(out);
        done.insert(name.to_string(), Rc::clone(&out));
        Ok(out)
    }
}

fn is_abstract(name: &str) -> bool {
    name.len() >= 2 && name.starts_with('*') && name.ends_with('*')
}

fn preset(name: String, kind: Kind, values: &BTreeMap<String, String>, file: &str) -> Preset {
    Preset {
        name,
        file: file.to_string(),
        format: Format::Ini,
        kind,
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

    const BUNDLE: &str = "# a bundle\n[vendor]\nname = V\n[printer:*common*]\nbed_shape = 0x0,200x0,200x200,0x200\nretract_length = 1\n[printer:*fast*]\nmachine_max_feedrate_x = 300\nretract_length = 2\n[printer:A]\ninherits = *common*; *fast*\nprinter_model = A1\n[printer:B]\ninherits = A\nretract_length = 3\n[print:x]\nlayer_height = 0.2\n[filament:*PLA*]\nfilament_type = PLA\ntemperature = 210\n[filament:Fil]\ninherits = *PLA*\ntemperature = 215\n";

    fn printer(text: &str, name: Option<&str>) -> Result<Preset> {
        parse(text, "v.ini")?.preset(Kind::Printer, name, "v.ini", "v")
    }

    #[test]
    fn inherits_left_to_right_then_own() {
        let ini = parse(BUNDLE, "v.ini").unwrap();
        assert_eq!(ini.names(Kind::Printer, "v"), ["A", "B"]);
        assert_eq!(ini.names(Kind::Filament, "v"), ["Fil"]);
        let a = printer(BUNDLE, Some("A")).unwrap();
        assert_eq!(a.text("retract_length").as_deref(), Some("2"));
        assert_eq!(
            a.text("bed_shape").as_deref(),
            Some("0x0,200x0,200x200,0x200")
        );
        let b = printer(BUNDLE, Some("B")).unwrap();
        assert_eq!(b.text("retract_length").as_deref(), Some("3"));
        assert_eq!(b.text("printer_model").as_deref(), Some("A1"));
        assert!(b.text("layer_height").is_none());
        assert!(b.text("temperature").is_none());
        let f = ini.preset(Kind::Filament, None, "v.ini", "v").unwrap();
        assert_eq!(f.kind, Kind::Filament);
        assert_eq!(f.text("temperature").as_deref(), Some("215"));
        assert_eq!(f.text("filament_type").as_deref(), Some("PLA"));
    }

    #[test]
    fn cycles_missing_parents_and_choices_are_named() {
        let cyc = "[printer:A]\ninherits = B\n[printer:B]\ninherits = A\n";
        let e = printer(cyc, Some("A")).unwrap_err();
        assert!(e.to_string().contains("cycle: A → B → A"), "{e}");
        let missing = "[printer:A]\ninherits = *gone*\n";
        let e = printer(missing, None).unwrap_err();
        assert!(
            e.to_string()
                .contains("`A` inherits `*gone*`, which is not in this file"),
            "{e}"
        );
        let e = printer(BUNDLE, None).unwrap_err();
        assert!(e.to_string().contains("holds 2 printer presets"), "{e}");
        let e = printer(BUNDLE, Some("*fast*")).unwrap_err();
        assert!(e.to_string().contains("abstract"), "{e}");
        assert!(parse("just text\n", "t.ini").is_err());
    }

    /// Thirty levels of presets each inheriting the two of the level below
    /// (a diamond chain): each section is resolved once, so the preset
    /// resolves at once where a walk of every path takes 2³⁰ steps.
    #[test]
    fn a_diamond_of_inherits_resolves_each_section_once() {
        let mut text = String::from(
            "[printer:L0a]\nbed_shape = 0x0,1x0,1x1,0x1\n[printer:L0b]\nretract_length = 1\n",
        );
        for k in 1..=30 {
            for side in ["a", "b"] {
                text.push_str(&format!(
                    "[printer:L{k}{side}]\ninherits = L{j}a; L{j}b\nkey_{k}{side} = {k}\n",
                    j = k - 1
                ));
            }
        }
        let t = std::time::Instant::now();
        let p = printer(&text, Some("L30a")).unwrap();
        assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
        assert_eq!(p.text("key_1b").as_deref(), Some("1"));
        assert_eq!(p.text("retract_length").as_deref(), Some("1"));
        assert_eq!(p.values.len(), 2 + 59);
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
