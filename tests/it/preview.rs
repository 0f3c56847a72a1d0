//! Previews, through the real binary: `p3dp preview` to PNG and HTML,
//! `build --preview`, and bad thumbnail sizes (the thumbnails themselves are
//! checked in `internals::preview`).

use std::path::Path;

use crate::common::*;
use base64::Engine;

/// The PNG preview's background colour.
const BG: [u8; 3] = [30, 33, 39];

pub(crate) fn ok(out: &std::process::Output) -> String {
    assert!(
        out.status.success(),
        "exit {:?}\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

pub(crate) fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn is_model(px: [u8; 3]) -> bool {
    px.iter()
        .zip(BG)
        .map(|(a, b)| a.abs_diff(b) as u32)
        .sum::<u32>()
        > 24
}

/// `scale S px/mm, recipe (0, 0, 0) at pixel (X, Y)` from `preview`'s report.
fn frame(report: &str) -> (f64, f64, f64) {
    let num = |after: &str, until: char| -> f64 {
        let i = report
            .find(after)
            .unwrap_or_else(|| panic!("no `{after}` in {report}"))
            + after.len();
        report[i..]
            .split(until)
            .next()
            .unwrap()
            .trim()
            .parse()
            .unwrap()
    };
    let scale = num("scale ", ' ');
    let i = report.find("at pixel (").unwrap() + "at pixel (".len();
    let (x, y) = report[i..]
        .split(')')
        .next()
        .unwrap()
        .split_once(',')
        .unwrap();
    (scale, x.trim().parse().unwrap(), y.trim().parse().unwrap())
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path).unwrap().to_rgb8()
}

#[test]
fn png_is_the_size_asked_for_and_shows_a_model() {
    let dir = tmp("preview-size");
    let out = dir.join("sphere.png");
    ok(&p3dp(
        &dir,
        &[
            "preview",
            s(&recipe("sphere.yaml")),
            "-o",
            s(&out),
            "--size",
            "640x480",
        ],
    ));
    let img = rgb(&out);
    assert_eq!(img.dimensions(), (640, 480));
    let model = img.pixels().filter(|p| is_model(p.0)).count();
    assert!(
        model > 640 * 480 / 10,
        "only {model} pixels differ from the background"
    );
    let colours: std::collections::HashSet<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    assert!(colours.len() > 200, "{} colours: not shaded", colours.len());
    // default name and size: ./NAME.png, 1200 × 900
    ok(&p3dp(&dir, &["preview", s(&recipe("sphere.yaml"))]));
    assert_eq!(rgb(&dir.join("sphere.png")).dimensions(), (1200, 900));
}

#[test]
fn top_view_of_the_sphere_is_a_disc_where_the_bounding_box_says() {
    let dir = tmp("preview-top");
    let out = dir.join("top.png");
    let sphere = recipe("sphere.yaml");
    let report = ok(&p3dp(
        &dir,
        &[
            "preview",
            s(&sphere),
            "-o",
            s(&out),
            "--view",
            "top",
            "--size",
            "800x800",
            "--bare",
        ],
    ));
    let (scale, cx, cy) = frame(&report);
    ok(&p3dp(
        &dir,
        &[
            "build",
            s(&sphere),
            "-o",
            "sphere.gcode",
            "--stats-json",
            "stats.json",
        ],
    ));
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("stats.json")).unwrap()).unwrap();
    let bb = |k: &str, i: usize| stats["bbox"][k][i].as_f64().unwrap();
    // top view: x to the right, y up the image
    let (x0, x1) = (cx + scale * bb("min", 0), cx + scale * bb("max", 0));
    let (y0, y1) = (cy - scale * bb("max", 1), cy - scale * bb("min", 1));
    let img = rgb(&out);
    assert_eq!(img.dimensions(), (800, 800));
    // every model pixel inside the projected box (plus half a string and
    // anti-aliasing), and the box's edges reached within 2 %
    let slack = 0.6 * scale + 2.0;
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    for (x, y, p) in img.enumerate_pixels() {
        if is_model(p.0) {
            let (x, y) = (x as f64 + 0.5, y as f64 + 0.5);
            assert!(
                x >= x0 - slack && x <= x1 + slack && y >= y0 - slack && y <= y1 + slack,
                "model pixel ({x}, {y}) outside the box [{x0}, {x1}] × [{y0}, {y1}]"
            );
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
    }
    let tol = 0.02 * (x1 - x0);
    for (got, want) in [(lo.0, x0), (hi.0, x1), (lo.1, y0), (hi.1, y1)] {
        assert!(
            (got - want).abs() < tol,
            "model edge at {got}, box edge at {want}"
        );
    }
    // the sphere (radius 25) seen from above: from its centre, the first
    // background pixel in any direction is 25 mm away, within 2 %
    let want = 25.0 * scale;
    let mut radii = Vec::new();
    for k in 0..16 {
        let a = std::f64::consts::TAU * k as f64 / 16.0;
        let mut r = 0.0;
        while is_model(
            img.get_pixel((cx + r * a.cos()) as u32, (cy - r * a.sin()) as u32)
                .0,
        ) {
            r += 0.25;
        }
        radii.push(r);
        assert!(
            (r - want).abs() < 0.02 * want,
            "radius {r} px at {a:.2} rad, expected {want:.1}"
        );
    }
    // a disc, not a ring: filled inside
    let mut inside = 0;
    let mut filled = 0;
    let r_in = 0.95 * want;
    for (x, y, p) in img.enumerate_pixels() {
        let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
        if dx * dx + dy * dy < r_in * r_in {
            inside += 1;
            filled += is_model(p.0) as usize;
        }
    }
    assert!(
        filled as f64 > 0.99 * inside as f64,
        "{filled} of {inside} pixels of the disc drawn"
    );
}

