//! The bowl of Kanada's Fig. 12 (right): letters on a dome printed upside down.
//!
//! The strings' letter/background factors are read off the build (compared
//! with the same recipe without its `modulate_map`), then mapped the way a
//! person sees the finished bowl: turned over about the x axis
//! ((x, y, z) → (x, −y, −z)) and read from outside, where left to right is
//! counter-clockwise seen from above. The glyph grid so reconstructed must
//! match the 8 × 8 font's rendering of the text, not its mirror image.
//!
//! Past the public face: the `modulate_map` step is taken off
//! `Recipe::parts[0].steps` (`Step::key`), and the font's rendering is
//! `generate::step::Bitmap::from_text`. Home: beside `generate::step::modulate`.

use crate::base::testing::*;
use crate::generate::step::Bitmap;

const TEXT: &str = "PROCEDURAL 3D PRINTING  ";

fn letter_strings() -> (crate::base::toolpath::Toolpath, Vec<bool>, f64) {
    let mut recipe = crate::recipe::load(&recipe("bowl.yaml"), &[], None).unwrap();
    let repeat = recipe.params["repeat"];
    let fin = crate::generate::model::make_part(&recipe, 0).unwrap();
    assert_eq!(recipe.parts[0].steps.pop().unwrap().key(), "modulate_map");
    let base = crate::generate::model::make_part(&recipe, 0).unwrap();
    let letter = fin
        .strings
        .iter()
        .zip(&base.strings)
        .map(|(a, b)| {
            let f = a.c / b.c;
            assert!(
                (f - 1.0).abs() < 1e-12 || (f - 1.35).abs() < 1e-12,
                "factor {f}"
            );
            // constant flow: the head slows down over letters
            assert!((a.c * a.v - b.c * b.v).abs() < 1e-9);
            f > 1.0
        })
        .collect();
    (fin, letter, repeat)
}

#[test]
fn letters_only_in_the_band_and_read_from_outside_once_turned_over() {
    let (tp, letter, repeat) = letter_strings();
    let bitmap = Bitmap::from_text(TEXT).unwrap();
    let (lo, hi) = (12f64, 42f64); // band_lo, band_hi of the recipe
    let (w, h) = (bitmap.width, bitmap.height);
    // votes[row][col] = (letter strings, all strings) over one copy of the text
    let mut votes = vec![(0usize, 0usize); w * h];
    for (k, &is_letter) in letter.iter().enumerate() {
        let m = tp.midpoint(k);
        let lat = ((m.z - 0.3) / 40.0).clamp(-1.0, 1.0).asin().to_degrees();
        if lat < lo || lat > hi {
            assert!(!is_letter, "a letter outside the band at latitude {lat}");
            continue;
        }
        // turned over: theta_final = atan2(-y, x); `repeat` copies around
        let theta_final = (-m.y).atan2(m.x).rem_euclid(std::f64::consts::TAU);
        let u = (theta_final * repeat / std::f64::consts::TAU).fract();
        let v = (lat - lo) / (hi - lo); // the glyphs' tops towards the rim
        let col = ((u * w as f64) as usize).min(w - 1);
        let row = ((v * h as f64) as usize).min(h - 1);
        votes[row * w + col].1 += 1;
        if is_letter {
            votes[row * w + col].0 += 1;
        }
    }
    let read: Vec<bool> = votes.iter().map(|(l, n)| *n > 0 && 2 * l > *n).collect();
    let agree = |mirror: bool| {
        (0..w)
            .map(|s| {
                (0..h)
                    .flat_map(|r| (0..w).map(move |c| (r, c)))
                    .filter(|&(r, c)| {
                        let cc = if mirror {
                            (w - 1 - c + s) % w
                        } else {
                            (c + s) % w
                        };
                        read[r * w + c] == (bitmap.pixels[r * w + cc] < 0.5)
                    })
                    .count()
            })
            .max()
            .unwrap() as f64
            / (w * h) as f64
    };
    let (right, mirrored) = (agree(false), agree(true));
    assert!(right > 0.97, "the text reads back {right:.3}");
    assert!(mirrored < right - 0.1, "mirror {mirrored:.3} vs {right:.3}");
}
