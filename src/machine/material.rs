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
    /// Filament colour, sRGB (the 3MF mesh's material colour).
    pub color: [u8; 3],
}

/// The colour of a material that names none: the orange the previews draw
/// filament in (`#FA8F29`).
pub(crate) const DEFAULT_COLOR: [u8; 3] = [0xFA, 0x8F, 0x29];

/// Height above which the fan of a built-in material turns on, mm: past the
/// first layer or two.
pub(crate) const FAN_START_Z: f64 = 0.5;

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
            color: DEFAULT_COLOR,
        })
    }
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
