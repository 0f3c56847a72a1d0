//! SVG drawings as 2D polylines in mm: the `svg:` source of `path` and of
//! the `outline:` of `helix`, `spiral` and `cylinder`.
//!
//! The file is read bounded ([`MAX_SVG_BYTES`]), parsed once by roxmltree
//! with no DTD and a node limit, and checked by a pass over the XML that
//! counts what usvg's `<use>` expansion would make ([`MAX_EXPANDED`]) and how
//! deep elements nest ([`MAX_DEPTH`]) before usvg expands anything. usvg then
//! resolves shapes, units, transforms and `<use>` into paths of lines,
//! quadratic and cubic Béziers, which are flattened here to a chord tolerance.
//!
//! Units: usvg gives user units of the root's viewport in CSS px (96 per
//! inch, the root's `viewBox` already mapped onto its `width`/`height`), so
//! 1 px = 25.4/96 mm. A root with `width="100mm"` and `viewBox="0 0 100 100"`
//! thus gives 1 mm per user unit. SVG's y axis points down; it is flipped so
//! that the print seen from above looks like the drawing.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec2;

use crate::base::error::{Error, Result};

/// Largest SVG file read, bytes.
pub(crate) const MAX_SVG_BYTES: u64 = 4 << 20;

/// Most XML nodes parsed from one SVG file.
pub(crate) const MAX_NODES: u32 = 200_000;

/// Most elements a drawing may have once every `<use>` is expanded.
pub(crate) const MAX_EXPANDED: u64 = 100_000;

/// Deepest nesting of elements (counting each `<use>` as one more level).
pub(crate) const MAX_DEPTH: usize = 256;

/// Millimetres per CSS px (user unit of the root viewport).
pub(crate) const MM_PER_PX: f64 = 25.4 / 96.0;

/// Farthest a drawing's point may lie from its origin, mm.
pub(crate) const MAX_MM: f64 = 1e6;

/// The default chord tolerance of flattened curves, mm.
pub(crate) const DEFAULT_TOLERANCE: f64 = 0.01;

/// One subpath of a drawing: mm, y up, scaled.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Subpath {
    /// The flattened points, in drawing order (a closed one does not repeat
    /// its first point at the end).
    pub(crate) points: Vec<DVec2>,
    /// Ends with `Z` (or comes back to its first point).
    pub(crate) closed: bool,
    /// The id of the SVG element it came from ("" when it has none).
    pub(crate) element: String,
}

/// What to take from a drawing and how.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Options<'a> {
    /// Only the element with this id (and what it contains).
    pub(crate) id: Option<&'a str>,
    /// Factor on the drawn size.
    pub(crate) scale: f64,
    /// Largest distance of a flattened chord from its curve, mm (after `scale`).
    pub(crate) tolerance: f64,
    /// Most points all subpaths together may have.
    pub(crate) max_points: u64,
}

/// Reads and flattens the SVG file at `path`; errors name the file as
/// `shown` and, where there is one, the element and its line. The file is
/// noted in `reads` for `p3dp watch`.
pub(crate) fn load(
    path: &Path,
    shown: &str,
    opt: &Options,
    reads: &crate::base::input::Reads,
) -> Result<Vec<Subpath>> {
    let io = |e: &std::io::Error| Error {
        io_kind: Some(e.kind()),
        ..Error::input("", format!("cannot read the SVG file `{shown}`: {e}"))
    };
    reads.reach(path, "SVG file")?;
    std::fs::metadata(path).map_err(|e| io(&e))?;
    // a regular file only (never a FIFO or device)
    let file = crate::base::input::open_regular(path, "SVG file")?;
    let bytes = crate::base::input::read_bounded(file, MAX_SVG_BYTES).map_err(|e| io(&e))?;
    let Some(bytes) = bytes else {
        return Err(Error::input(
            "",
            format!(
                "the SVG file `{shown}` is larger than {} MB; expected a smaller file",
                MAX_SVG_BYTES >> 20
            ),
        ));
    };
    let text = String::from_utf8(bytes).map_err(|e| {
        Error::input(
            "",
            format!(
                "the SVG file `{shown}` is not UTF-8 text (byte {}); expected an SVG file",
                e.utf8_error().valid_up_to()
            ),
        )
    })?;
    parse(&text, opt).map_err(|m| Error::input("", format!("the SVG file `{shown}`: {m}")))
}

