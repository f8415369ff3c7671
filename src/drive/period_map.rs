//! The exact period maps of the cascade servo ([`super::servo`]): one interpolation period
//! in a linear regime as an affine map of the state, the grid of friction slopes that lets it
//! apply inside the Stribeck zone, the regime it holds in, and what the lane servos
//! ([`super::lane_servo`], [`super::lane_drive`]) take of it.

use std::cell::OnceCell;

use super::exp::exp;

#[cfg(target_arch = "x86_64")]
use super::product::Avx2;
use super::product::{ColumnProduct, Portable, Width};

/// Number of state variables of the cascade model: `x_m v_m x_t v_t F ∫ x_m,tick`.
pub(super) const N_STATE: usize = 7;

/// Inputs of a linear twin's period map: the state, `Δs` and `F_ff` (no friction, no
/// contact offset).
pub(super) const N_TWIN_INPUT: usize = N_STATE + 2;

/// What a lane servo needs to step a mapped period the way the scalar servo does: the
/// period map's first `C` columns and the constants of the period's inputs and checks. A
/// linear twin's ([`super::lane_servo`], [`super::AxisServo::advance_twin`]) is [`TwinPeriod`].
#[derive(Clone, Copy, Debug)]
pub(super) struct MappedPeriod<const C: usize> {
    /// Columns of the period map, rows `x_m v_m x_t v_t F ∫ x_m,tick` (positions relative
    /// to the previous setpoint).
    pub cols: [[f64; N_STATE]; C],
    /// SI units per interface unit and its inverse.
    pub scale: f64,
    pub inv_scale: f64,
    /// `1 / T_ipo`, 1/s.
    pub inv_t_ipo: f64,
    /// `k_aff m_tot`, kg or kg m².
    pub aff_mass: f64,
    /// Half the force limit, N or N m: the map applies while `|F|` stays within it.
    pub half_limit: f64,
    /// Divergence bound of the following errors, SI.
    pub fe_limit: f64,
}

/// A linear twin's mapped period: the first [`N_TWIN_INPUT`] columns (no friction, no
/// contact offset).
pub(super) type TwinPeriod = MappedPeriod<N_TWIN_INPUT>;

/// What a lane servo ([`super::lane_drive`]) needs to step a nonlinear drive's period the
/// way [`super::AxisServo::advance`] does when the period map of friction slope 0 applies: its
/// columns `[M | b_Δs | b_ff | b_fr | b_off]` and the constants of the regime checks, SI.
#[derive(Clone, Copy, Debug)]
pub(super) struct DrivePeriod {
    pub map: MappedPeriod<N_INPUT>,
    pub stiffness: f64,
    pub damping: f64,
    pub half_backlash: f64,
    pub coulomb: f64,
    pub static_friction: f64,
    pub stribeck: f64,
    pub mt_over_h: f64,
    /// The slope grid of [`ExactMaps`] and its tolerance.
    pub slope_step: f64,
    pub inv_slope_step: f64,
    pub delta_friction: f64,
    pub inv_stribeck: f64,
    pub tolerance: f64,
}

/// Everything a servo carries from one interpolation period to the next on the path of
/// [`super::AxisServo::advance_twin`], SI: what a lane servo gathers and scatters back.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct TwinState {
    pub setpoint: f64,
    pub v_ff: f64,
    /// `x_m v_m x_t v_t F ∫ x_m,tick`, positions absolute.
    pub x: [f64; N_STATE],
    pub velocity_si: f64,
    /// Periods advanced by the map.
    pub periods_exact: u64,
}

