//! Painting the strokes: the previews' own rasteriser of capsules in bands
//! of rows ([`paint_bands`]), for the PNG preview and the G-code
//! thumbnails.

use tiny_skia::Pixmap;

use crate::base::par;

/// Rows of pixels per band when the strokes are painted (a band is one
/// piece of work).
const BAND: usize = 32;

/// One stroke of the PNG preview, coloured, as the bands paint it.
#[derive(Clone, Copy, Default)]
pub(super) struct Px {
    pub(super) a: (f32, f32),
    pub(super) b: (f32, f32),
    pub(super) depth: f32,
    /// Half its width, px.
    pub(super) r: f32,
    pub(super) rgb: [u8; 3],
    /// Opacity, 0..=255.
    pub(super) alpha: u8,
    /// Its place in print order (ties of depth keep it).
    pub(super) seq: u32,
}

/// Paints the strokes (sorted far to near) into a transparent image in
/// bands of [`BAND`] rows, each band taken by whichever thread of the pool
/// is free ([`par::each`]).
///
/// A stroke is a capsule: the points within r (half its width) of segment
/// a–b. A pixel is covered by the overlap of its width with the capsule
/// across the line through its centre at distance d: min(d + ½, r) −
/// max(d − ½, −r), clamped to [0, 1] (a box filter; 1 inside, 0 beyond
/// r + ½), and takes the stroke's colour in that share times its opacity.
///
/// Near to far: each stroke goes *under* what is painted already
/// (premultiplied, dst += src·α·(1 − dst_α), in integers rounded the same
/// way everywhere), which gives the picture painting far to near over it
/// gives (Porter and Duff's over is associative), but a pixel already
/// opaque is passed over before its distance is measured, and a band whose
/// pixels are all opaque stops: the hidden back of a dense model costs
/// next to nothing. Each band paints every stroke that reaches it, in
/// order, so a pixel's result does not depend on how the image is cut into
/// bands. The caller lays the result over its background ([`over`]), or
/// keeps it transparent (the thumbnails).
pub(super) fn paint_bands(pm: &mut Pixmap, strokes: &[Px]) {
    let (width, height) = (pm.width() as usize, pm.height() as usize);
    let bins = bins(strokes, height);
    let mut bands: Vec<(&[u32], usize, &mut [u8])> = pm
        .data_mut()
        .chunks_mut(width * 4 * BAND)
        .zip(&bins)
        .enumerate()
        .map(|(i, (band, bin))| (bin.as_slice(), i * BAND, band))
        .collect();
    par::each(&mut bands, |(bin, y0, band)| {
        let y1 = *y0 + band.len() / (4 * width);
        let mut clear = band.len() / 4;
        for (j, &i) in bin.iter().rev().enumerate() {
            // a band's strokes lie scattered in the depth order: each was a
            // cache miss when fetched only as it was painted
            if let Some(&ahead) = bin.len().checked_sub(j + PREFETCH + 1).map(|k| &bin[k]) {
                prefetch(&strokes[ahead as usize]);
            }
            clear -= capsule(band, width, *y0, y1, &strokes[i as usize]);
            if clear == 0 {
                break; // every pixel of the band is opaque
            }
        }
    });
}

/// `pm` (premultiplied, as [`paint_bands`] leaves it) laid over an opaque
/// `background`: c + bg·(1 − α) per channel, then opaque.
pub(super) fn over(pm: &mut Pixmap, background: [u8; 3]) {
    for p in pm.data_mut().chunks_exact_mut(4) {
        let rem = 255 - u32::from(p[3]);
        for (c, bg) in p.iter_mut().zip(background) {
            *c += ((u32::from(bg) * rem + 127) / 255) as u8;
        }
        p[3] = 255;
    }
}

