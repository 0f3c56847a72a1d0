//! Support: every string rests on the bed or on filament printed before it
//! (Kanada's second condition for printing parts one after another).
//!
//! A string of cross-section c is taken as a bead of width w = the diameter of
//! a round bead of area c (Kanada's "0.196 mm², a 0.5 mm string"), but at
//! least the nozzle's diameter (the nozzle presses a thin string flat). Two
//! strings touch when their centre lines come closer than `support_tolerance`
//! × the mean of their widths; the bed holds a string whose centre line is at
//! most `support_tolerance` × w high. Each extruding string is sampled about
//! every w along its length, and each sample looks for earlier filament:
//! first the string that held the sample before and the next few after it
//! (on a helix, the turn below, string after string), else in the hashed
//! grid ([`super::grid`]) round it, newest first, stopping at the first
//! string it touches. The strings just laid before a sample on the
//! same path do not count: a candidate of the same part must lie farther
//! along the path than 3 × its distance in space (and than w), so a helix
//! rests on its previous turn and not on its own tail.
//!
//! Overhang is fine so long as the string touches what is under or beside it
//! (Kanada's sphere closes its top with near-horizontal turns, each leaning on
//! the one before). Consecutive unsupported samples make a run: a run with
//! supported ends is a `bridge` (a note up to `checks.max_bridge`, a warning
//! beyond), any other run longer than the string's width is `unsupported`
//! (an error: the string hangs from one end or floats). A declared hair (a
//! turtle's `hair:`, [`crate::base::toolpath::Strand::hair`]) hangs on purpose: it
//! is neither sampled nor support for later strings. Findings are one per
//! part and kind, with the run count, the total length of path (and the
//! filament it carries), the longest run, the place of the first run and the
//! worst overhang: how far sideways a sample reaches past the edge of the
//! nearest earlier filament at or below it (within [`GAP_SEARCH`] mm; a run
//! with nothing below it that close is reported as floating, with its height).

use glam::DVec3;

use super::{fmt_p, Finding, Severity};
use crate::base::geom::grid::{ceil_i64, closest, SegGrid};
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;

/// Width of a string of cross-section `c`: a round bead's diameter, at least the nozzle's.
#[inline]
pub(crate) fn width(c: f64, nozzle: f64) -> f64 {
    (2.0 * (c.max(0.0) / std::f64::consts::PI).sqrt()).max(nozzle)
}

/// [`width`] of strings taken in turn, worked out again only when the
/// cross-section changes (strings in a row mostly share one: a square root
/// and a division saved on each); the same bits in, the same width out.
pub(crate) struct Widths {
    nozzle: f64,
    /// The last cross-section and its width.
    last: (f64, f64),
}

impl Widths {
    /// Widths for a nozzle of this diameter.
    pub(crate) fn new(nozzle: f64) -> Widths {
        Widths {
            nozzle,
            last: (f64::NAN, width(f64::NAN, nozzle)),
        }
    }

    /// [`width`] of a string of cross-section `c`.
    #[inline]
    pub(crate) fn of(&mut self, c: f64) -> f64 {
        if c.to_bits() != self.last.0.to_bits() {
            self.last = (c, width(c, self.nozzle));
        }
        self.last.1
    }
}

/// How far beyond the search radius an unsupported sample looks for the
/// nearest filament, to say how far it hangs, mm.
const GAP_SEARCH: f64 = 5.0;
/// Strings listed near one sample (the grid's cubes round it) looked at for
/// one that holds it up; past this many it is held (see `rests`). The
/// gallery and tests/checks/ list at most 543 (the bowl).
const MAX_HOLDERS: usize = 4096;
/// Strings listed within [`GAP_SEARCH`] of one unsupported sample looked at
/// for its overhang; the gallery lists at most 8,261 (the brush).
const MAX_NEAR: usize = 32768;
/// Unsupported samples whose overhang is measured (the rest use the bed).
const GAP_BUDGET: usize = 20_000;

/// Points between the path lengths [`PathLength`] keeps.
const ARC_EVERY: usize = 16;

/// A path's length before each of its points, kept every [`ARC_EVERY`]
/// points and summed on from there (or from the last one asked, when that
/// is nearer): the same additions in the same order as a table of every
/// point, so the same bits, in 1/16 of the memory (a search asks in no
/// order: a walk of 8 lengths on average, not 32).
struct PathLength {
    /// The length before points 0, 16, 32 …
    every: Vec<f64>,
    /// The last point asked for and its length.
    cursor: std::cell::Cell<(usize, f64)>,
}

