//! A profile's own G-code (its start and end sequences, expanded) held to
//! the machine's limits, line by line, before anything is written:
//! temperatures at most the material's and the printer's maxima, feeds at
//! most the printer's `max_speed`, and every move inside the machine's
//! travel envelope (the bed grown by the profile's `envelope.margin`, never
//! below the bed but for `envelope.below_bed`, never metres away). Homing,
//! probing and levelling commands are allowed (the firmware moves within
//! its own limits; the head's position is unknown after them, and a
//! relative move from an unknown position may go no further than the
//! envelope is wide). A command that would make the moves after it
//! uncheckable (inches, redefined coordinates or offsets, an unknown G
//! command) is refused. A refusal names the key, the line, the line's text
//! and why.

use glam::DVec3;

use crate::base::error::{Error, Result};
use crate::base::format::fmt_num;
use crate::generate::model::Recipe;
use crate::machine::Bed;

/// Where the head is when the G-code starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Start {
    /// Unknown (the start G-code: the printer was just switched on, or
    /// finished another print).
    Unknown,
    /// At this machine point (the end G-code: the print's last point).
    At(DVec3),
}

/// The limits of one check.
struct Limits {
    nozzle: (f64, String),
    bed: f64,
    /// Fastest feed, mm/s.
    feed: f64,
    bed_shape: Bed,
    margin: f64,
    below: f64,
    max_z: f64,
}

/// The firmware's state as far as the lines so far tell it.
struct State {
    /// Machine position per axis, when known.
    pos: [Option<f64>; 3],
    /// `G91`: XYZ relative.
    relative: bool,
}

/// Checks every line of `text` (the expanded `key` of `recipe`'s profile)
/// from `start`; the first line at fault is an error naming it.
pub(crate) fn check(key: &str, text: &str, recipe: &Recipe, start: Start) -> Result<()> {
    let (p, m) = (&recipe.printer, &recipe.material);
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
    let lim = Limits {
        nozzle,
        bed: p.max_bed_temp.max(m.bed_temp),
        feed: p.max_speed,
        bed_shape: p.bed,
        margin: p.envelope.margin,
        below: p.envelope.below_bed,
        max_z: p.bed.max_z(),
    };
    let mut st = State {
        pos: match start {
            Start::Unknown => [None; 3],
            Start::At(q) => [Some(q.x), Some(q.y), Some(q.z)],
        },
        relative: false,
    };
    for (k, line) in text.split('\n').enumerate() {
        let place = format!("{key} line {}", k + 1);
        crate::base::safe_text::check_gcode_line(&place, line)?;
        st.line(line, &lim)
            .map_err(|why| Error::input(place, format!("`{}`: {why}", line.trim())))?;
    }
    Ok(())
}

/// One command: its letter and number (`G`, 1.0), or a named command
/// (Klipper's `SET_HEATER_TEMPERATURE`), and its parameters.
struct Command<'a> {
    letter: char,
    number: f64,
    name: &'a str,
    params: Vec<(String, f64)>,
    /// A named command's `KEY=VALUE` words as written.
    words: Vec<(&'a str, &'a str)>,
}

impl Command<'_> {
    fn get(&self, key: &str) -> Option<f64> {
        self.params
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|&(_, v)| v)
    }
}

/// M codes whose parameters are text (messages, file names, Prusa's model
/// checks): not read.
const TEXT_M: [f64; 13] = [
    0.0, 1.0, 16.0, 23.0, 28.0, 29.0, 30.0, 32.0, 33.0, 36.0, 117.0, 118.0, 115.0,
];

/// G codes that home, probe or level: allowed; the position is unknown after.
const HOMING_G: [f64; 13] = [
    28.0, 29.0, 30.0, 31.0, 32.0, 33.0, 34.0, 35.0, 80.0, 81.0, 12.0, 27.0, 61.0,
];

/// G codes that neither move nor change how moves are read.
const PLAIN_G: [f64; 8] = [4.0, 10.0, 11.0, 17.0, 18.0, 19.0, 21.0, 60.0];

/// M codes that change offsets or settings the moves after them depend on.
const OFFSET_M: [(f64, &str); 6] = [
    (92.0, "changes the steps per mm"),
    (206.0, "changes the home offsets"),
    (290.0, "babysteps the axes"),
    (428.0, "changes the home offsets"),
    (502.0, "resets every setting to the firmware's defaults"),
    (851.0, "changes the probe's offsets"),
];

