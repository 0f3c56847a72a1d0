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

/// Largest image file a `modulate_map` may read, bytes.
pub(crate) const MAX_IMAGE_BYTES: u64 = 64 << 20;

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
/// it is a change), in order, each once: what `p3dp watch` follows, and what
/// no output of the command may replace. Passed down by whoever loads a
/// recipe, never kept anywhere else.
///
/// It also holds the folder trees the build may read in (its *roots*): the
/// project of each file the user named ([`Reads::name`]) and the folders an
/// explicit option allows ([`Reads::allow`]). A file reached through a key
/// of a recipe, include or profile is read only inside them ([`Reads::reach`]).
#[derive(Debug, Default)]
pub struct Reads {
    files: std::sync::Mutex<Vec<PathBuf>>,
    roots: std::sync::Mutex<Vec<PathBuf>>,
}

/// Marks of a project's top folder: a recipe may read anything below the
/// nearest folder holding one of these (else only below its own folder).
pub(crate) const PROJECT_MARKS: [&str; 2] = ["p3dp.lock", ".git"];

/// Folders no recipe reads from, wherever its project is: the kernel's
/// views of processes and devices.
const NEVER_READ: [&str; 3] = ["/proc", "/sys", "/dev"];

impl Reads {
    /// Notes that `path` is read, or tried.
    pub(crate) fn note(&self, path: &Path) {
        let mut list = self.files.lock().unwrap_or_else(|e| e.into_inner());
        if !list.iter().any(|p| p == path) {
            list.push(path.to_path_buf());
        }
    }

    /// Notes a file the user named (on the command line, or a lock entry):
    /// the files it reaches may lie anywhere in its project (`project_root`).
    pub(crate) fn name(&self, path: &Path) {
        let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
        self.allow(&project_root(dir.unwrap_or(Path::new("."))));
    }

    /// Lets the files reached read anything below `dir` too.
    pub(crate) fn allow(&self, dir: &Path) {
        let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
        let mut roots = self.roots.lock().unwrap_or_else(|e| e.into_inner());
        if !roots.contains(&dir) {
            roots.push(dir);
        }
    }

    /// `read_text` of a file the user named: noted, its project allowed; a
    /// FIFO or device is read as it is (`p3dp check /dev/stdin`), bounded.
    pub(crate) fn read_text(&self, path: &Path, what: &str) -> Result<String> {
        self.note(path);
        self.name(path);
        read_text(path, what)
    }

    /// `read_plain` of a slicer's preset file: noted, and refused unless
    /// it is a regular file (a preset and its parents are files).
    pub(crate) fn read_plain(&self, path: &Path, what: &str) -> Result<String> {
        self.note(path);
        let file = open_regular(path, what)?;
        text_of(file, path, what, MAX_TEXT_BYTES, true)
    }

    /// Checks that `path`, reached through a key (`include:`, `svg:`,
    /// `inherits:`, an image…), may be read: noted, then refused unless it
    /// lies inside a root (symlinks resolved) and outside `/proc`, `/sys`
    /// and `/dev`. A missing file passes (its reader says it is missing).
    pub(crate) fn reach(&self, path: &Path, what: &str) -> Result<()> {
        self.note(path);
        let Ok(real) = path.canonicalize() else {
            return Ok(());
        };
        let shown = path.display();
        if NEVER_READ.iter().any(|d| real.starts_with(d)) {
            return Err(Error::input(
                "",
                format!(
                    "the {what} `{shown}` is a system file ({}); expected a file of the project",
                    real.display()
                ),
            ));
        }
        let roots = self.roots.lock().unwrap_or_else(|e| e.into_inner()).clone();
        let roots = if roots.is_empty() {
            vec![project_root(Path::new("."))]
        } else {
            roots
        };
        if roots.iter().any(|r| real.starts_with(r)) {
            return Ok(());
        }
        let list: Vec<String> = roots.iter().map(|r| r.display().to_string()).collect();
        Err(Error::input(
            "",
            format!(
                "the {what} `{shown}` is outside the folders this build may read ({}); expected a file there (a recipe reads below the folder holding p3dp.lock or .git, else below its own; --allow-read DIR adds a folder)",
                list.join(", ")
            ),
        ))
    }

    /// Opens a file reached through a key: [`Reads::reach`], then
    /// `open_regular`.
    pub(crate) fn open_reached(&self, path: &Path, what: &str) -> Result<std::fs::File> {
        self.reach(path, what)?;
        open_regular(path, what)
    }

