//! A slicer's printer preset in p3dp's terms and units: the profile's own
//! raw type ([`RawPrinter`], what a profile's YAML parses into), built
//! directly — `--printer FILE.ini|FILE.json` loads it as a profile file is
//! loaded, and `p3dp printers import` writes it as readable YAML
//! ([`Imported::yaml`], which parses back into the same value) — or a
//! refusal naming the one thing p3dp cannot do with the preset.
//!
//! What comes across: the bed (`bed_shape`/`printable_area`: a rectangle,
//! offset or not, or a circle on the origin), its height, the nozzle, the
//! filament diameter where the preset has it, the extruders (a multi-tool
//! machine prints with its first), the firmware flavour, the machine limits
//! (`machine_max_*`, unless `machine_limits_usage` is `ignore`), the
//! retraction, the thumbnails and their format, the model, and the start
//! and end G-code, kept in the slicers' macro language. Every variable the
//! G-code reads has a value with a stated source: p3dp's own (the profile,
//! the print, the material: `crate::machine::VARIABLES` and
//! `crate::machine::material::VARIABLES`), the preset's own setting of that
//! name, or a default a slicer would use that the YAML shows under
//! `gcode_variables:` — or a filament preset's (named at the build with
//! `--filament`); any other is refused by name. Before/after-layer and
//! tool-change hooks are named as ignored: p3dp prints strings, not layers,
//! with one tool.

use indexmap::IndexMap;

use super::{refuse, Format, Kind, Preset};
use crate::base::error::{Error, Result};
use crate::base::slicer_macro::Template;
use crate::machine::limits::NOZZLE_TEMP_MAX;
use crate::recipe::schema::{
    RawBed, RawExtrusion, RawFlavor, RawKinematics, RawPrinter, RawRetraction, RawVariable,
};

