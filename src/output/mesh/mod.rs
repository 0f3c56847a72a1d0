//! `p3dp mesh`: the toolpath as solid beads, for slicers and CAD (STL, 3MF,
//! OBJ; the writers are in [`write`]).
//!
//! Cross-section. A string of cross-section c laid h from the next pass (the
//! previews' reading, [`crate::base::geom::passes::Grid::local_near`]: h along the surface,
//! the surface normal n across it) becomes the bead a slicer assumes: h tall
//! along the surface, w wide along n, its two sides rounded. The rounded sides
//! are cut as chamfers of the same area, so the section is an octagon: the
//! rectangle w × h less four corner triangles of legs k = β·min(w, h), with
//! β = sqrt((1 − π/4) / 2) (two such triangles, 2·(k²/2) = (1 − π/4)·min²,
//! have exactly the area the two semicircular ends leave out of their
//! rectangle). Its area w·h − 2β²·min(w, h)² is set to c:
//!   - w ≥ h (c ≥ (π/4)·h²): w = c/h + (1 − π/4)·h, the rounded-ends width;
//!   - w < h: w is the smaller root of 2β²w² − h·w + c = 0;
//!   - no neighbouring pass: w = h = 2·sqrt(c/π), the round string's
//!     diameter, and the octagon has the circle's area.
//!
//! So every section has area c exactly, the flats of neighbouring passes
//! touch (they are h apart, each h tall) and a bead's volume is Σ c·L:
//! exactly for a straight bead, up to the joints' averaging of the sections
//! elsewhere.
//!
//! Beads. Consecutive extruding strings of one part are swept as one tube
//! (the section's frame carried along, its normal's sign kept), mitred at
//! each joint: the ring lies in the plane that bisects the turn, stretched
//! by 1/cos(θ/2) along the bend, so that it is each string's own section cut
//! on the slant and the volume is kept. A tube ends with flat caps at a
//! travel, an unextruded string, a turn over [`MAX_TURN_DEG`] or a mitre
//! longer than [`MITRE_SHARE`] of a string (a bead too thick for its curve);
//! a bead that ends where it starts is closed (a torus). Each bead is one
//! closed, consistently oriented (outward) 2-manifold shell; beads of
//! neighbouring passes touch as separate shells.
//!
//! Determinism. Vertices are rounded to a grid of 1 µm (integer micrometres)
//! before anything is written; within a bead a vertex is shared by index,
//! and only plain IEEE arithmetic (+, −, ×, ÷, sqrt) reaches them.

pub(crate) mod write;

use glam::DVec3;

use crate::analyse::plan::Plan;
use crate::base::geom::passes::{pass_spacing, round_diameter, Grid};
use crate::base::toolpath::Toolpath;

/// The vertices a section ring has (an octagon).
pub(crate) const RING: usize = 8;

/// β: the chamfer's leg over the section's smaller side (see the module
/// comment), sqrt((1 − π/4) / 2).
pub(crate) fn beta() -> f64 {
    ((1.0 - std::f64::consts::FRAC_PI_4) / 2.0).sqrt()
}

/// The sharpest turn a bead is mitred through, degrees; a sharper one ends
/// the bead (the next starts in the corner), so a mitre never grows more than
/// 1/cos(60°) = 2 times.
pub(crate) const MAX_TURN_DEG: f64 = 120.0;

/// The share of a string's length a mitre may take at either end; longer,
/// the tube would fold, and the bead ends there.
pub(crate) const MITRE_SHARE: f64 = 0.4;

/// Strings shorter than this (mm) are taken into the next one: the rings at
/// their ends would meet on the 1 µm grid.
pub(crate) const MIN_LEN: f64 = 0.01;

/// The thinnest a section is made, mm (a thinner one is widened to it).
pub(crate) const MIN_SIZE: f64 = 0.02;

/// Vertices in micrometres: the rounding grid.
pub(crate) const UNITS_PER_MM: f64 = 1000.0;

/// Triangles over shared vertices, on the 1 µm grid.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Mesh {
    /// Vertices, integer micrometres.
    pub(crate) vertices: Vec<[i64; 3]>,
    /// Triangles: vertex indices, counter-clockwise seen from outside.
    pub(crate) triangles: Vec<[u32; 3]>,
    /// Beads: closed shells, one per continuous run of extrusion.
    pub(crate) beads: usize,
    /// Of them, beads closed on themselves (rings, no caps).
    pub(crate) rings: usize,
}

