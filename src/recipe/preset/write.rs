//! An imported preset written as the YAML of a profile file: every key
//! whose value is not a profile's default, each written so it reads back as
//! the same value (a test parses it back), with the import's notes.

use std::fmt::Write as _;

use super::map::Imported;
use crate::recipe::schema::{
    RawBed, RawExtrusion, RawFlavor, RawKinematics, RawPrinter, RawVariable,
};

impl Imported {
    /// The profile as the YAML `p3dp printers import` writes: every key
    /// whose value is not a profile's default, each as it reads back (a
    /// test parses it into the same value), with the import's notes.
    pub fn yaml(&self) -> String {
        let r = &self.raw;
        let d = RawPrinter::new(
            String::new(),
            r.bed,
            r.origin,
            r.nozzle_diameter,
            r.filament_diameter,
        );
        let mut y = String::new();
        let _ = writeln!(
            y,
            "# Imported by `p3dp printers import` from {} ({}).\n# The figures are the preset's own; the start and end G-code is the maker's,\n# in the slicers' macro language, expanded and checked against the machine's\n# limits at every build. Edit freely.",
            comment(&self.file),
            self.format.describe()
        );
        let _ = writeln!(y, "name: {}", q(&r.name));
        if !r.model.is_empty() {
            let _ = writeln!(y, "model: {}", q(&r.model));
        }
        let _ = writeln!(y, "flavor: {}", flavor_name(r.flavor));
        let _ = writeln!(y, "bed: {}", bed_yaml(&r.bed));
        let _ = writeln!(y, "origin: [{}]", r.origin.map(num).join(", "));
        let _ = writeln!(y, "nozzle_diameter: {}", num(r.nozzle_diameter));
        let _ = writeln!(y, "filament_diameter: {}", num(r.filament_diameter));
        if r.extruders != d.extruders {
            let _ = writeln!(y, "# the extruders (or filament slots) the maker's G-code knows; p3dp prints with `tool`\nextruders: {}", r.extruders);
        }
        if r.tool != d.tool {
            let _ = writeln!(y, "tool: {}", r.tool);
        }
        let _ = writeln!(
            y,
            "extrusion: {}",
            match r.extrusion {
                RawExtrusion::Absolute => "absolute",
                RawExtrusion::Relative => "relative",
            }
        );
        if r.retraction != d.retraction {
            let t = &r.retraction;
            let _ = writeln!(
                y,
                "retraction: {{ length: {}, speed: {}, min_travel: {} }}",
                num(t.length),
                num(t.speed),
                num(t.min_travel)
            );
        }
        if r.firmware_retraction {
            let _ = writeln!(y, "firmware_retraction: true");
        }
        if r.max_speed != d.max_speed {
            let _ = writeln!(y, "max_speed: {}", num(r.max_speed));
        }
        if r.max_nozzle_temp != d.max_nozzle_temp {
            let _ = writeln!(
                y,
                "# the hottest the maker's own G-code heats the nozzle (see the notes)\nmax_nozzle_temp: {}",
                num(r.max_nozzle_temp)
            );
        }
        if r.travel_speed != d.travel_speed {
            let _ = writeln!(y, "travel_speed: {}", num(r.travel_speed));
        }
        if r.envelope != d.envelope {
            let e = &r.envelope;
            let mut keys = vec![
                format!("margin: {}", num(e.margin)),
                format!("below_bed: {}", num(e.below_bed)),
            ];
            for (k, v) in [("x", e.x), ("y", e.y)] {
                if let Some([lo, hi]) = v {
                    keys.push(format!("{k}: [{}, {}]", num(lo), num(hi)));
                }
            }
            let _ = writeln!(
                y,
                "# where the maker's G-code takes the head beyond the bed (see the notes)
envelope: {{ {} }}",
                keys.join(", ")
            );
        }
        if r.maker_temperatures {
            let _ = writeln!(y, "# the start G-code is the maker's: its flushes and purges may heat the nozzle\n# to max_nozzle_temp, the print starting within the material's limit\nmaker_temperatures: true");
        }
        if r.emit_limits {
            let _ = writeln!(y, "# the limits below written as M201, M203, M204, M205 before the start G-code\nemit_limits: true");
            if let Some([ax, ay]) = r.axis_acceleration {
                let _ = writeln!(y, "axis_acceleration: [{}, {}]", num(ax), num(ay));
            }
        }
        kinematics_yaml(&mut y, &r.kinematics, &d.kinematics);
        if !r.thumbnails.is_empty() {
            let _ = writeln!(y, "thumbnails: [{}]", r.thumbnails.join(", "));
        }
        if !r.gcode_variables.is_empty() {
            y.push_str("# values the G-code below reads that p3dp does not compute: the preset's own\n# settings, and defaults a slicer would use; change them to suit\ngcode_variables:\n");
            for (name, v) in &r.gcode_variables {
                let _ = writeln!(y, "  {}: {}", key(name), variable_yaml(v));
            }
        }
        block(&mut y, "start_gcode", &r.start_gcode);
        block(&mut y, "end_gcode", &r.end_gcode);
        if !self.notes.is_empty() {
            y.push_str("# Notes from the import:\n");
            for note in &self.notes {
                let _ = writeln!(y, "# - {}", comment(note));
            }
        }
        y
    }
}

