//! The `turtle` primitive through the real binary: the papers' turtle prints
//! (ExtruderTurtle, TEI '22) read back from their G-code.

use crate::common;

use std::collections::{BTreeMap, HashSet};

use crate::common::{p3dp, parse, recipe, root, tmp, to_recipe, Move};

/// Builds `path` with `sets` and returns the G-code text.
fn gcode(path: &std::path::Path, sets: &[&str], tag: &str) -> String {
    let dir = tmp(tag);
    let out = dir.join("out.gcode");
    let mut args = vec!["build", path.to_str().unwrap(), "-o", out.to_str().unwrap()];
    for s in sets {
        args.push("--set");
        args.push(s);
    }
    let o = p3dp(&dir, &args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read_to_string(out).unwrap()
}

fn extruding(m: &Move) -> bool {
    m.g == 1 && m.de > 0.0 && (m.from[0] != m.to[0] || m.from[1] != m.to[1] || m.from[2] != m.to[2])
}

/// Horizontal extruding moves grouped by height (µm).
fn layers(moves: &[Move]) -> BTreeMap<i64, Vec<Move>> {
    let mut out: BTreeMap<i64, Vec<Move>> = BTreeMap::new();
    for m in moves
        .iter()
        .filter(|m| extruding(m) && m.from[2] == m.to[2])
    {
        out.entry((m.to[2] * 1000.0).round() as i64)
            .or_default()
            .push(*m);
    }
    out
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn cardioid_has_66_layers_of_8_chords_from_n_to_2n() {
    let g = parse(&gcode(&recipe("cardioid.yaml"), &[], "cardioid"));
    let (n_points, radius) = (67usize, 40.0);
    // the point of the circle a machine position is at (within G-code rounding)
    let point = |p: [f64; 3]| -> Option<usize> {
        let q = to_recipe(p);
        (0..n_points).find(|&k| {
            let a = std::f64::consts::TAU * k as f64 / n_points as f64;
            (q[0] - radius * a.cos()).abs() < 2e-3 && (q[1] - radius * a.sin()).abs() < 2e-3
        })
    };
    // a chord joins two of the points; the rim's strings end between them
    let chords: Vec<Move> = g
        .moves
        .iter()
        .filter(|m| extruding(m) && point(m.from).is_some() && point(m.to).is_some())
        .copied()
        .collect();
    let by_layer = {
        let mut b: BTreeMap<i64, Vec<Move>> = BTreeMap::new();
        for m in &chords {
            b.entry((m.to[2] * 1000.0).round() as i64)
                .or_default()
                .push(*m);
        }
        b
    };
    assert_eq!(by_layer.len(), 66, "66 layers");
    let mut count = vec![0usize; n_points];
    for (z, ms) in &by_layer {
        // each layer: its rim's first move (after the travel to the rim) and 8 chords
        let chords: Vec<&Move> = ms
            .iter()
            .filter(|m| {
                point(m.from).is_some() && point(m.to).is_some() && dist(m.from, m.to) > 3.0
            })
            .collect();
        assert_eq!(
            chords.len(),
            8,
            "layer z = {} µm has {} chords",
            z,
            chords.len()
        );
        for m in chords {
            let (a, b) = (point(m.from).unwrap(), point(m.to).unwrap());
            assert_eq!(b, 2 * a % n_points, "chord {a} → {b}");
            count[a] += 1;
        }
    }
    assert_eq!(count.iter().sum::<usize>(), 66 * 8);
    assert_eq!(count[0], 0);
    assert!(
        count[1..].iter().all(|&c| c == 8),
        "each chord 8 times: {count:?}"
    );
}

#[test]
fn koch_tower_level_k_has_4_to_the_k_segments_a_side() {
    let g = parse(&gcode(&recipe("koch-tower.yaml"), &[], "koch"));
    let ls = layers(&g.moves);
    assert_eq!(ls.len(), 50);
    let side = 60.0;
    for (i, (z, ms)) in ls.iter().enumerate() {
        let k = (i / 10) as u32;
        let per_side = 4usize.pow(k);
        assert_eq!(ms.len(), 3 * per_side, "layer {i} (z {z} µm)");
        // every string is side/3^k long, and the triangle's corners come every 4^k strings
        let len = side / 3f64.powi(k as i32);
        assert!(ms.iter().all(|m| (dist(m.from, m.to) - len).abs() < 2e-3));
        let corners: Vec<[f64; 3]> = (0..3).map(|j| ms[j * per_side].from).collect();
        for j in 0..3 {
            let d = dist(corners[j], corners[(j + 1) % 3]);
            assert!((d - side).abs() < 2e-3, "layer {i}: corners {d} mm apart");
        }
        // closed: the last string ends where the first starts
        assert!(dist(ms[ms.len() - 1].to, ms[0].from) < 2e-3);
    }
}

#[test]
fn hilbert_of_order_k_visits_4_to_the_k_cells_once() {
    for order in [2u32, 3, 4] {
        let g = parse(&gcode(
            &recipe("hilbert.yaml"),
            &[&format!("order={order}"), "layers=4"],
            &format!("hilbert-{order}"),
        ));
        let ls = layers(&g.moves);
        assert_eq!(ls.len(), 4);
        let cells = 4usize.pow(order);
        let side = 2usize.pow(order);
        // the grid's first cell is at -half in x and y, cells 3 mm apart
        let half = (side as f64 - 1.0) * 3.0 / 2.0;
        let cell = |p: [f64; 3]| {
            let q = to_recipe(p);
            (
                ((q[0] + half) / 3.0).round() as i64,
                ((q[1] + half) / 3.0).round() as i64,
            )
        };
        for ms in ls.values() {
            assert_eq!(ms.len(), cells - 1);
            let mut seen = HashSet::new();
            seen.insert(cell(ms[0].from));
            for m in ms {
                assert!((dist(m.from, m.to) - 3.0).abs() < 2e-3, "one cell a move");
                assert!(
                    seen.insert(cell(m.to)),
                    "cell {:?} visited twice",
                    cell(m.to)
                );
            }
            assert_eq!(seen.len(), cells);
            assert!(seen
                .iter()
                .all(|&(i, j)| i < side as i64 && j < side as i64 && i >= 0 && j >= 0));
        }
    }
}

#[test]
fn pen_up_travels_and_retracts_and_pen_down_unretracts() {
    let text = gcode(&root().join("tests/fixtures/turtle-pen.yaml"), &[], "pen");
    let g = parse(&text);
    let area = std::f64::consts::PI * 0.875 * 0.875;
    // extruding strings: 20 mm and 10 mm at 0.2 mm², 10 mm at 0.05 mm/mm
    let strings = 0.2 * 30.0 / area + 0.05 * 10.0;
    let in_place = 2.0;
    // E total: every retraction undone, nothing lost or added
    let e_total: f64 = g.moves.iter().map(|m| m.de).sum();
    assert!((e_total - (strings + in_place)).abs() < 1e-5, "E {e_total}");
    let moved: f64 = g.moves.iter().filter(|m| extruding(m)).map(|m| m.de).sum();
    assert!((moved - strings).abs() < 1e-5);
    // the pen-up moves are G0 without E, each after a retraction
    let all: Vec<&str> = text.lines().filter(|l| l.starts_with('G')).collect();
    // the part: from its first extruding move to its last
    let first = all.iter().position(|l| l.starts_with("G1 X")).unwrap();
    let last = all.iter().rposition(|l| l.starts_with("G1 Y")).unwrap();
    let lines = &all[first..=last];
    let travels: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].starts_with("G0"))
        .collect();
    for &i in &travels {
        assert!(!lines[i].contains('E'));
        assert!(lines[i - 1].ends_with("; retract"), "{}", lines[i - 1]);
        assert!(lines[i + 1].ends_with("; unretract"), "{}", lines[i + 1]);
    }
    // the 1 mm pen-up move is shorter than min_travel: pen_up alone retracts it
    let short = g
        .moves
        .iter()
        .find(|m| m.g == 0 && (dist(m.from, m.to) - 1.0).abs() < 1e-9);
    assert!(short.is_some());
    assert!(text.contains("; extrude in place") && text.contains("G4 P500"));
}

