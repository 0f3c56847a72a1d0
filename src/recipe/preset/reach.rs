//! Where a maker's machine reaches beyond its bed, from its own G-code: the
//! literal X and Y of the absolute moves in the preset's start and end
//! G-code (a purge at X −48.2 on Bambu's A1, a park at Y −9 on Prusa's
//! CORE One) are the maker's statement of where its head goes. The profile's
//! `envelope.x`/`envelope.y` are set to hold them, so the check holds every
//! other move (a computed one, a recipe's, a stranger's edit) to that reach
//! rather than to the bed grown by a flat 5 mm. A literal more than
//! [`Envelope::MAX_REACH`] past the bed extends nothing: the build names it.
//! A literal Z below the bed (Bambu's nozzle pressed on the plate's bare
//! steel to stop it, `G0 Z-1.01`) sets `below_bed`, at most
//! [`Envelope::MAX_BELOW_BED`].

use crate::analyse::check::gcode::vocabulary::{self, Kind};
use crate::base::gcode::lex::{lex, Code, Line, Value};
use crate::machine::firmware;
use crate::machine::printer::Envelope;
use crate::machine::Flavor;

/// What the literal absolute moves of a preset's G-code need.
#[derive(Debug, Default, PartialEq)]
pub(crate) struct Reach {
    /// X and Y ranges beyond the bed grown by the margin.
    pub(crate) xy: [Option<[f64; 2]>; 2],
    /// Depth below z = 0.
    pub(crate) below: Option<f64>,
    /// A note for each, the farthest line named.
    pub(crate) notes: Vec<String>,
}

/// The reach along X and Y that the literal moves of `templates` (for a
/// `flavor` firmware) need beyond a bed spanning `bmin` to `bmax` grown by
/// `margin`, and the depth below the bed. An absolute move's literal X or
/// Y counts; so does a relative move or an arc's whole sweep from a point
/// the literal moves before it fixed (Bambu's A1 mini wipes its nozzle in
/// circles about `Y185`), until a command moves the head on its own.
pub(crate) fn reach(
    templates: &[(&str, &str)],
    bmin: [f64; 2],
    bmax: [f64; 2],
    margin: f64,
    flavor: Flavor,
) -> Reach {
    let mut r = Reacher {
        lo: [bmin[0] - margin, bmin[1] - margin],
        hi: [bmax[0] + margin, bmax[1] + margin],
        bmin,
        bmax,
        why: [None, None],
    };
    let mut below: Option<(f64, String)> = None;
    for (key, text) in templates {
        let mut relative = false;
        // the head's X and Y as the literal moves so far fix them
        let mut pos: [Option<f64>; 2] = [None, None];
        for (n, raw) in text.split('\n').enumerate() {
            let at = || {
                let code = raw.split(';').next().unwrap_or("").trim();
                format!("{key} line {}: `{code}`", n + 1)
            };
            let masked = literal(raw);
            let Some(l) = read_line(flavor, &masked) else {
                pos = [None, None];
                continue;
            };
            let Some(code) = &l.code else { continue };
            let g =
                |n: u32| matches!(code, Code::Number { letter: b'G', number, .. } if *number == n);
            if g(90) {
                relative = false;
            } else if g(91) {
                relative = true;
            } else if g(0) || g(1) {
                if let Some(z) = word(&l, "Z").literal().filter(|_| !relative) {
                    let deeper = below.as_ref().is_none_or(|(d, _)| -z > *d);
                    if z < 0.0 && -z <= Envelope::MAX_BELOW_BED && deeper {
                        below = Some((-z, at()));
                    }
                }
                for (k, axis) in ["X", "Y"].iter().enumerate() {
                    // a literal number only: a placeholder's value is the print's
                    pos[k] = match (word(&l, axis), relative) {
                        (Word::Absent, _) => pos[k],
                        (Word::Known(v), false) => Some(v),
                        (Word::Known(d), true) => pos[k].map(|p| p + d),
                        (Word::Unknown, _) => None,
                    };
                    if let Some(p) = pos[k] {
                        r.extend(k, p, &at);
                    }
                }
            } else if g(2) || g(3) {
                pos = r.arc(&l, pos, relative, g(3), &at);
            } else if !(g(4) || g(92)) && moves_on_its_own(flavor, code) {
                pos = [None, None];
            }
        }
    }
    let mut out = Reach::default();
    for k in 0..2 {
        if let Some(w) = &r.why[k] {
            out.xy[k] = Some([r.lo[k], r.hi[k]]);
            out.notes.push(format!(
                "envelope.{} [{}, {}]: where the maker's own G-code takes the head ({w}), past the bed grown by {margin} mm",
                ["x", "y"][k],
                r.lo[k],
                r.hi[k]
            ));
        }
    }
    if let Some((d, w)) = below {
        out.below = Some(d);
        out.notes.push(format!(
            "envelope.below_bed {d}: where the maker's own G-code takes the nozzle below the bed ({w})"
        ));
    }
    out
}