/// M codes that move the head to a place the firmware keeps (filament
/// change, pause, park, load/unload, probe tests): allowed; the position
/// is unknown after.
const MOVING_M: [f64; 9] = [
    48.0, 125.0, 600.0, 601.0, 602.0, 603.0, 701.0, 702.0, 1002.0,
];

fn parse(line: &str) -> std::result::Result<Option<Command<'_>>, String> {
    let code = line.split(';').next().unwrap_or("").trim();
    // a line number, `N12 G1 …`
    let code = match code.strip_prefix(['N', 'n']) {
        Some(rest) if rest.starts_with(|c: char| c.is_ascii_digit()) => rest
            .trim_start_matches(|c: char| c.is_ascii_digit())
            .trim_start(),
        _ => code,
    };
    if code.is_empty() {
        return Ok(None);
    }
    let first = code.chars().next().unwrap_or(' ').to_ascii_uppercase();
    let rest = &code[1..];
    let num_len = rest
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(rest.len());
    if matches!(first, 'G' | 'M' | 'T') && num_len > 0 {
        let number: f64 = rest[..num_len]
            .parse()
            .map_err(|_| format!("cannot read the command `{}`", &code[..1 + num_len]))?;
        let mut cmd = Command {
            letter: first,
            number,
            name: "",
            params: Vec::new(),
            words: Vec::new(),
        };
        if first != 'M' || !TEXT_M.contains(&number) {
            cmd.params = words(&rest[num_len..]);
        }
        return Ok(Some(cmd));
    }
    // a named command (a Klipper macro): NAME KEY=VALUE …
    let mut parts = code.split_whitespace();
    let name = parts.next().unwrap_or("");
    let words: Vec<(&str, &str)> = parts.filter_map(|w| w.split_once('=')).collect();
    let params = words
        .iter()
        .map(|(k, v)| (k.to_string(), v.parse().unwrap_or(f64::NAN)))
        .collect();
    Ok(Some(Command {
        letter: ' ',
        number: 0.0,
        name,
        params,
        words,
    }))
}

/// `X10 Y-3.5 F1000` (spaces optional between words): letters with their
/// numbers; a quoted string or a word that is no number is skipped (the
/// commands checked below find their parameter missing, and say so).
fn words(s: &str) -> Vec<(String, f64)> {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i] as char;
        if c == '"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += 1;
            }
            i += 1;
            continue;
        }
        if !c.is_ascii_alphabetic() {
            i += 1;
            continue;
        }
        let start = i + 1;
        let mut j = start;
        while j < b.len() && (b[j].is_ascii_digit() || matches!(b[j], b'.' | b'-' | b'+')) {
            j += 1;
        }
        let text = &s[start..j];
        match text.parse::<f64>() {
            Ok(v) => out.push((c.to_ascii_uppercase().to_string(), v)),
            Err(_) if text.is_empty() => out.push((c.to_ascii_uppercase().to_string(), f64::NAN)),
            Err(_) => out.push((c.to_ascii_uppercase().to_string(), f64::NAN)),
        }
        i = j.max(i + 1);
    }
    out
}

impl State {
    fn line(&mut self, line: &str, lim: &Limits) -> std::result::Result<(), String> {
        let Some(cmd) = parse(line)? else {
            return Ok(());
        };
        match cmd.letter {
            'G' => self.g(&cmd, lim),
            'M' => self.m(&cmd, lim),
            'T' => Ok(()),
            _ => self.named(&cmd, lim),
        }
    }

    fn unknown_position(&mut self) {
        self.pos = [None; 3];
    }

    fn g(&mut self, cmd: &Command, lim: &Limits) -> std::result::Result<(), String> {
        let n = cmd.number;
        if let Some(f) = cmd.get("F") {
            feed(f, lim)?;
        }
        match n {
            _ if n == 0.0 || n == 1.0 => self.linear(cmd, lim),
            _ if n == 2.0 || n == 3.0 => self.arc(cmd, lim),
            _ if n == 90.0 => {
                self.relative = false;
                Ok(())
            }
            _ if n == 91.0 => {
                self.relative = true;
                Ok(())
            }
            _ if n == 92.0 => {
                for axis in ["X", "Y", "Z"] {
                    if cmd.get(axis).is_some() {
                        return Err(format!(
                            "G92 {axis} redefines the coordinates: p3dp cannot check the moves after it (G92 E alone is fine)"
                        ));
                    }
                }
                Ok(())
            }
            _ if n == 20.0 => Err("G20 switches to inches; p3dp checks millimetres only".into()),
            _ if n == 10.0 => nozzle_params(cmd, &["S", "R"], lim),
            _ if n == 28.0 && ["X", "Y", "Z"].iter().any(|a| cmd.get(a).is_some()) => {
                for (k, a) in ["X", "Y", "Z"].iter().enumerate() {
                    if cmd.get(a).is_some() {
                        self.pos[k] = None;
                    }
                }
                Ok(())
            }
            _ if HOMING_G.contains(&n.trunc()) => {
                self.unknown_position();
                Ok(())
            }
            _ if PLAIN_G.contains(&n) => Ok(()),
            _ => Err(format!(
                "G{} is a command p3dp cannot check; expected moves (G0–G3), dwell (G4), units (G21), modes (G90, G91, G92 E), homing or probing (G28–G35, G80)",
                fmt_num(n)
            )),
        }
    }

