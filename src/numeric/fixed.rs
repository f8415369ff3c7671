//! Fixed-point number formatting for big text tables, without allocation. Kept instead of
//! `format!("{v:.6}")` for its cost (the trace's rows: docs/performance.md, the trace table).

/// Appends `v` with `decimals` digits after the point, as `format!("{v:.decimals$}")` would
/// for |v| < 1e12 (round half away from zero on the scaled value), without the formatting
/// machinery: the trace writes twenty numbers per millisecond of machine time.
pub fn push_fixed(out: &mut String, v: f64, decimals: u32) {
    let mut buf = [0u8; 24];
    match digits(&mut buf, v, decimals) {
        Some(pos) => out.push_str(std::str::from_utf8(&buf[pos..]).expect("ASCII digits")),
        None => {
            let _ = std::fmt::Write::write_fmt(out, format_args!("{v:.*}", decimals as usize));
        }
    }
}

/// [`push_fixed`] into a byte buffer (ASCII), allocation-free once the buffer has room: the
/// form the trace writer uses, one line buffer per row. The digits are written right to
/// left into a small stack buffer, two per division by a constant, and appended at once.
#[inline(always)]
pub fn push_fixed_bytes(out: &mut Vec<u8>, v: f64, decimals: u32) {
    const SCALE: [f64; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];
    let d = decimals as usize;
    let scaled = SCALE
        .get(d)
        .map(|s| round_half_away(v * s))
        .filter(|s| s.is_finite() && s.abs() < 9.0e15);
    let Some(scaled) = scaled else {
        let _ = std::io::Write::write_fmt(out, format_args!("{v:.*}", decimals as usize));
        return;
    };
    let n = scaled.abs() as u64;
    // Integer part and fraction; the trace's decimal counts divide by constants.
    let (int, frac) = match d {
        0 => (n, 0),
        4 => (n / 10_000, n % 10_000),
        6 => (n / 1_000_000, n % 1_000_000),
        7 => (n / 10_000_000, n % 10_000_000),
        _ => {
            let p = 10u64.pow(decimals);
            (n / p, n % p)
        }
    };
    append_field(out, int, frac, d, scaled < 0.0);
}

/// [`push_fixed_bytes`] with the number of decimals known at compile time (the trace's
/// columns): the same bytes, with the fraction's divisions unrolled and no branch on the
/// decimal count.
#[inline(always)]
pub fn push_fixed_bytes_const<const D: u32>(out: &mut Vec<u8>, v: f64) {
    const SCALE: [f64; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];
    const POW: [u64; 10] = [
        1,
        10,
        100,
        1_000,
        10_000,
        100_000,
        1_000_000,
        10_000_000,
        100_000_000,
        1_000_000_000,
    ];
    let d = D as usize;
    if d >= SCALE.len() {
        push_fixed_bytes(out, v, D);
        return;
    }
    // `round_half_away` in integers: `r` is the rounded scaled value, negative exactly
    // where `push_fixed_bytes` writes a sign (a value that rounds to -0 has none).
    let x = v * SCALE[d];
    // Not finite or too large: NaN fails the comparison too.
    if !(x.abs() < 9.0e15) {
        let _ = std::io::Write::write_fmt(out, format_args!("{v:.*}", d));
        return;
    }
    let t = x as i64;
    let f = x - t as f64;
    let r = t + (f >= 0.5) as i64 - (f <= -0.5) as i64;
    let n = r.unsigned_abs();
    if n >= 9_000_000_000_000_000 {
        let _ = std::io::Write::write_fmt(out, format_args!("{v:.*}", d));
        return;
    }
    append_field(out, n / POW[d], n % POW[d], d, r < 0);
}

/// Appends `int.frac` with `d` fraction digits (`frac` < 10^d), with a sign when
/// `negative`: the shared tail of [`push_fixed_bytes`] and [`push_fixed_bytes_const`].
#[inline(always)]
fn append_field(out: &mut Vec<u8>, mut int: u64, mut frac: u64, d: usize, negative: bool) {
    // At most 16 integer digits (|scaled| < 9e15), the point, 9 decimals and the sign: 27
    // bytes, right-aligned at FIELD_END; a fixed 32 bytes from the first digit are appended
    // (a copy of known length, no library call) and the excess cut off again.
    const FIELD_END: usize = 32;
    let mut buf = [b'0'; 2 * FIELD_END];
    let mut at = FIELD_END;
    // Right to left: the fraction (zero-padded to d digits), the point, the integer part.
    let mut left = d;
    // Four digits per division of the long dependency chain, their two pairs apart.
    while left >= 4 {
        let four = (frac % 10_000) as u32;
        frac /= 10_000;
        let (hi, lo) = (2 * (four / 100) as usize, 2 * (four % 100) as usize);
        at -= 4;
        buf[at] = PAIRS[hi];
        buf[at + 1] = PAIRS[hi + 1];
        buf[at + 2] = PAIRS[lo];
        buf[at + 3] = PAIRS[lo + 1];
        left -= 4;
    }
    while left >= 2 {
        let r = 2 * (frac % 100) as usize;
        frac /= 100;
        at -= 2;
        buf[at] = PAIRS[r];
        buf[at + 1] = PAIRS[r + 1];
        left -= 2;
    }
    if left == 1 {
        at -= 1;
        buf[at] = b'0' + (frac % 10) as u8;
    }
    if d > 0 {
        at -= 1;
        buf[at] = b'.';
    }
    while int >= 100 {
        let r = 2 * (int % 100) as usize;
        int /= 100;
        at -= 2;
        buf[at] = PAIRS[r];
        buf[at + 1] = PAIRS[r + 1];
    }
    if int >= 10 {
        let r = 2 * int as usize;
        at -= 2;
        buf[at] = PAIRS[r];
        buf[at + 1] = PAIRS[r + 1];
    } else {
        at -= 1;
        buf[at] = b'0' + int as u8;
    }
    if negative {
        at -= 1;
        buf[at] = b'-';
    }
    let len = out.len() + (FIELD_END - at);
    let field: &[u8; FIELD_END] = buf[at..at + FIELD_END].try_into().expect("32 bytes");
    out.extend_from_slice(field);
    out.truncate(len);
}

