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
    pub(crate) name: &'static str,
    /// What it tunes, for `--list`.
    pub(crate) what: &'static str,
    /// The recipe's text.
    pub(crate) recipe: &'static str,
    /// `(material, [start, end, step])`; the first is the default.
    pub(crate) ranges: &'static [(&'static str, [f64; 3])],
    /// The profile key `apply` writes, if any.
    pub(crate) key: Option<&'static str>,
    /// Without a key: what the value is and where it goes instead (`apply`
    /// says so, with the band's value, and writes nothing).
    pub(crate) instead: &'static str,
    /// The recipe and key for a Klipper printer, when they differ.
    pub(crate) klipper: Option<(&'static str, &'static str)>,
}

macro_rules! gallery_file {
    ($f:literal) => {
        include_str!(concat!("../../../recipes/calibration/", $f, ".yaml"))
    };
}

/// The gallery, in the order the calibration guides run the tests.
pub(crate) const TESTS: &[Test] = &[
    Test {
        name: "temperature",
        what: "nozzle temperature: a tower, one band per temperature",
        recipe: gallery_file!("temperature"),
        ranges: &[
            ("pla", [220.0, 190.0, -5.0]),
            ("petg", [250.0, 230.0, -5.0]),
            ("abs", [260.0, 230.0, -5.0]),
            ("tpu", [240.0, 210.0, -5.0]),
        ],
        key: None,
        instead: "the material's nozzle temperature: set it as your material's `nozzle_temp` (an inline `material:` map) or in your slicer",
        klipper: None,
    },
    Test {
        name: "volumetric-speed",
        what: "maximum volumetric speed: a vase, one flow (mm³/s) per band",
        recipe: gallery_file!("volumetric-speed"),
        ranges: &[("pla", [5.0, 15.0, 1.0]), ("petg", [4.0, 12.0, 1.0])],
        key: Some("max_flow"),
        instead: "",
        klipper: None,
    },
    Test {
        name: "pressure-advance-tower",
        what: "pressure (linear) advance: a tower, one band per factor",
        recipe: gallery_file!("pressure-advance-tower"),
        ranges: &[("pla", [0.0, 0.08, 0.008]), ("petg", [0.0, 0.1, 0.01])],
        key: Some("pressure_advance"),
        instead: "",
        klipper: None,
    },
    Test {
        name: "pressure-advance-line",
        what: "pressure (linear) advance: lines slow-fast-slow, one factor per line",
        recipe: gallery_file!("pressure-advance-line"),
        ranges: &[("pla", [0.0, 0.08, 0.01]), ("petg", [0.0, 0.1, 0.0125])],
        key: Some("pressure_advance"),
        instead: "",
        klipper: None,
    },
    Test {
        name: "pressure-advance-pattern",
        what: "pressure (linear) advance: Ellis' chevrons, one factor per chevron",
        recipe: gallery_file!("pressure-advance-pattern"),
        ranges: &[("pla", [0.0, 0.08, 0.01]), ("petg", [0.0, 0.1, 0.0125])],
        key: Some("pressure_advance"),
        instead: "",
        klipper: None,
    },
    Test {
        name: "flow",
        what: "flow factor: blocks, one factor per block",
        recipe: gallery_file!("flow"),
        ranges: &[("pla", [0.9, 1.1, 0.025])],
        key: None,
        instead: "the material's flow factor: set it with a `set` step's `flow` in your recipes, or as your slicer's extrusion multiplier",
        klipper: None,
    },
    Test {
        name: "retraction",
        what: "retraction length: two towers, one band per length",
        recipe: gallery_file!("retraction"),
        ranges: &[("pla", [0.2, 2.0, 0.2]), ("petg", [0.4, 2.4, 0.2])],
        key: Some("retraction.length"),
        instead: "",
        klipper: None,
    },
    Test {
        name: "cornering",
        what: "cornering: a fast tower, one jerk (Klipper: square-corner velocity) per band",
        recipe: gallery_file!("cornering"),
        ranges: &[("pla", [2.0, 20.0, 2.0])],
        key: Some("kinematics.jerk"),
        instead: "",
        klipper: Some((
            gallery_file!("cornering-scv"),
            "kinematics.square_corner_velocity",
        )),
    },
    Test {
        name: "input-shaping-frequency",
        what: "input shaper frequency: a fast tower, one band per frequency",
        recipe: gallery_file!("input-shaping-frequency"),
        ranges: &[("pla", [20.0, 70.0, 5.0])],
        key: None,
        instead: "the firmware's input shaper frequency: set it in the firmware's configuration (Klipper's `[input_shaper]`, Marlin's `M593 F` and `M500`)",
        klipper: None,
    },
    Test {
        name: "input-shaping-damping",
        what: "input shaper damping: a fast tower, one damping ratio per band",
        recipe: gallery_file!("input-shaping-damping"),
        ranges: &[("pla", [0.02, 0.2, 0.02])],
        key: None,
        instead: "the firmware's input shaper damping ratio: set it in the firmware's configuration (Klipper's `[input_shaper]`, Marlin's `M593 D` and `M500`)",
        klipper: None,
    },
    Test {
        name: "vfa",
        what: "vertical fine artefacts: a round tower, one head speed per band",
        recipe: gallery_file!("vfa"),
        ranges: &[("pla", [20.0, 100.0, 10.0])],
        key: None,
        instead: "the fastest wall speed free of fine vertical artefacts: print walls no faster (your recipes' `speed`)",
        klipper: None,
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
pub(crate) fn stage_recipe(
    t: &Test,
    recipe: &str,
    material: Option<&str>,
    dir: &Path,
) -> Result<PathBuf> {
    let mut text = recipe.to_string();
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

/// A scratch folder of its own for one call's staged recipe, removed when
/// dropped (two calls in one process, as tests make, never share one).
fn scratch() -> Result<tempfile::TempDir> {
    tempfile::Builder::new()
        .prefix("p3dp-calibrate-")
        .tempdir()
        .map_err(|e| {
            Error::io_from(
                std::env::temp_dir().display().to_string(),
                format!("cannot make a scratch folder for the test's recipe: {e}"),
                &e,
            )
        })
}

/// What `calibrate TEST` takes: the test, the material, and `build`'s
/// options (their recipe is the test's, staged).
pub(crate) struct Options {
    /// The test's name.
    pub(crate) test: String,
    /// `--material`.
    pub(crate) material: Option<String>,
    /// `build`'s options; `builds.recipes` is filled here.
    pub(crate) build: build::Options,
}

/// `p3dp calibrate TEST`: the test's recipe built as `build` builds it.
pub(crate) fn run(o: &Options) -> Vec<Error> {
    match prepare(o) {
        Ok((opts, _dir)) => build::run(&opts),
        Err(e) => vec![e],
    }
}

/// `build`'s options for the test: its recipe staged, its params set.
fn prepare(o: &Options) -> Result<(build::Options, tempfile::TempDir)> {
    let t = test(&o.test)?;
    let mut opts = o.build.clone();
    let printer = printer(opts.builds.printer.as_deref(), t, &opts.builds.allow_read)?;
    let material = o.material.as_deref().unwrap_or("pla");
    let user_end = opts.builds.sets.iter().any(|(k, _)| k == "end");
    opts.builds.sets = sets(t, material, printer.nozzle_diameter, &opts.builds.sets);
    if t.name == "volumetric-speed" && !user_end {
        cap_flow(&mut opts.builds.sets, &printer);
    }
    let dir = scratch()?;
    let file = stage_recipe(
        t,
        recipe_for(t, &printer).0,
        o.material.as_deref(),
        dir.path(),
    )?;
    opts.builds.recipes = vec![file];
    // the report names the test, not the staged file
    opts.shown = Some(format!("calibration test {}", t.name));
    Ok((opts, dir))
}

/// `volumetric-speed`'s `end` (not the user's) kept below the hot end's
/// hard limit (`checks.flow_hard_max` × `max_flow`), where the `flow` check
/// refuses a print as a clog: the last band `start + k·step` strictly
/// under it (a band at the limit itself could compute c·(Q/c) a hair
/// above it). Values that are no plain numbers are left alone.
fn cap_flow(sets: &mut [(String, String)], printer: &crate::machine::Printer) {
    let num = |key: &str| {
        let (_, v) = sets.iter().find(|(k, _)| k == key)?;
        crate::base::expr::eval_const(v, &crate::base::expr::Params::new()).ok()
    };
    let (Some(start), Some(end), Some(step)) = (num("start"), num("end"), num("step")) else {
        return;
    };
    let hard = printer.checks.flow_hard_max * printer.max_flow;
    if step <= 0.0 || end < hard || start >= hard {
        return;
    }
    let mut k = libm::floor((hard - start) / step + 1e-9);
    if start + k * step >= hard - 1e-9 {
        k -= 1.0;
    }
    let capped = libm::round((start + k * step) * 1e9) / 1e9;
    if let Some(e) = sets.iter_mut().find(|(key, _)| key == "end") {
        e.1 = format!("{capped}");
    }
}

/// The recipe and `apply`'s key of `t` for `printer`'s firmware.
fn recipe_for(t: &Test, printer: &crate::machine::Printer) -> (&'static str, Option<&'static str>) {
    match t.klipper {
        Some((r, k)) if printer.flavor == crate::machine::Flavor::Klipper => (r, Some(k)),
        _ => (t.recipe, t.key),
    }
}

/// The printer `printer` names (the recipe's own when none is given).
fn printer(
    printer: Option<&str>,
    t: &Test,
    allow_read: &[PathBuf],
) -> Result<crate::machine::Printer> {
    let spec = match printer {
        Some(p) => p.to_string(),
        None => {
            let raw: crate::recipe::RawRecipe = crate::recipe::parse_yaml(t.recipe, t.name)?;
            raw.printer.unwrap_or_else(|| "generic-220".into())
        }
    };
    let reads = crate::base::input::Reads::default();
    reads.allow(Path::new("."));
    for dir in allow_read {
        reads.allow(dir);
    }
    crate::recipe::profile::resolve(&spec, Path::new("."), &reads)
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
    pub(crate) test: String,
    /// The band.
    pub(crate) pick: Pick,
    /// `--printer`.
    pub(crate) printer: Option<String>,
    /// `--material`.
    pub(crate) material: Option<String>,
    /// `--set`, as the print was built.
    pub(crate) sets: Vec<(String, String)>,
    /// `--allow-read`: folders the printer's profile may be read from.
    pub(crate) allow_read: Vec<PathBuf>,
    /// `-o`: the profile written.
    pub(crate) output: PathBuf,
}

/// `p3dp calibrate apply`: the band's value written into a profile that
/// inherits the printer; the line to print. A test whose value no profile
/// key holds is refused, saying the band's value and where it goes.
pub(crate) fn apply(a: &Apply) -> Result<String> {
    let t = test(&a.test)?;
    let printer = a.printer.clone().unwrap_or_else(|| "generic-220".into());
    let key = recipe_for(t, &self::printer(Some(&printer), t, &a.allow_read)?).1;
    let band = picked(a, &printer)?;
    let value = band.value;
    let Some(key) = key else {
        return Err(Error::input(
            "TEST",
            format!(
                "`{}` tunes {}; a printer profile does not hold it, so nothing is written (band {} gives {value})",
                t.name, t.instead, band.index
            ),
        ));
    };
    let body = match key.split_once('.') {
        Some((map, k)) => format!("{map}: {{ {k}: {value} }}\n"),
        None => format!("{key}: {value}\n"),
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

/// The band `apply` picks, of the test built as the print was (the same
/// printer, material and `--set`).
fn picked(a: &Apply, printer: &str) -> Result<crate::analyse::stats::BandStats> {
    let o = Options {
        test: a.test.clone(),
        material: a.material.clone(),
        build: build::Options {
            builds: super::Builds {
                printer: Some(printer.to_string()),
                sets: a.sets.clone(),
                allow_read: a.allow_read.clone(),
                ..super::Builds::default()
            },
            ..build::Options::default()
        },
    };
    let (opts, _dir) = prepare(&o)?;
    let plan = crate::app::prepare::prepare(
        &opts.builds.recipes[0],
        &crate::app::prepare::Options {
            sets: opts.builds.sets.clone(),
            printer: Some(printer.to_string()),
            allow_read: opts.builds.allow_read.clone(),
            ..Default::default()
        },
    )?;
    let bands = crate::analyse::stats::bands(&plan.paths);
    let n = bands.len();
    bands
        .into_iter()
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
                    n.saturating_sub(1)
                ),
            )
        })
}

#[cfg(test)]
mod tests {
    use crate::app::testing::{p3dp, FLAVOURS};
    use crate::base::gcode::{Command, Setting};
    use crate::base::testing::{root, tmp};
    use crate::machine::firmware::read;
    use crate::machine::Flavor;

    /// The value a test's band sets, if `c` is that setting.
    fn value(test: &str, c: &Command) -> Option<f64> {
        match (test, c) {
            // the end G-code's heaters off are no band's
            (
                "temperature",
                Command::Set(Setting::Temperature {
                    heater: crate::base::gcode::Heater::Nozzle(_),
                    celsius,
                    ..
                }),
            ) if *celsius > 0.0 => Some(*celsius),
            (
                "pressure-advance-tower" | "pressure-advance-line" | "pressure-advance-pattern",
                Command::Set(Setting::PressureAdvance { k }),
            ) => Some(*k),
            ("flow", Command::Set(Setting::Flow(f))) => Some(*f),
            ("cornering", Command::Set(Setting::Jerk(j) | Setting::SquareCornerVelocity(j))) => {
                Some(*j)
            }
            (
                "input-shaping-damping",
                Command::Set(Setting::InputShaper {
                    damping: Some(d), ..
                }),
            ) => Some(*d),
            (
                "input-shaping-frequency",
                Command::Set(Setting::InputShaper {
                    frequency: [Some(f), _],
                    ..
                }),
            ) => Some(*f),
            _ => None,
        }
    }

    struct Built {
        gcode: String,
        stats: serde_json::Value,
    }

    fn build(test: &str, printer: &str, sets: &[&str]) -> std::result::Result<Built, String> {
        let dir = tmp(&format!("calibrate-{test}-{}", printer.replace('/', "-")));
        let printer = root().join(printer).display().to_string();
        let printer = if printer.ends_with(".yaml") {
            printer
        } else {
            printer.rsplit('/').next().unwrap().to_string()
        };
        let mut args = vec![
            "calibrate",
            test,
            "--printer",
            &printer,
            "-o",
            "out.gcode",
            "--stats-json",
            "stats.json",
        ];
        for s in sets {
            args.extend(["--set", s]);
        }
        // a profile a test wrote in its own folder may be read
        let folder = std::path::Path::new(&printer)
            .parent()
            .filter(|d| d.is_absolute() && !d.starts_with(root()))
            .map(|d| d.display().to_string());
        if let Some(d) = &folder {
            args.extend(["--allow-read", d]);
        }
        let out = p3dp(&dir, &args);
        if !out.success() {
            return Err(out.stderr);
        }
        Ok(Built {
            gcode: std::fs::read_to_string(dir.join("out.gcode")).unwrap(),
            stats: serde_json::from_str(&std::fs::read_to_string(dir.join("stats.json")).unwrap())
                .unwrap(),
        })
    }

    /// Every test and flavour: read back through the firmware's reader,
    /// one setting command per band, before the band's first move, its
    /// value `start + i·step`, the stats' bands and the labels' the same.
    #[test]
    fn one_setting_per_band_read_back_in_every_flavour() {
        for test in [
            "temperature",
            "pressure-advance-tower",
            "pressure-advance-line",
            "pressure-advance-pattern",
            "flow",
            "cornering",
            "input-shaping-frequency",
            "input-shaping-damping",
        ] {
            for (printer, flavor) in FLAVOURS {
                // a step no slicer offers: 3 °C, 7/1000 s, 7 Hz
                let step = match test {
                    "temperature" => "step=-3",
                    "input-shaping-frequency" => "step=7",
                    "cornering" => "step=3",
                    "flow" => "step=3/100",
                    "input-shaping-damping" => "step=3/100",
                    _ => "step=7/1000",
                };
                let b = match build(test, printer, &[step]) {
                    Ok(b) => b,
                    Err(e) => {
                        // Bambu's firmware has no input shaper command and no
                        // jerk: refused by name
                        assert!(
                            matches!(
                                test,
                                "input-shaping-frequency" | "input-shaping-damping" | "cornering"
                            ) && flavor == Flavor::Bambu,
                            "{test} on {printer}: {e}"
                        );
                        assert!(e.contains("[setting]") && e.contains("Bambu"), "{e}");
                        continue;
                    }
                };
                check_bands(test, flavor, &b);
            }
        }
    }

    fn check_bands(test: &str, flavor: Flavor, b: &Built) {
        let bands = b.stats["bands"].as_array().unwrap();
        let params = &b.stats["params"];
        let start = params["start"].as_f64().unwrap();
        let step = params["step"].as_f64().unwrap();
        assert!(bands.len() >= 5, "{test}: {bands:?}");
        let mut seen = Vec::new();
        let mut labels = Vec::new();
        let mut pending: Option<f64> = None;
        let mut z = 0.0;
        let mut in_parts = false;
        for line in b.gcode.lines() {
            if let Some(name) = line.strip_prefix("; part: label-") {
                labels.push(
                    name.split([' ', '-'])
                        .nth(1)
                        .unwrap()
                        .parse::<f64>()
                        .unwrap(),
                );
            }
            in_parts |= line.starts_with("; part: ");
            let r = read(flavor, line).unwrap();
            for c in &r.commands {
                if let Command::Move(m) = c {
                    z = m.to[2].unwrap_or(z);
                    if let (Some(v), Some(e)) = (pending, m.e) {
                        if e > 0.0 && m.to[0].is_some() {
                            // the band's first extruding move
                            seen.push((v, z));
                            pending = None;
                        }
                    }
                }
                if let (true, Some(v)) = (in_parts, value(test, c)) {
                    assert!(pending.is_none(), "{test}: two settings before a move");
                    pending = Some(v);
                }
            }
        }
        assert_eq!(seen.len(), bands.len(), "{test} {flavor:?}: {seen:?}");
        for (i, ((v, z), band)) in seen.iter().zip(bands).enumerate() {
            let want = start + i as f64 * step;
            assert!(
                (v - want).abs() < 6e-5,
                "{test} {flavor:?} band {i}: {v} ≠ {want}"
            );
            assert!((band["value"].as_f64().unwrap() - want).abs() < 1e-9);
            assert_eq!(band["index"].as_u64(), Some(i as u64));
            if let (Some(lo), Some(hi)) = (band["z_from"].as_f64(), band["z_to"].as_f64()) {
                // the band's first move lies in the band (the G-code's z is
                // the recipe's: these printers' z origin is 0)
                assert!(
                    *z >= lo - 1e-9 && *z < hi,
                    "{test} {flavor:?} band {i}: first move at z {z}, not in [{lo}, {hi})"
                );
            } else {
                assert_eq!(band["line"].as_u64(), Some(i as u64));
            }
        }
        let values: Vec<f64> = bands.iter().map(|b| b["value"].as_f64().unwrap()).collect();
        assert_eq!(labels.len(), values.len(), "{test}: {labels:?}");
        for (l, v) in labels.iter().zip(&values) {
            assert!((l - v).abs() < 1e-6, "{test}: label {l} for band value {v}");
        }
    }

    /// The labels the G-code's part names carry (`label-K-VALUE`), in order.
    fn labels(gcode: &str) -> Vec<f64> {
        gcode
            .lines()
            .filter_map(|l| l.strip_prefix("; part: label-"))
            .map(|name| name.split([' ', '-']).nth(1).unwrap().parse().unwrap())
            .collect()
    }

    /// The extruding moves of part `part` read back: (z, mm/s, mm³/s),
    /// the flow from E over the move's time (`area`: the filament's
    /// section, mm²).
    fn paced_moves(flavor: Flavor, gcode: &str, part: &str, area: f64) -> Vec<(f64, f64, f64)> {
        let (mut relative, mut e, mut feed) = (false, 0.0, 0.0);
        let mut at = [0.0; 3];
        let mut inside = false;
        let mut out = Vec::new();
        for line in gcode.lines() {
            if let Some(name) = line.strip_prefix("; part: ") {
                inside = name.split(' ').next() == Some(part);
            }
            for c in read(flavor, line).unwrap().commands {
                match c {
                    Command::RelativeE(r) => relative = r,
                    Command::SetPosition { e: Some(v), .. } => e = v,
                    Command::Move(m) => {
                        feed = m.feed.unwrap_or(feed);
                        let from = at;
                        for (a, to) in at.iter_mut().zip(m.to) {
                            *a = to.unwrap_or(*a);
                        }
                        let Some(v) = m.e else { continue };
                        let de = if relative { v } else { v - e };
                        e = if relative { e + v } else { v };
                        let len = (0..3)
                            .map(|k| (at[k] - from[k]).powi(2))
                            .sum::<f64>()
                            .sqrt();
                        if inside && de > 0.0 && len > 0.0 {
                            let speed = feed / 60.0;
                            out.push((at[2], speed, de * area * speed / len));
                        }
                    }
                    _ => {}
                }
            }
        }
        out
    }

    /// `vfa` and `volumetric-speed` (the moves' speed and flow, no firmware
    /// setting), every flavour, a step no slicer offers: read back, every
    /// extruding move of the wall lies in a band of the stats and carries
    /// that band's value `start + i·step` (F exactly, the flow from E and F
    /// to the writing's precision); every band has moves, its first at its
    /// bottom; the labels are the bands' values.
    #[test]
    fn paced_bands_read_back_in_every_flavour() {
        for (test, part, step) in [
            ("vfa", "tower", "step=7"),
            ("volumetric-speed", "vase", "step=7/10"),
        ] {
            for (printer, flavor) in FLAVOURS {
                let b = build(test, printer, &[step, "band_height=2"]).unwrap();
                let s = &b.stats;
                let area = s["filament_volume_mm3"].as_f64().unwrap()
                    / s["filament_length_mm"].as_f64().unwrap();
                let bands = s["bands"].as_array().unwrap();
                let (start, step) = (
                    s["params"]["start"].as_f64().unwrap(),
                    s["params"]["step"].as_f64().unwrap(),
                );
                assert!(bands.len() >= 12, "{test}: {bands:?}");
                let span = |b: &serde_json::Value| {
                    [b["z_from"].as_f64().unwrap(), b["z_to"].as_f64().unwrap()]
                };
                let mut first: Vec<Option<f64>> = vec![None; bands.len()];
                for (z, speed, flow) in paced_moves(flavor, &b.gcode, part, area) {
                    // the G-code's z is the recipe's (these printers' z origin is 0)
                    let last = bands.len() - 1;
                    let i = bands
                        .iter()
                        .position(|b| {
                            let [lo, hi] = span(b);
                            z >= lo - 1e-9
                                && (z < hi - 1e-9 || (z <= hi + 1e-9 && b == &bands[last]))
                        })
                        .unwrap_or_else(|| panic!("{test} {flavor:?}: a move at z {z} in no band"));
                    let want = start + i as f64 * step;
                    let got = if test == "vfa" { speed } else { flow };
                    assert!(
                        (got - want).abs() <= 2e-3 * want,
                        "{test} {flavor:?} band {i} at z {z}: {got} ≠ {want}"
                    );
                    if test == "vfa" {
                        assert_eq!(speed * 60.0, libm::round(want * 60.0));
                    }
                    first[i].get_or_insert(z);
                }
                for (i, (band, z)) in bands.iter().zip(&first).enumerate() {
                    assert_eq!(band["index"].as_u64(), Some(i as u64));
                    let want = start + i as f64 * step;
                    assert!((band["value"].as_f64().unwrap() - want).abs() < 1e-9);
                    let [lo, _] = span(band);
                    let z = z.unwrap_or_else(|| panic!("{test} {flavor:?}: band {i} has no move"));
                    assert!(
                        z >= lo - 1e-9 && z < lo + 0.2,
                        "{test} band {i}: first move at {z}, from {lo}"
                    );
                }
                let values: Vec<f64> = bands.iter().map(|b| b["value"].as_f64().unwrap()).collect();
                let labels = labels(&b.gcode);
                assert_eq!(labels.len(), values.len(), "{test}: {labels:?}");
                for (l, v) in labels.iter().zip(&values) {
                    assert!((l - v).abs() < 1e-6, "{test}: label {l} for band value {v}");
                }
                assert_eq!(b.gcode.matches("\n; band ").count(), bands.len());
            }
        }
    }

    /// Firmware retraction per band, every flavour with `G10`/`G11`: each
    /// band's length is set (`M207`, Klipper's `SET_RETRACTION`) to its
    /// value, never between a `G10` and its `G11` (Klipper's and
    /// RepRapFirmware's `G11` give back the length in force, not what the
    /// `G10` took), and every band retracts at its own length.
    #[test]
    fn firmware_retraction_bands_set_their_length_outside_a_retraction() {
        let dir = tmp("calibrate-firmware-retraction");
        for (printer, flavor) in FLAVOURS.into_iter().filter(|(_, f)| *f != Flavor::Bambu) {
            let profile = dir.join(format!("fw-{printer}.yaml"));
            std::fs::write(
                &profile,
                format!("inherits: {printer}\nname: fw-{printer}\nfirmware_retraction: true\n"),
            )
            .unwrap();
            let b = build(
                "retraction",
                &profile.display().to_string(),
                &["step=3/10", "end=2"],
            )
            .unwrap();
            let values: Vec<f64> = b.stats["bands"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x["value"].as_f64().unwrap())
                .collect();
            let (mut length, mut taken): (Option<f64>, Option<Option<f64>>) = (None, None);
            let mut set = Vec::new();
            let mut retracts = vec![0; values.len()];
            for line in b.gcode.lines() {
                for c in read(flavor, line).unwrap().commands {
                    match c {
                        Command::Set(Setting::Retraction {
                            length: Some(l), ..
                        }) => {
                            assert_eq!(taken, None, "{printer}: `{line}` inside a retraction");
                            length = Some(l);
                            set.push(l);
                        }
                        Command::FirmwareRetract { undo: false } => {
                            assert_eq!(taken, None, "{printer}: `{line}` retracted twice");
                            taken = Some(length);
                            if let Some(k) = length
                                .and_then(|l| values.iter().position(|v| (v - l).abs() < 1e-9))
                            {
                                retracts[k] += 1;
                            }
                        }
                        Command::FirmwareRetract { undo: true } => {
                            assert_eq!(
                                taken,
                                Some(length),
                                "{printer}: `{line}` gives back another length"
                            );
                            taken = None;
                        }
                        _ => {}
                    }
                }
            }
            assert_eq!(set, values, "{printer}: one setting a band, its value");
            assert!(
                retracts.iter().skip(1).all(|&n| n > 0),
                "{printer}: {retracts:?}"
            );
        }
        // the profile read off the print, from the folder it was allowed
        let profile = dir.join("fw-generic-220.yaml").display().to_string();
        let folder = dir.display().to_string();
        let apply = |extra: &[&str]| {
            let mut args = vec!["calibrate", "apply", "retraction", "--band", "2"];
            args.extend([
                "--printer",
                &profile,
                "--set",
                "step=3/10",
                "--set",
                "end=2",
            ]);
            args.extend(extra);
            args.extend(["-o", "applied.yaml"]);
            p3dp(&dir, &args)
        };
        let refused = apply(&[]);
        assert_eq!(refused.code, 2, "{}", refused.stderr);
        assert!(
            refused.stderr.contains("--allow-read"),
            "{}",
            refused.stderr
        );
        let out = apply(&["--allow-read", &folder]);
        assert!(out.success(), "{}", out.stderr);
        let text = std::fs::read_to_string(dir.join("applied.yaml")).unwrap();
        assert!(text.contains("retraction: { length: 0.8 }"), "{text}");
    }

    /// p3dp's own retraction per band, every flavour: after band k's note
    /// every retraction the reader reads takes back `start + k·step` mm, in
    /// absolute and relative E; the labels are the bands' values (firmware
    /// retraction: the test above).
    #[test]
    fn retraction_bands_are_the_retractions_read_back() {
        for (printer, flavor) in FLAVOURS {
            let b = build("retraction", printer, &["step=3/10", "end=2"]).unwrap();
            let bands = b.stats["bands"].as_array().unwrap();
            let (mut relative, mut e, mut band): (bool, f64, Option<f64>) = (false, 0.0, None);
            let mut checked = vec![0; bands.len()];
            for line in b.gcode.lines() {
                if let Some(rest) = line.strip_prefix("; retraction: ") {
                    band = Some(rest.split(' ').next().unwrap().parse().unwrap());
                }
                for c in read(flavor, line).unwrap().commands {
                    match c {
                        Command::RelativeE(r) => relative = r,
                        Command::SetPosition { e: Some(v), .. } => e = v,
                        Command::Move(m) => {
                            let Some(v) = m.e else { continue };
                            let de = if relative { v } else { v - e };
                            e = if relative { e + v } else { v };
                            if m.to == [None; 3] && de < 0.0 && line.contains("retract") {
                                if let Some(len) = band {
                                    assert!((-de - len).abs() < 1e-5, "{printer}: {de} for {len}");
                                    let k = bands
                                        .iter()
                                        .position(|x| {
                                            (x["value"].as_f64().unwrap() - len).abs() < 1e-9
                                        })
                                        .unwrap();
                                    checked[k] += 1;
                                }
                            }
                        }
                        _ => {}
                    }
                }
            }
            assert!(checked.iter().all(|&n| n > 0), "{printer}: {checked:?}");
            let values: Vec<f64> = bands.iter().map(|x| x["value"].as_f64().unwrap()).collect();
            let want: Vec<f64> = (0..values.len())
                .map(|i| libm::round((0.2 + 0.3 * i as f64) * 1e9) / 1e9)
                .collect();
            assert_eq!(values, want);
            assert_eq!(labels(&b.gcode), values, "{printer}");
        }
    }
}
