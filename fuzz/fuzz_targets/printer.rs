//! Printer profile text → load (through a file, as `--printer FILE` does).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| p3dp::testing::fuzz::printer(data));