/// The reach so far, and the line that set each axis's.
struct Reacher {
    lo: [f64; 2],
    hi: [f64; 2],
    bmin: [f64; 2],
    bmax: [f64; 2],
    why: [Option<String>; 2],
}

impl Reacher {
    /// Holds `v` on axis `k`, unless it is more than
    /// [`Envelope::MAX_REACH`] past the bed (the build names that one).
    fn extend(&mut self, k: usize, v: f64, at: &dyn Fn() -> String) {
        let m = Envelope::MAX_REACH;
        if !v.is_finite() || v < self.bmin[k] - m || v > self.bmax[k] + m {
            return;
        }
        if v < self.lo[k] || v > self.hi[k] {
            self.lo[k] = self.lo[k].min(v);
            self.hi[k] = self.hi[k].max(v);
            self.why[k] = Some(at());
        }
    }

    /// A `G2`/`G3` from `pos` with literal words: its whole sweep held;
    /// where it ends, if known.
    fn arc(
        &mut self,
        l: &Line,
        pos: [Option<f64>; 2],
        relative: bool,
        ccw: bool,
        at: &dyn Fn() -> String,
    ) -> [Option<f64>; 2] {
        let (Some(x0), Some(y0)) = (pos[0], pos[1]) else {
            return [None, None];
        };
        if l.has("R") {
            return [None, None];
        }
        let mut to = [x0, y0];
        for (k, p) in to.iter_mut().enumerate() {
            match (word(l, ["X", "Y"][k]), relative) {
                (Word::Absent, _) => {}
                (Word::Known(v), false) => *p = v,
                (Word::Known(d), true) => *p += d,
                (Word::Unknown, _) => return [None, None],
            }
        }
        let mut ij = [0.0; 2];
        for (k, c) in ij.iter_mut().enumerate() {
            match word(l, ["I", "J"][k]) {
                Word::Absent => {}
                Word::Known(v) => *c = v,
                Word::Unknown => return [None, None],
            }
        }
        for p in crate::base::gcode::arc_extremes([x0, y0], to, ij, ccw) {
            self.extend(0, p[0], at);
            self.extend(1, p[1], at);
        }
        [Some(to[0]), Some(to[1])]
    }
}

/// A template's line as the maker states it: a placeholder whose value is
/// a constant (`Y{(0 < 4 ? -7 : -4.5)}`: no variable, no `random`) is the
/// maker's literal, written as the slicer writes it; any other (`{…}`,
/// `[name]`) becomes `?`, a word without a value, which places nothing.
fn literal(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut depth = 0usize;
    let mut square = false;
    let mut from = 0;
    for (i, c) in text.char_indices() {
        match c {
            '{' if !square => {
                if depth == 0 {
                    from = i;
                }
                depth += 1;
            }
            '}' if depth > 0 => {
                depth -= 1;
                if depth == 0 {
                    out.push_str(&constant(&text[from..=i]).unwrap_or_else(|| "?".into()));
                }
            }
            '[' if depth == 0 && !square => {
                square = true;
                out.push('?');
            }
            ']' if square => square = false,
            _ if depth > 0 || square => {}
            _ => out.push(c),
        }
    }
    out
}

/// The value of one placeholder `{…}` that reads no variable.
fn constant(code: &str) -> Option<String> {
    if code.contains("random") {
        return None;
    }
    let t = crate::base::slicer_macro::Template::parse(code).ok()?;
    t.expand_io(&Default::default(), &mut Default::default())
        .ok()
        .map(|(text, _)| text)
}

/// The line read as `flavor`'s firmware reads it (the one reader,
/// [`firmware::read`]: the last of a repeated word, `M 104`, `M104.1`,
/// letters in quotes), `None` when no firmware could read it; a value the
/// firmware reads as text (Klipper's `X?`) leaves its word without one.
fn read_line(flavor: Flavor, text: &str) -> Option<Line<'_>> {
    match firmware::read(flavor, text) {
        Ok(r) => Some(r.line),
        Err(_) => lex(firmware::read::grammar(flavor), text).ok(),
    }
}

