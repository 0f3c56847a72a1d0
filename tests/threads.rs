//! One thread budget: a build gives the same bytes whatever `Options.threads`
//! (and `-j`) allows, on a vase large enough that its deform step is split
//! among threads.

mod common;

use common::*;
use p3dp::build::{plan, Options};
use p3dp::threads::Threads;

/// A scaled-down `benches/vase-2m.yaml`: 60 turns of 1000 strings, so the
/// deform step (60,000 points and strings) crosses `PAR_MIN` = 50,000.
const VASE: &str = r#"p3dp: 1
name: vase-60k
printer: generic-220
material: pla
params:
  radius: 30
  height: 6
  lobes: 6
defaults:
  cross_section: 0.08
  speed: 40
parts:
  - name: vase
    primitive:
      helix: { radius: radius, height: height, pitch: 0.1, segments: 1000, center: [0, 0, 0.2] }
    steps:
      - deform_cylinder:
          position: ["r*(0.8 + 0.2*sin(pi*z/height)) + 2*sin(lobes*theta + z/20)", theta, z]
          cross_section: "c*(1.2 - 0.4*z/height)"
"#;

#[test]
fn the_vase_is_the_same_bytes_on_1_2_and_4_threads() {
    let dir = tmp("threads-vase");
    let path = dir.join("vase.yaml");
    std::fs::write(&path, VASE).unwrap();
    let build = |n: usize| {
        let opts = Options {
            threads: Threads::new(n),
            ..Default::default()
        };
        let p = plan(&path, &opts).unwrap();
        assert!(p.paths.iter().map(|t| t.len()).sum::<usize>() > 50_000);
        let mut out = Vec::new();
        let stats = p.render(&mut out).unwrap();
        (out, stats.gcode_sha256, p.findings.len())
    };
    let one = build(1);
    for n in [2, 4] {
        let other = build(n);
        assert!(one.0 == other.0, "{n} threads changed the G-code");
        assert_eq!(one.1, other.1);
        assert_eq!(one.2, other.2);
    }
    // and through the binary: -j 1 and -j 4 write the same hash
    let hash = |j: &str| {
        let o = p3dp(&dir, &["hash", "-j", j, "vase.yaml"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap()
    };
    assert_eq!(hash("1"), hash("4"));
    assert!(hash("1").starts_with(&one.1));
}
