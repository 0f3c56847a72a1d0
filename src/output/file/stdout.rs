//! Standard output and error that never panic: a closed pipe (`p3dp check
//! … | head -1`) is noted and the command ends quietly, as `rg` does.

use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};

/// Set once standard output is a closed pipe (`p3dp build … -o - | head -1`).
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

/// Whether a write to [`Stdout`] found the pipe closed: the reader has all it
/// wanted, and the command ends quietly with status 0, as `rg` does.
pub(crate) fn stdout_closed() -> bool {
    STDOUT_CLOSED.load(Ordering::Relaxed)
}

/// Standard output that notes a closed pipe (see [`stdout_closed`]).
pub(crate) struct Stdout;

impl Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        io::stdout().lock().write(buf).inspect_err(note_closed)
    }
    fn flush(&mut self) -> io::Result<()> {
        io::stdout().lock().flush().inspect_err(note_closed)
    }
}

/// Writes to standard output through [`Stdout`]: a closed pipe
/// (`p3dp check … | head -1`) is noted, never a panic as `print!`'s is.
pub(crate) fn say_fmt(args: std::fmt::Arguments) {
    if !stdout_closed() {
        let _ = Stdout.write_fmt(args);
    }
}

/// Writes to standard error; a closed one is ignored, never a panic as
/// `eprint!`'s is.
pub(crate) fn tell_fmt(args: std::fmt::Arguments) {
    let _ = io::stderr().lock().write_fmt(args);
}

/// `print!` that ends quietly on a closed pipe (see `say_fmt`).
#[macro_export]
macro_rules! say {
    ($($t:tt)*) => { $crate::output::file::say_fmt(format_args!($($t)*)) };
}

/// `println!` that ends quietly on a closed pipe (see `say_fmt`).
#[macro_export]
macro_rules! sayln {
    ($($t:tt)*) => { $crate::output::file::say_fmt(format_args!("{}\n", format_args!($($t)*))) };
}

/// `eprint!` that never panics (see `tell_fmt`).
#[macro_export]
macro_rules! tell {
    ($($t:tt)*) => { $crate::output::file::tell_fmt(format_args!($($t)*)) };
}

/// `eprintln!` that never panics (see `tell_fmt`).
#[macro_export]
macro_rules! tellln {
    ($($t:tt)*) => { $crate::output::file::tell_fmt(format_args!("{}\n", format_args!($($t)*))) };
}

fn note_closed(e: &io::Error) {
    if e.kind() == io::ErrorKind::BrokenPipe {
        STDOUT_CLOSED.store(true, Ordering::Relaxed);
    }
}
