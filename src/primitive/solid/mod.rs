//! `solid`: a part modelled from features, printed from a z-buffer of loops.
//!
//! After the feature-based modelling paper (003 in `../shared/papers`): the
//! part is rectangular prisms (`box`) and vertical cylinders combined by
//! union, subtract and intersect, and the printer path comes straight from the
//! features' exact curves, with no STL and no slicing of triangles.
//!
//! 1. **z-buffer of loops.** Layer j (j = 1, 2, …) is printed at z = j·h and
//!    stands for the solid between (j − 1)·h and j·h; its cross-section is
//!    taken at the middle, (j − ½)·h. A feature holds a plane z when
//!    z0 ≤ z < z1. The section only changes where a feature starts or ends,
//!    so it is computed once per such *slab* and shared by its layers (the
//!    paper's "z-buffer is modified each time a feature is added"). Each
//!    section is the exact boolean of rectangles and discs
//!    ([`region::boolean`]), kept as loops of segments and circular arcs.
//!    Material below the bed (z < 0) is not printed.
//! 2. **Boundary first** (the paper's criterion). Each island of a section
//!    is printed on its own: its perimeters from the outside in, centre lines
//!    at (k + ½)·w inside the boundary for k = 0 … perimeters − 1 (w the line
//!    width), exact offsets of the section ([`offset::offset`]). Outside in,
//!    because the outer wall is laid against nothing and keeps the part's
//!    size; each inner one is pressed against the wall before it.
//! 3. **Infill** fills what the perimeters leave, the section offset by
//!    perimeters·w (w/2 with no perimeters), with scanlines at +angle on odd
//!    layers and −angle on even ones ([`infill::spans`]), `spacing` apart.
//! 4. Only then do arcs become strings, chords within `chord_tolerance` of
//!    the true curve ([`piece::chords`]).
//!
//! Each perimeter loop starts at its vertex nearest the head; loops, islands
//! and infill lines are taken nearest first, joined by travel moves. A layer
//! ends by rising straight up one layer before travelling to the next start.
//! Every string has the cross-section layer_height × line_width (a
//! rectangular bead) and the part's speed; the part's cross_section is not
//! used. All this is computed when the recipe is resolved, so the number of
//! strings is exact before any is made.

pub mod infill;
pub mod offset;
pub mod piece;
pub mod region;

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::recipe::{Num, Num3};
use crate::toolpath::Toolpath;

pub use region::{Loop, Op, Region, Shape};

/// Most layers a solid may have.
pub const MAX_LAYERS: u64 = 1_000_000;
/// Most scanlines (or chords of one circle) a layer may need.
pub const MAX_LINES: f64 = 1e5;

// ---------------------------------------------------------------- schema

/// `solid:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawSolid {
    /// mm (0.2).
    #[serde(default)]
    pub layer_height: Option<Num>,
    /// Perimeter loops per layer (2).
    #[serde(default)]
    pub perimeters: Option<Num>,
    /// Extrusion width, mm (0.45).
    #[serde(default)]
    pub line_width: Option<Num>,
    /// Most a chord may stray from an arc, mm (0.01).
    #[serde(default)]
    pub chord_tolerance: Option<Num>,
    /// Infill lines.
    #[serde(default)]
    pub infill: Option<RawInfill>,
    /// The features, combined in order.
    pub features: Vec<RawFeature>,
}

/// `infill:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawInfill {
    /// Degrees from +x (45).
    #[serde(default)]
    pub angle: Option<Num>,
    /// mm between lines (line_width: solid).
    #[serde(default)]
    pub spacing: Option<Num>,
    /// +angle and −angle on alternate layers (true).
    #[serde(default)]
    pub alternate: Option<bool>,
}

/// A feature as written: `{box: {…}}` or `{cylinder: {…}}`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum RawFeature {
    /// An axis-aligned rectangular prism.
    Box(RawBox),
    /// A vertical cylinder.
    Cylinder(RawCylinder),
}

