//! The makers' own commands, reach and flush temperatures (issue 39's
//! second phase): each as its firmware reads it, on G-code written for
//! these tests in the makers' style.

use crate::analyse::check::gcode::{check, command, Start};
use crate::generate::model::Recipe;
use crate::machine::Flavor;

/// A recipe printing PLA (at most 240 °C, printed at 215) on a bed of
/// 256 × 256 mm whose firmware is `flavor`.
fn on(flavor: Flavor) -> Recipe {
    let raw: crate::recipe::RawRecipe = crate::recipe::parse_yaml(
        "p3dp: 1\nname: t\nprinter: bambu-a1\nmaterial: pla\nparts:\n  - primitive: {helix: {radius: 10, height: 2, pitch: 0.5}}\n",
        "t.yaml",
    )
    .unwrap();
    let mut r = crate::recipe::resolve(&raw, &[], None, std::path::Path::new(".")).unwrap();
    r.printer.flavor = flavor;
    r
}

fn start(r: &Recipe, text: &str) -> Result<usize, String> {
    check("start_gcode", text, r, Start::Unknown)
        .map(|v| v.len())
        .map_err(|e| e.to_string())
}

/// Bambu's sequence commands are read as its firmware reads them: inert
/// ones pass, a motion's coordinates and a heating word are checked, a
/// code whose effect no preset states stays refused by name, as does a
/// babystep other than the maker's own reset (`M290`).
#[test]
fn bambus_own_commands_are_read_as_its_firmware_reads_them() {
    let r = on(Flavor::Bambu);
    let seq = "M1002 gcode_claim_action : 2\nG392 S0 ;turn off clog detect\nM975 S1\nM982.2 S1\nM622.1 S1\nM1002 judge_flag g29_before_print_flag\nM622 J1\nG29 A X10 Y10 I100 J100\nM500 ; save cali data\nM623\nG29.1 Z-0.04 ; Textured PEI Plate\nM211 X0 Y0 Z0 ;turn off soft endstop\nG150 T140 ; wipe\nG150.3 ; garbage can\nM620.10 A0 F74.8 L100 H0.4 T225 S1\nM620.17 T0 S220\nG39 S1 X187 Y178\nM960 S5 P1\nM991 S0 P-1";
    assert_eq!(start(&r, seq), Ok(seq.lines().count()));
    // the same lines on Marlin: Bambu's codes are not Marlin's
    let e = start(&on(Flavor::Marlin), "G392 S0").unwrap_err();
    assert!(
        e.contains("`G392` is a command p3dp cannot check on Marlin"),
        "{e}"
    );
    for (line, why) in [
        ("G150 T999", "`G150 T999`: a nozzle temperature of 999 °C"),
        (
            "M620.10 A0 T400",
            "`M620.10 A0 T400`: a nozzle temperature of 400 °C",
        ),
        (
            "G39 S1 X900 Y178",
            "x = 900 mm is outside the machine's travel envelope",
        ),
        (
            "G29.1 Z-3",
            "offsets the coordinates by Z -3 mm; expected at most 0.5 mm",
        ),
        ("M290 Z0.05", "`M290` is refused: it shifts"),
        ("M9999", "`M9999` is a command p3dp cannot check on Bambu"),
    ] {
        let e = start(&r, line).unwrap_err();
        assert!(e.contains(why), "{line}: {e}");
    }
    // a recipe's own command may not switch the soft endstops, store the
    // settings, or heat on its own
    let p = &r.printer;
    for (c, why) in [
        ("M211 X0 Y0 Z0", "switches the firmware's soft endstops"),
        ("M500", "stores the firmware's settings"),
        ("G150 T200", "it heats on its own"),
    ] {
        let e = command(c, p, &r.material).unwrap_err();
        assert!(e.contains(why), "{c}: {e}");
    }
    assert!(command("M1002 gcode_claim_action : 0", p, &r.material).is_ok());
}

/// Sailfish's homing to the endstops (Dremel's and FlashForge's presets say
/// `marlin`) is the firmware's own motion: the position is unknown after it.
#[test]
fn homing_to_an_endstop_leaves_the_position_unknown() {
    let r = on(Flavor::Marlin);
    assert_eq!(
        start(&r, "G162 Z F600\nG161 X Y F3300\nG91\nG1 X-10\nG90"),
        Ok(5)
    );
    let e = start(&r, "G161 X Y\nG91\nG1 X-300").unwrap_err();
    assert!(
        e.contains("span 300 mm, more than the machine is wide (266 mm)"),
        "{e}"
    );
}

/// A profile's `envelope.x`/`.y` is where its head reaches: the A1's purge
/// at X −48.2 passes, a move past it does not, and the message names the key.
#[test]
fn the_envelope_per_axis_holds_the_profiles_moves() {
    let mut r = on(Flavor::Bambu);
    let purge = "G28\nG1 X-48.2 Y10 F6000\nG1 Y-9";
    let e = start(&r, purge).unwrap_err();
    assert!(
        e.contains("x = -48.2 mm is outside the machine's travel envelope (x from -5 to 261 mm: the bed grown by envelope.margin 5 mm)"),
        "{e}"
    );
    r.printer.envelope.x = Some([-48.2, 261.0]);
    r.printer.envelope.y = Some([-9.0, 261.0]);
    r.printer.validate().unwrap();
    assert_eq!(start(&r, purge), Ok(3));
    let e = start(&r, "G28\nG1 X-49 Y10").unwrap_err();
    assert!(
        e.contains("x = -49 mm is outside the machine's travel envelope (x from -48.2 to 261 mm: the profile's envelope.x)"),
        "{e}"
    );
    // a reach must hold the bed and stay beside it
    for bad in [[10.0, 261.0], [-80.0, 261.0], [f64::NAN, 261.0]] {
        r.printer.envelope.x = Some(bad);
        let e = r.printer.validate().unwrap_err().to_string();
        assert!(e.contains("envelope.x"), "{e}");
    }
}

