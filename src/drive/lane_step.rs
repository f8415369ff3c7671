//! The lane stepping both lane kinds share: up to `W` servos of one axis, one per SIMD
//! lane, stepped through a block of setpoints by their period maps, a lane handing a period
//! its map cannot take to its scalar servo ([`super::lane_servo`] for the linear twins,
//! [`super::lane_drive`] for the nonlinear drives).
//!
//! Per interpolation period and lane `l`, both kinds start from the same setpoint step and
//! the same state inputs, and a period the map takes ends the same way:
//!
//! ```text
//! s⁺ = q · scale_l,  v_ff = (s⁺ - s) / T_ipo,l,  F_ff = k_aff m_l (v_ff - v_ff⁻) / T_ipo,l
//! u  = (x_m - s, v_m, x_t - s, v_t, F, ∫, x_m,tick - s, s⁺ - s, F_ff, …the kind's inputs)
//! y_r = (…((0 + M_l[r,0] u_0) + M_l[r,1] u_1) + …)                         r = 0..7
//! x⁺ = y with the positions made absolute (+ s),  s ← s⁺,  v_ff⁻ ← v_ff
//! ```
//!
//! with the map stored as `cols[j][r][l]`, so that the product is a multiply-add (a
//! multiplication, then an addition: never fused) of whole lane vectors per column and row.
//! What differs between the kinds is [`LaneKind`]: the inputs beyond the state, the checks a
//! lane's period must pass, what a lane carries beyond the common [`LaneState`] (the drive's
//! regime), and which scalar period takes over. A lane whose period fails its checks runs
//! that period through the scalar servo, its state scattered to it and gathered back: the
//! scalar servo then decides, counts and reports exactly as in a single run, and every
//! lane's positions are the single run's, bit for bit, whatever the vector width.

use super::period_map::{MappedPeriod, TwinState, N_STATE, N_TWIN_INPUT};
use super::servo::AxisServo;
use super::simd::{M, V};
use crate::error::Result;
use crate::{Axis, AxisVec};

/// Setpoints stepped at a time (a lane group's outputs: [`BLOCK`] per servo).
pub const BLOCK: usize = 256;

/// The distance between two servos' outputs in an axis's output arrays: servo `s`'s
/// [`BLOCK`] entries start at `s · SLOT`. Not `BLOCK` itself: a lane group writes one entry
/// per lane and period, `W` servos apart, and at a stride of 256 × 8 bytes (a power of two)
/// all of them fall into two sets of the L1 cache, which then evicts the lines it is still
/// filling (docs/performance.md, session 30). Eight more entries move each servo to its
/// own sets.
pub const SLOT: usize = BLOCK + 8;

pub(super) use super::simd::Lanes;

/// The period maps of a lane group's servos in lanes: the first `C` columns, `cols[j][r][l]`
/// (column `j`, row `r`, lane `l`), and the constants of the period's inputs and checks
/// ([`MappedPeriod`]).
#[derive(Clone, Debug)]
pub(super) struct LaneMaps<const C: usize, const W: usize> {
    pub cols: [[Lanes<W>; N_STATE]; C],
    pub scale: Lanes<W>,
    pub inv_scale: Lanes<W>,
    pub inv_t_ipo: Lanes<W>,
    pub aff_mass: Lanes<W>,
    pub half_limit: Lanes<W>,
    pub fe_limit: Lanes<W>,
}

impl<const C: usize, const W: usize> LaneMaps<C, W> {
    /// All lanes zero (padding lanes stay so).
    pub fn zero() -> LaneMaps<C, W> {
        let z = [0.0; W];
        LaneMaps {
            cols: [[z; N_STATE]; C],
            scale: z,
            inv_scale: z,
            inv_t_ipo: z,
            aff_mass: z,
            half_limit: z,
            fe_limit: z,
        }
    }

