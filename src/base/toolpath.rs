//! The one type that carries a part between stages: the papers' strings.
//!
//! Kanada represents a part as a sequence of strings S_i = (P_start_i, P_end_i,
//! c_i, v_i): straight pieces of filament with cross-section c (mm²) and head
//! speed v (mm/s). Consecutive strings share their end and start points, so a
//! part is stored as a polyline: string k runs from `points[k]` to
//! `points[k + 1]`, with its attributes in `strings[k]`.

use glam::DVec3;

/// Cross-section, speed and kind of one string (named `Strand` so as not to
/// clash with Rust's `String`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strand {
    /// Cross-section of the extruded filament, mm².
    pub c: f64,
    /// Head speed, mm/s.
    pub v: f64,
    /// A travel move: the head moves without extruding.
    pub travel: bool,
    /// A declared hair (a turtle's `hair:`): a thin string pulled from a blob
    /// into the air on purpose, which the `unsupported`, `thin-string` and
    /// `nozzle-collision` checks pass over (and nothing else does).
    pub(crate) hair: bool,
}

/// Something the printer does between two strings that is not a move
/// (ExtruderTurtle's dwell, pause and temperature commands; a turtle's pen-up
/// retraction and in-place extrusion; a recipe's own printer command).
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// Wait this many milliseconds (G4).
    Dwell {
        /// Milliseconds.
        ms: f64,
    },
    /// A firmware pause, so a person can act (insert a thread, change colour).
    Pause,
    /// Set the nozzle temperature, °C, and optionally wait for it.
    NozzleTemp {
        /// °C.
        celsius: f64,
        /// Wait until it is reached.
        wait: bool,
    },
    /// Set the bed temperature, °C, and optionally wait for it.
    BedTemp {
        /// °C.
        celsius: f64,
        /// Wait until it is reached.
        wait: bool,
    },
    /// Set the part-cooling fan, 0 (off) to 1 (full).
    Fan {
        /// Fraction of full speed.
        speed: f64,
    },
    /// Retract now with the profile's length; the next extruding move undoes it.
    Retract,
    /// Feed filament without moving the head.
    Extrude {
        /// Filament, mm.
        filament: f64,
        /// Filament speed, mm/s.
        speed: f64,
    },
    /// A printer command a recipe asked for, written as it is: one line,
    /// checked when the recipe was read (no line break, no move the
    /// writer cannot account for).
    Gcode(std::sync::Arc<str>),
    /// A setting of the printer (a `set` step): written in the printer's
    /// dialect and followed by the planner and the stats; the first setting
    /// of a calibration band carries the band.
    Set {
        /// What it sets.
        setting: crate::base::gcode::Setting,
        /// The band it begins, if any.
        band: Option<Band>,
        /// The key path of the value it was made from, when its maker
        /// knows it (a turtle's or path's `set` command:
        /// `parts[0].primitive.turtle.program[2].set.pressure_advance`),
        /// for the `setting` check to name.
        place: Option<std::sync::Arc<str>>,
    },
}

/// A band of a calibration print: where one value of a `set` step holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// The band's index (0 at the bottom, or the line's number).
    pub index: u32,
    /// The value its setting takes.
    pub value: f64,
    /// Its heights, `[from, to)` in recipe z, mm; `None` for a line (a
    /// part of its own).
    pub z: Option<[f64; 2]>,
}

/// Where a turtle stood when its program said `draw_turtle`
/// (ExtruderTurtle's `draw_Turtle()`): drawn in the previews as a small
/// triangle pointing along the heading, never written to the G-code.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Marker {
    /// The turtle's position, recipe coordinates, mm.
    pub(crate) pos: DVec3,
    /// Its heading (unit).
    pub(crate) heading: DVec3,
    /// Its up axis (unit), the triangle's normal.
    pub(crate) up: DVec3,
}

