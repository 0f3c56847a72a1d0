//! Resolving `turtle:`: the program compiled (every value an expression
//! compiled once, every name — procedure, loop counter, parameter —
//! resolved, every command tagged with its key path for errors), then run
//! by generation's interpreter ([`crate::generate::primitive::turtle::run`]).

use std::sync::Arc;

use glam::DVec3;
use indexmap::IndexMap;

use crate::base::error::{Error, Result};
use crate::base::expr::{var, Expr, ExprErrorKind, Params};
use crate::generate::primitive::turtle::interp::Program;
use crate::generate::primitive::turtle::lsystem::Lsystem;
use crate::generate::primitive::turtle::program::{
    Axis, Cmd, Curve, Op, Piece, Proc, Setting, Settings, Val, Values, STATE,
};
use crate::generate::primitive::turtle::{self, Env, Frame, Turtle};
use crate::recipe::eval::{at, join, key, Scope};
use crate::recipe::schema::{Num, Num3, RawLoop, RawPoint};
use crate::recipe::schema::{RawCommand, RawLsystem, RawProcedure, RawTurtle};

/// Compiles and runs a turtle; `s` is under `turtle`, the key paths of its
/// errors too.
pub(super) fn resolve(
    raw: &RawTurtle,
    s: &Scope,
    env: &Env,
    gcode: super::GcodeCheck,
) -> Result<Turtle> {
    // the program's places are relative to `turtle` (the interpreter's too)
    let mut t = compile(raw, &Scope::new(s.params), gcode)
        .and_then(|prog| turtle::run(&prog, env, gcode))
        .map_err(|e| e.under(s.here()))?;
    t.place_under(s.here());
    Ok(t)
}

/// The program of `raw` over the recipe's params: its start, seed,
/// procedures and commands.
fn compile(raw: &RawTurtle, s: &Scope, gcode: super::GcodeCheck) -> Result<Program> {
    let start = raw.start.clone().unwrap_or_default();
    let st = s.under(key!(raw.start));
    let pos = st.point_or(at!(start.position), DVec3::ZERO)?;
    let heading = st.point_or(at!(start.heading), DVec3::X)?;
    let up = st.point_or(at!(start.up), DVec3::Z)?;
    let frame = Frame::new(pos, heading, up).map_err(|e| st.error("", e.to_string()))?;
    let seed = s.checked_or(
        at!(raw.seed),
        0.0,
        |x| x.fract() == 0.0 && (0.0..=9007199254740992.0).contains(&x),
        "a whole number from 0 to 2^53",
    )? as u64;
    let compiler = Compiler::new(s.params, &raw.procedures, gcode);
    let procs = compiler.procedures(key!(raw.procedures))?;
    let main = compiler.block(&raw.program, key!(raw.program), &Arc::new(Vec::new()))?;
    Ok(Program {
        start: frame,
        seed,
        main,
        procs,
        path: false,
    })
}

/// Compiles and runs a `path`'s commands (written at `key` under `s`'s
/// place, `path`): the turtle's language, starting at the origin facing
/// +x, where a path starts where its first travel goes.
pub(super) fn resolve_path(
    cmds: &[RawCommand],
    key: &str,
    s: &Scope,
    env: &Env,
    gcode: super::GcodeCheck,
) -> Result<Turtle> {
    let compiler = Compiler::new(s.params, &IndexMap::new(), gcode);
    let mut t = compiler
        .block(cmds, key, &Arc::new(Vec::new()))
        .and_then(|main| {
            let prog = Program {
                start: Frame::new(DVec3::ZERO, DVec3::X, DVec3::Z)
                    .expect("+x and +z make a frame"),
                seed: 0,
                main,
                procs: Vec::new(),
                path: true,
            };
            turtle::run(&prog, env, gcode)
        })
        .map_err(|e| {
            // a path that draws nothing: name its commands, as v1 did
            let e = if e.place.as_deref() == Some("program") {
                Error::input(
                    key,
                    "expected at least one `draw` (or a movement with the pen down): a path that extrudes nothing prints nothing",
                )
            } else {
                e
            };
            e.under(s.here())
        })?;
    t.place_under(s.here());
    Ok(t)
}

/// Compiles the commands of one turtle.
pub(super) struct Compiler<'a> {
    params: &'a Params,
    procs: IndexMap<String, RawProcedure>,
    /// The check of the recipe's own printer commands.
    gcode: super::GcodeCheck<'a>,
}

/// Most names one scope of a turtle holds (loop counters, procedure
/// parameters, `let` values): each value compiled sees them all, so a chain
/// of 12,000 `let` names made 72 million names' worth of scopes (1.5 GB).
pub(crate) const MAX_NAMES: usize = 256;

/// Most control points of one `bezier` (each point of the curve sums a
/// term per control point; past about a thousand the binomial weights
/// leave f64's range anyway).
pub(crate) const MAX_BEZIER_POINTS: usize = 1000;

