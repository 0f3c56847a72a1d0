//! Printability and safety checks on the strings before any G-code is written.
//!
//! G-code drives a hot machine: a move outside the bed, below it or above the
//! reachable height, or a temperature past the material's or the printer's
//! limit, is an error; the build writes nothing unless the user forces it.
//! Beyond the machine's limits the checks test Kanada's two conditions for
//! printing parts one after another (every string rests on the bed or on
//! filament printed before it: [`support`]; the head never meets printed
//! filament: [`collision`]), the flow a hot end can melt and lay ([`flow`]),
//! and runs of moves too short for the firmware's planner ([`starvation`]).

pub(crate) mod collision;
pub(crate) mod first_layer;
pub(crate) mod flow;
pub(crate) mod gcode;
pub(crate) mod package;
pub(crate) mod pattern;
pub(crate) mod starvation;
pub(crate) mod support;
pub(crate) mod tasks;

use glam::DVec3;

pub(crate) use crate::base::finding::{
    apply_allow, failing, summary, validate_allow, Finding, Severity,
};

use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;

pub(crate) use crate::machine::Head;

pub(crate) fn fmt_p(p: DVec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z)
}

/// Refuses toolpaths that reach farther from the machine than its own size
/// (the largest of the bed's sides and its height) in any direction, or
/// that are not finite: previews and meshes sample the strings along their
/// length, so their work grows with the coordinates (a helix of radius 1e8
/// mm would take minutes and gigabytes) while a model near the bed, even
/// off it, is drawn as it is. `what` names the output (`preview`, `mesh`).
///
/// `known`: the box of every point when it is known ([`Extent`]'s, all
/// finite): within reach, the points are not looked at one by one (q = p +
/// origin rounds monotonically, so the box's corners bound every q).
///
/// [`Extent`]: crate::analyse::frame::Extent
pub(crate) fn within_reach(
    recipe: &Recipe,
    paths: &[Toolpath],
    known: Option<(DVec3, DVec3)>,
    what: &str,
) -> crate::base::error::Result<()> {
    let printer = &recipe.printer;
    let bed = printer.bed;
    let max_z = bed.max_z();
    let (lo, hi, reach) = match bed {
        crate::machine::Bed::Rectangle { size, .. } => {
            let m = size[0].max(size[1]).max(max_z);
            (
                DVec3::new(-m, -m, -m),
                DVec3::new(size[0] + m, size[1] + m, max_z + m),
                m,
            )
        }
        crate::machine::Bed::Circle { diameter, .. } => {
            let m = diameter.max(max_z);
            let r = diameter / 2.0 + m;
            (DVec3::new(-r, -r, -m), DVec3::new(r, r, max_z + m), m)
        }
    };
    if let Some((a, b)) = known {
        let (a, b) = (printer.to_machine(a), printer.to_machine(b));
        if a.cmpge(lo).all() && b.cmple(hi).all() {
            return Ok(());
        }
    }
    for tp in paths {
        for p in &tp.points {
            let q = printer.to_machine(*p);
            if !(q.is_finite() && q.cmpge(lo).all() && q.cmple(hi).all()) {
                return Err(crate::base::error::Error::input(
                    "",
                    format!(
                        "part `{}` reaches {} (machine coordinates {}), farther than {reach} mm from the printer's {} bed; a {what} is drawn of what lies near the machine: expected points within {reach} mm of it",
                        crate::base::safe_text::one_line(&tp.name),
                        fmt_p(*p),
                        fmt_p(q),
                        bed.describe()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Runs every check on the toolpaths of `recipe` (skirt first, then parts),
/// one after the other: the findings, and each part's footprint on the bed.
///
/// The cheap checks run first ([`cheap`]), and the costly ones only when
/// [`Cheap::geometric`] allows (their grids grow with the extent and the
/// cross-sections: a helix of radius 1e4 mm would have them fill memory
/// before the cheap ones refuse it). The costly checks are plain functions
/// of the parts, independent of each other ([`Costly`] lists them), so the
/// application may run them side by side; [`merge`] puts their findings in
/// one fixed order; each message ends with [`see`].
#[cfg(any(test, feature = "testing"))]
pub(crate) fn run(
    recipe: &Recipe,
    paths: &[&Toolpath],
    allowed: &[String],
) -> (Vec<Finding>, Vec<first_layer::Footprint>) {
    let tasks = tasks::Tasks::new(recipe, paths.to_vec(), allowed.to_vec());
    for t in tasks::Task::ORDER {
        tasks.run(t);
    }
    tasks.merged()
}

/// What the cheap checks found (one pass over each part's points and
/// strings): the machine's limits, speeds and flows, cross-sections, events;
/// the pattern helix's parameters.
pub(crate) struct Cheap {
    /// Their findings, in order.
    pub(crate) findings: Vec<Finding>,
    /// The pattern helix's, put last when merged.
    pub(crate) pattern: Vec<Finding>,
    /// Whether the costly checks may run: no error that is not allowed, and
    /// every point finite and within reach of the geometry.
    pub(crate) geometric: bool,
}

/// The cheap checks of `paths`; `allowed` are the codes silenced (an error
/// of theirs does not stop the costly checks).
pub(crate) fn cheap(recipe: &Recipe, paths: &[&Toolpath], allowed: &[String]) -> Cheap {
    let mut out = Vec::new();
    temperatures(recipe, &mut out);
    // the geometric checks need finite points within reach (others are
    // errors): tested in the machine limits' pass over the points
    let mut sane = true;
    for tp in paths {
        sane &= machine_limits(recipe, tp, &mut out);
        strings(recipe, tp, &mut out);
        flow::cross_sections(recipe, tp, &mut out);
        flow::klipper_moves(recipe, tp, &mut out);
        out.extend(events(recipe, tp));
        out.extend(settings(recipe, tp));
    }
    let cheap_error = out
        .iter()
        .any(|f| f.severity == Severity::Error && !allowed.iter().any(|a| a == f.code));
    // pattern_helix: parameters outside the paper's ranges, modulated strings
    let mut pattern = Vec::new();
    pattern::findings(recipe, paths, &mut pattern);
    Cheap {
        findings: out,
        pattern,
        geometric: !cheap_error && sane,
    }
}

/// The costly checks' findings, each from a plain function of the parts
/// ([`tasks`] runs them): [`support::check`], [`collision::check`],
/// [`starvation::check`], and the first layer's two halves
/// ([`first_layer::Bed::contacts`] and [`first_layer::Bed::areas`], put
/// together by [`first_layer::findings`]).
#[derive(Default)]
pub(crate) struct Costly {
    /// Runs of moves too short for the firmware's planner.
    pub(crate) starvation: Vec<Finding>,
    /// The first layer's hold on the bed.
    pub(crate) first_layer: Vec<Finding>,
    /// Strings that rest on nothing, and bridges.
    pub(crate) support: Vec<Finding>,
    /// The head meeting printed filament.
    pub(crate) collision: Vec<Finding>,
    /// Each part's footprint on the bed.
    pub(crate) footprints: Vec<first_layer::Footprint>,
}

/// Every finding in the one fixed order (the cheap checks', starvation,
/// first layer, support, collision, the pattern helix's), each message
/// ending with [`see`], and the parts' footprints.
pub(crate) fn merge(cheap: Cheap, costly: Costly) -> (Vec<Finding>, Vec<first_layer::Footprint>) {
    let mut out = cheap.findings;
    for v in [
        costly.starvation,
        costly.first_layer,
        costly.support,
        costly.collision,
        cheap.pattern,
    ] {
        out.extend(v);
    }
    for f in &mut out {
        f.message.push_str(&see(f.code));
    }
    (out, costly.footprints)
}

/// `; see: p3dp explain CODE`: the end of every finding's message, where
/// the user reads what the code means and how to fix it.
pub(crate) fn see(code: &str) -> String {
    format!("; see: p3dp explain {code}")
}

/// Temperature events (a turtle's `nozzle_temp`, `bed_temp`) above the limits: a nozzle temperature above the
/// material's or printer's limit (`nozzle-temp`), a bed temperature above the
/// printer's (`bed-temp`); one finding per part and kind, naming the first.
pub(crate) fn events(recipe: &Recipe, tp: &Toolpath) -> Vec<Finding> {
    let (m, p) = (&recipe.material, &recipe.printer);
    let nozzle_max = m.max_nozzle_temp.min(p.max_nozzle_temp);
    let mut out = Vec::new();
    let mut report = |code: &'static str, what: &str, limit: f64, hot: Vec<(usize, f64)>| {
        let Some(&(k, t)) = hot.first() else { return };
        let at = tp.points[k.min(tp.points.len() - 1)];
        out.push(Finding {
            code,
            severity: Severity::Error,
            message: format!(
                "part `{}` has {} {what} command{} asking for more than {limit} °C; the first, before string {k} at {}, for {t} °C",
                tp.name,
                hot.len(),
                if hot.len() == 1 { "" } else { "s" },
                fmt_p(at)
            ),
            part: Some(tp.name.clone()),
            string: Some(k),
            at: Some(at.to_array()),
            strings: Vec::new(),
        });
    };
    let pick = |bed: bool, limit: f64| -> Vec<(usize, f64)> {
        tp.events
            .iter()
            .filter_map(|(k, e)| match *e {
                crate::base::toolpath::Event::NozzleTemp { celsius, .. }
                    if !bed && celsius > limit =>
                {
                    Some((*k, celsius))
                }
                crate::base::toolpath::Event::BedTemp { celsius, .. } if bed && celsius > limit => {
                    Some((*k, celsius))
                }
                _ => None,
            })
            .collect()
    };
    report(
        "nozzle-temp",
        "nozzle_temp",
        nozzle_max,
        pick(false, nozzle_max),
    );
    report(
        "bed-temp",
        "bed_temp",
        p.max_bed_temp,
        pick(true, p.max_bed_temp),
    );
    out
}

/// A part's settings from `set` steps and commands (`setting`): each one
/// the printer's firmware has a command for, each value within the
/// material's and the machine's limits; one finding per part, naming the
/// first at fault, its band or the key path of its command, and how many
/// are.
pub(crate) fn settings(recipe: &Recipe, tp: &Toolpath) -> Vec<Finding> {
    let (m, p) = (&recipe.material, &recipe.printer);
    type Fault<'a> = (usize, Option<u32>, Option<&'a str>, String);
    let faults: Vec<Fault> = tp
        .events
        .iter()
        .filter_map(|(k, e)| match e {
            crate::base::toolpath::Event::Set {
                setting,
                band,
                place,
            } => gcode::setting(setting, p, m)
                .err()
                .map(|why| (*k, band.map(|b| b.index), place.as_deref(), why)),
            _ => None,
        })
        .collect();
    let Some((k, band, place, why)) = faults.first() else {
        return Vec::new();
    };
    let at = tp.points[(*k + 1).min(tp.points.len() - 1)];
    let band = band.map_or(String::new(), |b| format!(" (band {b})"));
    let band = match place {
        Some(place) => format!("{band}, set by `{place}`,"),
        None => band,
    };
    vec![Finding {
        code: "setting",
        severity: Severity::Error,
        message: format!(
            "part `{}` has {} setting{} the printer {} refuses; the first, before string {k}{band} at {}: {why}",
            tp.name,
            faults.len(),
            if faults.len() == 1 { "" } else { "s" },
            p.name,
            fmt_p(at)
        ),
        part: Some(tp.name.clone()),
        string: Some(*k),
        at: Some(at.to_array()),
        strings: Vec::new(),
    }]
}

fn temperatures(recipe: &Recipe, out: &mut Vec<Finding>) {
    let (m, p) = (&recipe.material, &recipe.printer);
    let limit = m.max_nozzle_temp.min(p.max_nozzle_temp);
    if m.nozzle_temp > limit {
        out.push(Finding {
            code: "nozzle-temp",
            severity: Severity::Error,
            message: format!(
                "material.nozzle_temp {} °C is above the limit of {limit} °C (material {} allows {} °C, printer {} allows {} °C)",
                m.nozzle_temp, m.name, m.max_nozzle_temp, p.name, p.max_nozzle_temp
            ),
            part: None,
            string: None,
            at: None,
            strings: Vec::new(),
        });
    }
    if m.bed_temp > p.max_bed_temp {
        out.push(Finding {
            code: "bed-temp",
            severity: Severity::Error,
            message: format!(
                "material.bed_temp {} °C is above printer {}'s limit of {} °C",
                m.bed_temp, p.name, p.max_bed_temp
            ),
            part: None,
            string: None,
            at: None,
            strings: Vec::new(),
        });
    }
}

/// Counts the points failing each of the `N` tests of `bad` (one pass over
/// the points, which is what costs on millions of them) and reports the
/// first of each, in the order of `what`: (code, what the points are).
/// Returns whether every point is finite and within 10⁵ mm of the origin on
/// each axis (what the geometric checks need), found in the same pass.
fn points_where<const N: usize>(
    tp: &Toolpath,
    what: [(&'static str, &str); N],
    bad: impl Fn(DVec3) -> [bool; N],
    recipe: &Recipe,
    out: &mut Vec<Finding>,
) -> bool {
    let mut first = [None; N];
    let mut count = [0usize; N];
    let mut sane = true;
    for (i, p) in tp.points.iter().enumerate() {
        sane &= p.is_finite() && p.abs().max_element() < 1e5;
        let b = bad(*p);
        for t in 0..N {
            if b[t] {
                count[t] += 1;
                first[t].get_or_insert(i);
            }
        }
    }
    for (t, (code, what)) in what.into_iter().enumerate() {
        let Some(i) = first[t] else { continue };
        let count = count[t];
        let p = tp.points[i];
        out.push(Finding {
            code,
            severity: Severity::Error,
            message: format!(
                "part `{}` has {count} point{} {what}; the first, point {i}, is at recipe {} = machine {}",
                tp.name,
                if count == 1 { "" } else { "s" },
                fmt_p(p),
                fmt_p(recipe.printer.to_machine(p))
            ),
            part: Some(tp.name.clone()),
            string: Some(i.saturating_sub(1)),
            at: Some(p.to_array()),
            strings: Vec::new(),
        });
    }
    sane
}

/// The points outside the machine's reach; whether all are sane (see
/// [`points_where`]).
fn machine_limits(recipe: &Recipe, tp: &Toolpath, out: &mut Vec<Finding>) -> bool {
    let printer = &recipe.printer;
    let bed = printer.bed;
    let max_z = bed.max_z();
    let outside = format!("outside the {} bed", bed.describe());
    let above = format!("above the highest reachable z of {max_z} mm");
    points_where(
        tp,
        [
            (
                "non-finite",
                "that are not finite numbers (NaN or infinite)",
            ),
            ("out-of-bed", &outside),
            ("below-bed", "below the bed (z < 0)"),
            ("above-max-z", &above),
        ],
        |p| {
            let m = printer.to_machine(p);
            let finite = p.is_finite();
            [
                !finite,
                finite && !bed.contains_xy(m),
                m.z < 0.0,
                m.z > max_z,
            ]
        },
        recipe,
        out,
    )
}

/// Filament fed in place (a blob, `extrude_volume`) melts as fast as it is
/// fed: its flow, the feed times the filament's cross-section, counts in
/// `flow` (first string, count, worst) as a string's c·v does.
fn in_place_flow(recipe: &Recipe, tp: &Toolpath, flow: &mut Option<(usize, usize, f64)>) {
    let area = support::filament_area(recipe);
    for (k, e) in &tp.events {
        if let crate::base::toolpath::Event::Extrude { filament, speed } = *e {
            let q = speed * area;
            if filament > 0.0 && q > recipe.printer.max_flow {
                let k = (*k).min(tp.len().saturating_sub(1));
                let e = flow.get_or_insert((k, 0, 0.0));
                e.1 += 1;
                e.2 = e.2.max(q);
            }
        }
    }
}

fn strings(recipe: &Recipe, tp: &Toolpath, out: &mut Vec<Finding>) {
    let p = &recipe.printer;
    let mut fast: Option<(usize, usize)> = None;
    let mut flow: Option<(usize, usize, f64)> = None;
    for (k, s) in tp.strings.iter().enumerate() {
        if s.travel {
            continue;
        }
        if s.v > p.max_speed {
            let e = fast.get_or_insert((k, 0));
            e.1 += 1;
        }
        let q = s.c * s.v;
        if q > p.max_flow {
            let e = flow.get_or_insert((k, 0, 0.0));
            e.1 += 1;
            e.2 = e.2.max(q);
        }
    }
    in_place_flow(recipe, tp, &mut flow);
    if let Some((k, n)) = fast {
        let m = tp.midpoint(k);
        out.push(Finding {
            code: "speed",
            severity: Severity::Error,
            message: format!(
                "part `{}` has {n} string{} faster than printer {}'s {} mm/s; the first, string {k} at {}, at {:.1} mm/s",
                tp.name,
                if n == 1 { "" } else { "s" },
                p.name,
                p.max_speed,
                fmt_p(m),
                tp.strings[k].v
            ),
            part: Some(tp.name.clone()),
            string: Some(k),
            at: Some(m.to_array()),
            strings: Vec::new(),
        });
    }
    if let Some((k, n, worst)) = flow {
        let m = tp.midpoint(k);
        // past the hard limit the hot end cannot melt the filament: a clog
        let hard = p.checks.flow_hard_max * p.max_flow;
        let (severity, beyond) = if worst > hard {
            (
                Severity::Error,
                format!(", past the hard limit of {hard:.1} mm³/s"),
            )
        } else {
            (Severity::Warning, String::new())
        };
        out.push(Finding {
            code: "flow",
            severity,
            message: format!(
                "part `{}` has {n} string{} or in-place extrusion{} needing more than the hot end's {} mm³/s (up to {worst:.1} mm³/s{beyond}); the first is at string {k}, {}",
                tp.name,
                if n == 1 { "" } else { "s" },
                if n == 1 { "" } else { "s" },
                p.max_flow,
                fmt_p(m)
            ),
            part: Some(tp.name.clone()),
            string: Some(k),
            at: Some(m.to_array()),
            strings: Vec::new(),
        });
    }
}
