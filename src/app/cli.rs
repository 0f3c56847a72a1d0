//! The command line: its clap definition ([`Cli`]), turned into the plain
//! options of each command ([`crate::app::command`]) and run inside the
//! pipeline's pool of `-j` threads. Nothing here builds, checks or writes:
//! each flag is declared once and each command is a file of `command/`.

use std::path::PathBuf;

use clap::{Args, CommandFactory, Parser, Subcommand, ValueEnum};

use crate::app::command::{self, Builds};
use crate::app::pipeline::{self, Threads};
use crate::base::error::{Error, Result};
use crate::machine::size::Size;
use crate::output::preview::{ColorMode, View};
use crate::recipe::parse_set;

/// Procedural 3D printing: YAML recipes of nozzle paths to G-code.
#[derive(Parser, Debug)]
#[command(name = "p3dp", version, about)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub(crate) command: Command,
}

/// The commands.
#[derive(Subcommand, Debug)]
pub(crate) enum Command {
    /// Write G-code (default ./NAME.gcode) and print a stats report.
    Build(BuildArgs),
    /// Build a calibration print of the gallery for a printer and material (`--list`), or write the value read off one into a profile (`calibrate apply`).
    Calibrate(Box<CalibrateArgs>),
    /// Put several recipes on one bed, arranged and printed one after another (RECIPE*N: N copies); write its G-code as build does.
    Plate(PlateArgs),
    /// Draw the toolpath: a PNG image, or a self-contained HTML file with a 3D viewer.
    Preview(PreviewArgs),
    /// Write the toolpath as solid beads for a slicer or CAD: FILE.stl, FILE.3mf or FILE.obj.
    Mesh(MeshArgs),
    /// Serve the 3D viewer on http://127.0.0.1:PORT/ and update it on every save of the recipe or a file it reads.
    Watch(WatchArgs),
    /// Run every printability check without writing G-code.
    Check {
        /// Shared flags.
        #[command(flatten)]
        batch: BatchFlags,
    },
    /// Upload built files to the printer's host (Moonraker, OctoPrint or PrusaLink, found by asking it); the API key comes from the environment variable P3DP_API_KEY.
    Send(SendArgs),
    /// Explain a check code: what it measures, why a print fails, how to fix it, the `allow` that silences it.
    Explain {
        /// The code, as a finding shows it in brackets (e.g. `small-contact`); without one, every code in a line each.
        #[arg(value_name = "CODE")]
        code: Option<String>,
    },
    /// List the built-in printer profiles (flavour, bed, origin, nozzle, filament), or list and import a slicer's printer presets.
    Printers(PrintersArgs),
    /// Print `SHA256  RECIPE`: the hash of exactly the bytes `build` would write.
    Hash(HashArgs),
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

/// `p3dp printers [list FILE | import FILE …]`.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct PrintersArgs {
    /// What to do; without it, list the built-in profiles.
    #[command(subcommand)]
    pub(crate) action: Option<PrintersAction>,
}

/// The actions of `p3dp printers`.
#[derive(Subcommand, Clone, Debug)]
pub(crate) enum PrintersAction {
    /// List the printer (or, with --filaments, filament) presets of a slicer's file: a PrusaSlicer/SuperSlicer .ini (bundle or exported config) or an OrcaSlicer/Bambu Studio .json.
    List {
        /// The preset file.
        #[arg(value_name = "FILE")]
        file: PathBuf,
        /// List the file's filament presets (for --filament-preset) instead of its printer presets.
        #[arg(long)]
        filaments: bool,
    },
    /// Write a slicer's printer preset as a p3dp printer profile (YAML, to standard output or -o): bed, height, nozzle, flavour, limits, retraction, thumbnails and the maker's start/end G-code.
    Import {
        /// The preset file (.ini or .json).
        #[arg(value_name = "FILE")]
        file: PathBuf,
        /// The preset to import, when the file holds several (`p3dp printers list FILE`).
        #[arg(long, value_name = "NAME")]
        preset: Option<String>,
        /// A folder of the slicer's presets where a .json preset's `inherits` parents are found (e.g. OrcaSlicer's resources/profiles/VENDOR); the file's own folder is searched first.
        #[arg(long, value_name = "DIR")]
        profiles: Option<PathBuf>,
        /// Write the profile here instead of standard output.
        #[arg(short = 'o', long, value_name = "OUT.yaml")]
        output: Option<PathBuf>,
    },
}

