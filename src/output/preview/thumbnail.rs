//! G-code thumbnails, in the form PrusaSlicer writes and Prusa and Creality
//! printers (and OctoPrint, Moonraker…) read: after the header comments, per
//! size asked for by the printer profile's `thumbnails: ["220x124", "16x16"]`,
//!
//! ```text
//! ; thumbnail begin 220x124 LEN
//! ; iVBORw0KGgo…            (base64 of a PNG, lines of at most 78 characters)
//! ; thumbnail end
//! ;
//! ```
//!
//! with LEN the length of the base64 text. The image is the iso view of the
//! model in filament colour on a transparent background; it is rendered from
//! the plan, so the G-code stays a function of the recipe (and its hash
//! deterministic).

use base64::Engine;

use super::{png, Scene, Size};
use crate::analyse::plan::Plan;
use crate::base::error::Result;
use crate::machine::size::{thumbnails, ImageFormat, Thumbnail as ThumbSpec};

/// Characters of base64 per comment line (PrusaSlicer's).
pub(crate) const LINE: usize = 78;

#[cfg(test)]
/// One thumbnail block for a PNG of `size`.
pub(crate) fn block(size: Size, png: &[u8]) -> String {
    block_of(ImageFormat::Png, size, png)
}

/// One thumbnail block for an image of `size` in `format`: PrusaSlicer's
/// `; thumbnail begin` (PNG), `; thumbnail_QOI begin`, `; thumbnail_JPG begin`.
pub(crate) fn block_of(format: ImageFormat, size: Size, bytes: &[u8]) -> String {
    let b64 = base64::engine::general_purpose::STANDARD.encode(bytes);
    let tag = match format {
        ImageFormat::Png => "thumbnail",
        ImageFormat::Qoi => "thumbnail_QOI",
        ImageFormat::Jpg => "thumbnail_JPG",
    };
    let mut s = format!(
        "; {tag} begin {}x{} {}\n",
        size.width,
        size.height,
        b64.len()
    );
    for chunk in b64.as_bytes().chunks(LINE) {
        s.push_str("; ");
        s.push_str(std::str::from_utf8(chunk).expect("base64 is ASCII"));
        s.push('\n');
    }
    s.push_str(&format!("; {tag} end\n;\n"));
    s
}

/// The thumbnails `plan`'s printer asks for, each its image's bytes in its
/// format (empty when none).
pub(crate) fn images(plan: &Plan) -> Result<Vec<(ThumbSpec, Vec<u8>)>> {
    let list = &plan.recipe.printer.thumbnails;
    if list.is_empty() {
        return Ok(Vec::new());
    }
    let specs = thumbnails(list).map_err(|e| e.in_file(&plan.recipe.printer.name))?;
    // a picture's work grows with the model's extent, as a preview's: a
    // model metres away is refused before it is drawn
    crate::analyse::check::within_reach(&plan.recipe, &plan.paths, plan.extent.points, "thumbnail")
        .map_err(|e| e.in_file(&plan.path))?;
    let sizes: Vec<Size> = specs.iter().map(|t| t.size).collect();
    let pixmaps = png::thumbnails(&Scene::round(plan), &sizes);
    Ok(specs
        .into_iter()
        .zip(pixmaps)
        .map(|(t, pm)| (t, encode(&pm, t.format)))
        .collect())
}

/// The bytes of `pm` in `format`: PNG and QOI keep the transparent
/// background (QOI's colours un-premultiplied, sRGB); JPEG, which has no
/// alpha, lays the image on white (quality 90).
pub(crate) fn encode(pm: &tiny_skia::Pixmap, format: ImageFormat) -> Vec<u8> {
    match format {
        ImageFormat::Png => png::encode(pm, true),
        ImageFormat::Qoi => {
            let mut rgba = Vec::with_capacity(pm.pixels().len() * 4);
            for px in pm.pixels() {
                let c = px.demultiply();
                rgba.extend_from_slice(&[c.red(), c.green(), c.blue(), c.alpha()]);
            }
            qoi::encode_to_vec(&rgba, pm.width(), pm.height())
                .expect("a thumbnail's size is within QOI's")
        }
        ImageFormat::Jpg => {
            let mut rgb = Vec::with_capacity(pm.pixels().len() * 3);
            for px in pm.pixels() {
                // premultiplied colour over white: c + (255 − a)
                let white = 255 - px.alpha();
                rgb.extend_from_slice(&[px.red() + white, px.green() + white, px.blue() + white]);
            }
            let mut out = Vec::new();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 90)
                .encode(
                    &rgb,
                    pm.width(),
                    pm.height(),
                    image::ExtendedColorType::Rgb8,
                )
                .expect("JPEG encoding into memory does not fail");
            out
        }
    }
}

