//! Per-axis servo drive models: the closed position loop of one machine axis, from the
//! interpolator's setpoint stream to the actual table position.
//!
//! Two models share one interface, [`AxisServo`]:
//!
//! * **first-order** — a P position loop around an ideal inner loop. The axis moves at
//!   exactly `v = Kv (x_cmd - x_fb) + k_vff dx_cmd/dt`, so its transfer function is
//!   `G(s) = Kv / (s + Kv)` without feedforward. The loop is integrated in closed form over each
//!   servo period (the command is linear in time there), so it is exact. Friction has no
//!   effect (the ideal inner loop rejects it); backlash `b` is a play element between motor and
//!   table: the table moves only when the motor pushes it at either end of the gap.
//! * **cascade** — a sampled P position loop, a sampled PI velocity loop on the motor
//!   velocity, a first-order current-loop lag with a force limit, and two-mass mechanics
//!   (motor side `m_m`, table side `m_t`) joined by a spring `k` and a damper `c` with the
//!   backlash dead zone `dz(d)`, and Stribeck friction with stiction on the table:
//!
//!   ```text
//!   v_cmd  = Kv (x_cmd - x_fb) + k_vff v_ff
//!   F_cmd  = sat( Kp (v_cmd - v_meas) + Kp/Ti ∫(v_cmd - v_meas) dt + k_aff m_tot a_ff )
//!   τ dF/dt = F_cmd - F
//!   m_m dv_m/dt = F - F_s,        F_s = k dz(x_m - x_t) + c (v_m - v_t)   (in contact)
//!   m_t dv_t/dt = F_s - F_f,      F_f = (Fc + (Fs - Fc) exp(-(v_t/vs)^2)) sign(v_t) + Fv v_t
//!   dz(d) = d - sign(d) b/2 for |d| > b/2, else 0
//!   ```
//!
//!   `x_fb` is the motor position (semi-closed loop) or the table position (fully-closed
//!   loop); `v_meas` is the motor encoder's position difference over one servo period.
//!   `Kp = 2π f_v m_tot` sets the velocity-loop bandwidth `f_v` for the rigid axis.
//!
//! **Setpoints and feedforward.** Setpoint `s_k` is where the axis should be at the end of
//! interpolation period `k`. During that period the command is the straight line from
//! `s_{k-1}` to `s_k`, sampled at each servo tick. The feedforward velocity and acceleration
//! come from the setpoint stream by finite differences, as in a real drive:
//! `v_ff = (s_k - s_{k-1}) / T_ipo` (exactly the slope of the fine-interpolated command) and
//! `a_ff = (v_ff,k - v_ff,k-1) / T_ipo`.
//!
//! **Integration.** The controller runs once per servo period and holds its force command
//! (zero-order hold). The mechanics take `substeps` steps of `h = T_servo / substeps` per
//! servo period with semi-implicit (symplectic) Euler: forces from the positions at the start
//! of the step, then velocities, then positions from the new velocities. The current-loop lag
//! is advanced exactly, `F += (F_cmd - F)(1 - exp(-h/τ))`. It is stable while
//! `h sqrt(k / min(m_m, m_t)) < 2`; the defaults give about 0.06.
//!
//! **Stiction.** Friction on the table is treated implicitly, as a force bounded by
//! `g(v) = Fc + (Fs - Fc) exp(-(v/vs)^2)` (which is `Fs` at rest). Each step first asks which
//! friction force would bring the table exactly to rest at the end of the step,
//! `F_stop = -(m_t v_t / h + F_s)`. If `|F_stop| <= g(v_t)` the table sticks: friction takes
//! that value and the new velocity is exactly zero. Otherwise the table slips with friction
//! `g(v_t)` opposing the motion, `clamp(F_stop, -g, g)`, and viscous friction enters
//! implicitly through the divisor `m_t + h Fv`. Friction can therefore never reverse the
//! velocity within a step, a resting table stays at rest until the spring force exceeds `Fs`
//! (breakaway), and there is no chattering about zero velocity nor any stiff step-size limit
//! from the friction law. With `coulomb = 0` there is no dry friction at all.
//!
//! **Units.** Positions are mm (linear) or deg (rotary) at the interface. Inside, everything
//! is SI: m, kg, N, N/m for linear axes, rad, kg m^2, N m, N m/rad for rotary ones.
//!
//! **Divergence.** After every interpolation period the state must be finite and the
//! following error (of table and motor) within `following_error_limit_mm`/`_deg`; otherwise
//! [`AxisServo::step`] returns [`Error::Diverged`]. No NaN ever leaves this module.

use std::cell::{Cell, OnceCell};
use std::f64::consts::PI;
use std::path::Path;

use super::exp::exp;
use super::period_map::{
    map_input, round_index, DrivePeriod, ExactMaps, MappedPeriod, PeriodMap, Regime, TwinPeriod,
    TwinState, N_INPUT, N_STATE, SLOPE_STEPS,
};
use super::presliding::{Presliding, ReversalValue};
use super::product::{all_finite, ColumnProduct, Portable};
use crate::error::{Error, Result};
use crate::input::drive::{si_per_unit, AxisDrive, Model};
use crate::Axis;

/// The state of one axis at the end of an interpolation period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServoState {
    /// Table-side position, mm or deg.
    pub actual: f64,
    /// Setpoint minus actual, mm or deg.
    pub following_error: f64,
    /// Motor-side position in table coordinates, mm or deg.
    pub motor: f64,
    /// Table velocity, mm/s or deg/s.
    pub velocity: f64,
    /// Motor force (N) or torque (N m); 0 in the first-order model.
    pub force: f64,
}

