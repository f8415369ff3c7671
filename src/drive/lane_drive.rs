//! Up to [`LANES`] distinct nonlinear drives (dry friction, backlash) of one axis stepped
//! side by side: the period map of friction slope 0 of [`AxisServo::advance`] in
//! structure-of-arrays form, with its regime checks as lane masks.
//!
//! The bulk of a drive's periods is one regime: the table slips beyond its Stribeck zone
//! (`exp(-(v/vs)²) = 0`, the friction `-Fc sign(v_t)` constant) while one side of the
//! backlash is in contact, or slips without backlash. Each lane takes such a period exactly
//! where the scalar servo would take it, by the same operations in the same order:
//!
//! ```text
//! regime r carried from the last period's end (none: scalar)
//! Δv_g = |v_ff - v_ff⁻|,   r admits 2 Δv_g            (slip margin, Regime::admits)
//! c = 2 (Fs - Fc) |v₀| / vs² · exp(-(v₀/vs)²),   c / Δc < ½      (grid slope index 0)
//! u = (x - s, Δs, F_ff, -side·g(v₀) - 0·v₀, off),   y_r = Σ_j M_l[r,j] u_j  (from 0)
//! y finite;   Δv = 2 max(|y_v_t - v₀|, Δv_g);   e_F(Δv, k) ≤ tol where it is asked
//! Δv ≤ 2 Δv_g or r admits Δv;   the regime at y is r's and admits Δv;   |fe| ≤ limit
//! ```
//!
//! (`e_F` with `k = 2`, then with the sharper `k` and its `exp`, as in [`AxisServo`]'s
//! period). A lane whose period fails any of these (another slope, no carried regime, the
//! substeps' own velocities needed, a failure) runs that period through the
//! scalar [`AxisServo::advance`] instead, its whole state (the carried regime and the
//! friction-bound cache included) scattered to it and gathered back. The friction bound at
//! the period's end is the scalar [`stribeck_bound_decay`] per lane (its `exp` the same
//! `libm::exp`). The stepping itself is [`super::lane_step`]'s, which both lane kinds share.

use super::lane_step::{self, lane_product, LaneKind, LaneMaps, LaneState, Lanes, LANES};
use super::period_map::{Regime, N_INPUT, N_STATE};
use super::product::all_finite;
use super::servo::{stribeck_bound_decay, AxisServo};
use crate::error::Result;
use crate::{Axis, AxisVec};
use libm::exp;

/// A group of up to [`LANES`] nonlinear drives of one axis, in structure-of-arrays form.
#[derive(Clone, Debug)]
pub struct DriveLaneGroup {
    servos: Vec<usize>,
    /// The slope-0 period maps.
    maps: LaneMaps<N_INPUT>,
    stiffness: Lanes,
    damping: Lanes,
    half_backlash: Lanes,
    coulomb: Lanes,
    static_friction: Lanes,
    stribeck: Lanes,
    mt_over_h: Lanes,
    slope_step: Lanes,
    inv_slope_step: Lanes,
    delta_friction: Lanes,
    inv_stribeck: Lanes,
    tolerance: Lanes,
}

/// A lane's carried regime ([`Regime`], field by field; `has` false: none) and
/// friction-bound cache `(v, g, exp)`, beyond the common [`LaneState`].
#[derive(Default)]
pub(super) struct RegimeLanes {
    has: [bool; LANES],
    side: Lanes,
    offset: Lanes,
    dry: [bool; LANES],
    speed: Lanes,
    push: Lanes,
    bound: Lanes,
    decay: Lanes,
    mt_over_h: Lanes,
    cache: [(f64, f64, f64); LANES],
}

/// The lanes' carried state over one block.
type State = LaneState<RegimeLanes>;

impl DriveLaneGroup {
    /// The group of `servos` (indices into `all`, at most [`LANES`]), or None when one of
    /// them has no slope-0 map ([`AxisServo::drive_period`]).
    pub fn new(all: &[Option<AxisServo>], servos: &[usize]) -> Option<DriveLaneGroup> {
        assert!(servos.len() <= LANES);
        let z = [0.0; LANES];
        let mut g = DriveLaneGroup {
            servos: servos.to_vec(),
            maps: LaneMaps::zero(),
            stiffness: z,
            damping: z,
            half_backlash: z,
            coulomb: z,
            static_friction: z,
            stribeck: z,
            mt_over_h: z,
            slope_step: z,
            inv_slope_step: z,
            delta_friction: z,
            inv_stribeck: z,
            tolerance: z,
        };
        for (l, &s) in servos.iter().enumerate() {
            let p = all[s].as_ref()?.drive_period()?;
            g.maps.set_lane(l, &p.map);
            g.stiffness[l] = p.stiffness;
            g.damping[l] = p.damping;
            g.half_backlash[l] = p.half_backlash;
            g.coulomb[l] = p.coulomb;
            g.static_friction[l] = p.static_friction;
            g.stribeck[l] = p.stribeck;
            g.mt_over_h[l] = p.mt_over_h;
            g.slope_step[l] = p.slope_step;
            g.inv_slope_step[l] = p.inv_slope_step;
            g.delta_friction[l] = p.delta_friction;
            g.inv_stribeck[l] = p.inv_stribeck;
            g.tolerance[l] = p.tolerance;
        }
        Some(g)
    }

