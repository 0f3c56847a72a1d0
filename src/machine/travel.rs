//! Travel between parts: how high the head rises before it moves across.

use glam::DVec3;

use crate::machine::printer::Printer;

/// The height travel between parts rises to (recipe z): above the highest
/// filament printed so far by the head's clearance, within the printer's
/// reach, and at least the heights of both ends. A move with no sideways
/// part is a plain vertical move (`None`).
pub(crate) fn safe_travel_z(
    printer: &Printer,
    from: DVec3,
    to: DVec3,
    printed_top: f64,
) -> Option<f64> {
    if from.x == to.x && from.y == to.y {
        return None;
    }
    let reach = printer.bed.max_z() - printer.origin[2];
    let want = (printed_top + printer.head.clearance).min(reach);
    Some(want.max(from.z).max(to.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn travel_between_parts_rises_over_the_print() {
        let p = crate::recipe::profile::built_in("generic-220").unwrap();
        let a = DVec3::new(0.0, 0.0, 0.2);
        let b = DVec3::new(30.0, 0.0, 0.2);
        assert_eq!(safe_travel_z(&p, a, b, 12.0), Some(13.0));
        assert_eq!(safe_travel_z(&p, a, b.with_z(20.0), 12.0), Some(20.0));
        assert_eq!(safe_travel_z(&p, a, a.with_z(5.0), 12.0), None);
        // never above the printer's reach (max_z 250, origin z 0)
        assert_eq!(safe_travel_z(&p, a, b, 400.0), Some(250.0));
    }
}
