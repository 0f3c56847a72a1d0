//! SVG outlines (issue 20): points lie on the SVG's exact shapes within the
//! chord tolerance, every turn of a vase follows the outline one pitch up,
//! and bad SVGs are refused naming the file and the element. The gallery's
//! star vase is checked in `internals::svg`.

use crate::common::*;
use glam::{DVec2, DVec3};
use p3dp::testing::Toolpath;
use std::path::Path;

/// Distance from `p` to the segment a–b.
fn to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
    p.distance(a + d * t)
}

/// Distance from `p` to the closed polygon `poly`.
pub(crate) fn to_polygon(p: DVec2, poly: &[DVec2]) -> f64 {
    (0..poly.len())
        .map(|j| to_segment(p, poly[j], poly[(j + 1) % poly.len()]))
        .fold(f64::INFINITY, f64::min)
}

/// The star of the test: outer radius 20, inner 9, centred at (25, 25) of a
/// 50 mm drawing, SVG coordinates (y down).
fn star_svg_points() -> Vec<DVec2> {
    (0..10)
        .map(|k| {
            let r = if k % 2 == 0 { 20.0 } else { 9.0 };
            let a = std::f64::consts::FRAC_PI_2 + k as f64 * std::f64::consts::PI / 5.0;
            DVec2::new(25.0 + r * a.cos(), 25.0 - r * a.sin())
        })
        .collect()
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

const HEAD: &str = "p3dp: 1\nname: t\nprinter: generic-220\nmaterial: pla\n";

fn star_dir(name: &str) -> crate::common::Tmp {
    let dir = tmp(name);
    let d: Vec<String> = star_svg_points()
        .iter()
        .map(|p| format!("{:.6} {:.6}", p.x, p.y))
        .collect();
    write(
        &dir,
        "star.svg",
        &format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="50mm" height="50mm" viewBox="0 0 50 50"><path id="s" d="M {} Z"/></svg>"#,
            d.join(" L ")
        ),
    );
    dir
}

fn part(dir: &Path, recipe: &str, k: usize) -> Toolpath {
    write(dir, "r.yaml", recipe);
    let r = p3dp::testing::load_recipe(&dir.join("r.yaml"), &[], None).unwrap();
    p3dp::testing::make_part(&r, k).unwrap()
}

/// The exact star as the helix places it: y flipped, its area centroid (the
/// star's centre, by symmetry) at `center`.
fn star_placed(center: DVec2) -> Vec<DVec2> {
    star_svg_points()
        .iter()
        .map(|p| DVec2::new(p.x - 25.0, 25.0 - p.y) + center)
        .collect()
}

#[test]
fn every_turn_of_a_star_helix_follows_the_star_one_pitch_up() {
    let dir = star_dir("star-helix");
    let (pitch, segments) = (0.5, 100usize);
    let tp = part(
        &dir,
        &format!(
            "{HEAD}parts:\n  - name: w\n    primitive:\n      helix: {{ outline: {{ svg: star.svg }}, height: 5, pitch: {pitch}, segments: {segments}, center: [3, -2, 0.2] }}\n"
        ),
        0,
    );
    let star = star_placed(DVec2::new(3.0, -2.0));
    let u = tp.turns.as_ref().expect("an outline part carries s");
    // per turn: the 100 even steps and the 10 corners (the start lies on
    // the ray theta = 0, on an edge)
    let m = segments + 10;
    assert_eq!(tp.len(), (5.0 / pitch) as usize * m);
    let perimeter: f64 = (0..10).map(|j| star[j].distance(star[(j + 1) % 10])).sum();
    for (j, p) in tp.points.iter().enumerate() {
        // on the exact star (usvg keeps coordinates as f32)
        let d = to_polygon(p.truncate(), &star);
        assert!(d < 2e-5, "point {j} is {d} mm off the star");
        // raised by (k + s)·pitch over the start
        assert!((p.z - 0.2 - u[j] * pitch).abs() < 1e-9, "point {j}");
        // one turn later: the same x, y, one pitch up
        if j + m < tp.points.len() {
            let q = tp.points[j + m];
            assert_eq!(q.truncate(), p.truncate(), "point {j}");
            assert!((q.z - p.z - pitch).abs() < 1e-9);
            assert!((u[j + m] - u[j] - 1.0).abs() < 1e-12);
        }
    }
    // the first turn starts on the ray theta = 0 from the centroid
    assert!((tp.points[0].y + 2.0).abs() < 1e-9 && tp.points[0].x > 3.0);
    // every corner of the star is a point of every turn
    for c in &star {
        let hits = tp
            .points
            .iter()
            .filter(|p| p.truncate().distance(*c) < 2e-5)
            .count();
        assert_eq!(hits, 10, "corner {c} once a turn");
    }
    // arc length, not angle: the strings of a turn are at most one even
    // step long (a corner splits one into two) and most exactly one
    let step = perimeter / segments as f64;
    let flat = |k: usize| (tp.points[k + 1] - tp.points[k]).truncate().length();
    let lens: Vec<f64> = (0..m).map(flat).collect();
    assert!(lens.iter().all(|&l| l <= step + 1e-4), "{lens:?}");
    let even = lens.iter().filter(|&&l| (l - step).abs() < 1e-4).count();
    assert!(even >= segments - 10, "{even} even strings of {m}");
    // s is the arc fraction: at point k of the first turn, the distance
    // walked along the star from the start
    let mut walked = 0.0;
    for (k, uk) in u.iter().enumerate().take(m) {
        assert!((uk * perimeter - walked).abs() < 1e-4, "s at point {k}");
        walked += flat(k);
    }
}