impl PathLength {
    /// The length before point `k` of `points`.
    fn at(&self, points: &[DVec3], k: usize) -> f64 {
        let base = k - k % ARC_EVERY;
        let (mut j, mut acc) = self.cursor.get();
        if !(base..=k).contains(&j) {
            (j, acc) = (base, self.every[k / ARC_EVERY]);
        }
        while j < k {
            acc += points[j].distance(points[j + 1]);
            j += 1;
        }
        self.cursor.set((k, acc));
        acc
    }
}

/// The extruding strings of all paths in print order, and the grid over them.
pub(crate) struct Deposits<'a> {
    /// The paths, in print order.
    pub(crate) paths: &'a [&'a Toolpath],
    /// (path, string) of each extruding string of nonzero length, in print
    /// order ([`Deposits::id`]); none kept when they are the strings of
    /// the first path in order (one part: 16 MB for 2M strings).
    ids: Vec<(u32, u32)>,
    /// How many deposits there are.
    count: usize,
    /// Per path, the path length before each point.
    arc: Vec<PathLength>,
    /// The grid over `ids[..built]`, made when a search first needs it and
    /// remade (at least twice as large) when a search needs later deposits.
    grid: std::cell::RefCell<(SegGrid, usize)>,
    /// Side of the grid's cubes, mm.
    cell: f64,
    /// Widest string, mm.
    pub(crate) w_max: f64,
    /// Nozzle diameter, mm (the narrowest string).
    pub(crate) nozzle: f64,
}

impl<'a> Deposits<'a> {
    /// Lists and grids the extruding strings of `paths`.
    pub(crate) fn new(paths: &'a [&'a Toolpath], nozzle: f64, tolerance: f64) -> Deposits<'a> {
        let total: usize = paths.iter().map(|tp| tp.len()).sum();
        let mut ids: Vec<(u32, u32)> = Vec::new();
        let (mut count, mut listed) = (0usize, false);
        let mut arc = Vec::with_capacity(paths.len());
        let mut c_max = f64::NEG_INFINITY;
        for (p, tp) in paths.iter().enumerate() {
            let mut s = Vec::with_capacity(tp.points.len() / ARC_EVERY + 1);
            let mut acc = 0.0;
            s.push(0.0);
            for (k, (st, ab)) in tp.strings.iter().zip(tp.points.windows(2)).enumerate() {
                let l = ab[0].distance(ab[1]);
                acc += l;
                if (k + 1) % ARC_EVERY == 0 {
                    s.push(acc);
                }
                // a hair holds nothing up: it is no deposit
                if !st.travel && !st.hair && l > 0.0 {
                    if !listed && (p, k) != (0, count) {
                        // no longer the first path's strings in order: the
                        // deposits so far listed, with room for every string
                        // (a vector doubling as it grows copies itself and
                        // faults its pages in again)
                        listed = true;
                        ids = crate::base::mem::with_capacity(total);
                        ids.extend((0..count).map(|k| (0, k as u32)));
                    }
                    if listed {
                        ids.push((p as u32, k as u32));
                    }
                    count += 1;
                    c_max = c_max.max(st.c);
                }
            }
            arc.push(PathLength {
                every: s,
                cursor: std::cell::Cell::new((0, 0.0)),
            });
        }
        // the widest string is the one of the largest cross-section (a
        // width is a chain of rounded steps that never decrease in c), at
        // least the nozzle: one square root, not one a string
        let w_max = width(c_max, nozzle);
        // cubes twice the widest reach: a sample's neighbours lie in ≤ 8 cubes
        let cell = (2.0 * tolerance * w_max).clamp(0.5, 8.0);
        Deposits {
            paths,
            ids,
            count,
            arc,
            grid: std::cell::RefCell::new((
                SegGrid::build(0, cell, |_| (DVec3::ZERO, DVec3::ZERO)),
                0,
            )),
            cell,
            w_max,
            nozzle,
        }
    }

    /// Calls `f` on the deposits before `g` within `r` of `p` (see
    /// [`SegGrid::search`]), until it says stop; whether it did.
    pub(crate) fn search(&self, p: DVec3, r: f64, g: u32, f: impl FnMut(u32) -> bool) -> bool {
        let mut grid = self.grid.borrow_mut();
        if (g as usize) > grid.1 {
            // a helix mostly finds its support by coherence: grids are made
            // rarely, and each at least doubles, so all cost ≤ 2 full ones
            let n = (g as usize).max(2 * grid.1).min(self.count);
            *grid = (SegGrid::build(n, self.cell, |i| self.ends(i as u32)), n);
        }
        grid.0.search(p, r, g, f)
    }

    /// Path `p`'s length before its point `k`, mm.
    pub(crate) fn arc(&self, p: usize, k: usize) -> f64 {
        self.arc[p].at(&self.paths[p].points, k)
    }

    /// Ends of deposit i.
    #[inline]
    pub(crate) fn ends(&self, i: u32) -> (DVec3, DVec3) {
        let (p, k) = self.id(i);
        self.paths[p as usize].ends(k as usize)
    }

    /// (path, string) of deposit `j`.
    #[inline]
    pub(crate) fn id(&self, j: u32) -> (u32, u32) {
        if self.ids.is_empty() {
            (0, j)
        } else {
            self.ids[j as usize]
        }
    }

    #[cfg(test)]
    /// How many deposits there are.
    pub(crate) fn len(&self) -> usize {
        self.count
    }
}