/// `box:` keys.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawBox {
    /// Centre of the box.
    pub center: Num3,
    /// Sizes along x, y, z.
    pub size: Num3,
    /// union (default), subtract or intersect.
    #[serde(default)]
    pub op: Option<RawOp>,
}

/// `cylinder:` keys.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RawCylinder {
    /// Centre of the bottom face.
    pub center: Num3,
    /// Radius.
    pub radius: Num,
    /// Height above the centre.
    pub height: Num,
    /// union (default), subtract or intersect.
    #[serde(default)]
    pub op: Option<RawOp>,
}

/// `op:` of a feature.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum RawOp {
    /// Adds material.
    Union,
    /// Removes material.
    Subtract,
    /// Keeps the common part.
    Intersect,
}

// ---------------------------------------------------------------- model

/// The solid of one feature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Body {
    /// An axis-aligned prism: centre and sizes.
    Box {
        /// Centre.
        center: DVec3,
        /// Sizes along x, y, z.
        size: DVec3,
    },
    /// A vertical cylinder standing on `center`.
    Cylinder {
        /// Centre of the bottom face.
        center: DVec3,
        /// Radius.
        radius: f64,
        /// Height.
        height: f64,
    },
}

/// A feature: a body and how it combines with those before it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Feature {
    /// The body.
    pub body: Body,
    /// The boolean operation.
    pub op: Op,
}

impl Feature {
    /// Lowest and highest z.
    pub fn z_range(&self) -> (f64, f64) {
        match self.body {
            Body::Box { center, size } => (center.z - size.z / 2.0, center.z + size.z / 2.0),
            Body::Cylinder { center, height, .. } => (center.z, center.z + height),
        }
    }

    /// The cross-section in the plane z (`None` outside z0 ≤ z < z1).
    pub fn section(&self, z: f64) -> Option<Shape> {
        let (z0, z1) = self.z_range();
        if !(z0 <= z && z < z1) {
            return None;
        }
        Some(match self.body {
            Body::Box { center, size } => {
                let (c, h) = (center.truncate(), size.truncate() / 2.0);
                Shape::Rect {
                    min: c - h,
                    max: c + h,
                }
            }
            Body::Cylinder { center, radius, .. } => Shape::Disc {
                c: center.truncate(),
                r: radius,
            },
        })
    }

    /// Bounding box in plan: lowest and highest corner.
    fn footprint(&self) -> [DVec2; 2] {
        match self.body {
            Body::Box { center, size } => {
                let (c, h) = (center.truncate(), size.truncate() / 2.0);
                [c - h, c + h]
            }
            Body::Cylinder { center, radius, .. } => {
                let c = center.truncate();
                [c - DVec2::splat(radius), c + DVec2::splat(radius)]
            }
        }
    }
}

/// Infill settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Infill {
    /// Degrees from +x.
    pub angle: f64,
    /// mm between lines.
    pub spacing: f64,
    /// +angle on odd layers, −angle on even ones.
    pub alternate: bool,
}

/// What one island of a section becomes.
#[derive(Clone, Debug, PartialEq)]
pub struct IslandPlan {
    /// The island: one outer loop and its holes.
    pub region: Region,
    /// The perimeters' centre lines, outermost first (exact loops).
    pub perimeters: Vec<Region>,
    /// The area the infill fills.
    pub infill_region: Region,
    /// Infill spans at +angle and at −angle.
    pub infill: [Vec<(DVec2, DVec2)>; 2],
}

/// The strings of one layer in the plane: polylines, each reached by travel.
#[derive(Clone, Debug, Default, PartialEq)]
struct Program {
    paths: Vec<Vec<DVec2>>,
    /// Draws plus the travels between paths.
    strings: u64,
}

/// One entry of the z-buffer: a cross-section shared by consecutive layers.
#[derive(Clone, Debug, PartialEq)]
pub struct Slab {
    /// The exact cross-section.
    pub region: Region,
    /// Its islands, perimeters and infill.
    pub islands: Vec<IslandPlan>,
    programs: [Program; 2],
}

