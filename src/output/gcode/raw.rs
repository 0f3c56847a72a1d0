//! A printer command a recipe writes itself (`gcode: "M600"`): which the
//! writer takes as it is, and which it refuses because it could not account
//! for them (the head or the filament moved behind its back, a temperature
//! past the checks, the position or the units changed).

use crate::base::safe_text;

/// G-codes that move the head or the filament, or change how positions
/// and E are read: the writer tracks both and could not check them.
const G_REFUSED: &str = "every G-code but G4 (dwell): G0–G3 and G5 move the head, G10/G11 retract (p3dp retracts itself), G28/G29 home and probe, G90–G92 change how positions and E are read, G53–G59 change coordinates";

/// M-codes refused, with why.
const M_REFUSED: &[(&[u32], &str)] = &[
    (
        &[104, 109, 140, 190, 141, 191, 303, 568],
        "sets a temperature the checks would not see (use `nozzle_temp` or `bed_temp`, which are checked)",
    ),
    (
        &[82, 83, 92, 200, 206, 428],
        "changes how E or the position is read",
    ),
    (
        &[207, 208, 209, 218, 290, 851],
        "moves the head or the filament (retraction settings, offsets, baby-steps)",
    ),
    (
        &[220, 221],
        "scales the speeds or the flow the checks and the estimate were made for",
    ),
    (
        &[17, 18, 84, 112, 500, 501, 502, 999],
        "switches the motors off, stops, restarts or rewrites the settings",
    ),
];

/// Klipper commands (macros) known to keep the head and the filament where
/// the writer left them.
const WORDS: &[&str] = &[
    "PAUSE",
    "RESUME",
    "M117",
    "RESPOND",
    "SET_FAN_SPEED",
    "SET_PIN",
];

/// Whether the writer may write `text` as it is: one line, a command that
/// leaves the head, the filament and the temperatures to it. The error
/// says why not.
pub(crate) fn check(text: &str) -> Result<(), String> {
    if let Some(c) = text.chars().find(|&c| safe_text::is_unsafe(c)) {
        return Err(format!(
            "the command holds {c:?}; expected one line of printable text (a line break would start a command of its own)"
        ));
    }
    let code = text.split(';').next().unwrap_or("").trim();
    if code.is_empty() {
        return Err("an empty command; expected a G-code such as M600".into());
    }
    let word = code.split_whitespace().next().unwrap_or("");
    let upper = word.to_ascii_uppercase();
    let mut chars = upper.chars();
    let letter = chars.next();
    let num = chars
        .as_str()
        .split('.')
        .next()
        .unwrap_or("")
        .parse::<u32>()
        .ok();
    match (letter, num) {
        (Some('G'), Some(4)) => Ok(()),
        (Some('G'), Some(_)) => Err(format!(
            "`{word}` is refused: p3dp writes the head's moves itself and could not check this one ({G_REFUSED})"
        )),
        (Some('M'), Some(n)) => match M_REFUSED.iter().find(|(codes, _)| codes.contains(&n)) {
            Some((_, why)) => Err(format!("`{word}` is refused: it {why}")),
            None => Ok(()),
        },
        (Some('T'), Some(_)) => Err(format!(
            "`{word}` is refused: a tool change moves the head and swaps the filament the checks were made for"
        )),
        _ if WORDS.contains(&upper.as_str()) => Ok(()),
        _ => Err(format!(
            "`{word}` is not a command p3dp knows to leave the head and the filament alone; expected an M-code (M600, M117 …), G4, or one of {}",
            WORDS.join(", ")
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_that_leave_the_head_alone_pass() {
        for ok in [
            "M600",
            "m600 ; change filament",
            "M117 layer 10",
            "G4 P500",
            "PAUSE",
            "M106 S255",
        ] {
            assert!(check(ok).is_ok(), "{ok}");
        }
    }

    #[test]
    fn moves_temperatures_and_line_breaks_are_refused() {
        for (bad, why) in [
            ("G1 X10 E5", "moves itself"),
            ("G92 E0", "moves itself"),
            ("G28", "moves itself"),
            ("M104 S300", "nozzle_temp"),
            ("M83", "how E"),
            ("M221 S150", "flow"),
            ("T1", "tool change"),
            ("M600\nG1 X0", "one line"),
            ("M600\u{2028}G28", "one line"),
            ("BED_MESH_CALIBRATE", "knows"),
            ("  ; only a comment", "empty"),
        ] {
            let e = check(bad).unwrap_err();
            assert!(e.contains(why), "{bad}: {e}");
        }
    }
}
