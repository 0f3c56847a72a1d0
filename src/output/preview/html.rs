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
use std::io::Write;

use base64::Engine;
use glam::DVec3;
use serde_json::json;

use super::{Options, Render, Scene};
use crate::analyse::plan::Plan;
use crate::analyse::stats::Stats;
use crate::base::error::Result;
use crate::base::format::hms;
use crate::base::geom::passes::Grid;
use crate::base::par;

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
    let mut parser = Parser::new(origin);
    gcode
        .lines()
        .filter_map(|l| parser.line(l.as_bytes()))
        .collect()
}

/// Whether `b` is whitespace to [`str::split_whitespace`] (of the ASCII).
fn space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | b'\x0b' | b'\x0c' | b'\r')
}

/// The number `s` spells, exactly as `str::parse::<f64>` reads it.
///
/// Plain decimals (an optional sign, up to 15 digits, a point), which is all
/// p3dp writes, are read directly: their digits m < 10^15 < 2^53 and 10^f
/// (f ≤ 15 decimals) are exact doubles, so the one correctly rounded
/// division m / 10^f is the correctly rounded value of the decimal, as
/// `parse` gives (the "fast path" of Clinger's algorithm). Anything else
/// goes to `parse`.
fn number(s: &[u8]) -> Option<f64> {
    const POW10: [f64; 16] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
    ];
    let (neg, digits) = match s.first() {
        Some(b'-') => (true, &s[1..]),
        Some(b'+') => (false, &s[1..]),
        _ => (false, s),
    };
    let (mut m, mut n, mut frac, mut point) = (0u64, 0usize, 0usize, false);
    for &b in digits {
        match b {
            b'0'..=b'9' if n < 15 => {
                m = m * 10 + u64::from(b - b'0');
                n += 1;
                frac += usize::from(point);
            }
            b'.' if !point => point = true,
            _ => return std::str::from_utf8(s).ok()?.parse().ok(),
        }
    }
    if n == 0 {
        return std::str::from_utf8(s).ok()?.parse().ok();
    }
    let v = m as f64 / POW10[frac];
    Some(if neg { -v } else { v })
}

/// The state of reading G-code line by line (see [`moves`]).
struct Parser {
    origin: DVec3,
    pos: [f64; 3],
    e: f64,
    feed: f64,
    relative: bool,
    part: usize,
    /// Whether [`Move::machine_um`] is wanted (else left at zero).
    um: bool,
}

impl Parser {
    fn new(origin: DVec3) -> Parser {
        Parser {
            origin,
            pos: [0.0; 3],
            e: 0.0,
            feed: 0.0,
            relative: false,
            part: 0,
            um: true,
        }
    }

    /// The move `line` makes, if it moves the head.
    ///
    /// Read as bytes; a line whose code (before any `;`) is not all ASCII is
    /// read as text, as `str::split_whitespace` and `str::parse` read it.
    fn line(&mut self, line: &[u8]) -> Option<Move> {
        if line.starts_with(b"; part: ") {
            self.part += 1;
        }
        let code = line.split(|&b| b == b';').next().unwrap_or(&[]);
        if !code.is_ascii() {
            let text = String::from_utf8_lossy(code);
            let words: Vec<&[u8]> = text.split_whitespace().map(str::as_bytes).collect();
            return self.words(&words);
        }
        let mut words: [&[u8]; 8] = [&[]; 8];
        let mut n = 0;
        for w in code.split(|&b| space(b)).filter(|w| !w.is_empty()) {
            if n == words.len() {
                // a long line: as many words as it has
                let all: Vec<&[u8]> = code
                    .split(|&b| space(b))
                    .filter(|w| !w.is_empty())
                    .collect();
                return self.words(&all);
            }
            words[n] = w;
            n += 1;
        }
        self.words(&words[..n])
    }

