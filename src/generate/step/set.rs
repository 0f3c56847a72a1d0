//! `set`: the printer's settings as values of the position and of a band
//! index, written once per band before the band's first extruding string
//! (a calibration print's temperature, pressure advance, acceleration …).
//!
//! Height bands: band k holds the extruding strings whose end lies in
//! `[from + k·every, from + (k+1)·every)`. The index is
//! `floor((z − from)/every + 1e-9)`: a layer at exactly a band's edge (5.0
//! written as 25 × 0.2 = 5.000000000000001 or 4.999999999999999) belongs to
//! the band above it, whatever the rounding of its z; only the part's top,
//! when it lies on an edge, closes the band below it.
//!
//! A pace (`speed`, `volumetric_speed`) is no firmware setting: the band's
//! extruding strings carry it (v, or v = Q/c for a flow Q), from the band's
//! first string to the next band's, and a `Band` event marks the band.

use crate::base::error::{Error, Result};
use crate::base::expr::{var, Expr, Memo, Vars};
use crate::base::gcode::named::Named;
use crate::base::gcode::Setting;
use crate::base::toolpath::{Band, Event, Pace, Toolpath};

/// Where a `set` step's bands are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Bands {
    /// Height bands `every` mm tall from `from`.
    Height {
        /// Where band 0 begins, mm.
        from: f64,
        /// A band's height, mm.
        every: f64,
    },
    /// The whole part is band `k` (a line test's line).
    Line(u32),
    /// Once, at the first extruding string, no band.
    Once,
}

/// A `set` step resolved.
#[derive(Clone, Debug)]
pub(crate) struct Set {
    /// Its bands.
    pub(crate) bands: Bands,
    /// The settings: each value an expression of x, y, z (variables) and
    /// `band` (extra slot 0).
    pub(crate) named: Named<Expr>,
    /// What the band's extruding strings carry (`speed` or
    /// `volumetric_speed`), an expression as the settings' are: the band's
    /// value when given.
    pub(crate) pace: Option<(Pace, Expr)>,
}

/// The variables a `set` value may read.
pub(crate) const VARS: &[usize] = &[var::X, var::Y, var::Z];
/// The extra names a `set` value may read.
pub(crate) const NAMES: &[&str] = &["band"];

/// What one band of a `set` step holds: the firmware's settings, the
/// strings' pace (if any), and the band's value (the pace, else the first
/// setting's).
struct Held {
    settings: Vec<Setting>,
    pace: Option<f64>,
    value: f64,
}

impl Set {
    /// `e` at `vars` in band `band`, a finite number.
    fn value(e: &Expr, vars: &Vars, band: u32, memo: &mut Memo) -> Result<f64> {
        let v = e.eval_ext(vars, &[f64::from(band)], memo);
        if !v.is_finite() {
            return Err(Error::input(
                "",
                format!(
                    "`{}` gives {v} in band {band} at (x, y, z) = ({:.3}, {:.3}, {:.3}); expected a finite number",
                    e.src(),
                    vars[var::X],
                    vars[var::Y],
                    vars[var::Z]
                ),
            ));
        }
        Ok(v)
    }

    /// What band `band` holds at `vars`: the settings merged as the
    /// firmware sets them (print and travel acceleration in one, the
    /// shaper's values in one …), the pace, and the band's value.
    fn held(&self, vars: &Vars, band: u32, memo: &mut Memo) -> Result<Held> {
        let pace = match &self.pace {
            Some((kind, e)) => {
                let v = Set::value(e, vars, band, memo)?;
                if v <= 0.0 {
                    let (key, unit) = match kind {
                        Pace::Speed => ("speed", "mm/s"),
                        Pace::Volumetric => ("volumetric_speed", "mm³/s"),
                    };
                    return Err(Error::input(
                        key,
                        format!(
                            "`{}` gives {v} in band {band}; expected a speed above 0, {unit}",
                            e.src()
                        ),
                    ));
                }
                Some(v)
            }
            None => None,
        };
        let mut first = pace;
        let out = self.named.lower(|_, e| {
            let v = Set::value(e, vars, band, memo)?;
            first.get_or_insert(v);
            Ok(v)
        })?;
        Ok(Held {
            settings: out.into_iter().map(|(s, _)| s).collect(),
            pace,
            value: first.unwrap_or(0.0),
        })
    }