/// What every build takes: params, the printer, the checks silenced.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct RecipeFlags {
    /// Override a param: NAME=VALUE (VALUE may be an expression); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub(crate) sets: Vec<String>,
    /// Use this printer (built-in name, YAML file, or a slicer's single-preset FILE.ini|FILE.json) instead of the recipe's.
    #[arg(long, value_name = "NAME|FILE")]
    pub(crate) printer: Option<String>,
    /// Use this slicer's filament preset (a PrusaSlicer .ini bundle or exported config, an OrcaSlicer/Bambu Studio .json) instead of the recipe's material: temperatures, diameter, density, flow limit, and the filament's values for the start and end G-code.
    #[arg(long, value_name = "FILE.ini|FILE.json")]
    pub(crate) filament: Option<PathBuf>,
    /// The filament preset of a bundle (`p3dp printers list FILE --filaments` lists them).
    #[arg(long, value_name = "NAME", requires = "filament")]
    pub(crate) filament_preset: Option<String>,
    /// Silence a check for this build: its code, e.g. `bridge`; repeatable.
    #[arg(long = "allow", value_name = "CODE")]
    pub(crate) allow: Vec<String>,
    /// Let the recipe read files below DIR too (it reads only below its project: the folder holding p3dp.lock or .git, else its own); repeatable.
    #[arg(long = "allow-read", value_name = "DIR")]
    pub(crate) allow_read: Vec<PathBuf>,
}

/// The thread budget.
#[derive(Args, Clone, Copy, Debug, Default)]
pub(crate) struct JobsFlag {
    /// At most N threads in all (default: one per core; at most 4 per core are used); the output is the same on any number.
    #[arg(short = 'j', long = "jobs", value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub(crate) jobs: Option<u16>,
}

impl JobsFlag {
    /// The threads of `-j N`: one per core by default.
    fn threads(self) -> Threads {
        self.jobs
            .map_or_else(Threads::available, |n| Threads::asked(usize::from(n)))
    }
}

/// The flags of the commands that build many recipes and sweeps.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct BatchFlags {
    /// Recipe files (YAML).
    #[arg(value_name = "RECIPE")]
    pub(crate) recipes: Vec<PathBuf>,
    /// Build every combination of values: NAME=v1,v2,…, NAME=a..b:step or NAME=a..b (step 1); repeatable.
    #[arg(long = "sweep", value_name = "NAME=VALUES")]
    pub(crate) sweeps: Vec<String>,
    /// Warnings fail the build too.
    #[arg(long)]
    pub(crate) strict: bool,
    /// Write even when checks fail.
    #[arg(long)]
    pub(crate) force: bool,
    /// Params, printer and checks.
    #[command(flatten)]
    pub(crate) recipe: RecipeFlags,
    /// Threads.
    #[command(flatten)]
    pub(crate) jobs: JobsFlag,
}

impl BatchFlags {
    /// The plain options: `--set` and `--sweep` parsed.
    fn builds(&self) -> Result<Builds> {
        let one = self.recipe.one(PathBuf::new())?;
        Ok(Builds {
            recipes: self.recipes.clone(),
            sweeps: self
                .sweeps
                .iter()
                .map(|s| crate::app::batch::parse_sweep(s))
                .collect::<Result<_>>()?,
            strict: self.strict,
            force: self.force,
            ..one
        })
    }
}

