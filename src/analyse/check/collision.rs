//! Collision: the head must never meet filament printed earlier (Kanada's
//! first condition; ExtruderTurtle's Fig. 13 shows the two ways it does).
//!
//! The head is the printer profile's `head:` ([`super::Head`]): a cone round
//! the nozzle, a flat tip of `tip_diameter` widening at `cone_angle` from the
//! vertical up to `cone_height`, and above that a box (`box`, round the
//! nozzle). Filament printed so far is kept as a height map: a grid of 0.25 mm
//! squares over the print, each holding the highest point of filament centre
//! line over it (where it is, and how high), and 4 mm tiles holding the
//! highest of their squares, so a look round the head skips low tiles whole. The head's path is walked as the G-code
//! moves it — strings, travel strings inside parts, and the travel between
//! parts that [`crate::output::gcode::Emitter::travel_to`] makes (up to the safe
//! height [`crate::machine::travel::safe_travel_z`], across, down) — sampled every square; at each
//! sample, filament higher above the tip than the support tolerance (1.5 ×
//! the nozzle: the layer a string rests on, pressed by the flat tip on a slope,
//! is contact, not collision)
//!
//! - within the cone, i.e. closer sideways than tip/2 + min(dz, cone_height)
//!   · tan(cone_angle) at height dz above the tip: `nozzle-collision`;
//! - more than `cone_height` above the tip and under the box: `head-collision`;
//! - more than the gantry's `height` above the tip, anywhere across the bed
//!   in x within the gantry's band in y (`head.gantry`, when the profile
//!   gives it: what the head hangs from): `head-collision` too. Objects
//!   printed one after another (a plate, [`crate::generate::plate`]) meet it
//!   when a finished one taller than that stands beside the next.
//!
//! The cone is the nozzle itself: filament more than a nozzle diameter inside
//! its surface is an error; less deep, the nozzle scrapes it (as on a helix
//! wall steeper than the cone, whose turn above leans over the nozzle): a
//! warning. The box is an estimate of the heater block (set `head:` to your
//! printer's): a warning. One finding per
//! part and kind, with the length of head path
//! concerned and the first place: the nozzle there, and the filament hit.
//! Filament counts once the nozzle is 2 mm of path past it (the nozzle still
//! sits in the string it lays). When the nozzle's lowest point on a move is
//! above all filament that counts, the move cannot collide and costs nothing
//! more; filament is mapped only when a move needs the map, so a helix
//! printed bottom to top is checked in passing. A declared hair (a turtle's
//! `hair:`, [`crate::base::toolpath::Strand::hair`]) is never mapped (a hair bends
//! out of the head's way), and the move that pulls it is not checked against
//! the cone (the nozzle rises out of its own blob), only against the box.

use glam::{DVec2, DVec3};

use super::{fmt_p, Finding, Severity};

use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;

/// Side of the height map's squares, mm (grown for very large prints).
const CELL: f64 = 0.25;
/// Squares per tile side.
const TILE: usize = 16;
/// Most squares in the map.
const MAX_CELLS: f64 = 2.0e6;
/// Path the nozzle travels before the filament it laid is mapped, mm.
pub(crate) const LAG: f64 = 2.0;

/// Highest filament centre line over each square of the print.
pub(crate) struct HeightMap {
    origin: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    z: Vec<f64>,
    /// Where over the square that highest filament lies.
    xy: Vec<[f32; 2]>,
    /// (path, string) of the filament that set each square.
    src: Vec<(u32, u32)>,
    tnx: usize,
    tz: Vec<f64>,
    /// Highest filament mapped, mm.
    pub(crate) top: f64,
}

/// A square of the map holding filament above a threshold.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hit {
    /// The highest filament over the square.
    pub(crate) at: DVec3,
    /// Distance from the query point to it, sideways, mm.
    pub(crate) side: f64,
    /// (path, string) of that filament.
    pub(crate) src: (u32, u32),
}

