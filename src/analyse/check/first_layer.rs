//! The first layer: where each part holds on to the bed.
//!
//! A string sticks to the bed when the nozzle runs no higher over it than the
//! string's width w (the round bead of its cross-section, at least the
//! nozzle's diameter): the bead then reaches down to the bed. (The support
//! check is more lenient, `support_tolerance` × w, as a string that high still
//! rests on the bed, though it barely holds; a wall starting 0.6 mm up on a
//! filled bottom lies on the bottom, not on the bed.) Its
//! filament of cross-section c, pressed into the gap h between nozzle and bed
//! (h = the string's mean height), covers a band of width c / h: a first layer
//! of c = 0.15 mm² at h = 0.2 mm sticks along a 0.75 mm band. The band is
//! taken at least the round bead's width and at most three nozzles (where the
//! nozzle nearly touches the bed, c / h runs away). The contact area is the
//! area of the union of the bands (each a capsule round its string, seen from
//! above) of the part's strings low enough to touch the bed, less what earlier
//! parts cover: measured on a grid of [`CELL`] mm squares, it does not depend
//! on how finely the path is cut (a helix's pole of 100,000 strings a turn
//! covers what one of 240 does). The footprint is the bounding rectangle of
//! the strings that lie on the bed, seen from above.
//!
//! The report and the stats JSON (`first_layer`) give each part's contact
//! length, area and footprint: the adhesion the papers leave to the designer
//! (a tall print on a small ring of contact is worth a skirt, a brim or a
//! slower first turn). A bed string with the nozzle
//! closer to the bed than `checks.first_layer_min` × the nozzle's diameter
//! is a warning: the nozzle scrapes the bed and the filament cannot get out.

use glam::{DVec2, DVec3};
use serde::Serialize;

use super::support::{width, Widths};
use super::{fmt_p, Finding, Severity};
use crate::base::geom::grid::{ceil_i64, floor_i64, GrowGrid};
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;

/// One part's hold on the bed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Footprint {
    /// The part's name (`skirt` for the skirt).
    pub part: String,
    /// Length of extruding strings lying on the bed, mm.
    pub contact_length_mm: f64,
    /// Area of bed the filament covers: the union of the bands of width c / h, mm².
    pub contact_area_mm2: f64,
    /// Lowest corner of the contact's bounding rectangle, recipe x and y.
    pub min: [f64; 2],
    /// Highest corner of the contact's bounding rectangle, recipe x and y.
    pub max: [f64; 2],
    /// Lowest nozzle height over the bed of a bed string, mm.
    pub min_height_mm: f64,
}

/// Width of the band of bed a string of cross-section `c` at mean height `h`
/// covers: c / h, between the round bead's width and three nozzles.
#[inline]
fn band(c: f64, h: f64, nozzle: f64) -> f64 {
    let lo = width(c, nozzle);
    let hi = (3.0 * nozzle).max(lo);
    if h > 0.0 {
        (c / h).clamp(lo, hi)
    } else {
        hi
    }
}

/// Side of the squares the contact area is measured on, mm.
pub(crate) const CELL: f64 = 0.025;

/// Squares per side of a tile of the [`Cover`].
const TILE: i64 = 64;

/// The bed squares covered so far: tiles of 64 × 64 squares of [`CELL`] mm,
/// one bit each, made as they are first touched.
#[derive(Default)]
struct Cover {
    /// Each tile's place in `tiles`.
    index: crate::base::geom::grid::CellMap<(i64, i64), usize>,
    tiles: Vec<[u64; (TILE * TILE / 64) as usize]>,
    /// The tile touched last and its place (the rows of one capsule mostly
    /// lie in one tile: looked up once, not once a row).
    last: Option<((i64, i64), usize)>,
}