/// A preset made into a profile: its raw form and what was left out or
/// assumed, one note each.
#[derive(Clone, Debug, PartialEq)]
pub struct Imported {
    /// The profile, as a profile file's YAML parses into.
    pub(crate) raw: RawPrinter,
    /// What p3dp ignored or assumed, for the user.
    pub(crate) notes: Vec<String>,
    /// The preset file, as the user named it.
    pub(crate) file: String,
    /// The preset file's family.
    pub(crate) format: Format,
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
    ("plate_name", "\"\"", "Bambu's plate name: none given"),
    (
        "standby_temperature_delta",
        "-5",
        "PrusaSlicer's default; p3dp never parks a tool",
    ),
    (
        "spiral_mode",
        "false",
        "no slicer's spiral-vase mode: p3dp prints its strings as written",
    ),
    ("wipe_tower", "false", "p3dp prints no wipe tower"),
    (
        "long_retraction_when_cut",
        "false",
        "Bambu's long retraction when the filament is cut: none, p3dp cuts no filament",
    ),
    (
        "retraction_distance_when_cut",
        "0",
        "the same: no retraction at a cut, mm",
    ),
    (
        "long_retraction_when_ec",
        "false",
        "Bambu's long retraction at an extruder change: none, p3dp changes no extruder",
    ),
    (
        "retraction_distance_when_ec",
        "0",
        "the same: no retraction at an extruder change, mm",
    ),
    (
        "wipe_tower_center_pos_valid",
        "false",
        "p3dp prints no wipe tower",
    ),
    ("wipe_tower_center_pos_x", "0", "p3dp prints no wipe tower"),
    ("wipe_tower_center_pos_y", "0", "p3dp prints no wipe tower"),
    (
        "hold_chamber_temp_for_flat_print",
        "false",
        "Bambu Studio's print option: the chamber is not held warm for a flat print",
    ),
    (
        "nozzle_high_flow",
        "[false]",
        "PrusaSlicer's default: a standard-flow nozzle (one value per extruder)",
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
    ("toolchange_gcode", "p3dp prints with one tool"),
    ("change_filament_gcode", "p3dp prints with one tool"),
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
    (
        "wrapping_detection_gcode",
        "p3dp prints strings, not layers",
    ),
];

/// Most extruders (or filament slots) a preset may list.
const MAX_EXTRUDERS: usize = 16;

/// Flavours p3dp writes, from the slicers' `gcode_flavor`.
fn flavor(p: &Preset) -> Result<(RawFlavor, Option<String>)> {
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
            .is_some_and(|m| m.starts_with("Prusa ") || m.starts_with("Original Prusa"))
        // Prusa's firmware alone checks the printer's model (the newest
        // bundle's MK4IS, CORE One notes no longer name the vendor)
        || p.first_text(&["start_gcode", "machine_start_gcode"])
            .is_some_and(|(_, g)| g.contains("M862.3 P"));
    // Bambu Lab's printers run Bambu's own Marlin-like firmware (its
    // presets say `marlin`): their own commands are read as it reads them
    let bambu = p
        .text("printer_model")
        .is_some_and(|m| m.starts_with("Bambu Lab"));
    let marlin = if prusa {
        RawFlavor::Prusa
    } else if bambu {
        RawFlavor::Bambu
    } else {
        RawFlavor::Marlin
    };
    let note = |s: &str| Some(s.to_string());
    Ok(match f.as_str() {
        "marlin" | "marlin2" | "marlinlegacy" => (marlin, None),
        "reprap" | "sprinter" => (
            marlin,
            note("gcode_flavor `reprap` (RepRap/Sprinter) is a Marlin dialect: written as Marlin"),
        ),
        "klipper" => (RawFlavor::Klipper, None),
        "reprapfirmware" => (RawFlavor::Reprap, None),
        other => {
            return Err(refuse(
                p,
                "gcode_flavor",
                format!("the firmware flavour `{other}`: p3dp writes Marlin, Prusa, Klipper and RepRapFirmware G-code"),
            ))
        }
    })
}

/// The preset as a profile, or the refusal naming what p3dp cannot do.
pub fn import(p: &Preset) -> Result<Imported> {
    if p.kind != Kind::Printer {
        return Err(Error::input(
            "",
            format!(
                "preset `{}` is a filament preset; expected a printer preset",
                p.name
            ),
        )
        .in_file(&p.file));
    }
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
        .first_number(&["max_print_height", "printable_height"])?
        .filter(|z| *z > 0.0)
    else {
        return Err(refuse(
            p,
            "max_print_height",
            "a preset without a height (max_print_height or printable_height)".into(),
        ));
    };
    let (bed, centre) = super::bed::bed(p, max_z, &mut notes)?;
    let (flavor, flavor_note) = flavor(p)?;
    notes.extend(flavor_note);
    let z_offset = p.number("z_offset")?.unwrap_or(0.0);
    let (nozzle, filament, extrusion, extruders) = extruder(p, &mut notes)?;
    let mut raw = RawPrinter::new(
        p.name.clone(),
        bed,
        [centre[0], centre[1], z_offset],
        nozzle,
        filament,
    );
    raw.model = p.text("printer_model").unwrap_or_default();
    raw.flavor = flavor;
    raw.extrusion = extrusion;
    raw.extruders = extruders as u32;
    raw.tool = main_extruder(p, extruders, &mut notes)? as u32;
    retraction(p, &mut raw, &mut notes)?;
    limits(p, &mut raw, &mut notes)?;
    raw.thumbnails = thumbnails(p, &mut notes);
    gcode(p, &mut raw, extruders, &mut notes)?;
    // the start G-code is the maker's: its flushes and purges may be hotter
    // than the print (docs/checks.md)
    raw.maker_temperatures = true;
    reach(&mut raw, &mut notes);
    hot_end(&mut raw, &mut notes);
    for (key, why) in IGNORED {
        if p.has(key) {
            notes.push(format!("{key} ignored: {why}"));
        }
    }
    Ok(Imported {
        raw,
        notes,
        file: p.file.clone(),
        format: p.format,
    })
}

/// The head's reach beyond a rectangular bed, from the maker's own moves
/// ([`super::reach`]).
fn reach(raw: &mut RawPrinter, notes: &mut Vec<String>) {
    if let RawBed::Rectangle { size, min, .. } = raw.bed {
        let max = [min[0] + size[0], min[1] + size[1]];
        let texts = [
            ("start_gcode", raw.start_gcode.as_str()),
            ("end_gcode", raw.end_gcode.as_str()),
        ];
        let flavor = raw.flavor.flavor();
        let r = super::reach::reach(&texts, min, max, raw.envelope.margin, flavor);
        [raw.envelope.x, raw.envelope.y] = r.xy;
        if let Some(d) = r.below {
            raw.envelope.below_bed = d;
        }
        notes.extend(r.notes);
    }
}

/// The printer's `max_nozzle_temp`, which no slicer's printer preset
/// gives: raised from p3dp's default to the hottest literal nozzle
/// temperature (`M104`/`M109 S`) of the maker's own start and end G-code,
/// the maker's statement of what its hot end takes (Bambu's X1E flushes at
/// `M109 S290`), at most [`NOZZLE_TEMP_MAX`] (a hotter one the build names).
fn hot_end(raw: &mut RawPrinter, notes: &mut Vec<String>) {
    let mut hottest: Option<(f64, String)> = None;
    for (key, text) in [
        ("start_gcode", &raw.start_gcode),
        ("end_gcode", &raw.end_gcode),
    ] {
        for (n, line) in text.split('\n').enumerate() {
            let code = line.split(';').next().unwrap_or("").trim();
            let mut words = code.split_ascii_whitespace();
            let first = words.next().map(str::to_ascii_uppercase);
            if !matches!(first.as_deref(), Some("M104" | "M109")) {
                continue;
            }
            for w in words {
                let Some(v) = w
                    .strip_prefix(['S', 's'])
                    .and_then(|v| v.parse::<f64>().ok())
                else {
                    continue;
                };
                let hotter = hottest.as_ref().is_none_or(|(t, _)| v > *t);
                if v.is_finite() && v <= NOZZLE_TEMP_MAX && hotter {
                    hottest = Some((v, format!("{key} line {}: `{code}`", n + 1)));
                }
            }
        }
    }
    if let Some((t, at)) = hottest.filter(|(t, _)| *t > raw.max_nozzle_temp) {
        raw.max_nozzle_temp = t;
        notes.push(format!(
            "max_nozzle_temp {t}: the hottest the maker's own G-code heats the nozzle ({at}); the preset names no limit"
        ));
    }
}

/// The nozzle, the filament, the extrusion mode and the number of
/// extruders (or filament slots) the per-extruder settings list.
fn extruder(p: &Preset, notes: &mut Vec<String>) -> Result<(f64, f64, RawExtrusion, usize)> {
    let nozzle = match p.number("nozzle_diameter")? {
        Some(d) => d,
        None => {
            notes.push("no nozzle_diameter in the preset: 0.4 mm, the slicers' default".into());
            0.4
        }
    };
    let extruders = p.list("nozzle_diameter").map_or(1, |l| l.len().max(1));
    if extruders > MAX_EXTRUDERS {
        return Err(refuse(
            p,
            "nozzle_diameter",
            format!("a printer of {extruders} extruders (at most {MAX_EXTRUDERS})"),
        ));
    }
    let filament = match p.number("filament_diameter")? {
        Some(d) => d,
        None => {
            notes.push("no filament_diameter in the preset: 1.75 mm (a recipe's material or --filament may say otherwise)".into());
            1.75
        }
    };
    let relative = match p.text("use_relative_e_distances") {
        Some(t) => t == "1" || t.eq_ignore_ascii_case("true"),
        None => p.format == Format::Json,
    };
    let extrusion = if relative {
        RawExtrusion::Relative
    } else {
        RawExtrusion::Absolute
    };
    Ok((nozzle, filament, extrusion, extruders))
}

/// The extruder p3dp prints with: Bambu Studio's `master_extruder_id`
/// (1-based; the H2D's right-hand nozzle, its T0), else the first.
fn main_extruder(p: &Preset, extruders: usize, notes: &mut Vec<String>) -> Result<usize> {
    let Some(m) = p.number("master_extruder_id")? else {
        if extruders > 1 {
            notes.push(format!(
                "a printer of {extruders} extruders or filament slots (nozzle_diameter lists {extruders}): p3dp prints with the first, the tool its start G-code selects (initial_tool 0)"
            ));
        }
        return Ok(0);
    };
    if m < 1.0 || m > extruders as f64 || m.fract() != 0.0 {
        return Err(refuse(
            p,
            "master_extruder_id",
            format!("a main extruder {m} of {extruders}"),
        ));
    }
    if extruders > 1 {
        notes.push(format!(
            "a printer of {extruders} extruders (nozzle_diameter lists {extruders}): p3dp prints with extruder {m}, the main one (master_extruder_id), its one filament the first (initial_tool 0, filament_map [{m}])"
        ));
    }
    Ok(m as usize - 1)
}

fn retraction(p: &Preset, raw: &mut RawPrinter, notes: &mut Vec<String>) -> Result<()> {
    let length = p.first_number(&["retract_length", "retraction_length"])?;
    let speed = p.first_number(&["retract_speed", "retraction_speed"])?;
    let travel = p.first_number(&["retract_before_travel", "retraction_minimum_travel"])?;
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
    let mut r = RawRetraction {
        length: length.max(0.0),
        speed,
        ..RawRetraction::default()
    };
    if let Some(t) = travel {
        r.min_travel = t.max(0.0);
    }
    raw.retraction = r;
    raw.firmware_retraction = p.text("use_firmware_retraction").is_some_and(|t| t == "1");
    if let Some(lift) = p
        .first_number(&["retract_lift", "z_hop"])?
        .filter(|l| *l > 0.0)
    {
        notes.push(format!(
            "retract_lift {} mm ignored: p3dp lifts for travel between parts only",
            n(lift)
        ));
    }
    Ok(())
}

/// A number in a note: Rust's shortest form that reads back the same.
fn n(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v}")
    }
}

