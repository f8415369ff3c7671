//! The interpolator against closed-form profiles and hand-computed geometry.

use std::f64::consts::PI;
use std::path::Path;

use mtsim::input::machine::Machine;
use mtsim::kinematics::{Branch, ToolPose, C_START_REFERENCE_DEG};
use mtsim::motion::interpolation::{InterpolationOptions, Interpolator, Setpoint};
use mtsim::program::{Feed, Motion, Move};
use mtsim::Plane;
use mtsim::{Axis, AxisVec, Result};
use nalgebra::{Point3, Rotation3, Vector3};

const PERIOD: f64 = 1e-3;

/// Limits of one axis: velocity units/min, acceleration units/s², jerk units/s³.
#[derive(Clone, Copy)]
struct Lim(f64, f64, f64);

fn machine(layout: &str, limits: &[(char, Lim)]) -> Machine {
    let mut text =
        format!("name = \"test\"\nkinematics = \"{layout}\"\ninterpolation_period_ms = 1.0\n");
    for (axis, Lim(v, a, j)) in limits {
        let continuous = if *axis == 'C' {
            "continuous = true\n"
        } else {
            ""
        };
        text += &format!(
            "[axes.{axis}]\nmin = -10000\nmax = 10000\n{continuous}max_velocity = {v}\nmax_acceleration = {a}\nmax_jerk = {j}\n"
        );
    }
    Machine::from_toml(Path::new("test.toml"), &text, None).expect("test machine is valid")
}

fn xyz_machine(lim: Lim) -> Machine {
    machine("xyz", &[('X', lim), ('Y', lim), ('Z', lim)])
}

fn ac_machine(linear: Lim, rotary: Lim) -> Machine {
    machine(
        "trt-ac",
        &[
            ('X', linear),
            ('Y', linear),
            ('Z', linear),
            ('A', rotary),
            ('C', rotary),
        ],
    )
}

fn q(values: &[f64]) -> AxisVec {
    let mut v = AxisVec::ZERO;
    v.0[..values.len()].copy_from_slice(values);
    v
}

fn block(line: usize, motion: Motion, start: AxisVec, end: AxisVec, feed: Option<f64>) -> Move {
    Move {
        line,
        motion,
        start,
        end,
        // `None`: a move without a feed (a rapid, a dwell, or a feed move made by hand).
        feed: feed.map_or(Feed::None, Feed::PerMinute),
        tcp: false,
        ..Move::default()
    }
}

fn g01(line: usize, start: AxisVec, end: AxisVec, feed: f64) -> Move {
    block(line, Motion::Linear, start, end, Some(feed))
}

/// A chain of G01 blocks through `points` with one feed per block.
fn chain(points: &[AxisVec], feeds: &[f64]) -> Vec<Move> {
    points
        .windows(2)
        .zip(feeds)
        .enumerate()
        .map(|(k, (w, &f))| g01(k + 1, w[0], w[1], f))
        .collect()
}

fn run_with(blocks: Vec<Move>, machine: &Machine, options: InterpolationOptions) -> Vec<Setpoint> {
    let interpolator =
        Interpolator::new(blocks.into_iter().map(Ok), machine, options).expect("program plans");
    interpolator
        .collect::<Result<Vec<_>>>()
        .expect("program runs")
}

fn run(blocks: Vec<Move>, machine: &Machine) -> Vec<Setpoint> {
    run_with(blocks, machine, InterpolationOptions::default())
}

/// Finite-difference velocity (units/s) of `axis` between setpoints n-1 and n.
fn velocity(s: &[Setpoint], n: usize, axis: Axis) -> f64 {
    (s[n].q[axis] - s[n - 1].q[axis]) / PERIOD
}

/// Time at which `axis` first crosses `level`, linearly interpolated between setpoints.
fn crossing_time(s: &[Setpoint], axis: Axis, level: f64) -> f64 {
    let n = s
        .iter()
        .position(|p| p.q[axis] >= level)
        .expect("level is reached");
    let (a, b) = (s[n - 1].q[axis], s[n].q[axis]);
    s[n - 1].time_s + PERIOD * (level - a) / (b - a)
}

/// Time of the first setpoint of each block, by block index.
fn block_starts(s: &[Setpoint]) -> Vec<f64> {
    let mut starts = vec![];
    for (n, p) in s.iter().enumerate() {
        if n == 0 || p.block_index != s[n - 1].block_index {
            assert_eq!(p.block_index as usize, starts.len(), "blocks run in order");
            starts.push(p.time_s);
        }
    }
    starts
}

fn assert_stream_shape(s: &[Setpoint], start: AxisVec, end: AxisVec) {
    assert_eq!(s[0].time_s, 0.0);
    assert_eq!(s[0].q, start, "first setpoint is the first block's start");
    for (n, p) in s.iter().enumerate() {
        assert!(
            (p.time_s - n as f64 * PERIOD).abs() < 1e-12,
            "setpoints one period apart"
        );
    }
    let last = s.last().unwrap();
    for axis in Axis::ALL {
        assert!(
            (last.q[axis] - end[axis]).abs() < 1e-9,
            "ends at the last end point"
        );
    }
    // At rest: the last period covers at most the tail of the final jerk phase.
    let before = s[s.len() - 2].q;
    assert!(
        (last.q - before).mixed_norm() / PERIOD < 0.05,
        "at rest at the end"
    );
}