impl RecipeFlags {
    /// The plain options of one recipe's build.
    fn one(&self, recipe: PathBuf) -> Result<Builds> {
        Ok(Builds {
            recipes: vec![recipe],
            sets: self
                .sets
                .iter()
                .map(|s| parse_set(s))
                .collect::<Result<_>>()?,
            printer: self.printer.clone(),
            filament: self
                .filament
                .as_ref()
                .map(|f| crate::recipe::preset::Source {
                    file: f.clone(),
                    preset: self.filament_preset.clone(),
                    profiles: None,
                }),
            allow: self.allow.clone(),
            allow_read: self.allow_read.clone(),
            ..Builds::default()
        })
    }
}

/// Flags of `build`.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct BuildArgs {
    /// Shared flags.
    #[command(flatten)]
    pub(crate) batch: BatchFlags,
    /// Output file (NAME.bgcode: Prusa's binary G-code; NAME.gcode.3mf: Bambu's package); a folder with several recipes; `-` for standard output.
    #[arg(short, long, value_name = "OUT")]
    pub(crate) output: Option<String>,
    /// Also write the stats as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub(crate) stats_json: Option<PathBuf>,
    /// Also write the cell array of the recipe's ca_helix as a PNG: one row per layer, filled cells dark.
    #[arg(long, value_name = "FILE")]
    pub(crate) pattern: Option<PathBuf>,
    /// Also write a preview of the build: FILE.png (an image) or FILE.html (a 3D viewer).
    #[arg(long, value_name = "FILE")]
    pub(crate) preview: Option<PathBuf>,
    /// Also write the z-buffer of the recipe's solid parts as JSON: each section's loops of lines and arcs, each layer's section.
    #[arg(long, value_name = "FILE")]
    pub(crate) zbuffer: Option<PathBuf>,
    /// Also draw one layer of the solid parts' z-buffer (--zbuffer-layer, default 1) as SVG: exact loops, perimeters, infill boundary.
    #[arg(long, value_name = "FILE")]
    pub(crate) zbuffer_svg: Option<PathBuf>,
    /// The layer --zbuffer-svg draws: 1 for the first on the bed.
    #[arg(long, value_name = "N")]
    pub(crate) zbuffer_layer: Option<u64>,
}

/// Flags of `calibrate`.
#[derive(Args, Clone, Debug, Default)]
#[command(args_conflicts_with_subcommands = true)]
pub(crate) struct CalibrateArgs {
    /// `apply`: write a band's value into a profile.
    #[command(subcommand)]
    pub(crate) action: Option<CalibrateAction>,
    /// List the tests.
    #[arg(long)]
    pub(crate) list: bool,
    /// The test (see --list).
    #[arg(value_name = "TEST")]
    pub(crate) test: Option<String>,
    /// The material (a built-in's name; its range of values by default).
    #[arg(long, value_name = "NAME")]
    pub(crate) material: Option<String>,
    /// `build`'s flags (--set start=… end=… step=…, --printer, -o, --stats-json, --preview …).
    #[command(flatten)]
    pub(crate) build: BuildArgs,
}

/// `calibrate apply`.
#[derive(clap::Subcommand, Clone, Debug)]
pub(crate) enum CalibrateAction {
    /// Write the value of a band of a printed test into a profile that inherits the printer.
    Apply {
        /// The test.
        #[arg(value_name = "TEST")]
        test: String,
        /// The band read off the print.
        #[arg(
            long,
            value_name = "N",
            conflicts_with = "height",
            required_unless_present = "height"
        )]
        band: Option<u32>,
        /// The height (mm) of the band read off the print.
        #[arg(long, value_name = "Z")]
        height: Option<f64>,
        /// The printer the test was printed on.
        #[arg(long, value_name = "NAME|FILE")]
        printer: Option<String>,
        /// The material it was printed with.
        #[arg(long, value_name = "NAME")]
        material: Option<String>,
        /// The params it was built with: NAME=VALUE; repeatable.
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
        /// A folder the printer's profile may be read from besides the project; repeatable.
        #[arg(long = "allow-read", value_name = "DIR")]
        allow_read: Vec<PathBuf>,
        /// The profile to write.
        #[arg(short = 'o', long, value_name = "OUT.yaml")]
        output: PathBuf,
    },
}

