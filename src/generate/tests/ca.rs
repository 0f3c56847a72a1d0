//! Kanada's self-organised patterns ("Self-organized 3D-printing Patterns
//! Simulated by Cellular Automata"): the `ca_helix` automaton checked on the
//! cell array against the paper's Figs. 6, 7, 9 and 11, the recipes' typed
//! primitives, and the binary's pattern PNG against the automaton.
//!
//! Past the public face: `generate::primitive::ca` (`Automaton`, `Pattern`,
//! `CaHelix`, `Rule`, `Layout`, `Initial`), `Primitive::{CaHelix,
//! PatternHelix}` read off `Recipe::parts`. Home: beside
//! `generate::primitive::ca` and `generate::primitive::pattern`; the PNG
//! test also runs the binary and keeps that half here.

use std::path::Path;

use crate::app::testing::p3dp;
use crate::base::testing::{parse, recipe, tmp};
use crate::generate::model::make_part;
use crate::generate::model::Recipe;
use crate::generate::primitive::ca::{Automaton, CaHelix, Initial, Layout, Pattern, Rule};
use crate::generate::primitive::{PatternHelix, Primitive};
use sha2::{Digest, Sha256};

const N: usize = 288;
const SEEDS: std::ops::Range<u64> = 0..8;

/// The basic rule of Fig. 5 on the paper's N = 288, e1 = 0.3, all ones first.
fn basic(p0: f64, p1: f64, layers: u32, seed: u64) -> Pattern {
    basic_model(p0, p1, layers, seed).run()
}

/// Section 4.2's rule with the values of `recipes/ca-split-merge.yaml`.
fn split_merge(layers: u32, seed: u64) -> Pattern {
    Automaton {
        rule: Rule::SplitMerge,
        consume: 0.7,
        ..basic_model(0.99, 0.7, layers, seed)
    }
    .run()
}

fn basic_model(p0: f64, p1: f64, layers: u32, seed: u64) -> Automaton {
    Automaton {
        cells: N as u32,
        layers,
        rule: Rule::Basic,
        layout: Layout::Helix,
        p0,
        p1,
        consume: 0.5,
        e1: 0.3,
        initial: Initial::Ones,
        seed,
    }
}

/// Of the chunks above turn `from`: the share standing straight on the cell
/// below (i − N) and the share standing only on the next cell below (i − N + 1).
fn straight_and_leaning(p: &Pattern, from: usize) -> (f64, f64) {
    let (mut straight, mut leaning, mut all) = (0, 0, 0);
    for i in from * N..p.cell.len() {
        if !p.filled(i) {
            continue;
        }
        all += 1;
        if p.filled(i - N) {
            straight += 1;
        } else if p.filled(i - N + 1) {
            leaning += 1;
        }
    }
    (straight as f64 / all as f64, leaning as f64 / all as f64)
}

/// The first turn from which every turn is the one below shifted by `shift`
/// cells against the head (0: the same columns; 1: leaning one cell a turn).
fn steady_from(p: &Pattern, shift: usize) -> Option<usize> {
    let same = |i: usize| p.filled(i) == p.filled(i - N + shift);
    let mut from = None;
    for l in 1..p.layers {
        if (l * N..(l + 1) * N).all(same) {
            from.get_or_insert(l);
        } else {
            from = None;
        }
    }
    from
}

fn chunks_in(p: &Pattern, layer: usize) -> usize {
    p.row(layer).iter().filter(|c| c.filled()).count()
}

#[test]
fn p0_one_gives_vertical_stripes_fig_6c() {
    for seed in SEEDS {
        // p1 = 0: from turn 2 on, the same columns turn after turn
        let p = basic(1.0, 0.0, 150, seed);
        assert_eq!(steady_from(&p, 0), Some(2), "seed {seed}");
        // p1 = 0.5: the chunk after the initial layer's gap can still lean, a
        // defect that wanders through vertical stripes (the waves of Fig. 11)
        let p = basic(1.0, 0.5, 150, seed);
        let (straight, _) = straight_and_leaning(&p, 1);
        assert!(straight > 0.9, "seed {seed}: {straight}");
        assert_eq!(p.events().extinctions, 0, "seed {seed}");
    }
}

#[test]
fn p1_one_gives_crisp_leaning_stripes_fig_6b() {
    for seed in SEEDS {
        // p0 = 1 does not make them vertical while p1 = 1: p0 is never
        // consulted once the stripes lean
        let p = basic(1.0, 1.0, 150, seed);
        assert!(steady_from(&p, 1).is_some_and(|f| f <= 5), "seed {seed}");
        assert_eq!(straight_and_leaning(&p, 5), (0.0, 1.0), "seed {seed}");
        let p = basic(0.99, 1.0, 150, seed);
        // from an early turn on, every turn is the one below moved one cell
        let from = steady_from(&p, 1).unwrap_or(usize::MAX);
        assert!(from <= 5, "seed {seed}: steady from turn {from}");
        let (straight, leaning) = straight_and_leaning(&p, 5);
        assert_eq!((straight, leaning), (0.0, 1.0), "seed {seed}");
        // nothing dies: as many chunks in the top turn as in turn 5
        assert!(chunks_in(&p, 149) >= chunks_in(&p, 5), "seed {seed}");
    }
}

