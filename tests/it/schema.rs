//! `p3dp schema`: the JSON Schema of the recipe format, made from the loader's
//! own `Raw*` types. A draft 2020-12 validator of the keywords the schema
//! uses (here, so the tests build no validator crate and its dependencies;
//! any other keyword fails) accepts every gallery recipe and
//! rejects the bad recipes whose mistake is a wrong key or type; the
//! committed `docs/recipe.schema.json` (which the recipes name for editors)
//! is exactly what `p3dp schema` prints.

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

fn validator(schema: &Value) -> Validator {
    Validator {
        root: schema.clone(),
    }
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
    let mut problems = Vec::new();
    schema_problems(&validator(&s), &s, "#", &mut problems);
    assert!(
        problems.is_empty(),
        "the schema is itself a valid schema of the keywords known: {problems:?}"
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
        let mut errors = Vec::new();
        v.errors(&v.root, &doc, "", &mut errors);
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

#[test]
fn the_validator_refuses_what_each_keyword_forbids() {
    let v = validator(&serde_json::json!({
        "type": "object",
        "required": ["at"],
        "additionalProperties": false,
        "properties": {
            "at": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
            "n": {"type": "integer", "minimum": 0},
            "kind": {"oneOf": [{"const": "a"}, {"enum": ["b", "c"]}]},
            "map": {"$ref": "#/$defs/Map"}
        },
        "$defs": {"Map": {"minProperties": 1, "propertyNames": {"enum": ["x"]}}}
    }));
    let good = serde_json::json!({"at": [0, 1, 2.5], "n": 3.0, "kind": "c", "map": {"x": 1}});
    assert!(v.is_valid(&good));
    for bad in [
        serde_json::json!({"n": 1}),
        serde_json::json!({"at": [0, 1, 2], "m": 1}),
        serde_json::json!({"at": [0, 1]}),
        serde_json::json!({"at": [0, 1, 2, 3]}),
        serde_json::json!({"at": [0, 1, "2"]}),
        serde_json::json!({"at": [0, 1, 2], "n": 1.5}),
        serde_json::json!({"at": [0, 1, 2], "n": -1}),
        serde_json::json!({"at": [0, 1, 2], "kind": "d"}),
        serde_json::json!({"at": [0, 1, 2], "map": {}}),
        serde_json::json!({"at": [0, 1, 2], "map": {"y": 1}}),
        serde_json::json!([]),
    ] {
        assert!(!v.is_valid(&bad), "{bad} passes");
    }
    // a keyword the validator does not know fails rather than passing
    let unknown = validator(&serde_json::json!({"pattern": "^a"}));
    assert!(!unknown.is_valid(&serde_json::json!("b")));
    let mut problems = Vec::new();
    schema_problems(&unknown, &unknown.root, "#", &mut problems);
    assert_eq!(problems.len(), 1, "{problems:?}");
}

/// The keywords `p3dp schema` writes that assert nothing (draft 2020-12
/// annotations; `format` too, which 2020-12 leaves to annotation).
const ANNOTATIONS: [&str; 7] = [
    "$schema",
    "$defs",
    "title",
    "description",
    "default",
    "examples",
    "format",
];

/// The draft 2020-12 keywords `p3dp schema` writes that constrain a value.
/// A keyword outside these and `ANNOTATIONS` is an error, so the schema
/// cannot grow one the validator would skip.
const ASSERTIONS: [&str; 15] = [
    "$ref",
    "type",
    "properties",
    "additionalProperties",
    "required",
    "minProperties",
    "propertyNames",
    "items",
    "minItems",
    "maxItems",
    "const",
    "enum",
    "anyOf",
    "oneOf",
    "minimum",
];

/// A draft 2020-12 validator for the keywords of `ASSERTIONS` (the ones
/// schemars emits for the loader's `Raw*` types), with `$ref`s to the
/// root's `$defs`.
struct Validator {
    root: Value,
}

impl Validator {
    /// Why `doc` fails `schema`, at JSON pointer `at`: one line an error.
    fn errors(&self, schema: &Value, doc: &Value, at: &str, out: &mut Vec<String>) {
        let map = match schema {
            Value::Bool(true) => return,
            Value::Bool(false) => return out.push(format!("{at}: no value is allowed here")),
            Value::Object(map) => map,
            other => return out.push(format!("{at}: the schema {other} is not a schema")),
        };
        for (key, arg) in map {
            if !ANNOTATIONS.contains(&key.as_str()) {
                self.keyword(key, arg, map, doc, at, out);
            }
        }
    }

    /// Whether `doc` passes the whole schema.
    fn is_valid(&self, doc: &Value) -> bool {
        self.valid(&self.root, doc)
    }

    /// Whether `doc` passes `schema`.
    fn valid(&self, schema: &Value, doc: &Value) -> bool {
        let mut out = Vec::new();
        self.errors(schema, doc, "", &mut out);
        out.is_empty()
    }

    /// Applies one keyword of `map` (its value `arg`) to `doc`.
    fn keyword(
        &self,
        key: &str,
        arg: &Value,
        map: &serde_json::Map<String, Value>,
        doc: &Value,
        at: &str,
        out: &mut Vec<String>,
    ) {
        let bound = || arg.as_u64().expect("a count") as usize;
        let fail = match key {
            "$ref" => return self.errors(self.resolve(arg), doc, at, out),
            "anyOf" => !list(arg).iter().any(|s| self.valid(s, doc)),
            "oneOf" => list(arg).iter().filter(|s| self.valid(s, doc)).count() != 1,
            "type" => !type_names(arg).iter().any(|t| has_type(doc, t)),
            "const" => !same(arg, doc),
            "enum" => !list(arg).iter().any(|v| same(v, doc)),
            "minimum" => doc.as_f64().is_some_and(|x| x < arg.as_f64().unwrap()),
            "minItems" => doc.as_array().is_some_and(|a| a.len() < bound()),
            "maxItems" => doc.as_array().is_some_and(|a| a.len() > bound()),
            "minProperties" => doc.as_object().is_some_and(|o| o.len() < bound()),
            "required" => match doc.as_object() {
                Some(o) => !list(arg)
                    .iter()
                    .all(|k| o.contains_key(k.as_str().unwrap())),
                None => false,
            },
            _ => return self.containers(key, arg, map, doc, at, out),
        };
        if fail {
            out.push(format!("{at}: {doc} fails `{key}: {arg}`"));
        }
    }

    /// The keywords that apply a subschema to the parts of an object or an
    /// array.
    fn containers(
        &self,
        key: &str,
        arg: &Value,
        map: &serde_json::Map<String, Value>,
        doc: &Value,
        at: &str,
        out: &mut Vec<String>,
    ) {
        let named = map.get("properties").and_then(Value::as_object);
        match (key, doc) {
            ("properties", Value::Object(o)) => {
                for (k, v) in o {
                    if let Some(s) = arg.get(k) {
                        self.errors(s, v, &format!("{at}/{k}"), out);
                    }
                }
            }
            ("additionalProperties", Value::Object(o)) => {
                for (k, v) in o {
                    if !named.is_some_and(|p| p.contains_key(k)) {
                        self.errors(arg, v, &format!("{at}/{k}"), out);
                    }
                }
            }
            ("propertyNames", Value::Object(o)) => {
                for k in o.keys() {
                    self.errors(arg, &Value::String(k.clone()), &format!("{at}/{k}"), out);
                }
            }
            ("items", Value::Array(a)) => {
                for (i, v) in a.iter().enumerate() {
                    self.errors(arg, v, &format!("{at}/{i}"), out);
                }
            }
            ("properties" | "additionalProperties" | "propertyNames" | "items", _) => {}
            _ => out.push(format!(
                "{at}: the keyword `{key}` is not one the validator knows"
            )),
        }
    }

    /// The schema a `$ref` (`#/$defs/NAME`) names.
    fn resolve(&self, reference: &Value) -> &Value {
        let r = reference.as_str().expect("a $ref is a string");
        let pointer = r.strip_prefix('#').expect("a $ref within the schema");
        self.root
            .pointer(pointer)
            .unwrap_or_else(|| panic!("the $ref {r} names nothing"))
    }
}

/// The subschemas of a schema, wherever they stand.
fn subschemas(schema: &Value) -> Vec<&Value> {
    let Some(map) = schema.as_object() else {
        return Vec::new();
    };
    let mut subs = Vec::new();
    for (key, arg) in map {
        match key.as_str() {
            "properties" | "$defs" => subs.extend(arg.as_object().unwrap().values()),
            "anyOf" | "oneOf" => subs.extend(list(arg)),
            "items" | "additionalProperties" | "propertyNames" => subs.push(arg),
            _ => {}
        }
    }
    subs
}

/// What a validator needs of a schema, short of the meta-schema: every
/// keyword known, with an argument of its kind, every `$ref` resolving.
fn schema_problems(v: &Validator, schema: &Value, at: &str, out: &mut Vec<String>) {
    if let Some(map) = schema.as_object() {
        for (key, arg) in map {
            let fits = match key.as_str() {
                k if ANNOTATIONS.contains(&k) => true,
                "$ref" => arg.as_str().is_some_and(|r| {
                    r.strip_prefix('#')
                        .is_some_and(|p| v.root.pointer(p).is_some())
                }),
                "type" => !type_names(arg).is_empty(),
                "required" => list(arg).iter().all(Value::is_string),
                "minItems" | "maxItems" | "minProperties" => arg.is_u64(),
                "minimum" => arg.is_number(),
                "enum" | "anyOf" | "oneOf" => !list(arg).is_empty(),
                "properties" => arg.is_object(),
                "additionalProperties" | "propertyNames" | "items" => {
                    arg.is_object() || arg.is_boolean()
                }
                k => ASSERTIONS.contains(&k),
            };
            if !fits {
                out.push(format!("{at}: `{key}: {arg}`"));
            }
        }
    } else if !schema.is_boolean() {
        out.push(format!("{at}: {schema} is not a schema"));
    }
    for (k, sub) in subschemas(schema).into_iter().enumerate() {
        schema_problems(v, sub, &format!("{at}/{k}"), out);
    }
}

/// An array's items (none for anything else).
fn list(v: &Value) -> &[Value] {
    v.as_array().map_or(&[], Vec::as_slice)
}

/// The type names of a `type` keyword, when they are JSON Schema's.
fn type_names(arg: &Value) -> Vec<&str> {
    const TYPES: [&str; 7] = [
        "null", "boolean", "object", "array", "number", "string", "integer",
    ];
    let names: Vec<&str> = match arg {
        Value::String(s) => vec![s.as_str()],
        Value::Array(a) => a.iter().filter_map(Value::as_str).collect(),
        _ => Vec::new(),
    };
    if names.iter().all(|n| TYPES.contains(n)) {
        names
    } else {
        Vec::new()
    }
}

/// Whether `doc` is of JSON Schema type `t` (an integer: a number without a
/// fractional part, 1.0 too).
fn has_type(doc: &Value, t: &str) -> bool {
    match t {
        "null" => doc.is_null(),
        "boolean" => doc.is_boolean(),
        "object" => doc.is_object(),
        "array" => doc.is_array(),
        "number" => doc.is_number(),
        "string" => doc.is_string(),
        "integer" => doc.as_f64().is_some_and(|x| x.fract() == 0.0),
        _ => false,
    }
}

/// JSON Schema's equality: numbers by value (1 and 1.0 alike).
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.as_f64() == y.as_f64(),
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(a, b)| same(a, b))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}
