//! A file written whole or not at all: a temp file beside its target,
//! renamed over it once every byte is on disk; a character device or a FIFO
//! written directly.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use super::temp::{live, sweep_stale};
use super::{follow, is_stream};
use crate::base::error::{Error, Result};

pub(super) enum Inner {
    Temp(tempfile::NamedTempFile),
    Direct(std::fs::File),
}

/// A file being written: a temp file beside its target, renamed into place by
/// [`AtomicFile::commit`]; dropped uncommitted, it leaves nothing behind. A
/// character device or FIFO is written directly instead.
pub(crate) struct AtomicFile {
    inner: Option<Inner>,
    /// The file renamed over: the target with its symlinks followed.
    target: PathBuf,
    shown: String,
}

impl AtomicFile {
    /// Opens a temp file in `target`'s folder (which must exist), or the
    /// target itself when it is a character device or a FIFO.
    pub(crate) fn create(target: &Path) -> Result<AtomicFile> {
        let shown = target.display().to_string();
        if target.as_os_str().is_empty() {
            return Err(Error::input(
                "",
                "an empty file name; expected the name of a file to write",
            ));
        }
        let (real, meta) =
            follow(target).map_err(|e| Error::io(&shown, format!("cannot write: {e}")))?;
        if let Some(m) = &meta {
            if m.is_dir() {
                return Err(Error::io(
                    &shown,
                    "cannot write: it is a folder; expected a file",
                ));
            }
            if is_stream(m) {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(&real)
                    .map_err(|e| Error::io(&shown, format!("cannot write: {e}")))?;
                return Ok(AtomicFile {
                    inner: Some(Inner::Direct(f)),
                    target: real,
                    shown,
                });
            }
            if !m.is_file() {
                return Err(Error::io(
                    &shown,
                    "cannot write: it is neither a regular file, a character device nor a FIFO",
                ));
            }
        }
        let dir = match real.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        sweep_stale(&dir);
        let mut builder = tempfile::Builder::new();
        builder.prefix(".p3dp-").suffix(".tmp").rand_bytes(6);
        #[cfg(unix)]
        {
            // an ordinary file (0666 less the umask), not tempfile's private 0600
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let mut files = live();
        let tmp = builder.tempfile_in(&dir).map_err(|e| {
            Error::io(
                &shown,
                format!("cannot create a file in {}: {e}", dir.display()),
            )
        })?;
        files.push(tmp.path().to_path_buf());
        Ok(AtomicFile {
            inner: Some(Inner::Temp(tmp)),
            target: real,
            shown,
        })
    }

    /// The file to write to.
    pub(crate) fn file(&mut self) -> &mut std::fs::File {
        match self.inner.as_mut().expect("not committed") {
            Inner::Temp(t) => t.as_file_mut(),
            Inner::Direct(f) => f,
        }
    }

    /// The file to write a big output to: as [`AtomicFile::file`], with the
    /// kernel asked to start writing each 2 MB to disk as it is written.
    pub(crate) fn streaming(&mut self) -> Streaming<'_> {
        let kick = matches!(self.inner, Some(Inner::Temp(_)));
        let file = match self.inner.as_mut().expect("not committed") {
            Inner::Temp(t) => t.as_file_mut(),
            Inner::Direct(f) => f,
        };
        Streaming {
            file,
            kick,
            written: 0,
            kicked: 0,
        }
    }

    /// Flushes to disk and renames the temp file to the target.
    pub(crate) fn commit(mut self) -> Result<()> {
        let shown = self.shown.clone();
        let io = |e: io::Error| Error::io_from(&shown, format!("cannot write: {e}"), &e);
        match self.inner.take().expect("committed once") {
            Inner::Direct(mut f) => f.flush().map_err(io),
            Inner::Temp(mut t) => {
                let path = t.path().to_path_buf();
                // durable before it takes the target's name
                let r = t
                    .as_file_mut()
                    .sync_all()
                    .map_err(io)
                    .and_then(|_| t.persist(&self.target).map(|_| ()).map_err(|e| io(e.error)));
                live().retain(|p| *p != path);
                r
            }
        }
    }
}

/// [`AtomicFile::streaming`]: every [`Streaming::KICK`] bytes, a
/// `sync_file_range(SYNC_FILE_RANGE_WRITE)` on the bytes before (Linux; it
/// starts the write-out and does not wait), so the commit's fsync has little
/// left to do. Elsewhere, and on a FIFO or device, a plain file.
pub(crate) struct Streaming<'a> {
    file: &'a mut std::fs::File,
    kick: bool,
    written: u64,
    kicked: u64,
}

impl Streaming<'_> {
    /// How many bytes are written between two kicks.
    pub(crate) const KICK: u64 = 2 << 20;

    #[cfg(target_os = "linux")]
    fn start_write_out(&self) {
        use std::os::fd::AsRawFd;
        // SAFETY: a plain system call on a file descriptor we hold open; it
        // reads no memory of ours. Its result is only advice, so ignored.
        unsafe {
            libc::sync_file_range(
                self.file.as_raw_fd(),
                self.kicked as libc::off64_t,
                (self.written - self.kicked) as libc::off64_t,
                libc::SYNC_FILE_RANGE_WRITE,
            );
        }
    }

    #[cfg(not(target_os = "linux"))]
    fn start_write_out(&self) {}
}

impl Write for Streaming<'_> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.file.write(buf)?;
        self.written += n as u64;
        if self.kick && self.written - self.kicked >= Self::KICK {
            self.start_write_out();
            self.kicked = self.written;
        }
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        // the end of the writing: the rest goes out before the commit syncs
        if self.kick && self.written > self.kicked {
            self.start_write_out();
            self.kicked = self.written;
        }
        self.file.flush()
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(Inner::Temp(t)) = self.inner.take() {
            let path = t.path().to_path_buf();
            drop(t); // removes the temp file
            live().retain(|p| *p != path);
        }
    }
}

/// Writes `target` atomically: a temp file beside it, renamed on success.
pub(crate) fn write_atomic(
    target: &Path,
    f: impl FnOnce(&mut std::fs::File) -> Result<()>,
) -> Result<()> {
    let mut a = AtomicFile::create(target)?;
    f(a.file())?;
    a.commit()
}