/// The strings' attributes, string k's at `[k]`: held once for a part
/// whose strings are all alike (a primitive before any step changes them;
/// 24 bytes a string otherwise), so a check of tens of millions of strings
/// keeps little more than their points.
#[derive(Clone, Debug, Default)]
pub struct Strands(Repr);

#[derive(Clone, Debug)]
enum Repr {
    /// `n` strings, all `strand`.
    Same(Strand, usize),
    /// One each.
    Each(Vec<Strand>),
}

impl Default for Repr {
    fn default() -> Repr {
        Repr::Each(Vec::new())
    }
}

impl Strands {
    /// `n` strings, all `strand`.
    pub(crate) fn same(strand: Strand, n: usize) -> Strands {
        Strands(Repr::Same(strand, n))
    }

    /// Number of strings.
    #[inline]
    pub fn len(&self) -> usize {
        match &self.0 {
            Repr::Same(_, n) => *n,
            Repr::Each(v) => v.len(),
        }
    }

    /// Whether there is none.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// String k's, if there is one.
    #[inline]
    pub fn get(&self, k: usize) -> Option<&Strand> {
        match &self.0 {
            Repr::Same(s, n) => (k < *n).then_some(s),
            Repr::Each(v) => v.get(k),
        }
    }

    /// The last string's.
    pub fn last(&self) -> Option<&Strand> {
        self.len().checked_sub(1).and_then(|k| self.get(k))
    }

    /// Each string's, in order.
    #[inline]
    pub fn iter(&self) -> Iter<'_> {
        match &self.0 {
            Repr::Same(s, n) => Iter::Same(s, *n),
            Repr::Each(v) => Iter::Each(v.iter()),
        }
    }

    /// One per string, to change in place (made so when they were alike).
    pub fn make_mut(&mut self) -> &mut Vec<Strand> {
        if let Repr::Same(s, n) = self.0 {
            self.0 = Repr::Each(crate::base::par::fill_vec(n, 8_192, |_| s));
        }
        match &mut self.0 {
            Repr::Each(v) => v,
            Repr::Same(..) => unreachable!("made one each above"),
        }
    }

    /// The one strand all strings share, when they are held once.
    pub(crate) fn alike(&self) -> Option<Strand> {
        match &self.0 {
            Repr::Same(s, _) => Some(*s),
            Repr::Each(_) => None,
        }
    }

    /// Adds a string's (alike ones stay held once).
    #[inline]
    pub fn push(&mut self, s: Strand) {
        match &mut self.0 {
            Repr::Same(t, n) if *t == s => *n += 1,
            Repr::Each(v) if v.is_empty() => self.0 = Repr::Same(s, 1),
            Repr::Each(v) => v.push(s),
            Repr::Same(..) => self.make_mut().push(s),
        }
    }

    /// Room for `n` more different strings.
    pub(crate) fn reserve(&mut self, n: usize) {
        if let Repr::Each(v) = &mut self.0 {
            v.reserve(n);
        }
    }

    /// Adds `other`'s strings after these.
    pub(crate) fn extend_from(&mut self, other: &Strands) {
        match (&mut self.0, &other.0) {
            (_, Repr::Same(_, 0)) => {}
            (Repr::Same(t, n), Repr::Same(s, m)) if t == s => *n += m,
            (Repr::Each(v), Repr::Same(s, m)) if v.is_empty() => {
                self.0 = Repr::Same(*s, *m);
            }
            (Repr::Same(_, 0), _) => *self = other.clone(),
            (Repr::Each(v), Repr::Each(o)) => v.extend_from_slice(o),
            _ => {
                let v = self.make_mut();
                v.extend(other.iter());
            }
        }
    }

    /// Puts `before`'s strings ahead of these.
    pub(crate) fn prepend(&mut self, mut before: Strands) {
        before.extend_from(self);
        *self = before;
    }

    /// Strings `from..to`'s.
    pub(crate) fn range(&self, from: usize, to: usize) -> Strands {
        match &self.0 {
            Repr::Same(s, n) => {
                assert!(from <= to && to <= *n, "strings {from}..{to} of {n}");
                Strands(Repr::Same(*s, to - from))
            }
            Repr::Each(v) => Strands::from(v[from..to].to_vec()),
        }
    }
}

