//! The gallery of Kanada's prints (cup, plates, heart, vases, deformed sphere,
//! lamp shades): each recipe checked for the geometry its comment promises,
//! part by part, before and after its steps.
//!
//! Past the public face: the parts are built with their steps cut short or
//! without brim and stand (`Part::steps`, `brim`, `stand`, `more`,
//! `Recipe::groups`, `Primitive::string_count`). Home: beside
//! `generate::assembly`.

use std::f64::consts::{PI, TAU};
use std::path::PathBuf;

use crate::base::toolpath::{polar, Toolpath};
use crate::generate::assembly::make_parts;
use crate::generate::model::Recipe;
use glam::DVec3;

/// The recipes made of a filled bottom and a wall standing on it.
const ON_A_BOTTOM: [&str; 5] = [
    "cup.yaml",
    "plate.yaml",
    "heart-plate.yaml",
    "vase.yaml",
    "twisted-heart-vase.yaml",
];

fn load(name: &str, sets: &[(&str, &str)]) -> Recipe {
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    crate::recipe::load(&path(name), &sets, None).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn param(recipe: &Recipe, name: &str) -> f64 {
    *recipe
        .params
        .get(name)
        .unwrap_or_else(|| panic!("no param `{name}`"))
}

/// Index of the part called `name`.
fn index(recipe: &Recipe, name: &str) -> usize {
    recipe
        .parts
        .iter()
        .position(|p| p.name == name)
        .unwrap_or_else(|| panic!("no part `{name}`"))
}

/// Part `name` with all its steps (and those of the groups around it).
/// Part `name`'s own strings (without a brim or a stand: the surfaces are
/// the part's).
fn part(recipe: &Recipe, name: &str) -> Toolpath {
    let k = index(recipe, name);
    let mut r = recipe.clone();
    for p in &mut r.parts {
        p.brim = None;
        p.stand = None;
    }
    make_parts(&r).unwrap().swap_remove(k)
}

/// Part `name` with only its first `steps` steps (0: the bare primitives).
fn part_upto(recipe: &Recipe, name: &str, steps: usize) -> Toolpath {
    let k = index(recipe, name);
    let mut r = recipe.clone();
    assert!(steps <= r.parts[k].steps.len() && r.groups.is_empty());
    r.parts[k].steps.truncate(steps);
    make_parts(&r).unwrap().swap_remove(k)
}

/// Part `name` as its primitives make it, before any step.
fn undeformed(recipe: &Recipe, name: &str) -> Toolpath {
    let k = index(recipe, name);
    let mut r = recipe.clone();
    r.groups.clear();
    r.parts[k].steps.clear();
    make_parts(&r).unwrap().swap_remove(k)
}

/// The strings of a part's first primitive and those of the rest (for a
/// part whose primitives meet end to start, without a joining travel).
fn split_first(recipe: &Recipe, k: usize, tp: &Toolpath) -> (Toolpath, Toolpath) {
    let n = recipe.parts[k].primitive.string_count() as usize;
    assert_eq!(tp.len() as u64, recipe.parts[k].string_count() - 1);
    let first = Toolpath {
        name: tp.name.clone(),
        points: tp.points[..=n].to_vec(),
        strings: tp.strings.range(0, n),
        events: Vec::new(),
        markers: Vec::new(),
        turns: None,
    };
    let rest = Toolpath {
        name: tp.name.clone(),
        points: tp.points[n..].to_vec(),
        strings: tp.strings.range(n, tp.len()),
        events: Vec::new(),
        markers: Vec::new(),
        turns: None,
    };
    (first, rest)
}

/// The bottom and the wall: two parts, or (cup, plate: Fig. 6 literally)
/// the two primitives of one part, with all their steps or with none.
fn bottom_and_wall(recipe: &Recipe, deformed: bool) -> (Toolpath, Toolpath) {
    if recipe.parts.iter().any(|p| p.name == "bottom") {
        if deformed {
            return (part(recipe, "bottom"), part(recipe, "wall"));
        }
        return (undeformed(recipe, "bottom"), undeformed(recipe, "wall"));
    }
    assert_eq!(recipe.parts.len(), 1);
    let name = recipe.parts[0].name.clone();
    assert_eq!(recipe.parts[0].more.len(), 1, "{name}: a bottom and a wall");
    let tp = if deformed {
        part(recipe, &name)
    } else {
        undeformed(recipe, &name)
    };
    split_first(recipe, 0, &tp)
}

fn r_of(p: DVec3) -> f64 {
    polar(p).0
}

fn theta_of(p: DVec3) -> f64 {
    polar(p).1
}

/// Signed turning angle of the horizontal projection at each interior point
/// of `pts` (positive: turning left, i.e. a convex corner of a curve run
/// counter-clockwise). Entry j belongs to `pts[j + 1]`.
fn turning(pts: &[DVec3]) -> Vec<f64> {
    pts.windows(3)
        .map(|w| {
            let a = (w[1] - w[0]).truncate();
            let b = (w[2] - w[1]).truncate();
            libm::atan2(a.perp_dot(b), a.dot(b))
        })
        .collect()
}

/// Local maxima of `f` over the interior of a sequence.
fn maxima(f: &[f64]) -> usize {
    f.windows(3).filter(|w| w[1] > w[0] && w[1] >= w[2]).count()
}

#[test]
fn walls_stand_on_the_rim_of_their_bottoms() {
    for name in ON_A_BOTTOM {
        let recipe = load(name, &[]);
        let (bottom, wall) = bottom_and_wall(&recipe, true);
        let top = bottom.points.iter().map(|p| p.z).fold(f64::MIN, f64::max);
        assert!(
            (top - param(&recipe, "bottom_top")).abs() < 1e-9,
            "{name}: top layer at {top}"
        );
        let rim = bottom
            .points
            .iter()
            .filter(|p| (p.z - top).abs() < 1e-9)
            .map(|&p| r_of(p))
            .fold(f64::MIN, f64::max);
        let start = wall.points[0];
        // the wall starts on the top layer, where the bottom's spiral ended
        assert!(
            (start.z - top).abs() < 1e-9,
            "{name}: wall starts at z = {}, top layer at {top}",
            start.z
        );
        assert!(
            (start - *bottom.points.last().unwrap()).length() < 1e-9,
            "{name}: the wall does not continue the bottom"
        );
        // its foot has the bottom's radius (exactly where they meet, and
        // within a string's width over the first turn)
        let foot: Vec<f64> = wall.points[..=segments(&recipe)]
            .iter()
            .map(|&p| r_of(p))
            .collect();
        for r in &foot {
            assert!(
                (r - rim).abs() < 0.6,
                "{name}: the first turn is at r = {r}, the bottom's rim at {rim}"
            );
        }
        assert!((foot[0] - param(&recipe, "radius")).abs() < 1e-9);
    }
}

/// Strings per turn of the wall (plate.yaml's own, else the cup's).
fn segments(recipe: &Recipe) -> usize {
    match recipe.params.get("wall_segments") {
        Some(&s) => s as usize,
        None => param(recipe, "segments") as usize,
    }
}

#[test]
fn cup_wall_is_a_helix_of_the_bottoms_radius() {
    let recipe = load("cup.yaml", &[]);
    // Fig. 6a: one part, its primitives the bottom and then the wall
    assert_eq!(recipe.parts.len(), 1);
    assert_eq!(recipe.parts[0].name, "cup");
    let (bottom, wall) = bottom_and_wall(&recipe, true);
    let extruding = |t: &Toolpath| {
        t.strings
            .iter()
            .filter(|s| !s.travel)
            .copied()
            .collect::<Vec<_>>()
    };
    assert!(extruding(&bottom).iter().all(|s| s.c == 0.1 && s.v == 25.0));
    assert_eq!(extruding(&wall).len(), wall.len());
    assert!(wall.strings.iter().all(|s| s.c == 0.15 && s.v == 30.0));
    let (radius, pitch, top) = (
        param(&recipe, "radius"),
        param(&recipe, "pitch"),
        param(&recipe, "bottom_top"),
    );
    for p in &wall.points {
        assert!((r_of(*p) - radius).abs() < 1e-9);
    }
    let seg = segments(&recipe);
    assert!((wall.points[seg].z - wall.points[0].z - pitch).abs() < 1e-9);
    let last = wall.points.last().unwrap().z;
    assert!((last - top - param(&recipe, "height")).abs() < 1e-9);
    // 2 to 3 bottom layers
    let mut zs: Vec<f64> = bottom.points.iter().map(|p| p.z).collect();
    zs.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    assert!((2..=3).contains(&zs.len()), "{} bottom layers", zs.len());
}

/// The wall of plate.yaml against the cup's helix, standing on the bottom at
/// z = lift: of its height z = h - lift above the foot, r' = r + 1.05 z,
/// z' = lift + 0.3 z plus the wave A (z / H) sin(m theta); the bottom is
/// left in place, its c too scaled by 0.96.
fn plate_wall_matches(sets: &[(&str, &str)]) -> (Recipe, Toolpath) {
    let recipe = load("plate.yaml", sets);
    let (bottom0, helix) = bottom_and_wall(&recipe, false);
    let (bottom, wall) = bottom_and_wall(&recipe, true);
    let (a, m, h, lift) = (
        param(&recipe, "amplitude"),
        param(&recipe, "cycles"),
        param(&recipe, "height"),
        param(&recipe, "bottom_top"),
    );
    assert_eq!(bottom0.points, bottom.points);
    for (s, t) in bottom0.strings.iter().zip(&bottom.strings) {
        assert!(t.travel || ((t.c - 0.96 * s.c).abs() < 1e-12 && t.v == s.v));
    }
    assert_eq!(helix.points.len(), wall.points.len());
    for (p, q) in helix.points.iter().zip(&wall.points) {
        let (r, theta) = polar(*p);
        let z = p.z - lift;
        let want_r = r + 1.05 * z;
        let want_z = 0.3 * z + a * (z / h) * libm::sin(m * theta) + lift;
        assert!(
            (r_of(*q) - want_r).abs() < 1e-9 && (q.z - want_z).abs() < 1e-9,
            "helix point {p} went to {q}, expected r = {want_r}, z = {want_z}"
        );
        if r_of(*q) > 1e-6 {
            let dt = (theta_of(*q) - theta).rem_euclid(TAU);
            assert!(dt.min(TAU - dt) < 1e-9, "theta changed at {p}");
        }
    }
    for (s, t) in helix.strings.iter().zip(&wall.strings) {
        assert!((t.c - 0.96 * s.c).abs() < 1e-12 && t.v == s.v);
    }
    (recipe, wall)
}

#[test]
fn plate_is_the_cup_deformed_by_the_papers_function() {
    // without the wave the deformation is exactly the paper's
    let (recipe, wall) = plate_wall_matches(&[("amplitude", "0")]);
    let lift = param(&recipe, "bottom_top");
    let (_, helix) = bottom_and_wall(&recipe, false);
    for (p, q) in helix.points.iter().zip(&wall.points) {
        assert!((q.z - (0.3 * (p.z - lift) + lift)).abs() < 1e-9);
        assert!((r_of(*q) - (r_of(*p) + 1.05 * (p.z - lift))).abs() < 1e-9);
    }
    // with it, only by the wave term
    plate_wall_matches(&[]);
    plate_wall_matches(&[("cycles", "3"), ("amplitude", "5")]);
    // the deformed vertical pitch: one turn later, 0.3 pitch higher (0.15 mm)
    let seg = segments(&recipe);
    let dz = wall.points[seg].z - wall.points[0].z;
    assert!((0.12..=0.35).contains(&dz), "vertical pitch {dz}");
}

#[test]
fn plate_rim_has_as_many_waves_as_cycles() {
    for (cycles, want) in [("4", 4), ("3", 3), ("5", 5)] {
        let recipe = load("plate.yaml", &[("cycles", cycles)]);
        let (_, wall) = bottom_and_wall(&recipe, true);
        let seg = segments(&recipe);
        let top = &wall.points[wall.points.len() - 1 - seg..];
        let z: Vec<f64> = top.iter().map(|p| p.z).collect();
        assert_eq!(maxima(&z), want, "cycles = {cycles}");
        // the crests rise `amplitude` above the mean rim height
        let a = param(&recipe, "amplitude");
        let (lo, hi) = z
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v)));
        assert!((hi - lo - 2.0 * a).abs() < 0.4, "rim from {lo} to {hi}");
    }
}

