//! The hashing writer: the SHA-256 and size of what passes through it.

use std::io::{self, Write};

use sha2::{Digest, Sha256};

/// A writer that hashes and counts what passes through it. The hash is
/// taken of the buffer's chunks as they go out (64 KiB at a time), not of
/// each small write: the same bytes in the same order, so the same SHA-256,
/// without copying every G-code line into the hasher's block buffer.
pub(crate) struct HashWriter<W: Write> {
    inner: io::BufWriter<Hashed<W>>,
}

/// What [`HashWriter`]'s buffer writes to: the writer, hashing what it takes.
struct Hashed<W: Write> {
    out: W,
    hasher: Sha256,
    bytes: u64,
}

impl<W: Write> Write for Hashed<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.out.write(buf)?;
        self.hasher.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

impl<W: Write> HashWriter<W> {
    /// Wraps `inner` (buffered).
    pub(crate) fn new(inner: W) -> HashWriter<W> {
        let hashed = Hashed {
            out: inner,
            hasher: Sha256::new(),
            bytes: 0,
        };
        HashWriter {
            inner: io::BufWriter::with_capacity(1 << 16, hashed),
        }
    }

    /// The writer, the hasher and the byte count apart, what was buffered
    /// written out first: for a caller that writes and hashes the same
    /// pieces on two threads (what goes to one must go to the other, in
    /// order, and be counted).
    pub(crate) fn parts(&mut self) -> io::Result<(&mut W, &mut Sha256, &mut u64)> {
        self.inner.flush()?;
        let h = self.inner.get_mut();
        Ok((&mut h.out, &mut h.hasher, &mut h.bytes))
    }

    /// The SHA-256 in hex and the byte count.
    pub(crate) fn finish(self) -> (String, u64) {
        let (hex, bytes, _) = self.finish_into();
        (hex, bytes)
    }

    /// The SHA-256 in hex, the byte count and the inner writer (flushed
    /// before: the writer of the G-code flushes at its end).
    pub(crate) fn finish_into(self) -> (String, u64, W) {
        let hashed = self
            .inner
            .into_inner()
            .unwrap_or_else(|e| panic!("flushed before: {e}"));
        let d = hashed.hasher.finalize();
        let hex: String = d.iter().map(|b| format!("{b:02x}")).collect();
        (hex, hashed.bytes, hashed.out)
    }
}

impl<W: Write> Write for HashWriter<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.inner.write(buf)
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.inner.write_all(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}