    /// The machine point a move's axis words reach, per axis (`None`: still
    /// unknown), after checking each.
    fn targets(
        &self,
        cmd: &Command,
        lim: &Limits,
    ) -> std::result::Result<[Option<f64>; 3], String> {
        let mut to = self.pos;
        let (bmin, bmax) = lim.bed_shape.extent();
        let span = [
            bmax[0] - bmin[0] + 2.0 * lim.margin,
            bmax[1] - bmin[1] + 2.0 * lim.margin,
            lim.max_z + lim.margin + lim.below,
        ];
        for (k, axis) in ["X", "Y", "Z"].iter().enumerate() {
            let Some(v) = cmd.get(axis) else { continue };
            if !v.is_finite() {
                return Err(format!("cannot read its {axis} value"));
            }
            to[k] = match (self.relative, self.pos[k]) {
                (false, _) => Some(v),
                (true, Some(p)) => Some(p + v),
                (true, None) => {
                    if v.abs() > span[k] {
                        return Err(format!(
                            "a relative {axis} move of {v} mm from an unknown position goes further than the machine is wide ({} mm)",
                            fmt_num(span[k])
                        ));
                    }
                    None
                }
            };
        }
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            if let Some(v) = to[k] {
                within(k, axis, v, lim)?;
            }
        }
        if let (Bed::Circle { diameter, .. }, Some(x), Some(y)) = (lim.bed_shape, to[0], to[1]) {
            let r = x.hypot(y);
            if r > diameter / 2.0 + lim.margin + 1e-9 {
                return Err(format!(
                    "({x}, {y}) is {} mm from the centre, outside the machine's travel envelope (the bed's radius {} mm grown by envelope.margin {} mm)",
                    fmt_num(r),
                    diameter / 2.0,
                    lim.margin
                ));
            }
        }
        Ok(to)
    }

    fn linear(&mut self, cmd: &Command, lim: &Limits) -> std::result::Result<(), String> {
        self.pos = self.targets(cmd, lim)?;
        Ok(())
    }

    /// `G2`/`G3` with I J: the whole sweep inside the envelope.
    fn arc(&mut self, cmd: &Command, lim: &Limits) -> std::result::Result<(), String> {
        let (Some(x0), Some(y0)) = (self.pos[0], self.pos[1]) else {
            return Err("an arc from an unknown position; p3dp cannot check where it goes".into());
        };
        if cmd.get("R").is_some() {
            return Err("an arc given by its radius (R); p3dp checks arcs given by I and J".into());
        }
        let to = self.targets(cmd, lim)?;
        let (x1, y1) = (to[0].unwrap_or(x0), to[1].unwrap_or(y0));
        let (i, j) = (cmd.get("I").unwrap_or(0.0), cmd.get("J").unwrap_or(0.0));
        if !(i.is_finite() && j.is_finite()) {
            return Err("cannot read its I or J value".into());
        }
        let (cx, cy) = (x0 + i, y0 + j);
        let r = i.hypot(j);
        let a0 = libm::atan2(y0 - cy, x0 - cx);
        let mut a1 = libm::atan2(y1 - cy, x1 - cx);
        let tau = std::f64::consts::TAU;
        let ccw = cmd.number == 3.0;
        // the sweep's size (a full circle when the ends meet) and its end angle
        let mut sweep = if ccw { a1 - a0 } else { a0 - a1 }.rem_euclid(tau);
        if sweep < 1e-12 {
            sweep = tau;
        }
        a1 = if ccw { a0 + sweep } else { a0 - sweep };
        // the ends and every quarter-turn extreme the sweep passes
        let quarter = std::f64::consts::FRAC_PI_2;
        let (lo, hi) = (a0.min(a1), a0.max(a1));
        let mut pts = vec![(x0, y0), (x1, y1)];
        let mut q = libm::ceil(lo / quarter);
        while q * quarter <= hi {
            let t = q * quarter;
            pts.push((cx + r * libm::cos(t), cy + r * libm::sin(t)));
            q += 1.0;
        }
        for (x, y) in pts {
            let probe = Command {
                letter: 'G',
                number: 1.0,
                name: "",
                params: vec![("X".into(), x), ("Y".into(), y)],
                words: Vec::new(),
            };
            let st = State {
                pos: self.pos,
                relative: false,
            };
            st.targets(&probe, lim)
                .map_err(|e| format!("the arc's sweep: {e}"))?;
        }
        self.pos = to;
        Ok(())
    }

    fn m(&mut self, cmd: &Command, lim: &Limits) -> std::result::Result<(), String> {
        let n = cmd.number;
        match n {
            _ if n == 104.0 || n == 109.0 => nozzle_params(cmd, &["S", "R"], lim),
            _ if n == 568.0 => nozzle_params(cmd, &["S", "R"], lim),
            _ if n == 140.0 || n == 190.0 => {
                for k in ["S", "R"] {
                    if let Some(t) = cmd.get(k) {
                        bed_temp(t, lim)?;
                    }
                }
                Ok(())
            }
            _ if n == 203.0 => {
                for axis in ["X", "Y"] {
                    if let Some(v) = cmd.get(axis) {
                        if !(v.is_finite() && v <= lim.feed + 1e-9) {
                            return Err(format!(
                                "sets the {axis} feed limit to {v} mm/s, past the printer's max_speed {} mm/s",
                                lim.feed
                            ));
                        }
                    }
                }
                Ok(())
            }
            _ if n == 220.0 => match cmd.get("S") {
                Some(s) if !(s.is_finite() && s <= 100.0) => Err(format!(
                    "a speed factor of {s} % would run the moves after it faster than written; expected at most 100"
                )),
                _ => Ok(()),
            },
            _ => {
                if let Some((_, why)) = OFFSET_M.iter().find(|(c, _)| *c == n) {
                    return Err(format!(
                        "M{} {why}: p3dp cannot check the moves after it",
                        fmt_num(n)
                    ));
                }
                if MOVING_M.contains(&n) {
                    self.unknown_position();
                }
                Ok(())
            }
        }
    }

    /// A named command (a Klipper macro or extended command): temperatures
    /// in its parameters checked; the position is unknown after it (a macro
    /// may move anywhere the firmware allows).
    fn named(&mut self, cmd: &Command, lim: &Limits) -> std::result::Result<(), String> {
        // the heater a command sets: the bed's when its name or its
        // HEATER=/SENSOR= word names the bed, else the nozzle's
        let names_bed = |s: &str| s.to_ascii_uppercase().contains("BED");
        let heater = cmd
            .words
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case("HEATER") || k.eq_ignore_ascii_case("SENSOR"));
        let bed = heater.is_some_and(|(_, v)| names_bed(v)) || names_bed(cmd.name);
        for (k, v) in &cmd.params {
            let up = k.to_ascii_uppercase();
            let temp =
                up.contains("TEMP") || (heater.is_some() && (up == "TARGET" || up == "MINIMUM"));
            if !temp || up.contains("CHAMBER") {
                continue;
            }
            if names_bed(k) || bed {
                bed_temp(*v, lim)?;
            } else {
                nozzle_temp(*v, lim)?;
            }
        }
        if cmd.name.eq_ignore_ascii_case("SET_VELOCITY_LIMIT") {
            if let Some(v) = cmd.get("VELOCITY") {
                feed(v * 60.0, lim)?;
            }
        }
        if !cmd.name.eq_ignore_ascii_case("SET_HEATER_TEMPERATURE")
            && !cmd.name.eq_ignore_ascii_case("TEMPERATURE_WAIT")
        {
            self.unknown_position();
        }
        Ok(())
    }
}

