//! The lane groups' vectors: [`LANES`] f64 as one array, and their masks.
//!
//! The one place the crate defines its lane vectors. [`V`] holds one value per lane and does
//! IEEE 754 arithmetic lane by lane, each operation rounded as the scalar one is (a
//! multiplication and an addition are never fused), so a lane's result is the scalar
//! model's bits whatever the vector width (a NaN's sign and payload aside, which are the
//! instruction's: a lane that is not finite fails its period's checks anyway). [`M`] is a
//! lane mask (all bits set: true), the result of a comparison: with NaN, `a.lt(b)`,
//! `a.le(b)`, `a.gt(b)` and `a.eq(b)` are false as the scalar comparisons are, so
//! `!(a <= b)` is written `!a.le(b)`. A per-lane choice (a regime, a check) is a mask and a
//! [`M::select`], not a branch.
//!
//! Each operation is a loop over the [`LANES`] lanes of plain arrays, always inlined: the
//! compiler turns it into vector instructions of the width of the function it is inlined
//! into (`DriveLanes::step_block` is compiled for AVX-512 or AVX at run time: two or four
//! registers a vector). `wide::f64x4`, which these vectors were before, picks its
//! instructions when that crate is compiled (SSE2 pairs without `-C target-feature`), so
//! its operations ran as four 128-bit instructions each even inside the AVX-512 function
//! (docs/performance.md, session 25).

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// Servos per lane group: two AVX-512 registers of f64 (four AVX ones), so that a period's
/// dependent operations (the map's product, row by row) have two independent chains to
/// overlap (docs/performance.md, session 29).
pub const LANES: usize = 16;

/// One value per lane, as the lanes' state is stored.
pub type Lanes = [f64; LANES];

/// One f64 per lane.
#[derive(Clone, Copy, Debug)]
pub(super) struct V(Lanes);

/// One truth value per lane (a lane's bits all set, or all clear).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct M([i64; LANES]);

/// `f` lane by lane.
#[inline(always)]
fn each<U>(f: impl Fn(usize) -> U) -> [U; LANES] {
    std::array::from_fn(f)
}

impl V {
    /// The lanes of `a`.
    #[inline(always)]
    pub fn load(a: &Lanes) -> V {
        V(*a)
    }

    /// `x` in every lane.
    #[inline(always)]
    pub fn splat(x: f64) -> V {
        V([x; LANES])
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn lanes(self) -> Lanes {
        self.0
    }

    /// `|x|` (the sign bit cleared, as `f64::abs`).
    #[inline(always)]
    pub fn abs(self) -> V {
        V(each(|l| self.0[l].abs()))
    }

    /// `max(x, y)` as `f64::max`: a NaN in one operand gives the other.
    #[inline(always)]
    pub fn max(self, y: V) -> V {
        V(each(|l| self.0[l].max(y.0[l])))
    }

    /// `min(x, y)` as `f64::min`: a NaN in one operand gives the other.
    #[inline(always)]
    pub fn min(self, y: V) -> V {
        V(each(|l| self.0[l].min(y.0[l])))
    }

    /// `x` finite per lane.
    #[inline(always)]
    pub fn is_finite(self) -> M {
        M(each(|l| -i64::from(self.0[l].is_finite())))
    }
}

/// The comparisons, `x.lt(y)` for `x < y` per lane and so on.
macro_rules! lane_cmp {
    ($($f:ident $op:tt),*) => {
        impl V {
            $(
                #[inline(always)]
                pub fn $f(self, y: V) -> M {
                    M(each(|l| -i64::from(self.0[l] $op y.0[l])))
                }
            )*
        }
    };
}
lane_cmp!(lt <, le <=, gt >, ge >=, eq ==);

macro_rules! lane_op {
    ($trait:ident, $f:ident, $op:tt) => {
        impl $trait for V {
            type Output = V;
            #[inline(always)]
            fn $f(self, y: V) -> V {
                V(each(|l| self.0[l] $op y.0[l]))
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl Neg for V {
    type Output = V;
    #[inline(always)]
    fn neg(self) -> V {
        V(each(|l| -self.0[l]))
    }
}

impl M {
    /// True in every lane.
    #[inline(always)]
    pub fn all_true() -> M {
        M([-1; LANES])
    }

    /// `b` in every lane.
    #[inline(always)]
    pub fn splat(b: bool) -> M {
        M([-i64::from(b); LANES])
    }

    /// Per lane, `t` where true and `f` where false.
    #[inline(always)]
    pub fn select(self, t: V, f: V) -> V {
        V(each(|l| if self.0[l] != 0 { t.0[l] } else { f.0[l] }))
    }

    /// One bit per lane, lane `l` at bit `l`.
    #[inline(always)]
    pub fn bits(self) -> u32 {
        (0..LANES).fold(0, |b, l| b | u32::from(self.0[l] != 0) << l)
    }

    /// True in some lane.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.bits() != 0
    }

    /// Lane `l`.
    #[inline(always)]
    pub fn get(self, l: usize) -> bool {
        self.0[l] != 0
    }

    /// Lane `l` set to `b`.
    #[inline(always)]
    pub fn set(&mut self, l: usize, b: bool) {
        self.0[l] = -i64::from(b);
    }
}

macro_rules! mask_op {
    ($trait:ident, $f:ident, $op:tt) => {
        impl $trait for M {
            type Output = M;
            #[inline(always)]
            fn $f(self, y: M) -> M {
                M(each(|l| self.0[l] $op y.0[l]))
            }
        }
    };
}
mask_op!(BitAnd, bitand, &);
mask_op!(BitOr, bitor, |);

impl Not for M {
    type Output = M;
    #[inline(always)]
    fn not(self) -> M {
        M(each(|l| !self.0[l]))
    }
}

/// The arithmetic and masks lane by lane against the scalar operations, NaN and signed
/// zeros included.
#[cfg(test)]
mod tests {
    use super::*;

    const VALUES: [f64; 8] = [1.5, -0.0, f64::NAN, 3.0, -2.25, f64::INFINITY, 0.0, 1e-300];
    const OTHERS: [f64; 8] = [1.5, 0.0, 2.0, f64::NAN, -3.0, 1.0, -0.0, 7.0];

    #[test]
    fn lanes_compute_as_the_scalar_operations() {
        // VALUES in each eight lanes, paired with OTHERS shifted by one more lane in each
        // eight after the first (so that every lane of a wider vector is checked too).
        let values: Lanes = each(|l| VALUES[l % 8]);
        let others: Lanes = each(|l| OTHERS[(l + l / 8) % 8]);
        let (a, b) = (V::load(&values), V::load(&others));
        // The same bits, or both NaN (a NaN's sign and payload are the instruction's).
        let same = |v: V, l: usize, r: f64| {
            let x = v.lanes()[l];
            x.to_bits() == r.to_bits() || (x.is_nan() && r.is_nan())
        };
        for l in 0..LANES {
            let (x, y) = (values[l], others[l]);
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
                assert!(same(a.min(b), l, x.min(y)), "lane {l}");
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
        let all = u32::MAX >> (32 - LANES);
        assert_eq!((!m & M::all_true()).bits(), all & !0b10_0000);
        assert!(m.any() && !M::default().any());
    }
}
