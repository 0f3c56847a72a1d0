//! Printer profiles read from YAML: the built-in ones (embedded in the
//! binary, parsed by the same code as a user's file), a user's file, and
//! `inherits:` chains merged key by key.

use crate::base::input::{Reads, MAX_TEXT_BYTES};
use std::path::Path;

use super::schema::{
    RawBed, RawExtrusion, RawFlavor, RawHead, RawKinematics, RawPrinter, RawRetraction, RawVariable,
};
use super::yaml::{parse_yaml, Tree};
use crate::base::error::{Error, Result};
use crate::base::slicer_macro::Value;
use crate::machine::printer::Envelope;
use crate::machine::{Bed, Extrusion, Flavor, Head, Kinematics, Printer, Retraction};

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
    (
        "bambu-x1c",
        include_str!("../machine/printers/bambu-x1c.yaml"),
    ),
    (
        "bambu-p1s",
        include_str!("../machine/printers/bambu-p1s.yaml"),
    ),
    (
        "bambu-a1",
        include_str!("../machine/printers/bambu-a1.yaml"),
    ),
    (
        "bambu-a1-mini",
        include_str!("../machine/printers/bambu-a1-mini.yaml"),
    ),
    (
        "prusa-mk4s",
        include_str!("../machine/printers/prusa-mk4s.yaml"),
    ),
    (
        "prusa-core-one",
        include_str!("../machine/printers/prusa-core-one.yaml"),
    ),
    (
        "prusa-mini",
        include_str!("../machine/printers/prusa-mini.yaml"),
    ),
    (
        "creality-k1",
        include_str!("../machine/printers/creality-k1.yaml"),
    ),
    (
        "ender3-v3",
        include_str!("../machine/printers/ender3-v3.yaml"),
    ),
];

/// Names of the built-in printer profiles.
pub fn built_in_names() -> Vec<&'static str> {
    BUILT_IN.iter().map(|(n, _)| *n).collect()
}

/// A built-in profile by name.
pub fn built_in(name: &str) -> Option<Printer> {
    let (_, text) = BUILT_IN.iter().find(|(n, _)| *n == name)?;
    let p: RawPrinter = parse_yaml(text, name).expect("built-in profiles parse");
    Some(printer(p))
}

/// A profile from a YAML file. With `inherits: NAME|FILE` the file's keys
/// override those of a built-in profile or another file (maps merged key
/// by key, see `Tree::merge`); a file without it is parsed on its own.
#[cfg(any(test, feature = "testing"))]
pub fn from_file(path: &Path) -> Result<Printer> {
    let reads = Reads::default();
    reads.name(path);
    from_file_in(path, &reads)
}

/// [`from_file`], every file read noted in `reads` and read
/// only inside its roots ([`Reads::reach`]).
pub(crate) fn from_file_in(path: &Path, reads: &Reads) -> Result<Printer> {
    let shown = path.display().to_string();
    let text = reads.read_reached(path, "printer profile", MAX_TEXT_BYTES)?;
    let tree = Tree::parse(&text, &shown)?;
    let raw: RawPrinter = if tree.has("inherits") {
        let named = tree.has("name");
        let mut seen = vec![path.canonicalize().unwrap_or_else(|_| path.to_path_buf())];
        let mut merged = inherit(tree, path, &mut seen, reads).map_err(|e| e.in_file(&shown))?;
        if !named {
            // a profile named after its file, not after its base
            if let Some(stem) = path.file_stem() {
                merged.set_str("name", stem.to_string_lossy().into_owned());
            }
        }
        merged.read(&shown)?
    } else {
        parse_yaml(&text, &shown)?
    };
    let mut p = printer(raw);
    p.source = Some(shown.clone());
    p.validate().map_err(|e| e.in_file(&shown))?;
    Ok(p)
}

/// A slicer's printer preset (see `recipe::preset`) as a
/// profile: the preset mapped to the profile's raw form (the value `p3dp
/// printers import` writes as YAML), loaded and checked as a profile
/// file is; errors name the preset file.
pub fn from_preset(src: &super::preset::Source, reads: &Reads) -> Result<Printer> {
    let preset = super::preset::load(src, reads)?;
    let imported = super::preset::map::import(&preset)?;
    from_raw(imported.raw, &preset.file)
}