/// The machine limits: `max_speed`, `travel_speed` and `kinematics:`; a
/// figure past what a machine can be is left out with a note (p3dp's
/// default stands), never made into a value the profile would refuse.
fn limits(p: &Preset, raw: &mut RawPrinter, notes: &mut Vec<String>) -> Result<()> {
    use crate::machine::limits::{ACCELERATION_MAX, SPEED_MAX};
    let usage = p.text("machine_limits_usage");
    if usage.as_deref() == Some("ignore") {
        notes.push("machine_limits_usage is `ignore`: p3dp's default limits".into());
        return Ok(());
    }
    emitted(p, usage.as_deref(), raw, notes)?;
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
    match bounded(notes, "machine_max_feedrate_x/y", vmax, SPEED_MAX, "mm/s") {
        Some(v) => {
            raw.max_speed = v;
            raw.travel_speed = v.min(120.0);
        }
        None => notes
            .push("no machine_max_feedrate_x/y in the preset: p3dp's max_speed 300 mm/s".into()),
    }
    let mut k = RawKinematics::default();
    let mut accel = |key: &str| -> Result<Option<f64>> {
        Ok(bounded(notes, key, pos(key)?, ACCELERATION_MAX, "mm/s²"))
    };
    if let Some(a) = accel("machine_max_acceleration_extruding")? {
        k.max_acceleration = a;
    }
    k.travel_acceleration = accel("machine_max_acceleration_travel")?;
    k.retract_acceleration = accel("machine_max_acceleration_retracting")?;
    let jerk = bounded(
        notes,
        "machine_max_jerk_x/y",
        min2(pos("machine_max_jerk_x")?, pos("machine_max_jerk_y")?),
        SPEED_MAX,
        "mm/s",
    );
    let jd = pos("machine_max_junction_deviation")?;
    if raw.flavor == RawFlavor::Klipper {
        // Klipper's square_corner_velocity is the slicers' jerk; its own
        // default is 5 mm/s
        k.square_corner_velocity = Some(jerk.unwrap_or(5.0));
    } else if jd.is_some() {
        k.junction_deviation = jd;
    } else {
        k.jerk = jerk;
    }
    k.max_z_speed = pos("machine_max_feedrate_z")?;
    k.max_z_acceleration = pos("machine_max_acceleration_z")?;
    k.max_extrude_only_velocity = pos("machine_max_feedrate_e")?;
    k.max_extrude_only_accel = pos("machine_max_acceleration_e")?;
    raw.kinematics = k;
    Ok(())
}