#[test]
fn plate_bottom_fits_the_deformed_wall_for_any_size() {
    for sets in [
        vec![],
        vec![("radius", "20"), ("height", "40")],
        vec![("bottom_layers", "1")],
    ] {
        let recipe = load("plate.yaml", &sets);
        let (bottom, wall) = bottom_and_wall(&recipe, true);
        let top = bottom.points.iter().map(|p| p.z).fold(f64::MIN, f64::max);
        let rim = bottom.points.iter().map(|&p| r_of(p)).fold(0.0, f64::max);
        assert!((wall.points[0].z - top).abs() < 1e-9, "{sets:?}");
        assert!((r_of(wall.points[0]) - rim).abs() < 1e-9, "{sets:?}");
        // the wall never dips below the top layer nor inside the rim
        assert!(wall.points.iter().all(|p| p.z >= top - 1e-9));
        assert!(wall.points.iter().all(|&p| r_of(p) >= rim - 1e-9));
    }
}

/// Index in the top turn of the heart's tip: the point on the -x side closest
/// to y = 0.
fn tip_index(turn: &[DVec3]) -> usize {
    (0..turn.len())
        .filter(|&i| turn[i].x < 0.0)
        .min_by(|&a, &b| turn[a].y.abs().total_cmp(&turn[b].y.abs()))
        .unwrap()
}

