//! Where the emitter's commands go: the one writer (text in the printer's
//! dialect) and the consumers of the stream (the firmware's state, and
//! through it the planner or the progress clock), in one pass.
//!
//! A [`Stream`] formats each command once ([`Out`]) and runs it through
//! the firmware's [`State`], handing the motion it makes to a [`Moves`]
//! sink (the planner, the places of progress lines, a viewer).

use std::io::{self, Write};

use glam::DVec3;

use crate::analyse::planner::{MoveKind, Moves};
use crate::base::format::Chunk;
use crate::base::gcode::{Command, Move, Setting, Verbatim};
use crate::machine::firmware::write::{write, write_move};
use crate::machine::firmware::{Dialect, Motion, State};

/// Text formatted into chunks and handed to `out`.
pub(crate) struct Out<W: Write> {
    /// The destination.
    pub(crate) out: W,
    buf: Chunk,
    /// Bytes handed on so far.
    handed: u64,
}

impl<W: Write> Out<W> {
    /// An output to `out`.
    pub(crate) fn new(out: W) -> Out<W> {
        Out {
            out,
            buf: Chunk::new(),
            handed: 0,
        }
    }

    /// The text not yet handed on.
    #[inline]
    fn chunk(&mut self) -> &mut Chunk {
        &mut self.buf
    }

    /// Hands the text on once there is a chunk of it.
    #[inline]
    fn hand_on(&mut self) -> io::Result<()> {
        if self.buf.full() {
            self.out.write_all(self.buf.bytes())?;
            self.handed += self.buf.bytes().len() as u64;
            self.buf.clear();
        }
        Ok(())
    }

    /// Hands on what is left and flushes.
    fn flush(&mut self) -> io::Result<()> {
        self.out.write_all(self.buf.bytes())?;
        self.handed += self.buf.bytes().len() as u64;
        self.buf.clear();
        self.out.flush()
    }

    /// Bytes written so far (handed on or not).
    #[inline]
    fn position(&self) -> u64 {
        self.handed + self.buf.bytes().len() as u64
    }
}

/// The emitter's commands written and followed (see the module comment).
pub(crate) struct Stream<W: Write, M: Moves> {
    /// The text.
    pub(crate) out: Out<W>,
    dialect: Dialect,
    state: State,
    /// The moves' consumer.
    pub(crate) moves: M,
    /// The firmware's own retraction: length (mm) and speed (mm/s).
    firmware_retraction: (f64, f64),
    /// The speed factor (`M220`), 1 = 100 %: every feed runs at it.
    speed: f64,
}

impl<W: Write, M: Moves> Stream<W, M> {
    /// A stream in `dialect` whose firmware retracts `firmware_retraction`
    /// (length, speed) on a `G10`.
    pub(crate) fn new(
        out: Out<W>,
        dialect: Dialect,
        moves: M,
        firmware_retraction: (f64, f64),
    ) -> Stream<W, M> {
        Stream {
            out,
            dialect,
            state: State::new(dialect.flavor),
            moves,
            firmware_retraction,
            speed: 1.0,
        }
    }

    /// A place where a progress line may go (before a move's line): told
    /// to the moves' consumer, which keeps it when it places progress.
    #[inline]
    pub(crate) fn progress_point(&mut self) -> io::Result<()> {
        self.moves.place(self.out.position());
        Ok(())
    }

    /// The first place of a progress line (0 %), before the start G-code.
    pub(crate) fn first_place(&mut self) {
        self.moves.first_place(self.out.position());
    }

    /// The last place of a progress line (100 %), before the end G-code.
    pub(crate) fn done(&mut self) -> io::Result<()> {
        self.moves.last_place(self.out.position());
        Ok(())
    }

    /// Writes `c` (`note` completing its line) without following it.
    #[inline]
    fn put(&mut self, c: &Command, note: &str) -> io::Result<()> {
        write(self.dialect, c, note, self.out.chunk());
        self.out.hand_on()
    }

    /// Writes `c` and follows it.
    #[inline]
    pub(crate) fn command(&mut self, c: &Command, note: &str) -> io::Result<()> {
        self.put(c, note)?;
        self.follow(c);
        Ok(())
    }

    /// Writes the straight move `m` and follows it: [`Stream::command`]
    /// of a [`Command::Move`] without the dispatch (the emitter's own
    /// moves, most of a G-code).
    #[inline]
    pub(crate) fn line(&mut self, m: &Move, note: &str) -> io::Result<()> {
        write_move(m, note, self.out.chunk());
        self.out.hand_on()?;
        let motion = self.state.line(m);
        self.motion(motion, m.to == [None; 3]);
        Ok(())
    }

    /// Text written as it is (comments, the header), a line feed added
    /// when it does not end with one; nothing for empty text.
    pub(crate) fn text(&mut self, s: &str) -> io::Result<()> {
        if !s.is_empty() {
            let buf = self.out.chunk();
            buf.put(s.as_bytes());
            if !s.ends_with('\n') {
                buf.push(b'\n');
            }
            self.out.hand_on()?;
        }
        Ok(())
    }

