//! Recipe text → load and resolve, then build and check it when small.
#![no_main]

use libfuzzer_sys::fuzz_target;
use p3dp::recipe::{parse_yaml, RawRecipe, Recipe};

/// Parts of at most this many strings are built and checked too.
const BUILD_STRINGS: u64 = 20_000;

fuzz_target!(|data: &[u8]| {
    // as Recipe::load reads a file: UTF-8 without a BOM, nesting capped
    let Ok(text) = p3dp::base::input::decode(data.to_vec()) else {
        return;
    };
    if p3dp::base::input::check_nesting(&text).is_err() {
        return;
    }
    let Ok(raw) = parse_yaml::<RawRecipe>(&text, "fuzz.yaml") else {
        return;
    };
    // a bound on the work of one input: the fuzzer wants many fast runs
    let raw = RawRecipe {
        max_strings: raw
            .max_strings
            .or(Some(p3dp::recipe::Num::Value(200_000.0))),
        ..raw
    };
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../recipes");
    let Ok(recipe) = Recipe::resolve(&raw, &[], None, &dir) else {
        return;
    };
    let strings: u64 = recipe
        .parts
        .iter()
        .map(|p| p.primitive.string_count())
        .sum();
    if strings > BUILD_STRINGS {
        return;
    }
    let mut paths = Vec::new();
    for k in 0..recipe.parts.len() {
        match p3dp::generate::model::make_part(&recipe, k) {
            Ok(tp) => paths.push(tp),
            Err(_) => return,
        }
    }
    let refs: Vec<&p3dp::base::toolpath::Toolpath> = paths.iter().collect();
    let _ = p3dp::analyse::check::run(&recipe, &refs, &recipe.allow);
});
