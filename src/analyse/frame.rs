//! The start and end G-code of one print, expanded and checked before any
//! byte is written: the profile's templates ([`crate::base::slicer_macro`])
//! filled from the recipe's material, the profile and the strings built
//! (the variables of [`crate::machine::VARIABLES`] and the profile's
//! `gcode_variables`), then every line held to the machine's limits
//! ([`crate::analyse::check::gcode`]). The writer writes exactly this text.

use glam::DVec3;

use crate::analyse::check::gcode::{self, Start};
use crate::base::error::{Error, Result};
use crate::base::format::Chunk;
use crate::base::gcode::{Command, Setting, Verbatim};
use crate::base::slicer_macro::{Template, Value, Vars};
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;
use crate::machine::firmware::write::{self, Dialect};
use crate::machine::{Flavor, Printer};

/// A print's start and end G-code, expanded and checked: each line as it
/// is written, and what its firmware reads in it.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Frame {
    /// Before the first part.
    pub(crate) start: Vec<Verbatim>,
    /// After the last part.
    pub(crate) end: Vec<Verbatim>,
}

#[cfg(any(test, feature = "testing"))]
impl Frame {
    /// The start G-code as it is written, a line feed after each line.
    pub(crate) fn start_text(&self) -> String {
        lines(&self.start)
    }

    /// The end G-code as it is written, a line feed after each line.
    pub(crate) fn end_text(&self) -> String {
        lines(&self.end)
    }
}

#[cfg(any(test, feature = "testing"))]
fn lines(v: &[Verbatim]) -> String {
    v.iter().map(|l| format!("{}\n", l.text)).collect()
}

/// What the strings say about the print for the templates: heights of the
/// extruding points (recipe z), the first layer's extent (machine XY), and
/// the speeds and flows the strings print at.
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
    /// The first extruding string's speed, mm/s.
    first_v: f64,
    /// The highest volumetric flow of an extruding string, c·v, mm³/s.
    max_flow: f64,
    /// The last point of the print (recipe coordinates), where the end
    /// G-code starts.
    end_at: Option<DVec3>,
    /// Highest z of any point, travel included, and at least 0.
    top: f64,
    /// Whether the print ends on a travel long enough to be retracted (the
    /// writer retracts before it), so the end G-code starts retracted.
    ends_retracted: bool,
    /// Volume of the extruding strings, mm³ (what E adds up to, times the
    /// filament's area).
    volume: f64,
    /// Lowest and highest z of any string that is not a travel (extruding
    /// or not), recipe z: the G-code's layers.
    pub(crate) drawn: Option<(f64, f64)>,
    /// The box of every point, recipe coordinates (None when a point is not
    /// finite, or there is none).
    pub(crate) points: Option<(DVec3, DVec3)>,
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
        has_values(recipe, &t, &vars, &globals).map_err(|(line, message)| {
            Error::input(format!("{key} line {line}"), message).in_file(&shown)
        })?;
        let (mut out, outputs) = t
            .expand_io(&vars, &mut globals)
            .map_err(|e| Error::input(format!("{key} line {}", e.line), e.message))
            .map_err(|e| e.in_file(&shown))?;
        let back = if end {
            String::new()
        } else {
            unretract(p, &outputs)
        };
        if !back.is_empty() {
            if !out.is_empty() && !out.ends_with('\n') {
                out.push('\n');
            }
            out.push_str(&back);
        }
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
    let mut start = emitted_limits(p);
    start.extend(one("start_gcode", &p.start_gcode, false)?);
    Ok(Frame {
        start,
        end: one("end_gcode", &p.end_gcode, true)?,
    })
}

/// What the print pushes back after a start G-code that left the filament
/// retracted and said so (`{e_retracted[t] = …}`, `e_restart_extra[t]`:
/// PrusaSlicer reads them back and unretracts their sum before the first
/// extrusion, its `GCodeWriter::unretract`): relative E, then that feed at
/// the retraction speed; nothing when the template set neither.
fn unretract(p: &Printer, outputs: &Vars) -> String {
    let at = |name: &str| match outputs.get(name) {
        Some(Value::List(items)) => items.get(p.tool).and_then(number).unwrap_or(0.0),
        _ => 0.0,
    };
    let feed = at("e_retracted") + at("e_restart_extra");
    if !(feed > 0.0 && feed.is_finite()) {
        return String::new();
    }
    let f = p.retraction.speed * 60.0;
    format!(
        "M83 ; relative E for the unretraction\nG1 E{} F{} ; unretract what the start G-code retracted (e_retracted, e_restart_extra)\n",
        crate::base::format::fmt_num(feed),
        crate::base::format::fmt_num(f)
    )
}

