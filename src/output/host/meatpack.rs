//! MeatPack (Scott Mudge's packing of G-code, as the binary G-code's
//! blocks use it with comment lines kept; written from its published
//! protocol): the 15 most common characters of G-code take 4 bits, two to a
//! byte, and any other character a whole byte after them.
//!
//! - Codes 0–9 are the digits, 10 `.`, 11 a space (with "no spaces" on:
//!   `E`, the spaces of a `G` line being dropped), 12 `\n`, 13 `G`, 14 `X`;
//!   15 says that character comes whole in a byte of its own.
//! - A byte holds two characters, the first in its low half. When one is
//!   not packable its half is 15 and it follows whole; when neither is, the
//!   byte is `0xFF` and both follow. A `\n` in the low half ends the line:
//!   the high half is not read.
//! - `0xFF 0xFF` then a byte is a command: 251 packing on, 250 off, 247 no
//!   spaces on.
//!
//! What the encoding drops, as libbgcode's does: a comment after a command
//! (`G1 X1 ; retract` keeps `G1 X1`), blank lines, the spaces of a line
//! that starts with `G` and a digit (a reader puts them back before each
//! parameter letter), and leading and trailing spaces. Lines that are
//! wholly comments are kept as they are, with packing off around them.

const SIGNAL: u8 = 0xFF;
const PACKING_ON: u8 = 251;
const PACKING_OFF: u8 = 250;
const NO_SPACES_ON: u8 = 247;

/// The 4-bit code of `c` with "no spaces" on, or None when it goes whole.
fn code(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'.' => Some(10),
        b'E' => Some(11),
        b'\n' => Some(12),
        b'G' => Some(13),
        b'X' => Some(14),
        _ => None,
    }
}

/// Packs the lines of `text` (a block of G-code) on their own: packing and
/// "no spaces" are switched on at the start.
pub(crate) fn pack(text: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(text.len() / 2);
    out.extend_from_slice(&[SIGNAL, SIGNAL, PACKING_ON, SIGNAL, SIGNAL, NO_SPACES_ON]);
    let mut packing = true;
    let mut line = Vec::new();
    for raw in text.split(|&b| b == b'\n') {
        if raw.first() == Some(&b';') {
            if packing {
                out.extend_from_slice(&[SIGNAL, SIGNAL, PACKING_OFF]);
                packing = false;
            }
            out.extend_from_slice(raw);
            out.push(b'\n');
            continue;
        }
        let cmd = raw.split(|&b| b == b';').next().unwrap_or_default();
        let cmd = cmd.trim_ascii();
        if cmd.is_empty() {
            continue;
        }
        line.clear();
        let g_line = cmd.len() > 1 && cmd[0] == b'G' && cmd[1].is_ascii_digit();
        line.extend(cmd.iter().copied().filter(|&b| !(g_line && b == b' ')));
        line.push(b'\n');
        if !packing {
            out.extend_from_slice(&[SIGNAL, SIGNAL, PACKING_ON]);
            packing = true;
        }
        for pair in line.chunks(2) {
            // an odd line's last `\n` is paired with another, never read
            let (a, b) = (pair[0], *pair.get(1).unwrap_or(&b'\n'));
            match (code(a), code(b)) {
                (Some(x), Some(y)) => out.push(x | y << 4),
                (Some(x), None) => out.extend_from_slice(&[x | 0xF0, b]),
                (None, Some(y)) => out.extend_from_slice(&[0x0F | y << 4, a]),
                (None, None) => out.extend_from_slice(&[0xFF, a, b]),
            }
        }
    }
    out
}

#[cfg(test)]
/// Unpacks what [`pack`] wrote (from the protocol above, for the tests):
/// the G-code as the firmware reads it, spaces of `G` lines left out.
pub(crate) fn unpack(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let (mut packing, mut no_spaces) = (false, false);
    let mut i = 0;
    let ch = |c: u8, no_spaces: bool| match c {
        0..=9 => b'0' + c,
        10 => b'.',
        11 if no_spaces => b'E',
        11 => b' ',
        12 => b'\n',
        13 => b'G',
        _ => b'X',
    };
    while i < data.len() {
        if data[i] == SIGNAL && data.get(i + 1) == Some(&SIGNAL) {
            match data.get(i + 2) {
                Some(&PACKING_ON) => packing = true,
                Some(&PACKING_OFF) => packing = false,
                Some(&NO_SPACES_ON) => no_spaces = true,
                _ => {}
            }
            i += 3;
            continue;
        }
        let b = data[i];
        i += 1;
        if !packing {
            out.push(b);
            continue;
        }
        let (lo, hi) = (b & 0xF, b >> 4);
        let whole = |out: &mut Vec<u8>, i: &mut usize| {
            out.push(data[*i]);
            *i += 1;
        };
        if lo == 0xF {
            whole(&mut out, &mut i);
        } else {
            out.push(ch(lo, no_spaces));
            if lo == 12 {
                continue;
            }
        }
        if hi == 0xF {
            whole(&mut out, &mut i);
        } else {
            out.push(ch(hi, no_spaces));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packs_and_unpacks_g_code() {
        let text = b"; a comment line\nG1 X10.5 Y20 E0.12345 F1200 ; with a comment\nM104 S210\n\nG0 Z1\nM73 P5 R12\n;LAYER_CHANGE\nG2 X1 Y2 I-3.5 J4 E5\n";
        let packed = pack(text);
        assert!(packed.len() < text.len());
        let back = unpack(&packed);
        assert_eq!(
            String::from_utf8(back).unwrap(),
            "; a comment line\nG1X10.5Y20E0.12345F1200\nM104 S210\nG0Z1\nM73 P5 R12\n;LAYER_CHANGE\nG2X1Y2I-3.5J4E5\n"
        );
    }
}
