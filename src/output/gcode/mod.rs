//! Strings to G-code.
//!
//! Numbers are fixed-point, never exponent notation and never `-0.000`: each
//! value is rounded once to integer units (µm for XYZ, 10 nm of filament for E)
//! and printed from the integer. E is tracked as the exact running total
//! Σ c·L / (pi·(d/2)²) and printed rounded, so the printed E values (absolute)
//! or deltas (relative) add up to the rounded exact total with no drift.
//!
//! Short-string merging (Kanada's `draw`): near a globe's poles 300 strings a
//! turn are far too short for the printer's planner. A run of consecutive
//! extruding strings, each shorter than the printer's `min_string_length`, is
//! written as one move from the run's start to the point where its length first
//! reaches that minimum. The move carries the run's filament exactly, and its
//! speed is set so that it takes the same time as the strings would.

pub(crate) mod labels;
pub(crate) mod metadata;
pub(crate) mod sink;

use std::io::{self, Read, Write};

use glam::DVec3;

use crate::analyse::plan::Plan;
use crate::analyse::planner::{Estimate, Moves};
pub(crate) use crate::analyse::stats::MoveStats;
use crate::base::error::Result;
use crate::base::format::{fmt_num, hms, units};
use crate::base::gcode::{Arc, Command, Heater, Move, Object, Setting};
use crate::base::safe_text::one_line;
use crate::base::toolpath::{Event, Toolpath};
use crate::generate::model::Recipe;
use crate::machine::firmware::write::{E, XYZ};
use crate::machine::firmware::{self, Dialect};
use crate::machine::{Extrusion, Printer};
use sink::{Out, Stream};

/// A feed of `mm_s` mm/s in whole mm/min as written after `F`, at least 1:
/// `libm::round(mm_s * 60).max(1) as i64` (`as` is monotone and 1 exact).
#[inline]
fn feed_units(mm_s: f64) -> i64 {
    crate::base::format::round_i64(mm_s * 60.0).max(1)
}

/// What goes at the head of the G-code besides the profile's: how it is
/// stamped, the print's totals when planned ahead, the thumbnail blocks.
#[derive(Clone, Debug, Default)]
pub(crate) struct Head {
    /// The date and the package (see [`metadata::Options`]).
    pub(crate) options: metadata::Options,
    /// The print's totals, when its moves were planned first.
    pub(crate) ahead: Option<metadata::Ahead>,
    /// Thumbnail blocks (comments, see `output::preview::thumbnail`).
    pub(crate) thumbnails: String,
    /// G-code drawn, never sent (a preview's): written even when the
    /// profile's start or end G-code failed its checks, so that a preview
    /// shows a print the checks refuse too.
    pub(crate) draft: bool,
}

/// The dialect `printer`'s firmware reads.
pub(crate) fn dialect(printer: &Printer) -> Dialect {
    let m = printer.model.to_ascii_uppercase();
    Dialect {
        flavor: printer.flavor,
        object_labels: printer.object_labels,
        prusa_8bit: m.starts_with("MK3") || m.starts_with("MK2"),
    }
}

/// Writes the G-code of `plan` to `out`: the header (with `head`'s
/// thumbnails), the start G-code, every part, the end G-code and the
/// summary. Every command is followed by the firmware's state as it is
/// written, its motion handed to `moves`; `estimate` turns them into the
/// print's times for the summary.
pub(crate) fn write<W: Write, M: Moves>(
    plan: &Plan,
    head: Head,
    out: W,
    moves: M,
    estimate: impl FnOnce(&mut M) -> Estimate,
) -> Result<(W, MoveStats)> {
    let (stream, stats) = emit(plan, head, out, moves, estimate)?;
    Ok((stream.out.out, stats))
}

/// The G-code of `plan` formatted into a scratch text (see [`write`]; the
/// header that needs the print's totals left out) with what it lacked put
/// in, piece by piece ([`WithProgress::fill`]): that header (Bambu's block,
/// from the planner's totals), then the text with a progress line (`M73`)
/// before each offset of its `lines` — the way slicers put progress in,
/// from the planner's times, the text formatted once. The caller writes
/// and hashes each piece (beside the next one's making, when it can).
pub(crate) struct WithProgress<'a, R> {
    text: R,
    lines: &'a [(u64, crate::analyse::planner::Progress)],
    /// The next of `lines` to put in, and the offset in `text` read to.
    next: usize,
    at: u64,
    dialect: Dialect,
    /// Bambu's header block, until the first piece takes it.
    header: Vec<u8>,
    line: crate::base::format::Chunk,
}

