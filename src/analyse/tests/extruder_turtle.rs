//! ExtruderTurtle's own prints (Pezzuti Dyer and Buechley, TEI '22) beyond
//! the basic shapes: declared hairs (§4.3 after Laput et al.), the string-art
//! parabola (Fig. 9 left) and the chain mail, each read back from its
//! strings and checked for the property its recipe promises.
//!
//! Past the public face: the checks run on strings changed by hand
//! (`analyse::check::run`). Home: beside `analyse::check`.

use crate::analyse::check::{self, Severity};
use crate::base::testing::linking_by_gauss;
use crate::base::toolpath::Toolpath;
use crate::generate::assembly::make_parts;
use crate::generate::model::Recipe;
use glam::DVec3;
use std::path::PathBuf;

/// The recipe's only part, with its steps.
fn only_part(recipe: &Recipe) -> Toolpath {
    let mut parts = make_parts(recipe).unwrap();
    assert_eq!(parts.len(), 1);
    parts.swap_remove(0)
}

/// The codes of the findings of `tp` (as the only part of `recipe`) that are
/// warnings or errors.
fn codes(recipe: &Recipe, tp: &Toolpath) -> Vec<&'static str> {
    let (f, _) = check::run(recipe, &[tp], &[]);
    f.iter()
        .filter(|f| f.severity != Severity::Info)
        .map(|f| f.code)
        .collect()
}

#[test]
fn hairs_are_rows_of_declared_hairs_of_the_recipes_length_that_pass_check() {
    let r = load("hairs.yaml");
    let tp = only_part(&r);
    let (rows, per_row, length) = (
        param(&r, "rows") as usize,
        param(&r, "per_row") as usize,
        param(&r, "length"),
    );
    let angle = param(&r, "angle").to_radians();
    let top = param(&r, "top") + param(&r, "layer_height");
    let hairs: Vec<(DVec3, DVec3)> = (0..tp.len())
        .filter(|&k| tp.strings[k].hair)
        .map(|k| tp.ends(k))
        .collect();
    // one hair per root, each `length` long, rising at `angle` towards +x
    // from a root one layer above the pad
    assert_eq!(hairs.len(), rows * per_row);
    for (a, b) in &hairs {
        let d = *b - *a;
        assert!((d.length() - length).abs() < 1e-9, "{a} → {b}");
        assert!((d.z - length * angle.sin()).abs() < 1e-9 && d.y.abs() < 1e-9);
        assert!((a.z - top).abs() < 1e-9, "root {a}");
    }
    // the roots make `rows` rows of `per_row` distinct roots
    let mut ys: Vec<i64> = hairs
        .iter()
        .map(|(a, _)| (a.y * 1e6).round() as i64)
        .collect();
    ys.dedup();
    assert_eq!(ys.len(), rows);
    // each hair: a blob pushed in place just before it, a retraction after it
    for k in (0..tp.len()).filter(|&k| tp.strings[k].hair) {
        assert!(tp.events.iter().any(|&(i, ref e)| i == k
            && matches!(e, crate::base::toolpath::Event::Extrude { filament, .. } if *filament > 0.0)));
        assert!(tp
            .events
            .iter()
            .any(|(i, e)| *i == k + 1 && *e == crate::base::toolpath::Event::Retract));
    }
    // declared, they pass every check; the same strings undeclared are what
    // the three checks exist to find
    assert_eq!(codes(&r, &tp), Vec::<&str>::new());
    let mut bare = tp.clone();
    for s in bare.strings.make_mut() {
        s.hair = false;
    }
    let found = codes(&r, &bare);
    for code in ["unsupported", "nozzle-collision"] {
        assert!(found.contains(&code), "{found:?}");
    }
    // hairs thinner still: declared, still clean; undeclared, `thin-string` too
    let r = load_with("hairs.yaml", &[("hair_rate", "0.004")]);
    let tp = only_part(&r);
    assert_eq!(codes(&r, &tp), Vec::<&str>::new());
    let mut bare = tp.clone();
    for s in bare.strings.make_mut() {
        s.hair = false;
    }
    assert!(codes(&r, &bare).contains(&"thin-string"));
}

