//! A profile's G-code checked as its firmware reads it: the makers' own
//! sequences pass; each way the old check read a line differently from the
//! firmware (issue 42's hostile corpus) is refused, naming the line.

use glam::DVec3;

use crate::analyse::check::gcode::{check, command, Start};
use crate::base::gcode::{Command, Heater, Setting};
use crate::generate::model::Recipe;

fn recipe_for(printer: &str) -> Recipe {
    let raw: crate::recipe::RawRecipe = crate::recipe::parse_yaml(
        &format!("p3dp: 1\nname: t\nprinter: {printer}\nmaterial: pla\nparts:\n  - primitive: {{helix: {{radius: 10, height: 2, pitch: 0.5}}}}\n"),
        "t.yaml",
    )
    .unwrap();
    crate::recipe::resolve(&raw, &[], None, std::path::Path::new(".")).unwrap()
}

fn recipe() -> Recipe {
    recipe_for("prusa-mk3s")
}

fn refused_on(printer: &str, text: &str) -> String {
    match check("start_gcode", text, &recipe_for(printer), Start::Unknown) {
        Ok(_) => panic!("passed on {printer}: {text}"),
        Err(e) => e.to_string(),
    }
}

fn refused(text: &str) -> String {
    refused_on("prusa-mk3s", text)
}

#[test]
fn a_makers_start_passes_and_keeps_its_lines() {
    let ok = "M862.3 P \"MK3S\" ; model\nG90\nM83\nM104 S215\nM140 S60\nM190 S60\nM109 S215\nG28 W\nG80\nG1 Z0.2 F720\nG1 Y-3 F1000\nG92 E0\nG1 X60 E9 F1000\nG1 X100 E12.5 F1000\nG92 E0\nM221 S95\n\tG4 ; tab\nSET_HEATER_TEMPERATURE HEATER=extruder TARGET=200\nT0";
    let lines = check("start_gcode", ok, &recipe(), Start::Unknown).unwrap();
    assert_eq!(lines.len(), ok.lines().count());
    assert_eq!(lines[0].text, "M862.3 P \"MK3S\" ; model");
    // what the firmware reads comes along: M221 S95 is a flow of 95 %
    assert!(lines
        .iter()
        .any(|l| l.commands == [Command::Set(Setting::Flow(0.95))]));
    let end = "G91\nG1 Z1 F720\nG90\nG1 X0 Y200 F3600\nG2 X20 Y200 I10 J0\nM84";
    check(
        "end_gcode",
        end,
        &recipe(),
        Start::At(DVec3::new(125.0, 105.0, 10.0), 1500.0),
    )
    .unwrap();
}

#[test]
fn unsafe_lines_are_named() {
    let e = refused("G28\nM104 S999");
    assert!(
        e.contains("start_gcode line 2: `M104 S999`: a nozzle temperature of 999 °C"),
        "{e}"
    );
    let e = refused("G28\nG1 Z5\nG1 Z-50 F300");
    assert!(
        e.contains("line 3: `G1 Z-50 F300`: z = -50 mm is below the bed"),
        "{e}"
    );
    assert!(
        refused("G0 X5000 Y5000").contains("x = 5000 mm is outside the machine's travel envelope")
    );
    assert!(refused("G0 X10 Y10 F300000")
        .contains("F300000 is 5000 mm/s, faster than the printer's max_speed"));
    assert!(refused("M140 S200").contains("bed temperature of 200"));
    assert!(refused("G28\nG91\nG1 X-3000").contains("span"));
    assert!(refused("G92 Z0").contains("redefines the coordinates"));
    assert!(
        refused("SET_HEATER_TEMPERATURE HEATER=heater_bed TARGET=180")
            .contains("bed temperature of 180")
    );
    assert!(
        refused("G1 X0 Y0\nG2 X0 Y0 I-100 J0").contains("the arc's sweep: x = -100 mm is outside")
    );
    assert!(refused("G28\nM851 Z-5").contains("shifts the coordinates"));
    assert!(refused("G28\u{2028}M104 S999").contains("line break (U+2028)"));
    assert!(refused("G20").contains("inches"));
}

