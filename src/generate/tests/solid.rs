//! The `solid` primitive: features → z-buffer of exact loops → perimeters and
//! ±45° infill → strings (feature-based modelling, paper 003). Through the
//! library (the exact loops, the strings made from them) and the binary
//! (the gallery recipes, the stats, bad input).
//!
//! Past the public face: `Primitive::Solid` and its layers, the z-buffer
//! (`ZBuffer`, `Body`, `Feature`, `Cache`, `reusing`), the regions of
//! `base::geom` (`region`, `offset`, `piece`) and the infill (`infill`,
//! `plan_join_inside`). Home: beside `generate::primitive::solid` (the
//! region, offset and piece tests beside `base::geom`); the tests that also
//! run the binary keep that half here.

use std::f64::consts::{FRAC_PI_4, PI};
use std::path::{Path, PathBuf};

use crate::app::prepare::plan;
use crate::base::toolpath::Toolpath;
use crate::generate::model::make_part;
use crate::generate::model::Recipe;
use crate::generate::primitive::solid::piece::Piece;
use crate::generate::primitive::solid::{Loop, Region, Solid};
use crate::generate::primitive::Primitive;
use glam::{DVec2, DVec3};

/// A recipe written into a test's own folder, which goes with it.
struct RecipeFile {
    _dir: crate::base::testing::Tmp,
    path: PathBuf,
}

