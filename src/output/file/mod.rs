//! Output files: written whole or not at all, never replacing a special
//! file, never one of the command's own inputs.
//!
//! A regular file (or a missing one) is written to a temp file beside it,
//! renamed over it on [`AtomicFile::commit`] ([`atomic`]). A symlink is
//! followed and its final target written that way (the link stays a link).
//! A character device (`/dev/null`) or a FIFO is written to directly; a
//! folder, a block device or a socket is refused. Temp files are removed
//! when a signal stops the process and swept when a killed one left them
//! ([`temp`]).

pub(crate) mod atomic;
pub(crate) mod hash;
pub(crate) mod scratch;
pub(crate) mod stdout;
pub(crate) mod temp;

use std::io;
use std::path::{Component, Path, PathBuf};

pub(crate) use atomic::{write_atomic, AtomicFile};
pub(crate) use hash::HashWriter;
pub(crate) use scratch::Scratch;
pub(crate) use stdout::{say_fmt, stdout_closed, tell_fmt, Stdout};
pub(crate) use temp::{remove_temp_files_on_signals, stop_on_signals};

use crate::base::error::{Error, Result};

/// The extension of `path` in lower case ("" without one): what an output's
/// format is told by.
pub(crate) fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Follows symlinks from `path` to the file they end at (which may be
/// missing); also returns its metadata when it exists.
pub(crate) fn follow(path: &Path) -> io::Result<(PathBuf, Option<std::fs::Metadata>)> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match p.symlink_metadata() {
            Ok(m) if m.file_type().is_symlink() => {
                let to = std::fs::read_link(&p)?;
                p = if to.is_absolute() {
                    to
                } else {
                    p.parent().unwrap_or(Path::new("")).join(to)
                };
            }
            Ok(m) => return Ok((p, Some(m))),
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok((p, None)),
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// Whether the metadata is of a file written to directly: a character device or a FIFO.
pub(crate) fn is_stream(m: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = m.file_type();
        t.is_char_device() || t.is_fifo()
    }
    #[cfg(not(unix))]
    {
        let _ = m;
        false
    }
}

/// What `path` names once symlinks, `.` and `..` are resolved, whether or
/// not it exists: two paths with the same identity are the same file.
pub(crate) fn identity(path: &Path) -> PathBuf {
    let followed = follow(path)
        .map(|(p, _)| p)
        .unwrap_or_else(|_| path.to_path_buf());
    if let Ok(c) = followed.canonicalize() {
        return c;
    }
    let abs = if followed.is_absolute() {
        followed
    } else {
        std::env::current_dir().unwrap_or_default().join(followed)
    };
    // the longest existing ancestor, canonical, then the rest lexically
    let comps: Vec<Component> = abs.components().collect();
    for k in (0..comps.len()).rev() {
        let head: PathBuf = comps[..k].iter().collect();
        if let Ok(mut out) = head.canonicalize() {
            for c in &comps[k..] {
                match c {
                    Component::ParentDir => {
                        out.pop();
                    }
                    Component::CurDir => {}
                    other => out.push(other.as_os_str()),
                }
            }
            return out;
        }
    }
    abs
}

/// Whether `path` is a character device or FIFO (written directly, so
/// several outputs may share it, like `/dev/null`).
fn is_shared_stream(path: &Path) -> bool {
    matches!(follow(path), Ok((_, Some(m))) if is_stream(&m))
}

/// Refuses outputs that resolve to the same file as another output or as
/// one of the command's `inputs`; each is `(option, path)`, e.g.
/// `("--stats-json", "s.json")`. Called before anything is written.
pub(crate) fn check_distinct(
    outputs: &[(String, PathBuf)],
    inputs: &[(String, PathBuf)],
) -> Result<()> {
    let ids: Vec<Option<PathBuf>> = outputs
        .iter()
        .map(|(_, p)| (!is_shared_stream(p)).then(|| identity(p)))
        .collect();
    let inputs: Vec<(&String, &PathBuf, PathBuf)> =
        inputs.iter().map(|(l, p)| (l, p, identity(p))).collect();
    // the first output of each identity (a batch may have 10,000)
    let mut first: std::collections::HashMap<&PathBuf, usize> = std::collections::HashMap::new();
    for (k, (label, path)) in outputs.iter().enumerate() {
        let Some(id) = &ids[k] else { continue };
        if let Some((what, input, _)) = inputs.iter().find(|(_, _, i)| i == id) {
            return Err(Error::input(
                label.as_str(),
                format!(
                    "`{}` is {what} `{}`, which this command reads; expected another file to write",
                    path.display(),
                    input.display()
                ),
            ));
        }
        if let Some(&j) = first.get(id) {
            return Err(Error::input(
                label.as_str(),
                format!(
                    "`{}` is the file {} `{}` writes too; expected a different file for each output",
                    path.display(),
                    outputs[j].0,
                    outputs[j].1.display()
                ),
            ));
        }
        first.insert(id, k);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::temp::is_temp_name;
    use super::*;
    use std::io::Write;

    #[test]
    fn temp_names_are_ours_only() {
        assert!(is_temp_name(".p3dp-a1B2c3.tmp"));
        assert!(!is_temp_name(".p3dp-a1B2c.tmp"));
        assert!(!is_temp_name("p3dp-a1B2c3.tmp"));
        assert!(!is_temp_name(".p3dp-a1B2c3.tmp.gcode"));
    }

    #[test]
    fn identity_resolves_dots_of_missing_paths() {
        let d = std::env::temp_dir().canonicalize().unwrap();
        assert_eq!(
            identity(&d.join("no-such-p3dp-dir/../x.gcode")),
            d.join("x.gcode")
        );
        assert_eq!(identity(&d.join("./y/./z")), d.join("y/z"));
    }

    #[test]
    fn a_streamed_file_is_every_byte_once_committed() {
        // past two kicks, in odd-sized writes: the kicks change no byte, and
        // nothing is at the target before the commit
        let dir = std::env::temp_dir().join(format!("p3dp-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("big.gcode");
        let bytes: Vec<u8> = (0..(2 * crate::output::file::atomic::Streaming::KICK + 12_345))
            .map(|k| (k % 251) as u8)
            .collect();
        let mut f = AtomicFile::create(&target).unwrap();
        let mut w = f.streaming();
        for piece in bytes.chunks(65_537) {
            w.write_all(piece).unwrap();
        }
        w.flush().unwrap();
        assert!(!target.exists());
        f.commit().unwrap();
        assert!(std::fs::read(&target).unwrap() == bytes);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bytes_written_after_a_flush_are_committed_too() {
        // flushed mid-way, written on: the commit makes every byte durable
        // and a dropped file leaves nothing behind
        let dir = std::env::temp_dir().join(format!("p3dp-flush-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.gcode");
        let mut f = AtomicFile::create(&target).unwrap();
        {
            let mut w = f.streaming();
            w.write_all(b"G1 X1\n").unwrap();
            w.flush().unwrap();
            w.write_all(b"G1 X2\n").unwrap();
            w.flush().unwrap();
        }
        f.commit().unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"G1 X1\nG1 X2\n");
        let mut g = AtomicFile::create(&dir.join("gone.gcode")).unwrap();
        g.streaming().flush().unwrap();
        drop(g);
        assert!(!dir.join("gone.gcode").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