/// Flags of `plate`.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct PlateArgs {
    /// The recipes to put on the bed, in print order: RECIPE, or RECIPE*N for N copies.
    #[arg(value_name = "RECIPE[*N]", required = true)]
    pub(crate) recipes: Vec<String>,
    /// The plate's name: the G-code's, and the file's (NAME.gcode).
    #[arg(long, value_name = "NAME", default_value = "plate")]
    pub(crate) name: String,
    /// Variants on the plate: NAME=v1,v2,…, NAME=a..b:step or NAME=a..b; every recipe goes on once per combination (each N times); repeatable.
    #[arg(long = "sweep", value_name = "NAME=VALUES")]
    pub(crate) sweeps: Vec<String>,
    /// Warnings fail the build too.
    #[arg(long)]
    pub(crate) strict: bool,
    /// Write even when checks fail.
    #[arg(long)]
    pub(crate) force: bool,
    /// Params (every recipe's), printer and checks.
    #[command(flatten)]
    pub(crate) recipe: RecipeFlags,
    /// Threads.
    #[command(flatten)]
    pub(crate) jobs: JobsFlag,
    /// Output file (NAME.bgcode: Prusa's binary G-code; NAME.gcode.3mf: Bambu's package); `-` for standard output.
    #[arg(short, long, value_name = "OUT")]
    pub(crate) output: Option<String>,
    /// Also write the stats as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub(crate) stats_json: Option<PathBuf>,
    /// Also write a preview of the plate: FILE.png (an image) or FILE.html (a 3D viewer).
    #[arg(long, value_name = "FILE")]
    pub(crate) preview: Option<PathBuf>,
}

/// Flags of `send`.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct SendArgs {
    /// The files to upload (G-code, .bgcode, .gcode.3mf), in order.
    #[arg(value_name = "FILE", required = true)]
    pub(crate) files: Vec<PathBuf>,
    /// The host's base URL: http://HOST[:PORT] (Moonraker's port is usually 7125); the API key goes in P3DP_API_KEY.
    #[arg(long, value_name = "URL")]
    pub(crate) to: String,
    /// Start printing the last file once it is uploaded.
    #[arg(long)]
    pub(crate) print: bool,
    /// The host's software, when asking it does not tell.
    #[arg(long, value_name = "HOST", value_parser = ["moonraker", "octoprint", "prusalink"])]
    pub(crate) host: Option<String>,
    /// Seconds the host may stay silent (connecting, each write of the upload, its answer), 1 to 3600.
    #[arg(long, value_name = "S", default_value_t = 60)]
    pub(crate) timeout: u64,
}

/// Flags of `hash`.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct HashArgs {
    /// Shared flags.
    #[command(flatten)]
    pub(crate) batch: BatchFlags,
    /// Write the hashes (with recipe paths and --set values) to a lock file; an existing lock keeps its other entries.
    #[arg(long, value_name = "FILE", conflicts_with = "check")]
    pub(crate) lock: Option<PathBuf>,
    /// Rebuild every entry of a lock file; exit 1 naming each that changed.
    #[arg(long, value_name = "FILE")]
    pub(crate) check: Option<PathBuf>,
}

/// Where a preview looks from.
#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub(crate) enum ViewArg {
    /// From above, a corner: the default.
    #[default]
    Iso,
    /// Straight down.
    Top,
    /// From the front (−y).
    Front,
    /// From the right (+x).
    Side,
}

/// What a preview's colours show.
#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub(crate) enum ColorArg {
    /// Speed, mm/s: the default.
    #[default]
    Speed,
    /// Cross-section, mm².
    CrossSection,
    /// Volumetric flow, mm³/s.
    Flow,
    /// Print order.
    Order,
    /// Where the checks found something.
    Findings,
    /// The filament's own colour.
    Plain,
}