impl AsRef<Path> for RecipeFile {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl std::ops::Deref for RecipeFile {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

/// Writes a one-part recipe whose primitive is `solid: {SOLID}` (YAML flow
/// text) into a fresh folder and returns its path.
fn recipe_file(tag: &str, solid: &str) -> RecipeFile {
    let dir = crate::base::testing::tmp(&format!("solid-{tag}"));
    let path = dir.join(format!("{tag}.yaml"));
    let text = format!(
        "p3dp: 1\nname: {tag}\nprinter: generic-220\nmaterial: pla\nparts:\n  - name: solid\n    speed: 40\n    primitive:\n      solid: {solid}\n"
    );
    std::fs::write(&path, text).unwrap();
    RecipeFile { _dir: dir, path }
}

fn load(path: &Path) -> Recipe {
    crate::recipe::load(path, &[], None).unwrap_or_else(|e| panic!("{e}"))
}

fn solid_of(recipe: &Recipe, k: usize) -> &Solid {
    match &recipe.parts[k].primitive {
        Primitive::Solid(s) => s,
        p => panic!("part {k} is not a solid: {p:?}"),
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Distance from `p` to a loop.
fn dist_loop(l: &Loop, p: DVec2) -> f64 {
    l.pieces
        .iter()
        .map(|q| q.distance(p))
        .fold(f64::INFINITY, f64::min)
}

/// Extruding strings at height `z`, as plan segments.
fn strings_at(t: &Toolpath, z: f64) -> Vec<(DVec2, DVec2)> {
    (0..t.len())
        .filter(|&k| !t.strings[k].travel)
        .map(|k| t.ends(k))
        .filter(|(a, b)| (a.z - z).abs() < 1e-9 && (b.z - z).abs() < 1e-9)
        .map(|(a, b)| (a.truncate(), b.truncate()))
        .collect()
}

/// The loops of every perimeter of a layer's islands, and of the innermost
/// perimeters only, and the infill regions.
struct LayerGeometry {
    perimeters: Vec<Loop>,
    innermost: Vec<Region>,
    infill_area: f64,
}

fn geometry(s: &Solid, index: u64) -> LayerGeometry {
    let layer = s.layers().find(|l| l.index == index).unwrap();
    let slab = layer.slab.expect("a printed layer");
    let mut g = LayerGeometry {
        perimeters: Vec::new(),
        innermost: Vec::new(),
        infill_area: 0.0,
    };
    for isl in &slab.islands {
        for r in &isl.perimeters {
            g.perimeters.extend(r.loops.iter().cloned());
        }
        if let Some(r) = isl.perimeters.last() {
            g.innermost.push(r.clone());
        }
        g.infill_area += isl.infill_region.area();
    }
    g
}

/// Splits a layer's strings into perimeter strings (both ends on a perimeter
/// loop, with that loop) and infill strings.
#[allow(clippy::type_complexity)]
fn classify<'a>(
    g: &'a LayerGeometry,
    strings: &[(DVec2, DVec2)],
) -> (Vec<(DVec2, DVec2, &'a Loop)>, Vec<(DVec2, DVec2)>) {
    let mut per = Vec::new();
    let mut inf = Vec::new();
    for &(a, b) in strings {
        match g
            .perimeters
            .iter()
            .find(|l| dist_loop(l, a) < 1e-9 && dist_loop(l, b) < 1e-9)
        {
            Some(l) => per.push((a, b, l)),
            None => inf.push((a, b)),
        }
    }
    (per, inf)
}

const BOX_WITH_HOLE: &str = "{layer_height: 0.2, perimeters: 2, chord_tolerance: 0.01, infill: {angle: 45, spacing: 0.8, alternate: true}, features: [{box: {center: [0, 0, 5], size: [40, 30, 10]}}, {cylinder: {center: [0, 0, 0], radius: 8, height: 10, op: subtract}}, {cylinder: {center: [15, 0, 10], radius: 5, height: 6, op: union}}]}";

#[test]
fn each_layer_of_a_box_with_a_hole_has_the_exact_area() {
    let path = recipe_file("box-hole", BOX_WITH_HOLE);
    let r = load(&path);
    let s = solid_of(&r, 0);
    let below = 40.0 * 30.0 - PI * 64.0;
    let boss = PI * 25.0;
    let mut n = 0;
    for layer in s.layers() {
        let region = &layer.slab.expect("every layer prints").region;
        let (want, loops) = if layer.z <= 10.0 + 1e-9 {
            (below, 2)
        } else {
            (boss, 1)
        };
        assert!(
            rel(region.area(), want) < 1e-6,
            "z {}: {}",
            layer.z,
            region.area()
        );
        assert!(
            rel(region.area(), want) < 1e-12,
            "arcs are exact until discretised"
        );
        assert_eq!(region.loops.len(), loops);
        n += 1;
    }
    assert_eq!(n, 80, "layers 0.2 … 16.0");
    // the same z-buffer in the stats JSON of a real build
    let dir = path.parent().unwrap();
    let out = crate::app::testing::p3dp(
        dir,
        &[
            "build",
            "box-hole.yaml",
            "-o",
            "box-hole.gcode",
            "--stats-json",
            "stats.json",
        ],
    );
    assert!(out.success(), "{}", out.stderr);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("stats.json")).unwrap()).unwrap();
    let layers = json["solids"][0]["layers"].as_array().unwrap();
    assert_eq!(json["solids"][0]["part"], "solid");
    assert_eq!(layers.len(), 80);
    assert!((layers[0]["z"].as_f64().unwrap() - 0.2).abs() < 1e-12);
    assert_eq!(layers[0]["loops"], 2);
    assert!(rel(layers[0]["area_mm2"].as_f64().unwrap(), below) < 1e-6);
    assert_eq!(layers[79]["loops"], 1);
    assert!(rel(layers[79]["area_mm2"].as_f64().unwrap(), boss) < 1e-6);
}

#[test]
fn boundary_strings_stay_within_the_chord_tolerance() {
    for tol in [0.01, 0.05] {
        let text =
            BOX_WITH_HOLE.replace("chord_tolerance: 0.01", &format!("chord_tolerance: {tol}"));
        let r = load(&recipe_file(&format!("chords-{tol}"), &text));
        let s = solid_of(&r, 0);
        let t = make_part(&r, 0).unwrap();
        for (index, z) in [(1, 0.2), (60, 12.0)] {
            let g = geometry(s, index);
            let (per, _) = classify(&g, &strings_at(&t, z));
            assert!(!per.is_empty());
            let mut worst: f64 = 0.0;
            for (a, b, l) in &per {
                for i in 0..=16 {
                    let p = a.lerp(*b, i as f64 / 16.0);
                    worst = worst.max(dist_loop(l, p));
                }
            }
            assert!(worst <= tol * (1.0 + 1e-9), "tol {tol}, z {z}: {worst}");
            // the budget is used, not wasted on needless strings
            assert!(worst > 0.5 * tol, "tol {tol}, z {z}: {worst}");
            // and every perimeter is there: the chords are as long as the
            // loops but for what they cut off (a fraction ≈ tol/3r of an arc)
            let printed: f64 = per.iter().map(|(a, b, _)| a.distance(*b)).sum();
            let exact: f64 = g.perimeters.iter().map(Loop::length).sum();
            assert!(
                printed <= exact && printed > exact * (1.0 - tol / 2.0),
                "{printed} vs {exact}"
            );
        }
    }
}

#[test]
fn infill_lies_inside_the_innermost_perimeter_fills_it_and_alternates() {
    let r = load(&recipe_file("infill", BOX_WITH_HOLE));
    let s = solid_of(&r, 0);
    let t = make_part(&r, 0).unwrap();
    let w = s.line_width;
    for (index, z) in [(1u64, 0.2), (2, 0.4), (30, 6.0), (61, 12.2), (62, 12.4)] {
        let g = geometry(s, index);
        let (_, inf) = classify(&g, &strings_at(&t, z));
        assert!(!inf.is_empty());
        let mut length = 0.0;
        for &(a, b) in &inf {
            for p in [a, b, a.lerp(b, 0.5)] {
                assert!(
                    g.innermost.iter().any(|r| r.contains(p)),
                    "z {z}: {p} outside the innermost perimeter"
                );
                // at least half a line inside that perimeter's centre line
                let d = g
                    .innermost
                    .iter()
                    .flat_map(|r| r.loops.iter())
                    .map(|l| dist_loop(l, p))
                    .fold(f64::INFINITY, f64::min);
                assert!(d >= 0.5 * w - 1e-9, "z {z}: {p} only {d} inside");
            }
            // +45° on odd layers, −45° on even ones
            let d = b - a;
            let angle = libm::atan2(d.y, d.x).rem_euclid(PI);
            let want = if index % 2 == 1 {
                FRAC_PI_4
            } else {
                3.0 * FRAC_PI_4
            };
            assert!((angle - want).abs() < 1e-9, "z {z}: line at {angle}");
            length += a.distance(b);
        }
        let filled = length * s.infill.spacing;
        assert!(
            rel(filled, g.infill_area) < 0.03,
            "z {z}: length × spacing {filled} vs area {}",
            g.infill_area
        );
    }
}

/// The infill strings of layer `index` of a one-part solid recipe.
fn infill_of(r: &Recipe, index: u64) -> Vec<(DVec2, DVec2)> {
    let s = solid_of(r, 0);
    let t = make_part(r, 0).unwrap();
    let g = geometry(s, index);
    classify(&g, &strings_at(&t, index as f64 * s.layer_height)).1
}

#[test]
fn a_line_exactly_through_corners_prints_whole() {
    // a 10 × 10 square, one perimeter 0.5 wide: the infill region is the
    // square ±4.5, whose diagonals are scanline 0 of +45° and of −45°
    let r = load(&recipe_file(
        "corners",
        "{layer_height: 0.2, perimeters: 1, line_width: 0.5, infill: {spacing: 0.5}, features: [{box: {center: [0, 0, 0.2], size: [10, 10, 0.4]}}]}",
    ));
    let b = 4.5;
    for (index, diagonal) in [(1, [(-b, -b), (b, b)]), (2, [(-b, b), (b, -b)])] {
        let inf = infill_of(&r, index);
        let [p, q] = diagonal.map(|(x, y)| DVec2::new(x, y));
        // the diagonal is one string from corner to corner, exactly: no gap
        // at either corner, nothing counted twice
        let on: Vec<_> = inf
            .iter()
            .filter(|(a, c)| (*a == p && *c == q) || (*a == q && *c == p))
            .collect();
        assert_eq!(on.len(), 1, "layer {index}: {inf:?}");
        // scanlines k·0.5 with |k·0.5| < 4.5·√2 each give one string, none stray
        let half_diag = b * 2f64.sqrt();
        let lines = (-20..=20)
            .filter(|&k| {
                let s = f64::from(k) * 0.5;
                2.0 * (half_diag - s.abs()) >= 0.25
            })
            .count();
        assert_eq!(inf.len(), lines, "layer {index}");
        let total: f64 = inf.iter().map(|(a, c)| a.distance(*c)).sum();
        assert!(rel(total * 0.5, 81.0) < 0.03);
    }
    // lines along the edges (horizontal, 0.5 apart, the edges at y = ±4.5):
    // each scanline is a whole-width string, the one on the top edge counts as
    // inside (a point on a scanline lies above it), the bottom one as outside
    let r = load(&recipe_file(
        "edges",
        "{layer_height: 0.2, perimeters: 1, line_width: 0.5, infill: {angle: 0, spacing: 0.5}, features: [{box: {center: [0, 0, 0.2], size: [10, 10, 0.4]}}]}",
    ));
    let inf = infill_of(&r, 1);
    assert_eq!(inf.len(), 18);
    for (a, c) in &inf {
        assert_eq!(a.y, c.y);
        assert_eq!((a.x - c.x).abs(), 9.0);
        assert!(a.y > -4.5 && a.y <= 4.5);
    }
}

#[test]
fn a_line_tangent_to_a_circle_prints_no_stray_string() {
    // radius 4.5, one perimeter 0.5 wide: the infill region is the disc of
    // radius 4; vertical lines x = k·0.5 (exact), so k = ±8 touch it
    let r = load(&recipe_file(
        "tangent",
        "{layer_height: 0.2, perimeters: 1, line_width: 0.5, infill: {angle: 90, spacing: 0.5}, features: [{cylinder: {center: [0, 0, 0], radius: 4.5, height: 0.4}}]}",
    ));
    for index in [1, 2] {
        let inf = infill_of(&r, index);
        assert_eq!(inf.len(), 15, "k = -7 … 7, none at the tangents");
        for (a, b) in &inf {
            assert_eq!(a.x, b.x);
            let k = a.x / 0.5;
            assert!(k.fract() == 0.0 && k.abs() <= 7.0);
            let chord = 2.0 * (16.0 - a.x * a.x).sqrt();
            assert!((a.distance(*b) - chord).abs() < 1e-12, "no gap at the ends");
        }
    }
    // at 45° the tangent lines are k·0.5 = ±4 up to rounding: the line then
    // misses the circle or cuts a chord too short to print; either way nothing
    let r = load(&recipe_file(
        "tangent45",
        "{layer_height: 0.2, perimeters: 1, line_width: 0.5, infill: {angle: 45, spacing: 0.5}, features: [{cylinder: {center: [0, 0, 0], radius: 4.5, height: 0.4}}]}",
    ));
    for index in [1, 2] {
        let inf = infill_of(&r, index);
        assert_eq!(inf.len(), 15);
        for (a, b) in &inf {
            assert!(a.distance(*b) >= 0.25);
            // every end on the circle of radius 4
            assert!((a.length() - 4.0).abs() < 1e-12 && (b.length() - 4.0).abs() < 1e-12);
        }
    }
}

#[test]
fn the_bracket_is_its_features_exactly() {
    let r = load(&crate::base::testing::recipe("bracket.yaml"));
    let p = |name: &str| r.params[name];
    let s = solid_of(&r, 0);
    let slot = 2.0 * p("slot_radius") * p("slot_length") + PI * p("slot_radius").powi(2);
    let plate =
        p("length") * p("width") - 4.0 * PI * p("hole").powi(2) - PI * p("bore").powi(2) - slot;
    let boss = PI * (p("boss").powi(2) - p("bore").powi(2));
    let mut seen = [0, 0];
    for layer in s.layers() {
        let region = &layer.slab.unwrap().region;
        if layer.z <= p("thickness") + 1e-9 {
            // outer loop, four holes, the bore, the slot: its circles meet
            // the box exactly at its corners, tangent to its long edges
            assert_eq!(region.loops.len(), 7);
            assert!(rel(region.area(), plate) < 1e-9, "z {}", layer.z);
            seen[0] += 1;
        } else {
            assert_eq!(region.loops.len(), 2);
            assert!(rel(region.area(), boss) < 1e-9, "z {}", layer.z);
            seen[1] += 1;
        }
    }
    assert_eq!(seen, [20, 60]);
    // the slot is one hole of two lines and two half circles
    let slab = s.layers().next().unwrap().slab.unwrap();
    let slot_loop = slab
        .region
        .loops
        .iter()
        .find(|l| rel(-l.area(), slot) < 1e-9)
        .expect("the slot");
    let kinds: Vec<bool> = slot_loop
        .pieces
        .iter()
        .map(|q| matches!(q, Piece::Line(..)))
        .collect();
    assert_eq!(kinds.len(), 4, "{slot_loop:?}");
    assert_eq!(kinds.iter().filter(|l| **l).count(), 2);
}

#[test]
fn string_counts_are_exact_before_building() {
    for name in ["bracket.yaml", "cup-solid-base.yaml"] {
        let r = load(&crate::base::testing::recipe(name));
        for k in 0..r.parts.len() {
            let t = make_part(&r, k).unwrap();
            assert_eq!(
                t.len() as u64,
                r.parts[k].primitive.string_count(),
                "{name} part {k}"
            );
        }
    }
    // a limit refuses a solid before it is made
    let path = recipe_file("limit", BOX_WITH_HOLE);
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("material: pla\n", "material: pla\nmax_strings: 1000\n");
    std::fs::write(&path, text).unwrap();
    let e = crate::recipe::load(&path, &[], None).unwrap_err();
    assert_eq!(e.place.as_deref(), Some("parts[0].primitive"));
    assert!(e.message.contains("more than the limit of 1000"), "{e}");
}

#[test]
fn the_solid_recipes_build_and_print() {
    let dir = crate::base::testing::tmp("solid-recipes");
    for name in ["bracket", "cup-solid-base"] {
        let recipe = crate::base::testing::recipe(&format!("{name}.yaml"));
        let recipe = recipe.to_str().unwrap();
        let checked = plan(Path::new(recipe), &Default::default()).unwrap();
        let text = crate::base::finding::summary(&checked.findings);
        assert!(text.contains("0 warnings, 0 errors"), "{text}");
        let json = format!("{name}.json");
        let gcode = format!("{name}.gcode");
        let out = crate::app::testing::p3dp(
            &dir,
            &["build", recipe, "-o", &gcode, "--stats-json", &json],
        );
        assert!(out.success(), "{}", out.stderr);
        let g = crate::base::testing::parse(
            &std::fs::read_to_string(dir.join(format!("{name}.gcode"))).unwrap(),
        );
        assert!(g.moves.iter().filter(|m| m.g == 1 && m.de > 0.0).count() > 1000);
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(&json)).unwrap()).unwrap();
        assert_eq!(stats["warnings"].as_array().unwrap().len(), 0);
        assert!(!stats["solids"][0]["layers"].as_array().unwrap().is_empty());
    }
    // the cup's wall starts on the base's top layer, over its outer perimeter
    let r = load(&crate::base::testing::recipe("cup-solid-base.yaml"));
    let s = solid_of(&r, 0);
    let top = s.layers().last().unwrap();
    let outer = &top.slab.unwrap().islands[0].perimeters[0];
    let wall = make_part(&r, 1).unwrap();
    let start = wall.points[0];
    assert!((start.z - top.z).abs() < 1e-12);
    assert!(dist_loop(&outer.loops[0], start.truncate()) < 1e-9);
    assert_eq!(
        start,
        DVec3::new(r.params["wall_radius"], 0.0, r.params["base"])
    );
    // the base is printed bottom up from the bed
    let base = make_part(&r, 0).unwrap();
    assert!((base.points[0].z - r.params["layer"]).abs() < 1e-12);
    let plan = plan(
        &crate::base::testing::recipe("cup-solid-base.yaml"),
        &Default::default(),
    )
    .unwrap();
    assert!(plan.failing(true).is_empty());
}

