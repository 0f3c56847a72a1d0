//! The strokes of a scene's strings: merged runs, each as wide as the flat
//! tube its passes make (see [`super::super`]), shaded and coloured.

use glam::DVec3;

use super::raster::Px;
use super::{Frame, FILAMENT, GREY, RED};
use crate::base::geom::passes::{round_diameter, Grid};
use crate::base::par;
use crate::output::preview::{colormap, Basis, ColorMode, Scene, View};

/// Strings shorter than this on screen are merged with their neighbours, px.
pub(super) const MERGE_PX: f64 = 2.0;
/// The thinnest the preview draws a string, px.
const MIN_PX: f32 = 0.75;
/// When following the neighbouring pass from stroke to stroke
/// ([`Grid::follow_other`]), every this many strokes search it in full.
const REFRESH: usize = 32;

/// One stroke to paint.
#[derive(Clone, Copy, Default)]
pub(super) struct Item {
    pub(super) a: (f32, f32),
    pub(super) b: (f32, f32),
    pub(super) depth: f64,
    /// The number the colour shows (scalar modes).
    pub(super) value: f64,
    /// Diffuse and highlight terms of its shading ([`shade`]).
    pub(super) diffuse: f64,
    pub(super) spec: f64,
    pub(super) width: f32,
    /// 0: lit string; 1: travel (faint, unlit); 2: flagged (lit, brighter).
    pub(super) kind: u8,
    /// The path it belongs to.
    pub(super) path: u32,
}

/// The strings of a scene made ready to paint into a rectangle of an image:
/// the projection, each path's grid of strings, and the pieces of work that
/// collect the strokes ([`Model::strokes`]).
pub(super) struct Model<'s, 'p> {
    scene: &'s Scene<'p>,
    pub(super) frame: Frame,
    mode: ColorMode,
    light: DVec3,
    /// The box of the extruding points, recipe coordinates.
    pub(super) bbox: (DVec3, DVec3),
    /// Their lowest and highest depth.
    depths: (f64, f64),
    /// The lowest and highest screen-plane point (u, w) of the extruding
    /// points ([`Frame::fit_box`]'s).
    pub(super) screen: ((f64, f64), (f64, f64)),
    /// Per path, its strings in a grid (to find the neighbouring pass);
    /// none with [`Passes::Round`].
    grids: Vec<Grid<'p>>,
    /// (path, first string, end) of each piece.
    pieces: Vec<(usize, usize, usize)>,
    /// Whether a stroke's neighbouring pass is looked for (followed from
    /// the last stroke's, [`Grid::follow_other`]); else every lit stroke is
    /// a round tube.
    neighbours: bool,
}

/// What a model's points span: on the screen plane (u, w), in depth, and
/// in recipe coordinates; and whether any string extrudes.
#[derive(Clone, Copy)]
struct Reach {
    lo2: (f64, f64),
    hi2: (f64, f64),
    depths: (f64, f64),
    lo: DVec3,
    hi: DVec3,
    any: bool,
}

impl Reach {
    const EMPTY: Reach = Reach {
        lo2: (f64::INFINITY, f64::INFINITY),
        hi2: (f64::NEG_INFINITY, f64::NEG_INFINITY),
        depths: (f64::INFINITY, f64::NEG_INFINITY),
        lo: DVec3::INFINITY,
        hi: DVec3::NEG_INFINITY,
        any: false,
    };

    /// The points of path `tp` that end its extruding strings `k0..k1`
    /// (the finite ones).
    fn of_piece(basis: Basis, tp: &crate::base::toolpath::Toolpath, k0: usize, k1: usize) -> Reach {
        let mut r = Reach::EMPTY;
        for k in k0..k1 {
            if tp.strings[k].travel {
                continue;
            }
            r.any = true;
            for p in [tp.points[k], tp.points[k + 1]] {
                if p.is_finite() {
                    r.add(basis, p);
                }
            }
        }
        r
    }

