//! The commands, one file each, from their plain options (the command line
//! makes them: [`crate::app::cli`]) to what they print and write; each
//! returns the errors it met, one per failed job.

pub(crate) mod build;
pub(crate) mod calibrate;
pub(crate) mod check;
pub(crate) mod explain;
pub(crate) mod hash;
pub(crate) mod mesh;
pub(crate) mod new;
pub(crate) mod plate;
pub(crate) mod preview;
pub(crate) mod printers;
pub(crate) mod send;

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::analyse::plan::Plan;
use crate::app::batch::{self, Job};
use crate::app::pipeline;
use crate::app::prepare::{prepare_in, Options};
use crate::base::error::{Error, Result};
use crate::base::input::Reads;
use crate::output::file::AtomicFile;
use crate::recipe::context::Context;
use crate::recipe::{parse_yaml, RawRecipe};

/// What the builds of a command take from the command line: the recipes,
/// each built once per combination of the sweeps' values.
#[derive(Clone, Debug, Default)]
pub(crate) struct Builds {
    /// Recipe files.
    pub(crate) recipes: Vec<PathBuf>,
    /// `--set NAME=VALUE`, in order.
    pub(crate) sets: Vec<(String, String)>,
    /// `--sweep NAME=VALUES`: each name and its values.
    pub(crate) sweeps: Vec<(String, Vec<String>)>,
    /// `--printer NAME|FILE`.
    pub(crate) printer: Option<String>,
    /// `--filament FILE [--filament-preset NAME]`.
    pub(crate) filament: Option<crate::recipe::preset::Source>,
    /// `--allow CODE`.
    pub(crate) allow: Vec<String>,
    /// `--allow-read DIR`.
    pub(crate) allow_read: Vec<PathBuf>,
    /// `--strict`: warnings fail the build too.
    pub(crate) strict: bool,
    /// `--force`: write even when checks fail.
    pub(crate) force: bool,
    /// `p3dp plate`: the plate the command line describes, built as the one
    /// job (its recipes and sweeps are its entries', not `recipes`).
    pub(crate) plate: Option<std::sync::Arc<crate::recipe::resolve::plate::PlateSpec>>,
}

impl Builds {
    /// The jobs: every recipe with every combination of the sweeps.
    pub(crate) fn jobs(&self) -> Result<Vec<Job>> {
        if let Some(spec) = &self.plate {
            return Ok(vec![Job {
                recipe: PathBuf::from(&spec.name),
                sets: self.sets.clone(),
                sweep: Vec::new(),
                printer: None,
            }]);
        }
        if self.recipes.is_empty() {
            return Err(Error::input(
                "",
                "no recipe given; expected one or more RECIPE files",
            ));
        }
        batch::check_count(self.recipes.len(), &self.sweeps)?;
        let mut jobs = batch::expand(&self.recipes, &self.sets, &self.sweeps);
        // a variant is named (file, summary) by the values its sweep gives
        // the params, not the text: `amplitude=1 + cycles/2` is 2.5 there;
        // a recipe that cannot be read keeps the text, its build says why
        // (each recipe read once, however many variants it has)
        let mut libraries = std::collections::HashMap::new();
        for job in jobs.iter_mut().filter(|j| !j.sweep.is_empty()) {
            let library = libraries
                .entry(job.recipe.clone())
                .or_insert_with(|| crate::recipe::expand::param_library(&job.recipe).ok());
            let params = library.as_ref().map(|l| l.eval_params(&job.sets));
            if let Some(Ok(params)) = params {
                for (name, value) in &mut job.sweep {
                    if let Some(shown) = params.show(name) {
                        *value = shown;
                    }
                }
            }
        }
        Ok(jobs)
    }

    /// Plans a job and refuses it when its checks fail (unless forced).
    pub(crate) fn checked_plan(&self, job: &Job) -> Result<Plan> {
        let mut p = self.prepared(job, &[])?;
        pipeline::check(&mut p, &self.allow);
        self.refuse_failing(&p)?;
        Ok(p)
    }

