//! Overlapped moves ([`mtsim::motion::overlap`]) against closed forms: on a machine planned by
//! LinuxCNC's rules (`[control] max_feed_override`) with 20 mm/s, 30 deg/s and 300 mm/s² (deg)
//! limits and no jerk limit to speak of (1e9), the moves of a chain with rotary axes run rest
//! to rest at half the acceleration limit, each starting where the one before starts slowing
//! down (or has `2P/sin(θ/2)` of X Y Z travel left), so the total time follows from the
//! trapezoid formulas `T = L/v + v/a` by hand.

use std::path::{Path, PathBuf};

use mtsim::input::machine::Machine;
use mtsim::motion::interpolation::{InterpolationOptions, Interpolator};
use mtsim::motion::overlap::tolerance_travel;
use mtsim::Axis;

const PERIOD: f64 = 1e-3;

/// The machine: X Y Z at 20 mm/s and 300 mm/s², A C at 30 deg/s and 300 deg/s², jerk 1e9.
fn machine() -> Machine {
    let mut text = String::from(
        "name = \"overlap\"\ninterpolation_period_ms = 1.0\ndialect = \"linuxcnc\"\n\
         [control]\nmax_feed_override = 2.0\n[kinematics]\ntable = [\"A\", \"C\"]\n\
         head = [\"X\", \"Y\", \"Z\"]\n",
    );
    for (axis, v) in [
        ("X", 1200),
        ("Y", 1200),
        ("Z", 1200),
        ("A", 1800),
        ("C", 1800),
    ] {
        text += &format!(
            "[axes.{axis}]\nmin = -1000\nmax = 1000\nmax_velocity = {v}\n\
             max_acceleration = 300\nmax_jerk = 1e9\n"
        );
    }
    Machine::from_toml(Path::new("overlap.toml"), &text, None).unwrap()
}

/// The setpoints of `program` (X Y Z A C each period), from all axes at 0.
fn run(program: &str) -> Vec<[f64; 5]> {
    let machine = machine();
    let options = ngc::Options {
        dialect: ngc::Dialect::Linuxcnc,
        ..ngc::Options::default()
    };
    let moves = ngc::read_str_with(&PathBuf::from("p.ngc"), program, &options)
        .map(|m| m.map_err(mtsim::error::Error::from));
    let axes = [Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::C];
    Interpolator::new(moves, &machine, InterpolationOptions::default())
        .unwrap()
        .map(|s| {
            let s = s.unwrap();
            axes.map(|a| s.q[a])
        })
        .collect()
}

/// The time (s) of the first setpoint at the program's end point: the motion's duration.
fn duration(rows: &[[f64; 5]]) -> f64 {
    let end = rows.last().unwrap();
    let k = rows
        .iter()
        .position(|r| r.iter().zip(end).all(|(a, b)| (a - b).abs() < 1e-9))
        .unwrap();
    k as f64 * PERIOD
}

/// Axis `j`'s velocity over period `k` (units/s).
fn velocity(rows: &[[f64; 5]], k: usize, j: usize) -> f64 {
    (rows[k + 1][j] - rows[k][j]) / PERIOD
}

/// The largest |velocity| and |acceleration| of axis `j` (finite differences).
fn peaks(rows: &[[f64; 5]], j: usize) -> (f64, f64) {
    let (mut v, mut a) = (0.0f64, 0.0f64);
    for k in 1..rows.len() - 1 {
        v = v.max(velocity(rows, k, j).abs());
        a = a.max(((rows[k + 1][j] - 2.0 * rows[k][j] + rows[k - 1][j]) / PERIOD.powi(2)).abs());
    }
    (v, a)
}

/// Three XC/YC moves at 10 mm/s (C at 5 deg/s) turning 90° twice, each 20 mm of X Y Z.
const SQUARE: &str = "G1 X20 C10 F600\nG1 Y20 C20\nG1 X0 C30\nM2\n";

