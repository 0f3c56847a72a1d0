//! Previews: see the print before printing it.
//!
//! Three outputs share one reading of the plan ([`Scene`]): a PNG rendering
//! ([`png`]), a self-contained HTML file with a WebGL viewer ([`html`]) and the
//! PNG thumbnails PrusaSlicer-style printers show from the G-code
//! ([`thumbnail`]).
//!
//! Projection. Every still view is orthographic. A view is an orthonormal
//! basis (right, up, toward) of recipe space, `toward` pointing at the viewer:
//! a point p lands on the screen plane at (u, w) = (p·right, p·up) and lies at
//! depth d = p·toward (larger is nearer). Pixels are x = cx + s·(u − u_c) and
//! y = cy − s·(w − w_c), with s the scale in px/mm and (u_c, w_c) the centre of
//! the drawing; the minus sign because image rows grow downwards.
//!
//! Width. A string of cross-section c laid h from the next pass (a helix's
//! layer height, measured on the path: [`Grid::local`]) fills those h along
//! the surface and is c / h thick across it, the real string width. The
//! previews draw it as that flat tube seen from the view: the projection of
//! its cross-section (an ellipse of axes h along the surface and c / h along
//! the normal) onto the screen direction across the string. So a wall seen
//! face on is closed, as printed, and its rim shows the real thickness; a
//! string with no neighbouring pass is drawn round, of diameter 2·sqrt(c/pi).

pub mod html;
pub mod png;
pub mod thumbnail;

mod text;

use std::collections::HashSet;

use std::path::Path;

use glam::DVec3;

use crate::analyse::plan::Plan;
use crate::analyse::stats::Stats;
use crate::base::error::{Error, Result};
use crate::base::geom::passes::{pass_spacing, round_diameter};
pub use crate::machine::Size;
use crate::output::file::write_atomic;

/// Where the still views look from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum View {
    /// Isometric, from the front right and above.
    #[default]
    Iso,
    /// From above: x to the right, y up the image.
    Top,
    /// From the front (−y): x to the right, z up.
    Front,
    /// From the right (+x): y to the right, z up.
    Side,
}

/// An orthonormal view basis in recipe coordinates (right × up = toward).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Basis {
    /// Screen right.
    pub right: DVec3,
    /// Screen up.
    pub up: DVec3,
    /// Towards the viewer; depth grows along it.
    pub toward: DVec3,
}

impl View {
    /// The names `--view` accepts.
    pub const NAMES: [&'static str; 4] = ["iso", "top", "front", "side"];

    /// Parses a `--view` value.
    pub fn parse(s: &str) -> Result<View> {
        match s {
            "iso" => Ok(View::Iso),
            "top" => Ok(View::Top),
            "front" => Ok(View::Front),
            "side" => Ok(View::Side),
            _ => Err(Error::input(
                "--view",
                format!(
                    "unknown view `{s}`; expected one of {}",
                    View::NAMES.join(", ")
                ),
            )),
        }
    }

    /// The view's name.
    pub fn name(self) -> &'static str {
        match self {
            View::Iso => "iso",
            View::Top => "top",
            View::Front => "front",
            View::Side => "side",
        }
    }

    /// The view's basis.
    pub fn basis(self) -> Basis {
        match self {
            View::Top => Basis {
                right: DVec3::X,
                up: DVec3::Y,
                toward: DVec3::Z,
            },
            View::Front => Basis {
                right: DVec3::X,
                up: DVec3::Z,
                toward: DVec3::NEG_Y,
            },
            View::Side => Basis {
                right: DVec3::Y,
                up: DVec3::Z,
                toward: DVec3::X,
            },
            View::Iso => {
                // the viewer on the diagonal (1, −1, 1): right = z × toward
                // (horizontal), up = toward × right (completes the basis)
                let toward = DVec3::new(1.0, -1.0, 1.0).normalize();
                let right = DVec3::Z.cross(toward).normalize();
                Basis {
                    right,
                    up: toward.cross(right),
                    toward,
                }
            }
        }
    }
}

