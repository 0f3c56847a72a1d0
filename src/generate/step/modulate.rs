//! `modulate_cylinder` and `modulate_map`: texture by changing the
//! cross-section (Kanada, section 3.5). With `keep: flow` the head speed is
//! divided by the same factor, so the extruder's flow c·v never changes and
//! only the head's (fast-responding) speed does — the paper's way.

use glam::DVec3;

use super::{not_finite, vars_at, Keep};
use crate::base::error::{Error, Result};
use crate::base::expr::{var, Expr, Memo};
use crate::base::toolpath::Toolpath;

/// Cross-section multiplied by an expression of the midpoint.
#[derive(Clone, Debug)]
pub(crate) struct Modulate {
    /// The factor fm.
    pub(crate) factor: Expr,
    /// What stays constant.
    pub(crate) keep: Keep,
}

/// A grey-level image, values 0 (black) to 1 (white).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Bitmap {
    /// Width in pixels.
    pub(crate) width: usize,
    /// Height in pixels.
    pub(crate) height: usize,
    /// Row-major luminance, 0..1, row 0 at the top.
    pub(crate) pixels: Vec<f32>,
}

impl Bitmap {
    /// The pixel at image coordinates (u, v) in 0..1, u left→right, v
    /// top→bottom, clamped to the image (nearest pixel, no blending).
    pub(crate) fn at(&self, u: f64, v: f64) -> f32 {
        let col = ((u * self.width as f64).floor().max(0.0) as usize).min(self.width - 1);
        let row = ((v * self.height as f64).floor().max(0.0) as usize).min(self.height - 1);
        self.pixels[row * self.width + col]
    }
}

impl Bitmap {
    /// `text` in one line of 8 × 8 glyphs (the `font8x8` crate's), one light
    /// column between letters and a light border of one pixel all round, so
    /// that looking up outside the text (clamped to the edge) finds background.
    pub(crate) fn from_text(text: &str) -> Result<Bitmap> {
        use font8x8::UnicodeFonts;
        if text.is_empty() {
            return Err(Error::input(
                "",
                "the text is empty; expected at least one character",
            ));
        }
        let chars: Vec<char> = text.chars().collect();
        if chars.len() > crate::base::input::MAX_MAP_TEXT_CHARS {
            return Err(Error::input(
                "",
                format!(
                    "the text has {} characters; expected at most {}",
                    chars.len(),
                    crate::base::input::MAX_MAP_TEXT_CHARS
                ),
            ));
        }
        let width = 1 + 9 * chars.len();
        let height = 10;
        let mut pixels = vec![1.0f32; width * height];
        for (k, ch) in chars.iter().enumerate() {
            let glyph = font8x8::BASIC_FONTS
                .get(*ch)
                .or_else(|| font8x8::LATIN_FONTS.get(*ch))
                .ok_or_else(|| {
                    Error::input(
                        "",
                        format!("no glyph for `{ch}` in the 8x8 font (Basic Latin and Latin-1)"),
                    )
                })?;
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    // bit 0 is the leftmost pixel of the row
                    if bits >> col & 1 == 1 {
                        pixels[(1 + row) * width + 1 + 9 * k + col] = 0.0;
                    }
                }
            }
        }
        Ok(Bitmap {
            width,
            height,
            pixels,
        })
    }
}

/// Cross-section multiplied by `dark` or `light` as the image says.
#[derive(Clone, Debug)]
pub(crate) struct ModulateMap {
    /// The image.
    pub(crate) image: Bitmap,
    /// u coordinate expression.
    pub(crate) u: Expr,
    /// v coordinate expression.
    pub(crate) v: Expr,
    /// Factor where the pixel is darker than `threshold`.
    pub(crate) dark: f64,
    /// Factor elsewhere.
    pub(crate) light: f64,
    /// Luminance threshold, 0..1.
    pub(crate) threshold: f64,
    /// What stays constant.
    pub(crate) keep: Keep,
}

fn scale(tp: &mut Toolpath, k: usize, f: f64, keep: Keep) {
    let s = &mut tp.strings[k];
    s.c *= f;
    if keep == Keep::Flow {
        s.v /= f;
    }
}

impl Modulate {
    /// Scales every extruding string.
    pub(crate) fn apply(&self, tp: &mut Toolpath) -> Result<()> {
        let n = tp.len();
        let mut memo = Memo::default();
        for k in 0..n {
            let s = tp.strings[k];
            if s.travel {
                continue;
            }
            let m = tp.midpoint(k);
            let mut vars = vars_at(m, k, n, true);
            vars[var::C] = s.c;
            vars[var::V] = s.v;
            vars[var::S] = tp.s_at_string(k);
            let f = self.factor.eval_in(&vars, &mut memo);
            check_factor(&self.factor, f, k, m)?;
            scale(tp, k, f, self.keep);
        }
        Ok(())
    }
}

