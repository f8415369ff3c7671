//! `eˣ` of our own, for the friction terms `exp(-(v/vs)²)`: one formula, written once for
//! an `f64` ([`exp`]) and for the lanes' vectors ([`exp_lanes`]), so every lane gives the
//! scalar result bit for bit (plain IEEE multiplications and additions, never fused, in
//! the same order).
//!
//! Method (a textbook one, derived here):
//!
//! ```text
//! x = k ln2 + r,   k = round(x / ln2),   |r| ≤ ln2/2 (a hair beyond where x/ln2 rounds)
//! eˣ = 2ᵏ · eʳ
//! ```
//!
//! * **Reduction (Cody–Waite).** `k` is rounded to an integer by adding and subtracting
//!   `1.5·2⁵²` (the sum's unit is 1). `ln2 = LN2_HI + LN2_LO` with `LN2_HI` holding 42
//!   significant bits, so `k · LN2_HI` is exact for `|k| < 2¹¹` and `x − k · LN2_HI` is
//!   exact too (Sterbenz: `x` and `k · LN2_HI` are within a factor 2 of each other when
//!   `k ≠ 0`); `r = (x − k LN2_HI) − k LN2_LO` is then rounded once. What `LN2_HI + LN2_LO`
//!   misses of `ln2` is below `2⁻¹⁰²`, `k` times that below `2⁻⁹¹`.
//! * **`eʳ`.** `eʳ = 1 + r + r²/2 + r³ P(r)`, `P` of degree 9 the Chebyshev interpolant of
//!   `(eʳ − 1 − r − r²/2) / r³` on `|r| ≤ 1.0001 · ln2/2` (coefficients derived with a
//!   50-digit evaluation, rounded to f64): its relative error on `eʳ` stays below 0.01 ulp.
//!   `P` is evaluated by Estrin's scheme (powers `r², r⁴, r⁸`: a shorter chain than
//!   Horner's). The sum is formed as `h = 1 + r` with its rounding error
//!   `e = (1 − h) + r` (exact: Fast2Sum, `|r| < 1`), then `h + (e + r² (½ + r P))`: the
//!   small tail's roundings weigh little against the one final rounding. Error budget in
//!   ulps of the result: the final rounding ½, `r`'s rounding ≤ 0.18 (`eʳ δr` with
//!   `|δr| ≤ 2⁻⁵⁵`, against an ulp of `2⁻⁵³` where `eʳ < 1`), the tail's roundings and `P`'s
//!   error below 0.07: under 1 ulp.
//! * **`2ᵏ`** from the exponent bits: the low bits of `x/ln2 + 1.5·2⁵²` are `k` itself;
//!   `2ᵏ = 2^k₁ · 2^k₂` with `k₁ = ⌊k/2⌋`, `k₂ = k − k₁`, each a normal number over the
//!   whole clamped range, so `(eʳ · 2^k₁) · 2^k₂` is exact wherever the result is normal
//!   and rounded once where it is subnormal.
//! * **Range.** `x` is clamped to `[−746, 710]` first (a NaN passes through and gives NaN):
//!   below, `eˣ < 2⁻¹⁰⁷⁵` rounds to 0; above, it overflows to `+∞`.
//!
//! The friction's arguments are `−u²` with `u² ∈ [0, 40]` (and, in the substeps' tolerance
//! bound, any `u² ≥ 1.23²`); the method holds over every finite argument.

use super::simd::V;
use std::ops::{Add, Mul, Sub};

/// `ln2`'s first 42 significant bits.
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fefa_3800);
/// `ln2 − LN2_HI`, rounded.
const LN2_LO: f64 = f64::from_bits(0x3d2e_f357_93c7_6730);
/// `1/ln2 = log₂ e`, rounded.
const INV_LN2: f64 = std::f64::consts::LOG2_E;
/// `1.5·2⁵²`: `y + SHIFTER` rounds `y` (|y| < 2⁵¹) to an integer, held in the sum's low bits.
const SHIFTER: f64 = 6_755_399_441_055_744.0;
/// Below this, `eˣ` rounds to 0.
const X_MIN: f64 = -746.0;
/// Above this, `eˣ` overflows.
const X_MAX: f64 = 710.0;
/// `P(r) = Σ Pᵢ rⁱ`, `eʳ ≈ 1 + r + r²/2 + r³ P(r)`.
const P: [f64; 10] = [
    0.166_666_666_666_666_69,
    0.041_666_666_666_666_664,
    0.008_333_333_333_330_062,
    0.001_388_888_888_888_655_2,
    0.000_198_412_698_630_536_18,
    2.480_158_731_714_449_8e-5,
    2.755_726_845_999_706_4e-6,
    2.755_728_296_954_995e-7,
    2.510_038_549_551_032e-8,
    2.091_123_663_026_154_5e-9,
];

