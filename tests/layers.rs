//! The layering rule of `docs/ARCHITECTURE.md`: no module of `src/` names a
//! module of a layer above its own, nor one later in its own layer (so no
//! two modules depend on each other). Test modules (`#[cfg(test)]`) may use
//! any layer to build their inputs, and comments may link anywhere.

use std::path::Path;

/// The crate's top-level modules, bottom layer first; within a layer, a
/// module may use only those listed before it.
const LAYERS: &[(&str, &[&str])] = &[
    (
        "plain types and utilities",
        &[
            "error",
            "safe_text",
            "input",
            "limits",
            "mem",
            "threads",
            "toolpath",
            "expr",
            "num",
            "finding",
            "format",
            "rng",
            "geom",
            "svg",
        ],
    ),
    ("machine model", &["machine"]),
    (
        "generation",
        &["primitive", "step", "model", "assembly", "skirt"],
    ),
    (
        "analysis and output",
        &["planner", "gcode", "check", "stats"],
    ),
    ("YAML edge", &["recipe"]),
    (
        "orchestration",
        &[
            "output",
            "plan",
            "preview",
            "mesh",
            "build",
            "batch",
            "lock",
            "diagnostic",
            "watch",
            "cli",
        ],
    ),
];

/// (layer, rank in the whole order) of a top-level module.
fn rank(module: &str) -> Option<(usize, usize)> {
    let mut k = 0;
    for (layer, (_, mods)) in LAYERS.iter().enumerate() {
        for m in *mods {
            if *m == module {
                return Some((layer, k));
            }
            k += 1;
        }
    }
    None
}

/// The code of a file without its test modules and comments.
fn code(text: &str) -> String {
    let mut out = String::new();
    let mut lines = text.lines().peekable();
    while let Some(line) = lines.next() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") {
            // skip the item that follows: up to its closing brace at the same indent
            let indent = line.len() - t.len();
            let close = format!("{}}}", " ".repeat(indent));
            for l in lines.by_ref() {
                if l == close {
                    break;
                }
            }
            continue;
        }
        if t.starts_with("//") {
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// Every `crate::NAME` a piece of code names.
fn crate_refs(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(k) = rest.find("crate::") {
        let after = &rest[k + 7..];
        let name: String = after
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect();
        if !name.is_empty() {
            out.push(name);
        }
        rest = after;
    }
    // `use crate::{a, b::c}` names several
    let mut rest = code;
    while let Some(k) = rest.find("crate::{") {
        let after = &rest[k + 8..];
        let end = after.find('}').unwrap_or(after.len());
        for item in after[..end].split(',') {
            let name: String = item
                .trim()
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.push(name);
            }
        }
        rest = after;
    }
    out
}

fn rs_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rs_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn no_module_imports_from_a_layer_above_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rs_files(&src, &mut files);
    files.sort();
    // `#[macro_export]` macros live at the crate root (`crate::say!`):
    // count each as a use of the module that defines it
    let mut macros = std::collections::HashMap::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let top = f.strip_prefix(&src).unwrap().components().next().unwrap();
        let top = top
            .as_os_str()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string();
        for line in text.lines() {
            if let Some(rest) = line.trim().strip_prefix("macro_rules! ") {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                macros.insert(name, top.clone());
            }
        }
    }
    let mut seen = 0;
    let mut wrong = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&src).unwrap();
        let top = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string();
        if top == "lib" || top == "main" {
            continue;
        }
        let (layer, me) =
            rank(&top).unwrap_or_else(|| panic!("src/{top} is in no layer of tests/layers.rs"));
        let text = std::fs::read_to_string(f).unwrap();
        for name in crate_refs(&code(&text)) {
            let name = macros.get(&name).cloned().unwrap_or(name);
            if name == top || name == "self" {
                continue;
            }
            let (their_layer, them) = rank(&name)
                .unwrap_or_else(|| panic!("{}: crate::{name} is in no layer", rel.display()));
            seen += 1;
            if them > me {
                wrong.push(format!(
                    "src/{} ({}) uses crate::{name} ({})",
                    rel.display(),
                    LAYERS[layer].0,
                    LAYERS[their_layer].0
                ));
            }
        }
    }
    wrong.sort();
    wrong.dedup();
    assert!(seen > 100, "the scan found only {seen} references");
    assert!(
        wrong.is_empty(),
        "imports against the layering:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_scan_sees_grouped_and_qualified_paths_but_not_tests_or_comments() {
    let c = code(
        "use crate::{a, b::c};\n// crate::zz\nfn f() { crate::d::e(); }\n#[cfg(test)]\nmod tests {\n    use crate::t;\n}\nfn g() { crate::h(); }\n",
    );
    assert_eq!(crate_refs(&c), ["d", "h", "a", "b"]);
}
