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
    // the built-in profile asks for none
    ok(&p3dp(&dir, &["build", s(&sphere), "-o", "plain.gcode"]));
    let plain = std::fs::read_to_string(dir.join("plain.gcode")).unwrap();
    assert!(!plain.contains("thumbnail"));
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