/// What [`exp_of`] needs of a number type: the IEEE operations, constants in every lane,
/// the clamp, and `2ᵏ` from the rounding sum's bits.
trait ExpArith: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> {
    /// `c` in every lane.
    fn constant(c: f64) -> Self;
    /// `lo` where `x < lo`, `hi` where `x > hi`, else `x` (NaN stays NaN).
    fn clamp_keep_nan(self, lo: f64, hi: f64) -> Self;
    /// `(2^k₁, 2^k₂)`, `k₁ = ⌊k/2⌋`, `k₂ = k − k₁`, with `k` the integer held in the low bits
    /// of `self = k + SHIFTER` (any bits give some finite factors: a NaN lane's result is
    /// NaN anyway).
    fn pow2_halves(self) -> (Self, Self);
}

/// `2^k₁, 2^k₂` of the integer `k` in the bits of `shifted = k + SHIFTER`.
#[inline(always)]
fn pow2_halves_of(shifted: f64) -> (f64, f64) {
    let k = (shifted.to_bits() as i64).wrapping_sub(SHIFTER.to_bits() as i64);
    let k1 = k >> 1;
    let k2 = k.wrapping_sub(k1);
    let pow2 = |j: i64| f64::from_bits((j.wrapping_add(1023) << 52) as u64);
    (pow2(k1), pow2(k2))
}

impl ExpArith for f64 {
    #[inline(always)]
    fn constant(c: f64) -> f64 {
        c
    }

    #[inline(always)]
    fn clamp_keep_nan(self, lo: f64, hi: f64) -> f64 {
        let x = if self < lo { lo } else { self };
        if x > hi {
            hi
        } else {
            x
        }
    }

    #[inline(always)]
    fn pow2_halves(self) -> (f64, f64) {
        pow2_halves_of(self)
    }
}

impl<const W: usize> ExpArith for V<W> {
    #[inline(always)]
    fn constant(c: f64) -> V<W> {
        V::splat(c)
    }

    #[inline(always)]
    fn clamp_keep_nan(self, lo: f64, hi: f64) -> V<W> {
        let (lo, hi) = (V::splat(lo), V::splat(hi));
        let x = self.lt(lo).select(lo, self);
        x.gt(hi).select(hi, x)
    }

    #[inline(always)]
    fn pow2_halves(self) -> (V<W>, V<W>) {
        let halves = self.lanes().map(pow2_halves_of);
        (V::load(&halves.map(|h| h.0)), V::load(&halves.map(|h| h.1)))
    }
}

/// `eˣ` by the module's method, in any [`ExpArith`].
#[inline(always)]
fn exp_of<T: ExpArith>(x: T) -> T {
    let c = T::constant;
    let x = x.clamp_keep_nan(X_MIN, X_MAX);
    let shifted = x * c(INV_LN2) + c(SHIFTER);
    let k = shifted - c(SHIFTER);
    let r = (x - k * c(LN2_HI)) - k * c(LN2_LO);
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let pair = |i: usize| c(P[i]) + r * c(P[i + 1]);
    let p = (pair(0) + r2 * pair(2)) + r4 * (pair(4) + r2 * pair(6)) + r8 * pair(8);
    let one = c(1.0);
    let h = one + r;
    let e = (one - h) + r;
    let tail = e + r2 * (c(0.5) + r * p);
    let (s1, s2) = shifted.pow2_halves();
    ((h + tail) * s1) * s2
}

/// `eˣ` within 1 ulp of the exact value for every finite `x` (0 below about −745.1, `+∞`
/// above about 709.8, NaN for NaN), the bits of [`exp_lanes`] in every lane.
#[inline]
pub(super) fn exp(x: f64) -> f64 {
    exp_of(x)
}

/// [`exp`] of every lane.
#[inline(always)]
pub(super) fn exp_lanes<const W: usize>(x: V<W>) -> V<W> {
    exp_of(x)
}

