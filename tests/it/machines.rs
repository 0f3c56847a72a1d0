//! Real printers: the built-in profiles, user profiles with `inherits`, the
//! firmware dialects (every line of the output parsed by a table of that
//! dialect's commands), the origin, and G2/G3 arc fitting.

use crate::common;

use std::f64::consts::PI;
use std::path::PathBuf;

use crate::common::{p3dp, recipe, root, tmp, Move};
use glam::DVec3;
use p3dp::testing::printers as built_in_names;
use p3dp::testing::Insides;
use p3dp::testing::{Bed, Printer};
use p3dp::testing::{Event, Toolpath};
use p3dp::{plan, Options};

const PROFILES: [&str; 15] = [
    "generic-220",
    "ender3",
    "prusa-mk3s",
    "prusa-mk4",
    "voron-350",
    "rostock-max",
    "bambu-x1c",
    "bambu-p1s",
    "bambu-a1",
    "bambu-a1-mini",
    "prusa-mk4s",
    "prusa-core-one",
    "prusa-mini",
    "creality-k1",
    "ender3-v3",
];

fn fixture(name: &str) -> PathBuf {
    root().join("tests/fixtures/printers").join(name)
}

// ---------------------------------------------------------------- dialects

/// Commands every dialect takes, with their parameter letters.
const COMMON: &[(&str, &str)] = &[
    ("G0", "XYZF"),
    ("G1", "XYZEF"),
    ("G2", "XYZIJEF"),
    ("G3", "XYZIJEF"),
    ("G4", "P"),
    ("G10", ""),
    ("G11", ""),
    ("G21", ""),
    ("G28", ""),
    ("G90", ""),
    ("G92", "E"),
    ("M82", ""),
    ("M83", ""),
    ("M84", ""),
];
const MARLIN: &[(&str, &str)] = &[
    ("M0", ""),
    ("M104", "S"),
    ("M109", "S"),
    ("M140", "S"),
    ("M190", "S"),
    ("M106", "S"),
    ("M107", ""),
    // Marlin's bed levelling (AUTO_BED_LEVELING_*; the Bambu firmwares too)
    ("G29", ""),
    // progress (issue 31): percent done, minutes left
    ("M73", "PR"),
];
const PRUSA_EXTRA: &[(&str, &str)] = &[("M601", ""), ("G28", "W"), ("G29", ""), ("G80", "")];
/// Klipper: its extended commands take `KEY=VALUE` (keys listed by spaces).
const KLIPPER: &[(&str, &str)] = &[
    ("M106", "S"),
    ("M107", ""),
    ("SET_HEATER_TEMPERATURE", "HEATER TARGET"),
    ("TEMPERATURE_WAIT", "SENSOR MINIMUM MAXIMUM"),
    ("TURN_OFF_HEATERS", ""),
    ("PAUSE", ""),
    // object labels (issue 31); CENTER and POLYGON are checked apart
    ("EXCLUDE_OBJECT_DEFINE", "NAME CENTER POLYGON"),
    ("EXCLUDE_OBJECT_START", "NAME"),
    ("EXCLUDE_OBJECT_END", "NAME"),
];
const REPRAP: &[(&str, &str)] = &[
    ("T0", ""),
    ("M104", "S"),
    ("M140", "S"),
    ("M116", "PH"),
    ("M106", "S"),
    ("M226", ""),
];

fn dialect(flavor: &str) -> Vec<(&'static str, &'static str)> {
    let mut t: Vec<_> = COMMON.to_vec();
    match flavor {
        "marlin" => t.extend_from_slice(MARLIN),
        "prusa" => {
            t.extend_from_slice(MARLIN);
            t.extend_from_slice(PRUSA_EXTRA);
        }
        "klipper" => t.extend_from_slice(KLIPPER),
        "reprap" => t.extend_from_slice(REPRAP),
        other => panic!("no dialect {other}"),
    }
    t
}

/// A number as the promise says: fixed point, no exponent, no `-0`.
fn plain_number(v: &str) -> bool {
    let body = v.strip_prefix('-').unwrap_or(v);
    let ok = !body.is_empty()
        && body.split('.').count() <= 2
        && body
            .split('.')
            .all(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()));
    ok && !(v.starts_with('-') && v.parse::<f64>().unwrap() == 0.0)
}

/// Klipper's `POLYGON=[[x,y],…]`: points of two plain numbers.
fn polygon(v: &str) -> bool {
    let Some(inner) = v.strip_prefix("[[").and_then(|v| v.strip_suffix("]]")) else {
        return false;
    };
    inner.split("],[").all(|p| {
        let xy: Vec<&str> = p.split(',').collect();
        xy.len() == 2 && xy.iter().all(|n| plain_number(n))
    })
}

