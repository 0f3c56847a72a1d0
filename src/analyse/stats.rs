//! The stats report: a few lines for people, and JSON for scripts.

use glam::DVec3;
use serde::Serialize;

use crate::analyse::check::Finding;
use crate::analyse::plan::Plan;
use crate::base::format::hms;
use crate::generate::model::Recipe;
use crate::generate::primitive::solid::{LayerStats, SolidStats};
use crate::generate::primitive::Primitive;

/// What the written moves add up to; the stats report is made from it.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct MoveStats {
    /// G1 moves that extrude.
    pub(crate) extrude_moves: u64,
    /// G0 moves.
    pub(crate) travel_moves: u64,
    /// Length of extruding moves, mm.
    pub(crate) extrude_length: f64,
    /// Length of travel moves, mm (the first move from home is not counted).
    pub(crate) travel_length: f64,
    /// Filament fed, mm (exact, before rounding).
    pub(crate) filament: f64,
    /// Extruded volume, mm³.
    pub(crate) volume: f64,
    /// Estimated printing time, s: the planner's (see [`crate::analyse::planner`]).
    pub(crate) time: f64,
    /// The planner's estimate in full: planned, ideal and nominal times of
    /// the print and of each part.
    pub(crate) estimate: crate::analyse::planner::Estimate,
    /// Lowest corner of the extruding moves, recipe coordinates.
    pub(crate) bbox_min: DVec3,
    /// Highest corner of the extruding moves, recipe coordinates.
    pub(crate) bbox_max: DVec3,
    /// Highest volumetric flow of any extruding move, mm³/s.
    pub(crate) max_flow: f64,
    /// Strings that were merged into longer moves.
    pub(crate) merged_strings: u64,
    /// Retractions made.
    pub(crate) retractions: u64,
}

/// Corners of the bounding box of the extruding moves, recipe coordinates.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BBox {
    /// Lowest corner.
    pub min: [f64; 3],
    /// Highest corner.
    pub max: [f64; 3],
}

/// One part's share.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PartStats {
    /// Part name (`skirt` for the skirt).
    pub name: String,
    /// Strings after all steps.
    pub strings: usize,
    /// Planned time of its moves (the travel to it included), s.
    pub print_time_s: f64,
    /// Planned time less Σ length / speed of its moves, s.
    pub time_lost_s: f64,
}

/// One object's share of a plate (its parts' together).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectStats {
    /// The object's name (its parts are `NAME/PART`).
    pub name: String,
    /// Strings of its parts (and its skirt).
    pub strings: usize,
    /// Planned time of its moves (the travel to it included), s.
    pub print_time_s: f64,
    /// Filament its strings extrude, mm.
    pub filament_length_mm: f64,
    /// That filament's mass, g.
    pub filament_mass_g: f64,
}