/// One layer of a solid, for reports and tests.
#[derive(Clone, Copy, Debug)]
pub struct Layer<'a> {
    /// 1 for the first layer on the bed.
    pub index: u64,
    /// Height the layer is printed at, mm.
    pub z: f64,
    /// Its cross-section and what it becomes (`None`: nothing at this height).
    pub slab: Option<&'a Slab>,
    /// Which infill direction: 0 for +angle, 1 for −angle.
    pub parity: usize,
}

/// A `solid` primitive resolved, with its z-buffer computed.
#[derive(Clone, Debug, PartialEq)]
pub struct Solid {
    /// mm.
    pub layer_height: f64,
    /// Perimeter loops per layer.
    pub perimeters: u32,
    /// Extrusion width, mm.
    pub line_width: f64,
    /// Most a chord may stray from an arc, mm.
    pub chord_tolerance: f64,
    /// Infill settings.
    pub infill: Infill,
    /// Features in order.
    pub features: Vec<Feature>,
    slabs: Vec<Slab>,
    /// Slab of layer j + 1.
    layer_slab: Vec<Option<usize>>,
    count: u64,
}

// ---------------------------------------------------------------- resolve

/// Resolves `solid:`; `num` evaluates a number (or expression) at a key path.
/// Places are relative to the primitive (`solid.features[1].cylinder.radius`).
pub fn resolve(raw: &RawSolid, num: &dyn Fn(&Num, &str) -> Result<f64>) -> Result<Solid> {
    let positive = |n: &Num, place: &str| -> Result<f64> {
        let v = num(n, place)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(Error::input(
                place,
                format!("{v} is not allowed; expected a number > 0"),
            ))
        }
    };
    let opt = |n: &Option<Num>, place: &str, default: f64| match n {
        Some(n) => positive(n, place),
        None => Ok(default),
    };
    let point = |n: &Num3, place: &str| -> Result<DVec3> {
        Ok(DVec3::new(
            num(&n[0], &format!("{place}[0]"))?,
            num(&n[1], &format!("{place}[1]"))?,
            num(&n[2], &format!("{place}[2]"))?,
        ))
    };
    let layer_height = opt(&raw.layer_height, "solid.layer_height", 0.2)?;
    let line_width = opt(&raw.line_width, "solid.line_width", 0.45)?;
    let chord_tolerance = opt(&raw.chord_tolerance, "solid.chord_tolerance", 0.01)?;
    let perimeters = match &raw.perimeters {
        Some(n) => {
            let v = num(n, "solid.perimeters")?;
            if v.fract() != 0.0 || !(0.0..=1000.0).contains(&v) {
                return Err(Error::input(
                    "solid.perimeters",
                    format!("{v} is not allowed; expected a whole number from 0 to 1000"),
                ));
            }
            v as u32
        }
        None => 2,
    };
    let infill = match &raw.infill {
        Some(i) => Infill {
            angle: match &i.angle {
                Some(n) => num(n, "solid.infill.angle")?,
                None => 45.0,
            },
            spacing: opt(&i.spacing, "solid.infill.spacing", line_width)?,
            alternate: i.alternate.unwrap_or(true),
        },
        None => Infill {
            angle: 45.0,
            spacing: line_width,
            alternate: true,
        },
    };
    if raw.features.is_empty() {
        return Err(Error::input(
            "solid.features",
            "expected at least one feature (`box` or `cylinder`)",
        ));
    }
    let mut features = Vec::with_capacity(raw.features.len());
    for (k, f) in raw.features.iter().enumerate() {
        let (key, op) = match f {
            RawFeature::Box(b) => ("box", b.op),
            RawFeature::Cylinder(c) => ("cylinder", c.op),
        };
        let place = format!("solid.features[{k}].{key}");
        let body = match f {
            RawFeature::Box(b) => {
                let size = point(&b.size, &format!("{place}.size"))?;
                for i in 0..3 {
                    if size[i] <= 0.0 {
                        return Err(Error::input(
                            format!("{place}.size[{i}]"),
                            format!("{} is not allowed; expected a number > 0", size[i]),
                        ));
                    }
                }
                Body::Box {
                    center: point(&b.center, &format!("{place}.center"))?,
                    size,
                }
            }
            RawFeature::Cylinder(c) => Body::Cylinder {
                center: point(&c.center, &format!("{place}.center"))?,
                radius: positive(&c.radius, &format!("{place}.radius"))?,
                height: positive(&c.height, &format!("{place}.height"))?,
            },
        };
        let op = match op {
            None | Some(RawOp::Union) => Op::Union,
            Some(RawOp::Subtract) => Op::Subtract,
            Some(RawOp::Intersect) => Op::Intersect,
        };
        if k == 0 && op != Op::Union {
            return Err(Error::input(
                format!("{place}.op"),
                "the first feature must be a union: there is nothing yet to subtract from or intersect with",
            ));
        }
        features.push(Feature { body, op });
    }
    Solid::new(
        layer_height,
        perimeters,
        line_width,
        chord_tolerance,
        infill,
        features,
    )
}