    /// Steps the group's live drives of `all` through `setpoints` (at `times_s`): actual
    /// positions and following errors (mm, deg) to `actual` and `following_error` at
    /// `s * BLOCK + j`, the setpoints completed to `completed[s]`; a drive that fails
    /// becomes None. Returns the lane periods stepped and how many of them were handed to
    /// the scalar servo.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn step_block(
        &self,
        all: &mut [Option<AxisServo>],
        axis: Axis,
        setpoints: &[AxisVec],
        times_s: &[f64],
        actual: &mut [f64],
        following_error: &mut [f64],
        completed: &mut [usize],
    ) -> (u64, u64) {
        let fe = Some(following_error);
        lane_step::step_block(self, all, axis, setpoints, times_s, actual, fe, completed)
    }

    /// Lane `l`'s checks after the product `y`: finite, the tolerance at k = 2 where it is
    /// asked, the margin of the period's own velocity change, the regime at its end (then
    /// carried in `st`), the following errors. The same decisions as `try_exact_period`
    /// and `end_period` in the same order of operations.
    #[inline(always)]
    // `!(a <= b)`: a NaN fails the test, as in the scalar period.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn period_ok(
        &self,
        st: &mut State,
        l: usize,
        y: &[Lanes; N_STATE],
        slope: &Lanes,
        dv_guess: &Lanes,
        s_new: f64,
    ) -> bool {
        if !all_finite(&std::array::from_fn(|r| y[r][l])) {
            return false;
        }
        let v0 = st.x[3][l];
        let dv = 2.0 * (y[3][l] - v0).abs().max(dv_guess[l]);
        if self.slope_step[l] > 0.0 && (v0.abs() - dv) * self.inv_stribeck[l] <= 40f64.sqrt() {
            // e_F at k = 2, then at the sharper k of `try_exact_period` (the same `exp`);
            // the substeps' own velocities are left to the scalar servo.
            let error = |k: f64| {
                let curvature =
                    self.delta_friction[l] * self.inv_stribeck[l] * self.inv_stribeck[l] * k;
                let grid_slope = 0.0 * self.slope_step[l];
                (slope[l] - grid_slope).abs() * dv + 0.5 * curvature * dv * dv
            };
            if !(error(2.0) <= self.tolerance[l]) {
                let u_low = (v0.abs() - dv).max(0.0) * self.inv_stribeck[l];
                let sharp = u_low >= 1.23
                    && error((4.0 * u_low * u_low - 2.0) * exp(-(u_low * u_low)))
                        <= self.tolerance[l];
                if !sharp {
                    return false;
                }
            }
        }
        if dv > 2.0 * dv_guess[l] && !admits(&st.extra, l, dv) {
            return false;
        }
        let Some((end, cache)) = self.end_regime(l, y) else {
            return false;
        };
        let same = end.side == st.extra.side[l] && end.offset == st.extra.offset[l];
        let end_admits =
            !end.dry || !(end.speed <= dv || end.push <= end.bound + end.mt_over_h * dv);
        if !(same && end_admits) {
            return false;
        }
        let s_old = st.setpoint[l];
        let fe = s_new - (y[2][l] + s_old);
        let fe_motor = s_new - (y[0][l] + s_old);
        if fe.abs() > self.maps.fe_limit[l] || fe_motor.abs() > self.maps.fe_limit[l] {
            return false;
        }
        st.extra.side[l] = end.side;
        st.extra.offset[l] = end.offset;
        st.extra.dry[l] = end.dry;
        st.extra.speed[l] = end.speed;
        st.extra.push[l] = end.push;
        st.extra.bound[l] = end.bound;
        st.extra.decay[l] = end.decay;
        st.extra.mt_over_h[l] = end.mt_over_h;
        if let Some(cache) = cache {
            st.extra.cache[l] = cache;
        }
        true
    }

    /// `linear_regime` of lane `l` at `y` (positions relative to the previous setpoint),
    /// with the friction bound's cache entry it computed.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    fn end_regime(
        &self,
        l: usize,
        y: &[Lanes; N_STATE],
    ) -> Option<(Regime, Option<(f64, f64, f64)>)> {
        let [x_m, v_m, x_t, v_t, force] = [y[0][l], y[1][l], y[2][l], y[3][l], y[4][l]];
        if force.abs() > self.maps.half_limit[l] {
            return None;
        }
        let (k, c) = (self.stiffness[l], self.damping[l]);
        let d = x_m - x_t;
        let hb = self.half_backlash[l];
        let offset = if hb > 0.0 {
            let side = if d < 0.0 { -1.0 } else { 1.0 };
            let f_spring = k * (d - side * hb) + c * (v_m - v_t);
            if d.abs() <= hb || side * f_spring <= 0.0 {
                return None;
            }
            side * hb
        } else {
            0.0
        };
        let (fc, fs) = (self.coulomb[l], self.static_friction[l]);
        if fc == 0.0 && fs == 0.0 {
            let regime = Regime::without_friction(offset);
            return Some((regime, None));
        }
        if v_t == 0.0 {
            return None;
        }
        let f_spring = k * (d - offset) + c * (v_m - v_t);
        let side = if v_t < 0.0 { -1.0 } else { 1.0 };
        let (bound, decay) = stribeck_bound_decay(v_t, fc, fs, self.stribeck[l]);
        let regime = Regime {
            side,
            offset,
            dry: true,
            speed: v_t.abs(),
            push: side * (self.mt_over_h[l] * v_t + f_spring),
            bound,
            decay,
            mt_over_h: self.mt_over_h[l],
        };
        Some((regime, Some((v_t, bound, decay))))
    }
}