    /// Takes finite point `p` in.
    fn add(&mut self, basis: Basis, p: DVec3) {
        // a plain comparison is f64::min's and max's result for a finite x
        let low = |a: &mut f64, x: f64| *a = if x < *a { x } else { *a };
        let high = |a: &mut f64, x: f64| *a = if x > *a { x } else { *a };
        let (u, w, d) = basis.project(p);
        low(&mut self.lo2.0, u);
        low(&mut self.lo2.1, w);
        high(&mut self.hi2.0, u);
        high(&mut self.hi2.1, w);
        low(&mut self.depths.0, d);
        high(&mut self.depths.1, d);
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    /// Both spans in one.
    fn join(a: Reach, b: Reach) -> Reach {
        Reach {
            lo2: (a.lo2.0.min(b.lo2.0), a.lo2.1.min(b.lo2.1)),
            hi2: (a.hi2.0.max(b.hi2.0), a.hi2.1.max(b.hi2.1)),
            depths: (a.depths.0.min(b.depths.0), a.depths.1.max(b.depths.1)),
            lo: a.lo.min(b.lo),
            hi: a.hi.max(b.hi),
            any: a.any || b.any,
        }
    }
}

/// How wide a lit stroke is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Passes {
    /// As wide as the flat tube its neighbouring pass makes it, that pass
    /// followed from the last stroke's (the PNG preview).
    Followed,
    /// A round tube, no neighbouring pass looked for: a cost that does not
    /// grow with how many passes lie in one place (a line retraced 600 000
    /// times took minutes), for the G-code's thumbnails, drawn on every
    /// build.
    Round,
}

/// A run of strings of one path drawn as one stroke: strings `first..end`,
/// alike (travel or not, flagged or not), with their cross-section and
/// colour value weighted by length.
struct Run {
    first: usize,
    end: usize,
    c: f64,
    v: f64,
    travel: bool,
    flagged: bool,
}

/// Where a piece's search for the neighbouring pass stands: the neighbour
/// found for the last stroke (its first string, the neighbour's string),
/// near which the next one's lies; and how many lit strokes were searched.
#[derive(Default)]
struct Follow {
    hint: Option<(usize, usize)>,
    lit: usize,
}

impl<'s, 'p> Model<'s, 'p> {
    /// Fits `scene` into `rect` seen from `view`; pieces of `piece` strings;
    /// each lit stroke as wide as its neighbouring passes make it
    /// ([`Passes::Followed`], each path's grid built in `parts`,
    /// [`Grid::for_surface_on`]) or a round tube ([`Passes::Round`]).
    pub(super) fn new(
        scene: &'s Scene<'p>,
        view: View,
        mode: ColorMode,
        rect: [f64; 4],
        piece: usize,
        passes: Passes,
        parts: usize,
    ) -> Model<'s, 'p> {
        let basis = view.basis();
        let mut pieces = Vec::new();
        for (pi, tp) in scene.plan.paths.iter().enumerate() {
            let mut k = 0;
            while k < tp.len() {
                let end = k.saturating_add(piece).min(tp.len());
                pieces.push((pi, k, end));
                k = end;
            }
        }
        // what the extruding points span, piece by piece over the pool (a
        // lowest and a highest are the same whatever order they are found
        // in); every finite point's when nothing extrudes
        let reach = par::map(&pieces, |&(pi, k0, k1)| {
            Reach::of_piece(basis, &scene.plan.paths[pi], k0, k1)
        })
        .into_iter()
        .fold(Reach::EMPTY, Reach::join);
        let reach = if reach.any {
            reach
        } else {
            let mut all = Reach::EMPTY;
            for tp in &scene.plan.paths {
                for p in tp.points.iter().filter(|p| p.is_finite()) {
                    all.add(basis, *p);
                }
            }
            all
        };
        let Reach {
            lo2,
            hi2,
            depths,
            lo,
            hi,
            ..
        } = reach;
        let frame = Frame::fit_box(basis, lo2, hi2, rect, scene.pad());
        let neighbours = passes == Passes::Followed;
        let grids: Vec<Grid> = if neighbours {
            scene
                .plan
                .paths
                .iter()
                .zip(&scene.spacing)
                .map(|(tp, &h)| Grid::for_surface_on(&tp.points, h, parts))
                .collect()
        } else {
            Vec::new()
        };
        Model {
            scene,
            frame,
            mode,
            // the light comes from the upper left, in front: fixed to the view
            light: (-0.6 * basis.right + 0.5 * basis.up + 0.6 * basis.toward).normalize(),
            bbox: (lo, hi),
            screen: (lo2, hi2),
            depths,
            grids,
            pieces,
            neighbours,
        }
    }