/// Checks every line of `text` against `flavor`'s table; panics naming the line.
fn check_dialect(text: &str, flavor: &str) {
    let table = dialect(flavor);
    for (n, raw) in text.lines().enumerate() {
        let code = raw.split(';').next().unwrap().trim();
        if code.is_empty() {
            continue;
        }
        let mut words = code.split_whitespace();
        let cmd = words.next().unwrap();
        let allowed: Vec<&str> = table
            .iter()
            .filter(|(c, _)| *c == cmd)
            .map(|(_, p)| *p)
            .collect();
        assert!(
            !allowed.is_empty(),
            "line {}: `{raw}`: {cmd} is not a {flavor} command",
            n + 1
        );
        let extended = cmd.contains('_') || cmd == "PAUSE";
        for w in words {
            let fine = if extended {
                let (k, v) = w.split_once('=').unwrap_or((w, ""));
                allowed.iter().any(|p| p.split(' ').any(|a| a == k))
                    && (plain_number(v)
                        || (k == "CENTER" && v.split(',').all(plain_number))
                        || (k == "POLYGON" && polygon(v))
                        || (!v.is_empty()
                            && v.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')))
            } else {
                let (letter, v) = w.split_at(1);
                allowed.iter().any(|p| p.contains(letter))
                    && (plain_number(v) || (cmd == "G28" && v.is_empty()))
            };
            assert!(
                fine,
                "line {}: `{raw}`: `{w}` is not a {flavor} parameter of {cmd}",
                n + 1
            );
        }
    }
}

// ------------------------------------------------------- reading moves back

impl Move {
    /// Points along the move as the firmware runs it (an arc: radius and z
    /// linear in the angle, from start to end).
    fn samples(&self, n: usize) -> Vec<DVec3> {
        let (a, b) = (DVec3::from(self.from), DVec3::from(self.to));
        if self.g < 2 {
            return (0..=n).map(|k| a.lerp(b, k as f64 / n as f64)).collect();
        }
        let c = a.truncate() + glam::DVec2::from(self.ij);
        let (ra, rb) = ((a.truncate() - c).length(), (b.truncate() - c).length());
        let t0 = (a.y - c.y).atan2(a.x - c.x);
        let t1 = (b.y - c.y).atan2(b.x - c.x);
        let mut sweep = t1 - t0;
        if self.g == 3 {
            while sweep <= 0.0 {
                sweep += 2.0 * PI;
            }
        } else {
            while sweep >= 0.0 {
                sweep -= 2.0 * PI;
            }
        }
        (0..=n)
            .map(|k| {
                let u = k as f64 / n as f64;
                let (t, r) = (t0 + sweep * u, ra + (rb - ra) * u);
                DVec3::new(c.x + r * t.cos(), c.y + r * t.sin(), a.z + (b.z - a.z) * u)
            })
            .collect()
    }
}

/// Every move of `text` (G28 makes the position unknown again).
fn moves(text: &str) -> Vec<Move> {
    common::parse(text).moves
}

/// Panics unless every known coordinate of every move (arcs sampled) lies
/// in `printer`'s volume.
fn assert_inside(text: &str, printer: &Printer, what: &str) {
    let max_z = printer.bed.max_z();
    for m in moves(text) {
        let pts = if m.from.iter().chain(&m.to).all(|v| v.is_finite()) {
            m.samples(16)
        } else {
            vec![DVec3::from(m.to)]
        };
        for p in pts {
            if p.z.is_finite() {
                assert!(
                    p.z >= -1e-9 && p.z <= max_z + 1e-9,
                    "{what}: z {p} of {m:?}"
                );
            }
            match printer.bed {
                Bed::Rectangle { size, .. } => {
                    if p.x.is_finite() {
                        assert!(
                            p.x >= -1e-9 && p.x <= size[0] + 1e-9,
                            "{what}: x {p} of {m:?}"
                        );
                    }
                    if p.y.is_finite() {
                        assert!(
                            p.y >= -1e-9 && p.y <= size[1] + 1e-9,
                            "{what}: y {p} of {m:?}"
                        );
                    }
                }
                Bed::Circle { diameter, .. } => {
                    if p.x.is_finite() && p.y.is_finite() {
                        let r = p.truncate().length();
                        assert!(
                            r <= diameter / 2.0 + 1e-9,
                            "{what}: {p} is {r} mm from the centre"
                        );
                    }
                }
            }
        }
    }
}

fn build(recipe_name: &str, printer: &str) -> String {
    // tests run in parallel and build the same pairs: one folder per call
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = tmp(&format!(
        "machines-{recipe_name}-{}-{call}",
        printer.replace('/', "_")
    ));
    let out = p3dp(
        &dir,
        &[
            "build",
            recipe(recipe_name).to_str().unwrap(),
            "--printer",
            printer,
            "-o",
            "out.gcode",
        ],
    );
    assert!(
        out.status.success(),
        "{recipe_name} on {printer}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("out.gcode")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    text
}

/// [`build`] of `recipe_name` on `printer`, built once per run and shared
/// by the tests that read the same pair (the cup on every profile).
fn shared(recipe_name: &str, printer: &str) -> std::sync::Arc<String> {
    crate::common::once(&format!("machines {recipe_name} on {printer}"), || {
        build(recipe_name, printer)
    })
}

// ------------------------------------------------------------------- tests

#[test]
fn the_built_in_list_and_the_printers_command() {
    assert_eq!(built_in_names(), PROFILES);
    let out = p3dp(&root(), &["printers"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for name in PROFILES {
        let p = p3dp::testing::profile::built_in(name).unwrap();
        let line = text
            .lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap_or_else(|| panic!("{name} missing from\n{text}"));
        assert!(line.contains(p.flavor.name()), "{line}");
        assert!(line.contains(&p.bed.describe()), "{line}");
        assert!(line.contains(" 0.4 "), "{line}");
    }
    // each built-in passes the checks a user's file gets
    let dir = tmp("machines-validate");
    for name in PROFILES {
        let f = dir.join(format!("{name}-user.yaml"));
        std::fs::write(&f, format!("inherits: {name}\n")).unwrap();
        let p = p3dp::testing::profile::from_file(&f).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(p.name, format!("{name}-user"));
        assert_eq!(p.nozzle_diameter, 0.4);
        assert_eq!(p.filament_diameter, 1.75);
    }
    let delta = p3dp::testing::profile::built_in("rostock-max").unwrap();
    assert_eq!(delta.origin, [0.0, 0.0, 0.0]);
    // SeeMeCNC's M665 B135: a printable radius of 135 mm
    assert!(matches!(delta.bed, Bed::Circle { diameter, .. } if diameter == 270.0));
}

#[test]
fn every_built_in_profile_builds_the_globe_and_the_cup_inside_its_volume() {
    for name in PROFILES {
        let printer = p3dp::testing::profile::built_in(name).unwrap();
        for r in ["globe.yaml", "cup.yaml"] {
            let text = shared(r, name);
            assert!(text.contains(&format!("; printer: {name} ")), "{name}");
            assert_inside(&text, &printer, &format!("{r} on {name}"));
            check_dialect(&text, printer.flavor.name());
            // the material's temperatures, within the printer's limits
            assert!(printer.max_nozzle_temp >= 210.0 && printer.max_bed_temp >= 60.0);
        }
    }
}

#[test]
fn start_gcode_matches_the_recorded_expectations() {
    for name in PROFILES {
        let text = shared("cup.yaml", name);
        let got: Vec<&str> = text
            .lines()
            // before the start G-code: progress and object labels (issue 31)
            .filter(|l| !l.starts_with(';') && !l.starts_with("M73 "))
            .filter(|l| !l.starts_with("EXCLUDE_OBJECT_DEFINE "))
            .take_while(|l| *l != "G92 E0")
            .chain(["G92 E0"])
            .collect();
        let want = std::fs::read_to_string(fixture(&format!("start/{name}.gcode"))).unwrap();
        assert_eq!(got.join("\n") + "\n", want, "{name}");
    }
}

/// Recipe coordinates are centred on the bed: the corner origin (generic) and
/// the centre origin (delta) put every move at the same place relative to
/// the bed's centre.
#[test]
fn corner_and_centre_origins_place_the_recipe_alike() {
    let parts = |text: &str| -> Vec<[f64; 3]> {
        let from = text.find("; part:").unwrap();
        moves(&text[from..])
            .iter()
            .filter(|m| m.g == 1 && m.de > 0.0 && m.from[0].is_finite())
            .map(|m| m.to)
            .collect()
    };
    let corner = parts(&shared("cup.yaml", "generic-220"));
    let centre = parts(&shared("cup.yaml", "rostock-max"));
    assert_eq!(corner.len(), centre.len());
    for (a, b) in corner.iter().zip(&centre) {
        // equal but for the µm rounding of each (a half-µm rounds away from 0)
        assert!((a[0] - 110.0 - b[0]).abs() < 1.5e-3, "{a:?} {b:?}");
        assert!((a[1] - 110.0 - b[1]).abs() < 1.5e-3, "{a:?} {b:?}");
        assert!((a[2] - b[2]).abs() < 1e-9, "{a:?} {b:?}");
    }
}

#[test]
fn user_profiles_inherit_and_override() {
    let p = p3dp::testing::profile::from_file(&fixture("child-user.yaml")).unwrap();
    // from the child, the file it inherits, and prusa-mk4 under both
    assert_eq!(p.name, "child-user");
    assert_eq!(p.retraction.length, 1.5);
    assert_eq!(
        p.retraction.speed, 35.0,
        "the rest of the map stays the base's"
    );
    assert_eq!(p.kinematics.max_acceleration, 2000.0);
    assert_eq!(p.kinematics.travel_acceleration, Some(4000.0));
    assert_eq!(p.nozzle_diameter, 0.6);
    assert_eq!(p.max_flow, 22.0);
    assert_eq!(p.flavor.name(), "prusa");
    let mk4 = p3dp::testing::profile::built_in("prusa-mk4").unwrap();
    assert_eq!(p.start_gcode, mk4.start_gcode);
    assert_eq!(p.bed, mk4.bed);

    let named = p3dp::testing::profile::from_file(&fixture("base-user.yaml")).unwrap();
    assert_eq!(named.name, "my-mk4");

    let round = p3dp::testing::profile::from_file(&fixture("round-over-rectangle.yaml")).unwrap();
    assert_eq!(
        round.bed,
        Bed::Circle {
            diameter: 180.0,
            max_z: 200.0
        }
    );
}

#[test]
fn bad_user_profiles_exit_2_naming_the_key() {
    let dir = tmp("machines-bad-profiles");
    for (file, want) in [
        ("unknown-base.yaml", "inherits: unknown printer `prusa-mk5`"),
        ("cycle-a.yaml", "inherits, directly or not, from itself"),
        ("bad-key.yaml", "unknown field `lenght`"),
    ] {
        let out = p3dp(
            &dir,
            &[
                "build",
                recipe("cup.yaml").to_str().unwrap(),
                "--printer",
                fixture(file).to_str().unwrap(),
                "-o",
                "x.gcode",
            ],
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{file}: {err}");
        assert!(err.contains(want), "{file}: {err}");
        assert!(err.contains(file), "{file}: {err}");
        assert!(!dir.join("x.gcode").exists());
    }
    let e = p3dp::testing::profile::from_file(&fixture("bad-key.yaml")).unwrap_err();
    assert_eq!(e.place.as_deref(), Some("retraction.lenght"), "{e}");
    // a --printer that names nothing is the option's mistake, not the recipe's
    for (spec, want) in [
        (
            "prusa-mk5",
            "error: --printer prusa-mk5: unknown printer `prusa-mk5`",
        ),
        (
            "missing.yaml",
            "error: --printer missing.yaml: no printer profile at `missing.yaml`",
        ),
    ] {
        let cup = recipe("cup.yaml");
        let out = p3dp(&dir, &["check", cup.to_str().unwrap(), "--printer", spec]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{spec}: {err}");
        assert!(err.starts_with(want), "{spec}: {err}");
    }
}

/// A part with every event, written for each flavour: each output passes its
/// dialect and carries that dialect's commands.
#[test]
fn events_and_firmware_retraction_in_each_dialect() {
    let fw = fixture("klipper-fw-retract.yaml");
    let cases = [
        ("generic-220", "M0 ; pause", "M109 S215", "M106 S128"),
        ("prusa-mk4", "M601 ; pause", "M109 S215", "M106 S128"),
        (
            "voron-350",
            "PAUSE ; resume",
            "TEMPERATURE_WAIT SENSOR=extruder MINIMUM=215",
            "M106 S128",
        ),
        ("rostock-max", "M226 ; pause", "M116 P0", "M106 S0.50"),
        (
            fw.to_str().unwrap(),
            "PAUSE",
            "SET_HEATER_TEMPERATURE HEATER=extruder TARGET=215",
            "M106 S128",
        ),
    ];
    for (printer, pause, heat, fan) in cases {
        let opts = Options {
            printer: Some(printer.to_string()),
            ..Default::default()
        };
        let mut pl = plan(&recipe("sphere.yaml"), &opts).unwrap();
        let mut tp = Toolpath::new(DVec3::new(0.0, 0.0, 0.2));
        for k in 0..40 {
            if k == 10 {
                tp.event(Event::Pause);
                tp.event(Event::NozzleTemp {
                    celsius: 215.0,
                    wait: true,
                });
                tp.event(Event::BedTemp {
                    celsius: 55.0,
                    wait: true,
                });
                tp.event(Event::Fan { speed: 0.5 });
                tp.event(Event::Dwell { ms: 500.0 });
                tp.event(Event::Retract);
            }
            if k == 20 {
                tp.travel(DVec3::new(10.0, 10.0, 0.2), 100.0);
            } else {
                let a = k as f64 * 0.3;
                tp.draw(DVec3::new(8.0 * a.cos(), 8.0 * a.sin(), 0.2), 0.1, 30.0);
            }
        }
        tp.event(Event::Fan { speed: 0.0 });
        tp.name = "events".into();
        pl.set_paths(vec![tp]).unwrap();
        let job = p3dp::pipeline::Job::default();
        let bytes = p3dp::pipeline::write(&mut pl, &job, Vec::new())
            .unwrap()
            .out;
        let text = String::from_utf8(bytes).unwrap();
        check_dialect(&text, pl.recipe().printer.flavor.name());
        for want in [pause, heat, fan] {
            assert!(text.contains(want), "{printer}: no `{want}` in\n{text}");
        }
        let fw = pl.recipe().printer.firmware_retraction;
        assert_eq!(text.contains("G10 ; retract"), fw, "{printer}");
        assert_eq!(text.contains("G11 ; unretract"), fw, "{printer}");
        if fw {
            assert!(
                !text.lines().any(|l| l.starts_with("G1 E")),
                "{printer}: an E-only move"
            );
        }
    }
}

// -------------------------------------------------------------------- arcs

/// The extruding strings of a plan, in print order, machine coordinates.
fn strings(paths: &[Toolpath], printer: &Printer) -> Vec<(DVec3, DVec3)> {
    let mut out = Vec::new();
    for tp in paths {
        for k in 0..tp.len() {
            if !tp.strings[k].travel {
                let (a, b) = tp.ends(k);
                out.push((printer.to_machine(a), printer.to_machine(b)));
            }
        }
    }
    out
}

fn point_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// Filament of the moves that move the head (retractions left out).
fn filament(text: &str) -> f64 {
    let from = text.find("; part:").unwrap();
    moves(&text[from..])
        .iter()
        .filter(|m| m.from != m.to)
        .map(|m| m.de)
        .sum()
}

/// Builds `recipe_name` with and without arcs; checks that every arc stays
/// within the tolerance of the original strings (followed in order), the
/// filament is the same, and returns (plain bytes, arc bytes).
fn arcs_follow_the_strings(recipe_name: &str, profile: &str) -> (usize, usize) {
    let opts = |p: &str| Options {
        printer: Some(p.to_string()),
        ..Default::default()
    };
    let mut arcs = plan(
        &recipe(recipe_name),
        &opts(fixture(profile).to_str().unwrap()),
    )
    .unwrap();
    let printer = &arcs.recipe().printer.clone();
    assert!(printer.arcs);
    let mut plain = arcs.clone();
    plain.recipe_mut().printer.arcs = false;
    let job = p3dp::pipeline::Job::default();
    let a = p3dp::pipeline::write(&mut arcs, &job, Vec::new()).unwrap();
    let p = p3dp::pipeline::write(&mut plain, &job, Vec::new()).unwrap();
    let (a_bytes, a_stats, p_bytes, p_stats) = (a.out, a.stats, p.out, p.stats);
    let (a_text, p_text) = (
        String::from_utf8(a_bytes).unwrap(),
        String::from_utf8(p_bytes).unwrap(),
    );
    check_dialect(&a_text, printer.flavor.name());
    assert_inside(&a_text, printer, recipe_name);

    // the same filament, in the G-code and in the stats
    let (fa, fp) = (filament(&a_text), filament(&p_text));
    assert!((fa - fp).abs() <= 1e-6 * fp, "{recipe_name}: {fa} vs {fp}");
    assert!(
        (a_stats.filament_length_mm - p_stats.filament_length_mm).abs()
            <= 1e-6 * p_stats.filament_length_mm
    );
    assert!(
        (a_stats.extrude_length_mm - p_stats.extrude_length_mm).abs()
            <= 1e-3 * p_stats.extrude_length_mm
    );

    // every arc within the tolerance of the strings, in order (each sample
    // near the first string from the previous sample's on: passes of a
    // helix lie far more than the tolerance apart); µm rounding of the
    // written ends and centre adds a little
    let segs = strings(arcs.paths(), printer);
    let tol = printer.arc_tolerance + 0.003;
    let mut cur = 0;
    let mut n_arcs = 0;
    for m in moves(&a_text) {
        if m.g < 2 {
            continue;
        }
        n_arcs += 1;
        for p in m.samples(32) {
            let mut best = f64::INFINITY;
            let near = segs
                .iter()
                .enumerate()
                .skip(cur)
                .take(4000)
                .find(|(_, (a, b))| {
                    let d = point_segment(p, *a, *b);
                    best = best.min(d);
                    d <= tol
                });
            let Some((at, _)) = near else {
                panic!("{recipe_name}: arc {m:?} leaves the strings by {best} mm at {p}");
            };
            cur = at;
        }
    }
    assert!(n_arcs > 0, "{recipe_name}: no arcs");
    (p_text.len(), a_text.len())
}

#[test]
fn arcs_shrink_the_globe_and_the_cup_and_follow_their_strings() {
    let (plain, arcs) = arcs_follow_the_strings("globe.yaml", "arcs.yaml");
    assert!(plain > 10 * arcs, "globe: {plain} → {arcs} bytes");
    let (plain, arcs) = arcs_follow_the_strings("cup.yaml", "arcs.yaml");
    assert!(plain > 5 * arcs, "cup: {plain} → {arcs} bytes");
    let (plain, arcs) = arcs_follow_the_strings("sphere.yaml", "arcs.yaml");
    assert!(plain > 5 * arcs, "sphere: {plain} → {arcs} bytes");
    // the delta: arcs in RepRapFirmware's dialect, inside the round bed, none
    // of a radius under 5 mm (taken as cut into 1 mm chords, see flavor.rs)
    let (plain, arcs) = arcs_follow_the_strings("globe.yaml", "arcs-rostock.yaml");
    assert!(
        plain > 5 * arcs,
        "globe on the delta: {plain} → {arcs} bytes"
    );
}

#[test]
fn arcs_are_off_by_default_and_deterministic() {
    for name in PROFILES {
        assert!(
            !p3dp::testing::profile::built_in(name).unwrap().arcs,
            "{name}"
        );
    }
    let a = build("globe.yaml", fixture("arcs.yaml").to_str().unwrap());
    let b = build("globe.yaml", fixture("arcs.yaml").to_str().unwrap());
    assert_eq!(a, b);
    assert!(a.contains("; arcs: G2/G3 within 0.025 mm"));
}

// ---------------------------------------------------------------- the fan

/// The cup with `material:` replaced by `material`, built to G-code text
/// (`Err` with stderr when the build fails).
fn cup_with(material: &str, tag: &str) -> Result<String, String> {
    let dir = tmp(&format!("machines-fan-{tag}"));
    let text = std::fs::read_to_string(recipe("cup.yaml")).unwrap();
    let text = text.replace("material: pla", &format!("material: {material}"));
    assert!(text.contains(material));
    std::fs::write(dir.join("cup.yaml"), text).unwrap();
    let out = p3dp(&dir, &["build", "cup.yaml", "-o", "cup.gcode"]);
    let r = if out.status.success() {
        Ok(std::fs::read_to_string(dir.join("cup.gcode")).unwrap())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).to_string())
    };
    let _ = std::fs::remove_dir_all(&dir);
    r
}

/// (line index, S value) of every `M106`, and the Z of the extruding move
/// that follows each, read as the firmware would.
fn fans(text: &str) -> Vec<(usize, String, f64)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        if let Some(rest) = l.strip_prefix("M106 ") {
            let s = rest.split_whitespace().next().unwrap().to_string();
            // the next G1 with E and the Z in force then
            let next = lines[i..]
                .iter()
                .position(|l| l.starts_with("G1 ") && l.contains(" E"))
                .unwrap();
            let z = lines[..i + next + 1]
                .iter()
                .rev()
                .find_map(|l| {
                    l.split_whitespace()
                        .find_map(|w| w.strip_prefix('Z'))
                        .filter(|_| l.starts_with("G0") || l.starts_with("G1"))
                })
                .unwrap()
                .parse::<f64>()
                .unwrap();
            out.push((i, s, z));
        }
    }
    out
}

#[test]
fn the_material_fan_turns_on_above_its_start_height() {
    // PLA: full fan from the first extruding move above z = 0.5 (the cup's
    // third bottom layer, at 0.6), none before, on generic-220 (bed at z = 0)
    let pla = cup_with("pla", "pla").unwrap();
    let f = fans(&pla);
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].1, "S255");
    assert!((f[0].2 - 0.6).abs() < 1e-9, "{f:?}");
    let before = common::parse(&pla.lines().take(f[0].0).collect::<Vec<_>>().join("\n"));
    assert!(before
        .moves
        .iter()
        .filter(|m| m.de > 0.0)
        .all(|m| m.to[2] <= 0.5));
    // PETG half, ABS none
    assert_eq!(fans(&cup_with("petg", "petg").unwrap())[0].1, "S128");
    assert!(fans(&cup_with("abs", "abs").unwrap()).is_empty());
    // an inline material: off unless it asks, at its own height
    let inline = "{density: 1.24, nozzle_temp: 200, bed_temp: 55, fan_speed: 0.4, fan_start_z: 10}";
    let f = fans(&cup_with(inline, "inline").unwrap());
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].1, "S102");
    assert!(f[0].2 > 10.0 && f[0].2 < 10.3, "{f:?}");
    let quiet = "{density: 1.24, nozzle_temp: 200, bed_temp: 55}";
    assert!(fans(&cup_with(quiet, "quiet").unwrap()).is_empty());
    // a fan faster than full is unusable input, named by its key
    let err = cup_with(
        "{density: 1.24, nozzle_temp: 200, bed_temp: 55, fan_speed: 2}",
        "bad",
    )
    .unwrap_err();
    assert!(err.contains("material.fan_speed"), "{err}");
}