impl Cover {
    /// Covers the squares of row `j` from column `i0` to `i1` (inclusive);
    /// returns how many were not covered before.
    fn row(&mut self, j: i64, i0: i64, i1: i64) -> u64 {
        let mut new = 0;
        let (tj, rj) = (j.div_euclid(TILE), j.rem_euclid(TILE));
        let mut i = i0;
        while i <= i1 {
            let (ti, ri) = (i.div_euclid(TILE), i.rem_euclid(TILE));
            let end = (i1 - i).min(TILE - 1 - ri); // squares after i in this tile
            let at = match self.last {
                Some((key, at)) if key == (ti, tj) => at,
                _ => {
                    let fresh = self.tiles.len();
                    let at = *self.index.entry((ti, tj)).or_insert(fresh);
                    if at == fresh {
                        self.tiles.push([0; (TILE * TILE / 64) as usize]);
                    }
                    self.last = Some(((ti, tj), at));
                    at
                }
            };
            let tile = &mut self.tiles[at];
            // one row of a tile is one u64
            let word = &mut tile[rj as usize];
            let mask = if end + 1 >= 64 {
                u64::MAX
            } else {
                ((1u64 << (end + 1)) - 1) << ri
            };
            // (no bit count for a row all new or all covered: counting bits
            // is a loop on CPUs before x86-64-v2, which builds target)
            let fresh = mask & !*word;
            if fresh == mask {
                new += (end + 1).min(64) as u64;
            } else if fresh != 0 {
                new += fresh.count_ones() as u64;
            }
            *word |= mask;
            i += end + 1;
        }
        new
    }

    /// Covers the squares whose centres lie within `r` of the segment `a`–`b`
    /// (a capsule); returns how many were not covered before.
    fn capsule(&mut self, a: DVec2, b: DVec2, r: f64) -> u64 {
        let lo = a.min(b) - r;
        let hi = a.max(b) + r;
        let j0 = ceil_i64(lo.y / CELL - 0.5);
        let j1 = floor_i64(hi.y / CELL - 0.5);
        // the segment's length and direction, the same for every row
        let d = b - a;
        let len = d.length();
        let axis = (len > 0.0).then(|| (d / len, len));
        let mut new = 0;
        for j in j0..=j1 {
            let y = (j as f64 + 0.5) * CELL;
            if let Some((x0, x1)) = capsule_row(a, b, r, y, axis) {
                let i0 = ceil_i64(x0 / CELL - 0.5);
                let i1 = floor_i64(x1 / CELL - 0.5);
                if i0 <= i1 {
                    new += self.row(j, i0, i1);
                }
            }
        }
        new
    }
}

/// The x-interval of the line at height `y` within `r` of the segment
/// `a`–`b` (a capsule is convex: the union of the intervals of its two end
/// discs and its rectangle); `axis` is the segment's unit direction and
/// length when it has one.
fn capsule_row(
    a: DVec2,
    b: DVec2,
    r: f64,
    y: f64,
    axis: Option<(DVec2, f64)>,
) -> Option<(f64, f64)> {
    let mut out: Option<(f64, f64)> = None;
    let mut join = |lo: f64, hi: f64| {
        if lo <= hi {
            out = Some(match out {
                Some((l, h)) => (l.min(lo), h.max(hi)),
                None => (lo, hi),
            });
        }
    };
    for c in [a, b] {
        let dy = y - c.y;
        if dy.abs() <= r {
            let s = (r * r - dy * dy).sqrt();
            join(c.x - s, c.x + s);
        }
    }
    if let Some((u, len)) = axis {
        // α·x + β within [lo, hi], for the distance across and the place along
        let solve = |alpha: f64, beta: f64, lo: f64, hi: f64| -> Option<(f64, f64)> {
            if alpha.abs() < 1e-12 {
                return (lo..=hi)
                    .contains(&beta)
                    .then_some((f64::NEG_INFINITY, f64::INFINITY));
            }
            let (p, q) = ((lo - beta) / alpha, (hi - beta) / alpha);
            Some((p.min(q), p.max(q)))
        };
        let across = solve(-u.y, u.x * (y - a.y) + u.y * a.x, -r, r);
        let along = solve(u.x, -u.x * a.x + u.y * (y - a.y), 0.0, len);
        if let (Some(p), Some(q)) = (across, along) {
            join(p.0.max(q.0), p.1.min(q.1));
        }
    }
    out
}

/// A bed string seen from above: its ends, its nozzle height, and where it
/// ends along the print (path index, extruded length so far).
#[derive(Clone, Copy)]
struct BedString {
    a: DVec2,
    b: DVec2,
    h: f64,
    path: usize,
    s: f64,
}

/// Whether bed string `e`, laid earlier, covers the bed under `q` (the
/// middle of a string of width `w`): it passes within w / 2 of it, seen from
/// above, lower than it; or as low, alongside it (the middle's foot on that
/// string falls between its ends: not a loop closing end to start) and not
/// just before it on the same path (farther back along the path than
/// w + 3 × its distance): a second pass over the same line.
fn covers(e: &BedString, q: &BedString, w: f64) -> bool {
    let p = q.a.lerp(q.b, 0.5);
    let ab = e.b - e.a;
    let l2 = ab.length_squared();
    let foot = if l2 > 0.0 {
        (p - e.a).dot(ab) / l2
    } else {
        0.0
    };
    let d = p.distance(e.a + ab * foot.clamp(0.0, 1.0));
    d < w / 2.0
        && (e.h < q.h - 1e-9
            || (e.h <= q.h + 1e-9
                && (0.0..=1.0).contains(&foot)
                && (e.path != q.path || q.s - e.s > w + 3.0 * d)))
}

