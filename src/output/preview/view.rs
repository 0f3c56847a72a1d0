//! What a preview shows: the still views (each an orthonormal basis, see
//! the projection in [`super`]), the colour modes and their scale, and the
//! options a caller picks them by.

use glam::DVec3;

use crate::machine::Size;

/// Where the still views look from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum View {
    /// Isometric, from the front right and above.
    #[default]
    Iso,
    /// From above: x to the right, y up the image.
    Top,
    /// From the front (−y): x to the right, z up.
    Front,
    /// From the right (+x): y to the right, z up.
    Side,
}

/// An orthonormal view basis in recipe coordinates (right × up = toward).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Basis {
    /// Screen right.
    pub(crate) right: DVec3,
    /// Screen up.
    pub(crate) up: DVec3,
    /// Towards the viewer; depth grows along it.
    pub(crate) toward: DVec3,
}

impl View {
    /// The view's name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            View::Iso => "iso",
            View::Top => "top",
            View::Front => "front",
            View::Side => "side",
        }
    }

    /// The view's basis.
    pub(crate) fn basis(self) -> Basis {
        match self {
            View::Top => Basis {
                right: DVec3::X,
                up: DVec3::Y,
                toward: DVec3::Z,
            },
            View::Front => Basis {
                right: DVec3::X,
                up: DVec3::Z,
                toward: DVec3::NEG_Y,
            },
            View::Side => Basis {
                right: DVec3::Y,
                up: DVec3::Z,
                toward: DVec3::X,
            },
            View::Iso => {
                // the viewer on the diagonal (1, −1, 1): right = z × toward
                // (horizontal), up = toward × right (completes the basis)
                let toward = DVec3::new(1.0, -1.0, 1.0).normalize();
                let right = DVec3::Z.cross(toward).normalize();
                Basis {
                    right,
                    up: toward.cross(right),
                    toward,
                }
            }
        }
    }
}

impl Basis {
    /// Screen-plane coordinates (u, w) and depth d of recipe point `p`.
    pub(crate) fn project(&self, p: DVec3) -> (f64, f64, f64) {
        (p.dot(self.right), p.dot(self.up), p.dot(self.toward))
    }
}

/// What the colour of a string shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum ColorMode {
    /// Head speed v, mm/s.
    #[default]
    Speed,
    /// Cross-section c, mm².
    CrossSection,
    /// Volumetric flow c·v, mm³/s.
    Flow,
    /// Print order, as the print time at which the string is laid, min.
    Order,
    /// Grey, with the strings the checks found problems in red.
    Findings,
    /// One filament colour (the G-code thumbnails).
    Plain,
}

impl ColorMode {
    /// The names `--color` accepts.
    pub(crate) const NAMES: [&'static str; 6] = [
        "speed",
        "cross-section",
        "flow",
        "order",
        "findings",
        "plain",
    ];

    /// The mode's name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            ColorMode::Speed => "speed",
            ColorMode::CrossSection => "cross-section",
            ColorMode::Flow => "flow",
            ColorMode::Order => "order",
            ColorMode::Findings => "findings",
            ColorMode::Plain => "plain",
        }
    }

    /// The unit of the scale, for the legend.
    pub(crate) fn unit(self) -> &'static str {
        match self {
            ColorMode::Speed => "mm/s",
            ColorMode::CrossSection => "mm²",
            ColorMode::Flow => "mm³/s",
            ColorMode::Order => "min",
            ColorMode::Findings | ColorMode::Plain => "",
        }
    }

    /// Whether the colour shows a number of each string (else every
    /// string's value is 0, [`super::Scene::value`]).
    pub(crate) fn has_value(self) -> bool {
        !matches!(self, ColorMode::Findings | ColorMode::Plain)
    }
}

/// What a preview shows and how big.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Options {
    /// Still view (the HTML viewer starts there).
    pub(crate) view: View,
    /// Colour mode (the HTML viewer starts there).
    pub(crate) color: ColorMode,
    /// Image size (PNG only).
    pub(crate) size: Size,
    /// Only the model: no title, stats or legend (PNG only).
    pub(crate) bare: bool,
}

/// Colour stops of the scalar modes: blue, cyan, green, yellow, red.
pub(crate) const STOPS: [[f32; 3]; 5] = [
    [0.23, 0.30, 0.85],
    [0.10, 0.65, 0.95],
    [0.25, 0.85, 0.45],
    [0.98, 0.80, 0.20],
    [0.90, 0.25, 0.15],
];

/// The colour of `t` in [0, 1] on the scale of [`STOPS`].
pub(crate) fn colormap(t: f64) -> [f32; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as f64;
    let k = (x.floor() as usize).min(STOPS.len() - 2);
    let f = (x - k as f64) as f32;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * f)
}

/// A number for a legend: three significant figures or so, no exponent.
pub(crate) fn fmt_value(v: f64) -> String {
    let a = v.abs();
    let s = if a >= 100.0 || a == 0.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    };
    match s.strip_prefix('-') {
        // never `-0.000`
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn view_bases_are_right_handed_and_orthonormal() {
        for view in [View::Iso, View::Top, View::Front, View::Side] {
            let b = view.basis();
            assert!(
                (b.right.cross(b.up) - b.toward).length() < 1e-12,
                "{view:?}"
            );
            for v in [b.right, b.up, b.toward] {
                assert!((v.length() - 1.0).abs() < 1e-12);
            }
            assert!(b.right.dot(b.up).abs() < 1e-12);
        }
        // iso: the z axis points up the image, the x axis to the lower right
        let b = View::Iso.basis();
        assert!(b.up.z > 0.0 && b.right.z == 0.0);
        assert!(DVec3::X.dot(b.right) > 0.0 && DVec3::X.dot(b.up) < 0.0);
    }

    #[test]
    fn sizes_parse() {
        assert_eq!(
            Size::parse("220x124", "s").unwrap(),
            Size {
                width: 220,
                height: 124
            }
        );
        assert_eq!(Size::parse("16X16", "s").unwrap().width, 16);
        for bad in ["", "12", "0x5", "5x", "ax3", "9000x10", "-3x4"] {
            assert!(Size::parse(bad, "--size").is_err(), "{bad}");
        }
    }

    #[test]
    fn colormap_ends_and_middle() {
        assert_eq!(colormap(0.0), STOPS[0]);
        assert_eq!(colormap(1.0), STOPS[4]);
        assert_eq!(colormap(0.5), STOPS[2]);
        assert_eq!(colormap(f64::NAN), STOPS[0]);
        assert_eq!(colormap(7.0), STOPS[4]);
    }

    #[test]
    fn legend_numbers() {
        assert_eq!(fmt_value(123.456), "123");
        assert_eq!(fmt_value(12.345), "12.3");
        assert_eq!(fmt_value(0.19634), "0.196");
        assert_eq!(fmt_value(-0.0001), "0.000");
        assert_eq!(fmt_value(-2.5), "-2.50");
        assert_eq!(fmt_value(0.0), "0");
    }
}