/// A `WIDTHxHEIGHT` size in pixels.
fn size(s: &str) -> std::result::Result<Size, String> {
    Size::parse(s, "--size").map_err(|e| e.message)
}

/// Flags of `preview`.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct PreviewArgs {
    /// Recipe file (YAML).
    #[arg(value_name = "RECIPE")]
    pub(crate) recipe: PathBuf,
    /// Params, printer and checks.
    #[command(flatten)]
    pub(crate) flags: RecipeFlags,
    /// Output: FILE.png or FILE.html (default ./NAME.png).
    #[arg(short, long, value_name = "FILE")]
    pub(crate) output: Option<PathBuf>,
    /// Where to look from (the viewer starts there).
    #[arg(long, value_name = "VIEW", value_enum, default_value_t)]
    pub(crate) view: ViewArg,
    /// What the colours show.
    #[arg(long, value_name = "MODE", value_enum, default_value_t)]
    pub(crate) color: ColorArg,
    /// Image size WIDTHxHEIGHT in pixels (PNG; default 1200x900).
    #[arg(long, value_name = "WxH", value_parser = size)]
    pub(crate) size: Option<Size>,
    /// The model alone: no name, stats or legend (PNG).
    #[arg(long)]
    pub(crate) bare: bool,
    /// Threads.
    #[command(flatten)]
    pub(crate) jobs: JobsFlag,
}

/// Flags of `mesh`.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct MeshArgs {
    /// Recipe file (YAML).
    #[arg(value_name = "RECIPE")]
    pub(crate) recipe: PathBuf,
    /// Params, printer and checks.
    #[command(flatten)]
    pub(crate) flags: RecipeFlags,
    /// Output: FILE.stl (binary), FILE.3mf (with the filament colour) or FILE.obj (default ./NAME.stl).
    #[arg(short, long, value_name = "FILE")]
    pub(crate) output: Option<PathBuf>,
    /// Threads.
    #[command(flatten)]
    pub(crate) jobs: JobsFlag,
}

/// Flags of `watch`.
#[derive(Args, Clone, Debug, Default)]
pub(crate) struct WatchArgs {
    /// Recipe file (YAML).
    #[arg(value_name = "RECIPE")]
    pub(crate) recipe: PathBuf,
    /// Params, printer and checks.
    #[command(flatten)]
    pub(crate) flags: RecipeFlags,
    /// Threads of each build.
    #[command(flatten)]
    pub(crate) jobs: JobsFlag,
    /// The port on 127.0.0.1 (loopback only) to serve on; 0 takes any free one.
    #[arg(long, value_name = "N", default_value_t = crate::app::watch::DEFAULT_PORT)]
    pub(crate) port: u16,
    /// Open the page in the system's web browser.
    #[arg(long)]
    pub(crate) open: bool,
}

/// The errors of one command's plain options, or what running it met.
fn errors(r: Result<Vec<Error>>) -> Vec<Error> {
    r.unwrap_or_else(|e| vec![e])
}

