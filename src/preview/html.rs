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

use std::collections::HashSet;

use base64::Engine;
use glam::DVec3;
use serde_json::json;

use super::{Grid, Options, Scene};
use crate::format::hms;
use crate::plan::Plan;
use crate::stats::Stats;

/// The viewer page; `__P3DP_TITLE__`, `__P3DP_LIVE__` and `__P3DP_DATA__` are filled in.
const TEMPLATE: &str = include_str!("viewer.html");

/// One G0/G1 move read back from G-code, in recipe coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// Where the move ends.
    pub to: DVec3,
    /// Feed rate in force, mm/min.
    pub feed: f64,
    /// Filament fed by the move, mm.
    pub de: f64,
    /// A G0 (travel) move.
    pub g0: bool,
    /// A G1 with an E word: an extruding string (p3dp writes E on every one).
    pub extrudes: bool,
    /// How many `; part:` comments came before it (0: the start G-code).
    pub part: usize,
    /// Machine position in µm, as written.
    pub machine_um: [i64; 3],
}

/// Reads the moves of p3dp's G-code (G90; M82 or M83; G92 E), machine
/// coordinates turned back into recipe coordinates by subtracting `origin`.
pub fn moves(gcode: &str, origin: DVec3) -> Vec<Move> {
    let mut pos = [0.0f64; 3];
    let (mut e, mut feed, mut relative, mut part) = (0.0, 0.0, false, 0);
    let mut out = Vec::new();
    for line in gcode.lines() {
        if line.starts_with("; part: ") {
            part += 1;
        }
        let code = line.split(';').next().unwrap_or("").trim();
        let mut words = code.split_whitespace();
        let Some(cmd) = words.next() else { continue };
        let value = |w: &str| w[1..].parse::<f64>().ok();
        match cmd {
            "M82" => relative = false,
            "M83" => relative = true,
            "G92" => {
                for w in words {
                    if w.starts_with('E') {
                        e = value(w).unwrap_or(e);
                    }
                }
            }
            "G0" | "G1" => {
                let mut moved = false;
                let mut has_e = false;
                let mut de = 0.0;
                for w in words {
                    let Some(v) = value(w) else { continue };
                    match w.as_bytes()[0] {
                        b'X' => (pos[0], moved) = (v, true),
                        b'Y' => (pos[1], moved) = (v, true),
                        b'Z' => (pos[2], moved) = (v, true),
                        b'E' => {
                            has_e = true;
                            de = if relative { v } else { v - e };
                            e = if relative { e + v } else { v };
                        }
                        b'F' => feed = v,
                        _ => {}
                    }
                }
                if moved {
                    out.push(Move {
                        to: DVec3::from_array(pos) - origin,
                        feed,
                        de,
                        g0: cmd == "G0",
                        extrudes: cmd == "G1" && has_e,
                        part,
                        machine_um: pos.map(|x| libm::round(x * 1e3) as i64),
                    });
                }
            }
            _ => {}
        }
    }
    out
}

/// A viewer page and how many points it carries.
pub struct Page {
    /// The HTML text.
    pub html: String,
    /// Points of the path (= the G-code's moves that change X, Y or Z).
    pub points: usize,
}

fn b64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Per extruding move, the spacing to the neighbouring pass (`h`, mm) and the
/// surface normal (`normal`, i8 × 127), from the moves of the same part.
fn surfaces(mv: &[Move], kind: &[u8], scene: &Scene, h: &mut [f64], normal: &mut [i8]) {
    let mut start = 0;
    while start < mv.len() {
        let part = mv[start].part;
        let mut end = start;
        while end < mv.len() && mv[end].part == part {
            end += 1;
        }
        let typical = part.checked_sub(1).and_then(|i| scene.spacing.get(i));
        if let Some(&typ) = typical {
            let pts: Vec<DVec3> = mv[start..end].iter().map(|m| m.to).collect();
            let grid = Grid::for_surface(&pts, typ);
            for j in 1..pts.len() {
                let k = start + j;
                if kind[k] != 1 && kind[k] != 2 {
                    continue;
                }
                let sm = (grid.arc(j - 1) + grid.arc(j)) / 2.0;
                if let Some(l) = grid.local(pts[j - 1], pts[j], sm) {
                    h[k] = l.spacing.clamp(0.5 * typ, 2.0 * typ);
                    for (i, x) in l.normal.to_array().iter().enumerate() {
                        normal[3 * k + i] = libm::round(x * 127.0) as i8;
                    }
                }
            }
        }
        start = end;
    }
}

