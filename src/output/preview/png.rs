//! The PNG preview: the strings as anti-aliased strokes (tiny-skia), painted
//! far to near so that the front of a sphere hides its back, shaded, with the
//! recipe's name, its key stats and a colour legend in the corners.
//!
//! Shading. A string is a thin tube: lit from a light L fixed to the view, the
//! brightest normal of a tube with unit tangent T gives the diffuse term
//! sqrt(1 − (L·T)²), and the highlight is (sqrt(1 − (L·T)²)·sqrt(1 − (V·T)²)
//! − (L·T)(V·T))^n with V the direction to the viewer (Stalling et al.'s
//! illuminated lines). A depth cue darkens far strings, so walls read as
//! surfaces and the near side of a helix stands out from the far side.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use glam::DVec3;
use tiny_skia::{LineCap, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform};

use super::Threads;
use super::{
    colormap, fmt_value, round_diameter, text, Basis, ColorMode, Grid, Options, Render, Scene, Size,
};
use crate::analyse::check::Severity;
use crate::analyse::plan::Plan;
use crate::analyse::stats::Stats;
use crate::base::error::Result;
use crate::base::format::hms;

/// Where recipe space lands in the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The view.
    pub basis: Basis,
    /// Pixels per mm.
    pub scale: f64,
    /// The screen-plane point (u, w) drawn at `pixel_centre`.
    pub centre: (f64, f64),
    /// Pixel where `centre` lands.
    pub pixel_centre: (f64, f64),
}

impl Frame {
    /// The largest scale that fits `points` (grown by `pad` mm on each side)
    /// into the pixel rectangle `rect` = [x0, y0, x1, y1], centred in it.
    pub fn fit(basis: Basis, points: &[DVec3], rect: [f64; 4], pad: f64) -> Frame {
        let mut lo = (f64::INFINITY, f64::INFINITY);
        let mut hi = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for p in points {
            let (u, w, _) = basis.project(*p);
            lo = (lo.0.min(u), lo.1.min(w));
            hi = (hi.0.max(u), hi.1.max(w));
        }
        Frame::fit_box(basis, lo, hi, rect, pad)
    }

    /// [`Frame::fit`] given the lowest and highest screen-plane coordinates
    /// (u, w) of the points (lo > hi: none).
    pub fn fit_box(
        basis: Basis,
        mut lo: (f64, f64),
        mut hi: (f64, f64),
        rect: [f64; 4],
        pad: f64,
    ) -> Frame {
        if lo.0 > hi.0 {
            (lo, hi) = ((0.0, 0.0), (0.0, 0.0));
        }
        // extent on the screen plane, at least 1 mm either way
        let du = (hi.0 - lo.0 + 2.0 * pad).max(1.0);
        let dw = (hi.1 - lo.1 + 2.0 * pad).max(1.0);
        let scale = ((rect[2] - rect[0]) / du).min((rect[3] - rect[1]) / dw);
        Frame {
            basis,
            scale,
            centre: ((lo.0 + hi.0) / 2.0, (lo.1 + hi.1) / 2.0),
            pixel_centre: ((rect[0] + rect[2]) / 2.0, (rect[1] + rect[3]) / 2.0),
        }
    }

    /// The pixel (x right, y down) where recipe point `p` lands.
    pub fn pixel(&self, p: DVec3) -> (f64, f64) {
        let (u, w, _) = self.basis.project(p);
        (
            self.pixel_centre.0 + self.scale * (u - self.centre.0),
            self.pixel_centre.1 - self.scale * (w - self.centre.1),
        )
    }
}

/// A rendered preview and where recipe space landed in it.
pub struct Rendered {
    /// The image (premultiplied RGBA).
    pub pixmap: Pixmap,
    /// The projection used.
    pub frame: Frame,
}

const BACKGROUND: [u8; 3] = [30, 33, 39];
const TEXT: [u8; 3] = [232, 234, 237];
const DIM: [u8; 3] = [160, 166, 175];
const RED: [f32; 3] = [0.95, 0.16, 0.13];
const GREY: [f32; 3] = [0.66, 0.68, 0.71];
/// PLA orange, the colour of the G-code thumbnails.
const FILAMENT: [f32; 3] = [0.98, 0.56, 0.16];
/// Strings shorter than this on screen are merged with their neighbours, px.
const MERGE_PX: f64 = 2.0;
/// Strings per piece of work when the strokes are collected on several
/// threads. Merged runs end at a piece's end, so the pieces are a fixed size
/// (not a share of the threads): the strokes are the same on any number.
const PIECE: usize = 1 << 14;
/// Rows of pixels per band when the strokes are painted on several threads.
const BAND: usize = 32;
/// When following the neighbouring pass from stroke to stroke
/// ([`Grid::follow_other`]), every this many strokes search it in full.
const REFRESH: usize = 32;

