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
//!    Material below the bed (z < 0) is not printed. The buffer is a
//!    [`ZBuffer`], updated feature by feature (see its module).
//! 2. **Boundary first** (the paper's criterion). Each island of a section
//!    is printed on its own: its perimeters from the outside in, centre lines
//!    at (k + ½)·w inside the boundary for k = 0 … perimeters − 1 (w the line
//!    width), exact offsets of the section ([`offset::offset`]). Outside in,
//!    because the outer wall is laid against nothing and keeps the part's
//!    size; each inner one is pressed against the wall before it.
//! 3. **Infill** fills what the perimeters leave, the section offset by
//!    perimeters·w (w/2 with no perimeters), with scanlines at +angle on odd
//!    layers and −angle on even ones ([`infill::spans`]), `spacing` apart;
//!    with `pattern: grid`, both directions in every layer (+angle first);
//!    with `connect`, each line joined to the next along the boundary where
//!    the join stays inside (`plan::connect`).
//! 4. Only then do arcs become strings, chords within `chord_tolerance` of
//!    the true curve ([`piece::chords`]).
//!
//! Each perimeter loop starts at its vertex nearest the head; loops, islands
//! and infill lines are taken nearest first, joined by travel moves. A layer
//! ends by rising straight up one layer before travelling to the next start.
//! Perimeter strings have the cross-section layer_height × line_width (a
//! rectangular bead), infill strings layer_height × min(spacing, line_width)
//! (lines closer than their width are squeezed to their spacing, so a solid
//! layer's filament is its area × height), all at the part's speed. A part's
//! cross_section other than layer_height × line_width is refused when the
//! recipe is resolved (it would be ignored). All this is computed when the recipe is resolved, so the number of
//! strings is exact before any is made.

pub(crate) mod infill;
pub(crate) use crate::base::geom::{offset, piece, region};

use std::sync::Arc;

use glam::{DVec2, DVec3};
use serde::Serialize;

use crate::base::error::{Error, Result};
use crate::base::toolpath::Toolpath;

pub(crate) use region::{Loop, Op, Region, Shape};

/// Most layers a solid may have.
pub(crate) const MAX_LAYERS: u64 = 1_000_000;
/// Most scanlines (or chords of one circle) a layer may need.
pub(crate) const MAX_LINES: f64 = 1e5;

mod export;
mod model;
pub(crate) mod plan;
mod stats;
mod zbuffer;

pub(crate) use export::*;
pub(crate) use model::*;
pub(crate) use stats::*;
pub(crate) use zbuffer::{Cache, Reuse, Reusing, ZBuffer};

#[cfg(test)]
mod tests {
    use super::plan::{nearest, order_spans};
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
                pattern: Pattern::Lines,
                connect: false,
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
            None,
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
                pattern: Pattern::Lines,
                connect: false,
            },
            vec![Feature {
                body: Body::Box {
                    center: DVec3::new(0.0, 0.0, -5.0),
                    size: DVec3::new(10.0, 10.0, 2.0),
                },
                op: Op::Union,
            }],
            None,
        )
        .unwrap_err();
        assert_eq!(e.place.as_deref(), Some("solid.features"));
    }
}