    /// `f` of every stroke, in print order, in one vector. The pieces'
    /// strokes are counted first ([`Model::count`]: no neighbour searched),
    /// so that each piece writes its own into its share of the vector, the
    /// pieces taken by the pool's threads ([`par::each`]). A piece's strokes
    /// follow from its strings alone (merged runs end at its end), so they
    /// are the same however the pieces are shared out.
    pub(super) fn strokes<T>(&self, f: impl Fn(&Item) -> T + Sync + Send) -> Vec<T>
    where
        T: Copy + Default + Send,
    {
        // each piece's runs found once: their ends, then how many strokes
        let ends = par::map(&self.pieces, |&(pi, k0, k1)| self.run_ends(pi, k0, k1));
        let counts: Vec<usize> = self
            .pieces
            .iter()
            .zip(&ends)
            .map(|(&(pi, k0, _), e)| self.count(pi, k0, e))
            .collect();
        let mut out = vec![T::default(); counts.iter().sum()];
        let mut shares = Vec::with_capacity(self.pieces.len());
        let mut rest = out.as_mut_slice();
        for ((&piece, &n), e) in self.pieces.iter().zip(&counts).zip(&ends) {
            let (share, tail) = rest.split_at_mut(n);
            shares.push((piece, e, share));
            rest = tail;
        }
        par::each(&mut shares, |((pi, k0, _), ends, share)| {
            let mut n = 0;
            self.collect(*pi, *k0, ends, |item| {
                share[n] = f(&item);
                n += 1;
            });
        });
        out
    }

    /// The ends of the runs [`Model::collect`] makes of strings `k0..k1`
    /// of path `pi` ([`Model::run_end`]), each less `k0`.
    fn run_ends(&self, pi: usize, k0: usize, k1: usize) -> Vec<u32> {
        let mut ends = Vec::new();
        let mut k = k0;
        while k < k1 {
            k = self.run_end(pi, k, k1);
            ends.push(u32::try_from(k - k0).expect("a piece's strings number below 2³²"));
        }
        ends
    }

    /// How many strokes [`Model::collect`] makes of the runs of path `pi`
    /// from string `k0` that end at `ends` (less `k0`): those whose ends
    /// are finite.
    fn count(&self, pi: usize, k0: usize, ends: &[u32]) -> usize {
        let tp = &self.scene.plan.paths[pi];
        let mut first = k0;
        let mut n = 0;
        for &e in ends {
            let end = k0 + e as usize;
            n += usize::from(tp.points[first].is_finite() && tp.points[end].is_finite());
            first = end;
        }
        n
    }

    /// The strokes of the runs of path `pi` from string `k0` that end at
    /// `ends` (less `k0`, as [`Model::run_ends`] finds them), in order,
    /// passed to `emit`: runs shorter than [`MERGE_PX`] on screen become
    /// one stroke ([`Model::run`]), so that the strokes number about the
    /// path's length on screen over [`MERGE_PX`] at most, however many
    /// strings it has; a run with an end that is not finite is left out.
    fn collect(&self, pi: usize, k0: usize, ends: &[u32], mut emit: impl FnMut(Item)) {
        let tp = &self.scene.plan.paths[pi];
        let mut follow = Follow::default();
        let mut k = k0;
        for &e in ends {
            let run = self.run(pi, k, k0 + e as usize);
            k = run.end;
            let (a, b) = (tp.points[run.first], tp.points[run.end]);
            if a.is_finite() && b.is_finite() {
                emit(self.stroke(pi, &run, a, b, &mut follow));
            }
        }
    }