/// One axis's servo drive, stepped once per interpolation period. Allocation-free.
#[derive(Clone, Debug)]
pub struct AxisServo {
    axis: Axis,
    model: Model,
    fully_closed: bool,
    /// SI units per interface unit: m/mm or rad/deg.
    scale: f64,
    /// `1 / scale`: interface units per SI unit (a product where the outputs are read).
    inv_scale: f64,
    /// Inverse of the interpolation period, 1/s.
    inv_t_ipo: f64,
    /// Servo periods per interpolation period, and the servo period, s.
    n_servo: usize,
    t_servo: f64,
    /// `j / n_servo` for each tick `j` in `0..=n_servo`: where the interpolated command is
    /// at each servo tick, computed once rather than divided out every period.
    tick_fractions: Box<[f64]>,
    n_sub: usize,
    /// Mechanics substep, s.
    h: f64,
    kv: f64,
    kvff: f64,
    /// `k_aff * m_total`, kg or kg m^2.
    aff_mass: f64,
    /// Velocity-loop P gain, N/(m/s) or N m/(rad/s), and `Kp T_servo / Ti`.
    kp: f64,
    ki_ts: f64,
    /// `1 - exp(-h/τ)` of the current loop.
    current_alpha: f64,
    force_limit: f64,
    /// `h / m_m`, `m_t / h`, `1 / (m_t + h Fv)`.
    h_over_mm: f64,
    mt_over_h: f64,
    inv_mt_plus_h_fv: f64,
    mt: f64,
    stiffness: f64,
    damping: f64,
    half_backlash: f64,
    coulomb: f64,
    static_friction: f64,
    /// Stribeck velocity, m/s or rad/s (0: plain stiction).
    stribeck: f64,
    /// `exp(-Kv T_servo)` for the first-order model.
    decay: f64,
    /// Divergence bound, SI.
    fe_limit: f64,
    // State, SI.
    setpoint: f64,
    v_ff: f64,
    x_m: f64,
    v_m: f64,
    x_t: f64,
    v_t: f64,
    force: f64,
    integral: f64,
    x_m_tick: f64,
    /// Pre-sliding (Dahl) friction on the table, replacing the Coulomb/stiction law.
    presliding: Option<Presliding>,
    /// The axis's lost motion at a reversal, mm or deg.
    reversal: ReversalValue,
    /// The exact affine maps of one interpolation period in the linear regime (cascade
    /// model); None for the first-order model or when switched off.
    exact: Option<Box<ExactMaps>>,
    /// The last friction bound the regime check computed, `(v, g(v))`: the check at a
    /// period's end and the one at the next period's start see the same table velocity, so
    /// `g` (an `exp`) is evaluated once for both.
    bound_cache: Cell<(f64, f64, f64)>,
    /// The regime found at the end of the last period, when that period took the map (the
    /// start of the next one).
    carried_regime: Option<Regime>,
    /// Table velocity after the last period, SI (first-order: its mean over the period).
    velocity_si: f64,
    /// Interpolation periods advanced by the affine map, and by substeps.
    periods_exact: u64,
    periods_substepped: u64,
}

impl AxisServo {
    /// The servo of `drive` (validated and in SI units, [`AxisDrive`]), stepped every
    /// `interpolation_period_s`. Starts at rest at `initial_position` (mm or deg), the backlash
    /// gap centred.
    pub fn new(
        drive: &AxisDrive,
        interpolation_period_s: f64,
        initial_position: f64,
    ) -> Result<AxisServo> {
        let axis = drive.axis;
        let where_ = format!("[axes.{axis}]");
        if !(interpolation_period_s.is_finite() && interpolation_period_s > 0.0) {
            return Err(Error::invalid(
                Path::new(&where_),
                format!(
                    "the interpolation period must be positive, got {interpolation_period_s} s"
                ),
            ));
        }
        if !initial_position.is_finite() {
            return Err(Error::invalid(
                Path::new(&where_),
                format!("the initial position must be finite, got {initial_position}"),
            ));
        }
        let d = drive;
        let scale = si_per_unit(axis);
        let t_ipo = interpolation_period_s;
        let n_servo = ((t_ipo / d.servo_period_s).round() as usize).max(1);
        let t_servo = t_ipo / n_servo as f64;
        let n_sub = d.substeps as usize;
        let h = t_servo / n_sub as f64;
        let mm = d.motor_mass_kg_or_kgm2;
        let mt = d.table_mass_kg_or_kgm2;
        let m_total = mm + mt;
        let stiffness = d.stiffness_n_per_m_or_nm_per_rad;
        let damping = 2.0 * d.damping_ratio * (stiffness * mm * mt / m_total).sqrt();
        let tau = d.current_time_constant_s;
        let viscous = d.viscous_n_s_per_m_or_nm_s_per_rad;
        let coulomb = d.coulomb_n_or_nm;
        let kp = 2.0 * PI * d.velocity_bandwidth_hz * m_total;
        let state = initial_position * scale;
        Ok(AxisServo {
            axis,
            model: d.model,
            fully_closed: d.fully_closed,
            scale,
            inv_scale: 1.0 / scale,
            inv_t_ipo: 1.0 / t_ipo,
            n_servo,
            t_servo,
            tick_fractions: (0..=n_servo).map(|j| j as f64 / n_servo as f64).collect(),
            n_sub,
            h,
            kv: d.kv_per_s,
            kvff: d.velocity_feedforward,
            aff_mass: d.acceleration_feedforward * m_total,
            kp,
            ki_ts: kp * t_servo / d.velocity_integral_time_s,
            current_alpha: if tau > 0.0 { -(-h / tau).exp_m1() } else { 1.0 },
            force_limit: d.force_limit_n_or_nm,
            h_over_mm: h / mm,
            mt_over_h: mt / h,
            inv_mt_plus_h_fv: 1.0 / (mt + h * viscous),
            mt,
            stiffness,
            damping,
            half_backlash: 0.5 * d.backlash_m_or_rad,
            coulomb,
            static_friction: coulomb * d.static_ratio,
            stribeck: d.stribeck_m_or_rad_per_s,
            decay: (-d.kv_per_s * t_servo).exp(),
            fe_limit: d.following_error_limit_m_or_rad,
            setpoint: state,
            v_ff: 0.0,
            x_m: state,
            v_m: 0.0,
            x_t: state,
            v_t: 0.0,
            force: 0.0,
            integral: 0.0,
            x_m_tick: state,
            presliding: (d.presliding_m_or_rad > 0.0 && coulomb > 0.0).then(|| {
                Presliding::new(
                    coulomb,
                    d.presliding_m_or_rad,
                    mt,
                    d.presliding_damping_ratio,
                )
            }),
            // The reversal value is a figure in the axis's interface unit (mm or deg).
            reversal: ReversalValue::new(
                d.backlash_mm_or_deg,
                coulomb,
                stiffness * scale,
                d.presliding_mm_or_deg,
                d.fully_closed,
            ),
            exact: None,
            bound_cache: Cell::new((0.0, coulomb * d.static_ratio, 1.0)),
            carried_regime: None,
            velocity_si: 0.0,
            periods_exact: 0,
            periods_substepped: 0,
        }
        .with_exact_map(true))
    }