#[test]
fn heart_plate_applies_the_heart_function_to_the_plate() {
    let recipe = load("heart-plate.yaml", &[]);
    let plate = part_upto(&recipe, "wall", 1);
    let heart = part_upto(&recipe, "wall", 2);
    let (b, radius, wave, waves, depth) = (
        param(&recipe, "b"),
        param(&recipe, "radius"),
        param(&recipe, "wave"),
        param(&recipe, "waves"),
        param(&recipe, "depth"),
    );
    assert!((0.0..=1.2).contains(&b));
    for (p, q) in plate.points.iter().zip(&heart.points) {
        let want = DVec3::new(
            p.x + b * p.z * (p.y.abs() / radius).sqrt(),
            p.y,
            p.z + wave * (p.z / depth) * libm::cos(waves * theta_of(*p)),
        );
        assert!((*q - want).length() < 1e-9, "{p} went to {q}, not {want}");
    }
}

#[test]
fn heart_plate_has_a_cusp_at_the_top_and_a_circle_at_the_bottom() {
    let recipe = load("heart-plate.yaml", &[]);
    let wall = part(&recipe, "wall");
    let seg = segments(&recipe);
    let step = TAU / seg as f64;

    // the top turn: the tip at y = 0 is the extreme x, a cusp
    let top = &wall.points[wall.points.len() - 1 - seg..];
    let tip = tip_index(top);
    assert!(top[tip].y.abs() < 1e-6, "tip at y = {}", top[tip].y);
    let min_x = top.iter().map(|p| p.x).fold(f64::MAX, f64::min);
    assert_eq!(top[tip].x, min_x, "the tip is not the leftmost point");
    let turns = turning(top);
    let at_tip = turns[tip - 1];
    assert!(at_tip > 1.0, "the tip turns by only {at_tip} rad");
    // elsewhere the curve turns by about one step per string; at the tip it
    // folds back. Next to the two cusps (the tip and the dent at +x) the
    // curve bends too, but far less
    let others = |near: f64| {
        turns
            .iter()
            .enumerate()
            .filter(|&(j, _)| j + 1 != tip && top[j + 1].y.abs() >= near)
            .map(|(_, &a)| a.abs())
            .fold(0.0, f64::max)
    };
    let next_to = others(0.0);
    assert!(
        at_tip > 4.0 * next_to,
        "tip {at_tip} rad, elsewhere up to {next_to} rad"
    );
    // a few strings away from y = 0, the section is smooth
    let far = others(3.0 * top[tip].distance(top[tip + 1]));
    assert!(
        at_tip > 20.0 * far,
        "tip {at_tip} rad, away up to {far} rad"
    );
    assert!(
        far < 4.0 * step,
        "a corner of {far} rad away from the cusps"
    );
    // the dent opposite, at +x, turns sharply inwards: a turn centred on it
    let n = wall.points.len();
    let around = &wall.points[n - 1 - seg - seg / 2..n - seg / 2];
    let dent = seg / 2;
    assert!(around[dent].x > 0.0 && around[dent].y.abs() < 1e-6);
    let at_dent = turning(around)[dent - 1];
    assert!(at_dent < -1.0, "the dent turns by {at_dent} rad");

    // the bottom turn: b z = 0 at its start, a circle of the bottom's radius
    // that the heart hardly touches yet. Off the plate's own circle
    // (r + 1.05 z) a point moves by at most b z sqrt(|y| / radius), z the
    // plate's height, which is at most squeeze pitch in the first turn
    let radius = param(&recipe, "radius");
    let (b, pitch, flare, squeeze) = (
        param(&recipe, "b"),
        param(&recipe, "pitch"),
        param(&recipe, "flare"),
        param(&recipe, "squeeze"),
    );
    let helix = part_upto(&recipe, "wall", 0);
    let off = |i: usize| (r_of(wall.points[i]) - (radius + flare * helix.points[i].z)).abs();
    assert!((r_of(wall.points[0]) - radius).abs() < 1e-12);
    let bound = b * squeeze * pitch * ((radius + flare * pitch) / radius).sqrt();
    let bottom_off = (0..=seg).map(off).fold(0.0, f64::max);
    assert!(bottom_off <= bound + 1e-9, "{bottom_off} mm off the circle");
    let top_off = (n - 1 - seg..n).map(off).fold(0.0, f64::max);
    assert!(
        bottom_off < 0.01 * top_off,
        "off the circle by {bottom_off} mm at the bottom, {top_off} mm at the top"
    );
    // and convex all round: no dent yet
    for a in turning(&wall.points[..=seg]) {
        assert!(a > 0.0, "the first turn bends inwards by {a} rad");
    }
}