impl<'a, R: Read> WithProgress<'a, R> {
    /// The text `scratch` of `plan` (whose moves add up to `ahead`) with
    /// progress lines before the offsets of `lines` (non-decreasing).
    pub(crate) fn new(
        plan: &Plan,
        head: &Head,
        ahead: &metadata::Ahead,
        scratch: R,
        lines: &'a [(u64, crate::analyse::planner::Progress)],
    ) -> WithProgress<'a, R> {
        let mut header = Vec::new();
        if head.options.bambu {
            let extent = metadata::Extent::of(plan);
            let layers = metadata::Layers::of(&extent, plan.recipe.printer.nozzle_diameter);
            let block = metadata::bambu_header(&plan.recipe, ahead, layers.as_ref());
            header.extend_from_slice(block.as_bytes());
        }
        WithProgress {
            text: scratch,
            lines,
            next: 0,
            at: 0,
            dialect: dialect(&plan.recipe.printer),
            header,
            line: crate::base::format::Chunk::new(),
        }
    }

    /// Appends the next piece of the G-code to `buf`, until it holds at
    /// least `want` bytes or the text ends; false once nothing is left.
    pub(crate) fn fill(&mut self, buf: &mut Vec<u8>, want: usize) -> io::Result<bool> {
        buf.append(&mut self.header);
        while buf.len() < want {
            let room = (want - buf.len()) as u64;
            let Some(&(offset, p)) = self.lines.get(self.next) else {
                // no line left to put in: the rest of the text
                if read_up_to(&mut self.text, buf, room)? == 0 {
                    return Ok(false);
                }
                continue;
            };
            let n = offset.saturating_sub(self.at).min(room);
            read_exactly(&mut self.text, buf, n)?;
            self.at += n;
            if self.at >= offset {
                self.line.clear();
                let c = Command::Progress {
                    percent: p.percent,
                    minutes_left: p.minutes_left,
                };
                crate::machine::firmware::write::write(self.dialect, &c, "", &mut self.line);
                buf.extend_from_slice(self.line.bytes());
                self.at = self.at.max(offset);
                self.next += 1;
            }
        }
        Ok(true)
    }
}

/// Appends exactly `n` bytes of `from` to `buf`.
fn read_exactly(from: &mut impl Read, buf: &mut Vec<u8>, n: u64) -> io::Result<()> {
    if read_up_to(from, buf, n)? as u64 == n {
        Ok(())
    } else {
        Err(io::ErrorKind::UnexpectedEof.into())
    }
}

/// Appends up to `n` bytes of `from` to `buf` (fewer at its end): how many.
fn read_up_to(from: &mut impl Read, buf: &mut Vec<u8>, n: u64) -> io::Result<usize> {
    from.take(n).read_to_end(buf)
}

/// [`write`], the stream back.
fn emit<W: Write, M: Moves>(
    plan: &Plan,
    head: Head,
    out: W,
    moves: M,
    estimate: impl FnOnce(&mut M) -> Estimate,
) -> Result<(Stream<W, M>, MoveStats)> {
    let io = |e: io::Error| {
        crate::base::error::Error::io_from(&plan.path, format!("cannot write the G-code: {e}"), &e)
    };
    if !head.draft {
        plan.frame_ok()?;
    }
    let p = &plan.recipe.printer;
    let retraction = (units(p.retraction.length, E) as f64 / E, p.retraction.speed);
    let stream = Stream::new(Out::new(out), dialect(p), moves, retraction);
    let extent = metadata::Extent::of(plan);
    let mut em = Emitter::new(stream, &plan.recipe);
    em.thumbnails = head.thumbnails;
    em.options = head.options;
    em.ahead = head.ahead;
    em.layers = metadata::Layers::of(&extent, p.nozzle_diameter);
    // a plate's objects, else each part: labelled, in print order
    let objects = plan.objects();
    em.names = labels::names(objects.iter().map(|(n, _)| n.as_str()));
    if p.object_labels {
        em.defines = objects
            .iter()
            .zip(&em.names)
            .map(|((_, r), n)| labels::define(n, &labels::hull_of(&plan.paths[r.clone()], p)))
            .collect();
    }
    let fan_events = |t: &Toolpath| {
        t.events.iter().any(|(_, e)| {
            matches!(
                e,
                Event::Fan { .. }
                    | Event::Set {
                        setting: Setting::Fan { .. },
                        ..
                    }
            )
        })
    };
    if plan.paths.iter().any(fan_events) {
        em.manual_fan();
    }
    em.start(&plan.recipe, &plan.frame.start)?;
    for (k, (_, r)) in objects.iter().enumerate() {
        em.label(k, true).map_err(io)?;
        for tp in &plan.paths[r.clone()] {
            em.part(tp).map_err(io)?;
        }
        em.label(k, false).map_err(io)?;
    }
    em.finish(&plan.recipe, &plan.frame.end, estimate)
}

