//! `p3dp mesh` on real recipes (the sphere, the globe, the plate): the STL
//! read back is a set of closed, consistently oriented shells whose volume
//! is the filament volume of the stats and whose box is the toolpath's grown
//! by half a bead; PrusaSlicer (`prusa-slicer --info`, when installed; CI
//! installs it and fails without it) calls it manifold with the same volume.
//! The 3MF and OBJ carry the same mesh, and every format is the same bytes
//! on every run (each format made twice for the sphere; the globe and the
//! plate, ten times its triangles, are meshed once per shape check).

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use crate::common::{p3dp, recipe, tmp};

/// A binary STL read back: its triangles' corners.
fn read_stl(path: &Path) -> Vec<[[f32; 3]; 3]> {
    let b = std::fs::read(path).unwrap();
    assert!(!b.starts_with(b"solid"), "binary STL");
    let n = u32::from_le_bytes(b[80..84].try_into().unwrap()) as usize;
    assert_eq!(b.len(), 84 + 50 * n, "size of {n} triangles");
    let f = |at: usize| f32::from_le_bytes(b[at..at + 4].try_into().unwrap());
    (0..n)
        .map(|t| {
            let at = 84 + 50 * t + 12;
            [0, 1, 2].map(|v| [0, 1, 2].map(|i| f(at + 12 * v + 4 * i)))
        })
        .collect()
}

/// Volume (Σ signed tetrahedra, a·(b × c)/6) and bounding box.
fn measure(tris: &[[[f32; 3]; 3]]) -> (f64, [f64; 3], [f64; 3]) {
    let mut vol = 0.0;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for t in tris {
        let p = t.map(|v| v.map(f64::from));
        let [a, b, c] = p;
        let cross = [
            b[1] * c[2] - b[2] * c[1],
            b[2] * c[0] - b[0] * c[2],
            b[0] * c[1] - b[1] * c[0],
        ];
        vol += (a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2]) / 6.0;
        for v in p {
            for i in 0..3 {
                lo[i] = lo[i].min(v[i]);
                hi[i] = hi[i].max(v[i]);
            }
        }
    }
    (vol, lo, hi)
}

/// The OBJ's faces by vertex index: how many edges are not used exactly
/// once each way (0: closed, consistently oriented shells), and how many
/// faces and vertices it has.
fn obj_edges(text: &str) -> (usize, usize, usize) {
    // each directed edge a → b as one number, sorted: an edge is good when
    // it appears once and so does its reverse b → a
    let mut edges: Vec<u64> = Vec::new();
    let (mut nv, mut nf) = (0, 0);
    for l in text.lines() {
        if l.starts_with("v ") {
            nv += 1;
        } else if let Some(f) = l.strip_prefix("f ") {
            nf += 1;
            let i: Vec<u32> = f.split(' ').map(|x| x.parse().unwrap()).collect();
            assert_eq!(i.len(), 3, "{l}");
            assert!(
                i[0] != i[1] && i[1] != i[2] && i[0] != i[2],
                "degenerate {l}"
            );
            for e in 0..3 {
                edges.push(u64::from(i[e]) << 32 | u64::from(i[(e + 1) % 3]));
            }
        }
    }
    edges.sort_unstable();
    // whether `e` is in the list exactly once
    let once = |e: u64| {
        let i = edges.partition_point(|&x| x < e);
        edges.get(i) == Some(&e) && edges.get(i + 1) != Some(&e)
    };
    let bad = edges
        .chunk_by(|a, b| a == b)
        .filter(|same| same.len() != 1 || !once(same[0].rotate_left(32))) // b → a
        .count();
    (bad, nf, nv)
}

/// `prusa-slicer --info FILE`'s `key = value` lines, or `None` when it is not
/// installed (a failure under CI, which installs it).
fn prusa_info(file: &Path) -> Option<HashMap<String, String>> {
    let out = match Command::new("prusa-slicer")
        .arg("--info")
        .arg(file)
        .output()
    {
        Ok(o) => o,
        Err(_) => {
            assert!(
                std::env::var_os("CI").is_none(),
                "prusa-slicer is not installed, and CI must run it (.ci/run installs it)"
            );
            eprintln!("note: prusa-slicer is not installed; its manifold check is skipped");
            return None;
        }
    };
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "prusa-slicer --info failed:\n{text}");
    Some(
        text.lines()
            .filter_map(|l| l.split_once(" = "))
            .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
            .collect(),
    )
}

