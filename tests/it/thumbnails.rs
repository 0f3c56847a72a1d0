//! G-code thumbnails asked for by a printer profile, read back block by
//! block: PNGs of the sizes asked for, where PrusaSlicer looks for them, the
//! same bytes on every build.
//!
//! The blocks are read back here, independently of the writer: each
//! `; thumbnail begin WxH LEN` block's base64 lines (at most 78 characters),
//! LEN the count of base64 characters, closed by `; thumbnail end`.

use base64::Engine;

use crate::common::*;

/// Thumbnail blocks read back: (width, height, PNG bytes); every block
/// closed, its LEN the base64 it holds, at most 78 of them a line.
fn thumbnails(gcode: &str) -> Vec<(u32, u32, Vec<u8>)> {
    let mut blocks = Vec::new();
    let mut lines = gcode.lines();
    while let Some(l) = lines.next() {
        let Some(head) = l.strip_prefix("; thumbnail begin ") else {
            continue;
        };
        let (size, len) = head.split_once(' ').expect("WxH LEN");
        let (w, h) = size.split_once('x').expect("WxH");
        let mut text = String::new();
        for l in lines.by_ref() {
            if l == "; thumbnail end" {
                break;
            }
            let data = l.strip_prefix("; ").expect("a comment line");
            assert!(data.len() <= 78, "{} characters on a line", data.len());
            text.push_str(data);
        }
        assert_eq!(text.len(), len.parse::<usize>().unwrap(), "LEN");
        let png = base64::engine::general_purpose::STANDARD
            .decode(&text)
            .unwrap();
        blocks.push((w.parse().unwrap(), h.parse().unwrap(), png));
    }
    blocks
}

fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn gcode_thumbnails_parse_back_as_pngs_of_the_sizes_asked_for() {
    let dir = tmp("preview-thumbnails");
    let profile = root().join("tests/fixtures/thumbnails-printer.yaml");
    let sphere = recipe("sphere.yaml");
    let args = [
        "build",
        s(&sphere),
        "-o",
        "t.gcode",
        "--printer",
        s(&profile),
    ];
    ok(&p3dp(&dir, &args));
    let gcode = std::fs::read_to_string(dir.join("t.gcode")).unwrap();
    let blocks = thumbnails(&gcode);
    let sizes: Vec<(u32, u32)> = blocks.iter().map(|b| (b.0, b.1)).collect();
    assert_eq!(sizes, [(220, 124), (16, 16)]);
    for (w, h, png) in &blocks {
        let img = image::load_from_memory(png).unwrap().to_rgba8();
        assert_eq!(img.dimensions(), (*w, *h));
        let drawn = img.pixels().filter(|p| p.0[3] > 0).count();
        assert!(
            drawn > (*w * *h / 10) as usize,
            "{w}x{h}: {drawn} pixels drawn"
        );
    }
    // after the header comments, before the start G-code, and still parsed as G-code
    let begin = gcode.find("; thumbnail begin").unwrap();
    assert!(begin > gcode.find("; recipe: sphere").unwrap());
    assert!(begin < gcode.find("M140").unwrap());
    assert!(!parse(&gcode).moves.is_empty());
    // deterministic: the hash is that of the bytes built, twice
    ok(&p3dp(
        &dir,
        &[
            "build",
            s(&sphere),
            "-o",
            "u.gcode",
            "--printer",
            s(&profile),
        ],
    ));
    assert!(
        std::fs::read(dir.join("t.gcode")).unwrap() == std::fs::read(dir.join("u.gcode")).unwrap()
    );
    let hash = ok(&p3dp(&dir, &["hash", s(&sphere), "--printer", s(&profile)]));
    use sha2::Digest;
    let digest: String = sha2::Sha256::digest(gcode.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert!(hash.starts_with(&digest), "{hash} vs {digest}");
    // a profile may ask for none
    let none = dir.join("none.yaml");
    std::fs::write(&none, "inherits: generic-220\nthumbnails: []\n").unwrap();
    ok(&p3dp(
        &dir,
        &[
            "build",
            s(&sphere),
            "-o",
            "plain.gcode",
            "--printer",
            s(&none),
        ],
    ));
    let plain = std::fs::read_to_string(dir.join("plain.gcode")).unwrap();
    assert!(!plain.contains("thumbnail"));
}

/// Every thumbnail block of `gcode`, PNG, QOI and JPG alike (PrusaSlicer's
/// `; thumbnail begin`, `; thumbnail_QOI begin`, `; thumbnail_JPG begin`):
/// `WxH/FORMAT` as a profile names it, each block's image decoded by its
/// format's own decoder and found of the size its header says.
fn every_block(gcode: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut lines = gcode.lines();
    while let Some(l) = lines.next() {
        let Some((tag, head)) = ["thumbnail", "thumbnail_QOI", "thumbnail_JPG"]
            .into_iter()
            .find_map(|t| Some((t, l.strip_prefix(&format!("; {t} begin "))?)))
        else {
            continue;
        };
        let (size, _) = head.split_once(' ').expect("WxH LEN");
        let (w, h) = size.split_once('x').expect("WxH");
        let (w, h): (u32, u32) = (w.parse().unwrap(), h.parse().unwrap());
        let end = format!("; {tag} end");
        let b64: String = lines
            .by_ref()
            .take_while(|l| *l != end)
            .map(|l| l.strip_prefix("; ").expect("a comment line"))
            .collect();
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(&b64)
            .unwrap();
        let (format, dims) = match tag {
            "thumbnail_QOI" => {
                let (header, _) = qoi::decode_to_vec(&bytes).expect("a QOI image");
                ("QOI", (header.width, header.height))
            }
            "thumbnail_JPG" => {
                let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Jpeg);
                ("JPG", img.expect("a JPEG").to_rgba8().dimensions())
            }
            _ => {
                let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png);
                ("PNG", img.expect("a PNG").to_rgba8().dimensions())
            }
        };
        assert_eq!(dims, (w, h), "{tag} {w}x{h}");
        out.push(format!("{w}x{h}/{format}"));
    }
    out
}

