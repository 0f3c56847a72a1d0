//! The globe of Kanada's Fig. 12: a sphere modulated by the 300 × 150 world map.
//!
//! The strings are compared with the same recipe built without its
//! `modulate_map` step, so each string's factor (land 1, sea 0.65) is read off
//! the result, not recomputed the way the recipe computes it.
//!
//! Past the public face: the `modulate_map` step is taken off
//! `Recipe::parts[0].steps` (`Step::key`). Home: beside
//! `generate::step::modulate`.

use crate::base::testing::*;
use crate::base::toolpath::Toolpath;

const SEA: f64 = 0.65;

struct Globe {
    /// Final strings.
    fin: Toolpath,
    /// factor[k] = c_final / c_unmodulated
    factor: Vec<f64>,
    /// speed[k] = v_final / v_unmodulated
    speed: Vec<f64>,
}

fn globe() -> Globe {
    let mut recipe = crate::recipe::load(&recipe("globe.yaml"), &[], None).unwrap();
    let fin = crate::generate::model::make_part(&recipe, 0).unwrap();
    let last = recipe.parts[0].steps.pop().unwrap();
    assert_eq!(last.key(), "modulate_map");
    let base = crate::generate::model::make_part(&recipe, 0).unwrap();
    assert_eq!(fin.points, base.points, "modulation must not move points");
    let factor = fin
        .strings
        .iter()
        .zip(&base.strings)
        .map(|(a, b)| a.c / b.c)
        .collect();
    let speed = fin
        .strings
        .iter()
        .zip(&base.strings)
        .map(|(a, b)| a.v / b.v)
        .collect();
    Globe { fin, factor, speed }
}

/// Land share of each map row, north first.
fn map_rows() -> Vec<f64> {
    let img = image::open(root().join("maps/world-300x150.png"))
        .unwrap()
        .to_luma8();
    assert_eq!(img.dimensions(), (300, 150));
    (0..150)
        .map(|r| (0..300).filter(|&c| img.get_pixel(c, r)[0] < 128).count() as f64 / 300.0)
        .collect()
}

fn is_land(f: f64) -> bool {
    (f - 1.0).abs() < 1e-12
}

/// Latitude (degrees) and counter-clockwise angle (degrees, seen from above) of string k.
fn place(g: &Globe, k: usize) -> (f64, f64) {
    let m = g.fin.midpoint(k);
    let lat = (m.z - 25.4).atan2(m.truncate().length()).to_degrees();
    let ang = m.y.atan2(m.x).to_degrees().rem_euclid(360.0);
    (lat, ang)
}

#[test]
fn structure_150_turns_of_300_strings() {
    let g = globe();
    assert_eq!(g.fin.len(), 45_000);
}

#[test]
fn land_fraction_matches_the_map_area_weighted() {
    let g = globe();
    // every string got exactly one of the two factors
    assert!(g
        .factor
        .iter()
        .all(|&f| is_land(f) || (f - SEA).abs() < 1e-12));
    let (mut land, mut all) = (0.0, 0.0);
    for k in 0..g.fin.len() {
        let l = g.fin.length(k);
        all += l;
        if is_land(g.factor[k]) {
            land += l;
        }
    }
    let printed = land / all;
    // the map: each row weighted by the cosine of its latitude
    let rows = map_rows();
    let (mut wl, mut w) = (0.0, 0.0);
    for (r, share) in rows.iter().enumerate() {
        let lat = (90.0 - 1.2 * (r as f64 + 0.5)).to_radians();
        wl += lat.cos() * share;
        w += lat.cos();
    }
    let expected = wl / w;
    assert!(
        (printed - expected).abs() < 0.01,
        "printed land {printed:.4}, map {expected:.4}"
    );
}

