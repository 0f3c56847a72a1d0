//! SVG text → parsed (roxmltree pre-passes, usvg) and flattened, and the
//! first closed subpath made an outline: no panic, and bounded time and
//! memory whatever the bytes (the limits of `p3dp::base::svg`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use p3dp::base::svg::{parse, Options, Outline};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let opt = Options {
        id: None,
        scale: 1.0,
        tolerance: 0.01,
        max_points: 200_000,
    };
    if let Ok(subpaths) = parse(text, &opt) {
        if let Ok(o) = Outline::from_subpaths(&subpaths) {
            let _ = o.fractions(240);
            let _ = o.point_at(0.5);
        }
    }
});
