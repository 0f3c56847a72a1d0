//! A plate: several recipes' prints on one bed, each printed complete before
//! the next ("complete objects", the makers' "print by object": a print of
//! p3dp's, which has no layers, can share a bed only that way), arranged
//! from what they occupy so that the head and the gantry never meet an
//! object already printed.
//!
//! The head is the printer profile's (`head:`, [`Head`]): its box and cone
//! reach `[x_min, x_max, y_min, y_max]` round the nozzle
//! ([`Head::reach`]), and its gantry, when the profile gives one, spans the
//! whole bed in x above `gantry.height` over the tip, `gantry.y` round the
//! nozzle in y. An object B printed after A is clear of A ([`clear`]) when
//!
//! - A lies outside B's shadow (the rectangle its points cover seen from
//!   above: its first layer, brim and skirt, and anything wider above them)
//!   grown by the head's reach and a [`MARGIN`]: the box sweeps B's shadow
//!   at every height B is printed at, and A stands taller than the box's
//!   floor (the slicers keep the same distance, `extruder_clearance_radius`);
//! - and, when A rises above the gantry over B's lowest point, A lies
//!   outside the gantry's band over B too (the slicers print objects taller
//!   than `extruder_clearance_height` last).
//!
//! [`arrange`] places objects one by one in print order, each at the
//! front-most, then left-most, place where it is clear of every object
//! before it (the places tried: the bed's corner and each place just clear
//! of an object already there, beside it or behind it, in front of it or to
//! its left), objects with a fixed place first, then the others in their
//! order with those too tall for the gantry last; the arrangement is then
//! centred on the bed when nothing is fixed. The collision check
//! ([`crate::analyse::check::collision`]) walks the head over the real
//! filament afterwards and must find nothing.

use glam::DVec2;

use crate::base::error::Result;
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;
use crate::machine::{Bed, Head, Printer};

/// Distance kept beyond the head's reach, and from the bed's edges, mm.
pub(crate) const MARGIN: f64 = 2.0;

/// What an object occupies, in its own coordinates: the rectangle its
/// points cover seen from above (travel included: the head goes there), its
/// highest extruding point and its lowest point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Shadow {
    /// Front-left corner (lowest x and y), mm.
    pub(crate) lo: DVec2,
    /// Back-right corner, mm.
    pub(crate) hi: DVec2,
    /// Highest extruding point, mm.
    pub(crate) top: f64,
    /// Lowest point the nozzle reaches, mm.
    pub(crate) bottom: f64,
}

impl Shadow {
    /// The shadow of an object's paths, or `None` when none extrudes.
    pub(crate) fn of(paths: &[Toolpath]) -> Option<Shadow> {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        let (mut top, mut bottom) = (f64::NEG_INFINITY, f64::INFINITY);
        for tp in paths {
            for (k, p) in tp.points.iter().enumerate() {
                lo = lo.min(p.truncate());
                hi = hi.max(p.truncate());
                bottom = bottom.min(p.z);
                let drawn = (k > 0 && !tp.strings[k - 1].travel)
                    || (k < tp.strings.len() && !tp.strings[k].travel);
                if drawn {
                    top = top.max(p.z);
                }
            }
        }
        top.is_finite().then_some(Shadow {
            lo,
            hi,
            top,
            bottom,
        })
    }

    /// The same shadow moved by `d`.
    pub(crate) fn moved(self, d: DVec2) -> Shadow {
        Shadow {
            lo: self.lo + d,
            hi: self.hi + d,
            ..self
        }
    }

    /// Width and depth, mm.
    pub(crate) fn size(&self) -> DVec2 {
        self.hi - self.lo
    }
}

