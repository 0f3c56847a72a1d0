//! G-code p3dp did not write itself, held to the machine's limits as the
//! firmware will read it: a profile's start and end G-code (expanded) and
//! a recipe's own commands. Each line goes through the one reader
//! ([`crate::machine::firmware::read`]: the firmware's own parser rules —
//! the last of a repeated parameter, `M 104` as `M104`, `M104.1` as
//! `M104` on Marlin, letters in quotes, a checksum), then through the
//! firmware's state ([`crate::machine::firmware::State`]) so that a
//! relative move is checked where it takes the head.
//!
//! - Temperatures: every value a line gives a heater (each of a repeated
//!   word, and `R`, `B` besides `S`) at most the material's and the
//!   printer's maxima (the material's own temperature may be higher).
//! - Moves inside the machine's travel envelope (the bed grown by
//!   `envelope.margin`, never below the bed but for `envelope.below_bed`),
//!   feeds at most `max_speed`; a repeated axis word whose values differ
//!   is refused (firmwares differ on which counts); after homing or
//!   another of the firmware's own moves the position is unknown, and the
//!   relative moves from it may span no more than the machine is wide.
//! - Filament: at most [`FEED_MAX`] mm fed or pulled back by one move or
//!   in place at once (the start G-code's E counted from 0, as a printer
//!   starts; the end G-code's from the print's total).
//! - Settings (accelerations, limits, corners, pressure advance, input
//!   shaping, flow and speed factors) within the machine's limits, which
//!   the planner and the stats then follow.
//! - A command that shifts the coordinates, changes the firmware's limits
//!   or stored settings, updates or restarts it, or one p3dp does not know
//!   ([`vocabulary`]), is refused by name.
//!
//! A recipe's own command ([`Policy::Raw`]) may set, wait, pause and talk,
//! never move the head or the filament nor change how they are read: p3dp
//! writes those itself.

pub(crate) mod vocabulary;

use glam::DVec3;

use crate::base::error::{Error, Result};
use crate::base::format::fmt_num;
use crate::base::gcode::lex::{Code, Line, Value};
use crate::base::gcode::{Command, Heater, Setting, Verbatim};
use crate::generate::model::Recipe;
use crate::machine::firmware::{self, State};
use crate::machine::limits::{
    ACCELERATION_MAX, CHAMBER_TEMP_MAX, CORNER_SPEED_MAX, DWELL_MAX, FEED_MAX,
    JUNCTION_DEVIATION_MAX, PRESSURE_ADVANCE_MAX, RETRACTION_MAX, SHAPER_FREQUENCY_MAX, SPEED_MAX,
};
use crate::machine::{Bed, Extrusion, Flavor, Material, Printer};
use vocabulary::{Kind, Only};

/// Where the head is when the G-code starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Start {
    /// Unknown (the start G-code: the printer was just switched on, or
    /// finished another print).
    Unknown,
    /// At this machine point, E read as the printer's `extrusion` says and
    /// at this total (the end G-code: the print's last point and filament).
    At(DVec3, f64),
}

/// How much a line may do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Policy {
    /// A profile's start or end G-code: moves within the envelope, the
    /// firmware's own motion, settings.
    Frame,
    /// A recipe's own command between its strings: settings, waits,
    /// pauses and messages only.
    Raw,
}

/// The limits lines are held to.
struct Limits {
    nozzle: (f64, String),
    bed: f64,
    /// Fastest feed, mm/s.
    feed: f64,
    /// Fastest Z feed, mm/s.
    z_feed: f64,
    /// Highest acceleration, mm/s².
    accel: f64,
    bed_shape: Bed,
    /// X and Y the head may reach, machine mm.
    reach: [[f64; 2]; 2],
    margin: f64,
    below: f64,
    max_z: f64,
}

impl Limits {
    fn of(p: &Printer, m: &Material) -> Limits {
        let nozzle = if m.max_nozzle_temp <= p.max_nozzle_temp {
            (
                m.max_nozzle_temp,
                format!("the material {}'s max_nozzle_temp", m.name),
            )
        } else {
            (
                p.max_nozzle_temp,
                "the printer's max_nozzle_temp".to_string(),
            )
        };
        // the recipe's own temperatures are its checks' business (nozzle-temp
        // and bed-temp: errors only --force passes); the profile's G-code may
        // set them, and nothing hotter
        let nozzle = if m.nozzle_temp > nozzle.0 {
            (
                m.nozzle_temp,
                format!("the material {}'s nozzle_temp", m.name),
            )
        } else {
            nozzle
        };
        let l = p.limits();
        let accel = l
            .max_acceleration
            .max(l.travel_acceleration)
            .max(l.retract_acceleration)
            .min(ACCELERATION_MAX);
        Limits {
            nozzle,
            bed: p.max_bed_temp.max(m.bed_temp),
            feed: p.max_speed,
            z_feed: l.max_z_velocity.unwrap_or(p.max_speed),
            accel,
            bed_shape: p.bed,
            reach: {
                let (bmin, bmax) = p.bed.extent();
                [0, 1].map(|k| p.envelope.reach(k, bmin[k], bmax[k]))
            },
            margin: p.envelope.margin,
            below: p.envelope.below_bed,
            max_z: p.bed.max_z(),
        }
    }

    /// How far the head may travel along each axis: the envelope's widths.
    fn span(&self) -> [f64; 3] {
        let [x, y] = self.reach;
        [
            x[1] - x[0],
            y[1] - y[0],
            self.max_z + self.margin + self.below,
        ]
    }
}

