//! A turtle's compiled program, as the interpreter ([`super::interp`]) runs
//! it: every value an expression compiled once, every name (procedure, loop
//! counter, parameter) resolved to a slot, every command tagged with its
//! key path for errors. The recipe compiles it from the `turtle:` as
//! written (`crate::recipe::resolve`).

use std::sync::Arc;

use crate::base::expr::Expr;

/// A compiled value: an expression and the names its extra slots hold.
#[derive(Clone, Debug)]
pub(crate) struct Val {
    /// The expression.
    pub expr: Expr,
    /// Names of the loop counters and procedure parameters in scope, in slot order.
    pub scope: Arc<Vec<String>>,
    /// Whether it reads the turtle's state ([`STATE`]), in the slots after
    /// the scope's.
    pub reads_state: bool,
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

/// A compiled command and its key path (relative to `turtle`).
#[derive(Clone, Debug)]
pub(crate) struct Cmd {
    /// Key path, e.g. `program[3].do[1].forward`.
    pub place: String,
    /// What it does.
    pub op: Op,
}

/// A compiled procedure.
#[derive(Clone, Debug)]
pub(crate) struct Proc {
    /// Its name.
    pub name: String,
    /// Its body (its parameters are the first slots).
    pub body: Vec<Cmd>,
}