impl HeightMap {
    /// An empty map over `lo`..`hi` (XY).
    pub(crate) fn new(lo: DVec2, hi: DVec2) -> HeightMap {
        let size = (hi - lo).max(DVec2::ZERO);
        let mut cell = CELL;
        while (size.x / cell + 3.0) * (size.y / cell + 3.0) > MAX_CELLS {
            cell *= 2.0;
        }
        let nx = (size.x / cell) as usize + 3;
        let ny = (size.y / cell) as usize + 3;
        let tnx = nx.div_ceil(TILE);
        let tny = ny.div_ceil(TILE);
        HeightMap {
            origin: lo - DVec2::splat(cell),
            cell,
            nx,
            ny,
            z: vec![f64::NEG_INFINITY; nx * ny],
            xy: vec![[0.0; 2]; nx * ny],
            src: vec![(0, 0); nx * ny],
            tnx,
            tz: vec![f64::NEG_INFINITY; tnx * tny],
            top: f64::NEG_INFINITY,
        }
    }

    /// Side of the squares, mm.
    pub(crate) fn cell(&self) -> f64 {
        self.cell
    }

    fn index(&self, p: DVec2) -> Option<(usize, usize)> {
        let q = (p - self.origin) / self.cell;
        if q.x >= 0.0 && q.y >= 0.0 && q.x < self.nx as f64 && q.y < self.ny as f64 {
            Some((q.x as usize, q.y as usize))
        } else {
            None
        }
    }

    /// Maps string a–b (its centre line, sampled every half square).
    pub(crate) fn deposit(&mut self, a: DVec3, b: DVec3, src: (u32, u32)) {
        let n = libm::ceil(2.0 * a.truncate().distance(b.truncate()) / self.cell).clamp(1.0, 1e7)
            as usize;
        for i in 0..=n {
            let p = a.lerp(b, i as f64 / n as f64);
            if let Some((x, y)) = self.index(p.truncate()) {
                let k = y * self.nx + x;
                if p.z > self.z[k] {
                    self.z[k] = p.z;
                    let o = p.truncate() - self.origin;
                    self.xy[k] = [o.x as f32, o.y as f32];
                    self.src[k] = src;
                    let t = (y / TILE) * self.tnx + x / TILE;
                    self.tz[t] = self.tz[t].max(p.z);
                    self.top = self.top.max(p.z);
                }
            }
        }
    }

    /// The first square (in a fixed order) over the rectangle `lo`..`hi`
    /// holding filament higher than `above` for which `hits` says yes.
    pub(crate) fn find(
        &self,
        lo: DVec2,
        hi: DVec2,
        above: f64,
        p: DVec2,
        mut hits: impl FnMut(f64, f64) -> bool,
    ) -> Option<Hit> {
        if above >= self.top {
            return None;
        }
        let cl = |v: f64, n: usize| (v.max(0.0) as usize).min(n - 1);
        let a = (lo - self.origin) / self.cell;
        let b = (hi - self.origin) / self.cell;
        if b.x < 0.0 || b.y < 0.0 || a.x >= self.nx as f64 || a.y >= self.ny as f64 {
            return None;
        }
        let (x0, x1) = (cl(a.x, self.nx), cl(b.x, self.nx));
        let (y0, y1) = (cl(a.y, self.ny), cl(b.y, self.ny));
        for ty in y0 / TILE..=y1 / TILE {
            for tx in x0 / TILE..=x1 / TILE {
                if self.tz[ty * self.tnx + tx] <= above {
                    continue;
                }
                for y in (ty * TILE).max(y0)..=((ty + 1) * TILE - 1).min(y1) {
                    for x in (tx * TILE).max(x0)..=((tx + 1) * TILE - 1).min(x1) {
                        let k = y * self.nx + x;
                        let z = self.z[k];
                        if z <= above {
                            continue;
                        }
                        // the square's highest filament, sideways from p
                        let [ox, oy] = self.xy[k];
                        let q = self.origin + DVec2::new(ox as f64, oy as f64);
                        let side = q.distance(p);
                        if hits(side, z) {
                            return Some(Hit {
                                at: q.extend(z),
                                side,
                                src: self.src[k],
                            });
                        }
                    }
                }
            }
        }
        None
    }
}

/// Collisions of one kind in one part.
#[derive(Default)]
struct Tally {
    samples: usize,
    len: f64,
    /// How far the deepest filament lies inside the cone's surface, and the nozzle then.
    depth: f64,
    depth_at: DVec3,
    /// Nozzle place, string (None: the travel to the part), travel?, hit.
    first: Option<(DVec3, Option<usize>, bool, Hit)>,
}

impl Tally {
    fn add(&mut self, at: DVec3, string: Option<usize>, travel: bool, hit: Hit, step: f64) {
        self.samples += 1;
        self.len += step;
        self.first.get_or_insert((at, string, travel, hit));
    }
}