#[test]
fn the_parabolas_chords_are_tangent_to_it_and_their_crossings_lie_on_it() {
    let r = load("string-art-parabola.yaml");
    let tp = only_part(&r);
    let (n, arm, h) = (
        param(&r, "divisions") as usize,
        param(&r, "arm"),
        param(&r, "layer_height"),
    );
    let (p0, o, p2) = (
        DVec3::new(-arm / 2.0, arm / 2.0, 0.0),
        DVec3::new(-arm / 2.0, -arm / 2.0, 0.0),
        DVec3::new(arm / 2.0, -arm / 2.0, 0.0),
    );
    // the quadratic Bezier P0, O, P2: the parabola the chords should envelop
    let curve = |t: f64| p0 * (1.0 - t) * (1.0 - t) + o * 2.0 * t * (1.0 - t) + p2 * t * t;
    let samples: Vec<DVec3> = (0..=20_000).map(|i| curve(i as f64 / 20_000.0)).collect();
    let flat = |v: DVec3| DVec3::new(v.x, v.y, 0.0);
    for layer in 0..param(&r, "layers") as usize {
        let z = h * (layer + 1) as f64;
        // the chords: strings off both arms (not along x = -arm/2 or y = -arm/2)
        let on_arm = |a: DVec3, b: DVec3| {
            ((a.x + arm / 2.0).abs() < 1e-9 && (b.x + arm / 2.0).abs() < 1e-9)
                || ((a.y + arm / 2.0).abs() < 1e-9 && (b.y + arm / 2.0).abs() < 1e-9)
        };
        let mut chords: Vec<(DVec3, DVec3)> = at_height(&tp, z)
            .into_iter()
            .filter(|&(a, b)| !on_arm(a, b))
            .map(|(a, b)| {
                // from the first arm (x = -arm/2) to the second
                let (a, b) = if (a.x + arm / 2.0).abs() < 1e-9 {
                    (a, b)
                } else {
                    (b, a)
                };
                (flat(a), flat(b))
            })
            .collect();
        assert_eq!(chords.len(), n - 1, "layer {layer}");
        chords.sort_by(|x, y| y.0.y.total_cmp(&x.0.y));
        for (i, &(a, b)) in chords.iter().enumerate() {
            // each chord touches the curve and has all of it on one side
            let u = (b - a).normalize();
            let d: Vec<f64> = samples
                .iter()
                .map(|&q| u.x * (q.y - a.y) - u.y * (q.x - a.x))
                .collect();
            let least = d.iter().fold(f64::INFINITY, |m, &v| m.min(v.abs()));
            assert!(least < 1e-3, "chord {i} misses the curve by {least} mm");
            let (lo, hi) = d
                .iter()
                .fold((0f64, 0f64), |(l, h), &v| (l.min(v), h.max(v)));
            assert!(
                lo > -1e-6 || hi < 1e-6,
                "chord {i} crosses the curve ({lo}, {hi})"
            );
        }
        // consecutive chords cross within h²/4 |P0 - 2 O + P2| of the curve
        // (their crossing is the blossom of t and t + 1/N: that far from the
        // point at t + 1/(2N), along P0 - 2 O + P2)
        let step = 1.0 / n as f64;
        let tol = step * step / 4.0 * (p0 - 2.0 * o + p2).length() + 1e-6;
        for w in chords.windows(2) {
            let ((a1, b1), (a2, b2)) = (w[0], w[1]);
            let (d1, d2) = (b1 - a1, b2 - a2);
            let den = d1.x * d2.y - d1.y * d2.x;
            let s = ((a2.x - a1.x) * d2.y - (a2.y - a1.y) * d2.x) / den;
            let x = a1 + d1 * s;
            let off = samples
                .iter()
                .fold(f64::INFINITY, |m, q| m.min(q.distance(x)));
            assert!(
                off <= tol,
                "crossing {x} is {off} mm off the parabola (tolerance {tol})"
            );
        }
    }
    assert!(codes(&r, &tp).is_empty(), "{:?}", codes(&r, &tp));
}

/// Distance from `p` to segment `a`–`b`.
fn to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let d = b - a;
    let t = if d.length_squared() > 0.0 {
        ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + d * t)
}

/// Least distance between two sets of strings, sampling the first every 0.1 mm.
fn apart(a: &[(DVec3, DVec3)], b: &[(DVec3, DVec3)]) -> f64 {
    let mut m = f64::INFINITY;
    for &(p, q) in a {
        let n = (p.distance(q) / 0.1).ceil().max(1.0) as usize;
        for i in 0..=n {
            let s = p.lerp(q, i as f64 / n as f64);
            for &(c, d) in b {
                m = m.min(to_segment(s, c, d));
            }
        }
    }
    m
}