/// Everything the spec's `--stats-json` promises, and a little more.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Stats {
    /// The recipe file as given.
    pub recipe: String,
    /// The recipe's name.
    pub name: String,
    /// Printer profile used.
    pub printer: String,
    /// Material used.
    pub material: String,
    /// Param values after `--set`, in order.
    pub params: indexmap::IndexMap<String, serde_json::Value>,
    /// SHA-256 of the G-code bytes.
    pub gcode_sha256: String,
    /// Size of the G-code.
    pub gcode_bytes: u64,
    /// Strings of all parts and the skirt.
    pub strings: u64,
    /// G1 moves that extrude.
    pub extrude_moves: u64,
    /// G0 moves.
    pub travel_moves: u64,
    /// Strings merged into longer moves (see `min_string_length`).
    pub merged_strings: u64,
    /// Retractions.
    pub retractions: u64,
    /// Length of extruding moves, mm.
    pub extrude_length_mm: f64,
    /// Length of travel moves, mm.
    pub travel_length_mm: f64,
    /// Filament fed, mm.
    pub filament_length_mm: f64,
    /// Filament volume, mm³.
    pub filament_volume_mm3: f64,
    /// Filament mass, g.
    pub filament_mass_g: f64,
    /// Estimated printing time, s: the planner's, with acceleration,
    /// junction speeds and speed limits (see `planner`).
    pub print_time_s: f64,
    /// Σ distance / speed at the G-code's speeds, s.
    pub print_time_ideal_s: f64,
    /// Time lost to acceleration, deceleration and corners, s (planned
    /// time less Σ distance / speed at the speeds the limits allow).
    pub time_lost_to_acceleration_s: f64,
    /// Time lost to `max_velocity` and `min_segment_time`, s; with the time
    /// lost to acceleration, `print_time_s − print_time_ideal_s`.
    pub time_lost_to_speed_limits_s: f64,
    /// The limits the planner used.
    pub planner: crate::analyse::planner::Limits,
    /// Bounding box of the extruding moves.
    pub bbox: BBox,
    /// Highest volumetric flow of any move, mm³/s.
    pub max_flow_mm3_s: f64,
    /// Each part's strings and time.
    pub parts: Vec<PartStats>,
    /// A plate's objects, in print order: each one's strings, time and
    /// filament (absent for a recipe).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<ObjectStats>,
    /// Findings of the checks (warnings and, under `--force`, errors).
    pub warnings: Vec<Finding>,
    /// Where each part (and the skirt) holds on to the bed: contact length,
    /// area and footprint; parts that start on earlier filament are absent.
    pub first_layer: Vec<crate::analyse::check::first_layer::Footprint>,
    /// The z-buffer of each `solid` part: loops and area per layer (absent without solids).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub solids: Vec<crate::generate::primitive::solid::SolidStats>,
    /// The bands of a calibration print's `set` steps, in print order
    /// (absent without them).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bands: Vec<BandStats>,
}

/// One band of a calibration print: its index, its setting's value, and
/// its heights (a height band) or its line (a line test's part).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BandStats {
    /// The band's index.
    pub index: u32,
    /// The value its setting takes.
    pub value: f64,
    /// The part it belongs to.
    pub part: String,
    /// Where the band begins, mm (height bands).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub z_from: Option<f64>,
    /// Where it ends, mm (height bands).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub z_to: Option<f64>,
    /// The line (a line test's band).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub line: Option<u32>,
}

/// The bands the `set` steps and commands of `paths` begin, in print order:
/// a firmware setting's or a pace's (`Event::Band`).
pub(crate) fn bands(paths: &[crate::base::toolpath::Toolpath]) -> Vec<BandStats> {
    let mut out = Vec::new();
    for tp in paths {
        for (_, e) in &tp.events {
            use crate::base::toolpath::Event;
            if let Event::Set { band: Some(b), .. } | Event::Band { band: b, .. } = e {
                out.push(BandStats {
                    index: b.index,
                    // start + band·step to 9 decimals: 0.6, not 0.6000000000000001
                    value: libm::round(b.value * 1e9) / 1e9,
                    part: tp.name.clone(),
                    z_from: b.z.map(|z| z[0]),
                    z_to: b.z.map(|z| z[1]),
                    line: b.z.is_none().then_some(b.index),
                });
            }
        }
    }
    out
}

impl Stats {
    /// The stats of `plan`'s G-code, written with `moves`, its SHA-256 hex
    /// `digest` (empty when not hashed) and size in bytes.
    pub(crate) fn of(plan: &Plan, moves: &MoveStats, digest: String, bytes: u64) -> Stats {
        let parts = plan
            .paths
            .iter()
            .zip(&moves.estimate.parts)
            .map(|(t, pt)| PartStats {
                name: t.name.clone(),
                strings: t.len(),
                print_time_s: pt.times.planned,
                time_lost_s: pt.times.lost(),
            })
            .collect();
        let mut stats = Stats::new(
            &plan.path,
            &plan.recipe,
            moves,
            parts,
            digest,
            bytes,
            plan.findings.clone(),
        );
        stats.first_layer = plan.footprints.clone();
        stats.bands = bands(&plan.paths);
        if !plan.recipe.objects.is_empty() {
            stats.objects = objects(plan, &stats.parts);
        }
        stats
    }
}

