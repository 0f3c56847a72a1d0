//! `p3dp hash`: the SHA-256 of exactly what `build` writes; lock files
//! written and checked, a change located to its first differing lines.

use std::io::Write;
use std::path::{Component, Path, PathBuf};

use super::{non_empty, Builds};
use crate::app::batch::{self, Job};
use crate::app::pipeline;
use crate::base::error::{Error, Result};
use crate::base::input::Reads;
use crate::base::safe_text::one_line;
use crate::output::file::{write_atomic, HashWriter};
use crate::output::lock::{self, Entry, LineHashes, Lock};
use crate::recipe::{parse_set, parse_yaml};

/// What `hash` takes from the command line.
#[derive(Clone, Debug, Default)]
pub(crate) struct Options {
    /// The recipes and how each is built.
    pub(crate) builds: Builds,
    /// `--lock FILE`: write the hashes there.
    pub(crate) lock: Option<PathBuf>,
    /// `--check FILE`: rebuild every entry of this lock file.
    pub(crate) check: Option<PathBuf>,
}

/// Builds a job on `threads` into nothing but its hash and line fingerprint.
/// The fingerprints of `jobs`, built in parallel within `-j`'s budget.
/// `outs`: the lock file written, if any (no recipe may read it).
fn fingerprints(
    c: &Builds,
    jobs: &[Job],
    outs: &[(String, PathBuf)],
) -> Vec<Result<(String, LineHashes)>> {
    batch::run_parallel(jobs.len(), |k| fingerprint(c, &jobs[k], outs), || {})
}

fn fingerprint(c: &Builds, job: &Job, outs: &[(String, PathBuf)]) -> Result<(String, LineHashes)> {
    // nothing is written: the G-code is hashed while the checks run
    let mut p = c.prepared(job, outs)?;
    // stamped as `build` stamps it (SOURCE_DATE_EPOCH's date)
    let job = pipeline::Job {
        hash: false,
        ..c.job(super::stamp()?)
    };
    let written = pipeline::write(&mut p, &job, HashWriter::new(LineHashes::default()));
    c.refuse_failing(&p)?;
    let hw = written?.out;
    let (digest, _, lines) = hw.finish_into();
    Ok((digest, lines))
}

