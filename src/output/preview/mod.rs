//! Previews: see the print before printing it.
//!
//! Three outputs share one reading of the plan ([`Scene`]): a PNG rendering
//! ([`png`]), a self-contained HTML file with a WebGL viewer ([`html`]) and the
//! PNG thumbnails PrusaSlicer-style printers show from the G-code
//! ([`thumbnail`]).
//!
//! Projection. Every still view is orthographic. A view is an orthonormal
//! basis (right, up, toward) of recipe space, `toward` pointing at the viewer:
//! a point p lands on the screen plane at (u, w) = (p·right, p·up) and lies at
//! depth d = p·toward (larger is nearer). Pixels are x = cx + s·(u − u_c) and
//! y = cy − s·(w − w_c), with s the scale in px/mm and (u_c, w_c) the centre of
//! the drawing; the minus sign because image rows grow downwards.
//!
//! Width. A string of cross-section c laid h from the next pass (a helix's
//! layer height, measured on the path: [`Grid::local`]) fills those h along
//! the surface and is c / h thick across it, the real string width. The
//! previews draw it as that flat tube seen from the view: the projection of
//! its cross-section (an ellipse of axes h along the surface and c / h along
//! the normal) onto the screen direction across the string. So a wall seen
//! face on is closed, as printed, and its rim shows the real thickness; a
//! string with no neighbouring pass is drawn round, of diameter 2·sqrt(c/pi).

pub mod html;
pub mod png;
pub mod thumbnail;

mod text;

use std::collections::HashSet;

use crate::base::geom::grid::{closest, cube, SegGrid};
use std::path::Path;

use glam::DVec3;

use crate::analyse::plan::Plan;
use crate::analyse::stats::Stats;
use crate::base::error::{Error, Result};
pub use crate::machine::Size;
use crate::output::file::write_atomic;

/// Where the still views look from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum View {
    /// Isometric, from the front right and above.
    #[default]
    Iso,
    /// From above: x to the right, y up the image.
    Top,
    /// From the front (−y): x to the right, z up.
    Front,
    /// From the right (+x): y to the right, z up.
    Side,
}

/// An orthonormal view basis in recipe coordinates (right × up = toward).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Basis {
    /// Screen right.
    pub right: DVec3,
    /// Screen up.
    pub up: DVec3,
    /// Towards the viewer; depth grows along it.
    pub toward: DVec3,
}

impl View {
    /// The names `--view` accepts.
    pub const NAMES: [&'static str; 4] = ["iso", "top", "front", "side"];

    /// Parses a `--view` value.
    pub fn parse(s: &str) -> Result<View> {
        match s {
            "iso" => Ok(View::Iso),
            "top" => Ok(View::Top),
            "front" => Ok(View::Front),
            "side" => Ok(View::Side),
            _ => Err(Error::input(
                "--view",
                format!(
                    "unknown view `{s}`; expected one of {}",
                    View::NAMES.join(", ")
                ),
            )),
        }
    }

    /// The view's name.
    pub fn name(self) -> &'static str {
        match self {
            View::Iso => "iso",
            View::Top => "top",
            View::Front => "front",
            View::Side => "side",
        }
    }

    /// The view's basis.
    pub fn basis(self) -> Basis {
        match self {
            View::Top => Basis {
                right: DVec3::X,
                up: DVec3::Y,
                toward: DVec3::Z,
            },
            View::Front => Basis {
                right: DVec3::X,
                up: DVec3::Z,
                toward: DVec3::NEG_Y,
            },
            View::Side => Basis {
                right: DVec3::Y,
                up: DVec3::Z,
                toward: DVec3::X,
            },
            View::Iso => {
                // the viewer on the diagonal (1, −1, 1): right = z × toward
                // (horizontal), up = toward × right (completes the basis)
                let toward = DVec3::new(1.0, -1.0, 1.0).normalize();
                let right = DVec3::Z.cross(toward).normalize();
                Basis {
                    right,
                    up: toward.cross(right),
                    toward,
                }
            }
        }
    }
}

impl Basis {
    /// Screen-plane coordinates (u, w) and depth d of recipe point `p`.
    pub fn project(&self, p: DVec3) -> (f64, f64, f64) {
        (p.dot(self.right), p.dot(self.up), p.dot(self.toward))
    }
}

/// What the colour of a string shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColorMode {
    /// Head speed v, mm/s.
    #[default]
    Speed,
    /// Cross-section c, mm².
    CrossSection,
    /// Volumetric flow c·v, mm³/s.
    Flow,
    /// Print order, as the print time at which the string is laid, min.
    Order,
    /// Grey, with the strings the checks found problems in red.
    Findings,
    /// One filament colour (the G-code thumbnails).
    Plain,
}

impl ColorMode {
    /// The names `--color` accepts.
    pub const NAMES: [&'static str; 6] = [
        "speed",
        "cross-section",
        "flow",
        "order",
        "findings",
        "plain",
    ];