    /// The band of an extruding string ending at height `z` in a part whose
    /// top is `top`, and the band's heights; `None` below band 0.
    fn band_of(&self, z: f64, top: f64) -> Option<(u32, Option<[f64; 2]>)> {
        match self.bands {
            Bands::Height { from, every } => {
                let mut b = libm::floor((z - from) / every + 1e-9);
                if b < 0.0 || b >= f64::from(u32::MAX) {
                    return None;
                }
                // the part's top on an edge closes the band below it
                if b > 0.0 && from + b * every >= top - 1e-9 {
                    b -= 1.0;
                }
                let b = b as u32;
                let lo = from + f64::from(b) * every;
                Some((b, Some([lo, (lo + every).min(top.max(lo))])))
            }
            Bands::Line(b) => Some((b, None)),
            Bands::Once => Some((0, None)),
        }
    }

    /// Puts the settings into `tp` before the first extruding string of
    /// each band (after the events already there); with a pace, every
    /// extruding string from a band's first to the next band's carries
    /// the band's.
    pub(crate) fn apply(&self, tp: &mut Toolpath) -> Result<()> {
        let mut memo = Memo::default();
        let mut new: Vec<(usize, Event)> = Vec::new();
        let top = (0..tp.len())
            .filter(|&k| !tp.strings[k].travel)
            .map(|k| tp.points[k + 1].z)
            .fold(f64::NEG_INFINITY, f64::max);
        let mut last: Option<u32> = None;
        let mut pace: Option<f64> = None;
        for k in 0..tp.len() {
            if tp.strings[k].travel {
                continue;
            }
            let p = tp.points[k + 1];
            let Some((band, z)) = self.band_of(p.z, top) else {
                continue;
            };
            if last.is_none_or(|l| band > l) {
                last = Some(band);
                let mut vars = [0.0; var::COUNT];
                vars[var::X] = p.x;
                vars[var::Y] = p.y;
                vars[var::Z] = p.z;
                let held = self.held(&vars, band, &mut memo)?;
                pace = held.pace;
                self.mark(k, band, z, held, &mut new);
            }
            if let (Some(v), Some((kind, _))) = (pace, &self.pace) {
                let s = &mut tp.strings[k];
                s.v = match kind {
                    Pace::Speed => v,
                    // v = Q / c: the string's flow is the band's
                    Pace::Volumetric if s.c > 0.0 => v / s.c,
                    Pace::Volumetric => s.v,
                };
            }
        }
        merge_events(tp, new);
        Ok(())
    }

    /// The events of band `band` at string `k`: its mark (a `Band` event
    /// when a pace gives its value, else on its first setting) and its
    /// settings.
    fn mark(
        &self,
        k: usize,
        band: u32,
        z: Option<[f64; 2]>,
        held: Held,
        new: &mut Vec<(usize, Event)>,
    ) {
        let mut mark = (self.bands != Bands::Once).then_some(Band {
            index: band,
            value: held.value,
            z,
        });
        if let (Some(b), Some((pace, _))) = (mark, &self.pace) {
            new.push((
                k,
                Event::Band {
                    band: b,
                    pace: *pace,
                },
            ));
            mark = None;
        }
        for s in held.settings {
            new.push((
                k,
                Event::Set {
                    setting: s,
                    band: mark.take(),
                    place: None,
                },
            ));
        }
    }
}

