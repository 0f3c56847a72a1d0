//! G-code read back: the moves of p3dp's G-code ([`moves`]), and the
//! [`Reader`] the HTML preview's G-code is written into, which keeps per move
//! only what the viewer draws.

use std::collections::HashSet;
use std::io::Write;

use glam::DVec3;

/// One G0/G1 move read back from G-code, in recipe coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Move {
    /// Where the move ends.
    pub to: DVec3,
    /// Feed rate in force, mm/min.
    pub feed: f64,
    /// Filament fed by the move, mm.
    pub de: f64,
    /// A G0 (travel) move.
    pub g0: bool,
    /// A G1 with an E word: an extruding string (p3dp writes E on every one).
    pub extrudes: bool,
    /// How many `; part:` comments came before it (0: the start G-code).
    pub part: usize,
    /// Machine position in µm, as written.
    pub machine_um: [i64; 3],
}

#[cfg(test)]
/// Reads the moves of p3dp's G-code (G90; M82 or M83; G92 E), machine
/// coordinates turned back into recipe coordinates by subtracting `origin`.
pub(crate) fn moves(gcode: &str, origin: DVec3) -> Vec<Move> {
    let mut parser = Parser::new(origin);
    gcode
        .lines()
        .filter_map(|l| parser.line(l.as_bytes()))
        .collect()
}

/// Whether `b` is whitespace to [`str::split_whitespace`] (of the ASCII).
fn space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | b'\x0b' | b'\x0c' | b'\r')
}

/// The number `s` spells, exactly as `str::parse::<f64>` reads it.
///
/// Plain decimals (an optional sign, up to 15 digits, a point), which is all
/// p3dp writes, are read directly: their digits m < 10^15 < 2^53 and 10^f
/// (f ≤ 15 decimals) are exact doubles, so the one correctly rounded
/// division m / 10^f is the correctly rounded value of the decimal, as
/// `parse` gives (the "fast path" of Clinger's algorithm). Anything else
/// goes to `parse`.
fn number(s: &[u8]) -> Option<f64> {
    match plain(s) {
        Some((v, len)) if len == s.len() => Some(v),
        _ => std::str::from_utf8(s).ok()?.parse().ok(),
    }
}

/// The plain decimal that starts `s` (an optional sign, 1 to 15 digits,
/// at most one point) and its length, when it is all of `s` or a space
/// ends it: its value m / 10^f, correctly rounded (see [`number`]).
fn plain(s: &[u8]) -> Option<(f64, usize)> {
    const POW10: [f64; 16] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
    ];
    let (neg, mut i) = match s.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    let (mut m, mut n, mut frac, mut point) = (0u64, 0usize, 0usize, false);
    while let Some(&b) = s.get(i) {
        match b {
            b'0'..=b'9' if n < 15 => {
                m = m * 10 + u64::from(b - b'0');
                n += 1;
                frac += usize::from(point);
            }
            b'.' if !point => point = true,
            b' ' => break,
            _ => return None,
        }
        i += 1;
    }
    if n == 0 {
        return None;
    }
    let v = m as f64 / POW10[frac];
    Some((if neg { -v } else { v }, i))
}

/// The state of reading G-code line by line (see [`moves`]).
struct Parser {
    origin: DVec3,
    pos: [f64; 3],
    e: f64,
    feed: f64,
    relative: bool,
    part: usize,
    /// Whether [`Move::machine_um`] is wanted (else left at zero).
    um: bool,
}

impl Parser {
    fn new(origin: DVec3) -> Parser {
        Parser {
            origin,
            pos: [0.0; 3],
            e: 0.0,
            feed: 0.0,
            relative: false,
            part: 0,
            um: true,
        }
    }

    /// The move `line` makes, if it moves the head: [`Parser::short`] for
    /// the lines p3dp writes nearly all of, [`Parser::general`] for the rest.
    fn line(&mut self, line: &[u8]) -> Option<Move> {
        match self.short(line) {
            Some(m) => m,
            None => self.general(line),
        }
    }

    /// The move of a line of the short form, `G0` or `G1` and then words of
    /// an ASCII capital and a plain decimal ([`plain`]), a single space
    /// before each, read in one pass; `None` when the line is not of that
    /// form. The same move [`Parser::general`] reads from such a line.
    fn short(&mut self, line: &[u8]) -> Option<Option<Move>> {
        let g0 = match line.get(..3)? {
            b"G0 " => true,
            b"G1 " => false,
            _ => return None,
        };
        let mut words = [(0u8, 0.0f64); 8];
        let mut n = 0;
        let mut rest = &line[3..];
        loop {
            let (&letter, tail) = rest.split_first()?;
            if !letter.is_ascii_uppercase() || n == words.len() {
                return None;
            }
            let (v, len) = plain(tail)?;
            words[n] = (letter, v);
            n += 1;
            if len == tail.len() {
                break;
            }
            rest = &tail[len + 1..];
        }
        Some(self.go(g0, words[..n].iter().copied()))
    }