/// The maker's flush above the material's limit passes in an imported
/// start G-code (held to the printer's limit), never in a hand-written
/// one; and the print never starts above the material's limit.
#[test]
fn a_makers_flush_may_be_hotter_than_the_material_but_not_the_print() {
    let mut r = on(Flavor::Bambu);
    let flush = "M109 S250 ; flush\nG1 E10 F300\nM109 S215";
    let e = start(&r, flush).unwrap_err();
    assert!(
        e.contains("a nozzle temperature of 250 °C, above the limit 240 °C (the material pla's max_nozzle_temp)"),
        "{e}"
    );
    r.printer.maker_temperatures = true;
    assert_eq!(start(&r, flush), Ok(3));
    // past the printer's own limit, still refused
    let e = start(&r, "M109 S310\nM109 S215").unwrap_err();
    assert!(
        e.contains("above the limit 300 °C (the printer's max_nozzle_temp"),
        "{e}"
    );
    // left at the flush temperature: the print would start there
    let e = start(&r, "M109 S215\nM109 S250 ; flush").unwrap_err();
    assert!(
        e.contains("start_gcode line 2: `M109 S250 ; flush`: the print would start at 250 °C, above the limit 240 °C"),
        "{e}"
    );
    // the end G-code is not the maker's flush: the material's limit holds
    let end = check(
        "end_gcode",
        "M104 S250",
        &r,
        Start::At(glam::DVec3::new(100.0, 100.0, 10.0), 0.0),
    );
    assert!(end.is_err());
}

/// Bambu's own codes of the current presets (issue 39): the maker's
/// "reset machine status" `M290 X40 Y40 Z2.6666666` passes, the position
/// forgotten after it; any other M290 is a shift p3dp cannot follow, as is
/// that line in a recipe's command. `M901 D4` may move the head where the
/// firmware goes on its own (the position forgotten); `M562`'s power off
/// and on around the camera's start moves and heats nothing.
#[test]
fn bambus_reset_timelapse_end_and_hot_end_power_are_read() {
    let r = on(Flavor::Bambu);
    let ok = "M290 X40 Y40 Z2.6666666\nM901 D4\nM104 S0\nM562 P1 E0 B1\nM18 E\nM562 P1 E1 B1\nG28\nG1 X10 Y10 Z5";
    assert_eq!(start(&r, ok), Ok(8));
    for (text, why) in [
        ("M290 Z0.5", "`M290` is refused: it shifts the coordinates"),
        (
            "M290 X40 Y40 Z2.6",
            "only the maker's own `M290 X40 Y40 Z2.6666666`",
        ),
        ("M290 X40 Y40 Z2.6666666 S1", "only the maker's own"),
        ("M290 X40 Y40", "only the maker's own"),
    ] {
        let e = start(&r, text).unwrap_err();
        assert!(e.contains(why), "{text}: {e}");
    }
    // the position is unknown after M290 and M901: an arc from there is
    // refused, and the relative moves span at most the machine
    for first in ["M290 X40 Y40 Z2.6666666", "M901 D4"] {
        let e = start(&r, &format!("G1 X10 Y10\n{first}\nG2 X12 Y10 I1 J0")).unwrap_err();
        assert!(
            e.contains("an arc from an unknown position"),
            "{first}: {e}"
        );
    }
    for t in ["M290 X40 Y40 Z2.6666666", "M901 D4"] {
        assert!(command(t, &r.printer, &r.material).is_err(), "{t}");
    }
    command("M562 P1 E1 B1", &r.printer, &r.material).unwrap();
    // on Marlin M562 and M901 are no known command; M290 a babystep
    let m = on(Flavor::Marlin);
    assert!(start(&m, "M901 D4").is_err());
    assert!(start(&m, "M290 X40 Y40 Z2.6666666").is_err());
}

/// The H2's nozzle load line (issue 39): after homing, a relative arc (a
/// helical circle `G3 Z0.4 I1.217 J0`) from a position unknown in Y is held
/// as the relative lines are (its sweep on a known X inside the envelope,
/// on Y within the machine's width), its filament bounded; a line that
/// starts with no letter and holds no number is no command to Marlin and
/// reads as nothing, one with a number stays refused.
#[test]
fn a_relative_arc_from_an_unknown_position_and_a_banner_line() {
    let r = on(Flavor::Bambu);
    let ok = "G28\nG90\nG1 X250 F6000\nM83\nG1 E5 F300\nG91\nG3 Z0.4 I1.217 J0 F6000\nG90\n    ========== record data ==========";
    assert_eq!(start(&r, ok), Ok(ok.lines().count()));
    for (text, why) in [
        // the known X swept past the bed
        (
            "G28\nG1 X250\nG91\nG3 I10 J0",
            "the arc's sweep: x = 270 mm is outside",
        ),
        // circles whose Y offsets span more than the machine
        (
            "G28\nG91\nG3 I0 J150\nG3 I0 J-150",
            "the relative X moves since the position was last known span 300 mm",
        ),
        (
            "G28\nG1 X100\nG91\nG3 I1 J0 E1500",
            "feeds 1500 mm of filament",
        ),
        // absolute words from an unknown start
        (
            "G28\nG90\nG3 X10 Y10 I1 J0",
            "an arc from an unknown position",
        ),
        ("=G1 X500", "does not start with a command"),
    ] {
        let e = start(&r, text).unwrap_err();
        assert!(e.contains(why), "{text}: {e}");
    }
}