fn flavor_name(f: RawFlavor) -> &'static str {
    match f {
        RawFlavor::Marlin => "marlin",
        RawFlavor::Klipper => "klipper",
        RawFlavor::Reprap => "reprap",
        RawFlavor::Prusa => "prusa",
        RawFlavor::Bambu => "bambu",
    }
}

fn bed_yaml(b: &RawBed) -> String {
    match *b {
        RawBed::Rectangle { size, max_z, min } => format!(
            "{{ shape: rectangle, size: [{}, {}], min: [{}, {}], max_z: {} }}",
            num(size[0]),
            num(size[1]),
            num(min[0]),
            num(min[1]),
            num(max_z)
        ),
        RawBed::Circle { diameter, max_z } => format!(
            "{{ shape: circle, diameter: {}, max_z: {} }}",
            num(diameter),
            num(max_z)
        ),
    }
}

/// The `kinematics:` keys that differ from the profile's defaults.
fn kinematics_yaml(y: &mut String, k: &RawKinematics, d: &RawKinematics) {
    let mut out = String::new();
    let mut put = |key: &str, v: Option<f64>, dv: Option<f64>| {
        if let Some(v) = v.filter(|_| v != dv) {
            let _ = writeln!(out, "  {key}: {}", num(v));
        }
    };
    put(
        "max_acceleration",
        Some(k.max_acceleration),
        Some(d.max_acceleration),
    );
    put(
        "travel_acceleration",
        k.travel_acceleration,
        d.travel_acceleration,
    );
    put(
        "retract_acceleration",
        k.retract_acceleration,
        d.retract_acceleration,
    );
    put(
        "junction_deviation",
        k.junction_deviation,
        d.junction_deviation,
    );
    put("jerk", k.jerk, d.jerk);
    put(
        "square_corner_velocity",
        k.square_corner_velocity,
        d.square_corner_velocity,
    );
    put("max_z_speed", k.max_z_speed, d.max_z_speed);
    put(
        "max_z_acceleration",
        k.max_z_acceleration,
        d.max_z_acceleration,
    );
    put(
        "max_extrude_only_velocity",
        k.max_extrude_only_velocity,
        d.max_extrude_only_velocity,
    );
    put(
        "max_extrude_only_accel",
        k.max_extrude_only_accel,
        d.max_extrude_only_accel,
    );
    if !out.is_empty() {
        let _ = writeln!(y, "# the firmware's limits (machine_max_*), for the checks and the time estimate\nkinematics:\n{out}");
    }
}

/// A number as YAML that reads back as the same `f64`: Rust's shortest
/// round-trip form.
fn num(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v}")
    }
}

/// Whether YAML carries `c` as it is (its printable set, less the line
/// breaks and the byte-order mark it treats apart).
fn printable(c: char) -> bool {
    matches!(c, '\t' | '\n' | ' '..='~' | '\u{A0}'..='\u{D7FF}' | '\u{E000}'..='\u{FFFD}' | '\u{10000}'..)
        && !matches!(c, '\u{2028}' | '\u{2029}' | '\u{FEFF}')
}