    /// The move `line` makes, if it moves the head, read the general way:
    /// as bytes, or, when its code (before any `;`) is not all ASCII, as
    /// text, as `str::split_whitespace` and `str::parse` read it.
    fn general(&mut self, line: &[u8]) -> Option<Move> {
        if line.starts_with(b"; part: ") {
            self.part += 1;
        }
        let code = line.split(|&b| b == b';').next().unwrap_or(&[]);
        if !code.is_ascii() {
            let text = String::from_utf8_lossy(code);
            let words: Vec<&[u8]> = text.split_whitespace().map(str::as_bytes).collect();
            return self.words(&words);
        }
        let mut words: [&[u8]; 8] = [&[]; 8];
        let mut n = 0;
        for w in code.split(|&b| space(b)).filter(|w| !w.is_empty()) {
            if n == words.len() {
                // a long line: as many words as it has
                let all: Vec<&[u8]> = code
                    .split(|&b| space(b))
                    .filter(|w| !w.is_empty())
                    .collect();
                return self.words(&all);
            }
            words[n] = w;
            n += 1;
        }
        self.words(&words[..n])
    }

    /// The move a `G0` (`g0`) or `G1` of these words (each its first byte
    /// and its value, those with no value left out) makes, if it moves the
    /// head.
    fn go(&mut self, g0: bool, words: impl Iterator<Item = (u8, f64)>) -> Option<Move> {
        let mut moved = false;
        let mut has_e = false;
        let mut de = 0.0;
        for (letter, v) in words {
            match letter {
                b'X' => (self.pos[0], moved) = (v, true),
                b'Y' => (self.pos[1], moved) = (v, true),
                b'Z' => (self.pos[2], moved) = (v, true),
                b'E' => {
                    has_e = true;
                    de = if self.relative { v } else { v - self.e };
                    self.e = if self.relative { self.e + v } else { v };
                }
                b'F' => self.feed = v,
                _ => {}
            }
        }
        moved.then(|| Move {
            to: DVec3::from_array(self.pos) - self.origin,
            feed: self.feed,
            de,
            g0,
            extrudes: !g0 && has_e,
            part: self.part,
            machine_um: if self.um {
                self.pos.map(|x| libm::round(x * 1e3) as i64)
            } else {
                [0; 3]
            },
        })
    }

    /// The move a line of these words makes, if it moves the head.
    fn words(&mut self, words: &[&[u8]]) -> Option<Move> {
        let (&cmd, words) = words.split_first()?;
        // a word's letter, and the number after it (a word is not empty)
        let value = |w: &[u8]| {
            if w[0].is_ascii() {
                return number(&w[1..]);
            }
            let first = std::str::from_utf8(w).ok()?.chars().next()?;
            number(&w[first.len_utf8()..])
        };
        match cmd {
            b"M82" => self.relative = false,
            b"M83" => self.relative = true,
            b"G92" => {
                for &w in words {
                    if w.starts_with(b"E") {
                        self.e = value(w).unwrap_or(self.e);
                    }
                }
            }
            b"G0" | b"G1" => {
                let words = words.iter().filter_map(|&w| Some((w[0], value(w)?)));
                return self.go(cmd == b"G0", words);
            }
            _ => {}
        }
        None
    }
}

/// G-code read as it is written (a writer): per move only what the viewer
/// draws, neither the text nor the [`Move`]s kept ([`reader`] makes one).
pub(crate) struct Reader {
    parser: Parser,
    /// The end of the last line, not yet read.
    partial: Vec<u8>,
    /// Per path, the strings the checks flagged (as [`Scene::flagged`]),
    /// kept for the scene.
    pub(super) flags: Vec<Vec<bool>>,
    /// The machine end points (µm) of the flagged strings.
    flagged_ends: HashSet<[i64; 3]>,
    /// Filament cross-section, mm².
    area: f64,
    pub(super) to: Vec<DVec3>,
    pub(super) feed: Vec<f64>,
    /// Kinds (0 travel, 1 extrude, 2 flagged, 3 dry).
    pub(super) kind: Vec<u8>,
    /// The cross-section each move lays, mm².
    pub(super) c: Vec<f64>,
    /// (part number, first move) of each run of moves of one part.
    pub(super) parts: Vec<(usize, usize)>,
    pub(super) bmin: DVec3,
    pub(super) bmax: DVec3,
}