#[test]
fn a_recipe_that_sets_the_fan_gets_no_automatic_fan() {
    // brush.yaml's turtle switches the fan on for the fibres and off after
    let text = build("brush.yaml", "generic-220");
    let fan_lines: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("M106") || l.starts_with("M107"))
        .collect();
    assert!(
        fan_lines.iter().all(|l| !l.contains("above z")),
        "{fan_lines:?}"
    );
    assert_eq!(fan_lines[0], "M107 ; fan off for the first moves");
    assert_eq!(fan_lines[1], "M106 S255 ; fan");
}

// ------------------------------------------------ the makers' own figures

/// A one-string recipe on `printer`: a string of cross-section `c` mm² at
/// `v` mm/s from `from` to `to` (recipe mm), in a material printing at
/// `nozzle` and `bed` °C (allowed up to 320 °C).
fn one_string(c: f64, v: f64, from: [f64; 3], to: [f64; 3], nozzle: f64, bed: f64) -> String {
    format!(
        "p3dp: 1\nname: figure\nmaterial: {{name: pla, density: 1.24, nozzle_temp: {nozzle}, bed_temp: {bed}, max_nozzle_temp: 320}}\nparts:\n  - name: s\n    cross_section: {c}\n    speed: {v}\n    primitive:\n      path:\n        commands:\n          - {{move: {from:?}}}\n          - {{draw: {to:?}}}\n"
    )
}

