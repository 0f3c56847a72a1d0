//! Steps: rewrite every point and/or every string's c and v (Kanada's Fig. 3
//! "part deformation" and "modulation").
//!
//! Expressions see the coordinates from before the step. Position expressions
//! run per point (`i` a point index, `n` the point count); cross-section, speed
//! and modulation expressions run per string at its midpoint (`i` a string
//! index, `n` the string count). Travel strings keep their c and v.

mod deform;
mod modulate;
pub(crate) mod set;
mod subdivide;

pub(crate) use deform::Deform;
pub(crate) use modulate::{Bitmap, Modulate, ModulateMap};
pub(crate) use set::Set;

use glam::{DAffine3, DVec3};

use crate::base::error::{Error, Result};
use crate::base::expr::{var, Vars};
use crate::base::toolpath::{angle, polar, radius, Toolpath};

/// What `modulate_*` keeps when it scales the cross-section.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Keep {
    /// Speed is divided by the factor, so the flow c·v stays constant.
    Flow,
    /// Speed is unchanged.
    Speed,
}

/// A step with its expressions compiled.
#[derive(Clone, Debug)]
pub(crate) enum Step {
    /// Deformation in Cartesian coordinates.
    DeformXyz(Deform),
    /// Deformation in cylinder coordinates.
    DeformCylinder(Deform),
    /// Cross-section scaled by a function of the midpoint.
    ModulateCylinder(Modulate),
    /// Cross-section scaled by a bitmap.
    ModulateMap(ModulateMap),
    /// Strings split into pieces no longer than this, mm.
    Subdivide(f64),
    /// Every point moved by this.
    Translate(DVec3),
    /// Every point mapped by this rotation, scaling or reflection; the key
    /// is the step's (`rotate`, `scale`, `mirror`).
    Place(&'static str, DAffine3),
    /// A printer command (checked when read) before the first extruding
    /// string that reaches this height, mm.
    GcodeAt(f64, std::sync::Arc<str>),
    /// The printer's settings, once per band (see [`set`]).
    Set(Box<Set>),
}

impl Step {
    /// The step's key in a recipe, for error places.
    pub(crate) fn key(&self) -> &'static str {
        match self {
            Step::DeformXyz(_) => "deform_xyz",
            Step::DeformCylinder(_) => "deform_cylinder",
            Step::ModulateCylinder(_) => "modulate_cylinder",
            Step::ModulateMap(_) => "modulate_map",
            Step::Subdivide(_) => "subdivide",
            Step::Translate(_) => "translate",
            Step::Place(key, _) => key,
            Step::GcodeAt(..) => "gcode_at",
            Step::Set(_) => "set",
        }
    }

    /// Whether one of the step's expressions reads variable slot `k`.
    pub(crate) fn uses(&self, k: usize) -> bool {
        match self {
            Step::DeformXyz(d) | Step::DeformCylinder(d) => d
                .position
                .iter()
                .flatten()
                .chain(&d.cross_section)
                .chain(&d.speed)
                .any(|e| e.uses(k)),
            Step::ModulateCylinder(m) => m.factor.uses(k),
            Step::ModulateMap(m) => m.u.uses(k) || m.v.uses(k),
            Step::Set(s) => {
                s.named.values.iter().any(|(_, e)| e.uses(k))
                    || s.pace.as_ref().is_some_and(|(_, e)| e.uses(k))
            }
            Step::Subdivide(_) | Step::Translate(_) | Step::Place(..) | Step::GcodeAt(..) => false,
        }
    }

    /// Applies the step in place (the same result whatever the threads).
    /// `max_strings` bounds what `subdivide` may make.
    pub(crate) fn apply(&self, tp: &mut Toolpath, max_strings: u64) -> Result<()> {
        if tp.turns.is_none() && self.uses(var::S) {
            return Err(Error::input(
                "",
                "`s` (the arc fraction along an `outline:`) has no meaning here: no primitive of this part follows an outline; expected `t` or an outline",
            ));
        }
        match self {
            Step::DeformXyz(d) | Step::DeformCylinder(d) => d.apply(tp),
            Step::ModulateCylinder(m) => m.apply(tp),
            Step::ModulateMap(m) => m.apply(tp),
            Step::Subdivide(max) => subdivide::apply(tp, *max, max_strings),
            Step::Translate(d) => {
                for p in &mut tp.points {
                    *p += *d;
                }
                for m in &mut tp.markers {
                    m.pos += *d;
                }
                Ok(())
            }
            Step::Set(s) => s.apply(tp),
            Step::GcodeAt(z, text) => {
                gcode_at(tp, *z, text);
                Ok(())
            }
            Step::Place(_, map) => {
                for p in &mut tp.points {
                    *p = map.transform_point3(*p);
                }
                for m in &mut tp.markers {
                    m.pos = map.transform_point3(m.pos);
                    m.heading = map.transform_vector3(m.heading).normalize_or_zero();
                    m.up = map.transform_vector3(m.up).normalize_or_zero();
                }
                Ok(())
            }
        }
    }
}