/// Parses and flattens SVG text; the error is a sentence naming the element.
pub(crate) fn parse(text: &str, opt: &Options) -> std::result::Result<Vec<Subpath>, String> {
    let doc = roxmltree::Document::parse_with_options(
        text,
        roxmltree::ParsingOptions {
            allow_dtd: false,
            nodes_limit: MAX_NODES,
            ..Default::default()
        },
    )
    .map_err(|e| {
        format!(
            "cannot read it as XML: {e}; expected an SVG file (no DTD, at most {MAX_NODES} nodes)"
        )
    })?;
    check_xml(&doc, opt)?;
    // paint servers and effects out of usvg's way (see `plain_paint`)
    let plain;
    let doc = match plain_paint(text, &doc) {
        Some(t) => {
            plain = t;
            roxmltree::Document::parse_with_options(
                &plain,
                roxmltree::ParsingOptions {
                    allow_dtd: false,
                    nodes_limit: MAX_NODES,
                    ..Default::default()
                },
            )
            .map_err(|e| format!("cannot read it as XML once its paint is made plain: {e}"))?
        }
        None => doc,
    };
    let uopt = usvg::Options {
        // never read a file or decode a picture an `<image>` names
        image_href_resolver: usvg::ImageHrefResolver {
            resolve_data: Box::new(|_, _, _| None),
            resolve_string: Box::new(|_, _| None),
        },
        ..Default::default()
    };
    let tree = usvg::Tree::from_xmltree(&doc, &uopt)
        .map_err(|e| format!("cannot read it as SVG: {e}; expected an SVG file"))?;
    let out = flatten(&tree, opt)?;
    drawn(out, opt)
}

/// The text of a drawing whose paint servers and effects usvg never sees,
/// or `None` when it names none: p3dp takes only the geometry, and usvg
/// panics on some degenerate ones (a `<pattern>` 1e-9 wide: its tile is
/// placed in f32, where the width vanishes against its position, and
/// tiny-skia's `NonZeroRect` unwraps a `None`). Every `url(…)` of a `fill`
/// or `stroke` (attribute, `style` or style sheet) becomes `black`, of a
/// `clip-path`, `mask`, `filter` or marker `none`; the shapes stay as
/// drawn, and `<pattern>`s and gradients are left unused.
fn plain_paint(text: &str, doc: &roxmltree::Document) -> Option<String> {
    let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
    for n in doc.descendants() {
        if n.is_element() {
            for a in n.attributes() {
                if !has_url(a.value()) {
                    continue;
                }
                let plain = match a.name() {
                    "style" => xml_escape(&css_plain(a.value())),
                    "fill" | "stroke" => "black".to_string(),
                    "clip-path" | "mask" | "filter" | "marker-start" | "marker-mid"
                    | "marker-end" => "none".to_string(),
                    _ => continue,
                };
                edits.push((a.range_value(), plain));
            }
        } else if n.is_text() && n.parent().is_some_and(|p| p.tag_name().name() == "style") {
            let t = n.text().unwrap_or("");
            if has_url(t) {
                edits.push((n.range(), xml_escape(&css_plain(t))));
            }
        }
    }
    if edits.is_empty() {
        return None;
    }
    edits.sort_by_key(|(r, _)| r.start);
    let mut out = String::with_capacity(text.len());
    let mut at = 0;
    for (r, plain) in edits {
        if r.start < at || r.end > text.len() {
            continue; // overlapping ranges cannot occur; kept safe anyway
        }
        out.push_str(&text[at..r.start]);
        out.push_str(&plain);
        at = r.end;
    }
    out.push_str(&text[at..]);
    Some(out)
}

/// Whether CSS or attribute text holds a `url(` (in any case).
fn has_url(s: &str) -> bool {
    s.to_ascii_lowercase().contains("url(")
}

/// CSS with each `url(…)` replaced: `black` where the property it is the
/// value of ends in `fill` or `stroke`, `none` elsewhere.
fn css_plain(css: &str) -> String {
    let lower = css.to_ascii_lowercase();
    let mut out = String::with_capacity(css.len());
    let mut at = 0;
    while let Some(k) = lower[at..].find("url(").map(|k| k + at) {
        let end = lower[k..].find(')').map_or(css.len(), |e| k + e + 1);
        let before = &lower[..k];
        let prop: String = before[..before.rfind(':').unwrap_or(0)]
            .trim_end()
            .chars()
            .rev()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        let paint = prop.ends_with("fill") || prop.ends_with("stroke");
        out.push_str(&css[at..k]);
        out.push_str(if paint { "black" } else { "none" });
        at = end;
    }
    out.push_str(&css[at..]);
    out
}

/// Text safe inside an XML attribute value (either quote) or element.
fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

/// The checks on the XML before usvg sees it: the `<use>` expansion, the
/// style sheets' work, no `<marker>`, and an element of id `opt.id` if one
/// is asked for.
fn check_xml(doc: &roxmltree::Document, opt: &Options) -> std::result::Result<(), String> {
    check_expansion(doc)?;
    check_style_work(doc)?;
    // usvg copies a marker's content to every vertex of every path that
    // names it (in an attribute or a style sheet): a small marker on a long
    // path is a bomb the `<use>` count does not see, and markers are
    // decoration (arrowheads), not outlines. Refused, naming the first.
    if let Some(m) = doc
        .descendants()
        .find(|n| n.is_element() && n.tag_name().name() == "marker")
    {
        return Err(format!(
            "{} is a marker, which p3dp does not draw (usvg would copy it to every vertex of the paths that use it); expected a drawing without `<marker>` elements",
            describe(doc, m)
        ));
    }
    if let Some(id) = opt.id {
        if !doc.descendants().any(|n| n.attribute("id") == Some(id)) {
            return Err(format!(
                "no element has id=\"{id}\"; expected the id of a shape or group"
            ));
        }
    }
    Ok(())
}