/// The stats' filament volume (mm³) and the toolpath's box.
fn stats(dir: &Path, name: &str) -> (f64, [f64; 3], [f64; 3]) {
    let r = recipe(&format!("{name}.yaml"));
    let out = p3dp(
        dir,
        &[
            "build",
            r.to_str().unwrap(),
            "-o",
            "x.gcode",
            "--stats-json",
            "x.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("x.json")).unwrap()).unwrap();
    let v3 = |k: &str| {
        let a = j["bbox"][k].as_array().unwrap();
        [0, 1, 2].map(|i| a[i].as_f64().unwrap())
    };
    (
        j["filament_volume_mm3"].as_f64().unwrap(),
        v3("min"),
        v3("max"),
    )
}

/// How much of [`check_recipe`] a recipe gets.
#[derive(Clone, Copy, PartialEq)]
enum Depth {
    /// Every format, each made twice (the same bytes), PrusaSlicer on the
    /// STL and the 3MF.
    Full,
    /// The STL and the OBJ (the mesh's shape: closed, its volume, its box),
    /// PrusaSlicer on the STL: the formats' writers are the sphere's.
    Shape,
}

/// Meshes `name` (every format with [`Depth::Full`]) and checks the STL;
/// returns the triangles.
fn check_recipe(name: &str, max_half_bead: f64, depth: Depth) -> usize {
    let dir = tmp(&format!("mesh-{name}"));
    let (filament, bmin, bmax) = stats(&dir, name);
    let r = recipe(&format!("{name}.yaml"));
    let r = r.to_str().unwrap();
    let formats: &[&str] = match depth {
        Depth::Full => &["m.stl", "m.3mf", "m.obj"],
        Depth::Shape => &["m.stl", "m.obj"],
    };
    for f in formats {
        let out = p3dp(&dir, &["mesh", r, "-o", f]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let line = String::from_utf8_lossy(&out.stdout);
        assert!(line.starts_with(&format!("mesh → {f}: ")), "{line}");
        if depth == Depth::Full {
            // deterministic: the same bytes again
            let first = std::fs::read(dir.join(f)).unwrap();
            let again = p3dp(&dir, &["mesh", r, "-o", &format!("again-{f}")]);
            assert!(again.status.success());
            assert!(
                first == std::fs::read(dir.join(format!("again-{f}"))).unwrap(),
                "{name} {f}: not the same bytes twice"
            );
        }
    }
    let tris = read_stl(&dir.join("m.stl"));
    let (vol, lo, hi) = measure(&tris);
    // closed, consistently oriented shells: in the OBJ, whose vertices are
    // shared by index within a bead, every edge is used once each way
    let obj = std::fs::read_to_string(dir.join("m.obj")).unwrap();
    let (bad_edges, nf, nv) = obj_edges(&obj);
    assert_eq!(
        bad_edges, 0,
        "{name}: edges not shared by two facing triangles"
    );
    assert_eq!(nf, tris.len());
    // 8 vertices a ring, 16 triangles between rings: about 2 triangles a vertex
    assert!(
        nv * 2 <= nf + nf / 10,
        "{name}: {nv} vertices for {nf} faces"
    );
    // volume: the filament's, up to joints and the 1 µm grid
    assert!(
        (vol - filament).abs() < 0.01 * filament,
        "{name}: mesh {vol} mm³ vs filament {filament} mm³"
    );
    // the box: the toolpath's grown by half a bead on every side
    for i in 0..3 {
        let (below, above) = (bmin[i] - lo[i], hi[i] - bmax[i]);
        for g in [below, above] {
            assert!(
                g > 0.05 && g <= max_half_bead,
                "{name} axis {i}: grown by {below:.3} below, {above:.3} above (toolpath {bmin:?}–{bmax:?})"
            );
        }
    }
    // the globe's file stays under 50 MB
    let size = std::fs::metadata(dir.join("m.stl")).unwrap().len();
    assert!(size < 50_000_000, "{name}: {size} bytes");
    // PrusaSlicer's own check, on the STL (and the 3MF)
    for f in &formats[..formats.len() - 1] {
        if let Some(info) = prusa_info(&dir.join(f)) {
            assert_eq!(
                info.get("manifold").map(String::as_str),
                Some("yes"),
                "{name} {f}: {info:?}"
            );
            assert_eq!(
                info.get("number_of_facets").map(String::as_str),
                Some(tris.len().to_string().as_str()),
                "{name} {f}"
            );
            let pv: f64 = info["volume"].parse().unwrap();
            assert!(
                (pv - filament).abs() < 0.1 * filament,
                "{name} {f}: PrusaSlicer's volume {pv} vs filament {filament}"
            );
            assert!((pv - vol).abs() < 1e-3 * vol, "{name} {f}: {pv} vs {vol}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    tris.len()
}

#[test]
fn sphere_mesh() {
    // 14 685 extruding strings, 16 side triangles each, and the caps
    let n = check_recipe("sphere", 0.45, Depth::Full);
    assert!((16 * 14_000..16 * 15_000 + 10_000).contains(&n), "{n}");
}

#[test]
fn globe_mesh() {
    let n = check_recipe("globe", 0.45, Depth::Shape);
    assert!((16 * 44_000..16 * 48_500 + 10_000).contains(&n), "{n}");
}

#[test]
fn plate_mesh() {
    let n = check_recipe("plate", 0.45, Depth::Shape);
    assert!((16 * 38_000..16 * 39_500 + 10_000).contains(&n), "{n}");
}

#[test]
fn the_3mf_carries_the_material_colour() {
    let dir = tmp("mesh-colour");
    let yaml = "p3dp: 1\nname: ring\nmaterial: {name: green-petg, density: 1.27, nozzle_temp: 235, bed_temp: 80, color: \"#2e7d32\"}\nparts:\n  - name: ring\n    primitive:\n      helix: {radius: 10, height: 3, pitch: 0.3}\n";
    std::fs::write(dir.join("ring.yaml"), yaml).unwrap();
    let out = p3dp(&dir, &["mesh", "ring.yaml", "-o", "ring.3mf"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(dir.join("ring.3mf")).unwrap();
    let mut z = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
    let mut model = String::new();
    std::io::Read::read_to_string(&mut z.by_name("3D/3dmodel.model").unwrap(), &mut model).unwrap();
    assert!(
        model.contains(r##"<base name="green-petg" displaycolor="#2E7D32FF"/>"##),
        "{}",
        &model[..600.min(model.len())]
    );
    // a colour that is not one names the key
    std::fs::write(dir.join("bad.yaml"), yaml.replace("#2e7d32", "green")).unwrap();
    let out = p3dp(&dir, &["mesh", "bad.yaml", "-o", "bad.3mf"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("material.color") && err.contains("#rrggbb"),
        "{err}"
    );
    assert!(!dir.join("bad.3mf").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_invocations_exit_2_and_write_nothing() {
    let dir = tmp("mesh-bad");
    let r = recipe("sphere.yaml");
    let r = r.to_str().unwrap();
    // an unknown extension
    let out = p3dp(&dir, &["mesh", r, "-o", "x.ply"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(".stl, .3mf or .obj"), "{err}");
    assert!(!dir.join("x.ply").exists());
    // the output over the recipe
    let copy = dir.join("s.yaml");
    std::fs::copy(r, &copy).unwrap();
    let before = std::fs::read(&copy).unwrap();
    let out = p3dp(&dir, &["mesh", "s.yaml", "-o", "s.yaml"]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(std::fs::read(&copy).unwrap(), before);
    // a bad --set names the param
    let out = p3dp(&dir, &["mesh", r, "--set", "radius=-3", "-o", "n.stl"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!dir.join("n.stl").exists());
    // the default name: ./NAME.stl
    let out = p3dp(&dir, &["mesh", "s.yaml"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("sphere.stl").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_edge_check_tells_a_closed_shell_from_an_open_or_flipped_one() {
    // a tetrahedron, its faces turned outwards
    let tet = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
    assert_eq!(obj_edges(tet), (0, 4, 4));
    // a face left out: its three edges have no partner
    let open = tet.replace("f 2 3 4\n", "");
    assert_eq!(obj_edges(&open).0, 3);
    // a face flipped: its edges run the same way as its neighbours'
    let flipped = tet.replace("f 2 3 4\n", "f 2 4 3\n");
    assert!(obj_edges(&flipped).0 > 0);
}
