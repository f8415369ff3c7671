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
//! `libm::exp`).

use super::lane_servo::{lane_product, Lanes, BLOCK, LANES};
use super::product::all_finite;
use super::servo::{stribeck_bound_decay, AxisServo, Regime, TwinState, N_INPUT, N_STATE};
use crate::{Axis, AxisVec};
use libm::exp;

/// A group of up to [`LANES`] nonlinear drives of one axis, in structure-of-arrays form.
#[derive(Clone, Debug)]
pub struct DriveLaneGroup {
    servos: Vec<usize>,
    /// The slope-0 period maps, `cols[j][r][l]`.
    cols: [[Lanes; N_STATE]; N_INPUT],
    scale: Lanes,
    inv_scale: Lanes,
    inv_t_ipo: Lanes,
    aff_mass: Lanes,
    half_limit: Lanes,
    fe_limit: Lanes,
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

/// The lanes' carried state over one block.
#[derive(Default)]
struct State {
    setpoint: Lanes,
    v_ff: Lanes,
    x: [Lanes; N_STATE],
    velocity: Lanes,
    periods_exact: [u64; LANES],
    live: [bool; LANES],
    /// The carried regime ([`Regime`], field by field; `has` false: none).
    has: [bool; LANES],
    side: Lanes,
    offset: Lanes,
    dry: [bool; LANES],
    speed: Lanes,
    push: Lanes,
    bound: Lanes,
    decay: Lanes,
    regime_mt_over_h: Lanes,
    /// The friction-bound cache `(v, g, exp)`.
    cache: [(f64, f64, f64); LANES],
}

impl DriveLaneGroup {
    /// The group of `servos` (indices into `all`, at most [`LANES`]), or None when one of
    /// them has no slope-0 map ([`AxisServo::drive_period`]).
    pub fn new(all: &[Option<AxisServo>], servos: &[usize]) -> Option<DriveLaneGroup> {
        assert!(servos.len() <= LANES);
        let z = [0.0; LANES];
        let mut g = DriveLaneGroup {
            servos: servos.to_vec(),
            cols: [[z; N_STATE]; N_INPUT],
            scale: z,
            inv_scale: z,
            inv_t_ipo: z,
            aff_mass: z,
            half_limit: z,
            fe_limit: z,
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
            for (col, lane_col) in p.map.cols.iter().zip(g.cols.iter_mut()) {
                for (&m, row) in col.iter().zip(lane_col.iter_mut()) {
                    row[l] = m;
                }
            }
            g.scale[l] = p.map.scale;
            g.inv_scale[l] = p.map.inv_scale;
            g.inv_t_ipo[l] = p.map.inv_t_ipo;
            g.aff_mass[l] = p.map.aff_mass;
            g.half_limit[l] = p.map.half_limit;
            g.fe_limit[l] = p.map.fe_limit;
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
        let mut st = self.gather(all);
        for &s in &self.servos {
            completed[s] = if all[s].is_some() { setpoints.len() } else { 0 };
        }
        let (mut stepped, mut handed_back) = (0, 0);
        for (j, (q, &t)) in setpoints.iter().zip(times_s).enumerate() {
            let q = q[axis];
            let ok = self.mapped_period(&mut st, q);
            for (l, &s) in self.servos.iter().enumerate() {
                if st.live[l] && !ok[l] {
                    handed_back += 1;
                    if !self.scalar_period(all, &mut st, l, q, t) {
                        completed[s] = j;
                    }
                }
                if st.live[l] {
                    stepped += 1;
                    let x_t = st.x[2][l];
                    actual[s * BLOCK + j] = x_t * self.inv_scale[l];
                    following_error[s * BLOCK + j] = (st.setpoint[l] - x_t) * self.inv_scale[l];
                }
            }
        }
        self.scatter(all, &st);
        (stepped, handed_back)
    }

    /// One period by the lanes' slope-0 maps where every lane's checks pass (state
    /// updated); per lane, whether it was taken.
    #[inline(always)]
    fn mapped_period(&self, st: &mut State, q: f64) -> [bool; LANES] {
        let s_new: Lanes = std::array::from_fn(|l| q * self.scale[l]);
        let s_old = st.setpoint;
        let v_ff: Lanes = std::array::from_fn(|l| (s_new[l] - s_old[l]) * self.inv_t_ipo[l]);
        let dv_guess: Lanes = std::array::from_fn(|l| (v_ff[l] - st.v_ff[l]).abs());
        let f_ff: Lanes = std::array::from_fn(|l| {
            self.aff_mass[l] * ((v_ff[l] - st.v_ff[l]) * self.inv_t_ipo[l])
        });
        let v0 = st.x[3];
        // The slope at v₀ and the friction input, as `try_exact_period` forms them.
        let mut slope = [0.0; LANES];
        let mut friction = [0.0; LANES];
        let mut start_ok = [false; LANES];
        for l in 0..LANES {
            let side = st.side[l];
            let f0 = if side == 0.0 {
                0.0
            } else {
                -side * st.bound[l]
            };
            let u = v0[l].abs() * self.inv_stribeck[l];
            let c = 2.0 * self.delta_friction[l] * u * self.inv_stribeck[l] * st.decay[l];
            slope[l] = if side == 0.0 || self.slope_step[l] == 0.0 {
                0.0
            } else {
                c
            };
            let grid_slope = 0.0 * self.slope_step[l];
            friction[l] = f0 - grid_slope * v0[l];
            let margin = 2.0 * dv_guess[l];
            start_ok[l] = st.live[l]
                & st.has[l]
                & admits(st, l, margin)
                & (slope[l] * self.inv_slope_step[l] < 0.5 || slope[l] == 0.0);
        }
        let relative = |x: &Lanes| std::array::from_fn(|l| x[l] - s_old[l]);
        let u: [Lanes; N_INPUT] = [
            relative(&st.x[0]),
            st.x[1],
            relative(&st.x[2]),
            st.x[3],
            st.x[4],
            st.x[5],
            relative(&st.x[6]),
            std::array::from_fn(|l| s_new[l] - s_old[l]),
            f_ff,
            friction,
            st.offset,
        ];
        let y = lane_product(&self.cols, &u);
        let mut ok = [false; LANES];
        for l in 0..LANES {
            ok[l] = start_ok[l]
                && q.is_finite()
                && self.period_ok(st, l, &y, &slope, &dv_guess, s_new[l]);
        }
        for l in 0..LANES {
            let take = |new: f64, old: f64| if ok[l] { new } else { old };
            st.x[0][l] = take(y[0][l] + s_old[l], st.x[0][l]);
            st.x[1][l] = take(y[1][l], st.x[1][l]);
            st.x[2][l] = take(y[2][l] + s_old[l], st.x[2][l]);
            st.x[3][l] = take(y[3][l], st.x[3][l]);
            st.x[4][l] = take(y[4][l], st.x[4][l]);
            st.x[5][l] = take(y[5][l], st.x[5][l]);
            st.x[6][l] = take(y[6][l] + s_old[l], st.x[6][l]);
            st.velocity[l] = take(y[3][l], st.velocity[l]);
            st.setpoint[l] = take(s_new[l], s_old[l]);
            st.v_ff[l] = take(v_ff[l], st.v_ff[l]);
            st.periods_exact[l] += u64::from(ok[l]);
        }
        ok
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
        if dv > 2.0 * dv_guess[l] && !admits(st, l, dv) {
            return false;
        }
        let Some((end, cache)) = self.end_regime(l, y) else {
            return false;
        };
        let same = end.side == st.side[l] && end.offset == st.offset[l];
        let end_admits =
            !end.dry || !(end.speed <= dv || end.push <= end.bound + end.mt_over_h * dv);
        if !(same && end_admits) {
            return false;
        }
        let s_old = st.setpoint[l];
        let fe = s_new - (y[2][l] + s_old);
        let fe_motor = s_new - (y[0][l] + s_old);
        if fe.abs() > self.fe_limit[l] || fe_motor.abs() > self.fe_limit[l] {
            return false;
        }
        st.side[l] = end.side;
        st.offset[l] = end.offset;
        st.dry[l] = end.dry;
        st.speed[l] = end.speed;
        st.push[l] = end.push;
        st.bound[l] = end.bound;
        st.decay[l] = end.decay;
        st.regime_mt_over_h[l] = end.mt_over_h;
        if let Some(cache) = cache {
            st.cache[l] = cache;
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
        if force.abs() > self.half_limit[l] {
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

    /// Lane `l`'s period through its scalar servo ([`AxisServo::advance`]); false when it
    /// failed (the servo is then dropped, the lane no longer live).
    #[cold]
    #[inline(never)]
    fn scalar_period(
        &self,
        all: &mut [Option<AxisServo>],
        st: &mut State,
        l: usize,
        q: f64,
        t: f64,
    ) -> bool {
        let s = self.servos[l];
        let servo = all[s].as_mut().expect("a live lane's servo");
        put(servo, st, l);
        if servo.advance(q, t).is_err() {
            all[s] = None;
            st.live[l] = false;
            return false;
        }
        get(servo, st, l);
        true
    }

    /// The servos' state in lanes (padding lanes and failed drives not live).
    fn gather(&self, all: &[Option<AxisServo>]) -> State {
        let mut st = State::default();
        for (l, &s) in self.servos.iter().enumerate() {
            if let Some(servo) = all[s].as_ref() {
                get(servo, &mut st, l);
                st.live[l] = true;
            }
        }
        st
    }

    /// The live lanes' state back to their drives.
    fn scatter(&self, all: &mut [Option<AxisServo>], st: &State) {
        for (l, &s) in self.servos.iter().enumerate() {
            if let (true, Some(servo)) = (st.live[l], all[s].as_mut()) {
                put(servo, st, l);
            }
        }
    }
}

/// [`Regime::admits`] of lane `l`'s carried regime.
#[inline(always)]
fn admits(st: &State, l: usize, dv_margin: f64) -> bool {
    !st.dry[l]
        || !(st.speed[l] <= dv_margin
            || st.push[l] <= st.bound[l] + st.regime_mt_over_h[l] * dv_margin)
}

/// Lane `l`'s state to `servo`.
fn put(servo: &mut AxisServo, st: &State, l: usize) {
    servo.set_twin_state(&TwinState {
        setpoint: st.setpoint[l],
        v_ff: st.v_ff[l],
        x: std::array::from_fn(|r| st.x[r][l]),
        velocity_si: st.velocity[l],
        periods_exact: st.periods_exact[l],
    });
    let regime = st.has[l].then_some(Regime {
        side: st.side[l],
        offset: st.offset[l],
        dry: st.dry[l],
        speed: st.speed[l],
        push: st.push[l],
        bound: st.bound[l],
        decay: st.decay[l],
        mt_over_h: st.regime_mt_over_h[l],
    });
    servo.set_regime_state(regime, st.cache[l]);
}

/// `servo`'s state to lane `l`.
fn get(servo: &AxisServo, st: &mut State, l: usize) {
    let state = servo.twin_state();
    st.setpoint[l] = state.setpoint;
    st.v_ff[l] = state.v_ff;
    for (row, &v) in st.x.iter_mut().zip(&state.x) {
        row[l] = v;
    }
    st.velocity[l] = state.velocity_si;
    st.periods_exact[l] = state.periods_exact;
    let (regime, cache) = servo.regime_state();
    st.has[l] = regime.is_some();
    let r = regime.unwrap_or(Regime::without_friction(0.0));
    st.side[l] = r.side;
    st.offset[l] = r.offset;
    st.dry[l] = r.dry;
    st.speed[l] = r.speed;
    st.push[l] = r.push;
    st.bound[l] = r.bound;
    st.decay[l] = r.decay;
    st.regime_mt_over_h[l] = r.mt_over_h;
    st.cache[l] = cache;
}
