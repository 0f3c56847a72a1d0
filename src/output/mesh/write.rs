//! The mesh's files: binary STL, OBJ and 3MF, told apart by the extension.
//!
//! All three carry the vertices on the 1 µm grid, in recipe coordinates, mm.
//! STL repeats each triangle's corners (its format has no index) with the
//! facet normal; OBJ and 3MF list each vertex once and the triangles by
//! index. The 3MF is a zip (deflate, entry times fixed at 1980-01-01) of the
//! package's content types, its relationship and one model: one object with
//! the material's colour (`basematerials`).

use std::io::{self, BufWriter, Seek, Write};
use std::path::Path;

use super::Mesh;
use crate::analyse::plan::Plan;
use crate::base::error::{Error, Result};
use crate::base::xml::Writer;
use crate::machine::Material;
use crate::output::file::write_atomic;

/// A mesh file's format, by its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Format {
    /// Binary STL.
    Stl,
    /// 3D Manufacturing Format (a zip of XML).
    ThreeMf,
    /// Wavefront OBJ.
    Obj,
}

impl Format {
    /// The format of `path` by its extension.
    pub(crate) fn of(path: &Path) -> Result<Format> {
        match crate::output::file::extension(path).as_str() {
            "stl" => Ok(Format::Stl),
            "3mf" => Ok(Format::ThreeMf),
            "obj" => Ok(Format::Obj),
            _ => Err(Error::input(
                "-o",
                format!(
                    "cannot tell the mesh format of `{}`; expected a file name ending in .stl, .3mf or .obj",
                    path.display()
                ),
            )),
        }
    }

    /// The format's name for reports.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Format::Stl => "STL",
            Format::ThreeMf => "3MF",
            Format::Obj => "OBJ",
        }
    }
}

/// Builds the mesh of `plan` and writes it to `out` (format by extension,
/// atomically); returns the report line.
pub(crate) fn write(plan: &Plan, out: &Path) -> Result<String> {
    let format = Format::of(out)?;
    crate::analyse::check::within_reach(&plan.recipe, &plan.paths, plan.extent.points, "mesh")
        .map_err(|e| e.in_file(&plan.path))?;
    let mesh = super::of_plan(plan);
    let shown = out.display().to_string();
    let fail = |e: io::Error| Error::io_from(&shown, format!("cannot write the mesh: {e}"), &e);
    write_atomic(out, |f| match format {
        Format::Stl => stl(&mesh, &mut BufWriter::new(f)).map_err(fail),
        Format::Obj => obj(&mesh, &mut BufWriter::new(f)).map_err(fail),
        Format::ThreeMf => three_mf(&mesh, &plan.recipe.material, BufWriter::new(f)).map_err(fail),
    })?;
    let filament: f64 = plan.paths.iter().map(|tp| tp.volume()).sum();
    let size = std::fs::metadata(out).map(|m| m.len()).unwrap_or(0);
    Ok(format!(
        "mesh → {shown}: {} {}, {} triangles, {} vertices, {} beads ({} closed), volume {:.1} mm³ (filament {:.1} mm³), {} kB",
        format.name(),
        if format == Format::Stl { "binary" } else { "indexed" },
        mesh.triangles.len(),
        mesh.vertices.len(),
        mesh.beads,
        mesh.rings,
        mesh.volume(),
        filament,
        size.div_ceil(1024)
    ))
}

/// A coordinate in micrometres as millimetres with three decimals.
fn mm(out: &mut Vec<u8>, um: i64) {
    if um < 0 {
        out.push(b'-');
    }
    let a = um.unsigned_abs();
    let mut b = itoa::Buffer::new();
    out.extend_from_slice(b.format(a / 1000).as_bytes());
    let f = a % 1000;
    if f != 0 {
        out.push(b'.');
        out.extend_from_slice(format!("{f:03}").trim_end_matches('0').as_bytes());
    }
}

