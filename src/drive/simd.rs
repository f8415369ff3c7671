//! The lane groups' vectors: [`LANES`] f64 as two `wide::f64x4`, and their masks.
//!
//! The one place the crate touches a SIMD library. [`V`] holds one value per lane and does
//! IEEE 754 arithmetic lane by lane, each operation rounded as the scalar one is (a
//! multiplication and an addition are never fused), so a lane's result is the scalar
//! model's bits whatever the vector width (a NaN's sign and payload aside, which are the
//! instruction's: a lane that is not finite fails its period's checks anyway). [`M`] is a lane mask (all bits set: true), the
//! result of a comparison: with NaN, `a.lt(b)`, `a.le(b)`, `a.gt(b)` and `a.eq(b)` are false
//! as the scalar comparisons are, so `!(a <= b)` is written `!a.le(b)`. A per-lane choice
//! (a regime, a check) is a mask and a [`M::select`], not a branch.
//!
//! `wide` picks its instructions when it is compiled (SSE2 pairs without `-C target-feature`);
//! the callers are compiled for AVX or AVX-512 at run time (`DriveLanes::step_block`), which
//! the inlined vector code takes on.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use wide::f64x4;

/// Servos per lane group: one AVX-512 register of f64, two `f64x4`.
pub const LANES: usize = 8;

/// One value per lane, as the lanes' state is stored.
pub type Lanes = [f64; LANES];

/// One f64 per lane.
#[derive(Clone, Copy, Debug)]
pub(super) struct V([f64x4; 2]);

/// One truth value per lane (a lane's bits all set, or all clear).
#[derive(Clone, Copy, Debug)]
pub(super) struct M([f64x4; 2]);

impl V {
    /// The lanes of `a`.
    #[inline(always)]
    pub fn load(a: &Lanes) -> V {
        V([
            f64x4::from([a[0], a[1], a[2], a[3]]),
            f64x4::from([a[4], a[5], a[6], a[7]]),
        ])
    }

    /// `x` in every lane.
    #[inline(always)]
    pub fn splat(x: f64) -> V {
        V([f64x4::splat(x); 2])
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn lanes(self) -> Lanes {
        let (a, b) = (self.0[0].to_array(), self.0[1].to_array());
        [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]
    }

    /// `|x|` (the sign bit cleared, as `f64::abs`).
    #[inline(always)]
    pub fn abs(self) -> V {
        V(self.0.map(f64x4::abs))
    }

    /// `max(x, y)` as `f64::max`: a NaN in one operand gives the other.
    #[inline(always)]
    pub fn max(self, y: V) -> V {
        V([self.0[0].max(y.0[0]), self.0[1].max(y.0[1])])
    }

    /// `x` finite per lane.
    #[inline(always)]
    pub fn is_finite(self) -> M {
        M(self.0.map(f64x4::is_finite))
    }
}

/// The comparisons, `x.lt(y)` for `x < y` per lane and so on.
macro_rules! lane_cmp {
    ($($f:ident $simd:ident),*) => {
        impl V {
            $(
                #[inline(always)]
                pub fn $f(self, y: V) -> M {
                    M([self.0[0].$simd(y.0[0]), self.0[1].$simd(y.0[1])])
                }
            )*
        }
    };
}
lane_cmp!(lt simd_lt, le simd_le, gt simd_gt, ge simd_ge, eq simd_eq);

macro_rules! lane_op {
    ($trait:ident, $f:ident) => {
        impl $trait for V {
            type Output = V;
            #[inline(always)]
            fn $f(self, y: V) -> V {
                V([self.0[0].$f(y.0[0]), self.0[1].$f(y.0[1])])
            }
        }
    };
}
lane_op!(Add, add);
lane_op!(Sub, sub);
lane_op!(Mul, mul);
lane_op!(Div, div);

impl Neg for V {
    type Output = V;
    #[inline(always)]
    fn neg(self) -> V {
        V(self.0.map(|x| -x))
    }
}

impl Default for M {
    fn default() -> M {
        M([f64x4::ZERO; 2])
    }
}

impl M {
    /// True in every lane.
    #[inline(always)]
    pub fn all_true() -> M {
        let ones = f64x4::splat(f64::from_bits(u64::MAX));
        M([ones; 2])
    }

