//! The printer's language as values: every command p3dp writes, and every
//! line it reads (a profile's start and end G-code, a recipe's own command,
//! G-code read back), as one type, [`Command`].
//!
//! Generation and analysis hold commands, never text: a move is its axes,
//! a temperature its heater and degrees, a pressure advance its factor. Text
//! appears at two edges only, both in `machine::firmware`: its writer formats
//! a command in a firmware's dialect, its reader turns a line into a command
//! as that firmware's own parser reads it ([`lex`] cuts the line the
//! firmware's way first).

pub(crate) mod lex;
pub(crate) mod named;

/// A heater.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Heater {
    /// A nozzle: tool 0 unless the line names another.
    Nozzle(u8),
    /// The bed.
    Bed,
    /// The chamber.
    Chamber,
}

impl Heater {
    /// Its name in messages: `nozzle`, `bed`, `chamber`.
    pub(crate) fn what(self) -> &'static str {
        match self {
            Heater::Nozzle(_) => "nozzle",
            Heater::Bed => "bed",
            Heater::Chamber => "chamber",
        }
    }
}

/// An input shaper's kind (Marlin's `M593`, Klipper's `SET_INPUT_SHAPER`,
/// RepRapFirmware's `M593 P`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shaper {
    /// Zero vibration.
    Zv,
    /// Modified zero vibration (Klipper's default).
    Mzv,
    /// Zero vibration and derivative.
    Zvd,
    /// Extra-insensitive.
    Ei,
    /// Two-hump extra-insensitive.
    TwoHumpEi,
    /// Three-hump extra-insensitive.
    ThreeHumpEi,
}

impl Shaper {
    /// Every kind, in the order the docs list them.
    pub(crate) const ALL: [Shaper; 6] = [
        Shaper::Zv,
        Shaper::Mzv,
        Shaper::Zvd,
        Shaper::Ei,
        Shaper::TwoHumpEi,
        Shaper::ThreeHumpEi,
    ];

    /// Its name as Klipper and RepRapFirmware write it: `zv`, `mzv`, `zvd`,
    /// `ei`, `2hump_ei`, `3hump_ei`.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Shaper::Zv => "zv",
            Shaper::Mzv => "mzv",
            Shaper::Zvd => "zvd",
            Shaper::Ei => "ei",
            Shaper::TwoHumpEi => "2hump_ei",
            Shaper::ThreeHumpEi => "3hump_ei",
        }
    }

    /// The kind of `name` (any case), if any.
    pub(crate) fn parse(name: &str) -> Option<Shaper> {
        Shaper::ALL
            .into_iter()
            .find(|s| s.name().eq_ignore_ascii_case(name.trim()))
    }
}

/// A setting of the printer: what a firmware command changes until the next
/// one, which the planner, the stats and the checks follow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    /// A heater's target, °C, and whether to wait until it is reached.
    Temperature {
        /// Which heater.
        heater: Heater,
        /// Target, °C (0: off).
        celsius: f64,
        /// Wait for it (while heating; a target of 0 is never waited for).
        wait: bool,
    },
    /// The part-cooling fan, 0 (off) to 1 (full).
    Fan {
        /// Fraction of full speed.
        speed: f64,
    },
    /// Pressure (linear) advance: Marlin's `K`, Klipper's and Prusa's
    /// `ADVANCE`/`S`, s of filament per mm/s (Marlin LA 1.5 has the same unit).
    PressureAdvance {
        /// The factor.
        k: f64,
    },
    /// Accelerations, mm/s²: of printing moves, travel moves and retractions
    /// (Marlin's `M204 P T R`; `S` sets the first two).
    Acceleration {
        /// Of printing moves.
        print: Option<f64>,
        /// Of travel moves.
        travel: Option<f64>,
        /// Of retractions (E-only moves).
        retract: Option<f64>,
    },
    /// The highest head speed, mm/s (Klipper's `VELOCITY`, Marlin's `M203 X Y`).
    SpeedLimit {
        /// mm/s.
        velocity: f64,
    },
    /// Klipper's square-corner velocity, mm/s.
    SquareCornerVelocity(f64),
    /// Marlin's junction deviation, mm (`M205 J`).
    JunctionDeviation(f64),
    /// Classic jerk of X and Y, mm/s (Marlin's `M205 X Y`, RepRapFirmware's `M566`).
    Jerk(f64),
    /// Klipper's minimum cruise ratio (0 to 1).
    MinimumCruiseRatio(f64),
    /// Input shaping: frequency per axis (Hz), damping ratio, kind.
    InputShaper {
        /// X and Y frequencies, Hz (0 switches shaping off on that axis).
        frequency: [Option<f64>; 2],
        /// Damping ratio (0 to 1).
        damping: Option<f64>,
        /// The shaper.
        kind: Option<Shaper>,
    },
    /// The flow (extrusion) factor, 1 = 100 % (`M221`).
    Flow(f64),
    /// The speed (feed) factor, 1 = 100 % (`M220`).
    Speed(f64),
    /// Retraction length (mm of filament) and speed (mm/s): p3dp's own
    /// retractions, or the firmware's (`M207`, `SET_RETRACTION`).
    Retraction {
        /// Length, mm.
        length: Option<f64>,
        /// Speed, mm/s.
        speed: Option<f64>,
    },
    /// The firmware's per-axis maximum accelerations, mm/s² (`M201 X Y Z E`).
    MaxAcceleration {
        /// X, Y, Z, E.
        axes: [Option<f64>; 4],
    },
    /// The firmware's per-axis maximum feed rates, mm/s (`M203 X Y Z E`).
    MaxFeedrate {
        /// X, Y, Z, E.
        axes: [Option<f64>; 4],
    },
}

