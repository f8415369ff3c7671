//! Drive configuration: `[axes.X.servo]`, `[axes.X.drive]` and `[axes.X.friction]` of a
//! machine file, with the defaults of a mid-size machining centre, validated and resolved per
//! axis kind into one [`AxisDrive`] in SI units. The models that run it are in `crate::drive`;
//! nothing else reads the three tables' keys.

use std::f64::consts::PI;
use std::path::Path;

use serde::Deserialize;

use crate::error::Result;
use crate::input::toml_text::value_error;
use crate::Axis;

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
    /// Pre-sliding displacement δ = Fc/σ0 of a linear axis, um (typically 1-5): the elastic
    /// travel at which the guides' and screw's bristles carry Fc. Set, it replaces the
    /// Coulomb/stiction law by the Dahl bristle model (`crate::drive::presliding`).
    /// Default 0 (off).
    pub presliding_um: Option<f64>,
    /// Pre-sliding angle δ of a rotary axis, deg (typically 0.0003-0.001). Default 0 (off).
    pub presliding_deg: Option<f64>,
    /// Damping ratio of the bristle on the table mass, `σ1 = 2 ζ sqrt(σ0 m_t)`. Default 1.
    pub presliding_damping_ratio: Option<f64>,
}

/// The two servo models.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
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

/// Every parameter of one axis, picked for its kind with its default, in the units of the
/// keys (mm, deg, um, N/um, ...), each with the key it came from: what the checks name.
struct Written {
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
    /// Pre-sliding displacement δ, um or deg (0: off).
    presliding: (&'static str, f64),
    presliding_damping_ratio: f64,
}

impl Written {
    fn new(axis: Axis, s: &ServoConfig, d: &DriveConfig, f: &FrictionConfig) -> Written {
        let picked = by_kind(s, d, f)
            .map(|(_, linear, rotary, defaults)| pick(axis, linear, rotary, defaults));
        let [fe_limit, backlash, motor_mass, table_mass, stiffness, force_limit, coulomb, stribeck, viscous, presliding] =
            picked;
        Written {
            model: parse_model(&s.model),
            fully_closed: parse_feedback(&s.feedback),
            fe_limit,
            backlash,
            motor_mass,
            table_mass,
            stiffness,
            damping_ratio: d.damping_ratio.unwrap_or(0.05),
            force_limit,
            coulomb,
            static_ratio: f.static_ratio.unwrap_or(1.3),
            stribeck,
            viscous,
            presliding,
            presliding_damping_ratio: f.presliding_damping_ratio.unwrap_or(1.0),
        }
    }

    /// The first problem found, as `(table, key, message)` with table "servo", "drive" or
    /// "friction".
    fn problem(
        axis: Axis,
        s: &ServoConfig,
        d: &DriveConfig,
        f: &FrictionConfig,
    ) -> Option<DriveProblem> {
        foreign_key(axis, s, d, f)
            .and_then(|()| Written::new(axis, s, d, f).check(axis, s))
            .err()
    }

