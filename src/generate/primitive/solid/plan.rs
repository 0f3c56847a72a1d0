//! The plan of a solid: its layers, islands and strings.

use super::*;

impl Solid {
    /// A solid with its z-buffer computed (from `reuse`'s when a cache is
    /// lent: see [`Reusing`]); the error names the key at fault (relative to
    /// the primitive, as the recipe's resolution does).
    pub(crate) fn new(
        layer_height: f64,
        perimeters: u32,
        line_width: f64,
        chord_tolerance: f64,
        infill: Infill,
        features: Vec<Feature>,
        reuse: Option<&Reusing>,
    ) -> Result<Solid> {
        let settings = Settings {
            layer_height,
            perimeters,
            line_width,
            chord_tolerance,
            infill,
        };
        Solid::from_zbuffer(&zbuffer::cached(settings, features, reuse)?)
    }

    /// The solid printed from a z-buffer (its slabs shared, not recomputed);
    /// refused when it leaves nothing to print.
    pub(crate) fn from_zbuffer(zb: &ZBuffer) -> Result<Solid> {
        let st = zb.settings();
        let mut s = Solid {
            layer_height: st.layer_height,
            perimeters: st.perimeters,
            line_width: st.line_width,
            chord_tolerance: st.chord_tolerance,
            infill: st.infill,
            features: zb.features().to_vec(),
            slabs: Vec::new(),
            layer_slab: Vec::with_capacity(zb.layer_count() as usize),
            count: 0,
        };
        for slab in zb.layer_slabs() {
            let k = slab.map(|slab| match s.slabs.last() {
                Some(last) if Arc::ptr_eq(last, slab) => s.slabs.len() - 1,
                _ => {
                    s.slabs.push(Arc::clone(slab));
                    s.slabs.len() - 1
                }
            });
            s.layer_slab.push(k);
        }
        s.count = s.count();
        if s.count == 0 {
            return Err(Error::input(
                "solid.features",
                "the features leave nothing to print: every layer's cross-section above the bed is empty or thinner than line_width",
            ));
        }
        Ok(s)
    }
}

impl Settings {
    /// Computes the slab whose middle plane is `zm`; `None` when empty.
    pub(super) fn make_slab(&self, features: &[Feature], zm: f64) -> Option<Slab> {
        let shapes: Vec<(Option<Shape>, Op)> =
            features.iter().map(|f| (f.section(zm), f.op)).collect();
        let region = region::boolean(&shapes);
        if region.is_empty() {
            return None;
        }
        let w = self.line_width;
        let dirs = [
            infill::direction(self.infill.angle),
            infill::direction(-self.infill.angle),
        ];
        let islands: Vec<IslandPlan> = region
            .islands()
            .into_iter()
            .map(|isl| {
                let perimeters = (0..self.perimeters)
                    .map(|k| offset::offset(&isl, (k as f64 + 0.5) * w))
                    .collect();
                let inset = if self.perimeters == 0 {
                    0.5 * w
                } else {
                    self.perimeters as f64 * w
                };
                let infill_region = offset::offset(&isl, inset);
                let min_span = 0.5 * w;
                let plus = infill::spans(&infill_region, dirs[0], self.infill.spacing, min_span);
                let minus = if self.infill.alternate || self.infill.pattern == Pattern::Grid {
                    infill::spans(&infill_region, dirs[1], self.infill.spacing, min_span)
                } else {
                    plus.clone()
                };
                IslandPlan {
                    region: isl,
                    perimeters,
                    infill_region,
                    infill: [plus, minus],
                }
            })
            .collect();
        let (lo, _) = bbox(&region);
        let p0 = self.program(&islands, 0, lo);
        let start1 = p0
            .paths
            .last()
            .and_then(|p| p.last())
            .copied()
            .unwrap_or(lo);
        let p1 = if self.infill.alternate && self.infill.pattern == Pattern::Lines {
            self.program(&islands, 1, start1)
        } else {
            p0.clone()
        };
        Some(Slab {
            region,
            islands,
            programs: [p0, p1],
        })
    }

    /// Orders a layer's strings from `head`: island by island (nearest
    /// first), perimeters outside in (each level's loops nearest first, each
    /// loop from its vertex nearest the head), then the infill spans (nearest
    /// end first).
    fn program(&self, islands: &[IslandPlan], parity: usize, mut head: DVec2) -> Program {
        let fams = self.families(parity);
        let mut todo = self.todo(islands, &fams);
        let mut paths: Vec<Vec<DVec2>> = Vec::new();
        let mut is_infill: Vec<bool> = Vec::new();
        while !todo.is_empty() {
            let k = nearest(todo.iter().map(|t| entry(t, head)));
            let (levels, families, island) = todo.remove(k);
            if levels.iter().all(Vec::is_empty) && families.iter().all(Vec::is_empty) {
                continue;
            }
            head = perimeter_paths(levels, head, &mut paths);
            for (spans, &(_, u)) in families.into_iter().zip(&fams) {
                is_infill.resize(paths.len(), false);
                let from = paths.len();
                head = order_spans(spans, u, self.infill.spacing, head, &mut paths);
                if self.infill.connect {
                    let region = &islands[island].infill_region;
                    let longest = JOIN_SPACINGS * self.infill.spacing;
                    connect(&mut paths, from, region, longest);
                }
                is_infill.resize(paths.len(), true);
            }
        }
        Program {
            strings: count_strings(&paths),
            paths,
            infill: is_infill,
        }
    }