#[test]
fn long_block_from_rest_to_rest_follows_the_closed_form_double_s_curve() {
    // 100 mm on X, vmax 50 mm/s, amax 200 mm/s², jmax 2000 mm/s³: every limit is reached
    // (vmax > amax²/jmax = 20 mm/s), so T = L/v + v/a + a/j = 2 + 0.25 + 0.1 = 2.35 s.
    let m = xyz_machine(Lim(3000.0, 200.0, 2000.0));
    let (a, b) = (q(&[0.0]), q(&[100.0]));
    let s = run(vec![g01(1, a, b, 6000.0)], &m);
    assert_stream_shape(&s, a, b);
    let expected_t = 100.0 / 50.0 + 50.0 / 200.0 + 200.0 / 2000.0;
    // The profile is point-symmetric, so the half-way crossing is at T/2.
    let t = 2.0 * crossing_time(&s, Axis::X, 50.0);
    assert!(
        (t - expected_t).abs() / expected_t < 1e-6,
        "T = {t} s, expected {expected_t} s"
    );
    // The first setpoint at the end point lies within one period after T.
    let arrival = s.iter().find(|p| p.q[Axis::X] == 100.0).unwrap().time_s;
    assert!(arrival >= expected_t - 1e-9 && arrival < expected_t + PERIOD + 1e-9);
    let peak = (1..s.len())
        .map(|n| velocity(&s, n, Axis::X))
        .fold(0.0, f64::max);
    assert!((peak - 50.0).abs() / 50.0 < 1e-9, "peak speed {peak} mm/s");
}

#[test]
fn short_block_peaks_below_vmax_at_the_closed_form_speed() {
    // vmax 1000 mm/s is out of reach in 100 mm with amax 200, jmax 2000. With the constant-
    // acceleration phase present, the peak v solves v²/a + v a/j = L:
    // v = (a/2) (-a/j + sqrt(a²/j² + 4L/a)) = 131.774 mm/s, and T = 2 (v/a + a/j).
    let (l, amax, jmax) = (100.0, 200.0, 2000.0);
    let m = xyz_machine(Lim(60000.0, amax, jmax));
    let s = run(vec![g01(1, q(&[0.0]), q(&[l]), 60000.0)], &m);
    let v = amax / 2.0 * (-amax / jmax + ((amax / jmax).powi(2) + 4.0 * l / amax).sqrt());
    assert!(v > amax * amax / jmax && v < 1000.0);
    let expected_t = 2.0 * (v / amax + amax / jmax);
    let t = 2.0 * crossing_time(&s, Axis::X, l / 2.0);
    assert!(
        (t - expected_t).abs() / expected_t < 1e-3,
        "T = {t} s, expected {expected_t} s"
    );
    let peak = (1..s.len())
        .map(|n| velocity(&s, n, Axis::X))
        .fold(0.0, f64::max);
    assert!(
        (peak - v).abs() / v < 1e-3,
        "peak {peak} mm/s, expected {v} mm/s"
    );
}

#[test]
fn sampled_acceleration_and_jerk_of_a_single_block_stay_within_the_limits() {
    let (amax, jmax) = (300.0, 4000.0);
    let m = xyz_machine(Lim(2400.0, amax, jmax));
    let s = run(
        vec![g01(1, q(&[0.0, 0.0, 0.0]), q(&[60.0, -30.0, 10.0]), 5000.0)],
        &m,
    );
    let mut peak_a: f64 = 0.0;
    for axis in Axis::LINEAR {
        for n in 3..s.len() {
            let x = |k: usize| s[k].q[axis];
            let acc = (x(n) - 2.0 * x(n - 1) + x(n - 2)) / PERIOD.powi(2);
            let jerk = (x(n) - 3.0 * x(n - 1) + 3.0 * x(n - 2) - x(n - 3)) / PERIOD.powi(3);
            assert!(
                acc.abs() <= amax * (1.0 + 1e-6),
                "{axis} acceleration {acc}"
            );
            assert!(jerk.abs() <= jmax * (1.0 + 1e-6), "{axis} jerk {jerk}");
            peak_a = peak_a.max(acc.abs());
        }
    }
    // X travels most, so X reaches the acceleration limit.
    assert!(peak_a > 0.99 * amax, "peak acceleration {peak_a}");
}

#[test]
fn a_block_too_fast_for_an_axis_is_slowed_to_exactly_that_axis_limit() {
    // F 6000 mm/min on (300, 100) would drive X at 6000·300/316.2 = 5692 mm/min > 3000.
    let m = machine(
        "xyz",
        &[
            ('X', Lim(3000.0, 500.0, 5000.0)),
            ('Y', Lim(20000.0, 500.0, 5000.0)),
            ('Z', Lim(20000.0, 500.0, 5000.0)),
        ],
    );
    let s = run(vec![g01(1, q(&[0.0, 0.0]), q(&[300.0, 100.0]), 6000.0)], &m);
    let peak_x = (1..s.len())
        .map(|n| velocity(&s, n, Axis::X))
        .fold(0.0, f64::max)
        * 60.0;
    let peak_y = (1..s.len())
        .map(|n| velocity(&s, n, Axis::Y))
        .fold(0.0, f64::max)
        * 60.0;
    assert!((peak_x - 3000.0).abs() < 1e-6, "X peak {peak_x} mm/min");
    assert!((peak_y - 1000.0).abs() < 1e-6, "Y peak {peak_y} mm/min");
}

