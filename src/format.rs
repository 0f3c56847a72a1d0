//! Numbers as text: the fixed-point coordinates of G-code, the short numbers
//! of comments and templates, and print times.

/// Rounds `x` to integer units of 10^-`decimals`.
#[inline]
pub fn units(x: f64, scale: f64) -> i64 {
    libm::round(x * scale) as i64
}

/// Appends `v / 10^decimals` in fixed point, e.g. `-12.345`.
pub fn put_fixed(buf: &mut Vec<u8>, v: i64, decimals: u32) {
    let pow = 10i64.pow(decimals);
    if v < 0 {
        buf.push(b'-');
    }
    let a = v.unsigned_abs();
    let mut ib = itoa::Buffer::new();
    buf.extend_from_slice(ib.format(a / pow as u64).as_bytes());
    buf.push(b'.');
    let frac = ib.format(a % pow as u64);
    for _ in frac.len()..decimals as usize {
        buf.push(b'0');
    }
    buf.extend_from_slice(frac.as_bytes());
}

/// A temperature or size for a comment or template: integers without decimals.
pub fn fmt_num(v: f64) -> String {
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

/// Seconds as `1h 2m 3s` (the form slicers write).
pub fn hms(t: f64) -> String {
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

    fn fixed(v: f64, d: u32) -> String {
        let mut b = Vec::new();
        put_fixed(&mut b, units(v, 10f64.powi(d as i32)), d);
        String::from_utf8(b).unwrap()
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