/// Turns a plan's strings into commands: the moves, retractions, events
/// and decorations of one print, into a [`Stream`] (which writes and
/// follows them).
pub(crate) struct Emitter<'a, W: Write, M: Moves> {
    s: Stream<W, M>,
    printer: &'a Printer,
    /// Filament cross-section area, mm².
    area: f64,
    /// Last written machine position in µm, once known.
    written: Option<[i64; 3]>,
    /// `written` in mm (zero before it is known).
    written_mm: DVec3,
    /// Exact head position, recipe coordinates.
    head: Option<DVec3>,
    /// Exact filament total, mm.
    e_exact: f64,
    /// Last E total written, 1e-5 mm.
    e_units: i64,
    retracted: bool,
    /// The feed last written, mm/min (-1 before any).
    feed: i64,
    /// `feed` in mm/s.
    feed_mm_s: f64,
    /// The moves so far.
    pub(crate) stats: MoveStats,
    pending: Pending,
    /// Thumbnail blocks written after the header comments (see
    /// `crate::output::preview::thumbnail`); empty for none.
    pub(crate) thumbnails: String,
    /// The material's fan: (speed, start z), until it is switched on or a
    /// `fan` event takes over.
    fan: Option<(f64, f64)>,
    /// How the G-code is stamped (date, package).
    options: metadata::Options,
    /// The print's totals, when planned ahead.
    ahead: Option<metadata::Ahead>,
    /// The layers as bands of nozzle height (None: nothing extrudes).
    layers: Option<metadata::Layers>,
    /// The layer reached so far (0 before any extrusion).
    layer: u32,
    /// Recipe z above which an extruding move begins a new layer.
    layer_above: f64,
    /// Each part's label (see [`labels`]).
    names: Vec<String>,
    /// Klipper's `EXCLUDE_OBJECT_DEFINE` lines, one per part, until the
    /// header is written; empty without `object_labels`.
    defines: Vec<String>,
    /// The flow factor the firmware applies (`M221`), 1 = 100 %: the
    /// filament it feeds is the E written times this.
    flow: f64,
    /// p3dp's own retraction: length (mm) and speed (mm/s), the printer's
    /// until a `set` step changes them.
    retraction: (f64, f64),
    /// The length of the retraction in force, 10 nm (its undoing feeds it back).
    retracted_units: i64,
}

#[derive(Default)]
struct Pending {
    count: u64,
    end: DVec3,
    path: f64,
    filament: f64,
    time: f64,
    v_last: f64,
}