#[test]
fn a_chain_within_all_limits_runs_every_block_at_its_programmed_feed() {
    // A gentle polyline whose F words change a little from block to block, like the
    // cone-frustum program: the interior blocks take exactly L/F.
    let m = xyz_machine(Lim(10000.0, 2000.0, 50000.0));
    let points: Vec<AxisVec> = (0..=40)
        .map(|k| {
            let k = k as f64;
            q(&[2.0 * k, 0.1 * (0.3 * k).sin(), 0.05 * k])
        })
        .collect();
    let feeds: Vec<f64> = (0..40)
        .map(|k| 1000.0 + 20.0 * (0.2 * k as f64).cos())
        .collect();
    let s = run(chain(&points, &feeds), &m);
    let starts = block_starts(&s);
    assert_eq!(starts.len(), 40);
    let (mut measured, mut programmed) = (0.0, 0.0);
    for k in 2..38 {
        let t = (points[k + 1] - points[k]).mixed_norm() / feeds[k] * 60.0;
        let dt = starts[k + 1] - starts[k];
        assert!(
            (dt - t).abs() <= PERIOD + 1e-9,
            "block {k}: {dt} s, programmed {t} s"
        );
        measured += dt;
        programmed += t;
    }
    assert!(
        (measured - programmed).abs() <= 2.0 * PERIOD,
        "{measured} vs {programmed}"
    );
    // Velocity between setpoints in the same interior block is F · d / |d|.
    for n in 1..s.len() {
        let k = s[n].block_index as usize;
        if s[n - 1].block_index as usize != k || !(2..38).contains(&k) {
            continue;
        }
        let d = points[k + 1] - points[k];
        for axis in Axis::LINEAR {
            let expected = feeds[k] / 60.0 * d[axis] / d.mixed_norm();
            assert!(
                (velocity(&s, n, axis) - expected).abs() < 1e-6,
                "block {k} axis {axis}"
            );
        }
    }
}

/// The cone-frustum program of the spec (15/10, centre (0, 0, 200), L = 100, F = 1000):
/// one G01 per degree with the mixed-unit F words. Returns the blocks and their
/// programmed times, s.
fn cone_frustum_program(m: &Machine, alpha_deg: f64, beta_deg: f64) -> (Vec<Move>, Vec<f64>) {
    let (alpha, beta, len, feed) = (alpha_deg.to_radians(), beta_deg.to_radians(), 100.0, 1000.0);
    let origin = Vector3::new(0.0, 0.0, 200.0);
    let tilt = Rotation3::from_axis_angle(&Vector3::y_axis(), -beta);
    let (r, h) = (len * alpha.cos(), len * alpha.sin());
    let apex = origin + tilt * Vector3::new(0.0, 0.0, len / alpha.sin());
    let point = |theta: f64| origin + tilt * Vector3::new(r * theta.cos(), r * theta.sin(), h);
    let mut c_prev = C_START_REFERENCE_DEG;
    let mut axes = vec![];
    for k in 0..=360 {
        let p = point((k as f64).to_radians());
        let pose = ToolPose {
            tip: Point3::from(p),
            axis: (apex - p).normalize(),
        };
        let qk = m.kinematics.inverse(&pose, Branch::Primary, c_prev);
        c_prev = qk[Axis::C];
        axes.push((qk, p));
    }
    let mut blocks = vec![];
    let mut times = vec![];
    for k in 0..360 {
        let ((q0, p0), (q1, p1)) = (axes[k], axes[k + 1]);
        let dt_min = (p1 - p0).norm() / feed;
        blocks.push(g01(k + 1, q0, q1, (q1 - q0).mixed_norm() / dt_min));
        times.push(dt_min * 60.0);
    }
    (blocks, times)
}

#[test]
fn cone_frustum_program_runs_at_the_programmed_feed_between_the_ramps() {
    // No axis limit binds: peak speeds are 2732 mm/min and 2214 deg/min (spec), and the
    // largest velocity step at a junction is 1.62 mm/s (X, 45/30) < 2000 mm/s² · 1 ms.
    let m = ac_machine(Lim(10000.0, 2000.0, 50000.0), Lim(10000.0, 2000.0, 50000.0));
    for (alpha, beta) in [(15.0, 10.0), (45.0, 30.0)] {
        let (blocks, times) = cone_frustum_program(&m, alpha, beta);
        let s = run(blocks.clone(), &m);
        assert_stream_shape(&s, blocks[0].start, blocks[359].end);
        let starts = block_starts(&s);
        assert_eq!(starts.len(), 360);
        for k in 1..359 {
            let dt = starts[k + 1] - starts[k];
            assert!(
                (dt - times[k]).abs() <= PERIOD + 1e-9,
                "block {k}: {dt} s, programmed {}",
                times[k]
            );
        }
        let programmed: f64 = times[1..359].iter().sum();
        assert!((starts[359] - starts[1] - programmed).abs() <= 2.0 * PERIOD);
        // Inside every interior block each axis moves at exactly F_k · d_k / L_k.
        for n in 1..s.len() {
            let k = s[n].block_index as usize;
            if s[n - 1].block_index as usize != k || !(1..359).contains(&k) {
                continue;
            }
            let b = &blocks[k];
            let d = b.end - b.start;
            for axis in [Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::C] {
                let expected = b.feed.rate().unwrap() / 60.0 * d[axis] / d.mixed_norm();
                assert!(
                    (velocity(&s, n, axis) - expected).abs() < 1e-6 * (1.0 + expected.abs()),
                    "block {k} axis {axis}"
                );
            }
        }
        // Whole program: 360 one-degree chords at 1000 mm/min plus short start and stop ramps.
        let total: f64 = times.iter().sum();
        let end = s.last().unwrap().time_s;
        assert!(
            end > total && end < total + 0.2,
            "program time {end} s, chords at F take {total} s"
        );
    }
}