/// Whether `b`, printed after `a`, is clear of it (see the module's
/// comment): `a` outside `b` grown by the head's reach and [`MARGIN`], and,
/// when `a` rises above the gantry over `b`'s lowest point, outside the
/// gantry's band over `b`.
pub(crate) fn clear(a: &Shadow, b: &Shadow, head: &Head) -> bool {
    let r = head.reach();
    let m = MARGIN;
    let boxed = a.hi.x + m <= b.lo.x + r[0]
        || a.lo.x - m >= b.hi.x + r[1]
        || a.hi.y + m <= b.lo.y + r[2]
        || a.lo.y - m >= b.hi.y + r[3];
    boxed && under_gantry(a, b, head).is_none_or(|[y0, y1]| a.hi.y + m <= y0 || a.lo.y - m >= y1)
}

/// The gantry's band in y over `b` when `a` rises above it there, else `None`.
fn under_gantry(a: &Shadow, b: &Shadow, head: &Head) -> Option<[f64; 2]> {
    let g = head.gantry?;
    (a.top > b.bottom + g.height).then_some([b.lo.y + g.y[0], b.hi.y + g.y[1]])
}

/// The bed as the arrangement sees it, recipe coordinates, [`MARGIN`] in
/// from its edges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Area {
    /// A rectangle.
    Rect {
        /// Front-left corner.
        lo: DVec2,
        /// Back-right corner.
        hi: DVec2,
    },
    /// A disc.
    Disc {
        /// Centre.
        centre: DVec2,
        /// Radius.
        r: f64,
    },
}

impl Area {
    /// The bed of `printer` in recipe coordinates.
    pub(crate) fn of(printer: &Printer) -> Area {
        let o = DVec2::new(printer.origin[0], printer.origin[1]);
        match printer.bed {
            Bed::Rectangle { size, min, .. } => {
                let lo = DVec2::from_array(min) - o + DVec2::splat(MARGIN);
                let hi =
                    DVec2::from_array(min) + DVec2::from_array(size) - o - DVec2::splat(MARGIN);
                Area::Rect { lo, hi }
            }
            Bed::Circle { diameter, .. } => Area::Disc {
                centre: -o,
                r: diameter / 2.0 - MARGIN,
            },
        }
    }

    /// Whether the rectangle `lo`..`hi` lies on it.
    pub(crate) fn holds(&self, lo: DVec2, hi: DVec2) -> bool {
        const EPS: f64 = 1e-9;
        match *self {
            Area::Rect { lo: a, hi: b } => {
                lo.x >= a.x - EPS && lo.y >= a.y - EPS && hi.x <= b.x + EPS && hi.y <= b.y + EPS
            }
            Area::Disc { centre, r } => [lo, hi, DVec2::new(lo.x, hi.y), DVec2::new(hi.x, lo.y)]
                .iter()
                .all(|p| p.distance(centre) <= r + EPS),
        }
    }

    /// Its centre.
    fn centre(&self) -> DVec2 {
        match *self {
            Area::Rect { lo, hi } => (lo + hi) / 2.0,
            Area::Disc { centre, .. } => centre,
        }
    }

    /// The lowest and highest x a rectangle of `size` may start at with its
    /// front edge at `y`.
    fn row(&self, size: DVec2, y: f64) -> (f64, f64) {
        match *self {
            Area::Rect { lo, hi } => (lo.x, hi.x - size.x),
            Area::Disc { centre, .. } => {
                let x0 = self.starts(size, y).0;
                (x0, 2.0 * centre.x - x0 - size.x)
            }
        }
    }

    /// Lowest x and y a rectangle `w` wide and `d` deep may start at, in
    /// the band of y from `y` (for a disc: where its chord is widest there).
    fn starts(&self, size: DVec2, y: f64) -> (f64, f64) {
        match *self {
            Area::Rect { lo, .. } => (lo.x, lo.y),
            Area::Disc { centre, r } => {
                let dy = (y - centre.y).abs().max((y + size.y - centre.y).abs());
                let half = libm::sqrt((r * r - dy * dy).max(0.0));
                let lowest = libm::sqrt((r * r - size.x * size.x / 4.0).max(0.0));
                (centre.x - half, centre.y - lowest)
            }
        }
    }
}

