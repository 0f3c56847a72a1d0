//! Lock files: recipes pinned to the hash of their G-code, for CI.
//!
//! `p3dp hash --lock p3dp.lock RECIPE…` records each recipe (path relative to
//! the lock file), its `--set` values, the `--printer` it was built for, and
//! the SHA-256 of its G-code, with a
//! fingerprint of the G-code's lines: the hashes of at most 512 consecutive
//! blocks of lines (one line per block when the output is that short), the
//! thumbnails' lines left out (a changed print changes its pictures first:
//! the fingerprint finds where its moves changed).
//! `p3dp hash --check p3dp.lock` rebuilds every entry (each read only inside
//! the lock's project, as any file a key reaches) and shows only those that
//! changed: the old and new SHA-256 whole, the first differing block and
//! its new lines.

use std::io::{self, Write};

use serde::{Deserialize, Serialize};

use crate::base::error::{Error, Result};

/// The lock file.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct Lock {
    /// Format version: 1.
    pub(crate) p3dp_lock: u32,
    /// One entry per recipe and parameter set.
    pub(crate) entries: Vec<Entry>,
}

/// One locked build.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct Entry {
    /// Recipe path, relative to the lock file, `/`-separated.
    pub(crate) recipe: String,
    /// `--set` values, `NAME=VALUE`, in order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) set: Vec<String>,
    /// The `--printer` it was built for: a built-in name, or a profile file
    /// relative to the lock file, `/`-separated; the recipe's own when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) printer: Option<String>,
    /// SHA-256 of the G-code.
    pub(crate) sha256: String,
    /// Lines of G-code.
    pub(crate) lines: u64,
    /// Lines per block of the fingerprint.
    pub(crate) block_lines: u64,
    /// Hash of each block, 8 hex digits each, space-separated.
    pub(crate) blocks: String,
}

/// Most lines a locked G-code may have: far more than any build writes,
/// few enough that no block arithmetic overflows.
pub(crate) const MAX_LINES: u64 = 1 << 40;

impl Lock {
    /// Refuses what `hash --check` cannot use, naming the key: another
    /// version, no entries, a hash that is not 64 hex digits, blocks that do
    /// not fit the line count.
    pub(crate) fn validate(&self) -> Result<()> {
        if self.p3dp_lock != 1 {
            return Err(Error::input(
                "p3dp_lock",
                format!(
                    "lock format version {} is not known; expected 1",
                    self.p3dp_lock
                ),
            ));
        }
        if self.entries.is_empty() {
            return Err(Error::input(
                "entries",
                "no entries: a lock without recipes checks nothing; expected at least one (write it with `p3dp hash --lock FILE RECIPE…`)",
            ));
        }
        for (k, e) in self.entries.iter().enumerate() {
            let place = |key: &str| format!("entries[{k}].{key}");
            if e.recipe.trim().is_empty() {
                return Err(Error::input(place("recipe"), "expected a recipe path"));
            }
            let hex = |s: &str| {
                s.bytes()
                    .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
            };
            if e.sha256.len() != 64 || !hex(&e.sha256) {
                return Err(Error::input(
                    place("sha256"),
                    "expected a SHA-256: 64 lowercase hex digits",
                ));
            }
            if e.lines > MAX_LINES {
                return Err(Error::input(
                    place("lines"),
                    format!("{} lines; expected at most {MAX_LINES}", e.lines),
                ));
            }
            let b = LineHashes::block_lines(e.lines);
            if e.block_lines != b {
                return Err(Error::input(
                    place("block_lines"),
                    format!(
                        "{} is not allowed; {} lines make blocks of {b} lines",
                        e.block_lines, e.lines
                    ),
                ));
            }
            let words: Vec<&str> = e.blocks.split_whitespace().collect();
            if words.len() as u64 > MAX_BLOCKS || words.iter().any(|w| w.len() != 8 || !hex(w)) {
                return Err(Error::input(
                    place("blocks"),
                    format!("expected at most {MAX_BLOCKS} block hashes of 8 lowercase hex digits"),
                ));
            }
        }
        Ok(())
    }
}

/// Most blocks one fingerprint has.
pub(crate) const MAX_BLOCKS: u64 = 512;

/// A writer that keeps a 64-bit FNV-1a hash of every line passing through,
/// but the lines of thumbnail blocks ([`Thumbnails`]).
#[derive(Default)]
pub(crate) struct LineHashes {
    /// Hash of each complete line.
    pub(crate) lines: Vec<u64>,
    current: u64,
    open: bool,
    /// The current line's first bytes, enough to tell a thumbnail's.
    head: Vec<u8>,
    thumbnails: Thumbnails,
}

/// Whether G-code lines, read in order, belong to a thumbnail block:
/// `; thumbnail begin WxH LEN` (or `thumbnail_QOI`, `thumbnail_JPG`), its
/// base64 lines, `; thumbnail end` and the `;` after it (PrusaSlicer's
/// form), so that G-code with thumbnails has the lines of G-code without.
#[derive(Default)]
pub(crate) struct Thumbnails {
    inside: bool,
    ended: bool,
}

