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

/// The sizes a profile's `thumbnails` list asks for; errors name `thumbnails[k]`.
pub(crate) fn sizes(list: &[String]) -> Result<Vec<Size>> {
    list.iter()
        .enumerate()
        .map(|(k, s)| Size::parse(s, &format!("thumbnails[{k}]")))
        .collect()
}