#[test]
fn heart_plate_without_b_has_no_cusp_and_with_more_b_a_sharper_one() {
    let tip_turn = |b: &str| {
        let recipe = load("heart-plate.yaml", &[("b", b)]);
        let wall = part(&recipe, "wall");
        let seg = segments(&recipe);
        let top = &wall.points[wall.points.len() - 1 - seg..];
        let tip = tip_index(top);
        turning(top)[tip - 1]
    };
    let step = TAU / 360.0;
    assert!((tip_turn("0") - step).abs() < 0.1 * step);
    let (a, b, c) = (tip_turn("0.4"), tip_turn("0.8"), tip_turn("1.2"));
    assert!(1.0 < a && a < b && b < c, "{a} {b} {c}");
}

#[test]
fn vase_wall_is_the_helix_deformed_by_its_trigonometric_functions() {
    let recipe = load("vase.yaml", &[]);
    let helix = part_upto(&recipe, "wall", 0);
    let wall = part(&recipe, "wall");
    let p = |n| param(&recipe, n);
    let (h, bulge, flute, lobes, wave, lift) = (
        p("height"),
        p("bulge"),
        p("flute"),
        p("lobes"),
        p("wave"),
        p("bottom_top"),
    );
    for (a, q) in helix.points.iter().zip(&wall.points) {
        let (r, t) = polar(*a);
        let want_r = r + bulge * libm::sin(PI * a.z / h) + flute * (a.z / h) * libm::cos(lobes * t);
        let want_z = a.z + wave * (a.z / h) * libm::sin(lobes * t) + lift;
        assert!((r_of(*q) - want_r).abs() < 1e-9 && (q.z - want_z).abs() < 1e-9);
    }
    // the belly: widest near mid-height, back to the radius at the rim
    let seg = segments(&recipe);
    let mean_r = |i: usize| {
        wall.points[i..i + seg]
            .iter()
            .map(|&q| r_of(q))
            .sum::<f64>()
            / seg as f64
    };
    let n = wall.points.len();
    assert!((mean_r(n / 2) - p("radius") - bulge).abs() < 0.1);
    assert!((mean_r(n - 1 - seg) - p("radius")).abs() < 0.2);
    // vertical pitch within pitch (1 ± wave/height)
    for i in (0..n - seg).step_by(97) {
        let dz = wall.points[i + seg].z - wall.points[i].z;
        assert!((0.15..=0.35).contains(&dz), "pitch {dz} at {i}");
    }
}