/// A built-in name, or else a path (relative paths from `base`): a
/// profile's YAML, or a slicer's `.ini` or `.json` printer preset; every
/// file read noted in `reads`.
pub(crate) fn resolve(spec: &str, base: &Path, reads: &Reads) -> Result<Printer> {
    if let Some(p) = built_in(spec) {
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
    reads
        .reach(&path, "printer profile")
        .map_err(|e| e.under("printer"))?;
    if !path.exists() {
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
    if super::preset::is_preset_file(spec) {
        let src = super::preset::Source {
            file: path,
            ..Default::default()
        };
        return from_preset(&src, reads);
    }
    from_file_in(&path, reads)
}

/// The profile of a raw form (an imported preset's, see
/// [`crate::recipe::preset::map`]) read from `file`: checked as a profile
/// file is, errors naming `file`.
pub(crate) fn from_raw(raw: RawPrinter, file: &str) -> Result<Printer> {
    let mut p = printer(raw);
    p.source = Some(file.to_string());
    p.validate().map_err(|e| e.in_file(file))?;
    Ok(p)
}

/// Whether a printer name that is not built in is meant as a file: it has a
/// `/` or ends in `.yaml` / `.yml` (or `.ini` / `.json`, a slicer's preset;
/// anything else is a misspelt name).
fn names_a_file(spec: &str) -> bool {
    spec.contains('/')
        || spec.ends_with(".yaml")
        || spec.ends_with(".yml")
        || super::preset::is_preset_file(spec)
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

/// Resolves the `inherits:` of a profile file's YAML `tree` (read from
/// `path`): the base (a built-in name, or a file relative to `path`, itself
/// resolved) with `tree`'s keys merged over it (maps merged key by key, but
/// a map whose `shape` differs replaces the base's whole: a round bed over a
/// rectangle). `seen` holds the files of the chain so far, to refuse cycles.
fn inherit(
    mut tree: Tree,
    path: &Path,
    seen: &mut Vec<std::path::PathBuf>,
    reads: &Reads,
) -> Result<Tree> {
    let Some(spec) = tree.remove("inherits") else {
        return Ok(tree);
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
    let base = if let Some((name, text)) = BUILT_IN.iter().find(|(n, _)| *n == spec) {
        Tree::parse(text, name).expect("built-in profiles parse")
    } else if names_a_file(&spec) {
        let rel = spec.trim_start_matches("./");
        let file = match path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() && dir != Path::new(".") => dir.join(rel),
            _ => Path::new(rel).to_path_buf(),
        };
        reads
            .reach(&file, "printer profile")
            .map_err(|e| e.under("inherits"))?;
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
        let text = reads
            .read_reached(&file, "printer profile", MAX_TEXT_BYTES)
            .map_err(|e| {
                if e.file.is_none() {
                    e.under("inherits")
                } else {
                    e
                }
            })?;
        let t = Tree::parse(&text, &shown)?;
        inherit(t, &file, seen, reads).map_err(|e| e.in_file(&shown))?
    } else {
        return Err(unknown_printer("inherits", &spec));
    };
    Ok(Tree::merge(base, tree, "shape"))
}

/// The profile as written, in the machine's types (checked by
/// [`Printer::validate`], which names the key of a value out of range).
fn printer(raw: RawPrinter) -> Printer {
    let flavor = flavor(raw.flavor);
    Printer {
        name: raw.name,
        model: raw.model,
        source: None,
        flavor,
        bed: match raw.bed {
            RawBed::Rectangle { size, max_z, min } => Bed::Rectangle { size, max_z, min },
            RawBed::Circle { diameter, max_z } => Bed::Circle { diameter, max_z },
        },
        origin: raw.origin,
        nozzle_diameter: raw.nozzle_diameter,
        filament_diameter: raw.filament_diameter,
        extrusion: match raw.extrusion {
            RawExtrusion::Absolute => Extrusion::Absolute,
            RawExtrusion::Relative => Extrusion::Relative,
        },
        extruders: raw.extruders as usize,
        tool: raw.tool as usize,
        start_gcode: raw.start_gcode,
        end_gcode: raw.end_gcode,
        gcode_variables: raw
            .gcode_variables
            .into_iter()
            .map(|(k, v)| (k, variable(v)))
            .collect(),
        envelope: Envelope {
            margin: raw.envelope.margin,
            below_bed: raw.envelope.below_bed,
            x: raw.envelope.x,
            y: raw.envelope.y,
        },
        travel_speed: raw.travel_speed,
        retraction: retraction(raw.retraction),
        firmware_retraction: raw.firmware_retraction,
        max_nozzle_temp: raw.max_nozzle_temp,
        max_bed_temp: raw.max_bed_temp,
        max_speed: raw.max_speed,
        max_flow: raw.max_flow,
        min_string_length: raw.min_string_length,
        arcs: raw.arcs,
        arc_tolerance: raw.arc_tolerance,
        thumbnails: raw.thumbnails,
        // the screens of Marlin 2 and Prusa's firmware show M73's progress
        progress: raw
            .progress
            .unwrap_or(matches!(flavor, Flavor::Marlin | Flavor::Prusa)),
        object_labels: raw.object_labels.unwrap_or(flavor == Flavor::Klipper),
        binary_gcode: raw.binary_gcode,
        maker_temperatures: raw.maker_temperatures,
        emit_limits: raw.emit_limits,
        axis_acceleration: raw.axis_acceleration,
        pressure_advance: raw.pressure_advance,
        kinematics: kinematics(raw.kinematics),
        head: head(raw.head),
        checks: raw.checks,
    }
}

/// A `gcode_variables` value as a template value.
pub(crate) fn variable(v: RawVariable) -> Value {
    match v {
        RawVariable::Bool(b) => Value::Bool(b),
        RawVariable::Int(i) => Value::Int(i),
        RawVariable::Float(f) => Value::Float(f),
        RawVariable::Str(s) => Value::Str(s),
        RawVariable::List(l) => Value::List(l.into_iter().map(variable).collect()),
    }
}

fn flavor(f: RawFlavor) -> Flavor {
    f.flavor()
}

fn retraction(r: RawRetraction) -> Retraction {
    Retraction {
        length: r.length,
        speed: r.speed,
        min_travel: r.min_travel,
    }
}

fn kinematics(k: RawKinematics) -> Kinematics {
    Kinematics {
        max_velocity: k.max_velocity,
        max_acceleration: k.max_acceleration,
        travel_acceleration: k.travel_acceleration,
        retract_acceleration: k.retract_acceleration,
        junction_deviation: k.junction_deviation,
        jerk: k.jerk,
        square_corner_velocity: k.square_corner_velocity,
        min_segment_time: k.min_segment_time,
        minimum_cruise_ratio: k.minimum_cruise_ratio,
        max_z_speed: k.max_z_speed,
        max_z_acceleration: k.max_z_acceleration,
        instantaneous_corner_velocity: k.instantaneous_corner_velocity,
        max_extrude_only_velocity: k.max_extrude_only_velocity,
        max_extrude_only_accel: k.max_extrude_only_accel,
        max_extrude_cross_section: k.max_extrude_cross_section,
        max_extrude_only_distance: k.max_extrude_only_distance,
        min_segment_time_floor: k.min_segment_time_floor,
        block_buffer_size: k.block_buffer_size,
        command_rate: k.command_rate,
    }
}

fn head(h: RawHead) -> Head {
    Head {
        cone_angle: h.cone_angle,
        cone_height: h.cone_height,
        tip_diameter: h.tip_diameter,
        head_box: h.head_box,
        clearance: h.clearance,
        gantry: h.gantry.map(|g| crate::machine::Gantry {
            height: g.height,
            y: g.y,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_profiles_checks_deserialise_into_check_limits_key_by_key() {
        let file = |checks: &str| {
            format!("name: p\nbed: {{shape: circle, diameter: 280, max_z: 300}}\norigin: [0,0,0]\nnozzle_diameter: 0.4\nfilament_diameter: 1.75\nchecks: {checks}\n")
        };
        // an absent key keeps CheckLimits::default's value
        let raw: RawPrinter =
            parse_yaml(&file("{ max_bridge: 4, planner_buffer: 8 }"), "p.yaml").unwrap();
        let want = crate::machine::CheckLimits {
            max_bridge: 4.0,
            planner_buffer: 8,
            ..Default::default()
        };
        assert_eq!(raw.checks, want);
        assert_eq!(printer(raw).checks, want);
        // a misspelt key is refused under `checks`, the real names offered
        let e = parse_yaml::<RawPrinter>(&file("{ max_brige: 4 }"), "p.yaml").unwrap_err();
        assert_eq!(e.place.as_deref(), Some("checks.max_brige"), "{e}");
        assert!(e.message.contains("unknown field `max_brige`"), "{e}");
        assert!(e.message.contains("`max_bridge`"), "{e}");
        // a value out of range is named by its key path when checked
        let raw: RawPrinter = parse_yaml(&file("{ support_tolerance: -1 }"), "p.yaml").unwrap();
        let e = printer(raw).validate().unwrap_err();
        assert_eq!(e.place.as_deref(), Some("checks.support_tolerance"), "{e}");
    }

    #[test]
    fn flavor_names_round_trip() {
        // the name the G-code layer gives a flavour is the one a profile reads
        for f in Flavor::ALL {
            let raw: RawFlavor = parse_yaml(f.name(), "p.yaml").unwrap();
            assert_eq!(flavor(raw), f);
        }
    }
}
