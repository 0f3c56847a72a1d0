//! `turtle:` as written: the start, the seed, procedures, and the program's
//! commands (one-key maps with a few companion keys, or bare words).

use std::fmt;

use indexmap::IndexMap;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;

use super::curve::{RawArcCmd, RawBezier, RawLine, RawRectangle};
use super::num::{Num, Num3, RawPoint};
use super::part::RawLoop;
use super::step::RawSet;

/// `turtle:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTurtle {
    /// Start position and frame.
    #[serde(default)]
    pub(crate) start: Option<RawStart>,
    /// Seed of `rand()` (0 when absent).
    #[serde(default)]
    pub(crate) seed: Option<Num>,
    /// Named procedures with parameters, run by `call`.
    #[serde(default)]
    pub(crate) procedures: IndexMap<String, RawProcedure>,
    /// The commands, run in order.
    pub(crate) program: Vec<RawCommand>,
}

/// `start:` of a turtle.
#[derive(Clone, Debug, Default, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawStart {
    /// Where the turtle starts ([0, 0, 0]).
    #[serde(default)]
    pub(crate) position: Option<Num3>,
    /// Which way it faces ([1, 0, 0]).
    #[serde(default)]
    pub(crate) heading: Option<Num3>,
    /// Its up axis ([0, 0, 1]), made perpendicular to the heading.
    #[serde(default)]
    pub(crate) up: Option<Num3>,
}

/// A procedure: parameter names and a body.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawProcedure {
    /// Parameter names, bound in order to a call's `args`.
    #[serde(default)]
    pub(crate) params: Vec<String>,
    /// The commands.
    #[serde(rename = "do")]
    pub(crate) body: Vec<RawCommand>,
}

/// `lsystem:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLsystem {
    /// The starting word.
    pub(crate) axiom: String,
    /// Rewriting rules: one symbol → its replacement, applied to every symbol at once.
    #[serde(default)]
    pub(crate) rules: IndexMap<String, String>,
    /// How many times the rules are applied (may use loop counters).
    pub(crate) iterations: Num,
    /// What each symbol of the final word does.
    pub(crate) commands: IndexMap<String, Vec<RawCommand>>,
}

