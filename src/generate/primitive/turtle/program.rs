//! A turtle's compiled program, as the interpreter ([`super::interp`]) runs
//! it: every value an expression compiled once, every name (procedure, loop
//! counter, parameter) resolved to a slot, every command tagged with its
//! key path for errors. The recipe compiles it from the `turtle:` as
//! written (`crate::recipe::resolve`).

use std::sync::Arc;

use crate::base::expr::Expr;
use crate::base::gcode::named::Named;

/// A compiled value: an expression and the names its extra slots hold.
#[derive(Clone, Debug)]
pub(crate) struct Val {
    /// The expression.
    pub(crate) expr: Expr,
    /// Names of the loop counters and procedure parameters in scope, in slot order.
    pub(crate) scope: Arc<Vec<String>>,
    /// Whether it reads the turtle's state ([`STATE`]), in the slots after
    /// the scope's.
    pub(crate) reads_state: bool,
}

/// The turtle's state an expression may read, as functions of no arguments
/// (ExtruderTurtle's `getYaw()` and friends): the heading's `yaw()` (degrees
/// from +x, counter-clockwise seen from above) and `pitch()` (degrees above
/// the bed's plane), the `roll()` about it (degrees, the left side lifted),
/// and `pen()` (1 down, 0 up). The position is `x`, `y`, `z`.
pub(crate) const STATE: [&str; 4] = ["yaw()", "pitch()", "roll()", "pen()"];

/// Which axis a turn is about.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Axis {
    /// About up: `yaw`, `left`, `right`.
    Yaw,
    /// About left: `pitch`.
    Pitch,
    /// About the heading: `roll`.
    Roll,
}

/// A setting of the deposition state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Setting {
    /// mm of filament per mm of travel.
    ExtrudeRate,
    /// mm².
    CrossSection,
    /// mm/s.
    Speed,
}

/// What a command does, with values compiled.
#[derive(Clone, Debug)]
#[allow(missing_docs)]
pub(crate) enum Op {
    /// `forward` (sign 1), `backward` (−1).
    Forward(Val, f64),
    Lift(Val),
    Goto([Val; 3]),
    /// `move` (a travel) or `draw` (an extruding string) to the point,
    /// whatever the pen: one string each, even of length 0 (a path's v1
    /// commands).
    To([Val; 3], bool),
    /// `for`: the body once per value of a range or list, the value in
    /// the scope's next slot.
    For {
        values: Box<Values>,
        body: Vec<Cmd>,
    },
    /// `let`: values put in the scope's next slots for the rest of the block.
    Let(Vec<Val>),
    /// A curve, its points visited as `goto`s.
    Curve(Box<Curve>),
    /// `extrude_volume`: mm³ fed in place, at the `feed` (filament mm/s).
    ExtrudeVolume(Val, Option<Val>),
    /// `gcode`: a printer command, checked when compiled.
    Gcode(std::sync::Arc<str>),
    /// `gcode` with `{expr}`s: the line made of its pieces and checked
    /// where it runs.
    GcodeWith(Vec<Piece>),
    /// `set`: the printer's settings, their values evaluated where it runs.
    Printer(Box<Settings>),
    /// A turn by sign × value degrees (`right` is yaw with sign −1).
    Turn(Axis, Val, f64),
    SetHeading(Box<([Val; 3], Option<[Val; 3]>)>),
    PenUp,
    PenDown,
    Pause,
    Push,
    Pop,
    /// `draw_turtle`: a marker in the previews, nothing in the G-code.
    DrawTurtle,
    Set(Setting, Val),
    Extrude(Val, Option<Val>),
    Dwell(Val),
    Fan(Val),
    Temp {
        bed: bool,
        celsius: Val,
        wait: bool,
    },
    Repeat {
        count: Val,
        counter: bool,
        body: Vec<Cmd>,
    },
    If {
        cond: Val,
        then: Vec<Cmd>,
        otherwise: Vec<Cmd>,
    },
    Call {
        proc: usize,
        args: Vec<Val>,
    },
    Lsystem(Box<super::lsystem::Lsystem>),
    /// `hair`: a blob of `blob` mm of filament in place, a pull of `length`
    /// mm along the heading at `rate` mm of filament per mm (a declared hair,
    /// [`crate::base::toolpath::Strand::hair`]), then a retraction with the pen up
    /// (Laput et al.'s blob-and-pull, ExtruderTurtle §4.3).
    Hair {
        length: Val,
        blob: Option<Val>,
        rate: Option<Val>,
    },
}

/// A piece of a `gcode` line with `{expr}`s.
#[derive(Clone, Debug)]
pub(crate) enum Piece {
    /// Text as it is.
    Text(String),
    /// A value, written as [`crate::base::format::fmt_value`] writes it.
    Value(Val),
}

/// The values of a `for`: a range `a..b` or `a..b:step` (b included when
/// reached; empty when the step moves away from b), or a list.
#[derive(Clone, Debug)]
// boxed where it is held (`Op::For`), so its size costs nothing
#[allow(clippy::large_enum_variant)]
pub(crate) enum Values {
    /// a, b and the step (1 when absent).
    Range(Val, Val, Option<Val>),
    /// The values in order.
    List(Vec<Val>),
}

/// A curve of one command: its points are visited in order, the first
/// included, drawing with the pen down and travelling with it up.
#[derive(Clone, Debug)]
#[allow(missing_docs)]
pub(crate) enum Curve {
    /// FullControl's `arcXY`/`spiralXY`/`helixZ`: point k of n + 1 at angle
    /// start + sweep·k/n, radius r0 + (r1 − r0)·k/n, z centre.z + rise·k/n.
    Arc {
        center: [Val; 3],
        radius: Val,
        start: Val,
        sweep: Val,
        segments: Val,
        end_radius: Option<Val>,
        rise: Option<Val>,
    },
    /// The Bézier curve of the control points at n + 1 evenly spaced values.
    Bezier {
        points: Vec<[Val; 3]>,
        segments: Val,
    },
    /// A straight line from `from` (the head when absent) in n equal strings.
    Line {
        from: Option<[Val; 3]>,
        to: [Val; 3],
        segments: Val,
    },
    /// FullControl's `rectangleXY`: corner, along x then y (or y then x
    /// when clockwise), back to the corner.
    Rectangle {
        corner: [Val; 3],
        size: [Val; 2],
        clockwise: bool,
    },
}

/// A compiled command and its key path (relative to `turtle`).
#[derive(Clone, Debug)]
pub(crate) struct Cmd {
    /// Key path, e.g. `program[3].do[1].forward`.
    pub(crate) place: String,
    /// What it does.
    pub(crate) op: Op,
}

/// A compiled procedure.
#[derive(Clone, Debug)]
pub(crate) struct Proc {
    /// Its name.
    pub(crate) name: String,
    /// Its body (its parameters are the first slots).
    pub(crate) body: Vec<Cmd>,
}

/// A `set` command compiled: its settings, and the line of a line test it
/// begins (`band`: a whole number where it runs), if any.
#[derive(Clone, Debug)]
pub(crate) struct Settings {
    /// The settings by name.
    pub(crate) named: Named<Val>,
    /// The band (a line's index) the command begins.
    pub(crate) band: Option<Val>,
}