impl Basis {
    /// Screen-plane coordinates (u, w) and depth d of recipe point `p`.
    pub fn project(&self, p: DVec3) -> (f64, f64, f64) {
        (p.dot(self.right), p.dot(self.up), p.dot(self.toward))
    }
}

/// What the colour of a string shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColorMode {
    /// Head speed v, mm/s.
    #[default]
    Speed,
    /// Cross-section c, mm².
    CrossSection,
    /// Volumetric flow c·v, mm³/s.
    Flow,
    /// Print order, as the print time at which the string is laid, min.
    Order,
    /// Grey, with the strings the checks found problems in red.
    Findings,
    /// One filament colour (the G-code thumbnails).
    Plain,
}

impl ColorMode {
    /// The names `--color` accepts.
    pub const NAMES: [&'static str; 6] = [
        "speed",
        "cross-section",
        "flow",
        "order",
        "findings",
        "plain",
    ];

    /// Parses a `--color` value.
    pub fn parse(s: &str) -> Result<ColorMode> {
        match s {
            "speed" => Ok(ColorMode::Speed),
            "cross-section" => Ok(ColorMode::CrossSection),
            "flow" => Ok(ColorMode::Flow),
            "order" => Ok(ColorMode::Order),
            "findings" => Ok(ColorMode::Findings),
            "plain" => Ok(ColorMode::Plain),
            _ => Err(Error::input(
                "--color",
                format!(
                    "unknown colour mode `{s}`; expected one of {}",
                    ColorMode::NAMES.join(", ")
                ),
            )),
        }
    }

    /// The mode's name.
    pub fn name(self) -> &'static str {
        match self {
            ColorMode::Speed => "speed",
            ColorMode::CrossSection => "cross-section",
            ColorMode::Flow => "flow",
            ColorMode::Order => "order",
            ColorMode::Findings => "findings",
            ColorMode::Plain => "plain",
        }
    }

    /// The unit of the scale, for the legend.
    pub fn unit(self) -> &'static str {
        match self {
            ColorMode::Speed => "mm/s",
            ColorMode::CrossSection => "mm²",
            ColorMode::Flow => "mm³/s",
            ColorMode::Order => "min",
            ColorMode::Findings | ColorMode::Plain => "",
        }
    }
}

/// What a preview shows and how big.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Options {
    /// Still view (the HTML viewer starts there).
    pub view: View,
    /// Colour mode (the HTML viewer starts there).
    pub color: ColorMode,
    /// Image size (PNG only).
    pub size: Size,
    /// Only the model: no title, stats or legend (PNG only).
    pub bare: bool,
    /// How many threads drawing it may use (`-j`); the output is the same on any number.
    pub threads: crate::base::threads::Threads,
}

/// The plan read for drawing: per path the spacing of its passes, per string
/// the print time at its end and whether a check found a problem in it.
pub struct Scene<'a> {
    /// The plan drawn.
    pub plan: &'a Plan,
    /// Per path: print time at the end of each string, s (Σ length / speed);
    /// made when first asked for ([`Scene::time`]).
    time: std::sync::OnceLock<Vec<Vec<f64>>>,
    /// [`Scene::range`] of each colour mode, once asked for.
    ranges: [std::sync::OnceLock<(f64, f64)>; 6],
    /// Per path: whether a finding concerns each string.
    pub flagged: Vec<Vec<bool>>,
    /// Per path: the typical spacing between its passes, mm.
    pub spacing: Vec<f64>,
    /// Where the findings are, recipe coordinates.
    pub marks: Vec<DVec3>,
    /// The turtles' `draw_turtle` markers of every part.
    pub turtles: Vec<crate::base::toolpath::Marker>,
}