/// Puts `text` before the first extruding string of `tp` that ends at or
/// above `z` (after the events already there); nothing when none does.
fn gcode_at(tp: &mut Toolpath, z: f64, text: &std::sync::Arc<str>) {
    let Some(k) = (0..tp.len()).find(|&k| !tp.strings[k].travel && tp.points[k + 1].z >= z) else {
        return;
    };
    let at = tp.events.partition_point(|(i, _)| *i <= k);
    tp.events
        .insert(at, (k, crate::base::toolpath::Event::Gcode(text.clone())));
}

/// Below this many items a step runs in one piece.
pub(crate) const PAR_MIN: usize = 8_192;

/// Variable values for point or string `i` of `n` at `p`; r and theta only
/// when `polar_too` (atan2 is the costly part).
#[inline]
pub(crate) fn vars_at(p: DVec3, i: usize, n: usize, polar_too: bool) -> Vars {
    vars_with(p, i, n, polar_too, polar_too)
}

/// [`vars_at`] with r only when `r_too` and theta only when `theta_too`
/// (left 0 otherwise: for expressions that do not read them).
#[inline]
pub(crate) fn vars_with(p: DVec3, i: usize, n: usize, r_too: bool, theta_too: bool) -> Vars {
    let mut v = [0.0; var::COUNT];
    v[var::X] = p.x;
    v[var::Y] = p.y;
    v[var::Z] = p.z;
    if r_too {
        v[var::R] = radius(p);
    }
    if theta_too {
        v[var::THETA] = angle(p);
    }
    v[var::I] = i as f64;
    v[var::N] = n as f64;
    v[var::T] = if n > 1 {
        i as f64 / (n - 1) as f64
    } else {
        0.0
    };
    v
}

/// A point's radius and angle about the z axis ([`polar`]),
/// remembered by the bits of its x and y: a helix's points come back to the
/// same (x, y) every turn (its turn's table), and an angle is an atan2. The
/// same bits in, the same values out: a look-up changes no result.
pub(crate) struct Polar {
    /// Slot h of (x, y) bits (h their hash), and its radius and angle.
    slots: Vec<([u64; 2], [f64; 2])>,
}

impl Polar {
    /// Slots (a power of two): a turn of up to a few thousand points.
    const SLOTS: usize = 1 << 13;

    /// An empty memory: every slot holds the values of a point whose x and
    /// y have all bits set (NaNs), as a look-up of it would.
    pub(crate) fn new() -> Polar {
        let nan = f64::from_bits(u64::MAX);
        let p = DVec3::new(nan, nan, 0.0);
        Polar {
            slots: vec![([u64::MAX; 2], polar(p).into()); Self::SLOTS],
        }
    }

    /// [`radius`] and [`angle`] of `p`.
    #[inline]
    pub(crate) fn of(&mut self, p: DVec3) -> (f64, f64) {
        let key = [p.x.to_bits(), p.y.to_bits()];
        let h = (key[0] ^ key[1].rotate_left(29)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let slot = &mut self.slots[(h >> (64 - Self::SLOTS.trailing_zeros())) as usize];
        if slot.0 != key {
            let (r, theta) = polar(p);
            *slot = (key, [r, theta]);
        }
        (slot.1[0], slot.1[1])
    }
}

/// The error for an expression that gave NaN or infinity (no place yet:
/// [`crate::generate::model::make_part`] names the step).
pub(crate) fn not_finite(
    what: &str,
    src: &str,
    value: f64,
    kind: &str,
    i: usize,
    p: DVec3,
) -> Error {
    Error::input(
        "",
        format!(
            "{what} `{src}` gives {value} at {kind} {i}, (x, y, z) = ({:.3}, {:.3}, {:.3}); expected a finite number",
            p.x, p.y, p.z
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_polar_memory_gives_the_bits_of_radius_and_angle() {
        let mut memo = Polar::new();
        let mut rng = crate::base::rng::SplitMix64::new(11);
        let nan = f64::from_bits(u64::MAX);
        let mut pts: Vec<DVec3> = [
            DVec3::new(nan, nan, 0.0), // the empty slots' key
            DVec3::new(f64::NAN, 1.0, 0.0),
            DVec3::new(0.0, -0.0, 1.0),
            DVec3::new(-0.0, 0.0, 1.0),
            DVec3::new(-1e-300, -0.0, 0.0),
            DVec3::new(f64::INFINITY, 2.0, 0.0),
        ]
        .to_vec();
        // a helix's turn of 1000 points three times, then random points
        // (tens of thousands: slots shared and overwritten)
        for turn in 0..3 {
            for k in 0..1000 {
                let a = std::f64::consts::TAU * k as f64 / 1000.0;
                pts.push(DVec3::new(
                    50.0 * libm::cos(a),
                    50.0 * libm::sin(a),
                    turn as f64,
                ));
            }
        }
        for _ in 0..40_000 {
            let u = rng.next_u64();
            pts.push(DVec3::new(
                (u % 2001) as f64 / 10.0 - 100.0,
                f64::from_bits(rng.next_u64() >> 2) - 1.0,
                0.0,
            ));
        }
        // the same bits, or both NaN (a NaN's payload reaches no output,
        // and a computation folded at compile time may give another)
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        for p in pts.iter().chain(&pts) {
            let (r, t) = memo.of(*p);
            assert!(same(r, radius(*p)), "{p:?}: {r} {}", radius(*p));
            assert!(same(t, angle(*p)), "{p:?}: {t} {}", angle(*p));
        }
    }
}
