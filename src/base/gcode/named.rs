//! Settings by name, as a recipe writes them (`pressure_advance: 0.04`),
//! made into [`Setting`]s the way a firmware sets them: the one lowering
//! that a `set` step and a turtle's or path's `set` command share.

use super::{Heater, Setting, Shaper};

/// A setting a `set` step or command may give a value to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Key {
    /// The nozzle's target, °C.
    NozzleTemperature,
    /// The part-cooling fan, 0 to 1.
    Fan,
    /// Pressure (linear) advance, s.
    PressureAdvance,
    /// p3dp's retraction length, mm.
    RetractionLength,
    /// p3dp's retraction speed, mm/s.
    RetractionSpeed,
    /// Print acceleration, mm/s².
    Acceleration,
    /// Travel acceleration, mm/s².
    TravelAcceleration,
    /// The head's speed limit, mm/s.
    SpeedLimit,
    /// Klipper's square-corner velocity, mm/s.
    SquareCornerVelocity,
    /// Marlin's junction deviation, mm.
    JunctionDeviation,
    /// Classic jerk, mm/s.
    Jerk,
    /// Input shaper frequency (both axes), Hz.
    ShaperFrequency,
    /// Input shaper damping ratio.
    ShaperDamping,
    /// Flow factor, 1 = 100 %.
    Flow,
}

impl Key {
    /// Every key, in the order of the docs.
    pub(crate) const ALL: [Key; 14] = [
        Key::NozzleTemperature,
        Key::Fan,
        Key::PressureAdvance,
        Key::RetractionLength,
        Key::RetractionSpeed,
        Key::Acceleration,
        Key::TravelAcceleration,
        Key::SpeedLimit,
        Key::SquareCornerVelocity,
        Key::JunctionDeviation,
        Key::Jerk,
        Key::ShaperFrequency,
        Key::ShaperDamping,
        Key::Flow,
    ];