#[test]
fn lines_are_read_as_the_firmware_reads_them() {
    // the last of a repeated word counts: every value is checked
    assert!(refused("M104 S200 S300").contains("nozzle temperature of 300"));
    // repeated axes with different values: firmwares differ on which counts
    assert!(refused("G1 X100 X5000").contains("X is given 2 times"));
    // a space between letter and number, a subcode
    assert!(refused("M 140 S200").contains("bed temperature of 200"));
    assert!(refused("M109.7 S300").contains("nozzle temperature of 300"));
    // Marlin reads letters in quotes
    assert!(refused("G1 X100 \"Y5000\"").contains("y = 5000 mm"));
    // a letter ends a number: X1E3 is X1 E3, and E3000 feeds 3 m
    assert!(refused("G28\nG1 X1E3000").contains("3000 mm of filament"));
    // autotemp's B is a temperature too
    assert!(refused("M104 S200 B255").contains("nozzle temperature of 255"));
    // a command beginning with a character outside ASCII is an error, not a panic
    assert!(refused("é G1 X5").contains("printable ASCII"));
    assert!(refused("G1 X５").contains("printable ASCII"));
}

#[test]
fn relative_moves_are_followed_where_they_take_the_head() {
    // from an unknown position, moves of 200 mm add up: the second spans
    // 400 mm of a 260 mm envelope
    let e = refused("G28\nG91\nG1 X200\nG1 X200\nG1 X200");
    assert!(e.contains("line 4") && e.contains("span 400 mm"), "{e}");
    // from a known one, where they end is checked
    let e = refused("G28\nG90\nG1 X10 Y10\nG91\nG1 X200\nG1 X200");
    assert!(e.contains("x = 410 mm"), "{e}");
    // back and forth within the machine passes
    check(
        "start_gcode",
        "G28\nG91\nG1 Z5\nG1 Z-5\nG1 X-20\nG1 X20\nG90",
        &recipe(),
        Start::Unknown,
    )
    .unwrap();
}

#[test]
fn coordinate_shifts_limits_and_firmware_updates_are_refused_by_name() {
    for (printer, line, why) in [
        (
            "voron-350",
            "SET_GCODE_OFFSET Z=1",
            "shifts the coordinates",
        ),
        ("voron-350", "G92", "sets every axis to 0"),
        ("voron-350", "M104.1 S200", "cannot check"),
        ("voron-350", "G1 X100 \"Y5000\"", "cannot read"),
        ("rostock-max", "G10 L2 P1 X0", "cannot check"),
        ("rostock-max", "M665 R100", "shifts the coordinates"),
        ("rostock-max", "M666 X1", "shifts the coordinates"),
        ("rostock-max", "M143 S400", "safety limit"),
        ("prusa-mk3s", "M852 I0.1", "shifts the coordinates"),
        ("prusa-mk3s", "M218 T1 X10", "shifts the coordinates"),
        ("prusa-mk3s", "M303 E0 S400 C8", "nozzle temperature of 400"),
        ("prusa-mk3s", "M303 E-1 S200 C8", "bed temperature of 200"),
        ("prusa-mk3s", "M997", "updates it"),
        ("prusa-mk3s", "M221 S1000", "flow factor of 1000 %"),
        ("prusa-mk3s", "M83\nG1 E5000", "5000 mm of filament"),
        ("prusa-mk3s", "M83\nG1 E600\nG1 E600", "in place"),
        ("prusa-mk3s", "M204 P100000", "print acceleration"),
        ("prusa-mk3s", "M203 X5000", "X feed limit"),
        ("prusa-mk3s", "M500", "stored settings"),
        ("prusa-mk3s", "M42 P6 S255", "pins"),
        ("prusa-mk3s", "X100 Y100", "begins with a parameter"),
        ("prusa-mk3s", "G4 P99999999", "dwell"),
    ] {
        let e = refused_on(printer, line);
        assert!(e.contains(why), "{printer}: {line}: {e}");
    }
}