// ---------------------------------------------------------------- plan

impl Solid {
    /// A solid with its z-buffer computed; the error names the key at fault
    /// (relative to the primitive, as [`resolve`] does).
    pub fn new(
        layer_height: f64,
        perimeters: u32,
        line_width: f64,
        chord_tolerance: f64,
        infill: Infill,
        features: Vec<Feature>,
    ) -> Result<Solid> {
        // nothing but a union adds material: the top is the highest union's
        let top = features
            .iter()
            .filter(|f| f.op == Op::Union)
            .map(|f| f.z_range().1)
            .fold(f64::NEG_INFINITY, f64::max);
        // layers whose middle (j − ½)·h lies below the top
        let layers = (libm::ceil(top / layer_height + 0.5) - 1.0).max(0.0);
        if layers > MAX_LAYERS as f64 {
            return Err(Error::input(
                "solid.layer_height",
                format!(
                    "{layer_height} would make {layers} layers up to z = {top}; expected at most {MAX_LAYERS}"
                ),
            ));
        }
        let layers = layers as u64;
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for f in &features {
            let [a, b] = f.footprint();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let diag = (hi - lo).length();
        if diag / infill.spacing > MAX_LINES {
            return Err(Error::input(
                "solid.infill.spacing",
                format!(
                    "{} would need more than {MAX_LINES} infill lines across the part ({diag:.1} mm); expected a larger spacing",
                    infill.spacing
                ),
            ));
        }
        if piece::chords(diag, std::f64::consts::TAU, chord_tolerance) as f64 > MAX_LINES {
            return Err(Error::input(
                "solid.chord_tolerance",
                format!("{chord_tolerance} would cut a circle into more than {MAX_LINES} strings; expected a larger tolerance"),
            ));
        }
        let mut s = Solid {
            layer_height,
            perimeters,
            line_width,
            chord_tolerance,
            infill,
            features,
            slabs: Vec::new(),
            layer_slab: Vec::with_capacity(layers as usize),
            count: 0,
        };
        // slab boundaries: every feature's ends
        let mut events: Vec<f64> = s
            .features
            .iter()
            .flat_map(|f| {
                let (a, b) = f.z_range();
                [a, b]
            })
            .collect();
        events.sort_by(f64::total_cmp);
        events.dedup();
        let mut current: Option<(usize, Option<usize>)> = None; // (event interval, slab)
        for j in 1..=layers {
            let zm = (j as f64 - 0.5) * layer_height;
            let interval = events.partition_point(|&e| e <= zm);
            let slab = match current {
                Some((iv, slab)) if iv == interval => slab,
                _ => {
                    let slab = s.make_slab(zm);
                    current = Some((interval, slab));
                    slab
                }
            };
            s.layer_slab.push(slab);
        }
        s.count = s.count();
        if s.count == 0 {
            return Err(Error::input(
                "solid.features",
                "the features leave nothing to print: every layer's cross-section above the bed is empty or thinner than line_width",
            ));
        }
        Ok(s)
    }

    /// Computes the slab whose middle plane is `zm`; `None` when empty.
    fn make_slab(&mut self, zm: f64) -> Option<usize> {
        let shapes: Vec<(Option<Shape>, Op)> = self
            .features
            .iter()
            .map(|f| (f.section(zm), f.op))
            .collect();
        let region = region::boolean(&shapes);
        if region.is_empty() {
            return None;
        }
        let w = self.line_width;
        let dirs = [
            infill::direction(self.infill.angle),
            infill::direction(-self.infill.angle),
        ];
        let islands: Vec<IslandPlan> = region
            .islands()
            .into_iter()
            .map(|isl| {
                let perimeters = (0..self.perimeters)
                    .map(|k| offset::offset(&isl, (k as f64 + 0.5) * w))
                    .collect();
                let inset = if self.perimeters == 0 {
                    0.5 * w
                } else {
                    self.perimeters as f64 * w
                };
                let infill_region = offset::offset(&isl, inset);
                let min_span = 0.5 * w;
                let plus = infill::spans(&infill_region, dirs[0], self.infill.spacing, min_span);
                let minus = if self.infill.alternate {
                    infill::spans(&infill_region, dirs[1], self.infill.spacing, min_span)
                } else {
                    plus.clone()
                };
                IslandPlan {
                    region: isl,
                    perimeters,
                    infill_region,
                    infill: [plus, minus],
                }
            })
            .collect();
        let (lo, _) = bbox(&region);
        let p0 = self.program(&islands, 0, lo);
        let start1 = p0
            .paths
            .last()
            .and_then(|p| p.last())
            .copied()
            .unwrap_or(lo);
        let p1 = if self.infill.alternate {
            self.program(&islands, 1, start1)
        } else {
            p0.clone()
        };
        self.slabs.push(Slab {
            region,
            islands,
            programs: [p0, p1],
        });
        Some(self.slabs.len() - 1)
    }

    /// Orders a layer's strings from `head`: island by island (nearest
    /// first), perimeters outside in (each level's loops nearest first, each
    /// loop from its vertex nearest the head), then the infill spans (nearest
    /// end first).
    fn program(&self, islands: &[IslandPlan], parity: usize, mut head: DVec2) -> Program {
        let w = self.line_width;
        let tol = self.chord_tolerance;
        // per island: the polylines of each perimeter level, and the spans
        let mut todo: Vec<Todo> = islands
            .iter()
            .map(|isl| {
                let levels = isl
                    .perimeters
                    .iter()
                    .map(|r| {
                        r.loops
                            .iter()
                            .filter(|l| l.length() >= w)
                            .map(|l| l.discretise(tol))
                            .collect()
                    })
                    .collect();
                (levels, isl.infill[parity].clone())
            })
            .collect();
        let mut paths: Vec<Vec<DVec2>> = Vec::new();
        let entry = |t: &Todo, h: DVec2| -> f64 {
            let mut best = f64::INFINITY;
            for level in &t.0 {
                for poly in level {
                    for p in poly {
                        best = best.min(p.distance(h));
                    }
                }
                if best.is_finite() {
                    return best;
                }
            }
            for (a, b) in &t.1 {
                best = best.min(a.distance(h)).min(b.distance(h));
            }
            best
        };
        while !todo.is_empty() {
            let k = nearest(todo.iter().map(|t| entry(t, head)));
            let (levels, spans) = todo.remove(k);
            if levels.iter().all(Vec::is_empty) && spans.is_empty() {
                continue;
            }
            for mut level in levels {
                while !level.is_empty() {
                    let k = nearest(level.iter().map(|poly| {
                        poly.iter()
                            .map(|p| p.distance(head))
                            .fold(f64::INFINITY, f64::min)
                    }));
                    let poly = level.remove(k);
                    let n = poly.len() - 1; // distinct points; poly[n] == poly[0]
                    let i = nearest(poly[..n].iter().map(|p| p.distance(head)));
                    let mut path = Vec::with_capacity(n + 1);
                    path.extend_from_slice(&poly[i..n]);
                    path.extend_from_slice(&poly[..=i]);
                    head = path[n];
                    paths.push(path);
                }
            }
            let u = infill::direction(if parity == 0 {
                self.infill.angle
            } else {
                -self.infill.angle
            });
            head = order_spans(spans, u, self.infill.spacing, head, &mut paths);
        }
        let mut strings = 0;
        for (i, p) in paths.iter().enumerate() {
            strings += p.len() as u64 - 1;
            if i > 0 && paths[i - 1].last() != p.first() {
                strings += 1;
            }
        }
        Program { paths, strings }
    }

    /// The number of strings [`Solid::walk`] makes, from each layer's
    /// program without making them: its strings, and between layers one
    /// travel up plus one across when the next layer starts elsewhere.
    fn count(&self) -> u64 {
        let mut n = 0;
        let mut prev: Option<DVec2> = None;
        for layer in self.layers() {
            let Some(slab) = layer.slab else { continue };
            let prog = &slab.programs[layer.parity];
            let (Some(first), Some(last)) = (prog.paths.first(), prog.paths.last()) else {
                continue;
            };
            if let Some(end) = prev {
                n += 1 + u64::from(end != first[0]);
            }
            n += prog.strings;
            prev = Some(last[last.len() - 1]);
        }
        n
    }

    /// Runs through every point of the part in order, calling
    /// `f(point, travel)`; the first call is the start point (its `travel`
    /// meaningless), each later one a string to that point.
    fn walk(&self, mut f: impl FnMut(DVec3, bool)) {
        let mut head: Option<DVec3> = None;
        for layer in self.layers() {
            let Some(slab) = layer.slab else { continue };
            let prog = &slab.programs[layer.parity];
            for (i, path) in prog.paths.iter().enumerate() {
                let start = path[0].extend(layer.z);
                match head {
                    None => f(start, true),
                    Some(h) => {
                        if i == 0 && h.z != layer.z {
                            // up first, then across
                            let up = DVec3::new(h.x, h.y, layer.z);
                            f(up, true);
                            if up != start {
                                f(start, true);
                            }
                        } else if h != start {
                            f(start, true);
                        }
                    }
                }
                for p in &path[1..] {
                    f(p.extend(layer.z), false);
                }
                head = Some(path[path.len() - 1].extend(layer.z));
            }
        }
    }

    /// The layers bottom up, each with its slab of the z-buffer.
    pub fn layers(&self) -> impl Iterator<Item = Layer<'_>> + '_ {
        self.layer_slab.iter().enumerate().map(|(k, s)| {
            let index = k as u64 + 1;
            Layer {
                index,
                z: index as f64 * self.layer_height,
                slab: s.map(|s| &self.slabs[s]),
                parity: if self.infill.alternate && index.is_multiple_of(2) {
                    1
                } else {
                    0
                },
            }
        })
    }

    /// The z-buffer: the distinct cross-sections.
    pub fn slabs(&self) -> &[Slab] {
        &self.slabs
    }

    /// Exactly how many strings [`Solid::build`] makes.
    pub fn string_count(&self) -> u64 {
        self.count
    }

    /// Makes the strings: cross-section layer_height × line_width, speed `v`
    /// (the part's cross-section `_c` is not used: a solid's beads are as
    /// high as its layers and as wide as its lines).
    pub fn build(&self, _c: f64, v: f64) -> Toolpath {
        let c = self.layer_height * self.line_width;
        let mut t: Option<Toolpath> = None;
        self.walk(|p, travel| match &mut t {
            None => t = Some(Toolpath::with_capacity(p, self.count as usize)),
            Some(t) if travel => t.travel(p, v),
            Some(t) => t.draw(p, c, v),
        });
        t.unwrap_or_default()
    }
}

/// An island still to print: its perimeter levels' closed polylines, its infill spans.
type Todo = (Vec<Vec<Vec<DVec2>>>, Vec<(DVec2, DVec2)>);

/// Appends the infill `spans` (lines along `u`, `spacing` apart) to `paths`
/// nearest first from `head`, each from its nearer end; returns the new head.
///
/// The nearest span is found as by trying them all (ties to the earlier
/// span), but spans are bucketed by scanline and buckets are searched
/// outwards from the head's own: a bucket r lines away is at least
/// (r − ½)·spacing from the head (whose own line is within ½ of it), so the
/// search stops once that exceeds the best distance found. Filling a region line after line, that is a bucket
/// or two per span instead of every span.
fn order_spans(
    spans: Vec<(DVec2, DVec2)>,
    u: DVec2,
    spacing: f64,
    mut head: DVec2,
    paths: &mut Vec<Vec<DVec2>>,
) -> DVec2 {
    if spans.is_empty() {
        return head;
    }
    let n = DVec2::new(-u.y, u.x);
    let line = |p: DVec2| libm::round(p.dot(n) / spacing) as i64;
    let k0 = spans.iter().map(|s| line(s.0)).min().unwrap();
    let k1 = spans.iter().map(|s| line(s.0)).max().unwrap();
    let mut buckets: Vec<Vec<usize>> = vec![Vec::new(); (k1 - k0 + 1) as usize];
    for (i, s) in spans.iter().enumerate() {
        buckets[(line(s.0) - k0) as usize].push(i);
    }
    for _ in 0..spans.len() {
        let here = head.dot(n) / spacing - k0 as f64;
        let c = libm::round(here).clamp(0.0, (buckets.len() - 1) as f64) as i64;
        let mut best: Option<(f64, usize, usize)> = None; // (distance, span, bucket)
        let mut r = 0i64;
        loop {
            let (lo, hi) = (c - r, c + r);
            if lo < 0 && hi >= buckets.len() as i64 {
                break;
            }
            let ring: &[i64] = if r == 0 { &[lo] } else { &[lo, hi] };
            for &b in ring {
                if b < 0 || b >= buckets.len() as i64 {
                    continue;
                }
                for &i in &buckets[b as usize] {
                    let (a, e) = spans[i];
                    let d = a.distance(head).min(e.distance(head));
                    if best.is_none_or(|(bd, bi, _)| d < bd || (d == bd && i < bi)) {
                        best = Some((d, i, b as usize));
                    }
                }
            }
            if let Some((bd, _, _)) = best {
                // every bucket further out is farther than this one
                if bd < (r as f64 + 1.0 - (here - c as f64).abs() - 1e-9) * spacing {
                    break;
                }
            }
            r += 1;
        }
        let (_, i, b) = best.expect("a span is left");
        buckets[b].retain(|&j| j != i);
        let (a, e) = spans[i];
        let path = if a.distance(head) <= e.distance(head) {
            vec![a, e]
        } else {
            vec![e, a]
        };
        head = path[1];
        paths.push(path);
    }
    head
}

/// Index of the smallest value (the first of equals).
fn nearest(values: impl Iterator<Item = f64>) -> usize {
    let mut best = (0, f64::INFINITY);
    for (k, v) in values.enumerate() {
        if v < best.1 {
            best = (k, v);
        }
    }
    best.0
}

/// Corners of a region's bounding box (of its pieces' end points and circles).
fn bbox(r: &Region) -> (DVec2, DVec2) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for l in &r.loops {
        for p in &l.pieces {
            let [a, b] = p.bbox(0.0);
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    (lo, hi)
}

// ---------------------------------------------------------------- stats

/// One layer of the z-buffer in the stats.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LayerStats {
    /// Height the layer is printed at, mm.
    pub z: f64,
    /// Loops of its cross-section (outer loops and holes).
    pub loops: usize,
    /// Area of its cross-section, mm².
    pub area_mm2: f64,
}

/// The z-buffer of one solid part in the stats.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SolidStats {
    /// Part name.
    pub part: String,
    /// Its layers bottom up.
    pub layers: Vec<LayerStats>,
}

