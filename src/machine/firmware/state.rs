//! The firmware's state as the commands run: where the head is (when it is
//! known), how positions and E are read, the feed, and what each command
//! does to the head and the filament ([`Motion`]). The planner, the
//! progress clock, the previews, the check of a profile's G-code and the
//! tests all follow a print through this one model.
//!
//! Modes as each firmware keeps them: Marlin's (Prusa's, Bambu's) `G90`
//! and `G91` set E's mode with the axes' (so `M82`/`M83` must follow them),
//! Klipper and RepRapFirmware read E relative under `G91` or `M83`; a `G92`
//! redefines the position of the axes it names.

use crate::base::gcode::{Command, Move};
use crate::machine::printer::Flavor;

/// What a command did to the head and the filament.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Motion {
    /// Nothing that moves.
    None,
    /// A straight move of the head (and the filament it feeds).
    Line {
        /// Where the head was, per axis (`None`: unknown).
        from: [Option<f64>; 3],
        /// Where it is now, per axis.
        to: [Option<f64>; 3],
        /// Filament fed, mm (negative: pulled back).
        de: f64,
        /// The feed it ran at, mm/min (`None`: never set).
        feed: Option<f64>,
        /// A `G0`.
        travel: bool,
    },
    /// An arc in the XY plane round `center` (machine XY), counter-clockwise
    /// when `ccw`, from `from` to `to`.
    Arc {
        /// The start.
        from: [f64; 3],
        /// The end.
        to: [f64; 3],
        /// The centre.
        center: [f64; 2],
        /// Counter-clockwise.
        ccw: bool,
        /// Filament fed, mm.
        de: f64,
        /// The feed, mm/min.
        feed: Option<f64>,
    },
    /// The head stands for this many seconds.
    Dwell(f64),
    /// The firmware's own motion (homing, a pause, a firmware retraction)
    /// or a wait: the head comes to rest.
    Stop,
}

/// The firmware's state (see the module comment).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct State {
    flavor: Flavor,
    /// Machine position per axis, when known.
    pub(crate) pos: [Option<f64>; 3],
    /// `G91`: XYZ relative.
    pub(crate) relative_xyz: bool,
    /// `M83` (and under Marlin, `G91`): E relative.
    relative_e: bool,
    /// E as the firmware counts it, mm.
    pub(crate) e: f64,
    /// The feed in force, mm/min.
    pub(crate) feed: Option<f64>,
    /// `G20`: inches.
    pub(crate) inches: bool,
}

impl State {
    /// A firmware just started: position unknown, absolute XYZ and E.
    pub(crate) fn new(flavor: Flavor) -> State {
        State {
            flavor,
            pos: [None; 3],
            relative_xyz: false,
            relative_e: false,
            e: 0.0,
            feed: None,
            inches: false,
        }
    }

    /// A firmware whose head is at `pos` (machine coordinates).
    pub(crate) fn at(flavor: Flavor, pos: [f64; 3]) -> State {
        State {
            pos: pos.map(Some),
            ..State::new(flavor)
        }
    }

    /// Whether E values are read as steps.
    pub(crate) fn e_relative(&self) -> bool {
        match self.flavor {
            Flavor::Marlin | Flavor::Prusa | Flavor::Bambu => self.relative_e,
            Flavor::Klipper | Flavor::Reprap => self.relative_e || self.relative_xyz,
        }
    }

    /// Runs `c`: the state follows it, and the motion it makes is returned.
    pub(crate) fn apply(&mut self, c: &Command) -> Motion {
        match c {
            Command::Move(m) => self.line(m),
            Command::Arc(a) => {
                let from = self.pos;
                let m = Move {
                    travel: false,
                    to: a.to,
                    e: a.e,
                    feed: a.feed,
                };
                let Motion::Line { to, de, feed, .. } = self.line(&m) else {
                    return Motion::Stop;
                };
                match (from, to) {
                    ([Some(x0), Some(y0), Some(z0)], [Some(x1), Some(y1), Some(z1)]) => {
                        Motion::Arc {
                            from: [x0, y0, z0],
                            to: [x1, y1, z1],
                            center: [x0 + a.ij[0], y0 + a.ij[1]],
                            ccw: a.ccw,
                            de,
                            feed,
                        }
                    }
                    _ => Motion::Stop,
                }
            }
            Command::Dwell { ms } => Motion::Dwell(ms.max(0.0) / 1000.0),
            Command::RelativeXyz(r) => {
                self.relative_xyz = *r;
                if matches!(self.flavor, Flavor::Marlin | Flavor::Prusa | Flavor::Bambu) {
                    self.relative_e = *r;
                }
                Motion::None
            }
            Command::RelativeE(r) => {
                self.relative_e = *r;
                Motion::None
            }
            Command::Inches(i) => {
                self.inches = *i;
                Motion::None
            }
            Command::SetPosition { axes, e } => {
                for (p, a) in self.pos.iter_mut().zip(axes) {
                    if let Some(v) = a {
                        *p = Some(*v);
                    }
                }
                if let Some(e) = e {
                    self.e = *e;
                }
                Motion::None
            }
            Command::Home { axes } => {
                for (p, &homed) in self.pos.iter_mut().zip(axes) {
                    if homed {
                        *p = None;
                    }
                }
                Motion::Stop
            }
            Command::Pause | Command::FirmwareRetract { .. } => Motion::Stop,
            Command::Set(crate::base::gcode::Setting::Temperature { wait: true, .. }) => {
                Motion::Stop
            }
            Command::Other(_) => Motion::Stop,
            _ => Motion::None,
        }
    }

    /// A `G0`/`G1`: [`State::apply`] of a [`Command::Move`].
    #[inline]
    pub(crate) fn line(&mut self, m: &Move) -> Motion {
        let from = self.pos;
        for k in 0..3 {
            if let Some(v) = m.to[k] {
                self.pos[k] = if self.relative_xyz {
                    self.pos[k].map(|p| p + v)
                } else {
                    Some(v)
                };
            }
        }
        let de = match m.e {
            None => 0.0,
            Some(v) if self.e_relative() => {
                self.e += v;
                v
            }
            Some(v) => {
                let d = v - self.e;
                self.e = v;
                d
            }
        };
        if let Some(f) = m.feed {
            self.feed = Some(f);
        }
        Motion::Line {
            from,
            to: self.pos,
            de,
            feed: self.feed,
            travel: m.travel,
        }
    }
}