/// A PNG thumbnail of `plan`, `width` × `height` pixels.
pub(crate) fn png_of(plan: &Plan, width: u32, height: u32) -> Vec<u8> {
    let pm = png::thumbnails(&Scene::round(plan), &[Size { width, height }]);
    png::encode(&pm[0], true)
}

/// Bambu's top and pick pictures of `plan`, `width` px square PNGs (see
/// [`png::bed_views`]): the whole bed seen from above, its objects (a
/// plate's, or each path of a recipe) numbered in the pick picture in the
/// order of [`Plan::objects`].
pub(crate) fn bed_views_png(plan: &Plan, width: u32) -> (Vec<u8>, Vec<u8>) {
    let p = &plan.recipe.printer;
    // the bed's box in machine coordinates, then recipe ones (− origin)
    let (lo, hi) = match p.bed {
        crate::machine::Bed::Rectangle { size, min, .. } => {
            (min, [min[0] + size[0], min[1] + size[1]])
        }
        crate::machine::Bed::Circle { diameter, .. } => {
            let r = diameter / 2.0;
            ([-r, -r], [r, r])
        }
    };
    let o = p.origin;
    let bed = [lo[0] - o[0], lo[1] - o[1], hi[0] - o[0], hi[1] - o[1]];
    let objects: Vec<std::ops::Range<usize>> = plan.objects().into_iter().map(|(_, r)| r).collect();
    let size = Size {
        width,
        height: width,
    };
    let (top, pick) = png::bed_views(&Scene::round(plan), size, bed, &objects);
    (png::encode(&top, true), png::encode(&pick, true))
}

/// The thumbnail blocks `plan`'s printer asks for (empty when none).
pub(crate) fn blocks(plan: &Plan) -> Result<String> {
    Ok(images(plan)?
        .iter()
        .map(|(t, bytes)| block_of(t.format, t.size, bytes))
        .collect())
}

#[cfg(test)]
/// A thumbnail read back from G-code.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Thumbnail {
    /// Width named in the block header, pixels.
    pub(crate) width: u32,
    /// Height named in the block header, pixels.
    pub(crate) height: u32,
    /// The image's format (the block's tag).
    pub(crate) format: ImageFormat,
    /// The decoded image bytes.
    pub(crate) bytes: Vec<u8>,
}

#[cfg(test)]
/// Why thumbnail blocks could not be read back: `line N: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct ThumbnailError {
    /// The 1-based line at fault (`None`: the end of the G-code).
    pub(crate) line: Option<usize>,
    /// What is wrong there.
    pub(crate) message: String,
}

#[cfg(test)]
impl std::fmt::Display for ThumbnailError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(l) = self.line {
            write!(f, "line {l}: ")?;
        }
        f.write_str(&self.message)
    }
}

#[cfg(test)]
impl std::error::Error for ThumbnailError {}

