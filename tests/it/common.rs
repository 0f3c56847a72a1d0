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