impl LaneKind for DriveLaneGroup {
    type Extra = RegimeLanes;

    fn servos(&self) -> &[usize] {
        &self.servos
    }

    fn inv_scale(&self) -> &Lanes {
        &self.maps.inv_scale
    }

    /// One period by the lanes' slope-0 maps where every lane's checks pass (state
    /// updated); per lane, whether it was taken.
    #[inline(always)]
    fn mapped_period(&self, st: &mut State, q: f64) -> [bool; LANES] {
        let step = self.maps.step(st, q);
        let dv_guess: Lanes = std::array::from_fn(|l| (step.v_ff[l] - st.v_ff[l]).abs());
        let v0 = st.x[3];
        // The slope at v₀ and the friction input, as `try_exact_period` forms them.
        let mut slope = [0.0; LANES];
        let mut friction = [0.0; LANES];
        let mut start_ok = [false; LANES];
        for l in 0..LANES {
            let side = st.extra.side[l];
            let f0 = if side == 0.0 {
                0.0
            } else {
                -side * st.extra.bound[l]
            };
            let u = v0[l].abs() * self.inv_stribeck[l];
            let c = 2.0 * self.delta_friction[l] * u * self.inv_stribeck[l] * st.extra.decay[l];
            slope[l] = if side == 0.0 || self.slope_step[l] == 0.0 {
                0.0
            } else {
                c
            };
            let grid_slope = 0.0 * self.slope_step[l];
            friction[l] = f0 - grid_slope * v0[l];
            let margin = 2.0 * dv_guess[l];
            start_ok[l] = st.live[l]
                & st.extra.has[l]
                & admits(&st.extra, l, margin)
                & (slope[l] * self.inv_slope_step[l] < 0.5 || slope[l] == 0.0);
        }
        let [u0, u1, u2, u3, u4, u5, u6, u7, u8] = step.state_inputs(st);
        let u: [Lanes; N_INPUT] = [
            u0,
            u1,
            u2,
            u3,
            u4,
            u5,
            u6,
            u7,
            u8,
            friction,
            st.extra.offset,
        ];
        let y = lane_product(&self.maps.cols, &u);
        let mut ok = [false; LANES];
        for l in 0..LANES {
            ok[l] = start_ok[l]
                && q.is_finite()
                && self.period_ok(st, l, &y, &slope, &dv_guess, step.s_new[l]);
        }
        for l in 0..LANES {
            step.take(st, l, ok[l], &y);
        }
        ok
    }

    /// Lane `l`'s state to `servo`: its [`TwinState`](super::period_map::TwinState), carried
    /// regime and friction-bound cache.
    fn put(servo: &mut AxisServo, st: &State, l: usize) {
        servo.set_twin_state(&st.twin_state(l));
        let r = &st.extra;
        let regime = r.has[l].then_some(Regime {
            side: r.side[l],
            offset: r.offset[l],
            dry: r.dry[l],
            speed: r.speed[l],
            push: r.push[l],
            bound: r.bound[l],
            decay: r.decay[l],
            mt_over_h: r.mt_over_h[l],
        });
        servo.set_regime_state(regime, r.cache[l]);
    }

    /// `servo`'s state to lane `l`.
    fn get(servo: &AxisServo, st: &mut State, l: usize) {
        st.set_twin_state(l, &servo.twin_state());
        let (regime, cache) = servo.regime_state();
        let e = &mut st.extra;
        e.has[l] = regime.is_some();
        let r = regime.unwrap_or(Regime::without_friction(0.0));
        e.side[l] = r.side;
        e.offset[l] = r.offset;
        e.dry[l] = r.dry;
        e.speed[l] = r.speed;
        e.push[l] = r.push;
        e.bound[l] = r.bound;
        e.decay[l] = r.decay;
        e.mt_over_h[l] = r.mt_over_h;
        e.cache[l] = cache;
    }

    fn advance(servo: &mut AxisServo, setpoint: f64, time_s: f64) -> Result<()> {
        servo.advance(setpoint, time_s)
    }
}

/// [`Regime::admits`] of lane `l`'s carried regime.
#[inline(always)]
fn admits(r: &RegimeLanes, l: usize, dv_margin: f64) -> bool {
    !r.dry[l] || !(r.speed[l] <= dv_margin || r.push[l] <= r.bound[l] + r.mt_over_h[l] * dv_margin)
}
