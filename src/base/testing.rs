//! Helpers for the tests beside the code that load real recipes: the
//! gallery's files, fresh temporary folders, G-code read back as a firmware
//! reads it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The crate root.
pub(crate) fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A recipe of `recipes/`.
pub(crate) fn recipe(name: &str) -> PathBuf {
    root().join("recipes").join(name)
}

/// A fresh empty temporary folder for one test. The tests of every module
/// share one process, so a counter keeps two calls apart even when two
/// modules pick the same name.
pub(crate) fn tmp(name: &str) -> Tmp {
    static CALLS: AtomicUsize = AtomicUsize::new(0);
    let n = CALLS.fetch_add(1, Ordering::Relaxed);
    let d = std::env::temp_dir().join(format!("p3dp-test-{}-{n}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Tmp(d)
}

/// A test's temporary folder, removed with what it holds when the test is
/// done with it; kept when the test fails, to look at.
#[derive(Debug)]
pub(crate) struct Tmp(PathBuf);

impl Drop for Tmp {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

impl std::ops::Deref for Tmp {
    type Target = PathBuf;
    fn deref(&self) -> &PathBuf {
        &self.0
    }
}

impl AsRef<Path> for Tmp {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

/// One move read back from G-code, in machine coordinates: a line (G0/G1)
/// or an arc (G2/G3).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Move {
    /// 0, 1, 2 or 3: G0, G1, G2, G3.
    pub(crate) g: u8,
    /// Position before the move.
    pub(crate) from: [f64; 3],
    /// Position after the move.
    pub(crate) to: [f64; 3],
    /// An arc's centre, offset from `from` (I, J); zero for a line.
    pub(crate) ij: [f64; 2],
    /// Filament fed by this move (negative for a retraction), mm.
    pub(crate) de: f64,
    /// Feed rate in force, mm/min.
    pub(crate) f: f64,
    /// Index of the `; part:` comment this move follows.
    pub(crate) part: usize,
}

/// G-code read back: the moves and the part names in order.
pub(crate) struct Gcode {
    pub(crate) moves: Vec<Move>,
    pub(crate) parts: Vec<String>,
    pub(crate) lines: Vec<String>,
}

/// Reads G-code as a firmware would: G90 XYZ, M82/M83 E, G92 E resets, modal
/// F; G28 makes the position unknown (NaN) until the moves name it again.
pub(crate) fn parse(text: &str) -> Gcode {
    let mut pos = [f64::NAN; 3];
    let (mut e, mut f, mut relative) = (0.0, 0.0, false);
    let mut moves = Vec::new();
    let mut parts = vec!["(before parts)".to_string()];
    let mut lines = Vec::new();
    for raw in text.lines() {
        lines.push(raw.to_string());
        if let Some(name) = raw.strip_prefix("; part: ") {
            parts.push(name.split(" (").next().unwrap().to_string());
        }
        let code = raw.split(';').next().unwrap().trim();
        let mut words = code.split_whitespace();
        let Some(cmd) = words.next() else { continue };
        match cmd {
            "M82" => relative = false,
            "M83" => relative = true,
            "G28" => pos = [f64::NAN; 3],
            "G92" => {
                for w in words {
                    if let Some(v) = w.strip_prefix('E') {
                        e = v.parse().unwrap();
                    }
                }
            }
            "G0" | "G1" | "G2" | "G3" => {
                let from = pos;
                let (mut de, mut ij) = (0.0, [0.0; 2]);
                for w in words {
                    let (axis, v) = w.split_at(1);
                    let v: f64 = v
                        .parse()
                        .unwrap_or_else(|_| panic!("bad number in `{raw}`"));
                    match axis {
                        "X" => pos[0] = v,
                        "Y" => pos[1] = v,
                        "Z" => pos[2] = v,
                        "I" | "J" if cmd == "G2" || cmd == "G3" => ij[usize::from(axis == "J")] = v,
                        "E" => {
                            de = if relative { v } else { v - e };
                            e = if relative { e + v } else { v };
                        }
                        "F" => f = v,
                        other => panic!("unexpected word {other} in `{raw}`"),
                    }
                }
                moves.push(Move {
                    g: cmd[1..].parse().unwrap(),
                    from,
                    to: pos,
                    ij,
                    de,
                    f,
                    part: parts.len() - 1,
                });
            }
            _ => {}
        }
    }
    Gcode {
        moves,
        parts,
        lines,
    }
}

/// Machine → recipe coordinates for the generic-220 profile (origin 110, 110, 0).
pub(crate) fn to_recipe(p: [f64; 3]) -> [f64; 3] {
    [p[0] - 110.0, p[1] - 110.0, p[2]]
}

/// Linking number of two closed polygons by the Gauss double integral, summed
/// exactly segment pair by segment pair as the solid angle each pair spans
/// (Klenin & Langowski 2000). An integer up to rounding for closed curves.
pub(crate) fn linking_by_gauss(a: &[glam::DVec3], b: &[glam::DVec3]) -> f64 {
    let mut omega = 0.0;
    for i in 0..a.len() {
        let (p1, p2) = (a[i], a[(i + 1) % a.len()]);
        for j in 0..b.len() {
            let (p3, p4) = (b[j], b[(j + 1) % b.len()]);
            let (r13, r14, r23, r24) = (p3 - p1, p4 - p1, p3 - p2, p4 - p2);
            let orient = (p4 - p3).cross(p2 - p1).dot(r13);
            let scale = (p4 - p3).length() * (p2 - p1).length() * r13.length();
            let faces = [
                r13.cross(r14),
                r14.cross(r24),
                r24.cross(r23),
                r23.cross(r13),
            ];
            if orient.abs() <= 1e-12 * scale || faces.iter().any(|n| n.length() < 1e-15) {
                continue; // the four points in a plane: no solid angle
            }
            let n = faces.map(|f| f.normalize());
            let mut w = 0.0;
            for k in 0..4 {
                w += n[k].dot(n[(k + 1) % 4]).clamp(-1.0, 1.0).asin();
            }
            omega += w * orient.signum();
        }
    }
    omega / (4.0 * std::f64::consts::PI)
}
