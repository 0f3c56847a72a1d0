//! A recipe resolved: printer, material and parts whose primitives and steps
//! have every number evaluated and every expression compiled. The YAML edge
//! ([`crate::recipe`]) makes it; the stages after it only read it.

use crate::base::error::{Error, Result};
use crate::base::expr::Params;
use crate::base::toolpath::Toolpath;
use crate::generate::primitive::{CaHelix, Primitive};
use crate::generate::step::Step;
use crate::machine::{Material, Printer};

/// The default limit on strings in one part (a recipe may change it).
pub(crate) const DEFAULT_MAX_STRINGS: u64 = 50_000_000;

/// `skirt:` resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Skirt {
    /// mm outside the parts' footprint.
    pub(crate) distance: f64,
    /// Number of loops.
    pub(crate) loops: u32,
}

/// A part resolved: numbers evaluated, expressions compiled.
#[derive(Clone, Debug)]
pub(crate) struct Part {
    /// Name for reports (`part 1` when the recipe gives none).
    pub(crate) name: String,
    /// Cross-section, mm².
    pub(crate) cross_section: f64,
    /// Speed, mm/s.
    pub(crate) speed: f64,
    /// The primitive (the first, when the part has several).
    pub(crate) primitive: Primitive,
    /// The steps.
    pub(crate) steps: Vec<Step>,
    /// The primitives after the first, in order (see [`crate::generate::assembly`]).
    pub(crate) more: Vec<Piece>,
    /// Where the part is written, through templates and loops
    /// (`parts[1].parts[0] (template ring, k = 3)`), for error places.
    pub(crate) place: String,
    /// Loops on the bed round its first contact, printed first.
    pub(crate) brim: Option<Brim>,
    /// A short printed tube round its first contact, printed first (before
    /// the brim, which then goes round the stand).
    pub(crate) stand: Option<Stand>,
}

/// A part's brim: `loops` closed circles on the bed round the part's first
/// contact, from the outside in, then the part (a remedy for a part that
/// stands on a small contact, as Kanada's sphere and globe on their poles).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Brim {
    /// Number of loops.
    pub(crate) loops: u32,
    /// Width of a loop and the step between loops, mm.
    pub(crate) line_width: f64,
    /// Height of the loops (their nozzle height over the bed), mm.
    pub(crate) layer_height: f64,
    /// Speed, mm/s.
    pub(crate) speed: f64,
}

impl Brim {
    /// Longest chord of a brim loop, mm.
    const CHORD: f64 = 0.5;

    /// The brim round `tp`'s first contact, then `tp`: the contact is the
    /// extruding strings within one brim layer of the part's lowest; the
    /// loops are circles about the middle of their bounding rectangle, the
    /// innermost 0.9 × line_width outside the farthest contact point (its
    /// bead overlaps the part's), each next one line_width further out,
    /// printed outermost first so the head ends inside, next to the part.
    #[cfg(test)]
    pub(crate) fn around(&self, tp: &Toolpath) -> Toolpath {
        let mut out = tp.clone();
        self.put_round(&mut out);
        out
    }

    /// [`Brim::around`] in place: the loops put ahead of `tp`'s strings.
    pub(crate) fn put_round(&self, tp: &mut Toolpath) {
        if tp.is_empty() || self.loops == 0 {
            return;
        }
        let (centre, reach) = first_contact(tp, self.layer_height);
        let (w, h) = (self.line_width, self.layer_height);
        let c = w * h;
        let r_in = reach + 0.9 * w;
        let on_circle = |r: f64, t: f64| {
            glam::DVec3::new(centre.x + r * libm::cos(t), centre.y + r * libm::sin(t), h)
        };
        let r_out = r_in + (self.loops - 1) as f64 * w;
        let mut out = Toolpath::new(on_circle(r_out, 0.0));
        for k in (0..self.loops).rev() {
            let r = r_in + k as f64 * w;
            let n = (libm::ceil(std::f64::consts::TAU * r / Self::CHORD) as usize).max(24);
            if k + 1 < self.loops {
                out.travel(on_circle(r, 0.0), self.speed);
            }
            for i in 1..=n {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                out.draw(on_circle(r, if i == n { 0.0 } else { t }), c, self.speed);
            }
        }
        tp.prepend(out, self.speed);
    }
}