#[test]
fn p1_below_one_gives_noisy_stripes_fig_6a() {
    for seed in SEEDS {
        let p = basic(0.99, 0.9, 150, seed);
        assert_eq!(steady_from(&p, 1), None, "seed {seed}");
        assert_eq!(steady_from(&p, 0), None, "seed {seed}");
        // a mixture: mostly leaning, partly straight
        let (straight, leaning) = straight_and_leaning(&p, 5);
        assert!((0.1..0.5).contains(&straight), "seed {seed}: {straight}");
        assert!(leaning > 0.5, "seed {seed}: {leaning}");
        let off: usize = (5 * N..p.cell.len())
            .filter(|&i| p.filled(i) != p.filled(i - N + 1))
            .count();
        assert!(off > p.cell.len() / 50, "seed {seed}: {off}");
    }
}

#[test]
fn p0_097_gives_extinctions_fig_7b() {
    let (mut low, mut high) = (0, 0);
    for seed in SEEDS {
        let p = basic(0.97, 0.9, 150, seed);
        let e = p.events();
        assert!(e.extinctions >= 20, "seed {seed}: {e:?}");
        // dead stripes are not replaced: the wall thins out
        assert!(chunks_in(&p, 149) * 3 < chunks_in(&p, 1) * 2, "seed {seed}");
        low += e.extinctions;
        high += basic(0.999, 0.9, 150, seed).events().extinctions;
        // with p1 = 1 every chunk leans at once, p0 is never consulted, and
        // nothing dies: Fig. 7b needs p1 < 1 in this model
        assert_eq!(basic(0.97, 1.0, 150, seed).events().extinctions, 0);
    }
    assert!(low > 5 * high, "p0 = 0.97: {low}, p0 = 0.999: {high}");
}

#[test]
fn split_merge_splits_and_merges_basic_never_does_fig_9() {
    let (mut splits, mut merges) = (0, 0);
    for seed in SEEDS {
        let e = split_merge(300, seed).events();
        assert!(e.splits >= 1 && e.merges >= 1, "seed {seed}: {e:?}");
        splits += e.splits;
        merges += e.merges;
        for (p0, p1) in [
            (0.99, 1.0),
            (0.99, 0.9),
            (0.97, 0.9),
            (1.0, 0.5),
            (0.97, 0.5),
        ] {
            let e = basic(p0, p1, 300, seed).events();
            assert_eq!((e.splits, e.merges), (0, 0), "basic {p0} {p1} seed {seed}");
        }
    }
    assert!(
        splits >= 80 && merges >= 20,
        "{splits} splits, {merges} merges"
    );
}

#[test]
fn the_same_seed_gives_the_same_cells_on_every_machine() {
    // pinned: a different platform, float library or generator would change these
    let bits = |p: &Pattern| -> String {
        let s: String = p
            .cell
            .iter()
            .map(|c| if c.filled() { '1' } else { '0' })
            .collect();
        let d = Sha256::digest(s.as_bytes());
        d.iter().map(|b| format!("{b:02x}")).collect()
    };
    let sm = split_merge(300, 7);
    assert_eq!(sm, split_merge(300, 7));
    let e = sm.events();
    let noisy = Automaton {
        initial: Initial::Random { noise: 0.1 },
        ..basic_model(0.97, 0.9, 150, 7)
    }
    .run();
    let got = (bits(&sm), e.splits, e.merges, e.extinctions, bits(&noisy));
    let want = (
        "bc6baef777a9c25f7232bb4b84d75edb1ebb882b50b043d8502c0be50d1da195".to_string(),
        18,
        4,
        64,
        "b3e2b6183e4330119a458782f76210f1f6c5005314810a3ee36dc0a56c8364b1".to_string(),
    );
    assert_eq!(got, want);
}

/// Fig. 11a's "layered-circle-based (non-helical) algorithm": one ring per
/// layer, cell (l, j) stacked on (l − 1, j) or (l − 1, j + 1 mod N).
fn layered(p0: f64, p1: f64, layers: u32, seed: u64) -> Automaton {
    Automaton {
        layout: Layout::Layers,
        ..basic_model(p0, p1, layers, seed)
    }
}

