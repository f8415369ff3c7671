//! A lane group's periods by substeps: where a lane's period map does not apply (no linear
//! regime at the period's start — the table at rest or sticking, the backlash gap open, the
//! force near its limit — or one of the map's checks fails), the scalar servo steps the
//! period by `n_servo` controller ticks of `n_sub` mechanics substeps each
//! (`AxisServo::substep_period`). The lanes step it the same way, every lane by its own
//! constants, with the same operations in the same order:
//!
//! ```text
//! per tick j:  x_cmd = s + (s⁺ - s) · (j / n_servo),   x_fb = x_t (fully closed) or x_m
//!              v_meas = (x_m - x_m,tick) / T_servo,   x_m,tick ← x_m
//!              e_v = Kv (x_cmd - x_fb) + k_vff v_ff - v_meas,   ∫' = ∫ + Kp T_servo/Ti e_v
//!              F_u = Kp e_v + ∫' + F_ff,   F_cmd = clamp(F_u, -F_max, F_max)
//!              ∫ ← ∫' where |F_u| ≤ F_max or sign(F_u) ≠ sign(e_v)      (anti-windup)
//! per substep: F_s = k (d ∓ b/2) + c Δv, clamped to push only, in contact (d = x_m - x_t);
//!              F_s = k d + c Δv without backlash
//!              F += (F_cmd - F) α,   v_m += (F - F_s) h / m_m
//!              F_f = clamp(-(m_t v_t / h + F_s), -g(v_t), g(v_t))           (stick or slip)
//!              v_t = (m_t v_t + h (F_s + F_f)) / (m_t + h Fv),   x_m += h v_m,   x_t += h v_t
//! ```
//!
//! Each branch of the scalar substep (the backlash side, the clamps, the anti-windup) is a
//! mask and a select; the friction bound `g(v_t)` is the lane group's
//! ([`super::lane_drive`], `stribeck_bound_decay` case for case), its `exp` the scalar's
//! in the lanes that substep. A lane's result is taken only
//! where the period's end checks pass (finite state, both following errors within their
//! limit); a lane that fails them hands the period to its scalar servo, which fails it the
//! same way and reports it. So a lane's state after the period is the scalar servo's, bit
//! for bit.

use super::lane_step::{LaneState, Lanes, SetpointStep};
use super::servo::SubstepConstants;
use super::simd::{M, V};

/// The substep constants of a lane group's servos ([`SubstepConstants`]) in lanes; all
/// lanes have the same numbers of ticks and substeps.
#[derive(Clone, Debug)]
pub(super) struct SubstepLanes<const W: usize> {
    n_servo: usize,
    n_sub: usize,
    inv_t_servo: Lanes<W>,
    fully_closed: M<W>,
    kv: Lanes<W>,
    kvff: Lanes<W>,
    kp: Lanes<W>,
    ki_ts: Lanes<W>,
    force_limit: Lanes<W>,
    current_alpha: Lanes<W>,
    h: Lanes<W>,
    h_over_mm: Lanes<W>,
    mt: Lanes<W>,
    inv_mt_plus_h_fv: Lanes<W>,
    mt_over_h: Lanes<W>,
    stiffness: Lanes<W>,
    damping: Lanes<W>,
    half_backlash: Lanes<W>,
    fe_limit: Lanes<W>,
}

impl<const W: usize> SubstepLanes<W> {
    /// The lanes of `constants` (at most `W`), or None when they are none or differ
    /// in their numbers of ticks or substeps (such a group hands its substep periods to the
    /// scalar servos).
    pub(super) fn new(constants: &[SubstepConstants]) -> Option<SubstepLanes<W>> {
        let first = constants.first()?;
        let (n_servo, n_sub) = (first.n_servo, first.n_sub);
        if constants
            .iter()
            .any(|c| c.n_servo != n_servo || c.n_sub != n_sub)
        {
            return None;
        }
        let lanes = |f: fn(&SubstepConstants) -> f64| -> Lanes<W> {
            std::array::from_fn(|l| constants.get(l).map_or(0.0, f))
        };
        let mut fully_closed = M::default();
        for (l, c) in constants.iter().enumerate().take(W) {
            fully_closed.set(l, c.fully_closed);
        }
        Some(SubstepLanes {
            n_servo,
            n_sub,
            inv_t_servo: lanes(|c| c.inv_t_servo),
            fully_closed,
            kv: lanes(|c| c.kv),
            kvff: lanes(|c| c.kvff),
            kp: lanes(|c| c.kp),
            ki_ts: lanes(|c| c.ki_ts),
            force_limit: lanes(|c| c.force_limit),
            current_alpha: lanes(|c| c.current_alpha),
            h: lanes(|c| c.h),
            h_over_mm: lanes(|c| c.h_over_mm),
            mt: lanes(|c| c.mt),
            inv_mt_plus_h_fv: lanes(|c| c.inv_mt_plus_h_fv),
            mt_over_h: lanes(|c| c.mt_over_h),
            stiffness: lanes(|c| c.stiffness),
            damping: lanes(|c| c.damping),
            half_backlash: lanes(|c| c.half_backlash),
            fe_limit: lanes(|c| c.fe_limit),
        })
    }
}

