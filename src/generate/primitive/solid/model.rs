//! The resolved solid: features, infill settings and the z-buffer of slabs.

use super::*;

/// The solid of one feature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Body {
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
pub(crate) struct Feature {
    /// The body.
    pub(crate) body: Body,
    /// The boolean operation.
    pub(crate) op: Op,
}

impl Feature {
    /// Lowest and highest z.
    pub(crate) fn z_range(&self) -> (f64, f64) {
        match self.body {
            Body::Box { center, size } => (center.z - size.z / 2.0, center.z + size.z / 2.0),
            Body::Cylinder { center, height, .. } => (center.z, center.z + height),
        }
    }

    /// The cross-section in the plane z (`None` outside z0 ≤ z < z1).
    pub(crate) fn section(&self, z: f64) -> Option<Shape> {
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
    pub(super) fn footprint(&self) -> [DVec2; 2] {
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
pub(crate) struct Infill {
    /// Degrees from +x.
    pub(crate) angle: f64,
    /// mm between lines.
    pub(crate) spacing: f64,
    /// +angle on odd layers, −angle on even ones (lines only).
    pub(crate) alternate: bool,
    /// Lines of one direction per layer, or the grid of both.
    pub(crate) pattern: Pattern,
    /// Lines joined end to end along the boundary (zig-zag) where the join
    /// stays inside, instead of a travel per line.
    pub(crate) connect: bool,
}

/// An infill pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pattern {
    /// One direction per layer (alternating with `alternate`).
    Lines,
    /// Both directions, +angle then −angle, in every layer (the paper's ±45° grid).
    Grid,
}

/// What one island of a section becomes.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct IslandPlan {
    /// The island: one outer loop and its holes.
    pub(crate) region: Region,
    /// The perimeters' centre lines, outermost first (exact loops).
    pub(crate) perimeters: Vec<Region>,
    /// The area the infill fills.
    pub(crate) infill_region: Region,
    /// Infill spans at +angle and at −angle.
    pub(crate) infill: [Vec<(DVec2, DVec2)>; 2],
}

/// The strings of one layer in the plane: polylines, each reached by travel.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Program {
    pub(super) paths: Vec<Vec<DVec2>>,
    /// Per path: whether it is infill (else a perimeter loop).
    pub(super) infill: Vec<bool>,
    /// Draws plus the travels between paths.
    pub(super) strings: u64,
}

/// One entry of the z-buffer: a cross-section shared by consecutive layers.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Slab {
    /// The exact cross-section.
    pub(crate) region: Region,
    /// Its islands, perimeters and infill.
    pub(crate) islands: Vec<IslandPlan>,
    pub(super) programs: [Program; 2],
}

/// One layer of a solid, for reports and tests.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layer<'a> {
    /// 1 for the first layer on the bed.
    pub(crate) index: u64,
    /// Height the layer is printed at, mm.
    pub(crate) z: f64,
    /// Its cross-section and what it becomes (`None`: nothing at this height).
    pub(crate) slab: Option<&'a Slab>,
    /// Which infill direction: 0 for +angle, 1 for −angle.
    pub(crate) parity: usize,
}

/// What a solid's slabs are made with, beside its features: a slab is a
/// function of these and of the features holding its plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Settings {
    /// mm.
    pub(crate) layer_height: f64,
    /// Perimeter loops per layer.
    pub(crate) perimeters: u32,
    /// Extrusion width, mm.
    pub(crate) line_width: f64,
    /// Most a chord may stray from an arc, mm.
    pub(crate) chord_tolerance: f64,
    /// Infill settings.
    pub(crate) infill: Infill,
}

/// A `solid` primitive resolved, with its z-buffer computed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Solid {
    /// mm.
    pub(crate) layer_height: f64,
    /// Perimeter loops per layer.
    pub(crate) perimeters: u32,
    /// Extrusion width, mm.
    pub(crate) line_width: f64,
    /// Most a chord may stray from an arc, mm.
    pub(crate) chord_tolerance: f64,
    /// Infill settings.
    pub(crate) infill: Infill,
    /// Features in order.
    pub(crate) features: Vec<Feature>,
    pub(super) slabs: Vec<Arc<Slab>>,
    /// Slab of layer j + 1.
    pub(super) layer_slab: Vec<Option<usize>>,
    pub(super) count: u64,
}
