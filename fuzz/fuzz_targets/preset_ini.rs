//! Slicer preset text (a PrusaSlicer-family .ini bundle) → every preset loaded, mapped to a profile, its YAML read back.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| p3dp::testing::fuzz::preset_ini(data));