/// Angle around z of the heart's tip in each turn of `wall` from `from` on,
/// with the helix height (before deformation) of that turn: the point where
/// the section turns most sharply to the left (convex).
fn tip_angles(wall: &Toolpath, seg: usize, from: usize, lift: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut i = from;
    while i + seg < wall.points.len() {
        let turn = &wall.points[i..=i + seg];
        let turns = turning(turn);
        let (j, _) = turns
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
        let p = turn[j + 1];
        out.push((p.z - lift, libm::atan2(p.y, p.x).rem_euclid(TAU)));
        i += seg;
    }
    out
}

#[test]
fn twisted_heart_turns_with_height_by_the_twist() {
    for twist in ["90", "45", "0"] {
        let recipe = load("twisted-heart-vase.yaml", &[("twist", twist)]);
        let wall = part(&recipe, "wall");
        let seg = segments(&recipe);
        let step = TAU / seg as f64;
        let (h, k, lift) = (
            param(&recipe, "height"),
            param(&recipe, "k"),
            param(&recipe, "bottom_top"),
        );
        assert!((k - twist.parse::<f64>().unwrap().to_radians() / h).abs() < 1e-12);
        // from a quarter of the height up, where the heart is sharp
        let from = wall.points.len() / 4 / seg * seg;
        let tips = tip_angles(&wall, seg, from, lift);
        assert!(tips.len() > 250);
        let mut prev = f64::MIN;
        let mut unwrapped = Vec::new();
        for &(z, a) in &tips {
            // the tip sits at pi + k z, to a string's angle
            let want = PI + k * z;
            let d = (a - want + PI).rem_euclid(TAU) - PI;
            assert!(
                d.abs() < 1.5 * step,
                "twist {twist}: tip at {a} rad at z = {z}, expected {want}"
            );
            let a = want + d;
            // monotonic, to within the angle of one string
            assert!(
                a > prev - 1.01 * step,
                "twist {twist}: tip went back at z = {z}"
            );
            prev = prev.max(a);
            unwrapped.push((z, a));
        }
        let (z0, a0) = unwrapped[0];
        let (z1, a1) = *unwrapped.last().unwrap();
        let want = k * (z1 - z0);
        assert!(
            (a1 - a0 - want).abs() < 2.0 * step,
            "twist {twist}: turned by {} rad, expected {want}",
            a1 - a0
        );
    }
}

