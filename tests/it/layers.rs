//! The layering rule of `docs/ARCHITECTURE.md`: `src/` is one folder per
//! layer (and `main.rs`, `lib.rs`), and no module names a module of a layer
//! above its own, nor one later in its own layer (so no two modules depend on
//! each other). A path is `crate::…`, or `super::…` read as the `crate::…`
//! path it names. Test code (`#[cfg(test)]` blocks, a module's `tests/`
//! folder, the `testing.rs` helpers, all compiled only for tests) may use
//! any layer to build its inputs, and comments may link anywhere.

use std::path::Path;

/// The layers, bottom first: each a folder of `src/` and its modules in
/// order (a module may use only those listed before it in its layer).
const LAYERS: &[(&str, &[&str])] = &[
    (
        "base",
        &[
            "error",
            "safe_text",
            "xml",
            "input",
            "mem",
            "par",
            "gcode",
            "toolpath",
            "grammar",
            "expr",
            "finding",
            "rng",
            "format",
            "slicer_macro",
            "geom",
            "svg",
        ],
    ),
    (
        "machine",
        &[
            "limits",
            "size",
            "material",
            "head",
            "kinematics",
            "printer",
            "travel",
            "firmware",
        ],
    ),
    (
        "generate",
        &["primitive", "step", "model", "assembly", "skirt", "plate"],
    ),
    ("analyse", &["planner", "check", "frame", "plan", "stats"]),
    (
        "output",
        &["file", "gcode", "preview", "mesh", "host", "lock"],
    ),
    (
        "recipe",
        &[
            "yaml", "context", "schema", "eval", "params", "expand", "preset", "profile", "resolve",
        ],
    ),
    (
        "app",
        &[
            "fuzzing",
            "pipeline",
            "prepare",
            "batch",
            "diagnostic",
            "http",
            "watch",
            "command",
            "cli",
        ],
    ),
];

/// (layer, rank of the module within it) of `crate::LAYER::MODULE`; the
/// module is `None` for the layer's own face (its `mod.rs` and what it
/// re-exports).
fn rank(layer: &str, module: Option<&str>) -> Option<(usize, Option<usize>)> {
    let l = LAYERS.iter().position(|(name, _)| *name == layer)?;
    match module {
        None => Some((l, None)),
        Some(m) => match LAYERS[l].1.iter().position(|x| *x == m) {
            Some(k) => Some((l, Some(k))),
            // an item the face re-exports (`crate::machine::Printer`)
            None => Some((l, None)),
        },
    }
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

/// A path segment: letters, digits and `_`.
fn ident(s: &str) -> String {
    s.chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect()
}

/// Every `crate::A::B` a piece of code names, as (A, B) (B empty when the
/// path stops at A or goes on with a brace or a macro's `!`).
fn crate_refs(code: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(k) = rest.find("crate::") {
        let after = &rest[k + 7..];
        let a = ident(after);
        let b = after[a.len()..]
            .strip_prefix("::")
            .map(ident)
            .unwrap_or_default();
        if !a.is_empty() {
            out.push((a, b));
        }
        rest = after;
    }
    out
}

/// The module path of a file of `src/` (`recipe/resolve/part.rs`: recipe,
/// resolve, part; a `mod.rs` is its folder's module).
fn module_path(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| {
            c.as_os_str()
                .to_string_lossy()
                .trim_end_matches(".rs")
                .to_string()
        })
        .collect();
    if parts.last().is_some_and(|m| m == "mod") {
        parts.pop();
    }
    parts
}

/// Every `super::…` path of a piece of code in the module `module`, as the
/// (A, B) of the `crate::A::B` it names (`super::NAME` in
/// `recipe/resolve/part.rs` names `crate::recipe::resolve::NAME`). Inside an
/// inline `mod NAME { … }` the module is one deeper.
fn super_refs(code: &str, module: &[String]) -> Vec<(String, String)> {
    let mut out = Vec::new();
    // inline modules open here: their names and closing lines
    let mut inline: Vec<(String, String)> = Vec::new();
    for line in code.lines() {
        if inline.last().is_some_and(|(_, close)| line == close) {
            inline.pop();
            continue;
        }
        let t = line.trim_start();
        let decl = t
            .strip_prefix("pub(crate) mod ")
            .or_else(|| t.strip_prefix("pub mod "))
            .or_else(|| t.strip_prefix("mod "));
        if let Some(rest) = decl.filter(|r| r.trim_end().ends_with('{')) {
            let indent = line.len() - t.len();
            inline.push((ident(rest), format!("{}}}", " ".repeat(indent))));
            continue;
        }
        let mut rest = line;
        while let Some(k) = rest.find("super::") {
            let part_of_a_name = rest[..k]
                .chars()
                .last()
                .is_some_and(|c| c.is_ascii_alphanumeric() || c == '_');
            let mut after = &rest[k..];
            if part_of_a_name {
                rest = &after[7..];
                continue;
            }
            let mut path: Vec<String> = module.to_vec();
            path.extend(inline.iter().map(|(name, _)| name.clone()));
            while let Some(a) = after.strip_prefix("super::") {
                path.pop();
                after = a;
            }
            loop {
                let name = ident(after);
                if name.is_empty() {
                    break;
                }
                after = &after[name.len()..];
                path.push(name);
                match after.strip_prefix("::") {
                    Some(a) => after = a,
                    None => break,
                }
            }
            if let Some(a) = path.first() {
                out.push((a.clone(), path.get(1).cloned().unwrap_or_default()));
            }
            rest = after;
        }
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

/// Whether a file of `src/` is compiled for tests only: a `tests/` folder
/// or a `testing.rs` helper.
fn test_only(rel: &Path) -> bool {
    rel.components()
        .any(|c| c.as_os_str() == "tests" || c.as_os_str() == "testing.rs")
}

/// The (layer, module) a file of `src/` belongs to.
fn home(rel: &Path) -> (String, Option<String>) {
    let parts: Vec<String> = rel
        .components()
        .map(|c| {
            c.as_os_str()
                .to_string_lossy()
                .trim_end_matches(".rs")
                .to_string()
        })
        .collect();
    let module = parts.get(1).filter(|m| *m != "mod").cloned();
    (parts[0].clone(), module)
}

#[test]
fn src_is_one_folder_per_layer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut loose = Vec::new();
    let mut folders = Vec::new();
    for e in std::fs::read_dir(&src).unwrap() {
        let e = e.unwrap();
        let name = e.file_name().to_string_lossy().to_string();
        if e.path().is_dir() {
            folders.push(name);
        } else {
            loose.push(name);
        }
    }
    loose.sort();
    folders.sort();
    assert_eq!(
        loose,
        ["lib.rs", "main.rs"],
        "only main.rs and lib.rs are loose in src/"
    );
    let mut layers: Vec<String> = LAYERS.iter().map(|(l, _)| l.to_string()).collect();
    layers.sort();
    assert_eq!(folders, layers, "src/ holds one folder per layer");
    // and each layer's modules are what the folder holds
    for (layer, modules) in LAYERS {
        let mut have: Vec<String> = std::fs::read_dir(src.join(layer))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.is_dir() || p.extension().is_some_and(|x| x == "rs"))
            .map(|p| p.file_stem().unwrap().to_string_lossy().to_string())
            .filter(|n| n != "mod" && n != "tests" && n != "testing")
            .collect();
        // folders of data (built-in printers, starters) are no modules
        have.retain(|n| {
            src.join(layer).join(n).join("mod.rs").exists()
                || src.join(layer).join(format!("{n}.rs")).exists()
        });
        have.sort();
        let mut want: Vec<String> = modules.iter().map(|m| m.to_string()).collect();
        want.sort();
        assert_eq!(have, want, "the modules of src/{layer}/");
    }
}