impl From<Vec<Strand>> for Strands {
    /// One per string; held once when they are all alike.
    fn from(v: Vec<Strand>) -> Strands {
        match v.first() {
            Some(&s) if v.iter().all(|t| *t == s) => Strands(Repr::Same(s, v.len())),
            _ => Strands(Repr::Each(v)),
        }
    }
}

impl PartialEq for Strands {
    fn eq(&self, other: &Strands) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}

impl std::ops::Index<usize> for Strands {
    type Output = Strand;

    #[inline]
    fn index(&self, k: usize) -> &Strand {
        match &self.0 {
            Repr::Same(s, n) => {
                assert!(k < *n, "string {k} of {n}");
                s
            }
            Repr::Each(v) => &v[k],
        }
    }
}

impl std::ops::IndexMut<usize> for Strands {
    fn index_mut(&mut self, k: usize) -> &mut Strand {
        &mut self.make_mut()[k]
    }
}

impl<'a> IntoIterator for &'a Strands {
    type Item = &'a Strand;
    type IntoIter = Iter<'a>;

    fn into_iter(self) -> Iter<'a> {
        self.iter()
    }
}

/// The strings' attributes in order ([`Strands::iter`]).
#[derive(Clone, Debug)]
pub enum Iter<'a> {
    /// The same one, this many times more.
    Same(&'a Strand, usize),
    /// One each.
    Each(std::slice::Iter<'a, Strand>),
}

impl<'a> Iterator for Iter<'a> {
    type Item = &'a Strand;

    #[inline]
    fn next(&mut self) -> Option<&'a Strand> {
        match self {
            Iter::Same(s, n) => {
                if *n == 0 {
                    None
                } else {
                    *n -= 1;
                    Some(*s)
                }
            }
            Iter::Each(it) => it.next(),
        }
    }

    #[inline]
    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = match self {
            Iter::Same(_, n) => *n,
            Iter::Each(it) => it.len(),
        };
        (n, Some(n))
    }
}

impl ExactSizeIterator for Iter<'_> {}

impl DoubleEndedIterator for Iter<'_> {
    fn next_back(&mut self) -> Option<Self::Item> {
        match self {
            Iter::Same(..) => self.next(),
            Iter::Each(it) => it.next_back(),
        }
    }
}

/// A part: a polyline of points and the strings between them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Toolpath {
    /// The part's name, for reports and error places.
    pub name: String,
    /// n + 1 points for n strings.
    pub points: Vec<DVec3>,
    /// String k runs from `points[k]` to `points[k + 1]`.
    pub strings: Strands,
    /// Events in order of their string index: `(k, e)` happens before
    /// string k (k = n: after the last string).
    pub(crate) events: Vec<(usize, Event)>,
    /// Turtle markers for the previews (`draw_turtle`), in program order.
    pub(crate) markers: Vec<Marker>,
    /// Per point, when a primitive of the part follows an `outline:`: turns
    /// along the outline, u = k + s on turn k at arc fraction s (so it grows
    /// along the part and interpolates linearly); expressions see
    /// s = u − floor(u) ([`Toolpath::s_at_point`]). Points of the part's
    /// other primitives have u = 0. `None`: no outline, and no `s`.
    pub turns: Option<Vec<f64>>,
}

impl Toolpath {
    /// An empty part whose head starts at `start`.
    pub fn new(start: DVec3) -> Toolpath {
        Toolpath {
            name: String::new(),
            points: vec![start],
            strings: Strands::default(),
            events: Vec::new(),
            markers: Vec::new(),
            turns: None,
        }
    }

