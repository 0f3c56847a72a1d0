//! The commands of Marlin-family makers other than Bambu (issue 39's third
//! phase): each accepted as what its maker's preset says it does, or only
//! where it sets what p3dp assumes, on G-code written for these tests.

use crate::analyse::check::gcode::{check, command, Start};
use crate::generate::model::Recipe;
use crate::machine::Flavor;

/// A recipe printing PLA on a Marlin printer (a bed of 220 × 220 mm).
fn marlin() -> Recipe {
    let raw: crate::recipe::RawRecipe = crate::recipe::parse_yaml(
        "p3dp: 1\nname: t\nprinter: generic-220\nmaterial: pla\nparts:\n  - primitive: {helix: {radius: 10, height: 2, pitch: 0.5}}\n",
        "t.yaml",
    )
    .unwrap();
    let mut r = crate::recipe::resolve(&raw, &[], None, std::path::Path::new(".")).unwrap();
    r.printer.flavor = Flavor::Marlin;
    r
}

fn start(r: &Recipe, text: &str) -> Result<usize, String> {
    check("start_gcode", text, r, Start::Unknown)
        .map(|v| v.len())
        .map_err(|e| e.to_string())
}

/// Anker's planner mode, Geeetech's light, iQ's housing fan, FlashForge's
/// case fan (`M651 S255`, `M652` off), Sailfish's
/// waits for the tool and the platform (`M6`, `M7`): inert, as
/// their presets' comments say; Sailfish's recall of the home offsets is
/// the firmware's own homing, after which the position is unknown (a
/// relative move may not follow before an absolute one).
#[test]
fn makers_codes_with_a_stated_effect_are_known() {
    let r = marlin();
    let seq = "M4899 T3 ; S-curve\nM2012 P8 S1 F100 ; light\nM806 S0 ; housing fan\nG28\nM132 X Y Z A B\nG1 Z50 F420\nG1 X10 Y10\nM7 T0 ; platform\nM6 T0 ; tool\nM651 S255; start case fan\nM652; turn off rear fan";
    assert_eq!(start(&r, seq), Ok(seq.lines().count()));
    let e = start(&r, "G28\nM132 X Y Z A B\nG91\nG1 X-300").unwrap_err();
    assert!(e.contains("more than the machine is wide"), "{e}");
    // a recipe's own command may not home
    let e = command("M132 X Y", &r.printer, &r.material).unwrap_err();
    assert!(e.contains("moves the head"), "{e}");
}

/// `M200`, `M206` and `M211` pass only where they set what p3dp assumes
/// (E as length, no home offset, the soft endstops on), the last of a
/// repeated word as the firmware reads it; otherwise they stay refused.
#[test]
fn a_code_that_sets_the_default_passes_and_no_other() {
    let r = marlin();
    for ok in [
        "M200 D0 ; volumetric off",
        "M200 S0",
        "M211 S1",
        "M206 X0 Y0 Z0",
        "M211 S0 S1",
    ] {
        assert_eq!(start(&r, ok), Ok(1), "{ok}");
    }
    for (bad, why) in [
        ("M200 D1.75", "changes how E is read"),
        ("M200 D0 D1.75", "changes how E is read"),
        ("M211 S0", "changes a safety limit"),
        ("M211 S1 S0", "changes a safety limit"),
        ("M206 Z0", "shifts the coordinates"),
        ("M206 X0 Y0 Z-2", "shifts the coordinates"),
    ] {
        let e = start(&r, bad).unwrap_err();
        assert!(e.contains(why), "{bad}: {e}");
        assert!(e.contains("which sets what p3dp assumes"), "{bad}: {e}");
    }
}

/// Prusa's MMU test load (Buddy's `M1704 P`) and the XL's tool park
/// (`P0`) are the firmware's own motion on Prusa's flavour; Marlin knows
/// neither.
#[test]
fn prusas_mmu_test_load_is_the_firmwares_motion() {
    let mut r = marlin();
    r.printer.flavor = Flavor::Prusa;
    assert_eq!(start(&r, "G28\nM1704 P0\nG1 X10 Y10"), Ok(3));
    let e = start(&r, "G28\nM1704 P0\nG91\nG1 X-300").unwrap_err();
    assert!(e.contains("more than the machine is wide"), "{e}");
    // the XL parks its tool (`P0`): the position is unknown after it
    assert_eq!(start(&r, "G28\nP0 S1 L1 D0 ; park\nG1 X10 Y10"), Ok(3));
    let e = start(&r, "G28\nP0 S1\nG91\nG1 X-300").unwrap_err();
    assert!(e.contains("more than the machine is wide"), "{e}");
    let e = start(&marlin(), "P0 S1").unwrap_err();
    assert!(e.contains("a line that begins with a parameter"), "{e}");
    let e = start(&marlin(), "M1704 P0").unwrap_err();
    assert!(e.contains("`M1704` is a command p3dp cannot check"), "{e}");
}

/// Klipper runs `M117 .` as M117 (its `cmd_default` takes the first word of
/// a command whose number runs into other text), `M23 x.gcode` as M23, and
/// skips any other such line as an unknown command.
#[test]
fn klipper_reads_a_number_run_into_text_as_its_first_word() {
    let mut r = marlin();
    r.printer.flavor = Flavor::Klipper;
    assert_eq!(start(&r, "M117 .\nM118 3.5 done\nM104 .S900"), Ok(3));
    let e = start(&r, "M23 .x.gcode").unwrap_err();
    assert!(e.contains("starts, changes or deletes files"), "{e}");
}