/// One stroke to paint.
struct Item {
    a: (f32, f32),
    b: (f32, f32),
    depth: f64,
    /// The number the colour shows (scalar modes).
    value: f64,
    /// Diffuse and highlight terms of its shading ([`shade`]).
    diffuse: f64,
    spec: f64,
    width: f32,
    /// 0: lit string; 1: travel (faint, unlit); 2: flagged (lit, brighter).
    kind: u8,
}

/// One stroke of the PNG preview, coloured, as the bands paint it.
struct Px {
    a: (f32, f32),
    b: (f32, f32),
    depth: f32,
    /// Half its width, px.
    r: f32,
    rgb: [u8; 3],
    /// Opacity, 0..=255.
    alpha: u8,
    /// Its place in print order (ties of depth keep it).
    seq: u32,
}

/// The full preview of `plan`: background, model, and unless `opts.bare`
/// (or the image is too small for text) the name, stats and legend; with the
/// stats `render` returned.
///
/// The G-code is written into nothing for the stats of the header (its
/// planner on a thread of its own), beside the drawing when `opts.threads`
/// allows more than one, before it otherwise. The drawing goes in phases,
/// each over `opts.threads`, each one's memory let go before the next: the
/// strokes are collected in pieces of [`PIECE`] strings (each piece by
/// whichever thread is free, coloured as it is collected, kept in its own
/// slot so that their order is the print order); then painted in bands of
/// [`BAND`] rows, each band by one thread. Every pixel sees the same strokes
/// in the same order on any number of threads, so the image is the same.
pub fn preview(plan: &Plan, opts: &Options, render: Render) -> Result<(Rendered, Stats)> {
    if opts.threads.get() == 1 {
        // one thread: the planner's memory is let go before the strokes take theirs
        let stats = render(&mut std::io::sink())?;
        let (pm, frame, scene) = draw(plan, opts);
        return Ok(finish(pm, frame, &scene, stats, opts));
    }
    // more: the G-code is written into nothing (for the header's stats) on
    // a thread of its own while the model is drawn, filling the cores where
    // the drawing runs on one thread (the pass spacing, the grids, the sort)
    let (stats, (pm, frame, scene)) = std::thread::scope(|s| {
        let stats = s.spawn(|| render(&mut std::io::sink()));
        let drawn = draw(plan, opts);
        let stats = stats
            .join()
            .unwrap_or_else(|e| std::panic::resume_unwind(e));
        (stats, drawn)
    });
    Ok(finish(pm, frame, &scene, stats?, opts))
}

/// The header and legend drawn over the model (unless bare or too small).
fn finish(
    mut pm: Pixmap,
    frame: Frame,
    scene: &Scene,
    stats: Stats,
    opts: &Options,
) -> (Rendered, Stats) {
    let (_, decorate, ts) = layout(scene, opts);
    if decorate {
        header(&mut pm, &stats, scene, ts);
        legend(&mut pm, scene, opts.color, ts);
    }
    (Rendered { pixmap: pm, frame }, stats)
}

/// The background and the model (with its marks), as [`preview`] paints them.
fn draw<'p>(plan: &'p Plan, opts: &Options) -> (Pixmap, Frame, Scene<'p>) {
    let threads = opts.threads;
    let scene = Scene::new(plan);
    let (rect, _, _) = layout(&scene, opts);
    let model = Model::new(
        &scene,
        opts.view,
        opts.color,
        rect,
        PIECE,
        true,
        threads.get(),
    );
    let (frame, bbox) = (model.frame, model.bbox);
    let pal = Palette {
        mode: opts.color,
        lo: scene.range(opts.color).0,
        hi: scene.range(opts.color).1,
        dmin: model.depths.0,
        dspan: if model.depths.1 > model.depths.0 {
            model.depths.1 - model.depths.0
        } else {
            1.0
        },
    };
    let min_px = 0.75f32;
    let slots = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        let work = || {
            model.work(&slots, |items| {
                items
                    .iter()
                    .map(|it| {
                        let (r, rgb, alpha) = if it.kind == 1 {
                            (min_px.max(1.0) * 0.5, [150, 155, 165], 90)
                        } else {
                            (it.width.max(min_px) * 0.5, pal.rgb(it), 255)
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
                    })
                    .collect()
            })
        };
        for _ in 1..threads.get() {
            s.spawn(work);
        }
        work();
    });
    drop(model);
    let mut strokes = gather(slots);
    // far first, print order among equals: the order of a stable sort, by an
    // unstable one that needs no room beside the strokes
    for (i, px) in strokes.iter_mut().enumerate() {
        px.seq = i as u32;
    }
    // (depth, seq) is a total order with no ties: one sorted order, on
    // the pool's threads or not
    let order = |a: &Px, b: &Px| a.depth.total_cmp(&b.depth).then(a.seq.cmp(&b.seq));
    if threads.get() >= 2 {
        use rayon::slice::ParallelSliceMut;
        strokes.par_sort_unstable_by(order);
    } else {
        strokes.sort_unstable_by(order);
    }
    let mut pm = Pixmap::new(opts.size.width, opts.size.height).expect("sizes are 1..=8192");
    pm.fill(tiny_skia::Color::from_rgba8(
        BACKGROUND[0],
        BACKGROUND[1],
        BACKGROUND[2],
        255,
    ));
    paint_bands(&mut pm, &strokes, threads);
    drop(strokes);
    marks(&mut pm, &scene, &frame, bbox, opts.color, rect);
    (pm, frame, scene)
}