    /// The move a line of these words makes, if it moves the head.
    fn words(&mut self, words: &[&[u8]]) -> Option<Move> {
        let (&cmd, words) = words.split_first()?;
        // a word's letter, and the number after it (a word is not empty)
        let value = |w: &[u8]| {
            if w[0].is_ascii() {
                return number(&w[1..]);
            }
            let first = std::str::from_utf8(w).ok()?.chars().next()?;
            number(&w[first.len_utf8()..])
        };
        match cmd {
            b"M82" => self.relative = false,
            b"M83" => self.relative = true,
            b"G92" => {
                for &w in words {
                    if w.starts_with(b"E") {
                        self.e = value(w).unwrap_or(self.e);
                    }
                }
            }
            b"G0" | b"G1" => {
                let mut moved = false;
                let mut has_e = false;
                let mut de = 0.0;
                for &w in words {
                    let Some(v) = value(w) else { continue };
                    match w[0] {
                        b'X' => (self.pos[0], moved) = (v, true),
                        b'Y' => (self.pos[1], moved) = (v, true),
                        b'Z' => (self.pos[2], moved) = (v, true),
                        b'E' => {
                            has_e = true;
                            de = if self.relative { v } else { v - self.e };
                            self.e = if self.relative { self.e + v } else { v };
                        }
                        b'F' => self.feed = v,
                        _ => {}
                    }
                }
                if moved {
                    return Some(Move {
                        to: DVec3::from_array(self.pos) - self.origin,
                        feed: self.feed,
                        de,
                        g0: cmd == b"G0",
                        extrudes: cmd == b"G1" && has_e,
                        part: self.part,
                        machine_um: if self.um {
                            self.pos.map(|x| libm::round(x * 1e3) as i64)
                        } else {
                            [0; 3]
                        },
                    });
                }
            }
            _ => {}
        }
        None
    }
}

/// G-code read as it is written (a writer): per move only what the viewer
/// draws, neither the text nor the [`Move`]s kept ([`reader`] makes one).
pub struct Reader {
    parser: Parser,
    /// The end of the last line, not yet read.
    partial: Vec<u8>,
    /// Per path, the strings the checks flagged (as [`Scene::flagged`]),
    /// kept for the scene.
    flags: Vec<Vec<bool>>,
    /// The machine end points (µm) of the flagged strings.
    flagged_ends: HashSet<[i64; 3]>,
    /// Filament cross-section, mm².
    area: f64,
    to: Vec<DVec3>,
    feed: Vec<f64>,
    /// Kinds (0 travel, 1 extrude, 2 flagged, 3 dry).
    kind: Vec<u8>,
    /// The cross-section each move lays, mm².
    c: Vec<f64>,
    /// (part number, first move) of each run of moves of one part.
    parts: Vec<(usize, usize)>,
    bmin: DVec3,
    bmax: DVec3,
}

impl Reader {
    fn new(origin: DVec3, flagged_ends: HashSet<[i64; 3]>, area: f64) -> Reader {
        Reader {
            parser: Parser {
                // the machine position is only looked up among the flagged ends
                um: !flagged_ends.is_empty(),
                ..Parser::new(origin)
            },
            partial: Vec::new(),
            flags: Vec::new(),
            flagged_ends,
            area,
            to: Vec::new(),
            feed: Vec::new(),
            kind: Vec::new(),
            c: Vec::new(),
            parts: Vec::new(),
            bmin: DVec3::splat(f64::INFINITY),
            bmax: DVec3::splat(f64::NEG_INFINITY),
        }
    }

    fn read_line(&mut self, line: &[u8]) {
        let Some(m) = self.parser.line(line) else {
            return;
        };
        let k = self.to.len();
        if self.parts.last().is_none_or(|p| p.0 != m.part) {
            self.parts.push((m.part, k));
        }
        let prev = self.to.last().copied();
        let kind = if m.g0 {
            0u8
        } else if !m.extrudes {
            3
        } else if self.flagged_ends.contains(&m.machine_um) {
            2
        } else {
            1
        };
        let mut c = 0.0;
        if m.extrudes {
            // the cross-section the move lays: filament volume over length
            let len = prev.map_or(0.0, |p| p.distance(m.to));
            if len > 0.0 {
                c = m.de.max(0.0) * self.area / len;
            }
            let prev = prev.unwrap_or(m.to);
            self.bmin = self.bmin.min(prev).min(m.to);
            self.bmax = self.bmax.max(prev).max(m.to);
        }
        self.to.push(m.to);
        self.feed.push(m.feed);
        self.kind.push(kind);
        self.c.push(c);
    }

    /// Reads all of `bytes` and what is left of the last line.
    fn read_all(&mut self, bytes: &[u8]) {
        // a reader takes every byte it is given
        let _ = self.write(bytes);
        self.end();
    }