    /// Its name as a recipe writes it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Key::NozzleTemperature => "nozzle_temperature",
            Key::Fan => "fan",
            Key::PressureAdvance => "pressure_advance",
            Key::RetractionLength => "retraction_length",
            Key::RetractionSpeed => "retraction_speed",
            Key::Acceleration => "acceleration",
            Key::TravelAcceleration => "travel_acceleration",
            Key::SpeedLimit => "speed_limit",
            Key::SquareCornerVelocity => "square_corner_velocity",
            Key::JunctionDeviation => "junction_deviation",
            Key::Jerk => "jerk",
            Key::ShaperFrequency => "input_shaper_frequency",
            Key::ShaperDamping => "input_shaper_damping",
            Key::Flow => "flow",
        }
    }

    /// The key of `name` as a recipe writes it.
    pub(crate) fn of(name: &str) -> Option<Key> {
        Key::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The setting this key gives at value `v` (`wait`: for a nozzle
    /// temperature, wait until it is reached).
    pub(crate) fn setting(self, v: f64, wait: bool) -> Setting {
        match self {
            Key::NozzleTemperature => Setting::Temperature {
                heater: Heater::Nozzle(0),
                celsius: v,
                wait,
            },
            Key::Fan => Setting::Fan { speed: v },
            Key::PressureAdvance => Setting::PressureAdvance { k: v },
            Key::RetractionLength => Setting::Retraction {
                length: Some(v),
                speed: None,
            },
            Key::RetractionSpeed => Setting::Retraction {
                length: None,
                speed: Some(v),
            },
            Key::Acceleration => Setting::Acceleration {
                print: Some(v),
                travel: None,
                retract: None,
            },
            Key::TravelAcceleration => Setting::Acceleration {
                print: None,
                travel: Some(v),
                retract: None,
            },
            Key::SpeedLimit => Setting::SpeedLimit { velocity: v },
            Key::SquareCornerVelocity => Setting::SquareCornerVelocity(v),
            Key::JunctionDeviation => Setting::JunctionDeviation(v),
            Key::Jerk => Setting::Jerk(v),
            Key::ShaperFrequency => Setting::InputShaper {
                frequency: [Some(v); 2],
                damping: None,
                kind: None,
            },
            Key::ShaperDamping => Setting::InputShaper {
                frequency: [None; 2],
                damping: Some(v),
                kind: None,
            },
            Key::Flow => Setting::Flow(v),
        }
    }
}

/// The key of an input shaper's kind, which takes a name, not a number.
pub(crate) const SHAPER_TYPE: &str = "input_shaper_type";

/// Settings by name, each value a `T` (an expression, compiled for where
/// it is written): what a `set` step or command gives.
#[derive(Clone, Debug)]
pub(crate) struct Named<T> {
    /// Each setting's value, in the order of the docs.
    pub(crate) values: Vec<(Key, T)>,
    /// Wait for the nozzle temperature.
    pub(crate) wait: bool,
    /// The input shaper's kind, if set.
    pub(crate) shaper: Option<Shaper>,
}

impl<T> Named<T> {
    /// The settings with each value `eval` gives, merged as the firmware
    /// sets them (print and travel acceleration in one command, the
    /// shaper's values in one …), each with the name of the first key that
    /// went into it (where a refusal points).
    pub(crate) fn lower<E>(
        &self,
        mut eval: impl FnMut(Key, &T) -> std::result::Result<f64, E>,
    ) -> std::result::Result<Vec<(Setting, &'static str)>, E> {
        let mut out: Vec<(Setting, &'static str)> = Vec::new();
        for (key, t) in &self.values {
            let v = eval(*key, t)?;
            merge(&mut out, key.setting(v, self.wait), key.name());
        }
        if let Some(kind) = self.shaper {
            let s = Setting::InputShaper {
                frequency: [None; 2],
                damping: None,
                kind: Some(kind),
            };
            merge(&mut out, s, SHAPER_TYPE);
        }
        Ok(out)
    }
}

/// Adds `s` (of key `name`) to `out`, into the setting of its kind already
/// there when the firmware sets both in one command (accelerations,
/// retraction, shaper).
fn merge(out: &mut Vec<(Setting, &'static str)>, s: Setting, name: &'static str) {
    for (o, _) in out.iter_mut() {
        match (o, s) {
            (
                Setting::Acceleration { print, travel, .. },
                Setting::Acceleration {
                    print: p,
                    travel: t,
                    ..
                },
            ) => {
                *print = p.or(*print);
                *travel = t.or(*travel);
                return;
            }
            (
                Setting::Retraction { length, speed },
                Setting::Retraction {
                    length: l,
                    speed: v,
                },
            ) => {
                *length = l.or(*length);
                *speed = v.or(*speed);
                return;
            }
            (
                Setting::InputShaper {
                    frequency,
                    damping,
                    kind,
                },
                Setting::InputShaper {
                    frequency: f,
                    damping: d,
                    kind: k,
                },
            ) => {
                for a in 0..2 {
                    frequency[a] = f[a].or(frequency[a]);
                }
                *damping = d.or(*damping);
                *kind = k.or(*kind);
                return;
            }
            _ => {}
        }
    }
    out.push((s, name));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_reads_back_as_its_key() {
        for k in Key::ALL {
            assert_eq!(Key::of(k.name()), Some(k));
        }
        assert_eq!(Key::of(SHAPER_TYPE), None);
    }

    #[test]
    fn what_one_command_sets_is_merged_and_named_by_its_first_key() {
        let named = Named {
            values: vec![
                (Key::TravelAcceleration, 5000.0),
                (Key::PressureAdvance, 0.04),
                (Key::Acceleration, 3000.0),
                (Key::ShaperDamping, 0.1),
            ],
            wait: false,
            shaper: Some(Shaper::Mzv),
        };
        let got = named
            .lower(|_, v| Ok::<f64, ()>(*v * 1.0))
            .expect("finite values");
        assert_eq!(
            got,
            vec![
                (
                    Setting::Acceleration {
                        print: Some(3000.0),
                        travel: Some(5000.0),
                        retract: None
                    },
                    "travel_acceleration"
                ),
                (Setting::PressureAdvance { k: 0.04 }, "pressure_advance"),
                (
                    Setting::InputShaper {
                        frequency: [None; 2],
                        damping: Some(0.1),
                        kind: Some(Shaper::Mzv)
                    },
                    "input_shaper_damping"
                ),
            ]
        );
        // an evaluation's error stops the lowering
        assert_eq!(
            named.lower(|k, _| Err::<f64, Key>(k)),
            Err(Key::TravelAcceleration)
        );
    }
}
