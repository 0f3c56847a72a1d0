//! Numbers as text: the fixed-point coordinates of G-code, the short numbers
//! of comments and templates, and print times.

/// Rounds `x` to integer units of 10^-`decimals` (`scale` = 10^`decimals`).
#[inline]
pub(crate) fn units(x: f64, scale: f64) -> i64 {
    round_i64(x * scale)
}

/// `libm::round(y) as i64` (halves away from zero, saturating, NaN to 0)
/// without the call, and without a branch to mispredict.
///
/// libm's `round(y)` is `trunc(y + copysign(0.5 − ε/4, y))` (0.5 − ε/4 is
/// exact in f64: the largest double below 0.5, so that y + it rounds up
/// to the next integer only from a half on). `as i64` truncates toward
/// zero, saturates and sends NaN to 0, so it gives the same integer for s
/// and for trunc(s): the one sum, then the cast. A test compares both on
/// many millions of values, halves and their neighbours included.
#[inline]
pub(crate) fn round_i64(y: f64) -> i64 {
    (y + (0.5 - 0.25 * f64::EPSILON).copysign(y)) as i64
}

/// "00".."99": two digits at a time.
const PAIRS: &[u8; 200] = b"\
0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// The decimal digits of `x`.
#[inline]
fn digits(x: u64) -> usize {
    x.checked_ilog10().unwrap_or(0) as usize + 1
}

/// Writes the decimal digits of `x` so that they end just before `end`.
#[inline]
fn digits_before(out: &mut [u8], mut end: usize, mut x: u64) {
    while x >= 100 {
        let r = (x % 100) as usize * 2;
        x /= 100;
        end -= 2;
        out[end..end + 2].copy_from_slice(&PAIRS[r..r + 2]);
    }
    if x >= 10 {
        let r = x as usize * 2;
        out[end - 2..end].copy_from_slice(&PAIRS[r..r + 2]);
    } else {
        out[end - 1] = b'0' + x as u8;
    }
}

/// A buffer of G-code text, written in chunks: lines are formatted straight
/// into it and it is handed on whole once [`Chunk::full`], so each byte is
/// copied once on its way out. Writes never fail nor run out of room (the
/// buffer grows for a long text); the number writers print from integers
/// without allocating.
pub(crate) struct Chunk {
    /// Zero-filled room; the text is `buf[..len]`.
    buf: Vec<u8>,
    len: usize,
}

impl Default for Chunk {
    fn default() -> Chunk {
        Chunk::new()
    }
}

impl Chunk {
    /// Handed on when this long (the hashing writer's buffer size, so that
    /// its chunks pass it by without a copy).
    pub(crate) const SIZE: usize = 1 << 16;

    /// An empty chunk with room for [`Chunk::SIZE`] bytes and a line more.
    pub(crate) fn new() -> Chunk {
        Chunk {
            buf: vec![0; Chunk::SIZE + 1024],
            len: 0,
        }
    }

    /// Whether it is long enough to hand on.
    #[inline]
    pub(crate) fn full(&self) -> bool {
        self.len >= Chunk::SIZE
    }

    #[cfg(test)]
    /// Whether it holds nothing.
    #[inline]
    pub(crate) fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The text so far.
    #[inline]
    pub(crate) fn bytes(&self) -> &[u8] {
        &self.buf[..self.len]
    }

    /// Empties it (its room is kept).
    #[inline]
    pub(crate) fn clear(&mut self) {
        self.len = 0;
    }

    /// Makes room for `n` more bytes.
    #[inline]
    fn room(&mut self, n: usize) {
        if self.len + n > self.buf.len() {
            self.buf.resize(self.len + n + Chunk::SIZE, 0);
        }
    }

    /// Appends one byte.
    #[inline]
    pub(crate) fn push(&mut self, b: u8) {
        self.room(1);
        self.buf[self.len] = b;
        self.len += 1;
    }

    /// Appends bytes.
    #[inline]
    pub(crate) fn put(&mut self, s: &[u8]) {
        self.room(s.len());
        self.buf[self.len..self.len + s.len()].copy_from_slice(s);
        self.len += s.len();
    }

    /// Appends `v` in decimal.
    #[inline]
    pub(crate) fn put_int(&mut self, v: i64) {
        self.room(20);
        if v < 0 {
            self.buf[self.len] = b'-';
            self.len += 1;
        }
        let a = v.unsigned_abs();
        let n = digits(a);
        digits_before(&mut self.buf, self.len + n, a);
        self.len += n;
    }

