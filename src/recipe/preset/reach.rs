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

use crate::machine::printer::Envelope;

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

/// The reach along X and Y that the literal absolute moves of `templates`
/// need beyond a bed spanning `bmin` to `bmax` grown by `margin`, and the
/// depth below the bed.
pub(crate) fn reach(
    templates: &[(&str, &str)],
    bmin: [f64; 2],
    bmax: [f64; 2],
    margin: f64,
) -> Reach {
    let mut lo = [bmin[0] - margin, bmin[1] - margin];
    let mut hi = [bmax[0] + margin, bmax[1] + margin];
    let mut why: [Option<String>; 2] = [None, None];
    let mut below: Option<(f64, String)> = None;
    for (key, text) in templates {
        let mut relative = false;
        for (n, line) in text.split('\n').enumerate() {
            let code = line.split(';').next().unwrap_or("").trim();
            let mut words = code.split_ascii_whitespace();
            match words.next().map(str::to_ascii_uppercase).as_deref() {
                Some("G90") => relative = false,
                Some("G91") => relative = true,
                Some("G0" | "G1") if !relative => {
                    for w in words {
                        let k = match w.as_bytes().first() {
                            Some(b'X' | b'x') => 0,
                            Some(b'Y' | b'y') => 1,
                            Some(b'Z' | b'z') => 2,
                            _ => continue,
                        };
                        // a literal number only: a placeholder's value is the print's
                        let Ok(v) = w[1..].parse::<f64>() else {
                            continue;
                        };
                        if k == 2 {
                            let deeper = below.as_ref().is_none_or(|(d, _)| -v > *d);
                            if v < 0.0 && -v <= Envelope::MAX_BELOW_BED && deeper {
                                below = Some((-v, format!("{key} line {}: `{}`", n + 1, code)));
                            }
                            continue;
                        }
                        let m = Envelope::MAX_REACH;
                        if !v.is_finite() || v < bmin[k] - m || v > bmax[k] + m {
                            continue;
                        }
                        if v < lo[k] || v > hi[k] {
                            lo[k] = lo[k].min(v);
                            hi[k] = hi[k].max(v);
                            why[k] = Some(format!("{key} line {}: `{}`", n + 1, code));
                        }
                    }
                }
                _ => {}
            }
        }
    }
    let mut out = Reach::default();
    for k in 0..2 {
        if let Some(w) = &why[k] {
            out.xy[k] = Some([lo[k], hi[k]]);
            out.notes.push(format!(
                "envelope.{} [{}, {}]: where the maker's own G-code takes the head ({w}), past the bed grown by {margin} mm",
                ["x", "y"][k],
                lo[k],
                hi[k]
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
        );
        assert_eq!(r, Reach::default());
    }
}