/// PrusaSlicer's `emit_to_gcode`, OrcaSlicer's flag (its default, on, is
/// taken only where the preset says it): the limits written as `M201`–`M205`
/// before the start G-code, on Marlin and RepRapFirmware as the slicers
/// write them, with the preset's per-axis X and Y accelerations.
fn emitted(
    p: &Preset,
    usage: Option<&str>,
    raw: &mut RawPrinter,
    notes: &mut Vec<String>,
) -> Result<()> {
    use crate::machine::limits::ACCELERATION_MAX;
    let orca = p
        .text("emit_machine_limits_to_gcode")
        .is_some_and(|t| t == "1" || t.eq_ignore_ascii_case("true"));
    if usage == Some("emit_to_gcode") || orca {
        let key = if orca {
            "emit_machine_limits_to_gcode"
        } else {
            "machine_limits_usage = emit_to_gcode"
        };
        if matches!(
            raw.flavor,
            RawFlavor::Marlin | RawFlavor::Prusa | RawFlavor::Reprap
        ) {
            raw.emit_limits = true;
            let mut a = |axis: &str| -> Result<Option<f64>> {
                let key = format!("machine_max_acceleration_{axis}");
                Ok(bounded(
                    notes,
                    &key,
                    p.number(&key)?.filter(|v| *v > 0.0),
                    ACCELERATION_MAX,
                    "mm/s²",
                ))
            };
            if let (Some(x), Some(y)) = (a("x")?, a("y")?) {
                raw.axis_acceleration = Some([x, y]);
            }
            notes.push(format!("{key}: the limits below are written as M201, M203, M204 and M205 before the start G-code (emit_limits), and the estimate follows them"));
        } else {
            notes.push(format!(
                "{key}: the slicers write no limits for this firmware, nor does p3dp"
            ));
        }
    }
    Ok(())
}

