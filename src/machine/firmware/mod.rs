//! The printer's language, per firmware: the one reader of G-code lines
//! ([`read`]: a line into typed commands, cut by the firmware's own parser
//! rules), the one writer ([`write`]: typed commands into a dialect's
//! text), and the firmware's state as commands run ([`state`]).

pub(crate) mod read;
pub(crate) mod state;
pub(crate) mod write;

pub(crate) use read::read;
pub(crate) use state::{Motion, State};
pub(crate) use write::Dialect;

#[cfg(test)]
mod tests;

use crate::machine::printer::Flavor;

/// What the G-code's header says of `flavor`'s arcs: Marlin (ARC_SUPPORT),
/// Prusa, RepRapFirmware and Bambu run `G2`/`G3`; Klipper with a
/// `[gcode_arcs]` section.
pub(crate) fn arc_note(flavor: Flavor) -> &'static str {
    match flavor {
        Flavor::Klipper => "arcs need `[gcode_arcs]` in printer.cfg",
        Flavor::Marlin => "arcs need ARC_SUPPORT (on in Marlin 2's default configuration)",
        Flavor::Prusa | Flavor::Reprap | Flavor::Bambu => "arcs are supported",
    }
}

/// How the dialect's stock firmware cuts an arc into straight moves (see
/// [`crate::base::geom::arc::Firmware`]): Marlin 2 in chords of at most 1 mm and at
/// least 72 a turn; Klipper's `[gcode_arcs]` in 1 mm chords; Prusa's,
/// Bambu's and RepRapFirmware are taken as 1 mm chords too (the cautious choice).
pub(crate) fn arc_firmware(flavor: Flavor) -> crate::base::geom::arc::Firmware {
    crate::base::geom::arc::Firmware {
        max_chord: 1.0,
        min_circle_segments: if flavor == Flavor::Marlin { 72 } else { 0 },
    }
}
