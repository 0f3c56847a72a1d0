//! The interpreter: runs a compiled turtle program into strings and events.
//!
//! It runs twice: first counting (strings, events and steps, nothing
//! stored), so a program over the limit is refused before it allocates, then
//! building a toolpath of exactly the counted size. `rand()` restarts from
//! the seed for each run, so both see the same numbers.

use glam::DVec3;

use super::frame::Frame;
use super::lsystem::{Lsystem, MAX_ITERATIONS};
use super::program::{Axis, Cmd, Curve, Op, Piece, Proc, Setting, Settings, Val, Values};
use crate::base::error::{Error, Result};
use crate::base::expr::{var, Memo};
use crate::base::format::fmt_value;
use crate::base::rng::SplitMix64;
use crate::base::toolpath::{Band, Event, Toolpath};

/// Deepest nesting of procedure calls (a procedure calling itself with no
/// `if` to stop it reaches this at once).
pub(crate) const MAX_CALL_DEPTH: usize = 200;
/// Filament speed of `extrude` in place without `feed:`, mm/s.
pub(crate) const DEFAULT_FEED: f64 = 1.0;
/// Filament of a hair's blob without `blob:`, mm (about 0.1 mm³ of 1.75 mm
/// filament: a bead a nozzle wide and high).
pub(crate) const DEFAULT_HAIR_BLOB: f64 = 0.05;
/// Extrude rate of a hair's pull without `rate:`, mm of filament per mm: a
/// third of ExtruderTurtle's 0.03 for a 0.2 mm layer, "extruding little".
pub(crate) const DEFAULT_HAIR_RATE: f64 = 0.01;

/// What a run may produce and how it starts.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    /// Most strings plus events (the recipe's `max_strings`).
    pub(crate) max_strings: u64,
    /// Most steps (commands run and L-system symbols visited).
    pub(crate) max_steps: u64,
}

/// The check of a recipe's own printer command for its printer and
/// material (a `gcode` line with `{expr}`s, made as the program runs):
/// `Err` says why it is refused.
pub(crate) type Check<'a> = &'a dyn Fn(&str) -> std::result::Result<(), String>;

/// A compiled program ready to run.
#[derive(Clone, Debug)]
pub(crate) struct Program {
    /// The start frame.
    pub(crate) start: Frame,
    /// Seed of `rand()`.
    pub(crate) seed: u64,
    /// The commands.
    pub(crate) main: Vec<Cmd>,
    /// The procedures, by number.
    pub(crate) procs: Vec<Proc>,
    /// A `path`'s commands rather than a turtle's: the path starts where
    /// its first movement goes when that travels (a `move`, a movement
    /// with the pen up) or is a curve's first point, instead of drawing or
    /// travelling there from `start`; a `pen_up` before anything is drawn
    /// retracts nothing.
    pub(crate) path: bool,
}

/// The state of one run.
struct Run<'a> {
    prog: &'a Program,
    /// The check of the `gcode` lines made as it runs.
    check: Check<'a>,
    limits: Limits,
    frame: Frame,
    pen_down: bool,
    c: f64,
    v: f64,
    area: f64,
    rng: SplitMix64,
    /// What the run's evaluations remember between them.
    memo: Memo,
    saved: Vec<Frame>,
    depth: usize,
    strings: u64,
    events: u64,
    steps: u64,
    /// Whether the head has moved (a path's first movement may place it).
    moved: bool,
    out: Option<Toolpath>,
}

/// Work a run has left, innermost last: the interpreter's own stack.
enum Task<'a> {
    /// The commands of a block still to run, and how many values the scope
    /// held when it began (its `let`s come off when it ends).
    Block(std::slice::Iter<'a, Cmd>, usize),
    /// A `for` over `n` values, `next` the one to start (the value of the
    /// one just run is the last of the values when this is on top again).
    For {
        body: &'a [Cmd],
        next: u64,
        n: u64,
        values: ForValues,
    },
    /// A `repeat` of `n` iterations, `next` the one to start (iteration
    /// next − 1 has run when this is on top again; its counter, with
    /// `counter`, is the last of the values).
    Repeat {
        body: &'a [Cmd],
        next: u64,
        n: u64,
        counter: bool,
    },
    /// The end of a call: the caller's values, to run on with.
    Return(Vec<f64>),
    /// L-system symbols still to run at derivation depth `d` of `n`, the
    /// `lsystem` command at `place`.
    Symbols {
        ls: &'a Lsystem,
        symbols: std::slice::Iter<'a, u16>,
        d: u32,
        n: u32,
        place: &'a str,
    },
}

/// The values of a running `for`.
enum ForValues {
    /// a + k·step.
    Range(f64, f64),
    /// The list, evaluated when the loop began.
    List(Vec<f64>),
}

impl ForValues {
    fn at(&self, k: u64) -> f64 {
        match self {
            ForValues::Range(a, step) => a + k as f64 * step,
            ForValues::List(v) => v[k as usize],
        }
    }
}

/// Counts of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Counts {
    /// Strings made.
    pub(crate) strings: u64,
    /// Events made.
    pub(crate) events: u64,
}