    /// Switches the exact affine period map of the linear regime on (the default) or off
    /// (every period by substeps, the reference the map is tested against).
    pub fn with_exact_map(mut self, on: bool) -> AxisServo {
        self.exact = (on && self.model == Model::Cascade).then(|| Box::new(self.exact_maps()));
        self
    }

    /// The period maps over the slope grid of [`ExactMaps`].
    fn exact_maps(&self) -> ExactMaps {
        let delta = self.static_friction - self.coulomb;
        let stribeck_zone =
            self.presliding.is_none() && self.coulomb > 0.0 && delta > 0.0 && self.stribeck > 0.0;
        if !stribeck_zone {
            return ExactMaps {
                maps: vec![OnceCell::from(self.period_map(0.0, false))],
                slope_step: 0.0,
                inv_slope_step: 0.0,
                delta_friction: 0.0,
                inv_stribeck: 0.0,
                tolerance: 0.0,
                // What `linear_regime` finds for such an axis: side 0 and offset 0 always.
                lti: self.presliding.is_none()
                    && !(self.half_backlash > 0.0)
                    && self.coulomb == 0.0
                    && self.static_friction == 0.0,
            };
        }
        let c_max = std::f64::consts::SQRT_2 * delta * (-0.5f64).exp() / self.stribeck;
        let step = c_max / SLOPE_STEPS as f64;
        ExactMaps {
            maps: (0..=SLOPE_STEPS).map(|_| OnceCell::new()).collect(),
            slope_step: step,
            inv_slope_step: 1.0 / step,
            delta_friction: delta,
            inv_stribeck: 1.0 / self.stribeck,
            tolerance: 1e-5 * self.static_friction,
            lti: false,
        }
    }

    /// Interpolation periods advanced so far by the exact map and by substeps.
    pub fn period_counts(&self) -> (u64, u64) {
        (self.periods_exact, self.periods_substepped)
    }

    /// Builds [`PeriodMap`] for friction slope `slope` by running
    /// [`AxisServo::linear_period`] on each unit input; with `substep_velocities`, also the
    /// map to the table velocity at each substep start after the first.
    fn period_map(&self, slope: f64, substep_velocities: bool) -> PeriodMap {
        let mut cols = [[0.0; 8]; N_INPUT];
        let n_mid = if substep_velocities {
            self.n_servo * self.n_sub - 1
        } else {
            0
        };
        let mut velocity_cols = vec![[[0.0; 8]; N_INPUT]; n_mid.div_ceil(8)];
        let mut mids = Vec::with_capacity(n_mid + 1);
        for (j, col) in cols.iter_mut().enumerate() {
            let mut x = [0.0; N_STATE];
            let mut u = [0.0; 4];
            if j < N_STATE {
                x[j] = 1.0;
            } else {
                u[j - N_STATE] = 1.0;
            }
            mids.clear();
            let y = self.linear_period(x, u[0], u[1], u[2], u[3], slope, &mut mids);
            col[..N_STATE].copy_from_slice(&y);
            for (block, lanes) in velocity_cols.iter_mut().enumerate() {
                for (lane, c) in lanes[j].iter_mut().enumerate() {
                    // Past the last substep: v_t at the period's start (column 3).
                    *c = match mids.get(block * 8 + lane) {
                        Some(&v) if block * 8 + lane < n_mid => v,
                        _ => f64::from(j == 3),
                    };
                }
            }
        }
        PeriodMap {
            cols,
            substep_velocities: velocity_cols,
        }
    }

    /// The cascade model over one interpolation period with its nonlinearities frozen: no
    /// force limit, table friction `friction + slope v_t` (at each substep's start
    /// velocity, as the substep model evaluates it), the spring `k (d - offset) +
    /// c Δv` without its contact clamp. Positions relative to `s_{k-1}`. The same arithmetic
    /// as [`AxisServo::step_cascade`] and [`AxisServo::substep`] in the regime they agree.
    /// Pushes the table velocity after each substep onto `velocities`.
    #[allow(clippy::too_many_arguments)]
    fn linear_period(
        &self,
        x: [f64; N_STATE],
        ds: f64,
        f_ff: f64,
        friction: f64,
        offset: f64,
        slope: f64,
        velocities: &mut Vec<f64>,
    ) -> [f64; N_STATE] {
        let [mut x_m, mut v_m, mut x_t, mut v_t, mut force, mut integral, mut x_m_tick] = x;
        let inv_ts = 1.0 / self.t_servo;
        let v_ff = ds * self.inv_t_ipo;
        for &fraction in &self.tick_fractions[..self.n_servo] {
            let x_cmd = ds * fraction;
            let x_fb = if self.fully_closed { x_t } else { x_m };
            let v_meas = (x_m - x_m_tick) * inv_ts;
            x_m_tick = x_m;
            let ev = self.kv * (x_cmd - x_fb) + self.kvff * v_ff - v_meas;
            integral += self.ki_ts * ev;
            let f_cmd = self.kp * ev + integral + f_ff;
            for _ in 0..self.n_sub {
                let f_spring = self.stiffness * (x_m - x_t - offset) + self.damping * (v_m - v_t);
                force += (f_cmd - force) * self.current_alpha;
                v_m += (force - f_spring) * self.h_over_mm;
                v_t = (self.mt * v_t + self.h * (f_spring + (friction + slope * v_t)))
                    * self.inv_mt_plus_h_fv;
                x_m += self.h * v_m;
                x_t += self.h * v_t;
                velocities.push(v_t);
            }
        }
        [x_m, v_m, x_t, v_t, force, integral, x_m_tick]
    }