    /// Parses a `--color` value.
    pub fn parse(s: &str) -> Result<ColorMode> {
        match s {
            "speed" => Ok(ColorMode::Speed),
            "cross-section" => Ok(ColorMode::CrossSection),
            "flow" => Ok(ColorMode::Flow),
            "order" => Ok(ColorMode::Order),
            "findings" => Ok(ColorMode::Findings),
            "plain" => Ok(ColorMode::Plain),
            _ => Err(Error::input(
                "--color",
                format!(
                    "unknown colour mode `{s}`; expected one of {}",
                    ColorMode::NAMES.join(", ")
                ),
            )),
        }
    }

    /// The mode's name.
    pub fn name(self) -> &'static str {
        match self {
            ColorMode::Speed => "speed",
            ColorMode::CrossSection => "cross-section",
            ColorMode::Flow => "flow",
            ColorMode::Order => "order",
            ColorMode::Findings => "findings",
            ColorMode::Plain => "plain",
        }
    }

    /// The unit of the scale, for the legend.
    pub fn unit(self) -> &'static str {
        match self {
            ColorMode::Speed => "mm/s",
            ColorMode::CrossSection => "mm²",
            ColorMode::Flow => "mm³/s",
            ColorMode::Order => "min",
            ColorMode::Findings | ColorMode::Plain => "",
        }
    }
}

/// How many threads the drawing may split over (by default the pool's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Threads(usize);

impl Threads {
    /// `n` threads, at least 1.
    pub fn new(n: usize) -> Threads {
        Threads(n.max(1))
    }

    /// The number of threads.
    pub fn get(self) -> usize {
        self.0
    }
}

impl Default for Threads {
    fn default() -> Threads {
        Threads::new(rayon::current_num_threads())
    }
}

/// What a preview shows and how big.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Options {
    /// Still view (the HTML viewer starts there).
    pub view: View,
    /// Colour mode (the HTML viewer starts there).
    pub color: ColorMode,
    /// Image size (PNG only).
    pub size: Size,
    /// Only the model: no title, stats or legend (PNG only).
    pub bare: bool,
    /// How many threads drawing it may use (`-j`); the output is the same on any number.
    pub threads: Threads,
}

/// The plan read for drawing: per path the spacing of its passes, per string
/// the print time at its end and whether a check found a problem in it.
pub struct Scene<'a> {
    /// The plan drawn.
    pub plan: &'a Plan,
    /// Per path: print time at the end of each string, s (Σ length / speed);
    /// made when first asked for ([`Scene::time`]).
    time: std::sync::OnceLock<Vec<Vec<f64>>>,
    /// [`Scene::range`] of each colour mode, once asked for.
    ranges: [std::sync::OnceLock<(f64, f64)>; 6],
    /// Per path: whether a finding concerns each string.
    pub flagged: Vec<Vec<bool>>,
    /// Per path: the typical spacing between its passes, mm.
    pub spacing: Vec<f64>,
    /// Where the findings are, recipe coordinates.
    pub marks: Vec<DVec3>,
    /// The turtles' `draw_turtle` markers of every part.
    pub turtles: Vec<crate::base::toolpath::Marker>,
}

