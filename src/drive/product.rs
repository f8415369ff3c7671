//! The column product of a period map, `y = Σ_j cols[j] u_j` over 8 rows, at the vector
//! width the CPU has.
//!
//! Every width does the same operations in the same order: per column and row one
//! multiplication, then one addition to the row's sum (never fused: Rust does not contract
//! them), the columns in order from a sum of `+0`. The result is therefore the same bit for
//! bit whatever the width; only the number of instructions differs (a column is two AVX
//! registers, four SSE2 ones). Not AVX-512: with one column a register it took fewer
//! instructions but more time (docs/performance.md).

/// Whether the state variables the divergence check covers, `x = (x_m v_m x_t v_t F ∫)`, are
/// finite (a state's or a product's first six rows: not `x_m,tick`, which is an earlier
/// `x_m`). `v - v` is 0 for a finite v and NaN otherwise: the sum is 0 exactly
/// when every one is finite (one comparison instead of six).
#[inline(always)]
#[allow(clippy::eq_op)] // `v - v` on purpose: NaN for a non-finite v
pub(super) fn all_finite(x: &[f64; 6]) -> bool {
    let probe = (x[0] - x[0])
        + (x[1] - x[1])
        + (x[2] - x[2])
        + (x[3] - x[3])
        + (x[4] - x[4])
        + (x[5] - x[5]);
    probe == 0.0
}

/// Columns of a period map: up to the map's inputs, 8 rows each (row 7 is padding).
type Columns<const C: usize> = [[f64; 8]; C];

/// One way of computing [`Columns`] times an input vector. A token: a value of a type other
/// than [`Portable`] exists only where the CPU has the instructions it uses.
pub(super) trait ColumnProduct: Copy {
    /// `Σ_j cols[j] input_j` over the first `N` columns (`N ≤ C`).
    fn product<const C: usize, const N: usize>(
        self,
        cols: &Columns<C>,
        input: &[f64; N],
    ) -> [f64; 8];

    /// Whether rows 0-5 of a product are finite ([`all_finite`]: row 6 is an earlier row 0,
    /// row 7 padding).
    fn finite(self, y: &[f64; 8]) -> bool;
}

/// The product in plain Rust, for any CPU (the compiler picks the width it may).
#[derive(Clone, Copy, Debug)]
pub(super) struct Portable;

impl ColumnProduct for Portable {
    #[inline(always)]
    fn product<const C: usize, const N: usize>(
        self,
        cols: &Columns<C>,
        input: &[f64; N],
    ) -> [f64; 8] {
        let mut acc = [0.0; 8];
        for (col, &u) in cols.iter().zip(input) {
            for (a, c) in acc.iter_mut().zip(col) {
                *a += c * u;
            }
        }
        acc
    }

    #[inline(always)]
    fn finite(self, y: &[f64; 8]) -> bool {
        // The six rows taken apart (`first_chunk().expect(..)`'s panic path, never taken,
        // moved other functions' code generation).
        let [x_m, v_m, x_t, v_t, force, integral, ..] = *y;
        all_finite(&[x_m, v_m, x_t, v_t, force, integral])
    }
}

/// The product in two AVX registers a column. Use it inside functions compiled for AVX2
/// (`#[target_feature]`): elsewhere its intrinsics stay calls. Its intrinsics are all AVX's,
/// but the token asks for AVX2 too: AVX2's broadcast from a register (`vbroadcastsd ymm,
/// xmm`) makes each column's `_mm256_set1_pd` one instruction, where AVX alone needs two
/// (`vmovddup` and `vinsertf128`).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(super) struct Avx2(());

/// The widest [`ColumnProduct`] the CPU has, found once.
#[derive(Clone, Copy, Debug)]
pub(super) enum Width {
    Portable,
    #[cfg(target_arch = "x86_64")]
    Avx2(Avx2),
}

impl Width {
    /// The widest the CPU has.
    pub(super) fn detect() -> Width {
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = Avx2::detect() {
            return Width::Avx2(k);
        }
        Width::Portable
    }
}

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// The token, where the CPU has AVX and AVX2.
    #[inline]
    fn detect() -> Option<Avx2> {
        (std::arch::is_x86_feature_detected!("avx") && std::arch::is_x86_feature_detected!("avx2"))
            .then_some(Avx2(()))
    }
}

#[cfg(target_arch = "x86_64")]
impl ColumnProduct for Avx2 {
    #[inline(always)]
    fn product<const C: usize, const N: usize>(
        self,
        cols: &Columns<C>,
        input: &[f64; N],
    ) -> [f64; 8] {
        // SAFETY: the token exists only where the CPU has AVX2 (`Avx2::detect`).
        unsafe { product_avx2(cols, input) }
    }

