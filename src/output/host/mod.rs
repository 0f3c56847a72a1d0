//! What goes to the printer's own software: the packages some printers take
//! instead of plain G-code (Prusa's binary `.bgcode`, Bambu's `.gcode.3mf`)
//! and their pieces.

pub(crate) mod bgcode;
pub(crate) mod heatshrink;
pub(crate) mod meatpack;
pub(crate) mod send;
pub(crate) mod threemf;

use std::path::Path;

use crate::analyse::plan::Plan;
use crate::analyse::stats::MoveStats;
use crate::base::error::Result;
use crate::output::gcode::metadata::{self, Extent, Layers};

/// What a build writes: plain G-code or a printer's package.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Package {
    /// ASCII G-code.
    Gcode,
    /// Prusa's binary G-code, `.bgcode`.
    Bgcode,
    /// Bambu's `.gcode.3mf`.
    Bambu,
}

impl Package {
    /// The package an output file's name asks for: `NAME.bgcode`,
    /// `NAME.gcode.3mf`, anything else plain G-code.
    pub(crate) fn of(path: &Path) -> Package {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        if name.ends_with(".bgcode") {
            Package::Bgcode
        } else if name.ends_with(".gcode.3mf") {
            Package::Bambu
        } else {
            Package::Gcode
        }
    }
}

impl Package {
    /// The `output-package` warning when a file of this package does not
    /// suit `printer`'s firmware ([`crate::analyse::check::package`]).
    pub(crate) fn unsuited(
        self,
        printer: &crate::machine::Printer,
    ) -> Option<crate::base::finding::Finding> {
        use crate::analyse::check::package::{output_package, Packed};
        match self {
            Package::Gcode => None,
            Package::Bgcode => output_package(Packed::Bgcode, printer),
            Package::Bambu => output_package(Packed::Bambu, printer),
        }
    }
}

/// The metadata pairs of `plan`'s print, as written (`stats`).
fn pairs(plan: &Plan, stats: &MoveStats) -> Vec<(&'static str, String)> {
    let extent = Extent::of(plan);
    let layers = Layers::of(&extent, plan.recipe.printer.nozzle_diameter);
    metadata::pairs(&plan.recipe, stats, layers.as_ref())
}

/// The `.bgcode` of `plan` from its ASCII G-code `gcode` and what its moves
/// came to (`stats`), with the profile's thumbnails as blocks (`images`).
pub(crate) fn bgcode_of(
    plan: &Plan,
    gcode: &[u8],
    stats: &MoveStats,
    images: &[(crate::machine::size::Thumbnail, Vec<u8>)],
) -> Result<Vec<u8>> {
    let all = pairs(plan, stats);
    let pick = |keys: &[&str]| -> Vec<(String, String)> {
        keys.iter()
            .filter_map(|k| all.iter().find(|(a, _)| a == k))
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect()
    };
    let mut printer = pick(&[
        "printer_model",
        "filament_type",
        "nozzle_diameter",
        "bed_temperature",
        "layer_height",
        "temperature",
        "max_layer_z",
    ]);
    if let Some((_, c)) = all.iter().find(|(k, _)| *k == "filament_colour") {
        printer.push(("extruder_colour".into(), format!("\"{c}\"")));
    }
    printer.extend(pick(&[
        "filament used [mm]",
        "filament used [g]",
        "estimated printing time (normal mode)",
    ]));
    let meta = bgcode::Metadata {
        file: vec![(
            "Producer".into(),
            format!("p3dp {}", env!("CARGO_PKG_VERSION")),
        )],
        printer,
        print: pick(&[
            "filament used [mm]",
            "filament used [cm3]",
            "filament used [g]",
            "total filament used [g]",
            "estimated printing time (normal mode)",
        ]),
        slicer: all
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect(),
    };
    Ok(bgcode::encode(gcode, &meta, images))
}

/// Bambu's `.gcode.3mf` of `plan` (see [`threemf`]): its G-code `gcode`
/// (written with Bambu's header block and layer markers), what its moves
/// came to (`stats`) and the plate's images: the iso view at 512 and 128
/// px, the top and pick pictures (PNGs).
pub(crate) fn threemf_of(
    plan: &Plan,
    gcode: &[u8],
    stats: &MoveStats,
    [image, small, top, pick]: [Vec<u8>; 4],
) -> Result<Vec<u8>> {
    let recipe = &plan.recipe;
    let p = &recipe.printer;
    let extent = Extent::of(plan);
    let layers = Layers::of(&extent, p.nozzle_diameter);
    let [r, g, b] = recipe.material.color;
    // a plate's objects (a recipe's parts), each with its box on the bed
    let parts = plan
        .objects()
        .into_iter()
        .map(|(name, k)| {
            let mut bx = [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ];
            for q in plan.paths[k].iter().flat_map(|t| &t.points) {
                let m = p.to_machine(*q);
                bx = [
                    bx[0].min(m.x),
                    bx[1].min(m.y),
                    bx[2].max(m.x),
                    bx[3].max(m.y),
                ];
            }
            (name, bx)
        })
        .collect();
    let plate = threemf::Plate {
        printer_model_id: threemf::model_id(&p.model),
        nozzle: p.nozzle_diameter,
        seconds: stats.time,
        metres: stats.filament / 1000.0,
        grams: metadata::grams(recipe, stats.volume),
        filament_type: metadata::filament_type(recipe).unwrap_or("").to_string(),
        colour: format!("#{r:02X}{g:02X}{b:02X}"),
        parts,
        sequential: !recipe.objects.is_empty(),
        layer_height: layers.map_or(0.0, |l| l.height),
        image,
        small,
        top,
        pick,
    };
    threemf::encode(gcode, &plate)
}
