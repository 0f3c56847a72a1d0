//! Bambu Lab's `.gcode.3mf`: the only form Bambu printers take a print in
//! over the network. A zip (an OPC package) holding, as Bambu Studio writes
//! them:
//!
//! - `Metadata/plate_1.gcode` and `Metadata/plate_1.gcode.md5` (its MD5 in
//!   upper-case hex, which the printer checks);
//! - `Metadata/plate_1.png` (512 px, the iso view), `plate_1_small.png`
//!   (128 px), `plate_no_light_1.png` (the iso view again), `top_1.png`
//!   (512 px, the whole bed from above) and `pick_1.png` (the same view,
//!   each object one flat colour that numbers it, its `identify_id` in
//!   `slice_info.config`: what the printer's screen picks objects by);
//! - `Metadata/slice_info.config` (printer model, nozzle, predicted time in
//!   s, weight in g, the parts, the filament), `Metadata/model_settings.config`
//!   and its relationships (which file is the plate's G-code), and
//!   `Metadata/plate_1.json` (the parts' boxes on the bed);
//! - `3D/3dmodel.model` with no mesh (the G-code is the print),
//!   `[Content_Types].xml` and `_rels/.rels`.
//!
//! Left out: `project_settings.config` (a slicer's whole configuration,
//! which Bambu Studio reads back and the printer does not need) and the
//! bed type, which only a slicer knows. The G-code inside carries Bambu's
//! header block and layer markers (see `output::gcode::metadata`). Every
//! entry has the same fixed date: the same print gives the same bytes.

use std::io::{self, Write};

use md5::Digest;

use crate::base::error::{Error, Result};
use crate::base::safe_text::one_line;
use crate::base::xml::Writer;

/// What the package says about the print besides its G-code.
#[derive(Clone, Debug, Default)]
pub(crate) struct Plate {
    /// Bambu's model id of the printer (`BL-P001` for an X1 Carbon…).
    pub(crate) printer_model_id: String,
    /// Nozzle diameter, mm.
    pub(crate) nozzle: f64,
    /// Planned time, s.
    pub(crate) seconds: f64,
    /// Filament, m, and its mass, g.
    pub(crate) metres: f64,
    /// Filament mass, g.
    pub(crate) grams: f64,
    /// Filament type (`PLA`…) and colour (`#RRGGBB`).
    pub(crate) filament_type: String,
    /// Filament colour, `#RRGGBB`.
    pub(crate) colour: String,
    /// Each object's name and its box on the bed, machine XY (x0, y0, x1,
    /// y1): a plate's objects, a recipe's parts.
    pub(crate) parts: Vec<(String, [f64; 4])>,
    /// The objects are printed one after another (a plate): Bambu's
    /// `is_seq_print`.
    pub(crate) sequential: bool,
    /// The first layer's height, mm.
    pub(crate) layer_height: f64,
    /// The plate's images: 512 px and 128 px PNGs.
    pub(crate) image: Vec<u8>,
    /// The small one.
    pub(crate) small: Vec<u8>,
    /// The bed seen from above (`top_1.png`).
    pub(crate) top: Vec<u8>,
    /// The objects from above, each a flat colour that numbers it
    /// (`pick_1.png`, what the printer's screen picks objects by).
    pub(crate) pick: Vec<u8>,
}

/// Bambu's model id for a profile's `printer_model` (its short names or the
/// id itself).
pub(crate) fn model_id(printer_model: &str) -> String {
    let key: String = printer_model
        .chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .collect::<String>()
        .to_ascii_uppercase();
    let id = match key.as_str() {
        "X1C" | "X1CARBON" | "BAMBULABX1CARBON" => "BL-P001",
        "X1" | "BAMBULABX1" => "BL-P002",
        "X1E" | "BAMBULABX1E" => "C13",
        "P1P" | "BAMBULABP1P" => "C11",
        "P1S" | "BAMBULABP1S" => "C12",
        "A1" | "BAMBULABA1" => "N2S",
        "A1M" | "A1MINI" | "BAMBULABA1MINI" => "N1",
        _ => return one_line(printer_model).into_owned(),
    };
    id.to_string()
}