#[test]
fn inverse_time_blocks_take_one_over_f_minutes() {
    let m = xyz_machine(Lim(10000.0, 1000.0, 20000.0));
    let points: Vec<AxisVec> = (0..=5).map(|k| q(&[10.0 * k as f64, 0.0])).collect();
    // F 60 /min: 1 s per 10 mm block (10 mm/s, the same speed on every block).
    let blocks: Vec<Move> = chain(&points, &[60.0; 5])
        .into_iter()
        .map(|b| Move {
            feed: Feed::InverseTime(60.0),
            ..b
        })
        .collect();
    let starts = block_starts(&run(blocks, &m));
    for k in 1..4 {
        assert!(
            (starts[k + 1] - starts[k] - 1.0).abs() <= PERIOD + 1e-9,
            "block {k}"
        );
    }
}

#[test]
fn rapid_moves_every_axis_at_its_limit_and_all_axes_arrive_together() {
    // X 200 mm at 6000 mm/min (100 mm/s) needs 2 s; Y 50 mm at 3000 mm/min needs 1 s.
    // So the path speed is L/2 s, X runs at 100 mm/s and Y at 25 mm/s.
    let (ax, ay, j) = (1000.0, 400.0, 20000.0);
    let m = machine(
        "xyz",
        &[
            ('X', Lim(6000.0, ax, j)),
            ('Y', Lim(3000.0, ay, j)),
            ('Z', Lim(3000.0, ay, j)),
        ],
    );
    let (a, b) = (q(&[0.0, 0.0]), q(&[200.0, 50.0]));
    let s = run(vec![block(1, Motion::Rapid, a, b, None)], &m);
    assert_stream_shape(&s, a, b);
    let l = (200f64).hypot(50.0);
    let v = l / 2.0;
    // Path limits: a_path = min(1000·L/200, 400·L/50) and the same for jerk.
    let ap = (ax * l / 200.0).min(ay * l / 50.0);
    let jp = (j * l / 200.0).min(j * l / 50.0);
    assert!(v > ap * ap / jp);
    let expected_t = l / v + v / ap + ap / jp;
    let t = 2.0 * crossing_time(&s, Axis::X, 100.0);
    assert!(
        (t - expected_t).abs() < 1e-6,
        "T = {t} s, expected {expected_t}"
    );
    let vx = (1..s.len())
        .map(|n| velocity(&s, n, Axis::X))
        .fold(0.0, f64::max);
    let vy = (1..s.len())
        .map(|n| velocity(&s, n, Axis::Y))
        .fold(0.0, f64::max);
    assert!(
        (vx - 100.0).abs() < 1e-6 && (vy - 25.0).abs() < 1e-6,
        "vx {vx} vy {vy}"
    );
}

#[test]
fn arc_setpoints_lie_on_the_circle_and_the_arc_takes_its_length_over_f() {
    // Line, tangent quarter arc G03 of radius 20 about (40, 20), line: at F 1200 mm/min the
    // arc takes (π/2 · 20) / 20 mm/s = π/2 s.
    let m = xyz_machine(Lim(10000.0, 2000.0, 50000.0));
    let (p0, p1, p2, p3) = (
        q(&[0.0, 0.0]),
        q(&[40.0, 0.0]),
        q(&[60.0, 20.0]),
        q(&[60.0, 60.0]),
    );
    let arc = Motion::Arc {
        clockwise: false,
        plane: Plane::XY,
        center_mm: [40.0, 20.0, 0.0],
    };
    let blocks = vec![
        g01(1, p0, p1, 1200.0),
        block(2, arc, p1, p2, Some(1200.0)),
        g01(3, p2, p3, 1200.0),
    ];
    let s = run(blocks, &m);
    let starts = block_starts(&s);
    let arc_time = (starts[2] - starts[1] - PI / 2.0).abs();
    assert!(arc_time <= PERIOD + 1e-9, "arc time off by {arc_time} s");
    for p in s.iter().filter(|p| p.block_index == 1) {
        let r = (p.q[Axis::X] - 40.0).hypot(p.q[Axis::Y] - 20.0);
        assert!((r - 20.0).abs() < 1e-9, "radius {r}");
        assert!(
            p.q[Axis::X] >= 40.0 - 1e-9 && p.q[Axis::Y] <= 20.0 + 1e-9,
            "stays in the quarter"
        );
    }
    // Tangent speed on the arc is the feed.
    for n in 1..s.len() {
        if s[n].block_index == 1 && s[n - 1].block_index == 1 {
            let v = velocity(&s, n, Axis::X).hypot(velocity(&s, n, Axis::Y));
            assert!((v - 20.0).abs() < 1e-3, "arc speed {v} mm/s");
        }
    }
}

