//! SVG text → parsed (roxmltree pre-passes, usvg) and flattened, and the
//! first closed subpath made an outline: no panic, and bounded time and
//! memory whatever the bytes (the limits of `p3dp's `base::svg``).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| p3dp::testing::fuzz::svg(data));