/// An axis word of a line as the firmware reads it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Word {
    /// Not given: the axis keeps its place.
    Absent,
    /// Given without a number p3dp knows (a placeholder).
    Unknown,
    /// A literal number.
    Known(f64),
}

impl Word {
    /// The number, if literal.
    fn literal(self) -> Option<f64> {
        match self {
            Word::Known(v) => Some(v),
            _ => None,
        }
    }
}

/// `key`'s word in `l` (the last of a repeated one, as the firmware).
fn word(l: &Line, key: &str) -> Word {
    match l.get(key) {
        None => Word::Absent,
        Some(Value::Number(v)) if v.is_finite() => Word::Known(*v),
        Some(_) => Word::Unknown,
    }
}

/// Whether the command `first` (`G28`, `M620.1`, `T1`) may move the head
/// where the literal moves do not say: any G-code but the moves, a tool
/// change, and what the checks' vocabulary reads as the firmware's own
/// motion (or does not know).
fn moves_on_its_own(flavor: Flavor, code: &Code) -> bool {
    match code {
        Code::Number {
            letter: b'M',
            number,
            ..
        } => {
            !matches!(
                vocabulary::kind(flavor, code),
                Some(Kind::Inert | Kind::Heats(_) | Kind::Trim(..) | Kind::FrameOnly(_))
            ) && !typed_m(*number)
        }
        _ => true,
    }
}

