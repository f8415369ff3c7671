//! The cut's reversal marks on a realistic servo (trt-ac's cascades: Kv 30/s, dry friction,
//! a two-mass drive), read outside the whole take-up of the axis's lost motion, against the
//! contract's first-order step `B |n_axis|` (`cutting-test.md`): B the axis's lost motion
//! from its parameters alone (ISO 230-2, semi-closed loop: the gap b and the drive's wind-up
//! by the friction, `B = b + 2 Fc / k`), n the surface normal at the reversal's pose through
//! the machine's kinematics. And no mark where no axis has lost motion.

use std::path::Path;

use mtsim::input::scenario::Scenario;
use mtsim::kinematics::Branch;
use mtsim::measure::cut::figures::Mark;
use mtsim::measure::cut::CutOptions;
use mtsim::study::cut::{run_cut, CutRun};
use mtsim::Axis;
use nalgebra::Vector3;

use crate::common::{scenario_text, scratch, trt_ac};

/// The `alpha`/`beta` cone (L 100 mm, O at (0, 0, 200)) in 720 blocks at F1000 on trt-ac as
/// bundled (its 20 mm cutter), with `overrides`, loaded.
fn cone(name: &str, (alpha, beta): (f64, f64), overrides: &str) -> Scenario {
    let dir = scratch("cut-marks", name);
    let path = dir.join("scenario.toml");
    let text = scenario_text(
        &trt_ac(),
        &format!(
            "[program.cone]\nhalf_apex_deg = {alpha}\ninclination_deg = {beta}\n\
             center_mm = [0.0, 0.0, 200.0]\nballbar_length_mm = 100.0\nsegments = 720\n\
             feed_mm_min = 1000.0\n{overrides}"
        ),
    );
    std::fs::write(&path, text).unwrap();
    Scenario::load(Path::new(&path)).unwrap()
}

/// No dry friction on any axis (the cascades kept).
fn frictionless() -> String {
    ["X", "Y", "Z", "A", "C"]
        .iter()
        .map(|a| {
            let key = if *a == "A" || *a == "C" {
                "coulomb_nm"
            } else {
                "coulomb_n"
            };
            format!("[machine_overrides.axes.{a}.friction]\n{key} = 0.0\n")
        })
        .collect()
}

fn backlash(axis: &str, mm: f64) -> String {
    format!("[machine_overrides.axes.{axis}.drive]\nbacklash_mm = {mm}\n")
}

fn cut(s: &Scenario) -> CutRun {
    run_cut(s, CutOptions::default(), false, &|_| {}).unwrap()
}

/// The axis's lost motion from its parameters, µm: `b + 2 Fc / k` (semi-closed loop).
fn lost_motion_um(s: &Scenario, axis: Axis) -> f64 {
    let d = s.machine.drive(axis);
    1e6 * (d.backlash_m_or_rad + 2.0 * d.coulomb_n_or_nm / d.stiffness_n_per_m_or_nm_per_rad)
}

/// The surface normal's component along machine `axis` at θ (deg): n in the cone frame,
/// turned into the table frame, then the machine frame at θ's pose.
fn normal_along(s: &Scenario, axis: Axis, theta_deg: f64) -> f64 {
    let test = mtsim::program::test_of(s);
    let cone = test.cone().unwrap();
    let kin = s.machine.kinematics;
    let (a, t) = (cone.half_apex_deg.to_radians(), theta_deg.to_radians());
    let q = kin.inverse(&cone.pose(t), Branch::Primary, 0.0);
    let n_cone = Vector3::new(a.cos() * t.cos(), a.cos() * t.sin(), a.sin());
    let n = kin.table_rotation(&q) * (cone.frame_rotation() * n_cone);
    match axis {
        Axis::X => n.x,
        Axis::Y => n.y,
        _ => n.z,
    }
}

/// Checks each of `axis`'s own marks against `B |n_axis|` within 5 %; returns how many.
fn assert_marks_are_b_times_n(name: &str, s: &Scenario, run: &CutRun, axis: Axis) -> usize {
    let b_um = lost_motion_um(s, axis);
    let figures = run.surface.figures();
    let own: Vec<&Mark> = figures
        .marks
        .iter()
        .filter(|m| m.axis == axis.to_string())
        .collect();
    for m in &own {
        let expected = b_um * normal_along(s, axis, m.theta_deg).abs();
        eprintln!(
            "{name}: {axis} at θ {:.2}°: step {:+.4} µm, B |n| = {b_um:.3} × {:.4} = {expected:.4} µm \
             ({:+.2} %), lost motion read {:?}, levels read outside θ {:.2} to {:.2}°",
            m.theta_deg,
            m.step_um,
            expected / b_um,
            100.0 * (m.step_um.abs() / expected - 1.0),
            m.lost_motion_um_or_arcsec,
            m.take_up_deg[0],
            m.take_up_deg[1]
        );
        assert!(
            (m.step_um.abs() - expected).abs() <= 0.05 * expected,
            "{name}: {axis} at θ {}: step {} µm against B |n| = {expected} µm",
            m.theta_deg,
            m.step_um
        );
        // The lost motion the run took up is the parameters' B.
        assert!(
            (m.lost_motion_um_or_arcsec[0] - b_um).abs() <= 0.02 * b_um,
            "{name}: lost motion {:?} µm against B = {b_um} µm",
            m.lost_motion_um_or_arcsec
        );
    }
    own.len()
}