/// One object to place: its shadow in its own coordinates and, when it has
/// a fixed place, where its (0, 0) goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Item {
    /// What it occupies.
    pub(crate) shadow: Shadow,
    /// Its fixed place, if any.
    pub(crate) at: Option<DVec2>,
}

/// Why a plate cannot be arranged: the object concerned (its index) and
/// what stands in its way.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Refusal {
    /// It does not fit on the bed even alone.
    TooBig(usize),
    /// It has a fixed place off the bed.
    Off(usize),
    /// Two objects with fixed places are not clear of each other (the
    /// first printed, the second).
    Fixed(usize, usize),
    /// It is taller than the gantry and no place keeps it out of the way of
    /// the one (the index) printed before it that is too.
    Gantry(usize, usize),
    /// The bed is full: no place is clear of the objects before it.
    Full(usize),
}

/// Whether an item is taller than the gantry over the lowest object.
fn tall(item: &Item, items: &[Item], head: &Head) -> bool {
    let low = items
        .iter()
        .map(|i| i.shadow.bottom)
        .fold(f64::INFINITY, f64::min);
    head.gantry
        .is_some_and(|g| item.shadow.top > low + g.height)
}

/// Places `items` on `area` for `head`: each item's index and where its
/// (0, 0) goes, in print order (see the module's comment). On a rectangular
/// bed with nothing fixed, rows of every width from one object to the bed's
/// are tried, and the arrangement that takes the smallest share of the bed
/// (the larger of its width's and its depth's) is kept: four pots make a
/// square, not a row of three and one.
pub(crate) fn arrange(
    items: &[Item],
    head: &Head,
    area: &Area,
) -> Result<Vec<(usize, DVec2)>, Refusal> {
    let whole = arrange_in(items, head, area)?;
    let Area::Rect { lo, hi } = *area else {
        return Ok(whole);
    };
    if items.iter().any(|i| i.at.is_some()) {
        return Ok(whole);
    }
    let share = |placed: &[(usize, DVec2)]| {
        let (mut a, mut b) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for &(k, d) in placed {
            let s = items[k].shadow.moved(d);
            a = a.min(s.lo);
            b = b.max(s.hi);
        }
        let (used, bed) = (b - a, hi - lo);
        (used.x / bed.x).max(used.y / bed.y)
    };
    // side by side, an object starts this far right of the one before
    let gap = MARGIN - head.reach()[0];
    let mut widths: Vec<f64> = items.iter().map(|i| i.shadow.size().x).collect();
    widths.sort_by(|a, b| b.total_cmp(a));
    let mut best = (share(&whole), whole);
    let mut row = 0.0;
    // at most 16 rows' widths tried: a plate holds few objects a row
    for (k, w) in widths.iter().enumerate().take(16) {
        // k + 1 of the widest side by side
        row += w + if k > 0 { gap } else { 0.0 };
        if lo.x + row > hi.x {
            break;
        }
        let narrow = Area::Rect {
            lo,
            hi: DVec2::new(lo.x + row, hi.y),
        };
        if let Ok(mut placed) = arrange_in(items, head, &narrow) {
            let mut all: Vec<(usize, DVec2, Shadow)> = placed
                .iter()
                .map(|&(k, d)| (k, d, items[k].shadow.moved(d)))
                .collect();
            centre(&mut all, area);
            placed = all.into_iter().map(|(k, d, _)| (k, d)).collect();
            let s = share(&placed);
            if s < best.0 - 1e-9 {
                best = (s, placed);
            }
        }
    }
    Ok(best.1)
}

