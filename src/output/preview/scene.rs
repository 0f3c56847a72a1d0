//! The plan read for drawing ([`Scene`]): what every preview draws of it,
//! read once: per path the spacing of its passes, per string whether a
//! check found a problem in it and the print time at its end, and the
//! value each colour mode shows.

use std::collections::HashSet;

use glam::DVec3;

use super::ColorMode;
use crate::analyse::plan::Plan;
use crate::base::geom::passes::{pass_spacing, round_diameter};

/// The plan read for drawing: per path the spacing of its passes, per string
/// the print time at its end and whether a check found a problem in it.
pub(crate) struct Scene<'a> {
    /// The plan drawn.
    pub(crate) plan: &'a Plan,
    /// Per path: print time at the end of each string, s (Σ length / speed);
    /// made when first asked for ([`Scene::time`]).
    time: std::sync::OnceLock<Vec<Vec<f64>>>,
    /// [`Scene::range`] of each colour mode, once asked for.
    ranges: [std::sync::OnceLock<(f64, f64)>; 6],
    /// Per path: whether a finding concerns each string.
    pub(crate) flagged: Vec<Vec<bool>>,
    /// Per path: the typical spacing between its passes, mm.
    pub(crate) spacing: Vec<f64>,
    /// Where the findings are, recipe coordinates.
    pub(crate) marks: Vec<DVec3>,
    /// The turtles' `draw_turtle` markers of every part.
    pub(crate) turtles: Vec<crate::base::toolpath::Marker>,
}

