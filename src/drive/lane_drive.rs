//! Up to `W` distinct nonlinear drives (dry friction, backlash) of one axis stepped
//! side by side: the period maps of [`AxisServo::advance`] in structure-of-arrays form, each
//! lane by its own friction slope's map, with the regime checks as lane masks.
//!
//! The bulk of a drive's periods is one regime: the table slips (beyond its Stribeck zone,
//! the friction `-Fc sign(v_t)` constant, or inside it, where the friction's slope picks a
//! map of the slope grid) while one side of the backlash is in contact, or slips without
//! backlash. Each lane takes such a period exactly where the scalar servo would take it,
//! by the same operations in the same order:
//!
//! ```text
//! regime r carried from the last period's end (none: scalar)
//! Δv_g = |v_ff - v_ff⁻|,   r admits 2 Δv_g            (slip margin, Regime::admits)
//! c = 2 (Fs - Fc) |v₀| / vs² · exp(-(v₀/vs)²),   i = round(c / Δc) ≤ 64   (grid slope index)
//! u = (x - s, Δs, F_ff, -side·g(v₀) - i Δc·v₀, off),   y_r = Σ_j M_l,i[r,j] u_j  (from 0)
//! y finite;   Δv = 2 max(|y_v_t - v₀|, Δv_g);   e_F(Δv, k) ≤ tol where it is asked
//! Δv ≤ 2 Δv_g or r admits Δv;   the regime at y is r's and admits Δv;   |fe| ≤ limit
//! ```
//!
//! (`e_F` with `k = 2`, then with the sharper `k` and its `exp`, as in [`AxisServo`]'s
//! period). Each lane keeps the map of one slope index in the group's columns; when a
//! period asks for another, that index's map is loaded from the lane's own servo (built
//! there as the scalar period builds it: the scalar servo and the lane use the same map).
//! Where neither tolerance bound admits a lane's period, its servo computes the bound over
//! the substeps' own velocity changes at the lane's inputs
//! ([`AxisServo::within_by_substeps`], the scalar period's own functions). A lane without
//! a carried regime (the last period went by substeps) finds it at the period's start, as
//! the scalar period does (`linear_regime`, the same operations as at a period's end).
//! Where the scalar period would step by substeps (no regime at the start, or a regime or
//! tolerance check fails), the lanes step those substeps themselves
//! ([`super::lane_substep`]). A lane whose period fails otherwise (its product or slope not
//! finite, a following error beyond its limit, a substep period that fails its end checks,
//! or a group whose lanes differ in their substeps) runs that period through the scalar
//! [`AxisServo::advance`] instead,
//! its whole state (the carried regime and the friction-bound cache included) scattered to
//! it and gathered back. The friction bound at the period's end follows
//! `servo::stribeck_bound_decay` case for case, as masks (its `exp` the scalar one's
//! formula, [`super::exp`], computed for all lanes at once and kept in the lanes that need
//! it). Every check is computed for all lanes at once
//! ([`super::simd`]'s vectors and masks): the regime a lane ends in (backlash side or gap,
//! slipping or at rest) is a mask and a select, not a branch. The stepping itself is
//! [`super::lane_step`]'s, which both lane kinds share.

use super::exp::exp_lanes;
use super::lane_step::{self, lane_product, LaneKind, LaneMaps, LaneState, Lanes};
use super::lane_substep::SubstepLanes;
use super::period_map::{Regime, N_INPUT, N_STATE, SLOPE_STEPS};
use super::servo::AxisServo;
use super::simd::{M, V};
use crate::error::Result;
use crate::{Axis, AxisVec};

/// A group of up to `W` nonlinear drives of one axis, in structure-of-arrays form.
#[derive(Clone, Debug)]
pub struct DriveLaneGroup<const W: usize> {
    servos: Vec<usize>,
    /// Each lane's period map, of its grid slope index `slope_index` (its own slope's map,
    /// loaded from its servo when the index a period asks for changes).
    maps: LaneMaps<N_INPUT, W>,
    slope_index: Lanes<W>,
    stiffness: Lanes<W>,
    damping: Lanes<W>,
    half_backlash: Lanes<W>,
    coulomb: Lanes<W>,
    static_friction: Lanes<W>,
    stribeck: Lanes<W>,
    mt_over_h: Lanes<W>,
    slope_step: Lanes<W>,
    inv_slope_step: Lanes<W>,
    delta_friction: Lanes<W>,
    inv_stribeck: Lanes<W>,
    tolerance: Lanes<W>,
    /// The constants of the lanes' substep periods (None: the lanes differ in their ticks
    /// or substeps, and hand those periods to the scalar servo).
    substeps: Option<SubstepLanes<W>>,
    /// Lane periods stepped by substeps in the lanes so far.
    substep_periods: u64,
}