    /// Appends `v / 10^D` in fixed point with `D` decimals (1 ≤ D ≤ 7),
    /// e.g. `-12.345`, as `format!` would print the exact quotient: no
    /// exponent, a `-` only when `v` < 0.
    #[inline(always)]
    pub(crate) fn put_fixed<const D: u32>(&mut self, v: i64) {
        const { assert!(D >= 1 && D <= 7) };
        let d = D as usize;
        self.room(48);
        let mut at = self.len;
        if v < 0 {
            self.buf[at] = b'-';
            at += 1;
        }
        let a = v.unsigned_abs();
        // the last 8 digits at once; any above them one by one
        let (high, low) = (a / 100_000_000, (a % 100_000_000) as u32);
        let w = eight_digits(low);
        if high == 0 {
            // low's digits without its leading zeros, but at least D + 1:
            // the first of the word's bytes is its leading digit
            let zeros = (w & 0x0f0f_0f0f_0f0f_0f0f).trailing_zeros() as usize / 8;
            let t = (8 - zeros).max(d + 1);
            let word = (w >> (8 * (8 - t))).to_le_bytes();
            self.buf[at..at + 8].copy_from_slice(&word);
            at += t - d;
        } else {
            if high < 100_000_000 {
                // a word of high's digits, its leading zeros shifted out
                let h = eight_digits(high as u32);
                let zeros = (h & 0x0f0f_0f0f_0f0f_0f0f).trailing_zeros() as usize / 8;
                self.buf[at..at + 8].copy_from_slice(&(h >> (8 * zeros)).to_le_bytes());
                at += 8 - zeros;
            } else {
                let n = digits(high);
                digits_before(&mut self.buf, at + n, high);
                at += n;
            }
            self.buf[at..at + 8].copy_from_slice(&w.to_le_bytes());
            at += 8 - d;
        }
        // the point, then the last D digits (the bytes after them are room)
        self.buf[at] = b'.';
        let frac = (w >> (8 * (8 - d))).to_le_bytes();
        self.buf[at + 1..at + 9].copy_from_slice(&frac);
        self.len = at + 1 + d;
    }
}

/// The 8 decimal digits of `x` < 10^8 in ASCII, zero-padded, the leading
/// one in the lowest byte (so the word's little-endian bytes read as text).
///
/// All in one 64-bit word, lanes of one number each: x = 10^4·h + l puts h
/// and l in two 32-bit lanes; n·10486 >> 20 = ⌊n/100⌋ for n < 43,699 splits
/// each into two 16-bit lanes (⌊n/100⌋, n mod 100), and n·103 >> 10 =
/// ⌊n/10⌋ for n < 179 each of those into two bytes. No lane's product
/// reaches the next lane, and the masks drop what shifts in from above.
#[inline]
fn eight_digits(x: u32) -> u64 {
    let x = x as u64;
    let merged = (x / 10_000) | ((x % 10_000) << 32);
    let top = ((merged * 10_486) >> 20) & ((0x7f << 32) | 0x7f);
    let hundreds = ((merged - 100 * top) << 16) + top;
    let mut tens = ((hundreds * 103) >> 10) & 0x000f_000f_000f_000f;
    tens += (hundreds - 10 * tens) << 8;
    tens | 0x3030_3030_3030_3030
}

/// A temperature or size for a comment or template: integers without decimals.
pub(crate) fn fmt_num(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        let s = format!("{v:.3}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        // −0.0004 rounds to "-0.000": no sign on a zero
        if s == "-0" {
            "0".to_string()
        } else {
            s.to_string()
        }
    }
}

/// A value put into a name or a recipe's printer command (`{expr}`):
/// integers without decimals, others with up to 6, never `-0`.
pub(crate) fn fmt_value(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        let s = format!("{v:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".into()
        } else {
            s.to_string()
        }
    }
}

/// A piece of a text with values in braces (a name such as `ring-{k}`, a
/// printer command such as `M900 K{0.01*k}`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Piece<'a> {
    /// Text as it is.
    Text(&'a str),
    /// An expression's source, between its braces.
    Expr(&'a str),
}

/// `text` cut into text and `{expr}`s: a `{` always opens an expression
/// and the next `}` closes it, as in the slicers' macro language of the
/// start and end G-code (neither has an escape: a recipe's expressions
/// are numbers, so no value holds a brace). `Err` for a `{` without its
/// `}`, saying so.
pub(crate) fn pieces(text: &str) -> std::result::Result<Vec<Piece<'_>>, String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(open) = rest.find('{') {
        if open > 0 {
            out.push(Piece::Text(&rest[..open]));
        }
        let after = &rest[open + 1..];
        let close = after
            .find('}')
            .ok_or_else(|| format!("{text:?} has a `{{` without its `}}`; expected `{{EXPR}}`"))?;
        out.push(Piece::Expr(&after[..close]));
        rest = &after[close + 1..];
    }
    if !rest.is_empty() {
        out.push(Piece::Text(rest));
    }
    Ok(out)
}

