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
use crate::base::gcode::lex::Code;
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
        for (n, line) in text.split('\n').enumerate() {
            let code = line.split(';').next().unwrap_or("").trim();
            let at = || format!("{key} line {}: `{}`", n + 1, code);
            let mut words = code.split_ascii_whitespace();
            let Some(first) = words.next().map(str::to_ascii_uppercase) else {
                continue;
            };
            let words: Vec<(usize, Option<f64>)> = words.filter_map(axis_word).collect();
            match first.as_str() {
                "G90" => relative = false,
                "G91" => relative = true,
                "G0" | "G1" => {
                    for &(k, v) in &words {
                        if k == 2 {
                            let Some(v) = v.filter(|_| !relative) else {
                                continue;
                            };
                            let deeper = below.as_ref().is_none_or(|(d, _)| -v > *d);
                            if v < 0.0 && -v <= Envelope::MAX_BELOW_BED && deeper {
                                below = Some((-v, at()));
                            }
                            continue;
                        }
                        if k > 2 {
                            continue;
                        }
                        // a literal number only: a placeholder's value is the print's
                        pos[k] = match (v, relative) {
                            (Some(v), false) => Some(v),
                            (Some(d), true) => pos[k].map(|p| p + d),
                            (None, _) => None,
                        };
                        if let Some(p) = pos[k] {
                            r.extend(k, p, &at);
                        }
                    }
                }
                "G2" | "G3" => {
                    pos = r.arc(&words, pos, relative, first == "G3", &at);
                }
                "G4" | "G92" => {}
                _ if moves_on_its_own(flavor, &first) => pos = [None, None],
                _ => {}
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
        words: &[(usize, Option<f64>)],
        pos: [Option<f64>; 2],
        relative: bool,
        ccw: bool,
        at: &dyn Fn() -> String,
    ) -> [Option<f64>; 2] {
        let word = |k: usize| words.iter().rev().find(|w| w.0 == k).map(|w| w.1);
        let (Some(x0), Some(y0)) = (pos[0], pos[1]) else {
            return [None, None];
        };
        let mut to = [x0, y0];
        for (k, p) in to.iter_mut().enumerate() {
            match (word(k), relative) {
                (None, _) => {}
                (Some(Some(v)), false) => *p = v,
                (Some(Some(d)), true) => *p += d,
                (Some(None), _) => return [None, None],
            }
        }
        let mut ij = [0.0; 2];
        for (k, c) in ij.iter_mut().enumerate() {
            match word(3 + k) {
                None => {}
                Some(Some(v)) => *c = v,
                Some(None) => return [None, None],
            }
        }
        for p in crate::base::gcode::arc_extremes([x0, y0], to, ij, ccw) {
            self.extend(0, p[0], at);
            self.extend(1, p[1], at);
        }
        [Some(to[0]), Some(to[1])]
    }
}

/// A word's axis (0 X, 1 Y, 2 Z, 3 I, 4 J) and its literal value (`None`
/// for a placeholder); `None` for any other word.
fn axis_word(w: &str) -> Option<(usize, Option<f64>)> {
    let k = match w.as_bytes().first()?.to_ascii_uppercase() {
        b'X' => 0,
        b'Y' => 1,
        b'Z' => 2,
        b'I' => 3,
        b'J' => 4,
        _ => return None,
    };
    Some((k, w[1..].parse::<f64>().ok()))
}

/// Whether the command `first` (`G28`, `M620.1`, `T1`) may move the head
/// where the literal moves do not say: any G-code but the moves, a tool
/// change, and what the checks' vocabulary reads as the firmware's own
/// motion (or does not know).
fn moves_on_its_own(flavor: Flavor, first: &str) -> bool {
    let (head, sub) = match first.split_once('.') {
        Some((h, s)) => (h, s.parse::<u32>().ok()),
        None => (first, None),
    };
    let letter = head.as_bytes().first().copied().unwrap_or(b'?');
    let Ok(number) = head[1..].parse::<u32>() else {
        return true;
    };
    match letter {
        b'M' => {
            let code = Code::Number {
                letter,
                number,
                sub,
            };
            !matches!(
                vocabulary::kind(flavor, &code),
                Some(Kind::Inert | Kind::Heats(_) | Kind::Trim(..) | Kind::FrameOnly(_))
            ) && !typed_m(number)
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
}
