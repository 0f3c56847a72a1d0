//! Resolving `pattern_helix` and `ca_helix` (Kanada's self-organised
//! patterns): range-checked numbers, errors naming `KIND.KEY`.

use glam::DVec3;

use crate::base::error::Result;
use crate::generate::primitive::ca::{Automaton, CaHelix, Initial, Layout, Rule};
use crate::generate::primitive::pattern::{FirstLayer, PatternHelix, FIRST_LAYER};
use crate::recipe::eval::{at, key, Scope};
use crate::recipe::schema::{RawCaHelix, RawInitial, RawLayout, RawPatternHelix, RawRule};

/// `pattern_helix:` every number resolved; `s` is under `pattern_helix`.
pub(super) fn pattern_helix(raw: &RawPatternHelix, s: &Scope) -> Result<PatternHelix> {
    let layer_height = s.positive(at!(raw.layer_height))?;
    // the fields in the order they were always read (the first error wins)
    Ok(PatternHelix {
        radius: s.positive(at!(raw.radius))?,
        layers: s.whole(at!(raw.layers), 1)?,
        layer_height,
        segments: s.segments(at!(raw.segments))?,
        cross_section: at!(raw.cross_section)
            .some()
            .map(|n| s.positive(n))
            .transpose()?,
        speed: at!(raw.speed).some().map(|n| s.positive(n)).transpose()?,
        first_layer: match &raw.first_layer {
            Some(f) => {
                let s = s.under(key!(raw.first_layer));
                FirstLayer {
                    cross_section: s
                        .positive_or(at!(f.cross_section), FIRST_LAYER.cross_section)?,
                    speed: s.positive_or(at!(f.speed), FIRST_LAYER.speed)?,
                }
            }
            None => FIRST_LAYER,
        },
        center: s.point_or(at!(raw.center), DVec3::new(0.0, 0.0, layer_height))?,
    })
}

const PROBABILITY: &str = "a probability from 0 to 1";

/// `ca_helix:` every number resolved; `s` is under `ca_helix`.
pub(super) fn ca_helix(raw: &RawCaHelix, s: &Scope) -> Result<CaHelix> {
    let radius = s.positive(at!(raw.radius))?;
    let layers = s.whole(at!(raw.layers), 1)?;
    let layer_height = s.positive(at!(raw.layer_height))?;
    let cells = match at!(raw.cells).some() {
        Some(n) => s.whole(n, 3)?,
        None => 4 * 72,
    };
    let rule = match raw.rule {
        None | Some(RawRule::Basic) => Rule::Basic,
        Some(RawRule::SplitMerge) => Rule::SplitMerge,
    };
    let unit = |x: f64| (0.0..=1.0).contains(&x);
    let open = |x: f64| x > 0.0 && x < 1.0;
    let p0 = s.checked_or(at!(raw.p0), 0.99, unit, PROBABILITY)?;
    let p1 = s.checked_or(at!(raw.p1), 1.0, unit, PROBABILITY)?;
    let e1 = s.checked_or(
        at!(raw.e1),
        0.3,
        open,
        "a number between 0 and 1 (0 < e1 < 1): the filament extruded per cell, in units of one chunk",
    )?;
    if rule == Rule::Basic && raw.consume.is_some() {
        return Err(s.error(
            key!(raw.consume),
            "only the split_merge rule uses `consume` (C); expected `rule: split_merge` or no `consume`",
        ));
    }
    let consume = s.checked_or(
        at!(raw.consume),
        0.5,
        open,
        "a number between 0 and 1 (0 < C < 1): the filament a straight stack uses",
    )?;
    let initial = match raw.initial.unwrap_or(RawInitial::Ones) {
        RawInitial::Ones if raw.noise.is_some() => {
            return Err(s.error(
                key!(raw.noise),
                "`noise` is the fraction of zeros of a random first turn; expected `initial: random` or no `noise`",
            ))
        }
        RawInitial::Ones => Initial::Ones,
        RawInitial::Random => Initial::Random {
            noise: s.checked_or(at!(raw.noise), 0.5, unit, "a fraction from 0 to 1")?,
        },
    };
    let seed = s.checked_or(
        at!(raw.seed),
        0.0,
        |x| x.fract() == 0.0 && (0.0..=9007199254740992.0).contains(&x),
        "a whole number from 0 to 9007199254740992 (2^53)",
    )? as u64;
    Ok(CaHelix {
        radius,
        layer_height,
        center: s.point_or(at!(raw.center), DVec3::new(0.0, 0.0, layer_height))?,
        model: Automaton {
            cells,
            layers,
            rule,
            layout: match raw.layout {
                None | Some(RawLayout::Helix) => Layout::Helix,
                Some(RawLayout::Layers) => Layout::Layers,
            },
            p0,
            p1,
            consume,
            e1,
            initial,
            seed,
        },
    })
}
