//! `ca_helix`: Kanada's cellular-automaton model of self-organised printing
//! ("Self-organized 3D-printing Patterns Simulated by Cellular Automata",
//! sections 3 and 4), written as G-code so that a viewer shows the pattern.
//!
//! **The model** (section 3.1, Figs. 4 and 5). The helix is cut into N arcs per
//! turn (the paper's N = 4 × 72 = 288): the cells of a one-dimensional
//! asynchronous automaton that grows upwards. One array holds every layer, as
//! Fig. 5's algorithm keeps it: cell `i` lies one turn above cell `i − N`, and
//! its neighbour below in the direction of the head is `i − N + 1`, so the
//! layers join without a seam exactly as the helix does. The cells of the first
//! turn are the initial layer (all ones, or with random zeros: Fig. 11b); then
//! cells are decided one at a time, in the order the head passes them. Each
//! step extrudes `e1` (0 < e1 < 1) of filament into a store, and a cell can be
//! filled only when the store holds at least 1:
//!
//! ```text
//! basic (Fig. 5):                       split_merge (section 4.2, Fig. 9a):
//! if cell[i-N]   and u < p0: fill, 0     if cell[i-N-1] and u < p1: fill, store = 0
//! elif cell[i-N+1] and u < p1: fill, 0   elif cell[i-N+1] and u < p1: fill, store = 0
//! else empty                             elif cell[i-N] and u < p0: fill, store -= C
//!                                        else empty
//! store += e1 after every cell
//! ```
//!
//! As in Fig. 5's `cell[i-N] > 0 and random() <= p0 or …`, a failed draw falls
//! through to the next condition, and a number is drawn only when the cell it
//! is about is filled. `u < p` with u in [0, 1) stands for the paper's
//! `random() <= p` (they differ only when u = p exactly, and `<` makes p = 0
//! never and p = 1 always true). The store starts empty, so the first chunk of
//! turn 1 is at cell 1/e1 (4 for e1 = 0.3), not 0, which leaves one gap of
//! two chunk spacings in that turn.
//!
//! The paper's section 3.2 and Figs. 6 and 7, as this model gives them:
//! p1 = 1 gives crisp stripes leaning one cell per layer (6b): once a chunk
//! stands on its neighbour the next one is ready just before the next stripe,
//! stacks on it too, and p0 is never consulted again. p1 < 1 gives noisy
//! stripes (6a), runs of straight and leaning chunks. p0 = 1 with p1 < 1 gives
//! vertical stripes (6c), exactly so for p1 = 0; for p1 > 0 the gap of turn 1
//! is a defect wandering through them (the waves of Fig. 11). A smaller p0
//! (0.97) lets stripes die out when p1 < 1 too (7b). Chunks of the basic rule
//! lie at least 1/e1 cells apart, so for e1 < 1/2 it never splits or merges a
//! stripe; split_merge, by stacking on i − 1 too and keeping 1 − C of the
//! store after a straight stack, does both (Fig. 9b).
//!
//! **Layered circles** (`layout: layers`, Fig. 11a, "the layered-circle-based
//! (non-helical) algorithm in the previous study"): each turn is a flat ring
//! and a layer change (a travel straight up) joins them; cell (l, j) stands on
//! (l − 1, j ± 1 mod N) of the ring below, while the store runs on from one
//! ring into the next. The seam then keeps launching waves along the layer,
//! the edges that made the paper print a helix (section 2).
//!
//! **Randomness** comes from SplitMix64 (Steele, Lea and Flood 2014): integer
//! arithmetic only, uniforms made from the top 53 bits, so a seed gives the
//! same pattern, and the same G-code, on every machine.
//!
//! **Output**: a filled cell is an extruded arc, an empty one a travel move;
//! `p3dp build --pattern FILE.png` writes the cell array as an image.

use glam::DVec3;

use super::on_circle;
use crate::base::error::{Error, Result};
use crate::base::rng::SplitMix64;
use crate::base::toolpath::Toolpath;

/// Which of the paper's rules decides a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rule {
    /// Fig. 5: straight up at p0, else on the next cell (i + 1) at p1.
    Basic,
    /// Section 4.2: on i − 1, else on i + 1 at p1, else straight up at p0 using C.
    SplitMerge,
}

