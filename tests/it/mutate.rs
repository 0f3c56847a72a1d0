//! Mutated gallery recipes (issue 17): a seeded mutation loop, on the stable
//! toolchain, that keeps hostile input from panicking.
//!
//! Every recipe of `recipes/` is mutated a few hundred times (numbers made
//! hostile, lines deleted, doubled, swapped or re-indented, brackets, control
//! characters and aliases inserted, the text cut short). Each mutant is
//! loaded and resolved in process, and built and checked when it is small;
//! it must not panic, and an error must name the file and a place (a line or
//! a key path). A sample of the refused mutants is also run through the
//! binary: exit status 2, the file named, nothing written.
//!
//! `P3DP_MUTANTS=N` sets the mutants per recipe (default 200), and
//! `P3DP_MUTATE_SEED=S` the seed.
//!
//! Past the public face only for the budget: the mutant's string count
//! before building (`Primitive::string_count` off `Recipe::parts`). It runs
//! the binary too, so it stays an integration test: a public string count
//! of a loaded recipe would bring it back to the public modules.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use crate::common::*;
use p3dp::{plan, Options};
use p3dp::testing::Recipe;

/// xorshift64*: a small seeded generator, so a failure can be replayed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a>(&mut self, xs: &[&'a str]) -> &'a str {
        xs[self.below(xs.len())]
    }
}

const NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1e300",
    "-1e300",
    "1e-300",
    "1e-320",
    ".nan",
    ".inf",
    "-.inf",
    "1e9",
    "4294967296",
    "18446744073709551616",
    "0.0000001",
    "\"1/0\"",
    "\"x\"",
    "\"-----------1\"",
    "\"max()\"",
    "[]",
    "{}",
    "~",
];

const LINES: &[&str] = &[
    "  x: [[[[[[[[",
    "name: \"a\\nM109 S450\"",
    "max_strings: 0",
    "max_strings: 1e12",
    "- *nope",
    "  - &a {helix: {radius: 1, height: 1, pitch: 1}}",
    "---",
    "printer: /dev/null",
    "printer: ../recipes",
    "material: {density: 1, nozzle_temp: 900, bed_temp: 0}",
    "skirt: {distance: 1e300, loops: 1000}",
    "    steps: [{subdivide: {max_length: 1e-300}}]",
    "\t",
    "\u{feff}",
    "? [a, b]\n: c",
    "params: {a: 1, a: 2}",
    "allow: [nope]",
];

const CHARS: &[&str] = &[
    "[", "]", "{", "}", ":", ",", "-", "#", "&", "*", "!", "|", ">", "'", "\"", "\\", "%", "@",
    "\0", "\r", "\u{2028}", "é", "0", "9", ".", "e", " ",
];

/// Byte offsets of the numbers (runs of digits, `.`, `e`, `-`) in `text`.
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut k = 0;
    while k < b.len() {
        let starts = b[k].is_ascii_digit() && (k == 0 || !b[k - 1].is_ascii_alphanumeric());
        if starts {
            let s = k;
            while k < b.len() && (b[k].is_ascii_digit() || b[k] == b'.' || b[k] == b'e') {
                k += 1;
            }
            out.push((s, k));
        } else {
            k += 1;
        }
    }
    out
}

/// The nearest char boundary at or before `k`.
fn boundary(text: &str, mut k: usize) -> usize {
    k = k.min(text.len());
    while !text.is_char_boundary(k) {
        k -= 1;
    }
    k
}

/// One mutation of `text`.
fn mutate_once(text: &str, rng: &mut Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        return format!("{text}{}", rng.pick(LINES));
    }
    let n = lines.len();
    match rng.below(9) {
        0 | 1 => {
            let nums = numbers(text);
            if nums.is_empty() {
                return text.to_string();
            }
            let (s, e) = nums[rng.below(nums.len())];
            format!("{}{}{}", &text[..s], rng.pick(NUMBERS), &text[e..])
        }
        2 => {
            lines.remove(rng.below(n));
            lines.join("\n")
        }
        3 => {
            let k = rng.below(lines.len());
            let l = lines.get(k).cloned().unwrap_or_default();
            lines.insert(k, l);
            lines.join("\n")
        }
        4 => {
            lines.insert(rng.below(n + 1), rng.pick(LINES).to_string());
            lines.join("\n")
        }
        5 => {
            let k = boundary(text, rng.below(text.len() + 1));
            text[..k].to_string()
        }
        6 => {
            let k = boundary(text, rng.below(text.len() + 1));
            format!("{}{}{}", &text[..k], rng.pick(CHARS), &text[k..])
        }
        7 => {
            let (a, b) = (rng.below(lines.len()), rng.below(lines.len()));
            if a < lines.len() && b < lines.len() {
                lines.swap(a, b);
            }
            lines.join("\n")
        }
        _ => {
            let k = rng.below(lines.len());
            if let Some(l) = lines.get_mut(k) {
                if rng.below(2) == 0 {
                    l.insert_str(0, "  ");
                } else if let Some(r) = l.strip_prefix("  ") {
                    *l = r.to_string();
                }
            }
            lines.join("\n")
        }
    }
}

fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut t = text.to_string();
    for _ in 0..1 + rng.below(3) {
        t = mutate_once(&t, rng);
    }
    t
}

/// Parts of the mutant small enough to build and check quickly.
const BUILD_STRINGS: u64 = 5_000;

/// The `max_strings` given to each recipe before it is mutated.
const MUTANT_MAX_STRINGS: u64 = 500_000;

/// Every how many mutants of a recipe one is built and checked too (a debug
/// build of a gallery recipe takes up to seconds; loading, milliseconds).
const BUILD_EVERY: usize = 25;

/// What went wrong with one mutant, if anything.
fn try_mutant(path: &Path, build: bool) -> Result<Option<p3dp::Error>, String> {
    let shown = path.display().to_string();
    let loaded = catch_unwind(AssertUnwindSafe(|| p3dp::testing::load_recipe(path, &[], None)))
        .map_err(|_| "panicked while loading".to_string())?;
    let err = match loaded {
        Err(e) => Some(e),
        Ok(r) => {
            let strings: u64 = r.parts.iter().map(|p| p.primitive.string_count()).sum();
            if !build || strings > BUILD_STRINGS {
                None
            } else {
                let built = catch_unwind(AssertUnwindSafe(|| {
                    plan(path, &Options::default())
                        .and_then(|mut p| {
                            let job = p3dp::pipeline::Job::default();
                            p3dp::pipeline::write(&mut p, &job, std::io::sink()).map(|_| ())
                        })
                }))
                .map_err(|_| "panicked while building".to_string())?;
                built.err()
            }
        }
    };
    if let Some(e) = &err {
        if e.kind != p3dp::Kind::Check {
            if e.file.is_none() {
                return Err(format!("the error names no file: {e}"));
            }
            // the file is the recipe or one it reads (an include, a profile)
            let file = e.file.as_deref().unwrap_or(&shown);
            if e.line.is_none() && e.place.is_none() && !e.to_string().starts_with(file) {
                return Err(format!("the error names no place: {e}"));
            }
            // an empty or comments-only file: the place is the whole file
            let whole_file = e.message.starts_with("the file is empty")
                || e.message.starts_with("the file has only comments");
            if e.line.is_none() && e.place.is_none() && !whole_file {
                return Err(format!("the error names no line nor key: {e}"));
            }
        }
    }
    Ok(err)
}

/// `dir` made a copy of the gallery's project: `maps/`, the drawings and
/// included files beside the recipes in `recipes/`, and a `p3dp.lock` that
/// marks `dir` as the project's top (so `../maps/` may be read).
fn gallery_project(dir: &Path) {
    let rdir = dir.join("recipes");
    std::fs::create_dir_all(&rdir).unwrap();
    std::fs::create_dir_all(dir.join("maps")).unwrap();
    for e in std::fs::read_dir(root().join("maps")).unwrap().flatten() {
        std::fs::copy(e.path(), dir.join("maps").join(e.file_name())).unwrap();
    }
    for e in std::fs::read_dir(root().join("recipes")).unwrap().flatten() {
        std::fs::copy(e.path(), rdir.join(e.file_name())).unwrap();
    }
    std::fs::write(dir.join("p3dp.lock"), "p3dp_lock: 1\nentries: []\n").unwrap();
}