/// One run of unsupported samples.
#[derive(Clone, Copy)]
struct Run {
    first: DVec3,
    first_k: usize,
    /// The last string of the run.
    last_k: usize,
    len: f64,
    /// Filament the run carries, as mm³ (c × length).
    vol: f64,
    before: Option<DVec3>,
    width: f64,
    worst: f64,
    worst_at: DVec3,
    /// The largest height over the filament below, mm.
    drop: f64,
    floating: Option<(f64, DVec3)>,
}

/// Unsupported runs or bridges of one part.
#[derive(Default)]
struct Tally {
    runs: usize,
    len: f64,
    vol: f64,
    /// The longest run's length of path, mm.
    longest_run: f64,
    /// The largest height of a sample over the filament below it, mm.
    drop: f64,
    /// The highest sample with no filament below it within reach: (height, place).
    floating: Option<(f64, DVec3)>,
    first: Option<(usize, DVec3)>,
    /// The runs' strings, [first, end).
    spans: Vec<[usize; 2]>,
    worst: f64,
    worst_at: DVec3,
    longest: f64,
    longest_at: DVec3,
}

impl Tally {
    fn add(&mut self, r: &Run, span: f64, middle: DVec3) {
        self.runs += 1;
        self.spans.push([r.first_k, r.last_k + 1]);
        self.len += r.len;
        self.vol += r.vol;
        self.longest_run = self.longest_run.max(r.len);
        self.drop = self.drop.max(r.drop);
        if let Some((h, at)) = r.floating {
            if self.floating.is_none_or(|(f, _)| h > f) {
                self.floating = Some((h, at));
            }
        }
        self.first.get_or_insert((r.first_k, r.first));
        if r.worst > self.worst || self.runs == 1 {
            self.worst = r.worst;
            self.worst_at = r.worst_at;
        }
        if span > self.longest {
            self.longest = span;
            self.longest_at = middle;
        }
    }
}

/// The support check: `unsupported` and `bridge` findings, one per part and
/// kind.
pub(crate) fn check(recipe: &Recipe, paths: &[&Toolpath]) -> Vec<Finding> {
    let mut out = Vec::new();
    let p = &recipe.printer;
    let dep = Deposits::new(paths, p.nozzle_diameter, p.checks.support_tolerance);
    let mut budget = GAP_BUDGET;
    let mut g = 0u32; // global id of the current string
                      // the whole print's extruding path, which a part's bridges are weighed against
    let print: f64 = paths
        .iter()
        .flat_map(|tp| {
            (0..tp.len())
                .filter(|&i| !tp.strings[i].travel)
                .map(|i| tp.length(i))
        })
        .sum();
    for (pi, tp) in paths.iter().enumerate() {
        let t = scan_part(recipe, &dep, pi, tp, &mut g, &mut budget);
        let area = filament_area(recipe);
        out.extend(unsupported_finding(tp, &t.unsup, area));
        out.extend(bridge_finding(
            tp,
            &t.bridges,
            (t.bridge_max, p.checks.max_bridge),
            print,
            area,
        ));
    }
    out
}

/// The filament's cross-section, mm² (the material's diameter, else the printer's).
pub(crate) fn filament_area(recipe: &Recipe) -> f64 {
    let d = recipe
        .material
        .filament_diameter
        .unwrap_or(recipe.printer.filament_diameter);
    std::f64::consts::PI * 0.25 * d * d
}

/// What the support check found in one part.
struct PartTally {
    unsup: Tally,
    bridges: Tally,
    /// Bridges longer than `checks.max_bridge`.
    bridge_max: usize,
}

