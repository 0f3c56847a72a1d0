//! A slicer preset in p3dp's terms and units: the YAML text of a printer
//! profile (what `p3dp printers import` writes, readable and editable, and
//! what `--printer FILE.ini|FILE.json` loads), or a refusal naming the one
//! thing p3dp cannot do with the preset.
//!
//! What comes across: the bed (`bed_shape`/`printable_area`: a rectangle,
//! offset or not, or a circle on the origin), its height, the nozzle, the
//! filament diameter where the preset has it, the firmware flavour, the
//! machine limits (`machine_max_*`, unless `machine_limits_usage` is
//! `ignore`), the retraction, the thumbnails and their format, the model,
//! and the start and end G-code (kept in the slicers' macro language, every
//! variable one p3dp gives or a `gcode_variables` entry with a default the
//! user sees). Before/after-layer and tool-change hooks are named as
//! ignored: p3dp prints strings, not layers, with one extruder.

use std::fmt::Write as _;

use super::{Format, Preset};
use crate::base::error::{Error, Result};
use crate::base::slicer_macro::Template;

/// A preset made into a profile: its YAML text and what was left out or
/// assumed, one note each.
#[derive(Clone, Debug, PartialEq)]
pub struct Imported {
    /// The profile, YAML.
    pub yaml: String,
    /// What p3dp ignored or assumed, for the user.
    pub notes: Vec<String>,
}

/// Values only a slicer knows that start and end G-code may use, with the
/// default an import writes under `gcode_variables:` (where the user sees
/// and may change it) and why.
pub(crate) const SLICER_DEFAULTS: &[(&str, &str, &str)] = &[
    (
        "print_settings_id",
        "\"\"",
        "the print preset's name: p3dp has none",
    ),
    (
        "print_preset",
        "\"\"",
        "the print preset's name: p3dp has none",
    ),
    (
        "curr_bed_type",
        "\"Textured PEI Plate\"",
        "the Bambu plate on the bed",
    ),
    (
        "scan_first_layer",
        "false",
        "Bambu's first-layer lidar scan",
    ),
    ("timelapse_type", "0", "Bambu's timelapse: none"),
    (
        "print_sequence",
        "\"by object\"",
        "p3dp prints its parts one after another",
    ),
];

/// Hooks p3dp does not run, and why.
const IGNORED: &[(&str, &str)] = &[
    ("before_layer_gcode", "p3dp prints strings, not layers"),
    (
        "before_layer_change_gcode",
        "p3dp prints strings, not layers",
    ),
    ("layer_gcode", "p3dp prints strings, not layers"),
    ("layer_change_gcode", "p3dp prints strings, not layers"),
    ("time_lapse_gcode", "p3dp prints strings, not layers"),
    ("toolchange_gcode", "p3dp drives one extruder"),
    ("change_filament_gcode", "p3dp drives one extruder"),
    ("between_objects_gcode", "p3dp travels between parts itself"),
    (
        "printing_by_object_gcode",
        "p3dp travels between parts itself",
    ),
    ("color_change_gcode", "p3dp has no colour changes"),
    ("pause_print_gcode", "p3dp writes its flavour's own pause"),
    ("machine_pause_gcode", "p3dp writes its flavour's own pause"),
    (
        "template_custom_gcode",
        "p3dp has no custom G-code per layer",
    ),
];

/// Flavours p3dp writes, from the slicers' `gcode_flavor`.
fn flavor(p: &Preset) -> Result<(&'static str, Option<String>)> {
    let given = p.text("gcode_flavor");
    // PrusaSlicer's default is RepRap/Sprinter, a Marlin dialect
    let f = given.clone().unwrap_or_else(|| match p.format {
        Format::Ini => "reprap".into(),
        Format::Json => "marlin".into(),
    });
    let prusa = p
        .text("printer_notes")
        .is_some_and(|n| n.contains("PRINTER_VENDOR_PRUSA3D"))
        || p.text("printer_model")
            .is_some_and(|m| m.starts_with("Prusa ") || m.starts_with("Original Prusa"));
    let marlin = if prusa { "prusa" } else { "marlin" };
    let note = |s: &str| Some(s.to_string());
    Ok(match f.as_str() {
        "marlin" | "marlin2" | "marlinlegacy" => (marlin, None),
        "reprap" | "sprinter" => (
            marlin,
            note("gcode_flavor `reprap` (RepRap/Sprinter) is a Marlin dialect: written as Marlin"),
        ),
        "klipper" => ("klipper", None),
        "reprapfirmware" => ("reprap", None),
        other => {
            return Err(refuse(
                p,
                "gcode_flavor",
                format!("the firmware flavour `{other}`: p3dp writes Marlin, Prusa, Klipper and RepRapFirmware G-code"),
            ))
        }
    })
}