#[test]
fn holes_and_islands_print_one_after_another() {
    // two separate blocks, each with a hole: two islands per layer; each is
    // finished (perimeters, then infill) before the head travels to the other
    let r = load(&recipe_file(
        "islands",
        "{layer_height: 0.2, perimeters: 2, features: [{box: {center: [-15, 0, 0.3], size: [20, 20, 0.6]}}, {box: {center: [15, 0, 0.3], size: [20, 20, 0.6]}}, {cylinder: {center: [-15, 0, -1], radius: 4, height: 3, op: subtract}}, {cylinder: {center: [15, 0, -1], radius: 4, height: 3, op: subtract}}]}",
    ));
    let s = solid_of(&r, 0);
    let t = make_part(&r, 0).unwrap();
    for layer in s.layers() {
        let slab = layer.slab.unwrap();
        assert_eq!(slab.islands.len(), 2);
        // which island each extruding string of this layer belongs to, in order
        let seq: Vec<bool> = strings_at(&t, layer.z)
            .iter()
            .map(|(a, _)| a.x > 0.0)
            .collect();
        let switches = seq.windows(2).filter(|w| w[0] != w[1]).count();
        assert_eq!(switches, 1, "z {}: islands interleaved", layer.z);
        // no string is printed inside a hole
        for (a, b) in strings_at(&t, layer.z) {
            for c in [-15.0, 15.0] {
                let m = a.lerp(b, 0.5);
                assert!(m.distance(DVec2::new(c, 0.0)) > 4.0, "{m} in a hole");
            }
        }
    }
}