/// The subpaths of the whole drawing, or of the element of id `opt.id`.
fn flatten(tree: &usvg::Tree, opt: &Options) -> std::result::Result<Vec<Subpath>, String> {
    let mut out = Vec::new();
    let mut count = 0u64;
    let mut ctx = Flatten {
        opt,
        out: &mut out,
        count: &mut count,
    };
    match opt.id {
        Some(id) => match tree.node_by_id(id) {
            Some(node) => ctx.node(node, id)?,
            None => {
                return Err(format!(
                    "the element with id=\"{id}\" draws nothing (no path, shape or group that usvg keeps); expected the id of a shape or group"
                ))
            }
        },
        None => ctx.group(tree.root(), "")?,
    }
    Ok(out)
}

/// The subpaths of two points or more, refusing a drawing that has none
/// or that reaches beyond [`MAX_MM`].
fn drawn(mut out: Vec<Subpath>, opt: &Options) -> std::result::Result<Vec<Subpath>, String> {
    if out.iter().all(|s| s.points.len() < 2) {
        let what = match opt.id {
            Some(id) => format!("the element with id=\"{id}\""),
            None => "the drawing".to_string(),
        };
        return Err(format!(
            "{what} is empty (no path or shape with two points or more); expected at least one path"
        ));
    }
    out.retain(|s| s.points.len() >= 2);
    // a huge `scale` (or viewBox ratio) must not reach the geometry as
    // infinities: a drawing lies within a kilometre of its origin
    if let Some(s) = out.iter().find(|s| {
        s.points
            .iter()
            .any(|p| !p.is_finite() || p.abs().max_element() > MAX_MM)
    }) {
        let what = if s.element.is_empty() {
            "a path".to_string()
        } else {
            format!("the element with id=\"{}\"", s.element)
        };
        return Err(format!(
            "{what} reaches beyond {MAX_MM} mm at scale {}; expected a smaller scale",
            opt.scale
        ));
    }
    Ok(out)
}

/// Most style-sheet rules × elements that usvg's CSS matching may try (each
/// element is matched against every rule, so the work is their product).
pub(crate) const MAX_STYLE_WORK: u64 = 10_000_000;

/// Refuses a style sheet whose rules, matched against every element, would
/// cost more than [`MAX_STYLE_WORK`]: 60,000 rules over 60,000 elements fit
/// in 3 MB but are 3.6·10⁹ matches. Rules are counted by their `{`.
fn check_style_work(doc: &roxmltree::Document) -> std::result::Result<(), String> {
    let elements = doc.descendants().filter(|n| n.is_element()).count() as u64;
    let mut rules = 0u64;
    let mut first = None;
    for n in doc
        .descendants()
        .filter(|n| n.is_element() && n.tag_name().name() == "style")
    {
        let text: u64 = n
            .descendants()
            .filter(|t| t.is_text())
            .filter_map(|t| t.text())
            .map(|t| t.matches('{').count() as u64)
            .sum();
        rules += text;
        first.get_or_insert(n);
    }
    match first {
        Some(n) if rules.saturating_mul(elements) > MAX_STYLE_WORK => Err(format!(
            "its style sheets (the first: {}) hold {rules} rules for {elements} elements, more than {MAX_STYLE_WORK} rule × element matches; expected a shorter style sheet (or styles written on the elements)",
            describe(doc, n)
        )),
        _ => Ok(()),
    }
}

/// Names an element for errors: its tag, id and line.
fn describe(doc: &roxmltree::Document, n: roxmltree::Node) -> String {
    let pos = doc.text_pos_at(n.range().start);
    match n.attribute("id") {
        Some(id) => format!("<{} id=\"{id}\"> at line {}", n.tag_name().name(), pos.row),
        None => format!("<{}> at line {}", n.tag_name().name(), pos.row),
    }
}

/// The element a `<use>` refers to (`href="#id"` or `xlink:href="#id"`).
fn use_target<'a, 'i>(
    doc: &'a roxmltree::Document<'i>,
    ids: &HashMap<&'a str, roxmltree::Node<'a, 'i>>,
    n: roxmltree::Node<'a, 'i>,
) -> Option<roxmltree::Node<'a, 'i>> {
    let _ = doc;
    let href = n
        .attributes()
        .find(|a| a.name() == "href")
        .map(|a| a.value())?;
    ids.get(href.strip_prefix('#')?).copied()
}