/// A candidate bed string: as seen at its middle (`here`, `s` the length
/// along its path to the middle) and as it covers later ones (`laid`, `s` to
/// its end), with its width and where it is.
struct Candidate {
    here: BedString,
    laid: BedString,
    w: f64,
    k: usize,
}

/// The strings of some paths low enough to touch the bed, in print order
/// (the work both halves of the check share: [`Bed::areas`] and
/// [`Bed::contacts`], which may run on two threads).
pub(crate) struct Bed {
    cands: Vec<Candidate>,
    /// Path j's candidates are `cands[starts[j]..starts[j + 1]]`.
    starts: Vec<usize>,
}

/// A path's contact with the bed, less its area (see [`Bed::contacts`]).
#[derive(Clone, Debug)]
pub(crate) struct Contact {
    /// Length of the strings lying on the bed, mm.
    length: f64,
    /// Their bounding rectangle, seen from above.
    lo: DVec2,
    hi: DVec2,
    /// The lowest nozzle height of a string on the bed, mm.
    lowest: f64,
    /// The first string lower than the scraping height, and its height.
    scrape: Option<(usize, f64)>,
}

impl Contact {
    /// The footprint of part `name` with this contact and `cells` squares
    /// of bed covered ([`Bed::areas`]).
    fn footprint(&self, name: &str, cells: u64) -> Footprint {
        Footprint {
            part: name.to_string(),
            contact_length_mm: self.length,
            contact_area_mm2: cells as f64 * CELL * CELL,
            min: self.lo.to_array(),
            max: self.hi.to_array(),
            min_height_mm: self.lowest,
        }
    }
}

impl Bed {
    /// Every string of `paths` low enough to touch the bed, for a nozzle of
    /// this diameter.
    pub(crate) fn of(paths: &[&Toolpath], nozzle: f64) -> Bed {
        let mut cands: Vec<Candidate> = Vec::new();
        let mut starts = Vec::with_capacity(paths.len() + 1);
        for (j, tp) in paths.iter().enumerate() {
            starts.push(cands.len());
            let (mut along, mut summed) = (0.0, 0);
            let mut widths = Widths::new(nozzle);
            // extruded length along the path up to the current string's middle,
            // summed only when a string low enough needs it (a tall part's
            // strings above its first layer need no length): the same lengths
            // added in the same order, so the same sums; `summed` strings are in
            for (k, s) in tp.strings.iter().enumerate() {
                if s.travel {
                    continue;
                }
                let (a, b) = tp.ends(k);
                // a string is too high when an end is over its width w ≥ the
                // nozzle's: no end over the nozzle's diameter is never too high
                if (a.z > nozzle || b.z > nozzle) && {
                    let w = widths.of(s.c);
                    a.z > w || b.z > w
                } {
                    continue;
                }
                let w = width(s.c, nozzle);
                let l = a.distance(b);
                if l <= 0.0 {
                    continue;
                }
                for i in summed..k {
                    if !tp.strings[i].travel {
                        along += tp.length(i);
                    }
                }
                summed = k + 1;
                let mid = along + l / 2.0;
                along += l;
                let here = BedString {
                    a: a.truncate(),
                    b: b.truncate(),
                    h: (a.z + b.z) / 2.0,
                    path: j,
                    s: mid,
                };
                cands.push(Candidate {
                    here,
                    laid: BedString { s: along, ..here },
                    w,
                    k,
                });
            }
        }
        starts.push(cands.len());
        Bed { cands, starts }
    }

