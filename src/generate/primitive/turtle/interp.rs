//! The interpreter: runs a compiled turtle program into strings and events.
//!
//! It runs twice: first counting (strings, events and steps, nothing
//! stored), so a program over the limit is refused before it allocates, then
//! building a toolpath of exactly the counted size. `rand()` restarts from
//! the seed for each run, so both see the same numbers.

use glam::DVec3;

use super::frame::Frame;
use super::lsystem::{Lsystem, MAX_ITERATIONS};
use super::program::{Axis, Cmd, Op, Proc, Setting, Val};
use crate::base::error::{Error, Result};
use crate::base::expr::{var, Memo};
use crate::base::rng::SplitMix64;
use crate::base::toolpath::{Event, Toolpath};

/// Deepest nesting of procedure calls (a procedure calling itself with no
/// `if` to stop it reaches this at once).
pub const MAX_CALL_DEPTH: usize = 200;
/// Filament speed of `extrude` in place without `feed:`, mm/s.
pub const DEFAULT_FEED: f64 = 1.0;
/// Filament of a hair's blob without `blob:`, mm (about 0.1 mm³ of 1.75 mm
/// filament: a bead a nozzle wide and high).
pub const DEFAULT_HAIR_BLOB: f64 = 0.05;
/// Extrude rate of a hair's pull without `rate:`, mm of filament per mm: a
/// third of ExtruderTurtle's 0.03 for a 0.2 mm layer, "extruding little".
pub const DEFAULT_HAIR_RATE: f64 = 0.01;

/// What a run may produce and how it starts.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Most strings plus events (the recipe's `max_strings`).
    pub max_strings: u64,
    /// Most steps (commands run and L-system symbols visited).
    pub max_steps: u64,
}

/// A compiled program ready to run.
#[derive(Clone, Debug)]
pub struct Program {
    /// The start frame.
    pub start: Frame,
    /// Seed of `rand()`.
    pub seed: u64,
    /// The commands.
    pub main: Vec<Cmd>,
    /// The procedures, by number.
    pub procs: Vec<Proc>,
}

/// The state of one run.
struct Run<'a> {
    prog: &'a Program,
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
    out: Option<Toolpath>,
}

/// Work a run has left, innermost last: the interpreter's own stack.
enum Task<'a> {
    /// The commands of a block still to run.
    Block(std::slice::Iter<'a, Cmd>),
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

/// Counts of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Counts {
    /// Strings made.
    pub strings: u64,
    /// Events made.
    pub events: u64,
}

impl Program {
    /// Runs the program: strings start with cross-section `c` and speed `v`;
    /// `area` (mm²) turns `extrude_rate` into a cross-section.
    pub fn run(&self, c: f64, v: f64, area: f64, limits: Limits) -> Result<Toolpath> {
        let (counts, _) = self.execute(c, v, area, limits, None)?;
        let mut tp = Toolpath::with_capacity(self.start.pos, counts.strings as usize);
        tp.events.reserve(counts.events as usize);
        let (_, tp) = self.execute(c, v, area, limits, Some(tp))?;
        Ok(tp.expect("a building run returns its toolpath"))
    }

    /// Counts what the program makes, storing nothing.
    pub fn count(&self, c: f64, v: f64, area: f64, limits: Limits) -> Result<Counts> {
        Ok(self.execute(c, v, area, limits, None)?.0)
    }

