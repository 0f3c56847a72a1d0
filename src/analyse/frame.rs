//! The start and end G-code of one print, expanded and checked before any
//! byte is written: the profile's templates ([`crate::base::slicer_macro`])
//! filled from the recipe's material, the profile and the strings built
//! (the variables of [`crate::machine::VARIABLES`] and the profile's
//! `gcode_variables`), then every line held to the machine's limits
//! ([`crate::analyse::check::gcode`]). The writer writes exactly this text.

use glam::DVec3;

use crate::analyse::check::gcode::{self, Start};
use crate::base::error::{Error, Result};
use crate::base::gcode::Verbatim;
use crate::base::slicer_macro::{Value, Vars};
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;

/// A print's start and end G-code, expanded and checked: each line as it
/// is written, and what its firmware reads in it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Before the first part.
    pub start: Vec<Verbatim>,
    /// After the last part.
    pub end: Vec<Verbatim>,
}

impl Frame {
    /// The start G-code as it is written, a line feed after each line.
    pub fn start_text(&self) -> String {
        lines(&self.start)
    }

    /// The end G-code as it is written, a line feed after each line.
    pub fn end_text(&self) -> String {
        lines(&self.end)
    }
}

fn lines(v: &[Verbatim]) -> String {
    v.iter().map(|l| format!("{}\n", l.text)).collect()
}

/// What the strings say about the print for the templates: heights of the
/// extruding points (recipe z) and the first layer's extent (machine XY).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Extent {
    /// Lowest extruding point's z.
    low: f64,
    /// Highest extruding point's z.
    high: f64,
    /// The last extruding point's z.
    last: f64,
    /// XY corners of the extruding strings below twice `low`, machine mm.
    first_min: [f64; 2],
    first_max: [f64; 2],
    /// The first extruding string's cross-section, mm².
    first_c: f64,
    /// The last point of the print (recipe coordinates), where the end
    /// G-code starts.
    end_at: Option<DVec3>,
    /// Highest z of any point, travel included, and at least 0.
    top: f64,
    /// Volume of the extruding strings, mm³ (what E adds up to, times the
    /// filament's area).
    volume: f64,
    /// Lowest and highest z of any string that is not a travel (extruding
    /// or not), recipe z: the G-code's layers.
    pub(crate) drawn: Option<(f64, f64)>,
}

impl Extent {
    /// Highest z of any point, travel included, and at least 0.
    pub(crate) fn top(&self) -> f64 {
        self.top
    }
}

/// The start and end G-code of `recipe` printing `paths`, expanded and
/// checked; an error names the profile (its file, or the built-in name),
/// the template's key and line, and why.
pub(crate) fn frame(recipe: &Recipe, ext: &Extent) -> Result<Frame> {
    let p = &recipe.printer;
    let ext = *ext;
    let shown = match &p.source {
        Some(f) => f.clone(),
        None => format!("built-in printer `{}`", p.name),
    };
    // a `global` of the start G-code is still set in the end G-code
    let mut globals = Vars::new();
    let mut one = |key: &str, text: &str, end: bool| -> Result<Vec<Verbatim>> {
        let t = p.template(key, text).map_err(|e| e.in_file(&shown))?;
        let vars = variables(recipe, &ext, end);
        let out = t
            .expand_with(&vars, &mut globals)
            .map_err(|e| Error::input(format!("{key} line {}", e.line), e.message))
            .map_err(|e| e.in_file(&shown))?;
        let from = if end {
            let d = recipe
                .material
                .filament_diameter
                .unwrap_or(p.filament_diameter);
            let area = std::f64::consts::PI * d * d / 4.0;
            Start::At(
                p.to_machine(ext.end_at.unwrap_or(DVec3::ZERO)),
                ext.volume / area,
            )
        } else {
            Start::Unknown
        };
        gcode::check(key, &out, recipe, from).map_err(|e| e.in_file(&shown))
    };
    Ok(Frame {
        start: one("start_gcode", &p.start_gcode, false)?,
        end: one("end_gcode", &p.end_gcode, true)?,
    })
}

