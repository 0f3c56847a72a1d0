//! ExtruderTurtle's own prints (Pezzuti Dyer and Buechley, TEI '22) beyond
//! the basic shapes: filled shapes (Fig. 4) and flexible circles, each read
//! back from its strings and checked for the property its recipe promises.
//! The hairs, the string-art parabola and the chain mail, which run the
//! checks on strings changed by hand, are in `internals::extruder_turtle`.

use std::path::PathBuf;

use glam::DVec3;
use p3dp::testing::make_parts;
use p3dp::testing::Recipe;
use p3dp::testing::Toolpath;

pub(crate) fn load(name: &str) -> Recipe {
    load_with(name, &[])
}

pub(crate) fn load_with(name: &str, sets: &[(&str, &str)]) -> Recipe {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("recipes")
        .join(name);
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    p3dp::testing::load_recipe(&path, &sets, None).unwrap_or_else(|e| panic!("{name}: {e}"))
}

pub(crate) fn param(recipe: &Recipe, name: &str) -> f64 {
    *recipe
        .params
        .get(name)
        .unwrap_or_else(|| panic!("no param `{name}`"))
}

/// Extruding strings of `tp` at height `z` (within 1 µm), as segments.
pub(crate) fn at_height(tp: &Toolpath, z: f64) -> Vec<(DVec3, DVec3)> {
    (0..tp.len())
        .filter(|&k| !tp.strings[k].travel)
        .map(|k| tp.ends(k))
        .filter(|(a, b)| (a.z - z).abs() < 1e-6 && (b.z - z).abs() < 1e-6)
        .collect()
}

/// Total length of the extruding strings of `tp` at height `z`, mm.
fn length_at(tp: &Toolpath, z: f64) -> f64 {
    at_height(tp, z).iter().map(|(a, b)| a.distance(*b)).sum()
}

#[test]
fn filled_shapes_fill_their_area_and_stay_inside_it() {
    let r = load("filled-shapes.yaml");
    let parts = make_parts(&r).unwrap();
    let (h, fill, sparse, cube, apothem) = (
        param(&r, "layer_height"),
        param(&r, "fill"),
        param(&r, "sparse"),
        param(&r, "cube"),
        param(&r, "apothem"),
    );
    let t36 = 36f64.to_radians().tan();
    // the pentagon's bottom layers: length × spacing ≈ its area, 5 a² tan 36°
    let pent = &parts[0];
    let area = 5.0 * apothem * apothem * t36;
    for layer in 0..param(&r, "bottom") as usize {
        let z = h * (layer + 1) as f64;
        let covered = length_at(pent, z) * fill;
        assert!(
            (covered / area - 1.0).abs() < 0.03,
            "layer {layer}: {covered} of {area} mm²"
        );
        // every string inside the pentagon, at least fill/2 from its sides
        for (a, b) in at_height(pent, z) {
            for p in [a, b] {
                for k in 0..5 {
                    let th = (-90.0 + 72.0 * k as f64).to_radians();
                    let reach = p.x * th.cos() + p.y * th.sin();
                    assert!(reach <= apothem - fill / 2.0 + 1e-9, "{p} outside");
                }
            }
        }
    }
    // above the bottom: one ring a layer, the outermost (a hollow prism)
    let z = h * (param(&r, "bottom") + 1.0);
    let ring = 10.0 * (apothem - fill / 2.0) * t36;
    assert!((length_at(pent, z) - ring).abs() < 1e-6);
    // the cubes: every layer's fill lines (along x; the zig-zag's short
    // joins aside) times their spacing cover the square within 3 %, the
    // sparse one with lines `sparse` apart (a lower fill density)
    for (tp, s) in [(&parts[1], fill), (&parts[2], sparse)] {
        let layers = (cube / h).round() as usize;
        for layer in 0..layers {
            let lines: f64 = at_height(tp, h * (layer + 1) as f64)
                .iter()
                .filter(|(a, b)| (a.y - b.y).abs() < 1e-9)
                .map(|(a, b)| a.distance(*b))
                .sum();
            let (covered, area) = (lines * s, cube * cube);
            assert!(
                (covered / area - 1.0).abs() < 0.03,
                "{} layer {layer}: {covered} of {area}",
                tp.name
            );
        }
    }
    let dense: f64 = parts[1].volume();
    let thin: f64 = parts[2].volume();
    assert!(
        (dense / thin - sparse / fill).abs() / (sparse / fill) < 0.1,
        "{dense} {thin}"
    );
}

#[test]
fn flexible_circles_have_a_pillar_per_side_in_every_layer_and_differ_by_rate() {
    let r = load("flexible-circles.yaml");
    let parts = make_parts(&r).unwrap();
    let (segments, poke, radius, h) = (
        param(&r, "segments") as usize,
        param(&r, "poke"),
        param(&r, "radius"),
        param(&r, "layer_height"),
    );
    let layers = (param(&r, "height") / h).round() as usize;
    assert_eq!(parts.len(), 3);
    for tp in &parts {
        let centre = {
            let (lo, hi) = tp.points.iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(l, h), p| (l.min(*p), h.max(*p)),
            );
            DVec3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, 0.0)
        };
        let mut first: Vec<(i64, i64)> = Vec::new();
        for l in 0..layers {
            // the pokes: outward strings `poke` long from a vertex of the ring
            let mut tips: Vec<(i64, i64)> = at_height(tp, h * (l + 1) as f64)
                .into_iter()
                .filter(|(a, b)| (a.distance(*b) - poke).abs() < 1e-9)
                .filter_map(|(a, b)| {
                    let (ra, rb) = (
                        (a - centre).truncate().length(),
                        (b - centre).truncate().length(),
                    );
                    ((ra - radius).abs() < 1e-6 && (rb - radius - poke).abs() < 1e-6)
                        .then(|| ((b.x * 1e4).round() as i64, (b.y * 1e4).round() as i64))
                })
                .collect();
            tips.sort();
            assert_eq!(tips.len(), segments, "{} layer {l}", tp.name);
            // the same places in every layer: the pokes stack into pillars
            if l == 0 {
                first = tips;
            } else {
                assert_eq!(tips, first, "{} layer {l}", tp.name);
            }
        }
    }
    // the same path, filament in the ratio of the extrude rates
    let v: Vec<f64> = parts.iter().map(|t| t.volume()).collect();
    let (lo, mid, hi) = (
        param(&r, "rate_lo"),
        param(&r, "rate_mid"),
        param(&r, "rate_hi"),
    );
    assert!((v[1] / v[0] - mid / lo).abs() < 1e-9 && (v[2] / v[0] - hi / lo).abs() < 1e-9);
}