/// A section: w along the normal, h along the surface, chamfer legs k.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Section {
    /// Width across the surface's normal direction n, mm.
    pub(crate) w: f64,
    /// Height along the surface (across to the next pass), mm.
    pub(crate) h: f64,
}

impl Section {
    /// The section of cross-section `c` laid `h` from the neighbouring pass.
    pub(crate) fn flat(c: f64, h: f64) -> Section {
        let b2 = 2.0 * beta() * beta(); // 1 − π/4
        let (w, h) = if c >= (1.0 - b2) * h * h {
            (c / h + b2 * h, h)
        } else {
            // 2β²w² − h·w + c = 0, the root below h
            ((h - (h * h - 4.0 * b2 * c).sqrt()) / (2.0 * b2), h)
        };
        Section {
            w: w.max(MIN_SIZE),
            h: h.max(MIN_SIZE),
        }
    }

    /// The section of a string with no neighbouring pass: as wide as tall,
    /// the round string's diameter 2·sqrt(c/π).
    pub(crate) fn round(c: f64) -> Section {
        let d = round_diameter(c).max(MIN_SIZE);
        Section { w: d, h: d }
    }

    /// The chamfer's leg, mm.
    pub(crate) fn k(&self) -> f64 {
        beta() * self.w.min(self.h)
    }

    /// Area, mm².
    pub(crate) fn area(&self) -> f64 {
        let k = self.k();
        self.w * self.h - 2.0 * k * k
    }

    /// The octagon's corners (x along n, y along the surface), counter-clockwise.
    pub(crate) fn corners(&self) -> [(f64, f64); RING] {
        let (x, y, k) = (self.w / 2.0, self.h / 2.0, self.k());
        [
            (x, -(y - k)),
            (x, y - k),
            (x - k, y),
            (-(x - k), y),
            (-x, y - k),
            (-x, -(y - k)),
            (-(x - k), -y),
            (x - k, -y),
        ]
    }
}

/// One string of a bead: its ends, unit tangent t, section normal n (unit,
/// ⊥ t) and section.
#[derive(Clone, Copy, Debug)]
struct Seg {
    a: DVec3,
    b: DVec3,
    t: DVec3,
    n: DVec3,
    len: f64,
    sec: Section,
    /// How far the strings taken into this one (a chord) lie from it, mm.
    dev: f64,
}

/// The mesh of every extruding string of a plan (skirt and parts), each
/// path's passes taken as lying [`pass_spacing`] apart (half the nozzle when
/// it has none, as the previews take it).
pub(crate) fn of_plan(plan: &Plan) -> Mesh {
    let fallback = plan.recipe.printer.nozzle_diameter / 2.0;
    let mut mesh = Mesh::default();
    for tp in &plan.paths {
        add_path(&mut mesh, tp, pass_spacing(&tp.points).unwrap_or(fallback));
    }
    mesh
}

/// Adds the beads of one part whose passes lie about `h_typ` apart (the
/// [`pass_spacing`]).
pub(crate) fn add_path(mesh: &mut Mesh, tp: &Toolpath, h_typ: f64) {
    let grid = Grid::for_surface(&tp.points, h_typ);
    let mut bead: Vec<Seg> = Vec::new();
    // where the bead's next string starts (strings too short are skipped
    // over, so the one after them starts here)
    let mut from: Option<DVec3> = None;
    // the neighbour found for an earlier string (its string, the
    // neighbour's): the next string's lies about as far along, and a
    // search that starts from it ends sooner with the same answer
    // ([`Grid::local_near`])
    let mut hint: Option<(usize, usize)> = None;
    for k in 0..tp.len() {
        let s = tp.strings[k];
        let (a0, b) = tp.ends(k);
        if s.travel || s.c.is_nan() || s.c <= 0.0 || !a0.is_finite() || !b.is_finite() {
            flush(mesh, &mut bead);
            from = None;
            continue;
        }
        let a = from.unwrap_or(a0);
        from = Some(a);
        let len = a.distance(b);
        if len < MIN_LEN {
            continue;
        }
        from = Some(b);
        let t = (b - a) / len;
        // the previews' section: h the spacing to the neighbouring pass, kept
        // within half and twice the part's typical spacing (as they draw it)
        let sm = (grid.arc(k) + grid.arc(k + 1)) / 2.0;
        let guess = hint.map(|(at, j)| j + (k - at));
        let found = grid.local_near(a, b, sm, guess, false);
        hint = found.map(|(_, j)| (k, j)).or(hint);
        let local = found.map(|(l, _)| l).filter(|l| {
            // a neighbour much nearer than the typical spacing may lie ahead
            // of the string, not beside it (a loop's own start met again at
            // its end): such a one is no neighbouring pass
            l.spacing >= 0.5 * h_typ
                || grid
                    .nearest_other((a + b) * 0.5, sm)
                    .is_some_and(|q| l.spacing >= 0.5 * q.distance((a + b) * 0.5))
        });
        // the previous string's normal turned with the tangent: a flat
        // section keeps its side (its normal's sign) by it, a round one
        // takes it
        let along = carried(bead.last(), t);
        let (sec, n) = match local {
            Some(l) => {
                let h = l.spacing.clamp(0.5 * h_typ, 2.0 * h_typ);
                let n = if along.dot(l.normal) < 0.0 {
                    -l.normal
                } else {
                    l.normal
                };
                (Section::flat(s.c, h), n)
            }
            None => (Section::round(s.c), along),
        };
        let seg = Seg {
            a,
            b,
            t,
            n: perpendicular(n, t),
            len,
            sec,
            dev: 0.0,
        };
        push(mesh, &mut bead, seg);
    }
    flush(mesh, &mut bead);
}