/// The heights and the first layer of `paths`, in one pass over their
/// strings (and one over the first layer's).
pub(crate) fn extent(recipe: &Recipe, paths: &[Toolpath]) -> Extent {
    let mut e = Extent {
        low: f64::INFINITY,
        high: f64::NEG_INFINITY,
        last: 0.0,
        first_min: [f64::INFINITY; 2],
        first_max: [f64::NEG_INFINITY; 2],
        first_c: 0.0,
        end_at: paths.iter().rev().find_map(|t| t.points.last().copied()),
        top: paths
            .iter()
            .flat_map(|t| t.points.iter().map(|p| p.z))
            .fold(0.0, f64::max),
        volume: 0.0,
        drawn: None,
    };
    let (mut dlo, mut dhi) = (f64::INFINITY, f64::NEG_INFINITY);
    let extruding = |t: &Toolpath, k: usize| !t.strings[k].travel && t.strings[k].c > 0.0;
    for t in paths {
        for k in 0..t.len() {
            if t.strings[k].travel {
                continue;
            }
            let (a, b) = t.ends(k);
            dlo = dlo.min(a.z.min(b.z));
            dhi = dhi.max(a.z.max(b.z));
            if !extruding(t, k) {
                continue;
            }
            if e.first_c == 0.0 {
                e.first_c = t.strings[k].c;
            }
            e.volume += t.strings[k].c * a.distance(b);
            e.low = e.low.min(a.z.min(b.z));
            e.high = e.high.max(a.z.max(b.z));
            e.last = b.z;
        }
    }
    e.drawn = (dlo <= dhi).then_some((dlo, dhi));
    if !e.low.is_finite() {
        // nothing extrudes: every height is the bed's
        (e.low, e.high) = (0.0, 0.0);
        return e;
    }
    // the first layer: strings whose lower end lies below where a second
    // layer of the first one's height would start
    for t in paths {
        for k in 0..t.len() {
            let (a, b) = t.ends(k);
            if !extruding(t, k) || a.z.min(b.z) >= 2.0 * e.low {
                continue;
            }
            for q in [a, b] {
                let m = recipe.printer.to_machine(q);
                e.first_min = [e.first_min[0].min(m.x), e.first_min[1].min(m.y)];
                e.first_max = [e.first_max[0].max(m.x), e.first_max[1].max(m.y)];
            }
        }
    }
    e
}

/// A temperature as the slicers hold it: an integer (a fraction of a
/// degree stays a real).
fn temp(t: f64) -> Value {
    if t.fract() == 0.0 && t.abs() < 1e9 {
        Value::Int(t as i64)
    } else {
        Value::Float(t)
    }
}

fn list(v: Value) -> Value {
    Value::List(vec![v])
}

fn pair(x: f64, y: f64) -> Value {
    Value::List(vec![Value::Float(x), Value::Float(y)])
}

/// The variables of [`crate::machine::VARIABLES`] and the profile's own;
/// `end` for the end G-code (where `layer_z` is the last point's height).
fn variables(recipe: &Recipe, ext: &Extent, end: bool) -> Vars {
    let p = &recipe.printer;
    let m = &recipe.material;
    let mut v: Vars = p.gcode_variables.clone();
    let mut set = |name: &str, value: Value| {
        v.insert(name.to_string(), value);
    };
    own(recipe, ext, &mut set);
    for n in [
        "first_layer_temperature",
        "temperature",
        "nozzle_temperature_initial_layer",
        "nozzle_temperature",
    ] {
        set(n, list(temp(m.nozzle_temp)));
    }
    for n in [
        "first_layer_bed_temperature",
        "bed_temperature",
        "bed_temperature_initial_layer",
    ] {
        set(n, list(temp(m.bed_temp)));
    }
    for plate in ["hot", "cool", "eng", "textured"] {
        set(&format!("{plate}_plate_temp"), list(temp(m.bed_temp)));
        set(
            &format!("{plate}_plate_temp_initial_layer"),
            list(temp(m.bed_temp)),
        );
    }
    set("bed_temperature_initial_layer_single", temp(m.bed_temp));
    set("filament_type", list(Value::Str(m.name.to_uppercase())));
    set("filament_settings_id", list(Value::Str(m.name.clone())));
    set("printer_settings_id", Value::Str(p.name.clone()));
    set("printer_model", Value::Str(p.model.clone()));
    for n in [
        "initial_tool",
        "initial_extruder",
        "current_extruder",
        "total_toolchanges",
    ] {
        set(n, Value::Int(0));
    }
    set("has_wipe_tower", Value::Bool(false));
    set(
        "has_single_extruder_multi_material_priming",
        Value::Bool(false),
    );
    set("input_filename_base", Value::Str(recipe.name.clone()));
    set("input_filename", Value::Str(recipe.name.clone()));
    layers(recipe, ext, end, &mut set);
    machine(recipe, &mut set);
    v
}