/// A small deterministic generator (no dependency, same numbers everywhere).
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A multiple of `step` in [lo, hi]: a coarse grid, so that edges
    /// coincide, corners meet and circles touch edges and each other.
    fn grid(&mut self, lo: f64, hi: f64, step: f64) -> f64 {
        let n = ((hi - lo) / step) as u64;
        lo + step * ((self.unit() * (n + 1) as f64) as u64).min(n) as f64
    }
}

#[test]
fn random_features_on_a_grid_agree_with_point_tests() {
    use crate::generate::primitive::solid::infill::{direction, spans};
    use crate::generate::primitive::solid::offset::offset;
    use crate::generate::primitive::solid::region::{boolean, evaluate, Op, Shape};

    fn holds(s: &Shape, p: DVec2) -> bool {
        match *s {
            Shape::Rect { min, max } => p.cmpge(min).all() && p.cmple(max).all(),
            Shape::Disc { c, r } => p.distance(c) <= r,
        }
    }
    fn near(r: &Region, p: DVec2, tol: f64) -> bool {
        r.loops
            .iter()
            .flat_map(|l| l.pieces.iter())
            .any(|q| q.distance(p) < tol)
    }

    let mut rng = Lcg(987654321);
    for case in 0..800 {
        let n = 2 + (rng.unit() * 8.0) as usize;
        let shapes: Vec<(Option<Shape>, Op)> = (0..n)
            .map(|k| {
                let s = if rng.unit() < 0.5 {
                    let min = DVec2::new(rng.grid(-8.0, 6.0, 0.5), rng.grid(-8.0, 6.0, 0.5));
                    let size = DVec2::new(rng.grid(0.5, 8.0, 0.5), rng.grid(0.5, 8.0, 0.5));
                    Shape::Rect {
                        min,
                        max: min + size,
                    }
                } else {
                    Shape::Disc {
                        c: DVec2::new(rng.grid(-6.0, 6.0, 0.5), rng.grid(-6.0, 6.0, 0.5)),
                        r: rng.grid(0.25, 5.0, 0.25),
                    }
                };
                let op = match (k, (rng.unit() * 3.0) as u32) {
                    (0, _) | (_, 0) => Op::Union,
                    (_, 1) => Op::Subtract,
                    _ => Op::Intersect,
                };
                (Some(s), op)
            })
            .collect();
        let ops: Vec<Op> = shapes.iter().map(|s| s.1).collect();
        let r = boolean(&shapes);
        for l in &r.loops {
            for k in 0..l.pieces.len() {
                assert_eq!(
                    l.pieces[k].end(),
                    l.pieces[(k + 1) % l.pieces.len()].start()
                );
            }
        }
        let o = offset(&r, 0.45);
        let bounds: Vec<Piece> = r
            .loops
            .iter()
            .flat_map(|l| l.pieces.iter().copied())
            .collect();
        let mut count = 0;
        let cell = 28.0 / 70.0;
        for i in 0..70 {
            for j in 0..70 {
                // off the grid the features are snapped to
                let p = DVec2::new(
                    -14.0 + (i as f64 + 0.5) * cell + 1e-7,
                    -14.0 + (j as f64 + 0.5) * cell + 2e-7,
                );
                let want = evaluate(&ops, |k| holds(&shapes[k].0.unwrap(), p));
                count += want as u32;
                assert!(
                    r.contains(p) == want || near(&r, p, 1e-6),
                    "case {case}: {p} {shapes:?}"
                );
                let want = want && bounds.iter().all(|q| q.distance(p) >= 0.45);
                assert!(
                    o.contains(p) == want || near(&o, p, 1e-6),
                    "case {case}: offset at {p} {shapes:?}"
                );
            }
        }
        // the exact area against the count of cells (its error is about
        // half a cell along the boundary)
        let per: f64 = r.loops.iter().map(Loop::length).sum();
        assert!(
            (r.area() - count as f64 * cell * cell).abs() <= 0.5 * per * cell + 1e-9,
            "case {case}: {} {shapes:?}",
            r.area()
        );
        // every infill span inside the offset region, its ends on its boundary
        for deg in [45.0, -45.0, 30.0] {
            for (a, b) in spans(&o, direction(deg), 0.5, 1e-3) {
                assert!(near(&o, a, 1e-7) && near(&o, b, 1e-7), "case {case}");
                for i in 1..10 {
                    let p = a.lerp(b, i as f64 / 10.0);
                    assert!(o.contains(p) || near(&o, p, 1e-6), "case {case}: {p}");
                }
            }
        }
    }
}

