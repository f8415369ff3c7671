//! Up to [`LANES`] distinct linear twins of one axis stepped side by side, one per SIMD
//! lane: the period map of [`AxisServo::advance_twin`] in structure-of-arrays form.
//!
//! Each lane is its own servo (its own drive configuration, so its own period map), on the
//! axis's one setpoint stream. Per interpolation period and lane `l`, the same operations in
//! the same order as the scalar period:
//!
//! ```text
//! s⁺ = q · scale_l,  v_ff = (s⁺ - s) / T_ipo,l,  F_ff = k_aff m_l (v_ff - v_ff⁻) / T_ipo,l
//! u  = (x_m - s, v_m, x_t - s, v_t, F, ∫, x_m,tick - s, s⁺ - s, F_ff)
//! y_r = (…((0 + M_l[r,0] u_0) + M_l[r,1] u_1) + …) + M_l[r,8] u_8        r = 0..7
//! ```
//!
//! with the map stored as `cols[j][r][l]`, so that the product is 63 multiply-adds (a
//! multiplication, then an addition: never fused) of whole lane vectors. A lane takes the
//! map where the scalar period would and then passes its checks: `|F| ≤ F_max/2` at both
//! ends, the state finite, both following errors within their limit. A lane that does not
//! (rare: the force near its limit, a failure) runs that period through the scalar
//! [`AxisServo::advance_twin`] instead, its state scattered to it and gathered back: the
//! scalar servo then decides, counts and reports exactly as in a single run. Every lane's
//! positions are therefore the single run's, bit for bit, whatever the vector width.

use super::product::all_finite;
use super::servo::{AxisServo, TwinState, N_STATE, N_TWIN_INPUT};
use crate::{Axis, AxisVec};

/// Setpoints stepped at a time (a lane group's outputs: [`BLOCK`] per servo).
pub const BLOCK: usize = 256;

/// Servos per lane group: one AVX-512 register of f64 (two AVX ones).
pub const LANES: usize = 8;

/// One value per lane.
pub(super) type Lanes = [f64; LANES];

/// A group of up to [`LANES`] linear twins of one axis, in structure-of-arrays form.
#[derive(Clone, Debug)]
pub struct TwinLanes {
    /// Which of the axis's servos each lane steps (the first `servos.len()` lanes).
    servos: Vec<usize>,
    /// The period maps, `cols[j][r][l]`: column `j`, row `r`, lane `l`.
    cols: [[Lanes; N_STATE]; N_TWIN_INPUT],
    scale: Lanes,
    inv_scale: Lanes,
    inv_t_ipo: Lanes,
    aff_mass: Lanes,
    half_limit: Lanes,
    fe_limit: Lanes,
}

/// The lanes' carried state over one block (gathered from the servos at its start and
/// scattered back at its end, so that the servos hold it between blocks).
#[derive(Default)]
struct State {
    setpoint: Lanes,
    v_ff: Lanes,
    x: [Lanes; N_STATE],
    velocity: Lanes,
    periods_exact: [u64; LANES],
    /// The lane steps a servo that has not failed.
    live: [bool; LANES],
}

impl TwinLanes {
    /// The group of `servos` (indices into `all`, at most [`LANES`]), or None when one of
    /// them has no twin map ([`AxisServo::twin_period`]).
    pub fn new(all: &[Option<AxisServo>], servos: &[usize]) -> Option<TwinLanes> {
        assert!(servos.len() <= LANES);
        let mut group = TwinLanes {
            servos: servos.to_vec(),
            cols: [[[0.0; LANES]; N_STATE]; N_TWIN_INPUT],
            scale: [0.0; LANES],
            inv_scale: [0.0; LANES],
            inv_t_ipo: [0.0; LANES],
            aff_mass: [0.0; LANES],
            half_limit: [0.0; LANES],
            fe_limit: [0.0; LANES],
        };
        for (l, &s) in servos.iter().enumerate() {
            let p = all[s].as_ref()?.twin_period()?;
            for (col, lane_col) in p.cols.iter().zip(group.cols.iter_mut()) {
                for (&m, row) in col.iter().zip(lane_col.iter_mut()) {
                    row[l] = m;
                }
            }
            group.scale[l] = p.scale;
            group.inv_scale[l] = p.inv_scale;
            group.inv_t_ipo[l] = p.inv_t_ipo;
            group.aff_mass[l] = p.aff_mass;
            group.half_limit[l] = p.half_limit;
            group.fe_limit[l] = p.fe_limit;
        }
        Some(group)
    }

