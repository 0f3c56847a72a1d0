//! The junction speed at a corner between two moves: the "approximated
//! centripetal acceleration" both firmwares take from Grbl (Marlin's junction
//! deviation, Klipper's square-corner velocity).

use glam::DVec3;

use super::{Last, Planner};

/// The shape of the corner between two moves of unit directions `a` and
/// `b`, which depends on nothing else (see [`Planner::junction_v2`]).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Turn {
    /// |a − b|² = 4·cos²(θ/2), at most 4: 0 straight on.
    w: f64,
    /// cos²(θ/2).
    cos_half2: f64,
    /// sin(θ/2): 0 a full reversal.
    sin_half: f64,
    /// The junction circle's radius over δ: sin/(1 − sin) of θ/2.
    r: f64,
    /// cos(θ/2).
    x: f64,
}

impl Turn {
    /// The corner from direction `a` into direction `b`.
    pub(super) fn new(a: DVec3, b: DVec3) -> Turn {
        // w = |u1 − u2|² = 2·(1 − cos φ) = 4·cos²(θ/2): stable for small turns
        let w = (a - b).length_squared().min(4.0);
        let mut t = Turn {
            w,
            ..Turn::default()
        };
        if w <= 0.0 {
            return t; // straight on
        }
        t.cos_half2 = 0.25 * w; // cos²(θ/2)
        t.sin_half = (1.0 - t.cos_half2).max(0.0).sqrt(); // sin(θ/2)
        if t.sin_half <= 0.0 {
            return t; // a full reversal
        }
        // sin/(1 − sin) = sin·(1 + sin)/cos², exact where sin is near 1
        t.r = t.sin_half * (1.0 + t.sin_half) / t.cos_half2;
        t.x = t.cos_half2.sqrt();
        t
    }
}

impl Planner {
    /// Highest v² at the corner from `prev` into a block along `dir` of length
    /// `len`, acceleration `accel` (`accel_share` of its kind's) and cruise
    /// v² `cruise_v2` (never above either block's cruise v²).
    ///
    /// With θ the angle between the reversed incoming direction and the
    /// outgoing one (θ = 180° straight on, 90° a square corner, 0 a reversal),
    /// both firmwares use the "approximated centripetal acceleration" of
    /// Grbl (Marlin's junction deviation; Klipper's Kinematics document): a
    /// circle tangent to both moves whose closest approach to the corner is δ
    /// has radius R = δ·sin(θ/2) / (1 − sin(θ/2)), and the speed on it at
    /// acceleration a is v² = a·R.
    ///
    /// - Marlin: δ = `junction_deviation`, a the outgoing block's
    ///   acceleration. With `JD_HANDLE_SMALL_SEGMENTS` (on in Marlin's default
    ///   configuration) a block shorter than 1 mm turning by less than 45° is
    ///   taken as a chord of an arc of radius L / φ (φ = π − θ the turn), so
    ///   also v² ≤ a·L / φ. (Marlin approximates φ by a polynomial that never
    ///   goes below 0.033 rad; here φ is exact.)
    /// - Klipper: δ = scv²·(√2 − 1) / a_nom with a_nom its `max_accel`, and
    ///   v² = R·δ·a for each of the two moves' own a, so a 90° corner gets
    ///   exactly scv (less where the Z axis lowers a move's a); and the
    ///   circle must touch each move no further than its middle:
    ///   v² ≤ ½·L·a·tan(θ/2) for both moves.
    pub(super) fn junction_v2(
        &self,
        prev: &Last,
        t: &Turn,
        len: f64,
        accel: f64,
        accel_share: f64,
        cruise_v2: f64,
    ) -> f64 {
        let both = cruise_v2.min(prev.cruise_v2);
        if t.w <= 0.0 {
            return both; // straight on
        }
        if t.sin_half <= 0.0 {
            return 0.0; // a full reversal stops the head
        }
        let (cos_half2, sin_half, r) = (t.cos_half2, t.sin_half, t.r);
        match (
            self.limits.square_corner_velocity,
            self.limits.junction_deviation,
        ) {
            (Some(scv), _) => {
                let share = accel_share.min(prev.accel_share);
                let jd_v2 = r * scv * scv * (std::f64::consts::SQRT_2 - 1.0) * share;
                let tan_half = sin_half / t.x; // t.x = √cos²(θ/2)
                let c_this = 0.5 * len * accel * tan_half;
                let c_prev = 0.5 * prev.len * prev.accel * tan_half;
                jd_v2.min(c_this).min(c_prev).min(both)
            }
            (None, Some(delta)) => {
                let mut v2 = r * accel * delta;
                // turn φ = π − θ = 2·asin(cos(θ/2)); φ < 45° ⇔ θ > 135°
                // ⇔ cos²(θ/2) < sin²(22.5°) = (1 − √½)/2
                const SMALL_TURN: f64 = 0.5 * (1.0 - std::f64::consts::FRAC_1_SQRT_2);
                let cap = v2.min(both);
                // 2x ≤ 2·asin x ≤ π·x: skip the asin when even the largest φ
                // leaves a limit above the others
                let x = t.x;
                if len < 1.0
                    && cos_half2 < SMALL_TURN
                    && len * accel < cap * std::f64::consts::PI * x
                {
                    let phi = 2.0 * libm::asin(x.min(1.0));
                    v2 = v2.min(len * accel / phi);
                }
                v2.min(both)
            }
            (None, None) => both,
        }
    }
}