#[test]
fn the_same_recipe_gives_the_same_bytes() {
    let dir = tmp("preview-determinism");
    for (r, a, b) in [
        ("globe.yaml", "a.png", "b.png"),
        ("sphere.yaml", "a.html", "b.html"),
    ] {
        let r = recipe(r);
        ok(&p3dp(
            &dir,
            &["preview", s(&r), "-o", a, "--size", "400x300"],
        ));
        ok(&p3dp(
            &dir,
            &["preview", s(&r), "-o", b, "--size", "400x300"],
        ));
        assert!(
            std::fs::read(dir.join(a)).unwrap() == std::fs::read(dir.join(b)).unwrap(),
            "{a} and {b} differ"
        );
    }
}

#[test]
fn the_thread_count_does_not_change_a_byte() {
    // the benchmark vase cut to 60,000 strings: several pieces of work, so
    // 2 and 4 threads share them out differently from 1
    let dir = tmp("preview-threads");
    let vase = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/vase-2m.yaml");
    for ext in ["png", "html"] {
        let out: Vec<Vec<u8>> = ["1", "2", "4"]
            .iter()
            .map(|j| {
                let name = format!("j{j}.{ext}");
                let args = [
                    "preview",
                    s(&vase),
                    "--set",
                    "height=6",
                    "-o",
                    &name,
                    "--size",
                    "500x400",
                    "-j",
                    j,
                ];
                ok(&p3dp(&dir, &args));
                std::fs::read(dir.join(&name)).unwrap()
            })
            .collect();
        assert!(out[0].len() > 1000, "{ext}: {} bytes", out[0].len());
        assert!(out[0] == out[1], "{ext}: 1 and 2 threads differ");
        assert!(out[0] == out[2], "{ext}: 1 and 4 threads differ");
    }
    // and the image shows the vase: a shaded model, not the background alone
    let img = rgb(&dir.join("j2.png"));
    let model = img.pixels().filter(|p| is_model(p.0)).count();
    assert!(model > 10_000, "{model} model pixels");
}