/// The firmware's limits written before the start G-code when the profile
/// says `emit_limits` (PrusaSlicer's `machine_limits_usage = emit_to_gcode`,
/// OrcaSlicer's `emit_machine_limits_to_gcode`, which write `M201`, `M203`,
/// `M204`, `M205` there, on Marlin and RepRapFirmware only): typed settings
/// through the one writer, which the planner then follows as it follows any
/// setting of the start G-code. `M201 X Y` is the profile's
/// `axis_acceleration`, else the head's highest acceleration.
fn emitted_limits(p: &Printer) -> Vec<Verbatim> {
    if !p.emit_limits || !matches!(p.flavor, Flavor::Marlin | Flavor::Prusa | Flavor::Reprap) {
        return Vec::new();
    }
    let l = p.limits();
    let head = l.max_acceleration.max(l.travel_acceleration);
    let [ax, ay] = p.axis_acceleration.unwrap_or([head, head]);
    let mut settings = vec![
        Setting::MaxAcceleration {
            axes: [
                Some(ax),
                Some(ay),
                l.max_z_acceleration,
                l.max_extrude_only_accel,
            ],
        },
        Setting::MaxFeedrate {
            axes: [
                Some(l.max_velocity),
                Some(l.max_velocity),
                l.max_z_velocity,
                l.max_extrude_only_velocity,
            ],
        },
        Setting::Acceleration {
            print: Some(l.max_acceleration),
            travel: Some(l.travel_acceleration),
            retract: Some(l.retract_acceleration),
        },
    ];
    match (p.kinematics.jerk, p.kinematics.junction_deviation) {
        (Some(j), _) => settings.push(Setting::Jerk(j)),
        (None, Some(jd)) if p.flavor == Flavor::Marlin => {
            settings.push(Setting::JunctionDeviation(jd))
        }
        _ => {}
    }
    // the dialect as the output writes it (output::gcode::dialect)
    let m = p.model.to_ascii_uppercase();
    let d = Dialect {
        flavor: p.flavor,
        object_labels: p.object_labels,
        prusa_8bit: m.starts_with("MK3") || m.starts_with("MK2"),
    };
    settings
        .into_iter()
        .map(|s| {
            let c = Command::Set(s);
            let mut out = Chunk::new();
            write::write(d, &c, "", &mut out);
            let text = String::from_utf8_lossy(out.bytes()).trim_end().to_string();
            Verbatim {
                text,
                commands: vec![c],
            }
        })
        .collect()
}

/// Refuses a variable of the template `t` that has no value for this print
/// (a filament preset's setting where the material comes from none): its
/// line and a message naming it and where a value may come from. A variable
/// is refused wherever it stands, a comment line or a branch not taken;
/// a `global` of a template expanded before (the start G-code's) has one.
fn has_values(
    recipe: &Recipe,
    t: &Template,
    vars: &Vars,
    globals: &Vars,
) -> std::result::Result<(), (usize, String)> {
    for (name, line) in t.variables() {
        let base = match name.rsplit_once('_') {
            Some((b, i)) if i.parse::<usize>().is_ok() => b,
            _ => name.as_str(),
        };
        if vars.contains_key(&name) || vars.contains_key(base) || globals.contains_key(&name) {
            continue;
        }
        let m = &recipe.material;
        let why = match &m.preset {
            Some(f) => format!("the filament preset `{}` has no `{name}` either", f.name),
            None => format!(
                "it is a filament preset's setting, and the material `{}` comes from none: give one with --filament FILE [--filament-preset NAME]",
                m.name
            ),
        };
        return Err((
            line,
            format!("the variable `{name}` has no value for this print: {why}, or a value under the profile's `gcode_variables:`"),
        ));
    }
    Ok(())
}

/// Strings per piece of [`extent`]'s work: a fixed size, not a share of
/// the threads, so the pieces (and the volume's sum) are the same on any
/// number of them.
const PIECE: usize = 1 << 15;

/// What one piece of a path's strings adds to the [`Extent`].
#[derive(Clone, Copy)]
struct Piece {
    /// Lowest and highest z of a string that is not a travel.
    drawn: (f64, f64),
    /// The first extruding string's cross-section and speed.
    first: Option<(f64, f64)>,
    max_flow: f64,
    volume: f64,
    /// Lowest and highest extruding z, and the last extruding string's end z.
    low: f64,
    high: f64,
    last: Option<f64>,
    /// The box of its points (its highest z the highest point's), and
    /// whether every one is finite.
    lo: DVec3,
    hi: DVec3,
    finite: bool,
    /// Whether an extruding string's height is not a number (its piece
    /// is looked at for the first layer, as every piece below twice `low`).
    nan: bool,
}