    /// The linear regime the state is in, or None (near rest or sticking, inside the backlash
    /// gap, near the force limit): the direction of slip (0 without dry friction) and the
    /// contact offset, with what [`Regime::admits`] needs to tell whether the regime holds
    /// through a velocity change `dv_margin` of the period.
    #[inline(always)]
    fn linear_regime(&self, x: &[f64; N_STATE]) -> Option<Regime> {
        if self.presliding.is_some() {
            return None; // the bristle has its own state
        }
        let [x_m, v_m, x_t, v_t, force, _, _] = *x;
        if force.abs() > 0.5 * self.force_limit {
            return None;
        }
        let d = x_m - x_t;
        let hb = self.half_backlash;
        let offset = if hb > 0.0 {
            // d ≠ 0 wherever `side` is used (|d| > hb below).
            let side = if d < 0.0 { -1.0 } else { 1.0 };
            let f_spring = self.stiffness * (d - side * hb) + self.damping * (v_m - v_t);
            // In contact, pushing, and not about to open the gap.
            if d.abs() <= hb || side * f_spring <= 0.0 {
                return None;
            }
            side * hb
        } else {
            0.0
        };
        if self.coulomb == 0.0 && self.static_friction == 0.0 {
            return Some(Regime::without_friction(offset));
        }
        // Slipping (the margins are checked by `admits`), friction at its bound against
        // the motion.
        if v_t == 0.0 {
            return None;
        }
        let f_spring = self.stiffness * (d - offset) + self.damping * (v_m - v_t);
        let side = if v_t < 0.0 { -1.0 } else { 1.0 }; // v_t ≠ 0 here
        let (bound, decay) = self.friction_bound_cached(v_t);
        Some(Regime {
            side,
            offset,
            dry: true,
            speed: v_t.abs(),
            push: side * (self.mt_over_h * v_t + f_spring),
            bound,
            decay,
            mt_over_h: self.mt_over_h,
        })
    }

    /// [`AxisServo::try_exact_period`] for an axis without dry friction and backlash: its
    /// only regime condition is the force within half its limit at both ends (the same
    /// decisions and the same arithmetic as the general path, without its friction terms).
    #[inline(always)]
    fn try_lti_period<K: ColumnProduct>(
        &mut self,
        k: K,
        s_old: f64,
        s_new: f64,
        f_ff: f64,
    ) -> bool {
        let limit = 0.5 * self.force_limit;
        if self.force.abs() > limit {
            return false;
        }
        let Some(map) = self.exact.as_deref().and_then(|e| e.maps[0].get()) else {
            return false;
        };
        let x = [
            self.x_m - s_old,
            self.v_m,
            self.x_t - s_old,
            self.v_t,
            self.force,
            self.integral,
            self.x_m_tick - s_old,
        ];
        let (y, finite) = map.apply_without_friction(k, &x, s_new - s_old, f_ff);
        if y[4].abs() > limit || !finite {
            return false;
        }
        self.x_m = y[0] + s_old;
        self.v_m = y[1];
        self.x_t = y[2] + s_old;
        self.v_t = y[3];
        self.force = y[4];
        self.integral = y[5];
        self.x_m_tick = y[6] + s_old;
        true
    }

    /// [`AxisServo::friction_bound`] through `bound_cache`, with the `exp(-(v/vs)²)` it
    /// took (see [`stribeck_bound_decay`]).
    #[inline(always)]
    fn friction_bound_cached(&self, v: f64) -> (f64, f64) {
        let (v_cached, g, decay) = self.bound_cache.get();
        if v_cached.to_bits() == v.to_bits() {
            return (g, decay);
        }
        let (g, decay) = stribeck_bound_decay(v, self.coulomb, self.static_friction, self.stribeck);
        self.bound_cache.set((v, g, decay));
        (g, decay)
    }

    /// One period by the exact map when the state is in a linear regime at both its ends and
    /// the friction's linearisation error is within tolerance ([`ExactMaps`]); false (state
    /// untouched) otherwise.
    #[inline(always)]
    fn try_exact_period<K: ColumnProduct>(
        &mut self,
        k: K,
        s_old: f64,
        s_new: f64,
        f_ff: f64,
    ) -> bool {
        let Some(exact) = self.exact.as_deref() else {
            return false;
        };
        if exact.lti {
            return self.try_lti_period(k, s_old, s_new, f_ff);
        }
        let x = [
            self.x_m - s_old,
            self.v_m,
            self.x_t - s_old,
            self.v_t,
            self.force,
            self.integral,
            self.x_m_tick - s_old,
        ];
        // Velocity may change by about what the command's velocity does over the period.
        let dv_guess = ((s_new - s_old) * self.inv_t_ipo - self.v_ff).abs();
        // The end-point check below asks for at least twice this margin at x: ask it now, so
        // that x needs no second check unless the period's own velocity change is larger.
        // The previous period's end check, when it took the map: the same state, so the
        // same regime (its spring force from the positions relative to the previous
        // setpoint, which can differ from these in the last bit).
        let regime = match self.carried_regime.take() {
            Some(regime) => regime,
            None => match self.linear_regime(&x) {
                Some(regime) => regime,
                None => return false,
            },
        };
        if !regime.admits(2.0 * dv_guess) {
            return false;
        }
        let v0 = x[3];
        // Friction at v0 and its slope there (0 outside a Stribeck zone), the grid slope.
        let (f0, slope, index) = if regime.side == 0.0 {
            (0.0, 0.0, 0)
        } else if exact.slope_step == 0.0 {
            (-regime.side * regime.bound, 0.0, 0)
        } else {
            let u = v0.abs() * exact.inv_stribeck;
            // The exp of the friction bound at v0 (0 beyond u² = 40, where the substep
            // model's g(v) is Fc exactly: see `stribeck_bound`).
            let slope = 2.0 * exact.delta_friction * u * exact.inv_stribeck * regime.decay;
            let index = round_index(slope * exact.inv_slope_step, SLOPE_STEPS);
            (-regime.side * regime.bound, slope, index)
        };
        let grid_slope = index as f64 * exact.slope_step;
        let map = exact.maps[index].get_or_init(|| self.period_map(grid_slope, true));
        let friction = f0 - grid_slope * v0;
        let input = map_input(&x, s_new - s_old, f_ff, friction, regime.offset);
        let (y, finite) = map.product_and_finite(k, &input);
        if !finite {
            return false; // the substeps find it too, and end_period reports it
        }
        let dv = 2.0 * (y[3] - x[3]).abs().max(dv_guess);
        if exact.slope_step > 0.0 && (v0.abs() - dv) * exact.inv_stribeck <= 40f64.sqrt() {
            // e_F = |c - cᵢ| Δv + ½ max|f''| Δv² within tolerance (ExactMaps).
            let within = |dv: f64| exact.friction_error_within(slope, grid_slope, v0, dv);
            // First with Δv bounded from the end points and the command; where that is not
            // enough (a command whose velocity jumps from period to period, such as the
            // rounded positions of a fine-segment file), with the substeps' own velocities.
            if !within(dv) && !within(map.largest_substep_velocity_change(&input)) {
                return false;
            }
        }
        if dv > 2.0 * dv_guess && !regime.admits(dv) {
            return false;
        }
        match self.linear_regime(&y) {
            Some(end) if end.same(&regime) && end.admits(dv) => self.carried_regime = Some(end),
            _ => return false,
        }
        self.x_m = y[0] + s_old;
        self.v_m = y[1];
        self.x_t = y[2] + s_old;
        self.v_t = y[3];
        self.force = y[4];
        self.integral = y[5];
        self.x_m_tick = y[6] + s_old;
        true
    }