/// How the cells' turns are laid out: one helix, or one circle per layer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Layout {
    /// One helix, the paper's method (section 2): a cell's neighbours below
    /// run on across the seam into the turn being printed.
    #[default]
    Helix,
    /// Layered circles with a layer change, the "layered-circle-based
    /// (non-helical) algorithm in the previous study" of Fig. 11a: each
    /// layer is a ring of its own, so its neighbours below wrap round in the
    /// layer below.
    Layers,
}

/// The first turn of the automaton.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Initial {
    /// All filled.
    Ones,
    /// Each cell empty with probability `noise`.
    Random {
        /// Fraction of zeros, 0 to 1.
        noise: f64,
    },
}

/// What one cell holds: empty, or filled and on what it was stacked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub(crate) enum Cell {
    /// No chunk: the head travels.
    Empty,
    /// Filled as part of the initial layer.
    Initial,
    /// Stacked straight up, on cell i − N.
    Below,
    /// Stacked on the next cell below, i − N + 1 (ahead of the head).
    Next,
    /// Stacked on the previous cell below, i − N − 1 (split_merge only).
    Prev,
}

impl Cell {
    /// Whether the cell holds a chunk.
    pub(crate) fn filled(self) -> bool {
        self != Cell::Empty
    }
}

/// The automaton's parameters (section 3.1, Fig. 5; section 4.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Automaton {
    /// Cells (arcs) per turn, the paper's N.
    pub(crate) cells: u32,
    /// Turns, the initial one included.
    pub(crate) layers: u32,
    /// Basic or split-and-merge.
    pub(crate) rule: Rule,
    /// A helix or layered circles.
    pub(crate) layout: Layout,
    /// Probability of stacking straight up.
    pub(crate) p0: f64,
    /// Probability of stacking on a neighbour below.
    pub(crate) p1: f64,
    /// C: filament used by a straight stack (split_merge), 0 < C < 1.
    pub(crate) consume: f64,
    /// Filament extruded per cell step, 0 < e1 < 1.
    pub(crate) e1: f64,
    /// The first turn.
    pub(crate) initial: Initial,
    /// Seed of the generator.
    pub(crate) seed: u64,
}

/// Split, merge and extinction counts of a pattern (see [`Pattern::events`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg(test)]
pub(crate) struct Events {
    /// A stripe piece touching two or more separate pieces above it (each extra one counts).
    pub(crate) splits: usize,
    /// A stripe piece touching two or more separate pieces below it (each extra one counts).
    pub(crate) merges: usize,
    /// A stripe piece with nothing above it (below the top turn).
    pub(crate) extinctions: usize,
}

/// The cell array: `layers` turns of `cells` cells, turn 0 first.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Pattern {
    /// Cells per turn.
    pub(crate) cells: usize,
    /// Turns.
    pub(crate) layers: usize,
    /// Cell i is at position i mod cells of turn i / cells.
    pub(crate) cell: Vec<Cell>,
}

impl Automaton {
    /// Cells in all (= strings of the G-code).
    pub(crate) fn len(&self) -> u64 {
        self.cells as u64 * self.layers as u64
    }

