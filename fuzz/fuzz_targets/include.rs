//! Included library text → a recipe that includes it and uses its
//! template `cup` (the gallery's `cup.yaml` is the seed), loaded through
//! files as `p3dp` loads them: the include's size, nesting, BOM, encoding
//! and YAML, its own includes (inside the fuzz folder only) and templates.
#![no_main]

use libfuzzer_sys::fuzz_target;

const RECIPE: &str =
    "p3dp: 1\nname: f\ninclude: [lib.yaml]\nmax_strings: 200000\nparts:\n  - template: cup\n";

fuzz_target!(|data: &[u8]| {
    // one folder per process, marked as a project (includes stay inside)
    let dir = std::env::temp_dir().join(format!("p3dp-fuzz-include-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let _ = std::fs::write(dir.join("p3dp.lock"), "p3dp_lock: 1\nentries: []\n");
    let recipe = dir.join("r.yaml");
    if std::fs::write(&recipe, RECIPE).is_err()
        || std::fs::write(dir.join("lib.yaml"), data).is_err()
    {
        return;
    }
    let _ = p3dp::recipe::Recipe::load(&recipe, &[], None);
});
