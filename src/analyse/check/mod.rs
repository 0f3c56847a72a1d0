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
pub mod first_layer;
pub mod flow;
pub mod pattern;
pub mod starvation;
pub mod support;

use glam::DVec3;

pub use crate::base::finding::{
    apply_allow, failing, is_code, summary, validate_allow, Finding, Severity, CODES, SAFETY,
};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

use crate::base::threads::Threads;
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;

pub use crate::machine::{CheckLimits, Head};

/// Strings a long check goes through between two calls of its `between`
/// (see [`Tasks::new`]): about a millisecond of its work.
pub const BETWEEN: usize = 1 << 14;

pub(crate) fn fmt_p(p: DVec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z)
}

/// Runs every check on the toolpaths of `recipe` (skirt first, then parts):
/// the findings, and each part's footprint on the bed (none when a point is
/// not finite or out of reach, or a cheap check found an error that is not
/// in `allowed`, where the geometric checks do not run).
///
/// The cheap checks run first, and the geometric ones (support, first layer,
/// collision: their grids grow with the extent and the cross-sections) only
/// when the cheap ones found no error that is not allowed (a helix of radius
/// 1e4 mm or a cross-section of 1e7 mm² took 25 s and 5 GB before they
/// refused it). The costly checks are tasks ([`Tasks`]) that a pool worker
/// takes too when `threads` allows two; the findings are put together in
/// one fixed order, so they are the same whoever ran what.
pub fn run(
    recipe: &Recipe,
    paths: &[&Toolpath],
    allowed: &[String],
    threads: Threads,
) -> (Vec<Finding>, Vec<first_layer::Footprint>) {
    let tasks = Tasks::new(recipe, paths, allowed, &|| {});
    // a panic in the worker's tasks is raised when the scope ends
    rayon::in_place_scope(|s| {
        if threads.parallel() {
            s.spawn(|_| while tasks.run_next() {});
        }
        while tasks.run_next() {}
    });
    tasks.finish()
}

/// The costly checks of one plan as tasks that any thread may take, one at a
/// time, in any interleaving: each writes its findings to its own slot, and
/// [`Tasks::finish`] puts them together in one fixed order, so the findings
/// are the same whichever thread ran what. [`Tasks::new`] runs the cheap
/// checks first (see [`run`]); the geometric tasks are empty when those
/// found an error that is not allowed, or points the geometry cannot take.
pub struct Tasks<'a> {
    recipe: &'a Recipe,
    paths: &'a [&'a Toolpath],
    /// Called after each cheap pass over a part and every [`BETWEEN`]
    /// strings of the long tasks (the build plans the moves written so far
    /// there).
    between: &'a (dyn Fn() + Sync),
    geometric: bool,
    /// The cheap checks' findings, then the pattern helix's (put last).
    cheap: Vec<Finding>,
    pattern: Vec<Finding>,
    /// The next task to take (an index into [`Tasks::ORDER`]).
    next: AtomicUsize,
    /// How many tasks have finished.
    finished: AtomicUsize,
    slots: [OnceLock<Vec<Finding>>; 4],
    footprints: OnceLock<Vec<first_layer::Footprint>>,
    /// The first-layer check's candidates and its two halves, the findings
    /// made (into the first layer's slot) by whichever finishes second.
    bed: OnceLock<first_layer::Bed>,
    halves: std::sync::Mutex<Halves>,
}

/// The halves of the first-layer check done so far.
#[derive(Default)]
struct Halves {
    contacts: Option<Vec<Option<first_layer::Contact>>>,
    areas: Option<Vec<u64>>,
}

/// A task of [`Tasks`].
#[derive(Clone, Copy)]
enum Task {
    Support,
    /// The first layer's strings on the bed (its findings' slot).
    FirstLayer,
    Collision,
    Starvation,
    /// The first layer's contact area (the cover of its bands).
    FirstLayerArea,
}

impl<'a> Tasks<'a> {
    /// The order tasks are taken in: the longest first, so the last to
    /// finish is a short one (the first layer's check in two halves, each
    /// shorter than the support check: as one it was the longest task of
    /// the sphere, left to one thread while the other had nothing to do).
    /// The half that comes first finds the strings on the bed for both:
    /// the sphere's longest after support (its skirt and brim). The vase's
    /// collision check (36 ms), taken after both halves, was its last
    /// task while the other thread had nothing to do: it comes between.
    const ORDER: [Task; 5] = [
        Task::Support,
        Task::FirstLayerArea,
        Task::Collision,
        Task::FirstLayer,
        Task::Starvation,
    ];