/// A lane's carried regime ([`Regime`], field by field; `has` false: none) and
/// friction-bound cache `(v, g, exp)`, beyond the common [`LaneState`].
pub(super) struct RegimeLanes<const W: usize> {
    has: M<W>,
    side: Lanes<W>,
    offset: Lanes<W>,
    dry: M<W>,
    speed: Lanes<W>,
    push: Lanes<W>,
    bound: Lanes<W>,
    decay: Lanes<W>,
    mt_over_h: Lanes<W>,
    cache: [Lanes<W>; 3],
    /// Periods the lane's servo advanced by substeps so far (its count, carried).
    substepped: [u64; W],
}

impl<const W: usize> Default for RegimeLanes<W> {
    fn default() -> Self {
        let z = [0.0; W];
        RegimeLanes {
            has: M::default(),
            side: z,
            offset: z,
            dry: M::default(),
            speed: z,
            push: z,
            bound: z,
            decay: z,
            mt_over_h: z,
            cache: [z; 3],
            substepped: [0; W],
        }
    }
}

/// A regime per lane (the fields of [`Regime`]), as [`DriveLaneGroup::end_regime`] finds it.
struct RegimeV<const W: usize> {
    side: V<W>,
    offset: V<W>,
    dry: M<W>,
    speed: V<W>,
    push: V<W>,
    bound: V<W>,
    decay: V<W>,
    mt_over_h: V<W>,
}

impl<const W: usize> RegimeV<W> {
    /// [`Regime::admits`] per lane.
    #[inline(always)]
    fn admits(&self, dv_margin: V<W>) -> M<W> {
        !self.dry
            | !(self.speed.le(dv_margin) | self.push.le(self.bound + self.mt_over_h * dv_margin))
    }
}

/// The lanes' carried state over one block.
type State<const W: usize> = LaneState<RegimeLanes<W>, W>;