/// The lines' state: the firmware's, and what the checks add to it.
struct Checker {
    flavor: Flavor,
    policy: Policy,
    lim: Limits,
    st: State,
    /// Per axis whose position is unknown: the relative moves' sum since it
    /// became unknown, and the least and most of that sum so far.
    drift: [(f64, f64, f64); 3],
    /// Per axis whose coordinates Klipper's `SET_KINEMATIC_POSITION`
    /// redefined (until the axis is homed): the coordinate of the point
    /// where the drift is 0, so that an absolute move's drift is its
    /// coordinate less this (see [`Checker::kinematic_position`]).
    shifted: [Option<f64>; 3],
    /// Filament fed in place since the head last moved, mm.
    in_place: f64,
}

/// Checks every line of `text` (the expanded `key` of `recipe`'s profile)
/// from `start`; the first line at fault is an error naming it. The lines
/// as they will be written, each with what the firmware reads in it.
pub(crate) fn check(key: &str, text: &str, recipe: &Recipe, start: Start) -> Result<Vec<Verbatim>> {
    let p = &recipe.printer;
    let mut lim = Limits::of(p, &recipe.material);
    // the maker's own start sequence may flush and purge hotter than the
    // print, up to what the hot end takes; the print starts within the
    // material's limit (checked after the last line)
    let material = lim.nozzle.clone();
    let maker = p.maker_temperatures && matches!(start, Start::Unknown);
    if maker && p.max_nozzle_temp > lim.nozzle.0 {
        lim.nozzle = (
            p.max_nozzle_temp,
            "the printer's max_nozzle_temp (the maker's own sequence: maker_temperatures)".into(),
        );
    }
    let mut c = Checker::new(p.flavor, Policy::Frame, lim);
    if let Start::At(q, e) = start {
        c.st = State::at(p.flavor, q.to_array());
        let relative = p.extrusion == Extrusion::Relative;
        c.st.apply(&Command::RelativeE(relative));
        c.st.e = if relative { 0.0 } else { e };
    }
    let body = text.strip_suffix('\n').unwrap_or(text);
    if body.is_empty() {
        return Ok(Vec::new());
    }
    let mut out = Vec::new();
    let mut last_nozzle = None;
    for (k, line) in body.split('\n').enumerate() {
        let place = format!("{key} line {}", k + 1);
        crate::base::safe_text::check_gcode_line(&place, line)?;
        let shown = |why: String| Error::input(&place, format!("`{}`: {why}", line.trim()));
        let read = firmware::read(p.flavor, line).map_err(shown)?;
        c.line(&read.line, &read.commands).map_err(shown)?;
        for cmd in &read.commands {
            if let Command::Set(Setting::Temperature {
                heater: Heater::Nozzle(_),
                celsius,
                ..
            }) = cmd
            {
                last_nozzle = Some((*celsius, k, line));
            }
        }
        out.push(Verbatim {
            text: line.to_string(),
            commands: read.commands,
        });
    }
    if let Some(why) = c.still_shifted() {
        return Err(Error::input(
            format!("{key} line {}", body.split('\n').count()),
            why,
        ));
    }
    if let (true, Some((t, k, line))) = (maker, last_nozzle) {
        if t > material.0 {
            return Err(Error::input(
                format!("{key} line {}", k + 1),
                format!(
                    "`{}`: the print would start at {} °C, above the limit {} °C ({}); the maker's sequence may flush hotter, but must leave the nozzle where the material prints",
                    line.trim(),
                    fmt_num(t),
                    fmt_num(material.0),
                    material.1
                ),
            ));
        }
    }
    Ok(out)
}

/// Checks a recipe's own command `text` (one line) for printer `p` and
/// material `m` ([`Policy::Raw`]): what the firmware reads in it, or why
/// it is refused.
pub(crate) fn command(
    text: &str,
    p: &Printer,
    m: &Material,
) -> std::result::Result<Verbatim, String> {
    if let Some(c) = text.chars().find(|&c| crate::base::safe_text::is_unsafe(c)) {
        return Err(format!(
            "the command holds {c:?}; expected one line of printable text (a line break would start a command of its own)"
        ));
    }
    let read = firmware::read(p.flavor, text)?;
    if read.line.code.is_none() {
        return Err("an empty command; expected a G-code such as M600".into());
    }
    let mut c = Checker::new(p.flavor, Policy::Raw, Limits::of(p, m));
    c.line(&read.line, &read.commands)?;
    Ok(Verbatim {
        text: text.trim().to_string(),
        commands: read.commands,
    })
}

/// Checks a `set` step's or command's setting for printer `p` and material `m`: a
/// command the printer's firmware has (`write::refusal`), its values within
/// the limits a recipe's own command is held to ([`Policy::Raw`]).
pub(crate) fn setting(s: &Setting, p: &Printer, m: &Material) -> std::result::Result<(), String> {
    let d = firmware::Dialect {
        flavor: p.flavor,
        object_labels: false,
        prusa_8bit: false,
    };
    if let Some(why) = firmware::write::refusal(d, &Command::Set(*s)) {
        return Err(why);
    }
    Checker::new(p.flavor, Policy::Raw, Limits::of(p, m)).setting(s)
}