    /// Plans a job without checking it yet, and refuses it when one of
    /// `outputs` (the files the command writes) is a file the load read (or
    /// tried): an include, a profile or its parent, an image, an SVG… — all
    /// of them, whether the load succeeded or not, before anything is written.
    pub(crate) fn prepared(&self, job: &Job, outputs: &[(String, PathBuf)]) -> Result<Plan> {
        let (plan, reads) = self.load(job);
        check_reads(outputs, &reads)?;
        plan
    }

    /// What loading `job` takes from the command line.
    fn options(&self, job: &Job) -> Options {
        Options {
            sets: job.sets.clone(),
            printer: self.printer.clone().or_else(|| job.printer.clone()),
            filament: self.filament.clone(),
            allow: self.allow.clone(),
            allow_read: self.allow_read.clone(),
        }
    }

    /// Refuses a sweep one of whose variants cannot be resolved (a value
    /// that is no value, or that makes the recipe invalid), before any
    /// variant is built: every variant resolved side by side, the errors
    /// named by their `--sweep` value, each once ([`batch::unresolved`]).
    /// Nothing to do without a sweep (one build says its own errors).
    pub(crate) fn refuse_unresolved(&self, jobs: &[Job]) -> Vec<Error> {
        if jobs.iter().all(|j| j.sweep.is_empty()) {
            return Vec::new();
        }
        let results = batch::run_parallel(
            jobs.len(),
            |k| {
                let cx = Context::default();
                crate::app::prepare::resolve_in(&jobs[k].recipe, &self.options(&jobs[k]), &cx)
            },
            || {},
        );
        batch::unresolved(jobs, results, crate::app::diagnostic::check_help)
    }

    /// Plans a job (unchecked), with the files its load read or tried.
    pub(crate) fn load(&self, job: &Job) -> (Result<Plan>, Reads) {
        let opts = self.options(job);
        let cx = Context::default();
        let plan = match &self.plate {
            Some(spec) => crate::app::prepare::prepare_plate_in(spec, &spec.name, &opts, &cx),
            None => prepare_in(&job.recipe, &opts, &cx),
        };
        (plan, cx.reads)
    }

    /// A plan of the one recipe, checked; drawn or meshed whatever its
    /// findings; refused when one of `outputs` is a file it read.
    pub(crate) fn plan_one(&self, outputs: &[(String, PathBuf)]) -> Result<Plan> {
        let jobs = self.jobs()?;
        let mut p = self.prepared(&jobs[0], outputs)?;
        pipeline::check(&mut p, &self.allow);
        Ok(p)
    }

    /// The files a command reads: its recipes (a plate's entries) and a
    /// `--printer` file.
    pub(crate) fn inputs(&self) -> Vec<(String, PathBuf)> {
        match &self.plate {
            Some(spec) => {
                let recipes: Vec<PathBuf> = spec
                    .entries
                    .iter()
                    .map(|e| spec.dir.join(&e.recipe))
                    .collect();
                inputs_of(&recipes, self.printer.as_deref())
            }
            None => inputs_of(&self.recipes, self.printer.as_deref()),
        }
    }

    /// The name of `job`'s recipe (a plate's own), read without building it.
    pub(crate) fn name_of(&self, job: &Job) -> Result<String> {
        match &self.plate {
            Some(spec) => Ok(spec.name.clone()),
            None => recipe_name(&job.recipe),
        }
    }