/// The axis's reversal angles as the cut read them.
fn reversals_of(run: &CutRun, axis: Axis) -> Vec<f64> {
    run.surface
        .reversals()
        .iter()
        .find(|(a, _)| *a == axis)
        .map(|(_, r)| r.clone())
        .unwrap_or_default()
}

/// 10 µm of X backlash on trt-ac as bundled: each X reversal marks `B |n_x|` within 5 %,
/// with B = 10 µm + 2 Fc / k (the friction's wind-up, 1.5 µm), on the 15/10 cone and on
/// the 45/30 one.
#[test]
fn x_backlash_on_a_realistic_servo_marks_b_times_n_x_on_two_cones() {
    for (name, angles) in [("15-10", (15.0, 10.0)), ("45-30", (45.0, 30.0))] {
        let s = cone(&format!("x-{name}"), angles, &backlash("X", 0.010));
        let run = cut(&s);
        let reversals = reversals_of(&run, Axis::X);
        assert_eq!(reversals.len(), 2, "{name}: {reversals:?}");
        let n = assert_marks_are_b_times_n(name, &s, &run, Axis::X);
        assert_eq!(n, 2, "{name}: a mark at each X reversal");
    }
}

/// 10 µm of Y backlash: the Y reversals Y makes alone mark `B |n_y|` within 5 %; the two
/// it shares with Z and A (θ 0° and 180° on the 15/10 cone) are one mark named by all
/// three.
#[test]
fn y_backlash_on_a_realistic_servo_marks_b_times_n_y() {
    let s = cone("y", (15.0, 10.0), &backlash("Y", 0.010));
    let run = cut(&s);
    let n = assert_marks_are_b_times_n("15-10", &s, &run, Axis::Y);
    assert_eq!(n, 2, "Y reverses alone twice on the 15/10 cone");
    let shared: Vec<String> = run
        .surface
        .figures()
        .marks
        .iter()
        .filter(|m| m.axis.contains('+'))
        .map(|m| format!("{} at {:.2}", m.axis, m.theta_deg))
        .collect();
    assert_eq!(shared, ["Y+Z+A at 0.00", "Y+Z+A at 180.00"]);
}

/// Without backlash, the friction's wind-up alone (B = 2 Fc / k = 1.5 µm on trt-ac) is the
/// lost motion a CMM sees at X's reversals: `B |n_x|` within 5 %.
#[test]
fn friction_wind_up_alone_marks_its_own_lost_motion() {
    let s = cone("wind-up", (15.0, 10.0), "");
    let run = cut(&s);
    let n = assert_marks_are_b_times_n("wind-up", &s, &run, Axis::X);
    assert_eq!(n, 2);
}

/// A machine without lost motion (no backlash, no dry friction, cascades as bundled):
/// no mark anywhere, though every axis reverses; the same machine with 10 µm of X backlash
/// marks X alone, `b |n_x|` within 5 %.
#[test]
fn no_lost_motion_no_mark_and_backlash_alone_marks_its_axis() {
    let clean = cone("clean", (15.0, 10.0), &frictionless());
    let run = cut(&clean);
    let figures = run.surface.figures();
    assert!(
        run.surface
            .reversals()
            .iter()
            .map(|(_, r)| r.len())
            .sum::<usize>()
            >= 8,
        "{:?}",
        run.surface.reversals()
    );
    assert!(figures.marks.is_empty(), "{:?}", figures.marks);
    let s = cone(
        "clean-x",
        (15.0, 10.0),
        &(frictionless() + &backlash("X", 0.010)),
    );
    let run = cut(&s);
    let figures = run.surface.figures();
    assert!(
        figures.marks.iter().all(|m| m.axis == "X"),
        "{:?}",
        figures.marks
    );
    assert_eq!(assert_marks_are_b_times_n("clean-x", &s, &run, Axis::X), 2);
}
