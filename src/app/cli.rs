//! The command line: its clap definition ([`Cli`]) and the commands `build`,
//! `preview`, `mesh`, `check`, `printers` and `hash`, as the spec's contract says;
//! `watch` runs in [`crate::app::watch`].
//!
//! A command expands its recipes and `--sweep`s into jobs (see [`crate::app::batch`])
//! and runs them in parallel. Each returns the errors it met (one per failed
//! job); the binary prints them and exits with the worst status: 2 unusable
//! input, 1 failed check.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::{Args, CommandFactory, Parser, Subcommand};

use crate::analyse::stats::Stats;
use crate::app::batch::{self, Job};
use crate::app::build::{plan, Options, Plan};
use crate::base::error::{Error, Result};
use crate::base::format::hms;
use crate::base::threads::Threads;
use crate::generate::model::pattern_png;
use crate::output::file::{write_atomic, AtomicFile, HashWriter};
use crate::output::lock::{self, Entry, LineHashes, Lock};
use crate::recipe::{parse_set, parse_yaml, RawRecipe};

/// Procedural 3D printing: YAML recipes of nozzle paths to G-code.
#[derive(Parser, Debug)]
#[command(name = "p3dp", version, about)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Write G-code (default ./NAME.gcode) and print a stats report.
    Build(BuildArgs),
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
        common: Common,
    },
    /// List the built-in printer profiles: flavour, bed, origin, nozzle and filament.
    Printers,
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

/// Runs a parsed command line; returns the errors met (the binary prints
/// them and exits with the worst status).
pub fn run(cli: Cli) -> Vec<Error> {
    match cli.command {
        Command::Build(a) => build(&a),
        Command::Preview(a) => preview(&a),
        Command::Mesh(a) => mesh(&a),
        Command::Watch(a) => match watch(&a) {
            Ok(()) => Vec::new(),
            Err(e) => vec![e],
        },
        Command::Check { common } => check(&common),
        Command::Printers => {
            crate::say!("{}", printers());
            Vec::new()
        }
        Command::Hash(a) => hash(&a),
        Command::New { name, from } => match new_recipe(&name, &from) {
            Ok(line) => {
                crate::sayln!("{line}");
                Vec::new()
            }
            Err(e) => vec![e],
        },
        Command::Completions { shell } => {
            // into memory first: clap_complete panics on a failed write
            let mut out = Vec::new();
            clap_complete::generate(shell, &mut Cli::command(), "p3dp", &mut out);
            let _ = crate::output::file::Stdout.write_all(&out);
            Vec::new()
        }
        Command::Schema => {
            let s = crate::recipe::schema::json_schema();
            crate::sayln!(
                "{}",
                serde_json::to_string_pretty(&s).expect("a schema serialises")
            );
            Vec::new()
        }
        Command::Man => {
            let mut out = Vec::new();
            match clap_mangen::Man::new(Cli::command()).render(&mut out) {
                Ok(()) => {
                    let _ = crate::output::file::Stdout.write_all(&out);
                    Vec::new()
                }
                Err(e) => vec![Error::io("-", format!("cannot write the manual: {e}"))],
            }
        }
    }
}

/// Flags every command shares.
#[derive(Args, Clone, Debug, Default)]
pub struct Common {
    /// Recipe files (YAML).
    #[arg(value_name = "RECIPE")]
    pub recipes: Vec<PathBuf>,
    /// Override a param: NAME=VALUE (VALUE may be an expression); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    /// Build every combination of values: NAME=v1,v2,… or NAME=a..b:step; repeatable.
    #[arg(long = "sweep", value_name = "NAME=VALUES")]
    pub sweeps: Vec<String>,
    /// At most N threads in all (default: one per core), shared by the builds running at once.
    #[arg(short = 'j', long = "jobs", value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub jobs: Option<u16>,
    /// Use this printer (built-in name or YAML file) instead of the recipe's.
    #[arg(long, value_name = "NAME|FILE")]
    pub printer: Option<String>,
    /// Warnings fail the build too.
    #[arg(long)]
    pub strict: bool,
    /// Write even when checks fail.
    #[arg(long)]
    pub force: bool,
    /// Silence a check for this build: its code, e.g. `bridge`; repeatable.
    #[arg(long = "allow", value_name = "CODE")]
    pub allow: Vec<String>,
}

/// Flags of `build`.
#[derive(Args, Clone, Debug, Default)]
pub struct BuildArgs {
    /// Shared flags.
    #[command(flatten)]
    pub common: Common,
    /// Output file; a folder with several recipes; `-` for standard output.
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<String>,
    /// Also write the stats as JSON to FILE.
    #[arg(long, value_name = "FILE")]
    pub stats_json: Option<PathBuf>,
    /// Also write the cell array of the recipe's ca_helix as a PNG: one row per layer, filled cells dark.
    #[arg(long, value_name = "FILE")]
    pub pattern: Option<PathBuf>,
    /// Also write a preview of the build: FILE.png (an image) or FILE.html (a 3D viewer).
    #[arg(long, value_name = "FILE")]
    pub preview: Option<PathBuf>,
    /// Also write the z-buffer of the recipe's solid parts as JSON: each section's loops of lines and arcs, each layer's section.
    #[arg(long, value_name = "FILE")]
    pub zbuffer: Option<PathBuf>,
    /// Also draw one layer of the solid parts' z-buffer (--zbuffer-layer, default 1) as SVG: exact loops, perimeters, infill boundary.
    #[arg(long, value_name = "FILE")]
    pub zbuffer_svg: Option<PathBuf>,
    /// The layer --zbuffer-svg draws: 1 for the first on the bed.
    #[arg(long, value_name = "N")]
    pub zbuffer_layer: Option<u64>,
}

/// Flags of `hash`.
#[derive(Args, Clone, Debug, Default)]
pub struct HashArgs {
    /// Shared flags.
    #[command(flatten)]
    pub common: Common,
    /// Write the hashes (with recipe paths and --set values) to a lock file.
    #[arg(long, value_name = "FILE", conflicts_with = "check")]
    pub lock: Option<PathBuf>,
    /// Rebuild every entry of a lock file; exit 1 naming each that changed.
    #[arg(long, value_name = "FILE")]
    pub check: Option<PathBuf>,
}