    /// `b` in every lane.
    #[inline(always)]
    pub fn splat(b: bool) -> M {
        if b {
            M::all_true()
        } else {
            M::default()
        }
    }

    /// Per lane, `t` where true and `f` where false.
    #[inline(always)]
    pub fn select(self, t: V, f: V) -> V {
        V([
            self.0[0].select(t.0[0], f.0[0]),
            self.0[1].select(t.0[1], f.0[1]),
        ])
    }

    /// One bit per lane, lane `l` at bit `l`.
    #[inline(always)]
    pub fn bits(self) -> u32 {
        self.0[0].to_bitmask() | self.0[1].to_bitmask() << 4
    }

    /// True in some lane.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.bits() != 0
    }

    /// Lane `l`.
    #[inline(always)]
    pub fn get(self, l: usize) -> bool {
        self.bits() >> l & 1 == 1
    }

    /// Lane `l` set to `b`.
    #[inline(always)]
    pub fn set(&mut self, l: usize, b: bool) {
        let mut half = self.0[l / 4].to_array();
        half[l % 4] = f64::from_bits(if b { u64::MAX } else { 0 });
        self.0[l / 4] = f64x4::from(half);
    }
}

impl BitAnd for M {
    type Output = M;
    #[inline(always)]
    fn bitand(self, y: M) -> M {
        M([self.0[0] & y.0[0], self.0[1] & y.0[1]])
    }
}

impl BitOr for M {
    type Output = M;
    #[inline(always)]
    fn bitor(self, y: M) -> M {
        M([self.0[0] | y.0[0], self.0[1] | y.0[1]])
    }
}

impl Not for M {
    type Output = M;
    #[inline(always)]
    fn not(self) -> M {
        M([!self.0[0], !self.0[1]])
    }
}

/// The arithmetic and masks lane by lane against the scalar operations, NaN and signed
/// zeros included.
#[cfg(test)]
mod tests {
    use super::*;

    const VALUES: Lanes = [1.5, -0.0, f64::NAN, 3.0, -2.25, f64::INFINITY, 0.0, 1e-300];
    const OTHERS: Lanes = [1.5, 0.0, 2.0, f64::NAN, -3.0, 1.0, -0.0, 7.0];

    #[test]
    fn lanes_compute_as_the_scalar_operations() {
        let (a, b) = (V::load(&VALUES), V::load(&OTHERS));
        // The same bits, or both NaN (a NaN's sign and payload are the instruction's).
        let same = |v: V, l: usize, r: f64| {
            let x = v.lanes()[l];
            x.to_bits() == r.to_bits() || (x.is_nan() && r.is_nan())
        };
        for l in 0..LANES {
            let (x, y) = (VALUES[l], OTHERS[l]);
            assert!(same(a + b, l, x + y), "lane {l}");
            assert!(same(a - b, l, x - y), "lane {l}");
            assert!(same(a * b, l, x * y), "lane {l}");
            assert!(same(a / b, l, x / y), "lane {l}");
            assert!(same(-a, l, -x), "lane {l}");
            assert!(same(a.abs(), l, x.abs()), "lane {l}");
            assert_eq!(a.lt(b).get(l), x < y);
            assert_eq!(a.le(b).get(l), x <= y);
            assert_eq!(a.gt(b).get(l), x > y);
            assert_eq!(a.ge(b).get(l), x >= y);
            assert_eq!(a.eq(b).get(l), x == y);
            assert_eq!(a.is_finite().get(l), x.is_finite());
            assert_eq!(
                a.lt(b).select(a, b).lanes()[l].to_bits(),
                if x < y { x } else { y }.to_bits()
            );
            if !(x == 0.0 && y == 0.0) {
                // `f64::max` of two zeros may give either.
                assert!(same(a.max(b), l, x.max(y)), "lane {l}");
            }
        }
    }

    #[test]
    fn masks_set_and_combine_lane_by_lane() {
        let mut m = M::default();
        m.set(2, true);
        m.set(5, true);
        assert_eq!(m.bits(), 0b10_0100);
        m.set(2, false);
        assert_eq!(m.bits(), 0b10_0000);
        assert!(m.get(5) && !m.get(2));
        assert_eq!((m | M::splat(false)).bits(), 0b10_0000);
        assert_eq!((!m & M::all_true()).bits(), 0b1101_1111);
        assert!(m.any() && !M::default().any());
    }
}