/// The heights and the first layer of `paths`: pieces of their strings
/// measured side by side ([`crate::base::par`]) and put together in print
/// order, then the first layer's strings in the pieces that reach below
/// twice the lowest extrusion.
pub(crate) fn extent(recipe: &Recipe, paths: &[Toolpath]) -> Extent {
    let pieces: Vec<(usize, usize, usize)> = paths
        .iter()
        .enumerate()
        .flat_map(|(i, t)| {
            (0..t.len())
                .step_by(PIECE)
                .map(move |k| (i, k, (k + PIECE).min(t.len())))
        })
        .collect();
    let measure = |&(i, k0, k1): &(usize, usize, usize)| piece(&paths[i], k0, k1);
    // a small print on this thread: its few pieces are not worth waking
    // another (nor the memory a second thread's first allocations take)
    let measured: Vec<Piece> = if pieces.len() < 4 {
        pieces.iter().map(measure).collect()
    } else {
        crate::base::par::map(&pieces, measure)
    };
    let mut e = Extent {
        low: f64::INFINITY,
        high: f64::NEG_INFINITY,
        last: 0.0,
        first_min: [f64::INFINITY; 2],
        first_max: [f64::NEG_INFINITY; 2],
        first_c: 0.0,
        first_v: 0.0,
        max_flow: 0.0,
        end_at: paths.iter().rev().find_map(|t| t.points.last().copied()),
        // a path's last point, after its last piece's strings
        top: paths
            .iter()
            .filter_map(|t| t.points.last().map(|p| p.z))
            .fold(0.0, f64::max),
        ends_retracted: paths.iter().rev().find(|t| !t.is_empty()).is_some_and(|t| {
            let k = t.len() - 1;
            let (a, b) = t.ends(k);
            let r = &recipe.printer.retraction;
            t.strings[k].travel && r.length > 0.0 && a.distance(b) >= r.min_travel
        }),
        volume: 0.0,
        drawn: None,
        points: None,
    };
    // every point: the pieces' (their strings' first ends) and each path's last
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let mut finite = true;
    for q in paths.iter().filter_map(|t| t.points.last()) {
        (lo, hi, finite) = (lo.min(*q), hi.max(*q), finite && q.is_finite());
    }
    let (mut dlo, mut dhi) = (f64::INFINITY, f64::NEG_INFINITY);
    for m in &measured {
        dlo = dlo.min(m.drawn.0);
        dhi = dhi.max(m.drawn.1);
        if let (true, Some((c, v))) = (e.first_c == 0.0, m.first) {
            (e.first_c, e.first_v) = (c, v);
        }
        e.max_flow = e.max_flow.max(m.max_flow);
        e.volume += m.volume;
        e.low = e.low.min(m.low);
        e.high = e.high.max(m.high);
        if let Some(z) = m.last {
            e.last = z;
        }
        e.top = e.top.max(m.hi.z);
        (lo, hi, finite) = (lo.min(m.lo), hi.max(m.hi), finite && m.finite);
    }
    e.points = (finite && lo.cmple(hi).all()).then_some((lo, hi));
    e.drawn = (dlo <= dhi).then_some((dlo, dhi));
    if !e.low.is_finite() {
        // nothing extrudes: every height is the bed's
        (e.low, e.high) = (0.0, 0.0);
        return e;
    }
    // the first layer: strings whose lower end lies below where a second
    // layer of the first one's height would start (only pieces reaching
    // below it can hold one; NaN heights are looked at as before)
    let extruding = |t: &Toolpath, k: usize| !t.strings[k].travel && t.strings[k].c > 0.0;
    let (low, printer) = (e.low, &recipe.printer);
    let near: Vec<(usize, usize, usize)> = pieces
        .iter()
        .zip(&measured)
        .filter(|(_, m)| m.nan || m.low < 2.0 * low)
        .map(|(p, _)| *p)
        .collect();
    let corners = crate::base::par::map(&near, |&(i, k0, k1)| {
        let t = &paths[i];
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for k in k0..k1 {
            let (a, b) = t.ends(k);
            if !extruding(t, k) || a.z.min(b.z) >= 2.0 * low {
                continue;
            }
            for q in [a, b] {
                let m = printer.to_machine(q);
                lo = [lo[0].min(m.x), lo[1].min(m.y)];
                hi = [hi[0].max(m.x), hi[1].max(m.y)];
            }
        }
        (lo, hi)
    });
    for (lo, hi) in corners {
        e.first_min = [e.first_min[0].min(lo[0]), e.first_min[1].min(lo[1])];
        e.first_max = [e.first_max[0].max(hi[0]), e.first_max[1].max(hi[1])];
    }
    e
}