#[test]
fn twisted_heart_is_round_at_the_bottom_and_the_heart_of_fig_10c_turned() {
    let recipe = load("twisted-heart-vase.yaml", &[]);
    let helix = part_upto(&recipe, "wall", 0);
    let wall = part_upto(&recipe, "wall", 2);
    let (b, k, radius) = (
        param(&recipe, "b"),
        param(&recipe, "k"),
        param(&recipe, "radius"),
    );
    for (p, q) in helix.points.iter().zip(&wall.points) {
        // the circle bent by x + b z sqrt(|y| / R), then turned by k z
        let x = p.x + b * p.z * (p.y.abs() / radius).sqrt();
        let a = libm::atan2(p.y, x) + k * p.z;
        let rr = (x * x + p.y * p.y).sqrt();
        let want = DVec3::new(rr * libm::cos(a), rr * libm::sin(a), p.z);
        assert!((*q - want).length() < 1e-9, "{p} went to {q}, not {want}");
    }
    let seg = segments(&recipe);
    for p in &wall.points[..=seg] {
        assert!((r_of(*p) - radius).abs() < 0.1);
    }
    // every turn has a string end exactly at its tip, at angle pi + k z
    for i in (seg / 2..wall.points.len()).step_by(seg) {
        let p = wall.points[i];
        let want = (PI + k * p.z).rem_euclid(TAU);
        let got = theta_of(p);
        let d = (got - want + PI).rem_euclid(TAU) - PI;
        assert!(
            d.abs() < 1e-9,
            "tip of turn {} at {got}, not {want}",
            i / seg
        );
    }
}