/// Adds `q` to the bead: through a mitre when it can; else, when the turn
/// is gentle but the strings too short for the bead's thickness (a curve
/// tighter than the bead, near a pole), the last string and `q` become one
/// chord of the same volume (and again with the one before, while needed);
/// else the bead ends and `q` starts the next.
fn push(mesh: &mut Mesh, bead: &mut Vec<Seg>, mut q: Seg) {
    while let Some(p) = bead.last().copied() {
        if joins(&p, &q) {
            break;
        }
        match chord(&p, &q) {
            Some(m) if p.t.dot(q.t) >= max_turn_cos() => {
                bead.pop();
                q = m;
            }
            _ => {
                flush(mesh, bead);
                break;
            }
        }
    }
    bead.push(q);
}

/// The cosine of [`MAX_TURN_DEG`].
fn max_turn_cos() -> f64 {
    libm::cos(MAX_TURN_DEG.to_radians())
}

/// Strings `p` and `q` as one chord from p's start to q's end, its section
/// q's shape scaled to keep their volume, or `None` when the chord is too
/// short, would have to be more than twice as thick (in area) or would
/// leave the strings' path by more than a quarter of the bead.
fn chord(p: &Seg, q: &Seg) -> Option<Seg> {
    let len = p.a.distance(q.b);
    if len < MIN_LEN {
        return None;
    }
    let volume = p.sec.area() * p.len + q.sec.area() * q.len;
    let f = (volume / len / q.sec.area()).sqrt();
    if f.is_nan() || f > std::f64::consts::SQRT_2 {
        return None;
    }
    let t = (q.b - p.a) / len;
    // the path may leave the chord by a quarter of the bead at most
    let dev = (p.b - p.a).cross(t).length() + p.dev.max(q.dev);
    if dev > 0.25 * q.sec.w.max(q.sec.h) {
        return None;
    }
    Some(Seg {
        a: p.a,
        b: q.b,
        t,
        n: perpendicular(q.n, t),
        len,
        sec: Section {
            w: q.sec.w * f,
            h: q.sec.h * f,
        },
        dev,
    })
}

/// `n` made unit and perpendicular to `t` (any perpendicular when it is
/// along `t`).
fn perpendicular(n: DVec3, t: DVec3) -> DVec3 {
    let p = (n - t * n.dot(t)).normalize_or_zero();
    if p != DVec3::ZERO {
        return p;
    }
    // the axis least along t, crossed with it
    let axis = if t.x.abs() <= t.y.abs() && t.x.abs() <= t.z.abs() {
        DVec3::X
    } else if t.y.abs() <= t.z.abs() {
        DVec3::Y
    } else {
        DVec3::Z
    };
    t.cross(axis).normalize()
}

/// The normal of a round string: the previous string's turned with the
/// tangent (the least rotation from its tangent to `t`, so the tube does not
/// twist), else a horizontal one.
fn carried(prev: Option<&Seg>, t: DVec3) -> DVec3 {
    match prev {
        Some(p) => glam::DQuat::from_rotation_arc(p.t, t) * p.n,
        None => t.cross(DVec3::Z),
    }
}

