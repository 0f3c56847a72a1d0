//! The Olympic rings of Kanada's Fig. 5 (`recipes/olympic-rings.yaml`): five
//! rings printed as split pieces that are assembled by the print order.
//!
//! The recipe's parts are named `ring-COLOUR-K`; the bottom layers (each
//! piece's first run of extruding strings) of pieces 1, 2, … of a ring close
//! its centre curve. The tests rebuild those curves and check that
//! neighbouring rings are linked and others not, that pieces keep apart
//! except where one rests on another, that the nozzle never goes below
//! filament printed earlier (printing or travelling), and the print order.

use std::collections::BTreeMap;
use std::f64::consts::PI;

use crate::common::*;
use glam::{DVec2, DVec3};
use p3dp::testing::Insides;
use p3dp::Plan;
use p3dp::Severity;

/// Nozzle width of generic-220, mm.
const NOZZLE: f64 = 0.4;
/// Radius of the nozzle's tip face, mm: printed filament within this distance
/// of the tip (seen from above) must not be higher than the tip.
const FOOTPRINT: f64 = 1.0;
/// How far the tip may dip below earlier filament within the footprint, mm.
const TOL: f64 = 0.02;
/// The end of the pass being printed that the tip is excused, mm of path: a
/// footprint, doubled because the path climbs.
const TRAIL: f64 = 2.0 * FOOTPRINT;
/// The rings, left to right along the chain.
const CHAIN: [&str; 5] = ["blue", "yellow", "black", "green", "red"];

// ---------------------------------------------------------------------------
// geometry

/// Closest points of segments `p1q1` and `p2q2` (Ericson, "Real-Time Collision
/// Detection", 5.1.9): the distance and the closest point on each segment.
/// Handles parallel segments and segments shrunk to a point.
fn seg_seg(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> (f64, DVec3, DVec3) {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.length_squared();
    let e = d2.length_squared();
    let f = d2.dot(r);
    let tiny = 1e-24;
    let (s, t);
    if a <= tiny && e <= tiny {
        (s, t) = (0.0, 0.0);
    } else if a <= tiny {
        (s, t) = (0.0, (f / e).clamp(0.0, 1.0));
    } else {
        let c = d1.dot(r);
        if e <= tiny {
            (s, t) = ((-c / a).clamp(0.0, 1.0), 0.0);
        } else {
            let b = d1.dot(d2);
            // a e sin² of the angle between them; when they are parallel any
            // s will do: take 0 and let t decide
            let denom = a * e - b * b;
            let s0 = if denom > 1e-14 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            (s, t) = if t0 < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if t0 > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s0, t0)
            };
        }
    }
    let c1 = p1 + d1 * s;
    let c2 = p2 + d2 * t;
    (c1.distance(c2), c1, c2)
}

/// The distance from `p` to segment `ab`.
fn point_seg(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    seg_seg(p, p, a, b).0
}

/// Highest z of segment `ab` over the part of it within `radius` of `p` seen
/// from above, if any part is.
fn max_z_within(p: DVec3, a: DVec3, b: DVec3, radius: f64) -> Option<f64> {
    // |(a - p)xy + t (b - a)xy|² <= radius², t in [0, 1]
    let w = (a - p).truncate();
    let d = (b - a).truncate();
    let qa = d.length_squared();
    let qb = 2.0 * w.dot(d);
    let qc = w.length_squared() - radius * radius;
    let (t0, t1) = if qa < 1e-24 {
        if qc > 0.0 {
            return None;
        }
        (0.0, 1.0)
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            return None;
        }
        let sq = disc.sqrt();
        ((-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa))
    };
    let (t0, t1) = (t0.max(0.0), t1.min(1.0));
    if t0 > t1 {
        return None;
    }
    let z = |t: f64| a.z + (b.z - a.z) * t;
    Some(z(t0).max(z(t1)))
}

/// Where segments `a0a1` and `b0b1` cross seen from above: the parameters
/// (s, t) with s, t in [0, 1), so that a crossing at a shared vertex of a
/// polygon counts once.
fn cross_xy(a0: DVec3, a1: DVec3, b0: DVec3, b1: DVec3) -> Option<(f64, f64)> {
    let (p, r) = (a0.truncate(), (a1 - a0).truncate());
    let (q, s) = (b0.truncate(), (b1 - b0).truncate());
    let den = r.perp_dot(s);
    if den.abs() < 1e-12 * r.length() * s.length() {
        return None;
    }
    let qp = q - p;
    let u = qp.perp_dot(s) / den;
    let v = qp.perp_dot(r) / den;
    ((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v)).then_some((u, v))
}