#[test]
fn no_module_imports_from_a_layer_above_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rs_files(&src, &mut files);
    files.retain(|f| !test_only(f.strip_prefix(&src).unwrap()));
    files.sort();
    // `#[macro_export]` macros live at the crate root (`crate::say!`):
    // count each as a use of the module that defines it
    let mut macros = std::collections::HashMap::new();
    for f in &files {
        let rel = f.strip_prefix(&src).unwrap();
        if rel.components().count() < 2 {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap();
        for line in text.lines() {
            if let Some(rest) = line.trim().strip_prefix("macro_rules! ") {
                macros.insert(ident(rest), home(rel));
            }
        }
    }
    let mut seen = 0;
    let mut wrong = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&src).unwrap();
        if rel.components().count() < 2 {
            continue; // lib.rs, main.rs: the crate's face and the binary
        }
        let (layer, module) = home(rel);
        let (me, my_rank) = rank(&layer, module.as_deref())
            .unwrap_or_else(|| panic!("src/{} is in no layer of tests/layers.rs", rel.display()));
        let text = std::fs::read_to_string(f).unwrap();
        let code = code(&text);
        let mut refs = crate_refs(&code);
        refs.extend(super_refs(&code, &module_path(rel)));
        for (a, b) in refs {
            let (a, b) = match macros.get(&a) {
                Some((l, m)) => (l.clone(), m.clone().unwrap_or_default()),
                None => (a, b),
            };
            if a == "self" || a == "Error" || a == "Result" {
                continue;
            }
            let (them, their_rank) = rank(&a, Some(b.as_str()).filter(|b| !b.is_empty()))
                .unwrap_or_else(|| panic!("{}: crate::{a} is in no layer", rel.display()));
            seen += 1;
            let up = match (them.cmp(&me), my_rank, their_rank) {
                (std::cmp::Ordering::Greater, _, _) => true,
                (std::cmp::Ordering::Less, _, _) => false,
                // within a layer: only modules listed before one's own
                (_, Some(m), Some(t)) => t > m,
                // a module through its own layer's face could close a circle
                (_, Some(_), None) => true,
                (_, None, _) => false,
            };
            if up {
                wrong.push(format!(
                    "src/{} ({layer}) uses crate::{a}::{b} ({})",
                    rel.display(),
                    LAYERS[them].0
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
fn the_scan_sees_qualified_paths_but_not_tests_or_comments() {
    let c = code(
        "use crate::a::b;\n// crate::zz\nfn f() { crate::d::e(); }\n#[cfg(test)]\nmod tests {\n    use crate::t;\n}\nfn g() { crate::h!(); }\n",
    );
    let refs = crate_refs(&c);
    let got: Vec<(&str, &str)> = refs.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    assert_eq!(got, [("a", "b"), ("d", "e"), ("h", "")]);
}

#[test]
fn super_paths_name_the_crate_paths_they_mean() {
    let module: Vec<String> = ["recipe", "resolve", "part"].map(String::from).to_vec();
    let refs = super_refs(
        "use super::Ctx;\nuse super::super::schema::{RawPart};\nfn f() { super::super::eval::join(); }\nmod inner {\n    use super::super::step;\n}\nlet a = my_super::x;\n",
        &module,
    );
    let got: Vec<(&str, &str)> = refs.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    assert_eq!(
        got,
        [
            ("recipe", "resolve"),
            ("recipe", "schema"),
            ("recipe", "eval"),
            ("recipe", "resolve"),
        ]
    );
    assert_eq!(
        module_path(Path::new("recipe/schema/mod.rs")),
        ["recipe", "schema"]
    );
}
