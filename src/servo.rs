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

use std::f64::consts::PI;
use std::path::Path;

use serde::Deserialize;

use crate::axis::Axis;
use crate::error::{Error, Result};
use crate::toml_input::value_error;

/// `[axes.X.servo]`: the controller — loops, feedforward, feedback, timing.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ServoConfig {
    /// "first-order" (P loop, ideal inner loop) or "cascade" (P/PI/current loop, two masses).
    pub model: String,
    /// Position-loop gain Kv, 1/s. Default 30.
    pub kv_per_s: f64,
    /// Velocity feedforward, fraction 0..1. Default 0.
    pub velocity_feedforward: f64,
    /// Acceleration feedforward, fraction 0..1 (cascade only). Default 0.
    pub acceleration_feedforward: f64,
    /// Position feedback: "semi-closed" (motor encoder) or "fully-closed" (table scale).
    pub feedback: String,
    /// Velocity-loop bandwidth f_v, Hz: `Kp = 2π f_v m_total`. Default 60.
    pub velocity_bandwidth_hz: f64,
    /// Velocity-loop integral time Ti, ms. Default 10.
    pub velocity_integral_time_ms: f64,
    /// Current-loop time constant τ, ms; 0 is an ideal current loop. Default 0.2.
    pub current_time_constant_ms: f64,
    /// Servo (position and velocity loop) period, ms; rounded so that a whole number of
    /// servo periods fits one interpolation period. Default 0.25.
    pub servo_period_ms: f64,
    /// Mechanics integration substeps per servo period. Default 2 (h = 125 us: ω h ≈ 0.14
    /// for the default drive; the cone trace moves by < 0.02 um against 4 substeps).
    pub substeps: u32,
    /// Following error beyond which a linear axis counts as diverged, mm. Default 50.
    pub following_error_limit_mm: Option<f64>,
    /// Following error beyond which a rotary axis counts as diverged, deg. Default 90.
    pub following_error_limit_deg: Option<f64>,
}

impl Default for ServoConfig {
    fn default() -> Self {
        ServoConfig {
            model: "first-order".into(),
            kv_per_s: 30.0,
            velocity_feedforward: 0.0,
            acceleration_feedforward: 0.0,
            feedback: "semi-closed".into(),
            velocity_bandwidth_hz: 60.0,
            velocity_integral_time_ms: 10.0,
            current_time_constant_ms: 0.2,
            servo_period_ms: 0.25,
            substeps: 2,
            following_error_limit_mm: None,
            following_error_limit_deg: None,
        }
    }
}

/// `[axes.X.drive]`: the mechanics between motor and table (cascade model; the first-order
/// model uses only the backlash). Linear axes take the `_mm`/`_kg`/`_n` keys, rotary axes the
/// `_deg`/`_kgm2`/`_nm` keys; a key of the other kind is an error. Unset keys take the
/// defaults of a mid-size machining centre: a preloaded ball-screw axis, or a direct-drive
/// rotary table.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DriveConfig {
    /// Backlash of a linear axis, mm. Default 0 (preloaded nut).
    pub backlash_mm: Option<f64>,
    /// Backlash of a rotary axis, deg. Default 0 (direct drive; worm tables: 0.001-0.006).
    pub backlash_deg: Option<f64>,
    /// Motor-side mass (rotor and screw inertia reflected through the lead), kg. Default 250.
    pub motor_mass_kg: Option<f64>,
    /// Motor-side inertia of a rotary axis, kg m^2. Default 3.
    pub motor_inertia_kgm2: Option<f64>,
    /// Table-side mass (table, saddle, workpiece), kg. Default 500.
    pub table_mass_kg: Option<f64>,
    /// Table-side inertia of a rotary axis, kg m^2. Default 5.
    pub table_inertia_kgm2: Option<f64>,
    /// Axial stiffness between motor and table of a linear axis, N/um. Default 200.
    pub stiffness_n_per_um: Option<f64>,
    /// Torsional stiffness of a rotary axis, N m/rad. Default 3e6.
    pub stiffness_nm_per_rad: Option<f64>,
    /// Damping ratio of the motor-table mode, `c = 2 ζ sqrt(k m_m m_t / (m_m + m_t))`.
    /// Default 0.05.
    pub damping_ratio: Option<f64>,
    /// Motor force limit of a linear axis, N. Default 20000.
    pub force_limit_n: Option<f64>,
    /// Motor torque limit of a rotary axis, N m. Default 1200.
    pub torque_limit_nm: Option<f64>,
}