/// Thumbnails are on by default, in the formats and sizes the maker's own
/// slicer writes for that printer: PrusaSlicer's newest Prusa bundle for
/// the Prusa printers, Creality Print's presets for Creality's, OrcaSlicer's
/// default where a printer's presets name none (the Voron, the Rostock and
/// the generic printer), none in a Bambu printer's G-code (Bambu Studio puts
/// the pictures in the .gcode.3mf); each block decodes to its size.
#[test]
fn every_built_in_writes_its_makers_thumbnails() {
    let orca = ["48x48/PNG", "300x300/PNG"];
    let prusa = ["16x16/QOI", "313x173/QOI", "480x240/QOI", "380x285/PNG"];
    let creality = ["96x96/PNG", "300x300/PNG"];
    #[rustfmt::skip]
    let want: &[(&str, &[&str])] = &[
        ("generic-220", &orca),
        ("ender3", &["300x300/PNG"]),
        ("prusa-mk3s", &["160x120/PNG"]),
        ("prusa-mk4", &prusa),
        ("voron-350", &orca),
        ("rostock-max", &orca),
        ("bambu-x1c", &[]),
        ("bambu-p1s", &[]),
        ("bambu-a1", &[]),
        ("bambu-a1-mini", &[]),
        ("prusa-mk4s", &prusa),
        ("prusa-core-one", &prusa),
        ("prusa-mini", &["16x16/QOI", "220x124/QOI", "200x240/QOI", "380x285/PNG"]),
        ("creality-k1", &creality),
        ("ender3-v3", &creality),
    ];
    assert_eq!(
        want.len(),
        p3dp::testing::printers().len(),
        "every built-in"
    );
    let dir = tmp("thumbnails-built-ins");
    let ring = dir.join("ring.yaml");
    let yaml = "p3dp: 1\nname: ring\nmaterial: pla\nparts:\n  - primitive: {helix: {radius: 15, height: 3, pitch: 0.3, center: [0, 0, 0.3]}}\n";
    std::fs::write(&ring, yaml).unwrap();
    for (printer, sizes) in want {
        let out = format!("{printer}.gcode");
        ok(&p3dp(
            &dir,
            &["build", s(&ring), "--printer", printer, "-o", &out],
        ));
        let gcode = std::fs::read_to_string(dir.join(&out)).unwrap();
        assert_eq!(every_block(&gcode), *sizes, "{printer}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

fn ok(out: &std::process::Output) -> String {
    assert!(
        out.status.success(),
        "exit {:?}\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

/// A thumbnail is the print as the printer shows it, not the checks' view
/// of it: the G-code's bytes are the same whether a warning was found, was
/// allowed or the checks were not asked for, on one thread and on two (a
/// thumbnail drawn from the findings made the G-code wait for the checks,
/// and changed with an `--allow`).
#[test]
fn thumbnails_do_not_depend_on_the_findings() {
    let dir = tmp("thumbnails-findings");
    let bridge = root().join("tests/checks/long-bridge.yaml");
    let build = |name: &str, extra: &[&str]| -> Vec<u8> {
        let mut args = vec!["build", s(&bridge), "-o", name];
        args.extend_from_slice(extra);
        ok(&p3dp(&dir, &args));
        std::fs::read(dir.join(name)).unwrap()
    };
    let found = build("found.gcode", &["-j", "2"]);
    let text = String::from_utf8_lossy(&found);
    assert_eq!(every_block(&text), ["48x48/PNG", "300x300/PNG"]);
    assert!(found == build("allowed.gcode", &["-j", "2", "--allow", "bridge"]));
    assert!(found == build("one-thread.gcode", &["-j", "1"]));
    let _ = std::fs::remove_dir_all(&dir);
}
