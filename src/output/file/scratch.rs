//! A scratch file: text written once and read back once (the G-code
//! before its progress lines go in), kept out of the process's memory — an
//! unnamed temporary file the system deletes when it is closed — or, where
//! no such file can be made, in memory.

use std::io::{self, Read, Seek, Write};

/// Where scratch text goes (see the module comment).
pub(crate) enum Scratch {
    /// An unnamed temporary file.
    File(io::BufWriter<std::fs::File>),
    /// Memory, when no temporary file could be made.
    Memory(Vec<u8>),
}

impl Scratch {
    /// A new, empty scratch file.
    pub(crate) fn new() -> Scratch {
        match tempfile::tempfile() {
            Ok(f) => Scratch::File(io::BufWriter::with_capacity(1 << 16, f)),
            Err(_) => Scratch::Memory(Vec::new()),
        }
    }

    /// What was written, to read from the start. The file unbuffered: its
    /// reader takes pieces of hundreds of KiB straight into its own buffer
    /// (a buffer here would copy every byte once more).
    pub(crate) fn into_reader(self) -> io::Result<Box<dyn Read + Send>> {
        Ok(match self {
            Scratch::File(w) => {
                let mut f = w.into_inner().map_err(|e| e.into_error())?;
                f.rewind()?;
                Box::new(f)
            }
            Scratch::Memory(v) => Box::new(io::Cursor::new(v)),
        })
    }
}

impl Write for Scratch {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self {
            Scratch::File(f) => f.write(buf),
            Scratch::Memory(v) => v.write(buf),
        }
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        match self {
            Scratch::File(f) => f.write_all(buf),
            Scratch::Memory(v) => v.write_all(buf),
        }
    }
    fn flush(&mut self) -> io::Result<()> {
        match self {
            Scratch::File(f) => f.flush(),
            Scratch::Memory(_) => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_is_written_reads_back_whole() {
        let text: Vec<u8> = (0..200_000u32).flat_map(|k| k.to_le_bytes()).collect();
        for mut s in [Scratch::new(), Scratch::Memory(Vec::new())] {
            s.write_all(&text).unwrap();
            s.flush().unwrap();
            let mut back = Vec::new();
            s.into_reader().unwrap().read_to_end(&mut back).unwrap();
            assert_eq!(back, text);
        }
    }
}
