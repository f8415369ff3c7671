//! The cube root the motion planner uses for its jerk-limited reach.

/// Cube root within 0.67 ulp (FreeBSD's `s_cbrt.c`, as musl and the earlier Rust `libm`
/// have it): the exponent divided by 3 in the bits, a polynomial to 23 bits,
///
/// ```text
/// t ← t · P(r),  r = t³/x;   then one Newton step   t ← t + t (x/t² - t) / (2t + x/t²)
/// ```
///
/// on `t` rounded to 21 bits (so that `t²` is exact). Kept instead of `f64::cbrt` (correctly
/// rounded, dearer: docs/performance.md) because the planner's bits, and so every output,
/// depend on it.
#[inline]
pub fn cbrt(x: f64) -> f64 {
    const B1: u32 = 715_094_163; // (1023 - 1023/3 - 0.03306235651) · 2²⁰
    const B2: u32 = 696_219_795; // (1023 - 1023/3 - 54/3 - 0.03306235651) · 2²⁰
    const P0: f64 = 1.875_951_824_271_770_096_43;
    const P1: f64 = -1.884_979_795_433_771_698_75;
    const P2: f64 = 1.621_429_720_105_354_466_140;
    const P3: f64 = -0.758_397_934_778_766_047_437;
    const P4: f64 = 0.145_996_192_886_612_446_982;
    let mut bits = x.to_bits();
    let mut hx = (bits >> 32) as u32 & 0x7fff_ffff;
    if hx >= 0x7ff0_0000 {
        return x + x; // NaN or ±∞
    }
    if hx < 0x0010_0000 {
        // Zero or subnormal: scale by 2⁵⁴ first.
        bits = (x * f64::from_bits(0x4350_0000_0000_0000)).to_bits();
        hx = (bits >> 32) as u32 & 0x7fff_ffff;
        if hx == 0 {
            return x;
        }
        hx = hx / 3 + B2;
    } else {
        hx = hx / 3 + B1;
    }
    bits &= 1 << 63;
    bits |= (hx as u64) << 32;
    let mut t = f64::from_bits(bits);
    let r = (t * t) * (t / x);
    t *= (P0 + r * (P1 + r * P2)) + ((r * r) * r) * (P3 + r * P4);
    t = f64::from_bits((t.to_bits() + 0x8000_0000) & 0xffff_ffff_c000_0000);
    let s = t * t;
    let r = x / s;
    let w = t + t;
    let r = (r - t) / (w + r);
    t + t * r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cube root against the library's (correctly rounded) over 30 decades
    /// and both signs, and at the special values.
    #[test]
    fn cube_root_is_within_one_ulp_of_the_library() {
        let mut worst: f64 = 0.0;
        let mut x = 1e-150;
        while x < 1e150 {
            for v in [x, -x] {
                let (a, b) = (cbrt(v), v.cbrt());
                worst = worst.max((a - b).abs() / (b.abs() * f64::EPSILON));
            }
            x *= 1.000_731;
        }
        assert!(worst <= 1.0, "worst {worst} ulp");
        assert_eq!(cbrt(27.0), 3.0);
        assert_eq!(cbrt(-8.0), -2.0);
        assert_eq!(cbrt(0.0).to_bits(), 0.0f64.to_bits());
        assert_eq!(cbrt(-0.0).to_bits(), (-0.0f64).to_bits());
        assert!(
            (cbrt(f64::MIN_POSITIVE * 1e-10) - (f64::MIN_POSITIVE * 1e-10).cbrt()).abs() < 1e-120
        );
        assert!(cbrt(f64::NAN).is_nan());
        assert_eq!(cbrt(f64::INFINITY), f64::INFINITY);
    }
}
