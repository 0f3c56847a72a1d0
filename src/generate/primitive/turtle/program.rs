//! The `turtle` schema as written in YAML, and its compilation: every value
//! an expression compiled once, every name (procedure, loop counter,
//! parameter) resolved, every command tagged with its key path for errors.

use std::fmt;
use std::sync::Arc;

use indexmap::IndexMap;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;

use crate::base::error::{Error, Result};
use crate::base::expr::{var, Expr, ExprErrorKind, Params};
use crate::base::num::{Num, Num3};

/// `turtle:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawTurtle {
    /// Start position and frame.
    #[serde(default)]
    pub start: Option<RawStart>,
    /// Seed of `rand()` (0 when absent).
    #[serde(default)]
    pub seed: Option<Num>,
    /// Named procedures with parameters, run by `call`.
    #[serde(default)]
    pub procedures: IndexMap<String, RawProcedure>,
    /// The commands, run in order.
    pub program: Vec<RawCommand>,
}

/// `start:` of a turtle.
#[derive(Clone, Debug, Default, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawStart {
    /// Where the turtle starts ([0, 0, 0]).
    #[serde(default)]
    pub position: Option<Num3>,
    /// Which way it faces ([1, 0, 0]).
    #[serde(default)]
    pub heading: Option<Num3>,
    /// Its up axis ([0, 0, 1]), made perpendicular to the heading.
    #[serde(default)]
    pub up: Option<Num3>,
}

/// A procedure: parameter names and a body.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawProcedure {
    /// Parameter names, bound in order to a call's `args`.
    #[serde(default)]
    pub params: Vec<String>,
    /// The commands.
    #[serde(rename = "do")]
    pub body: Vec<RawCommand>,
}

/// `lsystem:` as written.
#[derive(Clone, Debug, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawLsystem {
    /// The starting word.
    pub axiom: String,
    /// Rewriting rules: one symbol → its replacement, applied to every symbol at once.
    #[serde(default)]
    pub rules: IndexMap<String, String>,
    /// How many times the rules are applied (may use loop counters).
    pub iterations: Num,
    /// What each symbol of the final word does.
    pub commands: IndexMap<String, Vec<RawCommand>>,
}