    /// A part through `points` (at least one) whose strings all extrude with
    /// cross-section `c` at speed `v`: the same as `new(first)` then `draw`
    /// to each of the rest, without a push per string.
    pub(crate) fn uniform(points: Vec<DVec3>, c: f64, v: f64) -> Toolpath {
        assert!(!points.is_empty(), "a part starts somewhere");
        let strand = Strand {
            c,
            v,
            travel: false,
            hair: false,
        };
        Toolpath {
            name: String::new(),
            strings: Strands::same(strand, points.len() - 1),
            points,
            events: Vec::new(),
            markers: Vec::new(),
            turns: None,
        }
    }

    /// An empty part with room for `n` strings' points.
    pub(crate) fn with_capacity(start: DVec3, n: usize) -> Toolpath {
        let mut points = Vec::with_capacity(n + 1);
        points.push(start);
        Toolpath {
            name: String::new(),
            points,
            strings: Strands::default(),
            events: Vec::new(),
            markers: Vec::new(),
            turns: None,
        }
    }

    /// The head's current position (the last point).
    pub fn head(&self) -> DVec3 {
        *self.points.last().expect("a toolpath has a start point")
    }

    /// Keeps `turns` one per point: a new point repeats the last value.
    #[inline]
    fn push_turns(&mut self) {
        if let Some(u) = &mut self.turns {
            u.push(u.last().copied().unwrap_or(0.0));
        }
    }

    /// The `s` of string k's midpoint (0 with no outline).
    #[inline]
    pub(crate) fn s_at_string(&self, k: usize) -> f64 {
        match &self.turns {
            Some(u) => frac(0.5 * (u[k] + u[k + 1])),
            None => 0.0,
        }
    }

    /// Adds an extruding string to `p` (the papers' `draw`).
    pub fn draw(&mut self, p: DVec3, c: f64, v: f64) {
        self.push_turns();
        self.points.push(p);
        self.strings.push(Strand {
            c,
            v,
            travel: false,
            hair: false,
        });
    }

    /// Adds a declared hair to `p`: an extruding string of cross-section `c`
    /// that is meant to hang in the air (see `Strand::hair`).
    pub(crate) fn hair(&mut self, p: DVec3, c: f64, v: f64) {
        self.push_turns();
        self.points.push(p);
        self.strings.push(Strand {
            c,
            v,
            travel: false,
            hair: true,
        });
    }

    /// Adds a travel string to `p` (the papers' `move`).
    pub fn travel(&mut self, p: DVec3, v: f64) {
        self.push_turns();
        self.points.push(p);
        self.strings.push(Strand {
            c: 0.0,
            v,
            travel: true,
            hair: false,
        });
    }

    /// Adds an event before the next string.
    pub fn event(&mut self, e: Event) {
        self.events.push((self.strings.len(), e));
    }

    /// Number of strings.
    pub fn len(&self) -> usize {
        self.strings.len()
    }

    /// Whether the part has no strings.
    pub fn is_empty(&self) -> bool {
        self.strings.is_empty()
    }

    /// Start and end point of string k.
    pub fn ends(&self, k: usize) -> (DVec3, DVec3) {
        (self.points[k], self.points[k + 1])
    }

    /// Length of string k, mm.
    pub(crate) fn length(&self, k: usize) -> f64 {
        let (a, b) = self.ends(k);
        a.distance(b)
    }

    /// Midpoint of string k, where its c and v expressions are evaluated.
    pub(crate) fn midpoint(&self, k: usize) -> DVec3 {
        let (a, b) = self.ends(k);
        (a + b) * 0.5
    }

    /// Extruded volume Σ c·L over the extruding strings, mm³.
    pub fn volume(&self) -> f64 {
        (0..self.len())
            .filter(|&k| !self.strings[k].travel)
            .map(|k| self.strings[k].c * self.length(k))
            .sum()
    }