impl Common {
    fn jobs(&self) -> Result<Vec<Job>> {
        let sets: Vec<(String, String)> = self
            .sets
            .iter()
            .map(|s| parse_set(s))
            .collect::<Result<_>>()?;
        let sweeps: Vec<(String, Vec<String>)> = self
            .sweeps
            .iter()
            .map(|s| batch::parse_sweep(s))
            .collect::<Result<_>>()?;
        if self.recipes.is_empty() {
            return Err(Error::input(
                "",
                "no recipe given; expected one or more RECIPE files",
            ));
        }
        batch::check_count(self.recipes.len(), &sweeps)?;
        Ok(batch::expand(&self.recipes, &sets, &sweeps))
    }

    /// The one thread budget of `-j N` (default: one per core) for `jobs`
    /// builds: min(N, jobs) workers, each build given N / workers threads.
    fn budget(&self, jobs: usize) -> (usize, Threads) {
        let n = self
            .jobs
            .map_or_else(|| Threads::available().get(), |n| usize::from(n).max(1));
        // the pool of the builds' chunks, N workers, started now so that its
        // threads are up before the first step needs them
        crate::base::threads::warm(n);
        let workers = n.min(jobs).max(1);
        (workers, Threads::new(n / workers))
    }

    /// Plans a job on `threads` and refuses it when its checks fail (unless forced).
    fn checked_plan(&self, job: &Job, threads: Threads) -> Result<Plan> {
        let mut p = self.prepared(job, threads)?;
        p.check(&self.allow);
        self.refuse_failing(&p)?;
        Ok(p)
    }

    /// Plans a job on `threads` without checking it yet.
    fn prepared(&self, job: &Job, threads: Threads) -> Result<Plan> {
        let opts = Options {
            sets: job.sets.clone(),
            printer: self.printer.clone().or_else(|| job.printer.clone()),
            allow: self.allow.clone(),
            threads,
        };
        crate::app::build::prepare(&job.recipe, &opts)
    }

    /// The error of a checked plan whose checks fail (unless forced).
    fn refuse_failing(&self, p: &Plan) -> Result<()> {
        let failing = p.failing(self.strict);
        if !failing.is_empty() && !self.force {
            let mut msg = format!(
                "{} check{} failed, nothing written (--force writes anyway):",
                failing.len(),
                plural(failing.len())
            );
            for f in failing {
                msg.push_str(&format!("\n  [{}] {}", f.code, f.message));
            }
            return Err(Error::check(&p.path, msg));
        }
        Ok(())
    }
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// A file name made of the recipe name: letters, digits, `.`, `_` and `-`.
pub fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// `name_param-value_…`: the file stem of a sweep variant.
pub fn variant_stem(name: &str, sweep: &[(String, String)]) -> String {
    let mut s = file_stem(name);
    for (n, v) in sweep {
        s.push_str(&format!("_{}-{}", file_stem(n), file_stem(v)));
    }
    s
}

fn job_label(job: &Job) -> String {
    let mut s = job.recipe.display().to_string();
    if !job.sweep.is_empty() {
        let v: Vec<String> = job.sweep.iter().map(|(n, v)| format!("{n}={v}")).collect();
        s.push_str(&format!(" [{}]", v.join(" ")));
    }
    s
}

#[derive(Clone, Debug)]
enum Target {
    Stdout,
    File(PathBuf),
}

/// The recipe's name, read without building it.
fn recipe_name(path: &Path) -> Result<String> {
    let shown = path.display().to_string();
    let text = crate::base::input::read_text(path, "recipe")?;
    Ok(parse_yaml::<RawRecipe>(&text, &shown)?.name)
}

/// Where each job writes, and the folder of a batch (for summary.csv).
fn targets(a: &BuildArgs, jobs: &[Job]) -> Result<(Vec<Result<Target>>, PathBuf)> {
    let many = jobs.len() > 1;
    let dir = match a.output.as_deref() {
        Some("-") if many => {
            return Err(Error::input(
                "-o -",
                "standard output takes one recipe; give a folder with -o to build several",
            ))
        }
        Some("-") => return Ok((vec![Ok(Target::Stdout)], PathBuf::from("."))),
        // folders are made only when a build succeeds (see `make_parent`)
        Some(o) if many || Path::new(o).is_dir() || o.ends_with('/') => PathBuf::from(o),
        Some(o) => return Ok((vec![Ok(Target::File(PathBuf::from(o)))], PathBuf::from("."))),
        None => PathBuf::from("."),
    };
    let mut out: Vec<Result<Target>> = Vec::with_capacity(jobs.len());
    let mut seen: Vec<(PathBuf, String)> = Vec::new();
    for job in jobs {
        let t = recipe_name(&job.recipe).map(|name| {
            let file = format!("{}.gcode", variant_stem(&name, &job.sweep));
            if dir == Path::new(".") {
                PathBuf::from(file)
            } else {
                dir.join(file)
            }
        });
        // two jobs writing one file: refused before any is built
        if let Ok(file) = &t {
            if let Some((_, other)) = seen.iter().find(|(f, _)| f == file) {
                return Err(Error::input(
                    "name",
                    format!(
                        "{} and {other} would both write {}; give the recipes different names (nothing was written)",
                        job_label(job),
                        file.display()
                    ),
                )
                .in_file(&job.recipe.display().to_string()));
            }
            seen.push((file.clone(), job_label(job)));
        }
        out.push(t.map(Target::File));
    }
    Ok((out, dir))
}

fn progress(n: usize) -> indicatif::ProgressBar {
    if n < 2 {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(n as u64),
        indicatif::ProgressDrawTarget::stderr_with_hz(4),
    );
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} builds  {elapsed}")
    {
        bar.set_style(style);
    }
    bar
}

/// Makes the folder `file` goes in, if missing.
fn make_parent(file: &Path) -> Result<()> {
    match file.parent() {
        Some(d) if !d.as_os_str().is_empty() => std::fs::create_dir_all(d).map_err(|e| {
            Error::io_from(
                d.display().to_string(),
                format!("cannot create the folder: {e}"),
                &e,
            )
        }),
        _ => Ok(()),
    }
}

/// An option naming a file must not be empty (`-o ''`).
fn non_empty(option: &str, value: Option<&Path>) -> Result<()> {
    match value {
        Some(v) if v.as_os_str().is_empty() => Err(Error::input(
            option,
            "an empty file name; expected the name of a file to write",
        )),
        _ => Ok(()),
    }
}

/// The files a command reads: its recipes and a `--printer` file.
fn inputs(c: &Common) -> Vec<(String, PathBuf)> {
    inputs_of(&c.recipes, c.printer.as_deref())
}