/// The package's content types: `[Content_Types].xml`.
fn content_types() -> Result<String> {
    let mut w = Writer::new(" ");
    let ns = "http://schemas.openxmlformats.org/package/2006/content-types";
    w.open(0, "Types", &[("xmlns", ns)])?;
    for (ext, ctype) in [
        (
            "rels",
            "application/vnd.openxmlformats-package.relationships+xml",
        ),
        (
            "model",
            "application/vnd.ms-package.3dmanufacturing-3dmodel+xml",
        ),
        ("png", "image/png"),
        ("gcode", "text/x.gcode"),
    ] {
        w.empty(1, "Default", &[("Extension", ext), ("ContentType", ctype)])?;
    }
    w.close(0, "Types");
    Ok(w.finish())
}

/// A relationships part: each (target, id, type).
fn relationships(rels: &[(&str, &str, &str)]) -> Result<String> {
    let mut w = Writer::new(" ");
    let ns = "http://schemas.openxmlformats.org/package/2006/relationships";
    w.open(0, "Relationships", &[("xmlns", ns)])?;
    for (target, id, kind) in rels {
        w.empty(
            1,
            "Relationship",
            &[("Target", target), ("Id", id), ("Type", kind)],
        )?;
    }
    w.close(0, "Relationships");
    Ok(w.finish())
}

/// `_rels/.rels`: the model and the plate's pictures.
fn rels() -> Result<String> {
    let bambu = "http://schemas.bambulab.com/package/2021";
    relationships(&[
        (
            "/3D/3dmodel.model",
            "rel-1",
            "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel",
        ),
        (
            "/Metadata/plate_1.png",
            "rel-2",
            "http://schemas.openxmlformats.org/package/2006/relationships/metadata/thumbnail",
        ),
        (
            "/Metadata/plate_1.png",
            "rel-4",
            &format!("{bambu}/cover-thumbnail-middle"),
        ),
        (
            "/Metadata/plate_1_small.png",
            "rel-5",
            &format!("{bambu}/cover-thumbnail-small"),
        ),
    ])
}

/// `Metadata/_rels/model_settings.config.rels`: which file is the plate's
/// G-code.
fn gcode_rels() -> Result<String> {
    relationships(&[(
        "/Metadata/plate_1.gcode",
        "rel-1",
        "http://schemas.bambulab.com/package/2021/gcode",
    )])
}

/// `3D/3dmodel.model`: no mesh, the G-code is the print.
fn model() -> Result<String> {
    let mut w = Writer::new(" ");
    w.open(
        0,
        "model",
        &[
            ("unit", "millimeter"),
            ("xml:lang", "en-US"),
            (
                "xmlns",
                "http://schemas.microsoft.com/3dmanufacturing/core/2015/02",
            ),
            (
                "xmlns:BambuStudio",
                "http://schemas.bambulab.com/package/2021",
            ),
        ],
    )?;
    let app = format!("p3dp-{}", env!("CARGO_PKG_VERSION"));
    w.leaf(1, "metadata", &[("name", "Application")], &app)?;
    w.leaf(1, "metadata", &[("name", "BambuStudio:3mfVersion")], "1")?;
    w.open(1, "resources", &[])?;
    w.close(1, "resources");
    w.empty(1, "build", &[])?;
    w.close(0, "model");
    Ok(w.finish())
}