impl Thumbnails {
    /// The longest line start [`Thumbnails::part`] reads, bytes.
    pub(crate) const HEAD: usize = 24;

    /// Whether `line` (without its line break; only its first [`HEAD`]
    /// bytes are needed) is part of a thumbnail block, the lines before it
    /// given.
    ///
    /// [`HEAD`]: Thumbnails::HEAD
    pub(crate) fn part(&mut self, line: &[u8]) -> bool {
        let tagged = |rest: &[u8]| {
            [&b"; thumbnail"[..], b"; thumbnail_QOI", b"; thumbnail_JPG"]
                .iter()
                .any(|t| line.strip_prefix(*t).is_some_and(|r| r.starts_with(rest)))
        };
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if self.inside {
            let end = [
                &b"; thumbnail end"[..],
                b"; thumbnail_QOI end",
                b"; thumbnail_JPG end",
            ];
            if end.contains(&line) {
                (self.inside, self.ended) = (false, true);
            }
            return true;
        }
        if std::mem::take(&mut self.ended) && line == b";" {
            return true;
        }
        self.inside = tagged(b" begin ");
        self.inside
    }
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

impl Write for LineHashes {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        for &b in buf {
            if !self.open {
                self.current = FNV_OFFSET;
                self.open = true;
                self.head.clear();
            }
            self.current = (self.current ^ b as u64).wrapping_mul(FNV_PRIME);
            if b == b'\n' {
                if !self.thumbnails.part(&self.head) {
                    self.lines.push(self.current);
                }
                self.open = false;
            } else if self.head.len() < Thumbnails::HEAD {
                self.head.push(b);
            }
        }
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

impl LineHashes {
    /// Lines per block for `n` lines so that there are at most [`MAX_BLOCKS`].
    pub(crate) fn block_lines(n: u64) -> u64 {
        n.div_ceil(MAX_BLOCKS).max(1)
    }

    /// Block hashes for blocks of `b` lines (a last partial line counts as a line).
    pub(crate) fn blocks(&self, b: u64) -> Vec<String> {
        let mut lines = self.lines.clone();
        if self.open {
            lines.push(self.current);
        }
        lines
            .chunks(b as usize)
            .map(|c| {
                let mut h = FNV_OFFSET;
                for l in c {
                    for byte in l.to_le_bytes() {
                        h = (h ^ byte as u64).wrapping_mul(FNV_PRIME);
                    }
                }
                format!("{:08x}", (h ^ (h >> 32)) as u32)
            })
            .collect()
    }

    /// Number of lines, a last partial line included.
    pub(crate) fn count(&self) -> u64 {
        self.lines.len() as u64 + self.open as u64
    }
}

/// Index of the first block that differs, or `None` when all shared blocks agree.
pub(crate) fn first_difference(old: &str, new: &[String]) -> Option<usize> {
    let old: Vec<&str> = old.split_whitespace().collect();
    let shared = old.len().min(new.len());
    (0..shared)
        .find(|&k| old[k] != new[k])
        .or((old.len() != new.len()).then_some(shared))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fingerprint_finds_the_changed_block() {
        let text_a: String = (0..1000).map(|k| format!("G1 X{k}\n")).collect();
        let text_b = text_a.replace("G1 X700\n", "G1 X700.5\n");
        let mut a = LineHashes::default();
        a.write_all(text_a.as_bytes()).unwrap();
        let mut b = LineHashes::default();
        // written in odd pieces: lines still split right
        for chunk in text_b.as_bytes().chunks(7) {
            b.write_all(chunk).unwrap();
        }
        assert_eq!(a.count(), 1000);
        let bl = LineHashes::block_lines(1000);
        assert_eq!(bl, 2);
        let old = a.blocks(bl).join(" ");
        let k = first_difference(&old, &b.blocks(bl)).unwrap();
        assert_eq!(k, 350); // lines 700 and 701 (0-based)
        assert_eq!(first_difference(&old, &a.blocks(bl)), None);
    }

    #[test]
    fn thumbnails_are_left_out_of_the_fingerprint() {
        let gcode = |pic: &str, x: &str| {
            format!("; generated\n; thumbnail begin 2x2 {}\n; {pic}\n; thumbnail end\n;\n; thumbnail_QOI begin 1x1 4\n; abcd\n; thumbnail_QOI end\n;\nG28\nG1 X{x}\n", pic.len())
        };
        let hashes = |text: &str| {
            let mut h = LineHashes::default();
            for chunk in text.as_bytes().chunks(5) {
                h.write_all(chunk).unwrap();
            }
            h
        };
        let a = hashes(&gcode("iVBORw0KGgo", "1"));
        // the lines kept: `; generated`, G28, G1
        assert_eq!(a.count(), 3);
        let old = a.blocks(1).join(" ");
        // another picture, longer: the same fingerprint
        let b = hashes(&gcode("iVBORw0KGgoAAAANSUhEUgAA\n; AAAB", "1"));
        assert_eq!(first_difference(&old, &b.blocks(1)), None);
        // a move changed: found where it is among the lines kept
        let c = hashes(&gcode("iVBORw0KGgoXX", "2"));
        assert_eq!(first_difference(&old, &c.blocks(1)), Some(2));
    }
}