/// Samples every extruding string of part `pi` for support, counting the
/// part's strings on from `g` and spending the gap `budget`.
fn scan_part(
    recipe: &Recipe,
    dep: &Deposits,
    pi: usize,
    tp: &Toolpath,
    g: &mut u32,
    budget: &mut usize,
) -> PartTally {
    let p = &recipe.printer;
    let tol = p.checks.support_tolerance;
    // the path length before string k, summed as `Deposits::arc` sums it
    let mut arc_k = 0.0;
    let mut runs = Runs {
        max_bridge: p.checks.max_bridge,
        tally: PartTally {
            unsup: Tally::default(),
            bridges: Tally::default(),
            bridge_max: 0,
        },
        run: None,
        pts: Vec::new(),
    };
    let mut last_ok: Option<DVec3> = None;
    let mut hint: Option<u32> = None;
    let mut widths = Widths::new(p.nozzle_diameter);
    for (k, s) in tp.strings.iter().enumerate() {
        let (a, b) = tp.ends(k);
        let l = a.distance(b);
        let before = arc_k;
        arc_k += l;
        if s.travel {
            runs.close(None);
            last_ok = None;
            hint = None;
            continue;
        }
        if l <= 0.0 {
            continue;
        }
        if s.hair {
            // a declared hair hangs in the air on purpose: not sampled, and
            // not a deposit (so `g` does not count it); the run before it
            // ends unsupported, as before a travel
            runs.close(None);
            last_ok = None;
            hint = None;
            continue;
        }
        let w = widths.of(s.c);
        // l is finite (the geometric checks run on finite points only) and
        // w > 0, so l / w is never NaN: libm's ceil, clamped and cast
        let n = ceil_i64(l / w).clamp(1, 1_000_000) as usize;
        for i in 0..n {
            let u = (i as f64 + 0.5) / n as f64;
            let q = a.lerp(b, u);
            let sq = before + u * l;
            let ok = q.z <= tol * w || {
                hint = rests(dep, *g, pi as u32, sq, q, w, tol, hint);
                hint.is_some()
            };
            if ok {
                if runs.run.is_some() {
                    runs.close(Some(q));
                }
                last_ok = Some(q);
                continue;
            }
            // the sideways reach past the nearest filament below; None when
            // nothing lies below within GAP_SEARCH (or the budget is spent)
            let reach = if *budget > 0 {
                *budget -= 1;
                overhang(dep, *g, pi as u32, sq, q, w)
            } else {
                None
            };
            let piece = Piece { k, l, n, c: s.c, w };
            runs.extend(piece, q, last_ok, reach, *budget > 0);
        }
        *g += 1;
    }
    runs.close(None);
    runs.tally
}

/// An extruding string as its samples see it.
#[derive(Clone, Copy)]
struct Piece {
    /// Its index in the part.
    k: usize,
    /// Its length, mm.
    l: f64,
    /// How many samples it takes (about one per width).
    n: usize,
    /// Its cross-section, mm².
    c: f64,
    /// Its width (see [`width`]).
    w: f64,
}

/// The runs of unsupported samples of one part: the open one and its
/// samples, and the tallies of those closed.
struct Runs {
    /// `checks.max_bridge`, mm.
    max_bridge: f64,
    /// The closed runs.
    tally: PartTally,
    /// The open run, if the last sample was unsupported.
    run: Option<Run>,
    /// The samples of the open run.
    pts: Vec<DVec3>,
}

impl Runs {
    /// Adds unsupported sample `q`, one of the `n` of string `s`, to the
    /// open run (opening one after `before`, the last supported sample):
    /// l / n of path, c·l / n of filament, and its `reach` past the
    /// filament below (see `overhang`); with no reach while the overhang
    /// budget is not spent (`spare`), the run floats at the sample's height.
    fn extend(
        &mut self,
        s: Piece,
        q: DVec3,
        before: Option<DVec3>,
        reach: Option<(f64, f64)>,
        spare: bool,
    ) {
        let r = self.run.get_or_insert(Run {
            first: q,
            first_k: s.k,
            last_k: s.k,
            len: 0.0,
            vol: 0.0,
            before,
            width: s.w,
            worst: 0.0,
            worst_at: q,
            drop: 0.0,
            floating: None,
        });
        r.last_k = s.k;
        r.len += s.l / s.n as f64;
        r.vol += s.c * s.l / s.n as f64;
        match reach {
            Some((x, drop)) => {
                if x > r.worst || r.worst_at == q {
                    r.worst = x;
                    r.worst_at = q;
                }
                r.drop = r.drop.max(drop);
            }
            None if spare && r.floating.is_none_or(|(h, _)| q.z > h) => {
                r.floating = Some((q.z, q));
            }
            _ => {}
        }
        self.pts.push(q);
    }

    /// Closes the open run, if any, before `after` (the supported sample
    /// that ends it; None at a travel, a hair or the part's end): a run no
    /// longer than its string's width is nothing, one held at both ends a
    /// bridge (its span end to end), any other unsupported.
    fn close(&mut self, after: Option<DVec3>) {
        let Some(r) = self.run.take() else { return };
        let middle = self.pts[self.pts.len() / 2];
        self.pts.clear();
        if r.len <= r.width {
            return; // a string may hang out by its own width
        }
        match (r.before, after) {
            (Some(a), Some(b)) => {
                let span = a.distance(b);
                if span > self.max_bridge {
                    self.tally.bridge_max += 1;
                }
                self.tally.bridges.add(&r, span, middle);
            }
            _ => self.tally.unsup.add(&r, r.len, r.first),
        }
    }
}

