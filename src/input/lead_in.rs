//! The lead-in of a circle test: path before θ = 0 long enough for the axes to reach the feed
//! and for the servo loops to settle, so that the measured revolution starts at speed.
//!
//! From rest the planner reaches the cruise speed `V` on an arc of radius r with the path
//! acceleration and jerk it gives curved blocks (`motion::interpolation`, "Limits along the
//! path"): `a = min(½ amax, ⅓ jmax / (3 V/r))`, `j = ⅓ jmax`, over the plane's axes. The
//! S-curve takes
//!
//! ```text
//! T_acc = V/a + a/j   (V > a²/j),   2 sqrt(V/j)   otherwise;   D_acc = V T_acc / 2
//! ```
//!
//! Then the loops settle: the following error's transient is at most the steady lag `V/Kv`
//! and decays with the slowest loop's time constant τ (`1/Kv`; for a cascade also the velocity
//! loop's `1/(2π f_v)`, its integral time Ti and the current loop's τ), so the lead holds
//! `n = max(5, ln(lag / 0.01 µm))` time constants at speed. The lead is
//! `1.25 D_acc + V n τ` (the planner's derivative bounds, raised between samples, make its
//! acceleration a few per cent lower than the closed form), rounded up to a whole degree.
//!
//! # Near the machine's limits: whole turns
//!
//! The planner caps each block's cruise speed from bounds on its own path derivatives, and
//! at a junction it scales the speed by the ratio of the two blocks' caps
//! (`motion::interpolation`, "Junctions"): where a cap holds a lead arc or the measured
//! revolution below F, the two caps differ, the tangent "jumps" by that ratio, and the
//! junction is taken at the speed the axes' acceleration allows in one period. The measured
//! revolution then starts far below F (r 10 mm at F7000 started at 2,638 mm/min). So when F
//! comes within [`NEAR_LIMIT_SHARE`] of what the axes can give on the circle at all,
//!
//! ```text
//! v_limit = min(vmax, sqrt(½ amax r), (⅓ jmax r²)^⅓)     (the plane axes' smallest limits)
//! ```
//!
//! the lead-in (and the lead-out) is made of whole turns of the measured circle instead,
//! each one block with the measured one's start, end and centre: the planner caps them all
//! alike, whatever its rules, so the junctions keep the speed and the measured revolution
//! runs at the speed the lead reached. The sized lead is rounded up to whole turns.
//! Below that share every block runs at its programmed F (the planner's bounds on a whole
//! turn give at least 0.8 of `v_limit`) and the lead keeps its arcs.

use serde::Serialize;

use crate::error::Result;
use crate::input::drive::Model;
use crate::input::machine::Machine;
use crate::input::program::CircleTest;

/// The transient left at θ = 0, mm: the lead holds time constants until the lag decays to it.
const SETTLED_MM: f64 = 1e-5;
/// Fewest time constants at speed before θ = 0.
const MIN_TIME_CONSTANTS: f64 = 5.0;
/// Margin on the closed-form acceleration distance and time.
const ACCEL_MARGIN: f64 = 1.25;
/// A feed above this share of the circle's closed-form speed limit gets a lead-in of whole
/// turns (see the module documentation).
pub const NEAR_LIMIT_SHARE: f64 = 0.5;

/// How long a circle test's lead-in is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LeadIn {
    /// Arc before θ = 0 (and after θ = 360°), deg.
    pub deg: f64,
    /// Planned time from rest to θ = 0, s.
    pub time_s: f64,
    /// Of which the speed change from rest to the feed (with the margin), s.
    pub accel_time_s: f64,
    /// And the time at speed before θ = 0, s (0 when the lead is too short to reach it).
    pub settle_time_s: f64,
    /// The slowest servo loop's time constant, s.
    pub time_constant_s: f64,
    /// The speed planned at θ = 0, mm/min: the programmed feed unless the axes' closed-form
    /// limits on the circle hold it lower (the planner's own bounds may hold it lower still).
    pub speed_mm_min: f64,
    /// The speed the tool had at θ = 0, as the samples show it (the slowest run's), mm/min;
    /// filled in by a simulation, left out before.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reached_mm_min: Option<f64>,
    /// Whether the lead was sized here (true) or given as `[simulate] lead_deg`.
    pub sized: bool,
    /// Whether the lead-in and lead-out are whole turns of the measured circle (`deg` a
    /// multiple of 360): a sized lead when F is near the axes' limits on the circle.
    pub whole_turns: bool,
}

/// The planner's speed change from rest on the circle: (cruise V mm/s, a mm/s², j mm/s³).
fn planned_speed_change(circle: &CircleTest, machine: &Machine) -> (f64, f64, f64) {
    let (limit, amax, jmax) = circle_limits(circle, machine);
    let r = circle.radius_mm;
    let speed = (circle.feed_mm_min / 60.0).min(limit);
    let accel = (0.5 * amax).min(jmax / (9.0 * speed / r));
    (speed, accel, jmax / 3.0)
}