impl Reader {
    pub(super) fn new(origin: DVec3, flagged_ends: HashSet<[i64; 3]>, area: f64) -> Reader {
        Reader {
            parser: Parser {
                // the machine position is only looked up among the flagged ends
                um: !flagged_ends.is_empty(),
                ..Parser::new(origin)
            },
            partial: Vec::new(),
            flags: Vec::new(),
            flagged_ends,
            area,
            to: Vec::new(),
            feed: Vec::new(),
            kind: Vec::new(),
            c: Vec::new(),
            parts: Vec::new(),
            bmin: DVec3::splat(f64::INFINITY),
            bmax: DVec3::splat(f64::NEG_INFINITY),
        }
    }

    fn read_line(&mut self, line: &[u8]) {
        let Some(m) = self.parser.line(line) else {
            return;
        };
        let k = self.to.len();
        if self.parts.last().is_none_or(|p| p.0 != m.part) {
            self.parts.push((m.part, k));
        }
        let prev = self.to.last().copied();
        let kind = if m.g0 {
            0u8
        } else if !m.extrudes {
            3
        } else if self.flagged_ends.contains(&m.machine_um) {
            2
        } else {
            1
        };
        let mut c = 0.0;
        if m.extrudes {
            // the cross-section the move lays: filament volume over length
            let len = prev.map_or(0.0, |p| p.distance(m.to));
            if len > 0.0 {
                c = m.de.max(0.0) * self.area / len;
            }
            let prev = prev.unwrap_or(m.to);
            self.bmin = self.bmin.min(prev).min(m.to);
            self.bmax = self.bmax.max(prev).max(m.to);
        }
        self.to.push(m.to);
        self.feed.push(m.feed);
        self.kind.push(kind);
        self.c.push(c);
    }

    /// Reads all of `bytes` and what is left of the last line.
    pub(super) fn read_all(&mut self, bytes: &[u8]) {
        // a reader takes every byte it is given
        let _ = self.write(bytes);
        self.end();
    }

    /// Reads what is left of the last line (G-code ending without a newline).
    pub(super) fn end(&mut self) {
        let rest = std::mem::take(&mut self.partial);
        if !rest.is_empty() {
            self.read_line(&rest);
        }
    }
}

impl std::io::Write for Reader {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let mut rest = buf;
        while let Some(at) = rest.iter().position(|&b| b == b'\n') {
            if self.partial.is_empty() {
                self.read_line(&rest[..at]);
            } else {
                let mut line = std::mem::take(&mut self.partial);
                line.extend_from_slice(&rest[..at]);
                self.read_line(&line);
            }
            rest = &rest[at + 1..];
        }
        self.partial.extend_from_slice(rest);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_read_back_absolute_and_relative() {
        let g = "G28\nG0 X110.000 Y110.000 Z0.200 F7200\n; part: a (2 strings)\nG1 X111.000 E0.05000 F1800\nG1 E-0.8 ; retract\nG1 E0.05 ; unretract\nG1 Y111.000 E0.10000\nM83\nG1 X110.000 E0.02\nG0 Z5\n";
        let m = moves(g, DVec3::new(110.0, 110.0, 0.0));
        assert_eq!(m.len(), 5);
        assert_eq!(m[0].to, DVec3::new(0.0, 0.0, 0.2));
        assert!(m[0].g0 && m[0].part == 0);
        assert!((m[1].de - 0.05).abs() < 1e-12 && m[1].feed == 1800.0 && m[1].part == 1);
        // the unretract restored E to 0.05; this move feeds 0.05
        assert!((m[2].de - 0.05).abs() < 1e-12);
        assert!((m[3].de - 0.02).abs() < 1e-12);
        assert!(m[3].extrudes && !m[4].extrudes && !m[0].extrudes);
        assert_eq!(m[4].machine_um, [110_000, 111_000, 5_000]);
    }

    #[test]
    fn the_reader_reads_what_moves_reads_however_the_text_is_cut() {
        let g = "G28\nG0 X110.000 Y110.000 Z0.200 F7200\n; part: a (2 strings)\nG1 X111.000 E0.05000 F1800\nG1 E-0.8 ; retract\nG1 E0.05 ; unretract\nG1 Y111.000 E0.10000\nM83\nG1 X110.000 E0.02\nG0 Z5";
        let origin = DVec3::new(110.0, 110.0, 0.0);
        let m = moves(g, origin);
        for cut in [1, 2, 7, 1000] {
            let mut r = Reader::new(origin, HashSet::new(), 2.0);
            for chunk in g.as_bytes().chunks(cut) {
                r.write_all(chunk).unwrap();
            }
            r.end();
            assert_eq!(r.to, m.iter().map(|x| x.to).collect::<Vec<_>>(), "{cut}");
            assert_eq!(r.kind, [0, 1, 1, 1, 0], "{cut}");
            assert_eq!(r.parts, [(0, 0), (1, 1)], "{cut}");
            // 0.05 mm of filament of 2 mm² over 1 mm
            assert!((r.c[1] - 0.1).abs() < 1e-12, "{cut}: {:?}", r.c);
        }
    }