    /// The end of the run of path `pi`'s strings from `k` (before `k1`)
    /// drawn as one stroke: strings alike to the first (travel or not,
    /// flagged or not), taken while the run is shorter than [`MERGE_PX`] on
    /// screen; at least one.
    fn run_end(&self, pi: usize, k: usize, k1: usize) -> usize {
        let scene = self.scene;
        let tp = &scene.plan.paths[pi];
        let start = tp.points[k];
        let (travel, flag) = (tp.strings[k].travel, scene.flagged[pi][k]);
        let mut end = k;
        while end < k1 && tp.strings[end].travel == travel && scene.flagged[pi][end] == flag {
            end += 1;
            if start.distance(tp.points[end]) * self.frame.scale >= MERGE_PX {
                break;
            }
        }
        end
    }

    /// The run of strings `k..end` ([`Model::run_end`]'s), its
    /// cross-section and value weighted by length.
    fn run(&self, pi: usize, k: usize, end: usize) -> Run {
        let (scene, mode) = (self.scene, self.mode);
        let tp = &scene.plan.paths[pi];
        let (mut len, mut csum, mut vsum) = (0.0, 0.0, 0.0);
        let valued = mode.has_value();
        for j in k..end {
            let l = tp.length(j);
            len += l;
            csum += tp.strings[j].c * l;
            if valued {
                vsum += scene.value(mode, pi, j) * l;
            }
        }
        let (c, v) = if len > 0.0 {
            (csum / len, vsum / len)
        } else {
            (tp.strings[k].c, scene.value(mode, pi, k))
        };
        Run {
            first: k,
            end,
            c,
            v,
            travel: tp.strings[k].travel,
            flagged: scene.flagged[pi][k],
        }
    }

    /// The stroke of `run` (of path `pi`) from `a` to `b`, its width and
    /// shading told by the surface it lies in.
    fn stroke(&self, pi: usize, run: &Run, a: DVec3, b: DVec3, follow: &mut Follow) -> Item {
        let frame = &self.frame;
        let tangent = (b - a).normalize_or_zero();
        let (width, (diffuse, spec)) = if run.travel {
            (0.0, (0.0, 0.0))
        } else {
            let (width, normal) = self.width(pi, run, a, b, tangent, follow);
            (width, shade(tangent, normal, self.light, frame.basis))
        };
        let pa = frame.pixel(a);
        let pb = frame.pixel(b);
        Item {
            a: (pa.0 as f32, pa.1 as f32),
            b: (pb.0 as f32, pb.1 as f32),
            depth: frame.basis.project((a + b) * 0.5).2,
            width: (width * frame.scale) as f32,
            value: run.v,
            diffuse,
            spec,
            kind: if run.travel {
                1
            } else if run.flagged {
                2
            } else {
                0
            },
            path: pi as u32,
        }
    }

    /// The width of a lit stroke, mm, and with a neighbouring pass the
    /// normals of its face and edge turned to the viewer and the share of
    /// its width that is face ([`flat_tube`]); without one it is round.
    ///
    /// The neighbour is looked for near the last stroke's, and followed from
    /// it ([`Grid::follow_other`]) but every [`REFRESH`] strokes, when the
    /// grid is searched in full.
    fn width(
        &self,
        pi: usize,
        run: &Run,
        a: DVec3,
        b: DVec3,
        tangent: DVec3,
        follow: &mut Follow,
    ) -> (f64, Option<(DVec3, DVec3, f64)>) {
        if !self.neighbours {
            return (round_diameter(run.c), None);
        }
        let grid = &self.grids[pi];
        let guess = follow.hint.map(|(at, j)| j + (run.first - at));
        let sm = (grid.arc(run.first) + grid.arc(run.end)) / 2.0;
        let followed = !follow.lit.is_multiple_of(REFRESH);
        follow.lit += 1;
        let found = grid.local_near(a, b, sm, guess, followed);
        follow.hint = found.map(|(_, j)| (run.first, j));
        let Some((l, _)) = found else {
            return (round_diameter(run.c), None);
        };
        // the pass spacing kept within half and twice the path's typical one
        let h_typ = self.scene.spacing[pi];
        let h = l.spacing.clamp(0.5 * h_typ, 2.0 * h_typ);
        let basis = self.frame.basis;
        let (w, face) = flat_tube(&basis, tangent, l.normal, run.c / h, h);
        // the sides facing the viewer
        let facing = |n: DVec3| {
            if n.dot(basis.toward) < 0.0 {
                -n
            } else {
                n
            }
        };
        let edge = l.normal.cross(tangent).normalize_or_zero();
        (w, Some((facing(l.normal), facing(edge), face)))
    }
}

