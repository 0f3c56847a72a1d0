//! The slicers' macro language through the real binary: a printer profile
//! whose start and end G-code use the constructs of the makers' current
//! presets (statements, `local`/`global`, inline `if`, the functions),
//! built, and its G-code read back; a hostile template refused with its
//! line and column, exit 2, nothing written.

use crate::common::{p3dp, recipe, tmp};

/// A profile on the generic printer whose start G-code reads `body`, and
/// whose end G-code reads the global `parked` the start G-code sets.
fn profile(body: &str) -> String {
    let quoted =
        serde_yaml::to_string(&format!("G28\n{body}\n{{global parked = 15}}G1 Z5 F600")).unwrap();
    format!(
        "inherits: generic-220\nname: macro-test\nmodel: generic-x\nstart_gcode: {quoted}end_gcode: \"M104 S0\\nG1 Z{{parked + max_layer_z}} F600\\n\"\n"
    )
}

/// Builds cup.yaml on a profile of `body`: the status, the G-code, stderr.
fn build(body: &str, tag: &str) -> (bool, String, String) {
    let dir = tmp(tag);
    std::fs::write(dir.join("printer.yaml"), profile(body)).unwrap();
    let out = dir.join("out.gcode");
    let o = p3dp(
        &dir,
        &[
            "build",
            recipe("cup.yaml").to_str().unwrap(),
            "--printer",
            "printer.yaml",
            "-o",
            out.to_str().unwrap(),
        ],
    );
    let text = std::fs::read_to_string(&out).unwrap_or_default();
    (
        o.status.success(),
        text,
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

#[test]
fn the_constructs_of_current_presets_expand_in_a_build() {
    let body = r#"{local t = first_layer_temperature[0]; local table = interpolate_table(t, (150, 1), (300, 3))}M104 S{if t > 300}300{elsif t >= 200}{t + 5}{else}0{endif}
M117 A {one_of(printer_model, "MK4", /gen.*/) ? "ok" : "no"} {digits(table, 4, 1)} {zdigits(7, 3)}
{local v = (1, 2, 3); v[2] = size(v) * 10}M117 B {v[2]} {empty(v)} {is_nil(bed_temperature[0])}
{if layer_height < 0.05 then "M117 C fine" else "M117 C normal" endif}
M117 D {random(1, 1)}"#;
    let (ok, text, err) = build(body, "macros-constructs");
    assert!(ok, "{err}");
    let lines: Vec<&str> = text.lines().collect();
    let find = |p: &str| -> &str {
        lines
            .iter()
            .find(|l| l.starts_with(p))
            .unwrap_or_else(|| panic!("no `{p}` line in the G-code"))
    };
    // cup.yaml's material: its first-layer temperature drives each value
    let m104 = find("M104 S");
    let t: f64 = m104[6..].parse().unwrap();
    assert!((205.0..=305.0).contains(&t), "{m104}");
    let table = 1.0 + 2.0 * ((t - 5.0 - 150.0) / 150.0);
    assert_eq!(find("M117 A"), format!("M117 A ok {table:4.1} 007"));
    assert_eq!(find("M117 B"), "M117 B 30 false false");
    assert_eq!(find("M117 C"), "M117 C normal");
    assert_eq!(find("M117 D"), "M117 D 1");
    // the end G-code reads the start G-code's global: 15 mm above the top
    let end = lines
        .iter()
        .rposition(|l| l.starts_with("M104 S0"))
        .unwrap();
    let z: f64 = lines[end + 1]
        .strip_prefix("G1 Z")
        .and_then(|r| r.split(' ').next())
        .unwrap()
        .parse()
        .unwrap();
    assert!(z > 15.0, "{}", lines[end + 1]);
}

#[test]
fn a_hostile_template_is_refused_with_line_and_column() {
    // a flat chain of 20,000 terms: an error, not a stack overflow
    let chain = format!("M104 S{{1{}}}", "+1".repeat(20_000));
    let (ok, text, err) = build(&chain, "macros-chain");
    assert!(!ok && text.is_empty(), "{err}");
    assert!(
        err.contains("start_gcode line 2")
            && err.contains("nested more than 100 deep")
            && err.contains("(column "),
        "{err}"
    );
    // an unknown variable names itself, in a branch never taken too
    let (ok, _, err) = build("{if false}{chamber_temp}{endif}", "macros-unknown");
    assert!(!ok && err.contains("`chamber_temp`"), "{err}");
}