fn refuse(p: &Preset, key: &str, what: String) -> Error {
    Error::input(
        key,
        format!("preset `{}`: p3dp cannot import {what}", p.name),
    )
    .in_file(&p.file)
}

/// The bed: the profile's `bed:` text, the origin (the bed's centre) and
/// the XY extent.
/// The corners of the bed setting `key`, `XxY` each.
fn corners(p: &Preset, key: &str) -> Result<Vec<(f64, f64)>> {
    let mut pts = Vec::new();
    for s in p.list(key).unwrap_or_default() {
        let parsed = s
            .split_once(['x', 'X'])
            .and_then(|(x, y)| Some((x.trim().parse::<f64>().ok()?, y.trim().parse::<f64>().ok()?)))
            .filter(|(x, y)| x.is_finite() && y.is_finite());
        match parsed {
            Some(xy) => pts.push(xy),
            None => {
                return Err(
                    Error::input(key, format!("`{s}` is not a corner; expected XxY"))
                        .in_file(&p.file),
                )
            }
        }
    }
    Ok(pts)
}

fn bed(p: &Preset, max_z: f64) -> Result<(String, [f64; 2])> {
    let Some((key, _)) = p.first_text(&["bed_shape", "printable_area"]) else {
        return Err(refuse(
            p,
            "bed_shape",
            "a preset without a bed (no bed_shape or printable_area)".into(),
        ));
    };
    let pts = corners(p, &key)?;
    let (xs, ys): (Vec<f64>, Vec<f64>) = pts.iter().copied().unzip();
    let (x0, x1) = (
        xs.iter().copied().fold(f64::INFINITY, f64::min),
        xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let (y0, y1) = (
        ys.iter().copied().fold(f64::INFINITY, f64::min),
        ys.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let on = |v: f64, a: f64, b: f64| (v - a).abs() < 1e-6 || (v - b).abs() < 1e-6;
    if pts.len() == 4
        && pts.iter().all(|&(x, y)| on(x, x0, x1) && on(y, y0, y1))
        && x1 > x0
        && y1 > y0
    {
        let text = format!(
            "{{ shape: rectangle, size: [{}, {}], min: [{}, {}], max_z: {} }}",
            n(x1 - x0),
            n(y1 - y0),
            n(x0),
            n(y0),
            n(max_z)
        );
        return Ok((text, [(x0 + x1) / 2.0, (y0 + y1) / 2.0]));
    }
    if pts.len() >= 8 {
        let k = pts.len() as f64;
        let (cx, cy) = (xs.iter().sum::<f64>() / k, ys.iter().sum::<f64>() / k);
        let radii: Vec<f64> = pts.iter().map(|&(x, y)| (x - cx).hypot(y - cy)).collect();
        let r = radii.iter().sum::<f64>() / k;
        let round = r > 0.0 && radii.iter().all(|q| (q - r).abs() <= 0.005 * r);
        if round && cx.hypot(cy) <= 0.01 * r {
            let d = libm::round(2.0 * r * 1000.0) / 1000.0;
            return Ok((
                format!(
                    "{{ shape: circle, diameter: {}, max_z: {} }}",
                    n(d),
                    n(max_z)
                ),
                [0.0, 0.0],
            ));
        }
        if round {
            return Err(refuse(
                p,
                &key,
                "a round bed whose centre is not the origin".into(),
            ));
        }
    }
    Err(refuse(
        p,
        &key,
        format!(
            "a bed of {} corners that is neither a rectangle nor a circle",
            pts.len()
        ),
    ))
}

/// A number as YAML: Rust's shortest form that reads back the same.
fn n(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v}")
    }
}