/// A SET_HEATER_TEMPERATURE's heater is read from its line: the bed's when
/// the line names the bed.
fn nozzle_params(cmd: &Command, keys: &[&str], lim: &Limits) -> std::result::Result<(), String> {
    for k in keys {
        if let Some(t) = cmd.get(k) {
            nozzle_temp(t, lim)?;
        }
    }
    Ok(())
}

fn nozzle_temp(t: f64, lim: &Limits) -> std::result::Result<(), String> {
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

fn bed_temp(t: f64, lim: &Limits) -> std::result::Result<(), String> {
    if !(t.is_finite() && t >= 0.0 && t <= lim.bed) {
        return Err(format!(
            "a bed temperature of {t} °C, outside 0 to {} °C (the printer's max_bed_temp, or the material's bed_temp if higher)",
            lim.bed
        ));
    }
    Ok(())
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
fn within(k: usize, axis: &str, v: f64, lim: &Limits) -> std::result::Result<(), String> {
    const EPS: f64 = 1e-9;
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
    let (bmin, bmax) = lim.bed_shape.extent();
    let (lo, hi) = (bmin[k] - lim.margin, bmax[k] + lim.margin);
    if v < lo - EPS || v > hi + EPS {
        return Err(format!(
            "{axis} = {} mm is outside the machine's travel envelope ({axis} from {} to {} mm: the bed grown by envelope.margin {} mm)",
            fmt_num(v),
            fmt_num(lo),
            fmt_num(hi),
            lim.margin
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recipe() -> Recipe {
        let raw: crate::recipe::RawRecipe = crate::recipe::parse_yaml(
            "p3dp: 1\nname: t\nprinter: prusa-mk3s\nmaterial: pla\nparts:\n  - primitive: {helix: {radius: 10, height: 2, pitch: 0.5}}\n",
            "t.yaml",
        )
        .unwrap();
        Recipe::resolve(&raw, &[], None, std::path::Path::new(".")).unwrap()
    }

    fn refused(text: &str) -> String {
        let e = check("start_gcode", text, &recipe(), Start::Unknown).unwrap_err();
        e.to_string()
    }

    #[test]
    fn a_makers_start_passes() {
        let ok = "M862.3 P \"MK3S\" ; model\nG90\nM83\nM104 S215\nM140 S60\nM190 S60\nM109 S215\nG28 W\nG80\nG1 Z0.2 F720\nG1 Y-3 F1000\nG92 E0\nG1 X60 E9 F1000\nG1 X100 E12.5 F1000\nG92 E0\nM221 S95\n\tG4 ; tab\nSET_HEATER_TEMPERATURE HEATER=extruder TARGET=200\nT0";
        check("start_gcode", ok, &recipe(), Start::Unknown).unwrap();
        let end = "G91\nG1 Z1 F720\nG90\nG1 X0 Y200 F3600\nG2 X20 Y200 I10 J0\nM84";
        check(
            "end_gcode",
            end,
            &recipe(),
            Start::At(DVec3::new(125.0, 105.0, 10.0)),
        )
        .unwrap();
    }

    #[test]
    fn unsafe_lines_are_named() {
        let e = refused("G28\nM104 S999");
        assert!(
            e.contains("start_gcode line 2: `M104 S999`: a nozzle temperature of 999 °C"),
            "{e}"
        );
        let e = refused("G28\nG1 Z5\nG1 Z-50 F300");
        assert!(
            e.contains("line 3: `G1 Z-50 F300`: z = -50 mm is below the bed"),
            "{e}"
        );
        let e = refused("G0 X5000 Y5000");
        assert!(
            e.contains("x = 5000 mm is outside the machine's travel envelope"),
            "{e}"
        );
        let e = refused("G0 X10 Y10 F300000");
        assert!(
            e.contains("F300000 is 5000 mm/s, faster than the printer's max_speed"),
            "{e}"
        );
        let e = refused("M140 S200");
        assert!(e.contains("bed temperature of 200"), "{e}");
        let e = refused("G28\nG91\nG1 X-3000");
        assert!(e.contains("from an unknown position"), "{e}");
        let e = refused("G92 Z0");
        assert!(e.contains("redefines the coordinates"), "{e}");
        let e = refused("SET_HEATER_TEMPERATURE HEATER=heater_bed TARGET=180");
        assert!(e.contains("bed temperature of 180"), "{e}");
        let e = refused("G1 X0 Y0\nG2 X0 Y0 I-100 J0");
        assert!(e.contains("the arc's sweep: x = -100 mm is outside"), "{e}");
        let e = refused("G28\nM851 Z-5");
        assert!(e.contains("probe's offsets"), "{e}");
        let e = refused("G28\u{2028}M104 S999");
        assert!(e.contains("line break (U+2028)"), "{e}");
        let e = refused("G20");
        assert!(e.contains("inches"), "{e}");
    }
}
