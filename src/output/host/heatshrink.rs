//! A heatshrink encoder (the LZSS of Atomic Object's heatshrink, as the
//! binary G-code's blocks use it; written here from its published format).
//!
//! The output is a bit stream, most significant bit first: a `1` bit then
//! 8 bits is a literal byte; a `0` bit then `W` bits of (offset − 1) and `L`
//! bits of (length − 1) copies `length` bytes from `offset` bytes back in
//! what was decoded (offset ≤ 2^W, length ≤ 2^L); the last byte is padded
//! with zero bits, too few to be a token. A copy costs 1 + W + L bits and
//! saves 9 a byte, so one of 2 bytes or more pays (W = 12, L = 4: 17 bits
//! against 18). Matches are found through chains of earlier positions that
//! share the next three bytes (at most [`CHAIN`] looked at), the longest
//! taken, the nearest among equals: the same input gives the same bytes.

/// Positions looked at per byte, at most.
const CHAIN: usize = 48;

/// Compresses `input` with a window of 2^`w` bytes and copies of up to
/// 2^`l` bytes.
pub(crate) fn encode(input: &[u8], w: u32, l: u32) -> Vec<u8> {
    let window = 1usize << w;
    let longest = 1usize << l;
    let mut out = Bits::default();
    // head[h]: the last position whose next three bytes hash to h; prev[i]:
    // the position before i with the same hash (usize::MAX: none)
    const HASH: usize = 1 << 14;
    let mut head = vec![usize::MAX; HASH];
    let mut prev = vec![usize::MAX; input.len()];
    let hash = |i: usize| {
        let a = input[i] as usize;
        let b = input[i + 1] as usize;
        let c = input[i + 2] as usize;
        ((a << 6) ^ (b << 3) ^ c ^ (a >> 2)) & (HASH - 1)
    };
    let insert = |i: usize, head: &mut Vec<usize>, prev: &mut Vec<usize>| {
        if i + 2 < input.len() {
            let h = hash(i);
            prev[i] = head[h];
            head[h] = i;
        }
    };
    let mut i = 0;
    while i < input.len() {
        let (mut best_len, mut best_off) = (0usize, 0usize);
        if i + 2 < input.len() {
            let max = longest.min(input.len() - i);
            let mut cand = head[hash(i)];
            let mut looked = 0;
            while cand != usize::MAX && i - cand <= window && looked < CHAIN {
                let n = input[cand..]
                    .iter()
                    .zip(&input[i..i + max])
                    .take_while(|(a, b)| a == b)
                    .count();
                if n > best_len {
                    (best_len, best_off) = (n, i - cand);
                    if n == max {
                        break;
                    }
                }
                cand = prev[cand];
                looked += 1;
            }
        }
        if best_len >= 2 {
            out.put(0, 1);
            out.put((best_off - 1) as u32, w);
            out.put((best_len - 1) as u32, l);
            for k in i..i + best_len {
                insert(k, &mut head, &mut prev);
            }
            i += best_len;
        } else {
            out.put(0x100 | u32::from(input[i]), 9);
            insert(i, &mut head, &mut prev);
            i += 1;
        }
    }
    out.finish()
}

/// A bit writer, most significant bit first.
#[derive(Default)]
struct Bits {
    bytes: Vec<u8>,
    acc: u32,
    n: u32,
}

impl Bits {
    fn put(&mut self, v: u32, bits: u32) {
        self.acc = (self.acc << bits) | v;
        self.n += bits;
        while self.n >= 8 {
            self.n -= 8;
            self.bytes.push((self.acc >> self.n) as u8);
        }
        self.acc &= (1 << self.n) - 1;
    }

    fn finish(mut self) -> Vec<u8> {
        if self.n > 0 {
            self.bytes.push((self.acc << (8 - self.n)) as u8);
        }
        self.bytes
    }
}

/// Decodes a heatshrink stream back into `size` bytes (from the format
/// above; None when it is not one).
#[cfg(any(test, feature = "testing"))]
pub(crate) fn decode(data: &[u8], size: usize, w: u32, l: u32) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(size);
    let mut pos = 0usize; // bit position
    let total = data.len() * 8;
    let get = |bits: u32, pos: &mut usize| -> Option<u32> {
        if *pos + bits as usize > total {
            return None;
        }
        let mut v = 0u32;
        for _ in 0..bits {
            let bit = (data[*pos / 8] >> (7 - *pos % 8)) & 1;
            v = (v << 1) | u32::from(bit);
            *pos += 1;
        }
        Some(v)
    };
    while out.len() < size {
        if get(1, &mut pos)? == 1 {
            out.push(get(8, &mut pos)? as u8);
        } else {
            let off = get(w, &mut pos)? as usize + 1;
            let len = get(l, &mut pos)? as usize + 1;
            if off > out.len() {
                return None;
            }
            for _ in 0..len {
                out.push(out[out.len() - off]);
            }
        }
    }
    (out.len() == size).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_shrinks_g_code() {
        let mut text = Vec::new();
        for k in 0..3000 {
            text.extend_from_slice(
                format!("G1X{}.{}Y12.5E{}\n", 100 + k % 7, k % 10, k).as_bytes(),
            );
        }
        for (w, l) in [(11, 4), (12, 4)] {
            let z = encode(&text, w, l);
            assert!(
                z.len() < text.len() * 6 / 10,
                "{} of {}",
                z.len(),
                text.len()
            );
            assert_eq!(decode(&z, text.len(), w, l).unwrap(), text);
        }
        for s in [
            &b""[..],
            b"a",
            b"ab",
            b"aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
            b"abcabcabd",
        ] {
            assert_eq!(decode(&encode(s, 12, 4), s.len(), 12, 4).unwrap(), s);
        }
    }
}