#[test]
fn solid_infill_fills_each_layer_with_its_area_times_height() {
    // the issue's plate: 40 × 30 × 2 mm with an 8 mm hole, line width 0.45;
    // for infill spacing ≤ line width the filament of each layer is its area
    // × layer height within 3 % (lines closer than their width are squeezed
    // to their spacing)
    for spacing in [0.45, 0.4, 0.3] {
        let path = recipe_file(
            &format!("plate-{}", (spacing * 100.0) as u32),
            &format!("{{layer_height: 0.2, perimeters: 2, line_width: 0.45, infill: {{angle: 45, spacing: {spacing}}}, features: [{{box: {{center: [0, 0, 1], size: [40, 30, 2]}}}}, {{cylinder: {{center: [0, 0, 0], radius: 4, height: 2, op: subtract}}}}]}}"),
        );
        let r = load(&path);
        let s = solid_of(&r, 0);
        let t = make_part(&r, 0).unwrap();
        for layer in s.layers() {
            let Some(slab) = layer.slab else { continue };
            let area = slab.region.area();
            let volume: f64 = (0..t.len())
                .filter(|&k| !t.strings[k].travel)
                .filter(|&k| {
                    let (a, b) = t.ends(k);
                    (a.z - layer.z).abs() < 1e-9 && (b.z - layer.z).abs() < 1e-9
                })
                .map(|k| t.strings[k].c * t.length(k))
                .sum();
            let want = area * s.layer_height;
            assert!(
                rel(volume, want) < 0.03,
                "spacing {spacing}, z {}: {volume} mm³ vs {want} mm³",
                layer.z
            );
        }
    }
}

/// Layer settings of the z-buffer tests.
fn zb_settings() -> crate::generate::primitive::solid::Settings {
    use crate::generate::primitive::solid::{Infill, Pattern, Settings};
    Settings {
        layer_height: 0.5,
        perimeters: 1,
        line_width: 0.45,
        chord_tolerance: 0.05,
        infill: Infill {
            angle: 45.0,
            spacing: 1.5,
            alternate: true,
            pattern: Pattern::Lines,
            connect: false,
        },
    }
}

#[test]
fn the_incremental_z_buffer_equals_a_full_rebuild_and_touches_only_its_range() {
    use crate::generate::primitive::solid::region::Op;
    use crate::generate::primitive::solid::{Body, Feature, ZBuffer};
    let st = zb_settings();
    let h = st.layer_height;
    for seed in 1..=6u64 {
        let mut g = Lcg(seed);
        // a pool of features on a coarse grid (shared edges, equal z ends)
        let pool: Vec<Feature> = (0..9)
            .map(|k| {
                let z0 = g.grid(-1.0, 6.0, 0.5);
                let dz = g.grid(0.5, 5.0, 0.5);
                let op = match (k, g.unit()) {
                    (0, _) => Op::Union,
                    (_, u) if u < 0.55 => Op::Union,
                    (_, u) if u < 0.85 => Op::Subtract,
                    _ => Op::Intersect,
                };
                let body = if g.unit() < 0.5 {
                    Body::Box {
                        center: DVec3::new(
                            g.grid(-6.0, 6.0, 1.0),
                            g.grid(-6.0, 6.0, 1.0),
                            z0 + dz / 2.0,
                        ),
                        size: DVec3::new(g.grid(2.0, 12.0, 1.0), g.grid(2.0, 12.0, 1.0), dz),
                    }
                } else {
                    Body::Cylinder {
                        center: DVec3::new(g.grid(-6.0, 6.0, 1.0), g.grid(-6.0, 6.0, 1.0), z0),
                        radius: g.grid(1.0, 6.0, 1.0),
                        height: dz,
                    }
                };
                Feature { body, op }
            })
            .collect();
        // in a random order, some removed between the additions
        let mut order: Vec<usize> = (0..pool.len()).collect();
        for i in (1..order.len()).rev() {
            let j = (g.unit() * (i + 1) as f64) as usize;
            order.swap(i, j.min(i));
        }
        let mut zb = ZBuffer::new(st);
        let mut held: Vec<(u64, Feature)> = Vec::new();
        let (mut touched, mut rebuilt) = (0u64, 0u64);
        let in_range = |f: &Feature, j: u64| {
            let (z0, z1) = f.z_range();
            let z = (j as f64 - 0.5) * h;
            z0 <= z && z < z1
        };
        let compare = |zb: &ZBuffer, held: &[(u64, Feature)], what: &str| -> u64 {
            let feats: Vec<Feature> = held.iter().map(|(_, f)| *f).collect();
            assert_eq!(zb.features(), &feats[..], "seed {seed}, {what}");
            let fresh = ZBuffer::build(st, feats).unwrap();
            assert_eq!(zb.layer_count(), fresh.layer_count(), "seed {seed}, {what}");
            for (j, (a, b)) in zb.layer_slabs().zip(fresh.layer_slabs()).enumerate() {
                assert_eq!(
                    a.map(|s| &**s),
                    b.map(|s| &**s),
                    "seed {seed}, {what}: layer {}",
                    j + 1
                );
            }
            fresh.layer_count()
        };
        for &k in &order {
            let f = pool[k];
            let up = zb.add_feature(f).unwrap();
            held.push((up.added[0], f));
            let n = compare(&zb, &held, &format!("add {k}"));
            touched += up.recomputed();
            rebuilt += n;
            if f.op != Op::Intersect {
                for &j in &up.layers {
                    assert!(in_range(&f, j), "seed {seed}: add {k} recomputed layer {j}");
                }
            }
            // every layer the feature reaches and the buffer has is recomputed
            for j in 1..=zb.layer_count() {
                if in_range(&f, j) {
                    assert!(up.layers.contains(&j), "seed {seed}: add {k} skipped {j}");
                }
            }
            assert!(up.sections <= up.recomputed());
            if g.unit() < 0.3 && held.len() > 1 {
                let i = (g.unit() * held.len() as f64) as usize % held.len();
                let (id, gone) = held.remove(i);
                match zb.remove_feature(id) {
                    Ok(up) => {
                        compare(&zb, &held, &format!("remove {id}"));
                        if gone.op != Op::Intersect {
                            for &j in &up.layers {
                                assert!(
                                    in_range(&gone, j),
                                    "seed {seed}: remove {id} recomputed layer {j}"
                                );
                            }
                        }
                        touched += up.recomputed();
                    }
                    Err(e) => panic!("seed {seed}: {e}"),
                }
            }
        }
        // fewer layers computed than by rebuilding after every addition
        assert!(touched < rebuilt, "seed {seed}: {touched} vs {rebuilt}");
    }
    // an unknown id is an input error naming the features
    let mut zb = ZBuffer::new(st);
    let e = zb.remove_feature(7).unwrap_err();
    assert_eq!(e.place.as_deref(), Some("solid.features"));
}