/// Linking number of two closed polygons (the last point joins the first) by
/// the signed crossings of their projections on the xy plane: each crossing
/// counts +1 or -1 by the handedness of (over, under), the sum is halved.
/// Also returns the smallest height difference at a crossing.
fn linking_by_crossings(a: &[DVec3], b: &[DVec3]) -> (f64, f64) {
    let mut sum = 0.0;
    let mut gap = f64::INFINITY;
    for i in 0..a.len() {
        let (a0, a1) = (a[i], a[(i + 1) % a.len()]);
        for j in 0..b.len() {
            let (b0, b1) = (b[j], b[(j + 1) % b.len()]);
            if let Some((s, t)) = cross_xy(a0, a1, b0, b1) {
                let za = a0.z + (a1.z - a0.z) * s;
                let zb = b0.z + (b1.z - b0.z) * t;
                gap = gap.min((za - zb).abs());
                let turn = (a1 - a0).truncate().perp_dot((b1 - b0).truncate());
                // (over × under)·z: positive for a right-handed crossing
                let sign = if za > zb {
                    turn.signum()
                } else {
                    -turn.signum()
                };
                sum += sign;
            }
        }
    }
    (sum / 2.0, gap)
}

// ---------------------------------------------------------------------------
// the recipe's pieces

/// The recipe as written, and with other params (bigger rings, a taller band).
const CONFIGS: [&[(&str, &str)]; 2] = [
    &[],
    &[
        ("radius", "20"),
        ("spacing", "45"),
        ("drop", "18"),
        ("band", "1.2"),
    ],
];

/// One filament string of a ring piece, in print order.
#[derive(Clone, Copy, Debug)]
struct Fil {
    a: DVec3,
    b: DVec3,
    /// Index of the piece in print order (0 = the first ring piece).
    piece: usize,
    /// Index of the ring in [`CHAIN`].
    ring: usize,
    /// Index of the run of consecutive extruding strings in the piece (0 = bottom layer).
    run: usize,
    /// Length of the run before this string, mm.
    along: f64,
}

/// The plan's ring pieces, in print order.
struct Pieces {
    plan: Plan,
    /// `--set` params, for messages.
    sets: String,
    /// (index into plan.paths, ring index, K of `ring-COLOUR-K`).
    parts: Vec<(usize, usize, usize)>,
    /// Every extruding string of the ring pieces, in print order.
    fil: Vec<Fil>,
    layer: f64,
}

fn load(sets: &[(&str, &str)]) -> Pieces {
    let opts = p3dp::Options {
        sets: sets
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        ..Default::default()
    };
    let plan = p3dp::plan(&recipe("olympic-rings.yaml"), &opts).unwrap_or_else(|e| panic!("{e}"));
    let layer = plan.recipe().params["layer"];
    let mut parts = Vec::new();
    for (k, tp) in plan.paths().iter().enumerate() {
        if tp.name == "skirt" {
            assert_eq!(k, 0, "the skirt comes first");
            continue;
        }
        let rest = tp
            .name
            .strip_prefix("ring-")
            .unwrap_or_else(|| panic!("part `{}` is not ring-COLOUR-K", tp.name));
        let (colour, num) = rest.rsplit_once('-').unwrap();
        let ring = CHAIN
            .iter()
            .position(|c| *c == colour)
            .unwrap_or_else(|| panic!("unknown ring colour in `{}`", tp.name));
        parts.push((k, ring, num.parse::<usize>().unwrap()));
    }
    let mut fil = Vec::new();
    for (piece, &(k, ring, _)) in parts.iter().enumerate() {
        let tp = &plan.paths()[k];
        let (mut run, mut along, mut in_run) = (0, 0.0, false);
        for j in 0..tp.len() {
            let s = tp.strings[j];
            if s.travel || s.c <= 0.0 {
                if in_run {
                    run += 1;
                }
                (along, in_run) = (0.0, false);
                continue;
            }
            in_run = true;
            let (a, b) = tp.ends(j);
            fil.push(Fil {
                a,
                b,
                piece,
                ring,
                run,
                along,
            });
            along += a.distance(b);
        }
    }
    let sets = sets
        .iter()
        .map(|(k, v)| format!(" --set {k}={v}"))
        .collect();
    Pieces {
        plan,
        sets,
        parts,
        fil,
        layer,
    }
}