impl Checker {
    fn new(flavor: Flavor, policy: Policy, lim: Limits) -> Checker {
        Checker {
            flavor,
            policy,
            lim,
            // a printer starts at E = 0, and the start G-code that purges
            // in absolute E (without `G92 E0`) counts on it; whatever a
            // firmware keeps from a print before, each feed is bounded
            st: State::new(flavor),
            drift: [(0.0, 0.0, 0.0); 3],
            shifted: [None; 3],
            in_place: 0.0,
        }
    }

    /// One line: every value it gives checked, then each thing it does.
    fn line(&mut self, l: &Line, commands: &[Command]) -> std::result::Result<(), String> {
        let Some(code) = &l.code else { return Ok(()) };
        self.all_values(code, l)?;
        if commands.iter().all(|c| matches!(c, Command::Other(_))) {
            if let Some(c) = commands.first() {
                return self.other(code, l, c);
            }
        }
        for c in commands {
            self.command(c, l)?;
        }
        Ok(())
    }

    /// The values the firmware might use, whichever of a repeated word it
    /// takes: feeds, and every temperature word of a heating command.
    fn all_values(&self, code: &Code, l: &Line) -> std::result::Result<(), String> {
        if (0..=3).any(|n| code.is(b'G', n)) {
            for f in l.numbers("F")? {
                feed(f, &self.lim)?;
            }
            for axis in ["X", "Y", "Z", "E", "I", "J"] {
                let v = l.numbers(axis)?;
                if v.windows(2).any(|w| w[0] != w[1]) {
                    return Err(format!(
                        "{axis} is given {} times with different values: firmwares differ on which counts; expected it once",
                        v.len()
                    ));
                }
            }
        }
        let heats: &[(&str, Heater)] = match code {
            c if c.is(b'M', 104) || c.is(b'M', 109) => &[
                ("S", Heater::Nozzle(0)),
                ("R", Heater::Nozzle(0)),
                ("B", Heater::Nozzle(0)),
            ],
            c if c.is(b'M', 140) || c.is(b'M', 190) => &[("S", Heater::Bed), ("R", Heater::Bed)],
            c if c.is(b'M', 141) || c.is(b'M', 191) => {
                &[("S", Heater::Chamber), ("R", Heater::Chamber)]
            }
            c if c.is(b'G', 10) && self.flavor == Flavor::Reprap => {
                &[("S", Heater::Nozzle(0)), ("R", Heater::Nozzle(0))]
            }
            _ => &[],
        };
        for (key, h) in heats {
            for t in l.numbers(key)? {
                temperature(*h, t, &self.lim)?;
            }
        }
        if matches!(code, Code::Name(_)) || self.flavor == Flavor::Klipper {
            self.named_temperatures(l)?;
        }
        Ok(())
    }

