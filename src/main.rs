//! The `p3dp` binary: parses the command line, calls the library, maps errors
//! to exit statuses (0 success, 1 a check failed, 2 unusable input).

use std::process::ExitCode;

use clap::Parser;
use p3dp::cli::{self, Cli};

fn main() -> ExitCode {
    let args = Cli::parse();
    cli::remove_temp_files_on_signals();
    let errors = cli::run(args);
    let mut code = 0;
    for e in &errors {
        cli::print_error(e);
        code = code.max(e.exit_code());
    }
    ExitCode::from(code as u8)
}