#[test]
fn findings_are_red_over_a_grey_model() {
    let dir = tmp("preview-findings");
    // the upper half of this wall needs too much flow (a warning)
    let fixture = root().join("tests/fixtures/preview-findings.yaml");
    let out = dir.join("f.png");
    ok(&p3dp(
        &dir,
        &[
            "preview",
            s(&fixture),
            "-o",
            s(&out),
            "--color",
            "findings",
            "--view",
            "front",
            "--bare",
        ],
    ));
    let img = rgb(&out);
    let red = |p: [u8; 3]| {
        p[0] > 120 && (p[1] as u32) < p[0] as u32 / 3 && (p[2] as u32) < p[0] as u32 / 3
    };
    let grey = |p: [u8; 3]| is_model(p) && p[0].abs_diff(p[1]) < 16 && p[1].abs_diff(p[2]) < 16;
    let (mut red_y, mut grey_y) = (Vec::new(), Vec::new());
    for (_, y, p) in img.enumerate_pixels() {
        if red(p.0) {
            red_y.push(y as f64);
        } else if grey(p.0) {
            grey_y.push(y as f64);
        }
    }
    assert!(
        red_y.len() > 1000 && grey_y.len() > 1000,
        "{} red, {} grey",
        red_y.len(),
        grey_y.len()
    );
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(
        mean(&red_y) < mean(&grey_y),
        "the red part is not the upper half"
    );
    // the viewer marks the same moves (kind 2): the upper half
    ok(&p3dp(&dir, &["preview", s(&fixture), "-o", "f.html"]));
    let data = viewer_data(&std::fs::read_to_string(dir.join("f.html")).unwrap());
    let kinds = decode(&data["kind"]);
    let flagged = kinds.iter().filter(|&&k| k == 2).count();
    let clean = kinds.iter().filter(|&&k| k == 1).count();
    assert!(
        flagged > 1000 && clean > 1000,
        "{flagged} flagged, {clean} clean"
    );
    // a clean recipe has no red
    ok(&p3dp(
        &dir,
        &[
            "preview",
            s(&recipe("sphere.yaml")),
            "-o",
            "clean.png",
            "--color",
            "findings",
            "--bare",
        ],
    ));
    let clean = rgb(&dir.join("clean.png"));
    assert_eq!(clean.pixels().filter(|p| red(p.0)).count(), 0);
    assert!(clean.pixels().filter(|p| grey(p.0)).count() > 1000);
}

/// The viewer's data: the JSON in `<script id="p3dp-data">`.
fn viewer_data(html: &str) -> serde_json::Value {
    let open = "<script type=\"application/json\" id=\"p3dp-data\">";
    let i = html.find(open).expect("the data element") + open.len();
    let j = i + html[i..].find("</script>").unwrap();
    serde_json::from_str(&html[i..j]).unwrap()
}

fn decode(v: &serde_json::Value) -> Vec<u8> {
    base64::engine::general_purpose::STANDARD
        .decode(v.as_str().unwrap())
        .unwrap()
}