#[test]
fn a_circle_of_bezier_curves_is_flattened_within_the_tolerance() {
    // a circle of radius 20 as four cubics (the usual kappa), in mm
    let (r, kappa) = (20.0f64, 0.552_284_749_8);
    let cx = 25.0;
    let k = r * kappa;
    // the four cubics, exactly, sampled finely (SVG coordinates)
    let ctrl: Vec<[DVec2; 4]> = {
        let v = |x: f64, y: f64| DVec2::new(x, y);
        let (a, b) = (cx + r, cx - r);
        let (p, m) = (cx + k, cx - k);
        vec![
            [v(a, cx), v(a, p), v(p, a), v(cx, a)],
            [v(cx, a), v(m, a), v(b, p), v(b, cx)],
            [v(b, cx), v(b, m), v(m, b), v(cx, b)],
            [v(cx, b), v(p, b), v(a, m), v(a, cx)],
        ]
    };
    let exact: Vec<DVec2> = ctrl
        .iter()
        .flat_map(|c| {
            (0..20_000).map(move |j| {
                let t = j as f64 / 20_000.0;
                let u = 1.0 - t;
                c[0] * (u * u * u)
                    + c[1] * (3.0 * u * u * t)
                    + c[2] * (3.0 * u * t * t)
                    + c[3] * (t * t * t)
            })
        })
        .map(|p| DVec2::new(p.x - cx, cx - p.y))
        .collect();
    let d = format!(
        "M {} {} {} Z",
        ctrl[0][0].x,
        ctrl[0][0].y,
        ctrl.iter()
            .map(|c| format!(
                "C {} {}, {} {}, {} {}",
                c[1].x, c[1].y, c[2].x, c[2].y, c[3].x, c[3].y
            ))
            .collect::<Vec<_>>()
            .join(" ")
    );
    // distance to the finely sampled curve, taken to its chords (which sag
    // less than 1e-8 mm at this spacing)
    let off = |p: DVec2| {
        (0..exact.len())
            .map(|j| to_segment(p, exact[j], exact[(j + 1) % exact.len()]))
            .fold(f64::INFINITY, f64::min)
    };
    let dir = tmp("circle-bezier");
    write(
        &dir,
        "c.svg",
        &format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="50mm" height="50mm" viewBox="0 0 50 50"><path d="{d}"/></svg>"#
        ),
    );
    let mut worst = Vec::new();
    for tol in [0.01, 0.2] {
        // the drawing as a path: every flattened point and every chord's
        // midpoint within `tol` of the exact curves
        let tp = part(
            &dir,
            &format!(
                "{HEAD}parts:\n  - name: w\n    primitive:\n      path: {{ svg: c.svg, tolerance: {tol} }}\n"
            ),
            0,
        );
        let mut w: f64 = 0.0;
        for k in 0..tp.len() {
            let (a, b) = tp.ends(k);
            assert!(
                off(a.truncate()) < 1e-4,
                "vertex {k} {a} {}",
                off(a.truncate())
            );
            w = w.max(off(((a + b) * 0.5).truncate()));
        }
        assert!(w <= tol, "chord sag {w} over tolerance {tol}");
        worst.push((w, tp.len()));
        // the outline of a helix: its points on those chords, so within tol too
        let h = part(
            &dir,
            &format!(
                "{HEAD}parts:\n  - name: w\n    primitive:\n      helix: {{ outline: {{ svg: c.svg, tolerance: {tol} }}, height: 1, pitch: 0.5, segments: 360 }}\n"
            ),
            0,
        );
        for p in &h.points {
            assert!(off(p.truncate()) <= tol, "{p}");
        }
    }
    // the tolerance is what decides: the coarse one cuts fewer, longer chords
    // that sag further
    assert!(worst[1].1 < worst[0].1 && worst[1].0 > 0.01, "{worst:?}");
}