/// The codes `p3dp check` finds in `yaml` built for `printer` (the `[code]`
/// of each finding in its report).
fn check_codes(yaml: &str, printer: &str, tag: &str) -> Vec<String> {
    let dir = tmp(&format!("machines-figure-{tag}"));
    std::fs::write(dir.join("r.yaml"), yaml).unwrap();
    let out = p3dp(&dir, &["check", "r.yaml", "--printer", printer]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{tag}: {text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
    text.lines()
        .filter_map(|l| Some(l.split_once('[')?.1.split_once(']')?.0.to_string()))
        .collect()
}

/// (printer, what, c mm², v mm/s, (from, to) recipe mm, nozzle °C, bed °C,
/// code, whether the check finds it).
type FigureCase<'a> = (
    &'a str,
    &'a str,
    f64,
    f64,
    ([f64; 3], [f64; 3]),
    f64,
    f64,
    &'a str,
    bool,
);

/// Each corrected figure of a built-in that a check reads (bed, height,
/// speed, temperatures, flow), on both sides of the maker's value: the side
/// between the old figure and the maker's is refused or passed as the
/// maker's figure says (each of these cases failed with the old figure).
#[test]
fn the_checks_hold_each_built_in_to_its_makers_figure() {
    let z = |h: f64| ([0.0, 0.0, 0.2], [0.5, 0.0, h]);
    let x = |r: f64| ([r - 1.0, 0.0, 0.2], [r, 0.0, 0.2]);
    let flat = ([-5.0, 0.0, 0.2], [5.0, 0.0, 0.2]);
    // (printer, what, c, v, (from, to), nozzle °C, bed °C, code, found)
    #[rustfmt::skip]
    let cases: &[FigureCase] = &[
        // printable_height 250 (was 256): a 252 mm part is refused
        ("bambu-x1c", "z 252", 0.1, 20.0, z(252.0), 210.0, 60.0, "above-max-z", true),
        ("bambu-x1c", "z 249", 0.1, 20.0, z(249.0), 210.0, 60.0, "above-max-z", false),
        ("bambu-p1s", "z 252", 0.1, 20.0, z(252.0), 210.0, 60.0, "above-max-z", true),
        ("bambu-p1s", "z 249", 0.1, 20.0, z(249.0), 210.0, 60.0, "above-max-z", false),
        // Voron's stepper_z position_max 330 (was 340)
        ("voron-350", "z 335", 0.1, 20.0, z(335.0), 210.0, 60.0, "above-max-z", true),
        ("voron-350", "z 329", 0.1, 20.0, z(329.0), 210.0, 60.0, "above-max-z", false),
        // SeeMeCNC's M665 B135: a radius of 135 (was 140)
        ("rostock-max", "r 137", 0.1, 20.0, x(137.0), 210.0, 60.0, "out-of-bed", true),
        ("rostock-max", "r 134", 0.1, 20.0, x(134.0), 210.0, 60.0, "out-of-bed", false),
        // max speed: CORE One 350 (was 400), K1 800 (was 600), MINI 400 (was
        // 180), Ender-3 500 (was 150), Rostock 250 (was 200)
        ("prusa-core-one", "380 mm/s", 0.02, 380.0, flat, 210.0, 60.0, "speed", true),
        ("prusa-core-one", "349 mm/s", 0.02, 349.0, flat, 210.0, 60.0, "speed", false),
        ("creality-k1", "790 mm/s", 0.02, 790.0, flat, 210.0, 60.0, "speed", false),
        ("creality-k1", "810 mm/s", 0.02, 810.0, flat, 210.0, 60.0, "speed", true),
        ("prusa-mini", "390 mm/s", 0.02, 390.0, flat, 210.0, 60.0, "speed", false),
        ("prusa-mini", "410 mm/s", 0.02, 410.0, flat, 210.0, 60.0, "speed", true),
        ("ender3", "490 mm/s", 0.016, 490.0, flat, 210.0, 60.0, "speed", false),
        ("ender3", "510 mm/s", 0.016, 510.0, flat, 210.0, 60.0, "speed", true),
        ("rostock-max", "240 mm/s", 0.02, 240.0, flat, 210.0, 60.0, "speed", false),
        ("rostock-max", "260 mm/s", 0.02, 260.0, flat, 210.0, 60.0, "speed", true),
        // bed: CORE One 115 (was 120), Ender-3 115 (was 100)
        ("prusa-core-one", "bed 118", 0.1, 20.0, flat, 210.0, 118.0, "bed-temp", true),
        ("prusa-core-one", "bed 115", 0.1, 20.0, flat, 210.0, 115.0, "bed-temp", false),
        ("ender3", "bed 112", 0.1, 20.0, flat, 210.0, 112.0, "bed-temp", false),
        ("ender3", "bed 117", 0.1, 20.0, flat, 210.0, 117.0, "bed-temp", true),
        // nozzle: the Voron's [extruder] max_temp 270 (was 300)
        ("voron-350", "nozzle 275", 0.1, 20.0, flat, 275.0, 60.0, "nozzle-temp", true),
        ("voron-350", "nozzle 265", 0.1, 20.0, flat, 265.0, 60.0, "nozzle-temp", false),
        // flow (c·v): Bambu 21 (was 32 and 28), K1 23 (was 32), Ender-3 V3
        // 23 (was 24), MINI 14 (was 10), MK3S 15 (was 11)
        ("bambu-x1c", "25 mm³/s", 0.1, 250.0, flat, 210.0, 60.0, "flow", true),
        ("bambu-x1c", "20 mm³/s", 0.1, 200.0, flat, 210.0, 60.0, "flow", false),
        ("bambu-a1", "25 mm³/s", 0.1, 250.0, flat, 210.0, 60.0, "flow", true),
        ("bambu-a1-mini", "25 mm³/s", 0.1, 250.0, flat, 210.0, 60.0, "flow", true),
        ("creality-k1", "25 mm³/s", 0.1, 250.0, flat, 210.0, 60.0, "flow", true),
        ("ender3-v3", "23.5 mm³/s", 0.1, 235.0, flat, 210.0, 60.0, "flow", true),
        ("prusa-mini", "13 mm³/s", 0.1, 130.0, flat, 210.0, 60.0, "flow", false),
        ("prusa-mk3s", "14 mm³/s", 0.1, 140.0, flat, 210.0, 60.0, "flow", false),
    ];
    for (k, &(printer, what, c, v, (from, to), nozzle, bed, code, found)) in
        cases.iter().enumerate()
    {
        let codes = check_codes(
            &one_string(c, v, from, to, nozzle, bed),
            printer,
            &format!("{k}"),
        );
        assert_eq!(
            codes.iter().any(|c| c == code),
            found,
            "{printer}, {what}: `{code}` {} in {codes:?}",
            if found { "expected" } else { "not expected" }
        );
    }
}

/// The stats and the G-code of a short print built for `printer`: two
/// strings on the bed, `gap` mm of travel apart.
fn two_strings(printer: &str, gap: f64) -> (serde_json::Value, String) {
    let dir = tmp(&format!("machines-two-{printer}-{gap}"));
    let yaml = format!(
        "p3dp: 1\nname: two\nmaterial: pla\ndefaults: {{cross_section: 0.1, speed: 12}}\nparts:\n  - name: a\n    primitive:\n      path:\n        commands:\n          - {{move: [-20, 0, 0.2]}}\n          - {{draw: [-10, 0, 0.2]}}\n          - {{move: [{}, 0, 0.2]}}\n          - {{draw: [{}, 0, 0.2]}}\n",
        -10.0 + gap,
        gap
    );
    std::fs::write(dir.join("r.yaml"), yaml).unwrap();
    let out = p3dp(
        &dir,
        &[
            "build",
            "r.yaml",
            "--printer",
            printer,
            "-o",
            "r.gcode",
            "--stats-json",
            "r.json",
        ],
    );
    assert!(
        out.status.success(),
        "{printer}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stats = serde_json::from_slice(&std::fs::read(dir.join("r.json")).unwrap()).unwrap();
    let text = std::fs::read_to_string(dir.join("r.gcode")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    (stats, text)
}

/// The number after letter `c` in G-code line `l`.
fn word(l: &str, c: char) -> Option<f64> {
    l.split(';')
        .next()?
        .split_whitespace()
        .find(|w| w.starts_with(c))?[1..]
        .parse()
        .ok()
}

/// The parts' retractions: (length, F mm/min) of the first, from its
/// `; retract` line and the `; unretract` after it (absolute E: their
/// difference), and how many there are.
fn retractions(text: &str) -> (Option<(f64, f64)>, usize) {
    let from = text.find("; part: ").unwrap_or(0);
    let lines: Vec<&str> = text[from..].lines().collect();
    let n = lines.iter().filter(|l| l.ends_with("; retract")).count();
    let Some(k) = lines.iter().position(|l| l.ends_with("; retract")) else {
        return (None, 0);
    };
    let re = word(lines[k], 'E').unwrap();
    let back = lines[k..]
        .iter()
        .find(|l| l.ends_with("; unretract"))
        .unwrap();
    let ue = word(back, 'E').unwrap();
    // the writer's own mode line, after the start G-code's
    let len = if text.lines().any(|l| l == "M83 ; relative extrusion") {
        -re
    } else {
        ue - re
    };
    (Some((len, word(lines[k], 'F').unwrap())), n)
}

/// (printer, [(planner key, value)], retraction (mm, F mm/min), travel F
/// mm/min, relative E).
type WriterCase<'a> = (&'a str, &'a [(&'a str, f64)], (f64, f64), f64, bool);