#[test]
fn sea_runs_faster_by_the_ratio_asked() {
    let g = globe();
    let mut seen = [false; 2];
    for k in 0..g.fin.len() {
        if is_land(g.factor[k]) {
            assert!((g.speed[k] - 1.0).abs() < 1e-12);
            seen[0] = true;
        } else {
            // constant flow: c·v unchanged, so v grows by 1/0.65
            assert!(
                (g.speed[k] - 1.0 / SEA).abs() < 1e-12,
                "string {k}: {}",
                g.speed[k]
            );
            seen[1] = true;
        }
    }
    assert!(seen[0] && seen[1]);
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

#[test]
fn north_is_up() {
    let g = globe();
    // land share per 1.2° band of the print, from the top down
    let mut bands = vec![(0.0, 0.0); 150];
    for k in 0..g.fin.len() {
        let (lat, _) = place(&g, k);
        let row = (((90.0 - lat) / 1.2) as usize).min(149);
        bands[row].1 += 1.0;
        if is_land(g.factor[k]) {
            bands[row].0 += 1.0;
        }
    }
    let printed: Vec<f64> = bands
        .iter()
        .map(|(l, n)| if *n > 0.0 { l / n } else { 0.0 })
        .collect();
    let rows = map_rows();
    let mut flipped = rows.clone();
    flipped.reverse();
    let up = correlation(&printed, &rows);
    let down = correlation(&printed, &flipped);
    assert!(up > 0.95, "top of the print vs top of the map: {up}");
    assert!(down < 0.5, "upside down fits too well: {down}");
    // Antarctica at the bottom, the Arctic Ocean at the top
    assert!(
        printed[145] > 0.9 && printed[2] < 0.5,
        "{} {}",
        printed[145],
        printed[2]
    );
}

#[test]
fn not_mirrored_east_is_counter_clockwise() {
    let g = globe();
    // land share per 1.2° × 1.2° cell between 60°S and 60°N, by latitude and
    // counter-clockwise angle seen from above
    const ROWS: std::ops::Range<usize> = 25..125;
    let mut cells = vec![(0.0, 0.0); 150 * 300];
    for k in 0..g.fin.len() {
        let (lat, ang) = place(&g, k);
        let r = (((90.0 - lat) / 1.2) as usize).min(149);
        let c = ((ang / 1.2) as usize).min(299);
        cells[r * 300 + c].1 += 1.0;
        if is_land(g.factor[k]) {
            cells[r * 300 + c].0 += 1.0;
        }
    }
    let printed: Vec<f64> = ROWS
        .flat_map(|r| (0..300).map(move |c| (r, c)))
        .map(|(r, c)| {
            let (l, n) = cells[r * 300 + c];
            if n > 0.0 {
                l / n
            } else {
                0.0
            }
        })
        .collect();
    let img = image::open(root().join("maps/world-300x150.png"))
        .unwrap()
        .to_luma8();
    let land = |r: usize, c: usize| (img.get_pixel(c as u32, r as u32)[0] < 128) as u8 as f64;
    // best circular shift: the globe may be turned about its axis, but a
    // mirrored one (east clockwise) must not fit
    let best = |mirror: bool| {
        (0..300)
            .map(|s| {
                let map: Vec<f64> = ROWS
                    .flat_map(|r| (0..300).map(move |c| (r, c)))
                    .map(|(r, c)| {
                        let col = if mirror {
                            (300 - c + s) % 300
                        } else {
                            (c + s) % 300
                        };
                        land(r, col)
                    })
                    .collect();
                correlation(&printed, &map)
            })
            .fold(f64::MIN, f64::max)
    };
    let (east, west) = (best(false), best(true));
    assert!(east > 0.95, "eastward fit {east}");
    assert!(west < 0.6, "mirrored fits too well: {west} vs {east}");
}

/// `p3dp new --from globe`: its lettering reads left to right seen from
/// outside. Seen from outside (from −y, x to the right), the front of the
/// sphere runs from theta = 180° (left) through 270° to 360° (right): a text
/// reads from outside when its columns follow the counter-clockwise angle
/// seen from above, and mirror-image when they run clockwise. The strings'
/// factors (read off against the starter built without its `modulate_map`)
/// are binned by that angle and by latitude (north up) and compared with
/// the text's own bitmap, at every turn of the globe about its axis.
#[test]
fn the_starter_globe_reads_from_outside() {
    use crate::generate::step::Bitmap;
    let dir = tmp("globe-starter");
    let o = crate::app::testing::p3dp(&dir, &["new", "lettered.yaml", "--from", "globe"]);
    assert!(o.success());
    let file = dir.join("lettered.yaml");
    let text_of = std::fs::read_to_string(&file).unwrap();
    let text = text_of
        .split("text: \"")
        .nth(1)
        .and_then(|t| t.split('"').next())
        .expect("the starter letters a text")
        .to_string();
    let mut recipe = crate::recipe::load(&file, &[], None).unwrap();
    let fin = crate::generate::model::make_part(&recipe, 0).unwrap();
    let last = recipe.parts[0].steps.pop().unwrap();
    assert_eq!(last.key(), "modulate_map");
    let base = crate::generate::model::make_part(&recipe, 0).unwrap();
    let bitmap = Bitmap::from_text(&text).unwrap();
    let (w, h) = (bitmap.width, bitmap.height);
    // the sphere's centre: radius 25 lifted by 0.4 (the starter's params)
    let centre_z = 25.4;
    let mut cells = vec![(0.0, 0.0); w * h];
    for k in 0..fin.len() {
        let m = fin.midpoint(k);
        let lat = (m.z - centre_z).atan2(m.truncate().length());
        // the starter's band: v = 0.5 − 3·lat/pi over the text's rows
        let v = 0.5 - 3.0 * lat / std::f64::consts::PI;
        if !(0.0..1.0).contains(&v) || base.strings[k].travel {
            continue;
        }
        let ang = m.y.atan2(m.x).rem_euclid(std::f64::consts::TAU);
        let col = ((ang / std::f64::consts::TAU * w as f64) as usize).min(w - 1);
        let row = ((v * h as f64) as usize).min(h - 1);
        let dark = (fin.strings[k].c / base.strings[k].c - 1.0).abs() < 1e-9;
        cells[row * w + col].1 += 1.0;
        cells[row * w + col].0 += f64::from(u8::from(dark));
    }
    let printed: Vec<f64> = cells
        .iter()
        .map(|&(d, n)| if n > 0.0 { d / n } else { 0.0 })
        .collect();
    let best = |mirror: bool| {
        (0..w)
            .map(|s| {
                let want: Vec<f64> = (0..h)
                    .flat_map(|r| (0..w).map(move |c| (r, c)))
                    .map(|(r, c)| {
                        let col = if mirror {
                            (w - 1 - c + s) % w
                        } else {
                            (c + s) % w
                        };
                        f64::from(u8::from(bitmap.pixels[r * w + col] < 0.5))
                    })
                    .collect();
                correlation(&printed, &want)
            })
            .fold(f64::MIN, f64::max)
    };
    let (reads, mirrored) = (best(false), best(true));
    assert!(
        reads > 0.85,
        "the text fits only {reads:.3} read from outside"
    );
    assert!(
        mirrored < 0.7,
        "mirror-image fits as well: {mirrored:.3} vs {reads:.3}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
