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
use crate::machine::size::{thumbs, ThumbFormat};

/// Characters of base64 per comment line (PrusaSlicer's).
pub(crate) const LINE: usize = 78;

#[cfg(test)]
/// One thumbnail block for a PNG of `size`.
pub(crate) fn block(size: Size, png: &[u8]) -> String {
    block_of(size, ThumbFormat::Png, png)
}

/// The word of a block's header and end line: `thumbnail` for PNG,
/// `thumbnail_JPG`, `thumbnail_QOI` (PrusaSlicer's).
fn word(format: ThumbFormat) -> &'static str {
    match format {
        ThumbFormat::Png => "thumbnail",
        ThumbFormat::Jpg => "thumbnail_JPG",
        ThumbFormat::Qoi => "thumbnail_QOI",
    }
}

/// One thumbnail block for an image of `size` encoded as `format`.
pub(crate) fn block_of(size: Size, format: ThumbFormat, bytes: &[u8]) -> String {
    let b64 = base64::engine::general_purpose::STANDARD.encode(bytes);
    let w = word(format);
    let mut s = format!("; {w} begin {}x{} {}\n", size.width, size.height, b64.len());
    for chunk in b64.as_bytes().chunks(LINE) {
        s.push_str("; ");
        s.push_str(std::str::from_utf8(chunk).expect("base64 is ASCII"));
        s.push('\n');
    }
    s.push_str(&format!("; {w} end\n;\n"));
    s
}

/// The thumbnail blocks `plan`'s printer asks for (empty when none).
pub(crate) fn blocks(plan: &Plan) -> Result<String> {
    let list = &plan.recipe.printer.thumbnails;
    if list.is_empty() {
        return Ok(String::new());
    }
    let thumbs = thumbs(list).map_err(|e| e.in_file(&plan.recipe.printer.name))?;
    let scene = Scene::new(plan);
    let mut out = String::new();
    for (size, format) in thumbs {
        let pm = png::thumbnail(&scene, size);
        let bytes = match format {
            ThumbFormat::Png => png::encode(&pm, true),
            ThumbFormat::Jpg => png::encode_jpeg(&pm),
            ThumbFormat::Qoi => png::encode_qoi(&pm),
        };
        out.push_str(&block_of(size, format, &bytes));
    }
    Ok(out)
}

#[cfg(test)]
/// A thumbnail read back from G-code.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Thumbnail {
    /// Width named in the block header, pixels.
    pub width: u32,
    /// Height named in the block header, pixels.
    pub height: u32,
    /// The decoded image bytes (PNG unless `format` says otherwise).
    pub png: Vec<u8>,
    /// The image's format, from the block's header word.
    pub format: ThumbFormat,
}

#[cfg(test)]
/// Why thumbnail blocks could not be read back: `line N: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct ThumbnailError {
    /// The 1-based line at fault (`None`: the end of the G-code).
    pub line: Option<usize>,
    /// What is wrong there.
    pub message: String,
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
    let mut cur: Option<(u32, u32, usize, String, ThumbFormat)> = None;
    for (k, line) in gcode.lines().enumerate() {
        let at = k + 1;
        let begin = [ThumbFormat::Png, ThumbFormat::Jpg, ThumbFormat::Qoi]
            .into_iter()
            .find_map(|f| Some((f, line.strip_prefix(&format!("; {} begin ", word(f)))?)));
        let end = cur
            .as_ref()
            .is_some_and(|c| line == format!("; {} end", word(c.4)));
        if let Some((format, rest)) = begin {
            let header = || bad(at, "expected `; thumbnail begin WxH LEN`".into());
            let (wh, len) = rest.split_once(' ').ok_or_else(header)?;
            let (w, h) = wh.split_once('x').ok_or_else(header)?;
            let num = |t: &str| t.parse::<u32>().map_err(|_| header());
            let len = len.parse::<usize>().map_err(|_| header())?;
            if cur.is_some() {
                return Err(bad(at, "a block begins inside another".into()));
            }
            cur = Some((num(w)?, num(h)?, len, String::new(), format));
        } else if end
            || (cur.is_none() && line.starts_with("; thumbnail") && line.ends_with(" end"))
        {
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
            let png = base64::engine::general_purpose::STANDARD
                .decode(b64)
                .map_err(|e| bad(at, format!("not base64: {e}")))?;
            out.push(Thumbnail {
                width,
                height,
                png,
                format,
            });
        } else if let Some((.., b64, _)) = cur.as_mut() {
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
        let img = image::load_from_memory(&got[0].png).unwrap();
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
    fn sizes_name_the_bad_entry() {
        let e = thumbs(&["16x16".into(), "big".into()]).unwrap_err();
        assert!(e.to_string().contains("thumbnails[1]"), "{e}");
        let e = thumbs(&["16x16/GIF".into()]).unwrap_err();
        assert!(
            e.to_string().contains("`GIF` is not a thumbnail format"),
            "{e}"
        );
        let t = thumbs(&["220x124".into(), "16x16/qoi".into(), "8x8/JPG".into()]).unwrap();
        assert_eq!(t[0].0.height, 124);
        assert_eq!(
            t.iter().map(|x| x.1).collect::<Vec<_>>(),
            [ThumbFormat::Png, ThumbFormat::Qoi, ThumbFormat::Jpg]
        );
    }

    #[test]
    fn qoi_and_jpg_blocks_read_back_as_their_images() {
        let size = Size {
            width: 12,
            height: 8,
        };
        let mut pm = tiny_skia::Pixmap::new(12, 8).unwrap();
        pm.fill(tiny_skia::Color::from_rgba8(200, 100, 20, 255));
        let text = block_of(size, ThumbFormat::Qoi, &png::encode_qoi(&pm))
            + &block_of(size, ThumbFormat::Jpg, &png::encode_jpeg(&pm));
        assert!(text.starts_with("; thumbnail_QOI begin 12x8 "), "{text}");
        assert!(text.contains("; thumbnail_JPG end\n"), "{text}");
        let got = parse(&text).unwrap();
        assert_eq!(got.len(), 2);
        for (t, f) in got
            .iter()
            .zip([image::ImageFormat::Qoi, image::ImageFormat::Jpeg])
        {
            let img = image::load_from_memory_with_format(&t.png, f)
                .unwrap()
                .to_rgb8();
            assert_eq!((img.width(), img.height()), (12, 8));
            let px = img.get_pixel(5, 4).0;
            assert!(px[0].abs_diff(200) < 8 && px[1].abs_diff(100) < 8, "{px:?}");
        }
    }
}