impl<const W: usize> DriveLaneGroup<W> {
    /// The group of `servos` (indices into `all`, at most `W`), or None when one of
    /// them has no slope-0 map ([`AxisServo::drive_period`]).
    pub fn new(all: &[Option<AxisServo>], servos: &[usize]) -> Option<DriveLaneGroup<W>> {
        assert!(servos.len() <= W);
        let z = [0.0; W];
        let mut g = DriveLaneGroup {
            servos: servos.to_vec(),
            maps: LaneMaps::zero(),
            slope_index: z,
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
            substeps: None,
            substep_periods: 0,
        };
        let mut constants = Vec::with_capacity(servos.len());
        for (l, &s) in servos.iter().enumerate() {
            let servo = all[s].as_ref()?;
            let p = servo.drive_period()?;
            constants.extend(servo.substep_constants());
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
        if constants.len() == servos.len() {
            g.substeps = SubstepLanes::new(&constants);
        }
        Some(g)
    }

    /// Steps the group's live drives of `all` through `setpoints` (at `times_s`): actual
    /// positions and following errors (mm, deg) to `actual` and `following_error` at
    /// `s * SLOT + j`, the setpoints completed to `completed[s]`; a drive that fails
    /// becomes None. Returns the lane periods stepped and how many of them were handed to
    /// the scalar servo.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn step_block(
        &mut self,
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

    /// Lane periods the group stepped by substeps in its lanes so far (of those
    /// [`DriveLaneGroup::step_block`] counts as stepped, none handed to the scalar servo).
    pub fn substep_periods(&self) -> u64 {
        self.substep_periods
    }

    /// The lanes' checks after the product `y` (`s`: the slope at v₀, the grid slope, the
    /// velocity change the setpoints ask for and the new setpoint), as masks, in the lanes
    /// of `start`: finite, the tolerance at k = 2 where it is asked (then at the sharper k,
    /// then over the substeps' own velocity changes by `by_substeps`, per lane), the margin of the period's own velocity
    /// change, the regime at its end (the same as the carried one, admitting the change),
    /// the following errors. The same decisions as `try_exact_period` and `end_period`,
    /// each lane's by the same operations; the regime's of the lanes that pass are carried
    /// in `st`. Returns the lanes that pass, and those whose product is finite but fail a
    /// regime or tolerance check (where the scalar period steps by substeps).
    #[inline(always)]
    fn period_ok(
        &self,
        st: &mut State<W>,
        (start, y): (M<W>, &[V<W>; N_STATE]),
        s: [V<W>; 4],
        by_substeps: impl Fn(&State<W>, M<W>) -> M<W>,
    ) -> (M<W>, M<W>) {
        let [slope, grid_slope, dv_guess, s_new] = s;
        let finite = (0..6).fold(start, |f, r| f & y[r].is_finite());
        let v0 = V::load(&st.x[3]);
        let two = V::splat(2.0);
        let dv = two * (y[3] - v0).abs().max(dv_guess);
        let (within, retry) = self.tolerance_ok(v0, dv, slope, grid_slope);
        let retry = finite & retry;
        let within = if retry.any() {
            within | by_substeps(st, retry)
        } else {
            within
        };
        let ok = finite & within;
        let carried = RegimeV {
            side: V::load(&st.extra.side),
            offset: V::load(&st.extra.offset),
            dry: st.extra.dry,
            speed: V::load(&st.extra.speed),
            push: V::load(&st.extra.push),
            bound: V::load(&st.extra.bound),
            decay: V::load(&st.extra.decay),
            mt_over_h: V::load(&st.extra.mt_over_h),
        };
        let ok = ok & (!dv.gt(two * dv_guess) | carried.admits(dv));
        let (end, end_ok, friction) = self.end_regime(y, ok);
        let same = end.side.eq(carried.side) & end.offset.eq(carried.offset);
        let ok = ok & end_ok & same & end.admits(dv);
        let regime_fails = finite & !ok;
        let s_old = V::load(&st.setpoint);
        let fe_limit = V::load(&self.maps.fe_limit);
        let fe = s_new - (y[2] + s_old);
        let fe_motor = s_new - (y[0] + s_old);
        let ok = ok & !fe.abs().gt(fe_limit) & !fe_motor.abs().gt(fe_limit);
        let e = &mut st.extra;
        let keep = |to: &mut Lanes<W>, new: V<W>, m: M<W>| *to = m.select(new, V::load(to)).lanes();
        keep(&mut e.side, end.side, ok);
        keep(&mut e.offset, end.offset, ok);
        e.dry = (ok & end.dry) | (!ok & e.dry);
        keep(&mut e.speed, end.speed, ok);
        keep(&mut e.push, end.push, ok);
        keep(&mut e.bound, end.bound, ok);
        keep(&mut e.decay, end.decay, ok);
        keep(&mut e.mt_over_h, end.mt_over_h, ok);
        let cached = ok & friction;
        keep(&mut e.cache[0], y[3], cached);
        keep(&mut e.cache[1], end.bound, cached);
        keep(&mut e.cache[2], end.decay, cached);
        (ok, regime_fails)
    }

    /// `linear_regime` at the period's start `x` (positions relative to the previous
    /// setpoint, as `try_exact_period` forms them) into the lanes of `fresh` (which carry
    /// none) where there is one, carried from here as the scalar period carries the regime
    /// it finds at its start; `exp` only in the lanes of `fresh`.
    #[inline(always)]
    fn regime_at_start(&self, st: &mut State<W>, x: &[V<W>; N_STATE], fresh: M<W>) {
        let (r, exists, _) = self.end_regime(x, fresh);
        let found = fresh & exists;
        let e = &mut st.extra;
        let keep = |to: &mut Lanes<W>, new: V<W>| *to = found.select(new, V::load(to)).lanes();
        keep(&mut e.side, r.side);
        keep(&mut e.offset, r.offset);
        e.dry = (found & r.dry) | (!found & e.dry);
        keep(&mut e.speed, r.speed);
        keep(&mut e.push, r.push);
        keep(&mut e.bound, r.bound);
        keep(&mut e.decay, r.decay);
        keep(&mut e.mt_over_h, r.mt_over_h);
        e.has = e.has | found;
    }

    /// The maps of grid slope `index` into the lanes of `asked` whose map is another
    /// slope's, from their servos in `all` (built there as the scalar period builds them);
    /// the lanes of `asked` whose map is now `index`'s.
    #[inline(always)]
    fn load_maps(&mut self, asked: M<W>, index: V<W>, all: &[Option<AxisServo>]) -> M<W> {
        let other = asked & !index.eq(V::load(&self.slope_index));
        if !other.any() {
            return asked;
        }
        self.load_maps_cold(asked, other, index, all)
    }

    #[cold]
    #[inline(never)]
    fn load_maps_cold(
        &mut self,
        asked: M<W>,
        other: M<W>,
        index: V<W>,
        all: &[Option<AxisServo>],
    ) -> M<W> {
        let mut failed = M::default();
        let index = index.lanes();
        for l in 0..self.servos.len() {
            if !other.get(l) {
                continue;
            }
            let i = index[l] as usize; // a whole number in [0, SLOPE_STEPS]
            match all[self.servos[l]]
                .as_ref()
                .and_then(|s| s.slope_columns(i))
            {
                Some(cols) => {
                    for (col, lane_col) in cols.iter().zip(self.maps.cols.iter_mut()) {
                        for (&m, row) in col.iter().zip(lane_col.iter_mut()) {
                            row[l] = m;
                        }
                    }
                    self.slope_index[l] = index[l];
                }
                None => failed.set(l, true),
            }
        }
        asked & !failed
    }

    /// Per lane of `lanes`, [`AxisServo::within_by_substeps`] of its servo at the period's
    /// inputs (to the axis position `q`, formed again from `st` as [`LaneKind::mapped_period`]
    /// forms them: the same operations), slope index `index` and `[slope, grid slope]`: the
    /// friction error over the substeps' own velocity changes, as the scalar period checks
    /// it where the bound from the end points is not enough (the lane's map is that
    /// index's, loaded this period).
    #[cold]
    #[inline(never)]
    fn within_by_substeps(
        &self,
        st: &State<W>,
        (lanes, q): (M<W>, f64),
        index: V<W>,
        slopes: [V<W>; 2],
        all: &[Option<AxisServo>],
    ) -> M<W> {
        let u = self.inputs(st, q, slopes[1]);
        let (index, slope, grid_slope) = (index.lanes(), slopes[0].lanes(), slopes[1].lanes());
        let mut pass = M::default();
        for (l, &s) in self.servos.iter().enumerate() {
            if !lanes.get(l) {
                continue;
            }
            let input: [f64; N_INPUT] = std::array::from_fn(|j| u[j].lanes()[l]);
            let at = (slope[l], grid_slope[l]);
            let within = all[s]
                .as_ref()
                .and_then(|servo| servo.within_by_substeps(index[l] as usize, &input, at));
            pass.set(l, within == Some(true));
        }
        pass
    }

    /// The period map's inputs per lane to the axis position `q` at the grid slope
    /// `grid_slope`: the state relative to the previous setpoint, `Δs`, `F_ff`, the friction
    /// `F_fr = -side g(v₀) - cᵢ v₀` and the contact offset, as `try_exact_period` forms them.
    #[inline(always)]
    fn inputs(&self, st: &State<W>, q: f64, grid_slope: V<W>) -> [V<W>; N_INPUT] {
        let step = self.maps.step(st, q);
        let v0 = V::load(&st.x[3]);
        let zero = V::splat(0.0);
        let side = V::load(&st.extra.side);
        let f0 = side.eq(zero).select(zero, -side * V::load(&st.extra.bound));
        let friction = f0 - grid_slope * v0;
        let [u0, u1, u2, u3, u4, u5, u6, u7, u8] = step.state_inputs(st);
        let offset = V::load(&st.extra.offset);
        [u0, u1, u2, u3, u4, u5, u6, u7, u8, friction, offset]
    }

    /// Per lane, the friction linearisation's force error `e_F(Δv, k)` within tolerance
    /// where it is asked (a Stribeck zone that the velocity change `dv` may reach from `v0`):
    /// at `k = 2`, else at the sharper `k = (4u² − 2) exp(−u²)` of `try_exact_period`, its
    /// `exp` the scalar one's bits (computed for all lanes, kept where needed); and the
    /// lanes where neither bound is enough (to be tried over the substeps' own velocity
    /// changes).
    #[inline(always)]
    fn tolerance_ok(&self, v0: V<W>, dv: V<W>, slope: V<W>, grid_slope: V<W>) -> (M<W>, M<W>) {
        let inv_vs = V::load(&self.inv_stribeck);
        let slope_step = V::load(&self.slope_step);
        let tolerance = V::load(&self.tolerance);
        let asked =
            slope_step.gt(V::splat(0.0)) & ((v0.abs() - dv) * inv_vs).le(V::splat(40f64.sqrt()));
        if !asked.any() {
            // Every lane beyond its Stribeck zone (most periods away from a reversal):
            // nothing to bound.
            return (M::all_true(), M::default());
        }
        let base = V::load(&self.delta_friction) * inv_vs * inv_vs;
        let error = |k: V<W>| {
            let curvature = base * k;
            (slope - grid_slope).abs() * dv + V::splat(0.5) * curvature * dv * dv
        };
        let coarse = error(V::splat(2.0)).le(tolerance);
        let u_low = (v0.abs() - dv).max(V::splat(0.0)) * inv_vs;
        let sharper = asked & !coarse & u_low.ge(V::splat(1.23));
        let mut sharp = M::default();
        if sharper.any() {
            let decay = sharper.select(exp_lanes(-(u_low * u_low)), V::splat(0.0));
            let k = (V::splat(4.0) * u_low * u_low - V::splat(2.0)) * decay;
            sharp = sharper & error(k).le(tolerance);
        }
        (!asked | coarse | sharp, asked & !coarse & !sharp)
    }

    /// `linear_regime` per lane at `y` (positions relative to the previous setpoint): the
    /// regime, whether there is one (beyond half the force limit, inside the backlash gap
    /// or pulling back in it, or at rest with dry friction there is none), and whether the
    /// lane has dry friction (its bound then cached). `exp` only in the lanes of `asked`.
    #[inline(always)]
    fn end_regime(&self, y: &[V<W>; N_STATE], asked: M<W>) -> (RegimeV<W>, M<W>, M<W>) {
        let [x_m, v_m, x_t, v_t, force] = [y[0], y[1], y[2], y[3], y[4]];
        let zero = V::splat(0.0);
        let (one, minus_one) = (V::splat(1.0), V::splat(-1.0));
        let force_ok = !force.abs().gt(V::load(&self.maps.half_limit));
        let (k, c) = (V::load(&self.stiffness), V::load(&self.damping));
        let d = x_m - x_t;
        let hb = V::load(&self.half_backlash);
        // Backlash: in contact on the side the motor is, and pushing there.
        let play = hb.gt(zero);
        let gap_side = d.lt(zero).select(minus_one, one);
        let f_gap = k * (d - gap_side * hb) + c * (v_m - v_t);
        let in_contact = !(d.abs().le(hb) | (gap_side * f_gap).le(zero));
        let offset = play.select(gap_side * hb, zero);
        let (fc, fs) = (V::load(&self.coulomb), V::load(&self.static_friction));
        let frictionless = fc.eq(zero) & fs.eq(zero);
        // Dry friction: slipping (at rest it sticks, which the map does not model).
        let f_spring = k * (d - offset) + c * (v_m - v_t);
        let side = v_t.lt(zero).select(minus_one, one);
        let mt_over_h = V::load(&self.mt_over_h);
        let (bound, decay) = self.bound_decay(v_t, asked & !frictionless);
        let dry = !frictionless;
        let regime = RegimeV {
            side: dry.select(side, zero),
            offset,
            dry,
            speed: dry.select(v_t.abs(), zero),
            push: dry.select(side * (mt_over_h * v_t + f_spring), zero),
            bound: dry.select(bound, zero),
            decay: dry.select(decay, zero),
            mt_over_h: dry.select(mt_over_h, zero),
        };
        let ok = force_ok & (!play | in_contact) & (frictionless | !v_t.eq(zero));
        (regime, ok, dry)
    }

    /// `stribeck_bound_decay` per lane at the table's velocity `v`: the friction bound
    /// `g(v) = Fc + (Fs − Fc) exp(−(v/vs)²)` and its decay, by the same cases and operations
    /// (no decay at `Fs = Fc` or at rest, none left beyond `(v/vs)² > 40` or without a
    /// Stribeck velocity); the `exp` only in the lanes of `asked` that need it.
    #[inline(always)]
    fn bound_decay(&self, v: V<W>, asked: M<W>) -> (V<W>, V<W>) {
        let (fc, fs) = (V::load(&self.coulomb), V::load(&self.static_friction));
        let vs = V::load(&self.stribeck);
        let (zero, one) = (V::splat(0.0), V::splat(1.0));
        let flat = fs.eq(fc) | v.eq(zero);
        let u = v / vs;
        let u2 = u * u;
        let beyond = !flat & (vs.le(zero) | u2.gt(V::splat(40.0)));
        let within = !flat & !beyond;
        let mut decay = zero;
        let needed = within & asked;
        if needed.any() {
            decay = needed.select(exp_lanes(-u2), zero);
        }
        let bound = flat.select(fs, beyond.select(fc, fc + (fs - fc) * decay));
        (bound, flat.select(one, beyond.select(zero, decay)))
    }
}

impl<const W: usize> LaneKind<W> for DriveLaneGroup<W> {
    type Extra = RegimeLanes<W>;