/// [`arrange`] on `area` as it is.
fn arrange_in(items: &[Item], head: &Head, area: &Area) -> Result<Vec<(usize, DVec2)>, Refusal> {
    let mut order: Vec<usize> = (0..items.len())
        .filter(|&k| items[k].at.is_some())
        .collect();
    let free: Vec<usize> = (0..items.len())
        .filter(|&k| items[k].at.is_none())
        .collect();
    order.extend(free.iter().filter(|&&k| !tall(&items[k], items, head)));
    order.extend(free.iter().filter(|&&k| tall(&items[k], items, head)));
    let mut placed: Vec<(usize, DVec2, Shadow)> = Vec::with_capacity(items.len());
    for &k in &order {
        let item = &items[k];
        let d = match item.at {
            Some(at) => {
                let s = item.shadow.moved(at);
                if !area.holds(s.lo, s.hi) {
                    return Err(Refusal::Off(k));
                }
                if let Some((j, _, _)) = placed.iter().find(|(_, _, a)| !clear(a, &s, head)) {
                    return Err(Refusal::Fixed(*j, k));
                }
                at
            }
            None => place(k, items, head, area, &placed)?,
        };
        placed.push((k, d, item.shadow.moved(d)));
    }
    if placed.len() == free.len() && !placed.is_empty() {
        centre(&mut placed, area);
    }
    Ok(placed.into_iter().map(|(k, d, _)| (k, d)).collect())
}

/// The front-most, then left-most, place of item `k` clear of `placed`.
fn place(
    k: usize,
    items: &[Item],
    head: &Head,
    area: &Area,
    placed: &[(usize, DVec2, Shadow)],
) -> Result<DVec2, Refusal> {
    let s = items[k].shadow;
    if let Some(corner) = first_corner(&s, head, area, placed) {
        return Ok(corner - s.lo);
    }
    let size = s.size();
    let alone = area.centre() - size / 2.0;
    if placed.is_empty() || !area.holds(alone, alone + size) {
        return Err(Refusal::TooBig(k));
    }
    let no_gantry = Head {
        gantry: None,
        ..*head
    };
    if first_corner(&s, &no_gantry, area, placed).is_some() {
        let other = placed
            .iter()
            .find(|(_, _, a)| head.gantry.is_some_and(|g| a.top > s.bottom + g.height))
            .map_or(k, |(j, _, _)| *j);
        return Err(Refusal::Gantry(k, other));
    }
    Err(Refusal::Full(k))
}

/// The front-left corner of the front-most, then left-most, place for
/// shadow `s` clear of `placed`, if any. The rows tried: the bed's front,
/// and each just clear of a placed object (behind it, in front of it,
/// behind its gantry band) or level with it; in a row, a placed object not clear of it in y
/// bars an interval of x (the row's gantry band, the whole row), and the
/// left-most x past every barred interval is the place. O(n² log n) for n
/// objects placed.
fn first_corner(
    s: &Shadow,
    head: &Head,
    area: &Area,
    placed: &[(usize, DVec2, Shadow)],
) -> Option<DVec2> {
    let (r, m, size) = (head.reach(), MARGIN, s.size());
    let mut ys = vec![area.starts(size, 0.0).1];
    for (_, _, a) in placed {
        ys.push(a.hi.y + m - r[2]);
        ys.push(a.lo.y - m - r[3] - size.y);
        ys.push(a.lo.y);
        if let Some(g) = head.gantry {
            ys.push(a.hi.y + m - g.y[0]);
        }
    }
    ys.retain(|y| y.is_finite());
    ys.sort_by(f64::total_cmp);
    ys.dedup();
    let mut barred: Vec<(f64, f64)> = Vec::with_capacity(placed.len());
    'rows: for y in ys {
        barred.clear();
        for (_, _, a) in placed {
            let (y0, y1) = (y, y + size.y);
            // the gantry over the row meets an earlier object taller than it
            if let Some(g) = head.gantry {
                let band = (y0 + g.y[0], y1 + g.y[1]);
                if a.top > s.bottom + g.height && a.hi.y + m > band.0 && a.lo.y - m < band.1 {
                    continue 'rows;
                }
            }
            // the box: clear in y, or else in x outside this interval
            if a.hi.y + m > y0 + r[2] && a.lo.y - m < y1 + r[3] {
                barred.push((a.lo.x - m - r[1] - size.x, a.hi.x + m - r[0]));
            }
        }
        barred.sort_by(|p, q| p.0.total_cmp(&q.0));
        let (x_min, x_max) = area.row(size, y);
        let mut x = x_min;
        for &(lo, hi) in &barred {
            if x <= lo {
                break;
            }
            x = x.max(hi);
        }
        let corner = DVec2::new(x, y);
        if x <= x_max + 1e-9 && area.holds(corner, corner + size) {
            return Some(corner);
        }
    }
    None
}

