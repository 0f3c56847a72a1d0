//! Inward offsets of regions bounded by segments and arcs, exactly.
//!
//! The region eroded by d is the set of points of R at least d from its
//! boundary. Its boundary is made of (1) each boundary piece moved d to its
//! left, into R: a segment stays a parallel segment, an arc keeps its centre
//! with radius r − d (R inside the circle, counter-clockwise) or r + d (a
//! hole's arc, clockwise); and (2) at each reflex corner (the boundary turns
//! right, so R wraps around the corner), an arc of radius d centred on the
//! corner joining the two moved pieces. Convex corners need nothing: the
//! moved pieces cross there and the overhanging ends are cut away below.
//!
//! Those candidates are trimmed by the overlay of [`super::region`]: split at
//! their mutual intersections, and a split piece is kept when its midpoint is
//! no closer than d to the whole boundary of R (an overhanging end, a piece
//! pushed across a thin wall or a loop that has collapsed is closer, and
//! goes). Where the nearest-distance status changes along a candidate, it
//! crosses another candidate, so the midpoint speaks for the whole piece.
//! Offsetting R directly by each distance, rather than offsetting offsets,
//! adds no error per perimeter.

use super::piece::{cross, perp, Arc, Piece};
use super::region::{overlay, Keep, Region};

