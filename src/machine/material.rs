//! Filament materials: the built-in `pla`, `abs` and `petg`, or a recipe's own.

/// A filament material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name for reports.
    pub name: String,
    /// Filament diameter, mm; the printer's when `None`.
    pub filament_diameter: Option<f64>,
    /// Density, g/cm³.
    pub density: f64,
    /// Printing temperature, °C.
    pub nozzle_temp: f64,
    /// Bed temperature, °C.
    pub bed_temp: f64,
    /// Hottest safe nozzle for this material, °C.
    pub max_nozzle_temp: f64,
    /// Part-cooling fan once the print is above `fan_start_z`, 0 (off) to 1.
    pub fan_speed: f64,
    /// Height (recipe z, mm) above which the fan turns on: the first layers
    /// stick better warm.
    pub fan_start_z: f64,
}

/// Height above which the fan of a built-in material turns on, mm: past the
/// first layer or two.
pub const FAN_START_Z: f64 = 0.5;

impl Material {
    /// A built-in material: `pla`, `abs` or `petg`.
    pub fn built_in(name: &str) -> Option<Material> {
        // PLA wants full cooling, PETG some (it sticks to itself less when
        // cold), ABS none (it warps and splits between layers)
        let (density, nozzle, bed, max, fan) = match name {
            "pla" => (1.24, 210.0, 60.0, 240.0, 1.0),
            "abs" => (1.04, 240.0, 100.0, 270.0, 0.0),
            "petg" => (1.27, 235.0, 80.0, 260.0, 0.5),
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
        })
    }
}