/// The files read by a command of these `recipes` and `--printer` (a file
/// unless it names a built-in profile).
fn inputs_of(recipes: &[PathBuf], printer: Option<&str>) -> Vec<(String, PathBuf)> {
    let mut v: Vec<(String, PathBuf)> = recipes
        .iter()
        .map(|r| ("the recipe".to_string(), r.clone()))
        .collect();
    if let Some(p) = printer {
        if crate::machine::Printer::built_in(p).is_none() {
            v.push(("the --printer profile".to_string(), PathBuf::from(p)));
        }
    }
    v
}

/// What one job of `build` made: its report and its files, not yet committed
/// when the build is a single job (all its outputs are committed together).
struct Done {
    built: (Stats, String, bool),
    files: Vec<AtomicFile>,
    lines: Vec<String>,
}

/// A file's bytes into an uncommitted [`AtomicFile`] (its folder made first).
fn stage(file: &Path, bytes: &[u8]) -> Result<AtomicFile> {
    make_parent(file)?;
    let mut f = AtomicFile::create(file)?;
    f.file().write_all(bytes).map_err(|e| {
        Error::io_from(file.display().to_string(), format!("cannot write: {e}"), &e)
    })?;
    Ok(f)
}

/// What `build` settles before any job runs: the jobs, where each writes,
/// the batch folder and the stats file opened early.
struct Prepared {
    jobs: Vec<Job>,
    targets: Vec<Result<Target>>,
    dir: PathBuf,
    stats_file: Option<AtomicFile>,
}

/// Expands the jobs and refuses flag combinations before anything is built.
fn prepare(a: &BuildArgs) -> Result<Prepared> {
    let jobs = a.common.jobs()?;
    for (option, value) in [
        ("-o", a.output.as_deref().map(Path::new)),
        ("--stats-json", a.stats_json.as_deref()),
        ("--preview", a.preview.as_deref()),
        ("--pattern", a.pattern.as_deref()),
        ("--zbuffer", a.zbuffer.as_deref()),
        ("--zbuffer-svg", a.zbuffer_svg.as_deref()),
    ] {
        non_empty(option, value)?;
    }
    for (option, given) in [
        ("--zbuffer", a.zbuffer.is_some()),
        ("--zbuffer-svg", a.zbuffer_svg.is_some()),
    ] {
        if given && jobs.len() > 1 {
            return Err(Error::input(
                option,
                "writes the z-buffer of one build; expected one recipe and no --sweep",
            ));
        }
    }
    if let Some(n) = a.zbuffer_layer {
        if a.zbuffer_svg.is_none() {
            return Err(Error::input(
                "--zbuffer-layer",
                "chooses the layer --zbuffer-svg draws; expected --zbuffer-svg FILE too",
            ));
        }
        if n == 0 {
            return Err(Error::input(
                "--zbuffer-layer",
                "0 is not a layer; expected 1 for the first layer on the bed, or higher",
            ));
        }
    }
    if a.pattern.is_some() && jobs.len() > 1 {
        return Err(Error::input(
            "--pattern",
            "writes the cell array of one build; expected one recipe and no --sweep",
        ));
    }
    if let Some(pv) = &a.preview {
        if jobs.len() > 1 {
            return Err(Error::input(
                "--preview",
                "a preview is of one build; give one recipe (or run `p3dp preview` per recipe)",
            ));
        }
        crate::output::preview::Format::of(pv)?;
    }
    let (targets, dir) = targets(a, &jobs)?;
    // no output over another, nor over an input: refused before any is written
    let mut outs: Vec<(String, PathBuf)> = targets
        .iter()
        .filter_map(|t| match t {
            Ok(Target::File(f)) => Some(("-o".to_string(), f.clone())),
            _ => None,
        })
        .collect();
    for (option, value) in [
        ("--stats-json", &a.stats_json),
        ("--preview", &a.preview),
        ("--pattern", &a.pattern),
        ("--zbuffer", &a.zbuffer),
        ("--zbuffer-svg", &a.zbuffer_svg),
    ] {
        if let Some(v) = value {
            outs.push((option.to_string(), v.clone()));
        }
    }
    if !a.common.sweeps.is_empty() {
        outs.push((
            "summary.csv of --sweep".to_string(),
            dir.join("summary.csv"),
        ));
    }
    crate::output::file::check_distinct(&outs, &inputs(&a.common))?;
    // open the stats file first where its folder exists: if it cannot be
    // written, no G-code is; a missing folder is made only after a build
    let mut stats_file = None;
    if let Some(p) = &a.stats_json {
        let folder_exists = p
            .parent()
            .is_none_or(|d| d.as_os_str().is_empty() || d.is_dir());
        if folder_exists {
            stats_file = Some(AtomicFile::create(p)?);
        }
    }
    Ok(Prepared {
        jobs,
        targets,
        dir,
        stats_file,
    })
}

/// Builds one job to its target (with its preview and pattern, if asked):
/// the stats, where it went, and whether that was standard output.
fn build_job(
    a: &BuildArgs,
    job: &Job,
    target: Result<Target>,
    threads: Threads,
    single: bool,
) -> Result<Done> {
    let target = target?;
    let mut p = a.common.prepared(job, threads)?;
    // a file in a folder that exists is written (to its temp file) while the
    // checks run, and committed below only if they pass; anything else waits
    // for the checks, so a failed check still writes nothing
    let mut early = None;
    if let Target::File(f) = &target {
        let folder = f.parent().filter(|d| !d.as_os_str().is_empty());
        if folder.is_none_or(|d| d.is_dir()) {
            if let Ok(mut file) = AtomicFile::create(f) {
                let stop = (!a.common.force).then_some(a.common.strict);
                let stats = p.check_and_render_until(&a.common.allow, stop, file.streaming());
                early = Some((file, stats));
            }
        }
    }
    if early.is_none() {
        p.check(&a.common.allow);
    }
    a.common.refuse_failing(&p)?;
    // the cell array of --pattern, made before any file is written
    let pattern = match &a.pattern {
        Some(f) => Some((f, pattern_png(&p.recipe).map_err(|e| e.in_file(&p.path))?)),
        None => None,
    };
    let zbuffer = zbuffer_files(a, &p)?;
    let mut files = Vec::new();
    let mut lines = Vec::new();
    let built = match &target {
        Target::Stdout => p
            .render(crate::output::file::Stdout)
            .map(|s| (s, "standard output".to_string(), true)),
        Target::File(f) => {
            let (file, stats) = match early {
                Some((file, stats)) => (file, stats?),
                None => {
                    make_parent(f)?;
                    let mut file = AtomicFile::create(f)?;
                    let stats = p.render(file.streaming())?;
                    (file, stats)
                }
            };
            files.push(file);
            Ok((stats, f.display().to_string(), false))
        }
    }?;
    if let Some(pv) = &a.preview {
        let (bytes, line) = crate::output::preview::bytes(
            &p,
            pv,
            &crate::output::preview::Options::default(),
            &|w| p.render_unhashed(w),
        )?;
        files.push(stage(pv, &bytes)?);
        lines.push(line);
    }
    if let Some((f, png)) = &pattern {
        files.push(stage(f, png)?);
    }
    for (f, bytes) in &zbuffer {
        files.push(stage(f, bytes)?);
    }
    // a batch keeps each variant that built; one build commits all its
    // outputs together, after the stats file is written too
    if !single {
        for f in files.drain(..) {
            f.commit()?;
        }
    }
    Ok(Done {
        built,
        files,
        lines,
    })
}