/// The pieces' results in order, as one list.
fn gather<T>(slots: Mutex<Vec<Option<Vec<T>>>>) -> Vec<T> {
    let done = slots.into_inner().unwrap_or_else(|e| e.into_inner());
    let n = done.iter().map(|d| d.as_ref().map_or(0, Vec::len)).sum();
    let mut out = Vec::with_capacity(n);
    for d in done {
        out.extend(d.expect("every piece is collected"));
    }
    out
}

/// Where the model goes in the image, whether the text goes round it, and
/// the text's scale.
fn layout(scene: &Scene, opts: &Options) -> ([f64; 4], bool, u32) {
    let Size { width, height } = opts.size;
    let (w, h) = (width as f64, height as f64);
    let decorate = !opts.bare && width >= 320 && height >= 240;
    let ts = (height / 450).clamp(1, 4);
    let m = 12.0 * ts as f64;
    let rect = if decorate {
        let header = m + 8.0 * (ts + 1) as f64 + 4.0 * 11.0 * ts as f64 + 6.0 * ts as f64;
        let legend = legend_width(scene, opts.color, ts) as f64 + m;
        [m, header, w - legend - m, h - m]
    } else {
        let pad = (w.min(h) * 0.03).max(1.0);
        [pad, pad, w - pad, h - pad]
    };
    (rect, decorate, ts)
}

/// A G-code thumbnail: the model alone in filament colour, iso view, on a
/// transparent background.
pub fn thumbnail(scene: &Scene, size: Size) -> Pixmap {
    let mut pm = Pixmap::new(size.width, size.height).expect("sizes are 1..=8192");
    let (w, h) = (size.width as f64, size.height as f64);
    let pad = (w.min(h) * 0.04).max(0.5);
    let rect = [pad, pad, w - pad, h - pad];
    // one piece per path, on the caller's thread: the bytes are part of the
    // G-code and its hash
    let model = Model::new(
        scene,
        super::View::Iso,
        ColorMode::Plain,
        rect,
        usize::MAX,
        false,
        1,
    );
    let slots = Mutex::new(Vec::new());
    model.work(&slots, |items| items);
    let (frame, bbox) = (model.frame, model.bbox);
    let mut items = gather(slots);
    sort(&mut items);
    paint_strokes(&mut pm, &items, scene, ColorMode::Plain, 1.0);
    marks(&mut pm, scene, &frame, bbox, ColorMode::Plain, rect);
    pm
}

/// Painter's algorithm: far (small depth) first; the sort is stable, so
/// strings at equal depth keep print order and the result is deterministic
/// (the PNG preview's strokes are sorted the same way).
fn sort(items: &mut [Item]) {
    items.sort_by(|a, b| a.depth.total_cmp(&b.depth));
}

/// The strings of a scene made ready to paint into a rectangle of an image:
/// the projection, each path's grid of strings, and the pieces of work that
/// collect the strokes (taken by whichever thread is free; each piece's
/// strokes are kept in its own slot, so their order is the print order).
struct Model<'s, 'p> {
    scene: &'s Scene<'p>,
    frame: Frame,
    mode: ColorMode,
    light: DVec3,
    /// The box of the extruding points, recipe coordinates.
    bbox: (DVec3, DVec3),
    /// Their lowest and highest depth.
    depths: (f64, f64),
    /// Per path, its strings in a grid (to find the neighbouring pass).
    grids: Vec<Grid<'p>>,
    /// (path, first string, end) of each piece.
    pieces: Vec<(usize, usize, usize)>,
    /// Whether a stroke's neighbouring pass is followed from the last
    /// stroke's ([`Grid::follow_other`]) rather than searched in full.
    follow: bool,
    next: AtomicUsize,
}

