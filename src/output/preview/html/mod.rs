//! The HTML preview: one self-contained file (no network, works from
//! `file://`) with a WebGL 2 viewer of the moves the G-code makes.
//!
//! The viewer shows exactly the G-code's moves, read back from the G-code
//! text: point k is where move k ends, for every G0/G1 line that names X, Y or
//! Z (retractions, which move only E, are not points). Short strings merged by
//! the G-code writer are therefore one move here too. The path travels as
//! base64 of little-endian binary: positions as f32 triples (recipe
//! coordinates, mm), feed rates as u16 (mm/min, as written), cross-sections and
//! the spacing to the neighbouring pass as u16 fractions of their maxima, the
//! surface normal as three i8 (× 127; zero where the move has no neighbouring
//! pass), and one kind byte per move (0 travel, 1 extruding, 2 extruding where
//! a check found a problem, 3 a G1 that does not extrude). The viewer draws
//! each move as the PNG preview does (see [`super`]): a flat tube h across and
//! c / h thick, lit by its normal.
//!
//! The G-code is read back by `gcode` (as it is written, nothing of it
//! kept but what the viewer draws), the page filled in by `page`; this
//! module finds each move's surface and writes the viewer's data.

mod gcode;
mod page;

pub(crate) use gcode::Reader;
pub(crate) use page::{page_with, write_page};

use std::collections::HashSet;
use std::io::Write;

use base64::Engine;
use glam::DVec3;
use serde_json::json;

use self::page::script_json;
use super::{Options, Scene};
use crate::analyse::plan::Plan;
use crate::analyse::stats::Stats;
use crate::base::format::hms;
use crate::base::geom::passes::Grid;
use crate::base::par;

fn b64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// Moves per piece of work when the surfaces are found; a multiple of
/// [`REFRESH`], and fixed, so that the answer does not depend on the
/// thread count.
const PIECE: usize = 1 << 14;

/// Every this many moves, the neighbouring pass is searched in full rather
/// than followed from the last move's ([`Grid::follow_other`]).
const REFRESH: usize = 32;

/// Per extruding move, the spacing to the neighbouring pass (`h`, mm) and the
/// surface normal (i8 × 127), from the moves of the same part; in pieces of
/// [`PIECE`] moves taken by the pool's threads ([`par::each`]).
fn surfaces(r: &Reader, scene: &Scene) -> (Vec<f64>, Vec<i8>) {
    let n = r.to.len();
    let (mut h, mut normal) = (vec![0.0; n], vec![0i8; 3 * n]);
    for (i, &(part, start)) in r.parts.iter().enumerate() {
        let end = r.parts.get(i + 1).map_or(n, |p| p.1);
        let Some(&typ) = part.checked_sub(1).and_then(|i| scene.spacing.get(i)) else {
            continue;
        };
        let pts = &r.to[start..end];
        let grid = Grid::for_surface_on(pts, typ, par::width());
        let mut pieces: Vec<(usize, &mut [f64], &mut [i8])> = h[start..end]
            .chunks_mut(PIECE)
            .zip(normal[3 * start..3 * end].chunks_mut(3 * PIECE))
            .enumerate()
            .map(|(p, (hp, np))| (p * PIECE, hp, np))
            .collect();
        par::each(&mut pieces, |(from, hp, np)| {
            let kinds = &r.kind[start..end];
            surface_piece(&grid, pts, kinds, typ, *from, hp, np);
        });
    }
    (h, normal)
}

/// [`surfaces`] of the moves `pts[from..]` of one part (`kinds` theirs,
/// `typ` the part's typical pass spacing) into `h` and `normal`, as many
/// as they hold. A move's neighbour is looked for near the last one's, and
/// followed from it ([`Grid::follow_other`]) but every [`REFRESH`] moves of
/// the part; the first move of a piece looks without a hint.
fn surface_piece(
    grid: &Grid,
    pts: &[DVec3],
    kinds: &[u8],
    typ: f64,
    from: usize,
    h: &mut [f64],
    normal: &mut [i8],
) {
    let mut hint: Option<usize> = None;
    for (o, hk) in h.iter_mut().enumerate() {
        let j = from + o;
        if j == 0 || (kinds[j] != 1 && kinds[j] != 2) {
            hint = None;
            continue;
        }
        let sm = (grid.arc(j - 1) + grid.arc(j)) / 2.0;
        let follow = !j.is_multiple_of(REFRESH);
        let found = grid.local_near(pts[j - 1], pts[j], sm, hint.map(|x| x + 1), follow);
        hint = found.map(|(_, x)| x);
        if let Some((l, _)) = found {
            *hk = l.spacing.clamp(0.5 * typ, 2.0 * typ);
            for (x, q) in l
                .normal
                .to_array()
                .iter()
                .zip(&mut normal[3 * o..3 * o + 3])
            {
                *q = libm::round(x * 127.0) as i8;
            }
        }
    }
}

