//! What a command with no typed meaning does, per firmware: the commands
//! the checks know to leave the head, the filament and the heaters alone,
//! to move the head within the firmware's own limits, or to heat as their
//! parameters say — and those refused, with why. A command in none of the
//! tables is refused as one p3dp cannot check.
//!
//! A maker's own command goes here, in the table of the flavours that run
//! it (Bambu's `M1002` in [`BAMBU`], Prusa's `M862.3` in [`PRUSA`]).

use crate::base::gcode::lex::Code;
use crate::base::gcode::Heater;
use crate::machine::Flavor;

/// What a command does, as far as the checks need to know.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Kind {
    /// Leaves the head, the filament and the heaters alone (messages,
    /// reports, timers, lights, waits).
    Inert,
    /// Moves the head (and maybe the filament) within the firmware's own
    /// limits: homing, probing, levelling, parking, wiping, loading
    /// filament, a printer's macro. The position is unknown after it.
    Firmware,
    /// Heats: the listed keys are temperatures of the heaters named.
    Heats(&'static [(&'static str, Heater)]),
    /// Moves the head within the firmware's own limits (as [`Kind::Firmware`])
    /// and heats: the listed keys are temperatures (a maker's nozzle wipe or
    /// flush at a temperature it names).
    MovesAndHeats(&'static [(&'static str, Heater)]),
    /// Offsets the coordinates by the key's value, at most the given mm
    /// either way (Bambu's z trim for a plate's thickness): more is refused.
    Trim(&'static str, f64),
    /// Accepted in a profile's own start and end G-code, whose every move
    /// p3dp checks itself, and refused in a recipe's command: why it is
    /// refused there.
    FrameOnly(&'static str),
    /// Refused, and why — unless the line gives one of the alternatives,
    /// each a set of words with their values (the last of a repeated word,
    /// as the firmware reads it), which [`Only`] says when to accept.
    RefusedUnless(
        &'static [&'static [(&'static str, f64)]],
        Only,
        &'static str,
    ),
    /// Refused, and why.
    Refused(&'static str),
}

/// When a [`Kind::RefusedUnless`] line's values are accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Only {
    /// Anywhere: the values set what p3dp assumes already (`M200 D0`: E
    /// read as filament length; `M211 S1`: the soft endstops on; `M206 X0
    /// Y0 Z0`: no home offset); other words may follow.
    Assumed,
    /// In a profile's own start or end G-code, with no other word: the
    /// firmware's resting state set again by the maker's own sequence,
    /// the head's position unknown after it.
    Resting,
}

use Kind::{Firmware, FrameOnly, Heats, Inert, MovesAndHeats, Refused, RefusedUnless, Trim};

const MOTORS_OFF: &str = "turns the motors off, and the printer loses the head's position: an end G-code's command, not one in the middle of a print";
const SHIFTS: &str =
    "shifts the coordinates or the machine's geometry, so p3dp could not check the moves after it";
const SETTINGS: &str = "rewrites or reloads the firmware's stored settings, which p3dp cannot see";
const STOPS: &str = "stops or restarts the firmware, or updates it";
const LIMIT: &str = "changes a safety limit of the firmware";
const FILES: &str = "starts, changes or deletes files on the printer";
const EXTRUSION: &str = "changes how E is read (volumetric, steps per mm, direction), so the filament fed would not be what p3dp wrote";
const MOTION: &str = "moves a motor outside the firmware's planner or limits";
const PINS: &str = "drives the controller's pins or a tool (a heater could be one of them)";

/// M codes of Marlin and its descendants (Prusa's, Bambu's).
const MARLIN_M: &[(u32, Kind)] = &[
    // Sailfish's waits (MakerBot's, FlashForge's and Dremel's printers, whose
    // presets say `marlin`): `M6 T` for the tool, `M7 T` for the platform to
    // reach its temperature; no heat of their own (Marlin's M7 is a
    // coolant pin, which no printer's configuration enables)
    (6, Inert),
    (7, Inert),
    (17, Inert),
    (18, FrameOnly(MOTORS_OFF)),
    (20, Inert),
    (21, Inert),
    (22, Inert),
    (23, Refused(FILES)),
    (24, Refused(FILES)),
    (25, Inert),
    (26, Refused(FILES)),
    (27, Inert),
    (28, Refused(FILES)),
    (29, Refused(FILES)),
    (30, Refused(FILES)),
    (31, Inert),
    (32, Refused(FILES)),
    (33, Inert),
    (34, Inert),
    (42, Refused(PINS)),
    (43, Refused(PINS)),
    (48, Firmware),
    (75, Inert),
    (76, Inert),
    (77, Inert),
    (78, Inert),
    (80, Inert),
    (81, Inert),
    (84, FrameOnly(MOTORS_OFF)),
    (85, Inert),
    (86, Inert),
    (92, Refused(EXTRUSION)),
    // Sailfish's "recall stored home offsets" (MakerBot's and FlashForge's
    // printers, after G161/G162 or G28): the axes take the machine's own
    // calibrated home position, which p3dp does not know until the next
    // absolute move; Marlin does not know the code and skips it
    (132, Firmware),
    (100, Inert),
    (105, Inert),
    (106, Inert),
    (107, Inert),
    (108, Inert),
    (110, Inert),
    (111, Inert),
    (112, Refused(STOPS)),
    (113, Inert),
    (114, Inert),
    (115, Inert),
    (117, Inert),
    (118, Inert),
    (119, Inert),
    (120, Refused(LIMIT)),
    (121, Refused(LIMIT)),
    (122, Inert),
    (125, Firmware),
    (143, Refused(LIMIT)),
    (145, Inert),
    (
        149,
        Refused(
            "changes the temperature units, so the temperatures after it would be read otherwise",
        ),
    ),
    (150, Inert),
    (154, Inert),
    (155, Inert),
    (163, Refused(EXTRUSION)),
    (164, Refused(EXTRUSION)),
    (165, Refused(EXTRUSION)),
    (
        200,
        RefusedUnless(&[&[("D", 0.0)], &[("S", 0.0)]], Only::Assumed, EXTRUSION),
    ),
    (205, Inert),
    (
        206,
        RefusedUnless(
            &[&[("X", 0.0), ("Y", 0.0), ("Z", 0.0)]],
            Only::Assumed,
            SHIFTS,
        ),
    ),
    (208, Inert),
    (209, Inert),
    (211, RefusedUnless(&[&[("S", 1.0)]], Only::Assumed, LIMIT)),
    (217, Inert),
    (218, Refused(SHIFTS)),
    (226, Inert),
    (240, Inert),
    (250, Inert),
    (256, Inert),
    (260, Refused(PINS)),
    (261, Refused(PINS)),
    (280, Inert),
    (281, Inert),
    (290, Refused(SHIFTS)),
    (300, Inert),
    (301, Refused(LIMIT)),
    (302, Inert),
    (303, Heats(&[("S", Heater::Nozzle(0))])),
    (304, Refused(LIMIT)),
    (350, Refused(EXTRUSION)),
    (351, Refused(EXTRUSION)),
    (355, Inert),
    (400, Inert),
    (401, Firmware),
    (402, Firmware),
    (403, Inert),
    (410, Refused(STOPS)),
    (412, Inert),
    (413, Inert),
    (420, Inert),
    (421, Refused(SHIFTS)),
    (422, Inert),
    (423, Refused(SHIFTS)),
    (425, Refused(SHIFTS)),
    (428, Refused(SHIFTS)),
    (486, Inert),
    (500, Refused(SETTINGS)),
    (501, Refused(SETTINGS)),
    (502, Refused(SETTINGS)),
    (503, Inert),
    (504, Inert),
    (524, Refused(FILES)),
    (540, Inert),
    (569, Refused(EXTRUSION)),
    (575, Inert),
    (592, Refused(EXTRUSION)),
    (600, Firmware),
    (602, Firmware),
    (603, Inert),
    (605, Refused(SHIFTS)),
    (665, Refused(SHIFTS)),
    (666, Refused(SHIFTS)),
    (672, Inert),
    (701, Firmware),
    (702, Firmware),
    (710, Inert),
    (
        810,
        Refused("runs a macro stored in the firmware, which p3dp cannot see"),
    ),
    (851, Refused(SHIFTS)),
    (852, Refused(SHIFTS)),
    (871, Inert),
    (876, Inert),
    (906, Inert),
    (907, Inert),
    (911, Inert),
    (912, Inert),
    (913, Inert),
    (914, Inert),
    (915, Inert),
    (928, Refused(FILES)),
    (997, Refused(STOPS)),
    (999, Refused(STOPS)),
    // makers' own codes, their effect from the comment their presets carry
    // beside them (stock Marlin skips a code it does not know):
    // iQ's housing fan ("turn off housing fan", `S0`)
    (806, Inert),
    // Geeetech's light ("ON Light")
    (2012, Inert),
    // FlashForge's case fan ("M651 S255; start case fan", the Guider 2s;
    // the Adventurer 3 and 4 send the same line): a fan on the housing,
    // no motion, no heat; `M652` ("turn off rear fan", their end G-code)
    // turns it off
    (651, Inert),
    (652, Inert),
    // Anker's planner mode ("Enable v3 jerk and S-curve acceleration"): how
    // the firmware shapes accelerations, no motion or heat of its own
    (4899, Inert),
];

/// G codes of Marlin and its descendants besides the typed ones.
const MARLIN_G: &[(u32, Kind)] = &[
    (
        5,
        Refused("a Bézier move: p3dp checks lines and arcs, not curves"),
    ),
    (12, Firmware),
    (17, Inert),
    (18, Inert),
    (19, Inert),
    (26, Heats(&[("B", Heater::Bed), ("H", Heater::Nozzle(0))])),
    (27, Firmware),
    (29, Firmware),
    (30, Firmware),
    (31, Firmware),
    (32, Firmware),
    (33, Firmware),
    (34, Firmware),
    (35, Firmware),
    (38, Firmware),
    (53, Refused(SHIFTS)),
    (54, Refused(SHIFTS)),
    (55, Refused(SHIFTS)),
    (56, Refused(SHIFTS)),
    (57, Refused(SHIFTS)),
    (58, Refused(SHIFTS)),
    (59, Refused(SHIFTS)),
    (60, Inert),
    (61, Firmware),
    (76, Firmware),
    (80, Firmware),
    (81, Firmware),
    // homing to the axes' minimum and maximum endstops (Sailfish, the
    // firmware of Dremel's and FlashForge's printers; Marlin skips them)
    (161, Firmware),
    (162, Firmware),
];

/// Prusa's own codes (the MK3's and the Buddy firmware's).
const PRUSA: &[(u8, u32, Kind)] = &[
    (b'M', 555, Inert),
    (b'M', 860, Inert),
    (b'M', 861, Inert),
    (b'M', 862, Inert),
    (b'M', 864, Inert),
    (b'M', 1200, Inert),
    (
        b'M',
        1700,
        Heats(&[("S", Heater::Nozzle(0)), ("B", Heater::Bed)]),
    ),
    (b'M', 1977, Inert),
    // the drivers' mode: stealthChop or spreadCycle ("set stealthchop for
    // X Y"); Prusa's firmware reads no direction or steps from it
    (b'M', 569, Inert),
    // filament stuck detection on and off (the XL's)
    (b'M', 591, Inert),
    // the heatbreak fan's target temperature ("reset heatbreak target
    // temp"): the fan cools the heatbreak to it, no heater heats
    (b'M', 142, Inert),
    // a register of the MMU (its pulley's current)
    (b'M', 708, Inert),
    (b'G', 64, Firmware),
    (b'G', 1009, Inert),
    // the MMU's test load of a slot (`P`), Buddy's `M1704` ("Test Load to
    // MMU", `mmu_load_test`): the MMU's motors and the extruder's feed the
    // filament and back, the firmware's own motion
    (b'M', 1704, Firmware),
];

const NOZZLE_T: &[(&str, Heater)] = &[("T", Heater::Nozzle(0))];

/// Bambu's own codes, as Bambu Studio's presets write them (their meaning
/// from the comments the presets carry beside them; a subcode not in
/// [`BAMBU_SUB`] is read as its code). Bambu publishes no reference: a code
/// whose effect the presets do not say is not here, so it is refused as
/// one p3dp cannot check. Where the community's readings (the Bambu Lab
/// forum's "X1 specific G-code" thread, OpenBambuAPI's `gcode.md`, the
/// annotated start G-code of the P2S) differ, the code is given the kind
/// that holds every reading (docs/printers.md).
const BAMBU: &[(u8, u32, Kind)] = &[
    // "reset machine status": every X1, P1 and X1E start G-code of Bambu
    // Studio sends exactly `M290 X40 Y40 Z2.6666666` before its first
    // homing, and Bambu publishes no meaning. Marlin reads M290 as a
    // babystep clamped to ±2 mm (these values are not one); what the
    // firmware does with it, the maker's every print starts with it and
    // prints land where the slicer put them, so these values are the
    // firmware's resting state, not a shift in force during a print. That
    // line is accepted (the position forgotten after it); any other M290
    // is a shift p3dp cannot follow.
    (
        b'M',
        290,
        RefusedUnless(
            &[&[("X", 40.0), ("Y", 40.0), ("Z", 2.666_666_6)]],
            Only::Resting,
            SHIFTS,
        ),
    ),
    // `M901 D4` of the H2 family's "reset machine status": read by the
    // community either as the end of a smooth timelapse at the firmware's
    // safe place or as a pressure-advance mode; at most the firmware's own
    // move to its own place, the position forgotten after it
    (b'M', 901, Firmware),
    // `M562 P<n> E0 B1` … `E1`: the hot end's power off and on again
    // around the toolhead camera's start (Bambu Studio's commit "prevent
    // toolhead camera initialization failure", after `M104 S0`); no
    // temperature of its own, no motion
    (b'M', 562, Inert),
    // a purge line at the firmware's own place and flow
    (b'G', 130, Firmware),
    // nozzle wipes and the purge chute ("wipe mouth", "move to garbage
    // can"), `T` the nozzle's temperature meanwhile
    (b'G', 150, MovesAndHeats(NOZZLE_T)),
    // "plug the heat nozzle" (the H2D's idle nozzle)
    (b'G', 151, Firmware),
    // a homing variant ("G2814 Z0.32")
    (b'G', 2814, Firmware),
    // levelling: probing the plate's area, ABL on and off
    (b'G', 29, Firmware),
    // probing and collision detection ("G380 is same as G38"; "detect
    // obstacles at the bottom of the heated bed")
    (b'G', 380, Firmware),
    (b'G', 3811, Firmware),
    // calibrations at a nozzle temperature (`T`, `U`)
    (
        b'G',
        383,
        MovesAndHeats(&[("T", Heater::Nozzle(0)), ("U", Heater::Nozzle(0))]),
    ),
    (b'G', 387, Firmware),
    (b'G', 389, Firmware),
    // nozzle-clumping ("nozzle wrapped") detection by probing
    (b'G', 39, Firmware),
    (b'G', 390, Firmware),
    // clog detection off
    (b'G', 392, Inert),
    // "push/pop soft endstop status", "turn off soft endstop": the
    // firmware's own limit, which p3dp's envelope check stands in for in
    // the profile's G-code
    (
        b'M',
        211,
        FrameOnly("switches the firmware's soft endstops, which a recipe's command may not"),
    ),
    // "save cali data": the calibration the start G-code just measured
    (
        b'M',
        500,
        FrameOnly("stores the firmware's settings, which a recipe's command may not"),
    ),
    // the AMS's filament change: the block M620 … M621 (every line of it
    // checked), its travel points (`X`, `Y` checked) and cut
    (b'M', 620, Firmware),
    (b'M', 621, Firmware),
    // conditional blocks: M1002 sets a flag, M622 J runs the lines up to
    // M623 if it matches; p3dp checks every line of the block as if it ran
    (b'M', 622, Inert),
    (b'M', 623, Inert),
    // timelapse and AMS bookkeeping around a change (`M628`, `M629`)
    (b'M', 628, Inert),
    (b'M', 629, Inert),
    (b'M', 630, Inert),
    // the H2's toolhead rack (`M640`–`M641`): swaps hot ends
    (b'M', 640, Firmware),
    (b'M', 641, Firmware),
    // "turn off cutter pos comp"
    (b'M', 481, Inert),
    // chamber and gear warning temperatures (warnings only), the air duct
    (b'M', 142, Inert),
    (b'M', 145, Inert),
    // lights, the camera and the lidar, scans and their registration
    (b'M', 960, Inert),
    (b'M', 963, Inert),
    (b'M', 964, Inert),
    (b'M', 969, Inert),
    (b'M', 971, Inert),
    (b'M', 972, Inert),
    (b'M', 973, Inert),
    (b'M', 976, Inert),
    (b'M', 977, Inert),
    // resonance measurement of the axes ("mech mode fast check") and
    // vibration suppression: the head shakes in place
    (b'M', 970, Inert),
    (b'M', 974, Inert),
    (b'M', 975, Inert),
    // a timelapse frame at a parking place (`X`, `Y` checked)
    (b'M', 9711, Firmware),
    // "end timelapse at safe pos", "notify layer change"
    (b'M', 991, Inert),
    // flow-dynamics calibration: it extrudes while it moves
    (b'M', 980, Inert),
    (b'M', 981, Inert),
    (b'M', 982, Inert),
    (b'M', 983, Firmware),
    (b'M', 9833, Firmware),
    (b'M', 984, Firmware),
    (b'M', 985, Inert),
    // the nozzle camera's detection state
    (b'M', 993, Inert),
    // messages, flags and sounds (`gcode_claim_action`, `judge_flag`,
    // the buzzer), mass estimation, detections switched on and off
    (b'M', 1002, Inert),
    (b'M', 1003, Inert),
    (b'M', 1004, Inert),
    (b'M', 1006, Inert),
    (b'M', 1007, Inert),
    (b'M', 1009, Inert),
    (b'M', 1010, Inert),
    (b'M', 1012, Inert),
    (b'M', 1015, Inert),
    (b'M', 1026, Inert),
    (b'M', 1028, Inert),
    // "action before has done 200s insulation": waits
    (b'M', 1030, Inert),
];

/// Bambu's subcodes that do otherwise than their code.
const BAMBU_SUB: &[(u8, u32, u32, Kind)] = &[
    // the z trim for a plate ("clear z-trim value first", "-0.04 for
    // Textured PEI Plate"): a few hundredths of a mm
    (b'G', 29, 1, Trim("Z", 0.5)),
    // ABL on and off
    (b'G', 29, 2, Inert),
    // the flush at the filament's flush temperature (`T`)
    (b'M', 620, 10, MovesAndHeats(NOZZLE_T)),
    // the wipe tower's interface purge at a temperature (`T`)
    (b'M', 620, 13, MovesAndHeats(NOZZLE_T)),
    // the wipe tower's place for later
    (b'M', 620, 14, Inert),
    // the pre-cooling target before the tower (`C`, `P`)
    (
        b'M',
        620,
        15,
        Heats(&[("C", Heater::Nozzle(0)), ("P", Heater::Nozzle(0))]),
    ),
    // each nozzle's first-layer temperature (`S`)
    (b'M', 620, 17, Heats(&[("S", Heater::Nozzle(0))])),
    // detections switched on (runout purge, tangle, air printing)
    (b'M', 620, 22, Inert),
    (b'M', 620, 3, Inert),
    (b'M', 620, 6, Inert),
    // M622.1 S: the default of a flag for older firmware
    (b'M', 622, 1, Inert),
    // "turn on/off deformation compensation", its mode
    (b'M', 983, 1, Inert),
    (b'M', 983, 4, Inert),
    // "reset acc magnitude", "reset left time magnitude": factors back to 1
    (b'M', 201, 2, Inert),
    (b'M', 204, 2, Inert),
    (b'M', 73, 2, Inert),
];

/// RepRapFirmware's codes besides the typed ones and Marlin's it shares.
const REPRAP: &[(u8, u32, Kind)] = &[
    (b'M', 3, Refused(PINS)),
    (b'M', 4, Refused(PINS)),
    (b'M', 5, Refused(PINS)),
    (b'M', 98, Firmware),
    (b'M', 116, Inert),
    (b'M', 291, Inert),
    (b'M', 292, Inert),
    (b'M', 376, Inert),
    (b'M', 452, Refused(PINS)),
    (b'M', 453, Refused(PINS)),
    (b'M', 557, Inert),
    (b'M', 561, Inert),
    (
        b'M',
        568,
        Heats(&[("S", Heater::Nozzle(0)), ("R", Heater::Nozzle(0))]),
    ),
    (b'M', 671, Inert),
];

/// Klipper's extended commands and macros refused by name.
const KLIPPER_REFUSED: &[(&str, &str)] = &[
    ("SET_GCODE_OFFSET", SHIFTS),
    // in a profile's start or end G-code the checks follow it instead
    // (`Checker::kinematic_position`): the axes' positions forgotten, their
    // moves bounded by the machine's span until they are homed again
    ("SET_KINEMATIC_POSITION", SHIFTS),
    ("SET_SKEW", SHIFTS),
    ("SKEW_PROFILE", SHIFTS),
    ("Z_OFFSET_APPLY_PROBE", SETTINGS),
    ("Z_OFFSET_APPLY_ENDSTOP", SETTINGS),
    ("SAVE_CONFIG", SETTINGS),
    ("FORCE_MOVE", MOTION),
    ("MANUAL_STEPPER", MOTION),
    ("SET_STEPPER_ENABLE", MOTION),
    ("SET_EXTRUDER_ROTATION_DISTANCE", EXTRUSION),
    ("SET_EXTRUDER_STEP_DISTANCE", EXTRUSION),
    ("SYNC_EXTRUDER_MOTION", EXTRUSION),
    ("FIRMWARE_RESTART", STOPS),
    ("RESTART", STOPS),
    ("M112", STOPS),
    ("SDCARD_PRINT_FILE", FILES),
    ("SDCARD_RESET_FILE", FILES),
];

/// Klipper's commands that leave the head alone.
const KLIPPER_INERT: &[&str] = &[
    "M105",
    "M114",
    "M115",
    "M117",
    "M118",
    "M400",
    "RESPOND",
    "SET_DISPLAY_TEXT",
    "SET_FAN_SPEED",
    "SET_LED",
    "SET_PIN",
    "SET_IDLE_TIMEOUT",
    "SET_GCODE_VARIABLE",
    "SAVE_VARIABLE",
    "SET_TEMPERATURE_FAN_TARGET",
    "TEMPERATURE_WAIT",
    "BED_MESH_PROFILE",
    "BED_MESH_CLEAR",
    "EXCLUDE_OBJECT_DEFINE",
    "EXCLUDE_OBJECT",
    "TIMELAPSE_TAKE_FRAME",
    "UPDATE_DELAYED_GCODE",
    "M106",
    "M107",
    "M73",
];

fn find<T: Copy>(table: &[(u32, T)], n: u32) -> Option<T> {
    table.iter().find(|(c, _)| *c == n).map(|&(_, k)| k)
}

fn find_lettered(table: &[(u8, u32, Kind)], l: u8, n: u32) -> Option<Kind> {
    table
        .iter()
        .find(|(c, m, _)| *c == l && *m == n)
        .map(|&(_, _, k)| k)
}

/// What `code` does on `flavor`'s firmware; `None` for a command the
/// checks do not know.
pub(crate) fn kind(flavor: Flavor, code: &Code) -> Option<Kind> {
    match (flavor, code) {
        (Flavor::Klipper, Code::Name(n)) if n.contains([' ', '\t']) => {
            // a traditional command whose number runs into other text
            // (`M117 .`): Klipper's `cmd_default` runs M117, M118 and M23
            // on the first word, and answers "Unknown command" to any
            // other (no handler or macro name holds a space)
            match n.split_whitespace().next() {
                Some("M117" | "M118") => Some(Inert),
                Some("M23") => Some(Refused(FILES)),
                _ => Some(Inert),
            }
        }
        (Flavor::Klipper, Code::Name(n)) => {
            if let Some((_, why)) = KLIPPER_REFUSED.iter().find(|(k, _)| k == n) {
                return Some(Refused(why));
            }
            if KLIPPER_INERT.contains(&n.as_str()) {
                return Some(Inert);
            }
            // a printer's own macro (PRINT_START, CLEAN_NOZZLE …) or one of
            // Klipper's levelling commands: it may move anywhere the
            // firmware allows; its temperature words are checked by name
            if n.contains('.') {
                return None;
            }
            Some(Firmware)
        }
        (Flavor::Klipper, Code::Number { letter, number, .. }) => {
            let n = format!("{}{number}", *letter as char);
            if let Some((_, why)) = KLIPPER_REFUSED.iter().find(|(k, _)| *k == n) {
                return Some(Refused(why));
            }
            if KLIPPER_INERT.contains(&n.as_str()) {
                return Some(Inert);
            }
            match (*letter, *number) {
                (b'M', 18 | 84) => Some(FrameOnly(MOTORS_OFF)),
                (b'G', 29 | 80) => Some(Firmware),
                // a printer's macro of that name (Klipper runs no M141):
                // the chamber heater its `S` names
                (b'M', 141 | 191) => Some(MovesAndHeats(&[("S", Heater::Chamber)])),
                // any other code stock Klipper skips is a printer's macro
                // (`G30`, `G31`, `M900` of a Kobra's config), as a named
                // one: it may move where the firmware allows, its
                // temperature words checked by name
                (b'G' | b'M', _) => Some(Firmware),
                _ => None,
            }
        }
        // Buddy's `P0`: the XL parks its tool in the changer's dock (its
        // `PrusaGcodeSuite::P0`, a change to no tool), the firmware's own
        // motion; a machine without a changer does not process it
        (Flavor::Prusa, Code::Name(n)) if n == "P0" => Some(Firmware),
        (_, Code::Name(n)) => named_elsewhere(flavor, n),
        (
            _,
            Code::Number {
                letter,
                number,
                sub,
            },
        ) => {
            let (l, n) = (*letter, *number);
            if let (Flavor::Bambu, Some(sub)) = (flavor, sub) {
                let own = BAMBU_SUB
                    .iter()
                    .find(|(c, m, u, _)| *c == l && *m == n && u == sub);
                if let Some(&(_, _, _, k)) = own {
                    return Some(k);
                }
            }
            let own = match flavor {
                Flavor::Prusa => find_lettered(PRUSA, l, n),
                Flavor::Bambu => find_lettered(BAMBU, l, n),
                Flavor::Reprap => find_lettered(REPRAP, l, n),
                _ => None,
            };
            own.or_else(|| match l {
                b'M' => find(MARLIN_M, n),
                b'G' => find(MARLIN_G, n),
                _ => None,
            })
        }
    }
}

/// A named command on a firmware that has none: Marlin and its descendants
/// answer "unknown command" and go on, so it does nothing; but a line that
/// begins with a parameter is a move under Marlin's `GCODE_MOTION_MODES`,
/// and RepRapFirmware runs its meta commands (`if`, `while`, `set` …).
fn named_elsewhere(flavor: Flavor, n: &str) -> Option<Kind> {
    let b = n.as_bytes();
    let parameter = b.len() >= 2
        && matches!(
            b[0],
            b'X' | b'Y' | b'Z' | b'E' | b'F' | b'I' | b'J' | b'R' | b'P' | b'Q'
        )
        && (b[1].is_ascii_digit() || b[1] == b'.');
    if parameter {
        return Some(Refused(
            "a line that begins with a parameter: Marlin with GCODE_MOTION_MODES runs it as a move",
        ));
    }
    match flavor {
        Flavor::Reprap if n == "ECHO" => Some(Inert),
        Flavor::Reprap => Some(Refused(
            "a RepRapFirmware meta command (conditions, loops, variables): p3dp cannot follow what it runs",
        )),
        _ => Some(Inert),
    }
}