impl Program {
    /// Runs the program: strings start with cross-section `c` and speed `v`;
    /// `area` (mm²) turns `extrude_rate` into a cross-section; `check`
    /// holds the `gcode` lines it makes to the printer.
    pub(crate) fn run(
        &self,
        (c, v, area): (f64, f64, f64),
        limits: Limits,
        check: Check,
    ) -> Result<Toolpath> {
        let (counts, _) = self.execute((c, v, area), limits, check, None)?;
        let mut tp = Toolpath::with_capacity(self.start.pos, counts.strings as usize);
        tp.events.reserve(counts.events as usize);
        let (_, tp) = self.execute((c, v, area), limits, check, Some(tp))?;
        Ok(tp.expect("a building run returns its toolpath"))
    }

    fn execute(
        &self,
        (c, v, area): (f64, f64, f64),
        limits: Limits,
        check: Check,
        out: Option<Toolpath>,
    ) -> Result<(Counts, Option<Toolpath>)> {
        least(&self.main, &Bound::steps(limits.max_steps))?;
        least(&self.main, &Bound::strings(limits.max_strings))?;
        let mut run = Run {
            prog: self,
            check,
            limits,
            frame: self.start,
            pen_down: true,
            c,
            v,
            area,
            rng: SplitMix64::new(self.seed),
            memo: Memo::default(),
            saved: Vec::new(),
            depth: 0,
            strings: 0,
            events: 0,
            steps: 0,
            moved: false,
            out,
        };
        let mut vals = Vec::new();
        run.block(&self.main, &mut vals)?;
        let counts = Counts {
            strings: run.strings,
            events: run.events,
        };
        Ok((counts, run.out))
    }
}

/// Steps a program may run before it has made anything (about 0.4 s).
pub(crate) const IDLE_STEPS: u64 = 4_000_000;
/// Steps allowed for each string or event made, on top of [`IDLE_STEPS`]:
/// the gallery's L-systems and recursive procedures need fewer than 8.
pub(crate) const STEPS_PER_STRING: u64 = 16;

/// Most `draw_turtle` markers a part keeps (the rest are not drawn).
pub(crate) const MAX_MARKERS: usize = 10_000;

/// Most frames `push` may save before a `pop`.
pub(crate) const MAX_SAVED: usize = 100_000;

/// What [`least`] bounds: each command's own count, the limit, and how
/// the error names them.
struct Bound {
    max: u64,
    unit: fn(&Op) -> u64,
    what: &'static str,
    raise: &'static str,
}

impl Bound {
    /// Steps: every command and L-system symbol is one.
    fn steps(max: u64) -> Bound {
        Bound {
            max,
            unit: |_| 1,
            what: "steps (commands and L-system symbols)",
            raise: "raise max_strings",
        }
    }

    /// Strings: a `forward`, `backward` or `lift` of a constant length other
    /// than 0 makes one, and so does a `move` or `draw` (but a path's first,
    /// which places it: hence one string of slack), so a runaway L-system is
    /// refused by its size before any string is made.
    fn strings(max: u64) -> Bound {
        Bound {
            max: max.saturating_add(1),
            unit: |op| {
                u64::from(match op {
                    Op::Forward(v, _) | Op::Lift(v) => v.expr.constant().is_some_and(|x| x != 0.0),
                    Op::To(..) => true,
                    _ => false,
                })
            },
            what: "strings (moves forward, lift, goto, move, draw)",
            raise: "raise the recipe's max_strings",
        }
    }
}

/// A lower bound of `b`'s count over `cmds`, known without running them:
/// each command counts its own unit, a `repeat` of a constant count runs
/// its body that many times, an `if` at least its shorter branch, an
/// L-system of constant iterations visits a known number of symbols
/// (counted per derivation depth, never expanded); counts that depend on
/// counters, parameters of procedures or `rand()`, and calls, count as
/// nothing more. The first construct whose bound passes the limit is
/// refused at once, naming its place, instead of after seconds of running
/// up to it.
fn least(cmds: &[Cmd], b: &Bound) -> Result<u64> {
    let mut total = 0u64;
    for cmd in cmds {
        let own = match &cmd.op {
            Op::Repeat { count, body, .. } => {
                let inner = least(body, b)?;
                match count.expr.constant() {
                    Some(n) if n.fract() == 0.0 && (0.0..=1e12).contains(&n) => {
                        (n as u64).saturating_mul(inner)
                    }
                    _ => 0,
                }
            }
            Op::If {
                then, otherwise, ..
            } => least(then, b)?.min(least(otherwise, b)?),
            Op::Lsystem(ls) => lsystem_least(ls, b)?,
            _ => 0,
        };
        let n = own.saturating_add((b.unit)(&cmd.op));
        if n > b.max {
            return Err(too_many(&cmd.place, "this runs", n, b));
        }
        total = total.saturating_add(n);
    }
    if total > b.max {
        let place = cmds.first().map_or("program", |c| c.place.as_str());
        return Err(too_many(place, "the commands from here run", total, b));
    }
    Ok(total)
}

