//! `p3dp build`: G-code and a report per job, with the extra outputs a
//! build may write (stats, preview, pattern, z-buffer); a sweep's summary.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use super::{job_label, make_parent, non_empty, stage, variant_stem, Builds};
use crate::analyse::plan::Plan;
use crate::analyse::stats::Stats;
use crate::app::batch::{self, Job};
use crate::app::pipeline;
use crate::base::error::{Error, Result};
use crate::base::format::hms;
use crate::generate::model::pattern_png;
use crate::output::file::{write_atomic, AtomicFile};
use crate::output::gcode::metadata::Options as Stamp;
use crate::output::host::Package;

/// What `build` takes from the command line.
#[derive(Clone, Debug, Default)]
pub(crate) struct Options {
    /// The recipes and how each is built.
    pub(crate) builds: Builds,
    /// `-o`: a file; a folder with several recipes; `-` for standard output.
    pub(crate) output: Option<String>,
    /// `--stats-json FILE`.
    pub(crate) stats_json: Option<PathBuf>,
    /// `--pattern FILE`.
    pub(crate) pattern: Option<PathBuf>,
    /// `--preview FILE`.
    pub(crate) preview: Option<PathBuf>,
    /// `--zbuffer FILE`.
    pub(crate) zbuffer: Option<PathBuf>,
    /// `--zbuffer-svg FILE`.
    pub(crate) zbuffer_svg: Option<PathBuf>,
    /// `--zbuffer-layer N`.
    pub(crate) zbuffer_layer: Option<u64>,
    /// The name the report, the stats and the messages after loading give
    /// the recipe instead of its path (`calibration test temperature`: the
    /// recipe `p3dp calibrate` staged, a file the user never wrote).
    pub(crate) shown: Option<String>,
}

#[derive(Clone, Debug)]
enum Target {
    Stdout,
    /// A file, and whether its name is the default one (`NAME.gcode`, which
    /// a profile's `binary_gcode` makes `NAME.bgcode`).
    File(PathBuf, bool),
}

