//! The `output-package` warning: a file written in a package the printer's
//! firmware cannot read — Prusa's binary G-code (`.bgcode`) for a printer
//! without Prusa's Buddy firmware, Bambu Lab's `.gcode.3mf` for a printer
//! that is not theirs. A warning, not an error: the user may know better
//! (a profile of a Buddy printer with an unknown model, a host that unpacks).

use super::see;
use crate::base::finding::{Finding, Severity};
use crate::base::safe_text::one_line;
use crate::machine::{Flavor, Printer};

/// A package some printers take instead of plain G-code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Packed {
    /// Prusa's binary G-code, `.bgcode`.
    Bgcode,
    /// Bambu Lab's `.gcode.3mf`.
    Bambu,
}

/// The Prusa printers whose firmware is Buddy, which reads binary G-code,
/// as their `model` names them (an `IS` suffix, the input shaper presets',
/// taken off first); the MK3S's firmware and the older ones' do not.
const BUDDY: [&str; 11] = [
    "MINI", "MK4", "MK4S", "MK3.5", "MK3.5S", "MK3.9", "MK3.9S", "XL", "COREONE", "COREONEL", "IX",
];

/// Bambu Lab's printers as their `model` names them (`Bambu Lab`
/// prefix, spaces and dashes taken off), and the model ids of their
/// packages (`BL-P001`, an X1 Carbon's…).
const BAMBU: [&str; 24] = [
    "X1C", "X1CARBON", "X1", "X1E", "P1P", "P1S", "P2S", "A1", "A1MINI", "A1M", "H2D", "H2DPRO",
    "H2S", "BLP001", "BLP002", "C11", "C12", "C13", "N1", "N2S", "O1D", "O1S", "N7", "O1E",
];

/// `model` upper-case without spaces, dashes and underscores.
fn plain(model: &str) -> String {
    model
        .trim()
        .to_ascii_uppercase()
        .chars()
        .filter(|c| !matches!(c, ' ' | '-' | '_'))
        .collect()
}

/// Whether `printer` is one of Bambu Lab's: the `bambu` flavour, or a
/// model of theirs (the built-ins speak their Marlin dialect, `marlin`).
fn is_bambu(printer: &Printer) -> bool {
    let model = plain(&printer.model);
    let model = model.strip_prefix("BAMBULAB").unwrap_or(&model);
    printer.flavor == Flavor::Bambu || BAMBU.contains(&model)
}

/// Whether `printer` runs Prusa's Buddy firmware: the `prusa` flavour and a
/// Buddy model, or a profile that says it writes binary G-code
/// (`binary_gcode`, as PrusaSlicer's printers that read it do).
fn reads_bgcode(printer: &Printer) -> bool {
    let model = plain(&printer.model);
    let model = model.strip_suffix("IS").unwrap_or(&model);
    (printer.flavor == Flavor::Prusa && BUDDY.contains(&model)) || printer.binary_gcode
}

/// `, model M` of a printer whose model is known.
fn model_of(printer: &Printer) -> String {
    if printer.model.trim().is_empty() {
        String::new()
    } else {
        format!(", model {}", one_line(printer.model.trim()))
    }
}

/// The `output-package` warning when `packed` does not suit `printer`.
pub(crate) fn output_package(packed: Packed, printer: &Printer) -> Option<Finding> {
    let name = one_line(&printer.name);
    let flavour = printer.flavor.name();
    let message = match packed {
        Packed::Bgcode if !reads_bgcode(printer) => format!(
            "binary G-code (.bgcode) is read by Prusa's Buddy firmware (MINI, MK4, MK3.5, XL, Core One); the printer `{name}` ({flavour} flavour{}) may not read it: expected -o NAME.gcode",
            model_of(printer)
        ),
        Packed::Bambu if !is_bambu(printer) => format!(
            "a .gcode.3mf is Bambu Lab's package, which their printers read; the printer `{name}` ({flavour} flavour{}) is not one of theirs: expected -o NAME.gcode",
            model_of(printer)
        ),
        _ => return None,
    };
    Some(Finding {
        code: "output-package",
        severity: Severity::Warning,
        message: format!("{message}{}", see("output-package")),
        part: None,
        string: None,
        at: None,
        strings: Vec::new(),
    })
}
