//! Slicer macro text (start/end G-code templates) → parse, list the
//! variables, expand twice.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| p3dp::testing::fuzz::slicer_macro(data));