impl<'a> Scene<'a> {
    /// Reads `plan` for drawing.
    pub fn new(plan: &'a Plan) -> Scene<'a> {
        Scene::with_flags(plan, flags(plan))
    }

    /// [`Scene::new`] given which strings the findings concern (as [`flags`]
    /// finds them), so that they may be known before the rest.
    fn with_flags(plan: &'a Plan, flagged: Vec<Vec<bool>>) -> Scene<'a> {
        let fallback = plan.recipe.printer.nozzle_diameter / 2.0;
        let spacing: Vec<f64> = plan
            .paths
            .iter()
            .map(|tp| pass_spacing(&tp.points).unwrap_or(fallback))
            .collect();
        Scene {
            plan,
            time: Default::default(),
            ranges: Default::default(),
            flagged,
            spacing,
            marks: plan
                .findings
                .iter()
                .filter_map(|f| f.at.map(DVec3::from_array))
                .filter(|p| p.is_finite())
                .collect(),
            turtles: plan
                .paths
                .iter()
                .flat_map(|tp| tp.markers.iter().copied())
                .filter(|m| m.pos.is_finite())
                .collect(),
        }
    }

    /// The triangle of a turtle marker (ExtruderTurtle's draw_Turtle(), Fig.
    /// 2c): its sharpest corner `size` mm ahead along the heading, the other
    /// two behind it on either side, in the turtle's plane (normal `up`).
    pub fn turtle_triangle(m: &crate::base::toolpath::Marker, size: f64) -> [DVec3; 3] {
        let left = m.up.cross(m.heading);
        [
            m.pos + m.heading * size,
            m.pos - m.heading * (0.5 * size) + left * (0.5 * size),
            m.pos - m.heading * (0.5 * size) - left * (0.5 * size),
        ]
    }

    /// Per path: print time at the end of each string, s (Σ length / speed).
    pub fn time(&self) -> &Vec<Vec<f64>> {
        self.time.get_or_init(|| {
            let mut t = 0.0;
            self.plan
                .paths
                .iter()
                .map(|tp| {
                    (0..tp.len())
                        .map(|k| {
                            let v = tp.strings[k].v;
                            if v > 0.0 {
                                t += tp.length(k) / v;
                            }
                            t
                        })
                        .collect()
                })
                .collect()
        })
    }

    /// The number string k of path `pi` shows in colour mode `mode`.
    pub fn value(&self, mode: ColorMode, pi: usize, k: usize) -> f64 {
        let s = self.plan.paths[pi].strings[k];
        match mode {
            ColorMode::Speed => s.v,
            ColorMode::CrossSection => s.c,
            ColorMode::Flow => s.c * s.v,
            ColorMode::Order => self.time()[pi][k] / 60.0,
            ColorMode::Findings | ColorMode::Plain => 0.0,
        }
    }

    /// Lowest and highest value over the extruding strings (0, 0 when none).
    pub fn range(&self, mode: ColorMode) -> (f64, f64) {
        let slot = ColorMode::NAMES
            .iter()
            .position(|n| *n == mode.name())
            .expect("every mode is named");
        *self.ranges[slot].get_or_init(|| self.find_range(mode))
    }

    fn find_range(&self, mode: ColorMode) -> (f64, f64) {
        if mode == ColorMode::Order {
            let end = self.time().iter().flatten().last().copied().unwrap_or(0.0);
            return (0.0, end / 60.0);
        }
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for (pi, tp) in self.plan.paths.iter().enumerate() {
            for (k, s) in tp.strings.iter().enumerate() {
                if !s.travel {
                    let v = self.value(mode, pi, k);
                    if v.is_finite() {
                        lo = lo.min(v);
                        hi = hi.max(v);
                    }
                }
            }
        }
        if lo > hi {
            (0.0, 0.0)
        } else {
            (lo, hi)
        }
    }

    /// The extruding points (all points when nothing extrudes).
    pub fn extruding_points(&self) -> Vec<DVec3> {
        let mut out = Vec::new();
        self.each_extruding_point(|p| {
            if out.last() != Some(&p) {
                out.push(p)
            }
        });
        out
    }

    /// Calls `f` on the finite ends of every extruding string, in print order
    /// (on every finite point when nothing extrudes), a point the same bits
    /// as the one just passed not again (the end two strings in a row
    /// share): [`Scene::extruding_points`] without holding them.
    pub fn each_extruding_point(&self, mut f: impl FnMut(DVec3)) {
        let mut any = false;
        let bits = |p: DVec3| p.to_array().map(f64::to_bits);
        for tp in &self.plan.paths {
            let mut last = None;
            for (k, s) in tp.strings.iter().enumerate() {
                if !s.travel {
                    any = true;
                    let (a, b) = tp.ends(k);
                    for p in [a, b] {
                        if p.is_finite() && last != Some(bits(p)) {
                            last = Some(bits(p));
                            f(p);
                        }
                    }
                }
            }
        }
        if !any {
            for tp in &self.plan.paths {
                for p in &tp.points {
                    if p.is_finite() {
                        f(*p);
                    }
                }
            }
        }
    }

    /// Half the widest a string is drawn, mm: room to leave round the model.
    pub fn pad(&self) -> f64 {
        let mut w: f64 = 0.0;
        for (tp, h) in self.plan.paths.iter().zip(&self.spacing) {
            let c = tp
                .strings
                .iter()
                .filter(|s| !s.travel)
                .fold(0.0f64, |a, s| a.max(s.c));
            w = w.max(*h).max(2.0 * c / h).max(round_diameter(c));
        }
        (w / 2.0).min(2.0 * self.plan.recipe.printer.nozzle_diameter)
    }

    /// The typical spacing between passes, weighted by string count, mm.
    pub fn typical_spacing(&self) -> f64 {
        let mut v: Vec<(f64, usize)> = self
            .spacing
            .iter()
            .zip(&self.plan.paths)
            .map(|(h, tp)| (*h, tp.len()))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        let total: usize = v.iter().map(|x| x.1).sum();
        let mut seen = 0;
        for (h, n) in &v {
            seen += n;
            if 2 * seen >= total {
                return *h;
            }
        }
        self.plan.recipe.printer.nozzle_diameter / 2.0
    }
}

/// Which strings the findings concern, per path.
///
/// A finding names its first string and, for runs (unsupported, bridges),
/// every string of them (`Finding::strings`); for the checks that judge each
/// string by itself (bed limits, speed, flow, finite numbers) every string that
/// fails the same test is marked, with the printer's limits the checks use.
fn flags(plan: &Plan) -> Vec<Vec<bool>> {
    let codes: HashSet<&str> = plan.findings.iter().map(|f| f.code).collect();
    let p = &plan.recipe.printer;
    let max_z = p.bed.max_z();
    let outside = |q: DVec3| {
        let m = p.to_machine(q);
        (codes.contains("non-finite") && !q.is_finite())
            || (codes.contains("out-of-bed") && q.is_finite() && !p.bed.contains_xy(m))
            || (codes.contains("below-bed") && m.z < 0.0)
            || (codes.contains("above-max-z") && m.z > max_z)
    };
    let mut out: Vec<Vec<bool>> = plan
        .paths
        .iter()
        .map(|tp| {
            let bad_point: Vec<bool> = tp.points.iter().map(|q| outside(*q)).collect();
            tp.strings
                .iter()
                .enumerate()
                .map(|(k, s)| {
                    bad_point[k]
                        || bad_point[k + 1]
                        || (!s.travel
                            && ((codes.contains("speed") && s.v > p.max_speed)
                                || (codes.contains("flow") && s.c * s.v > p.max_flow)))
                })
                .collect()
        })
        .collect();
    for f in &plan.findings {
        if let (Some(part), Some(k)) = (&f.part, f.string) {
            for (pi, tp) in plan.paths.iter().enumerate() {
                if &tp.name == part && k < tp.len() {
                    out[pi][k] = true;
                    // every string the finding names (an unsupported run, a bridge)
                    for &[a, b] in &f.strings {
                        for flag in &mut out[pi][a.min(tp.len())..b.min(tp.len())] {
                            *flag = true;
                        }
                    }
                }
            }
        }
    }
    out
}

/// Colour stops of the scalar modes: blue, cyan, green, yellow, red.
pub const STOPS: [[f32; 3]; 5] = [
    [0.23, 0.30, 0.85],
    [0.10, 0.65, 0.95],
    [0.25, 0.85, 0.45],
    [0.98, 0.80, 0.20],
    [0.90, 0.25, 0.15],
];

/// The colour of `t` in [0, 1] on the scale of [`STOPS`].
pub fn colormap(t: f64) -> [f32; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as f64;
    let k = (x.floor() as usize).min(STOPS.len() - 2);
    let f = (x - k as f64) as f32;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * f)
}

/// A number for a legend: three significant figures or so, no exponent.
pub fn fmt_value(v: f64) -> String {
    let a = v.abs();
    let s = if a >= 100.0 || a == 0.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    };
    match s.strip_prefix('-') {
        // never `-0.000`
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => s,
    }
}