#[test]
fn grid_infill_lays_both_directions_in_every_layer_inside_the_perimeters() {
    // the paper's ±45° grid: per layer, each direction alone has length ×
    // spacing ≈ the infill area (within 3 %), both together twice that; the
    // filament of a layer is still its area × height at the solid spacing
    // (2 × line width), as each line stands for half a spacing
    let grid = BOX_WITH_HOLE.replace(
        "infill: {angle: 45, spacing: 0.8, alternate: true}",
        "infill: {pattern: grid}",
    );
    let r = load(&recipe_file("grid", &grid));
    let s = solid_of(&r, 0);
    assert!(
        (s.infill.spacing - 0.9).abs() < 1e-12,
        "default: 2 × line_width"
    );
    let t = make_part(&r, 0).unwrap();
    let w = s.line_width;
    for layer in s.layers() {
        let g = geometry(s, layer.index);
        let (_, inf) = classify(&g, &strings_at(&t, layer.z));
        let mut length = [0.0; 2];
        for &(a, b) in &inf {
            for p in [a, b, a.lerp(b, 0.5)] {
                assert!(
                    g.innermost.iter().any(|r| r.contains(p)),
                    "z {}: {p}",
                    layer.z
                );
                let d = g
                    .innermost
                    .iter()
                    .flat_map(|r| r.loops.iter())
                    .map(|l| dist_loop(l, p))
                    .fold(f64::INFINITY, f64::min);
                assert!(d >= 0.5 * w - 1e-9, "z {}: {p} only {d} inside", layer.z);
            }
            let d = b - a;
            let angle = libm::atan2(d.y, d.x).rem_euclid(PI);
            let fam = if (angle - FRAC_PI_4).abs() < 1e-9 {
                0
            } else {
                assert!((angle - 3.0 * FRAC_PI_4).abs() < 1e-9, "line at {angle}");
                1
            };
            length[fam] += a.distance(b);
        }
        for (fam, l) in length.iter().enumerate() {
            let filled = l * s.infill.spacing;
            assert!(
                rel(filled, g.infill_area) < 0.03,
                "z {}, direction {fam}: {filled} vs {}",
                layer.z,
                g.infill_area
            );
        }
        // area × height of filament in the layer
        let volume: f64 = (0..t.len())
            .filter(|&k| !t.strings[k].travel)
            .filter(|&k| {
                let (a, b) = t.ends(k);
                (a.z - layer.z).abs() < 1e-9 && (b.z - layer.z).abs() < 1e-9
            })
            .map(|k| t.strings[k].c * t.length(k))
            .sum();
        let want = layer.slab.unwrap().region.area() * s.layer_height;
        assert!(
            rel(volume, want) < 0.03,
            "z {}: {volume} vs {want}",
            layer.z
        );
    }
}