/// The `unsupported` finding of a part, if it has unsupported runs;
/// `area` is the filament's cross-section, mm².
fn unsupported_finding(tp: &Toolpath, unsup: &Tally, area: f64) -> Option<Finding> {
    let (k, at) = unsup.first?;
    let mut worst = Vec::new();
    if unsup.drop > 0.0 {
        worst.push(format!(
            "at worst it reaches {:.2} mm sideways past the edge of the filament below, at {}, and hangs up to {:.2} mm over it",
            unsup.worst,
            fmt_p(unsup.worst_at),
            unsup.drop
        ));
    }
    if let Some((h, p)) = unsup.floating {
        worst.push(format!(
            "with nothing printed within {GAP_SEARCH} mm below, it hangs up to {h:.2} mm over the bed, at {}",
            fmt_p(p)
        ));
    }
    let worst = worst.join("; ");
    Some(Finding {
        code: "unsupported",
        severity: Severity::Error,
        message: format!(
            "{} run{} of part `{}` ({:.1} mm of path, {:.1} mm of filament; the longest run {:.1} mm) rest{} on neither the bed nor earlier filament; the first starts at string {k}, {}; {worst}",
            unsup.runs,
            if unsup.runs == 1 { "" } else { "s" },
            tp.name,
            unsup.len,
            unsup.vol / area,
            unsup.longest_run,
            if unsup.runs == 1 { "s" } else { "" },
            fmt_p(at),
        ),
        part: Some(tp.name.clone()),
        string: Some(k),
        at: Some(at.to_array()),
        strings: unsup.spans.clone(),
    })
}

/// More than this share of the print's extruding path bridging gaps in one
/// part makes its `bridge` finding a warning, however short the gaps (a vase
/// whose wall hangs between supports all the way round; a lone span
/// between two posts stays a note).
pub(crate) const BRIDGED_SHARE: f64 = 0.5;

/// The `bridge` finding of a part, if it bridges gaps; a warning when
/// `bridge_max` of them are longer than `max_bridge` mm, or when they are
/// more than [`BRIDGED_SHARE`] of the `print`'s extruding path (mm).
fn bridge_finding(
    tp: &Toolpath,
    bridges: &Tally,
    (bridge_max, max_bridge): (usize, f64),
    print: f64,
    area: f64,
) -> Option<Finding> {
    let (k, _) = bridges.first?;
    // most of the print laid over gaps is no detail, however short each
    // gap: the summary must not call it a note
    let share = if print > 0.0 {
        bridges.len / print
    } else {
        0.0
    };
    let mostly = share > BRIDGED_SHARE;
    let long = bridge_max > 0;
    let also = if mostly {
        format!(
            "; that is {:.0} % of the print's path hanging over gaps (more than {:.0} %): print slowly with the fan on, or check the design",
            100.0 * share,
            100.0 * BRIDGED_SHARE
        )
    } else {
        String::new()
    };
    Some(Finding {
        code: "bridge",
        severity: if long || mostly {
            Severity::Warning
        } else {
            Severity::Info
        },
        message: format!(
            "part `{}` bridges {} gap{} ({:.1} mm of path, {:.1} mm of filament, with nothing under it); the longest spans {:.1} mm, its middle at {}{}",
            tp.name,
            bridges.runs,
            if bridges.runs == 1 { "" } else { "s" },
            bridges.len,
            bridges.vol / area,
            bridges.longest,
            fmt_p(bridges.longest_at),
            if long {
                format!(
                    "; {bridge_max} longer than the {} mm a bridge holds (checks.max_bridge): print slowly with the fan on, or add support",
                    max_bridge
                )
            } else {
                String::new()
            }
        ) + &also,
        part: Some(tp.name.clone()),
        string: Some(k),
        at: Some(bridges.longest_at.to_array()),
        strings: bridges.spans.clone(),
    })
}

/// Whether deposit `j` holds up a sample at `q` (width `w`) that lies `sq`
/// along path `pi`: it passes within touching distance, not above the
/// sample, and it is not the sample's own tail (a deposit of the same path
/// must lie farther back along it than 3 × its distance in space, and than w).
#[inline]
fn holds(dep: &Deposits, j: u32, pi: u32, sq: f64, q: DVec3, w: f64, tol: f64) -> bool {
    let (pj, kj) = dep.id(j);
    let tp = dep.paths[pj as usize];
    let k = kj as usize;
    let (a, b) = (tp.points[k], tp.points[k + 1]);
    let u = closest(q, a, b);
    let x = a.lerp(b, u);
    let d = q.distance(x);
    if d > tol * (w + dep.w_max) / 2.0 || x.z > q.z + 0.25 * w {
        return false;
    }
    // its own width only when the narrowest could not reach: a width is
    // at least the nozzle, and tol > 0 (validated), so every rounded step
    // of the bound keeps that order
    if d > tol * (w + dep.nozzle) / 2.0 && d > tol * (w + width(tp.strings[k].c, dep.nozzle)) / 2.0
    {
        return false;
    }
    if pj != pi {
        return true;
    }
    let (s0, s1) = (dep.arc(pj as usize, k), dep.arc(pj as usize, k + 1));
    let sj = s0 + u * (s1 - s0);
    sq - sj > (3.0 * d).max(w)
}