/// The bytes of `--zbuffer` and `--zbuffer-svg`, made before any file is
/// written; refused when the recipe has no solid part or none has the layer.
fn zbuffer_files(a: &BuildArgs, p: &Plan) -> Result<Vec<(PathBuf, Vec<u8>)>> {
    let mut out = Vec::new();
    if a.zbuffer.is_none() && a.zbuffer_svg.is_none() {
        return Ok(out);
    }
    let curves = crate::analyse::stats::zbuffer_curves(&p.recipe);
    let option = if a.zbuffer.is_some() {
        "--zbuffer"
    } else {
        "--zbuffer-svg"
    };
    if curves.is_empty() {
        return Err(Error::input(
            option,
            "the recipe has no `solid` part; expected one whose z-buffer to write",
        ));
    }
    if let Some(f) = &a.zbuffer {
        let json = serde_json::json!({
            "p3dp_zbuffer": 1,
            "recipe": p.path,
            "solids": curves,
        });
        let mut text = serde_json::to_string_pretty(&json)
            .map_err(|e| Error::io("--zbuffer", e.to_string()))?;
        text.push('\n');
        out.push((f.clone(), text.into_bytes()));
    }
    if let Some(f) = &a.zbuffer_svg {
        let n = a.zbuffer_layer.unwrap_or(1);
        let most = curves.iter().map(|c| c.layers.len()).max().unwrap_or(0);
        let Some(svg) = crate::analyse::stats::zbuffer_svg(&p.recipe, n) else {
            return Err(Error::input(
                "--zbuffer-layer",
                format!("{n} is above the solid parts' layers; expected a layer from 1 to {most}"),
            ));
        };
        out.push((f.clone(), svg.into_bytes()));
    }
    Ok(out)
}

/// Writes `--stats-json`, then commits every pending output of a single
/// build: all committed, or none. The errors met, and whether they were.
fn commit_outputs(
    a: &BuildArgs,
    stats_file: Option<AtomicFile>,
    pending: Vec<AtomicFile>,
    all_stats: &[Stats],
) -> (Vec<Error>, bool) {
    let mut errors = Vec::new();
    let stats_file = match (&a.stats_json, all_stats.is_empty()) {
        (Some(path), false) => {
            let file = match stats_file {
                Some(f) => Ok(f),
                None => make_parent(path).and_then(|_| AtomicFile::create(path)),
            };
            match file.and_then(|f| write_stats(f, all_stats)) {
                Ok(f) => Some(f),
                Err(e) => return (vec![e], false),
            }
        }
        _ => None,
    };
    for f in pending.into_iter().chain(stats_file) {
        if let Err(e) = f.commit() {
            errors.push(e);
            return (errors, false);
        }
    }
    (errors, true)
}

/// Prints each job's report (or summary line), with its preview lines.
fn report_builds(jobs: &[Job], results: &[Built], preview_lines: &[String]) {
    let single = jobs.len() == 1;
    for (job, r) in jobs.iter().zip(results) {
        if let Ok((stats, shown, to_stdout)) = r {
            let text = if single {
                stats.report(shown)
            } else {
                summary_line(job, stats, shown)
            };
            for line in preview_lines {
                if *to_stdout {
                    crate::tellln!("{line}");
                } else {
                    crate::sayln!("{line}");
                }
            }
            if *to_stdout {
                crate::tell!("{text}");
            } else {
                crate::say!("{text}");
            }
        }
    }
}

/// `p3dp build`: writes G-code and prints a report per job.
pub fn build(a: &BuildArgs) -> Vec<Error> {
    let Prepared {
        jobs,
        targets,
        dir,
        stats_file,
    } = match prepare(a) {
        Ok(p) => p,
        Err(e) => return vec![e],
    };
    let single = jobs.len() == 1;
    let bar = progress(jobs.len());
    let (workers, threads) = a.common.budget(jobs.len());
    let done = batch::run_parallel(
        jobs.len(),
        workers,
        |k| build_job(a, &jobs[k], targets[k].clone(), threads, single),
        || bar.inc(1),
    );
    bar.finish_and_clear();
    if crate::output::file::stdout_closed() {
        // the reader of `-o -` has all it wanted: end quietly, write nothing
        return Vec::new();
    }
    let mut pending = Vec::new();
    let mut preview_lines = Vec::new();
    let results: Vec<Built> = done
        .into_iter()
        .map(|r| {
            r.map(|d| {
                pending.extend(d.files);
                preview_lines.extend(d.lines);
                d.built
            })
        })
        .collect();
    let mut errors: Vec<Error> = results.iter().filter_map(|r| r.clone().err()).collect();
    let all_stats: Vec<Stats> = results
        .iter()
        .filter_map(|r| r.as_ref().ok().map(|(s, _, _)| s.clone()))
        .collect();
    let (errs, committed) = commit_outputs(a, stats_file, pending, &all_stats);
    errors.extend(errs);
    if committed || !single {
        report_builds(&jobs, &results, &preview_lines);
    }
    if !a.common.sweeps.is_empty() {
        // every variant has a row, those that failed with their error
        let csv = dir.join("summary.csv");
        if let Err(e) = make_parent(&csv).and_then(|_| write_summary(&csv, &jobs, &results)) {
            errors.push(e);
        }
    }
    errors
}

