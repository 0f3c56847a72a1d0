//! The gallery of Kanada's prints (cup, plates, heart, vases, deformed sphere,
//! lamp shades) through the public face: each recipe plans cleanly, starts on
//! the bed and passes the binary's checks. Their geometry, part by part and
//! step by step, is checked in `internals::gallery`.

use std::path::PathBuf;

use glam::DVec3;
use p3dp::plan;
use p3dp::testing::Insides;
use p3dp::testing::Toolpath;
use p3dp::Severity;

/// Every recipe of the gallery.
const GALLERY: [&str; 8] = [
    "cup.yaml",
    "plate.yaml",
    "heart-plate.yaml",
    "vase.yaml",
    "twisted-heart-vase.yaml",
    "deformed-sphere.yaml",
    "lamp-shade.yaml",
    "lamp-shade-textured.yaml",
];

pub(crate) fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("recipes")
        .join(name)
}

/// Points of extruding strings (both ends).
pub(crate) fn extruding_points(tp: &Toolpath) -> impl Iterator<Item = DVec3> + '_ {
    (0..tp.len())
        .filter(|&k| !tp.strings[k].travel)
        .flat_map(|k| [tp.points[k], tp.points[k + 1]])
}

#[test]
fn every_gallery_recipe_plans_cleanly_and_starts_on_the_bed() {
    for name in GALLERY {
        let plan = plan(&path(name), &Default::default()).unwrap_or_else(|e| panic!("{e}"));
        let errors: Vec<_> = plan
            .findings
            .iter()
            .filter(|f| f.severity == Severity::Error)
            .collect();
        assert!(errors.is_empty(), "{name}: {errors:?}");
        // and no warning either (flow under the hot end's limit)
        assert!(plan.findings.is_empty(), "{name}: {:?}", plan.findings);
        let lowest = plan
            .paths()
            .iter()
            .flat_map(extruding_points)
            .map(|p| p.z)
            .fold(f64::INFINITY, f64::min);
        assert!(
            (0.0..=0.5).contains(&lowest),
            "{name}: lowest extruding point at z = {lowest}"
        );
        for tp in plan.paths() {
            assert!(tp.len() < 300_000, "{name}: {} has {}", tp.name, tp.len());
            for s in tp.strings.iter().filter(|s| !s.travel) {
                assert!(
                    (0.05..=0.3).contains(&s.c) && (3.0..=60.0).contains(&s.v),
                    "{name}: {} has a string with c = {}, v = {}",
                    tp.name,
                    s.c,
                    s.v
                );
            }
        }
    }
}

#[test]
fn the_binary_checks_every_gallery_recipe_clean() {
    // `p3dp check` on every recipe of recipes/, the gallery's among them
    // (one run, shared with checks::the_gallery_has_no_errors)
    let stdout = crate::checks::gallery_checked();
    for name in GALLERY {
        assert!(path(name).is_file(), "{name}");
        let line = stdout
            .lines()
            .find(|l| l.starts_with(&format!("{}:", path(name).display())))
            .unwrap_or_else(|| panic!("no line for {name} in\n{stdout}"));
        assert!(line.ends_with("0 warnings, 0 errors"), "{line}");
    }
}