#[test]
fn connected_infill_travels_less_and_its_joins_stay_inside() {
    use crate::generate::primitive::solid::plan::join_inside;
    for pattern in ["lines", "grid"] {
        let base = BOX_WITH_HOLE.replace(
            "infill: {angle: 45, spacing: 0.8, alternate: true}",
            &format!("infill: {{pattern: {pattern}, spacing: 0.9}}"),
        );
        let joined = base.replace("spacing: 0.9}", "spacing: 0.9, connect: true}");
        let (r0, r1) = (
            load(&recipe_file(&format!("apart-{pattern}"), &base)),
            load(&recipe_file(&format!("joined-{pattern}"), &joined)),
        );
        let (t0, t1) = (make_part(&r0, 0).unwrap(), make_part(&r1, 0).unwrap());
        let s = solid_of(&r1, 0);
        assert_eq!(t1.len() as u64, s.string_count());
        let travels = |t: &Toolpath| (0..t.len()).filter(|&k| t.strings[k].travel).count();
        let (n0, n1) = (travels(&t0), travels(&t1));
        assert!(n1 * 2 < n0, "{pattern}: {n1} travels joined vs {n0} apart");
        // the same lines are drawn; the joins are the other drawn strings
        let mut joins = 0;
        for layer in s.layers() {
            let g = geometry(s, layer.index);
            let slab = layer.slab.unwrap();
            let (_, inf) = classify(&g, &strings_at(&t1, layer.z));
            for &(a, b) in &inf {
                let d = b - a;
                let angle = libm::atan2(d.y, d.x).rem_euclid(PI);
                if (angle - FRAC_PI_4).abs() < 1e-9 || (angle - 3.0 * FRAC_PI_4).abs() < 1e-9 {
                    continue;
                }
                joins += 1;
                assert!(
                    a.distance(b) <= 3.0 * 0.9 + 1e-9,
                    "a join of {} from {a} to {b} at z {}",
                    a.distance(b),
                    layer.z
                );
                assert!(
                    slab.islands
                        .iter()
                        .any(|isl| join_inside(&isl.infill_region, a, b)),
                    "z {}: join {a} – {b} leaves the infill region",
                    layer.z
                );
                // and sampled: every point inside or on the region
                for i in 1..16 {
                    let p = a.lerp(b, i as f64 / 16.0);
                    assert!(
                        slab.islands.iter().any(|isl| isl.infill_region.contains(p)
                            || isl
                                .infill_region
                                .loops
                                .iter()
                                .any(|l| dist_loop(l, p) < 1e-6)),
                        "z {}: {p} of a join outside",
                        layer.z
                    );
                }
            }
            // the lines themselves: as long as without joining
            let (_, apart) = classify(&g, &strings_at(&t0, layer.z));
            let lines = |v: &[(DVec2, DVec2)]| -> f64 {
                v.iter()
                    .filter(|(a, b)| {
                        let d = *b - *a;
                        let angle = libm::atan2(d.y, d.x).rem_euclid(PI);
                        (angle - FRAC_PI_4).abs() < 1e-9 || (angle - 3.0 * FRAC_PI_4).abs() < 1e-9
                    })
                    .map(|(a, b)| a.distance(*b))
                    .sum()
            };
            assert!(rel(lines(&inf), lines(&apart)) < 1e-9, "z {}", layer.z);
        }
        assert!(joins > 100, "{pattern}: {joins} joins");
    }
}

#[test]
fn the_zbuffer_json_is_the_exact_loops_and_the_svg_draws_a_layer() {
    use crate::generate::primitive::solid::piece::Arc;
    let path = recipe_file("zbuf", BOX_WITH_HOLE);
    let dir = path.parent().unwrap();
    let out = crate::app::testing::p3dp(
        dir,
        &[
            "build",
            "zbuf.yaml",
            "-o",
            "z.gcode",
            "--stats-json",
            "s.json",
            "--zbuffer",
            "z.json",
            "--zbuffer-svg",
            "l.svg",
            "--zbuffer-layer",
            "60",
        ],
    );
    assert!(out.success(), "{}", out.stderr);
    let read = |f: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(f)).unwrap()).unwrap()
    };
    let (z, stats) = (read("z.json"), read("s.json"));
    let solid = &z["solids"][0];
    assert_eq!(solid["part"], "solid");
    let sections = solid["sections"].as_array().unwrap();
    let layers = solid["layers"].as_array().unwrap();
    let stat_layers = stats["solids"][0]["layers"].as_array().unwrap();
    assert_eq!(layers.len(), stat_layers.len());
    let r = load(&path);
    let s = solid_of(&r, 0);
    let pt = |v: &serde_json::Value| DVec2::new(v[0].as_f64().unwrap(), v[1].as_f64().unwrap());
    let (mut arcs, mut lines) = (0, 0);
    for ((layer, stat), mine) in layers.iter().zip(stat_layers).zip(s.layers()) {
        let k = layer["section"].as_u64().unwrap() as usize;
        let loops = sections[k]["loops"].as_array().unwrap();
        assert_eq!(loops.len() as u64, stat["loops"].as_u64().unwrap());
        assert_eq!(layer["z"].as_f64(), stat["z"].as_f64());
        let region = &mine.slab.unwrap().region;
        // the area from the curves alone: ½ Σ a × b for a line, ½ (c × (p1 −
        // p0) + r²·sweep) for an arc
        let mut area = 0.0;
        for (l, exact) in loops.iter().zip(&region.loops) {
            let mut loop_area = 0.0;
            let pieces = l["pieces"].as_array().unwrap();
            for (i, p) in pieces.iter().enumerate() {
                let (a, b) = (pt(&p["from"]), pt(&p["to"]));
                // each piece starts where the one before ends
                let prev = &pieces[(i + pieces.len() - 1) % pieces.len()];
                assert_eq!(pt(&prev["to"]), a);
                match p["kind"].as_str().unwrap() {
                    "line" => {
                        lines += 1;
                        assert_eq!(exact.pieces[i], Piece::Line(a, b));
                        loop_area += 0.5 * (a.x * b.y - a.y * b.x);
                    }
                    "arc" => {
                        arcs += 1;
                        let c = pt(&p["center"]);
                        let rad = p["radius"].as_f64().unwrap();
                        let sweep = p["sweep_rad"].as_f64().unwrap();
                        let arc = Arc {
                            c,
                            r: rad,
                            a0: p["start_rad"].as_f64().unwrap(),
                            sweep,
                            p0: a,
                            p1: b,
                        };
                        // read back bit for bit, and consistent with its ends
                        assert_eq!(exact.pieces[i], Piece::Arc(arc));
                        assert!(arc.at(0.0).distance(a) < 1e-9);
                        assert!(arc.at(sweep.abs()).distance(b) < 1e-9);
                        let d = b - a;
                        loop_area += 0.5 * (c.x * d.y - c.y * d.x + rad * rad * sweep);
                    }
                    other => panic!("a piece of kind {other}"),
                }
            }
            let want = if loop_area > 0.0 { "ccw" } else { "cw" };
            assert_eq!(l["orientation"], want);
            assert!((l["area_mm2"].as_f64().unwrap() - loop_area).abs() < 1e-9);
            area += loop_area;
        }
        let stat_area = stat["area_mm2"].as_f64().unwrap();
        assert!(
            rel(area, stat_area) < 1e-12,
            "z {}: {area} vs {stat_area}",
            stat["z"]
        );
    }
    assert!(arcs > 0 && lines > 0);
    // layer 60 (z 12): the boss alone, a circle of radius 5 drawn as two arcs
    let svg = std::fs::read_to_string(dir.join("l.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("layer 60 at z 12"),
        "{svg}"
    );
    assert!(svg.contains("A5 5 0 0 1"), "{svg}");
    // a layer above the part: exit 2 naming the option, and nothing written
    for f in ["z.gcode", "z.json", "l.svg"] {
        std::fs::remove_file(dir.join(f)).unwrap();
    }
    let out = crate::app::testing::p3dp(
        dir,
        &[
            "build",
            "zbuf.yaml",
            "-o",
            "z.gcode",
            "--zbuffer",
            "z.json",
            "--zbuffer-svg",
            "l.svg",
            "--zbuffer-layer",
            "81",
        ],
    );
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("--zbuffer-layer"));
    for f in ["z.gcode", "z.json", "l.svg"] {
        assert!(!dir.join(f).exists(), "{f} written by a failed build");
    }
    // never over an input
    let out = crate::app::testing::p3dp(
        dir,
        &[
            "build",
            "zbuf.yaml",
            "-o",
            "z.gcode",
            "--zbuffer",
            "zbuf.yaml",
        ],
    );
    assert_eq!(out.code, 2);
    assert!(std::fs::read_to_string(&path).unwrap().contains("solid:"));
}