/// M-codes with a typed meaning that leave the head where it is
/// (temperatures, fans, modes, settings, messages, waits).
fn typed_m(n: u32) -> bool {
    matches!(
        n,
        73 | 82 | 83 | 104 | 106 | 107 | 109 | 117 | 140 | 141 | 190 | 191 | 201
            ..=205 | 220 | 221 | 400 | 900
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A purge beside the bed sets the reach on its axis, in absolute mode
    /// only; a placeholder, a relative move and a move metres away set none.
    #[test]
    fn the_makers_literal_moves_set_the_reach() {
        let start = "G28\nG1 X-48.2 Y10 F6000 ; purge\nG91\nG1 X-100 Z-9\nG90\nG1 X{first_layer_print_min[0] - 50}\nG1 Y-500\nG0 Z-1.01 ; stop the nozzle\nG1 Z-40";
        let end = "G1 Y-9 ; park";
        let r = reach(
            &[("start_gcode", start), ("end_gcode", end)],
            [0.0, 0.0],
            [256.0, 256.0],
            5.0,
            Flavor::Bambu,
        );
        assert_eq!(r.xy, [Some([-48.2, 261.0]), Some([-9.0, 261.0])]);
        assert_eq!(r.below, Some(1.01));
        let notes = &r.notes;
        assert_eq!(notes.len(), 3);
        assert!(
            notes[0].contains("start_gcode line 2: `G1 X-48.2 Y10 F6000`"),
            "{notes:?}"
        );
        assert!(notes[1].contains("end_gcode line 1: `G1 Y-9`"), "{notes:?}");
        assert!(
            notes[2].contains("start_gcode line 8: `G0 Z-1.01`"),
            "{notes:?}"
        );
        // within the margin: nothing to set
        let r = reach(
            &[("start_gcode", "G1 X-3 Y260 Z0")],
            [0.0, 0.0],
            [256.0, 256.0],
            5.0,
            Flavor::Bambu,
        );
        assert_eq!(r, Reach::default());
    }

    /// A wipe in circles at the plate's edge: the arcs' sweep from the
    /// point the literal moves fixed sets the reach (Bambu's A1 mini about
    /// `Y185`); after a command that moves the head on its own, or from a
    /// placeholder, the relative moves and arcs set nothing.
    #[test]
    fn relative_moves_and_arcs_from_a_known_point_set_the_reach() {
        let start = "G0 X85 Y185 F10000\nG0 Z-1.01\nG91\nG2 I1 J0 X2 Y0 F2000\nG2 I-0.75 J0 X-1.5\nG1 X-30\nG90";
        let r = reach(
            &[("start_gcode", start)],
            [0.0, 0.0],
            [180.0, 180.0],
            5.0,
            Flavor::Bambu,
        );
        assert_eq!(r.xy, [None, Some([-5.0, 186.0])]);
        assert!(
            r.notes[0].contains("envelope.y [-5, 186]: where the maker's own G-code takes the head (start_gcode line 4: `G2 I1 J0 X2 Y0 F2000`)"),
            "{:?}",
            r.notes
        );
        for before in ["G28", "M620 S0A", "G1 X{a} Y185", "T1", "M901 D4"] {
            let text = format!("G0 X85 Y185\n{before}\nG91\nG2 I1 J0 X2 Y0\nG1 X-100");
            let r = reach(
                &[("start_gcode", &text)],
                [0.0, 0.0],
                [180.0, 180.0],
                5.0,
                Flavor::Bambu,
            );
            assert_eq!(r.xy, [None, None], "after {before}");
        }
        // waits, temperatures and messages keep the point
        let text =
            "G0 X85 Y185\nM400\nM109 S220\nM1002 gcode_claim_action : 2\nG91\nG2 I1 J0 X2 Y0";
        let r = reach(
            &[("start_gcode", text)],
            [0.0, 0.0],
            [180.0, 180.0],
            5.0,
            Flavor::Bambu,
        );
        assert_eq!(r.xy, [None, Some([-5.0, 186.0])]);
        // Comgrow's relative literal move from the corner its absolute
        // ones set; a macro that moves the head forgets the place
        let start = "G28\nG1 X0 F3000\nG1 Y0\nG91\nG1 X-2 Y-6\nG90\nG1 X10 Y10\nSTART_PRINT\nG91\nG1 Y-40\nG1 Z-3";
        let r = reach(
            &[("start_gcode", start)],
            [0.0, 0.0],
            [300.0, 300.0],
            5.0,
            Flavor::Klipper,
        );
        assert_eq!(r.xy, [None, Some([-6.0, 305.0])]);
        assert_eq!(r.below, None);
        assert!(
            r.notes[0].contains("start_gcode line 5: `G1 X-2 Y-6`"),
            "{:?}",
            r.notes
        );
        // a placeholder forgets the axis
        let start = "G1 Y0\nG1 Y{first_layer_print_min[1]}\nG91\nG1 Y-8";
        let r = reach(
            &[("start_gcode", start)],
            [0.0, 0.0],
            [300.0, 300.0],
            5.0,
            Flavor::Marlin,
        );
        assert_eq!(r, Reach::default());
    }
    /// The lines are read as the firmware reads them (the one reader):
    /// `G 1` and `G1X-30` are moves, the last of a repeated word counts, a
    /// letter in quotes is a word on Marlin, `g1` is `G1`; Klipper's
    /// `G1.1` is no move (a command of its own); a placeholder's constant
    /// value is the maker's literal (Prusa's XL 5T parks at
    /// `Y{(0 < 4 ? -7 : -4.5)}`).
    #[test]
    fn the_reach_reads_lines_as_the_firmware_does() {
        let reach_of = |text: &str, flavor: Flavor| {
            reach(
                &[("start_gcode", text)],
                [0.0, 0.0],
                [200.0, 200.0],
                5.0,
                flavor,
            )
            .xy
        };
        for (text, x, y) in [
            ("G 1 X-20", Some([-20.0, 205.0]), None),
            ("G1X-21Y-8", Some([-21.0, 205.0]), Some([-8.0, 205.0])),
            ("G1 X-40 X-22", Some([-22.0, 205.0]), None),
            ("G1 X-23 \"Y-9\"", Some([-23.0, 205.0]), Some([-9.0, 205.0])),
            ("g1 x-24", Some([-24.0, 205.0]), None),
            (
                "G1 X{5 - 30} Y{(0 < 4 ? -7 : -4.5)}",
                Some([-25.0, 205.0]),
                Some([-7.0, 205.0]),
            ),
            (
                "G1 X{first_layer_print_min[0] - 30} Y-10",
                None,
                Some([-10.0, 205.0]),
            ),
            (
                "G1 X[first_layer_print_min] Y-11",
                None,
                Some([-11.0, 205.0]),
            ),
            ("G1 X{random(2, 8) - 40}", None, None),
        ] {
            assert_eq!(reach_of(text, Flavor::Marlin), [x, y], "{text}");
        }
        // Klipper: `G1.1` is a command of its own, the place forgotten
        assert_eq!(
            reach_of("G1 X10 Y10\nG1.1 X5\nG91\nG1 X-30", Flavor::Klipper),
            [None, None]
        );
        assert_eq!(
            reach_of("G1 X10 Y10\nG91\nG1 X-30", Flavor::Klipper),
            [Some([-20.0, 205.0]), None]
        );
        // a placeholder is a word without a value on Klipper too
        assert_eq!(
            reach_of("G1 X{first_layer_print_min[0]} Y-12", Flavor::Klipper),
            [None, Some([-12.0, 205.0])]
        );
    }
}