/// Pairs of decimal digits "00" to "99".
const PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Writes the digits of `v` right-aligned into `buf` and returns where they start; None
/// when the fast path does not apply (too many decimals, |v| too large, not finite).
/// The integer `round(|v| 10^decimals)` is written two digits at a time, then the point
/// is put in front of its last `decimals` digits.
#[inline]
fn digits(buf: &mut [u8; 24], v: f64, decimals: u32) -> Option<usize> {
    const SCALE: [f64; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];
    let scaled = round_half_away(v * SCALE.get(decimals as usize)?);
    if !(scaled.is_finite() && scaled.abs() < 9.0e15) {
        return None;
    }
    // Digits of n right-aligned in tmp, at least decimals + 1 of them.
    let mut tmp = [b'0'; 24];
    let mut pos = tmp.len();
    let mut n = scaled.abs() as u64;
    while n >= 100 {
        let r = 2 * (n % 100) as usize;
        n /= 100;
        pos -= 2;
        tmp[pos..pos + 2].copy_from_slice(&PAIRS[r..r + 2]);
    }
    if n >= 10 {
        let r = 2 * n as usize;
        pos -= 2;
        tmp[pos..pos + 2].copy_from_slice(&PAIRS[r..r + 2]);
    } else {
        pos -= 1;
        tmp[pos] = b'0' + n as u8;
    }
    let d = decimals as usize;
    pos = pos.min(tmp.len() - d - 1);
    // Into buf, right-aligned: fraction, point, integer part, sign.
    let mut at = buf.len();
    if d > 0 {
        at -= d;
        buf[at..].copy_from_slice(&tmp[tmp.len() - d..]);
        at -= 1;
        buf[at] = b'.';
    }
    let int = &tmp[pos..tmp.len() - d];
    at -= int.len();
    buf[at..at + int.len()].copy_from_slice(int);
    if scaled < 0.0 {
        at -= 1;
        buf[at] = b'-';
    }
    Some(at)
}

/// `x.round()` (half away from zero) for |x| < 2^53 by integer truncation, exact there
/// (`x - trunc(x)` is exact), without a libm call; other values pass through `f64::round`.
#[inline]
fn round_half_away(x: f64) -> f64 {
    if !(x.abs() < 9.0e15) {
        return x.round();
    }
    let t = x as i64;
    let frac = x - t as f64;
    let r = if frac >= 0.5 {
        t + 1
    } else if frac <= -0.5 {
        t - 1
    } else {
        t
    };
    // Keep the sign of a value that rounds to zero from below, as f64::round does.
    if r == 0 && x.is_sign_negative() {
        -0.0
    } else {
        r as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_rounding_matches_f64_round() {
        for x in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -2.5,
            0.499_999_999_999_999_9,
            1e15 + 0.5,
            -7.3,
        ] {
            let (a, b) = (round_half_away(x), x.round());
            assert!(
                a == b && a.is_sign_negative() == b.is_sign_negative(),
                "{x}: {a} vs {b}"
            );
        }
    }

    #[test]
    fn the_compile_time_decimal_counts_write_the_same_bytes() {
        fn both<const D: u32>(v: f64) {
            let (mut a, mut b) = (Vec::new(), Vec::new());
            push_fixed_bytes(&mut a, v, D);
            push_fixed_bytes_const::<D>(&mut b, v);
            assert_eq!(a, b, "{v} with {D} decimals");
        }
        let mut x = 0.123_456_789_f64;
        for k in 0..2000 {
            // Values from 1e-9 to 1e13 of both signs, halves, zeros, non-finite.
            x = (x * 7.31 + 0.37).fract();
            let v = (x - 0.5) * 10f64.powi(k % 23 - 9);
            for v in [
                v,
                -v,
                (v * 1e4).round() / 1e4 + 0.5e-4,
                0.0,
                -0.0,
                f64::NAN,
                1e300,
            ] {
                both::<0>(v);
                both::<4>(v);
                both::<6>(v);
                both::<7>(v);
                both::<9>(v);
            }
        }
    }

    #[test]
    fn push_fixed_matches_the_standard_formatting() {
        for &v in &[
            10.0,
            99.5,
            100.0,
            -1234567.891,
            987654321.123456,
            0.0,
            -0.0,
            1.5,
            -1.5,
            0.000_049,
            -0.000_051,
            123.456_789_4,
            -184.523_696_2,
            1e-9,
            99.999_999_6,
            7.0,
            -0.3,
        ] {
            for d in [0u32, 1, 4, 6, 7] {
                let mut s = String::new();
                push_fixed(&mut s, v, d);
                let want = format!("{v:.*}", d as usize);
                // The standard library rounds the exact binary value; the scaled rounding can
                // differ in the last digit only at exact ties, which these values avoid.
                let want = if want
                    .trim_start_matches('-')
                    .chars()
                    .all(|c| c == '0' || c == '.')
                {
                    want.trim_start_matches('-').to_string()
                } else {
                    want
                };
                assert_eq!(s, want, "{v} with {d} decimals");
                let mut bytes = b"x,".to_vec();
                push_fixed_bytes(&mut bytes, v, d);
                assert_eq!(
                    &bytes[2..],
                    want.as_bytes(),
                    "{v} with {d} decimals (bytes)"
                );
            }
        }
    }
}