/// The state a substep period advances: `x_m v_m x_t v_t F ∫ x_m,tick`, absolute positions.
type Mechanics<const W: usize> = [V<W>; 7];

/// `x.clamp(lo, hi)` per lane as `f64::clamp` (`lo ≤ hi`): `lo` below it, `hi` above it,
/// else `x` (a NaN stays).
#[inline(always)]
fn clamp<const W: usize>(x: V<W>, lo: V<W>, hi: V<W>) -> V<W> {
    let x = x.lt(lo).select(lo, x);
    x.gt(hi).select(hi, x)
}

impl<const W: usize> SubstepLanes<W> {
    /// The period to the setpoint step `step` by substeps in the lanes of `lanes`, the
    /// friction bound `g(v)` by `bound` (its `exp` asked only in the lanes it is given);
    /// returns the lanes that took it (their state and new setpoint updated), the others of
    /// `lanes` (failing the end checks) left to the scalar servo with their state untouched.
    #[inline(always)]
    pub(super) fn period<E>(
        &self,
        st: &mut LaneState<E, W>,
        step: &SetpointStep<W>,
        lanes: M<W>,
        bound: impl Fn(V<W>, M<W>) -> V<W>,
    ) -> M<W> {
        let c = self;
        let mut x: Mechanics<W> = std::array::from_fn(|r| V::load(&st.x[r]));
        let n = c.n_servo as f64;
        let force_limit = V::load(&c.force_limit);
        let zero = V::splat(0.0);
        for j in 0..c.n_servo {
            let [x_m, _, x_t, _, _, integral, x_m_tick] = x;
            let x_cmd = step.s_old + (step.s_new - step.s_old) * V::splat(j as f64 / n);
            let x_fb = c.fully_closed.select(x_t, x_m);
            let v_meas = (x_m - x_m_tick) * V::load(&c.inv_t_servo);
            x[6] = x_m;
            let v_cmd = V::load(&c.kv) * (x_cmd - x_fb) + V::load(&c.kvff) * step.v_ff;
            let ev = v_cmd - v_meas;
            let next = integral + V::load(&c.ki_ts) * ev;
            let f_unlimited = V::load(&c.kp) * ev + next + step.f_ff;
            let f_cmd = clamp(f_unlimited, -force_limit, force_limit);
            let (up, ev_up) = (f_unlimited.gt(zero), ev.gt(zero));
            let wind = f_unlimited.abs().le(force_limit) | (up & !ev_up) | (!up & ev_up);
            x[5] = wind.select(next, integral);
            for _ in 0..c.n_sub {
                self.substep(&mut x, f_cmd, |v| bound(v, lanes));
            }
        }
        let [x_m, v_m, x_t, v_t, force, integral, _] = x;
        let finite = [x_m, v_m, x_t, v_t, force, integral]
            .iter()
            .fold(lanes, |f, v| f & v.is_finite());
        let fe_limit = V::load(&self.fe_limit);
        let fe = step.s_new - x_t;
        let fe_motor = step.s_new - x_m;
        let took = finite & !fe.abs().gt(fe_limit) & !fe_motor.abs().gt(fe_limit);
        let take = |to: &mut Lanes<W>, new: V<W>| *to = took.select(new, V::load(to)).lanes();
        for (row, &new) in st.x.iter_mut().zip(&x) {
            take(row, new);
        }
        take(&mut st.velocity, v_t);
        take(&mut st.setpoint, step.s_new);
        take(&mut st.v_ff, step.v_ff);
        took
    }

    /// One substep of the current loop and the two masses under the held force command
    /// `f_cmd` (`AxisServo::substep`), the friction bound `g(v)` by `bound`.
    #[inline(always)]
    fn substep(&self, x: &mut Mechanics<W>, f_cmd: V<W>, bound: impl Fn(V<W>) -> V<W>) {
        let c = self;
        let [x_m, v_m, x_t, v_t, force, _, _] = *x;
        let zero = V::splat(0.0);
        let (k, damping) = (V::load(&self.stiffness), V::load(&self.damping));
        let hb = V::load(&self.half_backlash);
        let d = x_m - x_t;
        let dv = v_m - v_t;
        // A contact pushes but never pulls: the damper cannot make the force change sign.
        let pushing = (k * (d - hb) + damping * dv).max(zero);
        let pulling = (k * (d + hb) + damping * dv).min(zero);
        let in_play = d.gt(hb).select(pushing, d.lt(-hb).select(pulling, zero));
        let f_spring = hb.gt(zero).select(in_play, k * d + damping * dv);
        let force = force + (f_cmd - force) * V::load(&c.current_alpha);
        let v_m = v_m + (force - f_spring) * V::load(&c.h_over_mm);
        let bound = bound(v_t);
        let f_stop = -(V::load(&self.mt_over_h) * v_t + f_spring);
        let f_friction = clamp(f_stop, -bound, bound);
        let h = V::load(&c.h);
        let v_t =
            (V::load(&c.mt) * v_t + h * (f_spring + f_friction)) * V::load(&c.inv_mt_plus_h_fv);
        x[0] = x_m + h * v_m;
        x[1] = v_m;
        x[2] = x_t + h * v_t;
        x[3] = v_t;
        x[4] = force;
    }
}