/// The middle of the bounding rectangle of `tp`'s first contact (its
/// extruding strings within `layer` mm of its lowest), seen from above, and
/// the farthest contact point's distance from it.
fn first_contact(tp: &Toolpath, layer: f64) -> (glam::DVec2, f64) {
    let drawn = || {
        (0..tp.len())
            .filter(|&k| !tp.strings[k].travel)
            .flat_map(|k| {
                let (a, b) = tp.ends(k);
                [a, b]
            })
    };
    let z0 = drawn().map(|p| p.z).fold(f64::INFINITY, f64::min);
    let (mut lo, mut hi) = (
        glam::DVec2::splat(f64::INFINITY),
        glam::DVec2::splat(f64::NEG_INFINITY),
    );
    for p in drawn().filter(|p| p.z <= z0 + layer) {
        lo = lo.min(p.truncate());
        hi = hi.max(p.truncate());
    }
    if !lo.is_finite() {
        let p = tp
            .points
            .first()
            .map_or(glam::DVec2::ZERO, |p| p.truncate());
        (lo, hi) = (p, p);
    }
    let centre = (lo + hi) * 0.5;
    let reach = drawn()
        .filter(|p| p.z <= z0 + layer)
        .map(|p| p.truncate().distance(centre))
        .fold(0.0, f64::max);
    (centre, reach)
}

/// A part's stand: a short tube of `walls` concentric walls printed on the
/// bed before the part, centred under its first contact, its top just under
/// where the part passes over it: the foot of Kanada's bowl ("a half sphere
/// and a stand", paper 000 Fig. 12), for a part that stands on a pole. It
/// widens the part's hold on the bed, and a part that flares out over it
/// (a sphere from its pole) lays its strings on the tube's top.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Stand {
    /// Radius of the outermost wall's centre line, mm.
    pub(crate) radius: f64,
    /// Number of walls, `line_width` apart, from `radius` inwards.
    pub(crate) walls: u32,
    /// Height, mm (whole layers); `None`: as tall as the part leaves room for.
    pub(crate) height: Option<f64>,
    /// Width of a wall, mm.
    pub(crate) line_width: f64,
    /// Height of a layer (the first layer's nozzle height), mm.
    pub(crate) layer_height: f64,
    /// Speed, mm/s.
    pub(crate) speed: f64,
}

impl Stand {
    /// Longest chord of a wall's circle, mm.
    const CHORD: f64 = 0.5;

    /// How many layers the stand has under `tp` (see [`Stand::under`]), and
    /// its centre; errors name the key under `stand.`.
    ///
    /// The room: the nozzle's flat tip reaches `tip_radius` round the
    /// nozzle, so where the nozzle, running along a string of the part
    /// (travel too), comes within `tip_radius` of the tube's band (from the
    /// inner wall's inner edge to the outer wall's outer edge, seen from
    /// above), the tube's top (its last layer's nozzle height) may be no
    /// higher than the nozzle: the lower end of every such string bounds it.
    /// A part that flares out over the stand (a sphere from its pole) then
    /// lays its strings just over the tube's top, a little higher the
    /// steeper it rises. The layers are whole: n = ⌊top / layer_height⌋ (with
    /// a micron's tolerance for the rounding of the division).
    pub(crate) fn layers(&self, tp: &Toolpath, tip_radius: f64) -> Result<(glam::DVec2, u32)> {
        let (centre, _) = first_contact(tp, self.layer_height);
        let (lo, hi) = self.band(tip_radius)?;
        let over = lowest_over(tp, centre, lo, hi);
        let n = match self.height {
            Some(want) => self.wanted_layers(want, over)?,
            None => self.fitted_layers(over)?,
        };
        if n > 10_000.0 {
            return Err(Error::input(
                "stand.height",
                format!("{} layers is too many; expected at most 10000", n),
            ));
        }
        Ok((centre, n as u32))
    }