impl Pieces {
    fn name(&self, piece: usize) -> &str {
        &self.plan.paths()[self.parts[piece].0].name
    }

    fn param(&self, name: &str) -> f64 {
        self.plan.recipe().params[name]
    }

    /// The points of a piece's first run of extruding strings: its bottom layer.
    fn bottom(&self, piece: usize) -> Vec<DVec3> {
        let tp = &self.plan.paths()[self.parts[piece].0];
        let first = (0..tp.len())
            .find(|&j| !tp.strings[j].travel)
            .expect("a piece extrudes");
        let end = (first..tp.len())
            .find(|&j| tp.strings[j].travel)
            .unwrap_or(tp.len());
        tp.points[first..=end].to_vec()
    }

    /// Each ring's closed centre curve: the bottom layers of its pieces in the
    /// order of K, each starting where the one before ends (the last point,
    /// equal to the first, is dropped).
    fn curves(&self) -> Vec<Vec<DVec3>> {
        (0..CHAIN.len())
            .map(|ring| {
                let mut pieces: Vec<(usize, usize)> = (0..self.parts.len())
                    .filter(|&p| self.parts[p].1 == ring)
                    .map(|p| (self.parts[p].2, p))
                    .collect();
                pieces.sort();
                let ks: Vec<usize> = pieces.iter().map(|x| x.0).collect();
                assert_eq!(
                    ks,
                    (1..=ks.len()).collect::<Vec<_>>(),
                    "pieces of the {} ring",
                    CHAIN[ring]
                );
                let mut curve: Vec<DVec3> = Vec::new();
                for &(_, p) in &pieces {
                    let b = self.bottom(p);
                    if let Some(last) = curve.last() {
                        assert!(
                            last.distance(b[0]) < 1e-6,
                            "{} starts {} mm from where the piece before it ends",
                            self.name(p),
                            last.distance(b[0])
                        );
                        curve.pop();
                    }
                    curve.extend(b);
                }
                let gap = curve[0].distance(*curve.last().unwrap());
                assert!(gap < 1e-6, "{} ring not closed: {gap} mm", CHAIN[ring]);
                curve.pop();
                curve
            })
            .collect()
    }
}

/// Ring pairs that are neighbours in the chain.
fn neighbours(i: usize, j: usize) -> bool {
    i.abs_diff(j) == 1
}

// ---------------------------------------------------------------------------
// unit tests of the geometry

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

