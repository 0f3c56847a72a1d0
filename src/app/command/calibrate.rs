//! `p3dp calibrate`: the gallery of calibration prints (`recipes/calibration/`,
//! built into the binary), each built for a printer and a material as
//! `build` builds a recipe; `calibrate apply` writes the value read off a
//! print into a profile that inherits the printer.

use std::path::{Path, PathBuf};

use super::build;
use crate::base::error::{Error, Result};

/// A test of the gallery: its name, what it tunes, its recipe, its params
/// per material (`start`, `end`, `step`), and the profile key `apply` writes.
pub(crate) struct Test {
    /// The name on the command line.
    pub name: &'static str,
    /// What it tunes, for `--list`.
    pub what: &'static str,
    /// The recipe's text.
    pub recipe: &'static str,
    /// `(material, [start, end, step])`; the first is the default.
    pub ranges: &'static [(&'static str, [f64; 3])],
    /// The profile key `apply` writes, if any.
    pub key: Option<&'static str>,
}

macro_rules! recipe {
    ($f:literal) => {
        include_str!(concat!("../../../recipes/calibration/", $f, ".yaml"))
    };
}

/// The gallery, in the order the calibration guides run the tests.
pub(crate) const TESTS: &[Test] = &[
    Test {
        name: "temperature",
        what: "nozzle temperature: a tower, one band per temperature",
        recipe: recipe!("temperature"),
        ranges: &[
            ("pla", [220.0, 190.0, -5.0]),
            ("petg", [250.0, 230.0, -5.0]),
            ("abs", [260.0, 230.0, -5.0]),
            ("tpu", [240.0, 210.0, -5.0]),
        ],
        key: None,
    },
    Test {
        name: "pressure-advance-tower",
        what: "pressure (linear) advance: a tower, one band per factor",
        recipe: recipe!("pressure-advance-tower"),
        ranges: &[("pla", [0.0, 0.08, 0.008]), ("petg", [0.0, 0.1, 0.01])],
        key: Some("pressure_advance"),
    },
    Test {
        name: "pressure-advance-line",
        what: "pressure (linear) advance: lines slow-fast-slow, one factor per line",
        recipe: recipe!("pressure-advance-line"),
        ranges: &[("pla", [0.0, 0.08, 0.01]), ("petg", [0.0, 0.1, 0.0125])],
        key: Some("pressure_advance"),
    },
    Test {
        name: "retraction",
        what: "retraction length: two towers, one band per length",
        recipe: recipe!("retraction"),
        ranges: &[("pla", [0.2, 2.0, 0.2]), ("petg", [0.4, 2.4, 0.2])],
        key: Some("retraction.length"),
    },
    Test {
        name: "input-shaping-frequency",
        what: "input shaper frequency: a fast tower, one band per frequency",
        recipe: recipe!("input-shaping-frequency"),
        ranges: &[("pla", [20.0, 70.0, 5.0])],
        key: None,
    },
];

/// The test named `name`, or an error listing the gallery.
pub(crate) fn test(name: &str) -> Result<&'static Test> {
    TESTS.iter().find(|t| t.name == name).ok_or_else(|| {
        let names: Vec<&str> = TESTS.iter().map(|t| t.name).collect();
        Error::input(
            "TEST",
            format!(
                "unknown calibration test `{name}`; expected one of {}",
                names.join(", ")
            ),
        )
    })
}

/// `p3dp calibrate --list`: each test and what it tunes.
pub(crate) fn list() -> String {
    let w = TESTS.iter().map(|t| t.name.len()).max().unwrap_or(0);
    TESTS
        .iter()
        .map(|t| {
            let mats: Vec<&str> = t.ranges.iter().map(|r| r.0).collect();
            format!(
                "{:<w$}  {} (ranges for {})\n",
                t.name,
                t.what,
                mats.join(", ")
            )
        })
        .collect()
}

/// The params a test is built with: the printer's nozzle, the material's
/// range, then the user's `--set` (which win).
pub(crate) fn sets(
    t: &Test,
    material: &str,
    nozzle: f64,
    user: &[(String, String)],
) -> Vec<(String, String)> {
    let range = t
        .ranges
        .iter()
        .find(|r| r.0 == material)
        .unwrap_or(&t.ranges[0])
        .1;
    let mut out: Vec<(String, String)> = vec![("nozzle".into(), format!("{nozzle}"))];
    for (k, v) in ["start", "end", "step"].iter().zip(range) {
        out.push(((*k).into(), format!("{v}")));
    }
    out.retain(|(k, _)| !user.iter().any(|(u, _)| u == k));
    out.extend(user.iter().cloned());
    out
}

/// The test's recipe for `material` written into `dir` (the recipe's own
/// material swapped for it): the file to build.
pub(crate) fn stage_recipe(t: &Test, material: Option<&str>, dir: &Path) -> Result<PathBuf> {
    let mut text = t.recipe.to_string();
    if let Some(m) = material {
        crate::base::safe_text::check("--material", m)?;
        if !m
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(Error::input(
                "--material",
                format!("`{m}`: expected a built-in material's name (letters, digits, - and _)"),
            ));
        }
        text = text.replacen("\nmaterial: pla\n", &format!("\nmaterial: {m}\n"), 1);
    }
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::io_from(
            dir.display().to_string(),
            format!("cannot make the folder: {e}"),
            &e,
        )
    })?;
    let file = dir.join(format!("{}.yaml", t.name));
    std::fs::write(&file, text).map_err(|e| {
        Error::io_from(
            file.display().to_string(),
            format!("cannot write the recipe: {e}"),
            &e,
        )
    })?;
    Ok(file)
}