/// The output format, by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// A PNG image.
    Png,
    /// A self-contained HTML viewer.
    Html,
}

impl Format {
    /// The format of `path` by its extension.
    pub fn of(path: &Path) -> Result<Format> {
        match crate::output::file::extension(path).as_str() {
            "png" => Ok(Format::Png),
            "html" | "htm" => Ok(Format::Html),
            _ => Err(Error::input(
                "preview",
                format!(
                    "cannot tell the format of `{}`; expected a file name ending in .png or .html",
                    path.display()
                ),
            )),
        }
    }
}

/// Writes a plan's G-code to a writer and returns its stats (the build's
/// renderer, passed down so that previews need not know how G-code is made).
/// `Sync`, so that it may run on a thread of its own beside the drawing.
pub type Render<'a> = &'a (dyn Fn(&mut dyn std::io::Write) -> Result<Stats> + Sync);

/// Writes a preview of `plan` to `out` (PNG or HTML by extension, atomically);
/// returns a line for the report. `render` writes the plan's G-code.
pub fn write(plan: &Plan, out: &Path, opts: &Options, render: Render) -> Result<String> {
    let shown = out.display().to_string();
    let io =
        |e: std::io::Error| Error::io_from(&shown, format!("cannot write the preview: {e}"), &e);
    if Format::of(out)? == Format::Html {
        // streamed into the file as it is encoded
        let (data, stats) = html::read(plan, opts, render)?;
        let mut len = 0;
        write_atomic(out, |f| {
            use std::io::Write;
            let mut w = Counted {
                inner: std::io::BufWriter::with_capacity(1 << 16, f),
                n: 0,
            };
            html::write_page(&stats.name, &data, &mut w).map_err(io)?;
            w.inner.flush().map_err(io)?;
            len = w.n;
            Ok(())
        })?;
        return Ok(html_line(&shown, data.points(), len));
    }
    let (bytes, line) = bytes(plan, out, opts, render)?;
    write_atomic(out, |f| {
        use std::io::Write;
        f.write_all(&bytes).map_err(io)
    })?;
    Ok(line)
}

