//! Cross-sections a nozzle can lay: far above nozzle² the nozzle cannot
//! shape the bead (it floods and clogs), far below it the string breaks.
//! Warnings past `checks.cross_section_max` / `_min` (× nozzle²), errors past
//! the hard limits; a declared hair (`hair:`) is thin on purpose and never
//! `thin-string` (it may still be `over-extrusion`). The volumetric flow c·v is checked in [`super::run`]'s
//! `flow` (the hot end's `max_flow`); [`klipper_moves`] holds a Klipper
//! printer's strings to its extruder's own limits.

use super::{fmt_p, Finding, Severity};
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;

/// Strings of one kind: count, first, extreme.
struct Tally {
    n: usize,
    first: usize,
    extreme: f64,
    hard: bool,
    /// The strings counted, as runs [first, end).
    spans: Vec<[usize; 2]>,
}

impl Tally {
    /// Counts string `k` of cross-section `c` into `slot`, keeping the
    /// extreme by `pick` (max or min) and whether any passed the hard limit.
    fn count(slot: &mut Option<Tally>, k: usize, c: f64, hard: bool, pick: fn(f64, f64) -> f64) {
        let t = slot.get_or_insert(Tally {
            n: 0,
            first: k,
            extreme: c,
            hard: false,
            spans: Vec::new(),
        });
        match t.spans.last_mut() {
            Some(last) if last[1] == k => last[1] = k + 1,
            _ => t.spans.push([k, k + 1]),
        }
        t.n += 1;
        t.extreme = pick(t.extreme, c);
        t.hard |= hard;
    }

    /// The finding of these strings of `tp`: an error past the hard limit,
    /// else a warning; `what` says how their cross-sections are off.
    fn finding(&self, tp: &Toolpath, code: &'static str, what: &str) -> Finding {
        let m = tp.midpoint(self.first);
        Finding {
            code,
            severity: if self.hard { Severity::Error } else { Severity::Warning },
            message: format!(
                "part `{}` has {} string{} with cross-sections {what}; the first is string {} at {}",
                tp.name,
                self.n,
                if self.n == 1 { "" } else { "s" },
                self.first,
                fmt_p(m)
            ),
            part: Some(tp.name.clone()),
            string: Some(self.first),
            at: Some(m.to_array()),
            strings: self.spans.clone(),
        }
    }
}

/// The `over-extrusion` and `thin-string` findings of one path.
pub(crate) fn cross_sections(recipe: &Recipe, tp: &Toolpath, out: &mut Vec<Finding>) {
    let p = &recipe.printer;
    let n2 = p.nozzle_diameter * p.nozzle_diameter;
    let lim = &p.checks;
    let (hi, hard_hi) = (lim.cross_section_max * n2, lim.cross_section_hard_max * n2);
    let (lo, hard_lo) = (lim.cross_section_min * n2, lim.cross_section_hard_min * n2);
    let mut over: Option<Tally> = None;
    let mut thin: Option<Tally> = None;
    for (k, s) in tp.strings.iter().enumerate() {
        if s.travel || !s.c.is_finite() {
            continue;
        }
        // a declared hair is thin on purpose (toolpath::Strand::hair)
        let (too_thick, too_thin) = (s.c > hi, s.c < lo && !s.hair);
        // a string of no length counts for neither: measured only when it
        // would count (a pass over the points saved on most paths)
        if !(too_thick || too_thin) || tp.length(k) <= 0.0 {
            continue;
        }
        if too_thick {
            Tally::count(&mut over, k, s.c, s.c > hard_hi, f64::max);
        } else {
            Tally::count(&mut thin, k, s.c, s.c < hard_lo, f64::min);
        }
    }
    let nozzle = p.nozzle_diameter;
    if let Some(t) = over {
        let hard = if t.hard {
            format!(", past the hard limit of {hard_hi:.3} mm²: the nozzle floods and clogs")
        } else {
            String::new()
        };
        let factor = lim.cross_section_max;
        let what = format!(
            "above {hi:.3} mm² ({factor} × the {nozzle} mm nozzle²), up to {:.3} mm²{hard}",
            t.extreme
        );
        out.push(t.finding(tp, "over-extrusion", &what));
    }
    if let Some(t) = thin {
        let hard = if t.hard {
            format!(", past the hard limit of {hard_lo:.4} mm²: the string breaks")
        } else {
            ": the string may break".to_string()
        };
        let factor = lim.cross_section_min;
        let what = format!(
            "below {lo:.4} mm² ({factor} × the {nozzle} mm nozzle²), down to {:.4} mm²{hard}",
            t.extreme
        );
        out.push(t.finding(tp, "thin-string", &what));
    }
}

