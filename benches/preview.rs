//! The previews of the 2,000,000-string vase (`benches/vase-2m.yaml`), PNG
//! and HTML, through the release binary as a user runs it, a fresh process
//! per run (so each peak of resident memory is that run's own): wall, CPU
//! and peak memory; every run must write the same bytes.
//!
//!     cargo bench --bench preview
//!     P3DP_BASELINE=/path/to/older/p3dp cargo bench --bench preview
//!
//! With `P3DP_BASELINE` the older binary runs the same cases, alternately
//! with this one (figures and targets: docs/performance.md).

mod common;

use std::path::Path;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let recipe = root.join("benches/vase-2m.yaml");
    let dir = std::env::temp_dir().join(format!("p3dp-bench-preview-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a folder for the outputs");
    for ext in ["png", "html"] {
        let out = dir.join(format!("vase.{ext}"));
        let first = std::cell::RefCell::new(std::collections::HashMap::new());
        common::compare(
            &format!("vase-2m preview {ext}"),
            &[
                "preview",
                recipe.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ],
            &dir,
            5,
            || {
                let _ = std::fs::remove_file(&out);
            },
            |bin| {
                let bytes = std::fs::read(&out).expect("the preview");
                let mut seen = first.borrow_mut();
                let f = seen.entry(bin.to_string()).or_insert_with(|| bytes.clone());
                assert!(
                    *f == bytes,
                    "{ext} [{bin}]: not the same bytes on every run"
                );
            },
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