    /// Checks every value in turn (the order of the keys in docs/servo.md): the first out of
    /// its range is the problem; its message is written only then (a study validates every
    /// point).
    fn check(&self, axis: Axis, s: &ServoConfig) -> std::result::Result<(), DriveProblem> {
        let unit = axis.unit();
        let finite_in = |v: f64, lo: f64, hi: f64| v.is_finite() && (lo..=hi).contains(&v);
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        require(self.model.is_some(), "servo", "model", || {
            format!("must be \"first-order\" or \"cascade\", got {:?}", s.model)
        })?;
        require(self.fully_closed.is_some(), "servo", "feedback", || {
            format!(
                "must be \"semi-closed\" or \"fully-closed\", got {:?}",
                s.feedback
            )
        })?;
        check_kv(s.kv_per_s)?;
        for (key, v) in [
            ("velocity_feedforward", s.velocity_feedforward),
            ("acceleration_feedforward", s.acceleration_feedforward),
        ] {
            require(finite_in(v, 0.0, 1.0), "servo", key, || {
                format!("must be a fraction in 0..=1, got {v}")
            })?;
        }
        let hz = s.velocity_bandwidth_hz;
        require(
            positive(hz) && hz <= 1e5,
            "servo",
            "velocity_bandwidth_hz",
            || format!("must be a positive frequency in Hz (typically 50-300), got {hz}"),
        )?;
        let ti = s.velocity_integral_time_ms;
        require(positive(ti), "servo", "velocity_integral_time_ms", || {
            format!("must be a positive time in ms (typically 2-20), got {ti}")
        })?;
        let tc = s.current_time_constant_ms;
        require(
            finite_in(tc, 0.0, 100.0),
            "servo",
            "current_time_constant_ms",
            || format!("must be a time in 0..=100 ms (typically 0.1-0.5), got {tc}"),
        )?;
        let period = s.servo_period_ms;
        require(
            positive(period) && period <= 100.0,
            "servo",
            "servo_period_ms",
            || format!("must be a period in (0, 100] ms (typically 0.125-1), got {period}"),
        )?;
        require(
            (1..=1000).contains(&s.substeps),
            "servo",
            "substeps",
            || format!("must be a whole number in 1..=1000, got {}", s.substeps),
        )?;
        let (key, v) = self.fe_limit;
        require(positive(v), "servo", key, || {
            format!("must be a positive distance ({unit}), got {v}")
        })?;
        check_backlash(axis, self.backlash.1)?;
        for (key, v) in [self.motor_mass, self.table_mass, self.stiffness] {
            require(positive(v), "drive", key, || {
                format!("must be positive, got {v}")
            })?;
        }
        let zeta = self.damping_ratio;
        require(finite_in(zeta, 0.0, 10.0), "drive", "damping_ratio", || {
            format!("must be in 0..=10 (typically 0.02-0.1), got {zeta}")
        })?;
        let (key, v) = self.force_limit;
        require(positive(v), "drive", key, || {
            format!("must be positive, got {v}")
        })?;
        let (key, v) = self.coulomb;
        require(non_negative(v), "friction", key, || {
            format!("must be >= 0, got {v}")
        })?;
        let ratio = self.static_ratio;
        require(
            finite_in(ratio, 1.0, 100.0),
            "friction",
            "static_ratio",
            || format!("must be Fs/Fc >= 1 (typically 1.1-1.5), got {ratio}"),
        )?;
        for (key, v) in [self.stribeck, self.viscous] {
            require(non_negative(v), "friction", key, || {
                format!("must be >= 0, got {v}")
            })?;
        }
        let (key, v) = self.presliding;
        let (most, in_unit, typical) = if axis.is_rotary() {
            (1.0, "deg", "0.0003-0.001")
        } else {
            (1000.0, "um", "1-5")
        };
        require(finite_in(v, 0.0, most), "friction", key, || {
            format!(
                "must be a displacement >= 0 ({in_unit}; 0 is off, typically {typical}), got {v}"
            )
        })?;
        let zeta = self.presliding_damping_ratio;
        require(
            finite_in(zeta, 0.0, 10.0),
            "friction",
            "presliding_damping_ratio",
            || format!("must be in 0..=10 (typically 0.5-1), got {zeta}"),
        )
    }
}

/// The position-loop gain `kv_per_s`, 1/s: positive, at most 10⁴.
fn check_kv(kv: f64) -> std::result::Result<(), DriveProblem> {
    require(
        kv.is_finite() && (1e-3..=1e4).contains(&kv) && kv > 0.0,
        "servo",
        "kv_per_s",
        || format!("must be a positive gain in 1/s (typically 20-60), got {kv}"),
    )
}

/// The backlash of `axis` (`backlash_mm` or `backlash_deg`), mm or deg: finite, >= 0.
fn check_backlash(axis: Axis, v: f64) -> std::result::Result<(), DriveProblem> {
    let key = if axis.is_rotary() {
        "backlash_deg"
    } else {
        "backlash_mm"
    };
    require(v.is_finite() && v >= 0.0, "drive", key, || {
        format!("must be >= 0 ({}), got {v}", axis.unit())
    })
}

/// `Err` with the problem of `table`.`key` unless `ok`; the message is written only then.
fn require(
    ok: bool,
    table: &'static str,
    key: &'static str,
    message: impl FnOnce() -> String,
) -> std::result::Result<(), DriveProblem> {
    if ok {
        return Ok(());
    }
    Err(DriveProblem {
        table,
        key,
        message: message(),
    })
}

/// A setting with a key for each kind of axis: its table, the linear key and value, the
/// rotary key and value, and the defaults (linear, rotary).
type ByKind = (
    &'static str,
    (&'static str, Option<f64>),
    (&'static str, Option<f64>),
    (f64, f64),
);

/// The settings keyed by the kind of axis, as written (the fields of [`Written`] that carry
/// their key, in its order).
fn by_kind(s: &ServoConfig, d: &DriveConfig, f: &FrictionConfig) -> [ByKind; 10] {
    [
        (
            "servo",
            ("following_error_limit_mm", s.following_error_limit_mm),
            ("following_error_limit_deg", s.following_error_limit_deg),
            (50.0, 90.0),
        ),
        (
            "drive",
            ("backlash_mm", d.backlash_mm),
            ("backlash_deg", d.backlash_deg),
            (0.0, 0.0),
        ),
        (
            "drive",
            ("motor_mass_kg", d.motor_mass_kg),
            ("motor_inertia_kgm2", d.motor_inertia_kgm2),
            (250.0, 3.0),
        ),
        (
            "drive",
            ("table_mass_kg", d.table_mass_kg),
            ("table_inertia_kgm2", d.table_inertia_kgm2),
            (500.0, 5.0),
        ),
        (
            "drive",
            ("stiffness_n_per_um", d.stiffness_n_per_um),
            ("stiffness_nm_per_rad", d.stiffness_nm_per_rad),
            (200.0, 3.0e6),
        ),
        (
            "drive",
            ("force_limit_n", d.force_limit_n),
            ("torque_limit_nm", d.torque_limit_nm),
            (20_000.0, 1200.0),
        ),
        (
            "friction",
            ("coulomb_n", f.coulomb_n),
            ("coulomb_nm", f.coulomb_nm),
            (150.0, 15.0),
        ),
        (
            "friction",
            ("stribeck_velocity_mm_per_s", f.stribeck_velocity_mm_per_s),
            ("stribeck_velocity_deg_per_s", f.stribeck_velocity_deg_per_s),
            (0.5, 0.1),
        ),
        (
            "friction",
            ("viscous_n_s_per_m", f.viscous_n_s_per_m),
            ("viscous_nm_s_per_rad", f.viscous_nm_s_per_rad),
            (1000.0, 5.0),
        ),
        (
            "friction",
            ("presliding_um", f.presliding_um),
            ("presliding_deg", f.presliding_deg),
            (0.0, 0.0),
        ),
    ]
}

/// A key of the other kind of axis than `axis` (`backlash_mm` on a rotary axis), named with
/// the key to use instead.
fn foreign_key(
    axis: Axis,
    s: &ServoConfig,
    d: &DriveConfig,
    f: &FrictionConfig,
) -> std::result::Result<(), DriveProblem> {
    let (kind, other) = if axis.is_rotary() {
        ("rotary", "linear")
    } else {
        ("linear", "rotary")
    };
    for (table, linear, rotary, _) in by_kind(s, d, f) {
        let ((key, value), instead) = if axis.is_rotary() {
            (linear, rotary.0)
        } else {
            (rotary, linear.0)
        };
        require(value.is_none(), table, key, || {
            format!("is a {other}-axis key, but axis {axis} is {kind}; use `{instead}`")
        })?;
    }
    Ok(())
}

/// A drive setting that is not valid: its table ("servo", "drive" or "friction"), its key,
/// and what is wrong with it.
#[derive(Clone, Debug, PartialEq)]
pub struct DriveProblem {
    pub table: &'static str,
    pub key: &'static str,
    pub message: String,
}

impl DriveProblem {
    /// The problem as an error that names `[axes.X]` and the key (a value changed after
    /// loading, such as a fit's step, has no line to point at).
    pub fn of_axis(self, axis: Axis) -> crate::error::Error {
        crate::error::Error::invalid(
            Path::new(&format!("[axes.{axis}]")),
            format!("`{}.{}`: {}", self.table, self.key, self.message),
        )
    }
}

/// SI units per interface unit of `axis`'s positions: m per mm, or rad per deg.
pub fn si_per_unit(axis: Axis) -> f64 {
    if axis.is_rotary() {
        PI / 180.0
    } else {
        1e-3
    }
}

/// One axis's drive, validated and resolved for its kind, in SI units: positions in m
/// (linear) or rad (rotary), masses in kg or kg m², forces in N or N m. The servo models run
/// it as it is; the keys of the machine file it came from are in [`ServoConfig`],
/// [`DriveConfig`] and [`FrictionConfig`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisDrive {
    pub axis: Axis,
    pub model: Model,
    /// Position feedback from the table scale (fully closed) or the motor encoder.
    pub fully_closed: bool,
    /// Position-loop gain Kv, 1/s.
    pub kv_per_s: f64,
    /// Velocity and acceleration feedforward, fractions in 0..=1.
    pub velocity_feedforward: f64,
    pub acceleration_feedforward: f64,
    /// Velocity-loop bandwidth f_v, Hz.
    pub velocity_bandwidth_hz: f64,
    /// Velocity-loop integral time Ti, s.
    pub velocity_integral_time_s: f64,
    /// Current-loop time constant τ, s (0: an ideal current loop).
    pub current_time_constant_s: f64,
    /// Servo period as configured, s (the servo rounds it to divide the interpolation period).
    pub servo_period_s: f64,
    /// Mechanics integration substeps per servo period.
    pub substeps: u32,
    /// Following error beyond which the axis counts as diverged, m or rad.
    pub following_error_limit_m_or_rad: f64,
    /// Backlash (the whole gap), m or rad.
    pub backlash_m_or_rad: f64,
    /// Motor-side and table-side mass, kg, or inertia, kg m².
    pub motor_mass_kg_or_kgm2: f64,
    pub table_mass_kg_or_kgm2: f64,
    /// Stiffness between motor and table, N/m or N m/rad.
    pub stiffness_n_per_m_or_nm_per_rad: f64,
    /// Damping ratio ζ of the motor-table mode.
    pub damping_ratio: f64,
    /// Motor force limit, N, or torque limit, N m.
    pub force_limit_n_or_nm: f64,
    /// Coulomb friction Fc, N or N m (0: no dry friction).
    pub coulomb_n_or_nm: f64,
    /// Static over Coulomb friction Fs/Fc.
    pub static_ratio: f64,
    /// Stribeck velocity vs, m/s or rad/s.
    pub stribeck_m_or_rad_per_s: f64,
    /// Viscous friction Fv, N s/m or N m s/rad.
    pub viscous_n_s_per_m_or_nm_s_per_rad: f64,
    /// Pre-sliding displacement δ of the Dahl bristle model, m or rad (0: off).
    pub presliding_m_or_rad: f64,
    /// Damping ratio of the bristle on the table mass.
    pub presliding_damping_ratio: f64,
    /// Backlash and pre-sliding displacement in the axis's interface unit (mm or deg), as
    /// the lost motion at a reversal (ISO 230-2 reversal value) is reported.
    pub backlash_mm_or_deg: f64,
    pub presliding_mm_or_deg: f64,
}

impl AxisDrive {
    /// Validates the three tables of `axis` and resolves them: each key of the axis's kind,
    /// or its default, converted to SI. The first problem found is returned instead.
    pub fn resolve(
        axis: Axis,
        servo: &ServoConfig,
        drive: &DriveConfig,
        friction: &FrictionConfig,
    ) -> std::result::Result<AxisDrive, DriveProblem> {
        if let Some(problem) = Written::problem(axis, servo, drive, friction) {
            return Err(problem);
        }
        let w = Written::new(axis, servo, drive, friction);
        let si = si_per_unit(axis);
        Ok(AxisDrive {
            axis,
            model: w.model.unwrap_or(Model::Cascade),
            fully_closed: w.fully_closed.unwrap_or(false),
            kv_per_s: servo.kv_per_s,
            velocity_feedforward: servo.velocity_feedforward,
            acceleration_feedforward: servo.acceleration_feedforward,
            velocity_bandwidth_hz: servo.velocity_bandwidth_hz,
            velocity_integral_time_s: servo.velocity_integral_time_ms * 1e-3,
            current_time_constant_s: servo.current_time_constant_ms * 1e-3,
            servo_period_s: servo.servo_period_ms * 1e-3,
            substeps: servo.substeps,
            following_error_limit_m_or_rad: w.fe_limit.1 * si,
            backlash_m_or_rad: w.backlash.1 * si,
            motor_mass_kg_or_kgm2: w.motor_mass.1,
            table_mass_kg_or_kgm2: w.table_mass.1,
            // N/um for a linear axis; N m/rad as written for a rotary one.
            stiffness_n_per_m_or_nm_per_rad: if axis.is_rotary() {
                w.stiffness.1
            } else {
                w.stiffness.1 * 1e6
            },
            damping_ratio: w.damping_ratio,
            force_limit_n_or_nm: w.force_limit.1,
            coulomb_n_or_nm: w.coulomb.1,
            static_ratio: w.static_ratio,
            stribeck_m_or_rad_per_s: w.stribeck.1 * si,
            viscous_n_s_per_m_or_nm_s_per_rad: w.viscous.1,
            // um for a linear axis, deg for a rotary one.
            presliding_m_or_rad: w.presliding.1 * if axis.is_rotary() { si } else { 1e-6 },
            presliding_damping_ratio: w.presliding_damping_ratio,
            backlash_mm_or_deg: w.backlash.1,
            presliding_mm_or_deg: w.presliding.1 * if axis.is_rotary() { 1.0 } else { 1e-3 },
        })
    }

    /// The drive of `axis` with every key at its default (no key written).
    pub fn default_for(axis: Axis) -> AxisDrive {
        AxisDrive::resolve(
            axis,
            &ServoConfig::default(),
            &DriveConfig::default(),
            &FrictionConfig::default(),
        )
        .expect("the defaults are valid for every axis")
    }

    /// The same drive with backlash `mm_or_deg` (the whole gap, mm or deg), checked as the
    /// machine file's `backlash_mm` or `backlash_deg` is.
    pub fn with_backlash_mm_or_deg(
        &self,
        mm_or_deg: f64,
    ) -> std::result::Result<AxisDrive, DriveProblem> {
        check_backlash(self.axis, mm_or_deg)?;
        Ok(AxisDrive {
            backlash_m_or_rad: mm_or_deg * si_per_unit(self.axis),
            backlash_mm_or_deg: mm_or_deg,
            ..*self
        })
    }

    /// The same drive with position-loop gain `kv_per_s` (1/s), checked as the machine
    /// file's `kv_per_s` is.
    pub fn with_kv_per_s(&self, kv_per_s: f64) -> std::result::Result<AxisDrive, DriveProblem> {
        check_kv(kv_per_s)?;
        Ok(AxisDrive { kv_per_s, ..*self })
    }

    /// The servo model's name as the machine file writes it.
    pub fn model_name(&self) -> &'static str {
        match self.model {
            Model::FirstOrder => "first-order",
            Model::Cascade => "cascade",
        }
    }

    /// The position feedback's name as the machine file writes it.
    pub fn feedback_name(&self) -> &'static str {
        if self.fully_closed {
            "fully-closed"
        } else {
            "semi-closed"
        }
    }

