//! Up to `W` distinct linear twins of one axis stepped side by side, one per SIMD
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
//! multiplication, then an addition: never fused) of whole lane vectors; the stepping is
//! [`super::lane_step`]'s, which both lane kinds share. A lane takes the
//! map where the scalar period would and then passes its checks: `|F| ≤ F_max/2` at both
//! ends, the state finite, both following errors within their limit. A lane that does not
//! (rare: the force near its limit, a failure) runs that period through the scalar
//! [`AxisServo::advance_twin`] instead, its state scattered to it and gathered back: the
//! scalar servo then decides, counts and reports exactly as in a single run. Every lane's
//! positions are therefore the single run's, bit for bit, whatever the vector width.

use super::lane_step::{self, lane_product, LaneKind, LaneMaps, LaneState, Lanes};
use super::period_map::N_TWIN_INPUT;
use super::servo::AxisServo;
use super::simd::{M, V};
use crate::error::Result;
use crate::{Axis, AxisVec};

/// A group of up to `W` linear twins of one axis, in structure-of-arrays form.
#[derive(Clone, Debug)]
pub struct TwinLanes<const W: usize> {
    /// Which of the axis's servos each lane steps (the first `servos.len()` lanes).
    servos: Vec<usize>,
    /// The period maps.
    maps: LaneMaps<N_TWIN_INPUT, W>,
}

impl<const W: usize> TwinLanes<W> {
    /// The group of `servos` (indices into `all`, at most `W`), or None when one of
    /// them has no twin map ([`AxisServo::twin_period`]).
    pub fn new(all: &[Option<AxisServo>], servos: &[usize]) -> Option<TwinLanes<W>> {
        assert!(servos.len() <= W);
        let mut maps = LaneMaps::zero();
        for (l, &s) in servos.iter().enumerate() {
            maps.set_lane(l, &all[s].as_ref()?.twin_period()?);
        }
        Some(TwinLanes {
            servos: servos.to_vec(),
            maps,
        })
    }

    /// Steps the group's live servos of `all` (the axis `axis`'s) through `setpoints`,
    /// reached at `times_s`: each servo's actual positions (mm, deg) go to
    /// `actual[s * SLOT + j]` and the setpoints it completed to `completed[s]`; a servo
    /// that fails becomes None there. Returns the lane periods stepped and how many of them
    /// were handed to the scalar servo.
    #[inline(always)]
    pub fn step_block(
        &mut self,
        all: &mut [Option<AxisServo>],
        axis: Axis,
        setpoints: &[AxisVec],
        times_s: &[f64],
        actual: &mut [f64],
        completed: &mut [usize],
    ) -> (u64, u64) {
        lane_step::step_block(self, all, axis, setpoints, times_s, actual, None, completed)
    }
}

impl<const W: usize> LaneKind<W> for TwinLanes<W> {
    type Extra = ();

    fn servos(&self) -> &[usize] {
        &self.servos
    }

    fn inv_scale(&self) -> &Lanes<W> {
        &self.maps.inv_scale
    }

    /// One period by the lanes' maps; per lane, whether it was taken (state updated) or the
    /// lane must run it scalar (state untouched). Every check is a lane mask: a lane's
    /// choice is a select, not a branch.
    #[inline(always)]
    fn mapped_period(
        &mut self,
        st: &mut LaneState<(), W>,
        q: f64,
        _: &[Option<AxisServo>],
    ) -> M<W> {
        let m = &self.maps;
        let step = m.step(st, q);
        let (s_new, s_old) = (step.s_new, step.s_old);
        let y = lane_product(&m.cols, &step.state_inputs(st));
        let (half_limit, fe_limit) = (V::load(&m.half_limit), V::load(&m.fe_limit));
        let x_m = y[0] + s_old;
        let x_t = y[2] + s_old;
        // The scalar period's `!(a > b)`, which a NaN passes (the finite test catches it);
        // `all_finite` over the first six rows.
        let finite = (0..6).fold(M::all_true(), |f, r| f & y[r].is_finite());
        let ok = st.live
            & M::splat(q.is_finite())
            & V::load(&st.x[4]).abs().le(half_limit)
            & !y[4].abs().gt(half_limit)
            & finite
            & !(s_new - x_t).abs().gt(fe_limit)
            & !(s_new - x_m).abs().gt(fe_limit);
        step.take(st, ok, &y);
        ok
    }

    fn put(servo: &mut AxisServo, st: &LaneState<(), W>, l: usize) {
        servo.set_twin_state(&st.twin_state(l));
    }

    fn get(servo: &AxisServo, st: &mut LaneState<(), W>, l: usize) {
        st.set_twin_state(l, &servo.twin_state());
    }

    fn advance(servo: &mut AxisServo, setpoint: f64, time_s: f64) -> Result<()> {
        servo.advance_twin(setpoint, time_s)
    }
}