/// Each object of a plate: its parts' strings and times added, and the
/// filament its strings extrude (Σ c·L over the filament's section).
fn objects(plan: &Plan, parts: &[PartStats]) -> Vec<ObjectStats> {
    let r = &plan.recipe;
    let d = r
        .material
        .filament_diameter
        .unwrap_or(r.printer.filament_diameter);
    let area = std::f64::consts::PI * (d / 2.0) * (d / 2.0);
    plan.objects()
        .into_iter()
        .map(|(name, k)| {
            let volume: f64 = plan.paths[k.clone()].iter().map(|t| t.volume()).sum();
            let mine = parts.get(k).unwrap_or_default();
            ObjectStats {
                name,
                strings: mine.iter().map(|p| p.strings).sum(),
                print_time_s: mine.iter().map(|p| p.print_time_s).sum(),
                filament_length_mm: volume / area,
                filament_mass_g: volume / 1000.0 * r.material.density,
            }
        })
        .collect()
}

impl Stats {
    /// Assembles the stats of one build.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        recipe_path: &str,
        recipe: &Recipe,
        m: &MoveStats,
        parts: Vec<PartStats>,
        sha256: String,
        bytes: u64,
        findings: Vec<Finding>,
    ) -> Stats {
        let bbox = if m.extrude_moves > 0 {
            BBox {
                min: m.bbox_min.to_array(),
                max: m.bbox_max.to_array(),
            }
        } else {
            BBox {
                min: [0.0; 3],
                max: [0.0; 3],
            }
        };
        Stats {
            recipe: recipe_path.to_string(),
            name: recipe.name.clone(),
            printer: recipe.printer.name.clone(),
            material: recipe.material.name.clone(),
            params: recipe.params.to_json(),
            gcode_sha256: sha256,
            gcode_bytes: bytes,
            strings: parts.iter().map(|p| p.strings as u64).sum(),
            extrude_moves: m.extrude_moves,
            travel_moves: m.travel_moves,
            merged_strings: m.merged_strings,
            retractions: m.retractions,
            extrude_length_mm: m.extrude_length,
            travel_length_mm: m.travel_length,
            filament_length_mm: m.filament,
            filament_volume_mm3: m.volume,
            filament_mass_g: m.volume / 1000.0 * recipe.material.density,
            print_time_s: m.time,
            print_time_ideal_s: m.estimate.total.ideal,
            time_lost_to_acceleration_s: m.estimate.total.lost_to_acceleration(),
            time_lost_to_speed_limits_s: m.estimate.total.lost_to_speed_limits(),
            planner: recipe.printer.limits(),
            bbox,
            max_flow_mm3_s: m.max_flow,
            parts,
            objects: Vec::new(),
            warnings: findings,
            solids: solid_stats(recipe),
            first_layer: Vec::new(),
            bands: Vec::new(),
        }
    }

    /// `  objects, printed one after another:` and a line each (a plate's).
    fn objects_report(&self) -> String {
        if self.objects.is_empty() {
            return String::new();
        }
        let mut s = String::from("  objects, printed one after another:\n");
        for o in &self.objects {
            s.push_str(&format!(
                "    {}: {}, filament {:.0} mm, {:.2} g\n",
                o.name,
                hms(o.print_time_s),
                o.filament_length_mm,
                o.filament_mass_g
            ));
        }
        s
    }

    /// `  bed contact: bottom 5653 mm² in 59.8 × 59.5 mm; …` (the first layer's hold).
    fn bed_contact(&self) -> String {
        if self.first_layer.is_empty() {
            return "  bed contact: none (nothing lies on the bed)\n".to_string();
        }
        let each: Vec<String> = self
            .first_layer
            .iter()
            .map(|f| {
                format!(
                    "{} {:.0} mm² in {:.1} × {:.1} mm",
                    f.part,
                    f.contact_area_mm2,
                    f.max[0] - f.min[0],
                    f.max[1] - f.min[1]
                )
            })
            .collect();
        format!("  bed contact: {}\n", each.join("; "))
    }

    /// The bands' table of a calibration print (empty without bands).
    fn bands_table(&self) -> String {
        if self.bands.is_empty() {
            return String::new();
        }
        let mut s = String::from("  bands:\n    band  value       where\n");
        for b in &self.bands {
            let at = match (b.z_from, b.z_to, b.line) {
                (Some(lo), Some(hi), _) => format!("z {lo:.2} to {hi:.2} mm"),
                (_, _, Some(l)) => format!("line {l} ({})", b.part),
                _ => String::new(),
            };
            s.push_str(&format!(
                "    {:>4}  {:<10}  {at}\n",
                b.index,
                crate::base::format::fmt_num(b.value)
            ));
        }
        s
    }

    /// The short human report printed after a build.
    pub(crate) fn report(&self, output: &str) -> String {
        let b = &self.bbox;
        let size = [0, 1, 2].map(|k| b.max[k] - b.min[k]);
        let mut s = format!(
            "{} → {output}\n  {} strings in {} part{}; {} extruding and {} travel moves ({} short strings merged)\n  size {:.1} × {:.1} × {:.1} mm\n  filament {:.0} mm, {:.2} g {} ({:.2} cm³); max flow {:.2} mm³/s\n  time {} ({} lost to acceleration and corners, {} to speed limits; at the G-code's speeds {})\n{}{}{}  {}\n",
            self.recipe,
            self.strings,
            self.parts.len(),
            if self.parts.len() == 1 { "" } else { "s" },
            self.extrude_moves,
            self.travel_moves,
            self.merged_strings,
            size[0],
            size[1],
            size[2],
            self.filament_length_mm,
            self.filament_mass_g,
            self.material,
            self.filament_volume_mm3 / 1000.0,
            self.max_flow_mm3_s,
            hms(self.print_time_s),
            hms(self.time_lost_to_acceleration_s),
            hms(self.time_lost_to_speed_limits_s),
            hms(self.print_time_ideal_s),
            if self.parts.len() > 1 {
                self.parts
                    .iter()
                    .map(|p| {
                        format!(
                            "    {}: {} ({} lost)\n",
                            p.name,
                            hms(p.print_time_s),
                            hms(p.time_lost_s)
                        )
                    })
                    .collect::<String>()
            } else {
                String::new()
            },
            self.objects_report(),
            self.bed_contact(),
            crate::analyse::check::summary(&self.warnings),
        );
        s.push_str(&self.bands_table());
        for f in &self.warnings {
            s.push_str(&format!(
                "  {} [{}]: {}\n",
                f.severity.word(),
                f.code,
                f.message
            ));
        }
        s
    }
}