/// The viewer page for `plan`, whose G-code is `gcode` and stats `stats`.
pub fn page(plan: &Plan, gcode: &str, stats: &Stats, opts: &Options) -> Page {
    let (data, points) = data(plan, gcode, stats, opts);
    Page {
        html: page_with(&stats.name, &data, &serde_json::Value::Null),
        points,
    }
}

/// A viewer page showing `data` (as [`data`] makes it; `null`: no model
/// yet) under `title`. `live` is `null` for a file; `p3dp watch` gives the
/// state the page starts from and follows its server-sent events.
pub fn page_with(title: &str, data: &serde_json::Value, live: &serde_json::Value) -> String {
    fill(
        TEMPLATE,
        &[
            ("__P3DP_TITLE__", escape_html(title)),
            ("__P3DP_LIVE__", script_json(live)),
            ("__P3DP_DATA__", script_json(data)),
        ],
    )
}

/// JSON to put inside a `<script>` element: every `<` written `\u003c` (the
/// same string to a JSON reader), so no `</script>` or `<!--` in a name or
/// a message can end or change the element.
fn script_json(v: &serde_json::Value) -> String {
    v.to_string().replace('<', "\\u003c")
}

/// `template` with each placeholder replaced by its value, in one pass (a
/// value that contains a placeholder's name is left as it is).
fn fill(template: &str, values: &[(&str, String)]) -> String {
    let mut out =
        String::with_capacity(template.len() + values.iter().map(|v| v.1.len()).sum::<usize>());
    let mut rest = template;
    loop {
        let next = values
            .iter()
            .filter_map(|(k, v)| rest.find(k).map(|at| (at, *k, v)))
            .min_by_key(|(at, _, _)| *at);
        let Some((at, k, v)) = next else {
            out.push_str(rest);
            return out;
        };
        out.push_str(&rest[..at]);
        out.push_str(v);
        rest = &rest[at + k.len()..];
    }
}

/// What the viewer shows of `plan` (whose G-code is `gcode` and stats
/// `stats`): its moves, stats and findings, as the JSON the page reads; and
/// how many points it carries.
pub fn data(plan: &Plan, gcode: &str, stats: &Stats, opts: &Options) -> (serde_json::Value, usize) {
    let printer = &plan.recipe.printer;
    let scene = Scene::new(plan);
    let mv = moves(gcode, DVec3::from_array(printer.origin));
    let d = plan
        .recipe
        .material
        .filament_diameter
        .unwrap_or(printer.filament_diameter);
    let area = std::f64::consts::PI * d * d / 4.0;
    let flagged = flagged_ends(plan, &scene);
    let n = mv.len();
    let a = per_move(&mv, &flagged, area);
    let mut h = vec![0.0; n];
    let mut normal = vec![0i8; 3 * n];
    surfaces(&mv, &a.kind, &scene, &mut h, &mut normal);
    let (cmax, cq) = quantize(&a.c);
    let (hmax, hq) = quantize(&h);
    let nq: Vec<u8> = normal.iter().map(|&x| x as u8).collect();
    let ranges = color_ranges(&mv, &a.kind, &a.c);
    let size = [0, 1, 2].map(|k| stats.bbox.max[k] - stats.bbox.min[k]);
    let findings: Vec<_> = plan
        .findings
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
        .collect();
    let data = json!({
        "format": "p3dp-preview 1",
        "name": stats.name,
        "view": opts.view.name(),
        "color": opts.color.name(),
        "points": n,
        "pos": b64(&a.pos),
        "feed": b64(&a.feed),
        "cq": b64(&cq),
        "cmax": cmax,
        "hq": b64(&hq),
        "hmax": hmax,
        "nq": b64(&nq),
        "kind": b64(&a.kind),
        "bbox": {"min": a.bmin.to_array(), "max": a.bmax.to_array()},
        "ranges": {"speed": ranges[0], "cross-section": ranges[1], "flow": ranges[2]},
        "stats": {
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
        },
        "findings": findings,
        // draw_turtle markers: position, heading, up (recipe coordinates)
        "turtles": scene
            .turtles
            .iter()
            .map(|m| [m.pos.to_array(), m.heading.to_array(), m.up.to_array()])
            .collect::<Vec<_>>(),
    });
    (data, n)
}