fn check_name(name: &str, params: &Params, scope: &[String], place: &str) -> Result<()> {
    if scope.len() >= MAX_NAMES {
        return Err(Error::input(
            place,
            format!("`{name}` is one name too many: a turtle's scope holds at most {MAX_NAMES} loop counters, parameters and `let` values"),
        ));
    }
    let ident = {
        let mut cs = name.chars();
        matches!(cs.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
            && cs.all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    let why = if !ident {
        "a name must be letters, digits and `_`, not starting with a digit"
    } else if matches!(name, "x" | "y" | "z" | "pi" | "e" | "rand") {
        "turtle expressions already use it (x y z are the turtle's position; pi, e, rand())"
    } else if params.has(name) {
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
    pub(super) fn new(
        params: &'a Params,
        procs: &IndexMap<String, RawProcedure>,
        gcode: super::GcodeCheck<'a>,
    ) -> Compiler<'a> {
        Compiler {
            params,
            procs: procs.clone(),
            gcode,
        }
    }

    /// Compiles every procedure (in the order written; calls may refer
    /// forward), written under `key`.
    pub(super) fn procedures(&self, key: &str) -> Result<Vec<Proc>> {
        let mut out = Vec::with_capacity(self.procs.len());
        for (name, p) in &self.procs {
            let place = join(key, name);
            let params = join(&place, key!(p.params));
            let mut scope = Vec::new();
            for (k, param) in p.params.iter().enumerate() {
                check_name(param, self.params, &scope, &format!("{params}[{k}]"))?;
                scope.push(param.clone());
            }
            out.push(Proc {
                name: name.clone(),
                // `body` is read as `do`
                body: self.block(&p.body, &join(&place, "do"), &Arc::new(scope))?,
            });
        }
        Ok(out)
    }

    /// Compiles `src` in `scope` (turtle position x, y, z; counters; `rand()`).
    pub(super) fn val(&self, n: &Num, scope: &Arc<Vec<String>>, place: &str) -> Result<Val> {
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

    fn opt_val(
        &self,
        n: &Option<Num>,
        scope: &Arc<Vec<String>>,
        place: &str,
    ) -> Result<Option<Val>> {
        match n {
            Some(n) => Ok(Some(self.val(n, scope, place)?)),
            None => Ok(None),
        }
    }

    /// Compiles a list of commands written at key path `place`.
    pub(super) fn block(
        &self,
        cmds: &[RawCommand],
        place: &str,
        scope: &Arc<Vec<String>>,
    ) -> Result<Vec<Cmd>> {
        let mut out = Vec::with_capacity(cmds.len());
        // a `let` adds its names to the scope of the commands after it
        let mut scope = scope.clone();
        for (k, c) in cmds.iter().enumerate() {
            let item = format!("{place}[{k}]");
            if let RawCommand::Let(lets) = c {
                let (cmd, inner) = self.lets(lets, &item, &scope)?;
                out.push(cmd);
                scope = inner;
                continue;
            }
            out.push(self.command(c, &item, &scope)?);
        }
        Ok(out)
    }

    /// `let: {name: value, …}`, list item `item`: each value over the names
    /// before it, and the scope with all of them.
    fn lets(
        &self,
        lets: &IndexMap<String, Num>,
        item: &str,
        scope: &Arc<Vec<String>>,
    ) -> Result<(Cmd, Arc<Vec<String>>)> {
        let place = format!("{item}.let");
        let mut s = (**scope).clone();
        let mut vals = Vec::with_capacity(lets.len());
        for (name, n) in lets {
            let at = join(&place, name);
            if s.len() >= MAX_NAMES {
                check_name(name, self.params, &s, &at)?;
            }
            let v = self.val(n, &Arc::new(s.clone()), &at)?;
            check_name(name, self.params, &s, &at)?;
            s.push(name.clone());
            vals.push(v);
        }
        Ok((
            Cmd {
                place,
                op: Op::Let(vals),
            },
            Arc::new(s),
        ))
    }

    /// One command, list item `item`: its place is `item.KEY`, KEY its command key.
    fn command(&self, c: &RawCommand, item: &str, scope: &Arc<Vec<String>>) -> Result<Cmd> {
        let at = |key: &str| format!("{item}.{key}");
        let (place, op) = match c {
            RawCommand::Bare(w) => (at(w), bare(w)),
            RawCommand::Scalar(w, n) => (at(w), scalar(w, self.val(n, scope, &at(w))?)),
            RawCommand::Goto(p) => (at("goto"), Op::Goto(self.point(p, scope, &at("goto"))?)),
            RawCommand::Move(p) => (
                at("move"),
                Op::To(self.point(p, scope, &at("move"))?, false),
            ),
            RawCommand::Draw(p) => (at("draw"), Op::To(self.point(p, scope, &at("draw"))?, true)),
            RawCommand::For { .. }
            | RawCommand::Let(_)
            | RawCommand::Arc(_)
            | RawCommand::Bezier(_)
            | RawCommand::Line(_)
            | RawCommand::Rectangle(_)
            | RawCommand::ExtrudeVolume { .. }
            | RawCommand::Gcode(_)
            | RawCommand::Set(_) => return self.more(c, item, scope),
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
                    self.opt_val(feed, scope, &at("feed"))?,
                ),
            ),
            RawCommand::Temp { bed, celsius, wait } => {
                let key = if *bed { "bed_temp" } else { "nozzle_temp" };
                let celsius = self.val(celsius, scope, &at(key))?;
                let (bed, wait) = (*bed, *wait);
                (at(key), Op::Temp { bed, celsius, wait })
            }
            RawCommand::Repeat { count, var, body } => {
                (at("repeat"), self.repeat(count, var, body, item, scope)?)
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
            RawCommand::Call { name, args } => (at("call"), self.call(name, args, item, scope)?),
            RawCommand::Lsystem(l) => {
                let ls = self.lsystem(l, scope, &at("lsystem"))?;
                (at("lsystem"), Op::Lsystem(Box::new(ls)))
            }
            RawCommand::Hair { length, blob, rate } => (
                at("hair"),
                Op::Hair {
                    length: self.val(length, scope, &at("hair"))?,
                    blob: self.opt_val(blob, scope, &at("blob"))?,
                    rate: self.opt_val(rate, scope, &at("rate"))?,
                },
            ),
        };
        Ok(Cmd { place, op })
    }

    /// A point: `[x, y, z]`, some of them with the others the head's
    /// (compiled as `x`, `y`, `z`), or a polar point (its coordinates'
    /// expressions, see [`RawPoint::coords`]).
    fn point(&self, p: &RawPoint, scope: &Arc<Vec<String>>, place: &str) -> Result<[Val; 3]> {
        let names = ["x", "y", "z"];
        let c = p.coords();
        let mut out = Vec::with_capacity(3);
        for (k, n) in c.into_iter().enumerate() {
            let (n, at) = match (n, p) {
                (Some(n), RawPoint::Full(_)) => (n, format!("{place}[{k}]")),
                (Some(n), RawPoint::Partial { .. }) => (n, join(place, names[k])),
                (Some(n), RawPoint::Polar { .. }) => (n, join(place, "polar")),
                (None, _) => (Num::Expr(names[k].into()), place.to_string()),
            };
            out.push(self.val(&n, scope, &at)?);
        }
        Ok(out.try_into().expect("three coordinates"))
    }

    /// The commands beyond v1's turtle: `for`, the curves,
    /// `extrude_volume`, `gcode` (`let` is the block's), list item `item`.
    fn more(&self, c: &RawCommand, item: &str, scope: &Arc<Vec<String>>) -> Result<Cmd> {
        let at = |key: &str| format!("{item}.{key}");
        let (place, op) = match c {
            RawCommand::For { loops, body } => {
                (at("for"), self.for_loops(loops, body, item, scope)?)
            }
            RawCommand::Arc(a) => {
                let p = at("arc");
                let v = |n: &Num, k: &str| self.val(n, scope, &join(&p, k));
                let curve = Curve::Arc {
                    center: self.point(&a.center, scope, &join(&p, "center"))?,
                    radius: v(&a.radius, "radius")?,
                    start: v(&a.start, "start")?,
                    sweep: v(&a.sweep, "sweep")?,
                    segments: v(&a.segments, "segments")?,
                    end_radius: a
                        .end_radius
                        .as_ref()
                        .map(|n| v(n, "end_radius"))
                        .transpose()?,
                    rise: a.rise.as_ref().map(|n| v(n, "rise")).transpose()?,
                };
                (p, Op::Curve(Box::new(curve)))
            }
            RawCommand::Bezier(b) => {
                let p = at("bezier");
                if b.points.len() < 2 {
                    return Err(Error::input(
                        join(&p, "points"),
                        format!("{} control point(s); expected at least two", b.points.len()),
                    ));
                }
                if b.points.len() > MAX_BEZIER_POINTS {
                    return Err(Error::input(
                        join(&p, "points"),
                        format!(
                            "{} control points; expected at most {MAX_BEZIER_POINTS} (a curve of more is better made of several)",
                            b.points.len()
                        ),
                    ));
                }
                let mut points = Vec::with_capacity(b.points.len());
                for (k, q) in b.points.iter().enumerate() {
                    points.push(self.point(q, scope, &format!("{p}.points[{k}]"))?);
                }
                let segments = self.val(&b.segments, scope, &join(&p, "segments"))?;
                (p, Op::Curve(Box::new(Curve::Bezier { points, segments })))
            }
            RawCommand::Line(l) => {
                let p = at("line");
                let from = match &l.from {
                    Some(f) => Some(self.point(f, scope, &join(&p, "from"))?),
                    None => None,
                };
                let curve = Curve::Line {
                    from,
                    to: self.point(&l.to, scope, &join(&p, "to"))?,
                    segments: self.val(&l.segments, scope, &join(&p, "segments"))?,
                };
                (p, Op::Curve(Box::new(curve)))
            }
            RawCommand::Rectangle(r) => {
                let p = at("rectangle");
                let curve = Curve::Rectangle {
                    corner: self.point(&r.corner, scope, &join(&p, "corner"))?,
                    size: [
                        self.val(&r.size[0], scope, &format!("{p}.size[0]"))?,
                        self.val(&r.size[1], scope, &format!("{p}.size[1]"))?,
                    ],
                    clockwise: r.clockwise.unwrap_or(false),
                };
                (p, Op::Curve(Box::new(curve)))
            }
            RawCommand::ExtrudeVolume { volume, feed } => (
                at("extrude_volume"),
                Op::ExtrudeVolume(
                    self.val(volume, scope, &at("extrude_volume"))?,
                    self.opt_val(feed, scope, &at("feed"))?,
                ),
            ),
            RawCommand::Gcode(text) => {
                let p = at("gcode");
                (p.clone(), self.gcode_line(text, scope, &p)?)
            }
            RawCommand::Set(raw) => {
                let p = at("set");
                (
                    p.clone(),
                    Op::Printer(Box::new(self.settings(raw, scope, &p)?)),
                )
            }
            _ => unreachable!("`more` takes the commands it names"),
        };
        Ok(Cmd { place, op })
    }

    /// `gcode: text` at `place`: a literal line checked now; one with
    /// `{expr}`s compiled into pieces, the line made and checked where it
    /// runs (its values seen in the command's scope, as any other's).
    fn gcode_line(&self, text: &str, scope: &Arc<Vec<String>>, place: &str) -> Result<Op> {
        use crate::base::format::{pieces, Piece as Cut};
        let cut = pieces(text).map_err(|m| Error::input(place, m))?;
        if cut.iter().all(|c| matches!(c, Cut::Text(_))) {
            (self.gcode)(text).map_err(|m| Error::input(place, m))?;
            return Ok(Op::Gcode(text.trim().into()));
        }
        let mut out = Vec::with_capacity(cut.len());
        for c in cut {
            out.push(match c {
                Cut::Text(t) => Piece::Text(t.into()),
                Cut::Expr(src) => Piece::Value(self.val(&Num::Expr(src.into()), scope, place)?),
            });
        }
        Ok(Op::GcodeWith(out))
    }

    /// `set: {…}` at `place`: the settings as a `set` step reads them
    /// (no height bands; `band`, a line's index, allowed), each value in
    /// the command's scope.
    fn settings(
        &self,
        raw: &crate::recipe::schema::RawSet,
        scope: &Arc<Vec<String>>,
        place: &str,
    ) -> Result<Settings> {
        for (key, given) in [("every", raw.every.is_some()), ("from", raw.from.is_some())] {
            if given {
                return Err(Error::input(
                    join(place, key),
                    format!("a `set` command sets its values here, where it runs, so it has no height bands (`{key}` is a `set` step's); expected the settings, each an expression of x, y, z and the names in scope, and `band` for a line test's line"),
                ));
            }
        }
        if let Some((key, _)) = raw.paces().first() {
            return Err(Error::input(
                join(place, key),
                format!("`{key}` in a `set` command: the turtle's own `speed` command sets the speed of the strings that follow (`{{speed: v}}`, or v = flow/cross-section); expected the firmware's settings only"),
            ));
        }
        let band = match &raw.band {
            Some(n) => Some(self.val(n, scope, &join(place, "band"))?),
            None => None,
        };
        let named = super::step::named(raw, place, |key, n| self.val(n, scope, &join(place, key)))?;
        Ok(Settings { named, band })
    }

    /// `for: {name: values, …}` with `do: body`, list item `item`: one
    /// loop per name, the first outermost.
    fn for_loops(
        &self,
        loops: &IndexMap<String, RawLoop>,
        body: &[RawCommand],
        item: &str,
        scope: &Arc<Vec<String>>,
    ) -> Result<Op> {
        let place = format!("{item}.for");
        if loops.is_empty() {
            return Err(Error::input(
                place,
                "expected a name and its values, e.g. {k: \"0..4\"}",
            ));
        }
        let mut values = Vec::with_capacity(loops.len());
        let mut inner = (**scope).clone();
        for (name, l) in loops {
            let at = join(&place, name);
            check_name(name, self.params, &inner, &at)?;
            let sc = Arc::new(inner.clone());
            values.push(match l {
                RawLoop::List(v) => {
                    let mut list = Vec::with_capacity(v.len());
                    for (k, n) in v.iter().enumerate() {
                        list.push(self.val(n, &sc, &format!("{at}[{k}]"))?);
                    }
                    Values::List(list)
                }
                RawLoop::Range(r) => self.range(r, &sc, &at)?,
            });
            inner.push(name.clone());
        }
        let mut op_body = self.block(body, &format!("{item}.do"), &Arc::new(inner))?;
        // the innermost loop runs the body; each outer one the loop inside it
        let mut values = values.into_iter().rev();
        let mut op = Op::For {
            values: Box::new(values.next().expect("one loop at least")),
            body: op_body,
        };
        for v in values {
            op_body = vec![Cmd {
                place: place.clone(),
                op,
            }];
            op = Op::For {
                values: Box::new(v),
                body: op_body,
            };
        }
        Ok(op)
    }

    /// `"a..b"` or `"a..b:step"` of a `for`, at `place`.
    fn range(&self, r: &str, scope: &Arc<Vec<String>>, place: &str) -> Result<Values> {
        let not_range = || {
            Error::input(place, format!("`{r}` is not a range; expected \"a..b\" or \"a..b:step\" (b included), or a list [v1, v2, …]"))
        };
        let (a, rest) = r.split_once("..").ok_or_else(not_range)?;
        let (b, step) = match rest.split_once(':') {
            Some((b, st)) => (b, Some(st)),
            None => (rest, None),
        };
        if a.trim().is_empty() || b.trim().is_empty() {
            return Err(not_range());
        }
        let val = |t: &str| self.val(&Num::Expr(t.trim().to_string()), scope, place);
        Ok(Values::Range(val(a)?, val(b)?, step.map(val).transpose()?))
    }

    /// `repeat: count` with `as: var` and `do: body`, list item `item`.
    fn repeat(
        &self,
        count: &Num,
        var: &Option<String>,
        body: &[RawCommand],
        item: &str,
        scope: &Arc<Vec<String>>,
    ) -> Result<Op> {
        let at = |key: &str| format!("{item}.{key}");
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
        Ok(Op::Repeat {
            count,
            counter: var.is_some(),
            body: self.block(body, &at("do"), &inner)?,
        })
    }

    /// `call: name` with `args`, list item `item`.
    fn call(&self, name: &str, args: &[Num], item: &str, scope: &Arc<Vec<String>>) -> Result<Op> {
        let at = |key: &str| format!("{item}.{key}");
        let Some((proc, _, p)) = self.procs.get_full(name) else {
            let known: Vec<&str> = self.procs.keys().map(String::as_str).collect();
            return Err(Error::input(
                at("call"),
                if known.is_empty() {
                    format!(
                        "undefined procedure `{name}`; this turtle defines none under `procedures:`"
                    )
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
        Ok(Op::Call { proc, args: vals })
    }

    /// Compiles the L-system `raw` written at `place`, its commands seeing
    /// `scope`: symbols numbered in order of first appearance.
    pub(super) fn lsystem(
        &self,
        raw: &RawLsystem,
        scope: &Arc<Vec<String>>,
        place: &str,
    ) -> Result<Lsystem> {
        let mut symbols: Vec<char> = Vec::new();
        let number = |ch: char, symbols: &mut Vec<char>| -> Result<u16> {
            if let Some(k) = symbols.iter().position(|&s| s == ch) {
                return Ok(k as u16);
            }
            if symbols.len() >= u16::MAX as usize {
                return Err(Error::input(place, "too many different symbols"));
            }
            symbols.push(ch);
            Ok(symbols.len() as u16 - 1)
        };
        if raw.axiom.is_empty() {
            return Err(Error::input(
                join(place, key!(raw.axiom)),
                "expected a non-empty word",
            ));
        }
        let mut axiom = Vec::new();
        for ch in raw.axiom.chars() {
            axiom.push(number(ch, &mut symbols)?);
        }
        let mut rules_at = Vec::new();
        for (key, rhs) in &raw.rules {
            let p = join(&join(place, key!(raw.rules)), key);
            let s = number(one_symbol(key, &p)?, &mut symbols)?;
            let mut word = Vec::new();
            for ch in rhs.chars() {
                word.push(number(ch, &mut symbols)?);
            }
            rules_at.push((s, word));
        }
        let mut commands_at = Vec::new();
        for (key, cmds) in &raw.commands {
            let p = join(&join(place, key!(raw.commands)), key);
            let s = number(one_symbol(key, &p)?, &mut symbols)?;
            commands_at.push((s, self.block(cmds, &p, scope)?));
        }
        let n = symbols.len();
        let mut rules = vec![None; n];
        for (s, w) in rules_at {
            rules[s as usize] = Some(w);
        }
        let mut commands = vec![Vec::new(); n];
        for (s, cmds) in commands_at {
            commands[s as usize] = cmds;
        }
        Ok(Lsystem {
            symbols,
            axiom,
            rules,
            commands,
            iterations: self.val(&raw.iterations, scope, &join(place, key!(raw.iterations)))?,
        })
    }
}

fn one_symbol(key: &str, place: &str) -> Result<char> {
    let mut cs = key.chars();
    match (cs.next(), cs.next()) {
        (Some(c), None) => Ok(c),
        _ => Err(Error::input(
            place,
            format!("`{key}` is not one symbol; expected a single character such as F or +"),
        )),
    }
}

/// What a bare word does.
fn bare(w: &str) -> Op {
    match w {
        "pen_up" => Op::PenUp,
        "pen_down" => Op::PenDown,
        "pause" => Op::Pause,
        "push" => Op::Push,
        "draw_turtle" => Op::DrawTurtle,
        _ => Op::Pop,
    }
}

/// What a command of one number does with its value `v`.
fn scalar(w: &str, v: Val) -> Op {
    match w {
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
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::toolpath::{Event, Toolpath};
    use crate::generate::primitive::Primitive;

    fn env() -> Env {
        Env {
            cross_section: 0.2,
            speed: 30.0,
            filament_area: 2.0,
            max_strings: 1_000_000,
        }
    }

    fn run_with(yaml: &str, env: &Env) -> Result<Toolpath> {
        let raw: RawTurtle = crate::recipe::parse_yaml(yaml, "t.yaml")?;
        let mut params = Params::new();
        params.insert("side".into(), 13.7);
        // a recipe's own commands checked as for generic-220 and PLA
        let printer = crate::recipe::profile::built_in("generic-220").unwrap();
        let material = crate::machine::Material::built_in("pla").unwrap();
        let check =
            |t: &str| crate::analyse::check::gcode::command(t, &printer, &material).map(|_| ());
        resolve(&raw, &Scope::new(&params).under("turtle"), env, &check).map(|t| t.path)
    }

    fn run(yaml: &str) -> Toolpath {
        run_with(yaml, &env()).unwrap_or_else(|e| panic!("{e}"))
    }

    fn err(yaml: &str) -> Error {
        run_with(yaml, &env()).unwrap_err()
    }

    #[test]
    fn expressions_read_the_turtles_state() {
        // each `forward` goes as far as the state it reads: yaw 30, pitch
        // -20, roll 45, pen 0 then 1 (ExtruderTurtle's getYaw() and friends)
        let t = run("program:\n  - {left: 30}\n  - {forward: \"yaw()\"}\n  - {pitch: -20}\n  - {forward: \"-pitch()\"}\n  - {roll: 45}\n  - {forward: \"roll ( )\"}\n  - pen_up\n  - {forward: \"1 + pen()\"}\n  - pen_down\n  - {forward: \"pen()*2 + rand()*0\"}\n");
        let lens: Vec<f64> = t.points.windows(2).map(|w| w[0].distance(w[1])).collect();
        let want = [30.0, 20.0, 45.0, 1.0, 2.0];
        assert_eq!(lens.len(), want.len(), "{lens:?}");
        for (got, w) in lens.iter().zip(want) {
            assert!((got - w).abs() < 1e-9, "{lens:?}");
        }
        // a counter or parameter keeps its own name beside them
        let t = run("program:\n  - repeat: 2\n    as: yaw\n    do: [{forward: \"yaw + 1\"}]\n");
        assert!((t.points[2].x - 3.0).abs() < 1e-12, "{:?}", t.points);
        // an unknown name lists what a turtle has
        let e = err("program:\n  - {forward: \"heading\"}\n");
        assert!(
            e.message.contains("yaw(), pitch(), roll(), pen(), rand()"),
            "{e}"
        );
    }

    #[test]
    fn a_hair_is_a_blob_a_declared_pull_and_a_retraction() {
        let t = run("program:\n  - {pitch: 90}\n  - {hair: 6, blob: 0.2, rate: 0.5}\n  - {forward: 2}\n  - pen_down\n  - {forward: 1}\n");
        // the pull, then (pen up) a travel, then a drawn string
        assert_eq!(t.len(), 3);
        assert!(t.strings[0].hair && !t.strings[0].travel);
        assert_eq!(t.points[1], DVec3::new(0.0, 0.0, 6.0));
        assert_eq!(t.strings[0].c, 0.5 * 2.0);
        assert!(t.strings[1].travel && !t.strings[1].hair);
        assert!(!t.strings[2].hair && !t.strings[2].travel);
        assert_eq!(
            t.events,
            vec![
                (
                    0,
                    Event::Extrude {
                        filament: 0.2,
                        speed: 1.0
                    }
                ),
                (1, Event::Retract)
            ]
        );
        let e = err("program:\n  - {hair: -1}\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].hair"));
        let e = err("program:\n  - {hair: 1, rate: 0}\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].rate"));
        let e = err("program:\n  - {hair: 1, feed: 2}\n");
        assert!(e.message.contains("its other keys are blob, rate"), "{e}");
    }

    #[test]
    fn closed_polygons_return_to_their_start() {
        for (sides, turn) in [(3, "right"), (6, "left"), (7, "left"), (17, "right")] {
            let t = run(&format!(
                "program:\n  - repeat: {sides}\n    do: [{{forward: side}}, {{{turn}: 360/{sides}}}]\n"
            ));
            assert_eq!(t.len(), sides);
            let d = t.head().distance(t.points[0]);
            assert!(d < 1e-9, "{sides}-gon misses its start by {d} mm");
        }
        // a star {7/3} and a square in a tilted plane
        let t = run("program:\n  - repeat: 7\n    do: [{forward: 50}, {right: 3*360/7}]\n");
        assert!(t.head().distance(t.points[0]) < 1e-9);
        let t = run("start: {position: [1, 2, 3]}\nprogram:\n  - {roll: 37}\n  - {pitch: 21}\n  - repeat: 4\n    do: [{forward: 10}, {left: 90}]\n");
        assert!(t.head().distance(t.points[0]) < 1e-9);
        assert!((t.points[2].z - t.points[0].z).abs() > 1.0, "tilted");
    }

    #[test]
    fn turns_are_rotations_of_the_own_frame() {
        // a sequence of turns and its inverse: forward goes along the start heading
        let t = run("program:\n  - {yaw: 30}\n  - {pitch: -55}\n  - {roll: 100}\n  - {left: 12}\n  - {left: -12}\n  - {roll: -100}\n  - {pitch: 55}\n  - {right: 30}\n  - {forward: 10}\n");
        assert!((t.head() - DVec3::new(10.0, 0.0, 0.0)).length() < 1e-12);
        // yaw turns about the turtle's own up, which a roll has tilted
        let t = run("program:\n  - {roll: 90}\n  - {yaw: 90}\n  - {forward: 1}\n");
        assert!((t.head() - DVec3::Z).length() < 1e-15, "{}", t.head());
    }

    #[test]
    fn goto_and_forward_agree() {
        let a = run("program:\n  - {yaw: 30}\n  - {pitch: 20}\n  - {forward: 10}\n  - {lift: 2}\n");
        let (s30, c30, s20, c20) = (
            0.5,
            0.75f64.sqrt(),
            libm::sin(20f64.to_radians()),
            libm::cos(20f64.to_radians()),
        );
        let fwd = DVec3::new(10.0 * c20 * c30, 10.0 * c20 * s30, 10.0 * s20);
        let up = DVec3::new(-2.0 * s20 * c30, -2.0 * s20 * s30, 2.0 * c20);
        assert!((a.points[1] - fwd).length() < 1e-12);
        assert!((a.points[2] - fwd - up).length() < 1e-12);
        let b = run(&format!(
            "program:\n  - goto: [{}, {}, {}]\n  - {{backward: 5}}\n",
            fwd.x, fwd.y, fwd.z
        ));
        // goto keeps the heading: backward goes back along +x
        assert_eq!(b.points[1], fwd);
        assert!((b.points[2] - fwd + DVec3::new(5.0, 0.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn a_polar_point_is_fullcontrol_s_polar_to_point() {
        use std::f64::consts::{PI, TAU};
        // FullControl's polar_to_point(centre, r, a): (cx + r cos a, cy + r sin a, cz)
        let t = run("program:\n  - goto: {polar: [1, 2, 0.3], radius: 10, angle: \"pi/6\"}\n  - for: {k: \"0..3\"}\n    do:\n      - move: {polar: [\"k\", 0, z], radius: \"side\", angle: \"k*tau/4\"}\n  - arc: {center: {polar: [0, 0, 0], radius: 5, angle: pi}, radius: 1, sweep: pi, segments: 2}\n");
        let want = DVec3::new(
            1.0 + 10.0 * libm::cos(PI / 6.0),
            2.0 + 10.0 * libm::sin(PI / 6.0),
            0.3,
        );
        assert!((t.points[1] - want).length() < 1e-12, "{:?}", t.points[1]);
        for k in 0..4 {
            let a = k as f64 * TAU / 4.0;
            let p = DVec3::new(k as f64 + 13.7 * libm::cos(a), 13.7 * libm::sin(a), 0.3);
            assert!(
                (t.points[2 + k] - p).length() < 1e-12,
                "{k}: {:?}",
                t.points[2 + k]
            );
        }
        // the arc's centre (-5, 0), its start (the default) +x: from (-4, 0) to (-6, 0)
        assert!((t.points[6] - DVec3::new(-4.0, 0.0, 0.0)).length() < 1e-12);
        assert!((t.head() - DVec3::new(-6.0, 0.0, 0.0)).length() < 1e-12);
        // all three or none, and not with x, y, z
        for bad in [
            "{polar: [0, 0, 0], radius: 1}",
            "{polar: [0, 0, 0], radius: 1, angle: 0, z: 2}",
            "{radius: 1, angle: 0}",
        ] {
            let e = run_with(&format!("program:\n  - goto: {bad}\n"), &env()).unwrap_err();
            assert!(e.message.contains("a polar point is"), "{bad}: {e}");
        }
        let e = err("program:\n  - goto: {polar: [0, 0, 0], radius: q, angle: 0}\n");
        assert_eq!(
            e.place.as_deref(),
            Some("turtle.program[0].goto.polar"),
            "{e}"
        );
    }

    #[test]
    fn for_let_curves_volume_and_gcode() {
        // a for over a range (b included) with a let: three draws along x
        let t =
            run("program:\n  - {for: {k: \"1..3\"}, do: [{let: {w: \"2*k\"}}, {draw: {x: w}}]}\n");
        let xs: Vec<f64> = t.points[1..].iter().map(|p| p.x).collect();
        assert_eq!(xs, vec![2.0, 4.0, 6.0]);
        // an arc: a quarter circle of 4 segments, each point on the circle
        let t = run("program:\n  - {arc: {center: [0, 0, 0], radius: 5, start: 0, sweep: \"tau/4\", segments: 4}}\n");
        assert_eq!(t.len(), 5);
        for p in &t.points[1..] {
            assert!((p.truncate().length() - 5.0).abs() < 1e-12, "{p}");
        }
        assert!((t.points[5] - DVec3::new(0.0, 5.0, 0.0)).length() < 1e-12);
        // a Bezier's middle point and a segmented line's equal pieces
        let t = run("program:\n  - {bezier: {points: [[0,0,0], [1,2,0], [2,0,0]], segments: 2}}\n  - {line: {to: [8, 1, 0], segments: 3}}\n");
        // (the first control point is where the turtle stands: no string to it)
        assert!((t.points[1] - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-12);
        assert!((t.points[4] - DVec3::new(6.0, 2.0 / 3.0, 0.0)).length() < 1e-12);
        // a volume in place: filament = volume / filament area (2 mm² here)
        let t = run(
            "program:\n  - {forward: 1}\n  - {extrude_volume: 3, feed: 2}\n  - {gcode: M600}\n",
        );
        assert_eq!(
            t.events[0],
            (
                1,
                Event::Extrude {
                    filament: 1.5,
                    speed: 2.0
                }
            )
        );
        assert_eq!(t.events[1], (1, Event::Gcode("M600".into())));
        // a move it could not account for is refused, naming the place
        let e = err("program:\n  - {gcode: \"G1 X10\"}\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].gcode"), "{e}");
        let e = err("program:\n  - {gcode: \"M600\\nG28\"}\n");
        assert!(e.message.contains("one line"), "{e}");
        let e = err("program:\n  - {bezier: {points: [[0,0,0]], segments: 2}}\n");
        assert!(e.message.contains("at least two"), "{e}");
        // a curve of 1,001 control points, and one whose points times
        // segments pass the cap: refused, naming the key, before any is made
        let many = |n: usize| vec!["[0,0,0]"; n].join(",");
        let e = err(&format!(
            "program:\n  - {{bezier: {{points: [{}], segments: 2}}}}\n",
            many(1001)
        ));
        assert_eq!(
            e.place.as_deref(),
            Some("turtle.program[0].bezier.points"),
            "{e}"
        );
        assert!(e.message.contains("at most 1000"), "{e}");
        let t0 = std::time::Instant::now();
        let e = err(&format!(
            "program:\n  - {{bezier: {{points: [{}], segments: 10000000}}}}\n",
            many(1000)
        ));
        assert_eq!(
            e.place.as_deref(),
            Some("turtle.program[0].bezier.segments"),
            "{e}"
        );
        assert!(e.message.contains("expected at most"), "{e}");
        assert!(
            t0.elapsed() < std::time::Duration::from_secs(2),
            "{:?}",
            t0.elapsed()
        );
    }

    #[test]
    fn settings_and_events() {
        let t = run("program:\n  - {forward: 1}\n  - pen_up\n  - {forward: 2}\n  - pen_down\n  - {extrude_rate: 0.05}\n  - {speed: 12}\n  - {forward: 3}\n  - {cross_section: 0.3}\n  - {extrude: 2, feed: 3}\n  - {dwell: 250}\n  - pause\n  - {nozzle_temp: 200, wait: true}\n  - {fan: 0.5}\n  - {forward: 1}\n");
        assert_eq!(t.len(), 4);
        assert!(!t.strings[0].travel && t.strings[1].travel && !t.strings[2].travel);
        assert_eq!((t.strings[0].c, t.strings[0].v), (0.2, 30.0));
        assert_eq!((t.strings[2].c, t.strings[2].v), (0.05 * 2.0, 12.0));
        assert_eq!(t.strings[3].c, 0.3);
        assert_eq!(t.events[0], (1, Event::Retract));
        assert_eq!(
            t.events[1],
            (
                3,
                Event::Extrude {
                    filament: 2.0,
                    speed: 3.0
                }
            )
        );
        assert_eq!(t.events.len(), 6);
        assert_eq!(
            t.events[4],
            (
                3,
                Event::NozzleTemp {
                    celsius: 200.0,
                    wait: true
                }
            )
        );
    }

    #[test]
    fn counters_procedures_if_and_push_pop() {
        let t = run("procedures:\n  leg:\n    params: [n, len]\n    do:\n      - if: \"n\"\n        do: [{forward: len}, {call: leg, args: [\"n - 1\", len]}]\n        else: [{lift: 1}]\nprogram:\n  - repeat: 3\n    as: k\n    do:\n      - push\n      - call: leg\n        args: [\"k + 1\", \"2*k + 1\"]\n      - pop\n");
        // k = 0: 1 × 1 mm + lift; k = 1: 2 × 3 mm + lift; k = 2: 3 × 5 mm + lift; and pops
        let travel = t.strings.iter().filter(|s| s.travel).count();
        assert_eq!(t.len() - travel, 6 + 3);
        assert_eq!(travel, 3);
        assert_eq!(t.head(), DVec3::ZERO);
        assert!(t.points.contains(&DVec3::new(15.0, 0.0, 1.0)));
    }

    #[test]
    fn lsystems_expand_lazily_as_their_words() {
        let yaml = |k: u32| {
            format!("program:\n  - lsystem:\n      axiom: F--F--F\n      rules: {{F: F+F--F+F}}\n      iterations: {k}\n      commands: {{F: [{{forward: 1}}], \"+\": [{{left: 60}}], \"-\": [{{right: 60}}]}}\n")
        };
        for k in 0..5 {
            let t = run(&yaml(k));
            assert_eq!(t.len(), 3 * 4usize.pow(k));
            assert!(t.head().distance(t.points[0]) < 1e-9);
        }
        let raw: RawTurtle = crate::recipe::parse_yaml(&yaml(2), "t.yaml").unwrap();
        let params = Params::new();
        let any = |_: &str| Ok(());
        let c = Compiler::new(&params, &raw.procedures, &any);
        let prog = c
            .block(&raw.program, "program", &Arc::new(Vec::new()))
            .unwrap();
        let Op::Lsystem(ls) = &prog[0].op else {
            panic!()
        };
        assert_eq!(ls.word(1, 100).unwrap(), "F+F--F+F--F+F--F+F--F+F--F+F");
        assert!(ls.word(30, 1000).is_none());
    }

    #[test]
    fn deep_calls_and_derivations_run_on_a_small_stack() {
        // 199 nested calls, each in an `if` and a `repeat`, then an L-system
        // 18 deep: the interpreter's tasks are on the heap, not the stack
        let yaml = "procedures:\n  down:\n    params: [n]\n    do:\n      - if: \"n\"\n        do:\n          - repeat: 1\n            do: [{forward: 1}, {call: down, args: [\"n - 1\"]}]\nprogram:\n  - {call: down, args: [199]}\n  - lsystem: {axiom: A, rules: {A: AB, B: A}, iterations: 18, commands: {A: [{left: 1}], B: [{forward: 1}]}}\n";
        let strings = std::thread::Builder::new()
            .stack_size(256 << 10)
            .spawn(move || run(yaml).len())
            .unwrap()
            .join()
            .unwrap();
        // the word after 18 iterations of A -> AB, B -> A has F(18) = 2584 Bs
        assert_eq!(strings, 199 + 2584);
    }

    #[test]
    fn rand_is_seeded() {
        let yaml = |seed: u32| {
            format!("seed: {seed}\nprogram:\n  - repeat: 20\n    do: [{{forward: \"1 + rand()\"}}, {{left: \"90*rand()\"}}]\n")
        };
        assert_eq!(run(&yaml(7)), run(&yaml(7)));
        assert_ne!(run(&yaml(7)), run(&yaml(8)));
        let t = run(&yaml(7));
        assert!((0..t.len()).all(|k| (1.0..2.0).contains(&t.length(k))));
    }

    #[test]
    fn limits_refuse_before_allocating() {
        let small = Env {
            max_strings: 1000,
            ..env()
        };
        // a constant count: refused before running, at the repeat
        let e = run_with(
            "program:\n  - repeat: 1e12\n    do: [{forward: 1}, {left: 1}]\n",
            &small,
        )
        .unwrap_err();
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].repeat"));
        assert!(e.message.contains("at least 2000000000001 steps"), "{e}");
        // a count known only when it runs: refused at the string past the limit
        let e = run_with(
            "program:\n  - repeat: 1\n    as: k\n    do:\n      - repeat: \"1e12 + k\"\n        do: [{forward: 1}, {left: 1}]\n",
            &small,
        )
        .unwrap_err();
        assert_eq!(
            e.place.as_deref(),
            Some("turtle.program[0].do[0].do[0].forward")
        );
        assert!(e.message.contains("limit of 1000"), "{e}");
        let e = run_with(
            "program:\n  - {forward: 1}\n  - repeat: 1e12\n    do: [{left: 1}]\n",
            &small,
        )
        .unwrap_err();
        assert!(e.message.contains("steps"), "{e}");
        let e = run_with("program:\n  - lsystem: {axiom: F, rules: {F: FF}, iterations: 40, commands: {F: [{forward: 1}]}}\n", &small).unwrap_err();
        assert!(e.message.contains("limit"), "{e}");
        let e = run_with("program:\n  - lsystem: {axiom: F, rules: {F: FF}, iterations: 41, commands: {F: [{forward: 1}]}}\n", &small).unwrap_err();
        assert_eq!(
            e.place.as_deref(),
            Some("turtle.program[0].lsystem.iterations")
        );
    }

    #[test]
    fn the_bound_before_running_is_exact_for_constant_programs() {
        // max_strings 1000 allows 8 × 1000 + 10^6 = 1008000 steps
        let small = Env {
            max_strings: 1000,
            ..env()
        };
        let turns = |n: u64| {
            format!("program:\n  - {{forward: 1}}\n  - repeat: {n}\n    do: [{{left: 1}}]\n")
        };
        assert!(run_with(&turns(1_007_998), &small).is_ok());
        let e = run_with(&turns(1_007_999), &small).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].forward"));
        assert!(e.message.contains("at least 1008001 steps"), "{e}");
        // the Fibonacci L-system A → AB, B → A: symbols visited at every
        // depth, counted here by walking the derivation tree
        fn visits(s: char, d: u32, n: u32) -> u64 {
            let here = match (d < n, s) {
                (true, 'A') => visits('A', d + 1, n) + visits('B', d + 1, n),
                (true, _) => visits('A', d + 1, n),
                (false, 'A') => 1, // {left: 1}
                (false, _) => 2,   // {left: 2}, {left: 3}
            };
            1 + here
        }
        let want = 1 + visits('A', 0, 27); // the lsystem command and its symbols
        assert!(want > 1_008_000);
        let e = run_with(
            "program:\n  - lsystem: {axiom: A, rules: {A: AB, B: A}, iterations: 27, commands: {A: [{left: 1}], B: [{left: 2}, {left: 3}]}}\n",
            &small,
        )
        .unwrap_err();
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].lsystem"));
        assert!(e.message.contains(&format!("at least {want} steps")), "{e}");
    }

    #[test]
    fn errors_name_the_key_path() {
        let e = err("program:\n  - {forward: 1}\n  - {fowrard: 1}\n");
        assert_eq!(e.place.as_deref(), Some("program[1]"));
        assert!(e.message.contains("unknown command `fowrard`"), "{e}");
        let e = err("program:\n  - forward\n");
        assert!(e.message.contains("needs a value"), "{e}");
        let e = err("program:\n  - {goto: [1, 2]}\n");
        assert_eq!(e.place.as_deref(), Some("program[0].goto"));
        let e = err("program:\n  - {forward: 1, left: 2}\n");
        assert!(e.message.contains("one command per list item"), "{e}");
        let e = err("program:\n  - {call: nope}\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].call"));
        assert!(e.message.contains("undefined procedure `nope`"), "{e}");
        let e = err("procedures:\n  p: {params: [a], do: [{forward: a}]}\nprogram:\n  - {call: p, args: [1, 2]}\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].args"));
        let e = err("procedures:\n  spin: {do: [{left: 1}, {call: spin}]}\nprogram:\n  - {forward: 1}\n  - {call: spin}\n");
        assert_eq!(
            e.place.as_deref(),
            Some("turtle.procedures.spin.do[1].call")
        );
        assert!(e.message.contains("recurses without bound"), "{e}");
        let e = err("program:\n  - repeat: 3\n    as: k\n    do: [{forward: \"1/(k - 1)\"}]\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].do[0].forward"));
        assert!(e.message.contains("with k = 1"), "{e}");
        let e = err("program:\n  - {forward: \"q\"}\n");
        assert!(e.message.contains("unknown name `q`"), "{e}");
        let e = err("program:\n  - pen_up\n  - {forward: 1}\n");
        assert!(e.message.contains("extrudes nothing"), "{e}");
        let e = err("program:\n  - repeat: 2\n    as: x\n    do: [{forward: 1}]\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].as"));
        let e = err("program:\n  - pop\n");
        assert!(e.message.contains("without a `push`"), "{e}");
        let e = err("start: {heading: [0, 0, 1]}\nprogram: [{forward: 1}]\n");
        assert_eq!(e.place.as_deref(), Some("turtle.start"));
    }

    /// `set` with `band`: line `band`'s mark on the command's first
    /// setting (its value that setting's), none on the others, no height.
    #[test]
    fn a_set_command_with_band_marks_its_line() {
        use crate::base::toolpath::Band;
        let t = run("program:\n  - for: {k: \"0..3\"}\n    do:\n      - {set: {band: \"3 - k\", acceleration: \"1000 + k\", pressure_advance: \"0.01*k\"}}\n      - {forward: 5}\n");
        let marks: Vec<(usize, Option<Band>)> = t
            .events
            .iter()
            .map(|(k, e)| match e {
                Event::Set { band, .. } => (*k, *band),
                e => panic!("{e:?}"),
            })
            .collect();
        assert_eq!(marks.len(), 8, "{marks:?}");
        for (j, (k, band)) in marks.iter().enumerate() {
            let line = j / 2;
            assert_eq!(*k, line);
            let want = (j % 2 == 0).then_some(Band {
                index: 3 - line as u32,
                // pressure advance comes first in the docs' order
                value: 0.01 * line as f64,
                z: None,
            });
            assert_eq!(*band, want, "{j}");
        }
    }

    /// `set`: one event per command the firmware sets (print and travel
    /// acceleration in one), values from the turtle's scope where it runs,
    /// each naming its key path under `turtle`; no bands without `band`.
    #[test]
    fn set_commands_evaluate_in_scope_and_name_their_keys() {
        use crate::base::gcode::Setting;
        let t = run("program:\n  - for: {k: \"0..2\"}\n    do:\n      - {set: {pressure_advance: \"0.01*k + x/1000\", travel_acceleration: \"side*100\", acceleration: 900}}\n      - {forward: 5}\n");
        let sets: Vec<(usize, Setting, Option<&str>)> = t
            .events
            .iter()
            .map(|(k, e)| match e {
                Event::Set {
                    setting,
                    band: None,
                    place,
                } => (*k, *setting, place.as_deref()),
                e => panic!("{e:?}"),
            })
            .collect();
        assert_eq!(sets.len(), 6, "{sets:?}");
        for (j, (k, s, place)) in sets.iter().enumerate() {
            let line = j / 2;
            // before the line's string, the head at x = 5·line
            assert_eq!(*k, line);
            if j % 2 == 0 {
                let want = 0.01 * line as f64 + 5.0 * line as f64 / 1000.0;
                assert_eq!(*s, Setting::PressureAdvance { k: want });
                assert_eq!(*place, Some("turtle.program[0].do[0].set.pressure_advance"));
            } else {
                assert_eq!(
                    *s,
                    Setting::Acceleration {
                        print: Some(900.0),
                        travel: Some(1370.0),
                        retract: None
                    }
                );
                assert_eq!(*place, Some("turtle.program[0].do[0].set.acceleration"));
            }
        }
        // a step's height bands have no meaning where the command runs,
        // nor a pace (the turtle's own `speed` sets it)
        for (key, why) in [
            ("every", "no height bands"),
            ("from", "no height bands"),
            ("speed", "the turtle's own `speed`"),
            ("volumetric_speed", "the turtle's own `speed`"),
        ] {
            let e = err(&format!(
                "program:\n  - {{set: {{{key}: 1, fan: 1}}}}\n  - {{forward: 1}}\n"
            ));
            assert_eq!(e.place, Some(format!("turtle.program[0].set.{key}")), "{e}");
            assert!(e.message.contains(why), "{e}");
        }
        // `band`: a line's index, a whole number from 0 where it runs
        let e = err("program:\n  - for: {k: \"0..1\"}\n    do:\n      - {set: {band: \"k - 1/2\", fan: 1}}\n      - {forward: 1}\n");
        assert_eq!(
            e.place.as_deref(),
            Some("turtle.program[0].do[0].set.band"),
            "{e}"
        );
        assert!(
            e.message.contains("gives -0.5; expected a whole number"),
            "{e}"
        );
        let e = err("program:\n  - {set: {}}\n  - {forward: 1}\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].set"), "{e}");
        assert!(e.message.contains("sets nothing"), "{e}");
        let e = err("program:\n  - {set: {fan: \"q\"}}\n  - {forward: 1}\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].set.fan"), "{e}");
        let e = err("program:\n  - {set: {input_shaper_type: bump}}\n  - {forward: 1}\n");
        assert_eq!(
            e.place.as_deref(),
            Some("turtle.program[0].set.input_shaper_type"),
            "{e}"
        );
        let e = err("program:\n  - {set: {fan: \"1/(x - x)\"}}\n  - {forward: 1}\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].set.fan"), "{e}");
        assert!(e.message.contains("finite"), "{e}");
    }

    /// `gcode` with `{expr}`: each value from the command's scope, the
    /// line made then checked as the literal line is, refused at its key.
    #[test]
    fn gcode_lines_take_values_and_are_checked_as_made() {
        let t = run("program:\n  - for: {k: \"1..2\"}\n    do:\n      - {gcode: \"M900 K{0.01*k} ; line {k} at {x}, {side}\"}\n      - {forward: 2.5}\n");
        let lines: Vec<&str> = t
            .events
            .iter()
            .map(|(_, e)| match e {
                Event::Gcode(l) => l.as_ref(),
                e => panic!("{e:?}"),
            })
            .collect();
        assert_eq!(
            lines,
            [
                "M900 K0.01 ; line 1 at 0, 13.7",
                "M900 K0.02 ; line 2 at 2.5, 13.7"
            ]
        );
        // refused exactly as the literal line it makes, naming the key
        let literal = err("program:\n  - {gcode: \"M104 S300\"}\n  - {forward: 1}\n");
        let made = err(
            "program:\n  - {let: {t: 299}}\n  - {gcode: \"M104 S{t + 1}\"}\n  - {forward: 1}\n",
        );
        assert_eq!(made.place.as_deref(), Some("turtle.program[1].gcode"));
        assert_eq!(
            made.message,
            format!("the line `M104 S300` made here: {}", literal.message)
        );
        let made = err("program:\n  - {forward: 1}\n  - {gcode: \"G1 X{x + 1}\"}\n");
        let literal = err("program:\n  - {gcode: \"G1 X2\"}\n");
        assert!(made.message.ends_with(&literal.message), "{made}");
        // a brace without its end, an unknown name: refused at the key
        let e = err("program:\n  - {gcode: \"M117 {k\"}\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].gcode"));
        assert!(e.message.contains("without its `}`"), "{e}");
        let e = err("program:\n  - {gcode: \"M117 {q}\"}\n");
        assert_eq!(e.place.as_deref(), Some("turtle.program[0].gcode"));
        assert!(e.message.contains("unknown name `q`"), "{e}");
    }

    #[test]
    fn temperature_events_are_checked() {
        let text = "p3dp: 1\nname: t\nparts:\n  - primitive:\n      turtle:\n        program:\n          - {nozzle_temp: 300}\n          - {forward: 10}\n          - {bed_temp: 60}\n          - {bed_temp: 150}\n          - {forward: 10}\n";
        let raw: crate::recipe::RawRecipe = crate::recipe::parse_yaml(text, "t.yaml").unwrap();
        let r = crate::recipe::resolve(&raw, &[], None, std::path::Path::new(".")).unwrap();
        let Primitive::Turtle(t) = &r.parts[0].primitive else {
            panic!()
        };
        let f = crate::analyse::check::events(&r, &t.path);
        assert_eq!(f.len(), 2, "{f:?}");
        assert_eq!((f[0].code, f[0].string), ("nozzle-temp", Some(0)));
        assert_eq!((f[1].code, f[1].string), ("bed-temp", Some(1)));
        assert!(f[1].message.contains("150"), "{}", f[1].message);
    }
}