/// `v`, or `None` with a note when it is past `max` (p3dp's default stands).
fn bounded(
    notes: &mut Vec<String>,
    key: &str,
    v: Option<f64>,
    max: f64,
    unit: &str,
) -> Option<f64> {
    match v {
        Some(v) if v > max => {
            notes.push(format!(
                "{key} {} {unit} is past p3dp's ceiling of {} {unit}: left out, p3dp's default stands",
                n(v),
                n(max)
            ));
            None
        }
        v => v,
    }
}

fn thumbnails(p: &Preset, notes: &mut Vec<String>) -> Vec<String> {
    let Some(list) = p.list("thumbnails") else {
        return Vec::new();
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
    out
}

/// Where a template variable's value comes from at the build.
enum Origin {
    /// p3dp gives it (the profile, the print, the material).
    Own,
    /// A filament preset gives it (`--filament`), else the build refuses it.
    Filament,
    /// The preset's own setting of that name.
    Preset(RawVariable),
    /// A slicer's default, shown under `gcode_variables:`.
    Default(&'static (&'static str, &'static str, &'static str)),
}

/// Where the value of `name` comes from, or `None` when nothing gives it.
fn origin(p: &Preset, name: &str, extruders: usize) -> Option<Origin> {
    if crate::machine::printer::gives(name) {
        return Some(Origin::Own);
    }
    if let Some(v) = p.values.get(name).and_then(|_| typed(p, name, extruders)) {
        return Some(Origin::Preset(v));
    }
    if let Some(d) = SLICER_DEFAULTS.iter().find(|d| d.0 == name) {
        return Some(Origin::Default(d));
    }
    if crate::machine::material::from_filament_preset(name) {
        return Some(Origin::Filament);
    }
    None
}