/// Under G64 without P each move starts where the one before starts slowing down: the moves
/// run at 150 mm/s² (half of 300), so the three take `3 L/v + v/a = 6 + 10/150` s (against
/// `3 (L/v + v/a_max) = 6.2` s stopping at full acceleration), and halfway through the
/// first overlap X and Y both move at 5 mm/s.
#[test]
fn moves_with_a_rotary_axis_overlap_from_where_the_first_slows_down() {
    let rows = run(&format!("G21 G90 G17 G64\n{SQUARE}"));
    let expected = 6.0 + 10.0 / 150.0;
    let t = duration(&rows);
    assert!(
        (t - expected).abs() < 1.5e-3,
        "{t} s, expected {expected} s"
    );
    // The overlap runs from 2.0 s to 2.0 + 10/150 s.
    let mid = ((2.0 + 5.0 / 150.0) / PERIOD) as usize;
    let (vx, vy) = (velocity(&rows, mid, 0), velocity(&rows, mid, 1));
    assert!(
        (vx - 5.0).abs() < 0.2 && (vy - 5.0).abs() < 0.2,
        "X {vx}, Y {vy} mm/s"
    );
    for j in 0..5 {
        let (v, a) = peaks(&rows, j);
        assert!(a <= 150.0 * (1.0 + 1e-6) + 1e-6, "axis {j}: {a} mm/s²");
        assert!(v <= 10.0 + 1e-9, "axis {j}: {v} mm/s");
    }
}

/// Under G64 P0.05 each 90° turn lets the next move start only with
/// `D = 2P/sin(45°) = 0.1414` mm left on the one before (less than its 0.333 mm of slowing
/// down), `sqrt(2D/a)` before its end: `3 (L/v + v/a) − 2 sqrt(2D/a)` with a = 150.
#[test]
fn the_tolerance_holds_the_overlap_to_2p_over_sin_half_the_turn() {
    let rows = run(&format!("G21 G90 G17 G64 P0.05\n{SQUARE}"));
    let d = 0.1 / std::f64::consts::FRAC_PI_4.sin();
    let expected = 3.0 * (2.0 + 10.0 / 150.0) - 2.0 * (2.0 * d / 150.0).sqrt();
    let t = duration(&rows);
    assert!(
        (t - expected).abs() < 1.5e-3,
        "{t} s, expected {expected} s"
    );
    assert!((tolerance_travel([20.0, 0.0, 0.0], [0.0, 20.0, 0.0], Some(0.05)) - d).abs() < 1e-12);
    assert_eq!(
        tolerance_travel([1.0, 0.0, 0.0], [2.0, 0.0, 0.0], Some(0.05)),
        f64::INFINITY
    );
    assert_eq!(
        tolerance_travel([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], None),
        f64::INFINITY
    );
}

/// `G1 X30 C60 F1200` runs at 15 mm/s (C at its 30 deg/s) slowing at 75 mm/s² (C at 150);
/// `G1 X60 C65` speeds X up at 150 mm/s² to 20. Started where the first slows down (as
/// LinuxCNC does) X would reach 25 mm/s; started `δ` later X peaks at `25 − 75 δ`, within
/// 20 from `δ = 1/15` s. So the two take `(30/15 + 15/75) + (30/20 + 20/150) − (0.2 − 1/15)`
/// = 3.7 s (3.633 s overlapped from where the first slows down), X exactly at its limit.
#[test]
fn an_overlap_waits_until_the_velocities_added_are_within_the_limit() {
    let rows = run("G21 G90 G17 G64\nG1 X30 C60 F1200\nG1 X60 C65\nM2\n");
    let expected = 2.2 + (1.5 + 20.0 / 150.0) - (0.2 - 1.0 / 15.0);
    let t = duration(&rows);
    assert!(
        (t - expected).abs() < 1.5e-3,
        "{t} s, expected {expected} s"
    );
    let (vx, _) = peaks(&rows, 0);
    assert!(
        vx <= 20.0 * (1.0 + 1e-9) && vx > 19.9,
        "X peaks at {vx} mm/s"
    );
}

/// F is the X Y Z speed when X Y Z move (LinuxCNC's rule): `G1 X20 C30 F600` runs X at
/// 10 mm/s and C at 15 deg/s, a last move at half the acceleration (C's 150 deg/s², 100 mm/s²
/// of X Y Z travel): `20/10 + 10/100` = 2.1 s (3.7 s with F as the speed of the X-C length).
#[test]
fn the_feed_is_the_x_y_z_speed_of_a_move_with_a_rotary_axis() {
    let rows = run("G21 G90 G17 G64\nG1 X20 C30 F600\nM2\n");
    let t = duration(&rows);
    assert!((t - 2.1).abs() < 1.5e-3, "{t} s, expected 2.1 s");
    let mid = (1.0 / PERIOD) as usize;
    let (vx, vc) = (velocity(&rows, mid, 0), velocity(&rows, mid, 4));
    assert!(
        (vx - 10.0).abs() < 1e-6 && (vc - 15.0).abs() < 1e-6,
        "X {vx}, C {vc}"
    );
}
