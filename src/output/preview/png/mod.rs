//! The PNG preview: the strings as anti-aliased strokes, the near ones
//! hiding the far (the front of a sphere hides its back), shaded, with the
//! recipe's name, its key stats and a colour legend in the corners.
//!
//! Rasterising. The preview's strokes are painted by this module's own
//! rasteriser (`raster`): a stroke is a capsule of its width, a pixel
//! takes the share of it a box filter gives, each stroke laid under the
//! nearer ones in integers rounded the same way everywhere (a pixel already
//! opaque costs nothing more), in bands of rows that the pool shares out with the
//! same bytes on any number of threads; the G-code thumbnails are painted
//! by it too. tiny-skia draws the rest: the turtles' markers, the findings' rings
//! and the legend's colour bar; the text is the previews' own 8 × 8 font.
//!
//! Shading. A string is a thin tube: lit from a light L fixed to the view, the
//! brightest normal of a tube with unit tangent T gives the diffuse term
//! sqrt(1 − (L·T)²), and the highlight is (sqrt(1 − (L·T)²)·sqrt(1 − (V·T)²)
//! − (L·T)(V·T))^n with V the direction to the viewer (Stalling et al.'s
//! illuminated lines). A depth cue darkens far strings, so walls read as
//! surfaces and the near side of a helix stands out from the far side.
//!
//! The work is split along its seams: this module fits the model into the
//! image and runs the phases ([`draw`], [`finish`]); `model` makes the
//! strokes of the strings (their width from the passes, their shading and
//! colour), `raster` paints them, `decor` the marks, header and legend.

mod decor;
mod model;
mod raster;

use glam::DVec3;
use tiny_skia::Pixmap;

use self::decor::{header, legend, legend_width, marks};
use self::model::{Model, Palette, Passes};
use self::raster::{over, paint_bands, Px};
use super::{Basis, ColorMode, Options, Scene, Size};
use crate::analyse::plan::Plan;
use crate::analyse::stats::Stats;
use crate::base::par;

/// Where recipe space lands in the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frame {
    /// The view.
    pub(crate) basis: Basis,
    /// Pixels per mm.
    pub(crate) scale: f64,
    /// The screen-plane point (u, w) drawn at `pixel_centre`.
    pub(crate) centre: (f64, f64),
    /// Pixel where `centre` lands.
    pub(crate) pixel_centre: (f64, f64),
}