/// Refuses a drawing whose `<use>` expansion would make more than
/// [`MAX_EXPANDED`] elements or nest deeper than [`MAX_DEPTH`], or that
/// refers to itself. size(e) = 1 + Σ size(children) + size(target) for a
/// `<use>`: memoised per element, so an exponential bomb (each `<use>` of the
/// level below twice) costs one visit per element, not per copy.
fn check_expansion(doc: &roxmltree::Document) -> std::result::Result<(), String> {
    let ids: HashMap<&str, roxmltree::Node> = doc
        .descendants()
        .filter(|n| n.is_element())
        .filter_map(|n| n.attribute("id").map(|id| (id, n)))
        .collect();
    struct Walk<'a, 'i, 'd> {
        doc: &'d roxmltree::Document<'i>,
        ids: &'d HashMap<&'a str, roxmltree::Node<'a, 'i>>,
        memo: HashMap<roxmltree::NodeId, u64>,
        open: Vec<roxmltree::NodeId>,
    }
    impl<'a, 'i, 'd> Walk<'a, 'i, 'd>
    where
        'd: 'a,
    {
        fn size(&mut self, n: roxmltree::Node<'a, 'i>) -> std::result::Result<u64, String> {
            if let Some(&s) = self.memo.get(&n.id()) {
                return Ok(s);
            }
            if self.open.contains(&n.id()) {
                return Err(format!(
                    "{} refers to itself through `<use>`; expected no cycle",
                    describe(self.doc, n)
                ));
            }
            if self.open.len() >= MAX_DEPTH {
                return Err(format!(
                    "{} nests elements and `<use>` more than {MAX_DEPTH} deep; expected a flatter drawing",
                    describe(self.doc, n)
                ));
            }
            self.open.push(n.id());
            let mut s = 1u64;
            for c in n.children().filter(|c| c.is_element()) {
                s = s.saturating_add(self.size(c)?);
            }
            if n.tag_name().name() == "use" {
                if let Some(t) = use_target(self.doc, self.ids, n) {
                    s = s.saturating_add(self.size(t)?);
                }
            }
            self.open.pop();
            if s > MAX_EXPANDED {
                return Err(format!(
                    "{} would expand (its `<use>` copies counted) to more than {MAX_EXPANDED} elements; expected a smaller drawing (an SVG bomb of nested `<use>` is refused)",
                    describe(self.doc, n)
                ));
            }
            self.memo.insert(n.id(), s);
            Ok(s)
        }
    }
    let mut w = Walk {
        doc,
        ids: &ids,
        memo: HashMap::new(),
        open: Vec::new(),
    };
    w.size(doc.root_element()).map(|_| ())
}

struct Flatten<'o, 'a> {
    opt: &'o Options<'a>,
    out: &'o mut Vec<Subpath>,
    count: &'o mut u64,
}

impl Flatten<'_, '_> {
    fn node(&mut self, n: &usvg::Node, id: &str) -> std::result::Result<(), String> {
        match n {
            usvg::Node::Group(g) => self.group(g, id),
            usvg::Node::Path(p) => self.path(p, id),
            _ => Ok(()),
        }
    }

    fn group(&mut self, g: &usvg::Group, id: &str) -> std::result::Result<(), String> {
        for c in g.children() {
            let cid = if c.id().is_empty() { id } else { c.id() };
            self.node(c, cid)?;
        }
        Ok(())
    }

    /// Flattens the visible path `p`, of element `id`, into subpaths.
    fn path(&mut self, p: &usvg::Path, id: &str) -> std::result::Result<(), String> {
        if !p.is_visible() {
            return Ok(());
        }
        let map = to_mm(p.abs_transform(), MM_PER_PX * self.opt.scale);
        let tol = self.opt.tolerance;
        let mut cur: Option<Subpath> = None;
        for seg in p.data().segments() {
            use usvg::tiny_skia_path::PathSegment as S;
            let added: Vec<DVec2> = match seg {
                S::MoveTo(q) => {
                    finish(&mut cur, self.out);
                    cur = Some(Subpath {
                        points: Vec::new(),
                        closed: false,
                        element: id.to_string(),
                    });
                    vec![map(q)]
                }
                S::LineTo(q) => vec![map(q)],
                S::QuadTo(a, b) => {
                    let p0 = last(&cur);
                    quad(p0, map(a), map(b), tol)
                }
                S::CubicTo(a, b, c) => {
                    let p0 = last(&cur);
                    cubic(p0, map(a), map(b), map(c), tol)
                }
                S::Close => {
                    self.close(&mut cur, id);
                    continue;
                }
            };
            self.add(&mut cur, added, id)?;
        }
        finish(&mut cur, self.out);
        // a lone start point left after a final Z draws nothing
        self.out.retain(|s| s.points.len() >= 2 || s.closed);
        Ok(())
    }