fn summary_line(job: &Job, s: &Stats, out: &str) -> String {
    format!(
        "{} → {out}: {} strings, {:.0} mm / {:.2} g, {}, {}, sha256 {}\n",
        job_label(job),
        s.strings,
        s.filament_length_mm,
        s.filament_mass_g,
        hms(s.print_time_s),
        crate::analyse::check::summary(&s.warnings),
        &s.gcode_sha256[..12]
    )
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

type Built = Result<(Stats, String, bool)>;

/// `summary.csv` of a sweep: one row per variant.
fn write_summary(path: &Path, jobs: &[Job], results: &[Built]) -> Result<()> {
    let names: Vec<&str> = jobs[0].sweep.iter().map(|(n, _)| n.as_str()).collect();
    let mut text = String::from("file,recipe");
    for n in &names {
        text.push(',');
        text.push_str(&csv_field(n));
    }
    text.push_str(",filament_mm,filament_g,print_time_s,warnings,sha256,error\n");
    for (job, r) in jobs.iter().zip(results) {
        let file = match r {
            Ok((_, f, _)) => Path::new(f)
                .file_name()
                .map(|n| n.to_string_lossy().to_string())
                .unwrap_or_default(),
            Err(_) => String::new(),
        };
        let mut row = vec![
            csv_field(&file),
            csv_field(&job.recipe.display().to_string()),
        ];
        row.extend(job.sweep.iter().map(|(_, v)| csv_field(v)));
        match r {
            Ok((s, _, _)) => row.extend([
                format!("{:.3}", s.filament_length_mm),
                format!("{:.3}", s.filament_mass_g),
                format!("{:.1}", s.print_time_s),
                // warnings and (forced) errors; notes are not counted
                s.warnings
                    .iter()
                    .filter(|f| f.severity >= crate::analyse::check::Severity::Warning)
                    .count()
                    .to_string(),
                s.gcode_sha256.clone(),
                String::new(),
            ]),
            Err(e) => row.extend(
                ["", "", "", "", ""]
                    .map(String::from)
                    .into_iter()
                    .chain([csv_field(&e.to_string())]),
            ),
        }
        text.push_str(&row.join(","));
        text.push('\n');
    }
    write_atomic(path, |f| {
        f.write_all(text.as_bytes())
            .map_err(|e| Error::io_from(path.display().to_string(), e.to_string(), &e))
    })
}

/// The stats as JSON into `file`, returned uncommitted.
fn write_stats(mut file: AtomicFile, stats: &[Stats]) -> Result<AtomicFile> {
    let json = if stats.len() == 1 {
        serde_json::to_string_pretty(&stats[0])
    } else {
        serde_json::to_string_pretty(stats)
    }
    .map_err(|e| Error::io("--stats-json", e.to_string()))?;
    file.file()
        .write_all(json.as_bytes())
        .and_then(|_| file.file().write_all(b"\n"))
        .map_err(|e| Error::io_from("--stats-json", e.to_string(), &e))?;
    Ok(file)
}

/// `p3dp check`: runs every check and prints the findings; writes nothing.
pub fn check(c: &Common) -> Vec<Error> {
    let jobs = match c.jobs() {
        Ok(j) => j,
        Err(e) => return vec![e],
    };
    let (workers, threads) = c.budget(jobs.len());
    let opts = |job: &Job| Options {
        sets: job.sets.clone(),
        printer: c.printer.clone(),
        allow: c.allow.clone(),
        threads,
    };
    let results = batch::run_parallel(
        jobs.len(),
        workers,
        |k| plan(&jobs[k].recipe, &opts(&jobs[k])),
        || {},
    );
    let mut errors = Vec::new();
    for (job, r) in jobs.iter().zip(results) {
        match r {
            Ok(p) => {
                crate::sayln!(
                    "{}: {}",
                    job_label(job),
                    crate::analyse::check::summary(&p.findings)
                );
                for f in &p.findings {
                    crate::sayln!("  {} [{}]: {}", f.severity.word(), f.code, f.message);
                }
                let failing = p.failing(c.strict).len();
                if failing > 0 {
                    errors.push(Error::check(
                        &p.path,
                        format!("{failing} check{} failed", plural(failing)),
                    ));
                }
            }
            Err(e) => errors.push(e),
        }
    }
    errors
}

/// Builds a job on `threads` into nothing but its hash and line fingerprint.
/// The fingerprints of `jobs`, built in parallel within `-j`'s budget.
fn fingerprints(c: &Common, jobs: &[Job]) -> Vec<Result<(String, LineHashes)>> {
    let (workers, threads) = c.budget(jobs.len());
    batch::run_parallel(
        jobs.len(),
        workers,
        |k| fingerprint(c, &jobs[k], threads),
        || {},
    )
}

fn fingerprint(c: &Common, job: &Job, threads: Threads) -> Result<(String, LineHashes)> {
    // nothing is written: the G-code is hashed while the checks run
    let mut p = c.prepared(job, threads)?;
    let stop = (!c.force).then_some(c.strict);
    let written = p.check_and_write_until(&c.allow, stop, HashWriter::new(LineHashes::default()));
    c.refuse_failing(&p)?;
    let (hw, _) = written?;
    let (digest, _, lines) = hw.finish_into();
    Ok((digest, lines))
}

/// `p3dp hash`: prints `SHA256  RECIPE`, the hash of exactly what `build` writes;
/// with `--lock` writes a lock file, with `--check` verifies one.
pub fn hash(a: &HashArgs) -> Vec<Error> {
    if let Some(lockfile) = &a.check {
        return check_lock(a, lockfile);
    }
    let c = &a.common;
    let jobs = match c.jobs() {
        Ok(j) => j,
        Err(e) => return vec![e],
    };
    if let Some(lockfile) = &a.lock {
        let outs = [("--lock".to_string(), lockfile.clone())];
        if let Err(e) = non_empty("--lock", Some(lockfile))
            .and_then(|_| crate::output::file::check_distinct(&outs, &inputs(c)))
        {
            return vec![e];
        }
    }
    let results = fingerprints(c, &jobs);
    let mut errors = Vec::new();
    let mut entries = Vec::new();
    for (job, r) in jobs.iter().zip(results) {
        match r {
            Ok((digest, lines)) => {
                let mut line = format!("{digest}  {}", job.recipe.display());
                if !job.sweep.is_empty() {
                    let v: Vec<String> =
                        job.sweep.iter().map(|(n, v)| format!("{n}={v}")).collect();
                    line.push_str(&format!("  {}", v.join(" ")));
                }
                crate::sayln!("{line}");
                if let Some(lockfile) = &a.lock {
                    let printer = c.printer.as_deref();
                    entries.push(lock_entry(lockfile, job, printer, digest, &lines));
                }
            }
            Err(e) => errors.push(e),
        }
    }
    if let Some(lockfile) = &a.lock {
        if !errors.is_empty() {
            errors.push(Error::check(
                lockfile.display().to_string(),
                "not written: some recipes failed to build",
            ));
            return errors;
        }
        let lock = Lock {
            p3dp_lock: 1,
            entries,
        };
        let text = format!(
            "# p3dp lock file: each recipe's G-code hash. Verify with: p3dp hash --check {}\n# An intended change of output is a commit that updates this file and says why.\n{}",
            lockfile.display(),
            serde_yaml::to_string(&lock).expect("a lock serialises")
        );
        if let Err(e) = write_atomic(lockfile, |f| {
            f.write_all(text.as_bytes())
                .map_err(|e| Error::io_from(lockfile.display().to_string(), e.to_string(), &e))
        }) {
            errors.push(e);
        }
    }
    errors
}

/// The path of `file` relative to the lock file's folder, `/`-separated
/// (with `..` where the file lies outside that folder), so the lock and its
/// recipes can move together.
fn relative_to_lock(lockfile: &Path, file: &Path) -> String {
    use std::path::Component;
    let base = lockfile
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let words = |p: &Path| -> Vec<String> {
        p.components()
            .filter(|c| !matches!(c, Component::RootDir | Component::CurDir))
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect()
    };
    let (b, f) = match (base.canonicalize(), file.canonicalize()) {
        (Ok(b), Ok(f)) => (words(&b), words(&f)),
        _ => return words(file).join("/"),
    };
    let common = b.iter().zip(&f).take_while(|(x, y)| x == y).count();
    let mut rel = vec!["..".to_string(); b.len() - common];
    rel.extend(f[common..].iter().cloned());
    rel.join("/")
}

fn lock_entry(
    lockfile: &Path,
    job: &Job,
    printer: Option<&str>,
    digest: String,
    lines: &LineHashes,
) -> Entry {
    let b = LineHashes::block_lines(lines.count());
    Entry {
        recipe: relative_to_lock(lockfile, &job.recipe),
        set: job.sets.iter().map(|(n, v)| format!("{n}={v}")).collect(),
        printer: printer.map(|p| {
            if crate::machine::Printer::built_in(p).is_some() {
                p.to_string()
            } else {
                relative_to_lock(lockfile, Path::new(p))
            }
        }),
        sha256: digest,
        lines: lines.count(),
        block_lines: b,
        blocks: lines.blocks(b).join(" "),
    }
}

fn check_lock(a: &HashArgs, lockfile: &Path) -> Vec<Error> {
    let shown = lockfile.display().to_string();
    let lock: Lock = match crate::base::input::read_text(lockfile, "lock file")
        .and_then(|t| parse_yaml::<Lock>(&t, &shown))
        .and_then(|l| l.validate().map(|_| l).map_err(|e| e.in_file(&shown)))
    {
        Ok(l) => l,
        Err(e) => return vec![e],
    };
    let base = lockfile.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut jobs = Vec::new();
    for (k, e) in lock.entries.iter().enumerate() {
        // a missing recipe or printer is the lock's mistake: name its entry
        let recipe = base.join(&e.recipe);
        if !recipe.exists() {
            return vec![Error::input(
                format!("entries[{k}].recipe"),
                format!(
                    "no recipe file at `{}` ({}); expected a path relative to the lock file",
                    e.recipe,
                    recipe.display()
                ),
            )
            .in_file(&shown)];
        }
        if let Some(p) = &e.printer {
            if crate::machine::Printer::built_in(p).is_none() && !base.join(p).exists() {
                return vec![Error::input(
                    format!("entries[{k}].printer"),
                    format!(
                        "`{p}` is neither a built-in printer ({}) nor a profile file relative to the lock file",
                        crate::recipe::profile::built_in_names().join(", ")
                    ),
                )
                .in_file(&shown)];
            }
        }
        let sets: Result<Vec<(String, String)>> = e.set.iter().map(|s| parse_set(s)).collect();
        match sets {
            Ok(sets) => jobs.push(Job {
                recipe: base.join(&e.recipe),
                sets,
                sweep: Vec::new(),
                printer: e.printer.as_ref().map(|p| {
                    if crate::machine::Printer::built_in(p).is_some() {
                        p.clone()
                    } else {
                        base.join(p).to_string_lossy().into_owned()
                    }
                }),
            }),
            Err(err) => return vec![err.under(&format!("entries[{k}].set")).in_file(&shown)],
        }
    }
    let c = &a.common;
    let results = fingerprints(c, &jobs);
    // the changed entries are rebuilt one at a time, each with the whole budget
    let (_, threads) = c.budget(1);
    let mut errors = Vec::new();
    for ((entry, job), r) in lock.entries.iter().zip(&jobs).zip(results) {
        let mut label = entry.recipe.clone();
        if !entry.set.is_empty() {
            label.push_str(&format!(" [{}]", entry.set.join(" ")));
        }
        if let Some(p) = &entry.printer {
            label.push_str(&format!(" (printer {p})"));
        }
        match r {
            Ok((digest, _)) if digest == entry.sha256 => crate::sayln!("ok       {label}"),
            Ok((digest, lines)) => {
                let new = lines.blocks(entry.block_lines);
                let place = match lock::first_difference(&entry.blocks, &new) {
                    Some(k) => {
                        let first = k as u64 * entry.block_lines;
                        let block = new_lines(c, job, first, entry.block_lines, threads);
                        let text = block.first().map_or("(end of file)", String::as_str);
                        if entry.block_lines == 1 {
                            format!("first differing line {}: `{text}`", first + 1)
                        } else {
                            changed_block(first, entry.block_lines, &block)
                        }
                    }
                    None => "the lines hash alike block by block (a hash collision?)".into(),
                };
                crate::sayln!("CHANGED  {label}");
                errors.push(Error::check(
                    &entry.recipe,
                    format!(
                        "G-code changed: sha256 was {}, now {digest}; {place}",
                        &entry.sha256[..12]
                    ),
                ));
            }
            Err(e) => errors.push(e),
        }
    }
    errors
}

/// Lines `k..k + n` (0-based) of the job's G-code, rebuilt on `threads`.
fn new_lines(c: &Common, job: &Job, k: u64, n: u64, threads: Threads) -> Vec<String> {
    let Some(text) = c
        .checked_plan(job, threads)
        .ok()
        .and_then(|p| p.write_gcode(Vec::new()).ok())
        .and_then(|(buf, _)| String::from_utf8(buf).ok())
    else {
        return Vec::new();
    };
    text.lines()
        .skip(k as usize)
        .take(n as usize)
        .map(str::to_string)
        .collect()
}

/// Where a block of `n` lines from line `first` (0-based) changed: the lock
/// keeps one hash per block, so the changed line is one of them; a short
/// block is quoted whole, a long one by its first and last lines and the
/// `; param` comments between them (where a changed param shows).
fn changed_block(first: u64, n: u64, block: &[String]) -> String {
    let range = format!("lines {}–{}", first + 1, first + n);
    if block.is_empty() {
        return format!("first difference in {range}, now past the end of the file");
    }
    let quote = |k: usize| format!("{}: `{}`", first + 1 + k as u64, block[k]);
    let picked: Vec<String> = if block.len() <= 4 {
        (0..block.len()).map(quote).collect()
    } else {
        let last = block.len() - 1;
        let mut v = vec![quote(0)];
        v.extend(
            (1..last)
                .filter(|&k| block[k].starts_with("; param "))
                .map(quote),
        );
        v.extend(["…".to_string(), quote(last)]);
        v
    };
    format!(
        "first difference in {range} (the lock keeps one hash per {n} lines, so it cannot tell which of them changed); they now read {}",
        picked.join(", ")
    )
}

/// Flags of `preview`.
#[derive(Args, Clone, Debug, Default)]
pub struct PreviewArgs {
    /// Recipe file (YAML).
    #[arg(value_name = "RECIPE")]
    pub recipe: PathBuf,
    /// Override a param: NAME=VALUE (VALUE may be an expression); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    /// Use this printer (built-in name or YAML file) instead of the recipe's.
    #[arg(long, value_name = "NAME|FILE")]
    pub printer: Option<String>,
    /// Output: FILE.png or FILE.html (default ./NAME.png).
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Where to look from: iso, top, front or side (the viewer starts there).
    #[arg(long, value_name = "VIEW")]
    pub view: Option<String>,
    /// Colour by speed, cross-section, flow, order, findings or plain.
    #[arg(long, value_name = "MODE")]
    pub color: Option<String>,
    /// Image size WIDTHxHEIGHT in pixels (PNG; default 1200x900).
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,
    /// The model alone: no name, stats or legend (PNG).
    #[arg(long)]
    pub bare: bool,
    /// Silence a check for this build: its code, e.g. `bridge`; repeatable.
    #[arg(long = "allow", value_name = "CODE")]
    pub allow: Vec<String>,
    /// At most N threads for the build and the drawing (default: one per core); the file is the same on any number.
    #[arg(short = 'j', long = "jobs", value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub jobs: Option<u16>,
}

/// `p3dp preview`: draws the toolpath to a PNG image or an HTML viewer; a
/// recipe that fails its checks is drawn too (`--color findings` shows where).
pub fn preview(a: &PreviewArgs) -> Vec<Error> {
    let run = || -> Result<()> {
        use crate::output::preview::{ColorMode, Options as PreviewOptions, Size, View};
        let threads = a
            .jobs
            .map_or_else(Threads::available, |n| Threads::new(usize::from(n)));
        let opts = PreviewOptions {
            view: a
                .view
                .as_deref()
                .map(View::parse)
                .transpose()?
                .unwrap_or_default(),
            color: a
                .color
                .as_deref()
                .map(ColorMode::parse)
                .transpose()?
                .unwrap_or_default(),
            size: a
                .size
                .as_deref()
                .map(|s| Size::parse(s, "--size"))
                .transpose()?
                .unwrap_or_default(),
            bare: a.bare,
        };
        let sets: Vec<(String, String)> =
            a.sets.iter().map(|s| parse_set(s)).collect::<Result<_>>()?;
        let out = match &a.output {
            Some(o) => o.clone(),
            None => PathBuf::from(format!("{}.png", file_stem(&recipe_name(&a.recipe)?))),
        };
        crate::output::preview::Format::of(&out)?;
        non_empty("-o", Some(&out))?;
        let ins = inputs_of(std::slice::from_ref(&a.recipe), a.printer.as_deref());
        crate::output::file::check_distinct(&[("-o".to_string(), out.clone())], &ins)?;
        let p = plan(
            &a.recipe,
            &Options {
                sets,
                printer: a.printer.clone(),
                allow: a.allow.clone(),
                threads,
            },
        )?;
        make_parent(&out)?;
        crate::sayln!(
            "{}",
            crate::output::preview::write(&p, &out, &opts, &|w| p.render_unhashed(w))?
        );
        Ok(())
    };
    match run() {
        Ok(()) => Vec::new(),
        Err(e) => vec![e],
    }
}

/// Flags of `mesh`.
#[derive(Args, Clone, Debug, Default)]
pub struct MeshArgs {
    /// Recipe file (YAML).
    #[arg(value_name = "RECIPE")]
    pub recipe: PathBuf,
    /// Override a param: NAME=VALUE (VALUE may be an expression); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    /// Use this printer (built-in name or YAML file) instead of the recipe's.
    #[arg(long, value_name = "NAME|FILE")]
    pub printer: Option<String>,
    /// Output: FILE.stl (binary), FILE.3mf (with the filament colour) or FILE.obj (default ./NAME.stl).
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Silence a check for this build: its code, e.g. `bridge`; repeatable.
    #[arg(long = "allow", value_name = "CODE")]
    pub allow: Vec<String>,
}

/// `p3dp mesh`: writes the toolpath as solid beads (see [`crate::output::mesh`]); as
/// with `preview`, a recipe that fails its checks is meshed too.
pub fn mesh(a: &MeshArgs) -> Vec<Error> {
    let run = || -> Result<()> {
        let sets: Vec<(String, String)> =
            a.sets.iter().map(|s| parse_set(s)).collect::<Result<_>>()?;
        let out = match &a.output {
            Some(o) => o.clone(),
            None => PathBuf::from(format!("{}.stl", file_stem(&recipe_name(&a.recipe)?))),
        };
        non_empty("-o", Some(&out))?;
        crate::output::mesh::write::Format::of(&out)?;
        let ins = inputs_of(std::slice::from_ref(&a.recipe), a.printer.as_deref());
        crate::output::file::check_distinct(&[("-o".to_string(), out.clone())], &ins)?;
        let p = plan(
            &a.recipe,
            &Options {
                sets,
                printer: a.printer.clone(),
                allow: a.allow.clone(),
                threads: Threads::available(),
            },
        )?;
        make_parent(&out)?;
        crate::sayln!("{}", crate::output::mesh::write::write(&p, &out)?);
        Ok(())
    };
    match run() {
        Ok(()) => Vec::new(),
        Err(e) => vec![e],
    }
}

/// Flags of `watch`.
#[derive(Args, Clone, Debug, Default)]
pub struct WatchArgs {
    /// Recipe file (YAML).
    #[arg(value_name = "RECIPE")]
    pub recipe: PathBuf,
    /// Override a param: NAME=VALUE (VALUE may be an expression); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    /// Use this printer (built-in name or YAML file) instead of the recipe's.
    #[arg(long, value_name = "NAME|FILE")]
    pub printer: Option<String>,
    /// Silence a check for this build: its code, e.g. `bridge`; repeatable.
    #[arg(long = "allow", value_name = "CODE")]
    pub allow: Vec<String>,
    /// At most N threads for each build (default: one per core).
    #[arg(short = 'j', long = "jobs", value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub jobs: Option<u16>,
    /// The port on 127.0.0.1 (loopback only) to serve on; 0 takes any free one.
    #[arg(long, value_name = "N", default_value_t = crate::app::watch::DEFAULT_PORT)]
    pub port: u16,
    /// Open the page in the system's web browser.
    #[arg(long)]
    pub open: bool,
}

/// `p3dp watch`: serves the HTML viewer of a recipe on loopback and rebuilds
/// it on every change of the recipe or a file it reads, until Ctrl-C.
pub fn watch(a: &WatchArgs) -> Result<()> {
    let sets: Vec<(String, String)> = a.sets.iter().map(|s| parse_set(s)).collect::<Result<_>>()?;
    crate::app::watch::run(&crate::app::watch::Options {
        recipe: a.recipe.clone(),
        build: Options {
            sets,
            printer: a.printer.clone(),
            allow: a.allow.clone(),
            threads: a
                .jobs
                .map_or_else(Threads::available, |n| Threads::new(usize::from(n))),
        },
        port: a.port,
        open: a.open,
    })
}

/// `p3dp printers`: one line per built-in profile (name, flavour, bed,
/// origin of recipe (0, 0, 0), nozzle and filament), under a header line.
pub fn printers() -> String {
    use crate::base::format::fmt_num;
    use crate::machine::Printer;
    use crate::recipe::profile::built_in_names;
    let mut out = format!(
        "{:<13} {:<8} {:<26} {:<14} {:<7} {}\n",
        "NAME", "FLAVOUR", "BED", "ORIGIN", "NOZZLE", "FILAMENT"
    );
    for name in built_in_names() {
        let p = Printer::built_in(name).expect("built-in profiles parse");
        let origin = p.origin.map(fmt_num).join(", ");
        out.push_str(&format!(
            "{:<13} {:<8} {:<26} {:<14} {:<7} {}\n",
            name,
            p.flavor.name(),
            p.bed.describe(),
            origin,
            fmt_num(p.nozzle_diameter),
            fmt_num(p.filament_diameter)
        ));
    }
    out.push_str("Use one with --printer NAME, or a YAML file (--printer FILE; `inherits: NAME` starts from a built-in one).\n");
    out
}

/// The starter recipes of `p3dp new --from KIND`: each kind and its text,
/// with `__NAME__` where the recipe's name goes.
pub const STARTERS: &[(&str, &str)] = &[
    ("sphere", include_str!("starters/sphere.yaml")),
    ("globe", include_str!("starters/globe.yaml")),
    ("plate", include_str!("starters/plate.yaml")),
    ("turtle", include_str!("starters/turtle.yaml")),
    ("solid", include_str!("starters/solid.yaml")),
];

/// The text of starter `from` for a recipe called `name`, built from `file`.
pub fn starter_text(name: &str, from: &str, file: &str) -> Result<String> {
    let text = STARTERS
        .iter()
        .find(|(k, _)| *k == from)
        .map(|(_, t)| *t)
        .ok_or_else(|| {
            let kinds: Vec<&str> = STARTERS.iter().map(|(k, _)| *k).collect();
            Error::input(
                format!("--from {from}"),
                format!("no starter `{from}`; expected one of {}", kinds.join(", ")),
            )
        })?;
    let plain = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c));
    let yaml_name = if plain {
        name.to_string()
    } else {
        serde_json::to_string(name).expect("a string serialises")
    };
    Ok(text
        .replace("__NAME__.yaml", file)
        .replace("__NAME__.gcode", &format!("{}.gcode", file_stem(name)))
        .replace("name: __NAME__", &format!("name: {yaml_name}"))
        .replace("__NAME__", name))
}