    /// The infill directions of the layer of this `parity`, each with the
    /// index of its spans in [`IslandPlan::infill`]: one (lines, turning by
    /// ±angle from layer to layer) or both (grid).
    fn families(&self, parity: usize) -> Vec<(usize, DVec2)> {
        match self.infill.pattern {
            Pattern::Lines => vec![(
                parity,
                infill::direction(if parity == 0 {
                    self.infill.angle
                } else {
                    -self.infill.angle
                }),
            )],
            Pattern::Grid => vec![
                (0, infill::direction(self.infill.angle)),
                (1, infill::direction(-self.infill.angle)),
            ],
        }
    }

    /// Per island: the polylines of each perimeter level (loops shorter than
    /// line_width left out, arcs within chord_tolerance), and the spans of
    /// each direction of `fams`.
    fn todo(&self, islands: &[IslandPlan], fams: &[(usize, DVec2)]) -> Vec<Todo> {
        let w = self.line_width;
        let tol = self.chord_tolerance;
        islands
            .iter()
            .enumerate()
            .map(|(k, isl)| {
                let levels = isl
                    .perimeters
                    .iter()
                    .map(|r| {
                        r.loops
                            .iter()
                            .filter(|l| l.length() >= w)
                            .map(|l| l.discretise(tol))
                            .collect()
                    })
                    .collect();
                let spans = fams.iter().map(|&(f, _)| isl.infill[f].clone()).collect();
                (levels, spans, k)
            })
            .collect()
    }
}

/// How far an island is from the head `h`: to its nearest point on the
/// outermost perimeter level that has one, else to its nearest span end.
fn entry(t: &Todo, h: DVec2) -> f64 {
    let mut best = f64::INFINITY;
    for level in &t.0 {
        for poly in level {
            for p in poly {
                best = best.min(p.distance(h));
            }
        }
        if best.is_finite() {
            return best;
        }
    }
    for (a, b) in t.1.iter().flatten() {
        best = best.min(a.distance(h)).min(b.distance(h));
    }
    best
}

/// Appends an island's perimeter loops to `paths`, level by level outside
/// in, each level's loops nearest first, each loop turned to start (and
/// close) at its vertex nearest the head; returns where the head ends.
fn perimeter_paths(
    levels: Vec<Vec<Vec<DVec2>>>,
    mut head: DVec2,
    paths: &mut Vec<Vec<DVec2>>,
) -> DVec2 {
    for mut level in levels {
        while !level.is_empty() {
            let k = nearest(level.iter().map(|poly| {
                poly.iter()
                    .map(|p| p.distance(head))
                    .fold(f64::INFINITY, f64::min)
            }));
            let poly = level.remove(k);
            let n = poly.len() - 1; // distinct points; poly[n] == poly[0]
            let i = nearest(poly[..n].iter().map(|p| p.distance(head)));
            let mut path = Vec::with_capacity(n + 1);
            path.extend_from_slice(&poly[i..n]);
            path.extend_from_slice(&poly[..=i]);
            head = path[n];
            paths.push(path);
        }
    }
    head
}

/// The strings of a layer's `paths`: each path's segments, plus one travel
/// before each path that does not start where the one before it ends.
fn count_strings(paths: &[Vec<DVec2>]) -> u64 {
    let mut strings = 0;
    for (i, p) in paths.iter().enumerate() {
        strings += p.len() as u64 - 1;
        if i > 0 && paths[i - 1].last() != p.first() {
            strings += 1;
        }
    }
    strings
}

impl Solid {
    /// The number of strings [`Solid::walk`] makes, from each layer's
    /// program without making them: its strings, and between layers one
    /// travel up plus one across when the next layer starts elsewhere.
    fn count(&self) -> u64 {
        let mut n = 0;
        let mut prev: Option<DVec2> = None;
        for layer in self.layers() {
            let Some(slab) = layer.slab else { continue };
            let prog = &slab.programs[layer.parity];
            let (Some(first), Some(last)) = (prog.paths.first(), prog.paths.last()) else {
                continue;
            };
            if let Some(end) = prev {
                n += 1 + u64::from(end != first[0]);
            }
            n += prog.strings;
            prev = Some(last[last.len() - 1]);
        }
        n
    }