/// A scratch folder of this process for the staged recipes.
pub(crate) fn scratch() -> PathBuf {
    std::env::temp_dir().join(format!("p3dp-calibrate-{}", std::process::id()))
}

/// What `calibrate TEST` takes: the test, the material, and `build`'s
/// options (their recipe is the test's, staged).
pub(crate) struct Options {
    /// The test's name.
    pub test: String,
    /// `--material`.
    pub material: Option<String>,
    /// `build`'s options; `builds.recipes` is filled here.
    pub build: build::Options,
}

/// `p3dp calibrate TEST`: the test's recipe built as `build` builds it.
pub(crate) fn run(o: &Options) -> Vec<Error> {
    match prepare(o) {
        Ok((opts, dir)) => {
            let errors = build::run(&opts);
            let _ = std::fs::remove_dir_all(dir);
            errors
        }
        Err(e) => vec![e],
    }
}

/// `build`'s options for the test: its recipe staged, its params set.
fn prepare(o: &Options) -> Result<(build::Options, PathBuf)> {
    let t = test(&o.test)?;
    let mut opts = o.build.clone();
    let nozzle = nozzle(opts.builds.printer.as_deref(), t)?;
    let material = o.material.as_deref().unwrap_or("pla");
    opts.builds.sets = sets(t, material, nozzle, &opts.builds.sets);
    let dir = scratch();
    let file = stage_recipe(t, o.material.as_deref(), &dir)?;
    opts.builds.recipes = vec![file];
    Ok((opts, dir))
}

/// The nozzle diameter of `printer` (the recipe's own when none is given).
fn nozzle(printer: Option<&str>, t: &Test) -> Result<f64> {
    let spec = match printer {
        Some(p) => p.to_string(),
        None => {
            let raw: crate::recipe::RawRecipe = crate::recipe::parse_yaml(t.recipe, t.name)?;
            raw.printer.unwrap_or_else(|| "generic-220".into())
        }
    };
    let reads = crate::base::input::Reads::default();
    reads.allow(Path::new("."));
    let p = crate::machine::Printer::resolve(&spec, Path::new("."), &reads)?;
    Ok(p.nozzle_diameter)
}

/// Which band `apply` reads: its index, or the height it holds.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Pick {
    /// `--band N`.
    Band(u32),
    /// `--height Z`.
    Height(f64),
}

/// What `calibrate apply` takes.
pub(crate) struct Apply {
    /// The test's name.
    pub test: String,
    /// The band.
    pub pick: Pick,
    /// `--printer`.
    pub printer: Option<String>,
    /// `--material`.
    pub material: Option<String>,
    /// `--set`, as the print was built.
    pub sets: Vec<(String, String)>,
    /// `-o`: the profile written.
    pub output: PathBuf,
}

/// `p3dp calibrate apply`: the band's value written into a profile that
/// inherits the printer; the line to print.
pub(crate) fn apply(a: &Apply) -> Result<String> {
    let t = test(&a.test)?;
    let Some(key) = t.key else {
        return Err(Error::input(
            "TEST",
            format!(
                "`{}` tunes a value a printer profile does not hold (the material's, or the firmware's own); read it off the print and set it there",
                t.name
            ),
        ));
    };
    let printer = a.printer.clone().unwrap_or_else(|| "generic-220".into());
    let o = Options {
        test: a.test.clone(),
        material: a.material.clone(),
        build: build::Options {
            builds: super::Builds {
                printer: Some(printer.clone()),
                sets: a.sets.clone(),
                ..super::Builds::default()
            },
            ..build::Options::default()
        },
    };
    let (opts, dir) = prepare(&o)?;
    let plan = crate::app::prepare::prepare(
        &opts.builds.recipes[0],
        &crate::app::prepare::Options {
            sets: opts.builds.sets.clone(),
            printer: Some(printer.clone()),
            ..Default::default()
        },
    );
    let _ = std::fs::remove_dir_all(&dir);
    let plan = plan?;
    let bands = crate::analyse::stats::bands(&plan.paths);
    let band = bands
        .iter()
        .find(|b| match a.pick {
            Pick::Band(n) => b.index == n,
            Pick::Height(z) => b
                .z_from
                .zip(b.z_to)
                .is_some_and(|(lo, hi)| z >= lo && z < hi),
        })
        .ok_or_else(|| {
            Error::input(
                "--band",
                format!(
                    "the print has no such band; expected one of bands 0 to {}",
                    bands.len().saturating_sub(1)
                ),
            )
        })?;
    let value = band.value;
    let body = match key {
        "retraction.length" => format!("retraction: {{ length: {value} }}\n"),
        k => format!("{k}: {value}\n"),
    };
    let text = format!(
        "# p3dp calibrate apply {} --band {}: {key} = {value}\ninherits: {printer}\n{body}",
        t.name, band.index
    );
    crate::output::file::write_atomic(&a.output, |f| {
        use std::io::Write;
        f.write_all(text.as_bytes()).map_err(|e| {
            Error::io_from(
                a.output.display().to_string(),
                format!("cannot write the profile: {e}"),
                &e,
            )
        })
    })?;
    Ok(format!(
        "{}: band {} gives {key} = {value}; wrote {}",
        t.name,
        band.index,
        a.output.display()
    ))
}