/// Walks the head's path and checks each move against the filament before it.
struct Walk<'a> {
    paths: &'a [&'a Toolpath],
    hd: &'a super::Head,
    map: HeightMap,
    tan: f64,
    r_tip: f64,
    r_top: f64,
    h_cone: f64,
    head_box: [f64; 4],
    /// Filament this far above the tip is not touched, mm.
    delta: f64,
    cone: Tally,
    head: Tally,
    gantry: Tally,
    /// Strings before this (path, string) are old enough to be met.
    elig: (usize, usize),
    /// Strings before this are in the map.
    mapped: (usize, usize),
    /// Highest of the strings old enough, mm.
    elig_top: f64,
}

impl Walk<'_> {
    /// Maps the filament that has become old enough since the last look
    /// (mapping waits for a look that needs it: a helix printed bottom to top
    /// never does).
    fn catch_up(&mut self) {
        while self.mapped < self.elig {
            let (p, k) = self.mapped;
            let Some(tp) = self.paths.get(p) else { break };
            if k >= tp.len() {
                self.mapped = (p + 1, 0);
                continue;
            }
            // a hair bends out of the head's way: it is not mapped
            if !tp.strings[k].travel && !tp.strings[k].hair {
                let (a, b) = tp.ends(k);
                self.map.deposit(a, b, (p as u32, k as u32));
            }
            self.mapped = (p, k + 1);
        }
    }

    /// Checks the head along a–b (`string` None for the travel between
    /// parts); pulling a hair (`hair`) is checked for the box only.
    #[inline]
    fn segment(&mut self, a: DVec3, b: DVec3, string: Option<usize>, travel: bool, hair: bool) {
        // no filament old enough above the move's lowest point: no collision
        // (a helix printed bottom to top, string after string)
        if a.z.min(b.z) + self.delta >= self.elig_top {
            return;
        }
        self.sample(a, b, string, travel, hair);
    }

    /// [`Walk::segment`] past its first test: the head at points along a–b.
    fn sample(&mut self, a: DVec3, b: DVec3, string: Option<usize>, travel: bool, hair: bool) {
        self.catch_up();
        let len = a.distance(b);
        let n = libm::ceil(len / self.map.cell()).clamp(1.0, 1e7) as usize;
        let step = len / n as f64;
        for i in 0..=n {
            let p = a.lerp(b, i as f64 / n as f64);
            self.at(p, string, travel, hair, if i == 0 { 0.0 } else { step });
        }
    }

    /// Checks the head with its nozzle tip at `p`.
    fn at(&mut self, p: DVec3, string: Option<usize>, travel: bool, hair: bool, step: f64) {
        let xy = p.truncate();
        let (tan, r_tip, h) = (self.tan, self.r_tip, self.h_cone);
        // the deepest filament inside the cone: how far inside its surface
        // (none while pulling a hair: the nozzle rises out of its own blob)
        let mut deepest: Option<(f64, f64, f64)> = None;
        let src = if hair {
            None
        } else {
            self.map.find(
                xy - DVec2::splat(self.r_top),
                xy + DVec2::splat(self.r_top),
                p.z + self.delta,
                xy,
                |side, z| {
                    let depth = r_tip + (z - p.z).min(h) * tan - side;
                    if depth > 0.0 && deepest.is_none_or(|d| depth > d.0) {
                        deepest = Some((depth, side, z));
                    }
                    false
                },
            )
        };
        debug_assert!(src.is_none());
        if let (false, Some((depth, side, z))) = (hair, deepest) {
            // find it again for its place and source
            let hit = self.map.find(
                xy - DVec2::splat(self.r_top),
                xy + DVec2::splat(self.r_top),
                p.z + self.delta,
                xy,
                |s, zz| s == side && zz == z,
            );
            if let Some(hit) = hit {
                self.cone.add(p, string, travel, hit, step);
                if depth > self.cone.depth {
                    self.cone.depth = depth;
                    self.cone.depth_at = p;
                }
            }
        }
        let b = self.head_box;
        let boxed = self.map.find(
            xy + DVec2::new(b[0], b[2]),
            xy + DVec2::new(b[1], b[3]),
            p.z + h,
            xy,
            |_, _| true,
        );
        if let Some(hit) = boxed {
            self.head.add(p, string, travel, hit, step);
        }
        if let Some(g) = self.hd.gantry {
            // the whole bed in x, the band in y
            let far = 1e12;
            let hit = self.map.find(
                DVec2::new(xy.x - far, xy.y + g.y[0]),
                DVec2::new(xy.x + far, xy.y + g.y[1]),
                p.z + g.height,
                xy,
                |_, _| true,
            );
            if let Some(hit) = hit {
                self.gantry.add(p, string, travel, hit, step);
            }
        }
    }
}

