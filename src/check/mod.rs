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

pub mod collision;
pub mod config;
pub mod first_layer;
pub mod flow;
pub mod grid;
pub mod starvation;
pub mod support;

use glam::DVec3;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::recipe::Recipe;
use crate::toolpath::Toolpath;

pub use config::{CheckLimits, Head};

/// How bad a finding is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Worth knowing (e.g. a short bridge); never fails a build.
    Info,
    /// Printable, but worth a look; fails the build under `--strict`.
    Warning,
    /// Not printable as it stands; fails the build.
    Error,
}

impl Severity {
    /// `info`, `warning` or `error`.
    pub fn word(self) -> &'static str {
        match self {
            Severity::Info => "info",
            Severity::Warning => "warning",
            Severity::Error => "error",
        }
    }
}

/// Every code a finding may carry, with what it means (for `allow:` and docs).
pub const CODES: &[(&str, &str)] = &[
    ("non-finite", "a point is not a finite number (error)"),
    ("out-of-bed", "a point lies outside the bed (error)"),
    ("below-bed", "a point lies below z = 0 (error)"),
    ("above-max-z", "a point lies above the highest reachable z (error)"),
    ("nozzle-temp", "the nozzle temperature is above the material's or printer's limit (error)"),
    ("bed-temp", "the bed temperature is above the printer's limit (error)"),
    ("speed", "a string runs faster than the printer's max_speed (error)"),
    ("flow", "c·v above the hot end's max_flow (warning; error past checks.flow_hard_max × max_flow)"),
    ("over-extrusion", "a cross-section far above what the nozzle lays (warning; error past the hard limit)"),
    ("thin-string", "a cross-section so small the string breaks (warning; error past the hard limit)"),
    ("starvation", "runs of moves shorter in time than the planner's minimum segment time (warning)"),
    ("unsupported", "filament with neither the bed nor earlier filament under it (error)"),
    ("first-layer", "the nozzle closer to the bed than checks.first_layer_min × its diameter (warning); each part's bed contact is in the report and the stats' first_layer"),
    ("bridge", "a string spanning a gap between supported ends (info; warning when longer than checks.max_bridge)"),
    ("nozzle-collision", "the nozzle's cone passes through filament printed earlier (error)"),
    ("head-collision", "the head's box passes through filament printed earlier (warning: the box is an estimate)"),
    ("pattern-range", "a pattern_helix parameter outside the paper's ranges (warning)"),
    ("pattern-modulated", "a pattern_helix whose strings are modulated (warning)"),
];

/// The machine's safety limits: a move outside the printer's volume, a
/// temperature past a limit, a speed past the axes' or a point that is no
/// number. No `allow:` or `--allow` silences them; only `--force` writes past
/// them, so a shared recipe can never switch them off for its user.
pub const SAFETY: &[&str] = &[
    "non-finite",
    "out-of-bed",
    "below-bed",
    "above-max-z",
    "nozzle-temp",
    "bed-temp",
    "speed",
];

/// Whether `code` is one of [`CODES`].
pub fn is_code(code: &str) -> bool {
    CODES.iter().any(|(c, _)| *c == code)
}

