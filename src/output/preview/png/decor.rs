//! What is drawn over the model: the turtles' markers and the findings'
//! rings, the recipe's name and stats, the colour legend.

use glam::DVec3;
use tiny_skia::{LineCap, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform};

use super::{Frame, DIM, GREY, RED, TEXT};
use crate::analyse::check::Severity;
use crate::analyse::stats::Stats;
use crate::base::format::hms;
use crate::output::preview::{colormap, fmt_value, text, ColorMode, Scene};

/// The turtles' markers and, in the findings mode, a ring round each finding.
pub(super) fn marks(
    pm: &mut Pixmap,
    scene: &Scene,
    frame: &Frame,
    bbox: (DVec3, DVec3),
    mode: ColorMode,
    rect: [f64; 4],
) {
    let mut paint = Paint {
        anti_alias: true,
        ..Paint::default()
    };
    // the turtles' markers (draw_turtle): a filled triangle each, pointing
    // along the heading, about 1/30 of the print's size
    if !scene.turtles.is_empty() {
        let (lo, hi) = bbox;
        let size = ((hi - lo).max_element() / 30.0).clamp(1.0, 20.0);
        paint.set_color_rgba8(255, 200, 40, 255);
        for m in &scene.turtles {
            let tri = super::Scene::turtle_triangle(m, size).map(|p| frame.pixel(p));
            let mut tb = PathBuilder::new();
            tb.move_to(tri[0].0 as f32, tri[0].1 as f32);
            tb.line_to(tri[1].0 as f32, tri[1].1 as f32);
            tb.line_to(tri[2].0 as f32, tri[2].1 as f32);
            tb.close();
            if let Some(path) = tb.finish() {
                pm.fill_path(
                    &path,
                    &paint,
                    tiny_skia::FillRule::Winding,
                    Transform::identity(),
                    None,
                );
            }
        }
    }
    if mode == ColorMode::Findings {
        paint.set_color_rgba8(255, 60, 50, 255);
        let r = (6.0 * (rect[3] - rect[1]) / 400.0).clamp(4.0, 24.0) as f32;
        let stroke = Stroke {
            line_cap: LineCap::Round,
            width: (r / 5.0).max(1.0),
            ..Stroke::default()
        };
        for p in &scene.marks {
            let (x, y) = frame.pixel(*p);
            if let Some(path) = PathBuilder::from_circle(x as f32, y as f32, r) {
                pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
            }
        }
    }
}

/// The legend's labels for `mode`.
fn legend_lines(scene: &Scene, mode: ColorMode) -> Vec<String> {
    let (lo, hi) = scene.range(mode);
    match mode {
        ColorMode::Plain => Vec::new(),
        ColorMode::Findings => {
            let n = scene.plan.findings.len();
            let mut v = vec![
                "findings".to_string(),
                format!("{n} finding{}", if n == 1 { "" } else { "s" }),
                "no finding".into(),
            ];
            let mut codes: Vec<&str> = Vec::new();
            for f in &scene.plan.findings {
                if !codes.contains(&f.code) {
                    codes.push(f.code);
                }
            }
            v.extend(codes.iter().map(|c| format!("· {c}")));
            v
        }
        _ => vec![
            mode.name().to_string(),
            mode.unit().to_string(),
            fmt_value(hi),
            fmt_value((lo + hi) / 2.0),
            fmt_value(lo),
        ],
    }
}

pub(super) fn legend_width(scene: &Scene, mode: ColorMode, ts: u32) -> u32 {
    let text = legend_lines(scene, mode)
        .iter()
        .map(|l| text::width(l, ts))
        .max()
        .unwrap_or(0);
    (22 * ts + text).max(text::width("cross-section", ts))
}

fn fill(pm: &mut Pixmap, x: f64, y: f64, w: f64, h: f64, rgb: [f32; 3]) {
    let mut paint = Paint::default();
    let [r, g, b] = rgb.map(|c| libm::round(c as f64 * 255.0) as u8);
    paint.set_color_rgba8(r, g, b, 255);
    paint.anti_alias = false;
    if let Some(rect) = Rect::from_xywh(x as f32, y as f32, w as f32, h as f32) {
        pm.fill_rect(rect, &paint, Transform::identity(), None);
    }
}