    /// Per path, the bed squares its bands cover that no earlier path's do
    /// (the union of the capsules of width c / h round its strings; see the
    /// module's comment).
    pub(crate) fn areas(&self, paths: &[&Toolpath], nozzle: f64) -> Vec<u64> {
        let mut painted = crate::base::geom::grid::CellSet::default();
        let mut cover = Cover::default();
        (0..paths.len())
            .map(|j| {
                let mut cells = 0u64;
                for c in &self.cands[self.starts[j]..self.starts[j + 1]] {
                    let band = band(paths[j].strings[c.k].c, c.here.h, nozzle);
                    // the same capsule again (a line retraced, either way)
                    // adds nothing to the union: painted once, whatever
                    // the number of passes
                    let (a, b) = (c.here.a.to_array(), c.here.b.to_array());
                    let (a, b) = if a <= b { (a, b) } else { (b, a) };
                    let key = [a[0], a[1], b[0], b[1], band].map(f64::to_bits);
                    if painted.insert(key) {
                        cells += cover.capsule(c.here.a, c.here.b, band / 2.0);
                    }
                }
                cells
            })
            .collect()
    }

    /// Per path, its strings lying on the bed (`None` where none does), and
    /// the first whose nozzle runs lower than `min_h`.
    ///
    /// A string lies on the bed when its nozzle height h ≤ its width w and
    /// no earlier bed string at or below h passes under its middle within
    /// w / 2, seen from above (so a second layer at 0.4 mm, on the first,
    /// does not count, nor a helix's second turn, nor a pass over the same
    /// line at the same height: that bed is covered already).
    pub(crate) fn contacts(&self, paths: &[&Toolpath], min_h: f64) -> Vec<Option<Contact>> {
        // seen from above (z = 0): only the strings kept (not covered
        // themselves) cover later ones, so only they are listed, as they are
        // kept; a grid of every candidate made a path retracing one line a
        // million times scan all the covered copies before the kept one
        // (quadratic: minutes for 2M strings)
        let cands = &self.cands;
        let flat = |p: DVec2| DVec3::new(p.x, p.y, 0.0);
        let mut grid = GrowGrid::new(1.0);
        let mut out = Vec::with_capacity(paths.len());
        for (j, tp) in paths.iter().enumerate() {
            let mut len = 0.0;
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            let mut lowest = f64::INFINITY;
            let mut scrape = None;
            for g in self.starts[j]..self.starts[j + 1] {
                let c = &cands[g];
                let mid = flat(c.here.a.lerp(c.here.b, 0.5));
                let covered = grid.search(mid, c.w / 2.0, |e| {
                    covers(&cands[e as usize].laid, &c.here, c.w)
                });
                if covered {
                    continue;
                }
                grid.insert(g as u32, flat(c.laid.a), flat(c.laid.b));
                let (a2, b2) = (c.here.a, c.here.b);
                let (a, b) = tp.ends(c.k);
                let l = a.distance(b);
                len += l;
                lo = lo.min(a2).min(b2);
                hi = hi.max(a2).max(b2);
                let low = a.z.min(b.z);
                lowest = f64::min(lowest, low);
                if low < min_h && scrape.is_none() {
                    scrape = Some((c.k, low));
                }
            }
            out.push((len > 0.0).then_some(Contact {
                length: len,
                lo,
                hi,
                lowest,
                scrape,
            }));
        }
        out
    }
}

/// The nozzle height under which a bed string scrapes the bed, mm.
pub(crate) fn min_height(recipe: &Recipe) -> f64 {
    recipe.printer.checks.first_layer_min * recipe.printer.nozzle_diameter
}

/// The `first-layer` findings (a warning per part where the nozzle runs too
/// close to the bed, and small contacts), and the footprints of the paths
/// that touch the bed, in print order, for the stats: from the two halves
/// of the work, [`Bed::contacts`] and [`Bed::areas`] of `paths`.
pub(crate) fn findings(
    recipe: &Recipe,
    paths: &[&Toolpath],
    contacts: &[Option<Contact>],
    areas: &[u64],
) -> (Vec<Finding>, Vec<Footprint>) {
    let mut findings = Vec::new();
    let out = &mut findings;
    let p = &recipe.printer;
    let min_h = min_height(recipe);
    let mut footprints = Vec::new();
    for ((tp, contact), &cells) in paths.iter().zip(contacts).zip(areas) {
        let Some(c) = contact else { continue };
        let f = c.footprint(&tp.name, cells);
        small_contact(recipe, tp, &f, out);
        footprints.push(f);
        if let Some((k, h)) = c.scrape {
            let at = tp.midpoint(k);
            out.push(Finding {
                code: "first-layer",
                severity: Severity::Warning,
                message: format!(
                    "part `{}` lays filament with the nozzle {h:.3} mm over the bed, closer than {min_h:.3} mm ({} × the {} mm nozzle, checks.first_layer_min): the nozzle scrapes the bed and the filament cannot get out; first at string {k}, {}",
                    tp.name,
                    p.checks.first_layer_min,
                    p.nozzle_diameter,
                    fmt_p(at)
                ),
                part: Some(tp.name.clone()),
                string: Some(k),
                at: Some(at.to_array()),
                strings: Vec::new(),
            });
        }
    }
    (findings, footprints)
}