/// Writes a binary STL: an 80-byte header (never starting with `solid`),
/// the triangle count, then per triangle its unit normal and three corners
/// as little-endian f32 (exact: a micrometre count under 2^24 is an exact
/// f32, and only the final division rounds) and two zero bytes.
pub(crate) fn stl(mesh: &Mesh, w: &mut impl Write) -> io::Result<()> {
    let n = u32::try_from(mesh.triangles.len()).map_err(|_| {
        io::Error::other(format!(
            "{} triangles are more than binary STL can count (2^32 − 1); write .3mf or .obj",
            mesh.triangles.len()
        ))
    })?;
    let mut header = [b' '; 80];
    let text = b"p3dp mesh: binary STL, mm, recipe coordinates";
    header[..text.len()].copy_from_slice(text);
    w.write_all(&header)?;
    w.write_all(&n.to_le_bytes())?;
    let mut rec = [0u8; 50];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.point(i));
        let normal = (b - a).cross(c - a).normalize_or_zero();
        let vals = [normal, a, b, c];
        for (j, v) in vals.iter().enumerate() {
            for (i, x) in v.to_array().iter().enumerate() {
                let at = 12 * j + 4 * i;
                rec[at..at + 4].copy_from_slice(&(*x as f32).to_le_bytes());
            }
        }
        w.write_all(&rec)?;
    }
    w.flush()
}

/// Writes a Wavefront OBJ: `v x y z` per vertex (mm), `f a b c` per
/// triangle (1-based, counter-clockwise seen from outside).
pub(crate) fn obj(mesh: &Mesh, w: &mut impl Write) -> io::Result<()> {
    w.write_all(b"# p3dp mesh: one shell per bead, mm, recipe coordinates\n")?;
    let mut line = Vec::with_capacity(64);
    for v in &mesh.vertices {
        line.clear();
        line.push(b'v');
        for x in v {
            line.push(b' ');
            mm(&mut line, *x);
        }
        line.push(b'\n');
        w.write_all(&line)?;
    }
    let mut b = itoa::Buffer::new();
    for t in &mesh.triangles {
        line.clear();
        line.push(b'f');
        for i in t {
            line.push(b' ');
            line.extend_from_slice(b.format(u64::from(*i) + 1).as_bytes());
        }
        line.push(b'\n');
        w.write_all(&line)?;
    }
    w.flush()
}

/// `[Content_Types].xml` and `_rels/.rels`: the package's parts.
fn package_parts() -> Result<(String, String)> {
    let mut types = Writer::new(" ");
    let ns = "http://schemas.openxmlformats.org/package/2006/content-types";
    types.open(0, "Types", &[("xmlns", ns)])?;
    for (ext, ctype) in [
        (
            "rels",
            "application/vnd.openxmlformats-package.relationships+xml",
        ),
        (
            "model",
            "application/vnd.ms-package.3dmanufacturing-3dmodel+xml",
        ),
    ] {
        types.empty(1, "Default", &[("Extension", ext), ("ContentType", ctype)])?;
    }
    types.close(0, "Types");
    let mut rels = Writer::new(" ");
    let ns = "http://schemas.openxmlformats.org/package/2006/relationships";
    rels.open(0, "Relationships", &[("xmlns", ns)])?;
    rels.empty(
        1,
        "Relationship",
        &[
            ("Target", "/3D/3dmodel.model"),
            ("Id", "rel0"),
            (
                "Type",
                "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel",
            ),
        ],
    )?;
    rels.close(0, "Relationships");
    Ok((types.finish(), rels.finish()))
}

/// The model's head, up to its first vertex: the material (its name
/// refused if XML cannot hold it) and the object.
fn model_head(material: &Material) -> Result<String> {
    let [r, g, b] = material.color;
    let colour = format!("#{r:02X}{g:02X}{b:02X}FF");
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
        ],
    )?;
    w.leaf(1, "metadata", &[("name", "Application")], "p3dp")?;
    w.open(1, "resources", &[])?;
    w.open(2, "basematerials", &[("id", "1")])?;
    w.empty(
        3,
        "base",
        &[("name", &material.name), ("displaycolor", &colour)],
    )?;
    w.close(2, "basematerials");
    let object = [
        ("id", "2"),
        ("type", "model"),
        ("pid", "1"),
        ("pindex", "0"),
    ];
    w.open(2, "object", &object)?;
    w.open(3, "mesh", &[])?;
    w.open(4, "vertices", &[])?;
    Ok(w.finish())
}