impl<'a, W: Write, M: Moves> Emitter<'a, W, M> {
    /// An emitter of `recipe`'s commands into `s`.
    pub(crate) fn new(s: Stream<W, M>, recipe: &'a Recipe) -> Emitter<'a, W, M> {
        let d = recipe
            .material
            .filament_diameter
            .unwrap_or(recipe.printer.filament_diameter);
        Emitter {
            s,
            printer: &recipe.printer,
            area: std::f64::consts::PI * (d / 2.0) * (d / 2.0),
            written: None,
            written_mm: DVec3::ZERO,
            head: None,
            e_exact: 0.0,
            e_units: 0,
            retracted: false,
            feed: -1,
            feed_mm_s: -1.0 / 60.0,
            stats: MoveStats {
                bbox_min: DVec3::splat(f64::INFINITY),
                bbox_max: DVec3::splat(f64::NEG_INFINITY),
                ..MoveStats::default()
            },
            pending: Pending::default(),
            thumbnails: String::new(),
            fan: (recipe.material.fan_speed > 0.0)
                .then_some((recipe.material.fan_speed, recipe.material.fan_start_z)),
            options: metadata::Options::default(),
            ahead: None,
            layers: None,
            layer: 0,
            layer_above: f64::NEG_INFINITY,
            names: Vec::new(),
            defines: Vec::new(),
            flow: 1.0,
            retraction: (
                recipe.printer.retraction.length,
                recipe.printer.retraction.speed,
            ),
            retracted_units: 0,
        }
    }

    fn text(&mut self, s: &str) -> io::Result<()> {
        self.s.text(s)
    }

    /// The labels that begin (`start`) or end part `k` (see [`labels`]).
    fn label(&mut self, k: usize, start: bool) -> io::Result<()> {
        self.flush()?;
        let Some(name) = self.names.get(k) else {
            return Ok(());
        };
        let o = if start {
            Object::Start(name.clone())
        } else {
            Object::End(name.clone())
        };
        self.s.command(&Command::Object(o), "")
    }

    /// Marks a new layer before an extruding move to `to` that rises above
    /// the layers so far (see [`metadata::Layers`]).
    #[inline]
    fn layer_at(&mut self, to: DVec3) -> io::Result<()> {
        if to.z > self.layer_above {
            self.new_layer(to.z)?;
        }
        Ok(())
    }

    /// Writes the markers of the layer of recipe height `z`.
    fn new_layer(&mut self, z: f64) -> io::Result<()> {
        let Some(l) = self.layers else {
            self.layer_above = f64::INFINITY;
            return Ok(());
        };
        let dz = self.printer.origin[2];
        let n = l.of_z(z + dz).max(self.layer + 1);
        self.layer = n;
        let top = l.top(n);
        // the band's top, and a millionth of a band over it
        self.layer_above = top - dz + 1e-6 * l.height;
        let shown = top.min(l.highest);
        let mut t = format!(
            ";LAYER_CHANGE\n;Z:{shown:.3}\n;HEIGHT:{:.3}\n;BEFORE_LAYER_CHANGE\n;{shown:.3}\n",
            l.height
        );
        if self.options.bambu {
            t.push_str(&format!(
                "M73 L{n}\nM991 S0 P{} ;notify layer change\n",
                n - 1
            ));
        }
        self.text(&t)
    }

    /// Header comments, `start` (the profile's start G-code, expanded and
    /// checked: [`crate::analyse::frame`]) and the extrusion mode.
    pub(crate) fn start(
        &mut self,
        recipe: &Recipe,
        start: &[crate::base::gcode::Verbatim],
    ) -> Result<()> {
        let io = |e: io::Error| crate::base::error::Error::io_from("output", e.to_string(), &e);
        if let (true, Some(a)) = (self.options.bambu, &self.ahead) {
            let block = metadata::bambu_header(recipe, a, self.layers.as_ref());
            self.text(&block).map_err(io)?;
        }
        self.text(&metadata::generated(self.options.date))
            .map_err(io)?;
        let head = format!(
            "; recipe: {}\n; printer: {} ({:?})\n; material: {}, {} °C nozzle, {} °C bed\n",
            one_line(&recipe.name),
            one_line(&self.printer.name),
            self.printer.flavor,
            one_line(&recipe.material.name),
            fmt_num(recipe.material.nozzle_temp),
            fmt_num(recipe.material.bed_temp),
        );
        self.text(&head).map_err(io)?;
        self.params(&recipe.params).map_err(io)?;
        if !self.thumbnails.is_empty() {
            let t = std::mem::take(&mut self.thumbnails);
            self.text(&t).map_err(io)?;
        }
        self.text(&metadata::layers_note(self.layers.as_ref()))
            .map_err(io)?;
        for d in std::mem::take(&mut self.defines) {
            self.text(&d).map_err(io)?;
        }
        if self.printer.arcs {
            self.text(&format!(
                "; arcs: G2/G3 within {} mm of the strings ({})",
                fmt_num(self.printer.arc_tolerance),
                firmware::arc_note(self.printer.flavor)
            ))
            .map_err(io)?;
        }
        self.s.first_place();
        self.profile_lines(start).map_err(io)?;
        let mode = match self.printer.extrusion {
            Extrusion::Absolute => (false, " ; absolute extrusion"),
            Extrusion::Relative => (true, " ; relative extrusion"),
        };
        let s = &mut self.s;
        s.command(&Command::Inches(false), " ; millimetres")
            .map_err(io)?;
        s.command(&Command::RelativeXyz(false), " ; absolute XYZ")
            .map_err(io)?;
        s.command(&Command::RelativeE(mode.0), mode.1).map_err(io)?;
        s.command(
            &Command::SetPosition {
                axes: [None; 3],
                e: Some(0.0),
            },
            "",
        )
        .map_err(io)?;
        if let Some(k) = self.printer.pressure_advance {
            // the profile's calibrated value (`p3dp calibrate apply`)
            s.command(
                &Command::Set(Setting::PressureAdvance { k }),
                " ; the profile's pressure_advance",
            )
            .map_err(io)?;
        }
        Ok(())
    }

    /// A profile's lines, as they were read and checked; the flow factor
    /// they set followed.
    fn profile_lines(&mut self, lines: &[crate::base::gcode::Verbatim]) -> io::Result<()> {
        for l in lines {
            for c in &l.commands {
                if let Command::Set(Setting::Flow(f)) = c {
                    self.flow = *f;
                }
            }
            self.s.verbatim(l)?;
        }
        Ok(())
    }

    /// ` F<f>` (mm/min) to write, when the feed changes.
    #[inline]
    fn feed_word(&mut self, f: i64) -> Option<f64> {
        if f != self.feed {
            self.feed = f;
            self.feed_mm_s = f as f64 / 60.0;
            Some(f as f64)
        } else {
            None
        }
    }

    /// The axes of a move to `to` (recipe coordinates) for those of `only`
    /// that change, and whether any does.
    #[inline]
    fn axes(&mut self, to: DVec3, only: [bool; 3]) -> ([Option<f64>; 3], bool) {
        let u = self.units_of(to);
        self.axes_units(u, only)
    }

    /// `to` (recipe coordinates) in the machine's µm, as written.
    #[inline]
    fn units_of(&self, to: DVec3) -> [i64; 3] {
        let m = self.printer.to_machine(to);
        [units(m.x, XYZ), units(m.y, XYZ), units(m.z, XYZ)]
    }

    /// [`Emitter::axes`] of a position already in µm.
    #[inline]
    fn axes_units(&mut self, u: [i64; 3], only: [bool; 3]) -> ([Option<f64>; 3], bool) {
        let mut words = [None; 3];
        let mut changed = false;
        for k in 0..3 {
            if only[k] && self.written.is_none_or(|w| w[k] != u[k]) {
                words[k] = Some(u[k] as f64 / XYZ);
                changed = true;
            }
        }
        let mut w = self.written.unwrap_or(u);
        for k in 0..3 {
            if only[k] {
                w[k] = u[k];
            }
        }
        self.written = Some(w);
        self.written_mm = DVec3::new(w[0] as f64, w[1] as f64, w[2] as f64) / XYZ;
        (words, changed)
    }

    fn retract(&mut self) -> io::Result<()> {
        let (length, speed) = self.retraction;
        if length <= 0.0 || self.retracted {
            return Ok(());
        }
        let len = units(length, E);
        self.retracted_units = len;
        self.retracted = true;
        self.stats.retractions += 1;
        if self.printer.firmware_retraction {
            // G10: the firmware's length and speed; E is untouched
            return self
                .s
                .command(&Command::FirmwareRetract { undo: false }, " ; retract");
        }
        self.s.progress_point()?;
        let e = match self.printer.extrusion {
            Extrusion::Absolute => self.e_units - len,
            Extrusion::Relative => -len,
        };
        let feed = self.feed_word(feed_units(speed));
        let m = Move {
            e: Some(e as f64 / E),
            feed,
            ..Move::default()
        };
        self.s.line(&m, " ; retract")
    }

    #[inline]
    fn unretract(&mut self) -> io::Result<()> {
        if !self.retracted {
            return Ok(());
        }
        self.unretract_now()
    }

    /// Writes the unretraction (see [`Emitter::unretract`]).
    fn unretract_now(&mut self) -> io::Result<()> {
        let speed = self.retraction.1;
        let len = self.retracted_units;
        self.retracted = false;
        if self.printer.firmware_retraction {
            return self
                .s
                .command(&Command::FirmwareRetract { undo: true }, " ; unretract");
        }
        self.s.progress_point()?;
        let e = match self.printer.extrusion {
            Extrusion::Absolute => self.e_units,
            Extrusion::Relative => len,
        };
        let feed = self.feed_word(feed_units(speed));
        let m = Move {
            e: Some(e as f64 / E),
            feed,
            ..Move::default()
        };
        self.s.line(&m, " ; unretract")
    }

    /// A straight travel move to `to` (G0), retracting first when it is long.
    fn travel_line(&mut self, to: DVec3, only: [bool; 3]) -> io::Result<()> {
        let from = self.head;
        let mut target = from.unwrap_or(to);
        for k in 0..3 {
            if only[k] {
                target[k] = to[k];
            }
        }
        let dist = from.map_or(0.0, |f| f.distance(target));
        if from.is_some() && dist >= self.printer.retraction.min_travel {
            self.retract()?;
        }
        self.s.progress_point()?;
        let (words, changed) = self.axes(target, only);
        if !changed {
            self.head = Some(target);
            return Ok(());
        }
        let tv = self.travel_feed(from, target, dist);
        let feed = self.feed_word(feed_units(tv));
        let m = Move {
            travel: true,
            to: words,
            e: None,
            feed,
        };
        self.s.line(&m, "")?;
        self.stats.travel_moves += 1;
        self.stats.travel_length += dist;
        self.head = Some(target);
        Ok(())
    }

    /// The feed of a travel move from `from` to `to` (`dist` mm apart): the
    /// profile's `travel_speed`, but no quicker than the Z axis can follow
    /// (`kinematics.max_z_speed` scaled by L/|dz|, rounded down to a whole
    /// mm/min), so hops and Z-only moves are written at a feed the firmware
    /// need not clamp.
    fn travel_feed(&self, from: Option<DVec3>, to: DVec3, dist: f64) -> f64 {
        let tv = self.printer.travel_speed;
        let (Some(f), Some(vz)) = (from, self.printer.kinematics.max_z_speed) else {
            return tv;
        };
        let dz = (to.z - f.z).abs();
        if dz <= 0.0 {
            return tv;
        }
        let cap = vz * dist / dz;
        if cap < tv {
            (libm::floor(cap * 60.0) / 60.0).max(1.0 / 60.0)
        } else {
            tv
        }
    }

    /// Travel to `to` between parts: up to a safe height (above everything
    /// printed so far by the head's clearance, see
    /// [`crate::machine::travel::safe_travel_z`]), across, then down, so the
    /// head never crosses what is printed; the collision check models the same.
    pub(crate) fn travel_to(&mut self, to: DVec3) -> io::Result<()> {
        self.flush()?;
        let Some(h) = self.head else {
            return self.travel_line(to, [true; 3]);
        };
        let top = if self.stats.extrude_moves > 0 {
            self.stats.bbox_max.z
        } else {
            f64::NEG_INFINITY
        };
        match crate::machine::travel::safe_travel_z(self.printer, h, to, top) {
            Some(z) => {
                self.travel_line(DVec3::new(h.x, h.y, z), [false, false, true])?;
                self.travel_line(to, [true, true, false])?;
                self.travel_line(to, [false, false, true])
            }
            None => self.travel_line(to, [false, false, true]),
        }
    }

    /// The recipe sets the fan itself (a turtle's `fan`): no automatic fan.
    pub(crate) fn manual_fan(&mut self) {
        self.fan = None;
    }

    /// Switches the material's fan on before the first extruding move that
    /// ends above its start height (slicers keep the first layers warm).
    #[inline]
    fn fan_on_above(&mut self, to: DVec3) -> io::Result<()> {
        match self.fan {
            Some((speed, z)) if to.z > z => {
                self.fan = None;
                let c = Command::Set(Setting::Fan { speed });
                self.s.command(&c, &format!(": above z = {z} mm"))
            }
            _ => Ok(()),
        }
    }

    /// `; param NAME = VALUE` for each param: a number, or a choice's
    /// string, a boolean, a list as the recipe reads them.
    fn params(&mut self, params: &crate::base::expr::Params) -> io::Result<()> {
        for (k, v) in params.iter() {
            let v = params.text(k).unwrap_or_else(|| fmt_num(*v));
            self.text(&format!("; param {} = {}", one_line(k), one_line(&v)))?;
        }
        for k in params.list_names() {
            let v = params.text(k).unwrap_or_default();
            self.text(&format!("; param {} = {}", one_line(k), v))?;
        }
        Ok(())
    }

    /// Adds `filament` mm to the exact E total: the E value to write, the
    /// rounded total (M82) or its step from the last written one (M83), so
    /// the written values add up to the exact total.
    #[inline]
    fn next_e(&mut self, filament: f64) -> f64 {
        self.e_exact += filament;
        let e_new = units(self.e_exact, E);
        let w = match self.printer.extrusion {
            Extrusion::Absolute => e_new,
            Extrusion::Relative => e_new - self.e_units,
        };
        self.e_units = e_new;
        w as f64 / E
    }

    /// One G1 extruding move to `to` carrying `filament` mm at `v` mm/s.
    fn extrude_line(&mut self, to: DVec3, filament: f64, v: f64) -> io::Result<()> {
        // the written position, once (what comes before the move's line
        // writes no axis)
        let u = self.units_of(to);
        if self.written == Some(u) && units(self.e_exact + filament, E) == self.e_units {
            // no axis and no E step once rounded (`G1 E0.00000`): firmware
            // ignores such a line, and a planner would stop the head for
            // it; its filament joins the exact E total, written next
            self.e_exact += filament;
            self.stats.filament += filament * self.flow;
            self.stats.volume += filament * self.flow * self.area;
            self.head = Some(to);
            return Ok(());
        }
        self.layer_at(to)?;
        self.fan_on_above(to)?;
        self.unretract()?;
        let from = self.head.expect("extrusion starts after a travel");
        let feed = feed_units(v);
        let f = feed as f64 / 60.0;
        let len = from.distance(to);
        let t = if len > 0.0 { len / f } else { filament / f };
        self.s.progress_point()?;
        let (words, _) = self.axes_units(u, [true; 3]);
        let e = self.next_e(filament);
        let feed = self.feed_word(feed);
        let m = Move {
            travel: false,
            to: words,
            e: Some(e),
            feed,
        };
        self.s.line(&m, "")?;
        self.count_extrusion(len, filament, t, &[from, to]);
        self.head = Some(to);
        Ok(())
    }

    /// Counts one extruding move in the stats: `len` mm through `points`,
    /// carrying `filament` mm (the firmware feeds it times the flow
    /// factor) in `t` s.
    #[inline]
    fn count_extrusion(&mut self, len: f64, filament: f64, t: f64, points: &[DVec3]) {
        let fed = filament * self.flow;
        let st = &mut self.stats;
        st.extrude_moves += 1;
        st.extrude_length += len;
        st.filament += fed;
        st.volume += fed * self.area;
        if t > 0.0 {
            st.max_flow = st.max_flow.max(fed * self.area / t);
        }
        for p in points {
            st.bbox_min = st.bbox_min.min(*p);
            st.bbox_max = st.bbox_max.max(*p);
        }
    }

    /// One `G2`/`G3` move along `arc` (see [`crate::base::geom::arc`]), replacing strings
    /// `arc.start..arc.end` of `tp`: E is their exact filament, the speed the
    /// one that keeps their time, I J the centre from the written start.
    fn arc_move(&mut self, tp: &Toolpath, arc: &crate::base::geom::arc::Arc) -> io::Result<()> {
        self.layer_at(tp.points[arc.end])?;
        self.fan_on_above(tp.points[arc.end])?;
        self.unretract()?;
        let (mut filament, mut time) = (0.0, 0.0);
        for k in arc.start..arc.end {
            let (len, s) = (tp.length(k), tp.strings[k]);
            filament += s.c * len / self.area;
            time += len / s.v;
        }
        let len = arc.length();
        let v = if time > 0.0 {
            len / time
        } else {
            tp.strings[arc.start].v
        };
        let start = self.written_mm;
        let to = tp.points[arc.end];
        self.s.progress_point()?;
        let (words, _) = self.axes(to, [true; 3]);
        let c = self.printer.to_machine(arc.center.extend(0.0));
        let ij = [
            units(c.x - start.x, XYZ) as f64 / XYZ,
            units(c.y - start.y, XYZ) as f64 / XYZ,
        ];
        let e = self.next_e(filament);
        let feed = self.feed_word(feed_units(v));
        let a = Arc {
            ccw: arc.ccw,
            to: words,
            ij,
            e: Some(e),
            feed,
        };
        self.s.command(&Command::Arc(a), "")?;
        let f = self.feed_mm_s;
        self.count_extrusion(len, filament, len / f, &tp.points[arc.start..=arc.end]);
        self.head = Some(to);
        Ok(())
    }

    /// Writes what is pending of a run of short strings.
    fn flush(&mut self) -> io::Result<()> {
        if self.pending.count == 0 {
            return Ok(());
        }
        let p = std::mem::take(&mut self.pending);
        let from = self.head.expect("pending strings follow the head");
        let chord = from.distance(p.end);
        // same time as the strings: v = chord / Σ(L_i / v_i)
        let v = if chord > 0.0 && p.time > 0.0 {
            chord / p.time
        } else {
            p.v_last
        };
        if p.count > 1 {
            self.stats.merged_strings += p.count;
        }
        self.extrude_line(p.end, p.filament, v)
    }

    /// Writes an event between strings (see [`Event`]): a dialect command,
    /// a retraction, or filament fed in place.
    fn event(&mut self, e: &Event) -> io::Result<()> {
        self.flush()?;
        let c = match *e {
            Event::Retract => return self.retract(),
            Event::Extrude { filament, speed } => return self.extrude_in_place(filament, speed),
            Event::Dwell { ms } => Command::Dwell { ms },
            Event::Pause => Command::Pause,
            Event::NozzleTemp { celsius, wait } => Command::Set(Setting::Temperature {
                heater: Heater::Nozzle(0),
                celsius,
                wait,
            }),
            Event::BedTemp { celsius, wait } => Command::Set(Setting::Temperature {
                heater: Heater::Bed,
                celsius,
                wait,
            }),
            Event::Fan { speed } => {
                self.fan = None; // the recipe sets the fan itself from here on
                Command::Set(Setting::Fan { speed })
            }
            Event::Gcode(ref text) => {
                let commands = firmware::read(self.printer.flavor, text)
                    .map(|r| r.commands)
                    .unwrap_or_else(|_| vec![Command::Other(text.to_string())]);
                return self.s.raw(text, &commands);
            }
            Event::Set { setting, band, .. } => return self.set(setting, band),
            // no command: the band's strings carry its speed
            Event::Band { band, pace } => {
                let (what, unit) = match pace {
                    crate::base::toolpath::Pace::Speed => ("speed", "mm/s"),
                    crate::base::toolpath::Pace::Volumetric => ("volumetric speed", "mm3/s"),
                };
                let t = format!(
                    "; band {}: {what} {} {unit}",
                    band.index,
                    fmt_num(band.value)
                );
                return self.text(&t);
            }
        };
        self.s.command(&c, "")
    }

    /// A `set` step's setting: written in the dialect (p3dp's own
    /// retraction as a comment, its moves carry it) and followed: the flow
    /// factor into the stats, the retraction into p3dp's retractions, the
    /// rest by the stream (the planner).
    fn set(&mut self, s: Setting, band: Option<crate::base::toolpath::Band>) -> io::Result<()> {
        let note = match band {
            Some(b) => format!(" ; band {}", b.index),
            None => String::new(),
        };
        match s {
            Setting::Flow(f) => self.flow = f,
            Setting::Fan { .. } => self.fan = None,
            Setting::Retraction { length, speed } if !self.printer.firmware_retraction => {
                let r = &mut self.retraction;
                r.0 = length.unwrap_or(r.0);
                r.1 = speed.unwrap_or(r.1);
                let t = format!(
                    "; retraction: {} mm at {} mm/s{note}",
                    fmt_num(r.0),
                    fmt_num(r.1)
                );
                return self.text(&t);
            }
            // Klipper's and RepRapFirmware's G11 give back the length in
            // force then, not what their G10 took (Marlin's, what it took):
            // back from a retraction before its length changes
            Setting::Retraction { .. } if self.retracted => self.unretract_now()?,
            _ => {}
        }
        self.s.command(&Command::Set(s), &note)
    }

    /// `G1 E… F…`: feeds `filament` mm at `speed` mm/s without moving.
    fn extrude_in_place(&mut self, filament: f64, speed: f64) -> io::Result<()> {
        if filament <= 0.0 {
            return Ok(());
        }
        self.unretract()?;
        // no faster than the machine feeds filament alone (its head's speed
        // when the profile gives no extrude-only limit)
        let limits = self.printer.limits();
        let speed = speed.min(
            limits
                .max_extrude_only_velocity
                .unwrap_or(limits.max_velocity),
        );
        self.s.progress_point()?;
        let e = self.next_e(filament);
        let feed = self.feed_word(feed_units(speed));
        let m = Move {
            e: Some(e),
            feed,
            ..Move::default()
        };
        self.s.line(&m, " ; extrude in place")?;
        let fed = filament * self.flow;
        let st = &mut self.stats;
        st.filament += fed;
        st.volume += fed * self.area;
        // fed in place, it melts as fast as it is fed
        st.max_flow = st.max_flow.max(speed * self.flow * self.area);
        Ok(())
    }

    /// Writes one part: a comment, a travel to its start, then its strings.
    pub(crate) fn part(&mut self, tp: &Toolpath) -> io::Result<()> {
        self.s.begin_part(&tp.name);
        let comment = format!("; part: {} ({} strings)", one_line(&tp.name), tp.len());
        self.flush()?;
        self.text(&comment)?;
        self.travel_to(tp.points[0])?;
        let min = self.printer.min_string_length;
        let mut events = tp.events.iter().peekable();
        let arcs = if self.printer.arcs {
            let fw = firmware::arc_firmware(self.printer.flavor);
            let mut arcs = crate::base::geom::arc::fit_part(tp, self.printer.arc_tolerance, fw);
            // an arc bulges past its strings by up to the tolerance: one whose
            // sweep leaves the bed stays strings (which the checks held to it)
            let o = self.printer.origin;
            let bed_origin = glam::DVec2::new(-o[0], -o[1]);
            arcs.retain(|a| {
                a.bounding_points(bed_origin)
                    .into_iter()
                    .all(|p| self.printer.bed.contains_xy(self.printer.to_machine(p)))
            });
            arcs
        } else {
            Vec::new()
        };
        let mut arcs = arcs.iter().peekable();
        let mut skip_to = 0;
        for k in 0..tp.len() {
            if k < skip_to {
                continue;
            }
            while let Some((_, e)) = events.next_if(|(at, _)| *at <= k) {
                self.event(e)?;
            }
            if let Some(a) = arcs.next_if(|a| a.start == k) {
                self.flush()?;
                self.arc_move(tp, a)?;
                skip_to = a.end;
                continue;
            }
            let s = tp.strings[k];
            let (a, b) = tp.ends(k);
            if s.travel {
                self.flush()?;
                self.travel_line(b, [true; 3])?;
                continue;
            }
            let len = a.distance(b);
            let filament = s.c * len / self.area;
            if len >= min && self.pending.count == 0 {
                self.extrude_line(b, filament, s.v)?;
                continue;
            }
            if len >= min {
                self.flush()?;
                self.extrude_line(b, filament, s.v)?;
                continue;
            }
            let p = &mut self.pending;
            p.count += 1;
            p.end = b;
            p.path += len;
            p.filament += filament;
            p.time += len / s.v;
            p.v_last = s.v;
            if p.path >= min {
                self.flush()?;
            }
        }
        self.flush()?;
        for (_, e) in events {
            self.event(e)?;
        }
        Ok(())
    }

    /// `end` (the profile's end G-code, expanded and checked) and the
    /// summary comments slicers write: `estimate` turns the moves' sink,
    /// every move handed to it, into the print's estimate (the planner's
    /// times are known only once it has them all).
    pub(crate) fn finish(
        mut self,
        recipe: &Recipe,
        end: &[crate::base::gcode::Verbatim],
        estimate: impl FnOnce(&mut M) -> Estimate,
    ) -> Result<(Stream<W, M>, MoveStats)> {
        let io = |e: io::Error| crate::base::error::Error::io_from("output", e.to_string(), &e);
        self.flush().map_err(io)?;
        if self.retracted && !self.printer.firmware_retraction {
            // a print that ends retracted took that filament back: the
            // stats count the filament fed, net (what the E values add to)
            let back = self.retracted_units as f64 / E * self.flow;
            self.stats.filament -= back;
            self.stats.volume -= back * self.area;
        }
        self.s.done().map_err(io)?;
        self.profile_lines(end).map_err(io)?;
        let limits = self.printer.limits();
        let est = estimate(&mut self.s.moves);
        self.stats.time = est.total.planned;
        let mut summary = metadata::footer(recipe, &self.stats, self.layers.as_ref());
        for p in &est.parts {
            summary.push_str(&format!(
                "; estimated time part {} = {}\n",
                one_line(&p.name),
                hms(p.times.planned)
            ));
        }
        summary.push_str(&format!(
            "; time at the G-code's speeds (distance / speed) = {}\n; time lost to acceleration and corners = {}\n; time lost to speed limits = {}\n; planner: {}\n",
            hms(est.total.ideal),
            hms(est.total.lost_to_acceleration()),
            hms(est.total.lost_to_speed_limits()),
            limits.describe()
        ));
        self.stats.estimate = est;
        self.text(&summary).map_err(io)?;
        self.s.flush().map_err(io)?;
        Ok((self.s, self.stats))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyse::planner::Progress;

    /// The text with its progress lines put in is the same whatever the
    /// size of the pieces asked for: each line before its offset, a line
    /// at the end of the text after it, the text whole.
    #[test]
    fn progress_lines_go_in_at_their_offsets_whatever_the_pieces() {
        let text: &[u8] = b"G1 X1\nG1 X2\nG1 X3\nG1 X4\n";
        let at = |percent: u32, minutes_left: u64| Progress {
            percent,
            minutes_left,
        };
        let lines = [
            (0, at(0, 3)),
            (12, at(50, 1)),
            (12, at(60, 1)),
            (24, at(100, 0)),
        ];
        let dialect = Dialect {
            flavor: crate::machine::Flavor::Marlin,
            object_labels: false,
            prusa_8bit: false,
        };
        let whole = |want: usize| {
            let mut copy = WithProgress {
                text,
                lines: &lines,
                next: 0,
                at: 0,
                dialect,
                header: b"; header\n".to_vec(),
                line: crate::base::format::Chunk::new(),
            };
            let (mut out, mut buf) = (Vec::new(), Vec::new());
            loop {
                buf.clear();
                let more = copy.fill(&mut buf, want).unwrap();
                out.extend_from_slice(&buf);
                if !more {
                    return String::from_utf8(out).unwrap();
                }
            }
        };
        let expected = "; header\nM73 P0 R3\nG1 X1\nG1 X2\nM73 P50 R1\nM73 P60 R1\nG1 X3\nG1 X4\nM73 P100 R0\n";
        for want in [1, 2, 5, 7, 12, 13, 1 << 20] {
            assert_eq!(whole(want), expected, "pieces of {want} bytes");
        }
    }
}
