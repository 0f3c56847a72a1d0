//! Included library text → a recipe that includes it and uses its
//! template `cup` (the gallery's `cup.yaml` is the seed), loaded through
//! files as `p3dp` loads them: the include's size, nesting, BOM, encoding
//! and YAML, its own includes (inside the fuzz folder only) and templates.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| p3dp::testing::fuzz::include(data));