/// The deposit (printed before string `g`) that holds up a sample at `q`, if
/// any: first the one that held the sample before and the next few after it
/// (a helix rests on its previous turn string after string), then the grid.
#[allow(clippy::too_many_arguments)]
fn rests(
    dep: &Deposits,
    g: u32,
    pi: u32,
    sq: f64,
    q: DVec3,
    w: f64,
    tol: f64,
    hint: Option<u32>,
) -> Option<u32> {
    if let Some(h) = hint {
        // the deposit after the last holder first: along a helix the
        // deposit under the samples moves on by one a string (the found
        // holder is only the next hint: whether one holds is the same
        // whichever is tried first, as the grid search below finds any)
        for j in [1, 0, 2, 3].map(|i| h.saturating_add(i)) {
            if j < g && holds(dep, j, pi, sq, q, w, tol) {
                return Some(j);
            }
        }
    }
    let reach = tol * (w + dep.w_max) / 2.0;
    let mut found = None;
    let mut visits = 0;
    dep.search(q, reach, g, |j| {
        // a pile of strings over one place (a path retracing a line a
        // million times) lists them all near every sample above it; a
        // sample with more than MAX_HOLDERS strings round it stands on a
        // pile, and counts as held (2M strings under 200 ran for minutes)
        visits += 1;
        if visits > MAX_HOLDERS {
            found = Some(j);
            return true;
        }
        let ok = holds(dep, j, pi, sq, q, w, tol);
        if ok {
            found = Some(j);
        }
        ok
    });
    found
}