    /// Runs through every point of the part in order, calling
    /// `f(point, travel, infill)`; the first call is the start point (its
    /// `travel` meaningless), each later one a string to that point, `infill`
    /// when it belongs to an infill path.
    fn walk(&self, mut f: impl FnMut(DVec3, bool, bool)) {
        let mut head: Option<DVec3> = None;
        for layer in self.layers() {
            let Some(slab) = layer.slab else { continue };
            let prog = &slab.programs[layer.parity];
            for (i, path) in prog.paths.iter().enumerate() {
                let start = path[0].extend(layer.z);
                let infill = prog.infill[i];
                match head {
                    None => f(start, true, false),
                    Some(h) => {
                        if i == 0 && h.z != layer.z {
                            // up first, then across
                            let up = DVec3::new(h.x, h.y, layer.z);
                            f(up, true, false);
                            if up != start {
                                f(start, true, false);
                            }
                        } else if h != start {
                            f(start, true, false);
                        }
                    }
                }
                for p in &path[1..] {
                    f(p.extend(layer.z), false, infill);
                }
                head = Some(path[path.len() - 1].extend(layer.z));
            }
        }
    }

    /// The layers bottom up, each with its slab of the z-buffer.
    pub(crate) fn layers(&self) -> impl Iterator<Item = Layer<'_>> + '_ {
        self.layer_slab.iter().enumerate().map(|(k, s)| {
            let index = k as u64 + 1;
            Layer {
                index,
                z: index as f64 * self.layer_height,
                slab: s.map(|s| &*self.slabs[s]),
                parity: if self.infill.alternate
                    && self.infill.pattern == Pattern::Lines
                    && index.is_multiple_of(2)
                {
                    1
                } else {
                    0
                },
            }
        })
    }

    /// The z-buffer: the distinct cross-sections.
    #[cfg(test)]
    pub(crate) fn slabs(&self) -> &[Arc<Slab>] {
        &self.slabs
    }

    /// Exactly how many strings [`Solid::build`] makes.
    pub(crate) fn string_count(&self) -> u64 {
        self.count
    }

    /// The width of layer each infill line stands for: its spacing with
    /// lines (a region of area A gets A / spacing of line); half of it with
    /// the grid (A / spacing per direction, 2·A / spacing in all).
    pub(crate) fn infill_share(&self) -> f64 {
        match self.infill.pattern {
            Pattern::Lines => self.infill.spacing,
            Pattern::Grid => 0.5 * self.infill.spacing,
        }
    }

    /// Makes the strings at speed `v`: perimeters of cross-section
    /// layer_height × line_width, infill of layer_height × min(share,
    /// line_width) ([`Solid::infill_share`]), so a solid layer's filament
    /// fills its area × height (lines closer than their width are squeezed
    /// to their share, not piled on each other). The part's cross-section `_c` is not used: the recipe's
    /// resolution refuses one that differs from layer_height × line_width.
    pub(crate) fn build(&self, _c: f64, v: f64) -> Toolpath {
        let c = self.layer_height * self.line_width;
        let c_infill = self.layer_height * self.line_width.min(self.infill_share());
        let mut t: Option<Toolpath> = None;
        self.walk(|p, travel, infill| match &mut t {
            None => t = Some(Toolpath::with_capacity(p, self.count as usize)),
            Some(t) if travel => t.travel(p, v),
            Some(t) => t.draw(p, if infill { c_infill } else { c }, v),
        });
        t.unwrap_or_default()
    }
}

/// An island still to print: its perimeter levels' closed polylines, its
/// infill spans of each direction, its index.
type Todo = (Vec<Vec<Vec<DVec2>>>, Vec<Vec<(DVec2, DVec2)>>, usize);

/// The longest join of connected infill, in spacings: lines at 45° to an
/// edge end √2 spacings apart along it; at 3 spacings, edges down to 19.5°
/// (1/sin θ ≤ 3) are joined, longer joins would lay thick seams.
pub(crate) const JOIN_SPACINGS: f64 = 3.0;

/// Connected infill: each infill path from `from` on is appended to the one
/// before it when the straight join from the one's end to the other's start
/// is at most `longest` and lies in `region` (see [`join_inside`]), so the
/// nozzle draws along the boundary instead of travelling (a zig-zag).
fn connect(paths: &mut Vec<Vec<DVec2>>, from: usize, region: &Region, longest: f64) {
    let mut out: Vec<Vec<DVec2>> = Vec::with_capacity(paths.len() - from);
    for path in paths.drain(from..) {
        match out.last_mut() {
            Some(prev)
                if prev[prev.len() - 1].distance(path[0]) <= longest
                    && join_inside(region, prev[prev.len() - 1], path[0]) =>
            {
                // the join is the string from prev's end to path[0]
                let skip = usize::from(prev[prev.len() - 1] == path[0]);
                prev.extend_from_slice(&path[skip..]);
            }
            _ => out.push(path),
        }
    }
    paths.extend(out);
}

