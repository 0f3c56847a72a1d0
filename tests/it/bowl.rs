//! The bowl of Kanada's Fig. 12 (right): a dome printed upside down, its
//! stand on it. The letters on the dome are checked in `internals::bowl`.

use crate::common::*;
use p3dp::testing::Insides;

#[test]
fn dome_is_a_half_sphere_on_the_bed_and_the_stand_sits_on_it() {
    let plan = p3dp::plan(&recipe("bowl.yaml"), &Default::default()).unwrap();
    assert!(plan.failing(false).is_empty(), "{:?}", plan.findings);
    let dome = plan.paths().iter().find(|t| t.name == "dome").unwrap();
    for p in &dome.points {
        let d = (p.truncate().length().powi(2) + (p.z - 0.3).powi(2)).sqrt();
        assert!((d - 40.0).abs() < 1e-9, "off the sphere by {}", d - 40.0);
    }
    // rim on the bed, closed at the pole
    assert_eq!(dome.points[0].z, 0.3);
    assert!(dome.head().truncate().length() < 1e-9);
    let stand = plan.paths().iter().find(|t| t.name == "stand").unwrap();
    let s0 = stand.points[0];
    // the stand starts on the dome where its radius is 14
    let dome_z = 0.3 + (40f64.powi(2) - 14f64.powi(2)).sqrt();
    assert!((s0.truncate().length() - 14.0).abs() < 1e-9);
    assert!(
        s0.z - dome_z > 0.0 && s0.z - dome_z < 0.3,
        "{} vs {dome_z}",
        s0.z
    );
}