#[test]
fn chain_mail_links_interlock_with_their_neighbours_only_and_never_touch() {
    let r = load("chain-mail.yaml");
    let tp = only_part(&r);
    let (links, pitch, a_len, reach, w, ox) = (
        param(&r, "links") as usize,
        param(&r, "pitch"),
        param(&r, "a_len"),
        param(&r, "reach"),
        param(&r, "b_half"),
        param(&r, "ox"),
    );
    // every extruding string belongs to one link: an A link's strings lie
    // in y = 0 within its x range, a B link's off it within its own
    let mut a_links: Vec<Vec<(DVec3, DVec3)>> = vec![Vec::new(); links];
    let mut b_links: Vec<Vec<(DVec3, DVec3)>> = vec![Vec::new(); links - 1];
    for k in (0..tp.len()).filter(|&k| !tp.strings[k].travel) {
        let (a, b) = tp.ends(k);
        let mx = (a.x + b.x) / 2.0;
        if a.y == 0.0 && b.y == 0.0 {
            let i = (0..links)
                .find(|&i| {
                    let x0 = ox + i as f64 * pitch;
                    (x0 - 1e-9..=x0 + a_len + 1e-9).contains(&mx)
                })
                .unwrap_or_else(|| panic!("string {k} {a}–{b} is in no A link"));
            a_links[i].push((a, b));
        } else {
            let i = (0..links - 1)
                .find(|&i| {
                    let x0 = ox + i as f64 * pitch + a_len - reach;
                    let x1 = ox + (i + 1) as f64 * pitch + reach;
                    (x0 - 1e-9..=x1 + 1e-9).contains(&mx)
                })
                .unwrap_or_else(|| panic!("string {k} {a}–{b} is in no B link"));
            b_links[i].push((a, b));
        }
    }
    // each link's centre curve, read from its strings: an A link is the
    // rectangle through its lowest and highest strings, closed by pillars
    // present in every layer between; a B link is its top layer, a closed
    // rectangle of perimeter 2 (x1 - x0) + 4 b_half
    let span = |s: &[(DVec3, DVec3)], f: fn(DVec3) -> f64| {
        s.iter()
            .flat_map(|&(a, b)| [f(a), f(b)])
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(v), h.max(v))
            })
    };
    let h = param(&r, "layer_height");
    let mut curves: Vec<Vec<DVec3>> = Vec::new();
    for (i, s) in a_links.iter().enumerate() {
        let (x0, x1) = span(s, |p| p.x);
        let (z0, z1) = span(s, |p| p.z);
        assert!((x1 - x0 - a_len).abs() < 1e-9 && (z1 - z0) > 5.0, "A {i}");
        let layers = ((z1 - z0) / h).round() as usize + 1;
        for l in 0..layers {
            let z = z0 + l as f64 * h;
            let here: Vec<_> = s.iter().filter(|(a, _)| (a.z - z).abs() < 1e-6).collect();
            for end in [x0, x1] {
                assert!(
                    here.iter().any(|(a, b)| a.x == end || b.x == end),
                    "A {i}: no pillar at x = {end}, z = {z}"
                );
            }
        }
        curves.push(vec![
            DVec3::new(x0, 0.0, z0),
            DVec3::new(x1, 0.0, z0),
            DVec3::new(x1, 0.0, z1),
            DVec3::new(x0, 0.0, z1),
        ]);
    }
    for (i, s) in b_links.iter().enumerate() {
        let (x0, x1) = span(s, |p| p.x);
        let (_, top) = span(s, |p| p.z);
        let lid: f64 = s
            .iter()
            .filter(|(a, b)| a.z == top && b.z == top)
            .map(|(a, b)| a.distance(*b))
            .sum();
        assert!(
            (lid - 2.0 * (x1 - x0) - 4.0 * w).abs() < 1e-9,
            "B {i}: {lid}"
        );
        curves.push(vec![
            DVec3::new(x0, -w, top),
            DVec3::new(x1, -w, top),
            DVec3::new(x1, w, top),
            DVec3::new(x0, w, top),
        ]);
    }
    assert_eq!(curves.len(), 2 * links - 1);
    // in chain order A0 B0 A1 B1 …: neighbours link once, others not at all
    let order: Vec<usize> = (0..2 * links - 1)
        .map(|j| if j % 2 == 0 { j / 2 } else { links + j / 2 })
        .collect();
    let strings = |j: usize| {
        if j < links {
            &a_links[j]
        } else {
            &b_links[j - links]
        }
    };
    for p in 0..order.len() {
        for q in p + 1..order.len() {
            let lk = linking_by_gauss(&curves[order[p]], &curves[order[q]]);
            let want = if q == p + 1 { 1.0 } else { 0.0 };
            assert!(
                (lk.abs() - want).abs() < 1e-6,
                "links {p} and {q} in the chain: linking number {lk}"
            );
            // no two links touch: more than a bead (generic-220's 0.4 mm
            // nozzle) apart, centre line to centre line, with room to spare
            let d = apart(strings(order[p]), strings(order[q]));
            assert!(d > 1.0, "links {p} and {q} come {d} mm close");
        }
    }
    assert!(codes(&r, &tp).is_empty(), "{:?}", codes(&r, &tp));
}

/// Extruding strings of `tp` at height `z` (within 1 µm), as segments.
fn at_height(tp: &Toolpath, z: f64) -> Vec<(DVec3, DVec3)> {
    (0..tp.len())
        .filter(|&k| !tp.strings[k].travel)
        .map(|k| tp.ends(k))
        .filter(|(a, b)| (a.z - z).abs() < 1e-6 && (b.z - z).abs() < 1e-6)
        .collect()
}

fn load(name: &str) -> Recipe {
    load_with(name, &[])
}

fn load_with(name: &str, sets: &[(&str, &str)]) -> Recipe {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("recipes")
        .join(name);
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    crate::recipe::load(&path, &sets, None).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn param(recipe: &Recipe, name: &str) -> f64 {
    *recipe
        .params
        .get(name)
        .unwrap_or_else(|| panic!("no param `{name}`"))
}
