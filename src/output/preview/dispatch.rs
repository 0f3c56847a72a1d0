//! The previews' files: the format told by the extension, and the bytes of
//! either written atomically, with the line that reports them.

use std::path::Path;

use glam::DVec3;

use super::{html, png, Options};
use crate::analyse::plan::Plan;
use crate::analyse::stats::Stats;
use crate::base::error::{Error, Result};
use crate::output::file::write_atomic;

/// The output format, by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// A PNG image.
    Png,
    /// A self-contained HTML viewer.
    Html,
}

impl Format {
    /// The format of `path` by its extension.
    pub fn of(path: &Path) -> Result<Format> {
        match crate::output::file::extension(path).as_str() {
            "png" => Ok(Format::Png),
            "html" | "htm" => Ok(Format::Html),
            _ => Err(Error::input(
                "preview",
                format!(
                    "cannot tell the format of `{}`; expected a file name ending in .png or .html",
                    path.display()
                ),
            )),
        }
    }
}

/// Writes a plan's G-code to a writer and returns its stats (the build's
/// renderer, passed down so that previews need not know how G-code is made).
/// `Sync`, so that it may run on a thread of its own beside the drawing.
pub type Render<'a> = &'a (dyn Fn(&mut dyn std::io::Write) -> Result<Stats> + Sync);

/// Writes a preview of `plan` to `out` (PNG or HTML by extension, atomically);
/// returns a line for the report. `render` writes the plan's G-code.
pub fn write(plan: &Plan, out: &Path, opts: &Options, render: Render) -> Result<String> {
    let shown = out.display().to_string();
    let io =
        |e: std::io::Error| Error::io_from(&shown, format!("cannot write the preview: {e}"), &e);
    if Format::of(out)? == Format::Html {
        // streamed into the file as it is encoded
        let (data, stats) = html::read(plan, opts, render)?;
        let mut len = 0;
        write_atomic(out, |f| {
            use std::io::Write;
            let mut w = Counted {
                inner: std::io::BufWriter::with_capacity(1 << 16, f),
                n: 0,
            };
            html::write_page(&stats.name, &data, &mut w).map_err(io)?;
            w.inner.flush().map_err(io)?;
            len = w.n;
            Ok(())
        })?;
        return Ok(html_line(&shown, data.points(), len));
    }
    let (bytes, line) = bytes(plan, out, opts, render)?;
    write_atomic(out, |f| {
        use std::io::Write;
        f.write_all(&bytes).map_err(io)
    })?;
    Ok(line)
}

/// A writer that counts the bytes through it.
struct Counted<W> {
    inner: W,
    n: usize,
}

impl<W: std::io::Write> std::io::Write for Counted<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let k = self.inner.write(buf)?;
        self.n += k;
        Ok(k)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The report line of an HTML preview of `points` points and `len` bytes.
fn html_line(shown: &str, points: usize, len: usize) -> String {
    format!(
        "preview → {shown}: HTML viewer, {points} points, {} kB",
        (len + 512) / 1024
    )
}

/// The bytes of the preview [`write`] writes to `out` (its format by the
/// extension), and the line reporting it; writes nothing, so a build can
/// commit the preview with its other outputs.
pub fn bytes(plan: &Plan, out: &Path, opts: &Options, render: Render) -> Result<(Vec<u8>, String)> {
    let format = Format::of(out)?;
    let shown = out.display().to_string();
    match format {
        Format::Png => {
            let (r, _) = png::preview(plan, opts, render)?;
            let bytes = png::encode_fast(&r.pixmap, false);
            let (x, y) = r.frame.pixel(DVec3::ZERO);
            Ok((bytes, format!(
                "preview → {shown}: {} × {} px, {} view, colour {}, scale {:.4} px/mm, recipe (0, 0, 0) at pixel ({x:.2}, {y:.2})",
                opts.size.width,
                opts.size.height,
                opts.view.name(),
                opts.color.name(),
                r.frame.scale
            )))
        }
        Format::Html => {
            let (data, stats) = html::read(plan, opts, render)?;
            let mut page = Vec::new();
            html::write_page(&stats.name, &data, &mut page).expect("writing to memory");
            let line = html_line(&shown, data.points(), page.len());
            Ok((page, line))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_by_extension() {
        assert_eq!(Format::of(Path::new("a/b.PNG")).unwrap(), Format::Png);
        assert_eq!(Format::of(Path::new("x.html")).unwrap(), Format::Html);
        assert!(Format::of(Path::new("x.jpg")).is_err());
        assert!(Format::of(Path::new("x")).is_err());
    }
}