impl<'a> Scene<'a> {
    /// Reads `plan` for drawing.
    pub fn new(plan: &'a Plan) -> Scene<'a> {
        Scene::with_flags(plan, flags(plan))
    }

    /// [`Scene::new`] given which strings the findings concern (as [`flags`]
    /// finds them), so that they may be known before the rest.
    fn with_flags(plan: &'a Plan, flagged: Vec<Vec<bool>>) -> Scene<'a> {
        let fallback = plan.recipe.printer.nozzle_diameter / 2.0;
        let spacing: Vec<f64> = plan
            .paths
            .iter()
            .map(|tp| pass_spacing(&tp.points).unwrap_or(fallback))
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
    pub fn turtle_triangle(m: &crate::base::toolpath::Marker, size: f64) -> [DVec3; 3] {
        let left = m.up.cross(m.heading);
        [
            m.pos + m.heading * size,
            m.pos - m.heading * (0.5 * size) + left * (0.5 * size),
            m.pos - m.heading * (0.5 * size) - left * (0.5 * size),
        ]
    }

    /// Per path: print time at the end of each string, s (Σ length / speed).
    pub fn time(&self) -> &Vec<Vec<f64>> {
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
    pub fn value(&self, mode: ColorMode, pi: usize, k: usize) -> f64 {
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
    pub fn range(&self, mode: ColorMode) -> (f64, f64) {
        let slot = ColorMode::NAMES
            .iter()
            .position(|n| *n == mode.name())
            .expect("every mode is named");
        *self.ranges[slot].get_or_init(|| self.find_range(mode))
    }

    fn find_range(&self, mode: ColorMode) -> (f64, f64) {
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

    /// The extruding points (all points when nothing extrudes).
    pub fn extruding_points(&self) -> Vec<DVec3> {
        let mut out = Vec::new();
        self.each_extruding_point(|p| {
            if out.last() != Some(&p) {
                out.push(p)
            }
        });
        out
    }

    /// Calls `f` on the finite ends of every extruding string, in print order
    /// (on every finite point when nothing extrudes), a point the same bits
    /// as the one just passed not again (the end two strings in a row
    /// share): [`Scene::extruding_points`] without holding them.
    pub fn each_extruding_point(&self, mut f: impl FnMut(DVec3)) {
        let mut any = false;
        let bits = |p: DVec3| p.to_array().map(f64::to_bits);
        for tp in &self.plan.paths {
            let mut last = None;
            for (k, s) in tp.strings.iter().enumerate() {
                if !s.travel {
                    any = true;
                    let (a, b) = tp.ends(k);
                    for p in [a, b] {
                        if p.is_finite() && last != Some(bits(p)) {
                            last = Some(bits(p));
                            f(p);
                        }
                    }
                }
            }
        }
        if !any {
            for tp in &self.plan.paths {
                for p in &tp.points {
                    if p.is_finite() {
                        f(*p);
                    }
                }
            }
        }
    }

    /// Half the widest a string is drawn, mm: room to leave round the model.
    pub fn pad(&self) -> f64 {
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
    pub fn typical_spacing(&self) -> f64 {
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
fn flags(plan: &Plan) -> Vec<Vec<bool>> {
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

/// The strings of a polyline in the shared segment grid
/// ([`crate::base::geom::grid::SegGrid`]), to find the nearest point of another
/// pass: one much farther along the path than in space (path distance over
/// 3 × straight distance), so that a point's own neighbours on its string do
/// not count.
pub struct Grid<'t> {
    points: &'t [DVec3],
    /// Arc length along the path at each point, mm.
    s: Vec<f64>,
    cell: f64,
    /// String k runs from point k to point k + 1; the strings in runs (the
    /// id of each run's first, and the run's grid, which numbers them from 0).
    strings: Vec<(usize, SegGrid)>,
}

impl<'t> Grid<'t> {
    /// Files the strings of the polyline `points` in cubes of `cell` mm.
    pub fn new(points: &'t [DVec3], cell: f64) -> Grid<'t> {
        Grid::new_on(points, cell, 1)
    }

    /// [`Grid::new`] in `parts` grids of a run of strings each, built at
    /// once on as many threads. A search looks in each; the nearest point
    /// (ties going to the lower string) is the same however they are cut.
    pub fn new_on(points: &'t [DVec3], cell: f64, parts: usize) -> Grid<'t> {
        let mut s = Vec::with_capacity(points.len());
        let mut acc = 0.0;
        for (k, p) in points.iter().enumerate() {
            if k > 0 {
                let d = p.distance(points[k - 1]);
                if d.is_finite() {
                    acc += d;
                }
            }
            s.push(acc);
        }
        let n = points.len().saturating_sub(1);
        let run = n.div_ceil(parts.max(1)).max(1);
        let build = |from: usize| {
            let to = (from + run).min(n);
            let g = SegGrid::build(to - from, cell, |k| {
                (points[from + k], points[from + k + 1])
            });
            (from, g)
        };
        let strings = if n <= run {
            vec![build(0)]
        } else {
            std::thread::scope(|sc| {
                let built: Vec<_> = (run..n)
                    .step_by(run)
                    .map(|from| sc.spawn(move || build(from)))
                    .collect();
                let mut all = vec![build(0)];
                all.extend(
                    built
                        .into_iter()
                        .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))),
                );
                all
            })
        };
        Grid {
            points,
            s,
            cell,
            strings,
        }
    }

    /// A grid to find the passes next to a surface whose passes lie about
    /// `h` apart: cells big enough to reach the ends of the strings nearby
    /// (longer than `h` on a coarse helix).
    pub fn for_surface(points: &'t [DVec3], h: f64) -> Grid<'t> {
        Grid::for_surface_on(points, h, 1)
    }

    /// [`Grid::for_surface`] in `parts` grids built at once ([`Grid::new_on`]).
    pub fn for_surface_on(points: &'t [DVec3], h: f64, parts: usize) -> Grid<'t> {
        let step = (points.len() / 4096).max(1);
        let mut lens: Vec<f64> = (step..points.len())
            .step_by(step)
            .map(|k| points[k].distance(points[k - 1]))
            .filter(|l| l.is_finite())
            .collect();
        lens.sort_by(f64::total_cmp);
        let l90 = lens.get(lens.len() * 9 / 10).copied().unwrap_or(0.0);
        Grid::new_on(
            points,
            (3.0 * h).max(0.6 * l90 + 1.5 * h).clamp(0.3, 4.0),
            parts,
        )
    }

    /// Arc length at point k, mm.
    pub fn arc(&self, k: usize) -> f64 {
        self.s[k]
    }

    /// The nearest point of another pass to `p` (at arc length `sp`): the
    /// closest point of the strings within one cell of `p`, or `None` when
    /// none lies that near.
    pub fn nearest_other(&self, p: DVec3, sp: f64) -> Option<DVec3> {
        self.nearest_other_near(p, sp, None).map(|(q, _)| q)
    }

    /// [`Grid::nearest_other`], and the string the point lies on, looking
    /// first at the strings around `hint` (the answer for a point nearby).
    ///
    /// The answer is the same with or without the hint: the nearest
    /// qualifying point, ties going to the lower string. The hint only
    /// narrows the search: a qualifying point d away from `p` bounds the
    /// answer's distance by d, so only the cubes within d of `p` (not within
    /// a whole cell) can hold it.
    pub fn nearest_other_near(
        &self,
        p: DVec3,
        sp: f64,
        hint: Option<usize>,
    ) -> Option<(DVec3, usize)> {
        self.nearest(p, sp, hint, false)
    }

    /// The point [`Grid::nearest_other_near`] finds, or, when a string
    /// within [`HINT_REACH`] of `hint` qualifies, the nearest point of those
    /// alone: a pass followed along (the next pass of a helix stays the next
    /// pass), the whole grid searched only when it is lost.
    pub fn follow_other(&self, p: DVec3, sp: f64, hint: usize) -> Option<(DVec3, usize)> {
        self.nearest(p, sp, Some(hint), true)
    }

    fn nearest(
        &self,
        p: DVec3,
        sp: f64,
        hint: Option<usize>,
        follow: bool,
    ) -> Option<(DVec3, usize)> {
        if !p.is_finite() {
            return None;
        }
        let mut best: Option<(f64, usize, DVec3)> = None;
        let consider = |k: usize, best: &mut Option<(f64, usize, DVec3)>| {
            let (a, b) = (self.points[k], self.points[k + 1]);
            // the closest point of the string: a + f·(b − a)
            let f = closest(p, a, b);
            let q = a + (b - a) * f;
            // no root where the square shows it too far: d² beyond
            // bound²·(1 + 10⁻¹²) makes the rounded root d above the bound
            // (as far as the cell, or the best so far), which is refused below
            let bound = best.map_or(self.cell, |b| b.0.min(self.cell));
            let d2 = (p - q).length_squared();
            if d2 > bound * bound * (1.0 + 1e-12) {
                return;
            }
            let d = d2.sqrt(); // p.distance(q), bit for bit
            let sq = self.s[k] + f * (self.s[k + 1] - self.s[k]);
            // 1 µm: a point revisited (a closed loop) is no neighbour
            if d > 1e-3
                && d < self.cell
                && best.is_none_or(|b| (d, k) < (b.0, b.1))
                && (sq - sp).abs() > 3.0 * d
            {
                *best = Some((d, k, q));
            }
        };
        let n = self.points.len().saturating_sub(1);
        if let Some(h) = hint {
            for k in h.saturating_sub(HINT_REACH)..h.saturating_add(HINT_REACH + 1).min(n) {
                consider(k, &mut best);
            }
        }
        if !(follow && best.is_some()) {
            for (from, g) in &self.strings {
                let r = best.map_or(self.cell, |b| b.0);
                g.search(p, r, u32::MAX, |k| {
                    consider(from + k as usize, &mut best);
                    false
                });
            }
        }
        best.map(|(_, k, q)| (q, k))
    }

    /// The surface a string from `a` to `b` lies in, told by the nearest
    /// other pass to its middle (arc length `sm`): see [`Local`].
    pub fn local(&self, a: DVec3, b: DVec3, sm: f64) -> Option<Local> {
        self.local_near(a, b, sm, None, false).map(|(l, _)| l)
    }

    /// [`Grid::local`] with a hint (see [`Grid::nearest_other_near`]), and
    /// the neighbouring string it found; with `follow`, the neighbour
    /// [`Grid::follow_other`] finds.
    pub fn local_near(
        &self,
        a: DVec3,
        b: DVec3,
        sm: f64,
        hint: Option<usize>,
        follow: bool,
    ) -> Option<(Local, usize)> {
        let t = (b - a).normalize_or_zero();
        let m = (a + b) * 0.5;
        let (q, k) = self.nearest(m, sm, hint, follow)?;
        // the way across to the neighbour, less any part along the string
        let across = (q - m) - t * (q - m).dot(t);
        let normal = t.cross(across).normalize_or_zero();
        if t == DVec3::ZERO || normal == DVec3::ZERO {
            return None;
        }
        Some((
            Local {
                normal,
                spacing: across.length(),
            },
            k,
        ))
    }
}

/// How many strings either side of a hint [`Grid::nearest_other_near`] tries.
pub const HINT_REACH: usize = 2;

/// The wall around one string: it fills the `spacing` across to the next
/// pass along the surface, and is c / spacing thick along `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Local {
    /// Unit normal of the surface (either side).
    pub normal: DVec3,
    /// Distance across to the neighbouring pass, mm.
    pub spacing: f64,
}

/// The distance between neighbouring passes of a polyline (a helix's layer
/// height, a spiral's pitch), mm, or `None` when it has no such neighbours:
/// the median, over up to 1024 sampled points, of the distance to the nearest
/// point of another pass within 2 mm (as [`Grid::nearest_other`] finds it).
///
/// With so few points asked about, no grid of all the strings is built: the
/// cubes of 2 mm within 2.5 mm of a sampled point list it, and each string
/// is measured once against the points listed in the cubes of its pieces (at
/// most 1 mm long, so a string within 2 mm of a point has a piece whose
/// middle lies within 2.5 mm of it).
pub fn pass_spacing(points: &[DVec3]) -> Option<f64> {
    const REACH: f64 = 2.0;
    let n = points.len();
    if n < 3 {
        return None;
    }
    let step = (n / 1024).max(1);
    let inv = 1.0 / REACH;
    // the sampled points with their arc lengths
    let mut samples: Vec<(DVec3, f64)> = Vec::new();
    let mut acc = 0.0;
    for (k, p) in points.iter().enumerate() {
        if k > 0 {
            let d = p.distance(points[k - 1]);
            if d.is_finite() {
                acc += d;
            }
        }
        if k.is_multiple_of(step) && p.is_finite() {
            samples.push((*p, acc));
        }
    }
    let near = Near::new(&samples, DVec3::splat(1.25 * REACH), inv);
    let mut best: Vec<Option<(f64, usize)>> = vec![None; samples.len()];
    let mut sa = 0.0;
    for k in 0..n - 1 {
        let (a, b) = (points[k], points[k + 1]);
        let l = a.distance(b);
        let sb = if l.is_finite() { sa + l } else { sa };
        let pieces = (l * 2.0 * inv).clamp(0.0, 1e6) as usize + 1;
        let mut last = None;
        for j in 0..pieces {
            let c = cube(a.lerp(b, (j as f64 + 0.5) / pieces as f64), inv);
            if last == Some(c) {
                continue;
            }
            last = Some(c);
            for &i in near.get(c) {
                let (p, sp) = samples[i as usize];
                // as Grid::nearest_other: the closest point a + f·(b − a)
                let f = closest(p, a, b);
                let d = p.distance(a + (b - a) * f);
                let sq = sa + f * (sb - sa);
                let slot = &mut best[i as usize];
                if d > 1e-3
                    && d < REACH
                    && slot.is_none_or(|o| (d, k) < o)
                    && (sq - sp).abs() > 3.0 * d
                {
                    *slot = Some((d, k));
                }
            }
        }
        sa = sb;
    }
    let mut found: Vec<f64> = best.iter().flatten().map(|b| b.0).collect();
    if found.len() < 8 {
        return None;
    }
    found.sort_by(f64::total_cmp);
    Some(found[found.len() / 2])
}

/// The sampled points of [`pass_spacing`] listed (ascending) under every cube
/// within `r` of them: in an array over the cubes of their box when it has
/// at most [`Near::DENSE`] cubes (a look-up is then an index), else in a map.
enum Near {
    /// Cube (x, y, z) of the box from `lo` of `dims` cubes lists
    /// `items[starts[c]..starts[c + 1]]`, c = (x·dims[1] + y)·dims[2] + z
    /// relative to `lo`.
    Dense {
        lo: [i64; 3],
        dims: [i64; 3],
        starts: Vec<u32>,
        items: Vec<u32>,
    },
    Map(std::collections::HashMap<[i64; 3], Vec<u32>, CubeHash>),
}

impl Near {
    /// The most cubes the array spans (16 MB of starts).
    const DENSE: i64 = 1 << 22;

    fn new(samples: &[(DVec3, f64)], r: DVec3, inv: f64) -> Near {
        let range = |p: DVec3| (cube(p - r, inv), cube(p + r, inv));
        let mut lo = [i64::MAX; 3];
        let mut hi = [i64::MIN; 3];
        for (p, _) in samples {
            let (a, b) = range(*p);
            for j in 0..3 {
                lo[j] = lo[j].min(a[j]);
                hi[j] = hi[j].max(b[j]);
            }
        }
        // cube coordinates are clamped to ±1e15, so these do not overflow
        let dims = [0, 1, 2].map(|j| (hi[j] - lo[j] + 1).max(0));
        let cubes = dims
            .iter()
            .try_fold(1i64, |acc, &d| acc.checked_mul(d))
            .filter(|&c| c <= Near::DENSE);
        let Some(cubes) = cubes.filter(|_| !samples.is_empty()) else {
            let mut map: std::collections::HashMap<[i64; 3], Vec<u32>, CubeHash> =
                Default::default();
            for (i, (p, _)) in samples.iter().enumerate() {
                let (a, b) = range(*p);
                for x in a[0]..=b[0] {
                    for y in a[1]..=b[1] {
                        for z in a[2]..=b[2] {
                            map.entry([x, y, z]).or_default().push(i as u32);
                        }
                    }
                }
            }
            return Near::Map(map);
        };
        // counted, then filled in the order of the samples (as the map's lists)
        let mut starts = vec![0u32; cubes as usize + 1];
        let index = |x: i64, y: i64, z: i64| {
            (((x - lo[0]) * dims[1] + (y - lo[1])) * dims[2] + (z - lo[2])) as usize
        };
        let each = |f: &mut dyn FnMut(usize, usize)| {
            for (i, (p, _)) in samples.iter().enumerate() {
                let (a, b) = range(*p);
                for x in a[0]..=b[0] {
                    for y in a[1]..=b[1] {
                        for z in a[2]..=b[2] {
                            f(index(x, y, z), i);
                        }
                    }
                }
            }
        };
        each(&mut |c, _| starts[c + 1] += 1);
        for c in 1..starts.len() {
            starts[c] += starts[c - 1];
        }
        let mut items = vec![0u32; starts[cubes as usize] as usize];
        let mut next = starts.clone();
        each(&mut |c, i| {
            items[next[c] as usize] = i as u32;
            next[c] += 1;
        });
        Near::Dense {
            lo,
            dims,
            starts,
            items,
        }
    }

    /// The samples listed under cube `c`.
    #[inline]
    fn get(&self, c: [i64; 3]) -> &[u32] {
        match self {
            Near::Dense {
                lo,
                dims,
                starts,
                items,
            } => {
                let d = [0, 1, 2].map(|j| c[j] - lo[j]);
                if (0..3).any(|j| d[j] < 0 || d[j] >= dims[j]) {
                    return &[];
                }
                let k = ((d[0] * dims[1] + d[1]) * dims[2] + d[2]) as usize;
                &items[starts[k] as usize..starts[k + 1] as usize]
            }
            Near::Map(map) => map.get(&c).map_or(&[][..], |v| v),
        }
    }
}

/// A quick hash of integer cube coordinates (a multiply and a rotation a
/// word): the cubes are keys of a map looked up once per string.
#[derive(Clone, Copy, Default)]
struct CubeHash;

/// [`CubeHash`]'s state.
#[derive(Default)]
struct CubeHasher(u64);

impl std::hash::BuildHasher for CubeHash {
    type Hasher = CubeHasher;
    fn build_hasher(&self) -> CubeHasher {
        CubeHasher(0)
    }
}

impl std::hash::Hasher for CubeHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(23) ^ v).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }

    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }

    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }

    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 29)
    }
}

/// The diameter of a round string of cross-section `c`, mm: how a string with
/// no neighbouring pass is drawn.
pub fn round_diameter(c: f64) -> f64 {
    2.0 * (c.max(0.0) / std::f64::consts::PI).sqrt()
}

/// Colour stops of the scalar modes: blue, cyan, green, yellow, red.
pub const STOPS: [[f32; 3]; 5] = [
    [0.23, 0.30, 0.85],
    [0.10, 0.65, 0.95],
    [0.25, 0.85, 0.45],
    [0.98, 0.80, 0.20],
    [0.90, 0.25, 0.15],
];

/// The colour of `t` in [0, 1] on the scale of [`STOPS`].
pub fn colormap(t: f64) -> [f32; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as f64;
    let k = (x.floor() as usize).min(STOPS.len() - 2);
    let f = (x - k as f64) as f32;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * f)
}

/// A number for a legend: three significant figures or so, no exponent.
pub fn fmt_value(v: f64) -> String {
    let a = v.abs();
    let s = if a >= 100.0 || a == 0.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    };
    match s.strip_prefix('-') {
        // never `-0.000`
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => s,
    }
}