impl<'s, 'p> Model<'s, 'p> {
    /// Fits `scene` into `rect` seen from `view`; pieces of `piece` strings;
    /// neighbouring passes followed or not (`follow`); each path's grid
    /// built in `parts` on as many threads ([`Grid::for_surface_on`]).
    fn new(
        scene: &'s Scene<'p>,
        view: super::View,
        mode: ColorMode,
        rect: [f64; 4],
        piece: usize,
        follow: bool,
        parts: usize,
    ) -> Model<'s, 'p> {
        let basis = view.basis();
        let mut lo2 = (f64::INFINITY, f64::INFINITY);
        let mut hi2 = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut depths = (f64::INFINITY, f64::NEG_INFINITY);
        scene.each_extruding_point(|p| {
            let (u, w, d) = basis.project(p);
            lo2 = (lo2.0.min(u), lo2.1.min(w));
            hi2 = (hi2.0.max(u), hi2.1.max(w));
            depths = (depths.0.min(d), depths.1.max(d));
            lo = lo.min(p);
            hi = hi.max(p);
        });
        let frame = Frame::fit_box(basis, lo2, hi2, rect, scene.pad());
        let grids: Vec<Grid> = scene
            .plan
            .paths
            .iter()
            .zip(&scene.spacing)
            .map(|(tp, &h)| Grid::for_surface_on(&tp.points, h, parts))
            .collect();
        let mut pieces = Vec::new();
        for (pi, tp) in scene.plan.paths.iter().enumerate() {
            let mut k = 0;
            while k < tp.len() {
                let end = k.saturating_add(piece).min(tp.len());
                pieces.push((pi, k, end));
                k = end;
            }
        }
        Model {
            scene,
            frame,
            mode,
            // the light comes from the upper left, in front: fixed to the view
            light: (-0.6 * basis.right + 0.5 * basis.up + 0.6 * basis.toward).normalize(),
            bbox: (lo, hi),
            depths,
            grids,
            pieces,
            follow,
            next: AtomicUsize::new(0),
        }
    }

    /// Collects pieces until none is left, each made into `f` of its strokes
    /// and kept in its slot (the piece's number) of `slots`.
    fn work<T>(&self, slots: &Mutex<Vec<Option<Vec<T>>>>, f: impl Fn(Vec<Item>) -> Vec<T>) {
        loop {
            let i = self.next.fetch_add(1, Ordering::Relaxed);
            let Some(&(pi, k0, k1)) = self.pieces.get(i) else {
                return;
            };
            let out = f(self.collect(pi, k0, k1));
            let mut slots = slots.lock().unwrap_or_else(|e| e.into_inner());
            if slots.len() <= i {
                slots.resize_with(i + 1, || None);
            }
            slots[i] = Some(out);
        }
    }

    /// The strokes of strings `k0..k1` of path `pi`: runs shorter than
    /// [`MERGE_PX`] on screen become one stroke (length-weighted
    /// cross-section and value), so a 2-million-string vase paints as fast as
    /// its pixels allow.
    fn collect(&self, pi: usize, k0: usize, k1: usize) -> Vec<Item> {
        let (scene, frame, mode) = (self.scene, &self.frame, self.mode);
        let tp = &scene.plan.paths[pi];
        let grid = &self.grids[pi];
        // neighbouring passes lie about `spacing` apart: look a little further
        let h_typ = scene.spacing[pi];
        let mut items = Vec::new();
        // the neighbour found for the last stroke: the next one's is near it
        let mut hint: Option<(usize, usize)> = None;
        let mut lit = 0usize;
        let mut k = k0;
        while k < k1 {
            let first = k;
            let start = tp.points[k];
            let s0 = tp.strings[k];
            let flag0 = scene.flagged[pi][k];
            let (mut len, mut csum, mut vsum) = (0.0, 0.0, 0.0);
            let mut end = k;
            // take strings while the run is shorter than MERGE_PX and alike
            while end < k1 && tp.strings[end].travel == s0.travel && scene.flagged[pi][end] == flag0
            {
                let l = tp.length(end);
                len += l;
                csum += tp.strings[end].c * l;
                vsum += scene.value(mode, pi, end) * l;
                end += 1;
                if start.distance(tp.points[end]) * frame.scale >= MERGE_PX {
                    break;
                }
            }
            let b = tp.points[end];
            let (c, v) = if len > 0.0 {
                (csum / len, vsum / len)
            } else {
                (s0.c, scene.value(mode, pi, k))
            };
            k = end;
            if !start.is_finite() || !b.is_finite() {
                continue;
            }
            let tangent = (b - start).normalize_or_zero();
            let local = if s0.travel {
                None
            } else {
                let guess = hint.map(|(at, j)| j + (first - at));
                let sm = (grid.arc(first) + grid.arc(end)) / 2.0;
                let follow = self.follow && !lit.is_multiple_of(REFRESH);
                lit += 1;
                let found = grid.local_near(start, b, sm, guess, follow);
                hint = found.map(|(_, j)| (first, j));
                found.map(|(l, _)| l)
            };
            let (width, normal) = match local {
                _ if s0.travel => (0.0, None),
                Some(l) => {
                    let h = l.spacing.clamp(0.5 * h_typ, 2.0 * h_typ);
                    let (w, face) = flat_tube(&frame.basis, tangent, l.normal, c / h, h);
                    // the sides facing the viewer
                    let facing = |n: DVec3| {
                        if n.dot(frame.basis.toward) < 0.0 {
                            -n
                        } else {
                            n
                        }
                    };
                    let edge = l.normal.cross(tangent).normalize_or_zero();
                    (w, Some((facing(l.normal), facing(edge), face)))
                }
                None => (round_diameter(c), None),
            };
            let (diffuse, spec) = if s0.travel {
                (0.0, 0.0)
            } else {
                shade(tangent, normal, self.light, frame.basis)
            };
            let pa = frame.pixel(start);
            let pb = frame.pixel(b);
            items.push(Item {
                a: (pa.0 as f32, pa.1 as f32),
                b: (pb.0 as f32, pb.1 as f32),
                depth: frame.basis.project((start + b) * 0.5).2,
                width: (width * frame.scale) as f32,
                value: v,
                diffuse,
                spec,
                kind: if s0.travel {
                    1
                } else if flag0 {
                    2
                } else {
                    0
                },
            });
        }
        items
    }
}

