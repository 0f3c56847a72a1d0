//! Per-layer and whole-solid statistics.

use super::*;

/// One layer of the z-buffer in the stats.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LayerStats {
    /// Height the layer is printed at, mm.
    pub z: f64,
    /// Loops of its cross-section (outer loops and holes).
    pub loops: usize,
    /// Area of its cross-section, mm².
    pub area_mm2: f64,
}

/// The z-buffer of one solid part in the stats.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SolidStats {
    /// Part name.
    pub part: String,
    /// Its layers bottom up.
    pub layers: Vec<LayerStats>,
}