/// The start and end G-code, their variables checked: each one p3dp gives,
/// the preset's own setting or a slicer's default (both under
/// `gcode_variables:`), a filament preset's, or refused naming it.
fn gcode(
    p: &Preset,
    raw: &mut RawPrinter,
    extruders: usize,
    notes: &mut Vec<String>,
) -> Result<()> {
    let mut vars: IndexMap<String, RawVariable> = IndexMap::new();
    let mut filament: Vec<String> = Vec::new();
    for (key, names) in [
        ("start_gcode", ["start_gcode", "machine_start_gcode"]),
        ("end_gcode", ["end_gcode", "machine_end_gcode"]),
    ] {
        let Some((from, text)) = p.first_text(&names) else {
            notes.push(format!("no {key} in the preset"));
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
            let base = list_base(&name);
            if vars.contains_key(base) || filament.iter().any(|f| f == base) {
                continue;
            }
            match origin(p, base, extruders) {
                Some(Origin::Own) => {}
                Some(Origin::Filament) => filament.push(base.to_string()),
                Some(Origin::Preset(v)) => {
                    vars.insert(base.to_string(), v);
                }
                Some(Origin::Default((_, value, why))) => {
                    let v: RawVariable = crate::recipe::yaml::parse_yaml(value, "default")
                        .expect("the defaults parse");
                    // a list default holds one value per extruder
                    let v = match v {
                        RawVariable::List(l) if l.len() == 1 => {
                            RawVariable::List(vec![l[0].clone(); extruders])
                        }
                        v => v,
                    };
                    notes.push(format!("gcode_variables.{base} = {value}: {why}"));
                    vars.insert(base.to_string(), v);
                }
                None => {
                    return Err(Error::input(
                        format!("{from} line {line}"),
                        format!(
                            "preset `{}`: the variable `{name}` is one p3dp cannot give: neither p3dp nor the preset has a value for it (its value is a slicer's)",
                            p.name
                        ),
                    )
                    .in_file(&p.file))
                }
            }
        }
        match key {
            "start_gcode" => raw.start_gcode = text,
            _ => raw.end_gcode = text,
        }
    }
    if !filament.is_empty() {
        notes.push(format!(
            "the G-code reads the filament's {}: a filament preset gives {} (--filament FILE at the build), else the build refuses {}",
            filament.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join(", "),
            if filament.len() == 1 { "it" } else { "them" },
            if filament.len() == 1 { "it" } else { "them" },
        ));
    }
    // the adaptive bed mesh p3dp computes reads the preset's own limits
    if raw.start_gcode.contains("adaptive_bed_mesh")
        || raw.start_gcode.contains("bed_mesh_probe_count")
    {
        for k in [
            "bed_mesh_min",
            "bed_mesh_max",
            "bed_mesh_probe_distance",
            "adaptive_bed_mesh_margin",
        ] {
            if let Some(v) = typed(p, k, extruders) {
                vars.entry(k.to_string()).or_insert(v);
            }
        }
    }
    raw.gcode_variables = vars;
    Ok(())
}

/// `name` or, for a legacy `[name_N]` whose `name` is a list, `name`.
fn list_base(name: &str) -> &str {
    match name.rsplit_once('_') {
        Some((b, i)) if i.parse::<usize>().is_ok() && !b.is_empty() => b,
        _ => name,
    }
}