/// Per band of [`BAND`] rows of an image `height` rows tall, the strokes
/// that reach it, in painting order.
fn bins(strokes: &[Px], height: usize) -> Vec<Vec<u32>> {
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); height.div_ceil(BAND)];
    for (i, px) in strokes.iter().enumerate() {
        if !(px.r.is_finite() && px.a.1.is_finite() && px.b.1.is_finite()) {
            continue; // not a number: [`capsule`] paints none of it
        }
        let ext = px.r + 0.5;
        let top = floor(px.a.1.min(px.b.1) - ext);
        let bottom = ceil(px.a.1.max(px.b.1) + ext).min(height as f32);
        if !(top < bottom && bottom > 0.0) {
            continue; // off the image
        }
        let first = top.max(0.0) as usize / BAND;
        let last = (bottom as usize - 1) / BAND;
        for bin in &mut bins[first..=last] {
            bin.push(i as u32);
        }
    }
    bins
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

/// Lays stroke `px` under what rows `y0..y1` of a premultiplied RGBA
/// image `width` pixels wide, held in `band`, already hold (see
/// [`paint_bands`]); returns how many of its pixels it made opaque.
fn capsule(band: &mut [u8], width: usize, y0: usize, y1: usize, px: &Px) -> usize {
    let (a, b, r) = (px.a, px.b, px.r);
    if !(r.is_finite() && a.0.is_finite() && a.1.is_finite() && b.0.is_finite() && b.1.is_finite())
    {
        return 0;
    }
    let alpha = f32::from(px.alpha);
    let ext = r + 0.5;
    let top = floor(a.1.min(b.1) - ext).max(y0 as f32);
    let bottom = ceil(a.1.max(b.1) + ext).min(y1 as f32);
    let left = floor(a.0.min(b.0) - ext).max(0.0);
    let right = ceil(a.0.max(b.0) + ext).min(width as f32);
    if top >= bottom || left >= right {
        return 0;
    }
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let inv = if l2 > 0.0 { 1.0 / l2 } else { 0.0 };
    let src = px.rgb.map(u32::from);
    // beyond r + ½ a pixel has no share (min(d + ½, r) ≤ r ≤ max(d − ½, −r));
    // tested on the square distance, a little beyond (the square rounded
    // in f32 stays below it), to skip the square root there
    let far = (ext * 1.001 + 1e-3) * (ext * 1.001 + 1e-3);
    let mut filled = 0;
    for y in top as usize..bottom as usize {
        let py = y as f32 + 0.5 - a.1;
        let row = &mut band[(y - y0) * width * 4..(y - y0 + 1) * width * 4];
        for x in left as usize..right as usize {
            let p = &mut row[4 * x..4 * x + 4];
            if p[3] == 255 {
                continue; // hidden by what is nearer
            }
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
            // under: the share k of what still shows, w = k·(255 − α)
            let w = k * (255 - u32::from(p[3]));
            for (c, s) in p.iter_mut().zip(src) {
                *c += ((s * w + 32_512) / 65_025) as u8;
            }
            p[3] += ((w + 127) / 255) as u8;
            filled += usize::from(p[3] == 255);
        }
    }
    filled
}

/// ⌊x⌋ for the finite x of a stroke's box, without a call to the C
/// library's `floorf` (no SSE4.1 on every x86_64); beyond ±2³¹ it gives
/// ±2³¹, which the box's clamps to the image make the same.
#[inline]
fn floor(x: f32) -> f32 {
    let i = x as i32 as f32;
    if i > x {
        i - 1.0
    } else {
        i
    }
}

/// ⌈x⌉ as [`floor`] gives ⌊x⌋.
#[inline]
fn ceil(x: f32) -> f32 {
    -floor(-x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_and_ceil_are_the_library_s() {
        for x in [
            -3.5f32, -3.0, -0.2, -0.0, 0.0, 0.2, 2.0, 2.7, 8191.5, 1e12, -1e12,
        ] {
            let clamp = |v: f32| v.clamp(-2e9, 2e9);
            assert_eq!(clamp(floor(x)), clamp(x.floor()), "{x}");
            assert_eq!(clamp(ceil(x)), clamp(x.ceil()), "{x}");
        }
    }
}
