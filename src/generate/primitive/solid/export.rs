//! The z-buffer's loops as curves: the data of `--zbuffer FILE.json` and the
//! drawing of `--zbuffer-svg FILE.svg`.
//!
//! Each distinct section (slab) is written once, as its loops of lines and
//! arcs exactly as the boolean made them; each layer names its section. A
//! loop runs with the solid on its left: outer loops counter-clockwise
//! (`ccw`, positive area), holes clockwise (`cw`, negative area), so the
//! signed areas of a section's loops add up to its area. An arc carries its
//! centre, radius, start angle and signed sweep (radians, positive
//! counter-clockwise) besides its end points, all as f64 written in the
//! shortest form that reads back to the same bits.

use std::fmt::Write as _;

use super::*;
use piece::Piece;

/// One piece of a loop.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub(crate) enum CurvePiece {
    /// A segment.
    Line {
        /// Start point.
        from: [f64; 2],
        /// End point.
        to: [f64; 2],
    },
    /// A circular arc from `from` to `to`.
    Arc {
        /// Start point.
        from: [f64; 2],
        /// End point.
        to: [f64; 2],
        /// Centre.
        center: [f64; 2],
        /// Radius.
        radius: f64,
        /// Angle of the start point, radians.
        start_rad: f64,
        /// Signed angle turned, radians (positive: counter-clockwise).
        sweep_rad: f64,
    },
}

/// One loop of a section.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct CurveLoop {
    /// `ccw` (an outer loop) or `cw` (a hole).
    pub(crate) orientation: &'static str,
    /// Signed area, mm² (negative for a hole).
    pub(crate) area_mm2: f64,
    /// The pieces in order, each starting where the one before ends.
    pub(crate) pieces: Vec<CurvePiece>,
}

/// One distinct section of the z-buffer.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct CurveSection {
    /// Area, mm².
    pub(crate) area_mm2: f64,
    /// Its loops.
    pub(crate) loops: Vec<CurveLoop>,
}

/// One layer: where it is printed and which section it prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct CurveLayer {
    /// 1 for the first layer on the bed.
    pub(crate) index: u64,
    /// Height the layer is printed at, mm (its section is taken half a layer lower).
    pub(crate) z: f64,
    /// Index into `sections` (`null`: nothing at this height).
    pub(crate) section: Option<usize>,
}

/// A solid part's z-buffer as curves.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub(crate) struct SolidCurves {
    /// Part name.
    pub(crate) part: String,
    /// mm.
    pub(crate) layer_height: f64,
    /// The distinct sections, bottom up.
    pub(crate) sections: Vec<CurveSection>,
    /// Every layer bottom up.
    pub(crate) layers: Vec<CurveLayer>,
}

fn xy(p: DVec2) -> [f64; 2] {
    [p.x, p.y]
}

/// A loop as curves.
pub(crate) fn curve_loop(l: &Loop) -> CurveLoop {
    let area = l.area();
    CurveLoop {
        orientation: if area >= 0.0 { "ccw" } else { "cw" },
        area_mm2: area,
        pieces: l
            .pieces
            .iter()
            .map(|p| match p {
                Piece::Line(a, b) => CurvePiece::Line {
                    from: xy(*a),
                    to: xy(*b),
                },
                Piece::Arc(k) => CurvePiece::Arc {
                    from: xy(k.p0),
                    to: xy(k.p1),
                    center: xy(k.c),
                    radius: k.r,
                    start_rad: k.a0,
                    sweep_rad: k.sweep,
                },
            })
            .collect(),
    }
}

impl Solid {
    /// The z-buffer as curves, under the part name `part`.
    pub(crate) fn curves(&self, part: &str) -> SolidCurves {
        SolidCurves {
            part: part.to_string(),
            layer_height: self.layer_height,
            sections: self
                .slabs
                .iter()
                .map(|s| CurveSection {
                    area_mm2: s.region.area(),
                    loops: s.region.loops.iter().map(curve_loop).collect(),
                })
                .collect(),
            layers: self
                .layer_slab
                .iter()
                .enumerate()
                .map(|(k, s)| CurveLayer {
                    index: k as u64 + 1,
                    z: (k as u64 + 1) as f64 * self.layer_height,
                    section: *s,
                })
                .collect(),
        }
    }
}

/// A number of the SVG drawing: at most 3 decimals (a micrometre), no
/// trailing zeros, `0` for a negative zero (`12.300000000000001` → `12.3`).
fn n(v: f64) -> String {
    crate::base::format::fmt_num(v)
}

/// SVG path data of a loop (y up as in the recipe; the drawing flips it).
/// An arc is an SVG elliptical arc with equal radii: large-arc when it
/// turns more than half a circle, sweep-flag 1 when counter-clockwise
/// (the positive direction of angles); a whole circle is two half circles.
fn path_data(l: &Loop, out: &mut String) {
    let Some(first) = l.pieces.first() else {
        return;
    };
    let s = first.start();
    let _ = write!(out, "M{} {}", n(s.x), n(s.y));
    for p in &l.pieces {
        match p {
            Piece::Line(_, b) => {
                let _ = write!(out, "L{} {}", n(b.x), n(b.y));
            }
            Piece::Arc(k) => {
                let sweep = u8::from(k.sweep > 0.0);
                let r = n(k.r);
                if k.is_full() {
                    let m = k.at(std::f64::consts::PI);
                    let _ = write!(
                        out,
                        "A{r} {r} 0 0 {sweep} {} {}A{r} {r} 0 0 {sweep} {} {}",
                        n(m.x),
                        n(m.y),
                        n(k.p1.x),
                        n(k.p1.y),
                    );
                } else {
                    let large = u8::from(k.sweep.abs() > std::f64::consts::PI);
                    let _ = write!(
                        out,
                        "A{r} {r} 0 {large} {sweep} {} {}",
                        n(k.p1.x),
                        n(k.p1.y),
                    );
                }
            }
        }
    }
    out.push('Z');
}