    /// Runs the cheap checks (calling `between` after each pass over a part) and
    /// readies the costly ones (which call it every [`BETWEEN`] strings).
    pub fn new(
        recipe: &'a Recipe,
        paths: &'a [&'a Toolpath],
        allowed: &[String],
        between: &'a (dyn Fn() + Sync),
    ) -> Tasks<'a> {
        let mut out = Vec::new();
        temperatures(recipe, &mut out);
        // the geometric checks need finite points within reach (others are
        // errors): tested in the machine limits' pass over the points
        let mut sane = true;
        for tp in paths {
            sane &= machine_limits(recipe, tp, &mut out);
            between();
            strings(recipe, tp, &mut out);
            between();
            flow::cross_sections(recipe, tp, &mut out);
            out.extend(events(recipe, tp));
            between();
        }
        let cheap_error = out
            .iter()
            .any(|f| f.severity == Severity::Error && !allowed.iter().any(|a| a == f.code));
        // pattern_helix: parameters outside the paper's ranges, modulated strings
        let mut pattern = Vec::new();
        pattern::findings(recipe, paths, &mut pattern);
        Tasks {
            recipe,
            paths,
            between,
            geometric: !cheap_error && sane,
            cheap: out,
            pattern,
            next: AtomicUsize::new(0),
            finished: AtomicUsize::new(0),
            slots: Default::default(),
            footprints: OnceLock::new(),
            bed: OnceLock::new(),
            halves: Default::default(),
        }
    }

    /// Takes the next task and runs it on the caller's thread; false when
    /// none is left to take.
    pub fn run_next(&self) -> bool {
        let k = self.next.fetch_add(1, Ordering::Relaxed);
        let Some(&task) = Self::ORDER.get(k) else {
            return false;
        };
        let (recipe, paths) = (self.recipe, self.paths);
        let nozzle = recipe.printer.nozzle_diameter;
        let mut v = Vec::new();
        // whether `v` is the task's findings (the first layer's halves set
        // their slot themselves, the second to finish)
        let mut fill = true;
        match task {
            Task::Starvation => starvation::check(recipe, paths, &mut v),
            _ if !self.geometric => {}
            Task::Support => support::check(recipe, paths, self.between, &mut v),
            Task::FirstLayer | Task::FirstLayerArea => {
                fill = false;
                // the two halves of the first-layer check, on any threads
                let bed = self.bed.get_or_init(|| first_layer::Bed::of(paths, nozzle));
                let (contacts, areas) = if let Task::FirstLayer = task {
                    (
                        Some(bed.contacts(paths, first_layer::min_height(recipe))),
                        None,
                    )
                } else {
                    (None, Some(bed.areas(paths, nozzle)))
                };
                let mut h = self.halves.lock().unwrap_or_else(|e| e.into_inner());
                h.contacts = h.contacts.take().or(contacts);
                h.areas = h.areas.take().or(areas);
                if let (Some(c), Some(a)) = (&h.contacts, &h.areas) {
                    let mut found = Vec::new();
                    let _ = self
                        .footprints
                        .set(first_layer::findings(recipe, paths, c, a, &mut found));
                    let _ = self.slots[Task::FirstLayer as usize].set(found);
                }
            }
            Task::Collision => collision::check(recipe, paths, self.between, &mut v),
        }
        if let Some(slot) = self.slots.get(task as usize).filter(|_| fill) {
            let _ = slot.set(v);
        }
        self.finished.fetch_add(1, Ordering::Release);
        true
    }

    /// Whether every task has finished (on whichever thread).
    pub fn all_done(&self) -> bool {
        self.finished.load(Ordering::Acquire) == Self::ORDER.len()
    }

    /// Whether the findings so far (all of them once [`Tasks::all_done`]),
    /// those of the codes in `allows` silenced, fail a build at this
    /// strictness.
    pub fn fail(&self, allows: &[&[String]], strict: bool) -> bool {
        let done = self.slots.iter().filter_map(|s| s.get()).flatten();
        let mut all: Vec<Finding> = self
            .cheap
            .iter()
            .chain(done)
            .chain(&self.pattern)
            .cloned()
            .collect();
        for allow in allows {
            apply_allow(&mut all, allow);
        }
        !failing(&all, strict).is_empty()
    }

    /// Every finding in the one fixed order (the cheap checks', starvation,
    /// first layer, support, collision, the pattern helix's) and the parts'
    /// footprints. Every task must have run (see [`Tasks::run_next`]).
    pub fn finish(self) -> (Vec<Finding>, Vec<first_layer::Footprint>) {
        let [support, first_layer, collision, starvation] = self
            .slots
            .map(|s| s.into_inner().expect("every check task ran"));
        let mut out = self.cheap;
        for v in [starvation, first_layer, support, collision, self.pattern] {
            out.extend(v);
        }
        (out, self.footprints.into_inner().unwrap_or_default())
    }
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
            strings: Vec::new(),
        });
    };
    let pick = |bed: bool, limit: f64| -> Vec<(usize, f64)> {
        tp.events
            .iter()
            .filter_map(|&(k, e)| match e {
                crate::base::toolpath::Event::NozzleTemp { celsius, .. }
                    if !bed && celsius > limit =>
                {
                    Some((k, celsius))
                }
                crate::base::toolpath::Event::BedTemp { celsius, .. } if bed && celsius > limit => {
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
                "part `{}` has {n} string{} needing more than the hot end's {} mm³/s (up to {worst:.1} mm³/s{beyond}); the first is string {k} at {}",
                tp.name,
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