/// How the lit strokes are coloured: the value range of the colour mode and
/// the depth range of the strokes (far ones are darker).
struct Palette {
    mode: ColorMode,
    lo: f64,
    hi: f64,
    dmin: f64,
    dspan: f64,
}

impl Palette {
    fn new(items: &[Item], scene: &Scene, mode: ColorMode) -> Palette {
        let (lo, hi) = scene.range(mode);
        let (dmin, dmax) = items
            .iter()
            .filter(|i| i.kind != 1)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), i| {
                (a.min(i.depth), b.max(i.depth))
            });
        let dspan = if dmax > dmin { dmax - dmin } else { 1.0 };
        Palette {
            mode,
            lo,
            hi,
            dmin,
            dspan,
        }
    }

    /// The colour of a lit (not travel) stroke.
    fn rgb(&self, it: &Item) -> [u8; 3] {
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

/// Paints the (sorted) strokes as tiny-skia's anti-aliased round-capped
/// strokes, at least `min_px` wide: the G-code thumbnails.
fn paint_strokes(pm: &mut Pixmap, items: &[Item], scene: &Scene, mode: ColorMode, min_px: f32) {
    let pal = Palette::new(items, scene, mode);
    let mut paint = Paint {
        anti_alias: true,
        ..Paint::default()
    };
    let mut stroke = Stroke {
        line_cap: LineCap::Round,
        ..Stroke::default()
    };
    let mut pb = PathBuilder::new();
    for it in items {
        if it.kind == 1 {
            paint.set_color_rgba8(150, 155, 165, 90);
            stroke.width = min_px.max(1.0);
        } else {
            let [r, g, b] = pal.rgb(it);
            paint.set_color_rgba8(r, g, b, 255);
            stroke.width = it.width.max(min_px);
        }
        pb.move_to(it.a.0, it.a.1);
        pb.line_to(it.b.0, it.b.1);
        let Some(path) = pb.finish() else {
            pb = PathBuilder::new();
            continue;
        };
        pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
        pb = path.clear();
    }
}

/// Paints the (sorted) strokes into an opaque image in bands of [`BAND`]
/// rows on up to `threads` threads.
///
/// A stroke is a capsule: the points within r (half its width) of segment
/// a–b. A pixel is covered by the overlap of its width with the capsule
/// across the line through its centre at distance d: min(d + ½, r) −
/// max(d − ½, −r), clamped to [0, 1] (a box filter; 1 inside, 0 beyond
/// r + ½), and takes the stroke's colour in that share times its opacity
/// (over: dst + (src − dst)·α, in integers rounded the same way everywhere).
/// Each band paints every stroke that reaches it, in order, so a pixel's
/// result does not depend on how the image is cut into bands.
fn paint_bands(pm: &mut Pixmap, strokes: &[Px], threads: Threads) {
    let (width, height) = (pm.width() as usize, pm.height() as usize);
    // each band's strokes, in painting order
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); height.div_ceil(BAND)];
    for (i, px) in strokes.iter().enumerate() {
        let ext = px.r + 0.5;
        let top = (px.a.1.min(px.b.1) - ext).floor();
        let bottom = (px.a.1.max(px.b.1) + ext).ceil().min(height as f32);
        if !(top < bottom && bottom > 0.0) {
            continue; // off the image, or not a number
        }
        let first = top.max(0.0) as usize / BAND;
        let last = (bottom as usize - 1) / BAND;
        for bin in &mut bins[first..=last] {
            bin.push(i as u32);
        }
    }
    let bands: Vec<(&[u32], usize, &mut [u8])> = pm
        .data_mut()
        .chunks_mut(width * 4 * BAND)
        .zip(&bins)
        .enumerate()
        .map(|(i, (band, bin))| (bin.as_slice(), i * BAND, band))
        .collect();
    let queue = Mutex::new(bands);
    let work = || loop {
        let Some((bin, y0, band)) = queue.lock().unwrap_or_else(|e| e.into_inner()).pop() else {
            return;
        };
        let y1 = y0 + band.len() / (4 * width);
        for (j, &i) in bin.iter().enumerate() {
            // a band's strokes lie scattered in the depth order: each was a
            // cache miss when fetched only as it was painted
            if let Some(&ahead) = bin.get(j + PREFETCH) {
                prefetch(&strokes[ahead as usize]);
            }
            capsule(band, width, y0, y1, &strokes[i as usize]);
        }
    };
    std::thread::scope(|s| {
        for _ in 1..threads.get() {
            s.spawn(work);
        }
        work();
    });
}

/// Strokes a band's painting fetches ahead of the one it paints.
const PREFETCH: usize = 16;