/// The `nozzle-collision` and `head-collision` findings.
pub(crate) fn check(recipe: &Recipe, paths: &[&Toolpath]) -> Vec<Finding> {
    let mut out = Vec::new();
    walk(recipe, paths, &mut out);
    out
}

/// [`check`] into `out`.
fn walk(recipe: &Recipe, paths: &[&Toolpath], out: &mut Vec<Finding>) {
    let printer = &recipe.printer;
    let Some((lo, hi)) = footprint(paths) else {
        return; // nothing extrudes
    };
    let mut w = Walk::new(recipe, paths, lo, hi);
    let mut head: Option<DVec3> = None;
    let mut printed_top = f64::NEG_INFINITY;
    for (pi, tp) in paths.iter().enumerate() {
        if let Some(h) = head {
            w.travel(recipe, h, tp.points[0], printed_top);
        }
        w.part(pi, tp, &mut printed_top);
        head = Some(tp.head());
        let cone = std::mem::take(&mut w.cone);
        let boxed = std::mem::take(&mut w.head);
        let gantry = std::mem::take(&mut w.gantry);
        let nozzle = printer.nozzle_diameter;
        report(&w, tp, cone, Met::Cone, nozzle, out);
        report(&w, tp, boxed, Met::Box, nozzle, out);
        report(&w, tp, gantry, Met::Gantry, nozzle, out);
    }
}

/// The corners of the filament's footprint on the bed (the ends of the
/// extruding strings), or None when nothing extrudes.
fn footprint(paths: &[&Toolpath]) -> Option<(DVec2, DVec2)> {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for tp in paths {
        // each point once: the points at either end of an extruding string
        // (the points are finite here: a min or max does not depend on the
        // order it takes them in)
        let n = tp.strings.len();
        for (i, p) in tp.points.iter().enumerate() {
            let before = i > 0 && !tp.strings[i - 1].travel;
            if before || (i < n && !tp.strings[i].travel) {
                lo = lo.min(p.truncate());
                hi = hi.max(p.truncate());
            }
        }
    }
    (lo.x <= hi.x && lo.y <= hi.y).then_some((lo, hi))
}