/// Moves the placed objects together so that their bounding rectangle is
/// centred on the bed, when they all stay on it.
fn centre(placed: &mut [(usize, DVec2, Shadow)], area: &Area) {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for (_, _, s) in placed.iter() {
        lo = lo.min(s.lo);
        hi = hi.max(s.hi);
    }
    let shift = area.centre() - (lo + hi) / 2.0;
    if placed
        .iter()
        .all(|(_, _, s)| area.holds(s.lo + shift, s.hi + shift))
    {
        for (_, d, s) in placed.iter_mut() {
            *d += shift;
            *s = s.moved(shift);
        }
    }
}

/// The strings of a recipe as its build prints them: its skirt (if any)
/// first, then each part with its own steps, its groups' steps, stands and
/// brims ([`crate::generate::assembly::make_parts`]).
pub(crate) fn made(recipe: &Recipe) -> Result<Vec<Toolpath>> {
    made_in(recipe, None)
}

/// [`made`], each part's own toolpath taken from `kept` when the build
/// before made it from the same inputs (`p3dp watch`).
pub(crate) fn made_in(
    recipe: &Recipe,
    kept: Option<&crate::generate::assembly::Parts>,
) -> Result<Vec<Toolpath>> {
    let parts = crate::generate::assembly::make_parts_in(recipe, kept)?;
    let mut paths = Vec::with_capacity(parts.len() + 1);
    if let Some(s) = &recipe.skirt {
        let cv = (recipe.parts[0].cross_section, recipe.parts[0].speed);
        let spacing = recipe.printer.nozzle_diameter;
        if let Some(sk) = crate::generate::skirt::make(s, &parts, spacing, cv, recipe.max_strings)
            .map_err(|e| e.under("skirt"))?
        {
            paths.push(sk);
        }
    }
    paths.extend(parts);
    Ok(paths)
}

