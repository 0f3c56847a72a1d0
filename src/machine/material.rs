//! Filament materials: the built-in `pla`, `abs` and `petg`, a recipe's
//! own, or a slicer's filament preset (`--filament`); and the template
//! variables of the start and end G-code a material gives ([`VARIABLES`]).

use std::collections::BTreeMap;

use crate::base::slicer_macro::Value;

/// A filament material.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Material {
    /// Name for reports.
    pub(crate) name: String,
    /// Filament diameter, mm; the printer's when `None`.
    pub(crate) filament_diameter: Option<f64>,
    /// Density, g/cm³.
    pub(crate) density: f64,
    /// Printing temperature, °C.
    pub(crate) nozzle_temp: f64,
    /// Bed temperature, °C.
    pub(crate) bed_temp: f64,
    /// Hottest safe nozzle for this material, °C.
    pub(crate) max_nozzle_temp: f64,
    /// Part-cooling fan once the print is above `fan_start_z`, 0 (off) to 1.
    pub(crate) fan_speed: f64,
    /// Height (recipe z, mm) above which the fan turns on: the first layers
    /// stick better warm.
    pub(crate) fan_start_z: f64,
    /// Filament colour, sRGB (the 3MF mesh's material colour).
    pub(crate) color: [u8; 3],
    /// Coolest nozzle the material prints at, °C: the low end of its range.
    pub(crate) min_nozzle_temp: f64,
    /// The filament's own volumetric flow limit, mm³/s, when known (a
    /// filament preset's `filament_max_volumetric_speed`).
    pub(crate) max_volumetric_speed: Option<f64>,
    /// Chamber temperature the material asks for, °C; 0 for none.
    pub(crate) chamber_temp: f64,
    /// Where the material softens (the slicers' `temperature_vitrification`),
    /// °C, when known.
    pub(crate) vitrification_temp: Option<f64>,
    /// The slicer's filament preset it came from, if any.
    pub(crate) preset: Option<FilamentPreset>,
}

/// A slicer's filament preset behind a material: its name, its file and
/// every setting as a template value (text on one line).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FilamentPreset {
    /// The preset's name.
    pub(crate) name: String,
    /// The preset file, as the user named it.
    pub(crate) file: String,
    /// Every setting, by the slicer's key.
    pub(crate) settings: BTreeMap<String, Value>,
}

/// The colour of a material that names none: the orange the previews draw
/// filament in (`#FA8F29`).
pub(crate) const DEFAULT_COLOR: [u8; 3] = [0xFA, 0x8F, 0x29];

/// Height above which the fan of a built-in material turns on, mm: past the
/// first layer or two.
pub(crate) const FAN_START_Z: f64 = 0.5;

impl Material {
    /// A built-in material: `pla`, `abs` or `petg`.
    pub(crate) fn built_in(name: &str) -> Option<Material> {
        // PLA wants full cooling, PETG some (it sticks to itself less when
        // cold), ABS none (it warps and splits between layers)
        // the coolest nozzle and the softening point: the low end of the
        // range and the temperature_vitrification of OrcaSlicer's generic
        // filament of the type (its fdm_filament_pla, _abs, _pet)
        let (density, nozzle, bed, max, fan, min, soft) = match name {
            "pla" => (1.24, 210.0, 60.0, 240.0, 1.0, 190.0, 45.0),
            "abs" => (1.04, 240.0, 100.0, 270.0, 0.0, 240.0, 110.0),
            "petg" => (1.27, 235.0, 80.0, 260.0, 0.5, 220.0, 70.0),
            _ => return None,
        };
        Some(Material {
            name: name.to_string(),
            filament_diameter: None,
            density,
            nozzle_temp: nozzle,
            bed_temp: bed,
            max_nozzle_temp: max,
            fan_speed: fan,
            fan_start_z: FAN_START_Z,
            color: DEFAULT_COLOR,
            min_nozzle_temp: min,
            max_volumetric_speed: None,
            chamber_temp: 0.0,
            vitrification_temp: Some(soft),
            preset: None,
        })
    }

    /// The filament preset's setting `key`, if the material came from one.
    pub(crate) fn setting(&self, key: &str) -> Option<&Value> {
        self.preset.as_ref()?.settings.get(key)
    }
}