/// Text for a YAML comment: on one line, every character YAML does not
/// carry written `\u{…}`.
fn comment(s: &str) -> String {
    let one = crate::base::safe_text::one_line(s);
    one.chars()
        .map(|c| {
            if printable(c) && c != '\n' {
                c.to_string()
            } else {
                c.escape_unicode().to_string()
            }
        })
        .collect()
}

/// A string as YAML: double-quoted, every character YAML does not carry
/// as it is escaped (`\n`, `\uXXXX`, `\UXXXXXXXX`), so it reads back the same.
fn q(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if printable(c) => out.push(c),
            c if (c as u32) <= 0xFFFF => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => {
                let _ = write!(out, "\\U{:08X}", c as u32);
            }
        }
    }
    out.push('"');
    out
}

/// A map key as YAML: plain when it is a plain identifier, else quoted.
fn key(s: &str) -> String {
    if !s.is_empty()
        && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !s.starts_with(|c: char| c.is_ascii_digit())
    {
        s.to_string()
    } else {
        q(s)
    }
}

/// A `gcode_variables` value as YAML that reads back as the same variant: a
/// real always with a decimal point or an exponent.
fn variable_yaml(v: &RawVariable) -> String {
    match v {
        RawVariable::Bool(b) => b.to_string(),
        RawVariable::Int(i) => i.to_string(),
        RawVariable::Float(f) => {
            let s = format!("{f:?}");
            if s.contains(['.', 'e', 'E']) {
                s
            } else {
                format!("{s}.0")
            }
        }
        RawVariable::Str(s) => q(s),
        RawVariable::List(l) => format!(
            "[{}]",
            l.iter().map(variable_yaml).collect::<Vec<_>>().join(", ")
        ),
    }
}

/// `key: |2…` a literal block of `text`, every line kept as it is (a text
/// a block cannot carry, a double-quoted string).
fn block(out: &mut String, key: &str, text: &str) {
    if text.is_empty() {
        return;
    }
    if !text.chars().all(printable) {
        let _ = writeln!(out, "{key}: {}", q(text));
        return;
    }
    let trailing = text.len() - text.trim_end_matches('\n').len();
    let chomp = match trailing {
        0 => "-",
        1 => "",
        _ => "+",
    };
    let _ = writeln!(out, "{key}: |2{chomp}");
    for line in text.trim_end_matches('\n').split('\n') {
        if line.is_empty() {
            out.push('\n');
        } else {
            let _ = writeln!(out, "  {line}");
        }
    }
    // `|2+` keeps the line breaks after the last line: one is written above
    for _ in 1..trailing {
        out.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use super::super::Format;
    use super::*;

    #[test]
    fn blocks_keep_every_line() {
        for text in [
            "G28\nG1 X1\n",
            "G28",
            " G28 ; indented\n\n",
            "\tG4\n\nM84\n\n\n",
        ] {
            let mut y = String::new();
            block(&mut y, "start_gcode", text);
            let v: std::collections::BTreeMap<String, String> =
                crate::recipe::yaml::parse_yaml(&y, "p.yaml").unwrap();
            assert_eq!(v["start_gcode"], text, "{y}");
        }
    }

    #[test]
    fn awkward_text_reads_back() {
        for text in [
            "a\u{85}b",
            "x\u{FFFE}\"\\y",
            "G28\r\nG1",
            "\tM84\u{2028}",
            "é\u{1F600}",
            "   lead\n  \n",
        ] {
            let mut raw = RawPrinter::new(
                text.into(),
                RawBed::Circle {
                    diameter: 100.0,
                    max_z: 100.0,
                },
                [0.0; 3],
                0.4,
                1.75,
            );
            raw.start_gcode = text.into();
            raw.model = text.into();
            raw.gcode_variables
                .insert("v".into(), RawVariable::Str(text.into()));
            let i = Imported {
                raw,
                notes: vec![text.into()],
                file: text.into(),
                format: Format::Json,
            };
            let y = i.yaml();
            let back: RawPrinter = crate::recipe::yaml::parse_yaml(&y, "p.yaml")
                .unwrap_or_else(|e| panic!("{text:?}: {e}\n{y}"));
            assert_eq!(back, i.raw, "{y}");
        }
    }
}
