//! The turtle's frame: a position and three orthonormal axes.
//!
//! `heading` (h), `left` (l) and `up` (u) form a right-handed frame,
//! h × l = u (with h = +x and u = +z, left is +y). Every turn rotates two of
//! the axes in their own plane by an angle in degrees and leaves the third:
//!
//! - `yaw(a)`:   h ← h·cos a + l·sin a, l ← l·cos a − h·sin a (about up,
//!   right-handed: seen from above with up = +z, a > 0 turns left);
//! - `pitch(a)`: h ← h·cos a + u·sin a, u ← u·cos a − h·sin a (about the
//!   left axis; a > 0 raises the nose);
//! - `roll(a)`:  l ← l·cos a + u·sin a, u ← u·cos a − l·sin a (about the
//!   heading, right-handed: a > 0 lifts the left side).
//!
//! Sines and cosines of whole multiples of 90° are exact (the angle is
//! reduced to [−45°, 45°] plus quarter turns before `libm` sees it), and the
//! frame is made orthonormal again after every turn (Gram–Schmidt), so
//! rounding never accumulates into a skewed frame.

use std::fmt;

use glam::DVec3;

/// Why a frame cannot face the way asked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FrameError {
    /// The heading is the zero vector.
    ZeroHeading,
    /// `up` is zero or parallel to the heading.
    BadUp,
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FrameError::ZeroHeading => "the heading must not be zero",
            FrameError::BadUp => "`up` must not be zero nor parallel to the heading",
        })
    }
}

impl std::error::Error for FrameError {}

/// Where the turtle is and which way it faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frame {
    /// Position, recipe coordinates, mm.
    pub(crate) pos: DVec3,
    /// Unit heading: where `forward` goes.
    pub(crate) heading: DVec3,
    /// Unit left axis: up × heading.
    pub(crate) left: DVec3,
    /// Unit up axis: where `lift` goes.
    pub(crate) up: DVec3,
}