    /// The lost motion this axis shows at a reversal (ISO 230-2 B and its parts), mm or deg.
    pub fn reversal_value(&self) -> ReversalValue {
        self.reversal
    }

    /// `map`'s first `C` columns with this servo's constants, for a lane servo.
    fn mapped_period<const C: usize>(&self, map: &PeriodMap) -> MappedPeriod<C> {
        MappedPeriod {
            cols: map.first_columns(),
            scale: self.scale,
            inv_scale: self.inv_scale,
            inv_t_ipo: self.inv_t_ipo,
            aff_mass: self.aff_mass,
            half_limit: 0.5 * self.force_limit,
            fe_limit: self.fe_limit,
        }
    }

    /// The linear twin's mapped period for a lane servo; None for any other servo (first
    /// order, dry friction, backlash, pre-sliding, no map), which steps on its own.
    pub(super) fn twin_period(&self) -> Option<TwinPeriod> {
        let exact = self.exact.as_deref().filter(|e| e.lti)?;
        let map = exact.maps[0].get()?;
        Some(self.mapped_period(map))
    }

    /// A nonlinear drive's mapped period at friction slope 0 (the map's grid slope index 0)
    /// for a lane servo; None for a drive without such a map (first order, pre-sliding, a
    /// linear twin, no map), which steps on its own. Builds that map where it was not yet
    /// (as the first period needing it would: the same map).
    pub(super) fn drive_period(&self) -> Option<DrivePeriod> {
        if self.presliding.is_some() {
            return None;
        }
        let exact = self.exact.as_deref().filter(|e| !e.lti)?;
        let grid_slope = 0.0 * exact.slope_step;
        let map = exact.maps[0].get_or_init(|| self.period_map(grid_slope, true));
        Some(DrivePeriod {
            map: self.mapped_period(map),
            stiffness: self.stiffness,
            damping: self.damping,
            half_backlash: self.half_backlash,
            coulomb: self.coulomb,
            static_friction: self.static_friction,
            stribeck: self.stribeck,
            mt_over_h: self.mt_over_h,
            slope_step: exact.slope_step,
            inv_slope_step: exact.inv_slope_step,
            delta_friction: exact.delta_friction,
            inv_stribeck: exact.inv_stribeck,
            tolerance: exact.tolerance,
        })
    }

    /// The columns of the period map of grid slope index `index` (`index · slope_step`,
    /// [`ExactMaps`]) for a lane servo, built where it was not yet as the first period
    /// needing it would build it (the same map); None for a drive without slope maps.
    pub(super) fn slope_columns(&self, index: usize) -> Option<[[f64; N_STATE]; N_INPUT]> {
        let exact = self.exact.as_deref().filter(|e| !e.lti)?;
        let grid_slope = index as f64 * exact.slope_step;
        let map = exact
            .maps
            .get(index)?
            .get_or_init(|| self.period_map(grid_slope, true));
        Some(map.first_columns())
    }

    /// Whether the friction error is within tolerance over the substeps' own velocity
    /// changes ([`PeriodMap::largest_substep_velocity_change`]) of the map of grid slope
    /// index `index` at `input`, as [`AxisServo::advance`]'s period asks where the bound
    /// from the end points is not enough; None without that map (not built).
    pub(super) fn within_by_substeps(
        &self,
        index: usize,
        input: &[f64; N_INPUT],
        (slope, grid_slope): (f64, f64),
    ) -> Option<bool> {
        let exact = self.exact.as_deref()?;
        let map = exact.maps.get(index)?.get()?;
        let dv = map.largest_substep_velocity_change(input);
        Some(exact.friction_error_within(slope, grid_slope, input[3], dv))
    }

    /// The constants of [`AxisServo::substep_period`] for a lane group that steps it in
    /// lanes ([`super::lane_drive`]); None for a drive whose substeps have their own state
    /// (pre-sliding) or that is not a cascade drive with period maps.
    pub(super) fn substep_constants(&self) -> Option<SubstepConstants> {
        if self.presliding.is_some() || self.exact.is_none() {
            return None;
        }
        Some(SubstepConstants {
            n_servo: self.n_servo,
            n_sub: self.n_sub,
            inv_t_servo: 1.0 / self.t_servo,
            fully_closed: self.fully_closed,
            kv: self.kv,
            kvff: self.kvff,
            kp: self.kp,
            ki_ts: self.ki_ts,
            force_limit: self.force_limit,
            current_alpha: self.current_alpha,
            h: self.h,
            h_over_mm: self.h_over_mm,
            mt: self.mt,
            inv_mt_plus_h_fv: self.inv_mt_plus_h_fv,
            mt_over_h: self.mt_over_h,
            stiffness: self.stiffness,
            damping: self.damping,
            half_backlash: self.half_backlash,
            fe_limit: self.fe_limit,
        })
    }

    /// Interpolation periods advanced by substeps so far (what [`AxisServo::period_counts`]
    /// gives second), for a lane group that steps some of them in lanes.
    pub(super) fn periods_substepped(&self) -> u64 {
        self.periods_substepped
    }

    /// Sets what [`AxisServo::periods_substepped`] gives.
    pub(super) fn set_periods_substepped(&mut self, n: u64) {
        self.periods_substepped = n;
    }

    /// The carried regime and the friction-bound cache, what [`AxisServo::advance`] carries
    /// beyond [`AxisServo::twin_state`].
    pub(super) fn regime_state(&self) -> (Option<Regime>, (f64, f64, f64)) {
        (self.carried_regime, self.bound_cache.get())
    }

    /// Sets what [`AxisServo::regime_state`] gives.
    pub(super) fn set_regime_state(&mut self, regime: Option<Regime>, cache: (f64, f64, f64)) {
        self.carried_regime = regime;
        self.bound_cache.set(cache);
    }