/// `region` eroded by `d` ≥ 0 (see the module comment); empty when nothing
/// of it is at least `d` from its boundary.
pub(crate) fn offset(region: &Region, d: f64) -> Region {
    if d <= 0.0 || region.is_empty() {
        return region.clone();
    }
    let eps = region.eps();
    let mut cands = Vec::new();
    for l in &region.loops {
        let n = l.pieces.len();
        for (i, p) in l.pieces.iter().enumerate() {
            let s = p.start() + perp(p.tangent_start()) * d;
            let e = p.end() + perp(p.tangent_end()) * d;
            match p {
                Piece::Line(..) => cands.push(Piece::Line(s, e)),
                Piece::Arc(k) => {
                    let r = k.r - k.dir() * d;
                    if r > eps {
                        cands.push(Piece::Arc(Arc {
                            r,
                            p0: s,
                            p1: e,
                            ..*k
                        }));
                    }
                }
            }
            if p.is_full() {
                continue;
            }
            let q = &l.pieces[(i + 1) % n];
            let (t1, t2) = (p.tangent_end(), q.tangent_start());
            let turn = cross(t1, t2);
            // A U-turn (the two pieces leave the corner the same way) is the
            // tip of a zero-width notch when the next piece curves left of
            // the reversed one (R wraps all round the tip: reflex), or of a
            // zero-width horn when it curves right (R is the sliver between
            // them: nothing to add).
            let notch =
                turn.abs() <= 1e-12 && t1.dot(t2) < 0.0 && q.curvature() + p.curvature() > 0.0;
            if turn < -1e-12 || notch {
                // reflex corner: an arc of radius d round it, clockwise (R
                // lies outside it), from one moved piece to the next
                let (n1, n2) = (perp(t1), perp(t2));
                let v = p.end();
                cands.push(Piece::Arc(Arc {
                    c: v,
                    r: d,
                    a0: libm::atan2(n1.y, n1.x),
                    sweep: if notch {
                        -std::f64::consts::PI
                    } else {
                        libm::atan2(cross(n1, n2), n1.dot(n2))
                    },
                    p0: e,
                    p1: v + n2 * d,
                }));
            }
        }
    }
    let bounds: Vec<Piece> = region
        .loops
        .iter()
        .flat_map(|l| l.pieces.iter().copied())
        .collect();
    overlay(&cands, eps, |sub| {
        let m = sub.midpoint();
        if bounds.iter().all(|b| b.distance(m) >= d - eps) {
            Keep::Forward
        } else {
            Keep::Drop
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::geom::region::{boolean, Op, Shape};
    use glam::DVec2;
    use std::f64::consts::PI;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Option<Shape> {
        Some(Shape::Rect {
            min: DVec2::new(x0, y0),
            max: DVec2::new(x1, y1),
        })
    }

    fn disc(x: f64, y: f64, r: f64) -> Option<Shape> {
        Some(Shape::Disc {
            c: DVec2::new(x, y),
            r,
        })
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-10 * b.abs().max(1.0)
    }

    #[test]
    fn box_with_hole_offsets_exactly() {
        let r = boolean(&[
            (rect(-20.0, -15.0, 20.0, 15.0), Op::Union),
            (disc(0.0, 0.0, 8.0), Op::Subtract),
        ]);
        let o = offset(&r, 1.0);
        assert_eq!(o.loops.len(), 2);
        assert!(close(o.area(), 38.0 * 28.0 - PI * 81.0), "{}", o.area());
    }

    #[test]
    fn reflex_corner_is_rounded() {
        // an L: 2x2 square minus its top-right 1x1 quarter
        let r = boolean(&[
            (rect(0.0, 0.0, 2.0, 2.0), Op::Union),
            (rect(1.0, 1.0, 2.0, 2.0), Op::Subtract),
        ]);
        let d = 0.25;
        let o = offset(&r, d);
        assert_eq!(o.loops.len(), 1);
        // two 1.5 x 0.5 arms share a 0.5 x 0.5 corner, plus the rounded
        // reflex corner: a d x d square minus a quarter disc of radius d
        let want = 1.5 * 0.5 * 2.0 - 0.25 + (d * d - PI * d * d / 4.0);
        assert!(close(o.area(), want), "{} vs {want}", o.area());
        let arcs = o.loops[0]
            .pieces
            .iter()
            .filter(|p| matches!(p, Piece::Arc(_)))
            .count();
        assert_eq!(arcs, 1);
    }

    #[test]
    fn thin_parts_split_and_small_loops_vanish() {
        // a dumbbell: two 4x4 squares joined by a 1-wide bar
        let r = boolean(&[
            (rect(0.0, 0.0, 4.0, 4.0), Op::Union),
            (rect(4.0, 1.5, 8.0, 2.5), Op::Union),
            (rect(8.0, 0.0, 12.0, 4.0), Op::Union),
        ]);
        assert_eq!(r.loops.len(), 1);
        let o = offset(&r, 0.6);
        assert_eq!(o.islands().len(), 2);
        // each square shrinks to 2.8 x 2.8 and bulges towards the bar between
        // the arcs of radius 0.6 round the bar's reflex corners, 1 apart:
        // 2·∫₀^½ (0.6 − √(0.36 − t²)) dt
        let quarter = 0.5 * (0.5 * 0.11f64.sqrt() + 0.36 * libm::asin(0.5 / 0.6));
        let bulge = 2.0 * (0.3 - quarter);
        assert!(close(o.area(), 2.0 * (2.8 * 2.8 + bulge)), "{}", o.area());
        // gone entirely
        assert!(offset(&r, 2.5).is_empty());
        // a disc shrinks to a disc
        let c = boolean(&[(disc(1.0, 1.0, 3.0), Op::Union)]);
        assert!(close(offset(&c, 1.0).area(), PI * 4.0));
        assert!(offset(&c, 3.0).is_empty());
    }

    #[test]
    fn the_tip_of_a_zero_width_notch_is_rounded() {
        // a box edge tangent to a disc: the disc added after a box cut away
        // the half plane beside it leaves a cusp-shaped notch between the
        // edge x = 0.5 and the circle, its tip at (0.5, 3); the boundary
        // turns back on itself there, and the offset goes round the tip
        let r = boolean(&[
            (disc(1.0, 4.0, 2.0), Op::Union),
            (rect(-7.5, 3.0, 0.5, 11.0), Op::Subtract),
            (disc(-3.5, 3.0, 4.0), Op::Union),
        ]);
        assert_eq!(r.loops.len(), 1);
        let o = offset(&r, 0.2);
        assert_eq!(o.loops.len(), 1);
        let tip = DVec2::new(0.5, 3.0);
        // the half circle round the tip is on the boundary, 0.2 below it
        let below = tip - DVec2::new(0.0, 0.2);
        let d = o.loops[0]
            .pieces
            .iter()
            .map(|p| p.distance(below))
            .fold(f64::INFINITY, f64::min);
        assert!(d < 1e-9, "{d}");
        assert!(o.contains(tip - DVec2::new(0.0, 0.3)));
        assert!(!o.contains(tip - DVec2::new(0.0, 0.1)));
    }

    #[test]
    fn hole_near_the_edge_merges_with_it() {
        // the wall between hole and edge is 0.5 thick: eroded by 0.6 the
        // hole breaks through the edge, by 0.2 it stays a hole
        let r = boolean(&[
            (rect(0.0, 0.0, 10.0, 10.0), Op::Union),
            (disc(5.0, 7.5, 2.0), Op::Subtract),
        ]);
        let o = offset(&r, 0.6);
        assert_eq!(o.loops.len(), 1, "{:?}", o.loops.len());
        // the grown hole (radius 2.6) sticks out 0.7 above the lowered edge
        // y = 9.4: the square less the disc plus that circular segment
        let (rr, h) = (2.6f64, 0.7);
        let segment =
            rr * rr * libm::acos((rr - h) / rr) - (rr - h) * (2.0 * rr * h - h * h).sqrt();
        assert!(
            close(o.area(), 8.8 * 8.8 - PI * rr * rr + segment),
            "{}",
            o.area()
        );
        let o = offset(&r, 0.2);
        assert_eq!(o.loops.len(), 2);
        assert!(close(o.area(), 9.6 * 9.6 - PI * 2.2 * 2.2));
    }
}
