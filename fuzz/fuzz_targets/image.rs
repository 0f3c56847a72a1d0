//! Image bytes → bitmap load. A decompression bomb (a PNG declaring 100,000 ×
//! 100,000 pixels) must be refused by its header, before decoding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| p3dp::testing::fuzz::image(data));