/// The output format, by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// A PNG image.
    Png,
    /// A self-contained HTML viewer.
    Html,
}

impl Format {
    /// The format of `path` by its extension.
    pub fn of(path: &Path) -> Result<Format> {
        match crate::output::file::extension(path).as_str() {
            "png" => Ok(Format::Png),
            "html" | "htm" => Ok(Format::Html),
            _ => Err(Error::input(
                "preview",
                format!(
                    "cannot tell the format of `{}`; expected a file name ending in .png or .html",
                    path.display()
                ),
            )),
        }
    }
}

/// Writes a plan's G-code to a writer and returns its stats (the build's
/// renderer, passed down so that previews need not know how G-code is made).
/// `Sync`, so that it may run on a thread of its own beside the drawing.
pub type Render<'a> = &'a (dyn Fn(&mut dyn std::io::Write) -> Result<Stats> + Sync);

/// Writes a preview of `plan` to `out` (PNG or HTML by extension, atomically);
/// returns a line for the report. `render` writes the plan's G-code.
pub fn write(plan: &Plan, out: &Path, opts: &Options, render: Render) -> Result<String> {
    let shown = out.display().to_string();
    let io =
        |e: std::io::Error| Error::io_from(&shown, format!("cannot write the preview: {e}"), &e);
    if Format::of(out)? == Format::Html {
        // streamed into the file as it is encoded
        let (data, stats) = html::read(plan, opts, render)?;
        let mut len = 0;
        write_atomic(out, |f| {
            use std::io::Write;
            let mut w = Counted {
                inner: std::io::BufWriter::with_capacity(1 << 16, f),
                n: 0,
            };
            html::write_page(&stats.name, &data, &mut w).map_err(io)?;
            w.inner.flush().map_err(io)?;
            len = w.n;
            Ok(())
        })?;
        return Ok(html_line(&shown, data.points(), len));
    }
    let (bytes, line) = bytes(plan, out, opts, render)?;
    write_atomic(out, |f| {
        use std::io::Write;
        f.write_all(&bytes).map_err(io)
    })?;
    Ok(line)
}