/// Whether string `q` continues the bead of `p` through a mitre.
fn joins(p: &Seg, q: &Seg) -> bool {
    let cos_turn = p.t.dot(q.t);
    if cos_turn < max_turn_cos() {
        return false;
    }
    // the mitre reaches r·tan(θ/2) along each string, r the section's
    // half-size; tan(θ/2) = sqrt((1 − cos θ) / (1 + cos θ))
    let r = 0.5 * p.sec.w.max(p.sec.h).max(q.sec.w).max(q.sec.h);
    let reach = r * ((1.0 - cos_turn).max(0.0) / (1.0 + cos_turn)).sqrt();
    reach <= MITRE_SHARE * p.len.min(q.len)
}

/// The ring of section `sec` centred at `c` in the plane of normal `t`, with
/// frame (n, t × n), stretched by `stretch` along `d` (a mitre).
fn ring(c: DVec3, t: DVec3, n: DVec3, sec: Section, d: DVec3, stretch: f64) -> [DVec3; RING] {
    let b = t.cross(n);
    sec.corners().map(|(x, y)| {
        let o = n * x + b * y;
        c + o + d * (o.dot(d) * stretch)
    })
}

/// The mitred ring where `p` turns into `q`: in the plane bisecting the turn,
/// the mean of their sections and of their normals (each turned into that
/// plane with its tangent), stretched by 1/cos(θ/2) − 1
/// along the bend.
fn joint(p: &Seg, q: &Seg) -> [DVec3; RING] {
    let t = (p.t + q.t).normalize();
    // both normals turned (half the turn each) into the mitre's plane
    let pn = glam::DQuat::from_rotation_arc(p.t, t) * p.n;
    let qn = glam::DQuat::from_rotation_arc(q.t, t) * q.n;
    let pn = if pn.dot(qn) < 0.0 { -pn } else { pn };
    let n = perpendicular(pn + qn, t);
    // the mean shape, scaled to the mean area (so that sections of one
    // area turned across each other do not swell at the joint)
    let mean = Section {
        w: 0.5 * (p.sec.w + q.sec.w),
        h: 0.5 * (p.sec.h + q.sec.h),
    };
    let f = (0.5 * (p.sec.area() + q.sec.area()) / mean.area()).sqrt();
    let sec = Section {
        w: mean.w * f,
        h: mean.h * f,
    };
    let cos_half = t.dot(q.t);
    let d = (q.t - p.t).normalize_or_zero();
    ring(q.a, t, n, sec, d, 1.0 / cos_half - 1.0)
}

/// Rounds a point to the grid, micrometres.
pub(crate) fn grid(p: DVec3) -> [i64; 3] {
    let q = (p * UNITS_PER_MM).round();
    [q.x as i64, q.y as i64, q.z as i64]
}

/// Meshes the bead in `segs` (and empties it).
fn flush(mesh: &mut Mesh, segs: &mut Vec<Seg>) {
    if segs.is_empty() {
        return;
    }
    let n = segs.len();
    let (first, last) = (segs[0], segs[n - 1]);
    let closed = n >= 3 && first.a.distance(last.b) < 1e-3 && joins(&last, &first);
    let mut rings: Vec<[DVec3; RING]> = Vec::with_capacity(n + 1);
    if closed {
        rings.push(joint(&last, &first));
    } else {
        rings.push(ring(first.a, first.t, first.n, first.sec, DVec3::ZERO, 0.0));
    }
    for i in 1..n {
        rings.push(joint(&segs[i - 1], &segs[i]));
    }
    if !closed {
        rings.push(ring(last.b, last.t, last.n, last.sec, DVec3::ZERO, 0.0));
    }
    // vertices, shared by index within the bead
    let base = mesh.vertices.len() as u32;
    for r in &rings {
        mesh.vertices.extend(r.iter().map(|p| grid(*p)));
    }
    let at = |ri: usize, i: usize| base + (ri * RING + i % RING) as u32;
    let tri = &mut mesh.triangles;
    // the sides: ring j to ring j + 1, corner i to corner i (outward, as the
    // corners run counter-clockwise about the tangent)
    let mut tube = |ra: usize, rb: usize, shift: usize| {
        for i in 0..RING {
            let (a0, a1) = (at(ra, i), at(ra, i + 1));
            let (b0, b1) = (at(rb, i + shift), at(rb, i + 1 + shift));
            tri.push([a0, a1, b1]);
            tri.push([a0, b1, b0]);
        }
    };
    for j in 0..rings.len() - 1 {
        tube(j, j + 1, 0);
    }
    if closed {
        // back to the first ring, turned to the corner that lies nearest
        // (its frame came round the loop and may be turned from the start's)
        let (l, f) = (&rings[n - 1], &rings[0]);
        let shift = (0..RING)
            .min_by(|&s, &u| {
                let cost = |s: usize| -> f64 {
                    (0..RING)
                        .map(|i| l[i].distance_squared(f[(i + s) % RING]))
                        .sum()
                };
                cost(s).total_cmp(&cost(u))
            })
            .unwrap_or(0);
        tube(n - 1, 0, shift);
        mesh.rings += 1;
    } else {
        // flat caps: fans, facing back along the first string and on along
        // the last
        let end = rings.len() - 1;
        for i in 1..RING - 1 {
            tri.push([at(0, 0), at(0, i + 1), at(0, i)]);
            tri.push([at(end, 0), at(end, i), at(end, i + 1)]);
        }
    }
    mesh.beads += 1;
    segs.clear();
}