    /// A named command's temperature words: any key holding `TEMP`, and
    /// `BED`, `EXTRUDER`, `HOTEND`, `NOZZLE`, `CHAMBER` with a number (a
    /// macro's `PRINT_START BED=60 EXTRUDER=215`), Klipper's `TARGET`,
    /// `MINIMUM`, `MAXIMUM` of the heater its `HEATER`/`SENSOR` names.
    fn named_temperatures(&self, l: &Line) -> std::result::Result<(), String> {
        let heater_of = |s: &str| {
            let s = s.to_ascii_uppercase();
            if s.contains("BED") {
                Heater::Bed
            } else if s.contains("CHAMBER") {
                Heater::Chamber
            } else {
                Heater::Nozzle(0)
            }
        };
        let named = l.word("HEATER").or_else(|| l.word("SENSOR"));
        for p in &l.params {
            let k = p.key.as_str();
            let plain = matches!(k, "BED" | "EXTRUDER" | "HOTEND" | "NOZZLE" | "CHAMBER");
            let target = matches!(k, "TARGET" | "MINIMUM" | "MAXIMUM") && named.is_some();
            let temp = k.contains("TEMP");
            if !(plain || target || temp) {
                continue;
            }
            let heater = if target {
                heater_of(named.unwrap_or(""))
            } else {
                heater_of(k)
            };
            match &p.value {
                Value::Number(t) => temperature(heater, *t, &self.lim)?,
                // one per extruder, as an IDEX macro takes them (`215,215`);
                // a numbered macro's `bedTemp=60` read as Klipper splits a
                // traditional command's words (`BEDTEMP` `=60`)
                Value::Text(t) if temp || target => {
                    let each: Option<Vec<f64>> = t
                        .trim_start_matches('=')
                        .split(',')
                        .map(|v| v.trim().parse::<f64>().ok())
                        .collect();
                    let Some(each) = each else {
                        return Err(format!("cannot read `{k}`'s value `{t}` as a temperature"));
                    };
                    for t in each {
                        temperature(heater, t, &self.lim)?;
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// A line whose command has no typed meaning: what the vocabulary says.
    fn other(&mut self, code: &Code, l: &Line, c: &Command) -> std::result::Result<(), String> {
        let shown = code.shown();
        if (code.is(b'G', 2) || code.is(b'G', 3)) && l.has("R") {
            return Err("an arc given by its radius (R); p3dp checks arcs given by I and J".into());
        }
        if let (Code::Name(_), Policy::Raw) = (code, self.policy) {
            if self.flavor != Flavor::Klipper {
                return Err(format!(
                    "`{shown}` is not a command {} firmware runs; expected an M-code (M600, M117 …) or G4",
                    self.flavor.display_name()
                ));
            }
        }
        if self.flavor == Flavor::Klipper
            && self.policy == Policy::Frame
            && matches!(code, Code::Name(n) if n == "SET_KINEMATIC_POSITION")
        {
            return self.kinematic_position(l);
        }
        let Some(kind) = vocabulary::kind(self.flavor, code) else {
            return Err(format!(
                "`{shown}` is a command p3dp cannot check on {} firmware; expected moves (G0–G3), dwell (G4), units (G21), modes (G90, G91, M82, M83, G92 E), homing or probing (G28, G29), temperatures, fans, or a command its table of known commands names (docs/printers.md)",
                self.flavor.display_name()
            ));
        };
        match (kind, self.policy) {
            (Kind::Refused(why), _) => Err(format!("`{shown}` is refused: it {why}")),
            (Kind::RefusedUnless(sets, only, why), policy) => {
                let resting = only == Only::Resting;
                for set in sets {
                    let listed = |k: &str| set.iter().any(|(w, _)| *w == k);
                    // a resting state: the maker's own line, no other word
                    let mut same = !resting
                        || (policy == Policy::Frame && l.params.iter().all(|p| listed(&p.key)));
                    for (key, v) in *set {
                        same &= l.number(key)?.is_some_and(|g| (g - v).abs() <= 1e-6);
                    }
                    if same {
                        if resting {
                            self.unknown_position();
                        }
                        return Ok(());
                    }
                }
                let shown_sets: Vec<String> = sets
                    .iter()
                    .map(|set| {
                        let words: Vec<String> = set
                            .iter()
                            .map(|(k, v)| match only {
                                Only::Assumed => format!("{k}{}", fmt_num(*v)),
                                Only::Resting => format!("{k}{v}"),
                            })
                            .collect();
                        format!("`{} {}`", code.shown(), words.join(" "))
                    })
                    .collect();
                Err(match only {
                    Only::Assumed => format!(
                        "`{shown}` is refused: it {why} (accepted as {}, which sets what p3dp assumes)",
                        shown_sets.join(" or ")
                    ),
                    Only::Resting => format!(
                        "`{shown}` is refused: it {why}; p3dp accepts only the maker's own {} in a profile's start or end G-code",
                        shown_sets.join(" or ")
                    ),
                })
            }
            (Kind::FrameOnly(why), Policy::Raw) => Err(format!("`{shown}` is refused: it {why}")),
            (Kind::Inert | Kind::FrameOnly(_), _) => Ok(()),
            (Kind::Trim(key, max), _) => {
                for v in l.numbers(key)? {
                    if !(v.is_finite() && v.abs() <= max) {
                        return Err(format!(
                            "`{shown}` offsets the coordinates by {key} {} mm; expected at most {} mm either way (a plate's trim)",
                            fmt_num(v),
                            fmt_num(max)
                        ));
                    }
                }
                Ok(())
            }
            (Kind::MovesAndHeats(keys), Policy::Frame) => {
                for (key, h) in keys {
                    for t in l.numbers(key)? {
                        temperature(*h, t, &self.lim)?;
                    }
                }
                self.firmware_reach(l)?;
                self.st.apply(c);
                self.unknown_position();
                Ok(())
            }
            (Kind::Heats(keys), Policy::Frame) => {
                for (key, h) in keys {
                    // M303 E-1 tunes the bed
                    let h = if code.is(b'M', 303) && l.number("E")? == Some(-1.0) {
                        Heater::Bed
                    } else {
                        *h
                    };
                    for t in l.numbers(key)? {
                        temperature(h, t, &self.lim)?;
                    }
                }
                if code.is(b'G', 26) {
                    self.unknown_position();
                }
                Ok(())
            }
            (Kind::Firmware, Policy::Frame) => {
                self.firmware_reach(l)?;
                self.st.apply(c);
                self.unknown_position();
                Ok(())
            }
            (Kind::Firmware, Policy::Raw) if returns_the_head(self.flavor, code) => Ok(()),
            (Kind::Heats(_) | Kind::MovesAndHeats(_), Policy::Raw) => Err(format!(
                "`{shown}` is refused: it heats on its own between p3dp's strings; expected nozzle_temp or bed_temp, which are checked"
            )),
            (Kind::Firmware, Policy::Raw) => Err(format!(
                "`{shown}` is refused: it moves the head, and p3dp writes the head's moves itself"
            )),
        }
    }

    /// A firmware motion's `X` and `Y` words in absolute mode: where it
    /// takes the head (a park, a purge's start, a probed area's corner, a
    /// filament change's travel point), each inside the envelope.
    fn firmware_reach(&self, l: &Line) -> std::result::Result<(), String> {
        if self.st.relative_xyz {
            return Ok(());
        }
        for (k, axis) in ["X", "Y"].iter().enumerate() {
            for v in l.numbers(axis)? {
                within(k, &axis.to_ascii_lowercase(), v, &self.lim)?;
            }
        }
        Ok(())
    }

    /// The position, unknown from here on.
    fn unknown_position(&mut self) {
        self.st.pos = [None; 3];
        for k in 0..3 {
            self.drift[k] = match self.shifted[k] {
                // the firmware moved the head in redefined coordinates: the
                // drift's bounds stay (an absolute move counts from the
                // same point), its sum is lost for relative moves
                Some(_) => (f64::NAN, self.drift[k].1, self.drift[k].2),
                None => (0.0, 0.0, 0.0),
            };
        }
    }

    /// Klipper's `SET_KINEMATIC_POSITION` (its `force_move` module): the
    /// head does not move, Klipper takes it to be where the words say
    /// (an axis not named keeps its position), and its soft limits then
    /// hold in those coordinates. A maker sets `Z=0` where its probe just
    /// touched the bed. p3dp cannot know where the redefined coordinates
    /// lie in the machine: each named axis's position is forgotten, and
    /// its moves from here count as moves from an unknown position (their
    /// span at most the machine's), an absolute one by how far it goes
    /// from the coordinate given, until a `G28` homes the axis again.
    fn kinematic_position(&mut self, l: &Line) -> std::result::Result<(), String> {
        for p in &l.params {
            if !matches!(p.key.as_str(), "X" | "Y" | "Z") {
                return Err(format!(
                    "`SET_KINEMATIC_POSITION {}=…` is refused: p3dp follows its X, Y and Z words only",
                    p.key
                ));
            }
        }
        for (k, axis) in ["X", "Y", "Z"].iter().enumerate() {
            let Some(g) = l.number(axis)? else { continue };
            if !g.is_finite() {
                return Err(format!("cannot read its {axis} value"));
            }
            // a second redefinition: its point is the head's, at the
            // drift's sum from the first one's (unknown after the
            // firmware's own motion: the bounds start again)
            let d = self.drift[k];
            self.drift[k] = match self.shifted[k] {
                Some(_) if d.0.is_finite() => d,
                _ => (0.0, 0.0, 0.0),
            };
            self.shifted[k] = Some(g - self.drift[k].0);
            self.st.pos[k] = None;
        }
        Ok(())
    }

    /// The error when coordinates are still redefined at the end of a
    /// profile's G-code: the print's own moves would land elsewhere.
    fn still_shifted(&self) -> Option<String> {
        let k = (0..3).find(|&k| self.shifted[k].is_some())?;
        Some(format!(
            "SET_KINEMATIC_POSITION redefined {} and no G28 homes it again before the G-code ends: p3dp's moves would land where it cannot check",
            ["X", "Y", "Z"][k]
        ))
    }

    /// One typed command.
    fn command(&mut self, c: &Command, l: &Line) -> std::result::Result<(), String> {
        let raw = self.policy == Policy::Raw;
        let moves_refused = || {
            Err::<(), String>(
                "moves the head or the filament, or changes how they are read: p3dp writes those itself (a recipe's own command may set, wait, pause and talk)".into(),
            )
        };
        match c {
            Command::Move(_) | Command::Arc(_) if raw => moves_refused(),
            Command::Move(m) => self.linear(c, m.to),
            Command::Arc(a) => self.arc(c, a),
            Command::Dwell { ms } => {
                if !(ms.is_finite() && *ms <= DWELL_MAX * 1000.0) {
                    return Err(format!(
                        "a dwell of {} s; expected at most {DWELL_MAX} s",
                        fmt_num(ms / 1000.0)
                    ));
                }
                Ok(())
            }
            Command::Set(s) => self.setting(s),
            Command::FirmwareRetract { .. }
            | Command::RelativeXyz(_)
            | Command::RelativeE(_)
            | Command::SetPosition { .. }
            | Command::Home { .. }
            | Command::Inches(_)
                if raw =>
            {
                moves_refused()
            }
            Command::Tool(n) if raw => Err(format!(
                "`T{n}` is refused: a tool change moves the head and swaps the filament the checks were made for"
            )),
            Command::Inches(true) => Err("G20 switches to inches; p3dp checks millimetres only".into()),
            Command::SetPosition { axes, .. } => {
                if let Some(k) = (0..3).find(|&k| axes[k].is_some()) {
                    let axis = ["X", "Y", "Z"][k];
                    return Err(if l.params.is_empty() {
                        "a G92 without words sets every axis to 0 on this firmware: p3dp cannot check the moves after it (G92 E alone is fine)".into()
                    } else {
                        format!(
                            "G92 {axis} redefines the coordinates: p3dp cannot check the moves after it (G92 E alone is fine)"
                        )
                    });
                }
                self.st.apply(c);
                Ok(())
            }
            Command::Home { axes } => {
                for (k, &homed) in axes.iter().enumerate() {
                    if homed {
                        self.st.pos[k] = None;
                        self.drift[k] = (0.0, 0.0, 0.0);
                        self.shifted[k] = None;
                    }
                }
                Ok(())
            }
            Command::Tool(_) => {
                self.unknown_position();
                Ok(())
            }
            Command::RelativeXyz(_) | Command::RelativeE(_) | Command::Inches(false) => {
                self.st.apply(c);
                Ok(())
            }
            Command::FirmwareRetract { .. }
            | Command::Progress { .. }
            | Command::Object(_)
            | Command::Pause => Ok(()),
            Command::Other(_) => Ok(()),
        }
    }

    /// A `G0`/`G1`: where it takes the head, each axis inside the
    /// envelope, and the filament it feeds.
    fn linear(&mut self, c: &Command, to: [Option<f64>; 3]) -> std::result::Result<(), String> {
        if self.st.inches {
            return Err("a move in inches; p3dp checks millimetres only".into());
        }
        let before = self.st.pos;
        let span = self.lim.span();
        for (k, axis) in ["X", "Y", "Z"].iter().enumerate() {
            let Some(v) = to[k] else { continue };
            if !v.is_finite() {
                return Err(format!("cannot read its {axis} value"));
            }
            let shifted = self.shifted[k];
            if (self.st.relative_xyz && before[k].is_none()) || shifted.is_some() {
                let d = &mut self.drift[k];
                match shifted {
                    Some(g) if !self.st.relative_xyz => d.0 = v - g,
                    _ if d.0.is_nan() => return Err(lost_drift(axis)),
                    _ => d.0 += v,
                }
                d.1 = d.1.min(d.0);
                d.2 = d.2.max(d.0);
                if d.2 - d.1 > span[k] + 1e-9 {
                    let moves = match shifted {
                        Some(_) => "moves since SET_KINEMATIC_POSITION redefined it",
                        None => "relative moves since the position was last known",
                    };
                    return Err(format!(
                        "the {axis} {moves} span {} mm, more than the machine is wide ({} mm)",
                        fmt_num(d.2 - d.1),
                        fmt_num(span[k])
                    ));
                }
            }
        }
        let motion = self.st.apply(c);
        for k in 0..3 {
            if self.shifted[k].is_some() {
                self.st.pos[k] = None;
            }
        }
        let firmware::Motion::Line { to, de, .. } = motion else {
            return Ok(());
        };
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            if let (Some(v), None) = (to[k], self.shifted[k]) {
                within(k, axis, v, &self.lim)?;
            }
        }
        self.within_circle(to)?;
        self.filament(de, to != before)
    }

    /// Filament fed (or pulled back) by one move: at most [`FEED_MAX`] mm,
    /// and in place at most that much in a row.
    fn filament(&mut self, de: f64, moved: bool) -> std::result::Result<(), String> {
        if !de.is_finite() || de.abs() > FEED_MAX {
            return Err(format!(
                "feeds {} mm of filament in one move; expected at most {FEED_MAX} mm",
                fmt_num(de)
            ));
        }
        if moved {
            self.in_place = 0.0;
            return Ok(());
        }
        self.in_place += de.max(0.0);
        if self.in_place > FEED_MAX {
            return Err(format!(
                "feeds {} mm of filament in place; expected at most {FEED_MAX} mm without moving",
                fmt_num(self.in_place)
            ));
        }
        Ok(())
    }

    /// A round bed: a known XY inside its circle grown by the margin.
    fn within_circle(&self, to: [Option<f64>; 3]) -> std::result::Result<(), String> {
        if let (Bed::Circle { diameter, .. }, Some(x), Some(y)) = (self.lim.bed_shape, to[0], to[1])
        {
            let r = x.hypot(y);
            if r > diameter / 2.0 + self.lim.margin + 1e-9 {
                return Err(format!(
                    "({x}, {y}) is {} mm from the centre, outside the machine's travel envelope (the bed's radius {} mm grown by envelope.margin {} mm)",
                    fmt_num(r),
                    diameter / 2.0,
                    self.lim.margin
                ));
            }
        }
        Ok(())
    }

    /// `G2`/`G3` with I J: the whole sweep inside the envelope.
    fn arc(&mut self, c: &Command, a: &crate::base::gcode::Arc) -> std::result::Result<(), String> {
        let (Some(x0), Some(y0)) = (self.st.pos[0], self.st.pos[1]) else {
            if self.st.relative_xyz {
                return self.relative_arc(c, a);
            }
            return Err("an arc from an unknown position; p3dp cannot check where it goes".into());
        };
        let mut probe = self.st.clone();
        let firmware::Motion::Line { to, .. } =
            probe.apply(&Command::Move(crate::base::gcode::Move {
                travel: false,
                to: a.to,
                e: None,
                feed: None,
            }))
        else {
            return Ok(());
        };
        let (x1, y1) = (to[0].unwrap_or(x0), to[1].unwrap_or(y0));
        let pts = crate::base::gcode::arc_extremes([x0, y0], [x1, y1], a.ij, a.ccw);
        for [x, y] in pts {
            within(0, "x", x, &self.lim).map_err(|e| format!("the arc's sweep: {e}"))?;
            within(1, "y", y, &self.lim).map_err(|e| format!("the arc's sweep: {e}"))?;
            self.within_circle([Some(x), Some(y), None])
                .map_err(|e| format!("the arc's sweep: {e}"))?;
        }
        let before = self.st.pos;
        let firmware::Motion::Arc { to, de, .. } = self.st.apply(c) else {
            return Ok(());
        };
        if let Some(z) = Some(to[2]) {
            within(2, "z", z, &self.lim)?;
        }
        self.filament(de, to.map(Some) != before)
    }

    /// A relative `G2`/`G3` from a position unknown on X or Y (Bambu's
    /// nozzle wiped in a circle after homing): on a known axis its sweep is
    /// held to the envelope; on an unknown one the sweep's offsets from
    /// where it starts count in the relative moves' span, as a line's do.
    fn relative_arc(
        &mut self,
        c: &Command,
        a: &crate::base::gcode::Arc,
    ) -> std::result::Result<(), String> {
        let pos = self.st.pos;
        let from = [pos[0].unwrap_or(0.0), pos[1].unwrap_or(0.0)];
        let to = [0, 1].map(|k| from[k] + a.to[k].unwrap_or(0.0));
        if !(to.iter().all(|v| v.is_finite()) && a.ij.iter().all(|v| v.is_finite())) {
            return Err("cannot read its X, Y, I or J value".into());
        }
        let pts = crate::base::gcode::arc_extremes(from, to, a.ij, a.ccw);
        let span = self.lim.span();
        for (k, axis) in ["x", "y"].iter().enumerate() {
            if pos[k].is_some() {
                for p in &pts {
                    within(k, axis, p[k], &self.lim)
                        .map_err(|e| format!("the arc's sweep: {e}"))?;
                }
                continue;
            }
            let lo = pts
                .iter()
                .map(|p| p[k] - from[k])
                .fold(f64::INFINITY, f64::min);
            let hi = pts
                .iter()
                .map(|p| p[k] - from[k])
                .fold(f64::NEG_INFINITY, f64::max);
            let d = &mut self.drift[k];
            if d.0.is_nan() {
                return Err(lost_drift(&axis.to_ascii_uppercase()));
            }
            d.1 = d.1.min(d.0 + lo);
            d.2 = d.2.max(d.0 + hi);
            d.0 += to[k] - from[k];
            if d.2 - d.1 > span[k] + 1e-9 {
                return Err(format!(
                    "the relative {} moves since the position was last known span {} mm, more than the machine is wide ({} mm)",
                    axis.to_ascii_uppercase(),
                    fmt_num(d.2 - d.1),
                    fmt_num(span[k])
                ));
            }
        }
        let dz = a.to[2].unwrap_or(0.0);
        if pos[2].is_none() {
            let d = &mut self.drift[2];
            if d.0.is_nan() {
                return Err(lost_drift("Z"));
            }
            d.0 += dz;
            d.1 = d.1.min(d.0);
            d.2 = d.2.max(d.0);
            if d.2 - d.1 > span[2] + 1e-9 {
                return Err(format!(
                    "the relative Z moves since the position was last known span {} mm, more than the machine is wide ({} mm)",
                    fmt_num(d.2 - d.1),
                    fmt_num(span[2])
                ));
            }
        }
        let de = match a.e {
            None => 0.0,
            Some(v) if self.st.e_relative() => v,
            Some(v) => v - self.st.e,
        };
        self.st.apply(c);
        if let Some(z) = self.st.pos[2] {
            within(2, "z", z, &self.lim)?;
        }
        self.filament(de, true)
    }

    /// A setting's values within the machine's limits.
    fn setting(&mut self, s: &Setting) -> std::result::Result<(), String> {
        let lim = &self.lim;
        let raw = self.policy == Policy::Raw;
        let within = |what: &str, v: f64, lo: f64, hi: f64, unit: &str| {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(format!(
                    "{what} of {} {unit}; expected {} to {} {unit}",
                    fmt_num(v),
                    fmt_num(lo),
                    fmt_num(hi)
                ))
            }
        };
        match *s {
            Setting::Temperature {
                heater, celsius, ..
            } => temperature(heater, celsius, lim),
            Setting::Fan { speed } => within("a fan speed", speed * 100.0, 0.0, 100.0, "%"),
            Setting::PressureAdvance { k } => {
                within("a pressure advance", k, 0.0, PRESSURE_ADVANCE_MAX, "s")
            }
            Setting::Acceleration {
                print,
                travel,
                retract,
            } => {
                for (what, v) in [("print", print), ("travel", travel), ("retract", retract)] {
                    if let Some(a) = v {
                        within(
                            &format!("a {what} acceleration (the printer's kinematics allow at most {} mm/s²)", fmt_num(lim.accel)),
                            a,
                            1.0,
                            lim.accel,
                            "mm/s²",
                        )?;
                    }
                }
                Ok(())
            }
            Setting::SpeedLimit { velocity } => within(
                "a speed limit (the printer's max_speed caps it)",
                velocity,
                1.0,
                lim.feed,
                "mm/s",
            ),
            Setting::SquareCornerVelocity(v) => {
                within("a square-corner velocity", v, 0.0, CORNER_SPEED_MAX, "mm/s")
            }
            Setting::JunctionDeviation(j) => {
                within("a junction deviation", j, 0.0, JUNCTION_DEVIATION_MAX, "mm")
            }
            Setting::Jerk(j) => within("a jerk", j, 0.0, CORNER_SPEED_MAX, "mm/s"),
            Setting::MinimumCruiseRatio(r) => within("a minimum cruise ratio", r, 0.0, 1.0, ""),
            Setting::InputShaper {
                frequency, damping, ..
            } => {
                for f in frequency.into_iter().flatten() {
                    within(
                        "an input shaper frequency",
                        f,
                        0.0,
                        SHAPER_FREQUENCY_MAX,
                        "Hz",
                    )?;
                }
                if let Some(d) = damping {
                    within("a damping ratio", d, 0.0, 1.0, "")?;
                }
                Ok(())
            }
            Setting::Flow(f) => {
                let hi = if raw { 1.5 } else { 1.0 };
                if !(f > 0.0 && f <= hi) {
                    return Err(format!(
                        "a flow factor of {} %: the strings would get {} the filament the checks were made for; expected above 0 and at most {} %",
                        fmt_num(f * 100.0),
                        if f > 1.0 { "more than" } else { "none of" },
                        fmt_num(hi * 100.0)
                    ));
                }
                Ok(())
            }
            Setting::Speed(f) => {
                if !(f.is_finite() && f > 0.0 && f <= 1.0) {
                    return Err(format!(
                        "a speed factor of {} % would run the moves after it faster than written; expected above 0 and at most 100",
                        fmt_num(f * 100.0)
                    ));
                }
                Ok(())
            }
            Setting::Retraction { length, speed } => {
                if let Some(l) = length {
                    within("a retraction length", l, 0.0, RETRACTION_MAX, "mm")?;
                }
                if let Some(v) = speed {
                    within("a retraction speed", v, 0.1, SPEED_MAX, "mm/s")?;
                }
                Ok(())
            }
            Setting::MaxAcceleration { axes } => {
                for (k, v) in axes.into_iter().enumerate() {
                    let Some(a) = v else { continue };
                    let hi = if k == 3 { ACCELERATION_MAX } else { lim.accel };
                    within(
                        &format!("a maximum {} acceleration", ["X", "Y", "Z", "E"][k]),
                        a,
                        1.0,
                        hi,
                        "mm/s²",
                    )?;
                }
                Ok(())
            }
            Setting::MaxFeedrate { axes } => {
                for (k, v) in axes.into_iter().enumerate() {
                    let Some(f) = v else { continue };
                    let hi = match k {
                        0 | 1 => lim.feed,
                        2 => lim.z_feed.max(1.0),
                        _ => SPEED_MAX,
                    };
                    if !(f.is_finite() && f > 0.0 && f <= hi + 1e-9) {
                        return Err(format!(
                            "sets the {} feed limit to {} mm/s, past the printer's {} {} mm/s",
                            ["X", "Y", "Z", "E"][k],
                            fmt_num(f),
                            if k == 2 { "Z speed" } else { "max_speed" },
                            fmt_num(hi)
                        ));
                    }
                }
                Ok(())
            }
        }
    }
}

/// Whether a firmware command returns the head where it found it (a
/// filament change or a pause parks and comes back): a recipe may ask for it.
fn returns_the_head(flavor: Flavor, code: &Code) -> bool {
    match code {
        Code::Number {
            letter: b'M',
            number,
            ..
        } => matches!(number, 600 | 601 | 602 | 125),
        Code::Name(n) => flavor == Flavor::Klipper && matches!(n.as_str(), "RESUME" | "M600"),
        _ => false,
    }
}

/// Heater `h` at `t` °C within the limits.
fn temperature(h: Heater, t: f64, lim: &Limits) -> std::result::Result<(), String> {
    match h {
        Heater::Nozzle(_) => {
            let (max, what) = &lim.nozzle;
            if !(t.is_finite() && t >= 0.0) {
                return Err(format!(
                    "a nozzle temperature of {t} °C; expected 0 to {max} °C"
                ));
            }
            if t > *max {
                return Err(format!(
                    "a nozzle temperature of {t} °C, above the limit {max} °C ({what})"
                ));
            }
            Ok(())
        }
        Heater::Bed => {
            if !(t.is_finite() && t >= 0.0 && t <= lim.bed) {
                return Err(format!(
                    "a bed temperature of {t} °C, outside 0 to {} °C (the printer's max_bed_temp, or the material's bed_temp if higher)",
                    lim.bed
                ));
            }
            Ok(())
        }
        Heater::Chamber => {
            if !(0.0..=CHAMBER_TEMP_MAX).contains(&t) {
                return Err(format!(
                    "a chamber temperature of {t} °C, outside 0 to {CHAMBER_TEMP_MAX} °C"
                ));
            }
            Ok(())
        }
    }
}

/// A feed `f` in mm/min at most the printer's `max_speed` (half a mm/min of
/// rounding allowed).
fn feed(f: f64, lim: &Limits) -> std::result::Result<(), String> {
    if !(f.is_finite() && f > 0.0) {
        return Err(format!("a feed of {f} mm/min; expected a positive number"));
    }
    if f > lim.feed * 60.0 + 0.5 {
        return Err(format!(
            "F{} is {} mm/s, faster than the printer's max_speed {} mm/s",
            fmt_num(f),
            fmt_num(f / 60.0),
            lim.feed
        ));
    }
    Ok(())
}

/// Axis `k` (named `axis`) at machine coordinate `v` inside the envelope.
/// A relative move on an axis `SET_KINEMATIC_POSITION` redefined, after
/// the firmware moved the head on its own.
fn lost_drift(axis: &str) -> String {
    format!(
        "a relative {axis} move after SET_KINEMATIC_POSITION redefined {axis} and the firmware moved the head: p3dp cannot bound where it goes; expected an absolute move or a G28 first"
    )
}

fn within(k: usize, axis: &str, v: f64, lim: &Limits) -> std::result::Result<(), String> {
    const EPS: f64 = 1e-9;
    if !v.is_finite() {
        return Err(format!("cannot read its {axis} value"));
    }
    if k == 2 {
        if v < -lim.below - EPS {
            return Err(format!(
                "z = {} mm is below the bed (the profile allows {} mm below it: envelope.below_bed)",
                fmt_num(v),
                lim.below
            ));
        }
        if v > lim.max_z + lim.margin + EPS {
            return Err(format!(
                "z = {} mm is above the machine's reach ({} mm: max_z grown by envelope.margin)",
                fmt_num(v),
                fmt_num(lim.max_z + lim.margin)
            ));
        }
        return Ok(());
    }
    let [lo, hi] = lim.reach[k];
    if v < lo - EPS || v > hi + EPS {
        let (bmin, bmax) = lim.bed_shape.extent();
        let why = if [bmin[k] - lim.margin, bmax[k] + lim.margin] == [lo, hi] {
            format!("the bed grown by envelope.margin {} mm", lim.margin)
        } else {
            format!("the profile's envelope.{axis}")
        };
        return Err(format!(
            "{axis} = {} mm is outside the machine's travel envelope ({axis} from {} to {} mm: {why})",
            fmt_num(v),
            fmt_num(lo),
            fmt_num(hi),
        ));
    }
    Ok(())
}