/// `p3dp new NAME [--from KIND]`: writes the starter recipe `NAME.yaml` (or
/// NAME itself when it ends in `.yaml`/`.yml`), never over an existing file;
/// returns the line to print.
pub fn new_recipe(name: &str, from: &str) -> Result<String> {
    let path = if name.ends_with(".yaml") || name.ends_with(".yml") {
        PathBuf::from(name)
    } else {
        PathBuf::from(format!("{name}.yaml"))
    };
    let shown = path.display().to_string();
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.trim().is_empty())
        .ok_or_else(|| Error::input(format!("new {name}"), "expected a recipe name"))?;
    let text = starter_text(&stem, from, &shown)?;
    make_parent(&path)?;
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&path)
        .map_err(|e| {
            let why = if e.kind() == std::io::ErrorKind::AlreadyExists {
                "already exists; not overwritten (choose another name or remove it)".to_string()
            } else {
                format!("cannot create the recipe: {e}")
            };
            Error::io_from(&shown, why, &e)
        })?;
    file.write_all(text.as_bytes())
        .map_err(|e| Error::io_from(&shown, format!("cannot write the recipe: {e}"), &e))?;
    Ok(format!(
        "wrote {shown} (a {from} to start from); build it with: p3dp build {shown}"
    ))
}

/// An error as the binary prints it: `error: FILE:LINE:COL: PATH: message`,
/// then (see [`crate::app::diagnostic`]) the source line underlined at the place
/// and a `help:` line when one is known; coloured only on a terminal without
/// `NO_COLOR`.
pub fn render_error(e: &Error) -> String {
    crate::app::diagnostic::render(e, crate::app::diagnostic::stderr_color())
}
