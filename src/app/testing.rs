//! The command line run in process, for the tests beside the code that
//! build a real recipe the way a user does and then look inside.

use std::path::Path;

use clap::Parser;

use crate::app::cli::{self, Cli};
use crate::machine::Flavor;

/// A built-in printer (or fixture) of each flavour, for the tests that read
/// a print back in every firmware's dialect.
pub(crate) const FLAVOURS: [(&str, Flavor); 5] = [
    ("generic-220", Flavor::Marlin),
    ("prusa-mk4", Flavor::Prusa),
    ("voron-350", Flavor::Klipper),
    ("rostock-max", Flavor::Reprap),
    ("tests/fixtures/printers/bambu-flavor.yaml", Flavor::Bambu),
];

/// What a command run in process left: its exit status (0, 1 or 2, as the
/// binary's) and its errors as the binary renders them.
pub(crate) struct Output {
    /// The exit status the binary would give.
    pub(crate) code: i32,
    /// The errors, rendered.
    pub(crate) stderr: String,
}

impl Output {
    /// Whether the command succeeded.
    pub(crate) fn success(&self) -> bool {
        self.code == 0
    }
}

/// Runs `p3dp ARGS` in process as if in `dir`: every argument that names a
/// file there (not an option, not a number) is taken relative to `dir`,
/// since a process has one working folder and the tests run side by side.
/// A `build` must name its output (`-o`): its default, beside the working
/// folder, would be the crate's own.
pub(crate) fn p3dp(dir: &Path, args: &[&str]) -> Output {
    assert!(
        args.first() != Some(&"build") || args.contains(&"-o"),
        "a build run in process must name its output with -o"
    );
    assert!(
        args.first() != Some(&"new") || args.get(1).is_some_and(|n| n.ends_with(".yaml")),
        "a starter made in process must be named NAME.yaml"
    );
    let mut argv = vec!["p3dp".to_string()];
    for a in args {
        let file = !a.starts_with('-') && a.contains('.') && a.parse::<f64>().is_err();
        argv.push(if file && Path::new(a).is_relative() {
            dir.join(a).display().to_string()
        } else {
            a.to_string()
        });
    }
    let errors = match Cli::try_parse_from(&argv) {
        Ok(c) => cli::run(c),
        Err(e) => {
            return Output {
                code: 2,
                stderr: e.to_string(),
            }
        }
    };
    Output {
        code: errors.iter().map(|e| e.exit_code()).max().unwrap_or(0),
        stderr: errors.iter().map(|e| cli::render_error(e) + "\n").collect(),
    }
}