/// p3dp's own placeholders, written as they always were.
fn own(recipe: &Recipe, ext: &Extent, set: &mut impl FnMut(&str, Value)) {
    use crate::base::format::fmt_num;
    let (p, m) = (&recipe.printer, &recipe.material);
    let (bx, by) = match p.bed {
        crate::machine::Bed::Rectangle { size, .. } => (size[0], size[1]),
        crate::machine::Bed::Circle { .. } => (0.0, 0.0),
    };
    let park = (p.to_machine(DVec3::new(0.0, 0.0, ext.top)).z + 10.0).min(p.bed.max_z());
    let shown = |x: f64, s: String| Value::Shown(x, s);
    set("nozzle_temp", shown(m.nozzle_temp, fmt_num(m.nozzle_temp)));
    set("bed_temp", shown(m.bed_temp, fmt_num(m.bed_temp)));
    let fd = m.filament_diameter.unwrap_or(p.filament_diameter);
    set("filament_diameter", list(shown(fd, fmt_num(fd))));
    set(
        "nozzle_diameter",
        list(shown(p.nozzle_diameter, fmt_num(p.nozzle_diameter))),
    );
    // positions as the moves write them: fixed point, 3 decimals
    set("bed_x", shown(bx, format!("{bx:.3}")));
    set("bed_y", shown(by, format!("{by:.3}")));
    let max_z = p.bed.max_z();
    set("max_z", shown(max_z, format!("{max_z:.3}")));
    set("park_z", shown(park, format!("{park:.3}")));
}

/// The "layer" values: p3dp prints strings, so they describe the strings.
fn layers(recipe: &Recipe, ext: &Extent, end: bool, set: &mut impl FnMut(&str, Value)) {
    let p = &recipe.printer;
    let h = ext.low.max(0.0);
    set("first_layer_height", Value::Float(h));
    set("layer_height", Value::Float(h));
    set(
        "layer_z",
        Value::Float(if end { ext.last.max(0.0) } else { h }),
    );
    set("max_layer_z", Value::Float(ext.high.max(0.0)));
    let (bmin, bmax) = p.bed.extent();
    let (fmin, fmax) = if ext.first_min[0].is_finite() {
        (ext.first_min, ext.first_max)
    } else {
        // nothing printed: the bed's centre
        let c = p.to_machine(DVec3::ZERO);
        ([c.x, c.y], [c.x, c.y])
    };
    set("first_layer_print_min", pair(fmin[0], fmin[1]));
    set("first_layer_print_max", pair(fmax[0], fmax[1]));
    set(
        "first_layer_print_size",
        pair(fmax[0] - fmin[0], fmax[1] - fmin[1]),
    );
    set("print_bed_min", pair(bmin[0], bmin[1]));
    set("print_bed_max", pair(bmax[0], bmax[1]));
    set("print_bed_size", pair(bmax[0] - bmin[0], bmax[1] - bmin[1]));
    let width = if h > 0.0 { ext.first_c / h } else { 0.0 };
    set("extrusion_width", Value::Float(width));
}

/// The machine's values: heights, speeds, retraction, planner limits.
fn machine(recipe: &Recipe, set: &mut impl FnMut(&str, Value)) {
    let p = &recipe.printer;
    let f = Value::Float;
    set("max_print_height", f(p.bed.max_z()));
    set("printable_height", f(p.bed.max_z()));
    set("z_offset", f(p.origin[2]));
    set("travel_speed", f(p.travel_speed));
    let r = &p.retraction;
    for n in ["retract_length", "retraction_length"] {
        set(n, list(f(r.length)));
    }
    for n in ["retract_speed", "retraction_speed"] {
        set(n, list(f(r.speed)));
    }
    for n in ["retract_lift", "z_hop"] {
        set(n, list(f(0.0)));
    }
    let l = p.limits();
    set(
        "machine_max_acceleration_extruding",
        list(f(l.max_acceleration)),
    );
    set(
        "machine_max_acceleration_travel",
        list(f(l.travel_acceleration)),
    );
    set(
        "machine_max_acceleration_retracting",
        list(f(l.retract_acceleration)),
    );
    set("machine_max_feedrate_x", list(f(l.max_velocity)));
    set("machine_max_feedrate_y", list(f(l.max_velocity)));
    set(
        "machine_max_feedrate_z",
        list(f(l.max_z_velocity.unwrap_or(l.max_velocity))),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_variable_has_a_value() {
        let raw: crate::recipe::RawRecipe =
            crate::recipe::parse_yaml("p3dp: 1\nname: t\nparts:\n  - primitive: {helix: {radius: 10, height: 2, pitch: 0.5}}\n", "t.yaml").unwrap();
        let r = Recipe::resolve(&raw, &[], None, std::path::Path::new(".")).unwrap();
        let ext = extent(&r, &[]);
        let v = variables(&r, &ext, false);
        for (name, _) in crate::machine::VARIABLES {
            assert!(v.contains_key(*name), "{name}");
        }
        assert_eq!(v.len(), crate::machine::VARIABLES.len());
    }
}