#[test]
fn deformed_sphere_lies_on_the_ribbed_sphere() {
    let recipe = load("deformed-sphere.yaml", &[]);
    let tp = part(&recipe, "sphere");
    let (radius, lift, a, m) = (
        param(&recipe, "radius"),
        param(&recipe, "lift"),
        param(&recipe, "depth"),
        param(&recipe, "lobes"),
    );
    let c = radius + lift;
    let mut worst: f64 = 0.0;
    for p in &tp.points {
        let (r, theta) = polar(*p);
        let circle = (radius * radius - (p.z - c) * (p.z - c)).max(0.0).sqrt();
        let want = circle * (1.0 + a * libm::sin(m * theta));
        worst = worst.max((r - want).abs());
    }
    assert!(worst < 1e-6, "a point is {worst} mm off the surface");
    // whole, from pole to pole
    let zs = tp.points.iter().map(|p| p.z);
    let (lo, hi) = zs.fold((f64::MAX, f64::MIN), |(l, h), z| (l.min(z), h.max(z)));
    assert!((lo - lift).abs() < 1e-9 && (hi - lift - 2.0 * radius).abs() < 1e-9);
    // the equator has `lobes` ribs, swelling to radius (1 + depth)
    let seg = segments(&recipe);
    let mid = tp.points.len() / 2 / seg * seg;
    let eq: Vec<f64> = tp.points[mid..=mid + seg]
        .iter()
        .map(|&p| r_of(p))
        .collect();
    assert_eq!(maxima(&eq), m as usize);
    let max = eq.iter().cloned().fold(0.0, f64::max);
    assert!(
        (max - radius * (1.0 + a)).abs() < 0.05,
        "equator up to {max}"
    );
}