    /// `p` into lane `l`.
    pub fn set_lane(&mut self, l: usize, p: &MappedPeriod<C>) {
        for (col, lane_col) in p.cols.iter().zip(self.cols.iter_mut()) {
            for (&m, row) in col.iter().zip(lane_col.iter_mut()) {
                row[l] = m;
            }
        }
        self.scale[l] = p.scale;
        self.inv_scale[l] = p.inv_scale;
        self.inv_t_ipo[l] = p.inv_t_ipo;
        self.aff_mass[l] = p.aff_mass;
        self.half_limit[l] = p.half_limit;
        self.fe_limit[l] = p.fe_limit;
    }

    /// The period's setpoint step to the axis position `q` (mm, deg), per lane.
    #[inline(always)]
    pub fn step<E>(&self, st: &LaneState<E, W>, q: f64) -> SetpointStep<W> {
        let inv_t_ipo = V::load(&self.inv_t_ipo);
        let s_new = V::splat(q) * V::load(&self.scale);
        let s_old = V::load(&st.setpoint);
        let v_ff = (s_new - s_old) * inv_t_ipo;
        let f_ff = V::load(&self.aff_mass) * ((v_ff - V::load(&st.v_ff)) * inv_t_ipo);
        SetpointStep {
            s_new,
            s_old,
            v_ff,
            f_ff,
        }
    }
}

/// One period's setpoint step per lane, SI: the new setpoint `s⁺`, the previous `s`, the
/// feedforward velocity `v_ff = (s⁺ - s) / T_ipo` and force `F_ff`.
pub(super) struct SetpointStep<const W: usize> {
    pub s_new: V<W>,
    pub s_old: V<W>,
    pub v_ff: V<W>,
    pub f_ff: V<W>,
}

impl<const W: usize> SetpointStep<W> {
    /// The map inputs both kinds share: the state with its positions relative to the
    /// previous setpoint, `Δs = s⁺ - s` and `F_ff`.
    #[inline(always)]
    pub fn state_inputs<E>(&self, st: &LaneState<E, W>) -> [V<W>; N_TWIN_INPUT] {
        let x = |r: usize| V::load(&st.x[r]);
        let s_old = self.s_old;
        [
            x(0) - s_old,
            x(1),
            x(2) - s_old,
            x(3),
            x(4),
            x(5),
            x(6) - s_old,
            self.s_new - s_old,
            self.f_ff,
        ]
    }

    /// The lanes' state after the period: the map's result `y` (positions relative to the
    /// previous setpoint) where `ok`, their state unchanged where not.
    #[inline(always)]
    pub fn take<E>(&self, st: &mut LaneState<E, W>, ok: M<W>, y: &[V<W>; N_STATE]) {
        let s_old = self.s_old;
        let take = |to: &mut Lanes<W>, new: V<W>| *to = ok.select(new, V::load(to)).lanes();
        take(&mut st.x[0], y[0] + s_old);
        take(&mut st.x[1], y[1]);
        take(&mut st.x[2], y[2] + s_old);
        take(&mut st.x[3], y[3]);
        take(&mut st.x[4], y[4]);
        take(&mut st.x[5], y[5]);
        take(&mut st.x[6], y[6] + s_old);
        take(&mut st.velocity, y[3]);
        st.setpoint = ok.select(self.s_new, s_old).lanes();
        take(&mut st.v_ff, self.v_ff);
        ok.count_into(&mut st.periods_exact);
    }
}

/// The lanes' carried state over one block (gathered from the servos at its start and
/// scattered back at its end, so that the servos hold it between blocks): what
/// [`TwinState`] holds, per lane, and what the kind carries beyond it (`extra`).
pub(super) struct LaneState<E, const W: usize> {
    pub setpoint: Lanes<W>,
    pub v_ff: Lanes<W>,
    /// `x_m v_m x_t v_t F ∫ x_m,tick`, positions absolute.
    pub x: [Lanes<W>; N_STATE],
    pub velocity: Lanes<W>,
    pub periods_exact: [u64; W],
    /// The lane steps a servo that has not failed.
    pub live: M<W>,
    pub extra: E,
}