#[test]
fn the_same_seed_gives_the_same_bytes_another_moves_only_the_bumps() {
    let a = gcode(&recipe("bumpy-prism.yaml"), &[], "bumpy-a");
    let b = gcode(&recipe("bumpy-prism.yaml"), &[], "bumpy-b");
    assert_eq!(a, b, "same seed, same bytes");
    let c = gcode(&recipe("bumpy-prism.yaml"), &["seed=2"], "bumpy-c");
    assert_ne!(a, c);
    let (ga, gc) = (parse(&a), parse(&c));
    assert_eq!(ga.moves.len(), gc.moves.len(), "same number of moves");
    let (la, lc) = (layers(&ga.moves), layers(&gc.moves));
    assert_eq!(
        la.keys().collect::<Vec<_>>(),
        lc.keys().collect::<Vec<_>>(),
        "same layers"
    );
    // the prism's corners are the same; the bumps (points off the walls) differ
    let corners = |g: &common::Gcode| -> Vec<[i64; 3]> {
        let mut v: Vec<[i64; 3]> = g
            .moves
            .iter()
            .filter(|m| extruding(m))
            .map(|m| m.to.map(|x| (x * 1000.0).round() as i64))
            .collect();
        v.sort();
        v
    };
    let (ca, cc) = (corners(&ga), corners(&gc));
    let on_corner = |p: &[i64; 3]| {
        let q = to_recipe(p.map(|x| x as f64 / 1000.0));
        let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
        (r - 20.0).abs() < 2e-3
    };
    let corner_set =
        |v: &[[i64; 3]]| -> Vec<[i64; 3]> { v.iter().filter(|p| on_corner(p)).cloned().collect() };
    assert_eq!(corner_set(&ca), corner_set(&cc));
    assert_eq!(
        corner_set(&ca).len(),
        100 * 6 + 100,
        "a corner a side, and each lift's top"
    );
    // the wall's bump apexes moved
    let apexes = |g: &common::Gcode| -> HashSet<[i64; 3]> {
        g.moves
            .iter()
            .filter(|m| extruding(m))
            .map(|m| m.to.map(|x| (x * 1000.0).round() as i64))
            .filter(|p| {
                let q = to_recipe(p.map(|x| x as f64 / 1000.0));
                // 1 mm out of a wall: farther from the centre than the wall's apothem + 0.5
                let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
                r > 20.0 * 0.75f64.sqrt() + 0.5 && (r - 20.0).abs() > 2e-3
            })
            .collect()
    };
    let (pa, pc) = (apexes(&ga), apexes(&gc));
    assert!(!pa.is_empty() && pa != pc);
}