/// `[axes.X.friction]`: friction on the table side (cascade model only).
/// `F = (Fc + (Fs - Fc) exp(-(v/vs)^2)) sign(v) + Fv v` with stiction `|F| <= Fs` at rest.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrictionConfig {
    /// Coulomb friction Fc of a linear axis, N; 0 removes dry friction. Default 150.
    pub coulomb_n: Option<f64>,
    /// Coulomb friction Fc of a rotary axis, N m; 0 removes dry friction. Default 15.
    pub coulomb_nm: Option<f64>,
    /// Static over Coulomb friction, Fs/Fc >= 1. Default 1.3.
    pub static_ratio: Option<f64>,
    /// Stribeck velocity vs of a linear axis, mm/s; 0 gives a plain stiction jump. Default 0.5.
    pub stribeck_velocity_mm_per_s: Option<f64>,
    /// Stribeck velocity vs of a rotary axis, deg/s. Default 0.1.
    pub stribeck_velocity_deg_per_s: Option<f64>,
    /// Viscous friction Fv of a linear axis, N per m/s. Default 1000.
    pub viscous_n_s_per_m: Option<f64>,
    /// Viscous friction Fv of a rotary axis, N m per rad/s. Default 5.
    pub viscous_nm_s_per_rad: Option<f64>,
}

/// The two servo models.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Model {
    FirstOrder,
    Cascade,
}

fn parse_model(name: &str) -> Option<Model> {
    match name {
        "first-order" => Some(Model::FirstOrder),
        "cascade" => Some(Model::Cascade),
        _ => None,
    }
}

fn parse_feedback(name: &str) -> Option<bool> {
    match name {
        "semi-closed" => Some(false),
        "fully-closed" => Some(true),
        _ => None,
    }
}