/// Checks the codes of an allow list; `place(i)` names entry i in errors.
pub fn validate_allow(codes: &[String], place: impl Fn(usize) -> String) -> Result<()> {
    for (i, c) in codes.iter().enumerate() {
        if !is_code(c) {
            let known: Vec<&str> = CODES.iter().map(|(c, _)| *c).collect();
            return Err(Error::input(
                place(i),
                format!(
                    "unknown check code `{c}`; expected one of {}",
                    known.join(", ")
                ),
            ));
        }
        if SAFETY.contains(&c.as_str()) {
            return Err(Error::input(
                place(i),
                format!(
                    "`{c}` is a safety limit of the machine and cannot be allowed; \
                     expected a code other than {}; `--force` writes the G-code past it",
                    SAFETY.join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// Removes the findings whose code is in `allow` (silenced for this build).
pub fn apply_allow(findings: &mut Vec<Finding>, allow: &[String]) {
    if !allow.is_empty() {
        findings.retain(|f| !allow.iter().any(|a| a == f.code));
    }
}

/// `3 warnings, 0 errors` (and `, 2 notes` when there are infos).
pub fn summary(findings: &[Finding]) -> String {
    let count = |s: Severity| findings.iter().filter(|f| f.severity == s).count();
    let (e, w, i) = (
        count(Severity::Error),
        count(Severity::Warning),
        count(Severity::Info),
    );
    let pl = |n: usize| if n == 1 { "" } else { "s" };
    let mut s = format!("{w} warning{}, {e} error{}", pl(w), pl(e));
    if i > 0 {
        s.push_str(&format!(", {i} note{}", pl(i)));
    }
    s
}

/// One finding: a stable code, a severity and the place.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Finding {
    /// Stable code, e.g. `out-of-bed`.
    pub code: &'static str,
    /// Warning or error.
    pub severity: Severity,
    /// What was found, with numbers.
    pub message: String,
    /// The part's name, when the finding is in one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub part: Option<String>,
    /// Index of the first string concerned.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub string: Option<usize>,
    /// Recipe coordinates of the first place concerned.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at: Option<[f64; 3]>,
}

pub(crate) fn fmt_p(p: DVec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z)
}

/// Runs every check on the toolpaths of `recipe` (skirt first, then parts):
/// the findings, and each part's footprint on the bed (none when a point is
/// not finite or out of reach, where the geometric checks do not run).
///
/// The support check, the costliest, runs on a second thread beside the
/// others; the findings are put together in one fixed order, so they are the
/// same whether or not a second core is there.
pub fn run(recipe: &Recipe, paths: &[&Toolpath]) -> (Vec<Finding>, Vec<first_layer::Footprint>) {
    run_allowing(recipe, paths, &recipe.allow)
}

/// [`run`], with `allowed` the check codes silenced for this build: the
/// cheap checks run first, and the geometric ones (support, first layer,
/// collision: their grids grow with the extent and the cross-sections) only
/// when the cheap ones found no error that is not allowed. A helix of radius
/// 1e4 mm or a cross-section of 1e7 mm² took 25 s and 5 GB before they
/// refused it.
pub fn run_allowing(
    recipe: &Recipe,
    paths: &[&Toolpath],
    allowed: &[String],
) -> (Vec<Finding>, Vec<first_layer::Footprint>) {
    let mut out = Vec::new();
    temperatures(recipe, &mut out);
    for tp in paths {
        machine_limits(recipe, tp, &mut out);
        strings(recipe, tp, &mut out);
        flow::cross_sections(recipe, tp, &mut out);
        out.extend(events(recipe, tp));
    }
    let cheap_error = out
        .iter()
        .any(|f| f.severity == Severity::Error && !allowed.iter().any(|a| a == f.code));
    // the geometric checks need finite points within reach (others are errors)
    let sane = |p: &DVec3| p.is_finite() && p.abs().max_element() < 1e5;
    let geometric = !cheap_error && paths.iter().all(|tp| tp.points.iter().all(sane));
    std::thread::scope(|s| {
        let support = geometric.then(|| {
            s.spawn(|| {
                let mut v = Vec::new();
                support::check(recipe, paths, &mut v);
                v
            })
        });
        starvation::check(recipe, paths, &mut out);
        let mut collisions = Vec::new();
        let mut footprints = Vec::new();
        if geometric {
            footprints = first_layer::check(recipe, paths, &mut out);
            collision::check(recipe, paths, &mut collisions);
        }
        if let Some(h) = support {
            out.extend(h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)));
        }
        out.extend(collisions);
        // pattern_helix: parameters outside the paper's ranges, modulated strings
        crate::primitive::pattern::findings(recipe, paths, &mut out);
        (out, footprints)
    })
}

/// Temperature events (a turtle's `nozzle_temp`, `bed_temp`) above the limits: a nozzle temperature above the
/// material's or printer's limit (`nozzle-temp`), a bed temperature above the
/// printer's (`bed-temp`); one finding per part and kind, naming the first.
pub fn events(recipe: &Recipe, tp: &Toolpath) -> Vec<Finding> {
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
        });
    };
    let pick = |bed: bool, limit: f64| -> Vec<(usize, f64)> {
        tp.events
            .iter()
            .filter_map(|&(k, e)| match e {
                crate::toolpath::Event::NozzleTemp { celsius, .. } if !bed && celsius > limit => {
                    Some((k, celsius))
                }
                crate::toolpath::Event::BedTemp { celsius, .. } if bed && celsius > limit => {
                    Some((k, celsius))
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
        });
    }
}

/// Counts points failing `bad` and reports the first.
fn points_where(
    tp: &Toolpath,
    code: &'static str,
    what: &str,
    bad: impl Fn(DVec3) -> bool,
    recipe: &Recipe,
    out: &mut Vec<Finding>,
) {
    let mut first = None;
    let mut count = 0usize;
    for (i, p) in tp.points.iter().enumerate() {
        if bad(*p) {
            count += 1;
            first.get_or_insert(i);
        }
    }
    if let Some(i) = first {
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
        });
    }
}

fn machine_limits(recipe: &Recipe, tp: &Toolpath, out: &mut Vec<Finding>) {
    let printer = &recipe.printer;
    points_where(
        tp,
        "non-finite",
        "that are not finite numbers (NaN or infinite)",
        |p| !p.is_finite(),
        recipe,
        out,
    );
    let bed = printer.bed;
    points_where(
        tp,
        "out-of-bed",
        &format!("outside the {} bed", bed.describe()),
        |p| p.is_finite() && !bed.contains_xy(printer.to_machine(p)),
        recipe,
        out,
    );
    points_where(
        tp,
        "below-bed",
        "below the bed (z < 0)",
        |p| printer.to_machine(p).z < 0.0,
        recipe,
        out,
    );
    let max_z = bed.max_z();
    points_where(
        tp,
        "above-max-z",
        &format!("above the highest reachable z of {max_z} mm"),
        |p| printer.to_machine(p).z > max_z,
        recipe,
        out,
    );
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
                "part `{}` has {n} string{} needing more than the hot end's {} mm³/s (up to {worst:.1} mm³/s{beyond}); the first is string {k} at {}",
                tp.name,
                if n == 1 { "" } else { "s" },
                p.max_flow,
                fmt_p(m)
            ),
            part: Some(tp.name.clone()),
            string: Some(k),
            at: Some(m.to_array()),
        });
    }
}

/// Errors, and warnings when `strict`: the findings that fail a build (infos never do).
pub fn failing(findings: &[Finding], strict: bool) -> Vec<&Finding> {
    findings
        .iter()
        .filter(|f| f.severity == Severity::Error || (strict && f.severity == Severity::Warning))
        .collect()
}
