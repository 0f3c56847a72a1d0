//! Lock file text → parse and validate, then compare its fingerprints.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| p3dp::testing::fuzz::lock(data));