/// Picks the key of the axis's kind: `(key, value)` of the linear or the rotary variant.
fn pick(
    axis: Axis,
    linear: (&'static str, Option<f64>),
    rotary: (&'static str, Option<f64>),
    defaults: (f64, f64),
) -> (&'static str, f64) {
    if axis.is_rotary() {
        (rotary.0, rotary.1.unwrap_or(defaults.1))
    } else {
        (linear.0, linear.1.unwrap_or(defaults.0))
    }
}

/// Every parameter of one axis, resolved for its kind, in interface units as written
/// (mm, deg, N, N m, ...), each with the key it came from.
struct Resolved {
    model: Option<Model>,
    fully_closed: Option<bool>,
    fe_limit: (&'static str, f64),
    backlash: (&'static str, f64),
    motor_mass: (&'static str, f64),
    table_mass: (&'static str, f64),
    stiffness: (&'static str, f64),
    damping_ratio: f64,
    force_limit: (&'static str, f64),
    coulomb: (&'static str, f64),
    static_ratio: f64,
    stribeck: (&'static str, f64),
    viscous: (&'static str, f64),
}

impl Resolved {
    fn new(axis: Axis, s: &ServoConfig, d: &DriveConfig, f: &FrictionConfig) -> Resolved {
        Resolved {
            model: parse_model(&s.model),
            fully_closed: parse_feedback(&s.feedback),
            fe_limit: pick(
                axis,
                ("following_error_limit_mm", s.following_error_limit_mm),
                ("following_error_limit_deg", s.following_error_limit_deg),
                (50.0, 90.0),
            ),
            backlash: pick(
                axis,
                ("backlash_mm", d.backlash_mm),
                ("backlash_deg", d.backlash_deg),
                (0.0, 0.0),
            ),
            motor_mass: pick(
                axis,
                ("motor_mass_kg", d.motor_mass_kg),
                ("motor_inertia_kgm2", d.motor_inertia_kgm2),
                (250.0, 3.0),
            ),
            table_mass: pick(
                axis,
                ("table_mass_kg", d.table_mass_kg),
                ("table_inertia_kgm2", d.table_inertia_kgm2),
                (500.0, 5.0),
            ),
            stiffness: pick(
                axis,
                ("stiffness_n_per_um", d.stiffness_n_per_um),
                ("stiffness_nm_per_rad", d.stiffness_nm_per_rad),
                (200.0, 3.0e6),
            ),
            damping_ratio: d.damping_ratio.unwrap_or(0.05),
            force_limit: pick(
                axis,
                ("force_limit_n", d.force_limit_n),
                ("torque_limit_nm", d.torque_limit_nm),
                (20_000.0, 1200.0),
            ),
            coulomb: pick(
                axis,
                ("coulomb_n", f.coulomb_n),
                ("coulomb_nm", f.coulomb_nm),
                (150.0, 15.0),
            ),
            static_ratio: f.static_ratio.unwrap_or(1.3),
            stribeck: pick(
                axis,
                ("stribeck_velocity_mm_per_s", f.stribeck_velocity_mm_per_s),
                ("stribeck_velocity_deg_per_s", f.stribeck_velocity_deg_per_s),
                (0.5, 0.1),
            ),
            viscous: pick(
                axis,
                ("viscous_n_s_per_m", f.viscous_n_s_per_m),
                ("viscous_nm_s_per_rad", f.viscous_nm_s_per_rad),
                (1000.0, 5.0),
            ),
        }
    }

    /// The first problem found, as `(table, key, message)` with table "servo", "drive" or
    /// "friction".
    fn problem(
        axis: Axis,
        s: &ServoConfig,
        d: &DriveConfig,
        f: &FrictionConfig,
    ) -> Option<(&'static str, &'static str, String)> {
        let kind = if axis.is_rotary() { "rotary" } else { "linear" };
        let other = if axis.is_rotary() { "linear" } else { "rotary" };
        // Keys of the other kind of axis.
        let foreign: [(&str, &str, Option<f64>, &str); 9] = if axis.is_rotary() {
            [
                (
                    "servo",
                    "following_error_limit_mm",
                    s.following_error_limit_mm,
                    "following_error_limit_deg",
                ),
                ("drive", "backlash_mm", d.backlash_mm, "backlash_deg"),
                (
                    "drive",
                    "motor_mass_kg",
                    d.motor_mass_kg,
                    "motor_inertia_kgm2",
                ),
                (
                    "drive",
                    "table_mass_kg",
                    d.table_mass_kg,
                    "table_inertia_kgm2",
                ),
                (
                    "drive",
                    "stiffness_n_per_um",
                    d.stiffness_n_per_um,
                    "stiffness_nm_per_rad",
                ),
                ("drive", "force_limit_n", d.force_limit_n, "torque_limit_nm"),
                ("friction", "coulomb_n", f.coulomb_n, "coulomb_nm"),
                (
                    "friction",
                    "stribeck_velocity_mm_per_s",
                    f.stribeck_velocity_mm_per_s,
                    "stribeck_velocity_deg_per_s",
                ),
                (
                    "friction",
                    "viscous_n_s_per_m",
                    f.viscous_n_s_per_m,
                    "viscous_nm_s_per_rad",
                ),
            ]
        } else {
            [
                (
                    "servo",
                    "following_error_limit_deg",
                    s.following_error_limit_deg,
                    "following_error_limit_mm",
                ),
                ("drive", "backlash_deg", d.backlash_deg, "backlash_mm"),
                (
                    "drive",
                    "motor_inertia_kgm2",
                    d.motor_inertia_kgm2,
                    "motor_mass_kg",
                ),
                (
                    "drive",
                    "table_inertia_kgm2",
                    d.table_inertia_kgm2,
                    "table_mass_kg",
                ),
                (
                    "drive",
                    "stiffness_nm_per_rad",
                    d.stiffness_nm_per_rad,
                    "stiffness_n_per_um",
                ),
                (
                    "drive",
                    "torque_limit_nm",
                    d.torque_limit_nm,
                    "force_limit_n",
                ),
                ("friction", "coulomb_nm", f.coulomb_nm, "coulomb_n"),
                (
                    "friction",
                    "stribeck_velocity_deg_per_s",
                    f.stribeck_velocity_deg_per_s,
                    "stribeck_velocity_mm_per_s",
                ),
                (
                    "friction",
                    "viscous_nm_s_per_rad",
                    f.viscous_nm_s_per_rad,
                    "viscous_n_s_per_m",
                ),
            ]
        };
        for (table, key, value, instead) in foreign {
            if value.is_some() {
                return Some((
                    table,
                    key,
                    format!("is a {other}-axis key, but axis {axis} is {kind}; use `{instead}`"),
                ));
            }
        }

        let r = Resolved::new(axis, s, d, f);
        let unit = axis.unit();
        let finite_in = |v: f64, lo: f64, hi: f64| v.is_finite() && (lo..=hi).contains(&v);
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        let checks: [(bool, &'static str, &'static str, String); 21] = [
            (
                r.model.is_some(),
                "servo",
                "model",
                format!("must be \"first-order\" or \"cascade\", got {:?}", s.model),
            ),
            (
                r.fully_closed.is_some(),
                "servo",
                "feedback",
                format!(
                    "must be \"semi-closed\" or \"fully-closed\", got {:?}",
                    s.feedback
                ),
            ),
            (
                finite_in(s.kv_per_s, 1e-3, 1e4) && s.kv_per_s > 0.0,
                "servo",
                "kv_per_s",
                format!(
                    "must be a positive gain in 1/s (typically 20-60), got {}",
                    s.kv_per_s
                ),
            ),
            (
                finite_in(s.velocity_feedforward, 0.0, 1.0),
                "servo",
                "velocity_feedforward",
                format!(
                    "must be a fraction in 0..=1, got {}",
                    s.velocity_feedforward
                ),
            ),
            (
                finite_in(s.acceleration_feedforward, 0.0, 1.0),
                "servo",
                "acceleration_feedforward",
                format!(
                    "must be a fraction in 0..=1, got {}",
                    s.acceleration_feedforward
                ),
            ),
            (
                positive(s.velocity_bandwidth_hz) && s.velocity_bandwidth_hz <= 1e5,
                "servo",
                "velocity_bandwidth_hz",
                format!(
                    "must be a positive frequency in Hz (typically 50-300), got {}",
                    s.velocity_bandwidth_hz
                ),
            ),
            (
                positive(s.velocity_integral_time_ms),
                "servo",
                "velocity_integral_time_ms",
                format!(
                    "must be a positive time in ms (typically 2-20), got {}",
                    s.velocity_integral_time_ms
                ),
            ),
            (
                finite_in(s.current_time_constant_ms, 0.0, 100.0),
                "servo",
                "current_time_constant_ms",
                format!(
                    "must be a time in 0..=100 ms (typically 0.1-0.5), got {}",
                    s.current_time_constant_ms
                ),
            ),
            (
                positive(s.servo_period_ms) && s.servo_period_ms <= 100.0,
                "servo",
                "servo_period_ms",
                format!(
                    "must be a period in (0, 100] ms (typically 0.125-1), got {}",
                    s.servo_period_ms
                ),
            ),
            (
                (1..=1000).contains(&s.substeps),
                "servo",
                "substeps",
                format!("must be a whole number in 1..=1000, got {}", s.substeps),
            ),
            (
                positive(r.fe_limit.1),
                "servo",
                r.fe_limit.0,
                format!("must be a positive distance ({unit}), got {}", r.fe_limit.1),
            ),
            (
                non_negative(r.backlash.1),
                "drive",
                r.backlash.0,
                format!("must be >= 0 ({unit}), got {}", r.backlash.1),
            ),
            (
                positive(r.motor_mass.1),
                "drive",
                r.motor_mass.0,
                format!("must be positive, got {}", r.motor_mass.1),
            ),
            (
                positive(r.table_mass.1),
                "drive",
                r.table_mass.0,
                format!("must be positive, got {}", r.table_mass.1),
            ),
            (
                positive(r.stiffness.1),
                "drive",
                r.stiffness.0,
                format!("must be positive, got {}", r.stiffness.1),
            ),
            (
                finite_in(r.damping_ratio, 0.0, 10.0),
                "drive",
                "damping_ratio",
                format!(
                    "must be in 0..=10 (typically 0.02-0.1), got {}",
                    r.damping_ratio
                ),
            ),
            (
                positive(r.force_limit.1),
                "drive",
                r.force_limit.0,
                format!("must be positive, got {}", r.force_limit.1),
            ),
            (
                non_negative(r.coulomb.1),
                "friction",
                r.coulomb.0,
                format!("must be >= 0, got {}", r.coulomb.1),
            ),
            (
                finite_in(r.static_ratio, 1.0, 100.0),
                "friction",
                "static_ratio",
                format!(
                    "must be Fs/Fc >= 1 (typically 1.1-1.5), got {}",
                    r.static_ratio
                ),
            ),
            (
                non_negative(r.stribeck.1),
                "friction",
                r.stribeck.0,
                format!("must be >= 0, got {}", r.stribeck.1),
            ),
            (
                non_negative(r.viscous.1),
                "friction",
                r.viscous.0,
                format!("must be >= 0, got {}", r.viscous.1),
            ),
        ];
        checks
            .into_iter()
            .find(|c| !c.0)
            .map(|(_, table, key, message)| (table, key, message))
    }
}

/// Checks the drive parameters of one axis; errors name the key in `[section.servo]`,
/// `[section.drive]` or `[section.friction]` and point at its line.
pub fn validate(
    path: &Path,
    text: &str,
    section: &str,
    axis: Axis,
    servo: &ServoConfig,
    drive: &DriveConfig,
    friction: &FrictionConfig,
) -> Result<()> {
    match Resolved::problem(axis, servo, drive, friction) {
        None => Ok(()),
        Some((table, key, message)) => Err(value_error(
            path,
            text,
            &format!("{section}.{table}"),
            key,
            message,
        )),
    }
}

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
    /// Inverse of the interpolation period, 1/s.
    inv_t_ipo: f64,
    /// Servo periods per interpolation period, and the servo period, s.
    n_servo: usize,
    t_servo: f64,
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
}

impl AxisServo {
    /// `axis.is_rotary()` selects deg/rad and the `*_deg`/`*_nm` keys. Starts at rest at
    /// `initial_position` (mm or deg), the backlash gap centred.
    pub fn new(
        axis: Axis,
        servo: &ServoConfig,
        drive: &DriveConfig,
        friction: &FrictionConfig,
        interpolation_period_s: f64,
        initial_position: f64,
    ) -> Result<AxisServo> {
        let where_ = format!("[axes.{axis}]");
        if let Some((table, key, message)) = Resolved::problem(axis, servo, drive, friction) {
            return Err(Error::invalid(
                Path::new(&where_),
                format!("`{table}.{key}`: {message}"),
            ));
        }
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
        let r = Resolved::new(axis, servo, drive, friction);
        let scale = if axis.is_rotary() { PI / 180.0 } else { 1e-3 };
        let t_ipo = interpolation_period_s;
        let n_servo = ((t_ipo / (servo.servo_period_ms * 1e-3)).round() as usize).max(1);
        let t_servo = t_ipo / n_servo as f64;
        let n_sub = servo.substeps as usize;
        let h = t_servo / n_sub as f64;
        let mm = r.motor_mass.1;
        let mt = r.table_mass.1;
        let m_total = mm + mt;
        // N/um -> N/m for linear axes; N m/rad as is for rotary ones.
        let stiffness = if axis.is_rotary() {
            r.stiffness.1
        } else {
            r.stiffness.1 * 1e6
        };
        let damping = 2.0 * r.damping_ratio * (stiffness * mm * mt / m_total).sqrt();
        let tau = servo.current_time_constant_ms * 1e-3;
        let viscous = r.viscous.1;
        let kp = 2.0 * PI * servo.velocity_bandwidth_hz * m_total;
        let state = initial_position * scale;
        Ok(AxisServo {
            axis,
            model: r.model.unwrap_or(Model::Cascade),
            fully_closed: r.fully_closed.unwrap_or(false),
            scale,
            inv_t_ipo: 1.0 / t_ipo,
            n_servo,
            t_servo,
            n_sub,
            h,
            kv: servo.kv_per_s,
            kvff: servo.velocity_feedforward,
            aff_mass: servo.acceleration_feedforward * m_total,
            kp,
            ki_ts: kp * t_servo / (servo.velocity_integral_time_ms * 1e-3),
            current_alpha: if tau > 0.0 { -(-h / tau).exp_m1() } else { 1.0 },
            force_limit: r.force_limit.1,
            h_over_mm: h / mm,
            mt_over_h: mt / h,
            inv_mt_plus_h_fv: 1.0 / (mt + h * viscous),
            mt,
            stiffness,
            damping,
            half_backlash: 0.5 * r.backlash.1 * scale,
            coulomb: r.coulomb.1,
            static_friction: r.coulomb.1 * r.static_ratio,
            stribeck: r.stribeck.1 * scale,
            decay: (-servo.kv_per_s * t_servo).exp(),
            fe_limit: r.fe_limit.1 * scale,
            setpoint: state,
            v_ff: 0.0,
            x_m: state,
            v_m: 0.0,
            x_t: state,
            v_t: 0.0,
            force: 0.0,
            integral: 0.0,
            x_m_tick: state,
        })
    }

    /// Advances one interpolation period towards `setpoint` (mm or deg), reached by the
    /// command at the end of the period; `time_s` is for error messages.
    pub fn step(&mut self, setpoint: f64, time_s: f64) -> Result<ServoState> {
        if !setpoint.is_finite() {
            return Err(self.diverged(time_s, format!("the setpoint is not finite ({setpoint})")));
        }
        let s_new = setpoint * self.scale;
        let s_old = self.setpoint;
        let v_ff = (s_new - s_old) * self.inv_t_ipo;
        let a_ff = (v_ff - self.v_ff) * self.inv_t_ipo;
        let x_t_old = self.x_t;
        match self.model {
            Model::FirstOrder => self.step_first_order(s_old, s_new, v_ff),
            Model::Cascade => self.step_cascade(s_old, s_new, v_ff, a_ff),
        }
        self.setpoint = s_new;
        self.v_ff = v_ff;

        let finite = [
            self.x_m,
            self.v_m,
            self.x_t,
            self.v_t,
            self.force,
            self.integral,
        ]
        .iter()
        .all(|v| v.is_finite());
        if !finite {
            return Err(self.diverged(time_s, "the drive state is no longer finite".into()));
        }
        let fe = s_new - self.x_t;
        let fe_motor = s_new - self.x_m;
        if fe.abs() > self.fe_limit || fe_motor.abs() > self.fe_limit {
            let unit = self.axis.unit();
            let worst = if fe.abs() >= fe_motor.abs() {
                fe
            } else {
                fe_motor
            };
            return Err(self.diverged(
                time_s,
                format!(
                    "following error {:.4} {unit} exceeds the limit {:.4} {unit}",
                    worst / self.scale,
                    self.fe_limit / self.scale
                ),
            ));
        }
        let velocity = match self.model {
            Model::FirstOrder => (self.x_t - x_t_old) * self.inv_t_ipo,
            Model::Cascade => self.v_t,
        };
        Ok(ServoState {
            actual: self.x_t / self.scale,
            following_error: fe / self.scale,
            motor: self.x_m / self.scale,
            velocity: velocity / self.scale,
            force: self.force,
        })
    }

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
        let n = self.n_servo as f64;
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
        for j in 1..=self.n_servo {
            let x_cmd = s_old + (s_new - s_old) * (j as f64 / n);
            let e0 = x_cmd - v_ff * self.t_servo - self.x_m;
            let e1 = e_inf + (e0 - e_inf) * self.decay;
            self.x_m = x_cmd - e1;
            self.x_t = play(self.x_m, self.x_t, self.half_backlash);
        }
        self.v_m = v_ff;
    }

    /// Cascade model over one interpolation period: `n_servo` controller ticks, each followed
    /// by `n_sub` mechanics substeps under the held force command.
    fn step_cascade(&mut self, s_old: f64, s_new: f64, v_ff: f64, a_ff: f64) {
        let n = self.n_servo as f64;
        let inv_ts = 1.0 / self.t_servo;
        let f_ff = self.aff_mass * a_ff;
        for j in 0..self.n_servo {
            // Controller, sampled at the start of the servo period.
            let x_cmd = s_old + (s_new - s_old) * (j as f64 / n);
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
        // Implicit friction (see the module docs): stick if the force needed to stop the
        // table within this step is below the friction bound, else slip against the bound.
        let bound = self.friction_bound(self.v_t);
        let f_stop = -(self.mt_over_h * self.v_t + f_spring);
        let f_friction = f_stop.clamp(-bound, bound);
        self.v_t = (self.mt * self.v_t + self.h * (f_spring + f_friction)) * self.inv_mt_plus_h_fv;
        self.x_m += self.h * self.v_m;
        self.x_t += self.h * self.v_t;
    }

    /// Magnitude bound of dry friction at table velocity `v`:
    /// `g(v) = Fc + (Fs - Fc) exp(-(v/vs)^2)`, which is `Fs` at rest.
    #[inline]
    fn friction_bound(&self, v: f64) -> f64 {
        stribeck_bound(v, self.coulomb, self.static_friction, self.stribeck)
    }
}

/// `Fc + (Fs - Fc) exp(-(v/vs)^2)`; with `vs = 0`, `Fs` at rest and `Fc` in motion.
#[inline]
fn stribeck_bound(v: f64, fc: f64, fs: f64, vs: f64) -> f64 {
    if fs == fc || v == 0.0 {
        return fs;
    }
    if vs <= 0.0 {
        return fc;
    }
    let u = v / vs;
    let u2 = u * u;
    if u2 > 40.0 {
        fc
    } else {
        fc + (fs - fc) * (-u2).exp()
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

    #[derive(Deserialize)]
    struct Axes {
        axes: std::collections::BTreeMap<String, Sections>,
    }
    #[derive(Deserialize)]
    struct Sections {
        #[serde(default)]
        servo: ServoConfig,
        #[serde(default)]
        drive: DriveConfig,
        #[serde(default)]
        friction: FrictionConfig,
    }

    fn check(axis: Axis, text: &str) -> Result<()> {
        let parsed: Axes = toml::from_str(text).expect("test TOML parses");
        let s = &parsed.axes[&axis.to_string()];
        validate(
            Path::new("m.toml"),
            text,
            &format!("axes.{axis}"),
            axis,
            &s.servo,
            &s.drive,
            &s.friction,
        )
    }

    fn message(e: Error) -> String {
        match e {
            Error::AtSource { line, message, .. } => format!("{line}: {message}"),
            other => other.to_string(),
        }
    }

    #[test]
    fn defaults_are_valid_for_linear_and_rotary_axes() {
        for axis in Axis::ALL {
            validate(
                Path::new("m.toml"),
                "",
                "axes.X",
                axis,
                &ServoConfig::default(),
                &DriveConfig::default(),
                &FrictionConfig::default(),
            )
            .unwrap();
        }
    }

    #[test]
    fn a_bad_value_points_at_its_line() {
        let text = "[axes.X.servo]\nmodel = \"cascade\"\nkv_per_s = -3\n";
        let m = message(check(Axis::X, text).unwrap_err());
        assert!(
            m.starts_with("3: `axes.X.servo.kv_per_s`: must be a positive gain"),
            "{m}"
        );
        let text = "[axes.X.servo]\nmodel = \"pid\"\n";
        assert!(
            message(check(Axis::X, text).unwrap_err()).contains("\"first-order\" or \"cascade\"")
        );
        let text = "[axes.Y.servo]\nvelocity_feedforward = 1.5\n";
        assert!(message(check(Axis::Y, text).unwrap_err()).contains("fraction in 0..=1"));
        let text = "[axes.Y.friction]\nstatic_ratio = 0.8\n";
        assert!(message(check(Axis::Y, text).unwrap_err())
            .starts_with("2: `axes.Y.friction.static_ratio`"));
        let text = "[axes.Y.drive]\ntable_mass_kg = 0\n";
        assert!(message(check(Axis::Y, text).unwrap_err())
            .starts_with("2: `axes.Y.drive.table_mass_kg`"));
    }

    #[test]
    fn a_key_of_the_other_kind_of_axis_is_an_error() {
        let m = message(check(Axis::C, "[axes.C.drive]\nbacklash_mm = 0.01\n").unwrap_err());
        assert!(
            m.contains("`axes.C.drive.backlash_mm`: is a linear-axis key")
                && m.contains("use `backlash_deg`"),
            "{m}"
        );
        let m = message(check(Axis::X, "[axes.X.drive]\nbacklash_deg = 0.01\n").unwrap_err());
        assert!(m.contains("use `backlash_mm`"), "{m}");
        let m = message(check(Axis::A, "[axes.A.friction]\ncoulomb_n = 10\n").unwrap_err());
        assert!(m.contains("use `coulomb_nm`"), "{m}");
        check(
            Axis::A,
            "[axes.A.friction]\ncoulomb_nm = 10\n[axes.A.drive]\nbacklash_deg = 0.003\n",
        )
        .unwrap();
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
        let mut s = AxisServo::new(
            Axis::X,
            &servo,
            &DriveConfig::default(),
            &FrictionConfig::default(),
            1e-3,
            0.0,
        )
        .unwrap();
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

    /// The machine loader calls [`validate`], so a bad drive key in a machine file is
    /// reported at its line.
    #[test]
    fn machine_files_report_drive_errors_at_their_line() {
        let axis = |name: &str, extra: &str| {
            format!("[axes.{name}]\nmin = -100\nmax = 100\nmax_velocity = 10000\nmax_acceleration = 1000\nmax_jerk = 10000\n{extra}")
        };
        let head = "name = \"m\"\nkinematics = \"xyz\"\n";
        let text = format!(
            "{head}{}{}{}",
            axis("X", "[axes.X.servo]\nmodel = \"cascade\"\n"),
            axis("Y", ""),
            axis("Z", "[axes.Z.drive]\nbacklash_deg = 0.1\n")
        );
        let e = crate::machine::Machine::from_toml(Path::new("m.toml"), &text, None).unwrap_err();
        let m = message(e);
        assert!(
            m.starts_with("24: `axes.Z.drive.backlash_deg`: is a rotary-axis key"),
            "{m}"
        );
    }
}

impl DriveConfig {
    /// The same drive with the backlash closed: what the drive would do if it were linear.
    pub fn without_backlash(&self, axis: Axis) -> DriveConfig {
        let mut d = self.clone();
        if axis.is_rotary() {
            d.backlash_deg = Some(0.0);
        } else {
            d.backlash_mm = Some(0.0);
        }
        d
    }

    /// Backlash, mm or deg, with the default for the axis's kind (0).
    pub fn backlash(&self, axis: Axis) -> f64 {
        if axis.is_rotary() {
            self.backlash_deg
        } else {
            self.backlash_mm
        }
        .unwrap_or(0.0)
    }
}

impl FrictionConfig {
    /// The same friction without its dry part (Coulomb, static, Stribeck): viscous only,
    /// which is linear in velocity.
    pub fn viscous_only(&self, axis: Axis) -> FrictionConfig {
        let mut f = self.clone();
        if axis.is_rotary() {
            f.coulomb_nm = Some(0.0);
        } else {
            f.coulomb_n = Some(0.0);
        }
        f
    }
}
