//! `label`: digits and short words drawn as printable strokes, for the
//! bands of a calibration print and the lines of a line test.
//!
//! The font is a seven-segment display's: each glyph is made of up to seven
//! straight strokes on a box `height` tall and `height/2` wide (a, the top;
//! b, c the right side top and bottom; d the bottom; e, f the left side
//! bottom and top; g the middle), a stroke of the nozzle's width each. Every
//! digit, `-`, `.`, a space and the letters a seven-segment display shows
//! (`A b C d E F G H I J L n o P r S t U y`) are drawn; the label is laid
//! `layers` times, one `layer_height` above the other, so it stands out.

use glam::{DVec2, DVec3};

use crate::base::toolpath::Toolpath;

/// The segments of a glyph (bit 0 = a … bit 6 = g), `None` for a character
/// the font has no glyph for. `.` is drawn apart.
pub(crate) fn segments(ch: char) -> Option<u8> {
    const A: u8 = 1;
    const B: u8 = 2;
    const C: u8 = 4;
    const D: u8 = 8;
    const E: u8 = 16;
    const F: u8 = 32;
    const G: u8 = 64;
    Some(match ch {
        '0' | 'O' => A | B | C | D | E | F,
        '1' => B | C,
        '2' => A | B | G | E | D,
        '3' => A | B | G | C | D,
        '4' => F | G | B | C,
        '5' | 'S' | 's' => A | F | G | C | D,
        '6' => A | F | G | E | D | C,
        '7' => A | B | C,
        '8' => A | B | C | D | E | F | G,
        '9' => A | B | C | D | F | G,
        '-' => G,
        ' ' | '.' => 0,
        'A' | 'a' => A | B | C | E | F | G,
        'b' | 'B' => F | E | D | C | G,
        'C' | 'c' => A | F | E | D,
        'd' | 'D' => B | C | D | E | G,
        'E' | 'e' => A | F | G | E | D,
        'F' | 'f' => A | F | G | E,
        'G' | 'g' => A | F | E | D | C,
        'H' | 'h' => F | E | G | B | C,
        'I' | 'i' => E | F,
        'J' | 'j' => B | C | D,
        'L' | 'l' => F | E | D,
        'n' | 'N' => E | G | C,
        'o' => C | D | E | G,
        'P' | 'p' => A | B | F | G | E,
        'r' | 'R' => E | G,
        't' | 'T' => F | E | D | G,
        'U' | 'u' => B | C | D | E | F,
        'y' | 'Y' => F | G | B | C | D,
        _ => return None,
    })
}

/// The characters the font draws, for messages.
pub(crate) const CHARSET: &str = "0-9, `-`, `.`, a space and A b C d E F G H I J L n o P r S t U y";

/// A label: its text laid `layers` times from `center.z` up.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Label {
    /// The text (every character one [`segments`] knows).
    pub(crate) text: String,
    /// The middle of the label's bottom edge; z the first layer's height.
    pub(crate) center: DVec3,
    /// A glyph's height, mm.
    pub(crate) height: f64,
    /// Layers of strokes.
    pub(crate) layers: u32,
    /// Between layers, mm.
    pub(crate) layer_height: f64,
    /// The text's direction, radians counter-clockwise from +x.
    pub(crate) angle: f64,
}

/// A stroke's ends on a glyph box of width w and height h: a … g.
fn stroke(k: u8, w: f64, h: f64) -> [DVec2; 2] {
    let m = h / 2.0;
    let p = |x: f64, y: f64| DVec2::new(x, y);
    match k {
        0 => [p(0.0, h), p(w, h)],
        1 => [p(w, h), p(w, m)],
        2 => [p(w, m), p(w, 0.0)],
        3 => [p(w, 0.0), p(0.0, 0.0)],
        4 => [p(0.0, 0.0), p(0.0, m)],
        5 => [p(0.0, m), p(0.0, h)],
        _ => [p(0.0, m), p(w, m)],
    }
}

