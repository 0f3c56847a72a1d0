//! Helpers shared by the integration tests: run the real binary, and what
//! the unit tests use too (the gallery's files, fresh temporary folders,
//! G-code read back as a firmware reads it), from the one file
//! `src/base/testing.rs`.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

#[path = "../../src/base/testing.rs"]
mod shared;

pub(crate) use shared::*;

/// Runs `p3dp ARGS` in `dir`.
pub fn p3dp(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_p3dp"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run p3dp")
}

/// Runs `p3dp ARGS` in `dir` (standard error dropped) and reads its peak
/// resident memory (`VmHWM`, kB) from `/proc` until it ends.
pub fn p3dp_peak(dir: &Path, args: &[&str]) -> (Output, u64) {
    let child = Command::new(env!("CARGO_BIN_EXE_p3dp"))
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("run p3dp");
    let pid = child.id();
    let peak = std::thread::spawn(move || {
        let mut peak = 0u64;
        while let Ok(s) = std::fs::read_to_string(format!("/proc/{pid}/status")) {
            let kb = s
                .lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok());
            match kb {
                Some(kb) => peak = peak.max(kb),
                None => break, // a zombie: done
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        peak
    });
    let out = child.wait_with_output().expect("p3dp ran");
    (out, peak.join().expect("the peak"))
}

/// `make()` for `key`, made once per run of the test binary and shared by
/// every test that asks for the same key (a build several tests read, such
/// as a recipe on each built-in printer); a second caller waits for the
/// first instead of making it again.
pub fn once(key: &str, make: impl FnOnce() -> String) -> std::sync::Arc<String> {
    use std::collections::HashMap;
    use std::sync::{Arc, Mutex, OnceLock};
    type Slot = Arc<OnceLock<Arc<String>>>;
    static MADE: OnceLock<Mutex<HashMap<String, Slot>>> = OnceLock::new();
    let slot = MADE
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .entry(key.to_string())
        .or_default()
        .clone();
    slot.get_or_init(|| Arc::new(make())).clone()
}
