//! Temp files of unfinished outputs: named `.p3dp-XXXXXX.tmp`, removed when
//! a signal (SIGINT, SIGTERM, SIGHUP) stops the process, and those a SIGKILL
//! left behind swept from a folder the next time p3dp writes there, once
//! they are [`STALE_AFTER`] old.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, SystemTime};

/// How old a temp file of our own naming must be before a later run removes it.
pub(crate) const STALE_AFTER: Duration = Duration::from_secs(3600);

/// Temp files being written now, removed when a signal stops the process.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Folders already swept of stale temp files by this process.
static SWEPT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

pub(super) fn live() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// What a command that stops cleanly by itself does with a signal, instead
/// of the exit of [`remove_temp_files_on_signals`]: given the signal, it
/// returns whether it took it.
pub(crate) type StopHook = Box<dyn FnOnce(i32) -> bool + Send>;

/// The hook of [`stop_on_signals`], taken by the first signal.
static ON_SIGNAL: Mutex<Option<StopHook>> = Mutex::new(None);

/// Removes every temp file being written and exits (128 + the signal) on
/// SIGINT, SIGTERM or SIGHUP; the first signal after [`stop_on_signals`]
/// goes to its hook instead. Called once by the binary.
pub(crate) fn remove_temp_files_on_signals() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
            return;
        };
        let _ = std::thread::Builder::new()
            .name("p3dp-signals".into())
            .spawn(move || {
                for sig in signals.forever() {
                    let hook = ON_SIGNAL.lock().unwrap_or_else(|e| e.into_inner()).take();
                    if hook.is_some_and(|stop| stop(sig)) {
                        continue; // the command stops by itself; a second signal exits
                    }
                    // held until exit: no temp file is made or renamed after this
                    let files = live();
                    for f in files.iter() {
                        let _ = std::fs::remove_file(f);
                    }
                    std::process::exit(128 + sig);
                }
            });
    }
}

/// Lets a command that writes no files and stops cleanly by itself (`p3dp
/// watch`) take the next SIGINT, SIGTERM or SIGHUP: `stop` is called with it
/// instead of the exit (once: a second signal exits as usual).
pub(crate) fn stop_on_signals(stop: StopHook) {
    *ON_SIGNAL.lock().unwrap_or_else(|e| e.into_inner()) = Some(stop);
}

/// Whether `name` is one of our temp files: `.p3dp-` + 6 letters or digits + `.tmp`.
pub(crate) fn is_temp_name(name: &str) -> bool {
    name.strip_prefix(".p3dp-")
        .and_then(|r| r.strip_suffix(".tmp"))
        .is_some_and(|mid| mid.len() == 6 && mid.bytes().all(|b| b.is_ascii_alphanumeric()))
}

/// Removes temp files of our naming in `dir` older than [`STALE_AFTER`]
/// (left by a killed run); each folder once per process.
pub(super) fn sweep_stale(dir: &Path) {
    let key = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    {
        let mut swept = SWEPT.lock().unwrap_or_else(|e| e.into_inner());
        if swept.contains(&key) {
            return;
        }
        swept.push(key.clone());
    }
    sweep_now(&key);
}

/// [`sweep_stale`]'s work, on the caller's thread.
fn sweep_now(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let now = SystemTime::now();
    for e in entries.flatten() {
        if !e.file_name().to_str().is_some_and(is_temp_name) {
            continue;
        }
        let Ok(meta) = e.path().symlink_metadata() else {
            continue;
        };
        let old = meta
            .modified()
            .ok()
            .and_then(|m| now.duration_since(m).ok())
            .is_some_and(|age| age > STALE_AFTER);
        if meta.is_file() && old {
            let _ = std::fs::remove_file(e.path());
        }
    }
}