/// [`least`] of an L-system of constant iterations: a symbol at depth d
/// counts its unit, then its rule's symbols at d + 1 (d < n) or its commands.
fn lsystem_least(ls: &Lsystem, b: &Bound) -> Result<u64> {
    let n = match ls.iterations.expr.constant() {
        Some(n) if n.fract() == 0.0 && (0.0..=MAX_ITERATIONS as f64).contains(&n) => n as u32,
        _ => return Ok(0),
    };
    // a symbol is a step of its own, and makes no string itself
    let sym = (b.unit)(&Op::PenUp);
    let own: Vec<u64> = ls
        .commands
        .iter()
        .map(|c| least(c, b))
        .collect::<Result<_>>()?;
    let mut at = own
        .iter()
        .map(|&k| k.saturating_add(sym))
        .collect::<Vec<_>>();
    for _ in 0..n {
        at = ls
            .rules
            .iter()
            .zip(&own)
            .map(|(rule, &k)| match rule {
                Some(r) => r
                    .iter()
                    .fold(sym, |acc, &t| acc.saturating_add(at[t as usize])),
                None => k.saturating_add(sym),
            })
            .collect();
    }
    Ok(ls
        .axiom
        .iter()
        .fold(0u64, |acc, &s| acc.saturating_add(at[s as usize])))
}

fn too_many(place: &str, what: &str, n: u64, b: &Bound) -> Error {
    let n = if n == u64::MAX {
        "2^64".to_string()
    } else {
        n.to_string()
    };
    Error::input(
        place,
        format!(
            "{what} at least {n} {}, more than the limit of {}; expected fewer repeats or iterations (or {})",
            b.what, b.max, b.raise
        ),
    )
}

impl<'a> Run<'a> {
    fn step(&mut self, place: &str) -> Result<()> {
        self.steps += 1;
        // work is budgeted by what it makes: a program may run IDLE_STEPS
        // steps, and STEPS_PER_STRING more for every string or event it has
        // made. A procedure calling itself twice, 60 deep, that draws
        // nothing ran 400 million steps (44 s) before the absolute limit
        // below stopped it; now it stops within a second.
        let made = self.strings.saturating_add(self.events);
        let allowed = STEPS_PER_STRING
            .saturating_mul(made)
            .saturating_add(IDLE_STEPS);
        if self.steps > allowed && self.steps <= self.limits.max_steps {
            return Err(Error::input(
                place,
                format!(
                    "the program has run {} steps (commands and L-system symbols) here but made only {made} strings and events; expected at most {STEPS_PER_STRING} steps per string after the first {IDLE_STEPS} (a procedure that calls itself without drawing?)",
                    self.steps
                ),
            ));
        }
        if self.steps > self.limits.max_steps {
            return Err(Error::input(
                place,
                format!(
                    "the program runs more than {} steps (commands and L-system symbols) here; expected a program that ends sooner (or raise max_strings)",
                    self.limits.max_steps
                ),
            ));
        }
        Ok(())
    }

    fn made(&mut self, place: &str) -> Result<()> {
        if self.strings + self.events > self.limits.max_strings {
            return Err(Error::input(
                place,
                format!(
                    "this turtle makes more than the limit of {} strings and events here; expected fewer repeats or iterations (or raise max_strings)",
                    self.limits.max_strings
                ),
            ));
        }
        Ok(())
    }

    /// Evaluates `val` with the counters and parameters `vals` in scope.
    fn eval(&mut self, val: &Val, vals: &mut Vec<f64>, place: &str) -> Result<f64> {
        let mut vars = [0.0; var::COUNT];
        vars[var::X] = self.frame.pos.x;
        vars[var::Y] = self.frame.pos.y;
        vars[var::Z] = self.frame.pos.z;
        let n = vals.len();
        // the turtle's state (program::STATE), after the scope's slots
        let state = if val.reads_state {
            self.frame.angles()
        } else {
            [0.0; 3]
        };
        vals.extend(state);
        vals.push(if self.pen_down { 1.0 } else { 0.0 });
        for _ in 0..val.expr.rands() {
            vals.push(self.rng.uniform());
        }
        let x = val.expr.eval_ext(&vars, vals, &mut self.memo);
        vals.truncate(n);
        if x.is_finite() {
            return Ok(x);
        }
        let mut with: Vec<String> = val
            .scope
            .iter()
            .zip(vals.iter())
            .map(|(name, v)| format!("{name} = {v}"))
            .collect();
        if val.expr.uses(var::X) || val.expr.uses(var::Y) || val.expr.uses(var::Z) {
            let p = self.frame.pos;
            with.push(format!("(x, y, z) = ({}, {}, {})", p.x, p.y, p.z));
        }
        Err(Error::input(
            place,
            format!(
                "`{}` gives {x}{}{}; expected a finite number",
                val.expr.src(),
                if with.is_empty() { "" } else { " with " },
                with.join(", ")
            ),
        ))
    }

    fn eval3(&mut self, v: &[Val; 3], vals: &mut Vec<f64>, place: &str) -> Result<DVec3> {
        Ok(DVec3::new(
            self.eval(&v[0], vals, &format!("{place}[0]"))?,
            self.eval(&v[1], vals, &format!("{place}[1]"))?,
            self.eval(&v[2], vals, &format!("{place}[2]"))?,
        ))
    }

