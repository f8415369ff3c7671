//! The lane groups' vectors: `W` f64 as one array ([`WIDE_LANES`] or [`NARROW_LANES`]), and
//! their masks.
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
//! Each operation is a loop over the `W` lanes of plain arrays, always inlined: the
//! compiler turns it into vector instructions of the width of the function it is inlined
//! into (`DriveLanes::step_block` is compiled for AVX-512, with 16 lanes, or AVX, with 8, at run
//! time: two registers a vector). `wide::f64x4`, which these vectors were before, picks its
//! instructions when that crate is compiled (SSE2 pairs without `-C target-feature`), so
//! its operations ran as four 128-bit instructions each even inside the AVX-512 function
//! (docs/performance.md, session 25).

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// Servos per lane group where the host has AVX-512: two registers of f64, so that a
/// period's dependent operations (the map's product, row by row) run as two independent
/// chains side by side (docs/performance.md, session 29).
pub const WIDE_LANES: usize = 16;

/// Servos per lane group elsewhere: two AVX registers (16 lanes, four AVX registers a
/// vector, ran 8-9 % slower there: docs/performance.md, session 29).
pub const NARROW_LANES: usize = 8;

/// One value per lane, as the lanes' state is stored, `W` lanes.
pub type Lanes<const W: usize> = [f64; W];

/// One f64 per lane, `W` lanes.
#[derive(Clone, Copy, Debug)]
pub(super) struct V<const W: usize>([f64; W]);

/// One truth value per lane (a lane's bits all set, or all clear), `W` lanes (at most 32).
#[derive(Clone, Copy, Debug)]
pub(super) struct M<const W: usize>([i64; W]);

impl<const W: usize> Default for M<W> {
    /// False in every lane.
    #[inline(always)]
    fn default() -> M<W> {
        M([0; W])
    }
}

/// `f` lane by lane.
#[inline(always)]
fn each<U, const W: usize>(f: impl Fn(usize) -> U) -> [U; W] {
    std::array::from_fn(f)
}

impl<const W: usize> V<W> {
    /// The lanes of `a`.
    #[inline(always)]
    pub fn load(a: &[f64; W]) -> V<W> {
        V(*a)
    }