/// Asks the processor to fetch `x` into its caches (a hint: nothing else).
#[inline]
fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch of a valid reference's address reads nothing the
    // program sees and cannot fault (SSE, on every x86_64)
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

/// Blends stroke `px` into rows `y0..y1` of an opaque premultiplied RGBA
/// image `width` pixels wide, held in `band` (see [`paint_bands`]).
fn capsule(band: &mut [u8], width: usize, y0: usize, y1: usize, px: &Px) {
    let (a, b, r) = (px.a, px.b, px.r);
    if !(r.is_finite() && a.0.is_finite() && a.1.is_finite() && b.0.is_finite() && b.1.is_finite())
    {
        return;
    }
    let alpha = f32::from(px.alpha);
    let ext = r + 0.5;
    let top = (a.1.min(b.1) - ext).floor().max(y0 as f32);
    let bottom = (a.1.max(b.1) + ext).ceil().min(y1 as f32);
    let left = (a.0.min(b.0) - ext).floor().max(0.0);
    let right = (a.0.max(b.0) + ext).ceil().min(width as f32);
    if top >= bottom || left >= right {
        return;
    }
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let inv = if l2 > 0.0 { 1.0 / l2 } else { 0.0 };
    let src = px.rgb.map(u32::from);
    let px_rgb = px.rgb;
    // beyond r + ½ a pixel has no share (min(d + ½, r) ≤ r ≤ max(d − ½, −r));
    // tested on the square distance, a little beyond (the square rounded
    // in f32 stays below it), to skip the square root there
    let far = (ext * 1.001 + 1e-3) * (ext * 1.001 + 1e-3);
    for y in top as usize..bottom as usize {
        let py = y as f32 + 0.5 - a.1;
        let row = &mut band[(y - y0) * width * 4..(y - y0 + 1) * width * 4];
        for x in left as usize..right as usize {
            let px = x as f32 + 0.5 - a.0;
            let t = ((px * dx + py * dy) * inv).clamp(0.0, 1.0);
            let (ex, ey) = (px - t * dx, py - t * dy);
            let d2 = ex * ex + ey * ey;
            if d2 > far {
                continue; // d > r + ½: no share
            }
            let d = d2.sqrt();
            let cov = ((d + 0.5).min(r) - (d - 0.5).max(-r)).clamp(0.0, 1.0);
            let k = (cov * alpha + 0.5) as u32;
            if k == 0 {
                continue;
            }
            let p = &mut row[4 * x..4 * x + 3];
            if k == 255 {
                // (s·255 + 127) / 255 = s
                p.copy_from_slice(&px_rgb);
                continue;
            }
            for (c, s) in p.iter_mut().zip(src) {
                *c = ((s * k + u32::from(*c) * (255 - k) + 127) / 255) as u8;
            }
        }
    }
}