    fn positive(&mut self, val: &Val, vals: &mut Vec<f64>, place: &str) -> Result<f64> {
        let x = self.eval(val, vals, place)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(Error::input(
                place,
                format!("`{}` gives {x}; expected a number > 0", val.expr.src()),
            ))
        }
    }

    fn within(
        &mut self,
        val: &Val,
        vals: &mut Vec<f64>,
        place: &str,
        lo: f64,
        hi: f64,
    ) -> Result<f64> {
        let x = self.eval(val, vals, place)?;
        if (lo..=hi).contains(&x) {
            Ok(x)
        } else {
            Err(Error::input(
                place,
                format!(
                    "`{}` gives {x}; expected a number from {lo} to {hi}",
                    val.expr.src()
                ),
            ))
        }
    }

    fn whole(&mut self, val: &Val, vals: &mut Vec<f64>, place: &str, max: f64) -> Result<u64> {
        let x = self.eval(val, vals, place)?;
        if x.fract() == 0.0 && (0.0..=max).contains(&x) {
            Ok(x as u64)
        } else {
            Err(Error::input(
                place,
                format!(
                    "`{}` gives {x}; expected a whole number from 0 to {max}",
                    val.expr.src()
                ),
            ))
        }
    }

    /// Moves the head to `to`: an extruding string with the pen down, else travel.
    fn go(&mut self, to: DVec3, place: &str) -> Result<()> {
        self.go_as(to, self.pen_down, false, place)
    }

    /// Moves the head to `to`: an extruding string when `draw`, else a
    /// travel; one of length 0 only when `keep` (a path's `move` and
    /// `draw`). A path's first movement, when it travels, is where the path
    /// starts instead.
    fn go_as(&mut self, to: DVec3, draw: bool, keep: bool, place: &str) -> Result<()> {
        let first = !self.moved;
        self.moved = true;
        if self.prog.path && first && !draw {
            self.start_at(to);
            return Ok(());
        }
        if to == self.frame.pos && !keep {
            return Ok(());
        }
        self.strings += 1;
        self.made(place)?;
        if let Some(tp) = &mut self.out {
            if draw {
                tp.draw(to, self.c, self.v);
            } else {
                tp.travel(to, self.v);
            }
        }
        self.frame.pos = to;
        Ok(())
    }

    /// The path starts at `to` (nothing drawn or travelled yet).
    fn start_at(&mut self, to: DVec3) {
        if let Some(tp) = &mut self.out {
            tp.points[0] = to;
        }
        self.frame.pos = to;
    }

    fn event(&mut self, e: Event, place: &str) -> Result<()> {
        self.events += 1;
        self.made(place)?;
        if let Some(tp) = &mut self.out {
            tp.event(e);
        }
        Ok(())
    }

    /// Runs `cmds` and everything they start, on the run's own stack of
    /// [`Task`]s (on the heap): the nesting of blocks, calls and L-system
    /// derivations uses no thread stack, so the interpreter runs on any
    /// thread. Commands, counters, calls and symbols come in exactly the
    /// order of a depth-first walk of the program.
    fn block(&mut self, cmds: &'a [Cmd], vals: &mut Vec<f64>) -> Result<()> {
        let mut tasks = vec![Task::Block(cmds.iter(), vals.len())];
        while let Some(task) = tasks.last_mut() {
            match task {
                Task::Block(cmds, base) => match cmds.next() {
                    Some(cmd) => self.command(cmd, vals, &mut tasks)?,
                    None => {
                        vals.truncate(*base);
                        tasks.pop();
                    }
                },
                Task::For {
                    body,
                    next,
                    n,
                    values,
                } => {
                    if *next > 0 {
                        vals.pop();
                    }
                    if *next < *n {
                        vals.push(values.at(*next));
                        *next += 1;
                        let body = *body;
                        tasks.push(Task::Block(body.iter(), vals.len()));
                    } else {
                        tasks.pop();
                    }
                }
                Task::Repeat {
                    body,
                    next,
                    n,
                    counter,
                } => {
                    // the counter of the iteration just run comes off first
                    if *counter && *next > 0 {
                        vals.pop();
                    }
                    if *next < *n {
                        if *counter {
                            vals.push(*next as f64);
                        }
                        *next += 1;
                        let body = *body;
                        tasks.push(Task::Block(body.iter(), vals.len()));
                    } else {
                        tasks.pop();
                    }
                }
                Task::Return(caller) => {
                    *vals = std::mem::take(caller);
                    self.depth -= 1;
                    tasks.pop();
                }
                Task::Symbols {
                    ls,
                    symbols,
                    d,
                    n,
                    place,
                } => {
                    let (ls, d, n, place) = (*ls, *d, *n, *place);
                    match symbols.next() {
                        Some(&s) => {
                            let base = vals.len();
                            self.symbol(ls, (s, d, n), base, place, &mut tasks)?
                        }
                        None => {
                            tasks.pop();
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Symbol `s` at derivation depth `d` of `n` (see [`super::lsystem`]):
    /// its rule's symbols at depth d + 1 while d < n, else its commands.
    fn symbol(
        &mut self,
        ls: &'a Lsystem,
        (s, d, n): (u16, u32, u32),
        base: usize,
        place: &'a str,
        tasks: &mut Vec<Task<'a>>,
    ) -> Result<()> {
        self.step(place)?;
        if d < n {
            if let Some(rule) = &ls.rules[s as usize] {
                tasks.push(Task::Symbols {
                    ls,
                    symbols: rule.iter(),
                    d: d + 1,
                    n,
                    place,
                });
                return Ok(());
            }
        }
        tasks.push(Task::Block(ls.commands[s as usize].iter(), base));
        Ok(())
    }

    /// Runs one command; one that runs others (`repeat`, `if`, `call`,
    /// `lsystem`) pushes them as tasks.
    fn command(
        &mut self,
        cmd: &'a Cmd,
        vals: &mut Vec<f64>,
        tasks: &mut Vec<Task<'a>>,
    ) -> Result<()> {
        let place = cmd.place.as_str();
        self.step(place)?;
        match &cmd.op {
            Op::Forward(..) | Op::Lift(_) | Op::Goto(_) | Op::Turn(..) | Op::SetHeading(_) => {
                self.movement(&cmd.op, vals, place)
            }
            Op::PenUp | Op::PenDown | Op::Pause | Op::DrawTurtle | Op::Push | Op::Pop => {
                self.pen(&cmd.op, place)
            }
            Op::Set(..) | Op::Extrude(..) | Op::Dwell(_) | Op::Fan(_) | Op::Temp { .. } => {
                self.setting(&cmd.op, vals, place)
            }
            Op::Hair { length, blob, rate } => self.hair(length, blob, rate, vals, place),
            Op::To(..)
            | Op::For { .. }
            | Op::Let(_)
            | Op::Curve(_)
            | Op::ExtrudeVolume(..)
            | Op::Gcode(_)
            | Op::GcodeWith(_)
            | Op::Printer(_) => self.program(&cmd.op, vals, place, tasks),
            Op::Repeat {
                count,
                counter,
                body,
            } => {
                let n = self.whole(count, vals, place, 1e12)?;
                tasks.push(Task::Repeat {
                    body,
                    next: 0,
                    n,
                    counter: *counter,
                });
                Ok(())
            }
            Op::If {
                cond,
                then,
                otherwise,
            } => {
                let x = self.eval(cond, vals, place)?;
                let branch = if x != 0.0 { then } else { otherwise };
                tasks.push(Task::Block(branch.iter(), vals.len()));
                Ok(())
            }
            Op::Call { proc, args } => self.call(*proc, args, vals, place, tasks),
            Op::Lsystem(ls) => {
                let p = format!("{place}.iterations");
                let n = self.whole(&ls.iterations, vals, &p, MAX_ITERATIONS as f64)? as u32;
                tasks.push(Task::Symbols {
                    ls,
                    symbols: ls.axiom.iter(),
                    d: 0,
                    n,
                    place,
                });
                Ok(())
            }
        }
    }

    /// `forward`, `backward`, `lift`, `goto`, the turns and `set_heading`.
    fn movement(&mut self, op: &Op, vals: &mut Vec<f64>, place: &str) -> Result<()> {
        match op {
            Op::Forward(d, sign) => {
                let d = sign * self.eval(d, vals, place)?;
                let to = self.frame.pos + self.frame.heading * d;
                self.go(to, place)?;
            }
            Op::Lift(d) => {
                let d = self.eval(d, vals, place)?;
                let to = self.frame.pos + self.frame.up * d;
                self.go(to, place)?;
            }
            Op::Goto(p) => {
                let to = self.eval3(p, vals, place)?;
                if self.prog.path && !self.moved {
                    // a path's first point visit is where it starts (as a
                    // curve's first point), not a string from the origin
                    self.moved = true;
                    self.start_at(to);
                } else {
                    self.go(to, place)?;
                }
            }
            Op::Turn(axis, a, sign) => {
                let a = sign * self.eval(a, vals, place)?;
                match axis {
                    Axis::Yaw => self.frame.yaw(a),
                    Axis::Pitch => self.frame.pitch(a),
                    Axis::Roll => self.frame.roll(a),
                }
            }
            Op::SetHeading(hu) => {
                let (h, up) = &**hu;
                let h = self.eval3(h, vals, place)?;
                let up = match up {
                    Some(u) => Some(self.eval3(u, vals, place)?),
                    None => None,
                };
                self.frame
                    .set_heading(h, up)
                    .map_err(|e| Error::input(place, e.to_string()))?;
            }
            _ => {}
        }
        Ok(())
    }

    /// The pen, `pause`, `draw_turtle`, `push` and `pop`.
    fn pen(&mut self, op: &Op, place: &str) -> Result<()> {
        match op {
            // a pen already up stays up without a second retraction
            Op::PenUp if self.pen_down => {
                // a path has nothing to retract before its first string
                if !(self.prog.path && self.strings == 0) {
                    self.event(Event::Retract, place)?;
                }
                self.pen_down = false;
            }
            Op::PenDown => self.pen_down = true,
            Op::Pause => self.event(Event::Pause, place)?,
            Op::DrawTurtle => {
                // ExtruderTurtle's draw_Turtle(): seen in the previews only
                if let Some(tp) = &mut self.out {
                    if tp.markers.len() < MAX_MARKERS {
                        tp.markers.push(crate::base::toolpath::Marker {
                            pos: self.frame.pos,
                            heading: self.frame.heading,
                            up: self.frame.up,
                        });
                    }
                }
            }
            Op::Push => {
                // each saved frame is memory: a push without a pop is bounded
                if self.saved.len() >= MAX_SAVED {
                    return Err(Error::input(
                        place,
                        format!("more than {MAX_SAVED} frames pushed and not popped; expected a `pop` for each `push`"),
                    ));
                }
                self.saved.push(self.frame)
            }
            Op::Pop => {
                let Some(f) = self.saved.pop() else {
                    return Err(Error::input(
                        place,
                        "`pop` without a `push` before it; expected one `push` per `pop`",
                    ));
                };
                // back to the saved place without drawing over what is printed
                let pen = self.pen_down;
                if pen && f.pos != self.frame.pos {
                    self.event(Event::Retract, place)?;
                }
                self.pen_down = false;
                self.go(f.pos, place)?;
                self.pen_down = pen;
                self.frame = f;
            }
            _ => {}
        }
        Ok(())
    }

    /// The settings (`extrude_rate`, `cross_section`, `speed`) and the
    /// events `extrude`, `dwell`, `fan` and the temperatures.
    fn setting(&mut self, op: &Op, vals: &mut Vec<f64>, place: &str) -> Result<()> {
        match op {
            Op::Set(what, x) => {
                let x = self.positive(x, vals, place)?;
                match what {
                    Setting::ExtrudeRate => self.c = x * self.area,
                    Setting::CrossSection => self.c = x,
                    Setting::Speed => self.v = x,
                }
            }
            Op::Extrude(mm, feed) => {
                let filament = self.within(mm, vals, place, 0.0, 1000.0)?;
                let speed = match feed {
                    Some(f) => {
                        let p = place.replace(".extrude", ".feed");
                        let max = crate::machine::limits::SPEED_MAX;
                        let s = self.positive(f, vals, &p)?;
                        if s > max {
                            return Err(Error::input(
                                &p,
                                format!("{s} mm/s of filament is past any machine's feed; expected at most {max} mm/s"),
                            ));
                        }
                        s
                    }
                    None => DEFAULT_FEED,
                };
                self.event(Event::Extrude { filament, speed }, place)?;
            }
            Op::Dwell(ms) => {
                let ms = self.within(ms, vals, place, 0.0, 3.6e6)?;
                self.event(Event::Dwell { ms }, place)?;
            }
            Op::Fan(s) => {
                let speed = self.within(s, vals, place, 0.0, 1.0)?;
                self.event(Event::Fan { speed }, place)?;
            }
            Op::Temp { bed, celsius, wait } => {
                // the physical bounds of crate::machine::limits: a hotter one is
                // refused, not left to a check that --force skips
                let max = if *bed {
                    crate::machine::limits::BED_TEMP_MAX
                } else {
                    crate::machine::limits::NOZZLE_TEMP_MAX
                };
                let t = self.within(celsius, vals, place, 0.0, max)?;
                let e = if *bed {
                    Event::BedTemp {
                        celsius: t,
                        wait: *wait,
                    }
                } else {
                    Event::NozzleTemp {
                        celsius: t,
                        wait: *wait,
                    }
                };
                self.event(e, place)?;
            }
            _ => {}
        }
        Ok(())
    }

    /// `call`: the arguments evaluated in the caller's values, then the
    /// procedure's body pushed above the caller's values to come back to.
    fn call(
        &mut self,
        proc: usize,
        args: &[Val],
        vals: &mut Vec<f64>,
        place: &str,
        tasks: &mut Vec<Task<'a>>,
    ) -> Result<()> {
        let mut inner = Vec::with_capacity(args.len());
        for (j, a) in args.iter().enumerate() {
            let p = format!("{}.args[{j}]", place.trim_end_matches(".call"));
            let x = self.eval(a, vals, &p)?;
            inner.push(x);
        }
        let prog = self.prog;
        let p = &prog.procs[proc];
        if self.depth >= MAX_CALL_DEPTH {
            return Err(Error::input(
                place,
                format!(
                    "calls nest deeper than {MAX_CALL_DEPTH} here: procedure `{}` recurses without bound; expected an `if` that stops the recursion",
                    p.name
                ),
            ));
        }
        self.depth += 1;
        tasks.push(Task::Return(std::mem::replace(vals, inner)));
        tasks.push(Task::Block(p.body.iter(), vals.len()));
        Ok(())
    }

    /// `hair`: Laput et al.'s blob-and-pull (ExtruderTurtle §4.3): a blob in
    /// place, a thin pull along the heading, a retraction that snaps it; the
    /// pen is up afterwards.
    fn hair(
        &mut self,
        length: &Val,
        blob: &Option<Val>,
        rate: &Option<Val>,
        vals: &mut Vec<f64>,
        place: &str,
    ) -> Result<()> {
        let len = self.positive(length, vals, place)?;
        let blob = match blob {
            Some(b) => {
                let p = place.replace(".hair", ".blob");
                self.within(b, vals, &p, 0.0, 1000.0)?
            }
            None => DEFAULT_HAIR_BLOB,
        };
        let rate = match rate {
            Some(r) => {
                let p = place.replace(".hair", ".rate");
                self.positive(r, vals, &p)?
            }
            None => DEFAULT_HAIR_RATE,
        };
        if blob > 0.0 {
            let e = Event::Extrude {
                filament: blob,
                speed: DEFAULT_FEED,
            };
            self.event(e, place)?;
        }
        let to = self.frame.pos + self.frame.heading * len;
        if !to.is_finite() {
            return Err(Error::input(place, "the hair's tip is not finite"));
        }
        self.strings += 1;
        self.made(place)?;
        if let Some(tp) = &mut self.out {
            tp.hair(to, rate * self.area, self.v);
        }
        self.frame.pos = to;
        self.event(Event::Retract, place)?;
        self.pen_down = false;
        Ok(())
    }
}

/// Most strings one curve command may make (each a step of its own beside).
pub(crate) const MAX_CURVE_SEGMENTS: f64 = 1e7;

/// Most terms of one `bezier`: (segments + 1) × control points, each term
/// two powers (a straight Bézier of two points may still have the most
/// segments).
pub(crate) const MAX_BEZIER_TERMS: f64 = 2e7;

impl<'a> Run<'a> {
    /// The commands the turtle shares with a path: `move`/`draw`, `for`,
    /// `let`, the curves, `extrude_volume` and `gcode`.
    fn program(
        &mut self,
        op: &'a Op,
        vals: &mut Vec<f64>,
        place: &str,
        tasks: &mut Vec<Task<'a>>,
    ) -> Result<()> {
        match op {
            Op::To(p, draw) => {
                let to = self.eval3(p, vals, place)?;
                self.go_as(to, *draw, true, place)
            }
            Op::For { values, body } => {
                let (n, values) = self.for_values(values, vals, place)?;
                tasks.push(Task::For {
                    body,
                    next: 0,
                    n,
                    values,
                });
                Ok(())
            }
            Op::Let(vs) => {
                for (k, v) in vs.iter().enumerate() {
                    let x = self.eval(v, vals, &format!("{place}[{k}]"))?;
                    vals.push(x);
                }
                Ok(())
            }
            Op::Curve(c) => {
                let points = self.curve(c, vals, place)?;
                for (k, p) in points.into_iter().enumerate() {
                    if k == 0 && self.prog.path && !self.moved {
                        // a curve that begins a path places it at its first point
                        self.moved = true;
                        self.start_at(p);
                        continue;
                    }
                    self.go(p, place)?;
                }
                Ok(())
            }
            Op::ExtrudeVolume(v, feed) => {
                let volume = self.within(v, vals, place, 0.0, 1e5)?;
                let speed = match feed {
                    Some(f) => {
                        let p = place.replace(".extrude_volume", ".feed");
                        self.positive(f, vals, &p)?
                    }
                    None => DEFAULT_FEED,
                };
                let filament = volume / self.filament_area();
                self.event(Event::Extrude { filament, speed }, place)
            }
            Op::Gcode(text) => self.event(Event::Gcode(text.clone()), place),
            Op::GcodeWith(pieces) => self.gcode(pieces, vals, place),
            Op::Printer(named) => self.printer(named, vals, place),
            _ => Ok(()),
        }
    }

    /// `gcode` with `{expr}`s: each value evaluated here and written into
    /// the line, which is then checked as a literal line is when compiled.
    fn gcode(&mut self, pieces: &[Piece], vals: &mut Vec<f64>, place: &str) -> Result<()> {
        let mut line = String::new();
        for p in pieces {
            match p {
                Piece::Text(t) => line.push_str(t),
                Piece::Value(v) => {
                    let x = self.eval(v, vals, place)?;
                    line.push_str(&fmt_value(x));
                }
            }
        }
        // the building run writes it: checked then (the counting run
        // evaluated the same values)
        if self.out.is_some() {
            (self.check)(&line).map_err(|m| {
                Error::input(place, format!("the line `{}` made here: {m}", line.trim()))
            })?;
        }
        self.event(Event::Gcode(line.trim().into()), place)
    }

    /// `set`: the printer's settings with their values here, one event
    /// each (as the firmware sets them: print and travel acceleration in
    /// one …), each naming its key path for the `setting` check; with
    /// `band`, the first carries the line's band (its value the first
    /// setting's), as a `set` step's does.
    fn printer(&mut self, set: &Settings, vals: &mut Vec<f64>, place: &str) -> Result<()> {
        let mut first = None;
        let settings = set.named.lower(|key, v| {
            // the key's place made only when its value fails
            let x = self.eval(v, vals, place).map_err(|mut e| {
                e.place = Some(format!("{place}.{}", key.name()));
                e
            })?;
            first.get_or_insert(x);
            Ok(x)
        })?;
        let mut band = match &set.band {
            Some(v) => Some(Band {
                index: self.line_index(v, vals, place)?,
                value: first.unwrap_or(0.0),
                z: None,
            }),
            None => None,
        };
        for (setting, key) in settings {
            let at = self.out.is_some().then(|| format!("{place}.{key}").into());
            let e = Event::Set {
                setting,
                band: band.take(),
                place: at,
            };
            self.event(e, place)?;
        }
        Ok(())
    }

    /// A `set` command's `band`: a whole number from 0, a line's index.
    fn line_index(&mut self, v: &Val, vals: &mut Vec<f64>, place: &str) -> Result<u32> {
        let at = format!("{place}.band");
        let b = self.eval(v, vals, &at)?;
        if b.fract() != 0.0 || !(0.0..=f64::from(u32::MAX)).contains(&b) {
            return Err(Error::input(
                at,
                format!("`band` gives {b}; expected a whole number from 0 (the index of a line test's line)"),
            ));
        }
        Ok(b as u32)
    }

    /// The filament's cross-section, mm² (`extrude_rate` and volumes use it).
    fn filament_area(&self) -> f64 {
        self.area
    }

    /// How many values a `for` runs over, and how to get each.
    fn for_values(
        &mut self,
        values: &Values,
        vals: &mut Vec<f64>,
        place: &str,
    ) -> Result<(u64, ForValues)> {
        match values {
            Values::List(list) => {
                let mut v = Vec::with_capacity(list.len());
                for (k, x) in list.iter().enumerate() {
                    v.push(self.eval(x, vals, &format!("{place}[{k}]"))?);
                }
                Ok((v.len() as u64, ForValues::List(v)))
            }
            Values::Range(a, b, step) => {
                let a = self.eval(a, vals, place)?;
                let b = self.eval(b, vals, place)?;
                let step = match step {
                    Some(s) => self.eval(s, vals, place)?,
                    None => 1.0,
                };
                if step == 0.0 {
                    return Err(Error::input(
                        place,
                        "the step of the range is 0; expected a step that moves from a to b",
                    ));
                }
                // b included within 1e-9 of a step (0..1:0.1 ends at 1), as
                // a part's `for`; a step away from b makes no values
                let span = (b - a) / step;
                let n = if span < -1e-9 {
                    0.0
                } else {
                    libm::floor(span + 1e-9 * span.abs().max(1.0)) + 1.0
                };
                if !n.is_finite() || n > 1e12 {
                    return Err(Error::input(
                        place,
                        format!("the range has {n} values; expected at most 10^12"),
                    ));
                }
                Ok((n as u64, ForValues::Range(a, step)))
            }
        }
    }

    /// The points of a curve, first to last.
    fn curve(&mut self, c: &Curve, vals: &mut Vec<f64>, place: &str) -> Result<Vec<DVec3>> {
        let segments = |run: &mut Self, v: &Val, vals: &mut Vec<f64>| -> Result<usize> {
            let p = format!("{place}.segments");
            let n = run.whole(v, vals, &p, MAX_CURVE_SEGMENTS)?;
            if n == 0 {
                return Err(Error::input(p, "0 segments; expected at least 1"));
            }
            Ok(n as usize)
        };
        let key = |k: &str| format!("{place}.{k}");
        Ok(match c {
            Curve::Arc {
                center,
                radius,
                start,
                sweep,
                segments: n,
                end_radius,
                rise,
            } => {
                let o = self.eval3(center, vals, &key("center"))?;
                let r0 = self.eval(radius, vals, &key("radius"))?;
                let a0 = self.eval(start, vals, &key("start"))?;
                let da = self.eval(sweep, vals, &key("sweep"))?;
                let n = segments(self, n, vals)?;
                let r1 = match end_radius {
                    Some(v) => self.eval(v, vals, &key("end_radius"))?,
                    None => r0,
                };
                let dz = match rise {
                    Some(v) => self.eval(v, vals, &key("rise"))?,
                    None => 0.0,
                };
                super::shapes::arc(o, r0, r1, a0, da, dz, n)
            }
            Curve::Bezier {
                points,
                segments: n,
            } => {
                let mut ctrl = Vec::with_capacity(points.len());
                for (k, p) in points.iter().enumerate() {
                    ctrl.push(self.eval3(p, vals, &format!("{place}.points[{k}]"))?);
                }
                let n = segments(self, n, vals)?;
                // each point of the curve sums a term per control point
                let terms = (n as f64 + 1.0) * ctrl.len() as f64;
                if terms > MAX_BEZIER_TERMS {
                    return Err(Error::input(
                        key("segments"),
                        format!(
                            "{n} segments of a curve of {} control points make {terms:.0} terms; expected at most {MAX_BEZIER_TERMS:.0} (fewer segments or control points)",
                            ctrl.len()
                        ),
                    ));
                }
                super::shapes::bezier(&ctrl, n)
            }
            Curve::Line {
                from,
                to,
                segments: n,
            } => {
                let a = match from {
                    Some(p) => self.eval3(p, vals, &key("from"))?,
                    None => self.frame.pos,
                };
                let b = self.eval3(to, vals, &key("to"))?;
                let n = segments(self, n, vals)?;
                (0..=n)
                    .map(|k| a + (b - a) * (k as f64 / n as f64))
                    .collect()
            }
            Curve::Rectangle {
                corner,
                size,
                clockwise,
            } => {
                let c = self.eval3(corner, vals, &key("corner"))?;
                let dx = self.eval(&size[0], vals, &key("size[0]"))?;
                let dy = self.eval(&size[1], vals, &key("size[1]"))?;
                super::shapes::rectangle(c, dx, dy, *clockwise)
            }
        })
    }
}
