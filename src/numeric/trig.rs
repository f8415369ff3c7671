//! Sine and cosine of an angle in degrees, reduced exactly in degrees.
//!
//! `θ = 90° k + r` with `k = round(θ / 90)` and `|r| ≤ 45°`. The remainder is exact: for
//! `k = 0` it is θ itself, otherwise θ and `90 k` lie within a factor of two of each other
//! (`|r| ≤ 45 ≤ |90 k| / 2`), so their difference is a double (Sterbenz). Then
//! `x = r π/180` (one rounding) and, on `|x| ≤ π/4`, the published minimax polynomials for
//! sine and cosine on that interval (the coefficients of Sun's fdlibm, error below one ulp):
//!
//! ```text
//! sin x = x + x³ (S1 + z (S2 + z (S3 + z (S4 + z (S5 + z S6))))),   z = x²
//! cos x = w + ((1 - w) - z/2) + z² (C1 + z (C2 + ... + z C6)),       w = 1 - z/2
//! ```
//!
//! (`w` first, then the rounding error of `1 - z/2` added back), and the quadrant `k mod 4`
//! swaps and negates them. Only multiplications and additions, so the result is the same on
//! every CPU; multiples of 90° give exact 0 and ±1, and large angles keep their accuracy (a
//! conversion to radians would round before the reduction).
//!
//! Kept rather than a library call: `to_radians().sin_cos()` costs about four times as much
//! (docs/performance.md), and `libm::sincos` on the same reduced `x` differs in the last bit
//! for about 0.1 % of angles, which changes the bundled outputs (blocks, summaries, fits).

use super::pair::{F64x2, LaneOps};

const S1: f64 = -1.666_666_666_666_663_243_48e-1;
const S2: f64 = 8.333_333_333_322_489_461_24e-3;
const S3: f64 = -1.984_126_982_985_794_931_34e-4;
const S4: f64 = 2.755_731_370_707_006_767_89e-6;
const S5: f64 = -2.505_076_025_340_686_341_95e-8;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;

const C1: f64 = 4.166_666_666_666_660_190_37e-2;
const C2: f64 = -1.388_888_888_887_410_957_49e-3;
const C3: f64 = 2.480_158_728_947_672_941_78e-5;
const C4: f64 = -2.755_731_435_139_066_330_35e-7;
const C5: f64 = 2.087_572_321_298_174_827_90e-9;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;

/// `1.5 · 2⁵²`: adding and subtracting it rounds a double below 2⁵¹ in magnitude to the
/// nearest integer (ties to even) without a library call.
const ROUNDER: f64 = 6_755_399_441_055_744.0;

/// `(sin θ, cos θ)` of `theta_deg` in degrees (see the module). Beyond ±10¹² deg, and for a
/// non-finite θ, it is `to_radians().sin_cos()`.
#[inline]
pub fn sin_cos_deg(theta_deg: f64) -> (f64, f64) {
    if !(theta_deg.abs() < 1e12) {
        return theta_deg.to_radians().sin_cos();
    }
    let (quadrant, sin, cos) = reduced(theta_deg);
    in_quadrant(quadrant, sin, cos)
}

/// [`sin_cos_deg`] of two angles at once, bit for bit ([`F64x2`]: the reduction and the
/// polynomials of both in one pass).
#[inline]
pub fn sin_cos_deg_pair(a_deg: f64, b_deg: f64) -> [(f64, f64); 2] {
    if !(a_deg.abs() < 1e12 && b_deg.abs() < 1e12) {
        return [sin_cos_deg(a_deg), sin_cos_deg(b_deg)];
    }
    let (quadrant, sin, cos) = reduced(F64x2::new(a_deg, b_deg));
    let (quadrant, sin, cos) = (quadrant.lanes(), sin.lanes(), cos.lanes());
    [
        in_quadrant(quadrant[0], sin[0], cos[0]),
        in_quadrant(quadrant[1], sin[1], cos[1]),
    ]
}

/// The quadrant of θ as `k + 1.5 · 2⁵²` (`k = round(θ / 90)`, deg) and the sine and cosine
/// of the remainder `θ - 90 k` (see the module), for `|θ| < 10¹²`.
#[inline(always)]
fn reduced<T: LaneOps>(theta_deg: T) -> (T, T, T) {
    let c = T::from;
    let quadrant = theta_deg * c(1.0 / 90.0) + c(ROUNDER);
    let k = quadrant - c(ROUNDER);
    let r = theta_deg - c(90.0) * k;
    let x = r * c(std::f64::consts::PI / 180.0);
    let z = x * x;
    let sin =
        x + z * x * (c(S1) + z * (c(S2) + z * (c(S3) + z * (c(S4) + z * (c(S5) + z * c(S6))))));
    let half = c(0.5) * z;
    let w = c(1.0) - half;
    let tail = z * z * (c(C1) + z * (c(C2) + z * (c(C3) + z * (c(C4) + z * (c(C5) + z * c(C6))))));
    let cos = w + (((c(1.0) - w) - half) + tail);
    (quadrant, sin, cos)
}