/// What strings `k0..k1` of `t` add to the [`Extent`] (see [`Piece`]).
fn piece(t: &Toolpath, k0: usize, k1: usize) -> Piece {
    let mut m = Piece {
        drawn: (f64::INFINITY, f64::NEG_INFINITY),
        first: None,
        max_flow: 0.0,
        volume: 0.0,
        low: f64::INFINITY,
        high: f64::NEG_INFINITY,
        last: None,
        nan: false,
        lo: DVec3::INFINITY,
        hi: DVec3::NEG_INFINITY,
        finite: true,
    };
    let mut nan = false;
    for k in k0..k1 {
        let p = t.points[k];
        // plain comparisons: f64::min's and max's results (a NaN passed
        // over), without their handling of a NaN bound, which never comes
        for i in 0..3 {
            if p[i] < m.lo[i] {
                m.lo[i] = p[i];
            }
            if p[i] > m.hi[i] {
                m.hi[i] = p[i];
            }
        }
        // min and max pass over NaN: a sum tells it (and inf − inf)
        let sum = p.x + p.y + p.z;
        nan |= sum.is_nan();
        let s = t.strings[k];
        if s.travel {
            continue;
        }
        let (a, b) = t.ends(k);
        let zmin = a.z.min(b.z);
        m.drawn = (m.drawn.0.min(zmin), m.drawn.1.max(a.z.max(b.z)));
        if s.c <= 0.0 || s.c.is_nan() {
            continue;
        }
        if m.first.is_none() {
            m.first = Some((s.c, s.v));
        }
        m.max_flow = m.max_flow.max(s.c * s.v);
        m.volume += s.c * a.distance(b);
        m.low = m.low.min(zmin);
        m.high = m.high.max(a.z.max(b.z));
        m.last = Some(b.z);
        m.nan |= zmin.is_nan();
    }
    m.finite = !nan && m.lo.is_finite() && m.hi.is_finite();
    m
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

/// One value per extruder, `v` for each of `n` (p3dp's one material is
/// the filament of every extruder, as a slicer's one filament preset is).
fn each(n: usize, v: Value) -> Value {
    Value::List(vec![v; n])
}

fn pair(x: f64, y: f64) -> Value {
    Value::List(vec![Value::Float(x), Value::Float(y)])
}

/// The number in a value.
fn number(v: &Value) -> Option<f64> {
    match *v {
        Value::Int(i) => Some(i as f64),
        Value::Float(f) | Value::Shown(f, _) => Some(f),
        _ => None,
    }
}

/// A filament preset's value: its first (a slicer's filament values are
/// per extruder variant; p3dp's one material is the first).
fn first(v: &Value) -> Value {
    match v {
        Value::List(items) => items.first().cloned().unwrap_or(Value::Str(String::new())),
        v => v.clone(),
    }
}

/// The variables of [`crate::machine::VARIABLES`] and
/// [`crate::machine::material::VARIABLES`], the profile's own
/// (`gcode_variables`) and a filament preset's settings; `end` for the end
/// G-code (where `layer_z` is the last point's height). Lists have one value
/// per extruder of the printer.
fn variables(recipe: &Recipe, ext: &Extent, end: bool) -> Vars {
    let p = &recipe.printer;
    let n = p.extruders.max(1);
    let mut v: Vars = p.gcode_variables.clone();
    // a filament preset's every setting, under the profile's and p3dp's own
    if let Some(f) = &recipe.material.preset {
        for (k, val) in &f.settings {
            v.entry(k.clone()).or_insert_with(|| each(n, first(val)));
        }
    }
    let mut set = |name: &str, value: Value| {
        v.insert(name.to_string(), value);
    };
    own(recipe, ext, n, &mut set);
    temperatures(recipe, n, &mut set);
    tools(recipe, ext, end, n, &mut set);
    layers(recipe, ext, end, &mut set);
    machine(recipe, n, &mut set);
    print(recipe, ext, &mut set);
    material(recipe, n, &mut set);
    // a value's text never breaks a line of the G-code (a comment's
    // included): every line break of any kind is written `\u{…}`
    v.into_iter().map(|(k, x)| (k, one_line(x))).collect()
}

/// `v` with every text on one line ([`crate::base::safe_text::one_line`]).
fn one_line(v: Value) -> Value {
    match v {
        Value::Str(s) => Value::Str(crate::base::safe_text::one_line(&s).into_owned()),
        Value::Shown(x, s) => Value::Shown(x, crate::base::safe_text::one_line(&s).into_owned()),
        Value::List(l) => Value::List(l.into_iter().map(one_line).collect()),
        v => v,
    }
}

/// p3dp's own placeholders, written as they always were.
fn own(recipe: &Recipe, ext: &Extent, n: usize, set: &mut impl FnMut(&str, Value)) {
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
    set("filament_diameter", each(n, shown(fd, fmt_num(fd))));
    set(
        "nozzle_diameter",
        each(n, shown(p.nozzle_diameter, fmt_num(p.nozzle_diameter))),
    );
    // positions as the moves write them: fixed point, 3 decimals
    set("bed_x", shown(bx, format!("{bx:.3}")));
    set("bed_y", shown(by, format!("{by:.3}")));
    let max_z = p.bed.max_z();
    set("max_z", shown(max_z, format!("{max_z:.3}")));
    set("park_z", shown(park, format!("{park:.3}")));
}

/// The material's temperatures under every name the slicers use, its type
/// and name.
fn temperatures(recipe: &Recipe, n: usize, set: &mut impl FnMut(&str, Value)) {
    let (p, m) = (&recipe.printer, &recipe.material);
    for name in [
        "first_layer_temperature",
        "temperature",
        "nozzle_temperature_initial_layer",
        "nozzle_temperature",
    ] {
        set(name, each(n, temp(m.nozzle_temp)));
    }
    for name in [
        "first_layer_bed_temperature",
        "bed_temperature",
        "bed_temperature_initial_layer",
    ] {
        set(name, each(n, temp(m.bed_temp)));
    }
    for plate in ["hot", "cool", "eng", "textured"] {
        set(&format!("{plate}_plate_temp"), each(n, temp(m.bed_temp)));
        set(
            &format!("{plate}_plate_temp_initial_layer"),
            each(n, temp(m.bed_temp)),
        );
    }
    set("bed_temperature_initial_layer_single", temp(m.bed_temp));
    // the filament preset's type (PLA, PETG…), else the material's name
    let kind = match m.setting("filament_type").map(first) {
        Some(Value::Str(t)) if !t.is_empty() => t,
        _ => m.name.to_uppercase(),
    };
    set("filament_type", each(n, Value::Str(kind)));
    let id = m.preset.as_ref().map_or(&m.name, |f| &f.name);
    set("filament_settings_id", each(n, Value::Str(id.clone())));
    set("filament_preset", each(n, Value::Str(id.clone())));
    set("printer_settings_id", Value::Str(p.name.clone()));
    set("printer_preset", Value::Str(p.name.clone()));
    set("printer_model", Value::Str(p.model.clone()));
}

/// The tools: p3dp prints with the first (the one the maker's start G-code
/// selects as `initial_tool`), the others unused.
fn tools(recipe: &Recipe, ext: &Extent, end: bool, n: usize, set: &mut impl FnMut(&str, Value)) {
    for name in [
        "initial_tool",
        "initial_extruder",
        "current_extruder",
        "initial_no_support_extruder",
        "initial_no_support_tool",
        "total_toolchanges",
    ] {
        set(name, Value::Int(0));
    }
    set("num_extruders", Value::Int(n as i64));
    let tool = recipe.printer.tool;
    // PrusaSlicer's list is 255 long at least, for templates written for
    // more tools than the machine has (its GCode.cpp)
    let used = (0..n.max(255)).map(|k| Value::Bool(k == tool)).collect();
    set("is_extruder_used", Value::List(used));
    // Bambu's filaments and nozzles: the print's one filament, on `tool`
    set(
        "filament_map",
        Value::List(vec![Value::Int(tool as i64 + 1)]),
    );
    for name in ["first_filaments", "first_non_support_filaments"] {
        set(name, each(n, Value::Int(0)));
    }
    for name in [
        "initial_filament_id",
        "initial_no_support_filament_id",
        "initial_nozzle_id",
        "initial_no_support_hotend",
        "first_non_support_hotend",
        "current_hotend",
    ] {
        set(name, Value::Int(0));
    }
    let d = recipe.printer.nozzle_diameter;
    set("nozzle_diameter_at_nozzle_id", each(n, Value::Float(d)));
    set("has_wipe_tower", Value::Bool(false));
    set(
        "has_single_extruder_multi_material_priming",
        Value::Bool(false),
    );
    // the filament taken back where the template runs: none at the start;
    // at the end, a retraction when the print ends on a long travel
    let r = &recipe.printer.retraction;
    let back = if end && ext.ends_retracted {
        r.length
    } else {
        0.0
    };
    set("e_retracted", each(n, Value::Float(back)));
    set("e_restart_extra", each(n, Value::Float(0.0)));
    set("zhop", Value::Float(0.0));
    set("input_filename_base", Value::Str(recipe.name.clone()));
    set("input_filename", Value::Str(recipe.name.clone()));
}

/// The "layer" values: p3dp prints strings, so they describe the strings.
fn layers(recipe: &Recipe, ext: &Extent, end: bool, set: &mut impl FnMut(&str, Value)) {
    let p = &recipe.printer;
    let h = ext.low.max(0.0);
    set("first_layer_height", Value::Float(h));
    set("initial_layer_print_height", Value::Float(h));
    set("layer_height", Value::Float(h));
    set(
        "layer_z",
        Value::Float(if end { ext.last.max(0.0) } else { h }),
    );
    set("max_layer_z", Value::Float(ext.high.max(0.0)));
    set("max_print_z", Value::Float(ext.high.max(0.0)));
    // the layers a slicer would cut the print's height into at that height
    let count = if h > 0.0 {
        libm::ceil(ext.high / h - 1e-9).max(1.0)
    } else {
        0.0
    };
    set("total_layer_count", Value::Int(count as i64));
    let num = if end { (count - 1.0).max(0.0) } else { 0.0 };
    set("layer_num", Value::Int(num as i64));
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
    set(
        "first_layer_center_no_wipe_tower",
        pair((fmin[0] + fmax[0]) / 2.0, (fmin[1] + fmax[1]) / 2.0),
    );
    set("print_bed_min", pair(bmin[0], bmin[1]));
    set("print_bed_max", pair(bmax[0], bmax[1]));
    set("print_bed_size", pair(bmax[0] - bmin[0], bmax[1] - bmin[1]));
    bed_mesh(recipe, fmin, fmax, set);
}

/// A point of a profile's `gcode_variables` (OrcaSlicer's `bed_mesh_min`:
/// `"x,y"`, `"xXy"` or a list of two numbers).
fn point(v: Option<&Value>) -> Option<[f64; 2]> {
    match v? {
        Value::List(l) if l.len() == 2 => Some([number(&l[0])?, number(&l[1])?]),
        Value::List(l) if l.len() == 1 => point(l.first()),
        Value::Str(s) => {
            let (x, y) = s.split_once([',', 'x', 'X'])?;
            Some([x.trim().parse().ok()?, y.trim().parse().ok()?])
        }
        _ => None,
    }
}

/// OrcaSlicer's adaptive bed mesh, as its documentation states it: the
/// first layer's extent grown by `adaptive_bed_mesh_margin` (0) and kept
/// within `bed_mesh_min`/`bed_mesh_max` (no limit when absent or empty);
/// per axis, the size over `bed_mesh_probe_distance` (50 mm) rounded up,
/// plus one, at least 3 points; `lagrange` below 4 points, else `bicubic`.
fn bed_mesh(recipe: &Recipe, fmin: [f64; 2], fmax: [f64; 2], set: &mut impl FnMut(&str, Value)) {
    let vars = &recipe.printer.gcode_variables;
    let margin = vars
        .get("adaptive_bed_mesh_margin")
        .and_then(number)
        .unwrap_or(0.0);
    let (lo, hi) = match (
        point(vars.get("bed_mesh_min")),
        point(vars.get("bed_mesh_max")),
    ) {
        (Some(a), Some(b)) if b[0] > a[0] && b[1] > a[1] => (a, b),
        _ => ([f64::NEG_INFINITY; 2], [f64::INFINITY; 2]),
    };
    let dist = point(vars.get("bed_mesh_probe_distance")).unwrap_or([50.0, 50.0]);
    let mut min = [0.0; 2];
    let mut max = [0.0; 2];
    let mut count = [0i64; 2];
    for k in 0..2 {
        min[k] = (fmin[k] - margin).clamp(lo[k], hi[k]);
        max[k] = (fmax[k] + margin).clamp(lo[k], hi[k]);
        let d = if dist[k] > 0.0 { dist[k] } else { 50.0 };
        count[k] = (libm::ceil((max[k] - min[k]) / d) as i64 + 1).max(3);
    }
    set("adaptive_bed_mesh_min", pair(min[0], min[1]));
    set("adaptive_bed_mesh_max", pair(max[0], max[1]));
    set(
        "bed_mesh_probe_count",
        Value::List(vec![Value::Int(count[0]), Value::Int(count[1])]),
    );
    let algo = if count[0].min(count[1]) < 4 {
        "lagrange"
    } else {
        "bicubic"
    };
    set("bed_mesh_algo", Value::Str(algo.into()));
}

/// The print's widths, speeds, flow and accelerations, from its strings.
fn print(recipe: &Recipe, ext: &Extent, set: &mut impl FnMut(&str, Value)) {
    let h = ext.low.max(0.0);
    let width = if h > 0.0 { ext.first_c / h } else { 0.0 };
    for name in [
        "extrusion_width",
        "line_width",
        "external_perimeter_extrusion_width",
    ] {
        set(name, Value::Float(width));
    }
    for name in [
        "initial_layer_speed",
        "external_perimeter_speed",
        "outer_wall_speed",
    ] {
        set(name, Value::Float(ext.first_v));
    }
    set("outer_wall_volumetric_speed", Value::Float(ext.max_flow));
    // p3dp's moves print at the machine's own acceleration
    let a = recipe.printer.limits().max_acceleration;
    for name in [
        "default_acceleration",
        "outer_wall_acceleration",
        "initial_layer_acceleration",
    ] {
        set(name, Value::Float(a));
    }
}

/// The machine's values: heights, speeds, retraction, planner limits.
fn machine(recipe: &Recipe, n: usize, set: &mut impl FnMut(&str, Value)) {
    let p = &recipe.printer;
    let f = Value::Float;
    set("max_print_height", f(p.bed.max_z()));
    set("printable_height", f(p.bed.max_z()));
    set("z_offset", f(p.origin[2]));
    set("travel_speed", f(p.travel_speed));
    let r = &p.retraction;
    for name in ["retract_length", "retraction_length"] {
        set(name, each(n, f(r.length)));
    }
    for name in ["retract_speed", "retraction_speed"] {
        set(name, each(n, f(r.speed)));
    }
    for name in ["retract_lift", "z_hop"] {
        set(name, each(n, f(0.0)));
    }
    let l = p.limits();
    set(
        "machine_max_acceleration_extruding",
        each(n, f(l.max_acceleration)),
    );
    set(
        "machine_max_acceleration_travel",
        each(n, f(l.travel_acceleration)),
    );
    set(
        "machine_max_acceleration_retracting",
        each(n, f(l.retract_acceleration)),
    );
    set("machine_max_feedrate_x", each(n, f(l.max_velocity)));
    set("machine_max_feedrate_y", each(n, f(l.max_velocity)));
    set(
        "machine_max_feedrate_z",
        each(n, f(l.max_z_velocity.unwrap_or(l.max_velocity))),
    );
}

/// The material's values ([`crate::machine::material::VARIABLES`]): the
/// filament preset's setting where the material came from one, else what
/// p3dp knows of the material.
fn material(recipe: &Recipe, n: usize, set: &mut impl FnMut(&str, Value)) {
    let (p, m) = (&recipe.printer, &recipe.material);
    let preset = |k: &str| m.setting(k).map(first);
    let positive = |k: &str| preset(k).as_ref().and_then(number).filter(|v| *v > 0.0);
    set("chamber_temperature", each(n, temp(m.chamber_temp)));
    set("overall_chamber_temperature", temp(m.chamber_temp));
    let or = |k: &str, d: Value| each(n, preset(k).unwrap_or(d));
    set(
        "chamber_minimal_temperature",
        or("chamber_minimal_temperature", Value::Int(0)),
    );
    set(
        "filament_abrasive",
        or("filament_abrasive", Value::Bool(false)),
    );
    set(
        "filament_notes",
        or("filament_notes", Value::Str(String::new())),
    );
    set("idle_temperature", or("idle_temperature", Value::Int(0)));
    set(
        "filament_multitool_ramming",
        or("filament_multitool_ramming", Value::Bool(false)),
    );
    let flow = m.max_volumetric_speed.unwrap_or(p.max_flow);
    set("filament_max_volumetric_speed", each(n, Value::Float(flow)));
    set(
        "nozzle_temperature_range_low",
        each(n, temp(m.min_nozzle_temp)),
    );
    set(
        "nozzle_temperature_range_high",
        each(n, temp(m.max_nozzle_temp)),
    );
    // Bambu Studio's rule: the flush's own figure, else the range's top
    // and the filament's flow limit
    let flush = positive("filament_flush_temp").unwrap_or(m.max_nozzle_temp);
    set("flush_temperatures", each(n, temp(flush)));
    let flush_flow = positive("filament_flush_volumetric_speed").unwrap_or(flow);
    set("flush_volumetric_speeds", each(n, Value::Float(flush_flow)));
    if let Some(t) = m.vitrification_temp {
        set("temperature_vitrification", each(n, temp(t)));
        set("min_vitrification_temperature", temp(t));
    }
    let fan = libm::round(m.fan_speed * 100.0);
    set("fan_max_speed", each(n, temp(fan)));
    set("max_fan_speed", each(n, temp(fan)));
    set("filament_density", each(n, Value::Float(m.density)));
    let vendor = match preset("filament_vendor") {
        Some(Value::Str(v)) if !v.is_empty() => v,
        _ => "Generic".to_string(),
    };
    set("is_all_bbl_filament", Value::Bool(vendor == "Bambu Lab"));
    set("filament_vendor", each(n, Value::Str(vendor)));
    if m.preset.is_some() {
        // OrcaSlicer's defaults when a filament preset names none
        set(
            "enable_pressure_advance",
            or("enable_pressure_advance", Value::Bool(false)),
        );
        set(
            "pressure_advance",
            or("pressure_advance", Value::Float(0.02)),
        );
    }
    if let Some(Value::Str(id)) = preset("filament_id") {
        set("filament_ids", each(n, Value::Str(id)));
    }
    let tpu = match preset("filament_type") {
        Some(Value::Str(t)) => t.eq_ignore_ascii_case("TPU"),
        _ => m.name.eq_ignore_ascii_case("tpu"),
    };
    set("has_tpu_in_first_layer", Value::Bool(tpu));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recipe(material: &str) -> Recipe {
        let text = format!("p3dp: 1\nname: t\nmaterial: {material}\nparts:\n  - primitive: {{helix: {{radius: 10, height: 2, pitch: 0.5}}}}\n");
        let raw: crate::recipe::RawRecipe = crate::recipe::parse_yaml(&text, "t.yaml").unwrap();
        crate::recipe::resolve(&raw, &[], None, std::path::Path::new(".")).unwrap()
    }

    /// The first layer's corners as defined: every extruding string whose
    /// lower end lies below twice the lowest extrusion, over every path,
    /// however late the lowest comes (the extent measures them among the
    /// strings below twice the lowest so far).
    #[test]
    fn the_first_layer_is_every_string_below_twice_the_lowest() {
        let r = recipe("pla");
        let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        // a part that starts high, dips to 0.3 late, then climbs; a second
        // that reaches the lowest, 0.2, at its end; a travel and a string
        // of no cross-section low down count for nothing
        let mut a = Toolpath::new(p(0.0, 0.0, 5.0));
        a.draw(p(1.0, 0.0, 5.0), 0.1, 20.0);
        a.draw(p(-7.0, 3.0, 0.35), 0.1, 20.0);
        a.draw(p(-8.0, 3.0, 0.3), 0.1, 20.0);
        a.draw(p(-8.0, 9.0, 3.0), 0.1, 20.0);
        a.travel(p(-30.0, -30.0, 0.0), 100.0);
        a.draw(p(-31.0, -30.0, 0.0), 0.0, 20.0);
        let mut b = Toolpath::new(p(20.0, 0.0, 4.0));
        b.draw(p(21.0, 0.0, 1.0), 0.1, 20.0);
        b.draw(p(22.0, 5.0, 0.2), 0.1, 20.0);
        let paths = [a, b];
        let e = extent(&r, &paths);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for t in &paths {
            for k in 0..t.len() {
                let (u, v) = t.ends(k);
                let s = t.strings[k];
                if s.travel || s.c <= 0.0 || u.z.min(v.z) >= 2.0 * 0.2 {
                    continue;
                }
                for q in [u, v] {
                    let m = r.printer.to_machine(q);
                    lo = [lo[0].min(m.x), lo[1].min(m.y)];
                    hi = [hi[0].max(m.x), hi[1].max(m.y)];
                }
            }
        }
        assert_eq!(e.low, 0.2);
        assert_eq!((e.first_min, e.first_max), (lo, hi));
        // the string from z 0.35 to 0.3 and the one to 0.2 are in it
        let o = r.printer.to_machine(p(-8.0, 3.0, 0.3));
        assert_eq!(e.first_min[0], o.x);
        assert_eq!(e.first_max[0], r.printer.to_machine(p(22.0, 5.0, 0.2)).x);
        assert_eq!(e.top(), 5.0);
    }

    /// A path of several pieces ([`PIECE`] strings each) whose lowest
    /// string comes in a late piece: the pieces put together give the
    /// figures their definitions give over the whole path, the same on one
    /// thread and on two (the volume summed in the same pieces).
    #[test]
    fn pieces_put_together_are_the_whole_path_s_figures() {
        let r = recipe("pla");
        let n = 3 * PIECE + 17;
        let mut t = Toolpath::new(DVec3::new(0.0, 0.0, 9.0));
        for k in 1..=n {
            let a = k as f64 * 0.01;
            // a slow descent to z 0.25 three quarters in, then a climb;
            // a travel every 1000th string
            let z = 0.25 + (k as f64 / n as f64 - 0.75).abs() * 12.0;
            let q = DVec3::new(30.0 * libm::cos(a), 30.0 * libm::sin(a), z);
            if k % 1000 == 0 {
                t.travel(q, 100.0);
            } else {
                t.draw(q, 0.1 + (k % 7) as f64 * 0.01, 20.0 + (k % 5) as f64);
            }
        }
        let paths = [t];
        let t = &paths[0];
        let extruding: Vec<usize> = (0..t.len())
            .filter(|&k| !t.strings[k].travel && t.strings[k].c > 0.0)
            .collect();
        let zmin = |k: usize| t.points[k].z.min(t.points[k + 1].z);
        let low = extruding
            .iter()
            .map(|&k| zmin(k))
            .fold(f64::INFINITY, f64::min);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &k in extruding.iter().filter(|&&k| zmin(k) < 2.0 * low) {
            for q in [t.points[k], t.points[k + 1]] {
                let m = r.printer.to_machine(q);
                lo = [lo[0].min(m.x), lo[1].min(m.y)];
                hi = [hi[0].max(m.x), hi[1].max(m.y)];
            }
        }
        let volume: f64 = extruding
            .iter()
            .map(|&k| t.strings[k].c * t.length(k))
            .sum();
        let last = &t.strings[extruding[0]];
        let one = crate::base::par::on_threads(1, || extent(&r, &paths));
        let two = crate::base::par::on_threads(2, || extent(&r, &paths));
        for e in [one, two] {
            assert_eq!(e.low, low);
            assert!((low - 0.25).abs() < 1e-3, "{low}");
            assert_eq!((e.first_min, e.first_max), (lo, hi));
            assert_eq!((e.first_c, e.first_v), (last.c, last.v));
            assert_eq!(e.last, t.points[*extruding.last().unwrap() + 1].z);
            assert_eq!(e.top(), t.points.iter().map(|p| p.z).fold(0.0, f64::max));
            let (lo, hi) = t
                .points
                .iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(*p), hi.max(*p))
                });
            assert_eq!(e.points, Some((lo, hi)));
            assert!(
                (e.volume - volume).abs() <= 1e-9 * volume,
                "{} {volume}",
                e.volume
            );
        }
        assert_eq!(one.volume.to_bits(), two.volume.to_bits());
        // a point not a number, in any piece: no box (every point is then
        // looked at where the box would have spared it)
        let mut bad = paths[0].clone();
        bad.points[2 * PIECE + 5].y = f64::NAN;
        assert_eq!(extent(&r, &[bad]).points, None);
    }

    /// Every variable the two tables list has a value (a built-in
    /// material's), and nothing else is given.
    #[test]
    fn every_listed_variable_has_a_value() {
        let r = recipe("pla");
        let ext = extent(&r, &[]);
        let v = variables(&r, &ext, false);
        let listed: Vec<&str> = crate::machine::printer::VARIABLES
            .iter()
            .chain(crate::machine::material::VARIABLES)
            .map(|(n, _)| *n)
            .collect();
        for name in &listed {
            // a filament preset's own, for a material from one
            if matches!(
                *name,
                "enable_pressure_advance" | "pressure_advance" | "filament_ids"
            ) {
                continue;
            }
            assert!(v.contains_key(*name), "{name}");
        }
        assert_eq!(v.len(), listed.len() - 3);
        // the tool's list: true for the tool p3dp prints with
        let Value::List(used) = &v["is_extruder_used"] else {
            panic!()
        };
        assert_eq!(used.len(), 255);
        assert_eq!(used[0], Value::Bool(true));
        assert!(used[1..].iter().all(|u| *u == Value::Bool(false)));
        assert_eq!(
            v["temperature_vitrification"],
            Value::List(vec![Value::Int(45)])
        );
    }

    /// A variable whose value p3dp cannot know is refused by name, with where
    /// a value may come from; wherever it stands (a comment line too).
    #[test]
    fn a_variable_without_a_value_is_refused_by_name() {
        let mut r = recipe("{name: mine, density: 1.2, nozzle_temp: 200, bed_temp: 50}");
        r.printer.start_gcode = "G28\n; softens at [temperature_vitrification]\n".into();
        let e = frame(&r, &extent(&r, &[])).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("start_gcode line 2"));
        assert!(
            e.message
                .contains("`temperature_vitrification` has no value for this print")
                && e.message
                    .contains("the material `mine` comes from none: give one with --filament"),
            "{e}"
        );
        // the built-in material's figure
        let mut r = recipe("pla");
        r.printer.start_gcode = "G28\n; softens at [temperature_vitrification]\n".into();
        assert!(frame(&r, &extent(&r, &[]))
            .unwrap()
            .start_text()
            .contains("; softens at 45"));
    }
}