/// The z-buffers of a recipe's solid parts (before any steps).
pub fn stats(recipe: &crate::recipe::Recipe) -> Vec<SolidStats> {
    recipe
        .parts
        .iter()
        .flat_map(|p| p.primitives().map(move |q| (p, q)))
        .filter_map(|(p, q)| match q {
            super::Primitive::Solid(s) => Some(SolidStats {
                part: p.name.clone(),
                layers: s
                    .layers()
                    .map(|l| LayerStats {
                        z: l.z,
                        loops: l.slab.map_or(0, |s| s.region.loops.len()),
                        area_mm2: l.slab.map_or(0.0, |s| s.region.area()),
                    })
                    .collect(),
            }),
            _ => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn plate_with_hole(perimeters: u32, spacing: f64) -> Solid {
        Solid::new(
            0.2,
            perimeters,
            0.45,
            0.01,
            Infill {
                angle: 45.0,
                spacing,
                alternate: true,
            },
            vec![
                Feature {
                    body: Body::Box {
                        center: DVec3::new(0.0, 0.0, 0.5),
                        size: DVec3::new(20.0, 10.0, 1.0),
                    },
                    op: Op::Union,
                },
                Feature {
                    body: Body::Cylinder {
                        center: DVec3::new(0.0, 0.0, -1.0),
                        radius: 3.0,
                        height: 3.0,
                    },
                    op: Op::Subtract,
                },
            ],
        )
        .unwrap()
    }

    #[test]
    fn layers_share_one_slab_and_count_exactly() {
        let s = plate_with_hole(2, 0.8);
        assert_eq!(s.layers().count(), 5);
        assert_eq!(s.slabs().len(), 1);
        let area = s.slabs()[0].region.area();
        assert!((area - (200.0 - 9.0 * PI)).abs() < 1e-9);
        let t = s.build(0.0, 30.0);
        assert_eq!(t.len() as u64, s.string_count());
        let zs: Vec<f64> = t.points.iter().map(|p| p.z).collect();
        assert!((zs[0] - 0.2).abs() < 1e-12);
        assert!((zs.last().unwrap() - 1.0).abs() < 1e-12);
        assert!(zs.windows(2).all(|w| w[1] >= w[0]), "bottom up");
        for k in 0..t.len() {
            if !t.strings[k].travel {
                assert!((t.strings[k].c - 0.09).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn rises_before_travelling_to_the_next_layer() {
        let s = plate_with_hole(1, 0.8);
        let t = s.build(0.0, 30.0);
        for k in 0..t.len() {
            let (a, b) = t.ends(k);
            if b.z != a.z {
                assert!(t.strings[k].travel);
                assert_eq!(a.truncate(), b.truncate(), "straight up");
            }
        }
    }

    #[test]
    fn bucketed_span_order_is_the_nearest_first_order() {
        // spans of a region with holes, ordered both ways from the same head
        let s = plate_with_hole(1, 0.45);
        let isl = &s.slabs()[0].islands[0];
        for (parity, deg) in [(0, 45.0), (1, -45.0)] {
            for head in [DVec2::new(-30.0, 7.0), DVec2::ZERO, DVec2::new(9.0, -4.9)] {
                let spans = isl.infill[parity].clone();
                assert!(spans.len() > 30);
                let mut fast = Vec::new();
                order_spans(spans.clone(), infill::direction(deg), 0.45, head, &mut fast);
                let (mut slow, mut rest, mut h) = (Vec::new(), spans, head);
                while !rest.is_empty() {
                    let k = nearest(rest.iter().map(|(a, b)| a.distance(h).min(b.distance(h))));
                    let (a, b) = rest.remove(k);
                    let path = if a.distance(h) <= b.distance(h) {
                        vec![a, b]
                    } else {
                        vec![b, a]
                    };
                    h = path[1];
                    slow.push(path);
                }
                assert_eq!(fast, slow);
            }
        }
    }

    #[test]
    fn empty_results_are_refused() {
        let e = Solid::new(
            0.2,
            2,
            0.45,
            0.01,
            Infill {
                angle: 45.0,
                spacing: 0.45,
                alternate: true,
            },
            vec![Feature {
                body: Body::Box {
                    center: DVec3::new(0.0, 0.0, -5.0),
                    size: DVec3::new(10.0, 10.0, 2.0),
                },
                op: Op::Union,
            }],
        )
        .unwrap_err();
        assert_eq!(e.place.as_deref(), Some("solid.features"));
    }
}