/// `Metadata/model_settings.config`: the plate's files.
fn model_settings() -> Result<String> {
    let mut w = Writer::new("  ");
    w.open(0, "config", &[])?;
    w.open(1, "plate", &[])?;
    for (key, value) in [
        ("plater_id", "1"),
        ("plater_name", ""),
        ("locked", "false"),
        ("gcode_file", "Metadata/plate_1.gcode"),
        ("thumbnail_file", "Metadata/plate_1.png"),
        ("thumbnail_no_light_file", "Metadata/plate_no_light_1.png"),
        ("top_file", "Metadata/top_1.png"),
        ("pick_file", "Metadata/pick_1.png"),
        ("pattern_bbox_file", "Metadata/plate_1.json"),
    ] {
        w.empty(2, "metadata", &[("key", key), ("value", value)])?;
    }
    w.close(1, "plate");
    w.close(0, "config");
    Ok(w.finish())
}

/// `Metadata/slice_info.config`: the printer, the estimate, the parts and
/// the filament. A name XML cannot hold (U+FFFE…) is refused by name.
fn slice_info(p: &Plate) -> Result<String> {
    let mut w = Writer::new("  ");
    let version = format!("p3dp-{}", env!("CARGO_PKG_VERSION"));
    w.open(0, "config", &[])?;
    w.open(1, "header", &[])?;
    for (key, value) in [
        ("X-BBL-Client-Type", "slicer"),
        ("X-BBL-Client-Version", version.as_str()),
    ] {
        w.empty(2, "header_item", &[("key", key), ("value", value)])?;
    }
    w.close(1, "header");
    w.open(1, "plate", &[])?;
    let (nozzle, seconds) = (
        p.nozzle.to_string(),
        (libm::round(p.seconds) as u64).to_string(),
    );
    let weight = format!("{:.2}", p.grams);
    for (key, value) in [
        ("index", "1"),
        ("printer_model_id", p.printer_model_id.as_str()),
        ("nozzle_diameters", nozzle.as_str()),
        ("timelapse_type", "0"),
        ("prediction", seconds.as_str()),
        ("weight", weight.as_str()),
        ("outside", "false"),
        ("support_used", "false"),
        ("label_object_enabled", "false"),
    ] {
        w.empty(2, "metadata", &[("key", key), ("value", value)])?;
    }
    for (k, (name, _)) in p.parts.iter().enumerate() {
        let id = (k + 1).to_string();
        w.empty(
            2,
            "object",
            &[("identify_id", &id), ("name", name), ("skipped", "false")],
        )?;
    }
    let (metres, grams) = (format!("{:.2}", p.metres), format!("{:.2}", p.grams));
    w.empty(
        2,
        "filament",
        &[
            ("id", "1"),
            ("tray_info_idx", ""),
            ("type", &p.filament_type),
            ("color", &p.colour),
            ("used_m", &metres),
            ("used_g", &grams),
        ],
    )?;
    w.close(1, "plate");
    w.close(0, "config");
    Ok(w.finish())
}

/// `Metadata/plate_1.json`: the parts' boxes on the bed.
fn plate_json(p: &Plate) -> String {
    let all = p.parts.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |a, (_, b)| {
            [
                a[0].min(b[0]),
                a[1].min(b[1]),
                a[2].max(b[2]),
                a[3].max(b[3]),
            ]
        },
    );
    let r = |v: f64| {
        if v.is_finite() {
            libm::round(v * 1000.0) / 1000.0
        } else {
            0.0
        }
    };
    let objects: Vec<serde_json::Value> = p
        .parts
        .iter()
        .enumerate()
        .map(|(k, (name, b))| {
            serde_json::json!({
                "area": r((b[2] - b[0]) * (b[3] - b[1])),
                "bbox": b.map(r),
                "id": k + 1,
                "layer_height": r(p.layer_height),
                "name": one_line(name),
            })
        })
        .collect();
    serde_json::json!({
        "bbox_all": all.map(r),
        "bbox_objects": objects,
        "filament_colors": [p.colour],
        "filament_ids": [0],
        "first_extruder": 0,
        "is_seq_print": p.sequential,
        "nozzle_diameter": p.nozzle,
        "version": 2,
    })
    .to_string()
}

