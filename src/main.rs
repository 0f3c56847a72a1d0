//! The `p3dp` binary: parses the command line, calls the library, maps errors
//! to exit statuses (0 success, 1 a check failed, 2 unusable input).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use p3dp::cli::{self, BuildArgs, Common};

/// Procedural 3D printing: YAML recipes of nozzle paths to G-code.
#[derive(Parser)]
#[command(name = "p3dp", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Args)]
struct CommonArgs {
    /// Recipe files (YAML).
    #[arg(required = true, value_name = "RECIPE")]
    recipes: Vec<PathBuf>,
    /// Override a param: NAME=VALUE (VALUE may be an expression); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// Use this printer (built-in name or YAML file) instead of the recipe's.
    #[arg(long, value_name = "NAME|FILE")]
    printer: Option<String>,
    /// Warnings fail the build too.
    #[arg(long)]
    strict: bool,
    /// Write even when checks fail.
    #[arg(long)]
    force: bool,
}

impl From<CommonArgs> for Common {
    fn from(a: CommonArgs) -> Common {
        Common {
            recipes: a.recipes,
            sets: a.sets,
            printer: a.printer,
            strict: a.strict,
            force: a.force,
        }
    }
}

#[derive(Subcommand)]
enum Command {
    /// Write G-code (default ./NAME.gcode) and print a stats report.
    Build {
        #[command(flatten)]
        common: CommonArgs,
        /// Output file; a folder with several recipes; `-` for standard output.
        #[arg(short, long, value_name = "OUT")]
        output: Option<String>,
        /// Also write the stats as JSON to FILE.
        #[arg(long, value_name = "FILE")]
        stats_json: Option<PathBuf>,
    },
    /// Run every printability check without writing G-code.
    Check {
        #[command(flatten)]
        common: CommonArgs,
    },
    /// Print `SHA256  RECIPE`: the hash of exactly the bytes `build` would write.
    Hash {
        #[command(flatten)]
        common: CommonArgs,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let errors = match cli.command {
        Command::Build {
            common,
            output,
            stats_json,
        } => cli::build(&BuildArgs {
            common: common.into(),
            output,
            stats_json,
        }),
        Command::Check { common } => cli::check(&common.into()),
        Command::Hash { common } => cli::hash(&common.into()),
    };
    let mut code = 0;
    for e in &errors {
        eprintln!("error: {e}");
        code = code.max(e.exit_code());
    }
    ExitCode::from(code as u8)
}