fn check_factor(e: &Expr, f: f64, k: usize, m: DVec3) -> Result<()> {
    if !f.is_finite() {
        return Err(not_finite("factor", e.src(), f, "string", k, m));
    }
    if f <= 0.0 {
        return Err(Error::input(
            "",
            format!(
                "factor `{}` gives {f} at string {k}, midpoint (x, y, z) = ({:.3}, {:.3}, {:.3}); expected a factor > 0",
                e.src(),
                m.x,
                m.y,
                m.z
            ),
        ));
    }
    Ok(())
}

impl ModulateMap {
    /// Looks up each extruding string's midpoint in the image and scales it.
    pub(crate) fn apply(&self, tp: &mut Toolpath) -> Result<()> {
        let n = tp.len();
        let mut memo = Memo::default();
        for k in 0..n {
            if tp.strings[k].travel {
                continue;
            }
            let m = tp.midpoint(k);
            let mut vars = vars_at(m, k, n, true);
            vars[var::S] = tp.s_at_string(k);
            let u = self.u.eval_in(&vars, &mut memo);
            let v = self.v.eval_in(&vars, &mut memo);
            if !u.is_finite() {
                return Err(not_finite("u", self.u.src(), u, "string", k, m));
            }
            if !v.is_finite() {
                return Err(not_finite("v", self.v.src(), v, "string", k, m));
            }
            let dark = (self.image.at(u, v) as f64) < self.threshold;
            scale(tp, k, if dark { self.dark } else { self.light }, self.keep);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::expr::Params;

    fn ex(src: &str) -> Expr {
        let all: Vec<usize> = (0..var::COUNT).collect();
        Expr::compile(src, &Params::new(), &all).unwrap()
    }

    fn two_strings() -> Toolpath {
        let mut t = Toolpath::new(DVec3::new(0.0, 0.0, 0.0));
        t.draw(DVec3::new(1.0, 0.0, 0.0), 0.2, 10.0);
        t.draw(DVec3::new(2.0, 0.0, 0.0), 0.2, 10.0);
        t
    }

    #[test]
    fn keep_flow_keeps_c_times_v() {
        let m = Modulate {
            factor: ex("1 + x"),
            keep: Keep::Flow,
        };
        let mut t = two_strings();
        m.apply(&mut t).unwrap();
        for s in &t.strings {
            assert!((s.c * s.v - 2.0).abs() < 1e-12);
        }
        assert!((t.strings[0].c - 0.3).abs() < 1e-12);
        assert!((t.strings[1].c - 0.5).abs() < 1e-12);
    }

    #[test]
    fn map_picks_dark_or_light() {
        let image = Bitmap {
            width: 2,
            height: 1,
            pixels: vec![0.0, 1.0],
        };
        let m = ModulateMap {
            image,
            u: ex("x / 2"),
            v: ex("0"),
            dark: 1.0,
            light: 0.5,
            threshold: 0.5,
            keep: Keep::Speed,
        };
        let mut t = two_strings();
        m.apply(&mut t).unwrap();
        assert_eq!(t.strings[0].c, 0.2); // midpoint x = 0.5 → u = 0.25: dark
        assert_eq!(t.strings[1].c, 0.1); // midpoint x = 1.5 → u = 0.75: light
        assert_eq!(t.strings[1].v, 10.0);
    }

    #[test]
    fn text_renders_glyphs_with_a_light_border() {
        let b = Bitmap::from_text("IL").unwrap();
        assert_eq!((b.width, b.height), (19, 10));
        // the border and the gap between letters are light
        assert!((0..b.width).all(|c| b.pixels[c] == 1.0 && b.pixels[9 * b.width + c] == 1.0));
        assert!((0..b.height).all(|r| b.pixels[r * b.width + 9] == 1.0));
        // `L` has a full-height left stroke and a bottom bar
        let dark = |r: usize, c: usize| b.pixels[r * b.width + c] == 0.0;
        let l0 = 10;
        assert!((1..8).filter(|&r| (l0..l0 + 8).any(|c| dark(r, c))).count() >= 6);
        assert!((l0..l0 + 8).filter(|&c| dark(7, c)).count() >= 5);
        assert!(Bitmap::from_text("").is_err());
        assert!(Bitmap::from_text("\u{1F600}").is_err());
    }

    #[test]
    fn zero_factor_is_refused() {
        let m = Modulate {
            factor: ex("x - 0.5"),
            keep: Keep::Flow,
        };
        let e = m.apply(&mut two_strings()).unwrap_err();
        assert!(e.message.contains("expected a factor > 0"), "{e}");
    }
}
