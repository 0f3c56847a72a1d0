//! The previews' files: the format told by the extension, the steps that
//! make either ([`Job`]), and its bytes written atomically, with the line
//! that reports them.

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::{html, png, Options};
use crate::analyse::plan::Plan;
use crate::analyse::stats::Stats;
use crate::base::error::{Error, Result};
use crate::output::file::write_atomic;

/// The output format, by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Format {
    /// A PNG image.
    Png,
    /// A self-contained HTML viewer.
    Html,
}

impl Format {
    /// The format of `path` by its extension.
    pub(crate) fn of(path: &Path) -> Result<Format> {
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

/// A preview of a plan to make, in steps a caller may schedule: the G-code
/// is written into [`Job::reader`] (for its stats, and for an HTML viewer
/// its moves) while [`Job::draw`] does all that needs neither, the two side
/// by side when there is a thread to spare; then [`Job::finish`]. The
/// result is the same in any order:
///
/// ```text
/// let job = Job::new(plan, out, opts)?;
/// let mut reader = job.reader();
/// let (stats, drawing) = par::join(|| render(&mut reader), || job.draw());
/// let line = job.finish(drawing, reader, &stats?).write()?;
/// ```
pub(crate) struct Job<'p> {
    plan: &'p Plan,
    out: PathBuf,
    format: Format,
    opts: Options,
}

/// What a preview takes of the G-code's command stream as it is written:
/// nothing for a PNG (its header needs the stats alone), the moves for an
/// HTML viewer.
pub(crate) struct Reader(Option<html::Reader>);

impl crate::analyse::planner::Moves for Reader {
    fn begin_part(&mut self, name: &str) {
        if let Some(r) = &mut self.0 {
            r.begin_part(name);
        }
    }
    fn stop(&mut self) {}
    fn dwell(&mut self, _seconds: f64) {}
    fn move_to(
        &mut self,
        to: glam::DVec3,
        e: f64,
        feed: f64,
        kind: crate::analyse::planner::MoveKind,
    ) {
        if let Some(r) = &mut self.0 {
            r.move_to(to, e, feed, kind);
        }
    }
    fn extrude_only(&mut self, _length: f64, _feed: f64) {}
    fn profile_move(
        &mut self,
        to: glam::DVec3,
        e: f64,
        feed: f64,
        kind: crate::analyse::planner::MoveKind,
    ) {
        if let Some(r) = &mut self.0 {
            r.profile_move(to, e, feed, kind);
        }
    }
}

/// A preview drawn, waiting for the G-code's stats ([`Job::draw`]).
pub(crate) enum Drawing<'p> {
    /// The image, but its header and legend.
    Png(png::Drawing<'p>),
    /// The viewer's reading of the plan.
    Html(html::Drawing<'p>),
}

/// A preview made, to be written or taken as bytes ([`Job::finish`]).
pub(crate) struct Finished {
    out: PathBuf,
    made: Made,
}

/// The preview of a [`Finished`].
enum Made {
    Png(png::Rendered, Options),
    Html(html::Data, String),
}

impl<'p> Job<'p> {
    /// A preview of `plan` to write to `out` (its format by the extension).
    pub(crate) fn new(plan: &'p Plan, out: &Path, opts: &Options) -> Result<Job<'p>> {
        Ok(Job {
            plan,
            out: out.to_path_buf(),
            format: Format::of(out)?,
            opts: *opts,
        })
    }

    /// The writer the plan's G-code is to be written into.
    pub(crate) fn reader(&self) -> Reader {
        Reader(match self.format {
            Format::Png => None,
            Format::Html => Some(html::reader(self.plan)),
        })
    }

    /// All of the preview that needs neither the G-code nor its stats.
    pub(crate) fn draw(&self) -> Drawing<'p> {
        match self.format {
            Format::Png => Drawing::Png(png::draw(self.plan, &self.opts)),
            Format::Html => Drawing::Html(html::draw(self.plan, &self.opts)),
        }
    }

    /// The preview, from this job's `drawing`, its `reader` once the G-code
    /// is written into it, and the `stats` the writing returned.
    pub(crate) fn finish(&self, drawing: Drawing<'p>, reader: Reader, stats: &Stats) -> Finished {
        let made = match drawing {
            Drawing::Png(d) => Made::Png(png::finish(d, stats), self.opts),
            Drawing::Html(d) => {
                let r = reader.0.expect("an HTML job's reader reads the moves");
                Made::Html(html::finish(d, r, stats), stats.name.clone())
            }
        };
        Finished {
            out: self.out.clone(),
            made,
        }
    }
}

impl Finished {
    /// Writes the preview to its file, atomically (an HTML page streamed
    /// into it as it is encoded); returns the line reporting it.
    pub(crate) fn write(self) -> Result<String> {
        let shown = self.out.display().to_string();
        let io = |e: std::io::Error| {
            Error::io_from(&shown, format!("cannot write the preview: {e}"), &e)
        };
        let Made::Html(data, title) = &self.made else {
            let out = self.out.clone();
            let (bytes, line) = self.bytes();
            write_atomic(&out, |f| {
                use std::io::Write;
                f.write_all(&bytes).map_err(io)
            })?;
            return Ok(line);
        };
        let mut len = 0;
        write_atomic(&self.out, |f| {
            use std::io::Write;
            let mut w = Counted {
                inner: std::io::BufWriter::with_capacity(1 << 16, f),
                n: 0,
            };
            html::write_page(title, data, &mut w).map_err(io)?;
            w.inner.flush().map_err(io)?;
            len = w.n;
            Ok(())
        })?;
        Ok(html_line(&shown, data.points(), len))
    }

    /// The preview's bytes, and the line reporting them.
    pub(crate) fn bytes(self) -> (Vec<u8>, String) {
        let shown = self.out.display().to_string();
        match self.made {
            Made::Png(r, opts) => {
                let bytes = png::encode(&r.pixmap, false);
                let (x, y) = r.frame.pixel(DVec3::ZERO);
                (bytes, format!(
                    "preview → {shown}: {} × {} px, {} view, colour {}, scale {:.4} px/mm, recipe (0, 0, 0) at pixel ({x:.2}, {y:.2})",
                    opts.size.width,
                    opts.size.height,
                    opts.view.name(),
                    opts.color.name(),
                    r.frame.scale
                ))
            }
            Made::Html(data, title) => {
                let mut page = Vec::new();
                html::write_page(&title, &data, &mut page).expect("writing to memory");
                let line = html_line(&shown, data.points(), page.len());
                (page, line)
            }
        }
    }
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