/// Settings whose text is a boolean `0`/`1` in both slicers.
const BOOLS: &[&str] = &[
    "nozzle_high_flow",
    "filament_abrasive",
    "single_extruder_multi_material",
    "use_firmware_retraction",
    "use_relative_e_distances",
    "retract_layer_change",
    "wipe",
    "auxiliary_fan",
    "support_chamber_temp_control",
    "support_air_filtration",
    "scan_first_layer",
    "bbl_calib_mark_logo",
    "enable_long_retraction_when_cut",
    "cooling_filter_enabled",
    "support_cooling_filter",
    "enable_pressure_advance",
    "activate_air_filtration",
    "activate_chamber_temp_control",
    "filament_multitool_ramming",
    "filament_long_retractions_when_cut",
    "long_retractions_when_cut",
    "is_support_timelapse",
    "support_object_skip_flush",
];

/// Settings that are text whatever they hold.
fn is_text(name: &str) -> bool {
    name.ends_with("_id")
        || name.ends_with("_notes")
        || name.ends_with("_gcode")
        || name.ends_with("_model")
        || name.ends_with("_variant")
        || name.ends_with("_type")
        || name.ends_with("_vendor")
        || name.ends_with("_format")
        || name.ends_with("_name")
}

/// The preset's setting `name` as a template value: a list where the
/// slicer has one (a `.json` list; an `.ini` value of one number per
/// extruder on a machine of several), a boolean for the settings that are
/// booleans, a number where the text is one, else text on one line (a line
/// break in a preset's text never reaches the G-code).
pub(crate) fn typed(p: &Preset, name: &str, extruders: usize) -> Option<RawVariable> {
    use super::Setting;
    let one = |s: &str| scalar(name, s);
    Some(match p.values.get(name)? {
        Setting::Json(serde_json::Value::Array(a)) => RawVariable::List(
            a.iter()
                .map(|v| one(&v.as_str().map_or_else(|| v.to_string(), str::to_string)))
                .collect(),
        ),
        Setting::Json(serde_json::Value::String(s)) => one(s),
        Setting::Json(serde_json::Value::Bool(b)) => RawVariable::Bool(*b),
        Setting::Json(serde_json::Value::Number(x)) => one(&x.to_string()),
        Setting::Json(_) => return None,
        Setting::Ini(s) => {
            let parts: Vec<&str> = s.split(',').map(str::trim).collect();
            let numbers = parts
                .iter()
                .all(|x| x.parse::<f64>().is_ok() || *x == "nil");
            if extruders > 1 && parts.len() == extruders && numbers && !is_text(name) {
                RawVariable::List(parts.iter().map(|x| one(x)).collect())
            } else {
                one(&super::ini::unescape(s))
            }
        }
    })
}