    #[test]
    fn numbers_read_as_parse_reads_them_bit_for_bit() {
        let mut words: Vec<String> = [
            "",
            "-",
            "+",
            ".",
            "-.",
            "0",
            "-0",
            "-0.000",
            "+1.5",
            ".5",
            "5.",
            "-.5",
            "+.5",
            "1.2.3",
            "--1",
            "1e3",
            "1E-2",
            "inf",
            "-inf",
            "NaN",
            "0x10",
            "12a",
            "1 2",
            "123456789012345",
            "1234567890123456",
            "0.000000000000001",
            "0.0000000000000001",
            "9007199254740993",
            "110.000",
            "0.05000",
            "1e400",
        ]
        .iter()
        .map(|w| w.to_string())
        .collect();
        // numbers as p3dp writes them, and some wider and longer
        let mut x: u64 = 0x2545_F491_4F6C_DD1D;
        for _ in 0..20_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = (x % 2_000_000_000) as f64 / 1000.0 - 1e6;
            let places = (x >> 40) as usize % 16;
            words.push(format!("{v:.places$}"));
            words.push(format!("{}", f64::from_bits(x >> 2)));
        }
        for w in &words {
            let want = w.parse::<f64>().ok();
            let got = number(w.as_bytes());
            assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{w:?}");
        }
    }

    #[test]
    fn short_lines_read_as_the_general_way_reads_them() {
        let mut lines: Vec<Vec<u8>> = [
            "G1 X1 Y2 Z3 E4 F5",
            "G0 X150.051 Y110.000 Z0.200 F7200",
            "G1 X150.126 Y110.252 E0.01049 F2400",
            "M83",
            "G1 E-0.8",
            "G1 X-0.5 E+0.25",
            "G92 E0",
            "M82",
            "G1 X1 Y2 ",
            "G1  X1",
            "G1 X1\r",
            "G1 X1 ; a",
            "G1 X1\tY2",
            "G1 x1 Y2",
            "G1 X1e3 Y2",
            "G1 X1234567890123456 Y2",
            "G1 X1..2",
            "G1 X. Y2",
            "G1 X",
            "G1 ",
            "G1",
            "G1 A1 B2 C3 D4 I5 J6 K7 X8",
            "G1 A1 B2 C3 D4 I5 J6 K7 L8 X10",
            "G1 XÉ Y2",
            "G2 X1 Y2",
        ]
        .iter()
        .map(|l| l.as_bytes().to_vec())
        .collect();
        lines.push(b"G1 X1 \xff Y2".to_vec());
        let (mut both, mut general) = (Parser::new(DVec3::ZERO), Parser::new(DVec3::ZERO));
        for l in &lines {
            let got = both.line(l);
            assert_eq!(got, general.general(l), "{:?}", String::from_utf8_lossy(l));
            assert_eq!((both.e, both.feed), (general.e, general.feed));
        }
        assert!(Parser::new(DVec3::ZERO).short(&lines[1]).is_some());
        assert!(Parser::new(DVec3::ZERO).short(&lines[9]).is_none());
    }

    #[test]
    fn lines_with_other_text_read_as_before() {
        let origin = DVec3::ZERO;
        let mut p = Parser::new(origin);
        // whitespace of every kind between the words, a comment with anything in it
        let m = p
            .line("G1\tX1.5\x0bY2 \x0cZ3\r ; é ; part: x".as_bytes())
            .unwrap();
        assert_eq!(m.to, DVec3::new(1.5, 2.0, 3.0));
        // a word that is not ASCII, and bytes that are not UTF-8, are skipped
        let m = p.line("G1 X4 ÉY7 Y5".as_bytes()).unwrap();
        assert_eq!(m.to, DVec3::new(4.0, 5.0, 3.0));
        let m = p.line(b"G1 X6 \xff Y8\xfe Z9").unwrap();
        assert_eq!(m.to, DVec3::new(6.0, 5.0, 9.0));
        // more words than usual
        let m = p.line(b"G1 A1 B2 C3 D4 I5 J6 K7 L8 X10").unwrap();
        assert_eq!(m.to.x, 10.0);
        assert!(p.line(b"; G1 X1").is_none() && p.line(b"").is_none());
    }
}