/// Whether the segment a–b (ends on the boundary of `region` or inside it)
/// lies in the closed region: it meets no boundary piece but at its ends,
/// and its midpoint is inside or on the boundary. A segment touching the
/// boundary between its ends counts as leaving (a join is only skipped).
pub(crate) fn join_inside(region: &Region, a: DVec2, b: DVec2) -> bool {
    let eps = region.eps();
    if a.distance(b) <= eps {
        return true;
    }
    let seg = piece::Piece::Line(a, b);
    for l in &region.loops {
        for p in &l.pieces {
            for (x, _, _) in piece::intersect(&seg, p, eps) {
                if x.distance(a) > eps && x.distance(b) > eps {
                    return false;
                }
            }
        }
    }
    let m = a.lerp(b, 0.5);
    region.contains(m)
        || region
            .loops
            .iter()
            .flat_map(|l| l.pieces.iter())
            .any(|p| p.distance(m) <= eps)
}

/// Appends the infill `spans` (lines along `u`, `spacing` apart) to `paths`
/// nearest first from `head`, each from its nearer end; returns the new head.
///
/// The nearest span is found as by trying them all (ties to the earlier
/// span), but spans are bucketed by scanline and buckets are searched
/// outwards from the head's own: a bucket r lines away is at least
/// (r − ½)·spacing from the head (whose own line is within ½ of it), so the
/// search stops once that exceeds the best distance found. Filling a region line after line, that is a bucket
/// or two per span instead of every span.
pub(super) fn order_spans(
    spans: Vec<(DVec2, DVec2)>,
    u: DVec2,
    spacing: f64,
    mut head: DVec2,
    paths: &mut Vec<Vec<DVec2>>,
) -> DVec2 {
    if spans.is_empty() {
        return head;
    }
    let n = DVec2::new(-u.y, u.x);
    let line = |p: DVec2| libm::round(p.dot(n) / spacing) as i64;
    let k0 = spans.iter().map(|s| line(s.0)).min().unwrap();
    let k1 = spans.iter().map(|s| line(s.0)).max().unwrap();
    let mut buckets: Vec<Vec<usize>> = vec![Vec::new(); (k1 - k0 + 1) as usize];
    for (i, s) in spans.iter().enumerate() {
        buckets[(line(s.0) - k0) as usize].push(i);
    }
    for _ in 0..spans.len() {
        let here = head.dot(n) / spacing - k0 as f64;
        let c = libm::round(here).clamp(0.0, (buckets.len() - 1) as f64) as i64;
        let mut best: Option<(f64, usize, usize)> = None; // (distance, span, bucket)
        let mut r = 0i64;
        loop {
            let (lo, hi) = (c - r, c + r);
            if lo < 0 && hi >= buckets.len() as i64 {
                break;
            }
            let ring: &[i64] = if r == 0 { &[lo] } else { &[lo, hi] };
            for &b in ring {
                if b < 0 || b >= buckets.len() as i64 {
                    continue;
                }
                for &i in &buckets[b as usize] {
                    let (a, e) = spans[i];
                    let d = a.distance(head).min(e.distance(head));
                    if best.is_none_or(|(bd, bi, _)| d < bd || (d == bd && i < bi)) {
                        best = Some((d, i, b as usize));
                    }
                }
            }
            if let Some((bd, _, _)) = best {
                // every bucket further out is farther than this one
                if bd < (r as f64 + 1.0 - (here - c as f64).abs() - 1e-9) * spacing {
                    break;
                }
            }
            r += 1;
        }
        let (_, i, b) = best.expect("a span is left");
        buckets[b].retain(|&j| j != i);
        let (a, e) = spans[i];
        let path = if a.distance(head) <= e.distance(head) {
            vec![a, e]
        } else {
            vec![e, a]
        };
        head = path[1];
        paths.push(path);
    }
    head
}

/// Index of the smallest value (the first of equals).
pub(super) fn nearest(values: impl Iterator<Item = f64>) -> usize {
    let mut best = (0, f64::INFINITY);
    for (k, v) in values.enumerate() {
        if v < best.1 {
            best = (k, v);
        }
    }
    best.0
}

/// Corners of a region's bounding box (of its pieces' end points and circles).
fn bbox(r: &Region) -> (DVec2, DVec2) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for l in &r.loops {
        for p in &l.pieces {
            let [a, b] = p.bbox(0.0);
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    (lo, hi)
}