/// The moves of one path a Klipper printer refuses (`klipper-extrusion`,
/// an error): Klipper's `[extruder]` stops the print at the first move
/// whose cross-section passes `max_extrude_cross_section` and at an
/// extrude-only move longer than `max_extrude_only_distance`
/// (klippy/kinematics/extruder.py, `check_move`). Klipper's cross-section
/// is the move's E over its XYZ length times the filament area of its own
/// config (the profile's `filament_diameter`); a move feeding at most
/// nozzle × `max_extrude_cross_section` / that area passes ("a tiny
/// amount"), and a move without X or Y is extrude-only: its E is held to
/// the distance instead. Strings are checked one by one, before the
/// writer merges short ones: a merged move's cross-section is the mean of
/// its strings', so this is Klipper's rule or stricter.
pub(crate) fn klipper_moves(recipe: &Recipe, tp: &Toolpath, out: &mut Vec<Finding>) {
    let p = &recipe.printer;
    if p.flavor != crate::machine::Flavor::Klipper {
        return;
    }
    let lim = p.kinematics.klipper_extruder(p.nozzle_diameter);
    let klipper_area = std::f64::consts::PI * 0.25 * p.filament_diameter * p.filament_diameter;
    // E = c·L / a (a: the material's filament area, what the writer
    // divides by); Klipper reads area = E / L × A (A: its own)
    let area = super::support::filament_area(recipe);
    let tiny = p.nozzle_diameter * lim.max_cross_section / klipper_area;
    // G-code carries 3 decimals: a move under half a micrometre in X and
    // in Y is written without them
    const NO_XY: f64 = 5e-4;
    let mut wide: Option<(usize, usize, f64)> = None;
    let mut long: Option<(usize, usize, f64)> = None;
    // (first string, count, the first's cross-section or filament)
    let tally = |slot: &mut Option<(usize, usize, f64)>, k: usize, v: f64| {
        slot.get_or_insert((k, 0, v)).1 += 1;
    };
    for (k, s) in tp.strings.iter().enumerate() {
        if s.travel || !(s.c.is_finite() && s.c > 0.0) {
            continue;
        }
        let (a, b) = (tp.points[k], tp.points[k + 1]);
        let len = a.distance(b);
        let e = s.c * len / area;
        if (b.x - a.x).abs() < NO_XY && (b.y - a.y).abs() < NO_XY {
            if e > lim.max_only_distance {
                tally(&mut long, k, e);
            }
        } else if s.c * klipper_area / area > lim.max_cross_section && e > tiny {
            tally(&mut wide, k, s.c * klipper_area / area);
        }
    }
    for (k, ev) in &tp.events {
        if let crate::base::toolpath::Event::Extrude { filament, .. } = *ev {
            if filament.abs() > lim.max_only_distance {
                tally(&mut long, *k, filament.abs());
            }
        }
    }
    let mut report = |(k, n, _): (usize, usize, f64), what: String, klipper: String| {
        // an in-place feed comes before string k, which may be none
        let m = if k < tp.len() {
            tp.midpoint(k)
        } else {
            tp.points[k.min(tp.points.len() - 1)]
        };
        out.push(Finding {
            code: "klipper-extrusion",
            severity: Severity::Error,
            message: format!(
                "part `{}` has {n} move{} Klipper refuses: {what}; the first, string {k} at {}, {klipper}",
                tp.name,
                if n == 1 { "" } else { "s" },
                fmt_p(m)
            ),
            part: Some(tp.name.clone()),
            string: Some(k),
            at: Some(m.to_array()),
            strings: Vec::new(),
        });
    };
    if let Some(w) = wide {
        let max = lim.max_cross_section;
        report(
            w,
            format!(
                "a cross-section above the extruder's max_extrude_cross_section of {max:.3} mm²"
            ),
            format!(
                "stops the print: `Move exceeds maximum extrusion ({:.3}mm^2 vs {max:.3}mm^2)`",
                w.2
            ),
        );
    }
    if let Some(l) = long {
        let max = lim.max_only_distance;
        report(
            l,
            format!("an extrude-only move (no X, no Y) of more than the extruder's max_extrude_only_distance of {max:.3} mm of filament"),
            format!("stops the print: `Extrude only move too long ({:.3}mm vs {max:.3}mm)`", l.2),
        );
    }
}