/// One interpolation period of the cascade model in its linear regime, as an affine map of
/// the state (positions relative to the previous setpoint `s_{k-1}`):
///
/// ```text
/// x⁺ = M(c) x + b_Δs Δs + b_ff F_ff + b_fr F_fr + b_off off
/// ```
///
/// with `Δs = s_k - s_{k-1}`, `F_ff = k_aff m_tot a_ff`, the table's dry friction affine in
/// its velocity, `F_fr + c v_t` (see [`ExactMaps`]; `F_fr = -Fc sign(v_t)`, `c = 0` while the
/// table slips faster than the Stribeck zone, both 0 without dry friction) and the spring's
/// contact offset `off` (`±b/2` while one side of the backlash is in contact, 0 without
/// backlash). Inside that regime the substep model is linear in `(x, Δs, F_ff, F_fr, off)`,
/// so its period map *is* this affine map: the columns are the substep model run once on
/// each unit vector (see [`super::AxisServo::linear_period`]). The result equals the substeps up to
/// rounding, at one 7×7 product per period instead of `n_servo · substeps` steps.
#[derive(Clone, Debug)]
pub(super) struct PeriodMap {
    /// Columns of `[M | b_Δs | b_ff | b_fr | b_off]`, each padded to 8 so that the product
    /// is a sum of whole-column vector operations.
    pub(super) cols: [[f64; 8]; N_INPUT],
    /// The same affine map to the table velocity at the start of each substep after the
    /// first (the velocities the substep model evaluates the friction at), 8 substeps per
    /// block of columns, in the same layout; lanes past the last substep repeat `v_t` at the
    /// period's start. Empty for a map without a Stribeck zone (no friction slope to check).
    pub(super) substep_velocities: Vec<[[f64; 8]; N_INPUT]>,
}

/// Inputs of [`PeriodMap`]: the state, `Δs`, `F_ff`, `F_fr`, `off`.
pub(super) const N_INPUT: usize = N_STATE + 4;

/// A linear regime of the cascade model at one state ([`super::AxisServo::linear_regime`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Regime {
    /// Direction of slip (0 without dry friction) and contact offset of the spring, SI.
    pub(super) side: f64,
    pub(super) offset: f64,
    /// Dry friction on the table: the margins below apply.
    pub(super) dry: bool,
    /// `|v_t|`, the push on the table against friction `sign(v_t) (m_t v_t / h + F_spring)`,
    /// the friction bound `g(v_t)` and `m_t / h`.
    pub(super) speed: f64,
    pub(super) push: f64,
    pub(super) bound: f64,
    /// `exp(-(v_t/vs)²)` where the bound needed it (0 beyond the Stribeck cut-off), for
    /// the friction's slope.
    pub(super) decay: f64,
    pub(super) mt_over_h: f64,
}

impl Regime {
    /// The regime of a table without dry friction: the spring's contact offset (SI) is its
    /// only condition.
    #[inline]
    pub(super) fn without_friction(offset: f64) -> Regime {
        Regime {
            side: 0.0,
            offset,
            dry: false,
            speed: 0.0,
            push: 0.0,
            bound: 0.0,
            decay: 0.0,
            mt_over_h: 0.0,
        }
    }

    /// Whether the regime holds through a velocity change of `dv_margin`: the table stays
    /// clear of rest and keeps slipping (`push > g + m_t dv / h`).
    #[inline]
    pub(super) fn admits(&self, dv_margin: f64) -> bool {
        !self.dry
            || !(self.speed <= dv_margin || self.push <= self.bound + self.mt_over_h * dv_margin)
    }

    /// The same regime (the same map inputs).
    #[inline]
    pub(super) fn same(&self, other: &Regime) -> bool {
        self.side == other.side && self.offset == other.offset
    }
}

/// `x.round()` for `x ≥ 0` (halves away from zero), at most `max` (0 for `x < 0`, `max`
/// for NaN, which `min` drops); written out because `f64::round` is a library call on
/// baseline x86-64. Through `i64`, whose conversions are one instruction each there (those
/// of `usize` are not), on `x` clamped to `[0, max + 1]`.
#[inline]
pub(super) fn round_index(x: f64, max: usize) -> usize {
    let x = x.min(max as f64 + 1.0).max(0.0);
    let i = x as i64; // truncates
    let i = if x - i as f64 >= 0.5 { i + 1 } else { i };
    (i as usize).min(max)
}