/// Runs a parsed command line; returns the errors met (the binary prints
/// them and exits with the worst status).
pub fn run(cli: Cli) -> Vec<Error> {
    match cli.command {
        Command::Build(a) => errors(build(&a)),
        Command::Calibrate(a) => errors(calibrate(*a)),
        Command::Plate(a) => errors(plate(&a)),
        Command::Preview(a) => errors(preview(&a)),
        Command::Mesh(a) => errors(mesh(&a)),
        Command::Watch(a) => errors(watch(&a).map(|()| Vec::new())),
        Command::Check { batch } => errors(
            batch
                .builds()
                .map(|b| pipeline::run(batch.jobs.threads(), || command::check::run(&b))),
        ),
        Command::Hash(a) => errors(hash(&a)),
        Command::Send(a) => errors(command::send::run(&command::send::Options {
            files: a.files,
            to: a.to,
            print: a.print,
            host: a.host,
            timeout: a.timeout,
        })),
        Command::Explain { code } => errors(command::explain::run(code.as_deref()).map(|text| {
            crate::say!("{text}");
            Vec::new()
        })),
        Command::Printers(a) => errors(printers(a.action).map(|text| {
            crate::say!("{text}");
            Vec::new()
        })),
        Command::New { name, from } => errors(command::new::write(&name, &from).map(|line| {
            crate::sayln!("{line}");
            Vec::new()
        })),
        Command::Completions { shell } => {
            // into memory first: clap_complete panics on a failed write
            let mut out = Vec::new();
            clap_complete::generate(shell, &mut Cli::command(), "p3dp", &mut out);
            command::print(&out);
            Vec::new()
        }
        Command::Schema => {
            command::schema();
            Vec::new()
        }
        Command::Man => {
            let mut out = Vec::new();
            match clap_mangen::Man::new(Cli::command()).render(&mut out) {
                Ok(()) => {
                    command::print(&out);
                    Vec::new()
                }
                Err(e) => vec![Error::io("-", format!("cannot write the manual: {e}"))],
            }
        }
    }
}

fn build(a: &BuildArgs) -> Result<Vec<Error>> {
    let opts = command::build::Options {
        builds: a.batch.builds()?,
        output: a.output.clone(),
        stats_json: a.stats_json.clone(),
        pattern: a.pattern.clone(),
        preview: a.preview.clone(),
        zbuffer: a.zbuffer.clone(),
        zbuffer_svg: a.zbuffer_svg.clone(),
        zbuffer_layer: a.zbuffer_layer,
        shown: None,
    };
    Ok(pipeline::run(a.batch.jobs.threads(), || {
        command::build::run(&opts)
    }))
}

/// `p3dp calibrate …`.
fn calibrate(a: CalibrateArgs) -> Result<Vec<Error>> {
    use command::calibrate;
    if let Some(CalibrateAction::Apply {
        test,
        band,
        height,
        printer,
        material,
        sets,
        allow_read,
        output,
    }) = a.action
    {
        let pick = match (band, height) {
            (Some(n), _) => calibrate::Pick::Band(n),
            (None, Some(z)) => calibrate::Pick::Height(z),
            (None, None) => return Err(Error::input("--band", "expected --band N or --height Z")),
        };
        let line = calibrate::apply(&calibrate::Apply {
            test,
            pick,
            printer,
            material,
            sets: sets.iter().map(|s| parse_set(s)).collect::<Result<_>>()?,
            allow_read,
            output,
        })?;
        crate::sayln!("{line}");
        return Ok(Vec::new());
    }
    if a.list {
        crate::say!("{}", calibrate::list());
        return Ok(Vec::new());
    }
    let Some(test) = a.test else {
        return Err(Error::input(
            "TEST",
            "expected a test's name (see `p3dp calibrate --list`)",
        ));
    };
    if !a.build.batch.recipes.is_empty() || !a.build.batch.sweeps.is_empty() {
        return Err(Error::input(
            "TEST",
            "calibrate builds one test; expected one TEST and no recipes or sweeps",
        ));
    }
    let b = &a.build;
    let opts = calibrate::Options {
        test,
        material: a.material,
        build: command::build::Options {
            builds: b.batch.builds()?,
            output: b.output.clone(),
            stats_json: b.stats_json.clone(),
            pattern: b.pattern.clone(),
            preview: b.preview.clone(),
            zbuffer: b.zbuffer.clone(),
            zbuffer_svg: b.zbuffer_svg.clone(),
            zbuffer_layer: b.zbuffer_layer,
            shown: None,
        },
    };
    Ok(pipeline::run(b.batch.jobs.threads(), || {
        calibrate::run(&opts)
    }))
}