/// Writes a 3MF package: the model's one object coloured by `material`.
pub(crate) fn three_mf(mesh: &Mesh, material: &Material, w: impl Write + Seek) -> io::Result<()> {
    let zerr = |e: zip::result::ZipError| match e {
        zip::result::ZipError::Io(e) => e,
        e => io::Error::other(e.to_string()),
    };
    let ioerr = |e: io::Error| e;
    // a model over 4 GiB needs zip64 (the estimate is generous)
    let big = mesh.vertices.len() as u64 * 64 + mesh.triangles.len() as u64 * 56 > 3 << 30;
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .last_modified_time(zip::DateTime::default())
        .unix_permissions(0o644);
    let xml = |e: Error| io::Error::other(e.message);
    let (types, rels) = package_parts().map_err(xml)?;
    let head = model_head(material).map_err(xml)?;
    let mut z = zip::ZipWriter::new(w);
    z.start_file("[Content_Types].xml", opts).map_err(zerr)?;
    z.write_all(types.as_bytes()).map_err(ioerr)?;
    z.start_file("_rels/.rels", opts).map_err(zerr)?;
    z.write_all(rels.as_bytes()).map_err(ioerr)?;
    // the model at deflate's level 3: its numbers compress nearly as well as
    // at the default level 6 (docs/performance.md) in a fraction of the time
    z.start_file(
        "3D/3dmodel.model",
        opts.large_file(big).compression_level(Some(3)),
    )
    .map_err(zerr)?;
    // the model's lines handed to the compressor in 64 KiB pieces: a line
    // at a time, flate2 clears its whole output buffer on every call
    {
        let z = &mut io::BufWriter::with_capacity(1 << 16, &mut z);
        z.write_all(head.as_bytes()).map_err(ioerr)?;
        let mut line = Vec::with_capacity(96);
        for v in &mesh.vertices {
            line.clear();
            line.extend_from_slice(b"     <vertex");
            for (name, x) in [b" x=\"", b" y=\"", b" z=\""].iter().zip(v) {
                line.extend_from_slice(*name);
                mm(&mut line, *x);
                line.push(b'"');
            }
            line.extend_from_slice(b"/>\n");
            z.write_all(&line).map_err(ioerr)?;
        }
        let mut middle = Writer::piece(" ");
        middle.close(4, "vertices");
        middle.open(4, "triangles", &[]).map_err(xml)?;
        z.write_all(middle.finish().as_bytes()).map_err(ioerr)?;
        let mut num = itoa::Buffer::new();
        for t in &mesh.triangles {
            line.clear();
            line.extend_from_slice(b"     <triangle");
            for (name, i) in [b" v1=\"", b" v2=\"", b" v3=\""].iter().zip(t) {
                line.extend_from_slice(*name);
                line.extend_from_slice(num.format(*i).as_bytes());
                line.push(b'"');
            }
            line.extend_from_slice(b"/>\n");
            z.write_all(&line).map_err(ioerr)?;
        }
        let mut tail = Writer::piece(" ");
        tail.close(4, "triangles");
        tail.close(3, "mesh");
        tail.close(2, "object");
        tail.close(1, "resources");
        tail.open(1, "build", &[]).map_err(xml)?;
        tail.empty(2, "item", &[("objectid", "2")]).map_err(xml)?;
        tail.close(1, "build");
        tail.close(0, "model");
        z.write_all(tail.finish().as_bytes()).map_err(ioerr)?;
        z.flush().map_err(ioerr)?;
    }
    let mut w = z.finish().map_err(zerr)?;
    w.flush().map_err(ioerr)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::toolpath::Toolpath;
    use glam::DVec3;

    fn bead() -> Mesh {
        let mut tp = Toolpath::new(DVec3::new(-1.0, 0.5, 0.2));
        tp.draw(DVec3::new(4.0, 0.5, 0.2), 0.12, 30.0);
        tp.draw(DVec3::new(4.0, 6.0, 0.2), 0.12, 30.0);
        let mut m = Mesh::default();
        super::super::add_path(&mut m, &tp, 0.2);
        m
    }

    #[test]
    fn millimetres_from_micrometres() {
        let mut s = Vec::new();
        for v in [0, 1, -1, 1500, -20000, 123456] {
            mm(&mut s, v);
            s.push(b' ');
        }
        assert_eq!(
            String::from_utf8(s).unwrap(),
            "0 0.001 -0.001 1.5 -20 123.456 "
        );
    }

    #[test]
    fn stl_is_the_triangles_with_their_normals() {
        let m = bead();
        let mut out = Vec::new();
        stl(&m, &mut out).unwrap();
        assert_eq!(out.len(), 84 + 50 * m.triangles.len());
        assert!(!out.starts_with(b"solid"));
        assert_eq!(
            u32::from_le_bytes(out[80..84].try_into().unwrap()) as usize,
            m.triangles.len()
        );
        let f = |at: usize| f32::from_le_bytes(out[at..at + 4].try_into().unwrap());
        // the first triangle: corners as the mesh has them, a unit normal
        // that agrees with their winding
        let [a, b, c] = m.triangles[0].map(|i| m.point(i));
        let rec = 84;
        let n = DVec3::new(f(rec) as f64, f(rec + 4) as f64, f(rec + 8) as f64);
        assert!((n.length() - 1.0).abs() < 1e-6);
        assert!(n.dot((b - a).cross(c - a)) > 0.0);
        assert_eq!(f(rec + 12), a.x as f32);
        assert_eq!(f(rec + 44), c.z as f32);
    }

    #[test]
    fn obj_lists_vertices_once_and_faces_by_index() {
        let m = bead();
        let mut out = Vec::new();
        obj(&m, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let vs: Vec<&str> = text.lines().filter(|l| l.starts_with("v ")).collect();
        let fs: Vec<&str> = text.lines().filter(|l| l.starts_with("f ")).collect();
        assert_eq!(vs.len(), m.vertices.len());
        assert_eq!(fs.len(), m.triangles.len());
        let t = m.triangles[3];
        assert_eq!(fs[3], format!("f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1));
        let v = m.point(t[0]);
        let parts: Vec<f64> = vs[t[0] as usize][2..]
            .split(' ')
            .map(|x| x.parse().unwrap())
            .collect();
        assert_eq!(parts, vec![v.x, v.y, v.z]);
    }

    #[test]
    fn three_mf_is_the_same_bytes_every_time_and_has_the_colour() {
        let m = bead();
        let mut mat = Material::built_in("petg").unwrap();
        mat.color = [0x12, 0xAB, 0xEF];
        mat.name = "a<b & \"c\"".into();
        let write = || {
            let mut cur = io::Cursor::new(Vec::new());
            three_mf(&m, &mat, &mut cur).unwrap();
            cur.into_inner()
        };
        let one = write();
        assert_eq!(one, write());
        assert!(one.starts_with(b"PK\x03\x04"));
        let mut z = zip::ZipArchive::new(io::Cursor::new(one)).unwrap();
        let names: Vec<String> = (0..z.len())
            .map(|i| z.by_index(i).unwrap().name().unwrap().to_string())
            .collect();
        for want in ["[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model"] {
            assert!(names.iter().any(|n| n == want), "{names:?}");
        }
        let mut model = String::new();
        io::Read::read_to_string(&mut z.by_name("3D/3dmodel.model").unwrap(), &mut model).unwrap();
        assert!(model
            .contains(r##"<base name="a&lt;b &amp; &quot;c&quot;" displaycolor="#12ABEFFF"/>"##));
        assert_eq!(model.matches("<vertex ").count(), m.vertices.len());
        assert_eq!(model.matches("<triangle ").count(), m.triangles.len());
    }

    #[test]
    fn a_hostile_material_name_reads_back_and_one_xml_forbids_is_refused() {
        let m = bead();
        let mut mat = Material::built_in("pla").unwrap();
        mat.name = "]]><x a='1'/>&amp; \u{202e} 🐢".into();
        let mut cur = io::Cursor::new(Vec::new());
        three_mf(&m, &mat, &mut cur).unwrap();
        let mut z = zip::ZipArchive::new(io::Cursor::new(cur.into_inner())).unwrap();
        for part in ["[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model"] {
            let mut text = String::new();
            io::Read::read_to_string(&mut z.by_name(part).unwrap(), &mut text).unwrap();
            let doc = roxmltree::Document::parse(&text).unwrap();
            if part == "3D/3dmodel.model" {
                let base = doc.descendants().find(|n| n.has_tag_name("base")).unwrap();
                assert_eq!(base.attribute("name"), Some(mat.name.as_str()));
                let count = |t: &str| doc.descendants().filter(|n| n.has_tag_name(t)).count();
                assert_eq!(count("vertex"), m.vertices.len());
                assert_eq!(count("triangle"), m.triangles.len());
            }
        }
        mat.name = "pla\u{fffe}".into();
        let e = three_mf(&m, &mat, io::Cursor::new(Vec::new())).unwrap_err();
        assert!(e.to_string().contains("U+FFFE"), "{e}");
    }

    #[test]
    fn formats_by_extension() {
        assert_eq!(Format::of(Path::new("a/b.STL")).unwrap(), Format::Stl);
        assert_eq!(Format::of(Path::new("b.3mf")).unwrap(), Format::ThreeMf);
        assert_eq!(Format::of(Path::new("b.obj")).unwrap(), Format::Obj);
        for bad in ["b.ply", "b", "b.stl.gz"] {
            let e = Format::of(Path::new(bad)).unwrap_err();
            assert!(e.to_string().contains(".stl, .3mf or .obj"), "{e}");
        }
    }
}