/// The G-code reader of `plan`'s viewer: the first step of [`read`], the
/// writer the G-code goes to as it is written (it keeps per move only what
/// the viewer draws, and which strings the checks flagged).
pub(crate) fn reader(plan: &Plan) -> Reader {
    let flags = super::scene::flags(plan);
    let ends = flagged_ends(plan, &flags);
    let mut r = Reader::new(origin(plan), ends, filament_area(plan));
    r.flags = flags;
    r
}

/// A viewer before the G-code is read: the plan read for drawing (but for
/// its flags, which the [`Reader`] holds) and what it shows.
pub(crate) struct Drawing<'p> {
    scene: Scene<'p>,
    opts: Options,
}

/// The second step of [`read`], which needs neither the G-code nor its
/// stats (a caller with a thread to spare runs it while the G-code is
/// written): the spacing of every path's passes.
pub(crate) fn draw<'p>(plan: &'p Plan, opts: &Options) -> Drawing<'p> {
    Drawing {
        scene: Scene::unflagged(plan),
        opts: *opts,
    }
}

/// The last step of [`read`]: what the viewer shows, from `drawing`, the
/// G-code `reader` read and the `stats` its writing returned.
pub(crate) fn finish(drawing: Drawing, mut reader: Reader, stats: &Stats) -> Data {
    let mut scene = drawing.scene;
    scene.flagged = std::mem::take(&mut reader.flags);
    Data::new(scene.plan, &scene, reader, stats, &drawing.opts)
}

fn origin(plan: &Plan) -> DVec3 {
    DVec3::from_array(plan.recipe.printer.origin)
}

/// The filament's cross-section, mm².
fn filament_area(plan: &Plan) -> f64 {
    let d = plan
        .recipe
        .material
        .filament_diameter
        .unwrap_or(plan.recipe.printer.filament_diameter);
    std::f64::consts::PI * d * d / 4.0
}

/// What the viewer shows of `plan` (whose G-code is `gcode` and stats
/// `stats`): its moves, stats and findings, as the JSON the page reads; and
/// how many points it carries.
pub(crate) fn data(
    plan: &Plan,
    r: Reader,
    stats: &Stats,
    opts: &Options,
) -> (serde_json::Value, usize) {
    let data = finish(draw(plan, opts), r, stats);
    (data.to_value(), data.points())
}

/// What the viewer shows of a plan: per move its point, feed rate, kind,
/// cross-section, spacing and normal (written as base64 of little-endian
/// binary), and the small fields (stats, findings, colour ranges…).
pub(crate) struct Data {
    small: serde_json::Value,
    to: Vec<DVec3>,
    feed: Vec<f64>,
    kind: Vec<u8>,
    c: Vec<f64>,
    h: Vec<f64>,
    normal: Vec<i8>,
    cmax: f64,
    hmax: f64,
}

/// The stats the viewer shows, as JSON.
fn stats_json(stats: &Stats, scene: &Scene) -> serde_json::Value {
    let size = [0, 1, 2].map(|k| stats.bbox.max[k] - stats.bbox.min[k]);
    json!({
        "size_mm": size,
        "filament_m": stats.filament_length_mm / 1000.0,
        "filament_g": stats.filament_mass_g,
        "material": stats.material,
        "printer": stats.printer,
        "time": hms(stats.print_time_s),
        "time_s": stats.print_time_s,
        "strings": stats.strings,
        "extrude_moves": stats.extrude_moves,
        "travel_moves": stats.travel_moves,
        "max_flow": stats.max_flow_mm3_s,
        "spacing_mm": scene.typical_spacing(),
    })
}

/// The checks' findings the viewer lists, as JSON.
fn findings_json(plan: &Plan) -> Vec<serde_json::Value> {
    plan.findings
        .iter()
        .map(|f| {
            json!({
                "code": f.code,
                "severity": f.severity.word(),
                "message": f.message,
                "part": f.part,
                "string": f.string,
                "at": f.at,
            })
        })
        .collect()
}

/// The per-move fields of the page, each written as base64 of binary.
const BLOBS: [&str; 6] = ["pos", "feed", "cq", "hq", "nq", "kind"];