impl<'a> Scene<'a> {
    /// Reads `plan` for drawing.
    pub(crate) fn new(plan: &'a Plan) -> Scene<'a> {
        Scene::with_flags(plan, flags(plan))
    }

    /// [`Scene::new`] but for the flags, `flagged` left empty: the HTML
    /// preview finds them first, for its G-code reader, and puts them in.
    pub(super) fn unflagged(plan: &'a Plan) -> Scene<'a> {
        Scene::with_flags(plan, Vec::new())
    }

    /// [`Scene::new`] but for the spacing of the passes, each path's taken
    /// as half the nozzle (what a path without neighbouring passes gets),
    /// and for the findings, none flagged: for round strokes only (the
    /// G-code's thumbnails, drawn on every build), whose drawing needs no
    /// spacing, and whose cost must not grow with how many passes lie in
    /// one place ([`pass_spacing`] of a line retraced 600 000 times took
    /// tens of seconds). A thumbnail is the print as the printer shows it,
    /// the same whether the checks ran, found something or were allowed:
    /// the G-code does not wait for the checks.
    pub(crate) fn round(plan: &'a Plan) -> Scene<'a> {
        let none = plan
            .paths
            .iter()
            .map(|tp| vec![false; tp.strings.len()])
            .collect();
        let mut scene = Scene::with_flags_spaced(plan, none, false);
        scene.marks.clear();
        scene
    }

    /// [`Scene::new`] given which strings the findings concern (as [`flags`]
    /// finds them).
    fn with_flags(plan: &'a Plan, flagged: Vec<Vec<bool>>) -> Scene<'a> {
        Scene::with_flags_spaced(plan, flagged, true)
    }

    /// [`Scene::with_flags`], each path's pass spacing measured when
    /// `spaced` ([`pass_spacing`]), else half the nozzle.
    fn with_flags_spaced(plan: &'a Plan, flagged: Vec<Vec<bool>>, spaced: bool) -> Scene<'a> {
        let fallback = plan.recipe.printer.nozzle_diameter / 2.0;
        let spacing: Vec<f64> = plan
            .paths
            .iter()
            .map(|tp| {
                if spaced {
                    pass_spacing(&tp.points).unwrap_or(fallback)
                } else {
                    fallback
                }
            })
            .collect();
        Scene {
            plan,
            time: Default::default(),
            ranges: Default::default(),
            flagged,
            spacing,
            marks: plan
                .findings
                .iter()
                .filter_map(|f| f.at.map(DVec3::from_array))
                .filter(|p| p.is_finite())
                .collect(),
            turtles: plan
                .paths
                .iter()
                .flat_map(|tp| tp.markers.iter().copied())
                .filter(|m| m.pos.is_finite())
                .collect(),
        }
    }

    /// The triangle of a turtle marker (ExtruderTurtle's draw_Turtle(), Fig.
    /// 2c): its sharpest corner `size` mm ahead along the heading, the other
    /// two behind it on either side, in the turtle's plane (normal `up`).
    pub(crate) fn turtle_triangle(m: &crate::base::toolpath::Marker, size: f64) -> [DVec3; 3] {
        let left = m.up.cross(m.heading);
        [
            m.pos + m.heading * size,
            m.pos - m.heading * (0.5 * size) + left * (0.5 * size),
            m.pos - m.heading * (0.5 * size) - left * (0.5 * size),
        ]
    }

    /// Per path: print time at the end of each string, s (Σ length / speed).
    pub(crate) fn time(&self) -> &Vec<Vec<f64>> {
        self.time.get_or_init(|| {
            let mut t = 0.0;
            self.plan
                .paths
                .iter()
                .map(|tp| {
                    (0..tp.len())
                        .map(|k| {
                            let v = tp.strings[k].v;
                            if v > 0.0 {
                                t += tp.length(k) / v;
                            }
                            t
                        })
                        .collect()
                })
                .collect()
        })
    }

    /// The number string k of path `pi` shows in colour mode `mode`.
    pub(crate) fn value(&self, mode: ColorMode, pi: usize, k: usize) -> f64 {
        let s = self.plan.paths[pi].strings[k];
        match mode {
            ColorMode::Speed => s.v,
            ColorMode::CrossSection => s.c,
            ColorMode::Flow => s.c * s.v,
            ColorMode::Order => self.time()[pi][k] / 60.0,
            ColorMode::Findings | ColorMode::Plain => 0.0,
        }
    }

    /// Lowest and highest value over the extruding strings (0, 0 when none).
    pub(crate) fn range(&self, mode: ColorMode) -> (f64, f64) {
        let slot = ColorMode::NAMES
            .iter()
            .position(|n| *n == mode.name())
            .expect("every mode is named");
        *self.ranges[slot].get_or_init(|| self.find_range(mode))
    }

    fn find_range(&self, mode: ColorMode) -> (f64, f64) {
        if !mode.has_value() {
            return (0.0, 0.0); // every string's value is 0
        }
        if mode == ColorMode::Order {
            let end = self.time().iter().flatten().last().copied().unwrap_or(0.0);
            return (0.0, end / 60.0);
        }
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for (pi, tp) in self.plan.paths.iter().enumerate() {
            for (k, s) in tp.strings.iter().enumerate() {
                if !s.travel {
                    let v = self.value(mode, pi, k);
                    if v.is_finite() {
                        lo = lo.min(v);
                        hi = hi.max(v);
                    }
                }
            }
        }
        if lo > hi {
            (0.0, 0.0)
        } else {
            (lo, hi)
        }
    }

    /// Half the widest a string is drawn, mm: room to leave round the model.
    pub(crate) fn pad(&self) -> f64 {
        let mut w: f64 = 0.0;
        for (tp, h) in self.plan.paths.iter().zip(&self.spacing) {
            let c = tp
                .strings
                .iter()
                .filter(|s| !s.travel)
                .fold(0.0f64, |a, s| a.max(s.c));
            w = w.max(*h).max(2.0 * c / h).max(round_diameter(c));
        }
        (w / 2.0).min(2.0 * self.plan.recipe.printer.nozzle_diameter)
    }

    /// The typical spacing between passes, weighted by string count, mm.
    pub(crate) fn typical_spacing(&self) -> f64 {
        let mut v: Vec<(f64, usize)> = self
            .spacing
            .iter()
            .zip(&self.plan.paths)
            .map(|(h, tp)| (*h, tp.len()))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        let total: usize = v.iter().map(|x| x.1).sum();
        let mut seen = 0;
        for (h, n) in &v {
            seen += n;
            if 2 * seen >= total {
                return *h;
            }
        }
        self.plan.recipe.printer.nozzle_diameter / 2.0
    }
}

/// Which strings the findings concern, per path.
///
/// A finding names its first string and, for runs (unsupported, bridges),
/// every string of them (`Finding::strings`); for the checks that judge each
/// string by itself (bed limits, speed, flow, finite numbers) every string that
/// fails the same test is marked, with the printer's limits the checks use.
pub(super) fn flags(plan: &Plan) -> Vec<Vec<bool>> {
    let codes: HashSet<&str> = plan.findings.iter().map(|f| f.code).collect();
    let p = &plan.recipe.printer;
    let max_z = p.bed.max_z();
    let outside = |q: DVec3| {
        let m = p.to_machine(q);
        (codes.contains("non-finite") && !q.is_finite())
            || (codes.contains("out-of-bed") && q.is_finite() && !p.bed.contains_xy(m))
            || (codes.contains("below-bed") && m.z < 0.0)
            || (codes.contains("above-max-z") && m.z > max_z)
    };
    let mut out: Vec<Vec<bool>> = plan
        .paths
        .iter()
        .map(|tp| {
            let bad_point: Vec<bool> = tp.points.iter().map(|q| outside(*q)).collect();
            tp.strings
                .iter()
                .enumerate()
                .map(|(k, s)| {
                    bad_point[k]
                        || bad_point[k + 1]
                        || (!s.travel
                            && ((codes.contains("speed") && s.v > p.max_speed)
                                || (codes.contains("flow") && s.c * s.v > p.max_flow)))
                })
                .collect()
        })
        .collect();
    for f in &plan.findings {
        if let (Some(part), Some(k)) = (&f.part, f.string) {
            for (pi, tp) in plan.paths.iter().enumerate() {
                if &tp.name == part && k < tp.len() {
                    out[pi][k] = true;
                    // every string the finding names (an unsupported run, a bridge)
                    for &[a, b] in &f.strings {
                        for flag in &mut out[pi][a.min(tp.len())..b.min(tp.len())] {
                            *flag = true;
                        }
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_string_of_an_unsupported_run_is_flagged() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/checks/pitch-gap.yaml");
        let plan =
            crate::app::prepare::plan(&path, &crate::app::prepare::Options::default()).unwrap();
        let f = plan
            .findings
            .iter()
            .find(|f| f.code == "unsupported")
            .expect("pitch-gap is unsupported");
        let spans = f.strings.clone();
        let named: usize = spans.iter().map(|[a, b]| b - a).sum();
        assert!(named > 10, "{spans:?}");
        let flags = flags(&plan);
        let pi = plan
            .paths
            .iter()
            .position(|tp| Some(&tp.name) == f.part.as_ref())
            .unwrap();
        for [a, b] in spans {
            assert!(flags[pi][a..b].iter().all(|&x| x));
        }
    }
}
