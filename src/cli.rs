//! The commands `build`, `check` and `hash`, as the spec's command-line contract says.
//!
//! Each returns the errors it met (one per failed recipe); the binary prints
//! them and exits with the worst status: 2 unusable input, 1 failed check.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::build::{plan, write_atomic, Options, Plan};
use crate::error::{Error, Result};
use crate::recipe::parse_set;
use crate::stats::Stats;

/// Flags every command shares.
#[derive(Clone, Debug, Default)]
pub struct Common {
    /// Recipe files.
    pub recipes: Vec<PathBuf>,
    /// `--set NAME=VALUE`, as typed.
    pub sets: Vec<String>,
    /// `--printer NAME|FILE`.
    pub printer: Option<String>,
    /// Warnings fail too.
    pub strict: bool,
    /// Write even when checks fail.
    pub force: bool,
}

/// Flags of `build`.
#[derive(Clone, Debug, Default)]
pub struct BuildArgs {
    /// Shared flags.
    pub common: Common,
    /// `-o OUT`: a file, a folder, or `-` for standard output.
    pub output: Option<String>,
    /// `--stats-json FILE`.
    pub stats_json: Option<PathBuf>,
}

impl Common {
    fn options(&self) -> Result<Options> {
        Ok(Options {
            sets: self
                .sets
                .iter()
                .map(|s| parse_set(s))
                .collect::<Result<_>>()?,
            printer: self.printer.clone(),
        })
    }

    /// Plans a recipe and refuses it when its checks fail (unless forced).
    fn checked_plan(&self, path: &Path, opts: &Options) -> Result<Plan> {
        let p = plan(path, opts)?;
        let failing = p.failing(self.strict);
        if !failing.is_empty() && !self.force {
            let mut msg = format!(
                "{} check{} failed, nothing written (--force writes anyway):",
                failing.len(),
                if failing.len() == 1 { "" } else { "s" }
            );
            for f in failing {
                msg.push_str(&format!("\n  [{}] {}", f.code, f.message));
            }
            return Err(Error::check(&p.path, msg));
        }
        Ok(p)
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

enum Target {
    Stdout,
    File(PathBuf),
}

fn targets(a: &BuildArgs, names: &[String]) -> Result<Vec<Target>> {
    let many = names.len() > 1;
    match a.output.as_deref() {
        Some("-") if many => Err(Error::input(
            "-o -",
            "standard output takes one recipe; give a folder with -o to build several",
        )),
        Some("-") => Ok(vec![Target::Stdout]),
        Some(o) if many || Path::new(o).is_dir() || o.ends_with('/') => {
            std::fs::create_dir_all(o)
                .map_err(|e| Error::io(o, format!("cannot create the output folder: {e}")))?;
            Ok(names
                .iter()
                .map(|n| Target::File(Path::new(o).join(format!("{}.gcode", file_stem(n)))))
                .collect())
        }
        Some(o) => Ok(vec![Target::File(PathBuf::from(o))]),
        None => Ok(names
            .iter()
            .map(|n| Target::File(PathBuf::from(format!("{}.gcode", file_stem(n)))))
            .collect()),
    }
}

/// `p3dp build`: writes G-code and prints a report per recipe.
pub fn build(a: &BuildArgs) -> Vec<Error> {
    let opts = match a.common.options() {
        Ok(o) => o,
        Err(e) => return vec![e],
    };
    let mut errors = Vec::new();
    let mut plans = Vec::new();
    for path in &a.common.recipes {
        match a.common.checked_plan(path, &opts) {
            Ok(p) => plans.push(p),
            Err(e) => errors.push(e),
        }
    }
    let names: Vec<String> = plans.iter().map(|p| p.recipe.name.clone()).collect();
    for (k, n) in names.iter().enumerate() {
        if let Some(j) = names[..k].iter().position(|m| file_stem(m) == file_stem(n)) {
            errors.push(Error::input(
                "name",
                format!(
                    "recipes {} and {} are both named `{n}` and would write the same file",
                    plans[j].path, plans[k].path
                ),
            ));
            return errors;
        }
    }
    let targets = match targets(a, &names) {
        Ok(t) => t,
        Err(e) => {
            errors.push(e);
            return errors;
        }
    };
    let mut all_stats = Vec::new();
    for (p, target) in plans.iter().zip(targets) {
        let result = match &target {
            Target::Stdout => {
                let out = std::io::stdout().lock();
                p.render(out).map(|s| (s, "standard output".to_string()))
            }
            Target::File(f) => {
                let mut stats = None;
                write_atomic(f, |file| {
                    stats = Some(p.render(file)?);
                    Ok(())
                })
                .map(|_| (stats.expect("rendered"), f.display().to_string()))
            }
        };
        match result {
            Ok((stats, shown)) => {
                let report = stats.report(&shown);
                match target {
                    Target::Stdout => eprint!("{report}"),
                    Target::File(_) => print!("{report}"),
                }
                all_stats.push(stats);
            }
            Err(e) => errors.push(e),
        }
    }
    if let Some(path) = &a.stats_json {
        if !all_stats.is_empty() {
            if let Err(e) = write_stats(path, &all_stats) {
                errors.push(e);
            }
        }
    }
    errors
}

fn write_stats(path: &Path, stats: &[Stats]) -> Result<()> {
    let json = if stats.len() == 1 {
        serde_json::to_string_pretty(&stats[0])
    } else {
        serde_json::to_string_pretty(stats)
    }
    .map_err(|e| Error::io(path.display().to_string(), e.to_string()))?;
    write_atomic(path, |f| {
        f.write_all(json.as_bytes())
            .and_then(|_| f.write_all(b"\n"))
            .map_err(|e| Error::io(path.display().to_string(), e.to_string()))
    })
}

/// `p3dp check`: runs every check and prints the findings; writes nothing.
pub fn check(c: &Common) -> Vec<Error> {
    let opts = match c.options() {
        Ok(o) => o,
        Err(e) => return vec![e],
    };
    let mut errors = Vec::new();
    for path in &c.recipes {
        match plan(path, &opts) {
            Ok(p) => {
                let n_err = p.failing(false).len();
                let n_warn = p.findings.len() - n_err;
                println!(
                    "{}: {} warning{}, {} error{}",
                    p.path,
                    n_warn,
                    if n_warn == 1 { "" } else { "s" },
                    n_err,
                    if n_err == 1 { "" } else { "s" }
                );
                for f in &p.findings {
                    println!("  {} [{}]: {}", f.severity.word(), f.code, f.message);
                }
                let failing = p.failing(c.strict).len();
                if failing > 0 {
                    errors.push(Error::check(
                        &p.path,
                        format!(
                            "{failing} check{} failed",
                            if failing == 1 { "" } else { "s" }
                        ),
                    ));
                }
            }
            Err(e) => errors.push(e),
        }
    }
    errors
}

/// `p3dp hash`: prints `SHA256  RECIPE`, the hash of exactly what `build` writes.
pub fn hash(c: &Common) -> Vec<Error> {
    let opts = match c.options() {
        Ok(o) => o,
        Err(e) => return vec![e],
    };
    let mut errors = Vec::new();
    for path in &c.recipes {
        match c
            .checked_plan(path, &opts)
            .and_then(|p| p.render(std::io::sink()))
        {
            Ok(s) => println!("{}  {}", s.gcode_sha256, path.display()),
            Err(e) => errors.push(e),
        }
    }
    errors
}