/// An SVG drawing of layer `index` of each solid (name, solid): the
/// section's exact loops filled (holes even-odd), outer loops drawn in
/// blue and holes in red, the perimeters' centre lines dashed and the
/// infill region's boundary dotted. `None` when no solid has that layer;
/// an error when a solid's name holds a character XML does not allow.
pub(crate) fn layer_svg(solids: &[(&str, &Solid)], index: u64) -> Result<Option<String>> {
    let mut drawing = LayerDrawing {
        lo: DVec2::splat(f64::INFINITY),
        hi: DVec2::splat(f64::NEG_INFINITY),
        body: String::new(),
    };
    let mut any = false;
    for (name, s) in solids {
        let Some(layer) = s.layers().find(|l| l.index == index) else {
            continue;
        };
        any = true;
        drawing.solid(name, &layer)?;
    }
    if !any {
        return Ok(None);
    }
    Ok(Some(drawing.svg()))
}

/// The drawing of one layer so far: the body of its SVG and the bounding
/// box (`lo`, `hi`) of the sections drawn in it.
struct LayerDrawing {
    lo: DVec2,
    hi: DVec2,
    body: String,
}

impl LayerDrawing {
    /// One solid's group: a title naming the solid, the layer and its
    /// height, then its section when the layer has one.
    fn solid(&mut self, name: &str, layer: &Layer) -> Result<()> {
        // the name as base::xml writes any XML text: refused if XML cannot hold it
        let name = crate::base::xml::escape("solid name", name)?;
        let _ = write!(
            self.body,
            "<g id=\"{name}\"><title>{name} layer {} at z {} mm</title>",
            layer.index,
            n(layer.z)
        );
        if let Some(slab) = layer.slab {
            self.slab(slab);
        }
        self.body.push_str("</g>");
        Ok(())
    }

    /// A section: its box added to the drawing's, its loops filled (holes
    /// even-odd) and outlined (outer loops blue, holes red), then its
    /// islands' perimeters and infill boundaries.
    fn slab(&mut self, slab: &Slab) {
        for l in &slab.region.loops {
            for p in &l.pieces {
                let [a, b] = p.bbox(0.0);
                self.lo = self.lo.min(a);
                self.hi = self.hi.max(b);
            }
        }
        let mut d = String::new();
        for l in &slab.region.loops {
            path_data(l, &mut d);
        }
        let _ = write!(
            self.body,
            "<path d=\"{d}\" fill=\"#dde6f0\" fill-rule=\"evenodd\" stroke=\"none\"/>"
        );
        for l in &slab.region.loops {
            let mut d = String::new();
            path_data(l, &mut d);
            let colour = if l.area() >= 0.0 {
                "#1f5fa8"
            } else {
                "#b3261e"
            };
            let _ = write!(
                self.body,
                "<path d=\"{d}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"0.08\"/>"
            );
        }
        for isl in &slab.islands {
            self.island(isl);
        }
    }

    /// An island's perimeters' centre lines (dashed) and its infill
    /// region's boundary (dotted).
    fn island(&mut self, isl: &IslandPlan) {
        for r in &isl.perimeters {
            for l in &r.loops {
                let mut d = String::new();
                path_data(l, &mut d);
                let _ = write!(self.body, "<path d=\"{d}\" fill=\"none\" stroke=\"#555\" stroke-width=\"0.04\" stroke-dasharray=\"0.3 0.2\"/>");
            }
        }
        for l in &isl.infill_region.loops {
            let mut d = String::new();
            path_data(l, &mut d);
            let _ = write!(self.body, "<path d=\"{d}\" fill=\"none\" stroke=\"#888\" stroke-width=\"0.03\" stroke-dasharray=\"0.05 0.15\"/>");
        }
    }

    /// The SVG document in mm: the box (the unit square when nothing was
    /// drawn) grown on each side by m = 0.05 · max(larger side, 1 mm), with
    /// y up: the body flipped about y = (lo.y + hi.y) / 2.
    fn svg(self) -> String {
        let (mut lo, mut hi) = (self.lo, self.hi);
        if lo.x > hi.x {
            lo = DVec2::ZERO;
            hi = DVec2::splat(1.0);
        }
        let m = 0.05 * (hi - lo).max_element().max(1.0);
        let (lo, hi) = (lo - DVec2::splat(m), hi + DVec2::splat(m));
        let size = hi - lo;
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"{} {} {} {}\" width=\"{}mm\" height=\"{}mm\">\n<g transform=\"matrix(1 0 0 -1 0 {})\">{}</g>\n</svg>\n",
            n(lo.x),
            n(lo.y),
            n(size.x),
            n(size.y),
            n(size.x),
            n(size.y),
            n(lo.y + hi.y),
            self.body
        )
    }
}