/// The closed-form speed limit on the circle, `min(vmax, sqrt(½ amax r), (⅓ jmax r²)^⅓)`
/// (mm/s), and the plane axes' smallest acceleration (mm/s²) and jerk (mm/s³) limits.
fn circle_limits(circle: &CircleTest, machine: &Machine) -> (f64, f64, f64) {
    let (u, v, _) = circle.axes();
    let r = circle.radius_mm;
    let (mut vmax, mut amax, mut jmax) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for axis in [u, v] {
        let c = machine.axis(axis);
        vmax = vmax.min(c.max_velocity / 60.0);
        amax = amax.min(c.max_acceleration);
        jmax = jmax.min(c.max_jerk);
    }
    let limit = vmax
        .min((0.5 * amax * r).sqrt())
        .min((jmax * r * r / 3.0).cbrt());
    (limit, amax, jmax)
}

/// Time of an S-curve from rest to `v` (zero acceleration at both ends), s.
fn accel_time(v: f64, a: f64, j: f64) -> f64 {
    if v > a * a / j {
        v / a + a / j
    } else {
        2.0 * (v / j).sqrt()
    }
}

/// The slowest loop's time constant of the plane's axes, s, and the smallest Kv, 1/s.
fn slowest_loop(circle: &CircleTest, machine: &Machine) -> Result<(f64, f64)> {
    let (u, v, _) = circle.axes();
    let (mut tau, mut kv) = (0.0f64, f64::INFINITY);
    for axis in [u, v] {
        let d = machine.drive(axis);
        kv = kv.min(d.kv_per_s);
        tau = tau.max(1.0 / d.kv_per_s);
        if d.model == Model::Cascade {
            tau = tau
                .max(1.0 / (std::f64::consts::TAU * d.velocity_bandwidth_hz))
                .max(d.velocity_integral_time_s)
                .max(d.current_time_constant_s);
        }
    }
    Ok((tau, kv))
}

impl LeadIn {
    /// The lead-in the circle needs on `machine` (see the module documentation).
    pub fn sized(circle: &CircleTest, machine: &Machine) -> Result<LeadIn> {
        let (speed, a, j) = planned_speed_change(circle, machine);
        let (tau, kv) = slowest_loop(circle, machine)?;
        let t_acc = ACCEL_MARGIN * accel_time(speed, a, j);
        let lag_mm = speed / kv;
        let n = MIN_TIME_CONSTANTS.max((lag_mm / SETTLED_MM).ln());
        let length_mm = 0.5 * speed * t_acc + speed * n * tau;
        let deg = (length_mm / circle.radius_mm).to_degrees().ceil();
        let (limit, _, _) = circle_limits(circle, machine);
        if circle.feed_mm_min / 60.0 > NEAR_LIMIT_SHARE * limit {
            return Ok(LeadIn {
                sized: true,
                whole_turns: true,
                ..LeadIn::given(circle, machine, 360.0 * (deg / 360.0).ceil())?
            });
        }
        Ok(LeadIn {
            sized: true,
            ..LeadIn::given(circle, machine, deg)?
        })
    }

    /// How long a lead of `deg` given by the user takes on `machine`.
    pub fn given(circle: &CircleTest, machine: &Machine, deg: f64) -> Result<LeadIn> {
        let (speed, a, j) = planned_speed_change(circle, machine);
        let (tau, _) = slowest_loop(circle, machine)?;
        let length_mm = deg.to_radians() * circle.radius_mm;
        let t_acc = ACCEL_MARGIN * accel_time(speed, a, j);
        let d_acc = 0.5 * speed * t_acc;
        let (accel_time_s, settle_time_s) = if length_mm >= d_acc {
            (t_acc, (length_mm - d_acc) / speed)
        } else {
            // Short of the feed: the speed w whose S-curve covers the lead, D(w) = w T(w)/2.
            let (mut lo, mut hi) = (0.0, speed);
            for _ in 0..60 {
                let w = 0.5 * (lo + hi);
                if 0.5 * w * accel_time(w, a, j) < length_mm {
                    lo = w;
                } else {
                    hi = w;
                }
            }
            (accel_time(lo, a, j), 0.0)
        };
        Ok(LeadIn {
            deg,
            time_s: accel_time_s + settle_time_s,
            accel_time_s,
            settle_time_s,
            time_constant_s: tau,
            speed_mm_min: if speed == circle.feed_mm_min / 60.0 {
                circle.feed_mm_min
            } else {
                speed * 60.0
            },
            sized: false,
            whole_turns: false,
            reached_mm_min: None,
        })
    }
}