impl Mesh {
    /// A vertex in millimetres.
    pub(crate) fn point(&self, i: u32) -> DVec3 {
        let v = self.vertices[i as usize];
        DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64) / UNITS_PER_MM
    }

    /// The enclosed volume, mm³: Σ over triangles of the signed tetrahedra
    /// to the origin, a·(b × c) / 6 (the divergence theorem), on the rounded
    /// vertices.
    pub(crate) fn volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.point(i));
                a.dot(b.cross(c))
            })
            .sum::<f64>()
            / 6.0
    }

    #[cfg(test)]
    /// The bounding box of the vertices, mm (`None` when empty).
    pub(crate) fn bbox(&self) -> Option<(DVec3, DVec3)> {
        let mut it = self.vertices.iter();
        let v = it.next()?;
        let mut lo = *v;
        let mut hi = *v;
        for v in it {
            for i in 0..3 {
                lo[i] = lo[i].min(v[i]);
                hi[i] = hi[i].max(v[i]);
            }
        }
        let mm = |v: [i64; 3]| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64) / UNITS_PER_MM;
        Some((mm(lo), mm(hi)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// The mesh holds the path's filament volume, within 1 %.
    fn same_volume(m: &Mesh, tp: &Toolpath) {
        let want = tp.volume();
        assert!(
            (m.volume() - want).abs() < 0.01 * want,
            "{} vs {want}",
            m.volume()
        );
    }

    /// Every edge used by exactly two triangles, once each way.
    fn closed_and_oriented(m: &Mesh) -> Result<(), String> {
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &m.triangles {
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(format!("degenerate {t:?}"));
            }
            for e in 0..3 {
                *edges.entry((t[e], t[(e + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            if n != 1 || edges.get(&(b, a)) != Some(&1) {
                return Err(format!(
                    "edge {a}–{b} used {n} times, back {:?}",
                    edges.get(&(b, a))
                ));
            }
        }
        Ok(())
    }

    fn line(n: usize, step: DVec3, c: f64) -> Toolpath {
        let mut tp = Toolpath::new(DVec3::ZERO);
        for i in 1..=n {
            tp.draw(step * i as f64, c, 30.0);
        }
        tp
    }

    #[test]
    fn sections_have_area_c() {
        for (c, h) in [
            (0.196, 0.2),
            (0.12, 0.3),
            (0.05, 0.4),
            (0.3, 0.1),
            (0.0785, 0.316),
        ] {
            let s = Section::flat(c, h);
            assert!((s.area() - c).abs() < 1e-12, "{c} {h} {s:?}");
            assert_eq!(s.h, h);
            let r = Section::round(c);
            assert!((r.area() - c).abs() < 1e-12, "{r:?}");
            assert!((r.w - 2.0 * (c / std::f64::consts::PI).sqrt()).abs() < 1e-12);
        }
        // the wide case is the rounded-ends bead: c/h + (1 − π/4)·h
        let s = Section::flat(0.196, 0.2);
        assert!((s.w - (0.98 + (1.0 - std::f64::consts::FRAC_PI_4) * 0.2)).abs() < 1e-12);
        // the two cases meet at c = (π/4)·h²
        let h = 0.3;
        let c = std::f64::consts::FRAC_PI_4 * h * h;
        assert!((Section::flat(c, h).w - h).abs() < 1e-9);
        assert!((Section::flat(c * (1.0 - 1e-9), h).w - h).abs() < 1e-6);
    }

    #[test]
    fn a_straight_bead_has_volume_c_times_length() {
        let c = 0.196;
        let tp = line(50, DVec3::new(0.2, 0.1, 0.0), c);
        let mut m = Mesh::default();
        add_path(&mut m, &tp, 0.2);
        assert_eq!(m.beads, 1);
        assert_eq!(m.rings, 0);
        // 51 rings: 50 × 16 side triangles, two caps of 6
        assert_eq!(m.vertices.len(), 51 * RING);
        assert_eq!(m.triangles.len(), 50 * 2 * RING + 2 * (RING - 2));
        closed_and_oriented(&m).unwrap();
        let l = tp.points[0].distance(tp.points[50]);
        let v = m.volume();
        // the 1 µm grid moves the corners by 0.5 µm at most
        assert!((v - c * l).abs() < 1e-3 * c * l, "{v} vs {}", c * l);
        assert!(v > 0.0, "outward");
    }

    /// A horizontal ring of radius 10 (a closed loop of `n` strings) and its
    /// bounding box: the loop's grown by half the round string.
    #[test]
    fn a_closed_ring_is_one_closed_shell() {
        let (n, r, c) = (240, 10.0, 0.2);
        let at = |i: usize| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            DVec3::new(r * libm::cos(a), r * libm::sin(a), 1.0)
        };
        let mut tp = Toolpath::new(at(0));
        for i in 1..=n {
            tp.draw(if i == n { at(0) } else { at(i) }, c, 30.0);
        }
        let mut m = Mesh::default();
        add_path(&mut m, &tp, 0.2);
        assert_eq!((m.beads, m.rings), (1, 1));
        assert_eq!(m.vertices.len(), n * RING);
        assert_eq!(m.triangles.len(), n * 2 * RING);
        closed_and_oriented(&m).unwrap();
        // distinct vertices within the bead
        let mut v = m.vertices.clone();
        v.sort();
        v.dedup();
        assert_eq!(v.len(), m.vertices.len());
        // the volume of the swept octagon: c times the centre line's length
        // (the polygon's perimeter), the grid's error aside
        let l: f64 = (0..n).map(|i| at(i).distance(at(i + 1))).sum();
        assert!((m.volume() - c * l).abs() < 2e-3 * c * l, "{}", m.volume());
        // bbox: the loop's (±r, z = 1) grown by half the round string
        let half = Section::round(c).w / 2.0;
        let (lo, hi) = m.bbox().unwrap();
        // the mitres stretch by 1/cos(θ/2), θ = 1.5°: < 1e-4 of half
        for (got, want) in [
            (lo, DVec3::new(-r - half, -r - half, 1.0 - half)),
            (hi, DVec3::new(r + half, r + half, 1.0 + half)),
        ] {
            assert!((got - want).abs().max_element() < 2e-3, "{got} vs {want}");
        }
    }

    /// A helix wall: each turn a bead h tall and w wide, touching the next;
    /// the box grows by w/2 across the wall and h/2 up and down.
    #[test]
    fn a_helix_wall_grows_by_half_its_bead() {
        let (per_turn, turns, r, pitch, c) = (200, 10, 10.0, 0.3, 0.15);
        let mut tp = Toolpath::new(DVec3::new(r, 0.0, 0.0));
        for i in 1..=per_turn * turns {
            let a = std::f64::consts::TAU * i as f64 / per_turn as f64;
            let z = pitch * i as f64 / per_turn as f64;
            tp.draw(DVec3::new(r * libm::cos(a), r * libm::sin(a), z), c, 30.0);
        }
        let h = pass_spacing(&tp.points).unwrap();
        assert!((h - pitch).abs() < 0.01);
        let mut m = Mesh::default();
        add_path(&mut m, &tp, h);
        assert_eq!(m.beads, 1);
        closed_and_oriented(&m).unwrap();
        same_volume(&m, &tp);
        // the wall is the flat bead of height `pitch`, w wide
        let flat = Section::flat(c, pitch);
        let (lo, hi) = m.bbox().unwrap();
        for (got, want) in [(lo.x, -r - flat.w / 2.0), (hi.x, r + flat.w / 2.0)] {
            assert!((got - want).abs() < 0.01, "{got} vs {want}");
        }
        // the first and last turns have a pass on one side: flat too
        assert!((lo.z + pitch / 2.0).abs() < 0.01, "{lo}");
        assert!(
            (hi.z - (pitch * turns as f64 + pitch / 2.0)).abs() < 0.01,
            "{hi}"
        );
    }

    #[test]
    fn sharp_turns_and_travels_end_beads() {
        // a zig-zag of 150° turns: one bead per stroke, nothing blown up
        let mut tp = Toolpath::new(DVec3::ZERO);
        for i in 1..=6 {
            let x = i as f64 * 0.5;
            let y = if i % 2 == 1 { 4.0 } else { 0.0 };
            tp.draw(DVec3::new(x, y, 0.0), 0.1, 30.0);
        }
        tp.travel(DVec3::new(10.0, 0.0, 0.0), 100.0);
        tp.draw(DVec3::new(12.0, 0.0, 0.0), 0.1, 30.0);
        let mut m = Mesh::default();
        add_path(&mut m, &tp, 0.2);
        assert_eq!(m.beads, 7);
        closed_and_oriented(&m).unwrap();
        let (lo, hi) = m.bbox().unwrap();
        let half = Section::round(0.1).w / 2.0;
        assert!(lo.y >= -half - 0.3 && hi.y <= 4.0 + half + 0.3, "{lo} {hi}");
        let want = tp.volume();
        assert!(
            (m.volume() - want).abs() < 1e-3 * want,
            "{} vs {want}",
            m.volume()
        );
        // a 90° corner is mitred: one bead
        let mut l = Toolpath::new(DVec3::ZERO);
        l.draw(DVec3::new(5.0, 0.0, 0.0), 0.1, 30.0);
        l.draw(DVec3::new(5.0, 5.0, 0.0), 0.1, 30.0);
        let mut m = Mesh::default();
        add_path(&mut m, &l, 0.2);
        assert_eq!(m.beads, 1);
        closed_and_oriented(&m).unwrap();
        // (a 0.36 mm bead: the 1 µm grid moves its area by up to ~0.3 %)
        assert!(
            (m.volume() - l.volume()).abs() < 4e-3 * l.volume(),
            "{} vs {}",
            m.volume(),
            l.volume()
        );
        let (lo, hi) = m.bbox().unwrap();
        assert!((lo.y + half).abs() < 2e-3 && (hi.x - 5.0 - half).abs() < 2e-3);
    }

    /// A wall round a rhombus (turns of 70° and 110°), rising 0.2 a turn:
    /// past 90° the flat bead must keep its side of the wall by its normal
    /// turned with the tangent (the side nearest the last normal is the
    /// wrong one, and the mitre's frame collapses).
    #[test]
    fn a_wall_keeps_its_side_round_sharp_corners() {
        let (c70, s70) = (libm::cos(70f64.to_radians()), libm::sin(70f64.to_radians()));
        let corners = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(20.0, 0.0, 0.0),
            DVec3::new(20.0 + 20.0 * c70, 20.0 * s70, 0.0),
            DVec3::new(20.0 * c70, 20.0 * s70, 0.0),
        ];
        let mut tp = Toolpath::new(corners[0] + DVec3::Z * 0.2);
        for i in 1..=40 {
            let z = 0.2 + 0.2 * i as f64 / 4.0;
            tp.draw(corners[i % 4] + DVec3::Z * z, 0.15, 30.0);
        }
        let mut m = Mesh::default();
        add_path(&mut m, &tp, 0.2);
        assert_eq!(m.beads, 1, "mitred at every corner");
        closed_and_oriented(&m).unwrap();
        same_volume(&m, &tp);
    }

    #[test]
    fn short_strings_are_taken_into_the_next() {
        let mut tp = Toolpath::new(DVec3::ZERO);
        for i in 1..=1000 {
            tp.draw(DVec3::new(i as f64 * 0.001, 0.0, 0.0), 0.1, 30.0);
        }
        let mut m = Mesh::default();
        add_path(&mut m, &tp, 0.2);
        assert_eq!(m.beads, 1);
        closed_and_oriented(&m).unwrap();
        assert!((m.volume() - 0.1).abs() < 1e-3, "{}", m.volume());
        assert!(m.vertices.len() <= 101 * RING + RING);
    }
}