#[test]
fn seg_seg_known_cases() {
    let close = |got: (f64, DVec3, DVec3), d: f64| {
        assert!((got.0 - d).abs() < 1e-12, "distance {} expected {d}", got.0);
        assert!((got.1.distance(got.2) - got.0).abs() < 1e-12);
    };
    let o = DVec3::ZERO;
    // parallel, side by side
    close(seg_seg(o, v(1., 0., 0.), v(0., 1., 0.), v(1., 1., 0.)), 1.0);
    // parallel, partly overlapping, and reversed
    close(
        seg_seg(o, v(2., 0., 0.), v(1., 0.5, 0.), v(3., 0.5, 0.)),
        0.5,
    );
    close(
        seg_seg(o, v(2., 0., 0.), v(3., 0.5, 0.), v(1., 0.5, 0.)),
        0.5,
    );
    // parallel and collinear, apart: end to end
    close(seg_seg(o, v(1., 0., 0.), v(2., 0., 0.), v(3., 0., 0.)), 1.0);
    close(seg_seg(v(3., 0., 0.), v(2., 0., 0.), o, v(1., 0., 0.)), 1.0);
    // parallel, shifted past each other: corner to corner
    close(
        seg_seg(o, v(1., 0., 0.), v(2., 1., 0.), v(3., 1., 0.)),
        2f64.sqrt(),
    );
    // crossing
    let x = seg_seg(v(-1., 0., 0.), v(1., 0., 0.), v(0., -1., 0.), v(0., 1., 0.));
    close(x, 0.0);
    assert!(x.1.length() < 1e-12 && x.2.length() < 1e-12);
    // skew, closest points inside both
    let s = seg_seg(v(-1., 0., 0.), v(1., 0., 0.), v(0., -1., 2.), v(0., 1., 2.));
    close(s, 2.0);
    assert!(s.1.distance(o) < 1e-12 && s.2.distance(v(0., 0., 2.)) < 1e-12);
    // skew, closest point at an end of one of them
    let s = seg_seg(o, v(1., 0., 0.), v(2., -1., 1.), v(2., 1., 1.));
    close(s, 2f64.sqrt());
    assert!(s.1.distance(v(1., 0., 0.)) < 1e-12 && s.2.distance(v(2., 0., 1.)) < 1e-12);
    // skew, closest points at ends of both
    close(
        seg_seg(o, v(1., 0., 0.), v(2., 1., 1.), v(2., 3., 1.)),
        3f64.sqrt(),
    );
    // touching at endpoints: a corner, and end to end in line
    close(seg_seg(o, v(1., 0., 0.), v(1., 0., 0.), v(1., 1., 0.)), 0.0);
    close(seg_seg(o, v(1., 0., 0.), v(1., 0., 0.), v(2., 0., 0.)), 0.0);
    // an end on the other's middle (a T)
    close(seg_seg(o, v(2., 0., 0.), v(1., 0., 0.), v(1., 1., 1.)), 0.0);
    // nearly parallel, one above the other
    close(
        seg_seg(o, v(10., 0., 0.), v(0., 0., 0.25), v(10., 1e-9, 0.25)),
        0.25,
    );
    // shrunk to points
    close(seg_seg(v(0., 3., 4.), v(0., 3., 4.), o, o), 5.0);
    close(seg_seg(v(1., 1., 0.), v(1., 1., 0.), o, v(2., 0., 0.)), 1.0);
    close(
        seg_seg(o, v(2., 0., 0.), v(3., 1., 0.), v(3., 1., 0.)),
        2f64.sqrt(),
    );
}