impl<'a> Walk<'a> {
    /// A walk over `paths` with the recipe's head, its height map covering
    /// `lo`–`hi`, nothing met yet.
    fn new(recipe: &'a Recipe, paths: &'a [&'a Toolpath], lo: DVec2, hi: DVec2) -> Walk<'a> {
        let printer = &recipe.printer;
        let hd = &printer.head;
        Walk {
            paths,
            hd,
            map: HeightMap::new(lo, hi),
            tan: hd.tan(),
            r_tip: hd.tip_diameter / 2.0,
            r_top: hd.top_radius(),
            h_cone: hd.cone_height,
            head_box: hd.head_box,
            delta: printer.checks.support_tolerance * printer.nozzle_diameter,
            cone: Tally::default(),
            head: Tally::default(),
            gantry: Tally::default(),
            elig: (0, 0),
            mapped: (0, 0),
            elig_top: f64::NEG_INFINITY,
        }
    }

    /// The travel from `h` to the next part's `start`, as the G-code makes
    /// it: up to the safe height over `printed_top`, across, down (or
    /// straight when no rise is needed).
    fn travel(&mut self, recipe: &Recipe, h: DVec3, start: DVec3, printed_top: f64) {
        match crate::machine::travel::safe_travel_z(&recipe.printer, h, start, printed_top) {
            Some(z) => {
                let up = DVec3::new(h.x, h.y, z);
                let over = DVec3::new(start.x, start.y, z);
                self.segment(h, up, None, true, false);
                self.segment(up, over, None, true, false);
                self.segment(over, start, None, true, false);
            }
            None => self.segment(h, start, None, true, false),
        }
    }

    /// Walks the strings of part `pi`, each becoming old enough to be met
    /// once the path is [`LAG`] past its end (all of them at the part's
    /// end); raises `printed_top` to the highest extruding string.
    fn part(&mut self, pi: usize, tp: &Toolpath, printed_top: &mut f64) {
        // string j becomes old enough once the path is LAG past its end
        let (mut arc, mut ek, mut earc) = (0.0, 0, 0.0);
        // the length of string ek, kept while it waits (not measured again
        // for every string after it)
        let mut el: Option<f64> = None;
        let mut old_enough = |w: &mut Walk, upto: usize, arc: f64, all: bool| {
            while ek < upto {
                let l = *el.get_or_insert_with(|| tp.length(ek));
                if !all && arc - (earc + l) < LAG {
                    break;
                }
                earc += l;
                if !tp.strings[ek].travel && !tp.strings[ek].hair {
                    let (a, b) = tp.ends(ek);
                    w.elig_top = w.elig_top.max(a.z).max(b.z);
                }
                ek += 1;
                el = None;
            }
            w.elig = (pi, ek);
        };
        for k in 0..tp.len() {
            let s = tp.strings[k];
            let (a, b) = tp.ends(k);
            self.segment(a, b, Some(k), s.travel, s.hair);
            arc += a.distance(b);
            if !s.travel {
                *printed_top = printed_top.max(a.z).max(b.z);
            }
            old_enough(self, k + 1, arc, false);
        }
        old_enough(self, tp.len(), arc, true);
        self.elig = (pi + 1, 0);
    }
}

/// What of the head met filament.
#[derive(Clone, Copy, PartialEq)]
enum Met {
    /// The nozzle's cone: `nozzle-collision`.
    Cone,
    /// The head's box: `head-collision`.
    Box,
    /// The gantry: `head-collision`.
    Gantry,
}

fn report(w: &Walk, tp: &Toolpath, t: Tally, met: Met, nozzle: f64, out: &mut Vec<Finding>) {
    let Some((at, string, travel, hit)) = t.first else {
        return;
    };
    let hd = w.hd;
    let cone = met == Met::Cone;
    let code = if cone {
        "nozzle-collision"
    } else {
        "head-collision"
    };
    let what = match (met, hd.gantry) {
        (Met::Cone, _) => format!(
            "the nozzle's cone ({}° from the vertical, {} mm high, {} mm tip)",
            hd.cone_angle, hd.cone_height, hd.tip_diameter
        ),
        (Met::Gantry, Some(g)) => format!(
            "the gantry (head.gantry: the whole bed's width in x, y {}…{} mm round the nozzle, from {} mm above the tip)",
            g.y[0], g.y[1], g.height
        ),
        _ => {
            let b = hd.head_box;
            format!(
                "the head's box (x {}…{}, y {}…{} mm round the nozzle, from {} mm above the tip)",
                b[0], b[1], b[2], b[3], hd.cone_height
            )
        }
    };
    let doing = match (string, travel) {
        (None, _) => format!("travelling to part `{}`", tp.name),
        (Some(k), true) => format!("on travel string {k}"),
        (Some(k), false) => format!("printing string {k}"),
    };
    let (sp, sk) = hit.src;
    let other = w.paths.get(sp as usize).map_or("?", |t| t.name.as_str());
    let deep = t.depth > nozzle;
    let depth = if !cone {
        String::new()
    } else if deep {
        format!(
            "; filament lies up to {:.2} mm inside the cone (nozzle at {})",
            t.depth,
            fmt_p(t.depth_at)
        )
    } else {
        format!(
            "; it grazes: at most {:.2} mm inside the cone's surface, less than a string (the nozzle scrapes the filament)",
            t.depth
        )
    };
    out.push(Finding {
        code,
        severity: if cone && deep {
            Severity::Error
        } else {
            Severity::Warning
        },
        message: format!(
            "{what} passes through filament printed earlier along {:.1} mm of part `{}`'s head path; first {doing} with the nozzle at {}: filament of part `{other}` (string {sk}) at {}, {:.2} mm above the tip and {:.2} mm to the side{depth}",
            t.len,
            tp.name,
            fmt_p(at),
            fmt_p(hit.at),
            hit.at.z - at.z,
            hit.side
        ),
        part: Some(tp.name.clone()),
        string,
        at: Some(at.to_array()),
        strings: Vec::new(),
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map_with_wall() -> HeightMap {
        let mut m = HeightMap::new(DVec2::new(-10.0, -10.0), DVec2::new(10.0, 10.0));
        // a wall along y = 0 from x = 0 to 5, 10 mm high
        m.deposit(
            DVec3::new(0.0, 0.0, 10.0),
            DVec3::new(5.0, 0.0, 10.0),
            (0, 7),
        );
        m
    }

    #[test]
    fn height_map_finds_the_highest_filament() {
        let m = map_with_wall();
        assert_eq!(m.top, 10.0);
        let all = |_, _| true;
        let p = DVec2::new(2.0, 3.0);
        let h = m
            .find(DVec2::new(-5.0, -5.0), DVec2::new(5.0, 5.0), 9.0, p, all)
            .unwrap();
        assert_eq!(h.src, (0, 7));
        assert!((h.at.z - 10.0).abs() < 1e-12);
        assert!(m
            .find(DVec2::new(-5.0, -5.0), DVec2::new(5.0, 5.0), 10.0, p, all)
            .is_none());
        assert!(m
            .find(DVec2::new(6.0, -5.0), DVec2::new(9.0, 5.0), 0.0, p, all)
            .is_none());
    }

    /// The `head-collision` findings of a tall tower at x = -40, then a low
    /// ring at x = +40, on `printer`.
    fn tower_then_ring(printer: &str) -> Vec<Finding> {
        let text = format!(
            "p3dp: 1\nname: t\nprinter: {printer}\nparts:\n  - {{name: tower, primitive: {{helix: {{radius: 8, height: 40, pitch: 0.3, center: [-40, 0, 0.2]}}}}}}\n  - {{name: ring, primitive: {{helix: {{radius: 8, height: 2, pitch: 0.3, center: [40, 0, 0.2]}}}}}}\n"
        );
        let raw = crate::recipe::parse_yaml(&text, "t.yaml").unwrap();
        let recipe = crate::recipe::resolve(&raw, &[], None, std::path::Path::new(".")).unwrap();
        let parts = crate::generate::assembly::make_parts(&recipe).unwrap();
        let refs: Vec<&Toolpath> = parts.iter().collect();
        check(&recipe, &refs)
            .into_iter()
            .filter(|f| f.code == "head-collision")
            .collect()
    }

    #[test]
    fn the_gantry_meets_a_taller_part_anywhere_across_the_bed() {
        // 80 mm apart in x, beyond the box's 30 mm: only the gantry (25 mm
        // above the tip, the whole bed's width) reaches the 40 mm tower
        let found = tower_then_ring("bambu-a1-mini");
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(
            found[0].message.contains("the gantry"),
            "{}",
            found[0].message
        );
        assert_eq!(found[0].part.as_deref(), Some("ring"));
        assert!(found[0].message.contains("filament of part `tower`"));
        // a profile without a gantry finds nothing
        assert!(tower_then_ring("generic-220").is_empty());
    }

    #[test]
    fn cone_reaches_wider_higher_up() {
        let hd = super::super::Head::default();
        // tip radius 0.5, 30°: 0.5 + 5 tan 30° ≈ 3.39 mm at the top
        assert!((hd.top_radius() - (0.5 + 5.0 * libm::tan(30f64.to_radians()))).abs() < 1e-12);
        let m = map_with_wall();
        let (tan, r_tip, h) = (hd.tan(), 0.5, 5.0);
        let cone = |p: DVec3| {
            let xy = p.truncate();
            m.find(
                xy - DVec2::splat(hd.top_radius()),
                xy + DVec2::splat(hd.top_radius()),
                p.z + 0.1,
                xy,
                |side, z| side < r_tip + (z - p.z).min(h) * tan,
            )
        };
        // 2 mm beside the wall and 9 mm below its top: the cone's rim is ≈3.4 mm out
        assert!(cone(DVec3::new(2.0, 2.0, 1.0)).is_some());
        // 4 mm beside it: clear of the cone (the box is another matter)
        assert!(cone(DVec3::new(2.0, 4.0, 1.0)).is_none());
        // 1 mm beside, 0.5 mm below the top: 0.5 + 0.5 tan 30° < 1
        assert!(cone(DVec3::new(2.0, 1.3, 9.5)).is_none());
        // above the wall: nothing
        assert!(cone(DVec3::new(2.0, 0.0, 10.5)).is_none());
    }
}