fn plate(a: &PlateArgs) -> Result<Vec<Error>> {
    let builds = Builds {
        strict: a.strict,
        force: a.force,
        ..a.recipe.one(PathBuf::new())?
    };
    let opts = command::plate::Options {
        recipes: a.recipes.clone(),
        name: a.name.clone(),
        sweeps: a
            .sweeps
            .iter()
            .map(|s| crate::app::batch::parse_sweep(s))
            .collect::<Result<_>>()?,
        build: command::build::Options {
            builds,
            output: a.output.clone(),
            stats_json: a.stats_json.clone(),
            preview: a.preview.clone(),
            ..command::build::Options::default()
        },
    };
    Ok(pipeline::run(a.jobs.threads(), || {
        command::plate::run(&opts)
    }))
}

/// `p3dp printers …`: the text for standard output.
fn printers(action: Option<PrintersAction>) -> Result<String> {
    match action {
        None => Ok(command::printers::list()),
        Some(PrintersAction::List { file, filaments }) => {
            let kind = if filaments {
                crate::recipe::preset::Kind::Filament
            } else {
                crate::recipe::preset::Kind::Printer
            };
            command::printers::presets(kind, &file)
        }
        Some(PrintersAction::Import {
            file,
            preset,
            profiles,
            output,
        }) => {
            let opts = command::printers::Import {
                source: crate::recipe::preset::Source {
                    file,
                    preset,
                    profiles,
                },
                output,
            };
            Ok(command::printers::import(&opts)?.unwrap_or_default())
        }
    }
}

fn hash(a: &HashArgs) -> Result<Vec<Error>> {
    let opts = command::hash::Options {
        builds: a.batch.builds()?,
        lock: a.lock.clone(),
        check: a.check.clone(),
    };
    Ok(pipeline::run(a.batch.jobs.threads(), || {
        command::hash::run(&opts)
    }))
}

fn preview(a: &PreviewArgs) -> Result<Vec<Error>> {
    let opts = command::preview::Options {
        builds: a.flags.one(a.recipe.clone())?,
        output: a.output.clone(),
        view: match a.view {
            ViewArg::Iso => View::Iso,
            ViewArg::Top => View::Top,
            ViewArg::Front => View::Front,
            ViewArg::Side => View::Side,
        },
        color: match a.color {
            ColorArg::Speed => ColorMode::Speed,
            ColorArg::CrossSection => ColorMode::CrossSection,
            ColorArg::Flow => ColorMode::Flow,
            ColorArg::Order => ColorMode::Order,
            ColorArg::Findings => ColorMode::Findings,
            ColorArg::Plain => ColorMode::Plain,
        },
        size: a.size.unwrap_or_default(),
        bare: a.bare,
    };
    Ok(pipeline::run(a.jobs.threads(), || {
        command::preview::run(&opts)
    }))
}

fn mesh(a: &MeshArgs) -> Result<Vec<Error>> {
    let opts = command::mesh::Options {
        builds: a.flags.one(a.recipe.clone())?,
        output: a.output.clone(),
    };
    Ok(pipeline::run(a.jobs.threads(), || {
        command::mesh::run(&opts)
    }))
}

fn watch(a: &WatchArgs) -> Result<()> {
    let b = a.flags.one(a.recipe.clone())?;
    crate::app::watch::run(&crate::app::watch::Options {
        recipe: a.recipe.clone(),
        build: crate::app::prepare::Options {
            sets: b.sets,
            printer: b.printer,
            filament: b.filament,
            allow: b.allow,
            allow_read: b.allow_read,
        },
        threads: a.jobs.threads(),
        port: a.port,
        open: a.open,
    })
}

/// An error as the binary prints it: `error: FILE:LINE:COL: PATH: message`,
/// then (see [`crate::app::diagnostic`]) the source line underlined at the place
/// and a `help:` line when one is known; coloured only on a terminal without
/// `NO_COLOR`.
pub(crate) fn render_error(e: &Error) -> String {
    crate::app::diagnostic::render(e, crate::app::diagnostic::stderr_color())
}