#[test]
fn layered_circles_close_each_ring_on_itself_fig_11a() {
    for seed in SEEDS {
        let p = layered(0.99, 1.0, 150, seed).run();
        let at = |l: usize, j: usize| p.filled(l * N + j % N);
        // every chunk stands on one in the ring below, across the seam too
        for l in 1..150 {
            for j in 0..N {
                assert!(
                    !at(l, j) || at(l - 1, j) || at(l - 1, j + 1),
                    "seed {seed}: ({l}, {j})"
                );
            }
        }
        // p1 = 1 on the helix: crisp stripes, every turn the one below
        // shifted one cell, from turn 5 on (Fig. 6b). On layered circles the
        // same rule leaves most layers the one below turned one cell in its
        // ring, but a layer's seam, where the store runs on from the end of
        // one ring to the start of the next, keeps launching waves: a
        // disturbance from column 0 along the layer (Fig. 11a, "waves by
        // simulation using the original algorithm")
        let helix = basic(0.99, 1.0, 150, seed);
        assert!(
            steady_from(&helix, 1).is_some_and(|f| f <= 5),
            "seed {seed}"
        );
        let mut waves = 0;
        for l in 5..150 {
            let moved: Vec<usize> = (0..N).filter(|&j| at(l, j) != at(l - 1, j + 1)).collect();
            if !moved.is_empty() {
                waves += 1;
                // it starts at the seam: within one chunk spacing (1/e1
                // cells) of column 0, or the ring's last cell alone
                assert!(
                    moved[0] < 4 || moved == [N - 1],
                    "seed {seed}, layer {l}: {moved:?}"
                );
            }
        }
        assert!(waves >= 145 / 10, "seed {seed}: {waves} layers with a wave");
        assert_eq!(helix.events().extinctions, 0, "seed {seed}");
    }
}

#[test]
fn layered_circles_print_flat_rings_joined_by_a_layer_change() {
    let (radius, h, layers) = (20.0, 0.2, 12u32);
    let ca = CaHelix {
        radius,
        layer_height: h,
        center: glam::DVec3::new(0.0, 0.0, h),
        model: layered(1.0, 0.5, layers, 3),
    };
    let pattern = ca.model.run();
    let t = ca.toolpath(&pattern, 0.15, 30.0);
    let l = layers as usize;
    assert_eq!(t.strings.len() as u64, ca.string_count());
    assert_eq!(t.strings.len(), N * l + l - 1);
    let mut k = 0;
    for layer in 0..l {
        if layer > 0 {
            // straight up by one layer height, not extruding
            let (a, b) = (t.points[k], t.points[k + 1]);
            assert!(t.strings[k].travel, "layer {layer}");
            assert!(
                (b.z - a.z - h).abs() < 1e-12
                    && (b.x - a.x).abs() < 1e-12
                    && (b.y - a.y).abs() < 1e-12
            );
            k += 1;
        }
        let z = h + h * layer as f64;
        for j in 0..N {
            let (a, b) = (t.points[k], t.points[k + 1]);
            assert!(
                (a.z - z).abs() < 1e-12 && (b.z - z).abs() < 1e-12,
                "layer {layer} cell {j}: {a} {b}"
            );
            assert!((a.truncate().length() - radius).abs() < 1e-9);
            assert_eq!(
                !t.strings[k].travel,
                pattern.filled(layer * N + j),
                "layer {layer} cell {j}"
            );
            k += 1;
        }
    }
    // the layer ends where it began: a closed ring
    assert!((t.points[N].truncate() - t.points[0].truncate()).length() < 1e-9);
}