/// Moves every point (and turtle marker) of `paths` by `d` in x and y.
pub(crate) fn translate(paths: &mut [Toolpath], d: DVec2) {
    let d3 = d.extend(0.0);
    for tp in paths {
        for p in &mut tp.points {
            *p += d3;
        }
        for m in &mut tp.markers {
            m.pos += d3;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::Gantry;

    fn head() -> Head {
        Head {
            head_box: [-30.0, 30.0, -30.0, 35.0],
            gantry: Some(Gantry {
                height: 25.0,
                y: [-30.0, 35.0],
            }),
            ..Head::default()
        }
    }

    fn pot(w: f64, top: f64) -> Item {
        Item {
            shadow: Shadow {
                lo: DVec2::splat(-w / 2.0),
                hi: DVec2::splat(w / 2.0),
                top,
                bottom: 0.2,
            },
            at: None,
        }
    }

    fn bed(side: f64) -> Area {
        Area::Rect {
            lo: DVec2::splat(-side / 2.0 + MARGIN),
            hi: DVec2::splat(side / 2.0 - MARGIN),
        }
    }

    /// Every pair in print order is clear, and every object on the bed.
    fn check(items: &[Item], placed: &[(usize, DVec2)], area: &Area, head: &Head) {
        for (i, &(a, da)) in placed.iter().enumerate() {
            let sa = items[a].shadow.moved(da);
            assert!(area.holds(sa.lo, sa.hi), "{a} off the bed");
            for &(b, db) in &placed[i + 1..] {
                let sb = items[b].shadow.moved(db);
                assert!(clear(&sa, &sb, head), "{b} after {a}");
            }
        }
    }

    #[test]
    fn four_pots_on_a_small_bed_keep_the_heads_reach() {
        let items = vec![pot(40.0, 20.0); 4];
        let area = bed(180.0);
        let placed = arrange(&items, &head(), &area).unwrap();
        assert_eq!(placed.len(), 4);
        check(&items, &placed, &area, &head());
        // a 2 × 2 grid: x apart by at least the box's 30 mm (+ margin)
        let xs: Vec<f64> = placed.iter().map(|p| p.1.x).collect();
        assert!(
            (xs[1] - xs[0] - (40.0 + 30.0 + MARGIN)).abs() < 1e-9,
            "{xs:?}"
        );
        // centred: the grid's middle is the bed's
        let mid = placed.iter().map(|p| p.1).sum::<DVec2>() / 4.0;
        assert!(mid.length() < 1e-9, "{mid}");
    }

    #[test]
    fn a_pot_too_tall_for_the_gantry_goes_last_and_two_cannot_share_a_row() {
        let mut items = vec![pot(30.0, 20.0); 3];
        items.insert(0, pot(30.0, 60.0));
        let area = bed(180.0);
        let placed = arrange(&items, &head(), &area).unwrap();
        assert_eq!(placed.last().unwrap().0, 0, "{placed:?}");
        check(&items, &placed, &area, &head());
        // five tall pots on the small bed: one gantry band each, no room
        let items = vec![pot(30.0, 60.0); 5];
        let e = arrange(&items, &head(), &area).unwrap_err();
        assert!(matches!(e, Refusal::Gantry(_, _)), "{e:?}");
    }

    #[test]
    fn objects_that_cannot_fit_are_named() {
        let area = bed(180.0);
        assert_eq!(
            arrange(&[pot(200.0, 5.0)], &head(), &area).unwrap_err(),
            Refusal::TooBig(0)
        );
        let items = vec![pot(60.0, 5.0); 5];
        assert_eq!(
            arrange(&items, &head(), &area).unwrap_err(),
            Refusal::Full(4)
        );
        // a fixed place off the bed, and two fixed places too close
        let mut off = pot(20.0, 5.0);
        off.at = Some(DVec2::new(85.0, 0.0));
        assert_eq!(
            arrange(&[off], &head(), &area).unwrap_err(),
            Refusal::Off(0)
        );
        let mut a = pot(20.0, 5.0);
        a.at = Some(DVec2::ZERO);
        let mut b = a;
        b.at = Some(DVec2::new(30.0, 0.0));
        assert_eq!(
            arrange(&[a, b], &head(), &area).unwrap_err(),
            Refusal::Fixed(0, 1)
        );
    }

    #[test]
    fn a_fixed_object_stays_and_the_rest_keep_clear_of_it() {
        let mut items = vec![pot(30.0, 10.0); 3];
        items[1].at = Some(DVec2::new(30.0, -40.0));
        let area = bed(180.0);
        let placed = arrange(&items, &head(), &area).unwrap();
        assert_eq!(placed[0], (1, DVec2::new(30.0, -40.0)));
        check(&items, &placed, &area, &head());
    }

    #[test]
    fn two_hundred_small_objects_are_placed_in_bounded_time() {
        // the most a plate takes: each placement tries O(n) rows of O(n)
        // barred intervals, not every pair of corners against every object
        let items = vec![pot(2.0, 3.0); 200];
        let area = bed(320.0);
        let h = Head::default();
        let t = std::time::Instant::now();
        let placed = arrange(&items, &h, &area).unwrap();
        assert_eq!(placed.len(), 200);
        check(&items, &placed, &area, &h);
        assert!(t.elapsed().as_secs_f64() < 20.0, "{:?}", t.elapsed());
    }

    #[test]
    fn a_round_bed_holds_what_lies_within_its_disc() {
        let area = Area::Disc {
            centre: DVec2::ZERO,
            r: 100.0,
        };
        let items = vec![pot(30.0, 10.0); 4];
        let placed = arrange(&items, &head(), &area).unwrap();
        check(&items, &placed, &area, &head());
    }
}