#[test]
fn the_zbuffer_svg_writes_numbers_to_the_micrometre() {
    // a box whose edges and centre are no binary fractions, a boss of
    // radius 2.35, and layer 3 printed at 3 × 0.2 = 0.6000000000000001
    let path = recipe_file(
        "zbuf-digits",
        "{layer_height: 0.2, perimeters: 1, infill: {angle: 45, spacing: 0.8}, features: [{box: {center: [0.1, -0.3, 1.5], size: [40.3, 30.7, 3]}}, {cylinder: {center: [-10.3, 0.7, 0], radius: 2.35, height: 3, op: subtract}}]}",
    );
    let r = load(&path);
    let s = solid_of(&r, 0);
    let layer = s.layers().find(|l| l.index == 3).unwrap();
    assert_ne!(
        format!("{}", layer.z),
        "0.6",
        "the test needs a z of many digits"
    );
    let svg = crate::generate::primitive::solid::layer_svg(&[("solid", s)], 3)
        .unwrap()
        .unwrap();
    assert!(svg.contains("layer 3 at z 0.6 mm"), "{svg}");
    // every number written: at most 3 decimals, no trailing zero, no -0
    let number = regex::Regex::new(r"-?[0-9]+(\.[0-9]+)?").unwrap();
    let mut seen = 0;
    for m in number.find_iter(&svg) {
        let t = m.as_str();
        seen += 1;
        assert!(t != "-0", "a negative zero in {svg}");
        if let Some((_, frac)) = t.split_once('.') {
            assert!(frac.len() <= 3 && !frac.ends_with('0'), "`{t}` in {svg}");
        }
    }
    assert!(seen > 20, "{svg}");
    // the outline as written is the exact one within half a micrometre:
    // the box's corners, x 0.1 ± 20.15, y -0.3 ± 15.35
    let d = svg.split("<path d=\"").nth(1).unwrap();
    let d = &d[..d.find('"').unwrap()];
    let values: Vec<f64> = number
        .find_iter(d)
        .map(|m| m.as_str().parse().unwrap())
        .collect();
    for (x, y) in [
        (-20.05, -15.65),
        (20.25, -15.65),
        (20.25, 15.05),
        (-20.05, 15.05),
    ] {
        let near = values
            .windows(2)
            .any(|p| (p[0] - x).abs() < 5e-4 && (p[1] - y).abs() < 5e-4);
        assert!(near, "no corner ({x}, {y}) in {d}");
    }
    // the hole's arcs keep their radius to the micrometre
    assert!(d.contains("A2.35 2.35 0"), "{d}");
}

#[test]
fn a_kept_z_buffer_re_slices_only_the_edited_feature() {
    use crate::generate::primitive::solid::{Cache, Reusing};
    use crate::recipe::context::Context;
    // as `p3dp watch` builds: the z-buffers of one build kept for the next
    let reusing = |cache: Cache, path: &std::path::Path| {
        let cx = Context {
            zbuffers: Some(Reusing::new(cache)),
            ..Context::default()
        };
        let r = crate::recipe::load_in(path, &[], None, &cx).unwrap_or_else(|e| panic!("{e}"));
        (r, cx.zbuffers.map(Reusing::finish).unwrap_or_default())
    };
    let path = recipe_file("kept", BOX_WITH_HOLE);
    let (r, cache) = reusing(Cache::default(), &path);
    assert_eq!(cache.last.len(), 1);
    assert_eq!((cache.last[0].layers, cache.last[0].recomputed), (80, 80));
    drop(r);
    // the boss (z 10 … 16) made 4 mm tall: layers 51 … 70 recomputed, 71 … 80 gone
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(
        &path,
        text.replace("radius: 5, height: 6", "radius: 5, height: 4"),
    )
    .unwrap();
    let (r, cache) = reusing(cache, &path);
    assert_eq!((cache.last[0].layers, cache.last[0].recomputed), (70, 20));
    let fresh = load(&path);
    assert_eq!(
        solid_of(&r, 0),
        solid_of(&fresh, 0),
        "equal to a build from scratch"
    );
    // the hole widened (z 0 … 10): the layers below the boss only
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, text.replace("radius: 8", "radius: 9")).unwrap();
    let (r, cache) = reusing(cache, &path);
    assert_eq!((cache.last[0].layers, cache.last[0].recomputed), (70, 50));
    assert_eq!(solid_of(&r, 0), solid_of(&load(&path), 0));
    // a setting changed: everything again
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, text.replace("perimeters: 2", "perimeters: 3")).unwrap();
    let (_, cache) = reusing(cache, &path);
    assert_eq!((cache.last[0].layers, cache.last[0].recomputed), (70, 70));
    // nothing changed: nothing recomputed
    let (_, cache) = reusing(cache, &path);
    assert_eq!((cache.last[0].layers, cache.last[0].recomputed), (70, 0));
}
