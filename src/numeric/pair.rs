//! Two `f64` lanes computed at once, each lane bit for bit the scalar result.
//!
//! Addition, subtraction, multiplication and negation of [`F64x2`] round each lane as the
//! `f64` operation does (SSE2's `addpd`, `subpd`, `mulpd` are the IEEE operations lane by
//! lane, and nothing is fused), so a formula written on pairs, in the same order, gives in
//! each lane the bits of the formula on one `f64`: two angles' polynomials for the price of
//! about one. Other targets compute the lanes one after the other.

use std::ops::{Add, Mul, Neg, Sub};

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{
    __m128d, _mm_add_pd, _mm_cvtsd_f64, _mm_mul_pd, _mm_set1_pd, _mm_set_pd, _mm_sub_pd,
    _mm_unpackhi_pd, _mm_xor_pd,
};

/// What a formula written once for `f64` and for [`F64x2`] uses: the four operations
/// and constants (`T::from(c)`, in every lane).
pub trait LaneOps:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self> + From<f64>
{
}

impl LaneOps for f64 {}
impl LaneOps for F64x2 {}

impl From<f64> for F64x2 {
    #[inline(always)]
    fn from(x: f64) -> F64x2 {
        F64x2::splat(x)
    }
}

/// Two `f64` lanes.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub struct F64x2(__m128d);

/// Two `f64` lanes.
#[cfg(not(target_arch = "x86_64"))]
#[derive(Clone, Copy, Debug)]
pub struct F64x2([f64; 2]);

#[cfg(target_arch = "x86_64")]
impl F64x2 {
    /// Lanes `(a, b)`.
    #[inline(always)]
    pub fn new(a: f64, b: f64) -> F64x2 {
        // SAFETY (every intrinsic here): SSE2 is part of every x86_64 CPU.
        F64x2(unsafe { _mm_set_pd(b, a) })
    }

    /// `x` in both lanes.
    #[inline(always)]
    pub fn splat(x: f64) -> F64x2 {
        F64x2(unsafe { _mm_set1_pd(x) })
    }

    /// The two lanes.
    #[inline(always)]
    pub fn lanes(self) -> [f64; 2] {
        unsafe {
            [
                _mm_cvtsd_f64(self.0),
                _mm_cvtsd_f64(_mm_unpackhi_pd(self.0, self.0)),
            ]
        }
    }
}

#[cfg(target_arch = "x86_64")]
macro_rules! lane_op {
    ($trait:ident, $method:ident, $intrinsic:ident) => {
        impl $trait for F64x2 {
            type Output = F64x2;
            #[inline(always)]
            fn $method(self, rhs: F64x2) -> F64x2 {
                F64x2(unsafe { $intrinsic(self.0, rhs.0) })
            }
        }
    };
}

#[cfg(target_arch = "x86_64")]
lane_op!(Add, add, _mm_add_pd);
#[cfg(target_arch = "x86_64")]
lane_op!(Sub, sub, _mm_sub_pd);
#[cfg(target_arch = "x86_64")]
lane_op!(Mul, mul, _mm_mul_pd);

#[cfg(target_arch = "x86_64")]
impl Neg for F64x2 {
    type Output = F64x2;
    /// The sign bit flipped, as `-x` does (so `-0` for `0`).
    #[inline(always)]
    fn neg(self) -> F64x2 {
        F64x2(unsafe { _mm_xor_pd(self.0, _mm_set1_pd(-0.0)) })
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl F64x2 {
    /// Lanes `(a, b)`.
    #[inline(always)]
    pub fn new(a: f64, b: f64) -> F64x2 {
        F64x2([a, b])
    }

    /// `x` in both lanes.
    #[inline(always)]
    pub fn splat(x: f64) -> F64x2 {
        F64x2([x, x])
    }

    /// The two lanes.
    #[inline(always)]
    pub fn lanes(self) -> [f64; 2] {
        self.0
    }
}

#[cfg(not(target_arch = "x86_64"))]
macro_rules! lane_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for F64x2 {
            type Output = F64x2;
            #[inline(always)]
            fn $method(self, rhs: F64x2) -> F64x2 {
                F64x2([self.0[0] $op rhs.0[0], self.0[1] $op rhs.0[1]])
            }
        }
    };
}

#[cfg(not(target_arch = "x86_64"))]
lane_op!(Add, add, +);
#[cfg(not(target_arch = "x86_64"))]
lane_op!(Sub, sub, -);
#[cfg(not(target_arch = "x86_64"))]
lane_op!(Mul, mul, *);

#[cfg(not(target_arch = "x86_64"))]
impl Neg for F64x2 {
    type Output = F64x2;
    #[inline(always)]
    fn neg(self) -> F64x2 {
        F64x2([-self.0[0], -self.0[1]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_lane_rounds_as_the_scalar_operation() {
        let values = [
            0.1,
            -0.0,
            0.0,
            1.0 / 3.0,
            -2.5e-300,
            1e308,
            f64::MIN_POSITIVE,
            7.0,
            f64::NAN,
            f64::INFINITY,
        ];
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        for &a in &values {
            for &b in &values {
                let (x, y) = (F64x2::new(a, b), F64x2::new(b, a));
                let checks = [
                    ((x + y).lanes(), [a + b, b + a]),
                    ((x - y).lanes(), [a - b, b - a]),
                    ((x * y).lanes(), [a * b, b * a]),
                    ((-x).lanes(), [-a, -b]),
                    ((x * F64x2::splat(3.0)).lanes(), [a * 3.0, b * 3.0]),
                ];
                for (got, want) in checks {
                    assert!(
                        same(got[0], want[0]) && same(got[1], want[1]),
                        "{a:e}, {b:e}: {got:?} against {want:?}"
                    );
                }
            }
        }
    }
}