/// The machine end points (µm) of the strings the checks flagged.
fn flagged_ends(plan: &Plan, scene: &Scene) -> HashSet<[i64; 3]> {
    let printer = &plan.recipe.printer;
    // a move is flagged when it ends where a flagged string ends (the writer
    // ends every move, merged or not, at the end point of a string)
    let mut flagged_ends = HashSet::new();
    for (pi, tp) in plan.paths.iter().enumerate() {
        for (k, f) in scene.flagged[pi].iter().enumerate() {
            if *f {
                let m = printer.to_machine(tp.points[k + 1]);
                flagged_ends.insert([m.x, m.y, m.z].map(|x| libm::round(x * 1e3) as i64));
            }
        }
    }
    flagged_ends
}

/// The per-move arrays of the page, and the box of what is extruded.
struct MoveArrays {
    pos: Vec<u8>,
    feed: Vec<u8>,
    kind: Vec<u8>,
    c: Vec<f64>,
    bmin: DVec3,
    bmax: DVec3,
}

/// Positions, feeds, kinds (0 travel, 1 extrude, 2 flagged, 3 dry) and laid
/// cross-sections of the moves, with a filament of `area` mm².
fn per_move(mv: &[Move], flagged_ends: &HashSet<[i64; 3]>, area: f64) -> MoveArrays {
    let n = mv.len();
    let mut pos = Vec::with_capacity(12 * n);
    let mut feed = Vec::with_capacity(2 * n);
    let mut kind = Vec::with_capacity(n);
    let mut c = vec![0.0; n];
    let mut bmin = DVec3::splat(f64::INFINITY);
    let mut bmax = DVec3::splat(f64::NEG_INFINITY);
    for (k, m) in mv.iter().enumerate() {
        let p = if m.to.is_finite() { m.to } else { DVec3::ZERO };
        for x in [p.x, p.y, p.z] {
            pos.extend_from_slice(&(x as f32).to_le_bytes());
        }
        feed.extend_from_slice(&(m.feed.clamp(0.0, 65535.0) as u16).to_le_bytes());
        let len = if k > 0 {
            mv[k - 1].to.distance(m.to)
        } else {
            0.0
        };
        let extruding = m.extrudes;
        let kd = if m.g0 {
            0u8
        } else if !extruding {
            3
        } else if flagged_ends.contains(&m.machine_um) {
            2
        } else {
            1
        };
        kind.push(kd);
        if extruding {
            // the cross-section the move lays: filament volume over length
            c[k] = if len > 0.0 {
                m.de.max(0.0) * area / len
            } else {
                0.0
            };
            let prev = if k > 0 { mv[k - 1].to } else { m.to };
            bmin = bmin.min(prev).min(m.to);
            bmax = bmax.max(prev).max(m.to);
        }
    }
    if bmin.x > bmax.x {
        (bmin, bmax) = (DVec3::ZERO, DVec3::ZERO);
    }
    MoveArrays {
        pos,
        feed,
        kind,
        c,
        bmin,
        bmax,
    }
}