/// Moves per block of a field's base64 ([`Data::write_blob`]): a multiple
/// of 3, so that a block of any field is whole groups of 3 bytes.
const BLOCK: usize = 3 << 12;

/// Blocks of a field encoded at once before they are written.
const BATCH: usize = 16;

impl Data {
    fn new(plan: &Plan, scene: &Scene, r: Reader, stats: &Stats, opts: &Options) -> Data {
        let n = r.to.len();
        // the scales' values are held for a moment: before the surfaces'
        // grids, not beside them
        let ranges = color_ranges(&r.feed, &r.kind, &r.c);
        let (h, normal) = surfaces(&r, scene);
        let (bmin, bmax) = if r.bmin.x > r.bmax.x {
            (DVec3::ZERO, DVec3::ZERO)
        } else {
            (r.bmin, r.bmax)
        };
        let cmax = r.c.iter().fold(0.0f64, |a, &b| a.max(b));
        let hmax = h.iter().fold(0.0f64, |a, &b| a.max(b));
        let small = json!({
            "format": "p3dp-preview 1",
            "name": stats.name,
            "view": opts.view.name(),
            "color": opts.color.name(),
            "points": n,
            "cmax": cmax,
            "hmax": hmax,
            "bbox": {"min": bmin.to_array(), "max": bmax.to_array()},
            "ranges": {"speed": ranges[0], "cross-section": ranges[1], "flow": ranges[2]},
            "stats": stats_json(stats, scene),
            "findings": findings_json(plan),
            // draw_turtle markers: position, heading, up (recipe coordinates)
            "turtles": scene
                .turtles
                .iter()
                .map(|m| [m.pos.to_array(), m.heading.to_array(), m.up.to_array()])
                .collect::<Vec<_>>(),
        });
        Data {
            small,
            to: r.to,
            feed: r.feed,
            kind: r.kind,
            c: r.c,
            h,
            normal,
            cmax,
            hmax,
        }
    }

    /// Points of the path (= the G-code's moves that change X, Y or Z).
    pub(crate) fn points(&self) -> usize {
        self.to.len()
    }

    /// The binary of field `key` (one of [`BLOBS`]) of `moves`, appended to
    /// `buf`: 12, 2, 2, 2, 3 or 1 bytes a move.
    fn blob(&self, key: &str, moves: std::ops::Range<usize>, buf: &mut Vec<u8>) {
        match key {
            "pos" => {
                for p in &self.to[moves] {
                    let p = if p.is_finite() { *p } else { DVec3::ZERO };
                    for x in [p.x, p.y, p.z] {
                        buf.extend_from_slice(&(x as f32).to_le_bytes());
                    }
                }
            }
            "feed" => {
                for f in &self.feed[moves] {
                    buf.extend_from_slice(&(f.clamp(0.0, 65535.0) as u16).to_le_bytes());
                }
            }
            "cq" => {
                for c in &self.c[moves] {
                    buf.extend_from_slice(&quantize(*c, self.cmax).to_le_bytes());
                }
            }
            "hq" => {
                for h in &self.h[moves] {
                    buf.extend_from_slice(&quantize(*h, self.hmax).to_le_bytes());
                }
            }
            "nq" => buf.extend(
                self.normal[3 * moves.start..3 * moves.end]
                    .iter()
                    .map(|&x| x as u8),
            ),
            _ => buf.extend_from_slice(&self.kind[moves]),
        }
    }

    /// Field `key` as base64, written to `w`: in blocks of [`BLOCK`] moves,
    /// [`BATCH`] blocks encoded at a time on the pool ([`par::map`]) and
    /// written in order. A block but the last is whole groups of 3 bytes,
    /// so its base64 has no padding and the blocks' texts end to end are
    /// the base64 of the whole field.
    fn write_blob(&self, key: &str, w: &mut dyn Write) -> std::io::Result<()> {
        let n = self.to.len();
        let starts: Vec<usize> = (0..n).step_by(BLOCK).collect();
        for batch in starts.chunks(BATCH) {
            let texts = par::map(batch, |&from| {
                let mut bin = Vec::with_capacity(12 * BLOCK);
                self.blob(key, from..(from + BLOCK).min(n), &mut bin);
                b64(&bin)
            });
            for text in &texts {
                w.write_all(text.as_bytes())?;
            }
        }
        Ok(())
    }