    /// `Z`: closes the subpath `cur` and starts the next at its first point
    /// (a segment after Z starts there).
    fn close(&mut self, cur: &mut Option<Subpath>, id: &str) {
        if let Some(s) = cur.as_mut() {
            s.closed = true;
            if s.points.len() > 1 && s.points[0] == *s.points.last().unwrap() {
                s.points.pop();
            }
        }
        let reopen = cur.as_ref().map(|s| s.points[0]);
        finish(cur, self.out);
        // a segment after Z starts at the closed subpath's start
        if let Some(start) = reopen {
            *cur = Some(Subpath {
                points: vec![start],
                closed: false,
                element: id.to_string(),
            });
            *self.count += 1;
        }
    }

    /// Appends the points `added` to the subpath `cur` (less repeats of its
    /// last point), refusing a drawing past `opt.max_points`.
    fn add(
        &mut self,
        cur: &mut Option<Subpath>,
        added: Vec<DVec2>,
        id: &str,
    ) -> std::result::Result<(), String> {
        *self.count += added.len() as u64;
        if *self.count > self.opt.max_points {
            let what = if id.is_empty() {
                "the drawing".to_string()
            } else {
                format!("the element with id=\"{id}\"")
            };
            return Err(format!(
                "{what} flattens to more than {} points at tolerance {} mm (the recipe's max_strings); expected a larger tolerance or a simpler drawing",
                self.opt.max_points, self.opt.tolerance
            ));
        }
        if let Some(s) = cur.as_mut() {
            for q in added {
                if s.points.last() != Some(&q) {
                    s.points.push(q);
                }
            }
        }
        Ok(())
    }
}

/// The affine map `t` of user units to mm (`k` mm a unit), y flipped:
/// applied to control points, so the curves stay Béziers and are flattened
/// in mm.
fn to_mm(t: usvg::Transform, k: f64) -> impl Fn(usvg::tiny_skia_path::Point) -> DVec2 {
    move |q| {
        let (x, y) = (q.x as f64, q.y as f64);
        let ux = t.sx as f64 * x + t.kx as f64 * y + t.tx as f64;
        let uy = t.ky as f64 * x + t.sy as f64 * y + t.ty as f64;
        DVec2::new(ux * k, -uy * k)
    }
}

/// Ends the subpath `cur`, if any, into `out`: closed when it comes back to
/// its first point (which it then does not repeat).
fn finish(cur: &mut Option<Subpath>, out: &mut Vec<Subpath>) {
    if let Some(mut s) = cur.take() {
        if s.points.len() > 2 && s.points[0] == *s.points.last().unwrap() {
            s.points.pop();
            s.closed = true;
        }
        out.push(s);
    }
}

fn last(cur: &Option<Subpath>) -> DVec2 {
    cur.as_ref()
        .and_then(|s| s.points.last().copied())
        .unwrap_or(DVec2::ZERO)
}

/// Most pieces one curve is cut into.
const MAX_PIECES: f64 = 100_000.0;

/// A quadratic Bézier cut into n equal parameter steps, its points after p0.
/// Its second derivative is the constant 2·(p0 − 2·p1 + p2), and a chord of a
/// curve over a parameter step h lies within h²/8·max|B''| of it, so
/// n = ⌈sqrt(2·|p0 − 2·p1 + p2| / (8·tol))⌉ keeps every chord within `tol`.
pub(crate) fn quad(p0: DVec2, p1: DVec2, p2: DVec2, tol: f64) -> Vec<DVec2> {
    let m = (p0 - 2.0 * p1 + p2).length();
    let n = libm::ceil(libm::sqrt(m / (4.0 * tol))).clamp(1.0, MAX_PIECES) as usize;
    (1..=n)
        .map(|j| {
            if j == n {
                return p2;
            }
            let t = j as f64 / n as f64;
            let u = 1.0 - t;
            p0 * (u * u) + p1 * (2.0 * u * t) + p2 * (t * t)
        })
        .collect()
}

/// A cubic Bézier cut into n equal parameter steps, its points after p0.
/// |B''| ≤ 6·max(|p0 − 2·p1 + p2|, |p1 − 2·p2 + p3|) (B'' is linear between
/// those two ends), so n = ⌈sqrt(6·M / (8·tol))⌉ keeps every chord within `tol`.
pub(crate) fn cubic(p0: DVec2, p1: DVec2, p2: DVec2, p3: DVec2, tol: f64) -> Vec<DVec2> {
    let m = (p0 - 2.0 * p1 + p2)
        .length()
        .max((p1 - 2.0 * p2 + p3).length());
    let n = libm::ceil(libm::sqrt(0.75 * m / tol)).clamp(1.0, MAX_PIECES) as usize;
    (1..=n)
        .map(|j| {
            if j == n {
                return p3;
            }
            let t = j as f64 / n as f64;
            let u = 1.0 - t;
            p0 * (u * u * u) + p1 * (3.0 * u * u * t) + p2 * (3.0 * u * t * t) + p3 * (t * t * t)
        })
        .collect()
}

