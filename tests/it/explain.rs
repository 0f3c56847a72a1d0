//! `p3dp explain CODE`: every code a check can emit has its section of
//! `docs/checks.md` (what it measures, why a print fails, the fix, the
//! `allow`), the page has no section of a code that does not exist, and an
//! unknown code is refused with the list of codes.

use crate::common::*;
use p3dp::{CODES, SAFETY};

/// The codes the checks' sources name: every hyphenated lower-case string
/// literal of `src/analyse/check/` and every `code: "…"` literal.
fn codes_in_sources() -> std::collections::BTreeSet<String> {
    let mut found = std::collections::BTreeSet::new();
    let mut files = Vec::new();
    let mut dirs = vec![root().join("src/analyse/check")];
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                dirs.push(p);
            } else {
                files.push(p);
            }
        }
    }
    for f in files {
        let text = std::fs::read_to_string(f).unwrap();
        for (k, lit) in text.split('"').enumerate().filter(|(k, _)| k % 2 == 1) {
            let plain = !lit.is_empty() && lit.chars().all(|c| c.is_ascii_lowercase() || c == '-');
            let before = text.split('"').nth(k - 1).unwrap_or("");
            if plain && (lit.contains('-') || before.ends_with("code: ")) {
                found.insert(lit.to_string());
            }
        }
    }
    found
}

#[test]
fn every_code_the_checks_emit_is_listed() {
    let found = codes_in_sources();
    let listed: std::collections::BTreeSet<String> =
        CODES.iter().map(|(c, _)| c.to_string()).collect();
    assert!(found.len() >= 15, "{found:?}");
    for c in &found {
        assert!(listed.contains(c), "`{c}` is emitted but not in CODES");
    }
    for c in &listed {
        assert!(found.contains(c), "`{c}` is in CODES but no check emits it");
    }
}

#[test]
fn explain_walks_every_code() {
    let dir = root();
    for (code, _) in CODES {
        let out = p3dp(&dir, &["explain", code]);
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{code}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            text.starts_with(&format!("## `{code}`\n")),
            "{code}: {text}"
        );
        for part in [
            "**Severity:**",
            "**What it measures:**",
            "**Why a print fails:**",
            "**How to fix it:**",
            "**Silence it:**",
        ] {
            assert_eq!(text.matches(part).count(), 1, "{code}: {part} in\n{text}");
        }
        // one section only: it stops before the next code's heading
        assert_eq!(text.matches("\n## ").count(), 0, "{code}: {text}");
        if SAFETY.contains(code) {
            assert!(text.contains("cannot be allowed"), "{code}: {text}");
            assert!(text.contains("--force"), "{code}: {text}");
        } else {
            assert!(text.contains(&format!("allow: [{code}]")), "{code}: {text}");
            assert!(text.contains(&format!("--allow {code}")), "{code}: {text}");
        }
    }
}

#[test]
fn the_page_explains_only_real_codes() {
    let page = std::fs::read_to_string(root().join("docs/checks.md")).unwrap();
    let headings: Vec<&str> = page
        .lines()
        .filter_map(|l| l.strip_prefix("## `")?.strip_suffix('`'))
        .collect();
    let codes: Vec<&str> = CODES.iter().map(|(c, _)| *c).collect();
    assert_eq!(
        headings, codes,
        "docs/checks.md: one section per code, in CODES' order"
    );
}

#[test]
fn an_unknown_code_is_refused_with_the_list() {
    let out = p3dp(&root(), &["explain", "brige"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("unknown check code `brige`"), "{err}");
    for (code, _) in CODES {
        assert!(err.contains(code), "{code} missing from {err}");
    }
}

#[test]
fn without_a_code_every_code_in_a_line() {
    let out = p3dp(&root(), &["explain"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for (code, what) in CODES {
        assert!(
            text.lines()
                .any(|l| l.starts_with(code) && l.ends_with(what)),
            "{code}: {text}"
        );
    }
}

#[test]
fn head_collision_names_the_head_keys_a_profile_has() {
    // a profile's head takes `box` and `gantry` (schema/profile.rs), not
    // the field's name inside p3dp
    let dir = tmp("explain-head");
    let o = p3dp(&dir, &["explain", "head-collision"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("`head.box`"), "{text}");
    assert!(!text.contains("head_box"), "{text}");
}
