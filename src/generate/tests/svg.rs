//! The gallery's star vase: without its steps the wall is the SVG outline,
//! turn after turn; with them, the steps' formula on top of it.
//!
//! Past the public face: the steps are taken off `Recipe::parts[1].steps`.
//! Home: beside `generate::primitive::outline`.

use crate::base::testing::*;
use glam::DVec2;

#[test]
fn the_star_vase_follows_its_outline_in_every_turn() {
    let r = crate::recipe::load(&recipe("star-vase.yaml"), &[], None).unwrap();
    // without its steps the wall is the outline, turn after turn
    let mut bare = r.clone();
    bare.parts[1].steps.clear();
    let tp = crate::generate::model::make_part(&bare, 1).unwrap();
    let star: Vec<DVec2> = (0..10)
        .map(|k| {
            let rr = if k % 2 == 0 { 28.0 } else { 15.0 };
            let a = std::f64::consts::FRAC_PI_2 + k as f64 * std::f64::consts::PI / 5.0;
            DVec2::new(rr * a.cos(), rr * a.sin())
        })
        .collect();
    let u = tp.turns.as_ref().unwrap();
    let pitch = r.params["pitch"];
    for (j, p) in tp.points.iter().enumerate() {
        assert!(to_polygon(p.truncate(), &star) < 1e-4, "point {j}");
        assert!((p.z - u[j] * pitch).abs() < 1e-9);
    }
    // the finished wall: its steps see s, so at the rim the ripple is
    // ripple·sin(2·pi·ripples·s) in r, on top of the twisted star
    let fin = crate::generate::model::make_part(&r, 1).unwrap();
    assert_eq!(fin.points.len(), tp.points.len());
    let p = |k: &str| r.params[k];
    for (j, ((a, b), s)) in fin.points.iter().zip(&tp.points).zip(u).enumerate() {
        let s = *s - s.floor();
        let z = b.z;
        let want = b.truncate().length()
            * (1.0 + p("belly") * (std::f64::consts::PI * z / p("height")).sin())
            + p("ripple") * (z / p("height")) * (std::f64::consts::TAU * p("ripples") * s).sin();
        assert!((a.truncate().length() - want).abs() < 1e-9, "point {j}");
        assert!((a.z - z - p("bottom_top")).abs() < 1e-9);
    }
}

/// Distance from `p` to the closed polygon `poly`.
fn to_polygon(p: DVec2, poly: &[DVec2]) -> f64 {
    (0..poly.len())
        .map(|j| to_segment(p, poly[j], poly[(j + 1) % poly.len()]))
        .fold(f64::INFINITY, f64::min)
}

/// Distance from `p` to the segment a–b.
fn to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
    p.distance(a + d * t)
}