/// The period maps of one axis for a grid of friction slopes, so that the map also applies
/// while the table slips *inside* its Stribeck zone, where the dry friction
/// `f(v) = -sign(v) g(|v|)` is a smooth function of the table velocity:
///
/// ```text
/// f(v) = f(v₀) + c (v - v₀) + ½ f''(ξ) (v - v₀)²,   c = f'(v₀) = 2 (Fs - Fc) |v₀| / vs² exp(-(v₀/vs)²)
/// ```
///
/// about the velocity `v₀` at the start of the period. The substep model evaluates `f` at each
/// substep's start velocity; the map with slope `cᵢ` (the grid point nearest `c`, `0 ≤ c ≤
/// c_max = √2 (Fs - Fc) e^{-1/2} / vs`) evaluates `f(v₀) + cᵢ (v - v₀)` instead. The friction
/// force differs by at most
///
/// ```text
/// e_F = |c - cᵢ| Δv + ½ max|f''| Δv²,   |f''| ≤ (Fs - Fc) / vs² · k(u),  k = max|(4u² - 2) e^{-u²}|
/// ```
///
/// over the period, with `Δv` the largest velocity change in it (first bounded by twice what
/// the period's end points and the command's velocity change show; where that is not enough,
/// `max_j |v_j - v₀|` over the substeps' own start velocities, each affine in the map's inputs:
/// [`PeriodMap::largest_substep_velocity_change`]), `k = 2` near rest and
/// `(4u² - 2) e^{-u²}` for `u = |v|/vs ≥ 1.23`, where it falls. A period takes the map only if
/// `e_F ≤ 10⁻⁵ Fs`; a force error that small moves a loaded axis by picometres. Without a
/// Stribeck zone (`vs = 0` or `Fs = Fc`) the grid is the single slope 0 and the map is exact.
#[derive(Clone, Debug)]
pub(super) struct ExactMaps {
    /// The map of grid slope `i · slope_step`, built when a period first needs it.
    pub(super) maps: Vec<OnceCell<PeriodMap>>,
    /// Grid spacing of the slopes, N/(m/s) or N m/(rad/s) (0 with a single map).
    pub(super) slope_step: f64,
    /// `1 / slope_step` (0 with a single map).
    pub(super) inv_slope_step: f64,
    /// `Fs - Fc` and `1 / vs` (0 without a Stribeck zone).
    pub(super) delta_friction: f64,
    pub(super) inv_stribeck: f64,
    /// Accepted friction force error, N or N m.
    pub(super) tolerance: f64,
    /// No dry friction, backlash or pre-sliding (a linear twin): the single map applies
    /// whenever the force stays within half its limit at both ends of the period.
    pub(super) lti: bool,
}

impl ExactMaps {
    /// Whether the friction linearisation's force error over a velocity change `dv` from
    /// `v0` is within tolerance, for the slope `slope` at `v0` and the map's `grid_slope`:
    /// `e_F = |c - cᵢ| Δv + ½ max|f''| Δv²` with `k = max|f''| vs² / (Fs - Fc) ≤ 2`, first
    /// with `k = 2` (`e_F` grows with `k`, in floating point too), the `exp` of the sharper
    /// `k = (4u² − 2) e^{-u²}` only when that bound is not enough (`u ≥ 1.23`).
    #[inline(always)]
    pub(super) fn friction_error_within(
        &self,
        slope: f64,
        grid_slope: f64,
        v0: f64,
        dv: f64,
    ) -> bool {
        let error = |k: f64| {
            let curvature = self.delta_friction * self.inv_stribeck * self.inv_stribeck * k;
            (slope - grid_slope).abs() * dv + 0.5 * curvature * dv * dv
        };
        if error(2.0) <= self.tolerance {
            return true;
        }
        let u_low = (v0.abs() - dv).max(0.0) * self.inv_stribeck;
        u_low >= 1.23
            && error((4.0 * u_low * u_low - 2.0) * exp(-(u_low * u_low))) <= self.tolerance
    }
}