/// The largest value and every value as a little-endian u16 fraction of it.
fn quantize(v: &[f64]) -> (f64, Vec<u8>) {
    let max = v.iter().fold(0.0f64, |a, &b| a.max(b));
    let mut out = Vec::with_capacity(2 * v.len());
    for x in v {
        let q = if max > 0.0 {
            libm::round(x / max * 65535.0) as u16
        } else {
            0
        };
        out.extend_from_slice(&q.to_le_bytes());
    }
    (max, out)
}

/// The 0.2 % and 99.8 % quantiles of the finite values ([0, 0] for none).
fn spread(vals: Vec<f64>) -> [f64; 2] {
    let mut v: Vec<f64> = vals.into_iter().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return [0.0, 0.0];
    }
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    [at(0.002), at(0.998)]
}

/// The colour scales of speed, cross-section and flow over the extruding moves.
fn color_ranges(mv: &[Move], kind: &[u8], c: &[f64]) -> [[f64; 2]; 3] {
    // the scales span the middle 99.6 % of the extruding moves, so that a few
    // merged moves near a pole (their chord shorter than their path) do not
    // squeeze the colours of all the others
    let ext: Vec<usize> = (0..mv.len())
        .filter(|&k| kind[k] == 1 || kind[k] == 2)
        .collect();
    [
        spread(ext.iter().map(|&k| mv[k].feed / 60.0).collect()),
        spread(ext.iter().map(|&k| c[k]).collect()),
        spread(ext.iter().map(|&k| c[k] * mv[k].feed / 60.0).collect()),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_read_back_absolute_and_relative() {
        let g = "G28\nG0 X110.000 Y110.000 Z0.200 F7200\n; part: a (2 strings)\nG1 X111.000 E0.05000 F1800\nG1 E-0.8 ; retract\nG1 E0.05 ; unretract\nG1 Y111.000 E0.10000\nM83\nG1 X110.000 E0.02\nG0 Z5\n";
        let m = moves(g, DVec3::new(110.0, 110.0, 0.0));
        assert_eq!(m.len(), 5);
        assert_eq!(m[0].to, DVec3::new(0.0, 0.0, 0.2));
        assert!(m[0].g0 && m[0].part == 0);
        assert!((m[1].de - 0.05).abs() < 1e-12 && m[1].feed == 1800.0 && m[1].part == 1);
        // the unretract restored E to 0.05; this move feeds 0.05
        assert!((m[2].de - 0.05).abs() < 1e-12);
        assert!((m[3].de - 0.02).abs() < 1e-12);
        assert!(m[3].extrudes && !m[4].extrudes && !m[0].extrudes);
        assert_eq!(m[4].machine_um, [110_000, 111_000, 5_000]);
    }

    #[test]
    fn template_has_its_placeholders_and_no_network() {
        for p in ["__P3DP_DATA__", "__P3DP_TITLE__", "__P3DP_LIVE__"] {
            assert!(TEMPLATE.contains(p), "{p}");
        }
        assert!(!TEMPLATE.contains("http://") && !TEMPLATE.contains("https://"));
        assert_eq!(escape_html("a<b>&\""), "a&lt;b&gt;&amp;&quot;");
    }

    #[test]
    fn placeholders_are_filled_once_and_script_json_cannot_close_its_element() {
        let v = serde_json::json!({"name": "</script><!-- __P3DP_DATA__"});
        let page = page_with("__P3DP_DATA__ <b>", &v, &serde_json::Value::Null);
        assert_eq!(
            page.matches("</script>").count(),
            TEMPLATE.matches("</script>").count()
        );
        assert!(
            page.contains("<title>__P3DP_DATA__ &lt;b&gt;"),
            "the title is filled as text"
        );
        assert!(!page.contains("__P3DP_LIVE__"));
        let json = script_json(&v);
        assert_eq!(serde_json::from_str::<serde_json::Value>(&json).unwrap(), v);
    }
}
