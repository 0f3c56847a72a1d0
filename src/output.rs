//! Outputs: files written whole or not at all, and a writer that hashes what
//! passes through it.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::error::{Error, Result};

/// A writer that hashes and counts what passes through it.
pub struct HashWriter<W: Write> {
    inner: io::BufWriter<W>,
    hasher: Sha256,
    bytes: u64,
}

impl<W: Write> HashWriter<W> {
    /// Wraps `inner` (buffered).
    pub fn new(inner: W) -> HashWriter<W> {
        HashWriter {
            inner: io::BufWriter::with_capacity(1 << 16, inner),
            hasher: Sha256::new(),
            bytes: 0,
        }
    }

    /// The SHA-256 in hex and the byte count.
    pub fn finish(self) -> (String, u64) {
        let (hex, bytes, _) = self.finish_into();
        (hex, bytes)
    }

    /// The SHA-256 in hex, the byte count and the inner writer.
    pub fn finish_into(self) -> (String, u64, W) {
        let d = self.hasher.finalize();
        let hex: String = d.iter().map(|b| format!("{b:02x}")).collect();
        let inner = self
            .inner
            .into_inner()
            .unwrap_or_else(|e| panic!("flushed before: {e}"));
        (hex, self.bytes, inner)
    }
}

impl<W: Write> Write for HashWriter<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// A file being written: a temp file beside its target, renamed into place by
/// [`AtomicFile::commit`]; dropped uncommitted, it leaves nothing behind.
pub struct AtomicFile {
    tmp: tempfile::NamedTempFile,
    target: PathBuf,
}

impl AtomicFile {
    /// Opens a temp file in `target`'s folder (which must exist).
    pub fn create(target: &Path) -> Result<AtomicFile> {
        let shown = target.display().to_string();
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let mut builder = tempfile::Builder::new();
        builder.prefix(".p3dp-").suffix(".tmp");
        #[cfg(unix)]
        {
            // an ordinary file (0666 less the umask), not tempfile's private 0600
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let tmp = builder.tempfile_in(dir).map_err(|e| {
            Error::io_from(
                &shown,
                format!("cannot create a file in {}: {e}", dir.display()),
                &e,
            )
        })?;
        Ok(AtomicFile {
            tmp,
            target: target.to_path_buf(),
        })
    }

    /// The temp file, to write to.
    pub fn file(&mut self) -> &mut std::fs::File {
        self.tmp.as_file_mut()
    }

    /// Flushes to disk and renames the temp file to the target.
    pub fn commit(mut self) -> Result<()> {
        let shown = self.target.display().to_string();
        self.tmp
            .as_file_mut()
            .sync_all()
            .map_err(|e| Error::io_from(&shown, format!("cannot write: {e}"), &e))?;
        self.tmp
            .persist(&self.target)
            .map_err(|e| Error::io_from(&shown, format!("cannot write: {}", e.error), &e.error))?;
        Ok(())
    }
}

/// Writes `target` atomically: a temp file beside it, renamed on success.
pub fn write_atomic(target: &Path, f: impl FnOnce(&mut std::fs::File) -> Result<()>) -> Result<()> {
    let mut a = AtomicFile::create(target)?;
    f(a.file())?;
    a.commit()
}