/// The `small-contact` warning of part `tp` with footprint `f`: its bed
/// contact is less than `checks.min_contact_per_height` × its height plus
/// `checks.min_contact_per_gram` × its filament's mass (a tall or heavy part
/// on a pole tips or comes off under the nozzle).
fn small_contact(recipe: &Recipe, tp: &Toolpath, f: &Footprint, out: &mut Vec<Finding>) {
    let lim = &recipe.printer.checks;
    let height = tp.points.iter().map(|p| p.z).fold(0.0, f64::max);
    let grams = tp.volume() / 1000.0 * recipe.material.density;
    let need = lim.min_contact_per_height * height + lim.min_contact_per_gram * grams;
    if f.contact_area_mm2 >= need {
        return;
    }
    let at = DVec3::new(
        (f.min[0] + f.max[0]) / 2.0,
        (f.min[1] + f.max[1]) / 2.0,
        0.0,
    );
    out.push(Finding {
        code: "small-contact",
        severity: Severity::Warning,
        message: format!(
            "part `{}` stands on {:.1} mm² of bed for {height:.1} mm of height and {grams:.1} g: less than the {need:.1} mm² it needs ({} mm²/mm of height + {} mm²/g, checks.min_contact_per_height, min_contact_per_gram); it may tip or come off the bed: add a `brim:` or a `stand:` to the part",
            tp.name,
            f.contact_area_mm2,
            lim.min_contact_per_height,
            lim.min_contact_per_gram,
        ),
        part: Some(tp.name.clone()),
        string: None,
        at: Some(at.to_array()),
        strings: Vec::new(),
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Per path, its footprint and its first scraping string, from the two
    /// halves of the check.
    #[allow(clippy::type_complexity)]
    fn footprint_all(
        paths: &[&Toolpath],
        nozzle: f64,
        min_h: f64,
    ) -> Vec<(Option<Footprint>, Option<(usize, f64)>)> {
        let bed = Bed::of(paths, nozzle);
        let areas = bed.areas(paths, nozzle);
        bed.contacts(paths, min_h)
            .into_iter()
            .zip(areas)
            .zip(paths)
            .map(|((c, cells), tp)| {
                let scrape = c.as_ref().and_then(|c| c.scrape);
                (c.map(|c| c.footprint(&tp.name, cells)), scrape)
            })
            .collect()
    }
    use crate::base::toolpath::{Strand, Strands};

    fn ring(r: f64, z: f64, n: usize, c: f64) -> Toolpath {
        let mut tp = Toolpath {
            markers: Vec::new(),
            name: "ring".into(),
            ..Toolpath::default()
        };
        for i in 0..=n {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            tp.points
                .push(DVec3::new(r * libm::cos(a), r * libm::sin(a), z));
        }
        tp.strings = Strands::from(vec![
            Strand {
                c,
                v: 30.0,
                travel: false,
                hair: false,
            };
            n
        ]);
        tp
    }

    #[test]
    fn a_ring_on_the_bed_covers_its_length_times_c_over_h() {
        // c = 0.15 at h = 0.2: a 0.75 mm band along the polygon's perimeter
        let tp = ring(10.0, 0.2, 360, 0.15);
        let (f, scrape) = footprint_all(&[&tp], 0.4, 0.08).remove(0);
        let f = f.unwrap();
        let perimeter = 360.0 * 2.0 * 10.0 * libm::sin(std::f64::consts::PI / 360.0);
        assert!((f.contact_length_mm - perimeter).abs() < 1e-9);
        // the annulus 0.75 mm wide round the circle: 2πr·0.75
        let annulus = std::f64::consts::TAU * 10.0 * 0.75;
        assert!((f.contact_area_mm2 / annulus - 1.0).abs() < 0.005, "{f:?}");
        assert!((f.min[0] + 10.0).abs() < 1e-9 && (f.max[1] - 10.0).abs() < 1e-3);
        assert_eq!(f.min_height_mm, 0.2);
        assert!(scrape.is_none());
    }

    #[test]
    fn raised_rings_do_not_touch_and_scraping_rings_warn() {
        // the round bead of c = 0.15 is 0.437 mm wide: a ring at 0.5 mm does not stick
        assert!(footprint_all(&[&ring(10.0, 0.5, 36, 0.15)], 0.4, 0.08)[0]
            .0
            .is_none());
        assert!(footprint_all(&[&ring(10.0, 0.43, 36, 0.15)], 0.4, 0.08)[0]
            .0
            .is_some());
        // at 0.05 mm the band is capped at three nozzles, and the nozzle scrapes
        let (f, scrape) = footprint_all(&[&ring(10.0, 0.05, 36, 0.15)], 0.4, 0.08).remove(0);
        let f = f.unwrap();
        assert!((f.contact_area_mm2 / (f.contact_length_mm * 1.2) - 1.0).abs() < 0.01);
        assert_eq!(scrape, Some((0, 0.05)));
    }

    #[test]
    fn layers_on_the_first_do_not_touch_the_bed() {
        // a second ring right over the first, 0.2 mm higher, lies on it
        let (lower, upper) = (ring(10.0, 0.2, 72, 0.15), ring(10.0, 0.4, 72, 0.15));
        let all = footprint_all(&[&lower, &upper], 0.4, 0.08);
        assert!(all[0].0.is_some() && all[1].0.is_none());
        // beside it, 1 mm out, it lies on the bed
        let beside = ring(11.0, 0.4, 72, 0.15);
        let all = footprint_all(&[&lower, &beside], 0.4, 0.08);
        let f = all[1].0.as_ref().unwrap();
        // its band, less the 0.75 mm band of the lower ring (to 10.375) it
        // overlaps: from 10.78 to 11.22
        let band = width(0.15, 0.4);
        let want =
            std::f64::consts::PI * ((11.0 + band / 2.0).powi(2) - (11.0 - band / 2.0).powi(2));
        assert!(
            (f.contact_area_mm2 / want - 1.0).abs() < 0.01,
            "{f:?} {want}"
        );
    }

    /// `ring` walked `turns` times at the same height, as one path.
    fn ring_turns(r: f64, z: f64, n: usize, turns: usize) -> Toolpath {
        let one = ring(r, z, n, 0.15);
        let mut tp = one.clone();
        for _ in 1..turns {
            tp.points.extend_from_slice(&one.points[1..]);
            tp.strings.extend_from(&one.strings);
        }
        tp
    }

    #[test]
    fn passes_over_the_same_line_cover_the_bed_once() {
        // 100 turns of 0.01 mm strings at 0.2 mm cover what one turn covers:
        // the bed under a line is covered once, however often it is drawn
        let once = footprint_all(&[&ring_turns(1.6, 0.2, 1000, 1)], 0.4, 0.08).remove(0);
        let many = footprint_all(&[&ring_turns(1.6, 0.2, 1000, 100)], 0.4, 0.08).remove(0);
        let (once, many) = (once.0.unwrap(), many.0.unwrap());
        let perimeter = 1000.0 * 2.0 * 1.6 * libm::sin(std::f64::consts::PI / 1000.0);
        // every string of the first turn counts, though each lies within w / 2
        // of the one before it
        assert!((once.contact_length_mm - perimeter).abs() < 1e-9);
        assert_eq!(many.contact_length_mm, once.contact_length_mm);
        assert_eq!(many.contact_area_mm2, once.contact_area_mm2);
        // the area does not depend on how the circle is cut
        let coarse = footprint_all(&[&ring_turns(1.6, 0.2, 24, 1)], 0.4, 0.08).remove(0);
        let coarse = coarse.0.unwrap().contact_area_mm2;
        assert!((coarse / once.contact_area_mm2 - 1.0).abs() < 0.02);
        // a second part drawn over the first at the same height adds nothing
        let again = ring(1.6, 0.2, 1000, 0.15);
        let both = footprint_all(&[&ring_turns(1.6, 0.2, 1000, 1), &again], 0.4, 0.08);
        assert!(both[1].0.is_none());
    }

    #[test]
    fn capsule_rows_cover_a_disc_and_a_rectangle() {
        // a 10 × 1 capsule: 10 + π·0.25 mm²
        let mut c = Cover::default();
        let n = c.capsule(DVec2::ZERO, DVec2::new(3.0, 4.0) * 2.0, 0.5);
        let area = n as f64 * CELL * CELL;
        assert!((area / (10.0 + std::f64::consts::PI * 0.25) - 1.0).abs() < 0.005);
        // drawn again: nothing new
        assert_eq!(c.capsule(DVec2::ZERO, DVec2::new(6.0, 8.0), 0.5), 0);
    }
}