/// `new` (sorted by string index) merged into `tp`'s events: each after
/// the events already at its index.
fn merge_events(tp: &mut Toolpath, new: Vec<(usize, Event)>) {
    if new.is_empty() {
        return;
    }
    let old = std::mem::take(&mut tp.events);
    let mut out = Vec::with_capacity(old.len() + new.len());
    let mut old = old.into_iter().peekable();
    for (k, e) in new {
        while let Some(o) = old.next_if(|(i, _)| *i <= k) {
            out.push(o);
        }
        out.push((k, e));
    }
    out.extend(old);
    tp.events = out;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::expr::Params;
    use crate::base::gcode::named::Key;
    use crate::base::gcode::Heater;
    use crate::base::toolpath::Strand;
    use glam::DVec3;

    /// A square wall of `layers` layers 0.2 mm apart, four strings a layer.
    fn wall(layers: usize) -> Toolpath {
        let mut tp = Toolpath::new(DVec3::new(0.0, 0.0, 0.2));
        let s = Strand {
            c: 0.2,
            v: 30.0,
            travel: false,
            hair: false,
        };
        for l in 0..layers {
            let z = 0.2 * (l + 1) as f64;
            for (x, y) in [(10.0, 0.0), (10.0, 10.0), (0.0, 10.0), (0.0, 0.0)] {
                tp.points.push(DVec3::new(x, y, z));
                tp.strings.push(s);
            }
        }
        tp
    }

    fn set(bands: Bands, src: &str) -> Set {
        Set {
            bands,
            named: Named {
                values: vec![(
                    Key::NozzleTemperature,
                    Expr::compile_ext(src, &Params::new(), VARS, NAMES).unwrap(),
                )],
                wait: false,
                shaper: None,
            },
            pace: None,
        }
    }

    #[test]
    fn one_setting_per_band_at_its_first_string_with_any_step() {
        for (every, step) in [(1.0, 5.0), (1.0, 2.5), (0.6, 3.0), (5.0, 1.0)] {
            let mut tp = wall(50); // 0.2 .. 10.0
            set(
                Bands::Height { from: 0.0, every },
                &format!("230 - band*{step}"),
            )
            .apply(&mut tp)
            .unwrap();
            let bands: Vec<(usize, Band)> = tp
                .events
                .iter()
                .map(|(k, e)| match e {
                    Event::Set { band: Some(b), .. } => (*k, *b),
                    e => panic!("{e:?}"),
                })
                .collect();
            // every band some layer reaches, each exactly once and in order
            // (the top, 10 mm, on an edge closes the band below it)
            let mut want: Vec<u32> = (1..=50)
                .map(|l| {
                    let b = libm::floor(0.2 * l as f64 / every + 1e-9) as u32;
                    if l == 50 && f64::from(b) * every >= 10.0 - 1e-9 {
                        b - 1
                    } else {
                        b
                    }
                })
                .collect();
            want.dedup();
            let got: Vec<u32> = bands.iter().map(|(_, b)| b.index).collect();
            assert_eq!(got, want, "every {every}");
            for (k, b) in &bands {
                assert_eq!(b.value, 230.0 - f64::from(b.index) * step);
                let lo = f64::from(b.index) * every;
                let z = tp.points[k + 1].z;
                assert!(z >= lo - 1e-6 && z < lo + every - 1e-6, "{z} {lo}");
                // the band's first string: every string before it ends in a band below
                let band_of = |z: f64| libm::floor(z / every + 1e-9) as u32;
                assert!(tp.points[1..=*k].iter().all(|p| band_of(p.z) < b.index));
            }
        }
    }

    #[test]
    fn a_layer_on_a_band_edge_opens_the_band_above() {
        let mut tp = wall(50);
        set(
            Bands::Height {
                from: 0.0,
                every: 1.0,
            },
            "band",
        )
        .apply(&mut tp)
        .unwrap();
        // layer 5 is at z = 5 × 0.2 (= 1.0000000000000002): band 1 begins there
        let (k, _) = tp.events[1];
        assert!(
            (tp.points[k + 1].z - 1.0).abs() < 1e-9,
            "{}",
            tp.points[k + 1].z
        );
    }

    #[test]
    fn a_line_band_is_written_once() {
        let mut tp = wall(3);
        set(Bands::Line(4), "200 + band").apply(&mut tp).unwrap();
        assert_eq!(tp.events.len(), 1);
        assert_eq!(
            tp.events[0].1,
            Event::Set {
                setting: Setting::Temperature {
                    heater: Heater::Nozzle(0),
                    celsius: 204.0,
                    wait: false
                },
                band: Some(Band {
                    index: 4,
                    value: 204.0,
                    z: None
                }),
                place: None,
            }
        );
    }
}
