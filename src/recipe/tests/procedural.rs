//! Procedural recipes (issue 15): templates, loops, groups and primitive
//! lists as the loader resolves them. A group's steps reach every string of
//! its parts, names and errors follow the expansion chain, expansion is
//! bounded, and the gallery's procedural recipes have the geometry their
//! comments promise.
//!
//! Past the public face: `recipe::{parse_yaml, RawRecipe, Num}`,
//! `recipe::resolve`, `Recipe::groups`, `Primitive::Helix` and
//! `Primitive::string_count` off `Recipe::parts`. Home: beside
//! `recipe::expand` and `recipe::resolve`.

use std::path::PathBuf;

use crate::base::testing::root;
use std::f64::consts::PI;

use crate::base::testing::recipe;
use crate::base::toolpath::{polar, Toolpath};
use crate::generate::assembly::make_parts;
use crate::generate::model::Recipe;
use crate::recipe::{parse_yaml, RawRecipe};
use glam::DVec3;

/// Resolves recipe `text` as if it were a file in `tests/fixtures/procedural`.
fn resolve(text: &str) -> Recipe {
    let raw: RawRecipe = parse_yaml(text, "t.yaml").unwrap_or_else(|e| panic!("{e}"));
    crate::recipe::resolve(&raw, &[], None, &fixture("")).unwrap_or_else(|e| panic!("{e}"))
}