    /// The same drive without its nonlinearities (backlash, Coulomb and static friction,
    /// pre-sliding): viscous friction only, so its response is linear in the setpoint.
    pub fn linear_twin(&self) -> AxisDrive {
        AxisDrive {
            backlash_m_or_rad: 0.0,
            coulomb_n_or_nm: 0.0,
            presliding_m_or_rad: 0.0,
            backlash_mm_or_deg: 0.0,
            presliding_mm_or_deg: 0.0,
            ..*self
        }
    }

    /// Whether the axis has dry friction the model runs (a cascade axis with Fc > 0), and so a
    /// slow zone about each reversal bounded by its Stribeck velocity.
    pub fn has_dry_friction(&self) -> bool {
        self.coulomb_n_or_nm > 0.0 && self.model != Model::FirstOrder
    }
}

/// Checks and resolves the drive parameters of one axis; errors name the key in
/// `[section.servo]`, `[section.drive]` or `[section.friction]` and point at its line.
pub fn validate(
    path: &Path,
    text: &str,
    section: &str,
    axis: Axis,
    servo: &ServoConfig,
    drive: &DriveConfig,
    friction: &FrictionConfig,
) -> Result<AxisDrive> {
    AxisDrive::resolve(axis, servo, drive, friction).map_err(|p| {
        value_error(
            path,
            text,
            &format!("{section}.{}", p.table),
            p.key,
            p.message,
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

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

    fn check(axis: Axis, text: &str) -> Result<AxisDrive> {
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
            Error::AtSource(e) => format!("{}: {}", e.line, e.message),
            Error::Located { line, message, .. } => format!("{line}: {message}"),
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

    /// The defaults and written keys in SI: each figure from the key's unit by hand.
    #[test]
    fn a_drive_resolves_to_si_units_for_its_kind() {
        let x = check(Axis::X, "[axes.X.servo]\n").unwrap();
        assert_eq!(x.model, Model::FirstOrder);
        assert!(!x.fully_closed);
        assert_eq!(x.servo_period_s, 0.25e-3);
        assert_eq!(x.velocity_integral_time_s, 10e-3);
        assert_eq!(x.following_error_limit_m_or_rad, 0.05); // 50 mm
        assert_eq!(x.motor_mass_kg_or_kgm2, 250.0);
        assert_eq!(x.stiffness_n_per_m_or_nm_per_rad, 2e8); // 200 N/um
        assert_eq!(x.stribeck_m_or_rad_per_s, 5e-4); // 0.5 mm/s
        assert_eq!(x.presliding_m_or_rad, 0.0);
        let text = "[axes.Y.servo]\nmodel = \"cascade\"\nfeedback = \"fully-closed\"\n\
                    [axes.Y.drive]\nbacklash_mm = 0.004\n[axes.Y.friction]\npresliding_um = 2\n";
        let y = check(Axis::Y, text).unwrap();
        assert_eq!((y.model, y.fully_closed), (Model::Cascade, true));
        assert_eq!(y.backlash_m_or_rad, 0.004 * 1e-3);
        assert_eq!(y.presliding_m_or_rad, 2.0 * 1e-6);
        assert_eq!(
            (y.backlash_mm_or_deg, y.presliding_mm_or_deg),
            (0.004, 2e-3)
        );
        assert!(y.has_dry_friction());
        let twin = y.linear_twin();
        assert_eq!(
            (
                twin.backlash_m_or_rad,
                twin.coulomb_n_or_nm,
                twin.presliding_m_or_rad
            ),
            (0.0, 0.0, 0.0)
        );
        assert!(!twin.has_dry_friction());
        assert_eq!(twin.viscous_n_s_per_m_or_nm_s_per_rad, 1000.0);
        let c = check(Axis::C, "[axes.C.drive]\nbacklash_deg = 0.003\n").unwrap();
        let rad = std::f64::consts::PI / 180.0;
        assert_eq!(c.backlash_m_or_rad, 0.003 * rad);
        assert_eq!(c.following_error_limit_m_or_rad, 90.0 * rad);
        assert_eq!(c.stribeck_m_or_rad_per_s, 0.1 * rad); // 0.1 deg/s
        assert_eq!(c.stiffness_n_per_m_or_nm_per_rad, 3e6);
        assert_eq!(c.coulomb_n_or_nm, 15.0);
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
}
