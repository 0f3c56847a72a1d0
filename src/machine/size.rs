//! Image sizes in pixels, as `WxH` (a profile's G-code thumbnails, a preview).

use crate::base::error::{Error, Result};

/// An image size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Size {
    /// Width, px.
    pub(crate) width: u32,
    /// Height, px.
    pub(crate) height: u32,
}

impl Default for Size {
    fn default() -> Size {
        Size {
            width: 1200,
            height: 900,
        }
    }
}

impl Size {
    /// Largest side accepted, px.
    pub(crate) const MAX: u32 = 8192;

    /// Parses `WxH`, e.g. `1200x900`; `what` names the place for errors.
    pub(crate) fn parse(s: &str, what: &str) -> Result<Size> {
        let bad = || {
            Error::input(
                what,
                format!(
                    "`{s}` is not a size; expected WIDTHxHEIGHT in pixels, e.g. 1200x900, each 1 to {}",
                    Size::MAX
                ),
            )
        };
        let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
        let w: u32 = w.trim().parse().map_err(|_| bad())?;
        let h: u32 = h.trim().parse().map_err(|_| bad())?;
        if !(1..=Size::MAX).contains(&w) || !(1..=Size::MAX).contains(&h) {
            return Err(bad());
        }
        Ok(Size {
            width: w,
            height: h,
        })
    }
}

/// The image format of a G-code thumbnail (PrusaSlicer's `thumbnails`
/// suffix: `16x16/QOI`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum ImageFormat {
    /// PNG: `; thumbnail begin` blocks (the default).
    #[default]
    Png,
    /// QOI: `; thumbnail_QOI begin` blocks (Prusa's firmware).
    Qoi,
    /// JPEG: `; thumbnail_JPG begin` blocks.
    Jpg,
}

impl ImageFormat {}

/// One thumbnail a profile asks for: its size and format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Thumbnail {
    /// Size in pixels.
    pub(crate) size: Size,
    /// Image format.
    pub(crate) format: ImageFormat,
}

/// The thumbnails a profile's `thumbnails` list asks for: each entry
/// `WxH` (PNG) or `WxH/FORMAT` with FORMAT one of `PNG`, `QOI`, `JPG` (any
/// case), as PrusaSlicer writes them; errors name `thumbnails[k]`.
pub(crate) fn thumbnails(list: &[String]) -> Result<Vec<Thumbnail>> {
    list.iter()
        .enumerate()
        .map(|(k, s)| {
            let what = format!("thumbnails[{k}]");
            let (size, format) = match s.split_once('/') {
                None => (s.as_str(), ImageFormat::Png),
                Some((size, f)) => {
                    let format = match f.trim().to_ascii_uppercase().as_str() {
                        "PNG" => ImageFormat::Png,
                        "QOI" => ImageFormat::Qoi,
                        "JPG" | "JPEG" => ImageFormat::Jpg,
                        _ => {
                            return Err(Error::input(
                                what,
                                format!("`{f}` is not a thumbnail format; expected PNG, QOI or JPG (as in `16x16/QOI`)"),
                            ))
                        }
                    };
                    (size, format)
                }
            };
            Ok(Thumbnail {
                size: Size::parse(size, &what)?,
                format,
            })
        })
        .collect()
}

#[cfg(test)]
/// The sizes a profile's `thumbnails` list asks for (see [`thumbnails`]);
/// errors name `thumbnails[k]`.
pub(crate) fn sizes(list: &[String]) -> Result<Vec<Size>> {
    Ok(thumbnails(list)?.into_iter().map(|t| t.size).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thumbnail_entries_take_a_format() {
        let list: Vec<String> = ["220x124", "16x16/QOI", "300x300/jpg", "40x40/PNG"]
            .map(String::from)
            .to_vec();
        let t = thumbnails(&list).unwrap();
        let formats: Vec<ImageFormat> = t.iter().map(|t| t.format).collect();
        use ImageFormat::*;
        assert_eq!(formats, [Png, Qoi, Jpg, Png]);
        assert_eq!((t[1].size.width, t[1].size.height), (16, 16));
        let e = thumbnails(&["16x16/GIF".to_string()]).unwrap_err();
        assert!(e.to_string().contains("thumbnails[0]"), "{e}");
        assert!(e.to_string().contains("expected PNG, QOI or JPG"), "{e}");
    }
}