/// A closed outline, parameterised by arc length: centred on its area
/// centroid, counter-clockwise seen from above, starting where the ray
/// theta = 0 from the centroid first leaves it (at its first point when the
/// ray misses it).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Outline {
    /// The vertices, centroid at the origin (the first is not repeated).
    pub(crate) points: Vec<DVec2>,
    /// Arc length from the start to vertex j, mm; one more entry: the total.
    pub(crate) at: Vec<f64>,
    /// Arc fractions s of the corners (vertices turning by more than
    /// [`CORNER_DEGREES`]), so a turn can pass through them exactly.
    pub(crate) corners: Vec<f64>,
}

/// A vertex turning by more than this many degrees is a corner.
pub(crate) const CORNER_DEGREES: f64 = 20.0;

impl Outline {
    /// The one closed subpath of `subpaths` as an outline; an error sentence
    /// when there is none, more than one, or it encloses no area.
    pub(crate) fn from_subpaths(subpaths: &[Subpath]) -> std::result::Result<Outline, String> {
        let closed: Vec<&Subpath> = subpaths
            .iter()
            .filter(|s| s.closed && s.points.len() >= 3)
            .collect();
        let s = match closed.as_slice() {
            [] => {
                let open: Vec<String> = subpaths
                    .iter()
                    .filter(|s| !s.element.is_empty())
                    .take(5)
                    .map(|s| format!("id=\"{}\"", s.element))
                    .collect();
                let which = if open.is_empty() {
                    String::new()
                } else {
                    format!(" (open: {})", open.join(", "))
                };
                return Err(format!(
                    "has no closed path{which}; expected one ending with `Z`, or a closed shape, for an outline"
                ));
            }
            [s] => s,
            more => {
                let names: Vec<String> = more
                    .iter()
                    .take(5)
                    .map(|s| {
                        if s.element.is_empty() {
                            "(no id)".to_string()
                        } else {
                            format!("id=\"{}\"", s.element)
                        }
                    })
                    .collect();
                return Err(format!(
                    "has {} closed paths ({}); expected one: choose it with `id`",
                    more.len(),
                    names.join(", ")
                ));
            }
        };
        Outline::new(&s.points).map_err(|m| match s.element.as_str() {
            "" => m,
            id => format!("the path with id=\"{id}\" {m}"),
        })
    }