/// Diameter of the part's bounding box seen from above, and its top.
fn bbox(tp: &Toolpath) -> (f64, f64, f64) {
    let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for p in extruding_points(tp) {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let d = hi - lo;
    (d.x, d.y, hi.z)
}

#[test]
fn lamp_shades_are_100_mm_partial_spheres_open_at_the_top() {
    for name in ["lamp-shade.yaml", "lamp-shade-textured.yaml"] {
        let recipe = load(name, &[]);
        let tp = part(&recipe, "shade");
        let (dx, dy, top) = bbox(&tp);
        for d in [dx, dy] {
            assert!((90.0..=110.0).contains(&d), "{name}: {d} mm across");
        }
        let (radius, lift, opening) = (
            param(&recipe, "radius"),
            param(&recipe, "lift"),
            param(&recipe, "opening"),
        );
        // open: the top is below the whole sphere's, and the last turn is a
        // rim of about the opening's radius around the hole
        assert!(top < lift + 2.0 * radius - 5.0, "{name}: top at {top}");
        let seg = segments(&recipe);
        let rim: Vec<f64> = tp.points[tp.points.len() - 1 - seg..]
            .iter()
            .map(|&p| r_of(p))
            .collect();
        let mean = rim.iter().sum::<f64>() / rim.len() as f64;
        assert!((mean - opening).abs() < 0.5, "{name}: rim radius {mean}");
        // it stands on its south pole
        assert!(tp.points[0].truncate().length() < 1e-9);
        assert!((tp.points[0].z - lift).abs() < 1e-9);
    }
}

#[test]
fn lamp_shade_lies_on_the_swirled_ribbed_sphere() {
    let recipe = load("lamp-shade.yaml", &[]);
    let tp = part(&recipe, "shade");
    let p = |n| param(&recipe, n);
    let (radius, lift, ripple, lobes, swirl) =
        (p("radius"), p("lift"), p("ripple"), p("lobes"), p("swirl"));
    let c = radius + lift;
    let mut worst: f64 = 0.0;
    for q in &tp.points {
        let (r, theta) = polar(*q);
        let phi = libm::acos(((c - q.z) / radius).clamp(-1.0, 1.0));
        let want =
            radius * libm::sin(phi) * (1.0 + ripple * libm::sin(lobes * theta + swirl * phi));
        worst = worst.max((r - want).abs());
    }
    assert!(worst < 1e-6, "a point is {worst} mm off the surface");
}

#[test]
fn textured_lamp_shade_modulates_thickness_at_constant_flow() {
    let recipe = load("lamp-shade-textured.yaml", &[]);
    let k = index(&recipe, "shade");
    let steps = recipe.parts[k].steps.len();
    let plain = part_upto(&recipe, "shade", steps - 1);
    let tp = part(&recipe, "shade");
    // the shape is the plain partial sphere's
    assert_eq!(plain.points, tp.points);
    let radius = param(&recipe, "radius");
    let c0 = recipe.parts[k].cross_section;
    let v0 = recipe.parts[k].speed;
    let texture = param(&recipe, "texture");
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for (j, (s, t)) in plain.strings.iter().zip(&tp.strings).enumerate() {
        // each string keeps its flow: c v unchanged
        assert!(
            ((t.c * t.v) / (s.c * s.v) - 1.0).abs() < 1e-12,
            "string {j}"
        );
        let f = t.c / s.c;
        assert!(f >= 1.0 - texture - 1e-12 && f <= 1.0 + texture + 1e-12);
        lo = lo.min(f);
        hi = hi.max(f);
        // away from the pole the plain shade runs at c0, v0: there the flow
        // is the same on every string while the section varies
        if r_of(tp.midpoint(j)) > 0.4 * radius {
            assert!((t.c * t.v - c0 * v0).abs() < 1e-9, "string {j}");
        }
    }
    assert!(
        lo < 1.0 - 0.9 * texture && hi > 1.0 + 0.9 * texture,
        "{lo}..{hi}"
    );
    // and the textured shade is on the plain sphere
    let c = radius + param(&recipe, "lift");
    for q in &tp.points {
        let circle = (radius * radius - (q.z - c) * (q.z - c)).max(0.0).sqrt();
        assert!((r_of(*q) - circle).abs() < 1e-6);
    }
}

/// Points of extruding strings (both ends).
fn extruding_points(tp: &Toolpath) -> impl Iterator<Item = DVec3> + '_ {
    (0..tp.len())
        .filter(|&k| !tp.strings[k].travel)
        .flat_map(|k| [tp.points[k], tp.points[k + 1]])
}

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("recipes")
        .join(name)
}