    fn execute(
        &self,
        c: f64,
        v: f64,
        area: f64,
        limits: Limits,
        out: Option<Toolpath>,
    ) -> Result<(Counts, Option<Toolpath>)> {
        least_steps(&self.main, limits.max_steps)?;
        let mut run = Run {
            prog: self,
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
pub const IDLE_STEPS: u64 = 4_000_000;
/// Steps allowed for each string or event made, on top of [`IDLE_STEPS`]:
/// the gallery's L-systems and recursive procedures need fewer than 8.
pub const STEPS_PER_STRING: u64 = 16;

/// Most `draw_turtle` markers a part keeps (the rest are not drawn).
pub const MAX_MARKERS: usize = 10_000;

/// Most frames `push` may save before a `pop`.
pub const MAX_SAVED: usize = 100_000;

/// A lower bound of the steps `cmds` run, known without running them: every
/// command is a step, a `repeat` of a constant count runs its body that many
/// times, an `if` at least its shorter branch, an L-system of constant
/// iterations visits a known number of symbols (counted per derivation depth,
/// never expanded); counts that depend on counters, parameters of procedures
/// or `rand()`, and calls, count as nothing more. The first construct whose
/// bound passes `max_steps` is refused at once, naming its place, instead of
/// after seconds of running up to the limit.
fn least_steps(cmds: &[Cmd], max_steps: u64) -> Result<u64> {
    let mut total = 0u64;
    for cmd in cmds {
        let own = match &cmd.op {
            Op::Repeat { count, body, .. } => {
                let inner = least_steps(body, max_steps)?;
                match count.expr.constant() {
                    Some(n) if n.fract() == 0.0 && (0.0..=1e12).contains(&n) => {
                        (n as u64).saturating_mul(inner)
                    }
                    _ => 0,
                }
            }
            Op::If {
                then, otherwise, ..
            } => least_steps(then, max_steps)?.min(least_steps(otherwise, max_steps)?),
            Op::Lsystem(ls) => match ls.iterations.expr.constant() {
                Some(n) if n.fract() == 0.0 && (0.0..=MAX_ITERATIONS as f64).contains(&n) => {
                    let own: Vec<u64> = ls
                        .commands
                        .iter()
                        .map(|c| least_steps(c, max_steps))
                        .collect::<Result<_>>()?;
                    // steps of one symbol at depth d: 1, then its rule's
                    // symbols at d + 1 (d < n) or its commands
                    let mut at = own.iter().map(|&k| k.saturating_add(1)).collect::<Vec<_>>();
                    for _ in 0..n as u32 {
                        at = ls
                            .rules
                            .iter()
                            .zip(&own)
                            .map(|(rule, &k)| match rule {
                                Some(r) => r
                                    .iter()
                                    .fold(1u64, |acc, &t| acc.saturating_add(at[t as usize])),
                                None => k.saturating_add(1),
                            })
                            .collect();
                    }
                    ls.axiom
                        .iter()
                        .fold(0u64, |acc, &s| acc.saturating_add(at[s as usize]))
                }
                _ => 0,
            },
            _ => 0,
        };
        let steps = own.saturating_add(1);
        if steps > max_steps {
            return Err(Error::input(
                &cmd.place,
                format!(
                    "this runs at least {} steps (commands and L-system symbols), more than the limit of {max_steps}; expected fewer repeats or iterations (or raise max_strings)",
                    if steps == u64::MAX { "2^64".to_string() } else { steps.to_string() }
                ),
            ));
        }
        total = total.saturating_add(steps);
    }
    if total > max_steps {
        let place = cmds.first().map_or("program", |c| c.place.as_str());
        return Err(Error::input(
            place,
            format!(
                "the commands from here run at least {total} steps, more than the limit of {max_steps}; expected fewer repeats or iterations (or raise max_strings)"
            ),
        ));
    }
    Ok(total)
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
        if to == self.frame.pos {
            return Ok(());
        }
        self.strings += 1;
        self.made(place)?;
        if let Some(tp) = &mut self.out {
            if self.pen_down {
                tp.draw(to, self.c, self.v);
            } else {
                tp.travel(to, self.v);
            }
        }
        self.frame.pos = to;
        Ok(())
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
        let mut tasks = vec![Task::Block(cmds.iter())];
        while let Some(task) = tasks.last_mut() {
            match task {
                Task::Block(cmds) => match cmds.next() {
                    Some(cmd) => self.command(cmd, vals, &mut tasks)?,
                    None => {
                        tasks.pop();
                    }
                },
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
                        tasks.push(Task::Block(body.iter()));
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
                        Some(&s) => self.symbol(ls, s, d, n, place, &mut tasks)?,
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
        s: u16,
        d: u32,
        n: u32,
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
        tasks.push(Task::Block(ls.commands[s as usize].iter()));
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
                tasks.push(Task::Block(if x != 0.0 { then } else { otherwise }.iter()));
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
                self.go(to, place)?;
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
                self.event(Event::Retract, place)?;
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
        tasks.push(Task::Block(p.body.iter()));
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