/// Slope grid intervals of [`ExactMaps`].
pub(super) const SLOPE_STEPS: usize = 64;

impl PeriodMap {
    /// The map without friction and contact offset (both 0): its first nine columns. The
    /// same result as `product_and_finite(&map_input(x, ds, f_ff, 0.0, 0.0))`: adding `c · 0 = ±0`
    /// to a sum leaves it unchanged unless the sum is `-0`, which a sum that starts at `+0`
    /// never is.
    #[inline(always)]
    pub(super) fn apply_without_friction<K: ColumnProduct>(
        &self,
        k: K,
        x: &[f64; N_STATE],
        ds: f64,
        f_ff: f64,
    ) -> ([f64; N_STATE], bool) {
        let input = [x[0], x[1], x[2], x[3], x[4], x[5], x[6], ds, f_ff];
        self.product_and_finite(k, &input)
    }

    /// The product over the first `N` columns, column by column by `k` (the same
    /// multiplications and additions in the same order whatever the vector width, so the
    /// result does not depend on the CPU), and whether it is finite ([`super::product::all_finite`]).
    /// Inlined into its caller, which picks `k`: [`super::Drives`] runs every axis in one
    /// function compiled for the widest vectors the CPU has.
    #[inline(always)]
    pub(super) fn product_and_finite<K: ColumnProduct, const N: usize>(
        &self,
        k: K,
        input: &[f64; N],
    ) -> ([f64; N_STATE], bool) {
        let acc = k.product(&self.cols, input);
        let y = [acc[0], acc[1], acc[2], acc[3], acc[4], acc[5], acc[6]];
        (y, k.finite(&acc))
    }

    /// The first `N` columns without their padding.
    pub(super) fn first_columns<const N: usize>(&self) -> [[f64; N_STATE]; N] {
        std::array::from_fn(|j| std::array::from_fn(|r| self.cols[j][r]))
    }

    /// `max_j |v_j - v₀|` over the table velocities `v_j` at the substep starts of the
    /// period (`v₀ = input[3]`, the first), for the map's inputs ([`map_input`]): the
    /// largest velocity change at which the substep model evaluates the friction in this
    /// period. Out of line: only periods whose cheap bound fails ask for it.
    ///
    /// At the CPU's widest product ([`Width`]: the same bits at every width), since a
    /// study's lanes ask it wherever neither cheap bound decides (docs/performance.md,
    /// session 30).
    #[inline(never)]
    pub(super) fn largest_substep_velocity_change(&self, input: &[f64; N_INPUT]) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if let Width::Avx2(k) = Width::detect() {
            // SAFETY: the CPU has AVX2, as the token says.
            return unsafe { self.largest_substep_velocity_change_avx2(k, input) };
        }
        self.largest_substep_velocity_change_with(Portable, input)
    }

    /// [`PeriodMap::largest_substep_velocity_change`] compiled for AVX2, its products inlined.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2")]
    unsafe fn largest_substep_velocity_change_avx2(&self, k: Avx2, input: &[f64; N_INPUT]) -> f64 {
        self.largest_substep_velocity_change_with(k, input)
    }

    #[inline(always)]
    fn largest_substep_velocity_change_with<K: ColumnProduct>(
        &self,
        k: K,
        input: &[f64; N_INPUT],
    ) -> f64 {
        let mut largest = 0.0f64;
        for cols in &self.substep_velocities {
            for v in k.product(cols, input) {
                largest = largest.max((v - input[3]).abs());
            }
        }
        largest
    }
}

/// The inputs of [`PeriodMap`] in column order: the state, `Δs`, `F_ff`, `F_fr`, `off`.
#[inline(always)]
pub(super) fn map_input(
    x: &[f64; N_STATE],
    ds: f64,
    f_ff: f64,
    friction: f64,
    offset: f64,
) -> [f64; N_INPUT] {
    [
        x[0], x[1], x[2], x[3], x[4], x[5], x[6], ds, f_ff, friction, offset,
    ]
}