/// The upper-case hex MD5 of `bytes`, as Bambu Studio writes it.
pub(crate) fn md5_upper(bytes: &[u8]) -> String {
    md5::Md5::digest(bytes)
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect()
}

/// The `.gcode.3mf` of `gcode` and `plate`.
pub(crate) fn encode(gcode: &[u8], plate: &Plate) -> Result<Vec<u8>> {
    let zerr =
        |e: zip::result::ZipError| Error::io("-o", format!("cannot write the .gcode.3mf: {e}"));
    let ioerr =
        |e: io::Error| Error::io_from("-o", format!("cannot write the .gcode.3mf: {e}"), &e);
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .last_modified_time(zip::DateTime::default())
        .unix_permissions(0o644);
    let mut z = zip::ZipWriter::new(io::Cursor::new(Vec::new()));
    let md5 = md5_upper(gcode);
    // a name XML cannot hold is the input's fault (exit 2), named
    let xml = |r: Result<String>| {
        r.map_err(|e| Error {
            message: format!("cannot write the .gcode.3mf: {}", e.message),
            ..e.in_file("-o")
        })
    };
    let (types, rels, gcode_rels) = (xml(content_types())?, xml(rels())?, xml(gcode_rels())?);
    let (model, settings, info) = (
        xml(model())?,
        xml(model_settings())?,
        xml(slice_info(plate))?,
    );
    let json = plate_json(plate);
    let entries: [(&str, &[u8]); 14] = [
        ("[Content_Types].xml", types.as_bytes()),
        ("_rels/.rels", rels.as_bytes()),
        ("3D/3dmodel.model", model.as_bytes()),
        ("Metadata/plate_1.gcode", gcode),
        ("Metadata/plate_1.gcode.md5", md5.as_bytes()),
        ("Metadata/model_settings.config", settings.as_bytes()),
        (
            "Metadata/_rels/model_settings.config.rels",
            gcode_rels.as_bytes(),
        ),
        ("Metadata/slice_info.config", info.as_bytes()),
        ("Metadata/plate_1.json", json.as_bytes()),
        ("Metadata/plate_1.png", &plate.image),
        ("Metadata/plate_no_light_1.png", &plate.image),
        ("Metadata/plate_1_small.png", &plate.small),
        ("Metadata/top_1.png", &plate.top),
        ("Metadata/pick_1.png", &plate.pick),
    ];
    for (name, bytes) in entries {
        z.start_file(name, opts).map_err(zerr)?;
        z.write_all(bytes).map_err(ioerr)?;
    }
    Ok(z.finish().map_err(zerr)?.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_package_holds_the_g_code_and_its_md5() {
        let plate = Plate {
            printer_model_id: model_id("X1C"),
            nozzle: 0.4,
            seconds: 600.4,
            metres: 1.5,
            grams: 4.5,
            filament_type: "PLA".into(),
            colour: "#FA8F29".into(),
            parts: vec![("a <b>".into(), [1.0, 2.0, 3.0, 4.0])],
            sequential: false,
            layer_height: 0.2,
            image: vec![1],
            small: vec![2],
            top: vec![3],
            pick: vec![4],
        };
        let gcode = b"; HEADER_BLOCK_START\nG28\n";
        let bytes = encode(gcode, &plate).unwrap();
        assert_eq!(bytes, encode(gcode, &plate).unwrap(), "the same bytes");
        let mut z = zip::ZipArchive::new(io::Cursor::new(bytes)).unwrap();
        let mut read = |n: &str| {
            let mut s = Vec::new();
            io::Read::read_to_end(&mut z.by_name(n).unwrap(), &mut s).unwrap();
            s
        };
        assert_eq!(read("Metadata/plate_1.gcode"), gcode);
        // each picture its own
        for (name, bytes) in [
            ("plate_1.png", 1),
            ("plate_no_light_1.png", 1),
            ("plate_1_small.png", 2),
            ("top_1.png", 3),
            ("pick_1.png", 4),
        ] {
            assert_eq!(read(&format!("Metadata/{name}")), [bytes], "{name}");
        }
        let md5 = String::from_utf8(read("Metadata/plate_1.gcode.md5")).unwrap();
        assert_eq!(md5, md5_upper(gcode));
        assert_eq!(md5.len(), 32);
        assert!(md5
            .chars()
            .all(|c| c.is_ascii_digit() || c.is_ascii_uppercase()));
        let info = String::from_utf8(read("Metadata/slice_info.config")).unwrap();
        assert!(
            info.contains(r#"key="printer_model_id" value="BL-P001""#),
            "{info}"
        );
        assert!(info.contains(r#"key="prediction" value="600""#));
        assert!(info.contains(r#"name="a &lt;b&gt;""#));
    }

    fn plate_named(names: &[&str]) -> Plate {
        Plate {
            printer_model_id: model_id("X1C"),
            nozzle: 0.4,
            seconds: 60.0,
            filament_type: "PLA".into(),
            colour: "#FA8F29".into(),
            parts: names
                .iter()
                .map(|n| (n.to_string(), [0.0, 0.0, 1.0, 1.0]))
                .collect(),
            ..Plate::default()
        }
    }

    /// Every XML entry of a package, parsed by a real XML reader.
    fn read_xml(bytes: Vec<u8>) -> Vec<(String, String)> {
        let mut z = zip::ZipArchive::new(io::Cursor::new(bytes)).unwrap();
        let names: Vec<String> = (0..z.len())
            .map(|i| z.by_index(i).unwrap().name().unwrap().to_string())
            .collect();
        let mut out = Vec::new();
        for n in names {
            if n.ends_with(".xml")
                || n.ends_with(".rels")
                || n.ends_with(".config")
                || n.ends_with(".model")
            {
                let mut s = String::new();
                io::Read::read_to_string(&mut z.by_name(&n).unwrap(), &mut s).unwrap();
                if let Err(e) = roxmltree::Document::parse(&s) {
                    panic!("{n} is not well-formed XML: {e}\n{s}");
                }
                out.push((n, s));
            }
        }
        out
    }

    #[test]
    fn hostile_part_names_read_back_whole_from_well_formed_xml() {
        let names = [
            "a <b> & \"c\" 'd'",
            "]]><!-- -->&amp;",
            "\u{202e}txt.exe \u{fffd} \u{10ffff} 🐢",
        ];
        let xml = read_xml(encode(b"G28\n", &plate_named(&names)).unwrap());
        assert_eq!(xml.len(), 6, "{xml:?}");
        let info = &xml
            .iter()
            .find(|(n, _)| n == "Metadata/slice_info.config")
            .unwrap()
            .1;
        let doc = roxmltree::Document::parse(info).unwrap();
        let read: Vec<&str> = doc
            .descendants()
            .filter(|n| n.has_tag_name("object"))
            .filter_map(|n| n.attribute("name"))
            .collect();
        assert_eq!(read, names);
    }

    #[test]
    fn names_xml_forbids_are_refused_by_name_not_written() {
        for bad in ["a\u{fffe}b", "a\u{ffff}", "x\u{1}y"] {
            let e = encode(b"G28\n", &plate_named(&["ok", bad])).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(
                e.message.contains("object name") && e.message.contains("XML 1.0 does not allow"),
                "{e}"
            );
        }
        let mut p = plate_named(&["ok"]);
        p.filament_type = "PLA\u{ffff}".into();
        let e = encode(b"G28\n", &p).unwrap_err();
        assert!(e.message.contains("filament type"), "{e}");
    }

    #[test]
    fn md5_of_a_known_text() {
        // RFC 1321's test suite
        assert_eq!(md5_upper(b"abc"), "900150983CD24FB0D6963F7D28E17F72");
    }
}