    /// A checked, hashed build as these options say: the codes allowed,
    /// and the writing given up as soon as the checks fail (unless forced),
    /// stamped `stamp`.
    pub(crate) fn job(
        &self,
        stamp: crate::output::gcode::metadata::Options,
    ) -> crate::app::pipeline::Job<'_> {
        use crate::app::pipeline::{Job, Stop};
        let stop = if self.force {
            Stop::Never
        } else {
            Stop::Failing {
                strict: self.strict,
            }
        };
        Job {
            check: Some((&self.allow, stop)),
            stamp,
            hash: true,
            draft: false,
        }
    }

    /// The error of a checked plan whose checks fail (unless forced).
    pub(crate) fn refuse_failing(&self, p: &Plan) -> Result<()> {
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

pub(crate) fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// A file name made of the recipe name: letters, digits, `.`, `_` and `-`.
pub(crate) fn file_stem(name: &str) -> String {
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
pub(crate) fn variant_stem(name: &str, sweep: &[(String, String)]) -> String {
    let mut s = file_stem(name);
    for (n, v) in sweep {
        s.push_str(&format!("_{}-{}", file_stem(n), file_stem(v)));
    }
    s
}

pub(crate) fn job_label(job: &Job) -> String {
    let mut s = job.recipe.display().to_string();
    if !job.sweep.is_empty() {
        let v: Vec<String> = job.sweep.iter().map(|(n, v)| format!("{n}={v}")).collect();
        s.push_str(&format!(" [{}]", v.join(" ")));
    }
    s
}

/// The recipe's name, read without building it.
pub(crate) fn recipe_name(path: &Path) -> Result<String> {
    let shown = path.display().to_string();
    let text = crate::base::input::read_text(path, "recipe")?;
    Ok(parse_yaml::<RawRecipe>(&text, &shown)?.name)
}

/// Makes the folder `file` goes in, if missing.
pub(crate) fn make_parent(file: &Path) -> Result<()> {
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
pub(crate) fn non_empty(option: &str, value: Option<&Path>) -> Result<()> {
    match value {
        Some(v) if v.as_os_str().is_empty() => Err(Error::input(
            option,
            "an empty file name; expected the name of a file to write",
        )),
        _ => Ok(()),
    }
}

/// The files read by a command of these `recipes` and `--printer` (a file
/// unless it names a built-in profile).
/// Refuses `outputs` that would replace a file of `reads` (those that exist).
pub(crate) fn check_reads(outputs: &[(String, PathBuf)], reads: &Reads) -> Result<()> {
    if outputs.is_empty() {
        return Ok(());
    }
    let read: Vec<(String, PathBuf)> = reads
        .files()
        .into_iter()
        .filter(|f| f.exists())
        .map(|f| ("the file read".to_string(), f))
        .collect();
    crate::output::file::check_distinct(outputs, &read).map_err(|e| Error {
        message: format!("{} (nothing written)", e.message),
        ..e
    })
}

pub(crate) fn inputs_of(recipes: &[PathBuf], printer: Option<&str>) -> Vec<(String, PathBuf)> {
    let mut v: Vec<(String, PathBuf)> = recipes
        .iter()
        .map(|r| ("the recipe".to_string(), r.clone()))
        .collect();
    if let Some(p) = printer {
        if crate::recipe::profile::built_in(p).is_none() {
            v.push(("the --printer profile".to_string(), PathBuf::from(p)));
        }
    }
    v
}

/// A file's bytes into an uncommitted [`AtomicFile`] (its folder made first).
pub(crate) fn stage(file: &Path, bytes: &[u8]) -> Result<AtomicFile> {
    make_parent(file)?;
    let mut f = AtomicFile::create(file)?;
    f.file().write_all(bytes).map_err(|e| {
        Error::io_from(file.display().to_string(), format!("cannot write: {e}"), &e)
    })?;
    Ok(f)
}

/// How a build's G-code is stamped (`build` and `hash` alike): its date is `SOURCE_DATE_EPOCH`'s
/// when the environment has one (seconds since 1970, the reproducible-builds
/// convention), else the epoch's.
pub(crate) fn stamp() -> Result<crate::output::gcode::metadata::Options> {
    let date = match std::env::var("SOURCE_DATE_EPOCH") {
        Ok(v) => Some(v.trim().parse::<i64>().map_err(|_| {
            Error::input(
                "SOURCE_DATE_EPOCH",
                format!("`{v}` is not a date; expected whole seconds since 1970-01-01 UTC, e.g. $(date +%s)"),
            )
        })?),
        Err(_) => None,
    };
    Ok(crate::output::gcode::metadata::Options { date, bambu: false })
}

/// Bytes to standard output, as they are (a closed pipe ends quietly).
pub(crate) fn print(bytes: &[u8]) {
    let _ = crate::output::file::Stdout.write_all(bytes);
}

/// `p3dp schema`: the JSON Schema of the recipe format.
pub(crate) fn schema() {
    let s = crate::recipe::schema::json_schema();
    crate::sayln!(
        "{}",
        serde_json::to_string_pretty(&s).expect("a schema serialises")
    );
}