#[test]
fn full_clockwise_helix_in_the_yz_plane_stays_on_its_cylinder() {
    // G19 G02 full circle of radius 10 about (Y, Z) = (0, 0) while X climbs 5 mm.
    let m = xyz_machine(Lim(10000.0, 2000.0, 50000.0));
    let (a, b) = (q(&[0.0, 10.0, 0.0]), q(&[5.0, 10.0, 0.0]));
    let arc = Motion::Arc {
        clockwise: true,
        plane: Plane::YZ,
        center_mm: [0.0, 0.0, 0.0],
    };
    let s = run(vec![block(1, arc, a, b, Some(600.0))], &m);
    assert_stream_shape(&s, a, b);
    for p in &s {
        let (y, z, x) = (p.q[Axis::Y], p.q[Axis::Z], p.q[Axis::X]);
        assert!((y.hypot(z) - 10.0).abs() < 1e-9);
        // Clockwise seen from +X: angle from +Y toward +Z decreases; X rises with the turn.
        let turned = (-z.atan2(y)).rem_euclid(2.0 * PI);
        if x > 1e-6 && x < 5.0 - 1e-6 {
            assert!(
                (turned / (2.0 * PI) * 5.0 - x).abs() < 1e-6,
                "x {x} at turn {turned}"
            );
        }
    }
    let went_negative_z = s.iter().any(|p| p.q[Axis::Z] < -9.0);
    assert!(
        went_negative_z,
        "a clockwise turn about +X from +Y goes through -Z first"
    );
    assert!(s[10].q[Axis::Z] < 0.0);
}

/// Tool tip in the table frame for a trt-ac machine with the pivot at 0, written out:
/// tip = Rz(-C) Rx(-A) (X, Y, Z).
fn tip_in_table(q: &AxisVec) -> Vector3<f64> {
    let (a, c) = (q[Axis::A].to_radians(), q[Axis::C].to_radians());
    let (x, y, z) = (q[Axis::X], q[Axis::Y], q[Axis::Z]);
    let (y1, z1) = (y * a.cos() + z * a.sin(), -y * a.sin() + z * a.cos());
    Vector3::new(x * c.cos() + y1 * c.sin(), -x * c.sin() + y1 * c.cos(), z1)
}

fn distance_to_line(p: Vector3<f64>, a: Vector3<f64>, b: Vector3<f64>) -> f64 {
    let d = (b - a).normalize();
    let v = p - a;
    (v - d * v.dot(&d)).norm()
}

