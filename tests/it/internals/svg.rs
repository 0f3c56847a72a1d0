//! The gallery's star vase: without its steps the wall is the SVG outline,
//! turn after turn; with them, the steps' formula on top of it.
//!
//! Past the public face: the steps are taken off `Recipe::parts[1].steps`.
//! Home: beside `generate::primitive::outline`.

use crate::common::*;
use crate::svg::to_polygon;
use glam::DVec2;
use p3dp::recipe::Recipe;

#[test]
fn the_star_vase_follows_its_outline_in_every_turn() {
    let r = Recipe::load(&recipe("star-vase.yaml"), &[], None).unwrap();
    // without its steps the wall is the outline, turn after turn
    let mut bare = r.clone();
    bare.parts[1].steps.clear();
    let tp = p3dp::generate::model::make_part(&bare, 1).unwrap();
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
    let fin = p3dp::generate::model::make_part(&r, 1).unwrap();
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
