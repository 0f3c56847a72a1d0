//! `p3dp schema`: the JSON Schema of the recipe format, made from the loader's
//! own `Raw*` types. A real validator (the `jsonschema` crate) accepts every
//! gallery recipe and rejects the bad recipes whose mistake is a wrong key or
//! type; the committed `docs/recipe.schema.json` (which the recipes name for
//! editors) is exactly what `p3dp schema` prints.

use crate::common::*;
use serde_json::Value;

fn schema() -> Value {
    let out = p3dp(&root(), &["schema"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("p3dp schema prints JSON")
}

fn yaml_file(path: &std::path::Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap();
    serde_yaml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn validator(schema: &Value) -> jsonschema::Validator {
    jsonschema::draft202012::new(schema).expect("a valid draft 2020-12 schema")
}

#[test]
fn the_schema_is_draft_2020_12_and_documents_keys() {
    let s = schema();
    assert_eq!(s["$schema"], "https://json-schema.org/draft/2020-12/schema");
    let props = &s["properties"];
    for key in ["p3dp", "name", "parts", "params", "templates", "include"] {
        assert!(props.get(key).is_some(), "no {key} in {props}");
    }
    assert!(
        props["name"]["description"].as_str().is_some(),
        "keys carry their doc comments"
    );
    assert!(
        jsonschema::meta::is_valid(&s),
        "the schema is itself a valid schema"
    );
}

#[test]
fn every_gallery_recipe_validates_and_names_the_schema() {
    let v = validator(&schema());
    let mut n = 0;
    for entry in std::fs::read_dir(root().join("recipes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("yaml") {
            continue;
        }
        let doc = yaml_file(&path);
        let errors: Vec<String> = v
            .iter_errors(&doc)
            .map(|e| format!("{} at {}", e, e.instance_path()))
            .collect();
        assert!(
            errors.is_empty(),
            "{}:\n{}",
            path.display(),
            errors.join("\n")
        );
        let first = std::fs::read_to_string(&path).unwrap();
        assert!(
            first.starts_with("# yaml-language-server: $schema=../docs/recipe.schema.json\n"),
            "{} does not name the schema on its first line",
            path.display()
        );
        n += 1;
    }
    assert!(n >= 20, "only {n} recipes");
}

#[test]
fn bad_recipes_with_a_wrong_key_or_type_fail_it() {
    let v = validator(&schema());
    for name in [
        "unknown-top-key",
        "unknown-primitive-key",
        "unknown-step-key",
        "unknown-step",
        "list-for-number",
        "string-for-list",
        "string-for-steps",
        "solid-unknown-key",
        "solid-unknown-op",
        "missing-name",
        "missing-parts",
    ] {
        let doc = yaml_file(&root().join("tests/bad").join(format!("{name}.yaml")));
        assert!(!v.is_valid(&doc), "{name}.yaml passes the schema");
    }
}

#[test]
fn the_committed_schema_is_what_p3dp_schema_prints() {
    let committed: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("docs/recipe.schema.json")).unwrap(),
    )
    .unwrap();
    assert!(
        committed == schema(),
        "docs/recipe.schema.json is stale: p3dp schema > docs/recipe.schema.json"
    );
}
