//! The servo models against the closed-form results of `docs/servo.md`:
//! two axes X and Y drive a planar circle (ISO 230-4), and the radial deviation of the actual
//! positions is compared with what the theory predicts.

use std::f64::consts::PI;

use mtsim::drive::AxisServo;
use mtsim::input::drive::{AxisDrive, DriveConfig, FrictionConfig, ServoConfig};
use mtsim::{Axis, Error};

/// Interpolation period, s.
const T: f64 = 1e-3;

/// Servo, drive and friction settings of one axis.
#[derive(Clone)]
struct Setup {
    servo: ServoConfig,
    drive: DriveConfig,
    friction: FrictionConfig,
}

fn first_order(kv: f64) -> Setup {
    Setup {
        servo: ServoConfig {
            model: "first-order".into(),
            kv_per_s: kv,
            ..Default::default()
        },
        drive: DriveConfig::default(),
        friction: FrictionConfig::default(),
    }
}

/// The default cascade drive without friction or backlash: a linear time-invariant axis.
fn cascade_linear() -> Setup {
    Setup {
        servo: ServoConfig {
            model: "cascade".into(),
            ..Default::default()
        },
        drive: DriveConfig::default(),
        friction: FrictionConfig {
            coulomb_n: Some(0.0),
            viscous_n_s_per_m: Some(0.0),
            ..Default::default()
        },
    }
}

/// One sample of a circle run: nominal angle (deg, in [0, 360)) and radial deviation (um).
#[derive(Clone, Copy, Debug)]
struct Sample {
    theta_deg: f64,
    radial_um: f64,
}

/// Runs a circle of radius `r` mm at `feed` mm/min, counter-clockwise when `ccw`, starting at
/// theta = 0 from rest. The first second (the start-up transient, > 30 time constants 1/Kv)
/// is discarded; then one full revolution is returned.
fn circle(x: &Setup, y: &Setup, r: f64, feed: f64, ccw: bool) -> Vec<Sample> {
    let omega = feed / 60.0 / r * if ccw { 1.0 } else { -1.0 };
    let mut sx = AxisServo::new(
        &AxisDrive::resolve(Axis::X, &x.servo, &x.drive, &x.friction).unwrap(),
        T,
        r,
    )
    .unwrap();
    let mut sy = AxisServo::new(
        &AxisDrive::resolve(Axis::Y, &y.servo, &y.drive, &y.friction).unwrap(),
        T,
        0.0,
    )
    .unwrap();
    let lead_in = (1.0 / T).round() as usize;
    let revolution = (2.0 * PI / omega.abs() / T).round() as usize;
    let mut samples = Vec::with_capacity(revolution);
    for k in 1..=lead_in + revolution {
        let t = k as f64 * T;
        let theta = omega * t;
        let ax = sx.step(r * theta.cos(), t).unwrap();
        let ay = sy.step(r * theta.sin(), t).unwrap();
        if k > lead_in {
            samples.push(Sample {
                theta_deg: theta.to_degrees().rem_euclid(360.0),
                radial_um: (ax.actual.hypot(ay.actual) - r) * 1e3,
            });
        }
    }
    samples
}

fn mean(s: &[Sample]) -> f64 {
    s.iter().map(|s| s.radial_um).sum::<f64>() / s.len() as f64
}

fn range(s: &[Sample]) -> f64 {
    let max = s.iter().map(|s| s.radial_um).fold(f64::MIN, f64::max);
    let min = s.iter().map(|s| s.radial_um).fold(f64::MAX, f64::min);
    max - min
}

/// Least-squares fit of `radial = c + a cos 2θ + b sin 2θ` over a full revolution (the
/// basis is orthogonal there, so each coefficient is a projection). Returns (a, b) in um.
fn fit_two_theta(s: &[Sample]) -> (f64, f64) {
    let m = mean(s);
    let n = s.len() as f64;
    let (mut a, mut b) = (0.0, 0.0);
    for p in s {
        let t = 2.0 * p.theta_deg.to_radians();
        a += (p.radial_um - m) * t.cos();
        b += (p.radial_um - m) * t.sin();
    }
    (2.0 * a / n, 2.0 * b / n)
}