/// The turtles' markers and, in the findings mode, a ring round each finding.
fn marks(
    pm: &mut Pixmap,
    scene: &Scene,
    frame: &Frame,
    bbox: (DVec3, DVec3),
    mode: ColorMode,
    rect: [f64; 4],
) {
    let mut paint = Paint {
        anti_alias: true,
        ..Paint::default()
    };
    // the turtles' markers (draw_turtle): a filled triangle each, pointing
    // along the heading, about 1/30 of the print's size
    if !scene.turtles.is_empty() {
        let (lo, hi) = bbox;
        let size = ((hi - lo).max_element() / 30.0).clamp(1.0, 20.0);
        paint.set_color_rgba8(255, 200, 40, 255);
        for m in &scene.turtles {
            let tri = super::Scene::turtle_triangle(m, size).map(|p| frame.pixel(p));
            let mut tb = PathBuilder::new();
            tb.move_to(tri[0].0 as f32, tri[0].1 as f32);
            tb.line_to(tri[1].0 as f32, tri[1].1 as f32);
            tb.line_to(tri[2].0 as f32, tri[2].1 as f32);
            tb.close();
            if let Some(path) = tb.finish() {
                pm.fill_path(
                    &path,
                    &paint,
                    tiny_skia::FillRule::Winding,
                    Transform::identity(),
                    None,
                );
            }
        }
    }
    if mode == ColorMode::Findings {
        paint.set_color_rgba8(255, 60, 50, 255);
        let r = (6.0 * (rect[3] - rect[1]) / 400.0).clamp(4.0, 24.0) as f32;
        let stroke = Stroke {
            line_cap: LineCap::Round,
            width: (r / 5.0).max(1.0),
            ..Stroke::default()
        };
        for p in &scene.marks {
            let (x, y) = frame.pixel(*p);
            if let Some(path) = PathBuilder::from_circle(x as f32, y as f32, r) {
                pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
            }
        }
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
pub fn flat_tube(basis: &Basis, t: DVec3, n: DVec3, thick: f64, along: f64) -> (f64, f64) {
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

/// The legend's labels for `mode`.
fn legend_lines(scene: &Scene, mode: ColorMode) -> Vec<String> {
    let (lo, hi) = scene.range(mode);
    match mode {
        ColorMode::Plain => Vec::new(),
        ColorMode::Findings => {
            let n = scene.plan.findings.len();
            let mut v = vec![
                "findings".to_string(),
                format!("{n} finding{}", if n == 1 { "" } else { "s" }),
                "no finding".into(),
            ];
            let mut codes: Vec<&str> = Vec::new();
            for f in &scene.plan.findings {
                if !codes.contains(&f.code) {
                    codes.push(f.code);
                }
            }
            v.extend(codes.iter().map(|c| format!("· {c}")));
            v
        }
        _ => vec![
            mode.name().to_string(),
            mode.unit().to_string(),
            fmt_value(hi),
            fmt_value((lo + hi) / 2.0),
            fmt_value(lo),
        ],
    }
}

fn legend_width(scene: &Scene, mode: ColorMode, ts: u32) -> u32 {
    let text = legend_lines(scene, mode)
        .iter()
        .map(|l| text::width(l, ts))
        .max()
        .unwrap_or(0);
    (22 * ts + text).max(text::width("cross-section", ts))
}

fn fill(pm: &mut Pixmap, x: f64, y: f64, w: f64, h: f64, rgb: [f32; 3]) {
    let mut paint = Paint::default();
    let [r, g, b] = rgb.map(|c| libm::round(c as f64 * 255.0) as u8);
    paint.set_color_rgba8(r, g, b, 255);
    paint.anti_alias = false;
    if let Some(rect) = Rect::from_xywh(x as f32, y as f32, w as f32, h as f32) {
        pm.fill_rect(rect, &paint, Transform::identity(), None);
    }
}

/// The colour scale (or the findings key) in the top-right corner.
fn legend(pm: &mut Pixmap, scene: &Scene, mode: ColorMode, ts: u32) {
    let lines = legend_lines(scene, mode);
    if lines.is_empty() {
        return;
    }
    let s = ts as f64;
    let m = 12.0 * s;
    let x = pm.width() as f64 - legend_width(scene, mode, ts) as f64 - m;
    let line = 11.0 * s;
    let (xi, yi) = (x as i32, m as i32);
    text::draw(pm, xi, yi, ts, &lines[0], TEXT);
    if mode == ColorMode::Findings {
        let y0 = m + 1.6 * line;
        for (k, (label, rgb)) in [(&lines[1], RED), (&lines[2], GREY)].iter().enumerate() {
            let y = y0 + k as f64 * 1.4 * line;
            fill(pm, x, y, 12.0 * s, 8.0 * s, *rgb);
            text::draw(pm, (x + 16.0 * s) as i32, y as i32, ts, label, TEXT);
        }
        for (k, code) in lines[3..].iter().enumerate() {
            let y = y0 + (2.0 * 1.4 + k as f64) * line + 4.0 * s;
            text::draw(pm, xi, y as i32, ts, code, DIM);
        }
        return;
    }
    text::draw(pm, xi, (m + line) as i32, ts, &lines[1], DIM);
    let top = m + 2.6 * line;
    let bar_h = (pm.height() as f64 * 0.42).round().max(20.0);
    let rows = bar_h as usize;
    for r in 0..rows {
        // top row: the highest value
        let t = 1.0 - r as f64 / (rows - 1) as f64;
        fill(pm, x, top + r as f64, 14.0 * s, 1.0, colormap(t));
    }
    let lx = (x + 20.0 * s) as i32;
    let (lo, hi) = scene.range(mode);
    let ticks: Vec<(f64, &String)> = if hi > lo {
        vec![
            (top, &lines[2]),
            (top + bar_h / 2.0, &lines[3]),
            (top + bar_h, &lines[4]),
        ]
    } else {
        vec![(top + bar_h / 2.0, &lines[3])]
    };
    for (y, label) in ticks {
        text::draw(pm, lx, (y - 4.0 * s) as i32, ts, label, TEXT);
    }
}

/// The recipe's name and key stats in the top-left corner.
fn header(pm: &mut Pixmap, st: &Stats, scene: &Scene, ts: u32) {
    let s = ts as f64;
    let m = 12.0 * s;
    let line = 11.0 * s;
    text::draw(pm, m as i32, m as i32, ts + 1, &st.name, TEXT);
    let size = [0, 1, 2].map(|k| st.bbox.max[k] - st.bbox.min[k]);
    let mut lines = vec![
        (
            format!("{:.1} × {:.1} × {:.1} mm", size[0], size[1], size[2]),
            TEXT,
        ),
        (
            format!(
                "filament {:.2} m, {:.1} g {}",
                st.filament_length_mm / 1000.0,
                st.filament_mass_g,
                st.material
            ),
            TEXT,
        ),
        (format!("time {}", hms(st.print_time_s)), TEXT),
    ];
    // the checks' summary, red with errors, amber with warnings, plain with notes
    let findings = &scene.plan.findings;
    if let Some(worst) = findings.iter().map(|f| f.severity).max() {
        let rgb = match worst {
            Severity::Error => [255, 110, 100],
            Severity::Warning => [255, 190, 90],
            Severity::Info => TEXT,
        };
        lines.push((crate::analyse::check::summary(findings), rgb));
    }
    let y0 = m + 8.0 * (ts + 1) as f64 + 6.0 * s;
    for (k, (l, rgb)) in lines.iter().enumerate() {
        text::draw(pm, m as i32, (y0 + k as f64 * line) as i32, ts, l, *rgb);
    }
}

/// PNG bytes of `pm`: RGB, or RGBA with `alpha` (colours un-premultiplied),
/// compressed as hard as the encoder can (the G-code thumbnails).
pub fn encode(pm: &Pixmap, alpha: bool) -> Vec<u8> {
    encode_with(pm, alpha, image::codecs::png::CompressionType::Best)
}

/// `pm` as a JPEG (quality 90) over white: the `/JPG` G-code thumbnails.
pub fn encode_jpeg(pm: &Pixmap) -> Vec<u8> {
    let mut data = Vec::with_capacity(pm.pixels().len() * 3);
    for px in pm.pixels() {
        // premultiplied colour over white: c + (255 − a)
        let a = 255 - px.alpha();
        data.extend([px.red(), px.green(), px.blue()].map(|c| c.saturating_add(a)));
    }
    let mut out = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 90)
        .encode(
            &data,
            pm.width(),
            pm.height(),
            image::ExtendedColorType::Rgb8,
        )
        .expect("JPEG encoding into memory does not fail");
    out
}

/// `pm` as a QOI image with alpha: the `/QOI` G-code thumbnails (Prusa's
/// MK4, MINI and XL firmware read them).
pub fn encode_qoi(pm: &Pixmap) -> Vec<u8> {
    use image::ImageEncoder;
    let mut data = Vec::with_capacity(pm.pixels().len() * 4);
    for px in pm.pixels() {
        let c = px.demultiply();
        data.extend([c.red(), c.green(), c.blue(), c.alpha()]);
    }
    let mut out = Vec::new();
    image::codecs::qoi::QoiEncoder::new(&mut out)
        .write_image(
            &data,
            pm.width(),
            pm.height(),
            image::ExtendedColorType::Rgba8,
        )
        .expect("QOI encoding into memory does not fail");
    out
}

/// [`encode`] with a quicker compression: the PNG previews (a flat
/// background and smooth shading compress well even so).
pub fn encode_fast(pm: &Pixmap, alpha: bool) -> Vec<u8> {
    encode_with(pm, alpha, image::codecs::png::CompressionType::Fast)
}

fn encode_with(pm: &Pixmap, alpha: bool, level: image::codecs::png::CompressionType) -> Vec<u8> {
    use image::ImageEncoder;
    let n = if alpha { 4 } else { 3 };
    let mut data = Vec::with_capacity(pm.pixels().len() * n);
    for px in pm.pixels() {
        let c = px.demultiply();
        data.extend_from_slice(&[c.red(), c.green(), c.blue()]);
        if alpha {
            data.push(c.alpha());
        }
    }
    let mut out = Vec::new();
    let kind = if alpha {
        image::ExtendedColorType::Rgba8
    } else {
        image::ExtendedColorType::Rgb8
    };
    use image::codecs::png::{FilterType, PngEncoder};
    PngEncoder::new_with_quality(&mut out, level, FilterType::Adaptive)
        .write_image(&data, pm.width(), pm.height(), kind)
        .expect("PNG encoding into memory does not fail");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::preview::View;

    #[test]
    fn fit_centres_and_scales() {
        let pts = [DVec3::new(-10.0, -5.0, 0.0), DVec3::new(10.0, 5.0, 3.0)];
        let f = Frame::fit(View::Top.basis(), &pts, [0.0, 0.0, 200.0, 100.0], 0.0);
        assert_eq!(f.scale, 10.0);
        assert_eq!(f.pixel(DVec3::ZERO), (100.0, 50.0));
        // +y is up the image, +x to the right
        assert_eq!(f.pixel(DVec3::new(10.0, 5.0, 0.0)), (200.0, 0.0));
        let f = Frame::fit(View::Front.basis(), &pts, [0.0, 0.0, 200.0, 100.0], 0.0);
        assert_eq!(f.pixel(DVec3::new(0.0, 0.0, 3.0)).1, 50.0 - 1.5 * f.scale);
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

    #[test]
    fn encode_round_trips() {
        let mut pm = Pixmap::new(5, 4).unwrap();
        pm.fill(tiny_skia::Color::from_rgba8(10, 20, 30, 255));
        let bytes = encode(&pm, false);
        let img = image::load_from_memory(&bytes).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (5, 4));
        assert_eq!(img.get_pixel(4, 3).0, [10, 20, 30]);
        let img = image::load_from_memory(&encode(&Pixmap::new(3, 3).unwrap(), true)).unwrap();
        assert_eq!(img.to_rgba8().get_pixel(1, 1).0[3], 0);
    }
}