    /// Runs Fig. 5's loop (or section 4.2's rule) over the whole helix.
    pub(crate) fn run(&self) -> Pattern {
        let n = self.cells as usize;
        let total = self.len() as usize;
        let mut rng = SplitMix64::new(self.seed);
        let mut cell = vec![Cell::Empty; total];
        for c in cell.iter_mut().take(n) {
            *c = match self.initial {
                Initial::Ones => Cell::Initial,
                Initial::Random { noise } if rng.chance(noise) => Cell::Empty,
                Initial::Random { .. } => Cell::Initial,
            };
        }
        // the store of extruded filament; IEEE sums, the same everywhere
        let mut store = 0.0f64;
        for i in n..total {
            if store >= 1.0 {
                let below = cell[i - n].filled();
                let (next, prev) = match self.layout {
                    // one array, as Fig. 5 keeps it: the cell ahead of the
                    // last one of a turn is the first of this turn, and the
                    // helix has no cell before its first one
                    Layout::Helix => (cell[i - n + 1].filled(), i > n && cell[i - n - 1].filled()),
                    // cell (l, j) stands on (l − 1, j ± 1 mod N): the ring of
                    // the layer below closes on itself
                    Layout::Layers => {
                        let (row, j) = (i - n - i % n, i % n);
                        (
                            cell[row + (j + 1) % n].filled(),
                            cell[row + (j + n - 1) % n].filled(),
                        )
                    }
                };
                match self.rule {
                    Rule::Basic => {
                        if below && rng.chance(self.p0) {
                            cell[i] = Cell::Below;
                            store = 0.0;
                        } else if next && rng.chance(self.p1) {
                            cell[i] = Cell::Next;
                            store = 0.0;
                        }
                    }
                    Rule::SplitMerge => {
                        if prev && rng.chance(self.p1) {
                            cell[i] = Cell::Prev;
                            store = 0.0;
                        } else if next && rng.chance(self.p1) {
                            cell[i] = Cell::Next;
                            store = 0.0;
                        } else if below && rng.chance(self.p0) {
                            cell[i] = Cell::Below;
                            store -= self.consume;
                        }
                    }
                }
            }
            store += self.e1;
        }
        Pattern {
            cells: n,
            layers: self.layers as usize,
            cell,
        }
    }
}

impl Pattern {
    /// Whether cell `i` holds a chunk.
    #[cfg(test)]
    pub(crate) fn filled(&self, i: usize) -> bool {
        self.cell[i].filled()
    }

    /// The cells of turn `l`.
    pub(crate) fn row(&self, l: usize) -> &[Cell] {
        &self.cell[l * self.cells..(l + 1) * self.cells]
    }

    /// Counts splits, merges and extinctions of stripes, as an eye sees them.
    ///
    /// A stripe piece is a run of consecutive filled cells along the helix;
    /// two pieces touch when a cell of one lies on a cell of the other
    /// (i − N − 1, i − N or i − N + 1: the eight-neighbourhood of the wall).
    /// A piece touching k > 1 pieces above it is k − 1 splits, one touching
    /// k > 1 pieces below it k − 1 merges, one touching none above it an
    /// extinction. Pieces of the initial turn are the ground, not stripes:
    /// they split, merge and end nothing. Pieces within one turn of the top
    /// are not counted as extinct.
    ///
    /// With e1 < 1/2 two chunks of the basic rule are at least three cells
    /// apart, so each stands on one chunk only: the basic rule gives no
    /// splits and no merges, only extinctions (the paper: "the original
    /// algorithm … never generates such patterns").
    #[cfg(test)]
    pub(crate) fn events(&self) -> Events {
        let n = self.cells;
        let total = self.cell.len();
        let mut run = vec![u32::MAX; total];
        let mut runs: Vec<(usize, usize)> = Vec::new();
        let mut i = 0;
        while i < total {
            if self.filled(i) {
                let start = i;
                while i < total && self.filled(i) {
                    run[i] = runs.len() as u32;
                    i += 1;
                }
                runs.push((start, i));
            } else {
                i += 1;
            }
        }
        let mut links: Vec<(u32, u32)> = Vec::new();
        for i in n + 1..total {
            if !self.filled(i) {
                continue;
            }
            for j in [i - n - 1, i - n, i - n + 1] {
                // chunks on the initial turn stand on the ground
                if j >= n && self.filled(j) && run[j] != run[i] {
                    links.push((run[j], run[i]));
                }
            }
        }
        links.sort_unstable();
        links.dedup();
        let mut above = vec![0usize; runs.len()];
        let mut below = vec![0usize; runs.len()];
        for &(lo, hi) in &links {
            above[lo as usize] += 1;
            below[hi as usize] += 1;
        }
        let mut ev = Events::default();
        for (k, &(start, end)) in runs.iter().enumerate() {
            if start < n {
                continue;
            }
            ev.splits += above[k].saturating_sub(1);
            ev.merges += below[k].saturating_sub(1);
            if above[k] == 0 && end + n < total {
                ev.extinctions += 1;
            }
        }
        ev
    }