/// The files a recipe reaches, mutated in place (issue 33): an included
/// library (`plate-sampler.yaml` → `plate.yaml` → `cup.yaml`), the SVG of
/// `star-vase.yaml`, and a printer profile that inherits a built-in one.
/// The recipe that reads each is loaded (and built now and then): no
/// panic, and every error names a file and a place.
#[test]
fn mutated_includes_drawings_and_profiles_never_panic() {
    let per_file: usize = std::env::var("P3DP_MUTANTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(150);
    let dir = tmp("mutate-reached");
    gallery_project(&dir);
    let rdir = dir.join("recipes");
    let profile = format!(
        "inherits: generic-220\n{}",
        std::fs::read_to_string(root().join("src/machine/printers/prusa-mk4.yaml")).unwrap()
    );
    std::fs::write(rdir.join("mine.yaml"), &profile).unwrap();
    let with_profile = std::fs::read_to_string(rdir.join("sphere.yaml"))
        .unwrap()
        .replacen("\nparts:", "\nprinter: mine.yaml\nparts:", 1);
    std::fs::write(rdir.join("sphere-mine.yaml"), with_profile).unwrap();
    let cases = [
        ("cup.yaml", "plate-sampler.yaml"),
        ("plate.yaml", "plate-sampler.yaml"),
        ("star.svg", "star-vase.yaml"),
        ("mine.yaml", "sphere-mine.yaml"),
    ];
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let mut problems = Vec::new();
    for (file, recipe) in cases {
        let original = std::fs::read_to_string(rdir.join(file)).unwrap();
        for k in 0..per_file {
            let mutant = mutate(&original, &mut rng);
            std::fs::write(rdir.join(file), &mutant).unwrap();
            if let Err(m) = try_mutant(&rdir.join(recipe), k % BUILD_EVERY == 0) {
                problems.push(format!("{file} of {recipe}: {m}\n--- mutant ---\n{mutant}"));
            }
        }
        std::fs::write(rdir.join(file), &original).unwrap();
    }
    assert!(
        problems.is_empty(),
        "{} mutants went wrong:\n\n{}",
        problems.len(),
        problems.join("\n\n")
    );
}

#[test]
fn mutated_gallery_recipes_never_panic_and_errors_have_places() {
    let per_recipe: usize = std::env::var("P3DP_MUTANTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200);
    let seed: u64 = std::env::var("P3DP_MUTATE_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x9e37_79b9_7f4a_7c15);
    let dir = tmp("mutate");
    let rdir = dir.join("recipes");
    std::fs::create_dir_all(&rdir).unwrap();
    gallery_project(&dir);
    let mut gallery: Vec<PathBuf> = std::fs::read_dir(root().join("recipes"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    gallery.sort();
    let start = std::time::Instant::now();
    let mut rng = Rng(seed);
    let mut problems = Vec::new();
    let mut refused: Vec<(PathBuf, String)> = Vec::new();
    let (mut ok, mut errors) = (0, 0);
    let mut slow = Vec::new();
    for g in &gallery {
        let mut text = std::fs::read_to_string(g).unwrap();
        // a tighter string limit bounds the work of any mutant (a turtle
        // looping until the default 50 million takes 20 s in a debug build)
        if !text.contains("\nmax_strings:") {
            text = text.replacen(
                "\nparts:",
                &format!("\nmax_strings: {MUTANT_MAX_STRINGS}\nparts:"),
                1,
            );
        }
        let stem = g.file_stem().unwrap().to_string_lossy().into_owned();
        for k in 0..per_recipe {
            let mutant = mutate(&text, &mut rng);
            let path = rdir.join(format!("{stem}-{k}.yaml"));
            std::fs::write(&path, &mutant).unwrap();
            let t = std::time::Instant::now();
            let result = try_mutant(&path, k % BUILD_EVERY == 0);
            if t.elapsed().as_millis() > 300 {
                slow.push(format!("{:?} {}", t.elapsed(), path.display()));
                let _ = std::fs::copy(&path, dir.join(format!("slow-{stem}-{k}.yaml")));
            }
            match result {
                Ok(None) => {
                    ok += 1;
                    let _ = std::fs::remove_file(&path);
                }
                Ok(Some(e)) => {
                    errors += 1;
                    if e.kind != p3dp::Kind::Check
                        && refused.len() < 2 * gallery.len()
                        && k % 50 == 0
                    {
                        refused.push((path, e.to_string()));
                    } else {
                        let _ = std::fs::remove_file(&path);
                    }
                }
                Err(m) => {
                    problems.push(format!("{}: {m}\n--- mutant ---\n{mutant}", path.display()))
                }
            }
        }
    }
    for s in &slow {
        println!("slow: {s}");
    }
    println!(
        "{} mutants of {} recipes: {ok} accepted, {errors} refused, {} problems, {:?}",
        per_recipe * gallery.len(),
        gallery.len(),
        problems.len(),
        start.elapsed()
    );
    assert!(
        problems.is_empty(),
        "{} mutants went wrong:\n\n{}",
        problems.len(),
        problems.join("\n\n")
    );
    // a sample of the refused ones through the binary: exit 2, file named, nothing written
    let out_dir = dir.join("out");
    std::fs::create_dir_all(&out_dir).unwrap();
    for (path, msg) in &refused {
        let out = p3dp(
            &rdir,
            &[
                "build",
                path.to_str().unwrap(),
                "-o",
                out_dir.join("m.gcode").to_str().unwrap(),
                "--stats-json",
                out_dir.join("m.json").to_str().unwrap(),
            ],
        );
        let e = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{}: {msg}\n{e}", path.display());
        assert!(
            e.contains(path.file_name().unwrap().to_str().unwrap()),
            "{}: {e}",
            path.display()
        );
        let left: Vec<_> = std::fs::read_dir(&out_dir).unwrap().flatten().collect();
        assert!(left.is_empty(), "{}: left {left:?}", path.display());
    }
}