/// Signed angular distance from `from` to `to`, deg, in [-180, 180).
fn angle_diff(to: f64, from: f64) -> f64 {
    (to - from + 180.0).rem_euclid(360.0) - 180.0
}

/// Samples whose nominal angle lies within [from, from + width) deg (wrapping at 360).
fn window(s: &[Sample], from: f64, width: f64) -> Vec<Sample> {
    s.iter()
        .copied()
        .filter(|p| (p.theta_deg - from).rem_euclid(360.0) < width)
        .collect()
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Spec result 1: `dr = r (1/sqrt(1 + (ω/Kv)^2) - 1)`: -3.09 um at F1000 and -27.8 um at
/// F3000 for r = 50 mm, Kv = 30 1/s, the same for CW and CCW.
#[test]
fn first_order_radial_error_matches_the_closed_form() {
    let (r, kv) = (50.0, 30.0);
    for (feed, quoted_um) in [(1000.0f64, -3.09f64), (3000.0, -27.8)] {
        let omega = feed / 60.0 / r;
        let closed_form_um = r * (1.0 / (1.0 + (omega / kv).powi(2)).sqrt() - 1.0) * 1e3;
        assert!((closed_form_um - quoted_um).abs() < 0.01 * quoted_um.abs());
        let ccw = circle(&first_order(kv), &first_order(kv), r, feed, true);
        let cw = circle(&first_order(kv), &first_order(kv), r, feed, false);
        for run in [&ccw, &cw] {
            let m = mean(run);
            assert!(
                (m - closed_form_um).abs() < 0.03 * closed_form_um.abs(),
                "F{feed}: mean radial {m} um, expected {closed_form_um} um"
            );
            assert!(
                range(run) < 0.01 * closed_form_um.abs(),
                "F{feed}: radial range {} um",
                range(run)
            );
        }
        eprintln!(
            "F{feed}: closed form {closed_form_um:.4} um, CCW {:.4} um, CW {:.4} um",
            mean(&ccw),
            mean(&cw)
        );
        assert!((mean(&ccw) - mean(&cw)).abs() < 0.01 * closed_form_um.abs());
    }
}

/// Spec result 2: velocity and acceleration feedforward at 100 % with an ideal inner loop
/// leave no radial error.
#[test]
fn full_feedforward_with_an_ideal_inner_loop_removes_the_radial_error() {
    let mut s = first_order(30.0);
    s.servo.velocity_feedforward = 1.0;
    s.servo.acceleration_feedforward = 1.0;
    for feed in [1000.0, 3000.0] {
        let run = circle(&s, &s, 50.0, feed, true);
        let worst = run.iter().map(|p| p.radial_um.abs()).fold(0.0, f64::max);
        eprintln!("F{feed}: max |radial| {worst:.2e} um");
        assert!(worst < 0.1, "F{feed}: |radial error| up to {worst} um");
    }
}

/// Spec result 3: Kvx = 30, Kvy = 27 at F1000. Each axis lags by the phase ω/Kv; the phase
/// difference makes an ellipse `r δφ sin 2(θ - φ)`-like in the radial trace, peak-to-peak
/// `r ω |1/Kvx - 1/Kvy| = v |1/Kvx - 1/Kvy|` ≈ 62 um, independent of r. With X the faster
/// axis the radius is largest at 135 deg (CCW) and 45 deg (CW).
#[test]
fn gain_mismatch_gives_a_45_degree_ellipse_that_flips_with_direction() {
    let (kvx, kvy, feed) = (30.0f64, 27.0f64, 1000.0f64);
    let expected_um = feed / 60.0 * (1.0 / kvx - 1.0 / kvy).abs() * 1e3;
    assert!((expected_um - 62.0).abs() < 0.5);
    for r in [25.0, 50.0] {
        for (ccw, major_deg) in [(true, 135.0), (false, 45.0)] {
            let run = circle(&first_order(kvx), &first_order(kvy), r, feed, ccw);
            let (a, b) = fit_two_theta(&run);
            let p2p = 2.0 * a.hypot(b);
            assert!(
                (p2p - expected_um).abs() < 0.1 * expected_um,
                "r {r}, ccw {ccw}: peak-to-peak {p2p} um, expected {expected_um} um"
            );
            let major = (b.atan2(a).to_degrees() / 2.0).rem_euclid(180.0);
            eprintln!("r {r}, ccw {ccw}: p2p {p2p:.2} um (expected {expected_um:.2}), major axis {major:.2} deg");
            assert!(
                angle_diff(major, major_deg).abs() < 5.0,
                "r {r}, ccw {ccw}: major axis at {major} deg, expected {major_deg}"
            );
        }
    }
}

/// Spec result 4: backlash b on X, semi-closed loop. Moving in +X the table trails the motor
/// by `b/2 + Ff/k`, moving in -X it leads by as much, so the trace is two half circles offset
/// by `±(b/2 + Ff/k)` along X: radial = c - s sign(vx) cos θ, and the step at X's reversal
/// angles (0 and 180 deg for x = r cos θ) is `2 s = b + 2 Ff/k`. (The brief's "90/270 deg"
/// are Y's reversal angles, where the X offset has no radial component.) Viscous friction is
/// off so that Ff = Fc; Y is frictionless.
#[test]
fn backlash_splits_the_circle_into_two_half_circles() {
    let (r, feed) = (50.0, 1000.0);
    for (backlash_mm, stiffness_n_per_um, coulomb_n) in
        [(0.010, 200.0, 150.0), (0.010, 50.0, 250.0)]
    {
        let mut x = cascade_linear();
        x.drive.backlash_mm = Some(backlash_mm);
        x.drive.stiffness_n_per_um = Some(stiffness_n_per_um);
        x.friction.coulomb_n = Some(coulomb_n);
        let expected_um = backlash_mm * 1e3 + 2.0 * coulomb_n / stiffness_n_per_um;
        for ccw in [true, false] {
            let run = circle(&x, &cascade_linear(), r, feed, ccw);
            // Least squares for radial = c + s g(θ), g = -sign(vx) cos θ, away from the
            // reversals (|cos θ| small there anyway, and the transient lives there).
            let pts: Vec<(f64, f64)> = run
                .iter()
                .filter(|p| {
                    angle_diff(p.theta_deg, 0.0).abs() > 15.0
                        && angle_diff(p.theta_deg, 180.0).abs() > 15.0
                })
                .map(|p| {
                    let t = p.theta_deg.to_radians();
                    let vx = -t.sin() * if ccw { 1.0 } else { -1.0 };
                    (-vx.signum() * t.cos(), p.radial_um)
                })
                .collect();
            let n = pts.len() as f64;
            let (gm, rm) = (
                pts.iter().map(|p| p.0).sum::<f64>() / n,
                pts.iter().map(|p| p.1).sum::<f64>() / n,
            );
            let s = pts.iter().map(|p| (p.0 - gm) * (p.1 - rm)).sum::<f64>()
                / pts.iter().map(|p| (p.0 - gm).powi(2)).sum::<f64>();
            let step = 2.0 * s;
            eprintln!("b {backlash_mm} mm, k {stiffness_n_per_um} N/um, Fc {coulomb_n} N, ccw {ccw}: step {step:.3} um, expected {expected_um:.3} um");
            assert!((step - expected_um).abs() < 0.1 * expected_um, "b {backlash_mm} mm, k {stiffness_n_per_um} N/um, Fc {coulomb_n} N, ccw {ccw}: step {step} um, expected {expected_um} um");
        }
    }
}

/// Spec result 5: friction on X only (fully-closed, so the steady lost motion is corrected
/// and only the transient remains). At each X reversal the table sticks while the velocity
/// loop winds its force from +Ff to -Fs, the command moves inward meanwhile, so the radius
/// shows an outward spike just after the reversal, in the direction of travel, micrometres
/// high. Y, without friction, shows nothing comparable at its reversal angles.
#[test]
fn friction_makes_an_outward_spike_after_each_reversal_of_that_axis_only() {
    let mut x = cascade_linear();
    x.servo.feedback = "fully-closed".into();
    x.friction = FrictionConfig::default();
    let mut y = cascade_linear();
    y.servo.feedback = "fully-closed".into();
    for ccw in [true, false] {
        let run = circle(&x, &y, 50.0, 1000.0, ccw);
        let baseline = median(&mut run.iter().map(|p| p.radial_um).collect::<Vec<_>>());
        let travel = if ccw { 1.0 } else { -1.0 };
        let mut spikes = Vec::new();
        for reversal in [0.0, 180.0] {
            // 30 deg after the reversal in the direction of travel.
            let after = window(&run, if ccw { reversal } else { reversal - 30.0 }, 30.0);
            let peak = after
                .iter()
                .max_by(|a, b| a.radial_um.total_cmp(&b.radial_um))
                .unwrap();
            let height = peak.radial_um - baseline;
            let lead = angle_diff(peak.theta_deg, reversal) * travel;
            assert!(
                height > 0.3 && height < 30.0,
                "ccw {ccw}: spike after {reversal} deg is {height} um"
            );
            assert!(
                lead > 0.0 && lead < 15.0,
                "ccw {ccw}: spike peaks {lead} deg after the reversal at {reversal} deg"
            );
            // Before the reversal the trace is still on the baseline.
            let before = window(
                &run,
                if ccw { reversal - 30.0 } else { reversal + 1.0 },
                29.0,
            );
            let before_max = before
                .iter()
                .map(|p| (p.radial_um - baseline).abs())
                .fold(0.0, f64::max);
            assert!(
                before_max < 0.25 * height,
                "ccw {ccw}: {before_max} um before the reversal at {reversal} deg"
            );
            eprintln!("ccw {ccw}: spike {height:.3} um at {lead:.2} deg after {reversal}; baseline {baseline:.3} um; before {before_max:.3} um");
            spikes.push(height);
        }
        let smallest = spikes.iter().copied().fold(f64::MAX, f64::min);
        for y_reversal in [90.0, 270.0] {
            let near = window(&run, y_reversal - 30.0, 60.0);
            let worst = near
                .iter()
                .map(|p| (p.radial_um - baseline).abs())
                .fold(0.0, f64::max);
            eprintln!("ccw {ccw}: near Y reversal {y_reversal}: {worst:.3} um");
            assert!(worst < 0.2 * smallest, "ccw {ccw}: {worst} um near Y's reversal at {y_reversal} deg vs spike {smallest} um");
        }
    }
}

/// Spec result 6: identical linear dynamics on both axes map a circle onto a circle: the
/// radial error is a constant (no ellipse, no quadrant marks).
#[test]
fn identical_dynamics_give_a_uniform_radial_error() {
    for setup in [first_order(30.0), cascade_linear()] {
        for feed in [1000.0, 3000.0] {
            let run = circle(&setup, &setup, 50.0, feed, true);
            let (m, g) = (mean(&run), range(&run));
            eprintln!(
                "{} F{feed}: mean {m:.4} um, range {g:.2e} um",
                setup.servo.model
            );
            assert!(
                m < 0.0 && g < 0.02 * m.abs(),
                "{} F{feed}: mean {m} um, range {g} um",
                setup.servo.model
            );
        }
    }
}

/// Runs a ramp at `speed` units/s for 2 s from rest and returns the final state.
fn ramp(axis: Axis, s: &Setup, speed: f64) -> mtsim::drive::ServoState {
    let mut servo = AxisServo::new(
        &AxisDrive::resolve(axis, &s.servo, &s.drive, &s.friction).unwrap(),
        T,
        10.0,
    )
    .unwrap();
    let mut last = None;
    for k in 1..=2000 {
        let t = k as f64 * T;
        last = Some(servo.step(10.0 + speed * t, t).unwrap());
    }
    last.unwrap()
}

/// On a ramp at speed v the P loop needs the error `v/Kv` to command v. With a PI velocity
/// loop the friction is taken up by the integrator, so a fully-closed loop shows exactly
/// `v/Kv`, and a semi-closed loop adds the elastic lag of the table behind the motor,
/// `(Fc + Fv v)/k`. Velocity feedforward removes the `v/Kv` part.
#[test]
fn ramp_following_error_is_v_over_kv_and_feedforward_removes_it() {
    // Linear axis at F1000: 16.67 mm/s; default friction 150 N + 1000 N s/m, k 200 N/um.
    let v = 1000.0 / 60.0;
    let lost_motion_mm = (150.0 + 1000.0 * v * 1e-3) / 200e6 * 1e3;
    // Rotary axis at 3600 deg/min: 60 deg/s; default 15 N m + 5 N m s/rad, k 3e6 N m/rad.
    let w = 60.0f64;
    let lost_motion_deg = ((15.0 + 5.0 * w.to_radians()) / 3e6f64).to_degrees();
    for (axis, speed, lost) in [(Axis::X, v, lost_motion_mm), (Axis::C, w, lost_motion_deg)] {
        let mut s = Setup {
            friction: FrictionConfig::default(),
            ..cascade_linear()
        };
        for feedback in ["fully-closed", "semi-closed"] {
            s.servo.feedback = feedback.into();
            let extra = if feedback == "semi-closed" { lost } else { 0.0 };
            s.servo.velocity_feedforward = 0.0;
            let fe = ramp(axis, &s, speed).following_error;
            let expected = speed / 30.0 + extra;
            eprintln!("{axis} {feedback}: fe {fe:.6e}, expected {expected:.6e}");
            assert!(
                (fe - expected).abs() < 1e-3 * expected,
                "{axis} {feedback}: {fe}, expected {expected}"
            );
            s.servo.velocity_feedforward = 1.0;
            let fe = ramp(axis, &s, speed).following_error;
            eprintln!("{axis} {feedback} with feedforward: fe {fe:.6e}, expected {extra:.6e}");
            assert!(
                (fe - extra).abs() < 0.02 * lost,
                "{axis} {feedback} with feedforward: {fe}, expected {extra}"
            );
        }
    }
    // The ideal first-order loop: exactly zero with feedforward.
    let mut s = first_order(30.0);
    s.servo.velocity_feedforward = 1.0;
    assert!(ramp(Axis::Y, &s, v).following_error.abs() < 1e-9);
}

/// Unstable parameter sets must stop with `Diverged` naming the axis, never with NaN:
/// a velocity loop far too stiff for its 1 ms sampling (ωv T = 19, discrete pole at
/// 1 - ωv T = -18) with no effective force limit, and a spring so stiff that one explicit
/// substep of 0.25 ms cannot resolve it (ω h = 5 > 2).
#[test]
fn an_unstable_drive_reports_divergence_on_its_axis() {
    let mut fast_loop = cascade_linear();
    fast_loop.servo.velocity_bandwidth_hz = 3000.0;
    fast_loop.servo.servo_period_ms = 1.0;
    fast_loop.drive.force_limit_n = Some(1e12);
    let mut stiff_spring = cascade_linear();
    stiff_spring.servo.substeps = 1;
    stiff_spring.drive.stiffness_n_per_um = Some(1e5);
    for s in [fast_loop, stiff_spring] {
        diverges_on_z(&s);
    }
    // A NaN setpoint is refused the same way.
    let mut servo = AxisServo::new(
        &AxisDrive::resolve(
            Axis::B,
            &ServoConfig::default(),
            &DriveConfig::default(),
            &FrictionConfig::default(),
        )
        .unwrap(),
        T,
        0.0,
    )
    .unwrap();
    assert!(matches!(
        servo.step(f64::NAN, 0.5),
        Err(Error::Diverged { axis: Axis::B, .. })
    ));
}

fn diverges_on_z(s: &Setup) {
    let mut servo = AxisServo::new(
        &AxisDrive::resolve(Axis::Z, &s.servo, &s.drive, &s.friction).unwrap(),
        T,
        0.0,
    )
    .unwrap();
    let mut outcome = None;
    for k in 1..=10_000 {
        let t = k as f64 * T;
        match servo.step(0.01 * t, t) {
            Ok(state) => assert!(
                state.actual.is_finite()
                    && state.following_error.is_finite()
                    && state.motor.is_finite()
            ),
            Err(e) => {
                outcome = Some(e);
                break;
            }
        }
    }
    match outcome {
        Some(Error::Diverged {
            axis,
            time_s,
            reason,
        }) => {
            assert_eq!(axis, Axis::Z);
            assert!(time_s > 0.0 && !reason.is_empty());
            eprintln!("diverged at {time_s} s: {reason}");
        }
        other => panic!("expected Diverged on Z, got {other:?}"),
    }
}

/// First-order model with backlash b: a play element between motor and table. On a ramp the
/// loop error is v/Kv at its feedback point, and the table trails the motor by b/2: a
/// semi-closed loop (motor encoder) shows `v/Kv + b/2` at the table, a fully-closed loop
/// (table scale) `v/Kv` with the motor b/2 ahead.
#[test]
fn first_order_backlash_is_a_play_element_between_motor_and_table() {
    let (v, b) = (1000.0 / 60.0, 0.02);
    let mut s = first_order(30.0);
    s.drive.backlash_mm = Some(b);
    for (feedback, expected_fe) in [
        ("semi-closed", v / 30.0 + b / 2.0),
        ("fully-closed", v / 30.0),
    ] {
        s.servo.feedback = feedback.into();
        let state = ramp(Axis::X, &s, v);
        eprintln!(
            "{feedback}: fe {:.6} mm, motor - table {:.6} mm",
            state.following_error,
            state.motor - state.actual
        );
        assert!(
            (state.following_error - expected_fe).abs() < 1e-3 * expected_fe,
            "{feedback}: {}",
            state.following_error
        );
        assert!(
            (state.motor - state.actual - b / 2.0).abs() < 1e-9,
            "{feedback}"
        );
    }
}

/// Spec result 5, last point: in a fully-closed loop backlash shows as a spike, larger than
/// the friction spike alone, instead of a step: the scale on the table corrects the lost
/// motion once the motor has crossed the gap, so the two half circles coincide again.
#[test]
fn fully_closed_backlash_gives_a_larger_spike_instead_of_a_step() {
    let mut friction_only = cascade_linear();
    friction_only.servo.feedback = "fully-closed".into();
    friction_only.friction = FrictionConfig::default();
    let mut with_backlash = friction_only.clone();
    with_backlash.drive.backlash_mm = Some(0.010);
    let mut y = cascade_linear();
    y.servo.feedback = "fully-closed".into();
    let spike = |x: &Setup| {
        let run = circle(x, &y, 50.0, 1000.0, true);
        let baseline = median(&mut run.iter().map(|p| p.radial_um).collect::<Vec<_>>());
        let after = window(&run, 0.0, 30.0)
            .iter()
            .map(|p| p.radial_um - baseline)
            .fold(f64::MIN, f64::max);
        // Away from the reversals the trace is back on the baseline on both sides of 0 deg.
        let settled = [window(&run, 60.0, 30.0), window(&run, 270.0, 30.0)]
            .iter()
            .flatten()
            .map(|p| (p.radial_um - baseline).abs())
            .fold(0.0, f64::max);
        (after, settled)
    };
    let (friction_spike, _) = spike(&friction_only);
    let (backlash_spike, settled) = spike(&with_backlash);
    eprintln!("friction spike {friction_spike:.3} um, with backlash {backlash_spike:.3} um, settled within {settled:.3} um");
    // Noticeably larger: by more than a tenth of the 10 um gap.
    assert!(
        backlash_spike > friction_spike + 0.1 * 10.0,
        "{backlash_spike} vs {friction_spike}"
    );
    assert!(
        settled < 0.05 * 10.0,
        "no step: {settled} um away from the reversals"
    );
}