#[test]
fn the_svg_file_is_recorded_for_watch() {
    let dir = star_dir("record");
    write(
        &dir,
        "r.yaml",
        &format!("{HEAD}parts:\n  - name: w\n    primitive:\n      helix: {{ outline: {{ svg: star.svg }}, height: 1, pitch: 0.5 }}\n"),
    );
    let cx = p3dp::testing::Context::default();
    p3dp::testing::load_recipe_in(&dir.join("r.yaml"), &[], None, &cx).unwrap();
    let files = cx.reads.files();
    assert!(files.contains(&dir.join("star.svg")), "{files:?}");
}

#[test]
fn a_param_named_s_still_works_and_shadows_the_variable() {
    let dir = tmp("param-s");
    let tp = part(
        &dir,
        &format!(
            "{HEAD}params: {{ s: 2 }}\nparts:\n  - name: w\n    primitive:\n      helix: {{ radius: 10, height: 1, pitch: 0.5 }}\n    steps:\n      - deform_xyz: {{ position: [\"x*s\", y, z] }}\n"
        ),
        0,
    );
    assert!((tp.points[0].x - 20.0).abs() < 1e-12);
}

#[test]
fn a_spiral_and_a_cylinder_shrink_the_outline_pitch_apart() {
    let dir = star_dir("spiral");
    let tp = part(
        &dir,
        &format!("{HEAD}parts:\n  - name: w\n    primitive:\n      spiral: {{ outline: {{ svg: star.svg }}, pitch: 2, inner_radius: 4, segments: 50 }}\n"),
        0,
    );
    let star = star_placed(DVec2::ZERO);
    let u = tp.turns.as_ref().unwrap();
    // the outward spiral ends on the outline at its start (u = 0)
    assert_eq!(*u.last().unwrap(), 0.0);
    assert!(to_polygon(tp.head().truncate(), &star) < 2e-5);
    // each point is on the star scaled by (20 + u·pitch) / 20 about the centroid
    for (j, p) in tp.points.iter().enumerate() {
        let k = (20.0 + u[j] * 2.0) / 20.0;
        let back = p.truncate() / k;
        assert!(to_polygon(back, &star) < 1e-4, "point {j}");
    }
    // the first turn is inner_radius / radius of the outline's size
    assert!((u[0] + 8.0).abs() < 0.02, "{}", u[0]);
    let cyl = part(
        &dir,
        &format!("{HEAD}parts:\n  - name: w\n    primitive:\n      cylinder: {{ outline: {{ svg: star.svg }}, height: 0.4, vpitch: 0.2, hpitch: 2, segments: 50 }}\n"),
        0,
    );
    // two layers, outward then inward, joined by one step up on the outline
    let travels: Vec<usize> = (0..cyl.len()).filter(|&k| cyl.strings[k].travel).collect();
    assert_eq!(travels.len(), 1);
    let (a, b) = cyl.ends(travels[0]);
    assert_eq!(a.truncate(), b.truncate());
    assert!(to_polygon(a.truncate(), &star) < 2e-5);
    assert_eq!(cyl.len(), 2 * travels[0] + 1);
}