    /// Reads what is left of the last line (G-code ending without a newline).
    fn end(&mut self) {
        let rest = std::mem::take(&mut self.partial);
        if !rest.is_empty() {
            self.read_line(&rest);
        }
    }
}

impl std::io::Write for Reader {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let mut rest = buf;
        while let Some(at) = rest.iter().position(|&b| b == b'\n') {
            if self.partial.is_empty() {
                self.read_line(&rest[..at]);
            } else {
                let mut line = std::mem::take(&mut self.partial);
                line.extend_from_slice(&rest[..at]);
                self.read_line(&line);
            }
            rest = &rest[at + 1..];
        }
        self.partial.extend_from_slice(rest);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
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

/// The viewer page for `plan`, whose G-code is `gcode` and stats `stats`.
pub fn page(plan: &Plan, gcode: &str, stats: &Stats, opts: &Options) -> Page {
    let (data, points) = data(plan, gcode, stats, opts);
    Page {
        html: page_with(&stats.name, &data, &serde_json::Value::Null),
        points,
    }
}

/// The G-code reader of `plan`'s viewer: the first step of [`read`], the
/// writer the G-code goes to as it is written (it keeps per move only what
/// the viewer draws, and which strings the checks flagged).
pub fn reader(plan: &Plan) -> Reader {
    let flags = super::scene::flags(plan);
    let ends = flagged_ends(plan, &flags);
    let mut r = Reader::new(origin(plan), ends, filament_area(plan));
    r.flags = flags;
    r
}

/// A viewer before the G-code is read: the plan read for drawing (but for
/// its flags, which the [`Reader`] holds) and what it shows.
pub struct Drawing<'p> {
    scene: Scene<'p>,
    opts: Options,
}

/// The second step of [`read`], which needs neither the G-code nor its
/// stats (a caller with a thread to spare runs it while the G-code is
/// written): the spacing of every path's passes.
pub fn draw<'p>(plan: &'p Plan, opts: &Options) -> Drawing<'p> {
    Drawing {
        scene: Scene::unflagged(plan),
        opts: *opts,
    }
}

/// The last step of [`read`]: what the viewer shows, from `drawing`, the
/// G-code `reader` read and the `stats` its writing returned.
pub fn finish(drawing: Drawing, mut reader: Reader, stats: &Stats) -> Data {
    reader.end();
    let mut scene = drawing.scene;
    scene.flagged = std::mem::take(&mut reader.flags);
    Data::new(scene.plan, &scene, reader, stats, &drawing.opts)
}

/// Reads `plan`'s G-code as `render` writes it (neither its text nor its
/// moves kept) into what the viewer shows; with the stats `render` returned.
///
/// One step after the other: [`reader`], `render` into it, [`draw`],
/// [`finish`]. A caller with a thread to spare runs `render` and [`draw`]
/// side by side instead (`par::join`); the data are the same.
pub fn read(plan: &Plan, opts: &Options, render: Render) -> Result<(Data, Stats)> {
    let mut r = reader(plan);
    let stats = render(&mut r)?;
    let drawing = draw(plan, opts);
    Ok((finish(drawing, r, &stats), stats))
}

/// Writes the viewer page of `data` under `title` to `w`, the path data
/// streamed as it is encoded (the same bytes as [`page`]).
pub fn write_page(title: &str, data: &Data, w: &mut dyn Write) -> std::io::Result<()> {
    let mut rest = TEMPLATE;
    let keys = ["__P3DP_TITLE__", "__P3DP_LIVE__", "__P3DP_DATA__"];
    loop {
        let next = keys
            .iter()
            .filter_map(|k| rest.find(k).map(|at| (at, *k)))
            .min_by_key(|(at, _)| *at);
        let Some((at, k)) = next else {
            return w.write_all(rest.as_bytes());
        };
        w.write_all(&rest.as_bytes()[..at])?;
        match k {
            "__P3DP_TITLE__" => w.write_all(escape_html(title).as_bytes())?,
            "__P3DP_LIVE__" => w.write_all(script_json(&serde_json::Value::Null).as_bytes())?,
            _ => data.write_json(w)?,
        }
        rest = &rest[at + k.len()..];
    }
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
    let mut r = reader(plan);
    r.read_all(gcode.as_bytes());
    let data = finish(draw(plan, opts), r, stats);
    (data.to_value(), data.points())
}