    /// Appends `other`, joining with a travel move when it starts elsewhere.
    pub(crate) fn append(&mut self, other: &Toolpath, travel_speed: f64) {
        let start = other.points[0];
        if self.head() != start {
            self.travel(start, travel_speed);
        }
        let base = self.len();
        self.events
            .extend(other.events.iter().map(|(k, e)| (k + base, e.clone())));
        if self.turns.is_some() || other.turns.is_some() {
            let mine = self.points.len();
            let u = self.turns.get_or_insert_with(|| vec![0.0; mine]);
            match &other.turns {
                Some(o) => u.extend_from_slice(&o[1..]),
                None => u.resize(mine + other.points.len() - 1, 0.0),
            }
        }
        self.points.extend_from_slice(&other.points[1..]);
        self.strings.extend_from(&other.strings);
        self.markers.extend_from_slice(&other.markers);
    }

    /// Puts `before` ahead of this path: the same path as
    /// `before.append(self)` with this one's name, made in this path's
    /// buffers (a brim or stand ahead of a 2M-string part copied all of it
    /// into new memory).
    pub(crate) fn prepend(&mut self, mut before: Toolpath, travel_speed: f64) {
        let start = self.points[0];
        if before.head() != start {
            before.travel(start, travel_speed);
        }
        let base = before.len();
        for (k, _) in &mut self.events {
            *k += base;
        }
        before.events.append(&mut self.events);
        self.events = before.events;
        if self.turns.is_some() || before.turns.is_some() {
            let theirs = before.points.len();
            let u = before.turns.unwrap_or_else(|| vec![0.0; theirs]);
            let mine = self
                .turns
                .get_or_insert_with(|| vec![0.0; self.points.len()]);
            mine.splice(0..1, u);
        }
        // the join is `before`'s last point, as in `append`
        self.points.splice(0..1, before.points);
        self.strings.prepend(before.strings);
        self.markers.splice(0..0, before.markers);
    }
}

/// x − floor(x): the fractional part, in [0, 1).
#[inline]
pub(crate) fn frac(x: f64) -> f64 {
    x - libm::floor(x)
}

/// Cylinder coordinates (r, theta) of a point, theta in [0, 2·pi).
#[inline]
pub(crate) fn polar(p: DVec3) -> (f64, f64) {
    (radius(p), angle(p))
}

/// Distance of a point from the z axis (the r of [`polar`]).
#[inline]
pub(crate) fn radius(p: DVec3) -> f64 {
    (p.x * p.x + p.y * p.y).sqrt()
}