    /// The band of the tube seen from above, widened by the nozzle's
    /// `tip_radius` on either side: its inner and outer radius; an error
    /// when the walls do not fit in the radius.
    fn band(&self, tip_radius: f64) -> Result<(f64, f64)> {
        let w = self.line_width;
        let inner = self.radius - self.walls.saturating_sub(1) as f64 * w;
        if self.walls == 0 || inner - 0.5 * w <= 0.0 {
            return Err(Error::input(
                "stand.walls",
                format!(
                    "{} walls {w} mm apart do not fit in a radius of {} mm; expected fewer walls or a larger radius",
                    self.walls, self.radius
                ),
            ));
        }
        Ok((
            inner - 0.5 * w - tip_radius,
            self.radius + 0.5 * w + tip_radius,
        ))
    }

    /// Whole layers up to `top`: ⌊top / layer_height⌋, with a micron's
    /// tolerance for the rounding of the division.
    fn fit(&self, top: f64) -> f64 {
        libm::floor(top / self.layer_height + 1e-6)
    }

    /// The layers of a stand `want` mm high, refused when less than one
    /// layer or higher than `over`, the lowest string over the band.
    fn wanted_layers(&self, want: f64, over: f64) -> Result<f64> {
        let h = self.layer_height;
        let n = self.fit(want);
        if n < 1.0 {
            return Err(Error::input(
                "stand.height",
                format!("{want} mm is less than one layer of {h} mm; expected at least {h}"),
            ));
        }
        if n * h > over + 1e-6 {
            return Err(Error::input(
                "stand.height",
                format!(
                    "the part passes over the stand's walls (radius {} mm, with the nozzle's room) at z = {over:.3} mm, so a stand of {:.3} mm would be hit; expected at most {:.3} mm (whole layers of {h} mm no higher than the nozzle there), or leave `height` out to fit it",
                    self.radius,
                    n * h,
                    (self.fit(over) * h).max(0.0)
                ),
            ));
        }
        Ok(n)
    }

    /// The layers of a stand as tall as fits under `over`, the lowest
    /// string over the band: refused when nothing passes over it, or when
    /// not even one layer fits.
    fn fitted_layers(&self, over: f64) -> Result<f64> {
        let h = self.layer_height;
        if !over.is_finite() {
            return Err(Error::input(
                "stand",
                format!(
                    "nothing of the part passes over a stand of radius {} mm, so its height cannot be fitted under the part; expected `height`",
                    self.radius
                ),
            ));
        }
        let n = self.fit(over);
        if n < 1.0 {
            return Err(Error::input(
                "stand.radius",
                format!(
                    "the part passes over the stand's walls at z = {over:.3} mm: no room for one layer of {h} mm under it; expected a larger radius (where the part is higher)"
                ),
            ));
        }
        Ok(n)
    }

    /// How many strings a stand of `layers` layers has.
    fn strings(&self, layers: u32) -> u64 {
        let per_layer: u64 = (0..self.walls)
            .map(|j| self.segments(self.radius - j as f64 * self.line_width) as u64 + 1)
            .sum();
        per_layer.saturating_mul(layers as u64)
    }

    fn segments(&self, r: f64) -> usize {
        (libm::ceil(std::f64::consts::TAU * r / Self::CHORD) as usize).max(24)
    }

    /// The stand under `tp`, then `tp`, refused past `budget` strings for
    /// the stand: layer k (1..=n) at nozzle height k·layer_height, each its
    /// walls as closed circles from the outermost in, a travel up to the next
    /// layer's outer wall, then the part from the stand's last point.
    pub(crate) fn under(&self, tp: &Toolpath, tip_radius: f64, budget: u64) -> Result<Toolpath> {
        if tp.is_empty() {
            return Ok(tp.clone());
        }
        let (centre, n) = self.layers(tp, tip_radius)?;
        let count = self.strings(n);
        if count > budget {
            return Err(Error::input(
                "stand",
                format!("the stand has {count} strings, more than the {budget} the recipe's max_strings leaves; expected a smaller stand"),
            ));
        }
        let (w, h) = (self.line_width, self.layer_height);
        let c = w * h;
        let at = |r: f64, t: f64, z: f64| {
            glam::DVec3::new(centre.x + r * libm::cos(t), centre.y + r * libm::sin(t), z)
        };
        let mut out = Toolpath::new(at(self.radius, 0.0, h));
        out.name = tp.name.clone();
        for layer in 1..=n {
            let z = layer as f64 * h;
            for j in 0..self.walls {
                let r = self.radius - j as f64 * w;
                if layer > 1 || j > 0 {
                    out.travel(at(r, 0.0, z), self.speed);
                }
                let m = self.segments(r);
                for i in 1..=m {
                    let t = std::f64::consts::TAU * i as f64 / m as f64;
                    out.draw(at(r, if i == m { 0.0 } else { t }, z), c, self.speed);
                }
            }
        }
        out.append(tp, self.speed);
        Ok(out)
    }
}