impl Label {
    /// A glyph's width, mm.
    fn width(&self) -> f64 {
        self.height / 2.0
    }

    /// From one glyph's start to the next's, mm.
    fn advance(&self) -> f64 {
        self.width() + 0.4 * self.height
    }

    /// The strokes of one layer, in the label's own frame (x along the
    /// text from its left end, y up the glyphs), in drawing order.
    pub(crate) fn strokes(&self) -> Vec<[DVec2; 2]> {
        let (w, h) = (self.width(), self.height);
        let mut out = Vec::new();
        for (j, ch) in self.text.chars().enumerate() {
            let x0 = j as f64 * self.advance();
            let off = DVec2::new(x0, 0.0);
            if ch == '.' {
                let d = (0.1 * h).max(0.4);
                out.push([off + DVec2::new(w / 2.0, 0.0), off + DVec2::new(w / 2.0, d)]);
                continue;
            }
            let bits = segments(ch).unwrap_or(0);
            for k in 0..7u8 {
                if bits & (1 << k) != 0 {
                    let [a, b] = stroke(k, w, h);
                    out.push([off + a, off + b]);
                }
            }
        }
        out
    }

    /// Strings of one layer: at most two per stroke (a travel and a draw).
    pub(crate) fn string_count(&self) -> u64 {
        2 * self.strokes().len() as u64 * u64::from(self.layers)
    }

    /// Makes the strings: each layer's strokes, a stroke that starts where
    /// the one before ended drawn on without a travel.
    pub(crate) fn build(&self, c: f64, v: f64) -> Toolpath {
        let strokes = self.strokes();
        let n = self.text.chars().count() as f64;
        let span = (n * self.advance() - 0.4 * self.height).max(0.0);
        let (s, co) = (libm::sin(self.angle), libm::cos(self.angle));
        let place = |q: DVec2, z: f64| {
            let x = q.x - span / 2.0;
            self.center + DVec3::new(x * co - q.y * s, x * s + q.y * co, 0.0) + DVec3::Z * z
        };
        let first = strokes.first().map_or(self.center, |s| place(s[0], 0.0));
        let mut t = Toolpath::new(first);
        for l in 0..self.layers {
            let z = f64::from(l) * self.layer_height;
            for [a, b] in &strokes {
                let (a, b) = (place(*a, z), place(*b, z));
                if t.head().distance(a) > 1e-9 {
                    t.travel(a, v);
                }
                t.draw(b, c, v);
            }
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn label(text: &str) -> Label {
        Label {
            text: text.into(),
            center: DVec3::new(10.0, 20.0, 0.2),
            height: 6.0,
            layers: 2,
            layer_height: 0.2,
            angle: 0.0,
        }
    }

    #[test]
    fn an_eight_is_seven_strokes_and_a_one_two() {
        assert_eq!(label("8").strokes().len(), 7);
        assert_eq!(label("1").strokes().len(), 2);
        assert_eq!(label("1.5").strokes().len(), 2 + 1 + 5);
        assert!(segments('#').is_none());
    }

    #[test]
    fn a_label_is_centred_and_laid_in_layers() {
        let t = label("230").build(0.1, 20.0);
        let ext: Vec<usize> = (0..t.len()).filter(|&k| !t.strings[k].travel).collect();
        assert_eq!(ext.len(), 2 * (5 + 5 + 6));
        let xs = t.points.iter().map(|p| p.x);
        let (lo, hi) = xs.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
        // three glyphs 3 mm wide, 2.4 mm apart: 13.8 mm about x = 10
        assert!((lo - (10.0 - 6.9)).abs() < 1e-9 && (hi - (10.0 + 6.9)).abs() < 1e-9);
        let zs: Vec<f64> = ext.iter().map(|&k| t.points[k + 1].z).collect();
        assert!(zs[..16].iter().all(|z| (z - 0.2).abs() < 1e-12));
        assert!(zs[16..].iter().all(|z| (z - 0.4).abs() < 1e-12));
        assert!(t.len() as u64 <= label("230").string_count());
    }
}