/// `p3dp hash`: prints `SHA256  RECIPE`, the hash of exactly what `build` writes;
/// with `--lock` writes a lock file, with `--check` verifies one.
pub(crate) fn run(a: &Options) -> Vec<Error> {
    if a.builds.filament.is_some() && (a.lock.is_some() || a.check.is_some()) {
        // a lock entry records the recipe, its --set values and its printer
        return vec![Error::input(
            "--filament",
            "a lock records no filament preset; hash with --filament without --lock or --check",
        )];
    }
    if let Some(lockfile) = &a.check {
        return check_lock(a, lockfile);
    }
    let c = &a.builds;
    let jobs = match c.jobs() {
        Ok(j) => j,
        Err(e) => return vec![e],
    };
    let outs: Vec<(String, PathBuf)> = a
        .lock
        .iter()
        .map(|l| ("--lock".to_string(), l.clone()))
        .collect();
    if let Some(lockfile) = &a.lock {
        if let Err(e) = non_empty("--lock", Some(lockfile))
            .and_then(|_| crate::output::file::check_distinct(&outs, &c.inputs()))
            .and_then(|_| lockable(lockfile, c, &jobs))
        {
            return vec![e];
        }
    }
    let results = fingerprints(c, &jobs, &outs);
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
        // an existing lock keeps its other entries: a build given again
        // (same recipe, --set values and printer) replaces its own entry
        let entries = match merge(lockfile, entries) {
            Ok(e) => e,
            Err(e) => return vec![e],
        };
        let lock = Lock {
            p3dp_lock: 1,
            entries,
        };
        let text = format!(
            "# p3dp lock file: each recipe's G-code hash. Verify with: p3dp hash --check {}\n# An intended change of output is a commit that updates this file and says why.\n{}",
            lockfile.display(),
            crate::recipe::yaml::to_yaml(&lock)
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

/// Refuses to write a lock `hash --check` would refuse: a recipe or
/// profile outside the lock's project and `--allow-read`.
fn lockable(lockfile: &Path, c: &Builds, jobs: &[Job]) -> Result<()> {
    let roots = LockRoots::new(&lock_folder(lockfile), &c.allow_read);
    let printer = c
        .printer
        .as_deref()
        .filter(|p| crate::recipe::profile::built_in(p).is_none());
    for job in jobs {
        let shown = job.recipe.display().to_string();
        roots.confine(&job.recipe, &shown, "recipe", "--lock")?;
    }
    if let Some(p) = printer {
        roots.confine(Path::new(p), p, "printer profile", "--lock")?;
    }
    Ok(())
}

/// The entries of the lock at `lockfile` (none when there is no file) with
/// `new` merged in: an entry of the same recipe, `--set` values and printer
/// replaced where it stands, the others appended in order. A file that is
/// not a lock is refused, not overwritten.
fn merge(lockfile: &Path, new: Vec<Entry>) -> Result<Vec<Entry>> {
    if !lockfile.exists() {
        return Ok(new);
    }
    let shown = lockfile.display().to_string();
    let old = crate::base::input::read_text(lockfile, "lock file")
        .and_then(|text| parse_yaml::<Lock>(&text, &shown))
        .and_then(|l| l.validate().map(|_| l))
        .map_err(|e| {
            e.in_file(&shown).with_help(
                "--lock adds to an existing lock file; this one cannot be read as one: give another path, or remove it to start a new lock",
            )
        })?;
    let same =
        |a: &Entry, b: &Entry| a.recipe == b.recipe && a.set == b.set && a.printer == b.printer;
    let mut entries = old.entries;
    for e in new {
        match entries.iter_mut().find(|o| same(o, &e)) {
            Some(o) => *o = e,
            None => entries.push(e),
        }
    }
    Ok(entries)
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
            if crate::recipe::profile::built_in(p).is_some() {
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

fn check_lock(a: &Options, lockfile: &Path) -> Vec<Error> {
    let (lock, jobs) = match read_lock(lockfile, &a.builds.allow_read) {
        Ok(l) => l,
        Err(e) => return vec![e],
    };
    let c = &a.builds;
    let results = fingerprints(c, &jobs, &[]);
    let mut errors = Vec::new();
    let mut changed = 0;
    for ((entry, job), r) in lock.entries.iter().zip(&jobs).zip(results) {
        let mut label = entry.recipe.clone();
        if !entry.set.is_empty() {
            label.push_str(&format!(" [{}]", entry.set.join(" ")));
        }
        if let Some(p) = &entry.printer {
            label.push_str(&format!(" (printer {p})"));
        }
        match r {
            Ok((digest, _)) if digest == entry.sha256 => {}
            Ok((digest, lines)) => {
                let new = lines.blocks(entry.block_lines);
                let place = match lock::first_difference(&entry.blocks, &new) {
                    Some(k) => {
                        let all = new_lines(c, job, 0, u64::MAX);
                        // the fingerprint's lines (no thumbnail's), numbered as in the file
                        let mut pictures = lock::Thumbnails::default();
                        let kept: Vec<usize> = (0..all.len())
                            .filter(|&i| !pictures.part(all[i].as_bytes()))
                            .collect();
                        let from = k * entry.block_lines as usize;
                        let block: Vec<(usize, &str)> = kept
                            .iter()
                            .skip(from)
                            .take(entry.block_lines as usize)
                            .map(|&i| (i + 1, all[i].as_str()))
                            .collect();
                        let first = kept.get(from).copied().unwrap_or(all.len());
                        let at = part_at(&all, first);
                        if entry.block_lines == 1 {
                            let text = block.first().map_or("(end of file)", |l| l.1);
                            format!("{at}first differing line {}: `{text}`", first + 1)
                        } else {
                            format!("{at}{}", changed_block(first as u64 + 1, entry.block_lines, &block))
                        }
                    }
                    None => "the lines hash alike block by block, thumbnails left out: its thumbnails changed (or the hashes collide)".into(),
                };
                // only what changed is shown, with both whole hashes
                changed += 1;
                // a lock's text reaches the terminal escaped, on one line
                crate::sayln!(
                    "CHANGED  {}\n         was {}\n         now {digest}",
                    one_line(&label),
                    entry.sha256
                );
                errors.push(Error::check(
                    one_line(&entry.recipe),
                    format!(
                        "G-code changed: sha256 was {}, now {digest}; {place}",
                        entry.sha256
                    ),
                ));
            }
            Err(e) => errors.push(e),
        }
    }
    crate::sayln!(
        "{}",
        summary(lock.entries.len(), changed, errors.len() - changed)
    );
    errors
}

/// `hash --check`'s last line: how many of `n` entries changed or failed.
fn summary(n: usize, changed: usize, failed: usize) -> String {
    let entries = if n == 1 {
        "1 entry".to_string()
    } else {
        format!("{n} entries")
    };
    let same = n - changed - failed;
    match (changed, failed) {
        (0, 0) => format!("{entries}, unchanged"),
        (c, 0) => format!("{entries}: {c} changed, {same} unchanged"),
        (c, f) => format!("{entries}: {c} changed, {f} failed to build, {same} unchanged"),
    }
}

/// A lock file read and checked, and the job of each entry (its recipe and
/// printer relative to the lock file's folder, confined to the lock's
/// project and the `allow` folders).
fn read_lock(lockfile: &Path, allow: &[PathBuf]) -> Result<(Lock, Vec<Job>)> {
    let shown = lockfile.display().to_string();
    let text = crate::base::input::read_text(lockfile, "lock file")?;
    let lock = parse_yaml::<Lock>(&text, &shown)?;
    lock.validate().map_err(|e| e.in_file(&shown))?;
    let base = lock_folder(lockfile);
    let roots = LockRoots::new(&base, allow);
    let jobs = lock
        .entries
        .iter()
        .enumerate()
        .map(|(k, e)| entry_job(&base, &roots, k, e).map_err(|err| err.in_file(&shown)))
        .collect::<Result<_>>()?;
    Ok((lock, jobs))
}

/// The folder a lock's entries are relative to.
fn lock_folder(lockfile: &Path) -> PathBuf {
    lockfile
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf()
}

/// The folders a lock's entries may name files in: `base::input`'s rule for
/// every file reached through a key, applied to the lock. Its **project**
/// (the nearest folder at or above the lock's holding `p3dp.lock` or
/// `.git`, else the lock's own folder) and the folders `--allow-read`
/// names; symlinks resolved, `/proc`, `/sys` and `/dev` never. A lock from
/// elsewhere cannot make `hash --check` read (and an error quote) a file
/// outside them.
struct LockRoots {
    reads: Reads,
    roots: Vec<PathBuf>,
}

impl LockRoots {
    fn new(base: &Path, allow: &[PathBuf]) -> LockRoots {
        let reads = Reads::default();
        let mut roots = vec![crate::base::input::project_root(base)];
        roots.extend(
            allow
                .iter()
                .map(|d| d.canonicalize().unwrap_or_else(|_| d.clone())),
        );
        for r in &roots {
            reads.allow(r);
        }
        LockRoots { reads, roots }
    }

    /// Whether `path` may be read: an existing file by its real path (as
    /// [`Reads::reach`] decides), a missing one by its lexical path, so
    /// that the answer tells nothing of files outside.
    fn admit(&self, path: &Path) -> bool {
        let dotted;
        let path = if path.is_relative() {
            dotted = Path::new(".").join(path);
            &dotted
        } else {
            path
        };
        if path.exists() {
            return self.reads.reach(path, "file").is_ok();
        }
        // missing: the real path of its deepest existing folder, and the
        // rest with no `..` in it
        let Some((known, real)) = path
            .ancestors()
            .find_map(|a| a.canonicalize().ok().map(|c| (a, c)))
        else {
            return false;
        };
        let rest = path.strip_prefix(known).unwrap_or(Path::new(""));
        !rest.components().any(|c| c == Component::ParentDir)
            && self.roots.iter().any(|r| real.join(rest).starts_with(r))
    }

    /// Refuses the `what` at `path`, named `name` at `place`, unless
    /// [`LockRoots::admit`]; the error names the entry, nothing else.
    fn confine(&self, path: &Path, name: &str, what: &str, place: &str) -> Result<()> {
        if self.admit(path) {
            return Ok(());
        }
        Err(Error::input(
            place,
            format!(
                "the {what} `{}` is outside the folders a lock may name (the lock's project: its folder, or the nearest above it holding p3dp.lock or .git; and those --allow-read adds); expected a file there (it was not read)",
                one_line(name)
            ),
        )
        .with_help("a lock names the files of its own project: keep it in a folder above them (where p3dp.lock or .git is), or give the same --allow-read DIR to `hash --lock` and `hash --check`"))
    }
}

/// The job of entry `k` of a lock file in folder `base`; a missing recipe or
/// printer is the lock's mistake, and the error names its entry. A recipe
/// or profile outside `roots` is refused before it is opened.
fn entry_job(base: &Path, roots: &LockRoots, k: usize, e: &Entry) -> Result<Job> {
    let place = format!("entries[{k}].recipe");
    let recipe = base.join(&e.recipe);
    roots.confine(&recipe, &e.recipe, "recipe", &place)?;
    if !recipe.exists() {
        return Err(Error::input(
            place,
            format!(
                "no recipe file at `{}`; expected a path relative to the lock file",
                one_line(&e.recipe)
            ),
        ));
    }
    // a FIFO or device named by a lock is refused before it is opened
    crate::base::input::check_regular(&recipe, "recipe").map_err(|e| e.under(&place))?;
    let built_in = |p: &str| crate::recipe::profile::built_in(p).is_some();
    if let Some(p) = &e.printer {
        let place = format!("entries[{k}].printer");
        if !built_in(p) {
            roots.confine(&base.join(p), p, "printer profile", &place)?;
        }
        if !built_in(p) && base.join(p).exists() {
            crate::base::input::check_regular(&base.join(p), "printer profile")
                .map_err(|e| e.under(&place))?;
        }
        if !built_in(p) && !base.join(p).exists() {
            return Err(Error::input(
                place,
                format!(
                    "`{}` is neither a built-in printer ({}) nor a profile file relative to the lock file",
                    one_line(p),
                    crate::recipe::profile::built_in_names().join(", ")
                ),
            ));
        }
    }
    let sets = e
        .set
        .iter()
        .map(|s| parse_set(s))
        .collect::<Result<Vec<_>>>()
        .map_err(|err| err.under(&format!("entries[{k}].set")))?;
    Ok(Job {
        recipe,
        sets,
        sweep: Vec::new(),
        printer: e.printer.as_ref().map(|p| {
            if built_in(p) {
                p.clone()
            } else {
                base.join(p).to_string_lossy().into_owned()
            }
        }),
    })
}

/// The part line `first` (0-based) of G-code `lines` belongs to (its own
/// `; part:` line included) and the
/// string it is at, counted as the part's moves (its travel to the start
/// is string 0's start): "in part `wall` at about string 1234: ", or
/// nothing before the first part.
fn part_at(lines: &[String], first: usize) -> String {
    let upto = &lines[..(first + 1).min(lines.len())];
    let Some(k) = upto.iter().rposition(|l| l.starts_with("; part: ")) else {
        return String::new();
    };
    let name = upto[k]["; part: ".len()..]
        .rsplit_once(" (")
        .map_or(&upto[k]["; part: ".len()..], |(n, _)| n);
    let moves = upto[k + 1..]
        .iter()
        .filter(|l| {
            let code = l.split(';').next().unwrap_or("");
            let mut w = code.split_whitespace();
            matches!(w.next(), Some("G0" | "G1" | "G2" | "G3"))
                && w.any(|x| x.starts_with(['X', 'Y', 'Z']))
        })
        .count();
    format!(
        "in part `{name}` at about string {}: ",
        moves.saturating_sub(1)
    )
}

/// Lines `k..k + n` (0-based) of the job's G-code, rebuilt.
fn new_lines(c: &Builds, job: &Job, k: u64, n: u64) -> Vec<String> {
    let options = super::stamp().unwrap_or_default();
    let Some(text) = c
        .checked_plan(job)
        .ok()
        .and_then(|mut p| {
            let job = pipeline::Job {
                stamp: options,
                ..pipeline::Job::default()
            };
            pipeline::write(&mut p, &job, Vec::new()).ok()
        })
        .and_then(|w| String::from_utf8(w.out).ok())
    else {
        return Vec::new();
    };
    text.lines()
        .skip(k as usize)
        .take(n as usize)
        .map(str::to_string)
        .collect()
}

/// Where a block of `n` lines from line `first` (1-based, the file's)
/// changed: the lock keeps one hash per block, so the changed line is one
/// of them; a short block is quoted whole, a long one by its first and last
/// lines and the `; param` comments between them (where a changed param
/// shows). `block` holds the block's lines with their numbers in the file.
fn changed_block(first: u64, n: u64, block: &[(usize, &str)]) -> String {
    let range = match block.last() {
        Some(&(last, _)) if block.len() as u64 == n => format!("lines {first}–{last}"),
        _ => format!("lines {first}–{}", first + n - 1),
    };
    if block.is_empty() {
        return format!("first difference in {range}, now past the end of the file");
    }
    let quote = |k: usize| format!("{}: `{}`", block[k].0, block[k].1);
    let picked: Vec<String> = if block.len() <= 4 {
        (0..block.len()).map(quote).collect()
    } else {
        let last = block.len() - 1;
        let mut v = vec![quote(0)];
        v.extend(
            (1..last)
                .filter(|&k| block[k].1.starts_with("; param "))
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