fn refuse(dir: &Path, svg: &str, file: &str, what: &[&str]) {
    write(
        dir,
        "r.yaml",
        &format!("{HEAD}parts:\n  - name: w\n    primitive:\n      helix: {{ outline: {{ svg: {file} }}, height: 1, pitch: 0.5 }}\n"),
    );
    if !svg.is_empty() {
        write(dir, file, svg);
    }
    let out = p3dp(dir, &["build", "r.yaml", "-o", "o.gcode"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("parts[0].primitive.helix.outline.svg"),
        "{err}"
    );
    assert!(err.contains(file), "{err}");
    for w in what {
        assert!(err.contains(w), "`{w}` not in {err}");
    }
    assert!(!dir.join("o.gcode").exists());
}

#[test]
fn bad_svgs_are_refused_naming_the_file_and_the_element() {
    let dir = tmp("bad-svg");
    let svg = |body: &str| {
        format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="10mm" height="10mm" viewBox="0 0 10 10">{body}</svg>"#
        )
    };
    refuse(&dir, "", "missing.svg", &["cannot read"]);
    refuse(
        &dir,
        &svg(r#"<path id="line" d="M 1 1 L 9 9"/>"#),
        "open.svg",
        &["no closed path", "id=\"line\""],
    );
    refuse(&dir, &svg("<g id=\"g\"/>"), "empty.svg", &["empty"]);
    refuse(
        &dir,
        &svg(r#"<path id="a" d="M 0 0 L 5 0 L 5 5 Z"/><path id="b" d="M 6 6 L 9 6 L 9 9 Z"/>"#),
        "two.svg",
        &["2 closed paths", "id=\"a\"", "id=\"b\""],
    );
    // a bomb: 8 levels each using the one below 10 times (10^8 copies)
    let mut body = String::from(r#"<defs><path id="l0" d="M 0 0 L 1 0 L 1 1 Z"/>"#);
    for k in 1..=8 {
        body.push_str(&format!("<g id=\"l{k}\">"));
        for _ in 0..10 {
            body.push_str(&format!(r##"<use xlink:href="#l{}"/>"##, k - 1));
        }
        body.push_str("</g>");
    }
    body.push_str(r##"</defs><use xlink:href="#l8"/>"##);
    let t = std::time::Instant::now();
    refuse(
        &dir,
        &svg(&body),
        "bomb.svg",
        &["<g id=\"l5\">", "line 1", "SVG bomb"],
    );
    assert!(t.elapsed().as_secs() < 20);
    // a huge file: refused by size before it is parsed
    let mut big = svg("");
    big.insert_str(big.len() - 6, &" ".repeat(5 << 20));
    refuse(&dir, &big, "huge.svg", &["larger than 4 MB"]);
    // a drawing that would flatten to more points than max_strings
    write(
        &dir,
        "r2.yaml",
        &format!("{HEAD}max_strings: 1000\nparts:\n  - name: w\n    primitive:\n      path: {{ svg: c.svg, tolerance: 0.00001 }}\n"),
    );
    write(
        &dir,
        "c.svg",
        &svg(r#"<circle id="round" cx="5" cy="5" r="4"/>"#),
    );
    let out = p3dp(&dir, &["build", "r2.yaml", "-o", "o.gcode"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("parts[0].primitive.path.svg")
            && err.contains("id=\"round\"")
            && err.contains("max_strings"),
        "{err}"
    );
}

#[test]
fn the_drawing_recipe_plots_every_shape() {
    let r = p3dp::testing::load_recipe(&recipe("svg-drawing.yaml"), &[], None).unwrap();
    let tp = p3dp::testing::make_part(&r, 0).unwrap();
    // one travel to each subpath after the first: house (3 shapes), sun (circle
    // and 4 rays), hill, 5 pickets
    let travels = tp.strings.iter().filter(|s| s.travel).count();
    assert_eq!(travels, 3 + 5 + 1 + 5 - 1);
    // all at the pen's height, centred on the origin, 1.5 times 80 × 60 mm
    // less the strokes (the bounding box of the geometry: 76 × 56 mm)
    assert!(tp.points.iter().all(|p| p.z == r.params["pen_z"]));
    let (lo, hi) = tp
        .points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
            (l.min(*p), h.max(*p))
        });
    assert!(((hi.x - lo.x) - 1.5 * 76.0).abs() < 1e-3, "{lo} {hi}");
    assert!((hi.x + lo.x).abs() < 1e-9 && (hi.y + lo.y).abs() < 1e-9);
}