/// Where each job writes, and the folder of a batch (for summary.csv).
fn targets(a: &Options, jobs: &[Job]) -> Result<(Vec<Result<Target>>, PathBuf)> {
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
        Some(o) => {
            let t = Target::File(PathBuf::from(o), false);
            return Ok((vec![Ok(t)], PathBuf::from(".")));
        }
        None => PathBuf::from("."),
    };
    let mut out: Vec<Result<Target>> = Vec::with_capacity(jobs.len());
    let mut seen: Vec<(PathBuf, String)> = Vec::new();
    // a recipe's name is read once, however many variants it sweeps
    let mut names: std::collections::HashMap<&Path, Result<String>> = Default::default();
    for job in jobs {
        let name = names
            .entry(job.recipe.as_path())
            .or_insert_with(|| a.builds.name_of(job))
            .clone();
        let t = name.map(|name| {
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
        out.push(t.map(|f| Target::File(f, true)));
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

/// What one job of `build` made: its report and its files, not yet committed
/// when the build is a single job (all its outputs are committed together).
struct Done {
    built: (Stats, String, bool),
    files: Vec<AtomicFile>,
    lines: Vec<String>,
}

/// What `build` settles before any job runs: the jobs, where each writes,
/// the batch folder and the stats file opened early.
struct Prepared {
    jobs: Vec<Job>,
    /// Every file the command writes, with its option.
    outputs: Vec<(String, PathBuf)>,
    targets: Vec<Result<Target>>,
    dir: PathBuf,
    stats_file: Option<AtomicFile>,
}

/// Expands the jobs and refuses flag combinations, and a sweep with a
/// variant that cannot be resolved, before anything is built.
fn prepare(a: &Options) -> std::result::Result<Prepared, Vec<Error>> {
    let jobs = a.builds.jobs().map_err(|e| vec![e])?;
    refuse_flags(a, jobs.len()).map_err(|e| vec![e])?;
    let unresolved = a.builds.refuse_unresolved(&jobs);
    if !unresolved.is_empty() {
        return Err(unresolved);
    }
    settle(a, jobs).map_err(|e| vec![e])
}

/// Where each job writes, its outputs checked against each other and the
/// inputs, the stats file opened early.
fn settle(a: &Options, jobs: Vec<Job>) -> Result<Prepared> {
    let (targets, dir) = targets(a, &jobs)?;
    // no output over another, nor over an input: refused before any is
    // written (and each job's own reads before it writes: `build_job`)
    let outputs = outputs(a, &targets, &dir);
    crate::output::file::check_distinct(&outputs, &a.builds.inputs())?;
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
        outputs,
        targets,
        dir,
        stats_file,
    })
}

/// Refuses empty file names, and the outputs of one build asked of `jobs`
/// builds, or asked wrongly.
fn refuse_flags(a: &Options, jobs: usize) -> Result<()> {
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
    let one = |option: &str, given: bool, what: &str| {
        if given && jobs > 1 {
            return Err(Error::input(option, what.to_string()));
        }
        Ok(())
    };
    let zbuffer = "writes the z-buffer of one build; expected one recipe and no --sweep";
    one("--zbuffer", a.zbuffer.is_some(), zbuffer)?;
    one("--zbuffer-svg", a.zbuffer_svg.is_some(), zbuffer)?;
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
    one(
        "--pattern",
        a.pattern.is_some(),
        "writes the cell array of one build; expected one recipe and no --sweep",
    )?;
    one(
        "--preview",
        a.preview.is_some(),
        "a preview is of one build; give one recipe (or run `p3dp preview` per recipe)",
    )?;
    if let Some(pv) = &a.preview {
        crate::output::preview::Format::of(pv)?;
    }
    Ok(())
}

/// Every file the build writes, with the option that names it.
fn outputs(a: &Options, targets: &[Result<Target>], dir: &Path) -> Vec<(String, PathBuf)> {
    let mut outs: Vec<(String, PathBuf)> = targets
        .iter()
        .filter_map(|t| match t {
            Ok(Target::File(f, _)) => Some(("-o".to_string(), f.clone())),
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
    if !a.builds.sweeps.is_empty() {
        outs.push((
            "summary.csv of --sweep".to_string(),
            dir.join("summary.csv"),
        ));
    }
    outs
}

/// Builds one job to its target (with its preview and pattern, if asked):
/// the stats, where it went, and whether that was standard output. Sets
/// `clobber` when one of `outputs` is a file the job read.
fn build_job(
    a: &Options,
    job: &Job,
    target: Result<Target>,
    single: bool,
    (outputs, clobber): (&[(String, PathBuf)], &AtomicBool),
) -> Result<Done> {
    let mut target = target?;
    let (p, reads) = a.builds.load(job);
    // an output over a file the job read (or tried) stops the whole command
    if let Err(e) = super::check_reads(outputs, &reads) {
        clobber.store(true, Ordering::Relaxed);
        return Err(e);
    }
    let mut p = p?;
    if let Some(name) = &a.shown {
        p.path.clone_from(name);
    }
    if let Target::File(f, true) = &target {
        if p.recipe.printer.binary_gcode {
            target = Target::File(f.with_extension("bgcode"), true);
        }
    }
    let options = super::stamp()?;
    // the G-code's SHA-256 only where something shows it: the summary of
    // several builds (and a sweep's summary.csv) and `--stats-json`
    let hash = !single || a.stats_json.is_some();
    if let Target::File(f, _) = &target {
        if Package::of(f) != Package::Gcode {
            return build_package(a, p, f, options, single);
        }
    }
    // a file in a folder that exists is written (to its temp file) while the
    // checks run, and committed below only if they pass; anything else waits
    // for the checks, so a failed check still writes nothing
    let mut early = None;
    if let Target::File(f, _) = &target {
        let folder = f.parent().filter(|d| !d.as_os_str().is_empty());
        if folder.is_none_or(|d| d.is_dir()) {
            if let Ok(mut file) = AtomicFile::create(f) {
                let job = pipeline::Job {
                    hash,
                    ..a.builds.job(options)
                };
                let stats = pipeline::write(&mut p, &job, file.streaming()).map(|w| w.stats);
                early = Some((file, stats));
            }
        }
    }
    if early.is_none() {
        pipeline::check(&mut p, &a.builds.allow);
    }
    a.builds.refuse_failing(&p)?;
    // the cell array of --pattern, made before any file is written
    let pattern = match &a.pattern {
        Some(f) => Some((f, pattern_png(&p.recipe).map_err(|e| e.in_file(&p.path))?)),
        None => None,
    };
    let zbuffer = zbuffer_files(a, &p)?;
    let mut files = Vec::new();
    let lines = Vec::new();
    let built = match &target {
        Target::Stdout => pipeline::write(
            &mut p,
            &unchecked(options, hash),
            crate::output::file::Stdout,
        )
        .map(|w| (w.stats, "standard output".to_string(), true)),
        Target::File(f, _) => {
            let (file, stats) = match early {
                Some((file, stats)) => (file, stats?),
                None => {
                    make_parent(f)?;
                    let mut file = AtomicFile::create(f)?;
                    let stats =
                        pipeline::write(&mut p, &unchecked(options, hash), file.streaming())?.stats;
                    (file, stats)
                }
            };
            files.push(file);
            Ok((stats, f.display().to_string(), false))
        }
    }?;
    extras(a, &p, pattern, zbuffer, built, files, lines, single)
}

/// A job that writes the G-code of a plan already checked, hashed when
/// `hash`.
fn unchecked(stamp: Stamp, hash: bool) -> pipeline::Job<'static> {
    pipeline::Job {
        stamp,
        hash,
        ..pipeline::Job::default()
    }
}

/// Builds one job into a printer's package (`.bgcode`, `.gcode.3mf`): the
/// G-code in memory while the checks run, then packed whole into the file,
/// whose SHA-256 and size the stats report.
fn build_package(
    a: &Options,
    mut p: Plan,
    f: &Path,
    mut options: Stamp,
    single: bool,
) -> Result<Done> {
    let package = Package::of(f);
    options.bambu = package == Package::Bambu;
    let job = pipeline::Job {
        hash: false,
        ..a.builds.job(options)
    };
    let written = pipeline::write(&mut p, &job, Vec::new());
    // a package the printer's firmware may not read: a warning, in the
    // report with the checks' findings (silenced as they are)
    if let Some(f) = package.unsuited(&p.recipe.printer) {
        let mut unsuited = vec![f];
        p.silence(&mut unsuited, &a.builds.allow);
        p.findings.extend(unsuited);
    }
    a.builds.refuse_failing(&p)?;
    let w = written?;
    let (gcode, moves) = (w.out, w.moves);
    let images = crate::output::preview::thumbnail::images(&p)?;
    let bytes = match package {
        Package::Bgcode => crate::output::host::bgcode_of(&p, &gcode, &moves, &images)?,
        Package::Bambu => {
            let png = |w: u32| crate::output::preview::thumbnail::png_of(&p, w, w);
            let (top, pick) = crate::output::preview::thumbnail::bed_views_png(&p, 512);
            crate::output::host::threemf_of(&p, &gcode, &moves, [png(512), png(128), top, pick])?
        }
        Package::Gcode => gcode,
    };
    let mut hw = crate::output::file::HashWriter::new(std::io::sink());
    hw.write_all(&bytes)
        .map_err(|e| Error::io_from(f.display().to_string(), e.to_string(), &e))?;
    let (digest, size) = hw.finish();
    let stats = Stats::of(&p, &moves, digest, size);
    let pattern = match &a.pattern {
        Some(pf) => Some((pf, pattern_png(&p.recipe).map_err(|e| e.in_file(&p.path))?)),
        None => None,
    };
    let zbuffer = zbuffer_files(a, &p)?;
    make_parent(f)?;
    let files = vec![stage(f, &bytes)?];
    let built = (stats, f.display().to_string(), false);
    extras(a, &p, pattern, zbuffer, built, files, Vec::new(), single)
}

/// The files a build writes beside its G-code (preview, pattern,
/// z-buffer), staged; committed at once unless the build is `single`.
#[allow(clippy::too_many_arguments)]
fn extras(
    a: &Options,
    p: &Plan,
    pattern: Option<(&PathBuf, Vec<u8>)>,
    zbuffer: Vec<(PathBuf, Vec<u8>)>,
    built: (Stats, String, bool),
    mut files: Vec<AtomicFile>,
    mut lines: Vec<String>,
    single: bool,
) -> Result<Done> {
    if let Some(pv) = &a.preview {
        let (bytes, line) =
            pipeline::preview(p, pv, &crate::output::preview::Options::default())?.bytes();
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
fn zbuffer_files(a: &Options, p: &Plan) -> Result<Vec<(PathBuf, Vec<u8>)>> {
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
        let svg = crate::analyse::stats::zbuffer_svg(&p.recipe, n)
            .map_err(|e| e.under("--zbuffer-svg"))?;
        let Some(svg) = svg else {
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
    a: &Options,
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
pub(crate) fn run(a: &Options) -> Vec<Error> {
    let Prepared {
        jobs,
        outputs,
        targets,
        dir,
        stats_file,
    } = match prepare(a) {
        Ok(p) => p,
        Err(e) => return e,
    };
    let single = jobs.len() == 1;
    let bar = progress(jobs.len());
    let clobber = AtomicBool::new(false);
    let done = batch::run_parallel(
        jobs.len(),
        |k| {
            let guard = (&outputs[..], &clobber);
            build_job(a, &jobs[k], targets[k].clone(), single, guard)
        },
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
    if clobber.load(Ordering::Relaxed) {
        // an output would replace an input: no stats, summary or G-code
        // left pending is written
        return errors;
    }
    let all_stats: Vec<Stats> = results
        .iter()
        .filter_map(|r| r.as_ref().ok().map(|(s, _, _)| s.clone()))
        .collect();
    let (errs, committed) = commit_outputs(a, stats_file, pending, &all_stats);
    errors.extend(errs);
    if committed || !single {
        report_builds(&jobs, &results, &preview_lines);
    }
    if !a.builds.sweeps.is_empty() {
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