/// How the lit strokes are coloured: the value range of the colour mode and
/// the depth range of the strokes (far ones are darker).
pub(super) struct Palette {
    mode: ColorMode,
    lo: f64,
    hi: f64,
    dmin: f64,
    dspan: f64,
}

impl Palette {
    /// The palette of the preview's strokes: the value range of `mode`, the
    /// depth range of the model's extruding points.
    pub(super) fn of_model(model: &Model, mode: ColorMode) -> Palette {
        let (lo, hi) = model.scene.range(mode);
        let (dmin, dmax) = model.depths;
        Palette {
            mode,
            lo,
            hi,
            dmin,
            dspan: if dmax > dmin { dmax - dmin } else { 1.0 },
        }
    }

    /// Stroke `it` coloured for the bands to paint ([`Px`]): a lit string
    /// at least [`MIN_PX`] wide; a travel faint, grey and [`MIN_PX`] or 1 px
    /// wide, whichever is more.
    pub(super) fn px(&self, it: &Item) -> Px {
        let (r, rgb, alpha) = if it.kind == 1 {
            (MIN_PX.max(1.0) * 0.5, [150, 155, 165], 90)
        } else {
            (it.width.max(MIN_PX) * 0.5, self.rgb(it), 255)
        };
        Px {
            a: it.a,
            b: it.b,
            depth: it.depth as f32,
            r,
            rgb,
            alpha,
            seq: 0,
        }
    }

    /// The colour of a lit (not travel) stroke.
    pub(super) fn rgb(&self, it: &Item) -> [u8; 3] {
        let (lo, hi) = (self.lo, self.hi);
        let base = match self.mode {
            ColorMode::Findings if it.kind == 2 => RED,
            ColorMode::Findings => GREY,
            ColorMode::Plain => FILAMENT,
            _ if hi > lo => colormap((it.value - lo) / (hi - lo)),
            _ => colormap(0.5),
        };
        let depth = (it.depth - self.dmin) / self.dspan;
        let mut k = 0.16 + 0.14 * depth + 0.85 * it.diffuse;
        if it.kind == 2 {
            k = 0.55 + 0.45 * k;
        }
        let c = base.map(|x| (x as f64 * k + 0.30 * it.spec).clamp(0.0, 1.0));
        c.map(|x| libm::round(x * 255.0) as u8)
    }
}

/// How a string of tangent `t` looks, as a flat tube: its width in mm and
/// the share of that width that is its face (normal `n`) rather than its edge
/// (normal b = n × t).
///
/// Its cross-section is an ellipse of axes `thick` along n and `along`
/// across the surface along b; seen across the string's image (screen
/// direction e) it spans sqrt((thick·n·e)² + (along·b·e)²), of which the face
/// makes |along·b·e| and the edge |thick·n·e|.
pub(crate) fn flat_tube(basis: &Basis, t: DVec3, n: DVec3, thick: f64, along: f64) -> (f64, f64) {
    let (du, dw) = (t.dot(basis.right), t.dot(basis.up));
    let l = (du * du + dw * dw).sqrt();
    if l < 1e-6 {
        // seen end on: the larger axis
        return (thick.max(along), 0.5);
    }
    let e = (-dw * basis.right + du * basis.up) / l;
    let b = n.cross(t).normalize_or_zero();
    let (face, edge) = ((along * b.dot(e)).abs(), (thick * n.dot(e)).abs());
    let share = if face + edge > 0.0 {
        face / (face + edge)
    } else {
        1.0
    };
    (libm::hypot(face, edge), share)
}