/// sin and cos of `deg` degrees, exact at multiples of 90°.
pub(crate) fn sin_cos_deg(deg: f64) -> (f64, f64) {
    let a = deg - 360.0 * libm::floor(deg / 360.0); // [0, 360]
    let q = libm::round(a / 90.0); // quarter turns, 0..=4
    let r = (a - 90.0 * q) * (std::f64::consts::PI / 180.0); // [-pi/4, pi/4]
    let (s, c) = if r == 0.0 {
        (0.0, 1.0)
    } else {
        (libm::sin(r), libm::cos(r))
    };
    match q as i64 % 4 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// Rotates the pair (a, b) in its plane: a towards b by `deg`.
fn turn(a: DVec3, b: DVec3, deg: f64) -> (DVec3, DVec3) {
    let (s, c) = sin_cos_deg(deg);
    (a * c + b * s, b * c - a * s)
}

impl Frame {
    /// A frame at `pos` facing `heading`, with `up` made perpendicular to it.
    pub(crate) fn new(pos: DVec3, heading: DVec3, up: DVec3) -> Result<Frame, FrameError> {
        let h = heading.try_normalize().ok_or(FrameError::ZeroHeading)?;
        // the part of `up` across the heading; none when they are parallel
        let across = h.cross(up).length() > 1e-9 * up.length();
        let u = (up - h * up.dot(h))
            .try_normalize()
            .filter(|_| across)
            .ok_or(FrameError::BadUp)?;
        let mut f = Frame {
            pos,
            heading: h,
            left: u.cross(h),
            up: u,
        };
        f.orthonormalize();
        Ok(f)
    }

    /// Gram–Schmidt from the heading: h, then l ⟂ h, then u = h × l.
    fn orthonormalize(&mut self) {
        let h = self.heading.normalize();
        let l = (self.left - h * self.left.dot(h)).normalize();
        self.heading = h;
        self.left = l;
        self.up = h.cross(l);
    }

    /// The frame's Tait–Bryan angles in degrees, `[yaw, pitch, roll]`: the
    /// turns `yaw(a)`, `pitch(b)`, `roll(c)` from the start frame (heading
    /// +x, up +z) in that order give back `[a, b, c]` for |b| < 90°.
    /// yaw = atan2(h_y, h_x), pitch = asin(h_z), roll = atan2(l_z, u_z)
    /// (the left axis rises by sin c · cos b, up keeps cos c · cos b).
    pub(crate) fn angles(&self) -> [f64; 3] {
        let h = self.heading;
        [
            libm::atan2(h.y, h.x).to_degrees(),
            libm::asin(h.z.clamp(-1.0, 1.0)).to_degrees(),
            libm::atan2(self.left.z, self.up.z).to_degrees(),
        ]
    }

    /// Turns about the up axis; positive turns left.
    pub(crate) fn yaw(&mut self, deg: f64) {
        (self.heading, self.left) = turn(self.heading, self.left, deg);
        self.orthonormalize();
    }

    /// Turns about the left axis; positive raises the nose.
    pub(crate) fn pitch(&mut self, deg: f64) {
        (self.heading, self.up) = turn(self.heading, self.up, deg);
        self.left = self.up.cross(self.heading);
        self.orthonormalize();
    }

    /// Turns about the heading; positive lifts the left side.
    pub(crate) fn roll(&mut self, deg: f64) {
        (self.left, self.up) = turn(self.left, self.up, deg);
        self.orthonormalize();
    }

    /// Faces `heading`; with `up`, the up axis is `up` made perpendicular to
    /// it, else the frame turns by the smallest rotation taking the old
    /// heading to the new one (about up when they are opposite).
    pub(crate) fn set_heading(
        &mut self,
        heading: DVec3,
        up: Option<DVec3>,
    ) -> Result<(), FrameError> {
        if let Some(up) = up {
            *self = Frame::new(self.pos, heading, up)?;
            return Ok(());
        }
        let h = heading.try_normalize().ok_or(FrameError::ZeroHeading)?;
        let axis = self.heading.cross(h);
        let (sin, cos) = (axis.length(), self.heading.dot(h));
        let l = if sin < 1e-12 {
            if cos > 0.0 {
                self.left
            } else {
                -self.left // half a turn about up
            }
        } else {
            // Rodrigues: rotate `left` about k by the angle between headings
            let k = axis / sin;
            let l = self.left;
            l * cos + k.cross(l) * sin + k * k.dot(l) * (1.0 - cos)
        };
        self.heading = h;
        self.left = l;
        self.orthonormalize();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn start() -> Frame {
        Frame::new(DVec3::ZERO, DVec3::X, DVec3::Z).unwrap()
    }

    #[test]
    fn quarter_turns_are_exact() {
        for k in -8..=8 {
            let (s, c) = sin_cos_deg(90.0 * k as f64);
            assert!(s.fract() == 0.0 && c.fract() == 0.0, "{k}: {s} {c}");
            assert_eq!(s * s + c * c, 1.0);
        }
        let (s, c) = sin_cos_deg(30.0);
        assert!((s - 0.5).abs() < 2e-16 && (c - 0.75f64.sqrt()).abs() < 2e-16);
        let mut f = start();
        f.yaw(90.0);
        assert_eq!(f.heading, DVec3::Y);
        assert_eq!(f.left, -DVec3::X);
        f.pitch(90.0);
        assert_eq!(f.heading, DVec3::Z);
        assert_eq!(f.up, -DVec3::Y);
    }

    #[test]
    fn conventions() {
        let mut f = start();
        assert_eq!(f.left, DVec3::Y);
        f.roll(90.0);
        assert_eq!((f.left, f.up), (DVec3::Z, -DVec3::Y));
        let mut f = start();
        f.pitch(30.0);
        assert!(f.heading.z > 0.0, "pitch up raises the nose");
    }

    #[test]
    fn a_sequence_and_its_inverse_return_the_frame() {
        let mut f = start();
        let turns = [(0, 37.0), (1, -71.5), (2, 123.0), (0, 200.0), (1, 13.25)];
        let apply = |f: &mut Frame, axis: usize, a: f64| match axis {
            0 => f.yaw(a),
            1 => f.pitch(a),
            _ => f.roll(a),
        };
        for &(axis, a) in &turns {
            apply(&mut f, axis, a);
        }
        for &(axis, a) in turns.iter().rev() {
            apply(&mut f, axis, -a);
        }
        let g = start();
        for (a, b) in [(f.heading, g.heading), (f.left, g.left), (f.up, g.up)] {
            assert!((a - b).length() < 1e-14, "{a} vs {b}");
        }
    }

    #[test]
    fn set_heading_turns_least() {
        let mut f = start();
        f.set_heading(DVec3::new(0.0, 1.0, 0.0), None).unwrap();
        assert!((f.up - DVec3::Z).length() < 1e-15);
        f.set_heading(DVec3::new(0.0, -3.0, 0.0), None).unwrap();
        assert!((f.up - DVec3::Z).length() < 1e-15 && (f.heading + DVec3::Y).length() < 1e-15);
        f.set_heading(DVec3::X, Some(DVec3::new(0.0, 1.0, 1.0)))
            .unwrap();
        assert!((f.up - DVec3::new(0.0, 1.0, 1.0).normalize()).length() < 1e-15);
        assert_eq!(
            f.set_heading(DVec3::X, Some(DVec3::X)),
            Err(FrameError::BadUp)
        );
        assert_eq!(
            f.set_heading(DVec3::ZERO, None),
            Err(FrameError::ZeroHeading)
        );
    }

    #[test]
    fn angles_give_back_the_turns() {
        for (a, b, c) in [
            (0.0, 0.0, 0.0),
            (30.0, 0.0, 0.0),
            (-135.0, 20.0, 0.0),
            (60.0, -45.0, 15.0),
            (170.0, 80.0, -100.0),
        ] {
            let mut f = Frame::new(DVec3::ZERO, DVec3::X, DVec3::Z).unwrap();
            f.yaw(a);
            f.pitch(b);
            f.roll(c);
            let got = f.angles();
            for (g, w) in got.iter().zip([a, b, c]) {
                assert!((g - w).abs() < 1e-9, "{a} {b} {c}: {got:?}");
            }
        }
    }
}