    /// The state [`AxisServo::advance_twin`] carries between periods.
    pub(super) fn twin_state(&self) -> TwinState {
        TwinState {
            setpoint: self.setpoint,
            v_ff: self.v_ff,
            x: [
                self.x_m,
                self.v_m,
                self.x_t,
                self.v_t,
                self.force,
                self.integral,
                self.x_m_tick,
            ],
            velocity_si: self.velocity_si,
            periods_exact: self.periods_exact,
        }
    }

    /// Sets the state of [`AxisServo::twin_state`] (a linear twin's: its carried regime and
    /// friction-bound cache are never read).
    pub(super) fn set_twin_state(&mut self, state: &TwinState) {
        self.setpoint = state.setpoint;
        self.v_ff = state.v_ff;
        [
            self.x_m,
            self.v_m,
            self.x_t,
            self.v_t,
            self.force,
            self.integral,
            self.x_m_tick,
        ] = state.x;
        self.velocity_si = state.velocity_si;
        self.periods_exact = state.periods_exact;
    }

    /// Advances one interpolation period towards `setpoint` (mm or deg), reached by the
    /// command at the end of the period; `time_s` is for error messages.
    pub fn step(&mut self, setpoint: f64, time_s: f64) -> Result<ServoState> {
        self.advance(setpoint, time_s)?;
        Ok(self.state())
    }

    /// The state at the end of the last period.
    pub fn state(&self) -> ServoState {
        ServoState {
            actual: self.actual(),
            following_error: self.following_error(),
            motor: self.x_m * self.inv_scale,
            velocity: self.velocity(),
            force: self.force,
        }
    }

    /// Table-side position at the end of the last period, mm or deg.
    #[inline]
    pub fn actual(&self) -> f64 {
        self.x_t * self.inv_scale
    }

    /// Setpoint minus actual at the end of the last period, mm or deg.
    #[inline]
    pub fn following_error(&self) -> f64 {
        (self.setpoint - self.x_t) * self.inv_scale
    }

    /// Table velocity at the end of the last period, mm/s or deg/s (first-order model: the
    /// mean over the period).
    #[inline]
    pub fn velocity(&self) -> f64 {
        self.velocity_si * self.inv_scale
    }

    /// [`AxisServo::step`] without forming its [`ServoState`] (read what is needed with
    /// [`AxisServo::actual`] and the like: each is a product).
    #[inline(always)]
    pub fn advance(&mut self, setpoint: f64, time_s: f64) -> Result<()> {
        self.advance_with(Portable, setpoint, time_s)
    }

    /// [`AxisServo::advance`] with the period map's product by `k` (the same result).
    #[inline(always)]
    pub(super) fn advance_with<K: ColumnProduct>(
        &mut self,
        k: K,
        setpoint: f64,
        time_s: f64,
    ) -> Result<()> {
        if !setpoint.is_finite() {
            return Err(self.diverged(time_s, format!("the setpoint is not finite ({setpoint})")));
        }
        let s_new = setpoint * self.scale;
        let s_old = self.setpoint;
        let v_ff = (s_new - s_old) * self.inv_t_ipo;
        let a_ff = (v_ff - self.v_ff) * self.inv_t_ipo;
        let x_t_old = self.x_t;
        let mapped = match self.model {
            Model::FirstOrder => {
                self.step_first_order(s_old, s_new, v_ff);
                false
            }
            Model::Cascade => self.step_cascade(k, s_old, s_new, v_ff, a_ff),
        };
        self.setpoint = s_new;
        self.v_ff = v_ff;
        self.end_period(s_new, x_t_old, time_s, mapped)
    }

    /// [`AxisServo::advance`] for a linear twin (no dry friction, backlash or pre-sliding,
    /// cascade model) with its period map inlined into the caller: the same arithmetic, the
    /// same state and the same checks as `advance`, which it falls back to (state untouched)
    /// wherever the map does not apply; any other axis goes to `advance` at once.
    #[inline(always)]
    pub fn advance_twin(&mut self, setpoint: f64, time_s: f64) -> Result<()> {
        self.advance_twin_with(Portable, setpoint, time_s)
    }

    /// [`AxisServo::advance_twin`] with the period map's product by `k` (the same result).
    #[inline(always)]
    pub(super) fn advance_twin_with<K: ColumnProduct>(
        &mut self,
        k: K,
        setpoint: f64,
        time_s: f64,
    ) -> Result<()> {
        let limit = 0.5 * self.force_limit;
        let map = match self.exact.as_deref() {
            Some(exact) if exact.lti && setpoint.is_finite() && self.force.abs() <= limit => {
                exact.maps[0].get()
            }
            _ => None,
        };
        let Some(map) = map else {
            return self.advance_with(k, setpoint, time_s);
        };
        let s_new = setpoint * self.scale;
        let s_old = self.setpoint;
        let v_ff = (s_new - s_old) * self.inv_t_ipo;
        let a_ff = (v_ff - self.v_ff) * self.inv_t_ipo;
        let f_ff = self.aff_mass * a_ff;
        let x = [
            self.x_m - s_old,
            self.v_m,
            self.x_t - s_old,
            self.v_t,
            self.force,
            self.integral,
            self.x_m_tick - s_old,
        ];
        let (y, finite) = map.apply_without_friction(k, &x, s_new - s_old, f_ff);
        if y[4].abs() > limit || !finite {
            return self.advance_with(k, setpoint, time_s);
        }
        let x_t_old = self.x_t;
        self.x_m = y[0] + s_old;
        self.v_m = y[1];
        self.x_t = y[2] + s_old;
        self.v_t = y[3];
        self.force = y[4];
        self.integral = y[5];
        self.x_m_tick = y[6] + s_old;
        self.periods_exact += 1;
        self.setpoint = s_new;
        self.v_ff = v_ff;
        self.end_period(s_new, x_t_old, time_s, true)
    }

    /// The divergence checks after a period and the velocity it leaves.
    #[inline(always)]
    /// `finite_checked`: the period's map already checked its result ([`all_finite`] on
    /// the values in registers, before storing them: reading them back from the state, two
    /// 8-byte stores as one 16-byte load, stalled store forwarding).
    fn end_period(
        &mut self,
        s_new: f64,
        x_t_old: f64,
        time_s: f64,
        finite_checked: bool,
    ) -> Result<()> {
        if !finite_checked
            && !all_finite(&[
                self.x_m,
                self.v_m,
                self.x_t,
                self.v_t,
                self.force,
                self.integral,
            ])
        {
            return Err(self.diverged(time_s, "the drive state is no longer finite".into()));
        }
        let fe = s_new - self.x_t;
        let fe_motor = s_new - self.x_m;
        if fe.abs() > self.fe_limit || fe_motor.abs() > self.fe_limit {
            return Err(self.following_error_exceeded(time_s, fe, fe_motor));
        }
        self.velocity_si = match self.model {
            Model::FirstOrder => (self.x_t - x_t_old) * self.inv_t_ipo,
            Model::Cascade => self.v_t,
        };
        Ok(())
    }