fn load(name: &str, sets: &[(&str, &str)]) -> Recipe {
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    crate::recipe::load(&recipe(name), &sets, None).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn ca_of(r: &Recipe) -> CaHelix {
    match &r.parts[0].primitive {
        Primitive::CaHelix(h) => *h,
        p => panic!("not a ca_helix: {p:?}"),
    }
}

#[test]
fn recipes_carry_the_papers_parameter_sets() {
    let h = ca_of(&load("ca-stripes.yaml", &[]));
    let m = h.model;
    assert_eq!(
        (m.cells, m.rule, m.initial),
        (288, Rule::Basic, Initial::Ones)
    );
    assert!(m.p0 < 1.0 && m.p0 >= 0.99 && m.p1 == 1.0, "Fig. 6b: {m:?}");
    let m = ca_of(&load("ca-stripes.yaml", &[("p1", "0.9")])).model;
    assert!(m.p1 < 1.0, "Fig. 6a");
    let m = ca_of(&load("ca-stripes.yaml", &[("p0", "1"), ("p1", "0.5")])).model;
    assert_eq!((m.p0, m.p1), (1.0, 0.5), "Fig. 6c");

    let m = ca_of(&load("ca-extinction.yaml", &[])).model;
    assert_eq!((m.cells, m.rule, m.p0), (288, Rule::Basic, 0.97), "Fig. 7b");
    assert!(m.p1 < 1.0);

    let m = ca_of(&load("ca-split-merge.yaml", &[])).model;
    assert_eq!((m.cells, m.rule), (288, Rule::SplitMerge), "Fig. 9");
    assert!(m.consume > 0.0 && m.consume < 1.0 && m.layers >= 200);
    let e = m.run().events();
    assert!(e.splits > 0 && e.merges > 0, "{e:?}");

    // the print: section 2 and Fig. 3a
    let r = load("self-organised-stripes.yaml", &[]);
    let Primitive::PatternHelix(p) = r.parts[0].primitive else {
        panic!("not a pattern_helix")
    };
    assert_eq!((p.segments, p.layer_height), (72, 0.3));
    assert_eq!((p.cross_section, p.speed), (Some(0.045), Some(60.0)));
    assert!(p.first_layer.cross_section > 0.1 && p.first_layer.speed < p.speed.unwrap());
    assert_eq!(r.material.name, "pla");
}

#[test]
fn pattern_helix_is_constant_after_the_first_turn() {
    let r = load("self-organised-stripes.yaml", &[]);
    let Primitive::PatternHelix(p): Primitive = r.parts[0].primitive.clone() else {
        panic!()
    };
    let PatternHelix {
        segments,
        layers,
        layer_height,
        ..
    } = p;
    let seg = segments as usize;
    let t = make_part(&r, 0).unwrap();
    assert_eq!(t.len(), layers as usize * seg);
    let first = t.strings[0];
    let after = t.strings[seg];
    assert_ne!((first.c, first.v), (after.c, after.v));
    for (k, s) in t.strings.iter().enumerate() {
        assert!(!s.travel);
        let want = if k < seg { first } else { after };
        assert!(s.c == want.c && s.v == want.v, "string {k}: {s:?}");
    }
    // segments strings a turn: point k + segments straight above point k,
    // one layer height higher
    for k in 0..t.len() + 1 - seg {
        let (a, b) = (t.points[k], t.points[k + seg]);
        assert!(a.x == b.x && a.y == b.y, "point {k}");
        assert!((b.z - a.z - layer_height).abs() < 1e-9, "point {k}");
    }
    // …and no point of a turn is straight above an earlier point of it
    for k in 1..seg {
        assert!(t.points[k].truncate().distance(t.points[0].truncate()) > 1.0);
    }
}

/// Pixels of a PNG, rows top to bottom.
fn png(path: &Path) -> image::GrayImage {
    image::open(path).unwrap().to_luma8()
}

#[test]
fn build_draws_the_pattern_in_gcode_and_png() {
    for (name, layers) in [
        ("ca-stripes.yaml", 150),
        ("ca-extinction.yaml", 150),
        ("ca-split-merge.yaml", 300),
    ] {
        let dir = tmp(&format!("ca-build-{name}"));
        let out = p3dp(
            &dir,
            &[
                "build",
                recipe(name).to_str().unwrap(),
                "-o",
                "c.gcode",
                "--pattern",
                "pics/c.png",
            ],
        );
        assert!(out.success(), "{name}: {}", out.stderr);
        let img = png(&dir.join("pics/c.png"));
        assert_eq!(img.dimensions(), (N as u32, layers), "{name}");
        // the cells, first turn first, from the image (first turn at the bottom)
        let cells: Vec<bool> = (0..layers)
            .rev()
            .flat_map(|y| (0..N as u32).map(move |x| (x, y)))
            .map(|(x, y)| img.get_pixel(x, y).0[0] < 128)
            .collect();
        assert!(
            cells[..N].iter().all(|&c| c),
            "{name}: the filled first turn"
        );
        let cells_of_lib = ca_of(&load(name, &[])).model.run();
        assert!(cells
            .iter()
            .enumerate()
            .all(|(i, &c)| c == cells_of_lib.filled(i)));
        // the G-code: after the travel to the start, one move per cell, an
        // extruding G1 for a filled one and a G0 for an empty one
        let g = parse(&std::fs::read_to_string(dir.join("c.gcode")).unwrap());
        let part = g.parts.len() - 1;
        let moves: Vec<_> = g.moves.iter().filter(|m| m.part == part).collect();
        // the travel to the first cell's start (radius 20, one layer up)
        assert_eq!(moves[0].to, [130.0, 110.0, 0.2], "{name}");
        let moves = &moves[1..=cells.len()];
        for (i, (m, &c)) in moves.iter().zip(&cells).enumerate() {
            assert_eq!(
                (m.g == 1 && m.de > 0.0, m.g == 0),
                (c, !c),
                "{name}: cell {i}"
            );
        }
    }
}
