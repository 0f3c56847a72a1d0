//! The `solid` primitive through the public face: a cross-section it would
//! ignore is refused on loading. Its z-buffer, loops and strings are checked
//! in `internals::solid`.

use crate::common;

#[test]
fn a_solid_refuses_a_cross_section_it_would_ignore() {
    let dir = common::tmp("solid-cross-section");
    let path = dir.join("c.yaml");
    let text = "p3dp: 1\nname: c\nprinter: generic-220\nmaterial: pla\nparts:\n  - name: solid\n    cross_section: 0.15\n    primitive:\n      solid: {layer_height: 0.2, line_width: 0.45, features: [{box: {center: [0, 0, 1], size: [10, 10, 2]}}]}\n";
    std::fs::write(&path, text).unwrap();
    let e = p3dp::testing::load_recipe(&path, &[], None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("cross_section") && e.contains("0.09"), "{e}");
    // the bead's own value is accepted
    std::fs::write(&path, text.replace("0.15", "0.09")).unwrap();
    p3dp::testing::load_recipe(&path, &[], None).unwrap();
}
