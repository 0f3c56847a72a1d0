//! G-code thumbnails, in the form PrusaSlicer writes and Prusa and Creality
//! printers (and OctoPrint, Moonraker…) read: after the header comments, per
//! size asked for by the printer profile's `thumbnails: ["220x124", "16x16"]`,
//!
//! ```text
//! ; thumbnail begin 220x124 LEN
//! ; iVBORw0KGgo…            (base64 of a PNG, lines of at most 78 characters)
//! ; thumbnail end
//! ;
//! ```
//!
//! with LEN the length of the base64 text. The image is the iso view of the
//! model in filament colour on a transparent background; it is rendered from
//! the plan, so the G-code stays a function of the recipe (and its hash
//! deterministic).

use base64::Engine;

use super::{png, Scene, Size};
use crate::build::Plan;
use crate::error::Result;

/// Characters of base64 per comment line (PrusaSlicer's).
pub const LINE: usize = 78;

/// The sizes a profile's `thumbnails` list asks for; errors name `thumbnails[k]`.
pub fn sizes(list: &[String]) -> Result<Vec<Size>> {
    list.iter()
        .enumerate()
        .map(|(k, s)| Size::parse(s, &format!("thumbnails[{k}]")))
        .collect()
}

/// One thumbnail block for a PNG of `size`.
pub fn block(size: Size, png: &[u8]) -> String {
    let b64 = base64::engine::general_purpose::STANDARD.encode(png);
    let mut s = format!(
        "; thumbnail begin {}x{} {}\n",
        size.width,
        size.height,
        b64.len()
    );
    for chunk in b64.as_bytes().chunks(LINE) {
        s.push_str("; ");
        s.push_str(std::str::from_utf8(chunk).expect("base64 is ASCII"));
        s.push('\n');
    }
    s.push_str("; thumbnail end\n;\n");
    s
}

/// The thumbnail blocks `plan`'s printer asks for (empty when none).
pub fn blocks(plan: &Plan) -> Result<String> {
    let list = &plan.recipe.printer.thumbnails;
    if list.is_empty() {
        return Ok(String::new());
    }
    let sizes = sizes(list).map_err(|e| e.in_file(&plan.recipe.printer.name))?;
    let scene = Scene::new(plan);
    let mut out = String::new();
    for size in sizes {
        let pm = png::thumbnail(&scene, size);
        out.push_str(&block(size, &png::encode(&pm, true)));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reads blocks back: (width, height, PNG bytes).
    fn read(text: &str) -> Vec<(u32, u32, Vec<u8>)> {
        let mut out = Vec::new();
        let mut cur: Option<(u32, u32, usize, String)> = None;
        for line in text.lines() {
            if let Some(rest) = line.strip_prefix("; thumbnail begin ") {
                let (wh, len) = rest.split_once(' ').unwrap();
                let (w, h) = wh.split_once('x').unwrap();
                cur = Some((
                    w.parse().unwrap(),
                    h.parse().unwrap(),
                    len.parse().unwrap(),
                    String::new(),
                ));
            } else if line == "; thumbnail end" {
                let (w, h, len, b64) = cur.take().unwrap();
                assert_eq!(b64.len(), len);
                let png = base64::engine::general_purpose::STANDARD
                    .decode(b64)
                    .unwrap();
                out.push((w, h, png));
            } else if let Some((.., b64)) = cur.as_mut() {
                let data = line.strip_prefix("; ").unwrap();
                assert!(data.len() <= LINE);
                b64.push_str(data);
            }
        }
        out
    }

    #[test]
    fn blocks_read_back_as_pngs_of_their_size() {
        let size = Size {
            width: 40,
            height: 30,
        };
        let pm = tiny_skia::Pixmap::new(40, 30).unwrap();
        let text = block(size, &png::encode(&pm, true));
        assert!(text.starts_with("; thumbnail begin 40x30 "));
        assert!(text.lines().all(|l| l.len() <= 2 + LINE));
        let got = read(&text);
        assert_eq!(got.len(), 1);
        let img = image::load_from_memory(&got[0].2).unwrap();
        assert_eq!((img.width(), img.height()), (40, 30));
    }

    #[test]
    fn sizes_name_the_bad_entry() {
        let e = sizes(&["16x16".into(), "big".into()]).unwrap_err();
        assert!(e.to_string().contains("thumbnails[1]"), "{e}");
        assert_eq!(sizes(&["220x124".into()]).unwrap()[0].height, 124);
    }
}