    #[inline(always)]
    fn finite(self, y: &[f64; 8]) -> bool {
        // SAFETY: as above.
        unsafe { finite_avx2(y) }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
unsafe fn product_avx2<const C: usize, const N: usize>(
    cols: &Columns<C>,
    input: &[f64; N],
) -> [f64; 8] {
    use std::arch::x86_64::*;
    let mut low = _mm256_setzero_pd();
    let mut high = _mm256_setzero_pd();
    for (col, &u) in cols.iter().zip(input) {
        let u = _mm256_set1_pd(u);
        // SAFETY: a column is 8 f64, read as two unaligned halves of 4.
        let (c_low, c_high) = unsafe {
            (
                _mm256_loadu_pd(col.as_ptr()),
                _mm256_loadu_pd(col.as_ptr().add(4)),
            )
        };
        low = _mm256_add_pd(low, _mm256_mul_pd(c_low, u));
        high = _mm256_add_pd(high, _mm256_mul_pd(c_high, u));
    }
    let mut acc = [0.0; 8];
    // SAFETY: `acc` is 8 f64, written as two unaligned halves of 4.
    unsafe {
        _mm256_storeu_pd(acc.as_mut_ptr(), low);
        _mm256_storeu_pd(acc.as_mut_ptr().add(4), high);
    }
    acc
}

/// [`ColumnProduct::finite`] on two AVX registers: `v - v` is 0 for a finite `v` and NaN
/// otherwise, so `(y_r - y_r) + (y_{r+4} - y_{r+4})` is 0 in all four lanes (rows 6 and 7
/// replaced by 0) exactly when rows 0-5 are finite, as [`all_finite`]'s sum is.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
#[allow(clippy::eq_op)] // `v - v` on purpose: NaN for a non-finite v
fn finite_avx2(y: &[f64; 8]) -> bool {
    use std::arch::x86_64::*;
    // SAFETY: `y` is 8 f64, read as two unaligned halves of 4.
    let (low, high) = unsafe {
        (
            _mm256_loadu_pd(y.as_ptr()),
            _mm256_loadu_pd(y.as_ptr().add(4)),
        )
    };
    let zero = _mm256_setzero_pd();
    let high = _mm256_blend_pd::<0b1100>(_mm256_sub_pd(high, high), zero);
    let probe = _mm256_add_pd(_mm256_sub_pd(low, low), high);
    _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_EQ_OQ>(probe, zero)) == 0b1111
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AVX token where the CPU has it; elsewhere None, after saying that `test` skips
    /// its checks of that width (the portable width's are still made).
    #[cfg(target_arch = "x86_64")]
    fn avx(test: &str) -> Option<Avx2> {
        let k = Avx2::detect();
        if k.is_none() {
            eprintln!("{test}: the AVX width's checks skipped: this CPU lacks AVX or AVX2");
        }
        k
    }

    /// No vector width besides the portable one off x86_64: None, after saying so.
    #[cfg(not(target_arch = "x86_64"))]
    fn avx(test: &str) -> Option<Portable> {
        eprintln!("{test}: the AVX width's checks skipped: not an x86_64 build");
        None
    }

    /// Every width gives the portable product bit for bit, signed zeros and all.
    #[test]
    fn every_width_gives_the_portable_product() {
        let mut cols = [[0.0; 8]; 11];
        for (j, col) in cols.iter_mut().enumerate() {
            for (r, c) in col.iter_mut().enumerate().take(7) {
                *c = ((j * 7 + r) as f64 * 0.37).sin() * 10f64.powi(r as i32 - 3);
            }
        }
        cols[2][4] = -0.0;
        let input: [f64; 11] = std::array::from_fn(|j| (j as f64 * 1.3).cos() * 1e-3);
        let zero: [f64; 9] = [-0.0; 9];
        // The portable product against the sum written out, row by row from +0.
        let expected = Portable.product(&cols, &input);
        for (r, &y) in expected.iter().enumerate() {
            let sum = cols
                .iter()
                .zip(input)
                .fold(0.0, |a, (col, u)| a + col[r] * u);
            assert_eq!(y.to_bits(), sum.to_bits(), "row {r}");
        }
        let expected_zero = Portable.product(&cols, &zero);
        let bits = |y: [f64; 8]| y.map(f64::to_bits);
        if let Some(k) = avx("every_width_gives_the_portable_product") {
            assert_eq!(bits(k.product(&cols, &input)), bits(expected));
            assert_eq!(bits(k.product(&cols, &zero)), bits(expected_zero));
        }
    }

    /// Every width finds rows 0-5 finite exactly when each of them is, whatever rows 6-7 hold.
    #[test]
    fn every_width_checks_rows_0_to_5_for_finite_values() {
        let k = avx("every_width_checks_rows_0_to_5_for_finite_values");
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for row in 0..8 {
                let mut y = [1.5, -2.0, 0.0, -0.0, 1e300, -1e-300, 3.0, 0.0];
                y[row] = bad;
                let expected = row >= 6;
                assert_eq!(Portable.finite(&y), expected, "row {row}: {bad}");
                if let Some(k) = k {
                    assert_eq!(k.finite(&y), expected, "row {row}: {bad}");
                }
            }
        }
    }
}
