//! Where a maker's machine reaches beyond its bed, from its own G-code: the
//! literal X and Y of the absolute moves in the preset's start and end
//! G-code (a purge at X −48.2 on Bambu's A1, a park at Y −9 on Prusa's
//! CORE One), and of the relative ones from a place such moves set
//! (Comgrow's `G1 X0`, `G1 Y0`, `G91`, `G1 X-2 Y-6`), are the maker's
//! statement of where its head goes. The profile's
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
        // where the literal moves have put the head, per axis: a relative
        // literal move from a known place is as much the maker's statement
        // as an absolute one (Comgrow's `G1 X0`, `G1 Y0`, `G91`,
        // `G1 X-2 Y-6`); anything else that may move the head forgets it
        let mut pos: [Option<f64>; 3] = [None; 3];
        for (n, line) in text.split('\n').enumerate() {
            let code = line.split(';').next().unwrap_or("").trim();
            let mut words = code.split_ascii_whitespace();
            let cmd = words.next().map(str::to_ascii_uppercase);
            match cmd.as_deref() {
                Some("G90") => relative = false,
                Some("G91") => relative = true,
                Some("G0" | "G1") => {
                    for w in words {
                        let k = match w.as_bytes().first() {
                            Some(b'X' | b'x') => 0,
                            Some(b'Y' | b'y') => 1,
                            Some(b'Z' | b'z') => 2,
                            _ => continue,
                        };
                        // a literal number only: a placeholder's value is the print's
                        let Ok(d) = w[1..].parse::<f64>() else {
                            pos[k] = None;
                            continue;
                        };
                        let v = match (relative, pos[k]) {
                            (false, _) => d,
                            (true, Some(p)) => p + d,
                            (true, None) => continue,
                        };
                        pos[k] = Some(v);
                        if k == 2 {
                            let deeper = below.as_ref().is_none_or(|(d, _)| -v > *d);
                            if v < 0.0 && -v <= Envelope::MAX_BELOW_BED && deeper && !relative {
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
                // no motion of the head
                None
                | Some(
                    "G4" | "G21" | "M82" | "M83" | "M104" | "M106" | "M107" | "M109" | "M140"
                    | "M190" | "M117" | "M400",
                ) => {}
                _ => pos = [None; 3],
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
    /// (or relative from a place they set); a placeholder, a relative move
    /// from an unknown place and a move metres away set none.
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
        // a relative literal move from a place the literal moves set
        let start = "G28\nG1 X0 F3000\nG1 Y0\nG91\nG1 X-2 Y-6\nG90\nG1 X10 Y10\nSTART_PRINT\nG91\nG1 Y-40\nG1 Z-3";
        let r = reach(&[("start_gcode", start)], [0.0, 0.0], [300.0, 300.0], 5.0);
        assert_eq!(r.xy, [None, Some([-6.0, 305.0])]);
        assert_eq!(r.below, None);
        assert!(
            r.notes[0].contains("start_gcode line 5: `G1 X-2 Y-6`"),
            "{:?}",
            r.notes
        );
        // a placeholder forgets the axis
        let start = "G1 Y0\nG1 Y{first_layer_print_min[1]}\nG91\nG1 Y-8";
        let r = reach(&[("start_gcode", start)], [0.0, 0.0], [300.0, 300.0], 5.0);
        assert_eq!(r, Reach::default());
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