    fn servos(&self) -> &[usize] {
        &self.servos
    }

    fn inv_scale(&self) -> &Lanes<W> {
        &self.maps.inv_scale
    }

    /// One period by the lanes' maps, each of its own slope, where every lane's checks pass (state
    /// updated); per lane, whether it was taken. Every check is a lane mask.
    #[inline(always)]
    fn mapped_period(&mut self, st: &mut State<W>, q: f64, all: &[Option<AxisServo>]) -> M<W> {
        let step = self.maps.step(st, q);
        let [u0, u1, u2, u3, u4, u5, u6, u7, u8] = step.state_inputs(st);
        let carried_before = st.extra.has;
        let fresh = st.live & !carried_before;
        if fresh.any() {
            self.regime_at_start(st, &[u0, u1, u2, u3, u4, u5, u6], fresh);
        }
        let dv_guess = (step.v_ff - V::load(&st.v_ff)).abs();
        let v0 = V::load(&st.x[3]);
        let zero = V::splat(0.0);
        let (inv_vs, slope_step) = (V::load(&self.inv_stribeck), V::load(&self.slope_step));
        // The slope at v₀ and the friction input, as `try_exact_period` forms them.
        let side = V::load(&st.extra.side);
        let no_side = side.eq(zero);
        let f0 = no_side.select(zero, -side * V::load(&st.extra.bound));
        let u = v0.abs() * inv_vs;
        let c =
            V::splat(2.0) * V::load(&self.delta_friction) * u * inv_vs * V::load(&st.extra.decay);
        let slope = (no_side | slope_step.eq(zero)).select(zero, c);
        let at = slope * V::load(&self.inv_slope_step);
        let index = round_index(at);
        let grid_slope = index * slope_step;
        let friction = f0 - grid_slope * v0;
        let margin = V::splat(2.0) * dv_guess;
        let carried = RegimeV {
            side,
            offset: zero,
            dry: st.extra.dry,
            speed: V::load(&st.extra.speed),
            push: V::load(&st.extra.push),
            bound: V::load(&st.extra.bound),
            decay: zero,
            mt_over_h: V::load(&st.extra.mt_over_h),
        };
        let q_finite = M::splat(q.is_finite());
        let regime_ok = st.extra.has & carried.admits(margin);
        let start_ok = st.live & regime_ok & at.is_finite() & q_finite;
        let start_ok = self.load_maps(start_ok, index, all);
        let offset = V::load(&st.extra.offset);
        let u = [u0, u1, u2, u3, u4, u5, u6, u7, u8, friction, offset];
        let y = lane_product(&self.maps.cols, &u);
        let s = [slope, grid_slope, dv_guess, step.s_new];
        let this = &*self;
        let by_substeps = |st: &State<W>, lanes: M<W>| {
            this.within_by_substeps(st, (lanes, q), index, [slope, grid_slope], all)
        };
        let (ok, regime_fails) = self.period_ok(st, (start_ok, &y), s, by_substeps);
        step.take(st, ok, &y);
        // Where the scalar period would step by substeps: no linear regime at the start, or
        // one the period's checks reject (not a product that is not finite, a slope that
        // is not, a map that could not be had: those lanes go to the scalar servo).
        let by_substeps = st.live & q_finite & (!regime_ok | regime_fails);
        let substepped = match self.substeps.as_ref() {
            Some(c) if by_substeps.any() => {
                let bound = |v: V<W>, lanes: M<W>| self.bound_decay(v, lanes).0;
                c.period(st, &step, by_substeps, bound)
            }
            _ => M::default(),
        };
        substepped.count_into(&mut st.extra.substepped);
        // The scalar period takes its carried regime: only a mapped period leaves one. A
        // lane handed to the scalar servo gives it the regime it had (none for a lane whose
        // regime was found at this start).
        st.extra.has = ok | (carried_before & !substepped);
        self.substep_periods += u64::from(substepped.bits().count_ones());
        ok | substepped
    }