/// Angle of a point about the z axis in [0, 2·pi) (the theta of [`polar`]).
#[inline]
pub(crate) fn angle(p: DVec3) -> f64 {
    let mut theta = libm::atan2(p.y, p.x);
    if theta < 0.0 {
        theta += std::f64::consts::TAU;
        if theta >= std::f64::consts::TAU {
            theta = 0.0; // -0 and tiny negatives round up to exactly 2·pi
        }
    }
    theta
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alike_strings_are_held_once_and_read_as_one_each() {
        let s = |c: f64| Strand {
            c,
            v: 30.0,
            travel: false,
            hair: false,
        };
        // a part of alike strings keeps one strand, whatever joins it
        let mut t = Toolpath::uniform(vec![DVec3::ZERO; 1001], 0.2, 30.0);
        assert_eq!(t.strings.alike(), Some(s(0.2)));
        t.draw(DVec3::X, 0.2, 30.0);
        let same = Toolpath::uniform(vec![DVec3::X; 11], 0.2, 30.0);
        t.append(&same, 99.0);
        assert_eq!(t.strings.alike(), Some(s(0.2)));
        assert_eq!(t.len(), 1011);
        assert_eq!(t.strings.range(3, 9), Strands::same(s(0.2), 6));
        // one different string: one each from then on, read the same
        t.draw(DVec3::Y, 0.3, 30.0);
        assert_eq!(t.strings.alike(), None);
        let want: Vec<Strand> = (0..1012)
            .map(|k| s(if k < 1011 { 0.2 } else { 0.3 }))
            .collect();
        assert!(t.strings.iter().eq(want.iter()));
        assert_eq!(t.strings.iter().len(), 1012);
        assert_eq!(t.strings, Strands::from(want.clone()));
        assert_eq!(t.strings[1011], s(0.3));
        assert_eq!(t.strings.last(), Some(&s(0.3)));
        // changed in place through `make_mut`, equal to the list changed so
        let mut u = Strands::same(s(0.2), 4);
        u[2].c = 0.5;
        assert_eq!(u, Strands::from(vec![s(0.2), s(0.2), s(0.5), s(0.2)]));
        // a list of alike ones is held once; prepending keeps the order
        assert_eq!(Strands::from(vec![s(0.1); 5]).alike(), Some(s(0.1)));
        let mut v = Strands::from(vec![s(0.3)]);
        v.prepend(Strands::same(s(0.1), 2));
        assert!(v.iter().map(|x| x.c).eq([0.1, 0.1, 0.3]));
        assert!(Strands::default().is_empty() && Strands::same(s(0.1), 0).last().is_none());
    }

    #[test]
    fn polyline_strings_share_points() {
        let mut t = Toolpath::new(DVec3::ZERO);
        t.draw(DVec3::new(3.0, 0.0, 0.0), 0.2, 10.0);
        t.travel(DVec3::new(3.0, 4.0, 0.0), 100.0);
        t.draw(DVec3::new(0.0, 0.0, 0.0), 0.1, 10.0);
        assert_eq!(t.len(), 3);
        assert_eq!(t.length(1), 4.0);
        assert_eq!(t.midpoint(0), DVec3::new(1.5, 0.0, 0.0));
        // the travel string extrudes nothing
        assert!((t.volume() - (0.2 * 3.0 + 0.1 * 5.0)).abs() < 1e-12);
    }

    #[test]
    fn prepend_is_append_the_other_way() {
        let path = |x: f64, turns: bool| {
            let mut t = Toolpath::new(DVec3::new(x, 0.0, 0.2));
            t.name = format!("at {x}");
            t.draw(DVec3::new(x + 1.0, 0.0, 0.2), 0.1, 10.0);
            t.events.push((1, Event::Pause));
            t.draw(DVec3::new(x + 1.0, 1.0, 0.2), 0.2, 20.0);
            t.markers.push(Marker {
                pos: DVec3::splat(x),
                heading: DVec3::X,
                up: DVec3::Z,
            });
            t.events.push((2, Event::Dwell { ms: x }));
            if turns {
                t.turns = Some(vec![x, x + 0.5, x + 1.0]);
            }
            t
        };
        for (tb, tp) in [(false, false), (true, false), (false, true), (true, true)] {
            // joined by a travel, and not (starting where `before` ends)
            for same in [false, true] {
                let (before, mut part) = (path(0.0, tb), path(5.0, tp));
                if same {
                    part.points[0] = before.head();
                }
                let mut want = before.clone();
                want.append(&part, 99.0);
                want.name = part.name.clone();
                let mut got = part;
                got.prepend(before, 99.0);
                assert_eq!(got.len(), 4 + usize::from(!same));
                assert_eq!(got, want, "turns {tb} {tp}, same {same}");
            }
        }
    }

    #[test]
    fn polar_angle_is_in_range() {
        let (r, th) = polar(DVec3::new(0.0, -2.0, 0.0));
        assert_eq!(r, 2.0);
        assert!((th - 1.5 * std::f64::consts::PI).abs() < 1e-15);
        let (_, th) = polar(DVec3::new(1.0, -1e-300, 0.0));
        assert!((0.0..std::f64::consts::TAU).contains(&th));
    }
}