/// A writer that counts the bytes through it.
struct Counted<W> {
    inner: W,
    n: usize,
}

impl<W: std::io::Write> std::io::Write for Counted<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let k = self.inner.write(buf)?;
        self.n += k;
        Ok(k)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The report line of an HTML preview of `points` points and `len` bytes.
fn html_line(shown: &str, points: usize, len: usize) -> String {
    format!(
        "preview → {shown}: HTML viewer, {points} points, {} kB",
        (len + 512) / 1024
    )
}

/// The bytes of the preview [`write`] writes to `out` (its format by the
/// extension), and the line reporting it; writes nothing, so a build can
/// commit the preview with its other outputs.
pub fn bytes(plan: &Plan, out: &Path, opts: &Options, render: Render) -> Result<(Vec<u8>, String)> {
    let format = Format::of(out)?;
    let shown = out.display().to_string();
    match format {
        Format::Png => {
            let (r, _) = png::preview(plan, opts, render)?;
            let bytes = png::encode_fast(&r.pixmap, false);
            let (x, y) = r.frame.pixel(DVec3::ZERO);
            Ok((bytes, format!(
                "preview → {shown}: {} × {} px, {} view, colour {}, scale {:.4} px/mm, recipe (0, 0, 0) at pixel ({x:.2}, {y:.2})",
                opts.size.width,
                opts.size.height,
                opts.view.name(),
                opts.color.name(),
                r.frame.scale
            )))
        }
        Format::Html => {
            let (data, stats) = html::read(plan, opts, render)?;
            let mut page = Vec::new();
            html::write_page(&stats.name, &data, &mut page).expect("writing to memory");
            let line = html_line(&shown, data.points(), page.len());
            Ok((page, line))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::toolpath::Toolpath;

    #[test]
    fn view_bases_are_right_handed_and_orthonormal() {
        for name in View::NAMES {
            let b = View::parse(name).unwrap().basis();
            assert!((b.right.cross(b.up) - b.toward).length() < 1e-12, "{name}");
            for v in [b.right, b.up, b.toward] {
                assert!((v.length() - 1.0).abs() < 1e-12);
            }
            assert!(b.right.dot(b.up).abs() < 1e-12);
        }
        // iso: the z axis points up the image, the x axis to the lower right
        let b = View::Iso.basis();
        assert!(b.up.z > 0.0 && b.right.z == 0.0);
        assert!(DVec3::X.dot(b.right) > 0.0 && DVec3::X.dot(b.up) < 0.0);
        assert!(View::parse("bottom").is_err());
    }

    #[test]
    fn sizes_parse() {
        assert_eq!(
            Size::parse("220x124", "s").unwrap(),
            Size {
                width: 220,
                height: 124
            }
        );
        assert_eq!(Size::parse("16X16", "s").unwrap().width, 16);
        for bad in ["", "12", "0x5", "5x", "ax3", "9000x10", "-3x4"] {
            assert!(Size::parse(bad, "--size").is_err(), "{bad}");
        }
    }

    #[test]
    fn colormap_ends_and_middle() {
        assert_eq!(colormap(0.0), STOPS[0]);
        assert_eq!(colormap(1.0), STOPS[4]);
        assert_eq!(colormap(0.5), STOPS[2]);
        assert_eq!(colormap(f64::NAN), STOPS[0]);
        assert_eq!(colormap(7.0), STOPS[4]);
    }

    #[test]
    fn legend_numbers() {
        assert_eq!(fmt_value(123.456), "123");
        assert_eq!(fmt_value(12.345), "12.3");
        assert_eq!(fmt_value(0.19634), "0.196");
        assert_eq!(fmt_value(-0.0001), "0.000");
        assert_eq!(fmt_value(-2.5), "-2.50");
        assert_eq!(fmt_value(0.0), "0");
    }

    /// The median distance from every `step`-th of `points` to the nearest
    /// point of another pass, as grid `g` finds it.
    fn median_nearest(g: &Grid, points: &[DVec3], step: usize) -> f64 {
        let mut d: Vec<f64> = (0..points.len())
            .step_by(step)
            .filter_map(|i| {
                let p = points[i];
                g.nearest_other(p, g.arc(i)).map(|q| p.distance(q))
            })
            .collect();
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }

    #[test]
    fn helix_spacing_is_its_pitch() {
        // a helix of radius 10, pitch 0.3, 200 strings a turn, 20 turns
        let mut tp = Toolpath::new(DVec3::new(10.0, 0.0, 0.0));
        let n = 200 * 20;
        for i in 1..=n {
            let a = std::f64::consts::TAU * i as f64 / 200.0;
            let z = 0.3 * i as f64 / 200.0;
            tp.draw(DVec3::new(10.0 * a.cos(), 10.0 * a.sin(), z), 0.1, 30.0);
        }
        let h = pass_spacing(&tp.points).unwrap();
        assert!((h - 0.3).abs() < 0.01, "{h}");
        // the same median as asking a grid of all the strings
        let g = Grid::new(&tp.points, 2.0);
        let step = (tp.points.len() / 1024).max(1);
        assert_eq!(h, median_nearest(&g, &tp.points, step));
        // following a pass from a hint finds the nearest point too, here
        let (p, k) = (tp.points[2500], 2500);
        let exact = g.nearest_other_near(p, g.arc(k), None);
        assert_eq!(g.nearest_other_near(p, g.arc(k), Some(2300)), exact);
        let q = exact.unwrap();
        assert_eq!(g.follow_other(p, g.arc(k), q.1 + 1), exact);
        // a single straight line has no other pass
        let mut line = Toolpath::new(DVec3::ZERO);
        for i in 1..100 {
            line.draw(DVec3::new(i as f64 * 0.1, 0.0, 0.0), 0.1, 30.0);
        }
        assert_eq!(pass_spacing(&line.points), None);
        // the surface of the helix: a horizontal normal, spacing the pitch
        let g = Grid::new(&tp.points, 1.0);
        let k = 200 * 10;
        let l = g.local(tp.points[k], tp.points[k + 1], g.arc(k)).unwrap();
        assert!(l.normal.z.abs() < 1e-6, "{l:?}");
        assert!((l.spacing - 0.3).abs() < 0.01, "{l:?}");
    }

    #[test]
    fn spacing_is_measured_the_same_however_the_samples_are_listed() {
        // two helices of pitch 0.3 far apart: the samples' box spans more
        // cubes than the array takes, so they are listed in a map
        let mut tp = Toolpath::new(DVec3::new(10.0, 0.0, 0.0));
        for far in [0.0, 1e6] {
            for i in 1..=200 * 10 {
                let a = std::f64::consts::TAU * i as f64 / 200.0;
                let z = 0.3 * i as f64 / 200.0;
                tp.draw(
                    DVec3::new(far + 10.0 * a.cos(), 10.0 * a.sin(), z),
                    0.1,
                    30.0,
                );
            }
        }
        let step = (tp.points.len() / 1024).max(1);
        let samples: Vec<(DVec3, f64)> =
            tp.points.iter().step_by(step).map(|p| (*p, 0.0)).collect();
        let r = DVec3::splat(2.5);
        assert!(matches!(Near::new(&samples, r, 0.5), Near::Map(_)));
        assert!(matches!(
            Near::new(&samples[..10], r, 0.5),
            Near::Dense { .. }
        ));
        // the array lists what the map lists
        let Near::Map(map) = Near::new(&samples, r, 0.5) else {
            unreachable!()
        };
        let dense = Near::new(&samples[..500], r, 0.5);
        for (c, list) in &map {
            let want: Vec<u32> = list.iter().copied().filter(|&i| i < 500).collect();
            assert_eq!(dense.get(*c), &want[..], "{c:?}");
        }
        assert!(dense.get([1 << 40, 0, 0]).is_empty());
        // and the spacing is the median a grid of all the strings finds
        let h = pass_spacing(&tp.points).unwrap();
        assert!((h - 0.3).abs() < 0.01, "{h}");
        for parts in [1, 3] {
            let g = Grid::new_on(&tp.points, 2.0, parts);
            assert_eq!(h, median_nearest(&g, &tp.points, step));
        }
    }

    #[test]
    fn a_grid_in_parts_finds_what_one_grid_finds() {
        let mut tp = Toolpath::new(DVec3::new(5.0, 0.0, 0.0));
        for i in 1..=100 * 30 {
            let a = std::f64::consts::TAU * i as f64 / 100.0;
            tp.draw(
                DVec3::new(5.0 * a.cos(), 5.0 * a.sin(), 0.2 * i as f64 / 100.0),
                0.1,
                30.0,
            );
        }
        let one = Grid::new(&tp.points, 0.6);
        for parts in [2, 3, 7] {
            let many = Grid::new_on(&tp.points, 0.6, parts);
            for k in (0..tp.points.len() - 1).step_by(7) {
                let (a, b) = (tp.points[k], tp.points[k + 1]);
                let sm = (one.arc(k) + one.arc(k + 1)) / 2.0;
                for hint in [None, Some(k.saturating_sub(100))] {
                    assert_eq!(
                        one.local_near(a, b, sm, hint, false),
                        many.local_near(a, b, sm, hint, false),
                        "{parts} {k}"
                    );
                }
            }
        }
    }

    #[test]
    fn formats_by_extension() {
        assert_eq!(Format::of(Path::new("a/b.PNG")).unwrap(), Format::Png);
        assert_eq!(Format::of(Path::new("x.html")).unwrap(), Format::Html);
        assert!(Format::of(Path::new("x.jpg")).is_err());
        assert!(Format::of(Path::new("x")).is_err());
    }
}

#[cfg(test)]
mod flag_tests {
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