impl<E: Default, const W: usize> Default for LaneState<E, W> {
    fn default() -> Self {
        let z = [0.0; W];
        LaneState {
            setpoint: z,
            v_ff: z,
            x: [z; N_STATE],
            velocity: z,
            periods_exact: [0; W],
            live: M::default(),
            extra: E::default(),
        }
    }
}

impl<E, const W: usize> LaneState<E, W> {
    /// `state` into lane `l` (its liveness and the kind's extra aside).
    pub fn set_twin_state(&mut self, l: usize, state: &TwinState) {
        self.setpoint[l] = state.setpoint;
        self.v_ff[l] = state.v_ff;
        for (row, &v) in self.x.iter_mut().zip(&state.x) {
            row[l] = v;
        }
        self.velocity[l] = state.velocity_si;
        self.periods_exact[l] = state.periods_exact;
    }

    /// Lane `l`'s [`TwinState`].
    pub fn twin_state(&self, l: usize) -> TwinState {
        TwinState {
            setpoint: self.setpoint[l],
            v_ff: self.v_ff[l],
            x: std::array::from_fn(|r| self.x[r][l]),
            velocity_si: self.velocity[l],
            periods_exact: self.periods_exact[l],
        }
    }
}

/// One kind of lane group: how its lanes take a period by their maps and how a lane's state
/// goes to and from its scalar servo, which takes the periods the map cannot.
pub(super) trait LaneKind<const W: usize> {
    /// What a lane carries beyond [`LaneState`]'s common part.
    type Extra: Default;
    /// The servos the lanes step (indices into the axis's servos; the first lanes).
    fn servos(&self) -> &[usize];
    /// SI units per interface unit, inverted, per lane.
    fn inv_scale(&self) -> &Lanes<W>;
    /// One period by the lanes' maps to the axis position `q`; per lane, whether it was
    /// taken (state updated) or the lane must run it scalar (state untouched). `all` are
    /// the axis's servos (a lane may load another of its servo's maps from them).
    fn mapped_period(
        &mut self,
        st: &mut LaneState<Self::Extra, W>,
        q: f64,
        all: &[Option<AxisServo>],
    ) -> M<W>;
    /// Lane `l`'s whole state to `servo`.
    fn put(servo: &mut AxisServo, st: &LaneState<Self::Extra, W>, l: usize);
    /// `servo`'s whole state to lane `l`.
    fn get(servo: &AxisServo, st: &mut LaneState<Self::Extra, W>, l: usize);
    /// The scalar period of `servo` to `setpoint` at `time_s`.
    fn advance(servo: &mut AxisServo, setpoint: f64, time_s: f64) -> Result<()>;
}

/// Steps the live servos of `all` (the axis `axis`'s) in `group` through `setpoints`,
/// reached at `times_s`: each servo's actual positions (mm, deg) go to
/// `actual[s * SLOT + j]`, and its following errors to `following_error` there when that
/// is asked for, and the setpoints it completed to `completed[s]`; a servo that fails
/// becomes None there. Returns the lane periods stepped and how many of them were handed to
/// the scalar servo.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn step_block<K: LaneKind<W>, const W: usize>(
    group: &mut K,
    all: &mut [Option<AxisServo>],
    axis: Axis,
    setpoints: &[AxisVec],
    times_s: &[f64],
    actual: &mut [f64],
    mut following_error: Option<&mut [f64]>,
    completed: &mut [usize],
) -> (u64, u64) {
    let mut st = gather(group, all);
    for &s in group.servos() {
        completed[s] = if all[s].is_some() { setpoints.len() } else { 0 };
    }
    let mut handed_back = 0;
    for (j, (q, &t)) in setpoints.iter().zip(times_s).enumerate() {
        let q = q[axis];
        let ok = group.mapped_period(&mut st, q, all);
        let scalar = st.live & !ok;
        if scalar.any() {
            for (l, &s) in group.servos().iter().enumerate() {
                if scalar.get(l) {
                    handed_back += 1;
                    if !scalar_period(group, all, &mut st, l, q, t) {
                        completed[s] = j;
                    }
                }
            }
        }
        let x_t = V::load(&st.x[2]);
        let inv_scale = V::load(group.inv_scale());
        // Every lane's, live or not (no branch a lane): a servo's entries beyond those it
        // completed are never read.
        let position = (x_t * inv_scale).lanes();
        for (l, &s) in group.servos().iter().enumerate() {
            actual[s * SLOT + j] = position[l];
        }
        if let Some(fe) = following_error.as_deref_mut() {
            let error = ((V::load(&st.setpoint) - x_t) * inv_scale).lanes();
            for (l, &s) in group.servos().iter().enumerate() {
                fe[s * SLOT + j] = error[l];
            }
        }
    }
    scatter(group, all, &st);
    // A lane steps every setpoint its servo completed (the one where it failed is not).
    let stepped = group.servos().iter().map(|&s| completed[s] as u64).sum();
    (stepped, handed_back)
}

