//! Printer profile text → load (through a file, as `--printer FILE` does).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // one file per process, beside the built-in-looking names it may inherit
    let dir = std::env::temp_dir().join(format!("p3dp-fuzz-printer-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let file = dir.join("profile.yaml");
    if std::fs::write(&file, data).is_err() {
        return;
    }
    let _ = p3dp::machine::Printer::from_file(&file);
});
