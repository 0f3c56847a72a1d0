//! A G-code line → read by each firmware's rules, each command written
//! back and read again.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| p3dp::testing::fuzz::gcode_line(data));