/// The lowest end of a string of `tp` that comes over the band `lo`..`hi`
/// round `centre` (seen from above): the segment's nearest point to the
/// centre within `hi`, its farthest end beyond `lo`; infinity for none.
fn lowest_over(tp: &Toolpath, centre: glam::DVec2, lo: f64, hi: f64) -> f64 {
    let mut over = f64::INFINITY;
    for k in 0..tp.len() {
        let (a, b) = tp.ends(k);
        let (a2, b2) = (a.truncate() - centre, b.truncate() - centre);
        let d = b2 - a2;
        let t = if d.length_squared() > 0.0 {
            (-a2.dot(d) / d.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let near = (a2 + t * d).length();
        let far = a2.length().max(b2.length());
        if near <= hi && far >= lo {
            over = over.min(a.z.min(b.z));
        }
    }
    over
}

/// A recipe resolved and ready to build.
#[derive(Clone, Debug)]
pub struct Recipe {
    /// Recipe name.
    pub(crate) name: String,
    /// Param values after `--set`.
    pub params: Params,
    /// Printer profile.
    pub printer: Printer,
    /// Material.
    pub(crate) material: Material,
    /// Optional skirt.
    pub(crate) skirt: Option<Skirt>,
    /// Parts in print order.
    pub(crate) parts: Vec<Part>,
    /// Most strings one part may have.
    pub(crate) max_strings: u64,
    /// Check codes the recipe silences (`allow:`).
    pub(crate) allow: Vec<String>,
    /// Steps of groups of parts, in the order they run (see `generate::assembly`).
    pub(crate) groups: Vec<Group>,
    /// A plate's objects, each printed complete before the next (see
    /// `generate::plate`); empty for a recipe, whose every part
    /// is an object of its own.
    pub(crate) objects: Vec<Object>,
}

/// One object of a plate: a whole recipe, printed complete before the next.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Object {
    /// Its name (`pot-2`); its parts are named `pot-2/PART`.
    pub(crate) name: String,
    /// Its paths in the plan, `first..end`: its skirt (when its recipe has
    /// one), then its parts.
    pub(crate) paths: std::ops::Range<usize>,
    /// Its parts in the recipe's `parts`, `first..end`.
    pub(crate) parts: std::ops::Range<usize>,
    /// Check codes its recipe silences (`allow:`), for its own findings.
    pub(crate) allow: Vec<String>,
}

/// Default cross-section when a recipe gives none: Kanada's 0.196 mm² (Fig. 9).
pub(crate) const DEFAULT_CROSS_SECTION: f64 = 0.196;
/// Default speed when a recipe gives none: Kanada's 40 mm/s (Fig. 9).
pub(crate) const DEFAULT_SPEED: f64 = 40.0;

/// A primitive after the first of a part, with its cross-section and speed.
#[derive(Clone, Debug)]
pub(crate) struct Piece {
    /// The primitive.
    pub(crate) primitive: Primitive,
    /// Cross-section of its strings where it sets none, mm².
    pub(crate) cross_section: f64,
    /// Speed of its strings where it sets none, mm/s.
    pub(crate) speed: f64,
}

/// The steps of a group, run on parts `first..end` of the recipe as one set.
#[derive(Clone, Debug)]
pub(crate) struct Group {
    /// First part of the group.
    pub(crate) first: usize,
    /// One past its last part.
    pub(crate) end: usize,
    /// The steps, in order.
    pub(crate) steps: Vec<Step>,
    /// Where the group is written (through templates and loops), for errors.
    pub(crate) place: String,
}

impl Recipe {
    /// Where part `k` is among a plate's paths (after the skirts of its
    /// object and those before it); `None` for a recipe (whose paths are
    /// its skirt, if any, then its parts).
    pub(crate) fn plate_path_of(&self, k: usize) -> Option<usize> {
        self.objects
            .iter()
            .find(|o| o.parts.contains(&k))
            .map(|o| o.paths.end - (o.parts.end - k))
    }

    /// How many strings its parts make, before any is built.
    #[cfg(any(test, feature = "testing"))]
    pub(crate) fn string_count(&self) -> u64 {
        self.parts
            .iter()
            .map(Part::string_count)
            .fold(0, u64::saturating_add)
    }
}

impl Part {
    /// The part's primitives in order: `primitive`, then `more`.
    pub(crate) fn primitives(&self) -> impl Iterator<Item = &Primitive> {
        std::iter::once(&self.primitive).chain(self.more.iter().map(|p| &p.primitive))
    }

    /// How many strings its primitives make, counting a joining travel
    /// between each two.
    pub(crate) fn string_count(&self) -> u64 {
        self.primitives()
            .map(Primitive::string_count)
            .fold(self.more.len() as u64, u64::saturating_add)
    }

    /// Builds the primitives in order, joined by travel strings where one
    /// ends away from the next one's start.
    pub(crate) fn build_primitives(&self) -> Toolpath {
        let mut tp = self.primitive.build(self.cross_section, self.speed);
        for p in &self.more {
            let next = p.primitive.build(p.cross_section, p.speed);
            tp.append(&next, p.speed);
        }
        tp
    }
}

/// Makes a part's strings (without its brim, which
/// [`crate::generate::assembly::make_parts`] adds last): its primitives, then each of its own steps in
/// order (a group's steps are [`crate::generate::assembly::make_parts`]'s).
#[cfg(any(test, feature = "testing"))]
pub fn make_part(recipe: &Recipe, k: usize) -> Result<Toolpath> {
    make_part_within(recipe, k, recipe.max_strings)
}

/// Makes a part as [`make_part`] does, its steps refused past `budget`
/// strings (what the recipe's limits leave after the parts before it).
pub(crate) fn make_part_within(recipe: &Recipe, k: usize, budget: u64) -> Result<Toolpath> {
    let part = &recipe.parts[k];
    let mut tp = part.build_primitives();
    tp.name = part.name.clone();
    for (j, step) in part.steps.iter().enumerate() {
        step.apply(&mut tp, budget)
            .map_err(|e| e.under(&format!("{}.steps[{j}].{}", part.place, step.key())))?;
    }
    Ok(tp)
}

/// The PNG of `--pattern`: the cell array of the recipe's one `ca_helix` part.
pub(crate) fn pattern_png(recipe: &Recipe) -> Result<Vec<u8>> {
    let models: Vec<&CaHelix> = recipe
        .parts
        .iter()
        .flat_map(|p| p.primitives())
        .filter_map(|p| match p {
            Primitive::CaHelix(h) => Some(h),
            _ => None,
        })
        .collect();
    match models.as_slice() {
        [h] => h
            .model
            .run()
            .to_png()
            .map_err(|e| e.under("--pattern")),
        _ => Err(Error::input(
            "--pattern",
            format!(
                "the recipe has {} `ca_helix` parts; --pattern writes the cell array of exactly one",
                models.len()
            ),
        )),
    }
}

#[cfg(test)]
mod brim_tests {
    use super::*;
    use glam::DVec3;

    /// A cone of strings from a point at (0, 0, 0.4) out to radius 10,
    /// rising 0.1 mm per mm outwards: a pole flaring out.
    fn flare() -> Toolpath {
        let mut tp = Toolpath::new(DVec3::new(0.0, 0.0, 0.4));
        tp.name = "pole".into();
        for k in 1..=100 {
            let r = 0.1 * k as f64;
            let t = 0.7 * k as f64;
            tp.draw(
                DVec3::new(r * t.cos(), r * t.sin(), 0.4 + 0.1 * r),
                0.1,
                30.0,
            );
        }
        tp
    }

    fn stand(radius: f64, height: Option<f64>) -> Stand {
        Stand {
            radius,
            walls: 2,
            height,
            line_width: 0.5,
            layer_height: 0.2,
            speed: 20.0,
        }
    }

    #[test]
    fn a_stand_fits_under_the_part_and_prints_first() {
        // walls at 6 and 5.5 (inner edge 5.25), tip radius 0.5: the part
        // comes within reach at r = 4.75, z = 0.875 there; the contact's
        // centre is the middle of the points within 0.2 of the lowest
        let tp = flare();
        let s = stand(6.0, None);
        let (centre, n) = s.layers(&tp, 0.5).unwrap();
        let over = (0..tp.len())
            .flat_map(|k| {
                let (a, b) = tp.ends(k);
                [a, b]
            })
            .filter(|p| p.truncate().distance(centre) >= 4.75 - 0.1)
            .map(|p| p.z)
            .fold(f64::INFINITY, f64::min);
        assert!(over < 0.4 + 0.1 * 4.9, "{over}");
        assert_eq!(n, (over / 0.2).floor() as u32);
        let out = s.under(&tp, 0.5, 1_000_000).unwrap();
        // layers at 0.2, 0.4, …; every drawn stand string at a wall's radius
        let k_part = out.len() - tp.len();
        for k in 0..k_part {
            if out.strings[k].travel {
                continue;
            }
            let (a, b) = out.ends(k);
            let r = b.truncate().distance(centre);
            assert!((r - 6.0).abs() < 1e-9 || (r - 5.5).abs() < 1e-9, "{r}");
            assert!((a.z / 0.2 - (a.z / 0.2).round()).abs() < 1e-9 && a.z <= over + 1e-9);
            assert!((out.strings[k].c - 0.1).abs() < 1e-12);
        }
        // the part follows whole
        assert_eq!(
            out.points[out.points.len() - 1],
            tp.points[tp.points.len() - 1]
        );
        // a stand taller than the room is refused, naming `stand.height`
        let e = stand(6.0, Some(2.0))
            .under(&tp, 0.5, 1_000_000)
            .unwrap_err();
        assert_eq!(e.place.as_deref(), Some("stand.height"), "{e}");
        // one the part leaves room for is built as asked
        let (_, n) = stand(6.0, Some(0.4)).layers(&tp, 0.5).unwrap();
        assert_eq!(n, 2);
        // walls that do not fit in the radius
        let e = stand(0.6, None).layers(&tp, 0.5).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("stand.walls"), "{e}");
        // more strings than the budget
        let e = s.under(&tp, 0.5, 10).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("stand"), "{e}");
    }

    #[test]
    fn a_brim_circles_the_first_contact_outside_in_then_prints_the_part() {
        let mut tp = Toolpath::new(DVec3::new(0.0, 0.0, 0.2));
        tp.name = "pole".into();
        tp.draw(DVec3::new(1.0, 0.0, 0.2), 0.1, 30.0);
        tp.draw(DVec3::new(1.0, 0.0, 5.0), 0.1, 30.0);
        let b = Brim {
            loops: 3,
            line_width: 0.5,
            layer_height: 0.2,
            speed: 20.0,
        };
        let out = b.around(&tp);
        assert_eq!(out.name, "pole");
        // the contact: the first string (within 0.2 of the lowest), centre
        // (0.5, 0), reach 0.5; loops at 0.5 + 0.45 + k·0.5, outermost first
        let centre = glam::DVec2::new(0.5, 0.0);
        let r_of = |p: DVec3| p.truncate().distance(centre);
        assert!((r_of(out.points[0]) - (0.95 + 1.0)).abs() < 1e-12);
        let drawn: Vec<usize> = (0..out.len()).filter(|&k| !out.strings[k].travel).collect();
        let last_brim = drawn[drawn.len() - 3]; // before the part's two strings
        assert!((r_of(out.ends(last_brim).1) - 0.95).abs() < 1e-12);
        for &k in &drawn[..drawn.len() - 2] {
            let (a, c) = (out.ends(k), out.strings[k].c);
            assert!((a.0.z - 0.2).abs() < 1e-12 && (c - 0.1).abs() < 1e-12);
        }
        // the part follows whole
        assert_eq!(out.points[out.points.len() - 1], DVec3::new(1.0, 0.0, 5.0));
        assert!(out.volume() > tp.volume() + 0.1 * std::f64::consts::TAU * 3.0 * 0.95);
    }
}