    /// The JSON the page reads, written to `w` (base64 streamed).
    pub(crate) fn write_json(&self, w: &mut dyn Write) -> std::io::Result<()> {
        // the small fields' object with the blobs put in front of its fields
        let small = script_json(&self.small);
        w.write_all(b"{")?;
        for key in BLOBS {
            write!(w, "\"{key}\":\"")?;
            self.write_blob(key, w)?;
            w.write_all(b"\",")?;
        }
        w.write_all(&small.as_bytes()[1..])
    }

    /// The JSON the page reads, as a value.
    pub(crate) fn to_value(&self) -> serde_json::Value {
        let mut v = self.small.clone();
        for key in BLOBS {
            let mut bytes = Vec::new();
            self.blob(key, 0..self.to.len(), &mut bytes);
            v[key] = serde_json::Value::String(b64(&bytes));
        }
        v
    }
}

/// The machine end points (µm) of the strings the checks flagged (`flags`,
/// per path, as [`Scene::flagged`]).
fn flagged_ends(plan: &Plan, flags: &[Vec<bool>]) -> HashSet<[i64; 3]> {
    let printer = &plan.recipe.printer;
    // a move is flagged when it ends where a flagged string ends (the writer
    // ends every move, merged or not, at the end point of a string)
    let mut flagged_ends = HashSet::new();
    for (pi, tp) in plan.paths.iter().enumerate() {
        for (k, f) in flags[pi].iter().enumerate() {
            if *f {
                let m = printer.to_machine(tp.points[k + 1]);
                flagged_ends.insert([m.x, m.y, m.z].map(|x| libm::round(x * 1e3) as i64));
            }
        }
    }
    flagged_ends
}

/// `x` as a u16 fraction of `max` (0 when `max` is not positive).
fn quantize(x: f64, max: f64) -> u16 {
    if max > 0.0 {
        libm::round(x / max * 65535.0) as u16
    } else {
        0
    }
}

/// The 0.2 % and 99.8 % quantiles of the finite values ([0, 0] for none):
/// the values of those ranks, found by selection rather than a full sort.
fn spread(vals: impl Iterator<Item = f64>) -> [f64; 2] {
    let mut v: Vec<f64> = vals.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return [0.0, 0.0];
    }
    let rank = |q: f64| ((v.len() - 1) as f64 * q).round() as usize;
    let (lo, hi) = (rank(0.002), rank(0.998));
    let a = *v.select_nth_unstable_by(lo, f64::total_cmp).1;
    let b = *v.select_nth_unstable_by(hi, f64::total_cmp).1;
    [a, b]
}

/// The colour scales of speed, cross-section and flow over the extruding moves.
fn color_ranges(feed: &[f64], kind: &[u8], c: &[f64]) -> [[f64; 2]; 3] {
    // the scales span the middle 99.6 % of the extruding moves, so that a few
    // merged moves near a pole (their chord shorter than their path) do not
    // squeeze the colours of all the others; one scale's values held at a time
    let ext = || (0..kind.len()).filter(|&k| kind[k] == 1 || kind[k] == 2);
    [
        spread(ext().map(|k| feed[k] / 60.0)),
        spread(ext().map(|k| c[k])),
        spread(ext().map(|k| c[k] * feed[k] / 60.0)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blobs_encoded_in_blocks_are_the_base64_of_the_whole() {
        for n in [0, 1, 2, BLOCK - 1, BLOCK, 2 * BLOCK + 5] {
            let data = Data {
                small: json!({"name": "x"}),
                to: (0..n).map(|k| DVec3::new(k as f64, 0.5, -1.0)).collect(),
                feed: (0..n).map(|k| (k % 7000) as f64).collect(),
                kind: (0..n).map(|k| (k % 4) as u8).collect(),
                c: (0..n).map(|k| (k % 13) as f64).collect(),
                h: (0..n).map(|k| (k % 5) as f64).collect(),
                normal: (0..3 * n).map(|k| (k % 255) as i8).collect(),
                cmax: 12.0,
                hmax: 4.0,
            };
            let mut page = Vec::new();
            data.write_json(&mut page).unwrap();
            let v: serde_json::Value = serde_json::from_slice(&page).unwrap();
            assert_eq!(v, data.to_value(), "{n}");
        }
    }

    #[test]
    fn quantiles_by_selection_are_the_sorted_ranks() {
        let v: Vec<f64> = (0..1001).map(|i| ((i * 7919) % 1001) as f64).collect();
        assert_eq!(spread(v.into_iter()), [2.0, 998.0]);
        assert_eq!(spread([f64::NAN].into_iter()), [0.0, 0.0]);
    }
}
