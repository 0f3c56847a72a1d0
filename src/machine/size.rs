//! Image sizes in pixels, as `WxH` (a profile's G-code thumbnails, a preview).

use crate::base::error::{Error, Result};

/// An image size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
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
    pub const MAX: u32 = 8192;

    /// Parses `WxH`, e.g. `1200x900`; `what` names the place for errors.
    pub fn parse(s: &str, what: &str) -> Result<Size> {
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
/// entries `WxH/PNG`, `WxH/JPG`, `WxH/QOI`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ThumbFormat {
    /// PNG: `; thumbnail begin` blocks.
    Png,
    /// JPEG: `; thumbnail_JPG begin` blocks.
    Jpg,
    /// QOI: `; thumbnail_QOI begin` blocks (Prusa MK4, MINI, XL firmware).
    Qoi,
}

impl ThumbFormat {
    /// The format named `s` (any case; `JPEG` too).
    pub(crate) fn parse(s: &str) -> Option<ThumbFormat> {
        match s.trim().to_ascii_uppercase().as_str() {
            "PNG" => Some(ThumbFormat::Png),
            "JPG" | "JPEG" => Some(ThumbFormat::Jpg),
            "QOI" => Some(ThumbFormat::Qoi),
            _ => None,
        }
    }
}

/// The thumbnails a profile's `thumbnails` list asks for, `WxH` or
/// `WxH/FORMAT` (PNG when none is named); errors name `thumbnails[k]`.
pub(crate) fn thumbs(list: &[String]) -> Result<Vec<(Size, ThumbFormat)>> {
    list.iter()
        .enumerate()
        .map(|(k, s)| {
            let what = format!("thumbnails[{k}]");
            let (size, format) = match s.split_once('/') {
                None => (s.as_str(), ThumbFormat::Png),
                Some((size, f)) => {
                    let format = ThumbFormat::parse(f).ok_or_else(|| {
                        Error::input(
                            what.as_str(),
                            format!("`{f}` is not a thumbnail format; expected PNG, JPG or QOI"),
                        )
                    })?;
                    (size, format)
                }
            };
            Ok((Size::parse(size.trim(), &what)?, format))
        })
        .collect()
}
