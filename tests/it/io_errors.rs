//! An I/O error on the output keeps its kind, so a caller can tell a broken
//! pipe (`p3dp build -o - | head`) from a full disk.

use crate::common::*;
use std::io::{self, Write};

/// A writer whose reader has gone away.
struct ClosedPipe;

impl Write for ClosedPipe {
    fn write(&mut self, _: &[u8]) -> io::Result<usize> {
        Err(io::Error::new(io::ErrorKind::BrokenPipe, "pipe closed"))
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[test]
fn a_broken_pipe_is_recognisable() {
    let first = std::fs::read_dir(root().join("recipes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .min()
        .unwrap();
    let mut p = p3dp::plan(&first, &Default::default()).unwrap();
    let job = p3dp::pipeline::Job {
        hash: true,
        ..Default::default()
    };
    let e = p3dp::pipeline::write(&mut p, &job, ClosedPipe)
        .err()
        .unwrap();
    assert_eq!(e.io_kind, Some(io::ErrorKind::BrokenPipe), "{e}");
    assert_eq!(e.exit_code(), 2);
}