    /// Lane `l`'s state to `servo`: its [`TwinState`](super::period_map::TwinState), carried
    /// regime and friction-bound cache.
    fn put(servo: &mut AxisServo, st: &State<W>, l: usize) {
        servo.set_twin_state(&st.twin_state(l));
        let r = &st.extra;
        let regime = r.has.get(l).then_some(Regime {
            side: r.side[l],
            offset: r.offset[l],
            dry: r.dry.get(l),
            speed: r.speed[l],
            push: r.push[l],
            bound: r.bound[l],
            decay: r.decay[l],
            mt_over_h: r.mt_over_h[l],
        });
        let cache = (r.cache[0][l], r.cache[1][l], r.cache[2][l]);
        servo.set_regime_state(regime, cache);
        servo.set_periods_substepped(r.substepped[l]);
    }

    /// `servo`'s state to lane `l`.
    fn get(servo: &AxisServo, st: &mut State<W>, l: usize) {
        st.set_twin_state(l, &servo.twin_state());
        let (regime, cache) = servo.regime_state();
        let e = &mut st.extra;
        e.has.set(l, regime.is_some());
        let r = regime.unwrap_or(Regime::without_friction(0.0));
        e.side[l] = r.side;
        e.offset[l] = r.offset;
        e.dry.set(l, r.dry);
        e.speed[l] = r.speed;
        e.push[l] = r.push;
        e.bound[l] = r.bound;
        e.decay[l] = r.decay;
        e.mt_over_h[l] = r.mt_over_h;
        (e.cache[0][l], e.cache[1][l], e.cache[2][l]) = cache;
        e.substepped[l] = servo.periods_substepped();
    }

    fn advance(servo: &mut AxisServo, setpoint: f64, time_s: f64) -> Result<()> {
        servo.advance(setpoint, time_s)
    }
}

/// `period_map::round_index(x, SLOPE_STEPS)` per lane for finite `x` (a lane whose `x` is
/// not finite hands its period to the scalar servo): `x` clamped to `[0, SLOPE_STEPS + 1]`,
/// its whole part `i` (`floor`, as `(x + 2⁵²) − 2⁵²` rounds to an integer, less one where
/// that rounded up: every step exact), `i + 1` where `x − i ≥ ½`, at most `SLOPE_STEPS`.
#[inline(always)]
fn round_index<const W: usize>(x: V<W>) -> V<W> {
    let (zero, one) = (V::splat(0.0), V::splat(1.0));
    let top = V::splat(SLOPE_STEPS as f64);
    let x = x.gt(top + one).select(top + one, x);
    let x = x.lt(zero).select(zero, x);
    let big = V::splat(4_503_599_627_370_496.0); // 2⁵²
    let r = (x + big) - big;
    let i = r.gt(x).select(r - one, r);
    let i = (x - i).ge(V::splat(0.5)).select(i + one, i);
    i.gt(top).select(top, i)
}