/// `(sin θ, cos θ)` from the remainder's, swapped and negated for θ's quadrant `k mod 4`,
/// given as `k + 1.5 · 2⁵²`: a double in [2⁵², 2⁵³) (|k| < 2⁵¹), whose ulp is 1, so its
/// significand's low bits are those of `k + 2⁵¹`, and `2⁵¹ ≡ 0 (mod 4)`.
#[inline(always)]
fn in_quadrant(quadrant: f64, sin: f64, cos: f64) -> (f64, f64) {
    match quadrant.to_bits() & 3 {
        0 => (sin, cos),
        1 => (cos, -sin),
        2 => (-sin, -cos),
        _ => (-cos, sin),
    }
}

/// θ in deg wrapped to [0, 360) (360 itself to 0), bit for bit as `rem_euclid(360)`.
#[inline]
pub fn wrap_360(deg: f64) -> f64 {
    // `rem_euclid` (an `fmod` call) only outside (-360, 360): inside, `deg % 360` is `deg`
    // exactly, so the result is `deg`, or `deg + 360` for a negative one (the same bits;
    // -0 stays -0 as `fmod` keeps it).
    let t = if (0.0..360.0).contains(&deg) {
        deg
    } else if deg > -360.0 && deg < 0.0 {
        deg + 360.0
    } else {
        deg.rem_euclid(360.0)
    };
    if t >= 360.0 {
        0.0
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_the_library_within_three_epsilon_over_many_turns() {
        // Reference: the library on θ reduced exactly to (-180, 180] (`%` is exact), whose
        // conversion to radians rounds by at most π ε/2: the tolerance is that plus the two
        // functions' own errors.
        let reference = |t: f64| {
            let r = t % 360.0;
            let r = if r > 180.0 {
                r - 360.0
            } else if r <= -180.0 {
                r + 360.0
            } else {
                r
            };
            r.to_radians().sin_cos()
        };
        let mut worst: f64 = 0.0;
        let mut theta: f64 = -3600.0;
        while theta < 3600.0 {
            let edge = 45.0 * (theta / 45.0).round();
            for t in [theta, edge, edge + 1e-9, edge - 1e-12] {
                let (s, c) = sin_cos_deg(t);
                let (s0, c0) = reference(t);
                worst = worst.max((s - s0).abs()).max((c - c0).abs());
            }
            theta += 0.012_345_678_9 * std::f64::consts::E;
        }
        assert!(worst <= 3.0 * f64::EPSILON, "worst difference {worst:e}");
    }

    #[test]
    fn the_pair_gives_each_angle_the_bits_of_the_single_one() {
        let mut angles = vec![0.0, -0.0, 90.0, -45.0, 45.0, 135.0, 1e12, -1e13, f64::NAN];
        let mut theta: f64 = -1000.0;
        while theta < 1000.0 {
            let edge = 45.0 * (theta / 45.0).round();
            angles.extend([theta, edge, edge.next_up(), edge.next_down(), 1e-9 * theta]);
            theta += 0.012_345_678_9 * std::f64::consts::PI;
        }
        let bits = |(s, c): (f64, f64)| (s.to_bits(), c.to_bits());
        for (i, &a) in angles.iter().enumerate() {
            let b = angles[(i * 7919 + 13) % angles.len()];
            let [pa, pb] = sin_cos_deg_pair(a, b);
            assert_eq!(bits(pa), bits(sin_cos_deg(a)), "{a:e} (with {b:e})");
            assert_eq!(bits(pb), bits(sin_cos_deg(b)), "{b:e} (with {a:e})");
        }
    }

    #[test]
    fn multiples_of_ninety_degrees_are_exact() {
        for (theta, sin, cos) in [
            (0.0, 0.0, 1.0),
            (90.0, 1.0, 0.0),
            (180.0, 0.0, -1.0),
            (270.0, -1.0, 0.0),
            (-90.0, -1.0, 0.0),
            (720.0, 0.0, 1.0),
        ] {
            // `==` takes -0 for 0.
            let (s, c) = sin_cos_deg(theta);
            assert!(s == sin && c == cos, "at {theta} deg: ({s}, {c})");
        }
    }

    #[test]
    fn thirty_and_sixty_degrees_match_their_closed_forms() {
        let (s, c) = sin_cos_deg(30.0);
        assert!((s - 0.5).abs() <= f64::EPSILON && (c - 3f64.sqrt() / 2.0).abs() <= f64::EPSILON);
        let (s, c) = sin_cos_deg(-420.0); // -60 - 360
        assert!((s + 3f64.sqrt() / 2.0).abs() <= f64::EPSILON && (c - 0.5).abs() <= f64::EPSILON);
    }

    #[test]
    fn non_finite_and_huge_angles_fall_back_to_the_library() {
        assert!(sin_cos_deg(f64::NAN).0.is_nan());
        assert!(sin_cos_deg(f64::INFINITY).1.is_nan());
        assert_eq!(sin_cos_deg(1e13), 1e13f64.to_radians().sin_cos());
    }
}