/// A string as YAML: JSON's quoting, which YAML reads.
fn q(s: &str) -> String {
    serde_json::to_string(s).expect("a string serialises")
}

/// `key: |2…` a literal block of `text`, every line kept as it is.
fn block(out: &mut String, key: &str, text: &str) {
    if text.is_empty() {
        let _ = writeln!(out, "{key}: \"\"");
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

/// The preset as a profile's YAML, or the refusal naming what p3dp cannot do.
pub fn to_yaml(p: &Preset) -> Result<Imported> {
    let mut notes = Vec::new();
    if let Some(t) = p
        .text("printer_technology")
        .filter(|t| !t.eq_ignore_ascii_case("FFF"))
    {
        return Err(refuse(
            p,
            "printer_technology",
            format!("a {t} (resin) printer: p3dp writes G-code for filament printers"),
        ));
    }
    let Some(max_z) = p
        .number("max_print_height")?
        .or(p.number("printable_height")?)
        .filter(|z| *z > 0.0)
    else {
        return Err(refuse(
            p,
            "max_print_height",
            "a preset without a height (max_print_height or printable_height)".into(),
        ));
    };
    let (bed, centre) = bed(p, max_z)?;
    let (flavor, flavor_note) = flavor(p)?;
    notes.extend(flavor_note);
    let mut y = String::new();
    let _ = writeln!(
        y,
        "# Imported by `p3dp printers import` from {} ({}).\n# The figures are the preset's own; the start and end G-code is the maker's,\n# in the slicers' macro language, expanded and checked against the machine's\n# limits at every build. Edit freely.",
        crate::base::safe_text::one_line(&p.file),
        p.format.describe()
    );
    let _ = writeln!(y, "name: {}", q(&p.name));
    if let Some(m) = p.text("printer_model").filter(|m| !m.is_empty()) {
        let _ = writeln!(y, "model: {}", q(&m));
    }
    let _ = writeln!(y, "flavor: {flavor}");
    let _ = writeln!(y, "bed: {bed}");
    let z_offset = p.number("z_offset")?.unwrap_or(0.0);
    let _ = writeln!(
        y,
        "origin: [{}, {}, {}]",
        n(centre[0]),
        n(centre[1]),
        n(z_offset)
    );
    extruder(p, &mut y, &mut notes)?;
    retraction(p, &mut y, &mut notes)?;
    limits(p, flavor, &mut y, &mut notes)?;
    thumbnails(p, &mut y, &mut notes);
    gcode(p, &mut y, &mut notes)?;
    for (key, why) in IGNORED {
        if p.has(key) {
            notes.push(format!("{key} ignored: {why}"));
        }
    }
    if !notes.is_empty() {
        y.push_str("# Notes from the import:\n");
        for note in &notes {
            let _ = writeln!(y, "# - {}", crate::base::safe_text::one_line(note));
        }
    }
    Ok(Imported { yaml: y, notes })
}

/// The nozzle, the filament and the extrusion mode.
fn extruder(p: &Preset, y: &mut String, notes: &mut Vec<String>) -> Result<()> {
    let nozzle = match p.number("nozzle_diameter")? {
        Some(d) => d,
        None => {
            notes.push("no nozzle_diameter in the preset: 0.4 mm, the slicers' default".into());
            0.4
        }
    };
    let _ = writeln!(*y, "nozzle_diameter: {}", n(nozzle));
    let tools = p.list("nozzle_diameter").map_or(1, |l| l.len());
    if tools > 1 {
        notes.push(format!(
            "a printer of {tools} extruders or filament slots (nozzle_diameter lists {tools}): p3dp drives the first; G-code that reads another's values is refused at the build"
        ));
    }
    let filament = match p.number("filament_diameter")? {
        Some(d) => d,
        None => {
            notes.push("no filament_diameter in the preset: 1.75 mm (a recipe's material may say otherwise)".into());
            1.75
        }
    };
    let _ = writeln!(*y, "filament_diameter: {}", n(filament));
    let relative = match p.text("use_relative_e_distances") {
        Some(t) => t == "1" || t.eq_ignore_ascii_case("true"),
        None => p.format == Format::Json,
    };
    let _ = writeln!(
        *y,
        "extrusion: {}",
        if relative { "relative" } else { "absolute" }
    );
    Ok(())
}

fn retraction(p: &Preset, y: &mut String, notes: &mut Vec<String>) -> Result<()> {
    let length = p
        .number("retract_length")?
        .or(p.number("retraction_length")?);
    let speed = p.number("retract_speed")?.or(p.number("retraction_speed")?);
    let travel = p
        .number("retract_before_travel")?
        .or(p.number("retraction_minimum_travel")?);
    let Some(length) = length else {
        notes.push("no retraction in the preset: none".into());
        return Ok(());
    };
    let speed = match speed {
        Some(s) if s > 0.0 => s,
        _ => {
            notes.push("no retraction speed in the preset: 35 mm/s".into());
            35.0
        }
    };
    let mut r = format!(
        "retraction: {{ length: {}, speed: {}",
        n(length.max(0.0)),
        n(speed)
    );
    if let Some(t) = travel {
        let _ = write!(r, ", min_travel: {}", n(t.max(0.0)));
    }
    let _ = writeln!(y, "{r} }}");
    if p.text("use_firmware_retraction").is_some_and(|t| t == "1") {
        let _ = writeln!(y, "firmware_retraction: true");
    }
    if let Some(lift) = p
        .number("retract_lift")?
        .or(p.number("z_hop")?)
        .filter(|l| *l > 0.0)
    {
        notes.push(format!(
            "retract_lift {} mm ignored: p3dp lifts for travel between parts only",
            n(lift)
        ));
    }
    Ok(())
}

/// The machine limits: `max_speed` and `kinematics:`.
fn limits(p: &Preset, flavor: &str, y: &mut String, notes: &mut Vec<String>) -> Result<()> {
    let usage = p.text("machine_limits_usage");
    if usage.as_deref() == Some("ignore") {
        notes.push("machine_limits_usage is `ignore`: p3dp's default limits".into());
        return Ok(());
    }
    if usage.as_deref() == Some("emit_to_gcode") {
        notes.push("machine_limits_usage is `emit_to_gcode`: the limits are p3dp's for its checks and estimate, but p3dp writes no M201–M205; the firmware keeps its own".into());
    }
    // OrcaSlicer and Bambu Studio call the feed rates machine_max_speed_*
    let pos = |key: &str| -> Result<Option<f64>> {
        let alias = match key.strip_prefix("machine_max_feedrate_") {
            Some(axis) => p.number(&format!("machine_max_speed_{axis}"))?,
            None => None,
        };
        Ok(p.number(key)?.or(alias).filter(|v| *v > 0.0))
    };
    let min2 = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    };
    let vmax = min2(
        pos("machine_max_feedrate_x")?,
        pos("machine_max_feedrate_y")?,
    );
    let mut k = String::new();
    let mut put = |key: &str, v: Option<f64>| {
        if let Some(v) = v {
            let _ = writeln!(k, "  {key}: {}", n(v));
        }
    };
    let ceiling = crate::machine::limits::SPEED_MAX;
    if let Some(v) = vmax.filter(|v| *v > ceiling) {
        notes.push(format!(
            "machine_max_feedrate_x/y {} mm/s is past p3dp's ceiling of {} mm/s (mm/min meant?): left out, p3dp's max_speed 300 mm/s",
            n(v),
            n(ceiling)
        ));
    }
    if let Some(v) = vmax.filter(|v| *v <= ceiling) {
        let _ = writeln!(y, "max_speed: {}", n(v));
        let _ = writeln!(y, "travel_speed: {}", n(v.min(120.0)));
    } else {
        notes.push("no machine_max_feedrate_x/y in the preset: p3dp's max_speed 300 mm/s".into());
    }
    put(
        "max_acceleration",
        pos("machine_max_acceleration_extruding")?,
    );
    put(
        "travel_acceleration",
        pos("machine_max_acceleration_travel")?,
    );
    put(
        "retract_acceleration",
        pos("machine_max_acceleration_retracting")?,
    );
    let jerk = min2(pos("machine_max_jerk_x")?, pos("machine_max_jerk_y")?);
    let jd = pos("machine_max_junction_deviation")?;
    if flavor == "klipper" {
        put("square_corner_velocity", Some(jerk.unwrap_or(5.0)));
    } else if jd.is_some() {
        put("junction_deviation", jd);
    } else {
        put("jerk", jerk);
    }
    put("max_z_speed", pos("machine_max_feedrate_z")?);
    put("max_z_acceleration", pos("machine_max_acceleration_z")?);
    put("max_extrude_only_velocity", pos("machine_max_feedrate_e")?);
    put("max_extrude_only_accel", pos("machine_max_acceleration_e")?);
    if !k.is_empty() {
        let _ = writeln!(y, "# the firmware's limits (machine_max_*), for the time estimate; p3dp does not\n# write M201–M205: the firmware keeps its own\nkinematics:\n{k}");
    }
    Ok(())
}

fn thumbnails(p: &Preset, y: &mut String, notes: &mut Vec<String>) {
    let Some(list) = p.list("thumbnails") else {
        return;
    };
    let default = p.text("thumbnails_format").unwrap_or_else(|| "PNG".into());
    let mut out = Vec::new();
    for entry in list.iter().map(|s| s.trim()).filter(|s| !s.is_empty()) {
        let (size, fmt) = entry.split_once('/').unwrap_or((entry, default.as_str()));
        let fmt = match fmt.trim().to_ascii_uppercase().as_str() {
            "PNG" => "PNG",
            "JPG" | "JPEG" => "JPG",
            "QOI" => "QOI",
            other => {
                notes.push(format!("thumbnail {entry} left out: p3dp writes PNG, JPG and QOI thumbnails, not {other}"));
                continue;
            }
        };
        if crate::machine::Size::parse(size.trim(), "thumbnails").is_err() {
            notes.push(format!("thumbnail `{entry}` left out: not a size"));
            continue;
        }
        out.push(format!("{}/{fmt}", size.trim()));
    }
    if !out.is_empty() {
        let _ = writeln!(y, "thumbnails: [{}]", out.join(", "));
    }
}

/// The start and end G-code, their variables checked: each one p3dp gives,
/// or a slicer's value with a default under `gcode_variables:`, or refused.
fn gcode(p: &Preset, y: &mut String, notes: &mut Vec<String>) -> Result<()> {
    let mut defaults: Vec<(&str, &str, &str)> = Vec::new();
    let mut texts = Vec::new();
    for (key, names) in [
        ("start_gcode", ["start_gcode", "machine_start_gcode"]),
        ("end_gcode", ["end_gcode", "machine_end_gcode"]),
    ] {
        let Some((from, text)) = p.first_text(&names) else {
            notes.push(format!("no {key} in the preset"));
            texts.push((key, String::new()));
            continue;
        };
        let text = text.replace("\r\n", "\n");
        let t = Template::parse(&text).map_err(|e| {
            Error::input(
                format!("{from} line {}", e.line),
                format!("preset `{}`: {}", p.name, e.message),
            )
            .in_file(&p.file)
        })?;
        for (name, line) in t.variables() {
            if known(&name) || defaults.iter().any(|d| d.0 == name) {
                continue;
            }
            match SLICER_DEFAULTS.iter().find(|d| d.0 == name) {
                Some(d) => defaults.push(*d),
                None => {
                    return Err(Error::input(
                        format!("{from} line {line}"),
                        format!(
                            "preset `{}`: the variable `{name}` is one p3dp cannot give (its value is a slicer's)",
                            p.name
                        ),
                    )
                    .in_file(&p.file))
                }
            }
        }
        texts.push((key, text));
    }
    if !defaults.is_empty() {
        y.push_str("# values only a slicer knows, used by the G-code below: change them to suit\ngcode_variables:\n");
        for (name, value, why) in &defaults {
            let _ = writeln!(y, "  {name}: {value} # {why}");
            notes.push(format!("gcode_variables.{name} = {value}: {why}"));
        }
    }
    for (key, text) in texts {
        block(y, key, &text);
    }
    Ok(())
}

/// Whether p3dp gives variable `name` (itself, or `name_N` of a list).
fn known(name: &str) -> bool {
    let listed = |n: &str| crate::machine::VARIABLES.iter().any(|(v, _)| *v == n);
    listed(name)
        || name
            .rsplit_once('_')
            .is_some_and(|(b, i)| i.parse::<usize>().is_ok() && listed(b))
}

#[cfg(test)]
mod tests {
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
}