    /// `x` in every lane.
    #[inline(always)]
    pub fn splat(x: f64) -> V<W> {
        V([x; W])
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn lanes(self) -> [f64; W] {
        self.0
    }

    /// `|x|` (the sign bit cleared, as `f64::abs`).
    #[inline(always)]
    pub fn abs(self) -> V<W> {
        V(each(|l| self.0[l].abs()))
    }

    /// `max(x, y)` as `f64::max`: a NaN in one operand gives the other.
    #[inline(always)]
    pub fn max(self, y: V<W>) -> V<W> {
        V(each(|l| self.0[l].max(y.0[l])))
    }

    /// `min(x, y)` as `f64::min`: a NaN in one operand gives the other.
    #[inline(always)]
    pub fn min(self, y: V<W>) -> V<W> {
        V(each(|l| self.0[l].min(y.0[l])))
    }

    /// `x` finite per lane.
    #[inline(always)]
    pub fn is_finite(self) -> M<W> {
        M(each(|l| -i64::from(self.0[l].is_finite())))
    }
}

/// The comparisons, `x.lt(y)` for `x < y` per lane and so on.
macro_rules! lane_cmp {
    ($($f:ident $op:tt),*) => {
        impl<const W: usize> V<W> {
            $(
                #[inline(always)]
                pub fn $f(self, y: V<W>) -> M<W> {
                    M(each(|l| -i64::from(self.0[l] $op y.0[l])))
                }
            )*
        }
    };
}
lane_cmp!(lt <, le <=, gt >, ge >=, eq ==);

macro_rules! lane_op {
    ($trait:ident, $f:ident, $op:tt) => {
        impl<const W: usize> $trait for V<W> {
            type Output = V<W>;
            #[inline(always)]
            fn $f(self, y: V<W>) -> V<W> {
                V(each(|l| self.0[l] $op y.0[l]))
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl<const W: usize> Neg for V<W> {
    type Output = V<W>;
    #[inline(always)]
    fn neg(self) -> V<W> {
        V(each(|l| -self.0[l]))
    }
}

impl<const W: usize> M<W> {
    /// True in every lane.
    #[inline(always)]
    pub fn all_true() -> M<W> {
        M([-1; W])
    }

    /// `b` in every lane.
    #[inline(always)]
    pub fn splat(b: bool) -> M<W> {
        M([-i64::from(b); W])
    }

    /// Per lane, `t` where true and `f` where false.
    #[inline(always)]
    pub fn select(self, t: V<W>, f: V<W>) -> V<W> {
        V(each(|l| if self.0[l] != 0 { t.0[l] } else { f.0[l] }))
    }

    /// One bit per lane, lane `l` at bit `l`.
    #[inline(always)]
    pub fn bits(self) -> u32 {
        (0..W).fold(0, |b, l| b | u32::from(self.0[l] != 0) << l)
    }

    /// True in some lane.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.bits() != 0
    }

    /// One more in `counts[l]` for each lane `l` that is true: a true lane's bits are -1,
    /// subtracted (one vector subtraction, not a loop over [`M::bits`]).
    #[inline(always)]
    pub fn count_into(self, counts: &mut [u64; W]) {
        for (n, &m) in counts.iter_mut().zip(&self.0) {
            *n = n.wrapping_sub(m as u64);
        }
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
        impl<const W: usize> $trait for M<W> {
            type Output = M<W>;
            #[inline(always)]
            fn $f(self, y: M<W>) -> M<W> {
                M(each(|l| self.0[l] $op y.0[l]))
            }
        }
    };
}
mask_op!(BitAnd, bitand, &);
mask_op!(BitOr, bitor, |);

impl<const W: usize> Not for M<W> {
    type Output = M<W>;
    #[inline(always)]
    fn not(self) -> M<W> {
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
        compute_as_the_scalar_operations::<NARROW_LANES>();
        compute_as_the_scalar_operations::<WIDE_LANES>();
    }

    fn compute_as_the_scalar_operations<const W: usize>() {
        // VALUES in each eight lanes, paired with OTHERS shifted by one more lane in each
        // eight after the first (so that every lane of a wider vector is checked too).
        let values: [f64; W] = each(|l| VALUES[l % 8]);
        let others: [f64; W] = each(|l| OTHERS[(l + l / 8) % 8]);
        let (a, b) = (V::load(&values), V::load(&others));
        // The same bits, or both NaN (a NaN's sign and payload are the instruction's).
        let same = |v: V<W>, l: usize, r: f64| {
            let x = v.lanes()[l];
            x.to_bits() == r.to_bits() || (x.is_nan() && r.is_nan())
        };
        for l in 0..W {
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
        masks_set_and_combine::<NARROW_LANES>();
        masks_set_and_combine::<WIDE_LANES>();
    }

    fn masks_set_and_combine<const W: usize>() {
        let mut m = M::<W>::default();
        m.set(2, true);
        m.set(5, true);
        assert_eq!(m.bits(), 0b10_0100);
        m.set(2, false);
        assert_eq!(m.bits(), 0b10_0000);
        assert!(m.get(5) && !m.get(2));
        assert_eq!((m | M::splat(false)).bits(), 0b10_0000);
        let all = u32::MAX >> (32 - W);
        assert_eq!((!m & M::all_true()).bits(), all & !0b10_0000);
        assert!(m.any() && !M::<W>::default().any());
        let mut counts: [u64; W] = each(|l| l as u64);
        m.count_into(&mut counts);
        M::all_true().count_into(&mut counts);
        for (l, &n) in counts.iter().enumerate() {
            assert_eq!(n, l as u64 + 1 + u64::from(l == 5), "lane {l}");
        }
    }
}
