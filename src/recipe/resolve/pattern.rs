//! Resolving `pattern_helix` and `ca_helix` (Kanada's self-organised
//! patterns): range-checked numbers, errors naming `KIND.KEY`.

use glam::DVec3;

use crate::base::error::{Error, Result};
use crate::generate::primitive::ca::{Automaton, CaHelix, Initial, Layout, Rule};
use crate::generate::primitive::pattern::{FirstLayer, PatternHelix, FIRST_LAYER};
use crate::recipe::eval::NumFn;
use crate::recipe::schema::{Num, Num3};
use crate::recipe::schema::{RawCaHelix, RawInitial, RawLayout, RawPatternHelix, RawRule};

impl RawPatternHelix {
    /// Resolves every number, naming `pattern_helix.KEY` in errors.
    pub fn resolve(&self, num: NumFn) -> Result<PatternHelix> {
        let v = Values {
            num,
            key: "pattern_helix",
        };
        let positive = |n: &Option<Num>, name: &str, default: f64| {
            v.opt(n, name, default, |x| x > 0.0, "a number > 0")
        };
        let layer_height = v.positive(&self.layer_height, "layer_height")?;
        let (fc, fv) = match &self.first_layer {
            Some(f) => (&f.cross_section, &f.speed),
            None => (&None, &None),
        };
        Ok(PatternHelix {
            radius: v.positive(&self.radius, "radius")?,
            layers: v.whole(&self.layers, "layers", 1)?,
            layer_height,
            segments: match &self.segments {
                Some(n) => v.whole(n, "segments", 3)?,
                None => 72,
            },
            cross_section: match &self.cross_section {
                Some(n) => Some(v.positive(n, "cross_section")?),
                None => None,
            },
            speed: match &self.speed {
                Some(n) => Some(v.positive(n, "speed")?),
                None => None,
            },
            first_layer: FirstLayer {
                cross_section: positive(
                    fc,
                    "first_layer.cross_section",
                    FIRST_LAYER.cross_section,
                )?,
                speed: positive(fv, "first_layer.speed", FIRST_LAYER.speed)?,
            },
            center: v.center(&self.center, layer_height)?,
        })
    }
}

/// Range-checked numbers for the pattern primitives, errors naming `key.name`.
struct Values<'a> {
    /// The recipe's evaluator.
    pub num: NumFn<'a>,
    /// `ca_helix` or `pattern_helix`.
    pub key: &'static str,
}

impl Values<'_> {
    fn place(&self, name: &str) -> String {
        format!("{}.{name}", self.key)
    }

    fn bad(&self, name: &str, v: f64, expected: &str) -> Error {
        Error::input(
            self.place(name),
            format!("{v} is not allowed; expected {expected}"),
        )
    }

    /// A number in `ok`, else an error saying `expected`.
    pub fn checked(
        &self,
        n: &Num,
        name: &str,
        ok: impl Fn(f64) -> bool,
        expected: &str,
    ) -> Result<f64> {
        let v = (self.num)(n, &self.place(name))?;
        if ok(v) {
            Ok(v)
        } else {
            Err(self.bad(name, v, expected))
        }
    }

    /// `n`, or `default` when absent, checked the same way.
    pub fn opt(
        &self,
        n: &Option<Num>,
        name: &str,
        default: f64,
        ok: impl Fn(f64) -> bool,
        expected: &str,
    ) -> Result<f64> {
        match n {
            Some(n) => self.checked(n, name, ok, expected),
            None => Ok(default),
        }
    }

    /// A number > 0.
    pub fn positive(&self, n: &Num, name: &str) -> Result<f64> {
        self.checked(n, name, |v| v > 0.0, "a number > 0")
    }

    /// A whole number from `min` to 10000000.
    pub fn whole(&self, n: &Num, name: &str, min: u32) -> Result<u32> {
        let ok = |v: f64| v.fract() == 0.0 && v >= min as f64 && v <= 1e7;
        let expected = format!("a whole number from {min} to 10000000");
        Ok(self.checked(n, name, ok, &expected)? as u32)
    }

    /// The centre, [0, 0, `z`] when absent.
    pub fn center(&self, c: &Option<Num3>, z: f64) -> Result<DVec3> {
        match c {
            Some(c) => {
                let at = |k: usize| (self.num)(&c[k], &self.place(&format!("center[{k}]")));
                Ok(DVec3::new(at(0)?, at(1)?, at(2)?))
            }
            None => Ok(DVec3::new(0.0, 0.0, z)),
        }
    }
}

const PROBABILITY: &str = "a probability from 0 to 1";

impl RawCaHelix {
    /// Resolves every number, naming `ca_helix.KEY` in errors.
    pub fn resolve(&self, num: NumFn) -> Result<CaHelix> {
        let v = Values {
            num,
            key: "ca_helix",
        };
        let radius = v.positive(&self.radius, "radius")?;
        let layers = v.whole(&self.layers, "layers", 1)?;
        let layer_height = v.positive(&self.layer_height, "layer_height")?;
        let cells = match &self.cells {
            Some(n) => v.whole(n, "cells", 3)?,
            None => 4 * 72,
        };
        let rule = match self.rule {
            None | Some(RawRule::Basic) => Rule::Basic,
            Some(RawRule::SplitMerge) => Rule::SplitMerge,
        };
        let unit = |x: f64| (0.0..=1.0).contains(&x);
        let open = |x: f64| x > 0.0 && x < 1.0;
        let p0 = v.opt(&self.p0, "p0", 0.99, unit, PROBABILITY)?;
        let p1 = v.opt(&self.p1, "p1", 1.0, unit, PROBABILITY)?;
        let e1 = v.opt(
            &self.e1,
            "e1",
            0.3,
            open,
            "a number between 0 and 1 (0 < e1 < 1): the filament extruded per cell, in units of one chunk",
        )?;
        if rule == Rule::Basic && self.consume.is_some() {
            return Err(Error::input(
                v.place("consume"),
                "only the split_merge rule uses `consume` (C); expected `rule: split_merge` or no `consume`",
            ));
        }
        let consume = v.opt(
            &self.consume,
            "consume",
            0.5,
            open,
            "a number between 0 and 1 (0 < C < 1): the filament a straight stack uses",
        )?;
        let initial = match (self.initial.unwrap_or(RawInitial::Ones), &self.noise) {
            (RawInitial::Ones, Some(_)) => {
                return Err(Error::input(
                    v.place("noise"),
                    "`noise` is the fraction of zeros of a random first turn; expected `initial: random` or no `noise`",
                ))
            }
            (RawInitial::Ones, None) => Initial::Ones,
            (RawInitial::Random, noise) => Initial::Random {
                noise: v.opt(noise, "noise", 0.5, unit, "a fraction from 0 to 1")?,
            },
        };
        let seed = v.opt(
            &self.seed,
            "seed",
            0.0,
            |s| s.fract() == 0.0 && (0.0..=9007199254740992.0).contains(&s),
            "a whole number from 0 to 9007199254740992 (2^53)",
        )? as u64;
        Ok(CaHelix {
            radius,
            layer_height,
            center: v.center(&self.center, layer_height)?,
            model: Automaton {
                cells,
                layers,
                rule,
                layout: match self.layout {
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
}
