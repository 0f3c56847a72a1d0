//! Small text for the previews: the `font8x8` crate's 8 × 8 glyphs (Basic
//! Latin and Latin-1, so `×`, `²`, `³` and `°` too), each lit font pixel
//! filled as a `scale` × `scale` square of image pixels.

use font8x8::UnicodeFonts;
use tiny_skia::{Pixmap, PremultipliedColorU8};

/// Advance of one glyph at scale 1, px.
pub(super) const ADVANCE: u32 = 8;

/// The glyph of `ch`, or a box for characters the font lacks.
fn glyph(ch: char) -> [u8; 8] {
    // font8x8 0.3 files ³ and ´ under U+00B2 too, and finds ´ for ²: its own
    // bitmaps of ² and ³ (LATIN_UNICODE[18] and [19]), given here
    match ch {
        '²' => return [0x1c, 0x30, 0x18, 0x0c, 0x3c, 0, 0, 0],
        '³' => return [0x1c, 0x30, 0x18, 0x30, 0x1c, 0, 0, 0],
        _ => {}
    }
    font8x8::BASIC_FONTS
        .get(ch)
        .or_else(|| font8x8::LATIN_FONTS.get(ch))
        .unwrap_or([0x7e, 0x42, 0x42, 0x42, 0x42, 0x42, 0x7e, 0x00])
}

/// Width of `s` drawn at `scale`, px.
pub(super) fn width(s: &str, scale: u32) -> u32 {
    s.chars().count() as u32 * ADVANCE * scale
}

/// Draws `s` with its top-left corner at (x, y), opaque `rgb`; clipped to the image.
pub(super) fn draw(pm: &mut Pixmap, x: i32, y: i32, scale: u32, s: &str, rgb: [u8; 3]) {
    let (w, h) = (pm.width() as i32, pm.height() as i32);
    let colour = PremultipliedColorU8::from_rgba(rgb[0], rgb[1], rgb[2], 255)
        .expect("opaque colours are valid");
    let sc = scale as i32;
    let pixels = pm.pixels_mut();
    for (n, ch) in s.chars().enumerate() {
        let gx = x + n as i32 * ADVANCE as i32 * sc;
        for (row, bits) in glyph(ch).iter().enumerate() {
            for col in 0..8 {
                // bit 0 is the leftmost pixel of the row
                if bits >> col & 1 == 0 {
                    continue;
                }
                for dy in 0..sc {
                    for dx in 0..sc {
                        let px = gx + col * sc + dx;
                        let py = y + row as i32 * sc + dy;
                        if px >= 0 && py >= 0 && px < w && py < h {
                            pixels[(py * w + px) as usize] = colour;
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_lit_pixels_inside_the_advance() {
        let mut pm = Pixmap::new(40, 20).unwrap();
        draw(&mut pm, 2, 2, 2, "H×", [255, 255, 255]);
        let lit: Vec<(u32, u32)> = (0..20)
            .flat_map(|y| (0..40).map(move |x| (x, y)))
            .filter(|&(x, y)| pm.pixel(x, y).unwrap().alpha() == 255)
            .collect();
        assert!(!lit.is_empty());
        assert!(lit
            .iter()
            .all(|&(x, y)| (2..34).contains(&x) && (2..18).contains(&y)));
        // text running off the edge is clipped, not a panic
        draw(&mut pm, 30, 15, 3, "WWW", [1, 2, 3]);
        assert_eq!(width("ab", 3), 48);
    }
}