/// Klipper's `SET_KINEMATIC_POSITION` in a maker's start G-code (Z set to
/// 0 where its probe touched the bed, FlyingBear's S1 and InfiMech's TX):
/// the axis's position forgotten, its moves bounded by the machine's span
/// from the point it was given at, until a G28 homes it again; left in
/// force at the end, with words p3dp does not follow, after the firmware
/// moved the head (a relative move), or in a recipe's command, refused.
#[test]
fn set_kinematic_position_forgets_the_axis_until_it_is_homed() {
    let r = recipe_for("voron-350");
    let probe = "G28\nG90\nG1 X110 Y110 F6000\nPROBE\nSET_KINEMATIC_POSITION Z=0 ; Z homing\nG1 Z5\nZ_TILT_ADJUST\nG1 Z10\nG28\nG1 X5 Y5 Z0.3";
    check("start_gcode", probe, &r, Start::Unknown).unwrap();
    for (text, why) in [
        (
            "G28\nPROBE\nSET_KINEMATIC_POSITION Z=0\nG1 Z5",
            "no G28 homes it again",
        ),
        (
            "G28\nSET_KINEMATIC_POSITION Z=0\nG1 Z200\nG1 Z-200\nG28",
            "the Z moves since SET_KINEMATIC_POSITION redefined it span 400 mm",
        ),
        // a second redefinition counts from the first one's point: Y 20
        // and then 300 below Y 300's point span 320 mm of a 360 mm bed+margin
        (
            "G28\nG1 X230 Y300\nSET_KINEMATIC_POSITION Y=0\nG1 Y20\nG1 Y0\nSET_KINEMATIC_POSITION Y=300\nG1 Y-50\nG28",
            "the Y moves since SET_KINEMATIC_POSITION redefined it span 370 mm",
        ),
        (
            "G28\nSET_KINEMATIC_POSITION Z=0\nQUAD_GANTRY_LEVEL\nG91\nG1 Z5\nG90\nG28",
            "a relative Z move after SET_KINEMATIC_POSITION",
        ),
        (
            "G28\nSET_KINEMATIC_POSITION CLEAR=Z\nG28",
            "follows its X, Y and Z words only",
        ),
    ] {
        let e = check("start_gcode", text, &r, Start::Unknown).unwrap_err().to_string();
        assert!(e.contains(why), "{text}: {e}");
    }
    let e = command("SET_KINEMATIC_POSITION Z=0", &r.printer, &r.material).unwrap_err();
    assert!(e.contains("shifts the coordinates"), "{e}");
}

#[test]
fn a_recipes_own_command_may_set_and_wait_never_move() {
    let r = recipe();
    let ok = |t: &str| command(t, &r.printer, &r.material).unwrap_or_else(|e| panic!("{t}: {e}"));
    let no = |t: &str| command(t, &r.printer, &r.material).unwrap_err();
    for t in [
        "M600",
        "m600 ; change filament",
        "M117 layer 10",
        "G4 P500",
        "M106 S255",
        "M104 S215",
        "M900 K0.05",
        "M204 P800",
    ] {
        ok(t);
    }
    assert_eq!(
        ok("M104 S215").commands,
        [Command::Set(Setting::Temperature {
            heater: Heater::Nozzle(0),
            celsius: 215.0,
            wait: false
        })]
    );
    for (t, why) in [
        ("G1 X10 E5", "moves the head"),
        ("G92 E0", "moves the head"),
        ("G28", "moves the head"),
        ("M104 S300", "nozzle temperature of 300"),
        ("M83", "moves the head"),
        ("M221 S150.5", "flow factor"),
        ("T1", "tool change"),
        ("M600\nG1 X0", "one line"),
        ("M600\u{2028}G28", "one line"),
        ("M997", "updates it"),
        ("M143 S300", "safety limit"),
        ("M665 R100", "shifts the coordinates"),
        ("M999", "restarts"),
        ("M112", "stops"),
        ("M218 T1 X5", "shifts the coordinates"),
        ("  ; only a comment", "empty"),
        ("M303 S200", "heats on its own"),
    ] {
        let e = no(t);
        assert!(e.contains(why), "{t}: {e}");
    }
    let k = recipe_for("voron-350");
    assert!(command("BED_MESH_CALIBRATE", &k.printer, &k.material)
        .unwrap_err()
        .contains("moves the head"));
    command("SET_PRESSURE_ADVANCE ADVANCE=0.04", &k.printer, &k.material).unwrap();
    command(
        "SET_VELOCITY_LIMIT SQUARE_CORNER_VELOCITY=5",
        &k.printer,
        &k.material,
    )
    .unwrap();
    // motors off mid-print loses the head's position: refused in a recipe's
    // command on every firmware, still an end G-code's own
    for printer in [
        "prusa-mk3s",
        "voron-350",
        "bambu-x1c",
        "rostock-max",
        "generic-220",
    ] {
        let r = recipe_for(printer);
        for t in ["M84", "M18", "M84 X Y"] {
            let e = command(t, &r.printer, &r.material).unwrap_err();
            assert!(e.contains("turns the motors off"), "{printer} {t}: {e}");
        }
        check("end_gcode", "M104 S0\nM84\n", &r, Start::Unknown)
            .unwrap_or_else(|e| panic!("{printer}: {e}"));
    }
}
