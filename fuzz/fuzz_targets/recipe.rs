//! Recipe text → load and resolve, then build and check it when small.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| p3dp::testing::fuzz::recipe(
    data,
    &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../recipes")
));