/// One command as written: a one-key map (`{forward: 10}`) with, for a few
/// commands, companion keys (`as`, `do`, `else`, `args`, `up`, `feed`,
/// `wait`), or a bare word (`pen_up`).
#[derive(Clone, Debug, PartialEq)]
#[allow(missing_docs)]
pub enum RawCommand {
    /// A command without a value: `pen_up`, `pen_down`, `pause`, `push`, `pop`, `draw_turtle`.
    Bare(&'static str),
    /// A command with one number: movement, turns, settings, events.
    Scalar(&'static str, Num),
    Goto(Num3),
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
    /// `hair: L` with `blob:` and `rate:`: a declared hair (see [`Op::Hair`]).
    Hair {
        length: Num,
        blob: Option<Num>,
        rate: Option<Num>,
    },
}

/// Commands written as bare words.
pub const BARE: &[&str] = &["pen_up", "pen_down", "pause", "push", "pop", "draw_turtle"];
/// Commands taking one number.
pub const SCALAR: &[&str] = &[
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
pub const COMMANDS: &str = "forward, backward, lift, goto, yaw, pitch, roll, left, right, \
set_heading, pen_up, pen_down, extrude_rate, cross_section, speed, extrude, dwell, pause, \
nozzle_temp, bed_temp, fan, push, pop, draw_turtle, repeat, if, call, lsystem, hair";

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
        f.write_str("a turtle command: a map like {forward: 10} or a bare word like pen_up")
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
            "unknown turtle command `{v}`; expected one of {COMMANDS}"
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
                "goto" | "set_heading" => {
                    let name = if key == "goto" { "goto" } else { "set_heading" };
                    set(&mut k.cmd, name)?;
                    k.vec = Some(m.next_value()?);
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
                        "unknown turtle command `{other}`; expected one of {COMMANDS}"
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
        let allowed: &[&str] = match cmd {
            "repeat" => &["as", "do"],
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
        if matches!(cmd, "repeat" | "if") && self.body.is_none() {
            return Err(E::custom(format!(
                "`{cmd}` needs `do: [ … ]`, the commands it runs"
            )));
        }
        Ok(match cmd {
            "goto" => RawCommand::Goto(self.vec.unwrap()),
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
}

/// A compiled value: an expression and the names its extra slots hold.
#[derive(Clone, Debug)]
pub struct Val {
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
pub const STATE: [&str; 4] = ["yaw()", "pitch()", "roll()", "pen()"];

/// Which axis a turn is about.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Axis {
    /// About up: `yaw`, `left`, `right`.
    Yaw,
    /// About left: `pitch`.
    Pitch,
    /// About the heading: `roll`.
    Roll,
}

/// A setting of the deposition state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
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
pub enum Op {
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
pub struct Cmd {
    /// Key path, e.g. `program[3].do[1].forward`.
    pub place: String,
    /// What it does.
    pub op: Op,
}

/// A compiled procedure.
#[derive(Clone, Debug)]
pub struct Proc {
    /// Its name.
    pub name: String,
    /// How many parameters it takes.
    pub arity: usize,
    /// Its body (parameters are slots 0..arity).
    pub body: Vec<Cmd>,
}

/// Compiles the commands of one turtle.
pub struct Compiler<'a> {
    params: &'a Params,
    procs: IndexMap<String, RawProcedure>,
}

fn check_name(name: &str, params: &Params, scope: &[String], place: &str) -> Result<()> {
    let ident = {
        let mut cs = name.chars();
        matches!(cs.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
            && cs.all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    let why = if !ident {
        "a name must be letters, digits and `_`, not starting with a digit"
    } else if matches!(name, "x" | "y" | "z" | "pi" | "e" | "rand") {
        "turtle expressions already use it (x y z are the turtle's position; pi, e, rand())"
    } else if params.contains_key(name) {
        "it is a param of the recipe"
    } else if scope.iter().any(|s| s == name) {
        "it is already a loop counter or parameter here"
    } else {
        return Ok(());
    };
    Err(Error::input(
        place,
        format!("`{name}` cannot name a loop counter or parameter: {why}"),
    ))
}

impl<'a> Compiler<'a> {
    /// A compiler for one turtle's procedures over the recipe's params.
    pub fn new(params: &'a Params, procs: &IndexMap<String, RawProcedure>) -> Compiler<'a> {
        Compiler {
            params,
            procs: procs.clone(),
        }
    }

    /// Compiles every procedure (in the order written; calls may refer forward).
    pub fn procedures(&self) -> Result<Vec<Proc>> {
        let mut out = Vec::with_capacity(self.procs.len());
        for (name, p) in &self.procs {
            let place = format!("procedures.{name}");
            let mut scope = Vec::new();
            for (k, param) in p.params.iter().enumerate() {
                check_name(param, self.params, &scope, &format!("{place}.params[{k}]"))?;
                scope.push(param.clone());
            }
            out.push(Proc {
                name: name.clone(),
                arity: p.params.len(),
                body: self.block(&p.body, &format!("{place}.do"), &Arc::new(scope))?,
            });
        }
        Ok(out)
    }

    /// Compiles `src` in `scope` (turtle position x, y, z; counters; `rand()`).
    pub fn val(&self, n: &Num, scope: &Arc<Vec<String>>, place: &str) -> Result<Val> {
        let mut names: Vec<&str> = scope.iter().map(String::as_str).collect();
        names.extend(STATE);
        let expr = Expr::compile_ext(&n.src(), self.params, &[var::X, var::Y, var::Z], &names)
            .map_err(|e| {
                let m = e.message;
                let m = if e.kind == ExprErrorKind::Name {
                    let mut more: Vec<&str> = scope.iter().map(String::as_str).collect();
                    more.extend(STATE);
                    more.push("rand()");
                    format!("{m}; a turtle also has {}", more.join(", "))
                } else {
                    m
                };
                Error::input(place, m)
            })?;
        let reads_state = (0..STATE.len()).any(|k| expr.uses_ext(scope.len() + k));
        Ok(Val {
            expr,
            scope: scope.clone(),
            reads_state,
        })
    }

    fn val3(&self, n: &Num3, scope: &Arc<Vec<String>>, place: &str) -> Result<[Val; 3]> {
        Ok([
            self.val(&n[0], scope, &format!("{place}[0]"))?,
            self.val(&n[1], scope, &format!("{place}[1]"))?,
            self.val(&n[2], scope, &format!("{place}[2]"))?,
        ])
    }

    /// Compiles a list of commands written at key path `place`.
    pub fn block(
        &self,
        cmds: &[RawCommand],
        place: &str,
        scope: &Arc<Vec<String>>,
    ) -> Result<Vec<Cmd>> {
        let mut out = Vec::with_capacity(cmds.len());
        for (k, c) in cmds.iter().enumerate() {
            out.push(self.command(c, &format!("{place}[{k}]"), scope)?);
        }
        Ok(out)
    }

    fn command(&self, c: &RawCommand, item: &str, scope: &Arc<Vec<String>>) -> Result<Cmd> {
        let at = |key: &str| format!("{item}.{key}");
        let (place, op) = match c {
            RawCommand::Bare(w) => (
                at(w),
                match *w {
                    "pen_up" => Op::PenUp,
                    "pen_down" => Op::PenDown,
                    "pause" => Op::Pause,
                    "push" => Op::Push,
                    "draw_turtle" => Op::DrawTurtle,
                    _ => Op::Pop,
                },
            ),
            RawCommand::Scalar(w, n) => {
                let place = at(w);
                let v = self.val(n, scope, &place)?;
                let op = match *w {
                    "forward" => Op::Forward(v, 1.0),
                    "backward" => Op::Forward(v, -1.0),
                    "lift" => Op::Lift(v),
                    "yaw" | "left" => Op::Turn(Axis::Yaw, v, 1.0),
                    "right" => Op::Turn(Axis::Yaw, v, -1.0),
                    "pitch" => Op::Turn(Axis::Pitch, v, 1.0),
                    "roll" => Op::Turn(Axis::Roll, v, 1.0),
                    "extrude_rate" => Op::Set(Setting::ExtrudeRate, v),
                    "cross_section" => Op::Set(Setting::CrossSection, v),
                    "speed" => Op::Set(Setting::Speed, v),
                    "dwell" => Op::Dwell(v),
                    _ => Op::Fan(v),
                };
                (place, op)
            }
            RawCommand::Goto(p) => (at("goto"), Op::Goto(self.val3(p, scope, &at("goto"))?)),
            RawCommand::SetHeading { heading, up } => (
                at("set_heading"),
                Op::SetHeading(Box::new((
                    self.val3(heading, scope, &at("set_heading"))?,
                    match up {
                        Some(u) => Some(self.val3(u, scope, &at("up"))?),
                        None => None,
                    },
                ))),
            ),
            RawCommand::Extrude { filament, feed } => (
                at("extrude"),
                Op::Extrude(
                    self.val(filament, scope, &at("extrude"))?,
                    match feed {
                        Some(f) => Some(self.val(f, scope, &at("feed"))?),
                        None => None,
                    },
                ),
            ),
            RawCommand::Temp { bed, celsius, wait } => {
                let key = if *bed { "bed_temp" } else { "nozzle_temp" };
                (
                    at(key),
                    Op::Temp {
                        bed: *bed,
                        celsius: self.val(celsius, scope, &at(key))?,
                        wait: *wait,
                    },
                )
            }
            RawCommand::Repeat { count, var, body } => {
                let count = self.val(count, scope, &at("repeat"))?;
                let inner = match var {
                    Some(name) => {
                        check_name(name, self.params, scope, &at("as"))?;
                        let mut s = (**scope).clone();
                        s.push(name.clone());
                        Arc::new(s)
                    }
                    None => scope.clone(),
                };
                (
                    at("repeat"),
                    Op::Repeat {
                        count,
                        counter: var.is_some(),
                        body: self.block(body, &at("do"), &inner)?,
                    },
                )
            }
            RawCommand::If {
                cond,
                then,
                otherwise,
            } => (
                at("if"),
                Op::If {
                    cond: self.val(cond, scope, &at("if"))?,
                    then: self.block(then, &at("do"), scope)?,
                    otherwise: self.block(otherwise, &at("else"), scope)?,
                },
            ),
            RawCommand::Call { name, args } => {
                let Some((proc, _, p)) = self.procs.get_full(name) else {
                    let known: Vec<&str> = self.procs.keys().map(String::as_str).collect();
                    return Err(Error::input(
                        at("call"),
                        if known.is_empty() {
                            format!("undefined procedure `{name}`; this turtle defines none under `procedures:`")
                        } else {
                            format!(
                                "undefined procedure `{name}`; the procedures are {}",
                                known.join(", ")
                            )
                        },
                    ));
                };
                if args.len() != p.params.len() {
                    return Err(Error::input(
                        at("args"),
                        format!(
                            "procedure `{name}` takes {} argument{} ({}) but is given {}",
                            p.params.len(),
                            if p.params.len() == 1 { "" } else { "s" },
                            p.params.join(", "),
                            args.len()
                        ),
                    ));
                }
                let mut vals = Vec::with_capacity(args.len());
                for (j, a) in args.iter().enumerate() {
                    vals.push(self.val(a, scope, &format!("{}[{j}]", at("args")))?);
                }
                (at("call"), Op::Call { proc, args: vals })
            }
            RawCommand::Hair { length, blob, rate } => (
                at("hair"),
                Op::Hair {
                    length: self.val(length, scope, &at("hair"))?,
                    blob: match blob {
                        Some(b) => Some(self.val(b, scope, &at("blob"))?),
                        None => None,
                    },
                    rate: match rate {
                        Some(r) => Some(self.val(r, scope, &at("rate"))?),
                        None => None,
                    },
                },
            ),
            RawCommand::Lsystem(l) => {
                let place = at("lsystem");
                (
                    place.clone(),
                    Op::Lsystem(Box::new(super::lsystem::Lsystem::compile(
                        l, self, scope, &place,
                    )?)),
                )
            }
        };
        Ok(Cmd { place, op })
    }
}