#[test]
fn html_carries_every_move_of_the_gcode() {
    let dir = tmp("preview-html");
    for name in ["sphere.yaml", "olympic-rings.yaml"] {
        let r = recipe(name);
        ok(&p3dp(&dir, &["preview", s(&r), "-o", "v.html"]));
        ok(&p3dp(
            &dir,
            &["build", s(&r), "-o", "v.gcode", "--stats-json", "v.json"],
        ));
        let html = std::fs::read_to_string(dir.join("v.html")).unwrap();
        let gcode = std::fs::read_to_string(dir.join("v.gcode")).unwrap();
        // self-contained: nothing loaded from the network
        for bad in [
            "http://",
            "https://",
            "<script src",
            "<link",
            "@import",
            "url(",
        ] {
            assert!(!html.contains(bad), "{name}: the page contains `{bad}`");
        }
        // the G-code's moves: G0/G1 lines naming X, Y or Z (retractions move E only)
        let moves: Vec<[f64; 3]> = parse(&gcode)
            .moves
            .iter()
            .zip(
                gcode
                    .lines()
                    .filter(|l| l.starts_with("G0 ") || l.starts_with("G1 ")),
            )
            .filter(|(_, line)| {
                line.split_whitespace()
                    .any(|w| w.starts_with(['X', 'Y', 'Z']))
            })
            .map(|(m, _)| to_recipe(m.to))
            .collect();
        let data = viewer_data(&html);
        let pos = decode(&data["pos"]);
        assert_eq!(pos.len() % 12, 0);
        let points: Vec<[f32; 3]> = pos
            .chunks(12)
            .map(|c| [0, 1, 2].map(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap())))
            .collect();
        assert_eq!(points.len(), moves.len(), "{name}: points vs G-code moves");
        assert_eq!(data["points"].as_u64().unwrap() as usize, moves.len());
        for (p, m) in points.iter().zip(&moves) {
            for k in 0..3 {
                assert!((p[k] as f64 - m[k]).abs() < 1e-3, "{name}: {p:?} vs {m:?}");
            }
        }
        // one feed, cross-section, spacing (u16), normal (3 × i8) and kind per point
        let n = points.len();
        for (key, per) in [("feed", 2), ("cq", 2), ("hq", 2), ("nq", 3), ("kind", 1)] {
            assert_eq!(decode(&data[key]).len(), per * n, "{name}: {key}");
        }
        // extruding: the G1 moves with an E word (an extrusion in place, a G1
        // with E and no axis, is counted by the stats but is no point here)
        let g1e = gcode
            .lines()
            .filter(|l| l.starts_with("G1 "))
            .filter(|l| {
                let code = l.split(';').next().unwrap();
                code.contains(" E")
                    && code
                        .split_whitespace()
                        .any(|w| w.starts_with(['X', 'Y', 'Z']))
            })
            .count();
        let extruding = decode(&data["kind"])
            .iter()
            .filter(|&&k| k == 1 || k == 2)
            .count();
        assert_eq!(extruding, g1e, "{name}");
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("v.json")).unwrap()).unwrap();
        assert!(extruding as u64 <= stats["extrude_moves"].as_u64().unwrap());
    }
}

#[test]
fn the_globe_viewer_is_well_under_2_mb() {
    let dir = tmp("preview-globe-html");
    let report = ok(&p3dp(
        &dir,
        &["preview", s(&recipe("globe.yaml")), "-o", "g.html"],
    ));
    let len = std::fs::metadata(dir.join("g.html")).unwrap().len();
    assert!(len < 1_500_000, "{len} bytes; {report}");
}