impl Frame {
    #[cfg(test)]
    /// The largest scale that fits `points` (grown by `pad` mm on each side)
    /// into the pixel rectangle `rect` = [x0, y0, x1, y1], centred in it.
    pub(crate) fn fit(basis: Basis, points: &[DVec3], rect: [f64; 4], pad: f64) -> Frame {
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
    pub(crate) fn fit_box(
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
    pub(crate) fn pixel(&self, p: DVec3) -> (f64, f64) {
        let (u, w, _) = self.basis.project(p);
        (
            self.pixel_centre.0 + self.scale * (u - self.centre.0),
            self.pixel_centre.1 - self.scale * (w - self.centre.1),
        )
    }
}

/// A rendered preview and where recipe space landed in it.
pub(crate) struct Rendered {
    /// The image (premultiplied RGBA).
    pub(crate) pixmap: Pixmap,
    /// The projection used.
    pub(crate) frame: Frame,
}

const BACKGROUND: [u8; 3] = [30, 33, 39];
const TEXT: [u8; 3] = [232, 234, 237];
const DIM: [u8; 3] = [160, 166, 175];
const RED: [f32; 3] = [0.95, 0.16, 0.13];
const GREY: [f32; 3] = [0.66, 0.68, 0.71];
/// PLA orange, the colour of the G-code thumbnails.
const FILAMENT: [f32; 3] = [0.98, 0.56, 0.16];
/// Strings per piece of work when the strokes are collected. Merged runs
/// end at a piece's end, so the pieces are a fixed size (not a share of the
/// threads): the strokes are the same on any number.
const PIECE: usize = 1 << 14;

/// A PNG preview drawn but not finished: the background, the model and its
/// marks painted; the header and legend, which need the G-code's stats, not
/// yet ([`finish`]).
pub(crate) struct Drawing<'p> {
    pixmap: Pixmap,
    frame: Frame,
    scene: Scene<'p>,
    opts: Options,
}

/// The header and legend drawn over the model (unless bare or too small):
/// the last step of [`preview`], the only one that needs the stats.
pub(crate) fn finish(drawing: Drawing, stats: &Stats) -> Rendered {
    let Drawing {
        mut pixmap,
        frame,
        scene,
        opts,
    } = drawing;
    let (_, decorate, ts) = layout(&scene, &opts);
    if decorate {
        header(&mut pixmap, stats, &scene, ts);
        legend(&mut pixmap, &scene, opts.color, ts);
    }
    Rendered { pixmap, frame }
}

/// The background and the model with its marks: all of the preview of
/// `plan` but what needs the stats.
///
/// In phases over the pool ([`crate::base::par`]), each one's memory let go
/// before the next: the strokes are collected in pieces of [`PIECE`]
/// strings, coloured as they are collected, the pieces' strokes kept in
/// print order ([`Model::strokes`]); sorted far to near ([`sort_far_first`]);
/// then painted near to far in bands of [`BAND`] rows ([`paint_bands`])
/// and laid over the background ([`over`]). Every pixel
/// sees the same strokes in the same order however the work is split, so
/// the image is the same on any number of threads.
pub(crate) fn draw<'p>(plan: &'p Plan, opts: &Options) -> Drawing<'p> {
    let scene = Scene::new(plan);
    let (rect, _, _) = layout(&scene, opts);
    let model = Model::new(
        &scene,
        opts.view,
        opts.color,
        rect,
        PIECE,
        Passes::Followed,
        par::width(),
    );
    let (frame, bbox) = (model.frame, model.bbox);
    let pal = Palette::of_model(&model, opts.color);
    let mut strokes = model.strokes(|it| pal.px(it));
    drop(model);
    sort_far_first(&mut strokes);
    let mut pixmap = Pixmap::new(opts.size.width, opts.size.height).expect("sizes are 1..=8192");
    paint_bands(&mut pixmap, &strokes);
    over(&mut pixmap, BACKGROUND);
    drop(strokes);
    marks(&mut pixmap, &scene, &frame, bbox, opts.color, rect);
    Drawing {
        pixmap,
        frame,
        scene,
        opts: *opts,
    }
}

/// Painter's algorithm for the preview's strokes: far (small depth) first,
/// print order among equals. That is a stable sort's order; it is made by
/// an unstable one (which needs no room beside the strokes) on the key
/// (depth, place in print order), a total order with no ties, so the one
/// sorted order whether the pool sorts it or this thread does.
fn sort_far_first(strokes: &mut [Px]) {
    for (i, px) in strokes.iter_mut().enumerate() {
        px.seq = i as u32;
    }
    par::sort_unstable_by_key(strokes, |p| (total_order(p.depth) << 32) | u64::from(p.seq));
}

