//! `eˣ` for non-positive x: the Stribeck law's decay in the servo's friction model.

/// `eˣ` for `-708 < x ≤ 0` (the Stribeck law's `exp(-(v/vs)²)`, `-40 ≤ x ≤ 0` there), as
/// fdlibm's `__ieee754_exp` computes it, error below one ulp: `x = k ln 2 + r` with
/// `k = round(x / ln 2)` and `|r| ≤ ln 2 / 2` (ln 2 in two parts, so `r` is exact to the
/// last bits), then
///
/// ```text
/// c = r - r² (P1 + r² (P2 + r² (P3 + r² (P4 + r² P5)))),   eʳ = 1 - ((r c) / (c - 2) - r)
/// ```
///
/// and `2ᵏ` put into the exponent. Only arithmetic, so the same on every CPU; any other x goes
/// to `f64::exp`. Kept instead of `f64::exp` for its cost (half the library call:
/// docs/performance.md) and because the servo's bits, and so every output, depend on it.
#[inline]
pub fn exp_neg(x: f64) -> f64 {
    const LN2_HI: f64 = 6.931_471_803_691_238_164_90e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_700_02e-10;
    const INV_LN2: f64 = 1.442_695_040_888_963_387_00;
    const P1: f64 = 1.666_666_666_666_660_190_37e-1;
    const P2: f64 = -2.777_777_777_701_559_338_42e-3;
    const P3: f64 = 6.613_756_321_437_934_361_17e-5;
    const P4: f64 = -1.653_390_220_546_525_153_90e-6;
    const P5: f64 = 4.138_136_797_057_238_460_39e-8;
    // 1.5 · 2⁵²: adding and subtracting it rounds to the nearest integer.
    const ROUNDER: f64 = 6_755_399_441_055_744.0;
    if !(x > -708.0 && x <= 0.0) {
        return x.exp();
    }
    let k = (x * INV_LN2 + ROUNDER) - ROUNDER;
    let hi = x - k * LN2_HI;
    let lo = k * LN2_LO;
    let r = hi - lo;
    let t = r * r;
    let c = r - t * (P1 + t * (P2 + t * (P3 + t * (P4 + t * P5))));
    let y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
    // 2ᵏ for -1022 ≤ k ≤ 0: a normal double.
    y * f64::from_bits(((1023 + k as i64) as u64) << 52)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_neg_is_within_one_ulp_of_the_library() {
        let mut worst: f64 = 0.0;
        let mut x = 0.0;
        while x > -700.0 {
            let (a, b) = (exp_neg(x), x.exp());
            worst = worst.max((a - b).abs() / (b * f64::EPSILON));
            x -= 0.003_141_592_653 * if x > -45.0 { 1.0 } else { 97.0 };
        }
        assert!(worst <= 1.0, "worst {worst} ulp");
        assert_eq!(exp_neg(0.0), 1.0);
        assert_eq!(exp_neg(-f64::MIN_POSITIVE), 1.0);
        assert!(exp_neg(f64::NAN).is_nan());
        assert_eq!(exp_neg(-800.0), 0.0);
    }
}