    /// The cell array as a grey PNG: one row per turn, the first turn at the
    /// bottom (as the wall stands), cell 0 on the left (the head runs
    /// counter-clockwise seen from above, so left to right seen from outside);
    /// filled cells black, empty ones white. Errors have no place (the caller
    /// names the option).
    pub(crate) fn to_png(&self) -> Result<Vec<u8>> {
        let mut px = Vec::with_capacity(self.cell.len());
        for l in (0..self.layers).rev() {
            px.extend(
                self.row(l)
                    .iter()
                    .map(|c| if c.filled() { 0u8 } else { 255u8 }),
            );
        }
        let img = image::GrayImage::from_raw(self.cells as u32, self.layers as u32, px)
            .ok_or_else(|| Error::input("", "the cell array does not fit an image"))?;
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png)
            .map_err(|e| Error::input("", format!("cannot encode the PNG: {e}")))?;
        Ok(out.into_inner())
    }
}

/// A helix of `model.layers` turns whose arcs are the automaton's cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CaHelix {
    /// Radius, mm.
    pub(crate) radius: f64,
    /// Rise per turn, mm.
    pub(crate) layer_height: f64,
    /// Centre; the first cell starts at height `center.z`.
    pub(crate) center: DVec3,
    /// The automaton.
    pub(crate) model: Automaton,
}

impl CaHelix {
    /// One string per cell (turns × cells per turn), and for layered
    /// circles one layer change between layers.
    pub(crate) fn string_count(&self) -> u64 {
        match self.model.layout {
            Layout::Helix => self.model.len(),
            Layout::Layers => self.model.len() + self.model.layers as u64 - 1,
        }
    }

    /// Runs the automaton; filled cells become arcs extruded at `c` and `v`,
    /// empty ones travel moves, so that the G-code draws the pattern.
    pub(crate) fn build(&self, c: f64, v: f64) -> Toolpath {
        self.toolpath(&self.model.run(), c, v)
    }