/// One value of setting `name` from its text.
fn scalar(name: &str, s: &str) -> RawVariable {
    let t = s.trim();
    if BOOLS.contains(&name) && matches!(t, "0" | "1" | "true" | "false") {
        return RawVariable::Bool(t == "1" || t == "true");
    }
    if !is_text(name) {
        if let Ok(i) = t.parse::<i64>() {
            return RawVariable::Int(i);
        }
        if let Ok(f) = t.parse::<f64>() {
            if f.is_finite() && t.chars().any(|c| c.is_ascii_digit()) {
                return RawVariable::Float(f);
            }
        }
    }
    RawVariable::Str(crate::base::safe_text::one_line(s).into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn preset(format: Format, values: &[(&str, &str)]) -> Preset {
        use super::super::Setting;
        Preset {
            name: "P".into(),
            file: "p.ini".into(),
            format,
            kind: Kind::Printer,
            values: values
                .iter()
                .map(|(k, v)| {
                    let s = match format {
                        Format::Ini => Setting::Ini(v.to_string()),
                        Format::Json => Setting::Json(serde_json::from_str(v).unwrap()),
                    };
                    (k.to_string(), s)
                })
                .collect(),
        }
    }

    /// The YAML written is the profile imported: parsed back, the same
    /// value, key by key (numbers, booleans, texts, lists, G-code blocks).
    #[test]
    fn the_yaml_reads_back_as_the_imported_profile() {
        let p = preset(
            Format::Ini,
            &[
                ("bed_shape", "3x3,228x3,228x228,3x228"),
                ("max_print_height", "250.5"),
                ("nozzle_diameter", "0.4,0.4,0.6"),
                ("gcode_flavor", "klipper"),
                ("machine_max_feedrate_x", "500"),
                ("machine_max_feedrate_y", "400"),
                ("machine_max_acceleration_extruding", "7000"),
                ("machine_max_jerk_x", "9"),
                ("retract_length", "0.8"),
                ("retract_speed", "35"),
                ("thumbnails", "16x16/QOI, 313x173/QOI, 300x300/PNG"),
                ("printer_notes", "line one\\nPRINTER_HAS_X"),
                ("extra_loading_move", "-2"),
                ("parking_pos_retraction", "92.5"),
                ("retract_length_toolchange", "1,2,3.5"),
                ("nozzle_high_flow", "0"),
                ("start_gcode", "G28 ; [printer_notes]\\nG1 E{extra_loading_move} F{parking_pos_retraction}\\n{if nozzle_high_flow}M221 S90{endif}\\nM104 S[retract_length_toolchange_2] T[initial_tool]\\n"),
                ("end_gcode", "M84\\n\\n"),
            ],
        );
        let i = import(&p).unwrap();
        assert_eq!(i.raw.extruders, 3);
        assert_eq!(
            i.raw.gcode_variables["printer_notes"],
            RawVariable::Str("line one\\u{a}PRINTER_HAS_X".into())
        );
        assert_eq!(
            i.raw.gcode_variables["extra_loading_move"],
            RawVariable::Int(-2)
        );
        assert_eq!(
            i.raw.gcode_variables["parking_pos_retraction"],
            RawVariable::Float(92.5)
        );
        assert_eq!(
            i.raw.gcode_variables["nozzle_high_flow"],
            RawVariable::Bool(false)
        );
        assert_eq!(
            i.raw.gcode_variables["retract_length_toolchange"],
            RawVariable::List(vec![
                RawVariable::Int(1),
                RawVariable::Int(2),
                RawVariable::Float(3.5)
            ])
        );
        let y = i.yaml();
        let back: RawPrinter = crate::recipe::yaml::parse_yaml(&y, "p.yaml").unwrap();
        assert_eq!(back, i.raw, "{y}");
    }

    /// Text YAML cannot carry as it is (C1 controls, U+FFFE, a carriage
    /// return, U+2028, tabs and quotes) reads back unchanged.
    /// A polygon bed: p3dp keeps to a rectangle or a circle inside it, every
    /// corner of which lies inside the maker's bed; a non-convex one (or a
    /// malformed rectangle) is refused.
    /// Klipper's square-corner velocity from a jerk no machine has is left
    /// out (Klipper's 5 mm/s), not written as a value the profile refuses;
    /// OrcaSlicer's `bed_shape = rectangular` yields to `printable_area`.
    #[test]
    fn a_jerk_past_the_ceiling_and_a_rectangular_bed_shape() {
        let p = preset(
            Format::Json,
            &[
                ("bed_shape", "\"rectangular\""),
                (
                    "printable_area",
                    "[\"0x0\", \"220x0\", \"220x220\", \"0x220\"]",
                ),
                ("printable_height", "\"250\""),
                ("gcode_flavor", "\"klipper\""),
                ("machine_max_jerk_x", "[\"20000\"]"),
                ("machine_max_jerk_y", "[\"20000\"]"),
            ],
        );
        let i = import(&p).unwrap();
        assert_eq!(i.raw.kinematics.square_corner_velocity, Some(5.0));
        assert!(
            i.notes
                .iter()
                .any(|n| n.contains("machine_max_jerk_x/y 20000 mm/s is past")),
            "{:?}",
            i.notes
        );
        assert!(matches!(i.raw.bed, RawBed::Rectangle { size, .. } if size == [220.0, 220.0]));
        crate::recipe::profile::from_raw(i.raw.clone(), "p.json").unwrap();
    }
}