/// The colour scale (or the findings key) in the top-right corner.
pub(super) fn legend(pm: &mut Pixmap, scene: &Scene, mode: ColorMode, ts: u32) {
    let lines = legend_lines(scene, mode);
    if lines.is_empty() {
        return;
    }
    let s = ts as f64;
    let m = 12.0 * s;
    let x = pm.width() as f64 - legend_width(scene, mode, ts) as f64 - m;
    let line = 11.0 * s;
    let (xi, yi) = (x as i32, m as i32);
    text::draw(pm, xi, yi, ts, &lines[0], TEXT);
    if mode == ColorMode::Findings {
        let y0 = m + 1.6 * line;
        for (k, (label, rgb)) in [(&lines[1], RED), (&lines[2], GREY)].iter().enumerate() {
            let y = y0 + k as f64 * 1.4 * line;
            fill(pm, x, y, 12.0 * s, 8.0 * s, *rgb);
            text::draw(pm, (x + 16.0 * s) as i32, y as i32, ts, label, TEXT);
        }
        for (k, code) in lines[3..].iter().enumerate() {
            let y = y0 + (2.0 * 1.4 + k as f64) * line + 4.0 * s;
            text::draw(pm, xi, y as i32, ts, code, DIM);
        }
        return;
    }
    text::draw(pm, xi, (m + line) as i32, ts, &lines[1], DIM);
    let top = m + 2.6 * line;
    let bar_h = (pm.height() as f64 * 0.42).round().max(20.0);
    let rows = bar_h as usize;
    for r in 0..rows {
        // top row: the highest value
        let t = 1.0 - r as f64 / (rows - 1) as f64;
        fill(pm, x, top + r as f64, 14.0 * s, 1.0, colormap(t));
    }
    let lx = (x + 20.0 * s) as i32;
    let (lo, hi) = scene.range(mode);
    let ticks: Vec<(f64, &String)> = if hi > lo {
        vec![
            (top, &lines[2]),
            (top + bar_h / 2.0, &lines[3]),
            (top + bar_h, &lines[4]),
        ]
    } else {
        vec![(top + bar_h / 2.0, &lines[3])]
    };
    for (y, label) in ticks {
        text::draw(pm, lx, (y - 4.0 * s) as i32, ts, label, TEXT);
    }
}

/// The recipe's name and key stats in the top-left corner.
pub(super) fn header(pm: &mut Pixmap, st: &Stats, scene: &Scene, ts: u32) {
    let s = ts as f64;
    let m = 12.0 * s;
    let line = 11.0 * s;
    text::draw(pm, m as i32, m as i32, ts + 1, &st.name, TEXT);
    let size = [0, 1, 2].map(|k| st.bbox.max[k] - st.bbox.min[k]);
    let mut lines = vec![
        (
            format!("{:.1} × {:.1} × {:.1} mm", size[0], size[1], size[2]),
            TEXT,
        ),
        (
            format!(
                "filament {:.2} m, {:.1} g {}",
                st.filament_length_mm / 1000.0,
                st.filament_mass_g,
                st.material
            ),
            TEXT,
        ),
        (format!("time {}", hms(st.print_time_s)), TEXT),
    ];
    // the checks' summary, red with errors, amber with warnings, plain with notes
    let findings = &scene.plan.findings;
    if let Some(worst) = findings.iter().map(|f| f.severity).max() {
        let rgb = match worst {
            Severity::Error => [255, 110, 100],
            Severity::Warning => [255, 190, 90],
            Severity::Info => TEXT,
        };
        lines.push((crate::analyse::check::summary(findings), rgb));
    }
    let y0 = m + 8.0 * (ts + 1) as f64 + 6.0 * s;
    for (k, (l, rgb)) in lines.iter().enumerate() {
        text::draw(pm, m as i32, (y0 + k as f64 * line) as i32, ts, l, *rgb);
    }
}