/// Seconds as `1h 2m 3s` (the form slicers write).
pub(crate) fn hms(t: f64) -> String {
    let s = libm::round(t) as u64;
    let (h, m, s) = (s / 3600, s / 60 % 60, s % 60);
    if h > 0 {
        format!("{h}h {m}m {s}s")
    } else if m > 0 {
        format!("{m}m {s}s")
    } else {
        format!("{s}s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn braces_cut_text_into_text_and_expressions() {
        assert_eq!(
            pieces("M900 K{0.01*k} ; {k}").unwrap(),
            vec![
                Piece::Text("M900 K"),
                Piece::Expr("0.01*k"),
                Piece::Text(" ; "),
                Piece::Expr("k"),
            ]
        );
        assert_eq!(pieces("M600").unwrap(), vec![Piece::Text("M600")]);
        assert_eq!(pieces("").unwrap(), vec![]);
        // a `}` alone is text; a `{` alone is an error naming the text
        assert_eq!(pieces("a}b").unwrap(), vec![Piece::Text("a}b")]);
        let e = pieces("M117 {k").unwrap_err();
        assert!(
            e.contains("\"M117 {k\"") && e.contains("without its `}`"),
            "{e}"
        );
        assert_eq!(fmt_value(0.0125), "0.0125");
        assert_eq!(fmt_value(3.0), "3");
        assert_eq!(fmt_value(-1e-9), "0");
        assert_eq!(fmt_value(1.0 / 3.0), "0.333333");
    }

    /// The formatter before [`Chunk`]: libm's round, then itoa's digits,
    /// written into `s` (cleared first, so that a long comparison reuses
    /// one buffer).
    fn reference_into(s: &mut String, v: f64, d: u32) {
        let u = libm::round(v * 10f64.powi(d as i32)) as i64;
        let pow = 10i64.pow(d);
        s.clear();
        if u < 0 {
            s.push('-');
        }
        let a = u.unsigned_abs();
        let mut ib = itoa::Buffer::new();
        s.push_str(ib.format(a / pow as u64));
        s.push('.');
        let frac = ib.format(a % pow as u64);
        for _ in frac.len()..d as usize {
            s.push('0');
        }
        s.push_str(frac);
    }

    /// `v` with `d` decimals as [`Chunk::put_fixed`] writes it, through `c`
    /// (cleared first: a new chunk is 65 kB of zeroed room).
    fn fixed_in(c: &mut Chunk, v: f64, d: u32) -> &str {
        c.clear();
        match d {
            3 => c.put_fixed::<3>(units(v, 1e3)),
            5 => c.put_fixed::<5>(units(v, 1e5)),
            _ => unreachable!("the G-code's decimals are 3 and 5"),
        }
        std::str::from_utf8(c.bytes()).unwrap()
    }

    fn fixed(v: f64, d: u32) -> String {
        fixed_in(&mut Chunk::new(), v, d).to_string()
    }

    #[test]
    fn fixed_point_never_exponent_nor_negative_zero() {
        assert_eq!(fixed(3e-5, 5), "0.00003");
        assert_eq!(fixed(-0.0001, 3), "0.000");
        assert_eq!(fixed(-0.0, 3), "0.000");
        assert_eq!(fixed(-12.3456, 3), "-12.346");
        assert_eq!(fixed(110.0, 3), "110.000");
        assert_eq!(fixed(1234567.5, 5), "1234567.50000");
    }

    /// SplitMix64's next value (the generator of `crate::base::rng`, inlined).
    fn next(state: &mut u64) -> u64 {
        *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Halves, integers and their neighbours at every scale, the limits of
    /// i64 and of exact integers, zeros, infinities, NaN, subnormals.
    fn edges() -> Vec<f64> {
        let mut v = vec![
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            5e-324,
            0.49999999999999994,
            i64::MAX as f64,
            (i64::MAX as f64).next_down(),
            i64::MIN as f64,
            (i64::MIN as f64).next_up(),
        ];
        let mut x = 0.5f64;
        while x < 1e20 {
            for base in [x, x + 0.5, x * 3.0, x + 1.0] {
                let mut b = base;
                for _ in 0..3 {
                    b = b.next_down();
                }
                for _ in 0..7 {
                    v.extend([b, -b]);
                    b = b.next_up();
                }
            }
            x *= 2.0;
        }
        for k in 0..20_000 {
            let h = k as f64 + 0.5;
            v.extend([
                h,
                -h,
                h.next_up(),
                h.next_down(),
                -h.next_up(),
                -h.next_down(),
            ]);
        }
        v
    }

    #[test]
    fn round_i64_is_libm_round_as_i64() {
        let same = |y: f64| {
            assert_eq!(
                round_i64(y),
                libm::round(y) as i64,
                "{y:e} ({:#x})",
                y.to_bits()
            );
        };
        for y in edges() {
            same(y);
        }
        let mut st = 21;
        for _ in 0..4_000_000 {
            // any bit pattern: every exponent, sign and NaN payload
            same(f64::from_bits(next(&mut st)));
            // coordinates and filament totals as the emitter scales them
            let u = (next(&mut st) >> 11) as f64 / (1u64 << 53) as f64;
            same((u - 0.5) * 2e6);
            same((u - 0.5) * 2e11);
            // values a hair either side of a half
            let h = (next(&mut st) % 2_000_000) as f64 - 1e6 + 0.5;
            same(h);
            same(h.next_up());
            same(h.next_down());
        }
    }

    #[test]
    fn chunk_numbers_are_the_old_formatter_s() {
        let mut st = 7;
        let (mut c, mut s) = (Chunk::new(), String::new());
        let mut check = |v: f64| {
            for d in [3, 5] {
                reference_into(&mut s, v, d);
                assert_eq!(fixed_in(&mut c, v, d), s, "{v:e} with {d} decimals");
            }
        };
        for v in edges() {
            check(v);
            check(v / 1e3);
            check(v / 1e5);
        }
        for _ in 0..1_000_000 {
            let u = (next(&mut st) >> 11) as f64 / (1u64 << 53) as f64;
            check((u - 0.5) * 2000.0);
            check((u - 0.5) * 2e7);
            check(f64::from_bits(next(&mut st)));
        }
        let mut ib = itoa::Buffer::new();
        let mut ints = vec![0, 1, -1, 9, 10, 99, 100, 101, i64::MAX, i64::MIN];
        ints.extend((0..100_000).map(|_| next(&mut st) as i64 >> (next(&mut st) % 64)));
        for v in ints {
            c.clear();
            c.put_int(v);
            assert_eq!(c.bytes(), ib.format(v).as_bytes());
        }
    }

    #[test]
    fn eight_digits_are_the_zero_padded_number() {
        let mut st = 3;
        let xs = (0..1_000_000u32)
            .chain((0..1_000_000).map(|_| (next(&mut st) % 100_000_000) as u32))
            .chain((0..100).map(|k| 99_999_999 - k));
        for x in xs {
            assert_eq!(eight_digits(x).to_le_bytes(), *format!("{x:08}").as_bytes());
        }
    }

    #[test]
    fn a_chunk_grows_for_long_text_and_keeps_it_in_order() {
        let mut c = Chunk::new();
        let long = vec![b'x'; 3 * Chunk::SIZE + 5];
        c.put(b"G1");
        c.put(&long);
        c.put_fixed::<3>(-1234);
        c.push(b'\n');
        assert!(c.full());
        assert_eq!(c.bytes().len(), 2 + long.len() + 7);
        assert!(c.bytes().starts_with(b"G1xx"));
        assert!(c.bytes().ends_with(b"xx-1.234\n"));
        c.clear();
        assert!(c.is_empty());
    }

    #[test]
    fn time_format() {
        assert_eq!(hms(3723.4), "1h 2m 3s");
        assert_eq!(hms(59.6), "1m 0s");
        assert_eq!(hms(5.0), "5s");
    }

    #[test]
    fn short_numbers() {
        assert_eq!(fmt_num(210.0), "210");
        assert_eq!(fmt_num(1.75), "1.75");
        assert_eq!(fmt_num(0.1234), "0.123");
        assert_eq!(fmt_num(-0.0004), "0");
        assert_eq!(fmt_num(-0.0), "0");
        assert_eq!(fmt_num(-2.5), "-2.5");
    }
}