/// How far an unsupported sample of width `w` overhangs: the least
/// horizontal distance from its centre to the edge of earlier filament below
/// it (lower by at least w / 2, within [`GAP_SEARCH`] mm), less half its own
/// width, at least 0, and its height over that filament (centre lines);
/// `None` when no earlier filament lies below it that close.
fn overhang(dep: &Deposits, g: u32, pi: u32, sq: f64, q: DVec3, w: f64) -> Option<(f64, f64)> {
    // (3D distance, reach, drop) of the one reached past least
    let mut best: Option<(f64, f64, f64)> = None;
    let mut visits = 0;
    dep.search(q, GAP_SEARCH, g, |j| {
        // a figure for the message: the nearest of the first MAX_NEAR
        // strings listed near the sample (newest first) is near enough
        visits += 1;
        if visits > MAX_NEAR {
            return true;
        }
        let (pj, kj) = dep.id(j);
        let k = kj as usize;
        let tp = dep.paths[pj as usize];
        let (a, b) = tp.ends(k);
        let u = closest(q, a, b);
        let x = a.lerp(b, u);
        let d = q.distance(x);
        // below: lower by at least half the width (not the string's own
        // earlier part at nearly its height)
        if x.z > q.z - w / 2.0 || d > GAP_SEARCH {
            return false;
        }
        let own_tail = pj == pi && {
            let (s0, s1) = (dep.arc(pj as usize, k), dep.arc(pj as usize, k + 1));
            sq - (s0 + u * (s1 - s0)) <= (3.0 * d).max(w)
        };
        if !own_tail {
            let wj = width(tp.strings[k].c, dep.nozzle);
            let reach = (q.truncate().distance(x.truncate()) - (w + wj) / 2.0).max(0.0);
            if best.is_none_or(|b| (reach, d) < (b.1, b.0)) {
                best = Some((d, reach, q.z - x.z));
            }
        }
        false
    });
    best.map(|b| (b.1, b.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths() {
        // Kanada's 0.196 mm² is a 0.5 mm string; thin strings are pressed to the nozzle
        assert!((width(0.196, 0.4) - 0.49956).abs() < 1e-4);
        assert_eq!(width(0.01, 0.4), 0.4);
        assert_eq!(width(-1.0, 0.4), 0.4);
        // taken in turn, repeated or not, the same bits as one at a time
        let mut ws = Widths::new(0.4);
        for c in [
            f64::NAN,
            0.196,
            0.196,
            0.0,
            -0.0,
            3.5,
            f64::NAN,
            0.01,
            0.196,
        ] {
            assert_eq!(ws.of(c).to_bits(), width(c, 0.4).to_bits(), "{c}");
        }
    }

    fn helix(pitch: f64, turns: usize, c: f64) -> Toolpath {
        let mut tp = Toolpath::new(DVec3::new(10.0, 0.0, 0.2));
        tp.name = "h".into();
        let n = 72;
        for i in 1..=turns * n {
            let t = i as f64 / n as f64;
            let th = std::f64::consts::TAU * t;
            tp.draw(
                DVec3::new(10.0 * libm::cos(th), 10.0 * libm::sin(th), 0.2 + pitch * t),
                c,
                30.0,
            );
        }
        tp
    }

    /// A recipe of the default printer (the paths are given by the tests).
    fn recipe() -> Recipe {
        crate::recipe::resolve(
            &crate::recipe::parse_yaml(
                "p3dp: 1\nname: t\nparts:\n  - primitive: {circle: {radius: 1}}\n",
                "t.yaml",
            )
            .unwrap(),
            &[],
            None,
            std::path::Path::new("."),
        )
        .unwrap()
    }

    fn run(tps: &[Toolpath]) -> Vec<Finding> {
        let refs: Vec<&Toolpath> = tps.iter().collect();
        check(&recipe(), &refs)
    }

    #[test]
    fn a_helix_rests_on_its_previous_turn() {
        assert!(run(&[helix(0.3, 5, 0.15)]).is_empty());
    }

    #[test]
    fn the_widest_deposit_is_the_widest_of_every_string() {
        // cross-sections up and down, thin, negative and NaN ones, a
        // travel (not a deposit: its huge c does not count) and a hair
        let mut tp = Toolpath::new(DVec3::ZERO);
        let cs = [0.1, 0.31, f64::NAN, -2.0, 0.3, 0.0001, 0.31 + 1e-12, 0.2];
        for (k, &c) in cs.iter().enumerate() {
            tp.draw(DVec3::new(k as f64 + 1.0, 0.0, 0.2), c, 30.0);
        }
        tp.travel(DVec3::new(20.0, 0.0, 0.2), 100.0);
        tp.strings.make_mut().last_mut().unwrap().c = 50.0;
        tp.draw(DVec3::new(21.0, 0.0, 0.2), 0.15, 30.0);
        let refs = [&tp];
        let dep = Deposits::new(&refs, 0.4, 1.5);
        let each = tp
            .strings
            .iter()
            .filter(|s| !s.travel)
            .map(|s| width(s.c, 0.4))
            .fold(0.4, f64::max);
        assert_eq!(dep.w_max.to_bits(), each.to_bits());
        assert_eq!(dep.w_max, width(0.31 + 1e-12, 0.4));
        assert_eq!(dep.len(), cs.len() + 1);
        // the deposits are listed past the travel (string 8), the same
        // (path, string) as a list of every one gives
        let want: Vec<(u32, u32)> = (0..8).chain(9..10).map(|k| (0, k)).collect();
        let got: Vec<(u32, u32)> = (0..dep.len() as u32).map(|j| dep.id(j)).collect();
        assert_eq!(got, want);
        // one path of extruding strings: its strings in order, none listed
        let h = helix(0.3, 2, 0.15);
        let two = [&h, &tp];
        let dep = Deposits::new(&two[..1], 0.4, 1.5);
        assert!(dep.ids.is_empty());
        assert_eq!(dep.len(), h.len());
        assert_eq!(dep.id(7), (0, 7));
        // a second path lists them all
        let dep = Deposits::new(&two, 0.4, 1.5);
        assert_eq!(dep.len(), h.len() + 9);
        assert_eq!(dep.id(7), (0, 7));
        assert_eq!(dep.id(h.len() as u32 + 8), (1, 9));
    }

    #[test]
    fn path_lengths_kept_every_64_points_are_a_full_table_s_bits() {
        // a wobbling helix, so the lengths differ string by string
        let mut tp = Toolpath::new(DVec3::new(10.0, 0.0, 0.2));
        for k in 1..1000 {
            let a = k as f64 * 0.1;
            let r = 10.0 + libm::sin(k as f64 * 0.37);
            tp.draw(
                DVec3::new(r * libm::cos(a), r * libm::sin(a), 0.2 + 0.001 * k as f64),
                0.1,
                30.0,
            );
        }
        let mut full = vec![0.0];
        for k in 0..tp.len() {
            full.push(full[k] + tp.length(k));
        }
        let refs = [&tp];
        let dep = Deposits::new(&refs, 0.4, 1.5);
        assert_eq!(dep.arc[0].every.len(), 1000 / ARC_EVERY + 1);
        // asked forwards, backwards, across blocks and again: the same bits
        let asks = (0..1000)
            .chain((0..1000).rev())
            .chain([999, 0, 640, 63, 64, 65, 700, 3]);
        for k in asks {
            assert_eq!(dep.arc(0, k).to_bits(), full[k].to_bits(), "point {k}");
        }
    }

    #[test]
    fn turns_that_do_not_touch_are_unsupported() {
        let f = run(&[helix(1.5, 3, 0.15)]);
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(f[0].code, "unsupported");
        // the first turn leaves the bed at 1.5 × its width (0.437 mm) and hangs from there
        let at = f[0].at.unwrap();
        assert!(at[2] > 0.64 && at[2] < 0.7, "{at:?}");
        assert!(f[0].message.contains("mm of path"), "{}", f[0].message);
    }

    /// A ring of radius 10 on the bed, then a helix from `z0` whose radius
    /// grows by `grow` a turn, `pitch` a turn, 3 turns, c = 0.15.
    fn ring_and_helix(z0: f64, pitch: f64, grow: f64) -> Vec<Toolpath> {
        let mut ring = Toolpath::new(DVec3::new(10.0, 0.0, 0.2));
        ring.name = "ring".into();
        let mut tp = Toolpath::new(DVec3::new(10.0, 0.0, z0));
        tp.name = "h".into();
        let n = 72;
        for i in 1..=3 * n {
            let t = i as f64 / n as f64;
            let th = std::f64::consts::TAU * t;
            let r = 10.0 + grow * t;
            tp.draw(
                DVec3::new(r * libm::cos(th), r * libm::sin(th), z0 + pitch * t),
                0.15,
                30.0,
            );
            if i <= n {
                ring.draw(
                    DVec3::new(10.0 * libm::cos(th), 10.0 * libm::sin(th), 0.2),
                    0.15,
                    30.0,
                );
            }
        }
        vec![ring, tp]
    }

    /// The number after `key` in `m`.
    fn after(m: &str, key: &str) -> f64 {
        let rest = m
            .split(key)
            .nth(1)
            .unwrap_or_else(|| panic!("{key} in {m}"));
        rest.split(' ').next().unwrap().parse().unwrap()
    }

    #[test]
    fn overhang_is_the_reach_past_the_filament_below() {
        // turns 1.5 mm apart straight over each other: no sideways reach;
        // the first turn climbs from 1.5 to 3 mm over the flat ring (its
        // last sample, half a string of 72 a turn short of it); lengths are
        // of path and the filament is c / area of it
        let f = run(&ring_and_helix(1.7, 1.5, 0.0));
        assert_eq!(f.len(), 1, "{f:?}");
        let m = &f[0].message;
        assert_eq!(after(m, "reaches "), 0.0, "{m}");
        let top = 1.5 + 1.5 * (1.0 - 0.5 / 72.0 / 2.0);
        assert!((after(m, "hangs up to ") - top).abs() < 0.02, "{m}");
        let path = after(m, "(");
        let filament = after(m, "mm of path, ");
        let area = std::f64::consts::PI * 0.875 * 0.875;
        assert!((filament - path * 0.15 / area).abs() < 0.1, "{m}");
        assert!(path > 3.0 * std::f64::consts::TAU * 10.0 * 0.95, "{m}");
        // a helix that widens by 2 mm a turn, 0.3 mm up a turn, reaches out
        // past the turn below by 2 − (0.437 + 0.437)/2 mm
        let f = run(&ring_and_helix(0.5, 0.3, 2.0));
        let m = &f[0].message;
        let want = 2.0 - width(0.15, 0.4);
        assert!((after(m, "reaches ") - want).abs() < 0.02, "{m}");
    }

    #[test]
    fn a_string_between_two_posts_is_a_bridge() {
        // two posts: small helices of radius 1 round x = -1 and x = 7
        let mut posts = Toolpath::new(DVec3::new(0.0, 0.0, 0.2));
        posts.name = "posts".into();
        for (k, cx) in [-1.0, 7.0].into_iter().enumerate() {
            if k == 1 {
                posts.travel(DVec3::new(cx - 1.0, 0.0, 0.2), 100.0);
            }
            for i in 1..=20 * 24 {
                let t = i as f64 / 24.0;
                let th = std::f64::consts::TAU * t * if k == 0 { 1.0 } else { -1.0 };
                let x = cx + if k == 0 { 1.0 } else { -1.0 } * libm::cos(th);
                posts.draw(DVec3::new(x, libm::sin(th), 0.2 + 0.2 * t), 0.15, 20.0);
            }
        }
        let mut span = Toolpath::new(DVec3::new(0.0, 0.0, 4.4));
        span.name = "span".into();
        span.draw(DVec3::new(6.0, 0.0, 4.4), 0.2, 10.0);
        let f = run(&[posts, span]);
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!((f[0].code, f[0].severity), ("bridge", Severity::Info));
        let at = f[0].at.unwrap();
        assert!(
            (at[0] - 3.0).abs() < 0.5 && (at[2] - 4.4).abs() < 1e-9,
            "{at:?}"
        );
    }
}