#[test]
fn tcp_keeps_the_tool_tip_on_the_chord_where_joint_interpolation_leaves_it() {
    let m = ac_machine(Lim(20000.0, 2000.0, 50000.0), Lim(20000.0, 2000.0, 50000.0));
    // Table turns C 0 → 90 deg with the tip at (100, 0, 0) on the table.
    // Joint mode: the machine goes straight from (100, 0, 0) to (0, 100, 0); half way it is
    // at (50, 50, 0) with C = 45, i.e. at Rz(-45)(50, 50, 0) = (70.711, 0, 0) on the table,
    // 100 (1 - 1/sqrt 2) = 29.289 mm from the programmed point.
    let joint = g01(
        1,
        q(&[100.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        q(&[0.0, 100.0, 0.0, 0.0, 0.0, 90.0]),
        3000.0,
    );
    let s = run(vec![joint], &m);
    let target = Vector3::new(100.0, 0.0, 0.0);
    let mid = s
        .iter()
        .min_by(|a, b| {
            (a.q[Axis::C] - 45.0)
                .abs()
                .total_cmp(&(b.q[Axis::C] - 45.0).abs())
        })
        .unwrap();
    let u = mid.q[Axis::C] / 90.0;
    let c = mid.q[Axis::C].to_radians();
    // By hand: machine (100(1-u), 100u, 0) turned back by C.
    let by_hand = Vector3::new(
        100.0 * (1.0 - u) * c.cos() + 100.0 * u * c.sin(),
        -100.0 * (1.0 - u) * c.sin() + 100.0 * u * c.cos(),
        0.0,
    );
    assert!((tip_in_table(&mid.q) - by_hand).norm() < 1e-9);
    let deviation = (tip_in_table(&mid.q) - target).norm();
    assert!(
        (deviation - 100.0 * (1.0 - 0.5f64.sqrt())).abs() < 0.05,
        "joint deviation {deviation} mm"
    );

    // TCP mode: the same move keeps the tip at (100, 0, 0) on the table.
    let tcp = Move {
        tcp: true,
        ..g01(
            1,
            q(&[100.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
            q(&[100.0, 0.0, 0.0, 0.0, 0.0, 90.0]),
            3000.0,
        )
    };
    let s = run(vec![tcp], &m);
    assert!((s.last().unwrap().q - q(&[0.0, 100.0, 0.0, 0.0, 0.0, 90.0])).mixed_norm() < 1e-9);
    for p in &s {
        assert!((tip_in_table(&p.q) - target).norm() < 1e-9);
    }

    // A general move: tip (100, 0, 0) → (100, 20, 10) on the table while A 0 → 30, C 0 → 90.
    let (t0, t1) = (
        Vector3::new(100.0, 0.0, 0.0),
        Vector3::new(100.0, 20.0, 10.0),
    );
    let tcp = Move {
        tcp: true,
        ..g01(
            1,
            q(&[100.0, 0.0, 0.0, 30.0 * 0.0, 0.0, 0.0]),
            q(&[100.0, 20.0, 10.0, 30.0, 0.0, 90.0]),
            1200.0,
        )
    };
    let s = run(vec![tcp], &m);
    let tcp_worst = s
        .iter()
        .map(|p| distance_to_line(tip_in_table(&p.q), t0, t1))
        .fold(0.0, f64::max);
    assert!(tcp_worst < 1e-9, "TCP deviation {tcp_worst} mm");
    // The tip advances in proportion to the rotary axes, at F along the chord.
    for p in &s {
        let progress = (tip_in_table(&p.q) - t0).norm() / (t1 - t0).norm();
        assert!((progress - p.q[Axis::C] / 90.0).abs() < 1e-9);
    }
    // Joint mode between the same end points (machine coordinates by hand):
    // end = Rx(30) Rz(90) (100, 20, 10) = Rx(30) (-20, 100, 10).
    let a = 30f64.to_radians();
    let end = q(&[
        -20.0,
        100.0 * a.cos() - 10.0 * a.sin(),
        100.0 * a.sin() + 10.0 * a.cos(),
        30.0,
        0.0,
        90.0,
    ]);
    let s = run(vec![g01(1, q(&[100.0, 0.0, 0.0]), end, 1200.0)], &m);
    assert!((tip_in_table(&s.last().unwrap().q) - t1).norm() < 1e-9);
    let joint_worst = s
        .iter()
        .map(|p| distance_to_line(tip_in_table(&p.q), t0, t1))
        .fold(0.0, f64::max);
    assert!(joint_worst > 10.0, "joint deviation {joint_worst} mm");
}

#[test]
fn no_sampled_axis_velocity_or_acceleration_exceeds_the_limits_over_a_mixed_program() {
    let (vmax, amax, jmax) = (4800.0, 800.0, 20000.0);
    let m = xyz_machine(Lim(vmax, amax, jmax));
    let p = |x: f64, y: f64, z: f64| q(&[x, y, z]);
    let arc = |cw, c: [f64; 3]| Motion::Arc {
        clockwise: cw,
        plane: Plane::XY,
        center_mm: c,
    };
    let blocks = vec![
        block(
            1,
            Motion::Rapid,
            p(50.0, 50.0, 20.0),
            p(0.0, 0.0, 2.0),
            None,
        ),
        g01(2, p(0.0, 0.0, 2.0), p(0.0, 0.0, 0.0), 300.0),
        g01(3, p(0.0, 0.0, 0.0), p(40.0, 0.0, 0.0), 9000.0),
        g01(4, p(40.0, 0.0, 0.0), p(40.0, 40.0, 0.0), 9000.0),
        block(
            5,
            arc(false, [20.0, 40.0, 0.0]),
            p(40.0, 40.0, 0.0),
            p(0.0, 40.0, 0.0),
            Some(9000.0),
        ),
        block(
            6,
            arc(true, [0.0, 45.0, 0.0]),
            p(0.0, 40.0, 0.0),
            p(0.0, 50.0, -1.0),
            Some(3000.0),
        ),
        g01(7, p(0.0, 50.0, -1.0), p(10.0, 51.0, -1.0), 6000.0),
        g01(8, p(10.0, 51.0, -1.0), p(0.0, 0.0, 0.0), 6000.0),
        block(9, Motion::Rapid, p(0.0, 0.0, 0.0), p(0.0, 0.0, 30.0), None),
    ];
    let s = run(blocks, &m);
    assert_stream_shape(&s, p(50.0, 50.0, 20.0), p(0.0, 0.0, 30.0));
    let (mut worst_v, mut worst_a): (f64, f64) = (0.0, 0.0);
    for axis in Axis::LINEAR {
        for n in 2..s.len() {
            let v = velocity(&s, n, axis).abs() * 60.0;
            let a = (velocity(&s, n, axis) - velocity(&s, n - 1, axis)).abs() / PERIOD;
            worst_v = worst_v.max(v / vmax);
            worst_a = worst_a.max(a / amax);
        }
    }
    assert!(
        worst_v <= 1.0 + 1e-9,
        "velocity reaches {worst_v} × the limit"
    );
    println!("worst sampled velocity {worst_v}, acceleration {worst_a} (fractions of the limits)");
    assert!(
        worst_a <= 1.05,
        "acceleration reaches {worst_a} × the limit"
    );
    assert!(
        worst_v > 0.99,
        "the program does reach the velocity limit ({worst_v})"
    );
}

#[test]
fn a_sharp_corner_is_passed_slowly_and_a_collinear_junction_at_full_speed() {
    let m = xyz_machine(Lim(10000.0, 1000.0, 20000.0));
    let corner = run(
        chain(
            &[q(&[0.0, 0.0]), q(&[50.0, 0.0]), q(&[50.0, 50.0])],
            &[3000.0, 3000.0],
        ),
        &m,
    );
    let straight = run(
        chain(
            &[q(&[0.0, 0.0]), q(&[50.0, 0.0]), q(&[100.0, 0.0])],
            &[3000.0, 3000.0],
        ),
        &m,
    );
    let speed_at_junction = |s: &[Setpoint]| {
        let n = s.iter().position(|p| p.block_index == 1).unwrap();
        velocity(s, n, Axis::X).hypot(velocity(s, n, Axis::Y))
    };
    // At 90 deg X drops and Y rises by the path speed v, each by at most
    // 1000 mm/s² · 1 ms, so v <= 1 mm/s; a setpoint step straddling the corner sees at most
    // sqrt(2) of that.
    let v = speed_at_junction(&corner);
    assert!(
        v <= 1000.0 * PERIOD * 2f64.sqrt() * 1.01,
        "corner speed {v} mm/s"
    );
    assert!(v > 0.5 * 1000.0 * PERIOD, "but it does not stop: {v} mm/s");
    let v = speed_at_junction(&straight);
    assert!((v - 50.0).abs() < 1e-9, "collinear junction speed {v} mm/s");
}

#[test]
fn dwell_holds_the_position_for_its_time() {
    let m = xyz_machine(Lim(10000.0, 1000.0, 20000.0));
    let (a, b, c) = (q(&[0.0]), q(&[10.0]), q(&[20.0]));
    let blocks = vec![
        g01(1, a, b, 600.0),
        block(2, Motion::Dwell { seconds: 1.5 }, b, b, None),
        g01(3, b, c, 600.0),
    ];
    let s = run(blocks, &m);
    let held: Vec<&Setpoint> = s.iter().filter(|p| p.q[Axis::X] == 10.0).collect();
    let held_time = held.last().unwrap().time_s - held[0].time_s;
    assert!(
        (held_time - 1.5).abs() <= PERIOD + 1e-9,
        "held for {held_time} s"
    );
    assert!(held.iter().any(|p| p.line == 2));
}

#[test]
fn a_short_lookahead_still_stops_at_the_end_and_keeps_the_limits() {
    let (amax, jmax) = (500.0, 10000.0);
    let m = xyz_machine(Lim(20000.0, amax, jmax));
    let points: Vec<AxisVec> = (0..=50).map(|k| q(&[k as f64, 0.0])).collect();
    let options = InterpolationOptions {
        lookahead_blocks: 2,
        ..InterpolationOptions::default()
    };
    let s = run_with(chain(&points, &[20000.0; 50]), &m, options);
    assert_stream_shape(&s, points[0], points[50]);
    for n in 2..s.len() {
        let a = (velocity(&s, n, Axis::X) - velocity(&s, n - 1, Axis::X)) / PERIOD;
        assert!(a.abs() <= amax * 1.05, "acceleration {a}");
    }
}

#[test]
fn an_empty_program_gives_no_setpoints() {
    let m = xyz_machine(Lim(10000.0, 1000.0, 20000.0));
    assert!(run(vec![], &m).is_empty());
}

fn first_error(blocks: Vec<Move>, options: InterpolationOptions) -> String {
    let m = xyz_machine(Lim(10000.0, 1000.0, 20000.0));
    match Interpolator::new(blocks.into_iter().map(Ok), &m, options) {
        Err(e) => e.to_string(),
        Ok(mut it) => it.find_map(|r| r.err()).expect("an error").to_string(),
    }
}

#[test]
fn a_move_without_feed_is_an_error_that_names_its_line() {
    let (a, b) = (q(&[0.0]), q(&[10.0]));
    let message = first_error(
        vec![block(7, Motion::Linear, a, b, None)],
        InterpolationOptions::default(),
    );
    assert!(
        message.contains("line 7") && message.contains("F word"),
        "{message}"
    );
    let message = first_error(vec![g01(3, a, b, 0.0)], InterpolationOptions::default());
    assert!(message.contains("line 3"), "{message}");
    // The reader refuses a G93 move without F; an inverse-time F of zero is refused here.
    let inverse = Move {
        feed: Feed::InverseTime(0.0),
        ..block(4, Motion::Linear, a, b, None)
    };
    let message = first_error(vec![inverse], InterpolationOptions::default());
    assert!(
        message.contains("line 4") && message.contains("G93"),
        "{message}"
    );
}

#[test]
fn non_finite_values_and_missing_axes_are_errors() {
    let a = q(&[0.0]);
    let message = first_error(
        vec![g01(2, a, q(&[f64::NAN]), 100.0)],
        InterpolationOptions::default(),
    );
    assert!(
        message.contains("line 2") && message.contains("finite"),
        "{message}"
    );
    let message = first_error(
        vec![g01(5, a, q(&[1.0, 0.0, 0.0, 10.0]), 100.0)],
        InterpolationOptions::default(),
    );
    assert!(
        message.contains("line 5") && message.contains("axis A"),
        "{message}"
    );
    let message = first_error(
        vec![
            g01(6, a, a, 100.0),
            block(
                9,
                Motion::Dwell {
                    seconds: f64::INFINITY,
                },
                a,
                a,
                None,
            ),
        ],
        InterpolationOptions::default(),
    );
    assert!(message.contains("line 9"), "{message}");
}

#[test]
fn an_error_beyond_the_lookahead_window_arrives_in_the_stream() {
    let mut points: Vec<AxisVec> = (0..=10).map(|k| q(&[k as f64])).collect();
    points.push(q(&[f64::INFINITY]));
    let blocks = chain(&points, &[600.0; 11]);
    let options = InterpolationOptions {
        lookahead_blocks: 2,
        ..InterpolationOptions::default()
    };
    let m = xyz_machine(Lim(10000.0, 1000.0, 20000.0));
    let mut it = Interpolator::new(blocks.into_iter().map(Ok), &m, options)
        .expect("the first blocks are fine");
    let error = it.find_map(|r| r.err()).expect("the bad block is reported");
    assert!(error.to_string().contains("line 11"), "{error}");
    assert!(it.next().is_none(), "the stream ends after an error");
}

#[test]
fn an_arc_whose_end_is_off_the_circle_is_an_error() {
    let arc = Motion::Arc {
        clockwise: false,
        plane: Plane::XY,
        center_mm: [0.0, 0.0, 0.0],
    };
    let message = first_error(
        vec![block(
            12,
            arc,
            q(&[10.0, 0.0]),
            q(&[0.0, 11.0]),
            Some(100.0),
        )],
        InterpolationOptions::default(),
    );
    assert!(
        message.contains("line 12") && message.contains("radius"),
        "{message}"
    );
}

/// An X-only machine (vmax 6000 mm/min, amax 200 mm/s², jmax 2000 mm/s³) whose control
/// looks `lookahead` blocks ahead, or the default when `None`.
fn machine_looking_ahead(lookahead: Option<usize>) -> Result<Machine> {
    let control = lookahead.map_or(String::new(), |n| {
        format!("[control]\nlookahead_blocks = {n}\n")
    });
    let text = format!(
        "name = \"test\"\nkinematics = \"xyz\"\ninterpolation_period_ms = 1.0\n{control}\
         [axes.X]\nmin = -10000\nmax = 10000\nmax_velocity = 6000\nmax_acceleration = 200\nmax_jerk = 2000\n\
         [axes.Y]\nmin = -10\nmax = 10\nmax_velocity = 6000\nmax_acceleration = 200\nmax_jerk = 2000\n\
         [axes.Z]\nmin = -10\nmax = 10\nmax_velocity = 6000\nmax_acceleration = 200\nmax_jerk = 2000\n"
    );
    Machine::from_toml(Path::new("test.toml"), &text, None)
}

/// The highest X speed of a run, mm/s (finite differences of the setpoints).
fn peak_x_speed(s: &[Setpoint]) -> f64 {
    (1..s.len())
        .map(|n| velocity(s, n, Axis::X))
        .fold(0.0, f64::max)
}

#[test]
fn the_controls_lookahead_depth_caps_the_speed_on_tiny_blocks() {
    // 2,000 collinear blocks of 0.1 mm at F6000 (100 mm/s). A planner that looks W blocks
    // ahead holds at most 1.5 W + 1 planned blocks beyond the one running, and the machine
    // must be able to stop within them: the fastest stop from v (at rest acceleration, jerk
    // j, acceleration a, v ≥ a²/j = 20 mm/s) takes S(v) = v (v/a + a/j) / 2. With W = 16,
    // S(v) ≤ (1.5·16 + 2) · 0.1 mm = 2.6 mm gives v² + 20 v − 1040 ≤ 0:
    // v ≤ −10 + √1140 = 23.76 mm/s, whatever the planner's own margins.
    let points: Vec<AxisVec> = (0..=2000).map(|k| q(&[0.1 * k as f64])).collect();
    let program = || chain(&points, &[6000.0; 2000]);
    let cap = -10.0 + 1140f64.sqrt();

    let shallow = machine_looking_ahead(Some(16)).expect("valid machine");
    let options = InterpolationOptions::for_machine(&shallow);
    assert_eq!(options.lookahead_blocks, 16);
    let s_shallow = run_with(program(), &shallow, options);
    assert_stream_shape(&s_shallow, points[0], points[2000]);
    let v_shallow = peak_x_speed(&s_shallow);
    assert!(
        v_shallow <= cap,
        "16 blocks ahead: {v_shallow} mm/s > {cap} mm/s"
    );

    // A control that sees the whole program is not held by the window: it goes past what
    // 16 blocks could ever allow, and finishes sooner.
    let deep = machine_looking_ahead(Some(4000)).expect("valid machine");
    let s_deep = run_with(program(), &deep, InterpolationOptions::for_machine(&deep));
    assert_stream_shape(&s_deep, points[0], points[2000]);
    let v_deep = peak_x_speed(&s_deep);
    assert!(v_deep > cap, "4,000 blocks ahead: only {v_deep} mm/s");
    let end = |s: &[Setpoint]| s.last().unwrap().time_s;
    assert!(end(&s_deep) < end(&s_shallow));

    // Without the key, the default depth (256 blocks).
    let default = machine_looking_ahead(None).expect("valid machine");
    assert_eq!(
        InterpolationOptions::for_machine(&default).lookahead_blocks,
        256
    );
}

#[test]
fn a_lookahead_depth_out_of_range_names_its_line() {
    for n in [0, 10_001] {
        let message = match machine_looking_ahead(Some(n)) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("lookahead_blocks = {n} was taken"),
        };
        assert!(
            message.contains("test.toml:5:") && message.contains("lookahead_blocks"),
            "{message}"
        );
        assert!(message.contains("[1, 10000]"), "{message}");
    }
}
