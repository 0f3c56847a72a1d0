//! Reading input files: bounded, UTF-8 with places, nesting capped.
//!
//! Every recipe, printer profile and lock file is read through [`read_text`]:
//! at most [`MAX_TEXT_BYTES`] (so `/dev/zero` given as a recipe is refused,
//! not read until memory runs out), a leading byte-order mark dropped, and
//! bytes that are not UTF-8 reported with their line and column. Before YAML
//! parses the text, [`check_nesting`] refuses brackets nested deeper than
//! [`MAX_NESTING`] (the parser's time grows faster than the nesting).
//!
//! Every file a build reads or tries to read (recipe, included files,
//! images, SVGs, printer profiles and those they inherit from) is noted in
//! the [`Reads`] its loader was given, so that `p3dp watch` knows which files
//! to follow, the missing ones included (creating one is a change too).

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::base::error::{Error, Result};

/// Largest recipe, profile or lock file, bytes.
pub(crate) const MAX_TEXT_BYTES: u64 = 16 << 20;

/// Deepest nesting of YAML flow collections (`[…]`, `{…}`).
pub(crate) const MAX_NESTING: usize = 64;

/// Most pixels of an image a `modulate_map` may read (decoded to 4 bytes each).
pub(crate) const MAX_IMAGE_PIXELS: u64 = 16 << 20;

/// Longest side of such an image, pixels.
pub(crate) const MAX_IMAGE_SIDE: u32 = 16384;

/// Most characters of a `modulate_map` text (9 × 10 pixels each).
pub(crate) const MAX_MAP_TEXT_CHARS: usize = 10_000;

/// Refuses image dimensions (as its header declares them, before decoding)
/// over [`MAX_IMAGE_SIDE`] or [`MAX_IMAGE_PIXELS`].
pub(crate) fn check_image_size(width: u32, height: u32) -> std::result::Result<(), String> {
    if width > MAX_IMAGE_SIDE
        || height > MAX_IMAGE_SIDE
        || width as u64 * height as u64 > MAX_IMAGE_PIXELS
    {
        return Err(format!(
            "declares {width} × {height} pixels; expected at most {MAX_IMAGE_SIDE} a side and {} million pixels",
            MAX_IMAGE_PIXELS >> 20
        ));
    }
    Ok(())
}

/// The files one build read or tried to read (a missing one too: creating
/// it is a change), in order, each once: what `p3dp watch` follows. Passed
/// down by whoever loads a recipe, never kept anywhere else.
#[derive(Debug, Default)]
pub struct Reads(std::sync::Mutex<Vec<PathBuf>>);

impl Reads {
    /// Notes that `path` is read, or tried.
    pub fn note(&self, path: &Path) {
        let mut list = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if !list.iter().any(|p| p == path) {
            list.push(path.to_path_buf());
        }
    }

    /// [`read_text`], noted.
    pub fn read_text(&self, path: &Path, what: &str) -> Result<String> {
        self.note(path);
        read_text(path, what)
    }

    /// [`read_plain`], noted.
    pub fn read_plain(&self, path: &Path, what: &str) -> Result<String> {
        self.note(path);
        read_plain(path, what)
    }