    /// The toolpath of an already computed pattern.
    pub(crate) fn toolpath(&self, pattern: &Pattern, c: f64, v: f64) -> Toolpath {
        let n = self.model.cells;
        let layered = self.model.layout == Layout::Layers;
        // the end of cell k − 1: on a helix it rises with every cell; on
        // layered circles it stays at its layer's height, cell (l, N − 1)
        // ending back at angle 0 of layer l
        let at = |k: u64| {
            let (x, y) = on_circle(self.radius, k, n);
            let z = if layered {
                self.layer_height * ((k.max(1) - 1) / n as u64) as f64
            } else {
                self.layer_height * k as f64 / n as f64
            };
            self.center + DVec3::new(x, y, z)
        };
        let mut t = Toolpath::with_capacity(at(0), self.string_count() as usize);
        for (i, cell) in pattern.cell.iter().enumerate() {
            if layered && i > 0 && i % n as usize == 0 {
                // the layer change: straight up, not extruding
                let (here, layer) = (at(i as u64), at(i as u64 + 1).z);
                t.travel(here.with_z(layer), v);
            }
            let p = at(i as u64 + 1);
            if cell.filled() {
                t.draw(p, c, v);
            } else {
                t.travel(p, v);
            }
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(rule: Rule, p0: f64, p1: f64) -> Automaton {
        Automaton {
            cells: 288,
            layers: 150,
            rule,
            layout: Layout::Helix,
            p0,
            p1,
            consume: 0.7,
            e1: 0.3,
            initial: Initial::Ones,
            seed: 7,
        }
    }

    #[test]
    fn same_seed_same_pattern_other_seed_other_pattern() {
        let m = model(Rule::Basic, 0.97, 0.9);
        assert_eq!(m.run(), m.run());
        assert_ne!(m.run(), Automaton { seed: 8, ..m }.run());
    }

    #[test]
    fn fig5_first_layers_by_hand() {
        // e1 = 0.3: the store reaches 1 every fourth cell; it starts at 0, so
        // the first chunk of turn 1 is at cell 4 (0.3·4 = 1.2 ≥ 1).
        let p = Automaton {
            layers: 3,
            ..model(Rule::Basic, 1.0, 0.0)
        }
        .run();
        assert!(p.row(0).iter().all(|c| *c == Cell::Initial));
        let row1: Vec<usize> = (0..288).filter(|&k| p.row(1)[k].filled()).collect();
        assert_eq!(row1, (1..72).map(|k| 4 * k).collect::<Vec<_>>());
        assert!(p
            .row(1)
            .iter()
            .all(|c| matches!(c, Cell::Empty | Cell::Below)));
        // p0 = 1, p1 = 0: the next turn stacks on exactly the same cells
        assert_eq!(p.row(2), p.row(1));
    }

    #[test]
    fn basic_stacks_on_the_next_cell_never_the_previous() {
        let p = model(Rule::Basic, 0.97, 0.9).run();
        assert!(p.cell.contains(&Cell::Next));
        assert!(!p.cell.contains(&Cell::Prev));
        // every chunk stands on the cell it says
        for (i, c) in p.cell.iter().enumerate().skip(288) {
            match c {
                Cell::Below => assert!(p.filled(i - 288)),
                Cell::Next => assert!(p.filled(i - 287)),
                Cell::Empty => {}
                _ => panic!("cell {i} is {c:?}"),
            }
        }
    }

    #[test]
    fn split_merge_stacks_on_both_neighbours() {
        let p = model(Rule::SplitMerge, 0.99, 0.7).run();
        for kind in [Cell::Below, Cell::Next, Cell::Prev] {
            assert!(p.cell.contains(&kind), "{kind:?}");
        }
    }

    #[test]
    fn random_initial_layer_has_about_noise_zeros() {
        let m = Automaton {
            cells: 10_000,
            layers: 1,
            initial: Initial::Random { noise: 0.25 },
            ..model(Rule::Basic, 1.0, 1.0)
        };
        let zeros = m.run().cell.iter().filter(|c| !c.filled()).count();
        assert!((2300..2700).contains(&zeros), "{zeros}");
    }

    #[test]
    fn events_count_a_drawn_split_and_merge() {
        // N = 8; turn 1 is one chunk, turn 2 two chunks on either side of it,
        // turn 3 one chunk on both of those: one split, one merge.
        let mut cell = vec![Cell::Empty; 8 * 5];
        cell[..8].fill(Cell::Initial);
        cell[8 + 4] = Cell::Below;
        cell[16 + 3] = Cell::Next;
        cell[16 + 5] = Cell::Prev;
        cell[24 + 4] = Cell::Prev;
        let p = Pattern {
            cells: 8,
            layers: 5,
            cell,
        };
        let e = p.events();
        assert_eq!((e.splits, e.merges, e.extinctions), (1, 1, 1));
    }

    #[test]
    fn toolpath_draws_filled_cells_and_travels_over_empty_ones() {
        let h = CaHelix {
            radius: 20.0,
            layer_height: 0.2,
            center: DVec3::new(0.0, 0.0, 0.2),
            model: Automaton {
                layers: 10,
                ..model(Rule::Basic, 0.97, 0.9)
            },
        };
        let p = h.model.run();
        let t = h.build(0.15, 30.0);
        assert_eq!(t.len() as u64, h.string_count());
        for (k, s) in t.strings.iter().enumerate() {
            assert_eq!(s.travel, !p.filled(k));
        }
        assert_eq!(t.points[0], DVec3::new(20.0, 0.0, 0.2));
        // one turn later: straight above, one layer up
        let q = t.points[288];
        assert!(q.x == 20.0 && q.y == 0.0 && (q.z - 0.4).abs() < 1e-12);
    }

    #[test]
    fn png_has_one_row_per_turn_first_turn_at_the_bottom() {
        let p = Automaton {
            layers: 4,
            ..model(Rule::Basic, 1.0, 0.0)
        }
        .run();
        let png = p.to_png().unwrap();
        let img = image::load_from_memory(&png).unwrap().to_luma8();
        assert_eq!(img.dimensions(), (288, 4));
        for x in 0..288 {
            assert_eq!(img.get_pixel(x, 3).0[0], 0, "the full first turn");
            let filled = p.row(1)[x as usize].filled();
            assert_eq!(img.get_pixel(x, 2).0[0] == 0, filled);
        }
    }
}