    /// Steps the group's live servos of `all` (the axis `axis`'s) through `setpoints`,
    /// reached at `times_s`: each servo's actual positions (mm, deg) go to
    /// `actual[s * BLOCK + j]` and the setpoints it completed to `completed[s]`; a servo
    /// that fails becomes None there. Returns the lane periods stepped and how many of them
    /// were handed to the scalar servo.
    #[inline(always)]
    pub fn step_block(
        &self,
        all: &mut [Option<AxisServo>],
        axis: Axis,
        setpoints: &[AxisVec],
        times_s: &[f64],
        actual: &mut [f64],
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
                    actual[s * BLOCK + j] = st.x[2][l] * self.inv_scale[l];
                }
            }
        }
        self.scatter(all, &st);
        (stepped, handed_back)
    }

    /// One period by the lanes' maps; per lane, whether it was taken (state updated) or the
    /// lane must run it scalar (state untouched).
    #[inline(always)]
    // `!(a > b)`: the scalar period's test, which a NaN passes (the finite test catches it).
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn mapped_period(&self, st: &mut State, q: f64) -> [bool; LANES] {
        let s_new: Lanes = std::array::from_fn(|l| q * self.scale[l]);
        let s_old = st.setpoint;
        let v_ff: Lanes = std::array::from_fn(|l| (s_new[l] - s_old[l]) * self.inv_t_ipo[l]);
        let f_ff = std::array::from_fn(|l| {
            self.aff_mass[l] * ((v_ff[l] - st.v_ff[l]) * self.inv_t_ipo[l])
        });
        let relative = |x: &Lanes| std::array::from_fn(|l| x[l] - s_old[l]);
        let u: [Lanes; N_TWIN_INPUT] = [
            relative(&st.x[0]),
            st.x[1],
            relative(&st.x[2]),
            st.x[3],
            st.x[4],
            st.x[5],
            relative(&st.x[6]),
            std::array::from_fn(|l| s_new[l] - s_old[l]),
            f_ff,
        ];
        let y = lane_product(&self.cols, &u);
        let mut ok = [false; LANES];
        for l in 0..LANES {
            let x_m = y[0][l] + s_old[l];
            let x_t = y[2][l] + s_old[l];
            // `&` rather than `&&`: every condition is computed, without branches.
            ok[l] = st.live[l]
                & q.is_finite()
                & (st.x[4][l].abs() <= self.half_limit[l])
                & !(y[4][l].abs() > self.half_limit[l])
                & all_finite(&std::array::from_fn(|r| y[r][l]))
                & !((s_new[l] - x_t).abs() > self.fe_limit[l])
                & !((s_new[l] - x_m).abs() > self.fe_limit[l]);
            let take = |new: f64, old: f64| if ok[l] { new } else { old };
            st.x[0][l] = take(x_m, st.x[0][l]);
            st.x[1][l] = take(y[1][l], st.x[1][l]);
            st.x[2][l] = take(x_t, st.x[2][l]);
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

    /// Lane `l`'s period through its scalar servo ([`AxisServo::advance_twin`]); false
    /// when it failed (the servo is then dropped, the lane no longer live).
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
        servo.set_twin_state(&lane_state(st, l));
        if servo.advance_twin(q, t).is_err() {
            all[s] = None;
            st.live[l] = false;
            return false;
        }
        set_lane_state(st, l, &servo.twin_state());
        true
    }

    /// The servos' state in lanes (padding lanes and failed servos not live).
    fn gather(&self, all: &[Option<AxisServo>]) -> State {
        let mut st = State::default();
        for (l, &s) in self.servos.iter().enumerate() {
            let Some(servo) = all[s].as_ref() else {
                continue;
            };
            set_lane_state(&mut st, l, &servo.twin_state());
            st.live[l] = true;
        }
        st
    }

    /// The live lanes' state back to their servos.
    fn scatter(&self, all: &mut [Option<AxisServo>], st: &State) {
        for (l, &s) in self.servos.iter().enumerate() {
            if let (true, Some(servo)) = (st.live[l], all[s].as_mut()) {
                servo.set_twin_state(&lane_state(st, l));
            }
        }
    }
}

/// `state` into lane `l` of the lanes' state (its liveness aside).
fn set_lane_state(st: &mut State, l: usize, state: &TwinState) {
    st.setpoint[l] = state.setpoint;
    st.v_ff[l] = state.v_ff;
    for (row, &v) in st.x.iter_mut().zip(&state.x) {
        row[l] = v;
    }
    st.velocity[l] = state.velocity_si;
    st.periods_exact[l] = state.periods_exact;
}

/// Lane `l` of the lanes' state.
fn lane_state(st: &State, l: usize) -> TwinState {
    TwinState {
        setpoint: st.setpoint[l],
        v_ff: st.v_ff[l],
        x: std::array::from_fn(|r| st.x[r][l]),
        velocity_si: st.velocity[l],
        periods_exact: st.periods_exact[l],
    }
}

/// `y_r = Σ_j cols[j][r] u_j` per lane, from 0 in column order: per lane the scalar
/// period map's product, one vector multiplication and one addition per column and row.
#[inline(always)]
pub(super) fn lane_product<const N: usize>(
    cols: &[[Lanes; N_STATE]; N],
    u: &[Lanes; N],
) -> [Lanes; N_STATE] {
    let mut y = [[0.0; LANES]; N_STATE];
    for (col, u_j) in cols.iter().zip(u) {
        for (y_r, m_r) in y.iter_mut().zip(col) {
            for l in 0..LANES {
                y_r[l] += m_r[l] * u_j[l];
            }
        }
    }
    y
}