    /// The files noted, in order.
    pub fn files(&self) -> Vec<PathBuf> {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// Reads `path` (a `what`, e.g. "recipe", for messages) as text, bounded.
pub(crate) fn read_text(path: &Path, what: &str) -> Result<String> {
    let shown = path.display().to_string();
    let text = read_plain(path, what)?;
    check_nesting(&text).map_err(|e| e.in_file(&shown))?;
    Ok(text)
}

/// [`read_text`] without the YAML nesting check: a file of another format
/// (a slicer's `.ini` or `.json` preset, whose parsers bound their own
/// nesting), bounded and UTF-8.
pub(crate) fn read_plain(path: &Path, what: &str) -> Result<String> {
    let shown = path.display().to_string();
    let file = std::fs::File::open(path)
        .map_err(|e| Error::io_from(&shown, format!("cannot read the {what}: {e}"), &e))?;
    let bytes = read_bounded(file, MAX_TEXT_BYTES)
        .map_err(|e| Error::io_from(&shown, format!("cannot read the {what}: {e}"), &e))?;
    let Some(bytes) = bytes else {
        return Err(Error::input(
            "",
            format!(
                "the {what} is larger than {} MB; expected a smaller file",
                MAX_TEXT_BYTES >> 20
            ),
        )
        .in_file(&shown));
    };
    decode(bytes).map_err(|e| e.in_file(&shown))
}

/// The bytes of `file`, or `None` when it holds more than `limit` (no more
/// than `limit + 1` bytes are read).
pub(crate) fn read_bounded(file: std::fs::File, limit: u64) -> std::io::Result<Option<Vec<u8>>> {
    let mut bytes = Vec::new();
    file.take(limit + 1).read_to_end(&mut bytes)?;
    Ok((bytes.len() as u64 <= limit).then_some(bytes))
}

/// UTF-8 text without a leading byte-order mark; an error at the line and
/// column of the first byte that is not UTF-8.
pub(crate) fn decode(bytes: Vec<u8>) -> Result<String> {
    let mut text = match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => {
            let bytes = e.as_bytes();
            let at = e.utf8_error().valid_up_to();
            let (line, col) = line_col(&bytes[..at]);
            let mut err = Error::input(
                "",
                format!("byte 0x{:02x} is not UTF-8; expected UTF-8 text", bytes[at]),
            );
            err.line = Some((line, col));
            return Err(err);
        }
    };
    if text.starts_with('\u{feff}') {
        text.drain(..'\u{feff}'.len_utf8());
    }
    Ok(text)
}

/// Line and column (1-based, in characters) just after `before`.
fn line_col(before: &[u8]) -> (usize, usize) {
    let text = String::from_utf8_lossy(before);
    let line = 1 + text.matches('\n').count();
    let col = 1 + text.rsplit('\n').next().unwrap_or("").chars().count();
    (line, col)
}

/// Refuses YAML whose flow collections (`[`, `{`) nest deeper than
/// [`MAX_NESTING`], naming the line and column, before a parser sees it.
/// Brackets inside quoted scalars and comments do not count.
pub(crate) fn check_nesting(text: &str) -> Result<()> {
    let mut depth = 0usize;
    let mut quote: Option<char> = None;
    let mut prev = '\n';
    let (mut line, mut col) = (1usize, 0usize);
    let mut comment = false;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        col += 1;
        if c == '\n' {
            line += 1;
            col = 0;
            comment = false;
            // a quoted scalar may span lines; a comment may not
        }
        if comment {
            prev = c;
            continue;
        }
        match quote {
            Some('\'') if c == '\'' => {
                if chars.peek() == Some(&'\'') {
                    chars.next(); // '' is an escaped quote
                    col += 1;
                } else {
                    quote = None;
                }
            }
            Some('"') if c == '\\' => {
                chars.next();
                col += 1;
            }
            Some('"') if c == '"' => quote = None,
            Some(_) => {}
            None => match c {
                '#' if prev.is_whitespace() => comment = true,
                '"' | '\'' if prev.is_whitespace() || matches!(prev, '[' | '{' | ',' | ':') => {
                    quote = Some(c)
                }
                '[' | '{' => {
                    depth += 1;
                    if depth > MAX_NESTING {
                        let mut e = Error::input(
                            "",
                            format!(
                                "brackets nest more than {MAX_NESTING} deep; expected flatter YAML"
                            ),
                        );
                        e.line = Some((line, col));
                        return Err(e);
                    }
                }
                ']' | '}' => depth = depth.saturating_sub(1),
                _ => {}
            },
        }
        prev = c;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_note_each_file_once_missing_ones_too() {
        let missing = Path::new("/nonexistent/p3dp/recipe.yaml");
        let reads = Reads::default();
        reads.note(Path::new("a.png"));
        let r = reads.read_text(missing, "recipe");
        reads.note(Path::new("a.png"));
        assert!(r.is_err());
        assert_eq!(
            reads.files(),
            [PathBuf::from("a.png"), missing.to_path_buf()]
        );
        assert!(Reads::default().files().is_empty());
    }

    #[test]
    fn nesting_counts_brackets_outside_strings_and_comments() {
        let deep = format!("a: {}1{}", "[".repeat(65), "]".repeat(65));
        let e = check_nesting(&deep).unwrap_err();
        assert_eq!(e.line, Some((1, 68)));
        let quoted = format!(
            "a: \"{}\"\nb: '{}' # {}",
            "[".repeat(100),
            "{".repeat(100),
            "[".repeat(100)
        );
        check_nesting(&quoted).unwrap();
        check_nesting("a: [1, [2, {b: 3}]]\nc: it's [fine]\n").unwrap();
    }

    #[test]
    fn decode_drops_a_bom_and_places_bad_bytes() {
        assert_eq!(decode(b"\xef\xbb\xbfname: x".to_vec()).unwrap(), "name: x");
        let e = decode(b"a: 1\nb: \xff".to_vec()).unwrap_err();
        assert_eq!(e.line, Some((2, 4)));
        assert!(e.message.contains("0xff"), "{e}");
    }
}