/// A writer that counts the bytes through it.
struct Counted<W> {
    inner: W,
    n: usize,
}

impl<W: std::io::Write> std::io::Write for Counted<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let k = self.inner.write(buf)?;
        self.n += k;
        Ok(k)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The report line of an HTML preview of `points` points and `len` bytes.
fn html_line(shown: &str, points: usize, len: usize) -> String {
    format!(
        "preview → {shown}: HTML viewer, {points} points, {} kB",
        (len + 512) / 1024
    )
}

/// The bytes of the preview [`write`] writes to `out` (its format by the
/// extension), and the line reporting it; writes nothing, so a build can
/// commit the preview with its other outputs.
pub fn bytes(plan: &Plan, out: &Path, opts: &Options, render: Render) -> Result<(Vec<u8>, String)> {
    let format = Format::of(out)?;
    let shown = out.display().to_string();
    match format {
        Format::Png => {
            let (r, _) = png::preview(plan, opts, render)?;
            let bytes = png::encode_fast(&r.pixmap, false);
            let (x, y) = r.frame.pixel(DVec3::ZERO);
            Ok((bytes, format!(
                "preview → {shown}: {} × {} px, {} view, colour {}, scale {:.4} px/mm, recipe (0, 0, 0) at pixel ({x:.2}, {y:.2})",
                opts.size.width,
                opts.size.height,
                opts.view.name(),
                opts.color.name(),
                r.frame.scale
            )))
        }
        Format::Html => {
            let (data, stats) = html::read(plan, opts, render)?;
            let mut page = Vec::new();
            html::write_page(&stats.name, &data, &mut page).expect("writing to memory");
            let line = html_line(&shown, data.points(), page.len());
            Ok((page, line))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn view_bases_are_right_handed_and_orthonormal() {
        for name in View::NAMES {
            let b = View::parse(name).unwrap().basis();
            assert!((b.right.cross(b.up) - b.toward).length() < 1e-12, "{name}");
            for v in [b.right, b.up, b.toward] {
                assert!((v.length() - 1.0).abs() < 1e-12);
            }
            assert!(b.right.dot(b.up).abs() < 1e-12);
        }
        // iso: the z axis points up the image, the x axis to the lower right
        let b = View::Iso.basis();
        assert!(b.up.z > 0.0 && b.right.z == 0.0);
        assert!(DVec3::X.dot(b.right) > 0.0 && DVec3::X.dot(b.up) < 0.0);
        assert!(View::parse("bottom").is_err());
    }

    #[test]
    fn sizes_parse() {
        assert_eq!(
            Size::parse("220x124", "s").unwrap(),
            Size {
                width: 220,
                height: 124
            }
        );
        assert_eq!(Size::parse("16X16", "s").unwrap().width, 16);
        for bad in ["", "12", "0x5", "5x", "ax3", "9000x10", "-3x4"] {
            assert!(Size::parse(bad, "--size").is_err(), "{bad}");
        }
    }

    #[test]
    fn colormap_ends_and_middle() {
        assert_eq!(colormap(0.0), STOPS[0]);
        assert_eq!(colormap(1.0), STOPS[4]);
        assert_eq!(colormap(0.5), STOPS[2]);
        assert_eq!(colormap(f64::NAN), STOPS[0]);
        assert_eq!(colormap(7.0), STOPS[4]);
    }

    #[test]
    fn legend_numbers() {
        assert_eq!(fmt_value(123.456), "123");
        assert_eq!(fmt_value(12.345), "12.3");
        assert_eq!(fmt_value(0.19634), "0.196");
        assert_eq!(fmt_value(-0.0001), "0.000");
        assert_eq!(fmt_value(-2.5), "-2.50");
        assert_eq!(fmt_value(0.0), "0");
    }

    #[test]
    fn formats_by_extension() {
        assert_eq!(Format::of(Path::new("a/b.PNG")).unwrap(), Format::Png);
        assert_eq!(Format::of(Path::new("x.html")).unwrap(), Format::Html);
        assert!(Format::of(Path::new("x.jpg")).is_err());
        assert!(Format::of(Path::new("x")).is_err());
    }
}

#[cfg(test)]
mod flag_tests {
    use super::*;

    #[test]
    fn every_string_of_an_unsupported_run_is_flagged() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/checks/pitch-gap.yaml");
        let plan = crate::app::build::plan(&path, &crate::app::build::Options::default()).unwrap();
        let f = plan
            .findings
            .iter()
            .find(|f| f.code == "unsupported")
            .expect("pitch-gap is unsupported");
        let spans = f.strings.clone();
        let named: usize = spans.iter().map(|[a, b]| b - a).sum();
        assert!(named > 10, "{spans:?}");
        let flags = flags(&plan);
        let pi = plan
            .paths
            .iter()
            .position(|tp| Some(&tp.name) == f.part.as_ref())
            .unwrap();
        for [a, b] in spans {
            assert!(flags[pi][a..b].iter().all(|&x| x));
        }
    }
}