/// Lane `l`'s period through its scalar servo ([`LaneKind::advance`]); false when it
/// failed (the servo is then dropped, the lane no longer live).
#[cold]
#[inline(never)]
fn scalar_period<K: LaneKind<W>, const W: usize>(
    group: &K,
    all: &mut [Option<AxisServo>],
    st: &mut LaneState<K::Extra, W>,
    l: usize,
    q: f64,
    t: f64,
) -> bool {
    let s = group.servos()[l];
    let servo = all[s].as_mut().expect("a live lane's servo");
    K::put(servo, st, l);
    if K::advance(servo, q, t).is_err() {
        all[s] = None;
        st.live.set(l, false);
        return false;
    }
    K::get(servo, st, l);
    true
}

/// The servos' state in lanes (padding lanes and failed servos not live).
fn gather<K: LaneKind<W>, const W: usize>(
    group: &K,
    all: &[Option<AxisServo>],
) -> LaneState<K::Extra, W> {
    let mut st = LaneState::default();
    for (l, &s) in group.servos().iter().enumerate() {
        if let Some(servo) = all[s].as_ref() {
            K::get(servo, &mut st, l);
            st.live.set(l, true);
        }
    }
    st
}

/// The live lanes' state back to their servos.
fn scatter<K: LaneKind<W>, const W: usize>(
    group: &K,
    all: &mut [Option<AxisServo>],
    st: &LaneState<K::Extra, W>,
) {
    for (l, &s) in group.servos().iter().enumerate() {
        if let (true, Some(servo)) = (st.live.get(l), all[s].as_mut()) {
            K::put(servo, st, l);
        }
    }
}

/// `y_r = Σ_j cols[j][r] u_j` per lane, from 0 in column order: per lane the scalar
/// period map's product, one multiplication and one addition per column, row and lane.
///
/// Row by row: one row's sum (two registers of [`V`]: `DriveLanes::step_block` is
/// compiled for AVX-512 with 16 lanes or AVX with 8) is live at a time, so none is spilled
/// to the stack between its columns. Summed column by column, all rows at once, two of the
/// 14 registers of sums went to the stack and back in every column, as register allocation
/// chose, and the period ran 6-10 % slower (docs/performance.md, session 29). The order of
/// operations per lane, hence every bit, is the same either way.
#[inline(always)]
pub(super) fn lane_product<const N: usize, const W: usize>(
    cols: &[[Lanes<W>; N_STATE]; N],
    u: &[V<W>; N],
) -> [V<W>; N_STATE] {
    let mut y = [V::splat(0.0); N_STATE];
    for (r, y_r) in y.iter_mut().enumerate() {
        let mut acc = V::splat(0.0);
        for (col, &u_j) in cols.iter().zip(u) {
            acc = acc + V::load(&col[r]) * u_j;
        }
        *y_r = acc;
    }
    y
}