fn resolve_err(text: &str) -> String {
    let raw: RawRecipe = parse_yaml(text, "t.yaml").unwrap_or_else(|e| panic!("{e}"));
    match crate::recipe::resolve(&raw, &[], None, &fixture("")) {
        Ok(_) => panic!("resolved:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_turtles_let_chain_is_bounded() {
    // one `let` of 12,000 names, each from the one before: refused at the
    // cap, not 1.5 GB of scopes
    let names: String = (0..12_000)
        .map(|k| match k {
            0 => "v0: 1".to_string(),
            _ => format!(", v{k}: v{} + 1", k - 1),
        })
        .collect();
    let text = format!(
        "p3dp: 1\nname: t\nparts:\n  - name: p\n    primitive:\n      turtle:\n        program:\n          - let: {{{names}}}\n          - forward: v10\n"
    );
    let e = resolve_err(&text);
    assert!(e.contains("v256") && e.contains("at most 256"), "{e}");
    // within the cap a chain works
    let few: String = (0..200)
        .map(|k| match k {
            0 => "v0: 1".to_string(),
            _ => format!(", v{k}: v{} + 1", k - 1),
        })
        .collect();
    let ok = format!(
        "p3dp: 1\nname: t\nparts:\n  - name: p\n    primitive:\n      turtle:\n        program:\n          - let: {{{few}}}\n          - forward: v199\n"
    );
    let r = resolve(&ok);
    assert_eq!(r.parts.len(), 1);
}

const TWO_HELICES: &str = "p3dp: 1
name: two
parts:
  - name: pair
    parts:
      - {name: a, primitive: {helix: {radius: 8, height: 2, pitch: 0.25, center: [-15, 0, 0.2]}}}
      - {name: b, primitive: {helix: {radius: 5, height: 3, pitch: 0.25, center: [15, 4, 0.2]}}}
    steps:
      - deform_cylinder: {position: [\"r*(1 + 0.1*sin(3*theta))\", \"theta + 0.02*z\", \"z + 0.01*r\"], cross_section: \"c*(1 + 0.001*r)\"}
";

/// The parts of `recipe` with their own steps only (no group step).
fn without_groups(recipe: &Recipe) -> Vec<Toolpath> {
    let mut r = recipe.clone();
    r.groups.clear();
    make_parts(&r).unwrap()
}

#[test]
fn a_groups_deformation_applies_to_every_string_of_every_child() {
    let recipe = resolve(TWO_HELICES);
    assert_eq!(recipe.parts.len(), 2);
    assert_eq!(recipe.groups.len(), 1);
    let before = without_groups(&recipe);
    let after = make_parts(&recipe).unwrap();
    for (p0, p1) in before.iter().zip(&after) {
        assert_eq!(p0.name, p1.name);
        assert_eq!(p0.points.len(), p1.points.len());
        for (p, q) in p0.points.iter().zip(&p1.points) {
            let (r, theta) = polar(*p);
            let want = DVec3::new(
                r * (1.0 + 0.1 * (3.0 * theta).sin()) * (theta + 0.02 * p.z).cos(),
                r * (1.0 + 0.1 * (3.0 * theta).sin()) * (theta + 0.02 * p.z).sin(),
                p.z + 0.01 * r,
            );
            assert!(
                (*q - want).length() < 1e-6,
                "{}: {p} went to {q}, expected {want}",
                p0.name
            );
        }
        for k in 0..p0.len() {
            let r = polar(p0.midpoint(k)).0;
            let want = p0.strings[k].c * (1.0 + 0.001 * r);
            assert!((p1.strings[k].c - want).abs() < 1e-9);
            assert_eq!(p1.strings[k].v, p0.strings[k].v);
        }
    }
}

#[test]
fn in_a_group_i_and_n_count_the_points_of_all_its_parts() {
    let (head, _) = TWO_HELICES.split_once("      - deform_cylinder").unwrap();
    let text = format!("{head}      - deform_xyz: {{position: [x, y, \"z + 0.001*i + n\"]}}\n");
    let recipe = resolve(&text);
    let before = without_groups(&recipe);
    let after = make_parts(&recipe).unwrap();
    let n: usize = before.iter().map(|t| t.points.len()).sum();
    let mut i = 0;
    for (p0, p1) in before.iter().zip(&after) {
        for (p, q) in p0.points.iter().zip(&p1.points) {
            assert!((q.z - (p.z + 0.001 * i as f64 + n as f64)).abs() < 1e-9);
            i += 1;
        }
    }
    assert_eq!(i, n);
}

#[test]
fn a_group_subdivides_its_parts_and_keeps_them_apart() {
    let text = TWO_HELICES.replace(
        "    steps:\n",
        "    steps:\n      - subdivide: {max_length: 0.2}\n",
    );
    let recipe = resolve(&text);
    let before = without_groups(&recipe);
    let after = make_parts(&recipe).unwrap();
    for (p0, p1) in before.iter().zip(&after) {
        assert!(p1.len() > 2 * p0.len(), "{} → {}", p0.len(), p1.len());
        // the ends of each part stay its own (deformed) ends
        assert!(p1.strings.iter().all(|s| !s.travel));
        assert!((p1.points[0].z - (p0.points[0].z + 0.01 * polar(p0.points[0]).0)).abs() < 1e-9);
    }
}

#[test]
fn after_a_groups_subdivide_n_counts_the_parts_points_only() {
    let (head, _) = TWO_HELICES.split_once("      - deform_cylinder").unwrap();
    let text = format!(
        "{head}      - subdivide: {{max_length: 0.2}}\n      - deform_xyz: {{position: [x, y, \"z + 0.000001*n\"]}}\n"
    );
    let recipe = resolve(&text);
    let before = without_groups(&recipe);
    let after = make_parts(&recipe).unwrap();
    let n: usize = after.iter().map(|t| t.points.len()).sum();
    for (p0, p1) in before.iter().zip(&after) {
        assert!(p1.points.len() > 2 * p0.points.len());
        for (p, q) in [
            (p0.points[0], p1.points[0]),
            (*p0.points.last().unwrap(), *p1.points.last().unwrap()),
        ] {
            assert!((q.z - (p.z + 1e-6 * n as f64)).abs() < 1e-12, "{p} {q} {n}");
        }
    }
}

#[test]
fn names_of_copies_and_template_params() {
    let recipe = resolve(
        "p3dp: 1
name: n
params: {size: 4}
templates:
  dot:
    params: {rad: size, h: \"2*rad\"}
    part:
      name: dot
      primitive: {helix: {radius: rad, height: h, pitch: 0.5, center: [0, 0, 0.2]}}
parts:
  - {template: dot, for: {k: \"1..2\"}, with: {rad: \"k\"}}
  - {template: dot, for: {k: [3, 4.5]}, name: \"big-{k}\", with: {rad: k}}
  - {template: dot, name: plain}
  - {name: grid, for: {p: [0, 1], q: [0, 1]}, primitive: {circle: {radius: 2, center: [\"9*p\", \"9*q\", 0.2]}}}
  - {for: {p: [0, 1]}, primitive: {circle: {radius: 1}}}
",
    );
    let names: Vec<&str> = recipe.parts.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "dot-0", "dot-1", "big-3", "big-4.5", "plain", "grid-0-0", "grid-0-1", "grid-1-0",
            "grid-1-1", "part 10", "part 11"
        ]
    );
    // a default over an earlier template param, with its `with` value
    let helix = |k: usize| match &recipe.parts[k].primitive {
        crate::generate::primitive::Primitive::Helix(h) => (h.radius, h.height),
        other => panic!("{other:?}"),
    };
    assert_eq!(helix(0), (1.0, 2.0));
    assert_eq!(helix(3), (4.5, 9.0));
    assert_eq!(helix(4), (4.0, 8.0));
    assert_eq!(recipe.parts[1].place, "parts[0] (template dot, k = 2)");
    assert_eq!(recipe.parts[8].place, "parts[3] (p = 1, q = 1)");
}

#[test]
fn errors_name_the_place_through_the_chain() {
    let base = "p3dp: 1
name: e
templates:
  ring:
    params: {k0: 0}
    part:
      name: ring
      primitive: {helix: {radius: \"5 - 2*k0\", height: 1, pitch: 0.25}}
parts:
  - name: row
    parts:
      - {primitive: {circle: {radius: 3}}}
      - {template: ring, for: {k: \"0..4\"}, with: {k0: k}}
";
    let e = resolve_err(base);
    assert!(
        e.contains(
            "parts[0].parts[1] (template ring, k = 3).primitive.helix.radius: -1 is not allowed"
        ),
        "{e}"
    );
    let e = resolve_err(&base.replace("with: {k0: k}", "with: {k1: k}"));
    assert!(
        e.contains("parts[0].parts[1] (k = 0).with.k1: template `ring` has no param `k1`"),
        "{e}"
    );
    let e = resolve_err(&base.replace("template: ring,", "template: rign,"));
    assert!(
        e.contains("(k = 0).template: unknown template `rign`; the templates are ring"),
        "{e}"
    );
    let e = resolve_err(&base.replace("{k: \"0..4\"}", "{theta: \"0..4\"}"));
    assert!(
        e.contains("parts[0].parts[1].for.theta: `theta` cannot name a loop variable"),
        "{e}"
    );
    let e = resolve_err(&base.replace("\"0..4\"", "\"0..k0\""));
    assert!(
        e.contains("parts[0].parts[1].for.k: unknown name `k0`"),
        "{e}"
    );
    let e = resolve_err(&base.replace("name: row", "name: \"row\\nG28\""));
    assert!(
        e.contains("parts[0].name: contains a line break (U+000A)"),
        "{e}"
    );
    let e = resolve_err(&base.replace("name: ring\n", "name: \"ring\\r{k0}\"\n"));
    assert!(
        e.contains("parts[0].parts[1] (template ring, k = 0).name"),
        "{e}"
    );
    let e = resolve_err(&base.replace("{primitive: {circle: {radius: 3}}}", "{parts: []}"));
    assert!(
        e.contains("parts[0].parts[0].parts: expected at least one part"),
        "{e}"
    );
    let e = resolve_err(&base.replace("name: row\n", "name: row\n    speed: 3\n"));
    assert!(
        e.contains("parts[0].speed: a group has no strings of its own"),
        "{e}"
    );
    let e = resolve_err(&base.replace("{primitive: {circle: {radius: 3}}}", "{primitive: []}"));
    assert!(
        e.contains("parts[0].parts[0].primitive: expected at least one primitive"),
        "{e}"
    );
    let e = resolve_err(&base.replace(
        "{primitive: {circle: {radius: 3}}}",
        "{with: {a: 1}, primitive: {circle: {radius: 3}}}",
    ));
    assert!(
        e.contains(
            "parts[0].parts[0].with: `with` gives the params of a template or an included recipe"
        ),
        "{e}"
    );
}

#[test]
fn expansion_is_bounded_before_it_is_made() {
    let many = "p3dp: 1
name: m
parts:
  - {for: {a: \"1..200\"}, parts: [{for: {b: \"1..200\"}, primitive: {circle: {radius: 1}}}]}
";
    let start = std::time::Instant::now();
    let e = resolve_err(many);
    assert!(
        e.contains("parts[0] (a = 51).parts[0].for: this `for` makes 200 copies after 10000 parts"),
        "{e}"
    );
    assert!(start.elapsed().as_secs() < 20);
    // a part list nested 40 deep
    let mut part = "{primitive: {circle: {radius: 1}}}".to_string();
    for _ in 0..40 {
        part = format!("{{parts: [{part}]}}");
    }
    let e = resolve_err(&format!("p3dp: 1\nname: d\nparts: [{part}]\n"));
    assert!(e.contains("nested more than 32 deep"), "{e}");
    // the strings of all parts together
    let e = resolve_err(
        "p3dp: 1
name: s
parts:
  - {for: {a: \"1..100\"}, primitive: {helix: {radius: 10, height: 100, pitch: 0.001}}}
",
    );
    assert!(e.contains("for the whole recipe"), "{e}");
}

/// The sampler: four plates of plate.yaml, named by their cycles, each where
/// its `for` value put it, its rim's wave with that many cycles.
#[test]
fn plate_sampler_lays_out_plates_of_3_to_6_cycles() {
    let recipe = crate::recipe::load(&recipe("plate-sampler.yaml"), &[], None).unwrap();
    let names: Vec<&str> = recipe.parts.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["plate-3", "plate-4", "plate-5", "plate-6"]);
    let param = |n: &str| recipe.params[n];
    let (spacing, size, depth, wave, foot) = (
        param("spacing"),
        param("size"),
        param("depth"),
        param("wave"),
        param("bottom_top"),
    );
    let parts = make_parts(&recipe).unwrap();
    for (j, tp) in parts.iter().enumerate() {
        let k = 3 + j;
        let centre = DVec3::new(
            ((j % 2) as f64 - 0.5) * spacing,
            ((j / 2) as f64 - 0.5) * spacing,
            0.0,
        );
        // the bottom's spiral starts at the plate's centre
        let start = tp.points[0];
        assert!(
            (start.truncate() - centre.truncate()).length() < 1e-9,
            "{}",
            tp.name
        );
        // the wall: r = size + 1.05 h and z = foot + 0.3 h + wave (h/depth) sin(k theta)
        let n0 = recipe.parts[j].primitive.string_count() as usize;
        let mut crest = 0;
        for p in &tp.points[n0..] {
            let (r, theta) = polar(*p - centre);
            let h = (r - size) / 1.05;
            let want = foot + 0.3 * h + wave * (h / depth) * (k as f64 * theta).sin();
            assert!(
                (p.z - want).abs() < 1e-6,
                "{}: {p}: z {} vs {want}",
                tp.name,
                p.z
            );
            crest += usize::from((want - foot - 0.3 * h) > 0.99 * wave);
        }
        assert!(crest > 0);
        // the rim's last turn has k crests
        let seg = param("wall_segments") as usize;
        let rim: Vec<f64> = tp.points[tp.points.len() - seg..]
            .iter()
            .map(|p| p.z)
            .collect();
        let maxima = rim
            .windows(3)
            .filter(|w| w[1] > w[0] && w[1] >= w[2])
            .count();
        assert_eq!(maxima, k, "{}", tp.name);
    }
}

/// The tiered lamp shade: every tier, a use of one template, has its own
/// radius profile, twisted with the others by the group's one step; the
/// tiers meet end to start on the base ring.
#[test]
fn lamp_shade_tiers_follow_their_templates_profile() {
    let path = recipe("lamp-shade-tiers.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    let raw: RawRecipe = parse_yaml(&text, "lamp-shade-tiers.yaml").unwrap();
    let recipe = crate::recipe::load(&path, &[], None).unwrap();
    let names: Vec<&str> = recipe.parts.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["base", "tier-1", "tier-2", "tier-3"]);
    let (ripple, twist, lift) = (
        recipe.params["ripple"],
        recipe.params["twist"],
        recipe.params["lift"],
    );
    let uses = raw.parts[0].parts.as_ref().unwrap();
    let parts = make_parts(&recipe).unwrap();
    for (t, tp) in parts.iter().enumerate().skip(1) {
        let with = |k: &str| match &uses[t].with[k] {
            crate::recipe::schema::RawParam::Num(crate::recipe::schema::Num::Value(v)) => *v,
            other => panic!("{other:?}"),
        };
        let (r0, r1, h, z0, lobes) = (with("r0"), with("r1"), with("h"), with("z0"), with("lobes"));
        for p in &tp.points {
            let (r, theta) = polar(*p);
            let s = (p.z - z0 - lift) / h;
            assert!(
                (-1e-9..=1.0 + 1e-9).contains(&s),
                "{}: z = {}",
                tp.name,
                p.z
            );
            let want = (r0 + (r1 - r0) * s)
                * (1.0 + ripple * (PI * s).sin() * (lobes * (theta - twist * p.z)).sin());
            assert!(
                (r - want).abs() < 1e-6,
                "{}: {p}: r = {r}, expected {want}",
                tp.name
            );
        }
        // each tier starts where the one below ends (the first on the base ring)
        let below = &parts[t - 1];
        assert!(
            (tp.points[0] - *below.points.last().unwrap()).length() < 1e-9,
            "{}",
            tp.name
        );
    }
    assert!(parts[0]
        .points
        .iter()
        .all(|p| (polar(*p).0 - 45.0).abs() < 1e-9));
}

fn fixture(name: &str) -> PathBuf {
    root().join("tests/fixtures/procedural").join(name)
}