/// The template variables a material gives the start and end G-code, and
/// where each value comes from: the filament preset's setting of the name
/// when the material came from one (`--filament`), else what the line says.
/// Lists have one value per extruder.
pub(crate) const VARIABLES: &[(&str, &str)] = &[
    ("chamber_temperature", "[the material's chamber temperature], °C: the filament preset's chamber_temperature(s), else 0 (the chamber left alone, the slicers' default)"),
    ("overall_chamber_temperature", "the same, °C (the hottest of the filaments used: p3dp uses one)"),
    ("chamber_minimal_temperature", "[the filament preset's, else 0], °C"),
    ("filament_abrasive", "[the filament preset's, else false]"),
    ("filament_notes", "[the filament preset's notes on one line, else empty]"),
    ("filament_max_volumetric_speed", "[the filament preset's, else the printer's max_flow], mm³/s"),
    ("nozzle_temperature_range_low", "[the coolest nozzle the material prints at], °C: the filament preset's, else the low end of OrcaSlicer's generic range of the type (PLA 190, ABS 240, PETG 220), else the material's nozzle temperature"),
    ("nozzle_temperature_range_high", "[the material's max_nozzle_temp], °C"),
    ("flush_temperatures", "[the filament preset's filament_flush_temp, else nozzle_temperature_range_high], °C: Bambu Studio's rule"),
    ("flush_volumetric_speeds", "[the filament preset's filament_flush_volumetric_speed, else filament_max_volumetric_speed], mm³/s: Bambu Studio's rule"),
    ("temperature_vitrification", "[where the material softens], °C: the filament preset's, else OrcaSlicer's generic figure of the type (PLA 45, ABS 110, PETG 70); refused for a recipe's own material"),
    ("min_vitrification_temperature", "the lowest temperature_vitrification of the filaments used, °C (one)"),
    ("idle_temperature", "[the filament preset's, else 0: no idle temperature]"),
    ("fan_max_speed", "[the material's fan_speed], percent"),
    ("max_fan_speed", "[the material's fan_speed], percent"),
    ("filament_density", "[the material's density], g/cm³"),
    ("filament_vendor", "[the filament preset's, else \"Generic\"]"),
    ("filament_preset", "the filament preset's name, else the material's (filament_settings_id)"),
    ("has_tpu_in_first_layer", "whether the material's type is TPU"),
    ("is_all_bbl_filament", "whether the filament preset's vendor is Bambu Lab (false for a recipe's material)"),
    ("filament_multitool_ramming", "[the filament preset's, else false: p3dp changes no tool]"),
    ("enable_pressure_advance", "[the filament preset's, else false, OrcaSlicer's default] (a recipe's own material: refused)"),
    ("pressure_advance", "[the filament preset's, else 0.02, OrcaSlicer's default] (a recipe's own material: refused)"),
    ("filament_ids", "[the filament preset's filament_id] (a recipe's own material: refused)"),
];

/// Whether a filament preset gives `name` and a material alone may not:
/// a setting every filament preset has (`filament_*`, `pressure_advance`…)
/// or that only the slicer knows for a filament. Without a filament preset
/// the build refuses it by name.
pub(crate) fn from_filament_preset(name: &str) -> bool {
    const NAMES: &[&str] = &[
        "pressure_advance",
        "enable_pressure_advance",
        "adaptive_pressure_advance",
        "chamber_temperatures",
        "filament_flush_temp",
        "filament_flush_volumetric_speed",
        "long_retractions_when_cut",
        "retraction_distances_when_cut",
        "long_retraction_when_ec",
        "retraction_distance_when_ec",
        "activate_air_filtration",
        "during_print_exhaust_fan_speed",
        "complete_print_exhaust_fan_speed",
        "activate_chamber_temp_control",
        "textured_cool_plate_temp",
        "supertack_plate_temp",
    ];
    name.starts_with("filament_") || NAMES.contains(&name)
}

/// Parses a colour written `#rrggbb` (hex digits, either case).
pub(crate) fn parse_color(s: &str) -> Option<[u8; 3]> {
    let hex = s.strip_prefix('#')?;
    if hex.len() != 6 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
    Some([byte(0)?, byte(2)?, byte(4)?])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colors_parse() {
        assert_eq!(parse_color("#FA8f29"), Some(DEFAULT_COLOR));
        assert_eq!(parse_color("#000000"), Some([0, 0, 0]));
        for bad in [
            "FA8F29",
            "#FA8F2",
            "#FA8F299",
            "#GG0000",
            "",
            "#",
            "#ＦＡ8F29",
        ] {
            assert_eq!(parse_color(bad), None, "{bad}");
        }
    }
}
