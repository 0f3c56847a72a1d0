//! Lock file text → parse and validate, then compare its fingerprints.
#![no_main]

use libfuzzer_sys::fuzz_target;
use p3dp::output::lock::{first_difference, LineHashes, Lock};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = p3dp::base::input::decode(data.to_vec()) else {
        return;
    };
    if p3dp::base::input::check_nesting(&text).is_err() {
        return;
    }
    let Ok(lock) = p3dp::recipe::parse_yaml::<Lock>(&text, "fuzz.lock") else {
        return;
    };
    if lock.validate().is_err() {
        return;
    }
    let mut lines = LineHashes::default();
    use std::io::Write;
    let _ = lines.write_all(b"G1 X1\nG1 X2\n; end\n");
    for e in &lock.entries {
        let new = lines.blocks(e.block_lines);
        let _ = first_difference(&e.blocks, &new);
        let _ = &e.sha256[..12];
    }
});
