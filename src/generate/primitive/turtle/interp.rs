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
use crate::base::expr::var;
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
    saved: Vec<Frame>,
    depth: usize,
    strings: u64,
    events: u64,
    steps: u64,
    out: Option<Toolpath>,
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

impl Run<'_> {
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
        let x = val.expr.eval_ext(&vars, vals);
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

    fn block(&mut self, cmds: &[Cmd], vals: &mut Vec<f64>) -> Result<()> {
        for cmd in cmds {
            self.command(cmd, vals)?;
        }
        Ok(())
    }

    /// Runs one command: the moves and turns here, the rest in a method each.
    fn command(&mut self, cmd: &Cmd, vals: &mut Vec<f64>) -> Result<()> {
        let place = cmd.place.as_str();
        self.step(place)?;
        match &cmd.op {
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
            Op::SetHeading(hu) => self.set_heading(&hu.0, hu.1.as_ref(), vals, place)?,
            Op::PenUp => {
                if self.pen_down {
                    self.event(Event::Retract, place)?;
                    self.pen_down = false;
                }
            }
            Op::PenDown => self.pen_down = true,
            Op::Pause => self.event(Event::Pause, place)?,
            Op::DrawTurtle => self.draw_turtle(),
            Op::Push => self.push(place)?,
            Op::Pop => self.pop(place)?,
            Op::Set(what, x) => self.set(*what, x, vals, place)?,
            Op::Extrude(mm, feed) => self.extrude(mm, feed.as_ref(), vals, place)?,
            Op::Dwell(ms) => {
                let ms = self.within(ms, vals, place, 0.0, 3.6e6)?;
                self.event(Event::Dwell { ms }, place)?;
            }
            Op::Fan(s) => {
                let speed = self.within(s, vals, place, 0.0, 1.0)?;
                self.event(Event::Fan { speed }, place)?;
            }
            Op::Temp { bed, celsius, wait } => self.temp(*bed, celsius, *wait, vals, place)?,
            Op::Repeat {
                count,
                counter,
                body,
            } => self.repeat(count, *counter, body, vals, place)?,
            Op::If {
                cond,
                then,
                otherwise,
            } => {
                let x = self.eval(cond, vals, place)?;
                self.block(if x != 0.0 { then } else { otherwise }, vals)?;
            }
            Op::Call { proc, args } => self.call(*proc, args, vals, place)?,
            Op::Hair { length, blob, rate } => {
                self.hair(length, blob.as_ref(), rate.as_ref(), vals, place)?
            }
            Op::Lsystem(ls) => self.lsystem(ls, vals, place)?,
        }
        Ok(())
    }

    /// `lsystem`: expands each symbol of the axiom `iterations` times deep.
    fn lsystem(&mut self, ls: &Lsystem, vals: &mut Vec<f64>, place: &str) -> Result<()> {
        let p = format!("{place}.iterations");
        let n = self.whole(&ls.iterations, vals, &p, MAX_ITERATIONS as f64)? as u32;
        for &s in &ls.axiom {
            self.expand(ls, s, 0, n, vals, place)?;
        }
        Ok(())
    }

    /// `set_heading`: turns the frame to heading `h`, and `up` if given
    /// (see [`Frame::set_heading`]).
    fn set_heading(
        &mut self,
        h: &[Val; 3],
        up: Option<&[Val; 3]>,
        vals: &mut Vec<f64>,
        place: &str,
    ) -> Result<()> {
        let h = self.eval3(h, vals, place)?;
        let up = match up {
            Some(u) => Some(self.eval3(u, vals, place)?),
            None => None,
        };
        self.frame
            .set_heading(h, up)
            .map_err(|e| Error::input(place, e.to_string()))
    }

    /// `draw_turtle`: a marker of the frame, up to [`MAX_MARKERS`].
    fn draw_turtle(&mut self) {
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

    /// `push`: saves the frame, up to [`MAX_SAVED`].
    fn push(&mut self, place: &str) -> Result<()> {
        // each saved frame is memory: a push without a pop is bounded
        if self.saved.len() >= MAX_SAVED {
            return Err(Error::input(
                place,
                format!("more than {MAX_SAVED} frames pushed and not popped; expected a `pop` for each `push`"),
            ));
        }
        self.saved.push(self.frame);
        Ok(())
    }

    /// `pop`: travels back to the last saved frame (a retraction first when
    /// the pen is down) and takes it, the pen as it was.
    fn pop(&mut self, place: &str) -> Result<()> {
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
        Ok(())
    }

    /// `extrude_rate` / `cross_section` / `speed`: the strings to come
    /// take value `x` (> 0); an extrude rate times the filament's area is
    /// a cross-section.
    fn set(&mut self, what: Setting, x: &Val, vals: &mut Vec<f64>, place: &str) -> Result<()> {
        let x = self.positive(x, vals, place)?;
        match what {
            Setting::ExtrudeRate => self.c = x * self.area,
            Setting::CrossSection => self.c = x,
            Setting::Speed => self.v = x,
        }
        Ok(())
    }

    /// `extrude`: `mm` of filament in place, at `feed` mm/s or [`DEFAULT_FEED`].
    fn extrude(
        &mut self,
        mm: &Val,
        feed: Option<&Val>,
        vals: &mut Vec<f64>,
        place: &str,
    ) -> Result<()> {
        let filament = self.within(mm, vals, place, 0.0, 1000.0)?;
        let speed = match feed {
            Some(f) => {
                let p = place.replace(".extrude", ".feed");
                self.positive(f, vals, &p)?
            }
            None => DEFAULT_FEED,
        };
        self.event(Event::Extrude { filament, speed }, place)
    }

    /// `bed_temp` / `nozzle_temp`: a temperature event within the physical bounds.
    fn temp(
        &mut self,
        bed: bool,
        celsius: &Val,
        wait: bool,
        vals: &mut Vec<f64>,
        place: &str,
    ) -> Result<()> {
        // the physical bounds of crate::machine::limits: a hotter one is
        // refused, not left to a check that --force skips
        let max = if bed {
            crate::machine::limits::BED_TEMP_MAX
        } else {
            crate::machine::limits::NOZZLE_TEMP_MAX
        };
        let t = self.within(celsius, vals, place, 0.0, max)?;
        let e = if bed {
            Event::BedTemp { celsius: t, wait }
        } else {
            Event::NozzleTemp { celsius: t, wait }
        };
        self.event(e, place)
    }

    /// `repeat`: runs `body` `count` times, the counter (0, 1, …) in scope
    /// when it has one.
    fn repeat(
        &mut self,
        count: &Val,
        counter: bool,
        body: &[Cmd],
        vals: &mut Vec<f64>,
        place: &str,
    ) -> Result<()> {
        let n = self.whole(count, vals, place, 1e12)?;
        for k in 0..n {
            if counter {
                vals.push(k as f64);
            }
            let r = self.block(body, vals);
            if counter {
                vals.pop();
            }
            r?;
        }
        Ok(())
    }

    /// `call`: runs procedure `proc` with `args` as its scope, up to
    /// [`MAX_CALL_DEPTH`] calls deep.
    fn call(&mut self, proc: usize, args: &[Val], vals: &mut Vec<f64>, place: &str) -> Result<()> {
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
        let r = self.block(&p.body, &mut inner);
        self.depth -= 1;
        r
    }

    /// `hair`: Laput et al.'s blob-and-pull (ExtruderTurtle §4.3): a blob
    /// in place, a thin pull of `length` along the heading, a retraction
    /// that snaps it; the pen is up afterwards.
    fn hair(
        &mut self,
        length: &Val,
        blob: Option<&Val>,
        rate: Option<&Val>,
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

    /// Runs symbol `s` at derivation depth `d` of `n` (see [`super::lsystem`]).
    fn expand(
        &mut self,
        ls: &Lsystem,
        s: u16,
        d: u32,
        n: u32,
        vals: &mut Vec<f64>,
        place: &str,
    ) -> Result<()> {
        self.step(place)?;
        if d < n {
            if let Some(rule) = &ls.rules[s as usize] {
                for &t in rule {
                    self.expand(ls, t, d + 1, n, vals, place)?;
                }
                return Ok(());
            }
        }
        self.block(&ls.commands[s as usize], vals)
    }
}