/// A straight move (`G0`/`G1`) in machine coordinates, as written: an axis
/// or E or F that is `None` is not written (the firmware keeps its value).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub(crate) struct Move {
    /// `G0` (a travel), not `G1`.
    pub(crate) travel: bool,
    /// X, Y, Z, mm.
    pub(crate) to: [Option<f64>; 3],
    /// E, mm of filament (a total or a step, as the extrusion mode says).
    pub(crate) e: Option<f64>,
    /// F, mm/min.
    pub(crate) feed: Option<f64>,
}

/// An arc (`G2` clockwise, `G3` counter-clockwise) to `to`, its centre
/// `ij` from the start.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub(crate) struct Arc {
    /// Counter-clockwise (`G3`).
    pub(crate) ccw: bool,
    /// X, Y, Z, mm.
    pub(crate) to: [Option<f64>; 3],
    /// The centre, offset from the start, mm (I, J).
    pub(crate) ij: [f64; 2],
    /// E, mm of filament.
    pub(crate) e: Option<f64>,
    /// F, mm/min.
    pub(crate) feed: Option<f64>,
}

/// The points an arc's extent rests on: its two ends and each
/// quarter-turn extreme (0°, 90°, 180°, 270° about the centre) its sweep
/// passes, from `from` to `to` about the centre `from + ij`, clockwise
/// unless `ccw`. Ends that meet make a full circle (as Marlin's
/// `plan_arc` reads them).
pub(crate) fn arc_extremes(from: [f64; 2], to: [f64; 2], ij: [f64; 2], ccw: bool) -> Vec<[f64; 2]> {
    let (cx, cy) = (from[0] + ij[0], from[1] + ij[1]);
    let r = ij[0].hypot(ij[1]);
    let a0 = libm::atan2(from[1] - cy, from[0] - cx);
    let tau = std::f64::consts::TAU;
    // the sweep's size (a full circle when the ends meet) and its end angle
    let a1 = libm::atan2(to[1] - cy, to[0] - cx);
    let mut sweep = if ccw { a1 - a0 } else { a0 - a1 }.rem_euclid(tau);
    if sweep < 1e-12 {
        sweep = tau;
    }
    let a1 = if ccw { a0 + sweep } else { a0 - sweep };
    let quarter = std::f64::consts::FRAC_PI_2;
    let (lo, hi) = (a0.min(a1), a0.max(a1));
    let mut pts = vec![from, to];
    let mut q = libm::ceil(lo / quarter);
    while q * quarter <= hi {
        let t = q * quarter;
        pts.push([cx + r * libm::cos(t), cy + r * libm::sin(t)]);
        q += 1.0;
    }
    pts
}

/// A host's cancel-object label (Klipper's `EXCLUDE_OBJECT_START`/`_END`,
/// and the `; printing object` comments slicers write); the objects'
/// `EXCLUDE_OBJECT_DEFINE` lines are the header's (`output::gcode::labels`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Object {
    /// The object's moves begin.
    Start(String),
    /// The object's moves end.
    End(String),
}

/// One command of the printer's language (see the module comment).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Command {
    /// A straight move.
    Move(Move),
    /// An arc.
    Arc(Arc),
    /// Wait, ms (`G4 P`).
    Dwell {
        /// Milliseconds.
        ms: f64,
    },
    /// A setting (temperature, fan, accelerations …).
    Set(Setting),
    /// Firmware retraction (`G10`), and back (`G11`).
    FirmwareRetract {
        /// `G11`: undo it.
        undo: bool,
    },
    /// `G90` (absolute) or `G91` (relative) XYZ.
    RelativeXyz(bool),
    /// `M82` (absolute) or `M83` (relative) E.
    RelativeE(bool),
    /// `G21` (millimetres) or `G20` (inches).
    Inches(bool),
    /// `G92`: the current position redefined; an axis not given keeps its value.
    SetPosition {
        /// X, Y, Z.
        axes: [Option<f64>; 3],
        /// E.
        e: Option<f64>,
    },
    /// Homing (`G28`): the axes named, or all.
    Home {
        /// X, Y, Z homed (all three when none is named).
        axes: [bool; 3],
    },
    /// Progress for the printer's screen (`M73`).
    Progress {
        /// Percent done.
        percent: u32,
        /// Minutes left.
        minutes_left: u64,
    },
    /// A host's object label.
    Object(Object),
    /// A pause for the operator (`M0`, `M601`, `PAUSE`, `M226`).
    Pause,
    /// Select a tool (`T<n>`).
    Tool(u32),
    /// A command without a typed meaning: its code as written (`M600`,
    /// `BED_MESH_CALIBRATE`); the checks decide whether it may run.
    Other(String),
}

/// A line of G-code p3dp did not write itself (a profile's start or end
/// G-code, a recipe's own command): its text, written as it is, and what
/// the firmware reads in it.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Verbatim {
    /// The line, without its line feed.
    pub(crate) text: String,
    /// What it does (see `machine::firmware::read`).
    pub(crate) commands: Vec<Command>,
}