    #[cold]
    #[inline(never)]
    fn following_error_exceeded(&self, time_s: f64, fe: f64, fe_motor: f64) -> Error {
        {
            let unit = self.axis.unit();
            let worst = if fe.abs() >= fe_motor.abs() {
                fe
            } else {
                fe_motor
            };
            self.diverged(
                time_s,
                format!(
                    "following error {:.4} {unit} exceeds the limit {:.4} {unit}",
                    worst / self.scale,
                    self.fe_limit / self.scale
                ),
            )
        }
    }

    #[cold]
    #[inline(never)]
    fn diverged(&self, time_s: f64, reason: String) -> Error {
        Error::Diverged {
            axis: self.axis,
            time_s,
            reason,
        }
    }

    /// First-order model over one interpolation period. Per servo period the command is
    /// linear, `x_cmd' = v_ff`, so the motor error `e = x_cmd - x_m` obeys
    /// `e' = (1 - k_vff) v_ff - Kv e` and `e(T) = e_inf + (e(0) - e_inf) exp(-Kv T)` with
    /// `e_inf = (1 - k_vff) v_ff / Kv` exactly. The table follows through the play element.
    /// With a fully-closed loop and backlash the loop closes over the play, which is not
    /// linear: it is then integrated with explicit Euler substeps.
    fn step_first_order(&mut self, s_old: f64, s_new: f64, v_ff: f64) {
        if self.fully_closed && self.half_backlash > 0.0 {
            let steps = self.n_servo * self.n_sub;
            for i in 0..steps {
                let x_cmd = s_old + (s_new - s_old) * (i as f64 / steps as f64);
                let v = self.kv * (x_cmd - self.x_t) + self.kvff * v_ff;
                self.x_m += v * self.h;
                self.x_t = play(self.x_m, self.x_t, self.half_backlash);
            }
            return;
        }
        let e_inf = (1.0 - self.kvff) * v_ff / self.kv;
        for &fraction in &self.tick_fractions[1..] {
            let x_cmd = s_old + (s_new - s_old) * fraction;
            let e0 = x_cmd - v_ff * self.t_servo - self.x_m;
            let e1 = e_inf + (e0 - e_inf) * self.decay;
            self.x_m = x_cmd - e1;
            self.x_t = play(self.x_m, self.x_t, self.half_backlash);
        }
        self.v_m = v_ff;
    }

    /// Cascade model over one interpolation period: `n_servo` controller ticks, each followed
    /// by `n_sub` mechanics substeps under the held force command.
    #[inline(always)]
    /// True when the exact map took the period (its result checked finite).
    fn step_cascade<K: ColumnProduct>(
        &mut self,
        k: K,
        s_old: f64,
        s_new: f64,
        v_ff: f64,
        a_ff: f64,
    ) -> bool {
        let f_ff = self.aff_mass * a_ff;
        if self.try_exact_period(k, s_old, s_new, f_ff) {
            self.periods_exact += 1;
            return true;
        }
        self.substep_period(s_old, s_new, v_ff, f_ff);
        false
    }

    /// [`AxisServo::step_cascade`] by substeps, where the exact map does not apply (kept out
    /// of line: the map takes 95-100 % of the periods).
    #[inline(never)]
    fn substep_period(&mut self, s_old: f64, s_new: f64, v_ff: f64, f_ff: f64) {
        self.periods_substepped += 1;
        let inv_ts = 1.0 / self.t_servo;
        for j in 0..self.n_servo {
            // Controller, sampled at the start of the servo period.
            let x_cmd = s_old + (s_new - s_old) * self.tick_fractions[j];
            let x_fb = if self.fully_closed {
                self.x_t
            } else {
                self.x_m
            };
            let v_meas = (self.x_m - self.x_m_tick) * inv_ts;
            self.x_m_tick = self.x_m;
            let v_cmd = self.kv * (x_cmd - x_fb) + self.kvff * v_ff;
            let ev = v_cmd - v_meas;
            let integral = self.integral + self.ki_ts * ev;
            let f_unlimited = self.kp * ev + integral + f_ff;
            let f_cmd = f_unlimited.clamp(-self.force_limit, self.force_limit);
            // Anti-windup: do not integrate further into the force limit.
            if f_unlimited.abs() <= self.force_limit || (f_unlimited > 0.0) != (ev > 0.0) {
                self.integral = integral;
            }
            for _ in 0..self.n_sub {
                self.substep(f_cmd);
            }
        }
    }

    /// One semi-implicit Euler step of the current loop and the two masses.
    #[inline]
    fn substep(&mut self, f_cmd: f64) {
        let d = self.x_m - self.x_t;
        let dv = self.v_m - self.v_t;
        let hb = self.half_backlash;
        let f_spring = if hb > 0.0 {
            // A contact pushes but never pulls: the damper cannot make the force change sign.
            if d > hb {
                (self.stiffness * (d - hb) + self.damping * dv).max(0.0)
            } else if d < -hb {
                (self.stiffness * (d + hb) + self.damping * dv).min(0.0)
            } else {
                0.0
            }
        } else {
            self.stiffness * d + self.damping * dv
        };
        self.force += (f_cmd - self.force) * self.current_alpha;
        self.v_m += (self.force - f_spring) * self.h_over_mm;
        let f_friction = self.table_friction(f_spring);
        self.v_t = (self.mt * self.v_t + self.h * (f_spring + f_friction)) * self.inv_mt_plus_h_fv;
        self.x_m += self.h * self.v_m;
        self.x_t += self.h * self.v_t;
        if let Some(p) = self.presliding.as_mut() {
            p.advance(self.h * self.v_t, self.h);
        }
    }

