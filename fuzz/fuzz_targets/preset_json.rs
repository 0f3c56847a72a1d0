//! Slicer preset text (an OrcaSlicer/Bambu Studio .json preset beside a parent, a template and a filament) → every preset loaded, mapped to a profile, its YAML read back.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| p3dp::testing::fuzz::preset_json(data));
