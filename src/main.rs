//! The `p3dp` binary: parses the command line, calls the library, maps errors
//! to exit statuses (0 success, 1 a check failed, 2 unusable input).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, CommandFactory, Parser, Subcommand};
use p3dp::cli::{self, BuildArgs, Common, HashArgs, PreviewArgs};

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
    #[arg(value_name = "RECIPE")]
    recipes: Vec<PathBuf>,
    /// Override a param: NAME=VALUE (VALUE may be an expression); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// Build every combination of values: NAME=v1,v2,… or NAME=a..b:step; repeatable.
    #[arg(long = "sweep", value_name = "NAME=VALUES")]
    sweeps: Vec<String>,
    /// At most N threads in all, shared by the builds run at once (default: one per core).
    #[arg(short = 'j', long = "jobs", value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    jobs: Option<u16>,
    /// Use this printer (built-in name or YAML file) instead of the recipe's.
    #[arg(long, value_name = "NAME|FILE")]
    printer: Option<String>,
    /// Warnings fail the build too.
    #[arg(long)]
    strict: bool,
    /// Write even when checks fail.
    #[arg(long)]
    force: bool,
    /// Silence a check for this build: its code, e.g. `bridge`; repeatable.
    #[arg(long = "allow", value_name = "CODE")]
    allow: Vec<String>,
}

impl From<CommonArgs> for Common {
    fn from(a: CommonArgs) -> Common {
        Common {
            recipes: a.recipes,
            sets: a.sets,
            sweeps: a.sweeps,
            jobs: a.jobs.map(usize::from),
            printer: a.printer,
            strict: a.strict,
            force: a.force,
            allow: a.allow,
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
        /// Also write the cell array of the recipe's ca_helix as a PNG: one row per layer, filled cells dark.
        #[arg(long, value_name = "FILE")]
        pattern: Option<PathBuf>,
        /// Also write a preview of the build: FILE.png (an image) or FILE.html (a 3D viewer).
        #[arg(long, value_name = "FILE")]
        preview: Option<PathBuf>,
    },
    /// Draw the toolpath: a PNG image, or a self-contained HTML file with a 3D viewer.
    Preview {
        /// Recipe file (YAML).
        #[arg(value_name = "RECIPE")]
        recipe: PathBuf,
        /// Override a param: NAME=VALUE (VALUE may be an expression); repeatable.
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
        /// Use this printer (built-in name or YAML file) instead of the recipe's.
        #[arg(long, value_name = "NAME|FILE")]
        printer: Option<String>,
        /// Output: FILE.png or FILE.html (default ./NAME.png).
        #[arg(short, long, value_name = "FILE")]
        output: Option<PathBuf>,
        /// Where to look from: iso, top, front or side (the viewer starts there).
        #[arg(long, value_name = "VIEW")]
        view: Option<String>,
        /// Colour by speed, cross-section, flow, order, findings or plain.
        #[arg(long, value_name = "MODE")]
        color: Option<String>,
        /// Image size WIDTHxHEIGHT in pixels (PNG; default 1200x900).
        #[arg(long, value_name = "WxH")]
        size: Option<String>,
        /// The model alone: no name, stats or legend (PNG).
        #[arg(long)]
        bare: bool,
        /// Silence a check for this build: its code, e.g. `bridge`; repeatable.
        #[arg(long = "allow", value_name = "CODE")]
        allow: Vec<String>,
    },
    /// Run every printability check without writing G-code.
    Check {
        #[command(flatten)]
        common: CommonArgs,
    },
    /// List the built-in printer profiles: flavour, bed, origin, nozzle and filament.
    Printers,
    /// Print `SHA256  RECIPE`: the hash of exactly the bytes `build` would write.
    Hash {
        #[command(flatten)]
        common: CommonArgs,
        /// Write the hashes (with recipe paths and --set values) to a lock file.
        #[arg(long, value_name = "FILE", conflicts_with = "check")]
        lock: Option<PathBuf>,
        /// Rebuild every entry of a lock file; exit 1 naming each that changed.
        #[arg(long, value_name = "FILE")]
        check: Option<PathBuf>,
    },
    /// Write a commented starter recipe, NAME.yaml, that builds as it is.
    New {
        /// The recipe's name (and file: NAME.yaml, or NAME itself when it ends in .yaml).
        #[arg(value_name = "NAME")]
        name: String,
        /// What to start from.
        #[arg(long, value_name = "KIND", default_value = "sphere",
              value_parser = ["sphere", "globe", "plate", "turtle", "solid"])]
        from: String,
    },
    /// Print a shell completion script: bash, zsh, fish, powershell or elvish.
    Completions {
        /// The shell.
        #[arg(value_name = "SHELL")]
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff; `p3dp man | man -l -`).
    Man,
    /// Print the JSON Schema (draft 2020-12) of the recipe format, for editors.
    Schema,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let errors = match cli.command {
        Command::Build {
            common,
            output,
            stats_json,
            pattern,
            preview,
        } => cli::build(&BuildArgs {
            common: common.into(),
            output,
            stats_json,
            pattern,
            preview,
        }),
        Command::Preview {
            recipe,
            sets,
            printer,
            output,
            view,
            color,
            size,
            bare,
            allow,
        } => cli::preview(&PreviewArgs {
            recipe,
            sets,
            printer,
            output,
            view,
            color,
            size,
            bare,
            allow,
        }),
        Command::Check { common } => cli::check(&common.into()),
        Command::Printers => {
            print!("{}", cli::printers());
            Vec::new()
        }
        Command::Hash {
            common,
            lock,
            check,
        } => cli::hash(&HashArgs {
            common: common.into(),
            lock,
            check,
        }),
        Command::New { name, from } => match cli::new_recipe(&name, &from) {
            Ok(line) => {
                println!("{line}");
                Vec::new()
            }
            Err(e) => vec![e],
        },
        Command::Completions { shell } => {
            clap_complete::generate(shell, &mut Cli::command(), "p3dp", &mut std::io::stdout());
            Vec::new()
        }
        Command::Schema => {
            let s = p3dp::recipe::schema::json_schema();
            println!(
                "{}",
                serde_json::to_string_pretty(&s).expect("a schema serialises")
            );
            Vec::new()
        }
        Command::Man => {
            let mut out = Vec::new();
            match clap_mangen::Man::new(Cli::command()).render(&mut out) {
                Ok(()) => {
                    use std::io::Write;
                    let _ = std::io::stdout().write_all(&out);
                    Vec::new()
                }
                Err(e) => vec![p3dp::error::Error::io(
                    "-",
                    format!("cannot write the manual: {e}"),
                )],
            }
        }
    };
    let mut code = 0;
    for e in &errors {
        eprint!("{}", cli::render_error(e));
        code = code.max(e.exit_code());
    }
    ExitCode::from(code as u8)
}