    /// Dry friction on the table over the next substep, N or N m, given the spring force on
    /// it: the friction hook. Implicit (see the module docs): stick if the force needed to
    /// stop the table within this step is below the friction bound, else slip against the
    /// bound. A friction model with its own state (e.g. pre-sliding) goes here; the exact
    /// period map then applies only where this is the constant `-Fc sign(v_t)`
    /// ([`AxisServo::linear_regime`]).
    #[inline]
    fn table_friction(&self, f_spring: f64) -> f64 {
        if let Some(p) = &self.presliding {
            return p.force();
        }
        let bound = self.friction_bound(self.v_t);
        let f_stop = -(self.mt_over_h * self.v_t + f_spring);
        f_stop.clamp(-bound, bound)
    }

    /// Magnitude bound of dry friction at table velocity `v`:
    /// `g(v) = Fc + (Fs - Fc) exp(-(v/vs)^2)`, which is `Fs` at rest.
    #[inline]
    fn friction_bound(&self, v: f64) -> f64 {
        stribeck_bound(v, self.coulomb, self.static_friction, self.stribeck)
    }
}

/// The constants of one cascade servo's substep period ([`AxisServo::substep_period`],
/// [`AxisServo::substep`]) beyond those of its regime checks ([`DrivePeriod`]), SI: what a
/// lane group needs to step that period in lanes by the same operations.
#[derive(Clone, Copy, Debug)]
pub(super) struct SubstepConstants {
    /// Servo periods per interpolation period, mechanics substeps per servo period.
    pub n_servo: usize,
    pub n_sub: usize,
    /// `1 / T_servo`, 1/s.
    pub inv_t_servo: f64,
    pub fully_closed: bool,
    pub kv: f64,
    pub kvff: f64,
    pub kp: f64,
    pub ki_ts: f64,
    pub force_limit: f64,
    /// `1 - exp(-h/τ)`, `h`, `h / m_m`, `m_t`, `1 / (m_t + h Fv)`.
    pub current_alpha: f64,
    pub h: f64,
    pub h_over_mm: f64,
    pub mt: f64,
    pub inv_mt_plus_h_fv: f64,
    /// `m_t / h`, the spring's `k` and `c`, half the backlash and the following errors'
    /// limit.
    pub mt_over_h: f64,
    pub stiffness: f64,
    pub damping: f64,
    pub half_backlash: f64,
    pub fe_limit: f64,
}

/// `Fc + (Fs - Fc) exp(-(v/vs)^2)`; with `vs = 0`, `Fs` at rest and `Fc` in motion.
#[inline]
fn stribeck_bound(v: f64, fc: f64, fs: f64, vs: f64) -> f64 {
    stribeck_bound_decay(v, fc, fs, vs).0
}

/// [`stribeck_bound`] and the `exp(-(v/vs)²)` it took (1 at rest, 0 beyond the cut-off
/// `(v/vs)² > 40`, where the bound is `Fc` exactly; unused without a Stribeck zone).
#[inline]
pub(super) fn stribeck_bound_decay(v: f64, fc: f64, fs: f64, vs: f64) -> (f64, f64) {
    if fs == fc || v == 0.0 {
        return (fs, 1.0);
    }
    if vs <= 0.0 {
        return (fc, 0.0);
    }
    let u = v / vs;
    let u2 = u * u;
    if u2 > 40.0 {
        (fc, 0.0)
    } else {
        let decay = exp(-u2);
        (fc + (fs - fc) * decay, decay)
    }
}

/// Play (backlash) element: the table at `x_t` stays put until the motor at `x_m` pushes it
/// at either end of the gap of half-width `half`.
#[inline]
fn play(x_m: f64, x_t: f64, half: f64) -> f64 {
    x_t.clamp(x_m - half, x_m + half)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::drive::{DriveConfig, FrictionConfig, ServoConfig};

    /// `round_index` is `f64::round` clamped to `[0, max]`, halves away from zero.
    #[test]
    fn round_index_rounds_halves_up_and_clamps() {
        for k in -40..=700 {
            let x = k as f64 * 0.125;
            let expected = x.round().clamp(0.0, 64.0) as usize;
            assert_eq!(round_index(x, 64), expected, "x = {x}");
        }
        assert_eq!(round_index(0.5 - f64::EPSILON / 4.0, 64), 0);
        assert_eq!(round_index(f64::NAN, 64), 64);
        assert_eq!(round_index(f64::INFINITY, 64), 64);
        assert_eq!(round_index(f64::NEG_INFINITY, 64), 0);
        assert_eq!(round_index(-0.0, 64), 0);
    }

    #[test]
    fn dead_zone_play_and_stribeck_bound_follow_their_definitions() {
        assert_eq!(play(1.0, 0.0, 0.25), 0.75);
        assert_eq!(play(-1.0, 0.0, 0.25), -0.75);
        assert_eq!(play(0.1, 0.0, 0.25), 0.0);
        assert_eq!(stribeck_bound(0.0, 100.0, 130.0, 1e-3), 130.0);
        assert!(
            (stribeck_bound(1e-3, 100.0, 130.0, 1e-3) - (100.0 + 30.0 / std::f64::consts::E)).abs()
                < 1e-12
        );
        assert_eq!(stribeck_bound(1.0, 100.0, 130.0, 1e-3), 100.0);
        assert_eq!(stribeck_bound(1e-9, 100.0, 130.0, 0.0), 100.0);
        assert_eq!(stribeck_bound(0.0, 0.0, 0.0, 0.0), 0.0);
    }

    /// A table held by a spring force below Fs sticks exactly; above it, it breaks away.
    #[test]
    fn stiction_holds_below_the_static_limit_and_breaks_away_above() {
        let servo = ServoConfig {
            model: "cascade".into(),
            ..Default::default()
        };
        let drive = AxisDrive::resolve(
            Axis::X,
            &servo,
            &DriveConfig::default(),
            &FrictionConfig::default(),
        )
        .unwrap();
        let mut s = AxisServo::new(&drive, 1e-3, 0.0).unwrap();
        // Spring pre-loaded to 0.9 Fs = 175.5 N: d = 175.5 / 2e8 m. Motor held (force cancels).
        let fs = 150.0 * 1.3;
        for (load, moves) in [(0.9 * fs, false), (1.1 * fs, true)] {
            s.x_t = 0.0;
            s.v_t = 0.0;
            s.v_m = 0.0;
            s.x_m = load / s.stiffness;
            for _ in 0..10 {
                let x_m = s.x_m;
                s.force = load;
                s.substep(load);
                s.x_m = x_m;
                s.v_m = 0.0;
            }
            assert_eq!(s.x_t != 0.0, moves, "load {load} N");
        }
    }
}
