//! G-code thumbnails asked for by a printer profile, read back block by
//! block: PNGs of the sizes asked for, where PrusaSlicer looks for them, the
//! same bytes on every build.
//!
//! Past the public face: the blocks are read back with the writer's own
//! reader, `output::preview::thumbnail::parse`. It runs the binary too:
//! home beside `output::preview::thumbnail` for the reader's half, here for
//! the rest.

use crate::common::*;
use crate::preview::{ok, s};

/// Thumbnail blocks read back: (width, height, PNG bytes). `parse` checks
/// LEN, the line length of 78 and that every block is closed.
fn thumbnails(gcode: &str) -> Vec<(u32, u32, Vec<u8>)> {
    p3dp::output::preview::thumbnail::parse(gcode)
        .expect("thumbnail blocks as PrusaSlicer writes them")
        .into_iter()
        .map(|t| (t.width, t.height, t.bytes))
        .collect()
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
