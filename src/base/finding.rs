//! What the checks find: a stable code, a severity, a message and a place;
//! the list of codes and which of them are the machine's safety limits.

use serde::Serialize;

use crate::base::error::{Error, Result};

/// How bad a finding is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// Worth knowing (e.g. a short bridge); never fails a build.
    Info,
    /// Printable, but worth a look; fails the build under `--strict`.
    Warning,
    /// Not printable as it stands; fails the build.
    Error,
}

impl Severity {
    /// `info`, `warning` or `error`.
    pub fn word(self) -> &'static str {
        match self {
            Severity::Info => "info",
            Severity::Warning => "warning",
            Severity::Error => "error",
        }
    }
}

/// Every code a finding may carry, with what it means (for `allow:` and docs).
pub const CODES: &[(&str, &str)] = &[
    ("non-finite", "a point is not a finite number (error)"),
    ("out-of-bed", "a point lies outside the bed (error)"),
    ("below-bed", "a point lies below z = 0 (error)"),
    ("above-max-z", "a point lies above the highest reachable z (error)"),
    ("nozzle-temp", "the nozzle temperature is above the material's or printer's limit (error)"),
    ("bed-temp", "the bed temperature is above the printer's limit (error)"),
    ("speed", "a string runs faster than the printer's max_speed (error)"),
    ("setting", "a `set` step's or command's setting the printer's firmware has no command for, or a value past the material's or machine's limits (error)"),
    ("flow", "c·v above the hot end's max_flow (warning; error past checks.flow_hard_max × max_flow)"),
    ("over-extrusion", "a cross-section far above what the nozzle lays (warning; error past the hard limit)"),
    ("thin-string", "a cross-section so small the string breaks (warning; error past the hard limit)"),
    ("klipper-extrusion", "a move a Klipper printer refuses: a cross-section past its extruder's max_extrude_cross_section (4 × nozzle² by default), or an extrude-only move past max_extrude_only_distance (error)"),
    ("starvation", "runs of moves shorter in time than the planner's minimum segment time (warning)"),
    ("unsupported", "filament with neither the bed nor earlier filament under it (error)"),
    ("first-layer", "the nozzle closer to the bed than checks.first_layer_min × its diameter (warning); each part's bed contact is in the report and the stats' first_layer"),
    ("small-contact", "a part stands on less bed than its height and mass need (checks.min_contact_per_height, min_contact_per_gram): add a brim or a stand (warning)"),
    ("bridge", "a string spanning a gap between supported ends (info; warning when longer than checks.max_bridge)"),
    ("nozzle-collision", "the nozzle's cone passes through filament printed earlier (error)"),
    ("head-collision", "the head's box passes through filament printed earlier (warning: the box is an estimate)"),
    ("pattern-range", "a pattern_helix parameter outside the paper's ranges (warning)"),
    ("pattern-modulated", "a pattern_helix whose strings are modulated (warning)"),
    ("output-package", "the output is a package the printer's firmware does not read: .bgcode without Prusa's Buddy firmware, .gcode.3mf for a printer not Bambu Lab's (warning)"),
];

/// The machine's safety limits: a move outside the printer's volume, a
/// temperature past a limit, a speed past the axes' or a point that is no
/// number. No `allow:` or `--allow` silences them; only `--force` writes past
/// them, so a shared recipe can never switch them off for its user.
pub const SAFETY: &[&str] = &[
    "non-finite",
    "out-of-bed",
    "below-bed",
    "above-max-z",
    "nozzle-temp",
    "bed-temp",
    "speed",
    "setting",
];

/// Whether `code` is one of [`CODES`].
pub(crate) fn is_code(code: &str) -> bool {
    CODES.iter().any(|(c, _)| *c == code)
}

/// Checks the codes of an allow list; `place(i)` names entry i in errors.
pub(crate) fn validate_allow(codes: &[String], place: impl Fn(usize) -> String) -> Result<()> {
    for (i, c) in codes.iter().enumerate() {
        if !is_code(c) {
            let known: Vec<&str> = CODES.iter().map(|(c, _)| *c).collect();
            return Err(Error::input(
                place(i),
                format!(
                    "unknown check code `{c}`; expected one of {}",
                    known.join(", ")
                ),
            ));
        }
        if SAFETY.contains(&c.as_str()) {
            return Err(Error::input(
                place(i),
                format!(
                    "`{c}` is a safety limit of the machine and cannot be allowed; \
                     expected a code other than {}; `--force` writes the G-code past it",
                    SAFETY.join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// What an error of an allowed code says: `allow` did not silence it.
pub(crate) const ALLOWED_ERROR: &str =
    "; `allow` silences warnings and notes only: an error stays one, and only --force writes past it";

/// Removes the warnings and notes whose code is in `allow` (silenced for
/// this build). An error stays (as `p3dp explain` and docs/checks.md say):
/// only `--force` writes past it; its message says why it was not silenced.
pub(crate) fn apply_allow(findings: &mut Vec<Finding>, allow: &[String]) {
    if allow.is_empty() {
        return;
    }
    findings.retain_mut(|f| {
        if !allow.iter().any(|a| a == f.code) {
            return true;
        }
        if f.severity == Severity::Error && !f.message.ends_with(ALLOWED_ERROR) {
            f.message.push_str(ALLOWED_ERROR);
        }
        f.severity == Severity::Error
    });
}

/// `3 warnings, 0 errors` (and `, 2 notes` when there are infos).
pub(crate) fn summary(findings: &[Finding]) -> String {
    let count = |s: Severity| findings.iter().filter(|f| f.severity == s).count();
    let (e, w, i) = (
        count(Severity::Error),
        count(Severity::Warning),
        count(Severity::Info),
    );
    let pl = |n: usize| if n == 1 { "" } else { "s" };
    let mut s = format!("{w} warning{}, {e} error{}", pl(w), pl(e));
    if i > 0 {
        s.push_str(&format!(", {i} note{}", pl(i)));
    }
    s
}

/// One finding: a stable code, a severity and the place.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Finding {
    /// Stable code, e.g. `out-of-bed`.
    pub code: &'static str,
    /// Warning or error.
    pub severity: Severity,
    /// What was found, with numbers.
    pub message: String,
    /// The part's name, when the finding is in one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub part: Option<String>,
    /// Index of the first string concerned.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub string: Option<usize>,
    /// Recipe coordinates of the first place concerned.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at: Option<[f64; 3]>,
    /// Every string concerned in `part`, as ranges [first, end) of string
    /// indices (empty: only `string`), so a preview can show them all.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub strings: Vec<[usize; 2]>,
}

/// Errors, and warnings when `strict`: the findings that fail a build (infos never do).
pub(crate) fn failing(findings: &[Finding], strict: bool) -> Vec<&Finding> {
    findings
        .iter()
        .filter(|f| f.severity == Severity::Error || (strict && f.severity == Severity::Warning))
        .collect()
}