#[cfg(test)]
/// Reads every thumbnail block of `gcode` back, checking what printers rely
/// on: LEN is the length of the base64 text, data lines are `; ` comments of
/// at most [`LINE`] characters, and every block is closed.
pub(crate) fn parse(gcode: &str) -> std::result::Result<Vec<Thumbnail>, ThumbnailError> {
    let bad = |line: usize, message: String| ThumbnailError {
        line: Some(line),
        message,
    };
    let mut out = Vec::new();
    let mut cur: Option<(u32, u32, usize, String, ImageFormat)> = None;
    for (k, line) in gcode.lines().enumerate() {
        let at = k + 1;
        let tagged = [
            ("; thumbnail begin ", ImageFormat::Png),
            ("; thumbnail_QOI begin ", ImageFormat::Qoi),
            ("; thumbnail_JPG begin ", ImageFormat::Jpg),
        ]
        .into_iter()
        .find_map(|(tag, f)| line.strip_prefix(tag).map(|r| (r, f)));
        let is_end = matches!(
            line,
            "; thumbnail end" | "; thumbnail_QOI end" | "; thumbnail_JPG end"
        );
        if let Some((rest, format)) = tagged {
            let header = || bad(at, "expected `; thumbnail begin WxH LEN`".into());
            let (wh, len) = rest.split_once(' ').ok_or_else(header)?;
            let (w, h) = wh.split_once('x').ok_or_else(header)?;
            let num = |t: &str| t.parse::<u32>().map_err(|_| header());
            let len = len.parse::<usize>().map_err(|_| header())?;
            if cur.is_some() {
                return Err(bad(at, "a block begins inside another".into()));
            }
            cur = Some((num(w)?, num(h)?, len, String::new(), format));
        } else if is_end {
            let (width, height, len, b64, format) = cur
                .take()
                .ok_or_else(|| bad(at, "an end without a begin".into()))?;
            if b64.len() != len {
                return Err(bad(
                    at,
                    format!(
                        "the block holds {} base64 characters, its header says {len}",
                        b64.len()
                    ),
                ));
            }
            let bytes = base64::engine::general_purpose::STANDARD
                .decode(b64)
                .map_err(|e| bad(at, format!("not base64: {e}")))?;
            out.push(Thumbnail {
                width,
                height,
                format,
                bytes,
            });
        } else if let Some((_, _, _, b64, _)) = cur.as_mut() {
            let data = line
                .strip_prefix("; ")
                .ok_or_else(|| bad(at, "a data line is not a `; ` comment".into()))?;
            if data.len() > LINE {
                return Err(bad(
                    at,
                    format!("{} characters of base64, more than {LINE}", data.len()),
                ));
            }
            b64.push_str(data);
        }
    }
    match cur {
        Some(_) => Err(ThumbnailError {
            line: None,
            message: "a thumbnail block is not closed".into(),
        }),
        None => Ok(out),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_read_back_as_pngs_of_their_size() {
        let size = Size {
            width: 40,
            height: 30,
        };
        let pm = tiny_skia::Pixmap::new(40, 30).unwrap();
        let text = block(size, &png::encode(&pm, true));
        assert!(text.starts_with("; thumbnail begin 40x30 "));
        assert!(text.lines().all(|l| l.len() <= 2 + LINE));
        let got = parse(&text).unwrap();
        assert_eq!(got.len(), 1);
        assert_eq!((got[0].width, got[0].height), (40, 30));
        let img = image::load_from_memory(&got[0].bytes).unwrap();
        assert_eq!((img.width(), img.height()), (40, 30));
    }

    #[test]
    fn parse_refuses_broken_blocks() {
        let size = Size {
            width: 8,
            height: 8,
        };
        let pm = tiny_skia::Pixmap::new(8, 8).unwrap();
        let good = block(size, &png::encode(&pm, true));
        let len = good
            .lines()
            .next()
            .unwrap()
            .rsplit(' ')
            .next()
            .unwrap()
            .to_string();
        let wrong_len = good.replacen(&format!(" {len}\n"), " 3\n", 1);
        assert!(parse(&wrong_len)
            .unwrap_err()
            .to_string()
            .contains("header says 3"));
        let unclosed = good.replace("; thumbnail end\n;\n", "");
        assert_eq!(parse(&unclosed).unwrap_err().line, None);
        let long = format!(
            "; thumbnail begin 1x1 80\n; {}\n; thumbnail end\n",
            "A".repeat(80)
        );
        assert!(parse(&long)
            .unwrap_err()
            .to_string()
            .contains("more than 78"));
    }

    #[test]
    fn qoi_and_jpg_blocks_read_back_as_their_images() {
        let mut pm = tiny_skia::Pixmap::new(16, 12).unwrap();
        pm.fill(tiny_skia::Color::from_rgba8(250, 143, 41, 255));
        let size = Size {
            width: 16,
            height: 12,
        };
        let text = [ImageFormat::Qoi, ImageFormat::Jpg]
            .map(|f| block_of(f, size, &encode(&pm, f)))
            .concat();
        assert!(text.starts_with("; thumbnail_QOI begin 16x12 "));
        assert!(text.contains("; thumbnail_JPG end\n"));
        let got = parse(&text).unwrap();
        let (qh, qpx) = qoi::decode_to_vec(&got[0].bytes).unwrap();
        assert_eq!(
            (qh.width, qh.height, got[0].format),
            (16, 12, ImageFormat::Qoi)
        );
        assert_eq!(&qpx[..4], &[250, 143, 41, 255]);
        assert_eq!(got[1].format, ImageFormat::Jpg);
        let jpg = image::load_from_memory(&got[1].bytes).unwrap().to_rgb8();
        let px = jpg.get_pixel(8, 6).0;
        assert!(
            px.iter()
                .zip([250u8, 143, 41])
                .all(|(a, b)| a.abs_diff(b) < 8),
            "{px:?}"
        );
        // the same bytes every time
        assert_eq!(encode(&pm, ImageFormat::Jpg), encode(&pm, ImageFormat::Jpg));
    }

    #[test]
    fn sizes_name_the_bad_entry() {
        use crate::machine::size::sizes;
        let e = sizes(&["16x16".into(), "big".into()]).unwrap_err();
        assert!(e.to_string().contains("thumbnails[1]"), "{e}");
        assert_eq!(sizes(&["220x124".into()]).unwrap()[0].height, 124);
    }
}