/// What the viewer shows of a plan: per move its point, feed rate, kind,
/// cross-section, spacing and normal (written as base64 of little-endian
/// binary), and the small fields (stats, findings, colour ranges…).
pub struct Data {
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
    pub fn points(&self) -> usize {
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
    pub fn write_json(&self, w: &mut dyn Write) -> std::io::Result<()> {
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
    pub fn to_value(&self) -> serde_json::Value {
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
    fn the_reader_reads_what_moves_reads_however_the_text_is_cut() {
        let g = "G28\nG0 X110.000 Y110.000 Z0.200 F7200\n; part: a (2 strings)\nG1 X111.000 E0.05000 F1800\nG1 E-0.8 ; retract\nG1 E0.05 ; unretract\nG1 Y111.000 E0.10000\nM83\nG1 X110.000 E0.02\nG0 Z5";
        let origin = DVec3::new(110.0, 110.0, 0.0);
        let m = moves(g, origin);
        for cut in [1, 2, 7, 1000] {
            let mut r = Reader::new(origin, HashSet::new(), 2.0);
            for chunk in g.as_bytes().chunks(cut) {
                r.write_all(chunk).unwrap();
            }
            r.end();
            assert_eq!(r.to, m.iter().map(|x| x.to).collect::<Vec<_>>(), "{cut}");
            assert_eq!(r.kind, [0, 1, 1, 1, 0], "{cut}");
            assert_eq!(r.parts, [(0, 0), (1, 1)], "{cut}");
            // 0.05 mm of filament of 2 mm² over 1 mm
            assert!((r.c[1] - 0.1).abs() < 1e-12, "{cut}: {:?}", r.c);
        }
    }

    #[test]
    fn numbers_read_as_parse_reads_them_bit_for_bit() {
        let mut words: Vec<String> = [
            "",
            "-",
            "+",
            ".",
            "-.",
            "0",
            "-0",
            "-0.000",
            "+1.5",
            ".5",
            "5.",
            "-.5",
            "+.5",
            "1.2.3",
            "--1",
            "1e3",
            "1E-2",
            "inf",
            "-inf",
            "NaN",
            "0x10",
            "12a",
            "1 2",
            "123456789012345",
            "1234567890123456",
            "0.000000000000001",
            "0.0000000000000001",
            "9007199254740993",
            "110.000",
            "0.05000",
            "1e400",
        ]
        .iter()
        .map(|w| w.to_string())
        .collect();
        // numbers as p3dp writes them, and some wider and longer
        let mut x: u64 = 0x2545_F491_4F6C_DD1D;
        for _ in 0..20_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = (x % 2_000_000_000) as f64 / 1000.0 - 1e6;
            let places = (x >> 40) as usize % 16;
            words.push(format!("{v:.places$}"));
            words.push(format!("{}", f64::from_bits(x >> 2)));
        }
        for w in &words {
            let want = w.parse::<f64>().ok();
            let got = number(w.as_bytes());
            assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{w:?}");
        }
    }

    #[test]
    fn lines_with_other_text_read_as_before() {
        let origin = DVec3::ZERO;
        let mut p = Parser::new(origin);
        // whitespace of every kind between the words, a comment with anything in it
        let m = p
            .line("G1\tX1.5\x0bY2 \x0cZ3\r ; é ; part: x".as_bytes())
            .unwrap();
        assert_eq!(m.to, DVec3::new(1.5, 2.0, 3.0));
        // a word that is not ASCII, and bytes that are not UTF-8, are skipped
        let m = p.line("G1 X4 ÉY7 Y5".as_bytes()).unwrap();
        assert_eq!(m.to, DVec3::new(4.0, 5.0, 3.0));
        let m = p.line(b"G1 X6 \xff Y8\xfe Z9").unwrap();
        assert_eq!(m.to, DVec3::new(6.0, 5.0, 9.0));
        // more words than usual
        let m = p.line(b"G1 A1 B2 C3 D4 I5 J6 K7 L8 X10").unwrap();
        assert_eq!(m.to.x, 10.0);
        assert!(p.line(b"; G1 X1").is_none() && p.line(b"").is_none());
    }

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