    /// The text of a file reached through a key ([`Reads::open_reached`]),
    /// bounded by `limit` bytes, checked as `read_text` checks.
    pub(crate) fn read_reached(&self, path: &Path, what: &str, limit: u64) -> Result<String> {
        let file = self.open_reached(path, what)?;
        let text = text_of(file, path, what, limit, false)?;
        check_nesting(&text).map_err(|e| e.in_file(&path.display().to_string()))?;
        Ok(text)
    }

    /// The files noted, in order.
    pub fn files(&self) -> Vec<PathBuf> {
        self.files.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// The top folder of the project holding `dir`: the nearest ancestor (itself
/// included) with one of [`PROJECT_MARKS`], else `dir`; canonical.
pub(crate) fn project_root(dir: &Path) -> PathBuf {
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    dir.ancestors()
        .find(|a| PROJECT_MARKS.iter().any(|m| a.join(m).exists()))
        .unwrap_or(&dir)
        .to_path_buf()
}

/// What kind of file the metadata is of, for a message; `None` for a
/// regular file.
fn special_kind(m: &std::fs::Metadata) -> Option<&'static str> {
    let t = m.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("a folder");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a FIFO");
        }
        if t.is_char_device() || t.is_block_device() {
            return Some("a device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

/// Refuses `path` unless it is a regular file (symlinks followed), naming
/// what it is; a missing file passes (its reader says so).
pub(crate) fn check_regular(path: &Path, what: &str) -> Result<()> {
    match std::fs::metadata(path).ok().as_ref().and_then(special_kind) {
        Some(kind) => Err(Error::input(
            "",
            format!(
                "the {what} `{}` is {kind}; expected a regular file",
                path.display()
            ),
        )),
        None => Ok(()),
    }
}

/// Opens `path` for reading only if it is a regular file: its type is
/// checked before it is opened (a device is never opened), then again on
/// the open file, which is opened without blocking (a FIFO swapped in
/// between, with no writer, does not hang the read).
pub(crate) fn open_regular(path: &Path, what: &str) -> Result<std::fs::File> {
    let shown = path.display().to_string();
    let io = |e: std::io::Error| Error::io_from(&shown, format!("cannot read the {what}: {e}"), &e);
    let refuse = |kind: &str| {
        Error::input(
            "",
            format!("the {what} `{shown}` is {kind}; expected a regular file"),
        )
    };
    let m = std::fs::metadata(path).map_err(io)?;
    if let Some(kind) = special_kind(&m) {
        return Err(refuse(kind));
    }
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY);
    }
    let file = options.open(path).map_err(io)?;
    if let Some(kind) = special_kind(&file.metadata().map_err(io)?) {
        return Err(refuse(kind));
    }
    Ok(file)
}

/// Reads `path` (a `what`, e.g. "recipe", for messages) as text, bounded.
/// A FIFO or device is read as it is: this is for the files the user names.
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
    text_of(file, path, what, MAX_TEXT_BYTES, true)
}

/// The text of the open `file` (read from `path`), at most `limit` bytes,
/// UTF-8 without a BOM (its callers check the nesting of YAML).
fn text_of(
    file: std::fs::File,
    path: &Path,
    what: &str,
    limit: u64,
    named: bool,
) -> Result<String> {
    let shown = path.display().to_string();
    let bytes = read_bounded(file, limit)
        .map_err(|e| Error::io_from(&shown, format!("cannot read the {what}: {e}"), &e))?;
    let Some(bytes) = bytes else {
        // a named file is the place of its own error; a reached one is
        // named in the message, the place is the key that reached it
        let e = Error::input(
            "",
            format!(
                "the {what}{} is larger than {}; expected a smaller file",
                if named {
                    String::new()
                } else {
                    format!(" `{shown}`")
                },
                size_text(limit)
            ),
        );
        return Err(if named { e.in_file(&shown) } else { e });
    };
    decode(bytes).map_err(|e| e.in_file(&shown))
}

/// `16 MB`, `1 MB`, `512 kB`, `100 bytes`.
fn size_text(n: u64) -> String {
    if n >= 1 << 20 && n.is_multiple_of(1 << 20) {
        format!("{} MB", n >> 20)
    } else if n >= 1 << 10 && n.is_multiple_of(1 << 10) {
        format!("{} kB", n >> 10)
    } else {
        format!("{n} bytes")
    }
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