    /// The closed polygon `pts` as an outline.
    pub(crate) fn new(pts: &[DVec2]) -> std::result::Result<Outline, String> {
        // area and centroid of the polygon (shoelace): A = ½Σ cross(p_j, p_j+1),
        // C = Σ (p_j + p_j+1)·cross(p_j, p_j+1) / (6A); taken about the first
        // point, for precision far from the origin
        let o = pts[0];
        let (mut a2, mut c) = (0.0, DVec2::ZERO);
        for j in 0..pts.len() {
            let p = pts[j] - o;
            let q = pts[(j + 1) % pts.len()] - o;
            let w = p.perp_dot(q);
            a2 += w;
            c += (p + q) * w;
        }
        let bbox = pts
            .iter()
            .fold((pts[0], pts[0]), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let size = (bbox.1 - bbox.0).max_element();
        if a2.abs() <= 1e-9 * size * size || size == 0.0 {
            return Err("encloses no area; expected a closed outline round an area".into());
        }
        let centroid = o + c / (3.0 * a2);
        let mut p: Vec<DVec2> = pts.iter().map(|q| *q - centroid).collect();
        if a2 < 0.0 {
            p.reverse();
        }
        // start where the ray theta = 0 crosses the outline (the nearest crossing)
        let n = p.len();
        let mut best: Option<(f64, usize, DVec2)> = None;
        for j in 0..n {
            let (a, b) = (p[j], p[(j + 1) % n]);
            if (a.y < 0.0) != (b.y < 0.0) || (a.y == 0.0 && a.x > 0.0) {
                let x = if a.y == b.y {
                    a.x
                } else {
                    a.x + (b.x - a.x) * (0.0 - a.y) / (b.y - a.y)
                };
                if x > 0.0 && best.is_none_or(|(bx, _, _)| x < bx) {
                    best = Some((x, j, DVec2::new(x, 0.0)));
                }
            }
        }
        if let Some((_, j, q)) = best {
            let mut r = Vec::with_capacity(n + 1);
            r.push(q);
            r.extend((1..=n).map(|i| p[(j + i) % n]));
            r.dedup();
            if r.last() == Some(&q) {
                r.pop();
            }
            p = r;
        }
        let n = p.len();
        let mut at = Vec::with_capacity(n + 1);
        let mut l = 0.0;
        at.push(0.0);
        for j in 0..n {
            l += p[j].distance(p[(j + 1) % n]);
            at.push(l);
        }
        let cos_corner = libm::cos(CORNER_DEGREES.to_radians());
        let corners = (0..n)
            .filter(|&j| {
                let d0 = (p[j] - p[(j + n - 1) % n]).normalize_or_zero();
                let d1 = (p[(j + 1) % n] - p[j]).normalize_or_zero();
                j > 0 && d0.dot(d1) < cos_corner
            })
            .map(|j| at[j] / l)
            .collect();
        Ok(Outline {
            points: p,
            at,
            corners,
        })
    }

    /// The outline's length, mm.
    pub(crate) fn length(&self) -> f64 {
        *self.at.last().unwrap()
    }

    /// The farthest distance of the outline from its centroid, mm.
    pub(crate) fn max_radius(&self) -> f64 {
        self.points.iter().map(|p| p.length()).fold(0.0, f64::max)
    }

    /// The point at arc fraction `s` (0..1, taken mod 1), centroid at the origin.
    pub(crate) fn point_at(&self, s: f64) -> DVec2 {
        let s = s - libm::floor(s);
        let d = s * self.length();
        // the last vertex j with at[j] ≤ d
        let j = self.at.partition_point(|&a| a <= d).saturating_sub(1);
        let n = self.points.len();
        let j = j.min(n - 1);
        let seg = self.at[j + 1] - self.at[j];
        let (a, b) = (self.points[j], self.points[(j + 1) % n]);
        if seg <= 0.0 {
            return a;
        }
        a.lerp(b, ((d - self.at[j]) / seg).clamp(0.0, 1.0))
    }

    /// The arc fractions of one turn of `segments` strings: k/segments for
    /// k < segments, and every corner, in order (each once).
    pub(crate) fn fractions(&self, segments: u32) -> Vec<f64> {
        let mut f: Vec<f64> = (0..segments).map(|k| k as f64 / segments as f64).collect();
        // a corner closer than a thousandth of a step to a sample replaces nothing
        let eps = 1e-3 / segments as f64;
        for &c in &self.corners {
            let near = f.iter().any(|&x| (x - c).abs() < eps || (1.0 - c) < eps);
            if !near {
                f.push(c);
            }
        }
        f.sort_by(f64::total_cmp);
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opt() -> Options<'static> {
        Options {
            id: None,
            scale: 1.0,
            tolerance: 0.01,
            max_points: 1_000_000,
        }
    }

    const MM: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">"#;

    #[test]
    fn degenerate_paint_servers_never_reach_usvg_and_the_shapes_stay() {
        // a pattern 1e-9 wide made tiny-skia unwrap a None inside usvg
        let defs = r#"<defs><pattern id="p" width="1e-9" height="1e-9"><rect width="1" height="1" fill="url(#p)"/></pattern><linearGradient id="g" x1="0" x2="1e-9"/><filter id="f" width="1e-9"/></defs>"#;
        let rect = r#"<rect id="r" x="20" y="20" width="10" height="10""#;
        let plain = parse(&format!("{MM}{rect}/></svg>"), &opt()).unwrap();
        for paint in [
            r#" fill="url(#p)""#,
            r#" stroke="url(#p)" fill="none""#,
            r#" fill="URL('#p') red""#,
            r#" style="fill: url(#p); stroke:url(#g)""#,
            r#" class="a""#,
            r#" fill="url(#g)" filter="url(#f)" mask="url(#p)" clip-path="url(#p)""#,
        ] {
            let sheet = r##"<style>.a { fill: url(#p) } rect { stroke: url( "#p" ) }</style>"##;
            let svg = format!("{MM}{sheet}{defs}{rect}{paint}/></svg>");
            let s = parse(&svg, &opt()).unwrap_or_else(|e| panic!("{paint}: {e}"));
            assert_eq!(s, plain, "{paint}");
        }
        assert_eq!(
            css_plain("a{fill:url(#p)} b{clip-path: url(#c) ;stroke-width:1}"),
            "a{fill:black} b{clip-path: none ;stroke-width:1}"
        );
    }

    #[test]
    fn a_mm_root_gives_mm_and_y_up() {
        let svg = format!(r#"{MM}<path id="sq" d="M 10 10 L 30 10 L 30 20 Z"/></svg>"#);
        let s = parse(&svg, &opt()).unwrap();
        assert_eq!(s.len(), 1);
        assert!(s[0].closed);
        let want = [(10.0, -10.0), (30.0, -10.0), (30.0, -20.0)];
        assert_eq!(s[0].points.len(), 3);
        for (p, w) in s[0].points.iter().zip(want) {
            assert!((p.x - w.0).abs() < 1e-4 && (p.y - w.1).abs() < 1e-4, "{p}");
        }
        assert_eq!(s[0].element, "sq");
    }

    #[test]
    fn transforms_and_px_units_are_resolved() {
        // no width/height: user units are px, 25.4/96 mm each
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg"><g transform="translate(96 0) scale(2)"><path d="M 0 0 L 48 0"/></g></svg>"#;
        let s = parse(svg, &opt()).unwrap();
        let p = &s[0].points;
        assert!((p[0].x - 25.4).abs() < 1e-4, "{p:?}");
        assert!((p[1].x - 50.8).abs() < 1e-4, "{p:?}");
    }

    #[test]
    fn curves_stay_within_the_tolerance() {
        // the quarter circle of radius 1 as one cubic: its points lie within
        // tol of the curve, and so within tol + 3e-4 of the circle
        let (p0, p1, p2, p3) = (
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 0.5523),
            DVec2::new(0.5523, 1.0),
            DVec2::new(0.0, 1.0),
        );
        let pts = cubic(p0, p1, p2, p3, 1e-4);
        assert!(pts.len() > 10);
        let mut prev = p0;
        for q in pts {
            let mid = (prev + q) * 0.5;
            assert!((mid.length() - 1.0).abs() < 1e-4 + 3e-4);
            prev = q;
        }
    }

    #[test]
    fn a_use_bomb_is_refused_before_expanding() {
        let mut svg = String::from(
            r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink"><defs><path id="a0" d="M0 0 L1 1"/>"#,
        );
        for k in 1..40 {
            svg.push_str(&format!(
                r##"<g id="a{k}"><use xlink:href="#a{0}"/><use xlink:href="#a{0}"/></g>"##,
                k - 1
            ));
        }
        svg.push_str(r##"</defs><use xlink:href="#a39"/></svg>"##);
        let e = parse(&svg, &opt()).unwrap_err();
        assert!(e.contains("<g id=\"a"), "{e}");
        assert!(e.contains("SVG bomb"), "{e}");
    }

    #[test]
    fn a_marker_is_refused_before_usvg_copies_it() {
        // 20,000 vertices each given a marker of 1,000 copies would be 2e7
        // elements once usvg expands them
        let mut d = String::from("M 0 0");
        for i in 1..20_000 {
            d.push_str(&format!(" L {} {}", i % 40, (i * 7) % 40));
        }
        let svg = format!(
            r##"{MM}<defs><path id="l0" d="M 0 0 L 1 0 L 1 1 Z"/><marker id="m"><use href="#l0"/></marker></defs><path id="p" d="{d}" style="marker-mid: url(#m)"/></svg>"##
        );
        let e = parse(&svg, &opt()).unwrap_err();
        assert!(e.contains("<marker id=\"m\"> at line 1"), "{e}");
    }

    #[test]
    fn a_style_sheet_matched_against_every_element_is_bounded() {
        // 4,000 rules × 4,000 elements = 1.6e7 matches: refused before usvg
        let mut svg = String::from(MM);
        svg.push_str("<style>");
        for i in 0..4000 {
            svg.push_str(&format!(".c{i}{{fill:red}}"));
        }
        svg.push_str("</style>");
        for i in 0..4000 {
            svg.push_str(&format!(r#"<path class="c{i}" d="M0 0L1 1"/>"#));
        }
        svg.push_str("</svg>");
        let e = parse(&svg, &opt()).unwrap_err();
        assert!(
            e.contains("<style> at line 1") && e.contains("4000 rules"),
            "{e}"
        );
        // a usual sheet passes
        let ok = format!(
            r#"{MM}<style>.a{{fill:red}} path{{stroke:black}}</style><path class="a" d="M0 0L1 1"/></svg>"#
        );
        assert!(parse(&ok, &opt()).is_ok());
    }

    #[test]
    fn a_huge_scale_is_refused() {
        let svg = format!(r#"{MM}<path id="p" d="M 0 0 L 10 0 L 10 10 Z"/></svg>"#);
        let e = parse(
            &svg,
            &Options {
                scale: 1e300,
                ..opt()
            },
        )
        .unwrap_err();
        assert!(e.contains("id=\"p\"") && e.contains("scale"), "{e}");
    }

    #[test]
    fn a_self_reference_is_refused() {
        let svg =
            r##"<svg xmlns="http://www.w3.org/2000/svg"><g id="g"><use href="#g"/></g></svg>"##;
        let e = parse(svg, &opt()).unwrap_err();
        assert!(e.contains("itself"), "{e}");
    }

    #[test]
    fn the_outline_is_centred_ccw_and_starts_at_theta_zero() {
        // a clockwise (in y-up terms) square from (0,0) to (2,2)
        let sq = [
            DVec2::new(0.0, 0.0),
            DVec2::new(0.0, 2.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(2.0, 0.0),
        ];
        let o = Outline::new(&sq).unwrap();
        assert_eq!(o.points[0], DVec2::new(1.0, 0.0));
        assert!((o.length() - 8.0).abs() < 1e-12);
        // counter-clockwise: the next corner is (1, 1)
        assert_eq!(o.points[1], DVec2::new(1.0, 1.0));
        assert_eq!(o.corners, vec![1.0 / 8.0, 3.0 / 8.0, 5.0 / 8.0, 7.0 / 8.0]);
        assert!((o.point_at(0.25) - DVec2::new(0.0, 1.0)).length() < 1e-12);
        assert!((o.point_at(1.0) - o.point_at(0.0)).length() < 1e-12);
    }
}
