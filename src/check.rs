//! Printability and safety checks on the strings before any G-code is written.
//!
//! G-code drives a hot machine: a move outside the bed, below it or above the
//! reachable height, or a temperature past the material's or the printer's
//! limit, is an error; the build writes nothing unless the user forces it.

use glam::DVec3;
use serde::Serialize;

use crate::recipe::Recipe;
use crate::toolpath::Toolpath;

/// How bad a finding is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Printable, but worth a look; fails the build under `--strict`.
    Warning,
    /// Not printable as it stands; fails the build.
    Error,
}

impl Severity {
    /// `warning` or `error`.
    pub fn word(self) -> &'static str {
        match self {
            Severity::Warning => "warning",
            Severity::Error => "error",
        }
    }
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

fn fmt_p(p: DVec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z)
}

/// Runs every check on the toolpaths of `recipe` (skirt first, then parts).
pub fn run(recipe: &Recipe, paths: &[&Toolpath]) -> Vec<Finding> {
    let mut out = Vec::new();
    temperatures(recipe, &mut out);
    for tp in paths {
        machine_limits(recipe, tp, &mut out);
        strings(recipe, tp, &mut out);
    }
    // pattern_helix: parameters outside the paper's ranges, modulated strings
    crate::primitive::pattern::findings(recipe, paths, &mut out);
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
                "{count} point{} of part `{}` {what}; the first, point {i}, is at recipe {} = machine {}",
                if count == 1 { "" } else { "s" },
                tp.name,
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
        "are not finite numbers",
        |p| !p.is_finite(),
        recipe,
        out,
    );
    let bed = printer.bed;
    points_where(
        tp,
        "out-of-bed",
        &format!("lie outside the {} bed", bed.describe()),
        |p| p.is_finite() && !bed.contains_xy(printer.to_machine(p)),
        recipe,
        out,
    );
    points_where(
        tp,
        "below-bed",
        "lie below the bed (z < 0)",
        |p| printer.to_machine(p).z < 0.0,
        recipe,
        out,
    );
    let max_z = bed.max_z();
    points_where(
        tp,
        "above-max-z",
        &format!("lie above the highest reachable z of {max_z} mm"),
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
                "{n} strings of part `{}` run faster than printer {}'s {} mm/s; the first, string {k} at {}, at {:.1} mm/s",
                tp.name,
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
        out.push(Finding {
            code: "flow",
            severity: Severity::Warning,
            message: format!(
                "{n} strings of part `{}` need more than the hot end's {} mm³/s (up to {worst:.1} mm³/s); the first is string {k} at {}",
                tp.name,
                p.max_flow,
                fmt_p(m)
            ),
            part: Some(tp.name.clone()),
            string: Some(k),
            at: Some(m.to_array()),
        });
    }
}

/// Errors, and warnings when `strict`: the findings that fail a build.
pub fn failing(findings: &[Finding], strict: bool) -> Vec<&Finding> {
    findings
        .iter()
        .filter(|f| f.severity == Severity::Error || strict)
        .collect()
}
