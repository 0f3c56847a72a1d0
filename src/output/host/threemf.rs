//! Bambu Lab's `.gcode.3mf`: the only form Bambu printers take a print in
//! over the network. A zip (an OPC package) holding, as Bambu Studio writes
//! them:
//!
//! - `Metadata/plate_1.gcode` and `Metadata/plate_1.gcode.md5` (its MD5 in
//!   upper-case hex, which the printer checks);
//! - `Metadata/plate_1.png` (512 px), `plate_1_small.png` (128 px),
//!   `plate_no_light_1.png`, `top_1.png` and `pick_1.png` (the same view:
//!   p3dp has no separate top or pick render);
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

/// What the package says about the print besides its G-code.
#[derive(Clone, Debug, Default)]
pub(crate) struct Plate {
    /// Bambu's model id of the printer (`BL-P001` for an X1 Carbon…).
    pub printer_model_id: String,
    /// Nozzle diameter, mm.
    pub nozzle: f64,
    /// Planned time, s.
    pub seconds: f64,
    /// Filament, m, and its mass, g.
    pub metres: f64,
    /// Filament mass, g.
    pub grams: f64,
    /// Filament type (`PLA`…) and colour (`#RRGGBB`).
    pub filament_type: String,
    /// Filament colour, `#RRGGBB`.
    pub colour: String,
    /// Each object's name and its box on the bed, machine XY (x0, y0, x1,
    /// y1): a plate's objects, a recipe's parts.
    pub parts: Vec<(String, [f64; 4])>,
    /// The objects are printed one after another (a plate): Bambu's
    /// `is_seq_print`.
    pub sequential: bool,
    /// The first layer's height, mm.
    pub layer_height: f64,
    /// The plate's images: 512 px and 128 px PNGs.
    pub image: Vec<u8>,
    /// The small one.
    pub small: Vec<u8>,
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

/// `&`, `<`, `>`, `"` and `'` escaped for an XML attribute.
fn attr(s: &str) -> String {
    one_line(s)
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

const CONTENT_TYPES: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">
 <Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>
 <Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>
 <Default Extension="png" ContentType="image/png"/>
 <Default Extension="gcode" ContentType="text/x.gcode"/>
</Types>
"#;

const RELS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
 <Relationship Target="/3D/3dmodel.model" Id="rel-1" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
 <Relationship Target="/Metadata/plate_1.png" Id="rel-2" Type="http://schemas.openxmlformats.org/package/2006/relationships/metadata/thumbnail"/>
 <Relationship Target="/Metadata/plate_1.png" Id="rel-4" Type="http://schemas.bambulab.com/package/2021/cover-thumbnail-middle"/>
 <Relationship Target="/Metadata/plate_1_small.png" Id="rel-5" Type="http://schemas.bambulab.com/package/2021/cover-thumbnail-small"/>
</Relationships>
"#;

const GCODE_RELS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
 <Relationship Target="/Metadata/plate_1.gcode" Id="rel-1" Type="http://schemas.bambulab.com/package/2021/gcode"/>
</Relationships>
"#;

fn model() -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<model unit="millimeter" xml:lang="en-US" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" xmlns:BambuStudio="http://schemas.bambulab.com/package/2021">
 <metadata name="Application">p3dp-{}</metadata>
 <metadata name="BambuStudio:3mfVersion">1</metadata>
 <resources>
 </resources>
 <build/>
</model>
"#,
        env!("CARGO_PKG_VERSION")
    )
}

const MODEL_SETTINGS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<config>
  <plate>
    <metadata key="plater_id" value="1"/>
    <metadata key="plater_name" value=""/>
    <metadata key="locked" value="false"/>
    <metadata key="gcode_file" value="Metadata/plate_1.gcode"/>
    <metadata key="thumbnail_file" value="Metadata/plate_1.png"/>
    <metadata key="thumbnail_no_light_file" value="Metadata/plate_no_light_1.png"/>
    <metadata key="top_file" value="Metadata/top_1.png"/>
    <metadata key="pick_file" value="Metadata/pick_1.png"/>
    <metadata key="pattern_bbox_file" value="Metadata/plate_1.json"/>
  </plate>
</config>
"#;

/// `Metadata/slice_info.config`.
fn slice_info(p: &Plate) -> String {
    let mut s = format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<config>
  <header>
    <header_item key="X-BBL-Client-Type" value="slicer"/>
    <header_item key="X-BBL-Client-Version" value="p3dp-{}"/>
  </header>
  <plate>
    <metadata key="index" value="1"/>
    <metadata key="printer_model_id" value="{}"/>
    <metadata key="nozzle_diameters" value="{}"/>
    <metadata key="timelapse_type" value="0"/>
    <metadata key="prediction" value="{}"/>
    <metadata key="weight" value="{:.2}"/>
    <metadata key="outside" value="false"/>
    <metadata key="support_used" value="false"/>
    <metadata key="label_object_enabled" value="false"/>
"#,
        env!("CARGO_PKG_VERSION"),
        attr(&p.printer_model_id),
        p.nozzle,
        libm::round(p.seconds) as u64,
        p.grams
    );
    for (k, (name, _)) in p.parts.iter().enumerate() {
        s.push_str(&format!(
            "    <object identify_id=\"{}\" name=\"{}\" skipped=\"false\" />\n",
            k + 1,
            attr(name)
        ));
    }
    s.push_str(&format!(
        "    <filament id=\"1\" tray_info_idx=\"\" type=\"{}\" color=\"{}\" used_m=\"{:.2}\" used_g=\"{:.2}\" />\n  </plate>\n</config>\n",
        attr(&p.filament_type),
        attr(&p.colour),
        p.metres,
        p.grams
    ));
    s
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
    let (model, info, json) = (model(), slice_info(plate), plate_json(plate));
    let entries: [(&str, &[u8]); 14] = [
        ("[Content_Types].xml", CONTENT_TYPES.as_bytes()),
        ("_rels/.rels", RELS.as_bytes()),
        ("3D/3dmodel.model", model.as_bytes()),
        ("Metadata/plate_1.gcode", gcode),
        ("Metadata/plate_1.gcode.md5", md5.as_bytes()),
        ("Metadata/model_settings.config", MODEL_SETTINGS.as_bytes()),
        (
            "Metadata/_rels/model_settings.config.rels",
            GCODE_RELS.as_bytes(),
        ),
        ("Metadata/slice_info.config", info.as_bytes()),
        ("Metadata/plate_1.json", json.as_bytes()),
        ("Metadata/plate_1.png", &plate.image),
        ("Metadata/plate_no_light_1.png", &plate.image),
        ("Metadata/plate_1_small.png", &plate.small),
        ("Metadata/top_1.png", &plate.image),
        ("Metadata/pick_1.png", &plate.image),
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

    #[test]
    fn md5_of_a_known_text() {
        // RFC 1321's test suite
        assert_eq!(md5_upper(b"abc"), "900150983CD24FB0D6963F7D28E17F72");
    }
}