#[test]
fn build_writes_its_preview_in_the_same_run() {
    let dir = tmp("preview-build");
    let sphere = recipe("sphere.yaml");
    let report = ok(&p3dp(
        &dir,
        &[
            "build",
            s(&sphere),
            "-o",
            "s.gcode",
            "--preview",
            "out/s.png",
        ],
    ));
    assert!(report.contains("preview → out/s.png"), "{report}");
    assert_eq!(rgb(&dir.join("out/s.png")).dimensions(), (1200, 900));
    assert!(dir.join("s.gcode").is_file());
    ok(&p3dp(
        &dir,
        &["build", s(&sphere), "-o", "t.gcode", "--preview", "t.html"],
    ));
    assert!(std::fs::read_to_string(dir.join("t.html"))
        .unwrap()
        .contains("p3dp-data"));
    // refused before anything is written: an unknown format, several recipes
    let out = p3dp(
        &dir,
        &["build", s(&sphere), "-o", "u.gcode", "--preview", "u.jpg"],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains(".png or .html"));
    assert!(!dir.join("u.gcode").exists());
    let cup = recipe("cup.yaml");
    let out = p3dp(
        &dir,
        &[
            "build",
            s(&sphere),
            s(&cup),
            "-o",
            "many/",
            "--preview",
            "m.png",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(!dir.join("many").exists());
}

#[test]
fn bad_preview_options_are_input_errors() {
    let dir = tmp("preview-bad");
    let sphere = recipe("sphere.yaml");
    for (args, said) in [
        (
            vec!["--view", "bottom"],
            "possible values: iso, top, front, side",
        ),
        (
            vec!["--color", "heat"],
            "possible values: speed, cross-section, flow, order, findings, plain",
        ),
        (vec!["--size", "0x10"], "not a size"),
        (vec!["--size", "big"], "not a size"),
        (vec!["-o", "x.jpg"], ".png or .html"),
    ] {
        let mut a = vec!["preview", s(&sphere)];
        a.extend(&args);
        let out = p3dp(&dir, &a);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(said), "{args:?}: {err}");
    }
    let out = p3dp(&dir, &["preview", "missing.yaml"]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "something was written"
    );
}

#[test]
fn a_bad_thumbnail_size_names_its_place() {
    let dir = tmp("preview-thumbnail-bad");
    let text = std::fs::read_to_string(root().join("tests/fixtures/thumbnails-printer.yaml"))
        .unwrap()
        .replace("[220x124, 16x16]", "[220x124, huge]");
    std::fs::write(dir.join("p.yaml"), text).unwrap();
    let out = p3dp(
        &dir,
        &[
            "build",
            s(&recipe("sphere.yaml")),
            "--printer",
            "p.yaml",
            "-o",
            "x.gcode",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("thumbnails[1]") && err.contains("`huge`"),
        "{err}"
    );
}

#[test]
fn draw_turtle_is_a_triangle_in_the_previews_and_nothing_in_the_g_code() {
    let dir = tmp("preview-turtle");
    let square = |mark: &str| {
        format!(
            "p3dp: 1\nname: sq\nparts:\n  - name: sq\n    primitive:\n      turtle:\n        start: {{position: [0, 0, 0.2]}}\n        program:\n          - repeat: 4\n            do: [{{forward: 20}}, {{left: 90}}]\n          - {{forward: 5}}\n          - {{left: 30}}\n{mark}"
        )
    };
    std::fs::write(dir.join("plain.yaml"), square("")).unwrap();
    std::fs::write(dir.join("marked.yaml"), square("          - draw_turtle\n")).unwrap();
    for f in ["plain", "marked"] {
        ok(&p3dp(
            &dir,
            &["build", &format!("{f}.yaml"), "-o", &format!("{f}.gcode")],
        ));
        ok(&p3dp(
            &dir,
            &[
                "preview",
                &format!("{f}.yaml"),
                "-o",
                &format!("{f}.png"),
                "--view",
                "top",
            ],
        ));
        ok(&p3dp(
            &dir,
            &["preview", &format!("{f}.yaml"), "-o", &format!("{f}.html")],
        ));
    }
    // the same G-code, byte for byte
    let g = |f: &str| std::fs::read(dir.join(f)).unwrap();
    assert_eq!(g("plain.gcode"), g("marked.gcode"));
    // the PNG: the marker's colour only where the turtle is drawn
    let yellow = |f: &str| {
        rgb(&dir.join(f))
            .pixels()
            .filter(|p| p.0 == [255, 200, 40])
            .count()
    };
    assert_eq!(yellow("plain.png"), 0);
    assert!(yellow("marked.png") > 20, "{}", yellow("marked.png"));
    // the viewer's data: the turtle where the program left it, heading 30°
    let data = |f: &str| viewer_data(&std::fs::read_to_string(dir.join(f)).unwrap());
    assert_eq!(data("plain.html")["turtles"], serde_json::json!([]));
    let t = &data("marked.html")["turtles"][0];
    let v = |i: usize, k: usize| t[i][k].as_f64().unwrap();
    assert!((v(0, 0) - 5.0).abs() < 1e-9 && v(0, 1).abs() < 1e-9 && (v(0, 2) - 0.2).abs() < 1e-9);
    assert!((v(1, 0) - 0.75f64.sqrt()).abs() < 1e-9 && (v(1, 1) - 0.5).abs() < 1e-9);
    assert!((v(2, 2) - 1.0).abs() < 1e-9);
}