/// One command as written: a one-key map (`{forward: 10}`) with, for a few
/// commands, companion keys (`as`, `do`, `else`, `args`, `up`, `feed`,
/// `wait`), or a bare word (`pen_up`).
#[derive(Clone, Debug, PartialEq)]
#[allow(missing_docs)]
pub(crate) enum RawCommand {
    /// A command without a value: `pen_up`, `pen_down`, `pause`, `push`, `pop`, `draw_turtle`.
    Bare(&'static str),
    /// A command with one number: movement, turns, settings, events.
    Scalar(&'static str, Num),
    /// `goto`: to the point, drawing with the pen down.
    Goto(RawPoint),
    /// `move`: a travel to the point, whatever the pen.
    Move(RawPoint),
    /// `draw`: an extruding string to the point, whatever the pen.
    Draw(RawPoint),
    /// `for: {name: range or list}` with `do:` run once per value (several
    /// names: nested, the first outermost).
    For {
        loops: IndexMap<String, RawLoop>,
        body: Vec<RawCommand>,
    },
    /// `let: {name: value, …}`: named values for the rest of the block.
    Let(IndexMap<String, Num>),
    /// A curve drawn in one command.
    Arc(Box<RawArcCmd>),
    Bezier(Box<RawBezier>),
    Line(Box<RawLine>),
    Rectangle(Box<RawRectangle>),
    /// `extrude_volume: mm³` in place, with `feed:` (FullControl's
    /// `StationaryExtrusion`).
    ExtrudeVolume {
        volume: Num,
        feed: Option<Num>,
    },
    /// `gcode: "M600"`: a printer command written here, each `{expr}` in
    /// it replaced by the expression's value.
    Gcode(String),
    /// `set: {pressure_advance: …, …}`: the printer's settings here, as a
    /// `set` step's (without its bands).
    Set(Box<RawSet>),
    SetHeading {
        heading: Num3,
        up: Option<Num3>,
    },
    Extrude {
        filament: Num,
        feed: Option<Num>,
    },
    Temp {
        bed: bool,
        celsius: Num,
        wait: bool,
    },
    Repeat {
        count: Num,
        var: Option<String>,
        body: Vec<RawCommand>,
    },
    If {
        cond: Num,
        then: Vec<RawCommand>,
        otherwise: Vec<RawCommand>,
    },
    Call {
        name: String,
        args: Vec<Num>,
    },
    Lsystem(Box<RawLsystem>),
    /// `hair: L` with `blob:` and `rate:`: a declared hair (see
    /// [`crate::generate::primitive::turtle::program::Op::Hair`]).
    Hair {
        length: Num,
        blob: Option<Num>,
        rate: Option<Num>,
    },
}

/// Commands written as bare words.
pub(super) const BARE: &[&str] = &["pen_up", "pen_down", "pause", "push", "pop", "draw_turtle"];
/// Commands taking one number.
pub(super) const SCALAR: &[&str] = &[
    "forward",
    "backward",
    "lift",
    "yaw",
    "pitch",
    "roll",
    "left",
    "right",
    "extrude_rate",
    "cross_section",
    "speed",
    "dwell",
    "fan",
];
/// Every command, for error messages.
pub(super) const COMMANDS: &str = "forward, backward, lift, goto, move, draw, yaw, pitch, roll, left, right, \
set_heading, pen_up, pen_down, extrude_rate, cross_section, speed, extrude, extrude_volume, dwell, pause, \
nozzle_temp, bed_temp, fan, gcode, set, push, pop, draw_turtle, repeat, for, let, if, call, lsystem, hair, \
arc, bezier, line, rectangle";

impl schemars::JsonSchema for RawCommand {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RawCommand".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let mut keys: Vec<&str> = COMMANDS.split(", ").collect();
        keys.extend([
            "as", "do", "else", "args", "up", "feed", "wait", "blob", "rate",
        ]);
        schemars::json_schema!({
            "description": "A turtle command: a one-key map such as {forward: 10} (with companion keys for a few), or a bare word such as pen_up.",
            "anyOf": [
                {"type": "string", "enum": BARE},
                {"type": "object", "minProperties": 1, "propertyNames": {"enum": keys}}
            ]
        })
    }
}

fn find(list: &[&'static str], word: &str) -> Option<&'static str> {
    list.iter().copied().find(|w| *w == word)
}

impl<'de> Deserialize<'de> for RawCommand {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<RawCommand, D::Error> {
        d.deserialize_any(CommandVisitor)
    }
}

struct CommandVisitor;

#[derive(Default)]
struct Keys {
    cmd: Option<&'static str>,
    num: Option<Num>,
    vec: Option<Num3>,
    point: Option<RawPoint>,
    loops: Option<IndexMap<String, RawLoop>>,
    lets: Option<IndexMap<String, Num>>,
    arc: Option<RawArcCmd>,
    bezier: Option<RawBezier>,
    line: Option<RawLine>,
    rectangle: Option<RawRectangle>,
    text: Option<String>,
    settings: Option<RawSet>,
    name: Option<String>,
    lsystem: Option<RawLsystem>,
    var: Option<String>,
    body: Option<Vec<RawCommand>>,
    otherwise: Option<Vec<RawCommand>>,
    args: Option<Vec<Num>>,
    up: Option<Num3>,
    feed: Option<Num>,
    wait: Option<bool>,
    blob: Option<Num>,
    rate: Option<Num>,
}

impl<'de> Visitor<'de> for CommandVisitor {
    type Value = RawCommand;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a command: a map like {forward: 10} or a bare word like pen_up")
    }

    fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<RawCommand, E> {
        if let Some(w) = find(BARE, v) {
            return Ok(RawCommand::Bare(w));
        }
        if find(SCALAR, v).is_some() || COMMANDS.split(", ").any(|c| c == v) {
            return Err(E::custom(format!(
                "`{v}` needs a value; expected a map such as `{{{v}: …}}`"
            )));
        }
        Err(E::custom(format!(
            "unknown command `{v}`; expected one of {COMMANDS}"
        )))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> std::result::Result<RawCommand, A::Error> {
        let mut k = Keys::default();
        while let Some(key) = m.next_key::<String>()? {
            match key.as_str() {
                w if find(SCALAR, w).is_some() => {
                    set(&mut k.cmd, find(SCALAR, w).unwrap())?;
                    k.num = Some(m.next_value()?);
                }
                "repeat" | "if" | "extrude" | "nozzle_temp" | "bed_temp" | "hair" => {
                    let name = match key.as_str() {
                        "repeat" => "repeat",
                        "if" => "if",
                        "extrude" => "extrude",
                        "hair" => "hair",
                        "nozzle_temp" => "nozzle_temp",
                        _ => "bed_temp",
                    };
                    set(&mut k.cmd, name)?;
                    k.num = Some(m.next_value()?);
                }
                "set_heading" => {
                    set(&mut k.cmd, "set_heading")?;
                    k.vec = Some(m.next_value()?);
                }
                "goto" | "move" | "draw" => {
                    let name = match key.as_str() {
                        "goto" => "goto",
                        "move" => "move",
                        _ => "draw",
                    };
                    set(&mut k.cmd, name)?;
                    k.point = Some(m.next_value()?);
                }
                "extrude_volume" => {
                    set(&mut k.cmd, "extrude_volume")?;
                    k.num = Some(m.next_value()?);
                }
                "for" => {
                    set(&mut k.cmd, "for")?;
                    k.loops = Some(m.next_value()?);
                }
                "let" => {
                    set(&mut k.cmd, "let")?;
                    k.lets = Some(m.next_value()?);
                }
                "gcode" => {
                    set(&mut k.cmd, "gcode")?;
                    k.text = Some(m.next_value()?);
                }
                "set" => {
                    set(&mut k.cmd, "set")?;
                    k.settings = Some(m.next_value()?);
                }
                "arc" => {
                    set(&mut k.cmd, "arc")?;
                    k.arc = Some(m.next_value()?);
                }
                "bezier" => {
                    set(&mut k.cmd, "bezier")?;
                    k.bezier = Some(m.next_value()?);
                }
                "line" => {
                    set(&mut k.cmd, "line")?;
                    k.line = Some(m.next_value()?);
                }
                "rectangle" => {
                    set(&mut k.cmd, "rectangle")?;
                    k.rectangle = Some(m.next_value()?);
                }
                "call" => {
                    set(&mut k.cmd, "call")?;
                    k.name = Some(m.next_value()?);
                }
                "lsystem" => {
                    set(&mut k.cmd, "lsystem")?;
                    k.lsystem = Some(m.next_value()?);
                }
                "as" => k.var = Some(m.next_value()?),
                "do" => k.body = Some(m.next_value()?),
                "else" => k.otherwise = Some(m.next_value()?),
                "args" => k.args = Some(m.next_value()?),
                "up" => k.up = Some(m.next_value()?),
                "feed" => k.feed = Some(m.next_value()?),
                "wait" => k.wait = Some(m.next_value()?),
                "blob" => k.blob = Some(m.next_value()?),
                "rate" => k.rate = Some(m.next_value()?),
                w if find(BARE, w).is_some() => {
                    return Err(de::Error::custom(format!(
                        "`{w}` takes no value; write it as a bare word: `- {w}`"
                    )))
                }
                other => {
                    return Err(de::Error::custom(format!(
                        "unknown command `{other}`; expected one of {COMMANDS}"
                    )))
                }
            }
        }
        k.build()
    }
}

/// Records the command key of an item; a second one is an error.
fn set<E: de::Error>(
    cmd: &mut Option<&'static str>,
    name: &'static str,
) -> std::result::Result<(), E> {
    match cmd.replace(name) {
        Some(first) => Err(E::custom(format!(
            "one command per list item, found `{first}` and `{name}`; write them as two items"
        ))),
        None => Ok(()),
    }
}

impl Keys {
    /// The command the keys of one list item make, or the deserializer's error.
    fn build<E: de::Error>(self) -> std::result::Result<RawCommand, E> {
        let Some(cmd) = self.cmd else {
            return Err(E::custom(format!(
                "expected a command key (one of {COMMANDS}) beside `as`, `do`, `else`, `args`, `up`, `feed`, `wait`, `blob` or `rate`"
            )));
        };
        self.companions(cmd)?;
        Ok(match cmd {
            "goto" => RawCommand::Goto(self.point.unwrap()),
            "move" => RawCommand::Move(self.point.unwrap()),
            "draw" => RawCommand::Draw(self.point.unwrap()),
            "for" => RawCommand::For {
                loops: self.loops.unwrap(),
                body: self.body.unwrap(),
            },
            "let" => RawCommand::Let(self.lets.unwrap()),
            "gcode" => RawCommand::Gcode(self.text.unwrap()),
            "set" => RawCommand::Set(Box::new(self.settings.unwrap())),
            "arc" => RawCommand::Arc(Box::new(self.arc.unwrap())),
            "bezier" => RawCommand::Bezier(Box::new(self.bezier.unwrap())),
            "line" => RawCommand::Line(Box::new(self.line.unwrap())),
            "rectangle" => RawCommand::Rectangle(Box::new(self.rectangle.unwrap())),
            "extrude_volume" => RawCommand::ExtrudeVolume {
                volume: self.num.unwrap(),
                feed: self.feed,
            },
            "set_heading" => RawCommand::SetHeading {
                heading: self.vec.unwrap(),
                up: self.up,
            },
            "extrude" => RawCommand::Extrude {
                filament: self.num.unwrap(),
                feed: self.feed,
            },
            "nozzle_temp" | "bed_temp" => RawCommand::Temp {
                bed: cmd == "bed_temp",
                celsius: self.num.unwrap(),
                wait: self.wait.unwrap_or(false),
            },
            "repeat" => RawCommand::Repeat {
                count: self.num.unwrap(),
                var: self.var,
                body: self.body.unwrap(),
            },
            "if" => RawCommand::If {
                cond: self.num.unwrap(),
                then: self.body.unwrap(),
                otherwise: self.otherwise.unwrap_or_default(),
            },
            "call" => RawCommand::Call {
                name: self.name.unwrap(),
                args: self.args.unwrap_or_default(),
            },
            "lsystem" => RawCommand::Lsystem(Box::new(self.lsystem.unwrap())),
            "hair" => RawCommand::Hair {
                length: self.num.unwrap(),
                blob: self.blob,
                rate: self.rate,
            },
            _ => RawCommand::Scalar(cmd, self.num.unwrap()),
        })
    }

    /// Refuses companion keys `cmd` does not take, and a `repeat` or `if`
    /// without its `do`.
    fn companions<E: de::Error>(&self, cmd: &str) -> std::result::Result<(), E> {
        let allowed: &[&str] = match cmd {
            "repeat" => &["as", "do"],
            "for" => &["do"],
            "extrude_volume" => &["feed"],
            "if" => &["do", "else"],
            "call" => &["args"],
            "set_heading" => &["up"],
            "extrude" => &["feed"],
            "nozzle_temp" | "bed_temp" => &["wait"],
            "hair" => &["blob", "rate"],
            _ => &[],
        };
        let present = [
            ("as", self.var.is_some()),
            ("do", self.body.is_some()),
            ("else", self.otherwise.is_some()),
            ("args", self.args.is_some()),
            ("up", self.up.is_some()),
            ("feed", self.feed.is_some()),
            ("wait", self.wait.is_some()),
            ("blob", self.blob.is_some()),
            ("rate", self.rate.is_some()),
        ];
        for (key, here) in present {
            if here && !allowed.contains(&key) {
                return Err(E::custom(if allowed.is_empty() {
                    format!("`{cmd}` takes no `{key}`; it stands alone")
                } else {
                    format!(
                        "`{cmd}` takes no `{key}`; its other keys are {}",
                        allowed.join(", ")
                    )
                }));
            }
        }
        if matches!(cmd, "repeat" | "if" | "for") && self.body.is_none() {
            return Err(E::custom(format!(
                "`{cmd}` needs `do: [ … ]`, the commands it runs"
            )));
        }
        Ok(())
    }
}