/// Diffuse and highlight terms of a string under `light` (world direction).
///
/// With a surface: for the face (normal N) and the edge (normal B), Lambert
/// N·L (with a quarter from a fill light at the viewer) and a Blinn highlight
/// (N·H)^40, H halfway between L and the viewer, mixed by (1 − f)³ where f
/// is the share of the string's width that is face. Without one the string is a thin tube of
/// tangent T (illuminated lines): sqrt(1 − (L·T)²), and the highlight
/// (sqrt(1 − (L·T)²)·sqrt(1 − (V·T)²) − (L·T)(V·T))^24.
fn shade(t: DVec3, normal: Option<(DVec3, DVec3, f64)>, light: DVec3, basis: Basis) -> (f64, f64) {
    let v = basis.toward;
    let lt = light.dot(t);
    let tube = (1.0 - lt * lt).max(0.0).sqrt();
    match normal {
        Some((face, edge, share)) => {
            let h = (light + v).normalize();
            let lambert = |n: DVec3| {
                // the key light, and a fill light from the viewer
                let d = 0.75 * n.dot(light).max(0.0) + 0.25 * n.dot(v).max(0.0);
                (d, n.dot(h).max(0.0).powi(40))
            };
            let (df, sf) = lambert(face);
            let (de, se) = lambert(edge);
            // in a wall the next pass hides most of a string's edge: it shows
            // where the face is seen nearly edge on (a rim, a wall from above)
            let e = (1.0 - share).powi(3);
            let diffuse = (1.0 - e) * df + e * de;
            // a trace of the tube term keeps the strings visible on the surface
            (diffuse * (0.85 + 0.15 * tube), (1.0 - e) * sf + e * se)
        }
        None => {
            let vt = v.dot(t);
            let spec = (tube * (1.0 - vt * vt).max(0.0).sqrt() - lt * vt).max(0.0);
            (tube, spec.powi(24))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The extruding points' span found piece by piece and joined is the
    /// span of the points themselves, whatever the pieces: travels' own
    /// ends and points that are not finite left out.
    #[test]
    fn a_span_joined_from_pieces_is_the_whole_path_s() {
        use crate::base::toolpath::Toolpath;
        let mut tp = Toolpath::new(DVec3::new(1.0, 2.0, 0.2));
        for k in 1..=40 {
            let a = f64::from(k) * 0.4;
            let q = DVec3::new(
                9.0 * libm::cos(a),
                7.0 * libm::sin(a),
                0.2 + 0.05 * f64::from(k),
            );
            if k % 9 == 0 {
                tp.travel(q + DVec3::new(50.0, 0.0, 0.0), 100.0);
                tp.travel(q, 100.0);
            } else {
                tp.draw(q, 0.1, 20.0);
            }
        }
        tp.travel(DVec3::new(-80.0, 0.0, 5.0), 100.0);
        tp.draw(DVec3::new(f64::NAN, 0.0, 5.0), 0.1, 20.0);
        let basis = View::Iso.basis();
        // the points next to an extruding string, one by one
        let mut want = Reach::EMPTY;
        for k in 0..tp.len() {
            if !tp.strings[k].travel {
                want.any = true;
                for p in [tp.points[k], tp.points[k + 1]] {
                    if p.is_finite() {
                        want.add(basis, p);
                    }
                }
            }
        }
        assert!(want.hi.x < 50.0, "a travel's far end is not in it");
        for piece in [1, 3, 7, 1000] {
            let mut got = Reach::EMPTY;
            let mut k = 0;
            while k < tp.len() {
                let end = (k + piece).min(tp.len());
                got = Reach::join(got, Reach::of_piece(basis, &tp, k, end));
                k = end;
            }
            assert_eq!(
                (got.lo2, got.hi2, got.depths),
                (want.lo2, want.hi2, want.depths)
            );
            assert_eq!((got.lo, got.hi, got.any), (want.lo, want.hi, want.any));
        }
    }

    #[test]
    fn wall_strings_look_as_tall_face_on_and_as_thick_edge_on() {
        // a horizontal string along x in a vertical wall (normal −y)
        let (t, n) = (DVec3::X, DVec3::NEG_Y);
        let front = View::Front.basis();
        let (w, face) = flat_tube(&front, t, n, 0.5, 0.3);
        assert!((w - 0.3).abs() < 1e-12 && face == 1.0);
        let top = View::Top.basis();
        let (w, face) = flat_tube(&top, t, n, 0.5, 0.3);
        assert!((w - 0.5).abs() < 1e-12 && face == 0.0);
        // seen end on (along x, from the side): the larger axis
        let side = View::Side.basis();
        assert_eq!(flat_tube(&side, t, n, 0.5, 0.3).0, 0.5);
    }
}