/// The planner's figures (what the estimate used, the stats' `planner`),
/// the retraction and the travel feed (the G-code's) and the E mode of
/// each built-in, as its maker's presets and firmware give them (each
/// printer had at least one of them different before).
#[test]
fn the_planner_and_the_writer_take_each_built_in_s_makers_figures() {
    let jd = |jerk: f64, accel: f64| 0.4 * jerk * jerk / accel;
    // (printer, [(planner key, value)], retraction (mm, F mm/min), travel
    // F mm/min, relative E)
    #[rustfmt::skip]
    let cases: &[WriterCase] = &[
        ("bambu-x1c", &[("max_acceleration", 20000.0), ("travel_acceleration", 9000.0), ("retract_acceleration", 5000.0), ("junction_deviation", jd(9.0, 20000.0)), ("max_z_velocity", 20.0), ("max_z_acceleration", 500.0)], (0.8, 1800.0), 30000.0, true),
        ("bambu-p1s", &[("travel_acceleration", 9000.0), ("junction_deviation", jd(9.0, 20000.0))], (0.8, 1800.0), 30000.0, true),
        ("bambu-a1", &[("max_acceleration", 12000.0), ("travel_acceleration", 9000.0), ("junction_deviation", jd(9.0, 12000.0)), ("max_z_velocity", 30.0), ("max_z_acceleration", 1500.0)], (0.8, 1800.0), 30000.0, true),
        ("bambu-a1-mini", &[("max_acceleration", 20000.0), ("travel_acceleration", 9000.0), ("max_z_velocity", 30.0), ("max_z_acceleration", 1500.0)], (0.8, 1800.0), 30000.0, true),
        ("prusa-core-one", &[("max_velocity", 350.0), ("max_acceleration", 7000.0), ("travel_acceleration", 7000.0), ("retract_acceleration", 2500.0), ("junction_deviation", 0.01), ("max_z_velocity", 12.0), ("max_z_acceleration", 400.0)], (0.7, 2700.0), 21000.0, true),
        ("prusa-mk4s", &[("max_acceleration", 4000.0), ("travel_acceleration", 4000.0), ("retract_acceleration", 2500.0), ("max_z_velocity", 40.0), ("max_z_acceleration", 200.0)], (0.7, 2100.0), 18000.0, true),
        ("prusa-mk4", &[("max_acceleration", 4000.0), ("travel_acceleration", 4000.0), ("retract_acceleration", 2500.0), ("max_z_velocity", 40.0)], (0.7, 2100.0), 18000.0, true),
        ("prusa-mini", &[("max_velocity", 400.0), ("max_acceleration", 4000.0), ("travel_acceleration", 4000.0), ("retract_acceleration", 1250.0), ("junction_deviation", jd(8.0, 4000.0))], (2.5, 4200.0), 24000.0, true),
        ("prusa-mk3s", &[("junction_deviation", jd(8.0, 1250.0))], (0.8, 2100.0), 10800.0, true),
        ("creality-k1", &[("max_velocity", 800.0), ("minimum_cruise_ratio", 0.0), ("max_z_velocity", 20.0), ("max_z_acceleration", 300.0)], (0.8, 2400.0), 30000.0, true),
        ("ender3-v3", &[("max_velocity", 600.0), ("max_z_velocity", 500.0), ("max_z_acceleration", 500.0)], (0.8, 2400.0), 30000.0, true),
        ("ender3", &[("max_velocity", 500.0), ("max_acceleration", 500.0), ("junction_deviation", 0.08)], (6.0, 2400.0), 7200.0, true),
        ("voron-350", &[("max_velocity", 300.0), ("max_acceleration", 3000.0), ("minimum_cruise_ratio", 0.5)], (0.8, 1800.0), 18000.0, true),
        ("rostock-max", &[("max_velocity", 250.0), ("max_acceleration", 3400.0), ("junction_deviation", jd(8.333, 3400.0)), ("max_z_velocity", 250.0), ("max_z_acceleration", 3400.0)], (3.0, 2400.0), 9000.0, false),
    ];
    for &(printer, planner, (len, f), travel, relative) in cases {
        let (stats, text) = two_strings(printer, 20.0);
        for &(key, want) in planner {
            let got = stats["planner"][key].as_f64().unwrap_or(f64::NAN);
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                "{printer}: planner {key} {got}, want {want}"
            );
        }
        let (first, _) = retractions(&text);
        let (rl, rf) = first.unwrap_or_else(|| panic!("{printer}: no retraction"));
        assert!(
            (rl - len).abs() < 1e-9 && rf == f,
            "{printer}: retraction {rl} mm at F{rf}, want {len} at F{f}"
        );
        let g0 = text
            .lines()
            .skip_while(|l| !l.ends_with("; retract"))
            .find(|l| l.starts_with("G0 X"))
            .unwrap_or_else(|| panic!("{printer}: no travel after the retraction"));
        assert_eq!(word(g0, 'F'), Some(travel), "{printer}: {g0}");
        // the writer's E mode (a start G-code may set M83 for its purge)
        assert_eq!(
            text.lines().any(|l| l == "M83 ; relative extrusion"),
            relative,
            "{printer}: M83"
        );
        assert_eq!(
            text.lines().any(|l| l == "M82 ; absolute extrusion"),
            !relative,
            "{printer}: M82"
        );
    }
}

/// Prusa's retract_before_travel 1.5 (was 1): a 1.2 mm travel is no longer
/// retracted on the MK4S, the CORE One, the MK4 and the MINI; a 1.8 mm one is.
#[test]
fn prusa_retracts_only_before_travel_of_1_5_mm() {
    for printer in ["prusa-mk4s", "prusa-core-one", "prusa-mk4", "prusa-mini"] {
        assert_eq!(retractions(&two_strings(printer, 1.2).1).1, 0, "{printer}");
        assert_eq!(retractions(&two_strings(printer, 1.8).1).1, 1, "{printer}");
    }
}