/// The bits of `x` as an unsigned number in [`f32::total_cmp`]'s order
/// (−NaN < −∞ < … < −0 < +0 < … < +∞ < NaN): negative numbers' bits all
/// flipped, the others' sign bit set.
fn total_order(x: f32) -> u64 {
    let b = x.to_bits();
    u64::from(if b >> 31 == 1 { !b } else { b | 0x8000_0000 })
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

/// The G-code thumbnails of `scene` (as [`Scene::round`] reads it), one per
/// size: the model alone in filament colour, iso view, on a transparent
/// background, its strings round tubes at least 1 px wide.
///
/// The strokes are collected once, in print order, fitted to the largest
/// size (pieces of [`PIECE`] strings shared over the pool as the
/// preview's, no neighbouring pass looked for) and coloured. Each size
/// takes them scaled about the image's centre (a frame fitted to the same
/// box differs only in its scale, p' = c' + (s'/s)(p − c)); a smaller size
/// merges those its scale makes short again ([`remerge`]), so that its
/// strokes number about its own length of the model over
/// [`model::MERGE_PX`], not the largest size's; then they are sorted far to
/// near ([`sort_far_first`]), kept [`once`] and painted with the preview's
/// rasteriser in bands ([`paint_bands`]): the same bytes on any number of
/// threads.
pub(crate) fn thumbnails(scene: &Scene, sizes: &[Size]) -> Vec<Pixmap> {
    let Some((bi, &big)) = sizes
        .iter()
        .enumerate()
        .max_by_key(|(_, s)| u64::from(s.width) * u64::from(s.height))
    else {
        return Vec::new();
    };
    let rect = |s: Size| {
        let (w, h) = (f64::from(s.width), f64::from(s.height));
        let pad = (w.min(h) * 0.04).max(0.5);
        [pad, pad, w - pad, h - pad]
    };
    let model = Model::new(
        scene,
        super::View::Iso,
        ColorMode::Plain,
        rect(big),
        PIECE,
        Passes::Round,
        par::width(),
    );
    let (frame, (lo, hi)) = (model.frame, model.screen);
    let pal = Palette::of_model(&model, ColorMode::Plain);
    // a lit string in filament colour, `r` half its width at the largest
    // size; a travel faint and grey, 1 px at every size (alpha 90 marks it).
    // No marks: a thumbnail is the print as the printer's screen shows it,
    // not the turtles' draw_turtle markers
    let strokes = model.strokes(|it| match it.kind {
        1 => Px {
            rgb: [150, 155, 165],
            alpha: 90,
            r: 0.5,
            ..pal.px(it)
        },
        _ => Px {
            r: 0.5 * it.width,
            ..pal.px(it)
        },
    });
    drop(model);
    let pad = scene.pad();
    // a size's scale k against the largest, and a stroke scaled to it
    let scaling = |size: Size| {
        let to = Frame::fit_box(frame.basis, lo, hi, rect(size), pad);
        let k = if frame.scale > 0.0 {
            to.scale / frame.scale
        } else {
            0.0
        };
        let at = move |p: (f32, f32)| {
            let x = to.pixel_centre.0 + k * (f64::from(p.0) - frame.pixel_centre.0);
            let y = to.pixel_centre.1 + k * (f64::from(p.1) - frame.pixel_centre.1);
            (x as f32, y as f32)
        };
        let sized = move |p: &Px| Px {
            a: at(p.a),
            b: at(p.b),
            r: match p.alpha {
                255 => (f64::from(p.r) * k).max(0.5) as f32,
                _ => 0.5,
            },
            ..*p
        };
        (k, sized)
    };
    let paint = |size: Size, mut list: Vec<Px>| {
        sort_far_first(&mut list);
        let mut pm = Pixmap::new(size.width, size.height).expect("sizes are 1..=8192");
        paint_bands(&mut pm, &once(list));
        pm
    };
    let mut out: Vec<Option<Pixmap>> = sizes.iter().map(|_| None).collect();
    for (i, &size) in sizes.iter().enumerate().filter(|(i, _)| *i != bi) {
        let (k, sized) = scaling(size);
        let list: Vec<Px> = if k < 1.0 {
            remerge(&strokes, k).iter().map(sized).collect()
        } else {
            strokes.iter().map(sized).collect()
        };
        out[i] = Some(paint(size, list));
    }
    // the largest last, its strokes scaled where they lie: no copy of them
    let (_, sized) = scaling(big);
    let mut strokes = strokes;
    for p in &mut strokes {
        *p = sized(p);
    }
    out[bi] = Some(paint(big, strokes));
    out.into_iter()
        .map(|pm| pm.expect("every size is drawn"))
        .collect()
}

/// The strokes of `strokes` (in print order, pixels of the largest size)
/// for a size `k` times as large: consecutive strokes that join end to
/// start, alike in opacity (lit or travel), taken as one while shorter
/// than [`model::MERGE_PX`] at that size, as [`Model`] merges strings. The
/// merged stroke goes from the first's start to the last's end, at the
/// middle of their depths, coloured and as wide as its middle stroke.
fn remerge(strokes: &[Px], k: f64) -> Vec<Px> {
    let joins = |p: &Px, q: &Px| {
        p.alpha == q.alpha
            && p.b.0.to_bits() == q.a.0.to_bits()
            && p.b.1.to_bits() == q.a.1.to_bits()
    };
    let span = |a: (f32, f32), b: (f32, f32)| {
        let (dx, dy) = (f64::from(b.0 - a.0), f64::from(b.1 - a.1));
        k * (dx * dx + dy * dy).sqrt()
    };
    let mut out = Vec::new();
    let mut i = 0;
    while i < strokes.len() {
        let first = strokes[i];
        let mut end = i + 1;
        while span(first.a, strokes[end - 1].b) < model::MERGE_PX
            && end < strokes.len()
            && joins(&strokes[end - 1], &strokes[end])
        {
            end += 1;
        }
        let last = strokes[end - 1];
        out.push(Px {
            a: first.a,
            b: last.b,
            depth: 0.5 * (first.depth + last.depth),
            ..strokes[(i + end - 1) / 2]
        });
        i = end;
    }
    out
}

/// Bambu's top and pick pictures of `scene` (as [`Scene::round`] reads
/// it), `size` each, seen from above with the bed's box `bed` (recipe
/// coordinates, [x0, y0, x1, y1]) filling the picture as Bambu Studio
/// frames them, so that a pixel is a place on the bed; travels left out,
/// on a transparent background.
///
/// - The top picture: the strings lit in filament colour, as the
///   thumbnails draw them.
/// - The pick picture: object k (its paths `objects[k]`) in one flat,
///   opaque colour that numbers it, k + 1 = r + 256 g + 65536 b (Bambu
///   Studio's encoding of an object's id, the `identify_id` the package's
///   `slice_info.config` gives it), drawn without blending: a pixel is
///   an object's where its strings cover at least half of it (a string at
///   least 2 px wide), else transparent, never a mix of two colours. A
///   higher object is drawn over a lower one.
pub(crate) fn bed_views(
    scene: &Scene,
    size: Size,
    bed: [f64; 4],
    objects: &[std::ops::Range<usize>],
) -> (Pixmap, Pixmap) {
    let (w, h) = (f64::from(size.width), f64::from(size.height));
    let rect = [0.0, 0.0, w, h];
    let mut model = Model::new(
        scene,
        super::View::Top,
        ColorMode::Plain,
        rect,
        PIECE,
        Passes::Round,
        par::width(),
    );
    model.frame = Frame::fit_box(
        model.frame.basis,
        (bed[0], bed[1]),
        (bed[2], bed[3]),
        rect,
        0.0,
    );
    let pal = Palette::of_model(&model, ColorMode::Plain);
    // each lit stroke with its path (a travel's alpha 0 marks it, dropped)
    let mut strokes: Vec<(Px, u32)> = model.strokes(|it| match it.kind {
        1 => (Px::default(), 0),
        _ => (
            Px {
                r: (0.5 * it.width).max(0.5),
                ..pal.px(it)
            },
            it.path,
        ),
    });
    drop(model);
    strokes.retain(|(px, _)| px.alpha == 255);
    let mut lit: Vec<Px> = strokes.iter().map(|(px, _)| *px).collect();
    sort_far_first(&mut lit);
    let mut top = Pixmap::new(size.width, size.height).expect("sizes are 1..=8192");
    paint_bands(&mut top, &once(lit));
    (top, pick(size, &strokes, objects))
}

/// The pick picture of [`bed_views`] from its strokes and their paths.
fn pick(size: Size, strokes: &[(Px, u32)], objects: &[std::ops::Range<usize>]) -> Pixmap {
    let (width, height) = (size.width as usize, size.height as usize);
    let mut out = Pixmap::new(size.width, size.height).expect("sizes are 1..=8192");
    let mut mask = Pixmap::new(size.width, size.height).expect("sizes are 1..=8192");
    // the objects lowest first (the top of the highest stroke), so that a
    // higher one is drawn over it
    let mut order: Vec<(f32, usize)> = objects
        .iter()
        .enumerate()
        .map(|(k, paths)| {
            let top = strokes
                .iter()
                .filter(|(_, p)| paths.contains(&(*p as usize)))
                .map(|(px, _)| px.depth)
                .fold(f32::NEG_INFINITY, f32::max);
            (top, k)
        })
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    for (_, k) in order {
        let mine: Vec<Px> = strokes
            .iter()
            .filter(|(_, p)| objects[k].contains(&(*p as usize)))
            .map(|(px, _)| Px {
                rgb: [255, 255, 255],
                r: px.r.max(1.0),
                ..*px
            })
            .collect();
        if mine.is_empty() {
            continue;
        }
        mask.fill(tiny_skia::Color::TRANSPARENT);
        paint_bands(&mut mask, &mine);
        let id = k as u32 + 1;
        let colour = [id & 0xff, (id >> 8) & 0xff, (id >> 16) & 0xff, 255].map(|c| c as u8);
        let src = mask.data();
        let dst = out.data_mut();
        for i in 0..width * height {
            if src[4 * i + 3] >= 128 {
                dst[4 * i..4 * i + 4].copy_from_slice(&colour);
            }
        }
    }
    out
}

/// Each stroke painted once: of strokes alike in all that is drawn of them
/// (ends, width, depth, colour, opacity), only the last in painting order,
/// the one that shows, is kept: a line retraced 600 000 times is a stroke
/// each way, not 600 000 (whose painting took tens of seconds). Strokes
/// alike have one depth, so they lie together in the sorted `strokes`: only
/// a run of equal depths is searched.
fn once(mut strokes: Vec<Px>) -> Vec<Px> {
    let key = |p: &Px| {
        (
            [p.a.0, p.a.1, p.b.0, p.b.1, p.r].map(f32::to_bits),
            p.rgb,
            p.alpha,
        )
    };
    // kept in place: the strokes kept so far are strokes[..w], w ≤ i
    let mut seen = std::collections::HashSet::new();
    let (mut w, mut i) = (0, 0);
    while i < strokes.len() {
        let depth = strokes[i].depth.to_bits();
        let end = i + strokes[i..]
            .iter()
            .take_while(|p| p.depth.to_bits() == depth)
            .count();
        if end - i == 1 {
            strokes[w] = strokes[i];
            w += 1;
        } else {
            // the last of each alike, kept in painting order
            seen.clear();
            let mut run: Vec<Px> = strokes[i..end]
                .iter()
                .rev()
                .filter(|p| seen.insert(key(p)))
                .copied()
                .collect();
            run.reverse();
            strokes[w..w + run.len()].copy_from_slice(&run);
            w += run.len();
        }
        i = end;
    }
    strokes.truncate(w);
    strokes
}

/// PNG bytes of `pm`: RGB, or RGBA with `alpha` (colours un-premultiplied),
/// compressed quickly (fdeflate, `CompressionType::Fast`): zlib's default
/// level took most of a thumbnail's time, and thumbnails are made on every
/// build, for a file about a tenth smaller; a flat background and smooth
/// shading compress well even so.
pub(crate) fn encode(pm: &Pixmap, alpha: bool) -> Vec<u8> {
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
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    PngEncoder::new_with_quality(&mut out, CompressionType::Fast, FilterType::Adaptive)
        .write_image(&data, pm.width(), pm.height(), kind)
        .expect("PNG encoding into memory does not fail");
    out
}

#[cfg(test)]
mod tests {
    /// The sort key's order of depths is `f32::total_cmp`'s.
    #[test]
    fn total_order_is_total_cmp_s() {
        let xs = [
            f32::NEG_INFINITY,
            -1e30,
            -2.5,
            -1e-40,
            -0.0,
            0.0,
            1e-40,
            0.5,
            3.0,
            1e30,
            f32::INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        for a in xs {
            for b in xs {
                assert_eq!(
                    super::total_order(a).cmp(&super::total_order(b)),
                    a.total_cmp(&b),
                    "{a} {b}"
                );
            }
        }
    }

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
    fn a_smaller_size_merges_what_its_scale_makes_short() {
        // a lit chain of 40 strokes 2 px long, a travel, then 8 lit strokes
        // that do not join one another (gaps between them)
        let mut strokes: Vec<Px> = (0..40)
            .map(|i| Px {
                a: (2.0 * i as f32, 5.0),
                b: (2.0 * (i + 1) as f32, 5.0),
                depth: i as f32,
                r: 1.0,
                alpha: 255,
                ..Px::default()
            })
            .collect();
        strokes.push(Px {
            a: (80.0, 5.0),
            b: (80.0, 9.0),
            alpha: 90,
            ..Px::default()
        });
        strokes.extend((0..8).map(|i| Px {
            a: (80.0 + i as f32, 9.0),
            b: (80.5 + i as f32, 9.0),
            alpha: 255,
            ..Px::default()
        }));
        // at a quarter of the size a 2 px stroke is ½ px: four make one
        let m = remerge(&strokes, 0.25);
        assert_eq!(m.len(), 10 + 1 + 8);
        for (j, p) in m[..10].iter().enumerate() {
            assert_eq!(
                (p.a, p.b),
                ((8.0 * j as f32, 5.0), (8.0 * (j + 1) as f32, 5.0))
            );
            assert_eq!(p.depth, 4.0 * j as f32 + 1.5);
        }
        // the travel and the strokes that do not join stay their own
        assert_eq!(m[10].alpha, 90);
        assert!(m[11..]
            .iter()
            .zip(&strokes[41..])
            .all(|(p, q)| p.a == q.a && p.b == q.b));
        // at the size they were made for nothing merges
        assert_eq!(remerge(&strokes, 1.0).len(), strokes.len());
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