/// Minimum of the convex function |P(s) - Q(t)| over the unit square by nested
/// ternary searches: slow, simple, independent of [`seg_seg`].
fn seg_seg_slow(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> f64 {
    let along = |s: f64| {
        let p = p1.lerp(q1, s);
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..100 {
            let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
            if p.distance(p2.lerp(q2, m1)) <= p.distance(p2.lerp(q2, m2)) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        p.distance(p2.lerp(q2, 0.5 * (lo + hi)))
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..100 {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if along(m1) <= along(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    along(0.5 * (lo + hi))
}

#[test]
fn seg_seg_agrees_with_a_brute_force_minimum() {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut rnd = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
    };
    for k in 0..3000 {
        let mut p = [0.0; 12];
        p.iter_mut().for_each(|x| *x = rnd());
        let (p1, q1, p2) = (
            v(p[0], p[1], p[2]),
            v(p[3], p[4], p[5]),
            v(p[6], p[7], p[8]),
        );
        let mut q2 = v(p[9], p[10], p[11]);
        match k % 4 {
            1 => q2 = p2 + (q1 - p1) * rnd(),                      // parallel
            2 => q2 = p2 + (q1 - p1).cross(v(0., 0., 1.)) * rnd(), // perpendicular
            _ => {}
        }
        let (d, c1, c2) = seg_seg(p1, q1, p2, q2);
        let slow = seg_seg_slow(p1, q1, p2, q2);
        assert!(
            (d - slow).abs() < 1e-7,
            "case {k}: {d} against {slow} for {p1} {q1} {p2} {q2}"
        );
        // the closest points lie on their segments
        assert!(point_seg(c1, p1, q1) < 1e-9 && point_seg(c2, p2, q2) < 1e-9);
    }
}

#[test]
fn linking_numbers_of_known_pairs() {
    let circle = |c: DVec3, tilt: bool, n: usize| -> Vec<DVec3> {
        (0..n)
            .map(|k| {
                let a = 2.0 * PI * k as f64 / n as f64;
                let (s, co) = a.sin_cos();
                c + if tilt { v(co, 0., s) } else { v(co, s, 0.) }
            })
            .collect()
    };
    // a Hopf link: a flat circle and one standing through it
    let a = circle(DVec3::ZERO, false, 40);
    let b = circle(v(1., 0., 0.), true, 40);
    let (lk, _) = linking_by_crossings(&a, &b);
    let g = linking_by_gauss(&a, &b);
    assert_eq!(lk.abs(), 1.0);
    assert!((g - lk).abs() < 1e-9, "Gauss {g}, crossings {lk}");
    // reversing one curve flips the sign
    let rev: Vec<DVec3> = b.iter().rev().copied().collect();
    assert_eq!(linking_by_crossings(&a, &rev).0, -lk);
    assert!((linking_by_gauss(&a, &rev) + lk).abs() < 1e-9);
    // unlinked: apart, and overlapping in plan but one wholly above
    for c in [v(3., 0., 0.), v(0.5, 0., 0.)] {
        let b = circle(c + v(0., 0., 0.5), false, 40);
        assert_eq!(linking_by_crossings(&a, &b).0, 0.0);
        assert!(linking_by_gauss(&a, &b).abs() < 1e-9);
    }
}

// ---------------------------------------------------------------------------
// the recipe

/// Builds the recipe with the binary; the G-code.
fn build_gcode(sets: &[(&str, &str)], tag: &str) -> String {
    let dir = tmp(&format!("olympic-{tag}"));
    let path = recipe("olympic-rings.yaml");
    let mut args = vec!["build", path.to_str().unwrap(), "-o", "olympic.gcode"];
    let pairs: Vec<String> = sets.iter().map(|(k, v)| format!("{k}={v}")).collect();
    for s in &pairs {
        args.extend(["--set", s.as_str()]);
    }
    let out = p3dp(&dir, &args);
    assert!(
        out.status.success(),
        "p3dp {}: exit {:?}\n{}",
        args.join(" "),
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    let g = std::fs::read_to_string(dir.join("olympic.gcode")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    g
}

#[test]
fn builds_without_errors() {
    for (c, sets) in CONFIGS.iter().enumerate() {
        let p = load(sets);
        let errors: Vec<_> = p
            .plan
            .findings
            .iter()
            .filter(|f| f.severity == Severity::Error)
            .collect();
        assert!(errors.is_empty(), "{}: {errors:#?}", p.sets);
        assert!(!build_gcode(sets, &format!("build-{c}")).is_empty());

        assert_eq!(p.plan.recipe().printer.nozzle_diameter, NOZZLE);
        // five rings in 16 pieces; sections, speeds and the first layer in range
        assert_eq!(p.parts.len(), 16);
        let z_min = p
            .fil
            .iter()
            .map(|f| f.a.z.min(f.b.z))
            .fold(f64::MAX, f64::min);
        assert!((0.2..=0.4).contains(&z_min), "lowest filament at {z_min}");
        for &(k, _, _) in &p.parts {
            let tp = &p.plan.paths()[k];
            for s in tp.strings.iter().filter(|s| !s.travel) {
                assert!((0.1..=0.25).contains(&s.c), "{}: c = {}", tp.name, s.c);
                assert!((10.0..=40.0).contains(&s.v), "{}: v = {}", tp.name, s.v);
            }
        }
    }
}

#[test]
fn neighbouring_rings_are_linked_and_others_not() {
    for sets in CONFIGS {
        let p = load(sets);
        let curves = p.curves();
        for (c, colour) in curves.iter().zip(CHAIN) {
            // the centre curve's height varies: on the bed and over arches
            let lo = c.iter().map(|q| q.z).fold(f64::MAX, f64::min);
            let hi = c.iter().map(|q| q.z).fold(f64::MIN, f64::max);
            assert!(hi - lo > 4.0 * p.layer, "{colour}: flat, {lo}..{hi}");
        }
        for i in 0..CHAIN.len() {
            for j in i + 1..CHAIN.len() {
                let (lk, gap) = linking_by_crossings(&curves[i], &curves[j]);
                let g = linking_by_gauss(&curves[i], &curves[j]);
                let pair = format!("{}–{}{}", CHAIN[i], CHAIN[j], p.sets);
                assert!(
                    (g - g.round()).abs() < 1e-6,
                    "{pair}: Gauss integral {g} is not an integer"
                );
                assert_eq!(g.round(), lk, "{pair}: Gauss {g}, crossings {lk}");
                println!("{pair}: linking number {lk} (Gauss integral {g:.12})");
                if neighbours(i, j) {
                    assert_eq!(lk.abs(), 1.0, "{pair} not linked: {lk}");
                    // the curves cross in plan with room between them
                    assert!(gap > 4.0 * p.layer, "{pair}: {gap} mm apart at a crossing");
                } else {
                    assert_eq!(lk, 0.0, "{pair} linked: {lk}");
                }
            }
        }
    }
}

/// Pairs of filament strings of different pieces that are closer than `d`,
/// the earlier first, with their distance and closest points.
fn close_pairs(p: &Pieces, d: f64) -> Vec<(Fil, Fil, f64, DVec3, DVec3)> {
    let mut out = Vec::new();
    for (i, e) in p.fil.iter().enumerate() {
        let lo = e.a.min(e.b) - DVec3::splat(d);
        let hi = e.a.max(e.b) + DVec3::splat(d);
        for l in &p.fil[i + 1..] {
            if l.piece == e.piece || l.a.min(l.b).cmpgt(hi).any() || l.a.max(l.b).cmplt(lo).any() {
                continue;
            }
            let (dist, ce, cl) = seg_seg(e.a, e.b, l.a, l.b);
            if dist < d {
                out.push((*e, *l, dist, ce, cl));
            }
        }
    }
    out
}

#[test]
fn pieces_keep_apart_except_where_one_rests_on_another() {
    for sets in CONFIGS {
        let p = load(sets);
        // "rests on": at their closest points the later string is 0 to 1.5
        // layers above the earlier one and within a nozzle width of it seen
        // from above (a vertical contact; 0 for the butt ends of a joint)
        let mut resting = 0;
        for (e, l, dist, ce, cl) in close_pairs(&p, NOZZLE) {
            let dz = cl.z - ce.z;
            let dxy = (cl - ce).truncate().length();
            assert!(
                (-1e-9..=1.5 * p.layer).contains(&dz) && dxy <= NOZZLE,
                "{}: {} and {} come {dist:.3} mm close at {ce} / {cl} (later {dz:.3} mm above, {dxy:.3} mm aside)",
                p.sets,
                p.name(e.piece),
                p.name(l.piece)
            );
            assert_eq!(e.ring, l.ring, "a ring rests on another ring");
            resting += 1;
        }
        // the scarfed joints do rest on each other
        assert!(resting > 16 * 6, "{resting} contacts");
        // and different rings never touch: two nozzle widths apart at least
        let near = close_pairs(&p, 2.0 * NOZZLE);
        if let Some((e, l, dist, ce, _)) = near.iter().find(|(e, l, ..)| e.ring != l.ring) {
            panic!(
                "{}: {} and {} are {dist:.3} mm apart at {ce}",
                p.sets,
                p.name(e.piece),
                p.name(l.piece)
            );
        }
    }
}

/// Segments indexed by the 1 mm squares (seen from above) within `reach` of them.
struct Grid {
    cells: BTreeMap<(i64, i64), Vec<usize>>,
}

impl Grid {
    fn new(segs: &[(DVec3, DVec3)], reach: f64) -> Grid {
        let mut cells: BTreeMap<(i64, i64), Vec<usize>> = BTreeMap::new();
        for (k, (a, b)) in segs.iter().enumerate() {
            let lo = a.min(*b).truncate() - DVec2::splat(reach);
            let hi = a.max(*b).truncate() + DVec2::splat(reach);
            for x in lo.x.floor() as i64..=hi.x.floor() as i64 {
                for y in lo.y.floor() as i64..=hi.y.floor() as i64 {
                    cells.entry((x, y)).or_default().push(k);
                }
            }
        }
        Grid { cells }
    }

    /// The segments that may be within `reach` of `p`.
    fn near(&self, p: DVec3) -> &[usize] {
        let key = (p.x.floor() as i64, p.y.floor() as i64);
        self.cells.get(&key).map_or(&[], |v| v.as_slice())
    }
}

/// Where the tip moving from `a` to `b` (sampled every 0.05 mm) goes more
/// than TOL below filament `segs[k]` within the footprint, for k before `now`
/// and not `skip(k, distance of the tip from a)`: the tip, k and the depth.
fn dip(
    a: DVec3,
    b: DVec3,
    segs: &[(DVec3, DVec3)],
    grid: &Grid,
    now: usize,
    skip: impl Fn(usize, f64) -> bool,
) -> Option<(DVec3, usize, f64)> {
    let n = (a.distance(b) / 0.05).ceil().max(1.0) as usize;
    for s in 0..=n {
        let frac = s as f64 / n as f64;
        let tip = a.lerp(b, frac);
        for &k in grid.near(tip) {
            if k >= now || skip(k, frac * a.distance(b)) {
                continue;
            }
            let (ea, eb) = segs[k];
            if let Some(z) = max_z_within(tip, ea, eb, FOOTPRINT) {
                if z > tip.z + TOL {
                    return Some((tip, k, z - tip.z));
                }
            }
        }
    }
    None
}

#[test]
fn the_nozzle_never_prints_below_earlier_filament() {
    // Every string of every piece against all filament printed before it:
    // other pieces, lower layers of its own and the pass being printed except
    // its last TRAIL mm, the trail the nozzle has just laid (behind a nozzle
    // going downhill the fresh string is higher than the tip: the slope limit
    // of non-planar printing, not a collision).
    for sets in CONFIGS {
        let p = load(sets);
        let segs: Vec<(DVec3, DVec3)> = p.fil.iter().map(|f| (f.a, f.b)).collect();
        let grid = Grid::new(&segs, FOOTPRINT);
        for (k, f) in p.fil.iter().enumerate() {
            let trail = |j: usize, on: f64| {
                let e = &p.fil[j];
                e.piece == f.piece
                    && e.run == f.run
                    && f.along + on - (e.along + e.a.distance(e.b)) < TRAIL
            };
            if let Some((tip, j, depth)) = dip(f.a, f.b, &segs, &grid, k, trail) {
                panic!(
                    "{}: {} (layer {}) puts the nozzle at {tip} {depth:.3} mm below {} (layer {}) printed before",
                    p.sets,
                    p.name(f.piece),
                    f.run + 1,
                    p.name(p.fil[j].piece),
                    p.fil[j].run + 1
                );
            }
        }
    }
}

#[test]
fn the_head_never_meets_filament_in_the_gcode() {
    // Every move the binary writes, travel included (p3dp's own joins rise
    // first and descend last; each piece starts with a move down from `hop`),
    // against the filament of the moves before it; extruding moves are
    // excused their own trail as above, travel moves nothing.
    for (c, sets) in CONFIGS.iter().enumerate() {
        let g = parse(&build_gcode(sets, &format!("gcode-{c}")));
        let moves: Vec<&Move> = g
            .moves
            .iter()
            .filter(|m| m.from.iter().all(|x| x.is_finite()))
            .collect();
        let segs: Vec<(DVec3, DVec3)> = moves
            .iter()
            .map(|m| (DVec3::from(m.from), DVec3::from(m.to)))
            .collect();
        let deposits = |k: usize| moves[k].g == 1 && moves[k].de > 0.0;
        // each extruding move's run of consecutive extruding moves, and the
        // length of the run before it
        let mut run = vec![usize::MAX; moves.len()];
        let mut along = vec![0.0; moves.len()];
        let (mut r, mut len) = (0, 0.0);
        for k in 0..moves.len() {
            if deposits(k) {
                (run[k], along[k]) = (r, len);
                len += segs[k].0.distance(segs[k].1);
            } else if segs[k].0 != segs[k].1 && k > 0 && run[k - 1] == r {
                (r, len) = (r + 1, 0.0);
            }
        }
        let grid = Grid::new(&segs, FOOTPRINT);
        let (mut travels, mut travel_mm) = (0, 0.0);
        for k in 0..moves.len() {
            let (a, b) = segs[k];
            if a == b {
                continue;
            }
            if !deposits(k) {
                travels += 1;
                travel_mm += a.distance(b);
            }
            let skip = |j: usize, on: f64| {
                !deposits(j)
                    || (run[j] == run[k]
                        && along[k] + on - (along[j] + segs[j].0.distance(segs[j].1)) < TRAIL)
            };
            if let Some((tip, j, depth)) = dip(a, b, &segs, &grid, k, skip) {
                panic!(
                    "{sets:?}: G{} move {k} of part `{}` puts the nozzle at {tip} {depth:.3} mm below filament of part `{}`",
                    moves[k].g, g.parts[moves[k].part], g.parts[moves[j].part]
                );
            }
        }
        assert!(travels > 16 * 8 && travel_mm > 100.0, "{travels} moves");
    }
}

#[test]
fn pieces_print_in_the_claimed_order() {
    for sets in CONFIGS {
        let p = load(sets);
        // wherever two rings cross seen from above, the higher string's piece
        // is printed after the lower string's piece
        let mut over: BTreeMap<(usize, usize), usize> = BTreeMap::new();
        for e in &p.fil {
            for l in &p.fil {
                if e.ring >= l.ring {
                    continue;
                }
                let Some((s, t)) = cross_xy(e.a, e.b, l.a, l.b) else {
                    continue;
                };
                let (ze, zl) = (e.a.lerp(e.b, s).z, l.a.lerp(l.b, t).z);
                let (hi, lo) = if ze > zl { (e, l) } else { (l, e) };
                assert!(
                    hi.piece > lo.piece,
                    "{}: {} passes over {} but is printed before it",
                    p.sets,
                    p.name(hi.piece),
                    p.name(lo.piece)
                );
                *over.entry((hi.piece, lo.piece)).or_default() += 1;
            }
        }
        // eight crossings, each of an arch over one low piece; no piece both
        // passes over another ring and lies under one
        let uppers: Vec<usize> = over.keys().map(|k| k.0).collect();
        let lowers: Vec<usize> = over.keys().map(|k| k.1).collect();
        assert_eq!(uppers.len(), 8, "{over:?}");
        assert!(uppers.iter().all(|u| !lowers.contains(u)));
        let mut arches = uppers.clone();
        arches.dedup();
        assert_eq!(arches.len(), 8, "one arch per crossing");
        // all four layers of an arch pass over all four of the piece below
        assert!(over.values().all(|&n| n == 16), "{over:?}");
        // the arches come last, after every low piece
        let first = p.parts.len() - arches.len();
        assert_eq!(arches, (first..p.parts.len()).collect::<Vec<_>>());
    }
}

#[test]
fn only_the_arches_bottom_layers_bridge() {
    // A string is supported when its middle is on the first layer, or 0.5 to
    // 1.5 layers above filament printed before it and within half a nozzle
    // width of it seen from above; otherwise it spans air. Only the bottom
    // layers of the arches may, and only between their feet.
    for sets in CONFIGS {
        let p = load(sets);
        let z0 = p
            .fil
            .iter()
            .map(|f| f.a.z.min(f.b.z))
            .fold(f64::MAX, f64::min);
        let segs: Vec<(DVec3, DVec3)> = p.fil.iter().map(|f| (f.a, f.b)).collect();
        let grid = Grid::new(&segs, NOZZLE);
        let mut bridged: BTreeMap<usize, f64> = BTreeMap::new();
        for (k, f) in p.fil.iter().enumerate() {
            let m = f.a.lerp(f.b, 0.5);
            if m.z <= z0 + 1e-6 {
                continue;
            }
            let held = grid.near(m).iter().any(|&j| {
                let (a, b) = segs[j];
                let flat = |q: DVec3| q.with_z(0.0);
                if j >= k || point_seg(flat(m), flat(a), flat(b)) > NOZZLE / 2.0 {
                    return false;
                }
                let (_, _, below) = seg_seg(m, m, a, b);
                (0.5 * p.layer..=1.5 * p.layer).contains(&(m.z - below.z))
            });
            if !held {
                assert_eq!(
                    f.run,
                    0,
                    "{}: {} layer {} is not supported at {m}",
                    p.sets,
                    p.name(f.piece),
                    f.run + 1
                );
                *bridged.entry(f.piece).or_default() += f.a.distance(f.b);
            }
        }
        // between the feet, and the first string off each foot
        let span = 2.0 * (p.param("half") - p.param("foot") + p.param("seg"));
        for (&piece, &len) in &bridged {
            let name = p.name(piece);
            assert!(
                len <= span,
                "{name}: {len:.1} mm bridged, more than {span:.1}"
            );
            println!(
                "{name}{}: {len:.1} mm of its bottom layer spans air",
                p.sets
            );
        }
        assert_eq!(bridged.len(), 8, "the eight arches bridge, nothing else");
    }
}