/// The z-buffers of a recipe's solid parts (before any steps).
pub(crate) fn solid_stats(recipe: &Recipe) -> Vec<SolidStats> {
    recipe
        .parts
        .iter()
        .flat_map(|p| p.primitives().map(move |q| (p, q)))
        .filter_map(|(p, q)| match q {
            Primitive::Solid(s) => Some(SolidStats {
                part: p.name.clone(),
                layers: s
                    .layers()
                    .map(|l| LayerStats {
                        z: l.z,
                        loops: l.slab.map_or(0, |s| s.region.loops.len()),
                        area_mm2: l.slab.map_or(0.0, |s| s.region.area()),
                    })
                    .collect(),
            }),
            _ => None,
        })
        .collect()
}

/// Each solid part of a recipe with its name (before any steps).
fn solids(recipe: &Recipe) -> Vec<(&str, &crate::generate::primitive::solid::Solid)> {
    recipe
        .parts
        .iter()
        .flat_map(|p| p.primitives().map(move |q| (p, q)))
        .filter_map(|(p, q)| match q {
            Primitive::Solid(s) => Some((p.name.as_str(), s)),
            _ => None,
        })
        .collect()
}

/// The z-buffers of a recipe's solid parts as curves (`--zbuffer`).
pub(crate) fn zbuffer_curves(
    recipe: &Recipe,
) -> Vec<crate::generate::primitive::solid::SolidCurves> {
    solids(recipe)
        .into_iter()
        .map(|(name, s)| s.curves(name))
        .collect()
}

/// An SVG of layer `index` of a recipe's solid parts (`--zbuffer-svg`);
/// `None` when none has that layer, an error for a name XML cannot hold.
pub(crate) fn zbuffer_svg(
    recipe: &Recipe,
    index: u64,
) -> crate::base::error::Result<Option<String>> {
    crate::generate::primitive::solid::layer_svg(&solids(recipe), index)
}
