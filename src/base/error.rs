//! Errors that name the file, the place in it and what was expected.
//!
//! Every error carries an exit status: 2 for unusable input, 1 for a failed
//! printability check (see `docs/recipe.md` and the README, "Exit status").

use std::fmt;
use std::io;

/// What kind of failure this is; decides the exit status.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// The input was unusable: bad YAML, unknown key, bad expression, missing image…
    Input,
    /// A printability check failed (an error, or a warning under `--strict`).
    Check,
    /// Reading or writing a file failed.
    Io,
}

/// A user-facing error: `file: place: message`.
#[derive(Debug, Clone, PartialEq)]
pub struct Error {
    /// Decides the exit status.
    pub kind: Kind,
    /// The file the problem is in, as the user named it.
    pub file: Option<String>,
    /// Line and column in the file, 1-based, when known.
    pub line: Option<(usize, usize)>,
    /// Where in the file: `line 3, column 5` or a key path like `parts[0].steps[1]`.
    pub place: Option<String>,
    /// What went wrong and what was expected.
    pub message: String,
    /// The kind of the I/O error behind it, when there is one (so a caller
    /// can tell, say, a broken pipe on `-o -`).
    pub io_kind: Option<io::ErrorKind>,
    /// A hint shown below the message as `help: …` (did you mean, the allowed
    /// keys, use spaces…), when one is known; not part of [`fmt::Display`]
    /// (boxed: keeps `Error` small).
    pub help: Option<Box<str>>,
}

/// Result type of the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An input error at a key path (file filled in later by [`Error::in_file`]).
    pub(crate) fn input(place: impl Into<String>, message: impl Into<String>) -> Error {
        let place = place.into();
        Error {
            kind: Kind::Input,
            file: None,
            line: None,
            place: if place.is_empty() { None } else { Some(place) },
            message: message.into(),
            io_kind: None,
            help: None,
        }
    }

    /// An I/O error about a file.
    pub(crate) fn io(file: impl Into<String>, message: impl Into<String>) -> Error {
        Error {
            kind: Kind::Io,
            file: Some(file.into()),
            line: None,
            place: None,
            message: message.into(),
            io_kind: None,
            help: None,
        }
    }

    /// A failed printability check.
    pub(crate) fn check(file: impl Into<String>, message: impl Into<String>) -> Error {
        Error {
            kind: Kind::Check,
            file: Some(file.into()),
            line: None,
            place: None,
            message: message.into(),
            io_kind: None,
            help: None,
        }
    }

    /// An I/O error about a file, caused by `e` (whose kind it keeps).
    pub(crate) fn io_from(
        file: impl Into<String>,
        message: impl Into<String>,
        e: &io::Error,
    ) -> Error {
        Error {
            io_kind: Some(e.kind()),
            ..Error::io(file, message)
        }
    }

    /// Adds a `help:` hint (replacing any earlier one).
    pub(crate) fn with_help(mut self, help: impl Into<String>) -> Error {
        self.help = Some(help.into().into_boxed_str());
        self
    }

    /// Sets the file when none is set yet.
    pub(crate) fn in_file(mut self, file: &str) -> Error {
        if self.file.is_none() {
            self.file = Some(file.to_string());
        }
        self
    }

    /// Prefixes the key path with `prefix` (e.g. `parts[0]`).
    pub(crate) fn under(mut self, prefix: &str) -> Error {
        self.place = Some(match self.place.take() {
            None => prefix.to_string(),
            Some(p) => place_under(prefix, &p),
        });
        self
    }

    /// The process exit status for this error: 1 for a failed check, else 2.
    pub fn exit_code(&self) -> i32 {
        match self.kind {
            Kind::Check => 1,
            Kind::Input | Kind::Io => 2,
        }
    }
}

/// Key path `place` under `prefix`: `prefix.place`, or `prefix[0]…` when
/// `place` begins with an index.
pub(crate) fn place_under(prefix: &str, place: &str) -> String {
    if place.starts_with('[') {
        format!("{prefix}{place}")
    } else {
        format!("{prefix}.{place}")
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            match self.line {
                Some((l, c)) => write!(f, "{file}:{l}:{c}: ")?,
                None => write!(f, "{file}: ")?,
            }
        }
        if let Some(place) = &self.place {
            write!(f, "{place}: ")?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for Error {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_names_file_place_and_message() {
        let e = Error::input("position[2]", "bad expression")
            .under("steps[1]")
            .under("parts[0]")
            .in_file("a.yaml");
        assert_eq!(
            e.to_string(),
            "a.yaml: parts[0].steps[1].position[2]: bad expression"
        );
        assert_eq!(e.exit_code(), 2);
        assert_eq!(Error::check("a.yaml", "x").exit_code(), 1);
    }

    #[test]
    fn io_errors_keep_their_kind() {
        let cause = io::Error::new(io::ErrorKind::BrokenPipe, "pipe closed");
        let e = Error::io_from("-", format!("cannot write: {cause}"), &cause);
        assert_eq!(e.io_kind, Some(io::ErrorKind::BrokenPipe));
        assert_eq!(e.to_string(), "-: cannot write: pipe closed");
        assert_eq!(e.exit_code(), 2);
        assert_eq!(Error::io("a", "b").io_kind, None);
    }
}