    /// A profile's line, written as it was read and checked, and followed:
    /// its settings told to the moves' consumer, its motion as a profile's
    /// (drawn by a viewer, not planned: the estimate is of p3dp's moves).
    pub(crate) fn verbatim(&mut self, line: &Verbatim) -> io::Result<()> {
        let buf = self.out.chunk();
        buf.put(line.text.as_bytes());
        buf.push(b'\n');
        self.out.hand_on()?;
        for c in &line.commands {
            if let Command::Set(s) = c {
                self.moves.setting(s);
                if let Setting::Speed(f) = s {
                    self.speed = *f;
                }
            }
            if let Motion::Line {
                to: [Some(x), Some(y), Some(z)],
                de,
                feed,
                travel,
                ..
            } = self.state.apply(c)
            {
                let kind = if travel {
                    MoveKind::Travel
                } else {
                    MoveKind::Extrude
                };
                let f = feed.unwrap_or(0.0) / 60.0;
                self.moves.profile_move(DVec3::new(x, y, z), de, f, kind);
            }
        }
        Ok(())
    }

    /// A recipe's own command (checked when the recipe was read), written
    /// as it is and followed as the firmware reads it.
    pub(crate) fn raw(&mut self, text: &str, commands: &[Command]) -> io::Result<()> {
        self.text(text)?;
        if commands.is_empty() {
            self.moves.stop();
        }
        for c in commands {
            self.follow(c);
        }
        Ok(())
    }

    /// A part begins (the planner times each).
    pub(crate) fn begin_part(&mut self, name: &str) {
        self.moves.begin_part(name);
    }

    /// Runs `c` through the firmware's state and hands its motion on.
    #[inline]
    fn follow(&mut self, c: &Command) {
        if let Command::Set(s) = c {
            self.moves.setting(s);
            if let Setting::Speed(f) = s {
                self.speed = *f;
            }
        }
        if let Command::Set(Setting::Retraction { length, speed }) = c {
            let (l, v) = &mut self.firmware_retraction;
            *l = length.unwrap_or(*l);
            *v = speed.unwrap_or(*v);
        }
        let motion = self.state.apply(c);
        let no_axes = matches!(c, Command::Move(m) if m.to == [None; 3]);
        match motion {
            Motion::Stop => match c {
                Command::FirmwareRetract { .. } => {
                    let (l, v) = self.firmware_retraction;
                    self.moves.extrude_only(l, v);
                }
                _ => self.moves.stop(),
            },
            m => self.motion(m, no_axes),
        }
    }

    /// Hands on the motion a command made (`no_axes`: a move that names
    /// no axis); a stop as a stop.
    #[inline]
    fn motion(&mut self, motion: Motion, no_axes: bool) {
        match motion {
            Motion::None => {}
            Motion::Line {
                to,
                de,
                feed,
                travel,
                from,
            } => {
                let f = feed.unwrap_or(0.0) / 60.0 * self.speed;
                if to == from && no_axes {
                    // E alone: a retraction, its undoing, or filament fed in place
                    self.moves.extrude_only(de.abs(), f);
                    return;
                }
                let p = DVec3::new(
                    to[0].unwrap_or(0.0),
                    to[1].unwrap_or(0.0),
                    to[2].unwrap_or(0.0),
                );
                let kind = if travel {
                    MoveKind::Travel
                } else {
                    MoveKind::Extrude
                };
                self.moves
                    .move_to(p, if travel { 0.0 } else { de }, f, kind);
            }
            Motion::Arc {
                from,
                to,
                center,
                ccw,
                de,
                feed,
            } => {
                let f = feed.unwrap_or(0.0) / 60.0 * self.speed;
                self.arc(from, to, center, ccw, de, f)
            }
            Motion::Dwell(s) => self.moves.dwell(s),
            Motion::Stop => self.moves.stop(),
        }
    }

    /// An arc as the firmware runs it: chords of at most 1 mm (Marlin's
    /// `MAX_ARC_SEGMENT_MM`, Klipper's `resolution`), Z rising evenly.
    fn arc(&mut self, from: [f64; 3], to: [f64; 3], c: [f64; 2], ccw: bool, de: f64, f: f64) {
        let r = (from[0] - c[0]).hypot(from[1] - c[1]);
        let a0 = libm::atan2(from[1] - c[1], from[0] - c[0]);
        let a1 = libm::atan2(to[1] - c[1], to[0] - c[0]);
        let tau = std::f64::consts::TAU;
        let mut sweep = if ccw { a1 - a0 } else { a0 - a1 }.rem_euclid(tau);
        if sweep < 1e-12 {
            sweep = tau;
        }
        let xy = r * sweep;
        let dz = to[2] - from[2];
        let len = (xy * xy + dz * dz).sqrt();
        let pieces = libm::ceil(len / 1.0).max(1.0) as usize;
        for i in 1..=pieces {
            let p = if i == pieces {
                DVec3::from_array(to)
            } else {
                let phi = sweep * i as f64 / pieces as f64;
                let a = if ccw { a0 + phi } else { a0 - phi };
                DVec3::new(
                    c[0] + r * libm::cos(a),
                    c[1] + r * libm::sin(a),
                    from[2] + dz * phi / sweep,
                )
            };
            self.moves
                .move_to(p, de / pieces as f64, f, MoveKind::Extrude);
        }
    }

    /// Hands on the text that is left and flushes the output.
    pub(crate) fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}