/// [`exp`] against an independent double-double evaluation of `eˣ` (Taylor series of the
/// reduced argument, about 100 bits) and against 40-digit constants; [`exp_lanes`] against
/// [`exp`] bit for bit.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::drive::simd::{Lanes, NARROW_LANES, WIDE_LANES};

    /// An unevaluated sum `hi + lo`, `|lo| ≤ ulp(hi)/2`.
    #[derive(Clone, Copy)]
    struct Dd(f64, f64);

    fn two_sum(a: f64, b: f64) -> Dd {
        let s = a + b;
        let bb = s - a;
        Dd(s, (a - (s - bb)) + (b - bb))
    }

    fn add(a: Dd, b: Dd) -> Dd {
        let s = two_sum(a.0, b.0);
        two_sum(s.0, s.1 + a.1 + b.1)
    }

    fn mul(a: Dd, b: Dd) -> Dd {
        let p = a.0 * b.0;
        let e = a.0.mul_add(b.0, -p); // exact: the product's rounding error
        two_sum(p, e + a.0 * b.1 + a.1 * b.0)
    }

    fn div_small(a: Dd, n: f64) -> Dd {
        let q = a.0 / n;
        let rem = (-q).mul_add(n, a.0) + a.1; // a.0 − q n exactly, plus the low part
        two_sum(q, rem / n)
    }

    /// `ln 2` to about 107 bits (its f64 and the rest), as published.
    const LN2_DD: Dd = Dd(
        f64::from_bits(0x3fe6_2e42_fefa_39ef),
        f64::from_bits(0x3c7a_bc9e_3b39_803f),
    );

    /// `eˣ` as a double-double, for `x` whose `eˣ` is a normal number: `x = k ln2 + r`
    /// (`k` the nearest integer to `x / ln2` by `f64::round`), `eʳ` by its Taylor series to
    /// the 30th power, times `2ᵏ`.
    fn reference(x: f64) -> Dd {
        let k = (x / std::f64::consts::LN_2).round();
        let r = add(Dd(x, 0.0), mul(Dd(-k, 0.0), LN2_DD));
        let (mut sum, mut term) = (Dd(1.0, 0.0), Dd(1.0, 0.0));
        for n in 1..=30 {
            term = div_small(mul(term, r), n as f64);
            sum = add(sum, term);
        }
        let scale = pow2(k as i32);
        Dd(sum.0 * scale, sum.1 * scale)
    }

    /// `2ⁱ` for `−1074 ≤ i ≤ 1023`, from its bits.
    fn pow2(i: i32) -> f64 {
        if i >= -1022 {
            f64::from_bits(((i + 1023) as u64) << 52)
        } else {
            f64::from_bits(1 << (i + 1074))
        }
    }

    /// `|got − exact| / ulp(exact)`, `exact = r.0 + r.1` (normal).
    fn ulps(got: f64, r: Dd) -> f64 {
        let exponent = ((r.0.to_bits() >> 52) & 0x7ff) as i32 - 1023;
        let mut ulp = pow2(exponent - 52);
        if r.0.to_bits() & ((1 << 52) - 1) == 0 && r.1 < 0.0 {
            ulp *= 0.5; // just below a power of 2
        }
        ((got - r.0) - r.1).abs() / ulp
    }

    fn assert_within_one_ulp(x: f64) -> f64 {
        let e = ulps(exp(x), reference(x));
        assert!(e <= 1.0, "exp({x:e}) = {:e}: {e} ulp off", exp(x));
        e
    }

    #[test]
    fn reference_meets_forty_digit_constants() {
        // e^x to 40 digits, as f64 pairs.
        for (x, hi, lo) in [
            (-1.0, 0.367_879_441_171_442_33, -1.242_875_367_278_836_3e-17),
            (
                -40.0,
                4.248_354_255_291_589e-18,
                1.243_747_080_264_577_3e-34,
            ),
            (-0.5, 0.606_530_659_712_633_4, -6.593_178_415_491_414e-19),
            (
                -10.0,
                4.539_992_976_248_485_4e-5,
                -2.637_554_055_327_531e-21,
            ),
        ] {
            let r = reference(x);
            assert_eq!(r.0, hi, "e^{x}");
            assert!(((r.1 - lo) / hi).abs() < 1e-30, "e^{x}: {} vs {lo}", r.1);
            assert!(ulps(exp(x), Dd(hi, lo)) <= 1.0, "exp({x})");
        }
    }

    #[test]
    fn exact_and_limit_cases() {
        assert_eq!(exp(0.0).to_bits(), 1f64.to_bits());
        assert_eq!(exp(-0.0).to_bits(), 1f64.to_bits());
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp(-746.0), 0.0);
        assert_eq!(exp(-1e300), 0.0);
        assert_eq!(exp(f64::INFINITY), f64::INFINITY);
        assert_eq!(exp(709.8), f64::INFINITY);
        assert!(exp(709.78).is_finite());
        assert!(exp(f64::NAN).is_nan());
        // e^−744 = 1.55 · 2⁻¹⁰⁷⁴ and e^−745.2 = 0.47 · 2⁻¹⁰⁷⁴ (40 digits), rounded.
        assert_eq!(exp(-744.0), f64::from_bits(2));
        assert_eq!(exp(-745.2), 0.0);
        // Below 2⁻¹⁰²², the rounding of a subnormal: e^−720 within one unit 2⁻¹⁰⁷⁴.
        let tiny = exp(-720.0);
        let scaled = reference(-720.0 + 64.0 * std::f64::consts::LN_2); // e^−720 · 2⁶⁴ (normal)
        let unit = pow2(-1074);
        assert!((tiny - scaled.0 * pow2(-64)).abs() <= unit, "{tiny:e}");
    }

    #[test]
    fn within_one_ulp_on_the_friction_domain() {
        // −u² on a dense grid of u ∈ [0, √40] and a dense grid of x ∈ [−40, 0].
        let n = 1 << 17;
        let mut worst = 0f64;
        for i in 0..=n {
            let u = 40f64.sqrt() * i as f64 / n as f64;
            worst = worst.max(assert_within_one_ulp(-(u * u)));
            worst = worst.max(assert_within_one_ulp(-40.0 * i as f64 / n as f64));
        }
        // The reduction's breakpoints x = (j + ½) ln2, where k changes, from both sides.
        for j in 0..60 {
            let x = -(j as f64 + 0.5) * std::f64::consts::LN_2;
            for d in -4i64..=4 {
                let x = f64::from_bits((x.to_bits() as i64 + d) as u64);
                worst = worst.max(assert_within_one_ulp(x));
            }
        }
        println!("largest error on the grid: {worst} ulp");
        assert!(worst > 0.3, "the grid reached the rounding: {worst}");
    }

    #[test]
    fn within_one_ulp_over_the_normal_range() {
        let n = 1 << 16;
        for i in 0..=n {
            assert_within_one_ulp(-708.0 + 1417.0 * i as f64 / n as f64);
        }
    }

    proptest::proptest! {
        /// Random arguments of the friction domain and of the whole normal range.
        #[test]
        fn random_arguments_within_one_ulp(u2 in 0.0..=40.0f64, x in -708.0..709.0f64) {
            assert_within_one_ulp(-u2);
            assert_within_one_ulp(x);
        }

        /// Every lane the scalar bits, whatever the other lanes hold; selected by a mask as
        /// the drive lanes select them.
        #[test]
        fn lanes_are_the_scalar_bits(
            u2 in proptest::collection::vec(-50.0..=800.0f64, WIDE_LANES),
            special in proptest::collection::vec(0usize..8, WIDE_LANES),
            mask in 0u32..=(u32::MAX >> (32 - WIDE_LANES)),
        ) {
            lanes_match::<WIDE_LANES>(&u2, &special, mask)?;
            lanes_match::<NARROW_LANES>(&u2, &special, mask)?;
        }
    }

    /// [`exp_lanes`] of `W` lanes (`-u2`, or a special value where `special` is 0) against
    /// [`exp`] lane by lane, and selected by `mask`.
    fn lanes_match<const W: usize>(
        u2: &[f64],
        special: &[usize],
        mask: u32,
    ) -> Result<(), proptest::test_runner::TestCaseError> {
        let specials = [
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            -0.0,
            1e308,
            -1e308,
            5e-324,
            0.0,
        ];
        let x: Lanes<W> = std::array::from_fn(|l| {
            if special[l] == 0 {
                specials[l % 8]
            } else {
                -u2[l]
            }
        });
        let lanes = exp_lanes(V::load(&x)).lanes();
        let mut m = crate::drive::simd::M::<W>::default();
        (0..W).for_each(|l| m.set(l, mask >> l & 1 == 1));
        let picked = m.select(exp_lanes(V::load(&x)), V::splat(0.0)).lanes();
        for l in 0..W {
            let s = exp(x[l]);
            let same = lanes[l].to_bits() == s.to_bits() || (s.is_nan() && lanes[l].is_nan());
            proptest::prop_assert!(same, "lane {}: {:e}", l, x[l]);
            let want = if m.get(l) { s } else { 0.0 };
            let kept = picked[l].to_bits() == want.to_bits();
            proptest::prop_assert!(kept || (want.is_nan() && picked[l].is_nan()));
        }
        Ok(())
    }
}