#[test]
fn every_turtle_recipe_passes_check() {
    for name in [
        "hex-prism",
        "koch-tower",
        "hilbert",
        "cardioid",
        "bumpy-prism",
        "rule30-prism",
        "ruffled-star",
        "nonplanar-star",
        "nonplanar-vase",
        "brush",
        "pine-tree",
        "hairs",
        "string-art-parabola",
        "filled-shapes",
        "flexible-circles",
        "chain-mail",
    ] {
        let o = p3dp(&root(), &["check", &format!("recipes/{name}.yaml")]);
        assert!(
            o.status.success(),
            "{name}: {}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

#[test]
fn hex_prism_thick_and_thin_differ_in_filament_by_the_rate() {
    let thick = parse(&gcode(&recipe("hex-prism.yaml"), &[], "hex-thick"));
    let thin = parse(&gcode(
        &recipe("hex-prism.yaml"),
        &["rate=0.02"],
        "hex-thin",
    ));
    let e = |g: &common::Gcode| {
        g.moves
            .iter()
            .filter(|m| extruding(m))
            .map(|m| m.de)
            .sum::<f64>()
    };
    // 60 layers of 6 × 15 mm plus 60 lifts of 0.2 mm, at rate mm of filament a mm
    let path = 60.0 * 90.0 + 60.0 * 0.2;
    assert!((e(&thick) - 0.1 * path).abs() < 1e-4, "{}", e(&thick));
    assert!((e(&thin) - 0.02 * path).abs() < 1e-4, "{}", e(&thin));
    let ls = layers(&thick.moves);
    assert_eq!(ls.len(), 60);
    assert!(ls.values().all(|ms| ms.len() == 6));
}
