//! The feed held to the machine (issue 9 item 12): the interpolator lowers the feed so that
//! no axis exceeds its velocity or acceleration limit, and says which axis held it, against
//! closed forms. Also the path-control modes G61, G61.1 and G64 P at a corner.

use crate::common;

use std::path::Path;

use mtsim::input::machine::Machine;
use mtsim::motion::interpolation::{
    FeedLimit, InterpolationOptions, Interpolator, LimitKind, Setpoint,
};
use mtsim::program::{Feed, Motion, Move, PathControl};
use mtsim::{Axis, AxisVec, Plane};

const PERIOD: f64 = 1e-3;

/// A trt-ac machine with max velocities (units/min) and accelerations (units/s²) per axis
/// X Y Z A C; jerk high enough not to matter at cruise.
fn machine(velocity: [f64; 5], acceleration: [f64; 5]) -> Machine {
    let mut text =
        "name = \"test\"\nkinematics = \"trt-ac\"\ninterpolation_period_ms = 1.0\n".to_string();
    for (k, axis) in ["X", "Y", "Z", "A", "C"].iter().enumerate() {
        let continuous = if *axis == "C" {
            "continuous = true\n"
        } else {
            ""
        };
        text += &format!(
            "[axes.{axis}]\nmin = -10000\nmax = 10000\n{continuous}max_velocity = {}\nmax_acceleration = {}\nmax_jerk = 1e7\n",
            velocity[k], acceleration[k]
        );
    }
    Machine::from_toml(Path::new("test.toml"), &text, None).expect("test machine is valid")
}

fn q(values: &[f64]) -> AxisVec {
    let mut v = AxisVec::ZERO;
    v.0[..values.len()].copy_from_slice(values);
    v
}

fn g01(line: usize, start: AxisVec, end: AxisVec, feed: f64) -> Move {
    Move {
        line,
        motion: Motion::Linear,
        start,
        end,
        feed: Feed::PerMinute(feed),
        ..Move::default()
    }
}

/// Setpoints and the feed limits noted.
fn run(blocks: Vec<Move>, machine: &Machine) -> (Vec<Setpoint>, Vec<FeedLimit>) {
    let options = InterpolationOptions {
        record_feed_limits: true,
        ..InterpolationOptions::default()
    };
    let mut it = Interpolator::new(blocks.into_iter().map(Ok), machine, options).unwrap();
    let mut setpoints = vec![];
    let mut limits = vec![];
    while let Some(s) = it.next() {
        setpoints.push(s.unwrap());
        limits.extend(it.take_feed_limits());
    }
    (setpoints, limits)
}

/// Largest finite-difference speed of `axis`, units/s.
fn peak_speed(s: &[Setpoint], axis: Axis) -> f64 {
    s.windows(2)
        .map(|w| ((w[1].q[axis] - w[0].q[axis]) / PERIOD).abs())
        .fold(0.0, f64::max)
}

const FAST: [f64; 5] = [30000.0, 30000.0, 30000.0, 5400.0, 9000.0];
const ACCEL: [f64; 5] = [3000.0, 3000.0, 3000.0, 3600.0, 7200.0];

/// A pure C move at F 20 000 (deg counted as mm) on a 9 000 deg/min axis runs at exactly
/// 9 000 deg/min = 150 deg/s, and the block is reported as held by C's velocity.
#[test]
fn a_pure_rotary_move_runs_at_exactly_the_axis_maximum() {
    let m = machine(FAST, ACCEL);
    let (s, limits) = run(
        vec![g01(
            5,
            q(&[0.0; 5]),
            q(&[0.0, 0.0, 0.0, 0.0, 0.0, 270.0]),
            20000.0,
        )],
        &m,
    );
    let peak = peak_speed(&s, Axis::C);
    assert!((peak - 150.0).abs() < 1e-9, "C peak {peak} deg/s");
    assert_eq!(limits.len(), 1);
    let l = limits[0];
    assert_eq!((l.line, l.axis, l.limit), (5, Axis::C, LimitKind::Velocity));
    assert!((l.programmed_per_min - 20000.0).abs() < 1e-9);
    assert!((l.planned_per_min - 9000.0).abs() < 1e-9, "{l:?}");
}

/// A 45° diagonal X/Y at F 20 000 with Y limited to 6 000 mm/min: Y runs at its maximum,
/// X at the same speed, the path at 6 000 √2 mm/min.
#[test]
fn a_diagonal_move_is_held_by_the_slower_axis() {
    let mut v = FAST;
    v[1] = 6000.0;
    let m = machine(v, ACCEL);
    let (s, limits) = run(vec![g01(3, q(&[0.0; 5]), q(&[200.0, 200.0]), 20000.0)], &m);
    assert!((peak_speed(&s, Axis::Y) - 100.0).abs() < 1e-9);
    assert!((peak_speed(&s, Axis::X) - 100.0).abs() < 1e-9);
    assert_eq!(limits.len(), 1);
    assert_eq!(
        (limits[0].axis, limits[0].limit),
        (Axis::Y, LimitKind::Velocity)
    );
    assert!((limits[0].planned_per_min - 6000.0 * 2f64.sqrt()).abs() < 1e-6);
}

/// A mixed-unit move X 10 mm + C 90 deg: `L = sqrt(10² + 90²)`, so C's share of the path
/// speed is 90/L and C reaches exactly its maximum; X moves at 10/90 of C's rate.
#[test]
fn a_mixed_unit_move_holds_the_rotary_axis_at_its_maximum() {
    let m = machine(FAST, ACCEL);
    let (s, limits) = run(
        vec![g01(
            1,
            q(&[0.0; 5]),
            q(&[10.0, 0.0, 0.0, 0.0, 0.0, 90.0]),
            20000.0,
        )],
        &m,
    );
    assert!((peak_speed(&s, Axis::C) - 150.0).abs() < 1e-9);
    assert!((peak_speed(&s, Axis::X) - 150.0 / 9.0).abs() < 1e-9);
    let length = (10.0f64.powi(2) + 90.0f64.powi(2)).sqrt();
    assert!((limits[0].planned_per_min - 9000.0 * length / 90.0).abs() < 1e-6);
    assert_eq!(limits[0].axis, Axis::C);
}

/// A full circle of radius 10 mm at F 10 000 (166.7 mm/s, centripetal 2 778 mm/s²) on axes
/// of 1 000 mm/s²: half the budget goes to the centripetal term, `v ≤ sqrt(½ amax r)`
/// = 70.71 mm/s. The planner bounds |q''| from 17 samples plus |q'''| times half their
/// spacing (here +22 %), so it runs at 91 % of that, never above.
#[test]
fn an_arc_is_held_by_the_centripetal_acceleration() {
    let accel = [1000.0, 1000.0, 1000.0, 3600.0, 7200.0];
    let m = machine(FAST, accel);
    let start = q(&[10.0]);
    let arc = Move {
        line: 2,
        motion: Motion::Arc {
            clockwise: false,
            plane: Plane::XY,
            center_mm: [0.0, 0.0, 0.0],
        },
        start,
        end: start,
        feed: Feed::PerMinute(10000.0),
        ..Move::default()
    };
    let (s, limits) = run(vec![arc], &m);
    let bound = (0.5f64 * 1000.0 * 10.0).sqrt() * 60.0;
    assert_eq!(limits.len(), 1);
    let l = limits[0];
    assert_eq!(l.limit, LimitKind::Acceleration, "{l:?}");
    assert!(
        l.planned_per_min <= bound && l.planned_per_min > 0.9 * bound,
        "{l:?}"
    );
    for axis in [Axis::X, Axis::Y] {
        for w in s.windows(3) {
            let a = (w[2].q[axis] - 2.0 * w[1].q[axis] + w[0].q[axis]) / PERIOD.powi(2);
            assert!(a.abs() <= 1000.0 * 1.02, "{axis} acceleration {a}");
        }
    }
}

/// Under TCP a short tip move that turns C by 90° must slow the tip so that C stays within
/// its 150 deg/s: C's peak speed is at most its limit and the planner uses most of it.
#[test]
fn a_tcp_move_keeps_the_rotary_axis_within_its_limit() {
    let m = machine(FAST, ACCEL);
    let start = q(&[50.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let end = q(&[51.0, 0.0, 0.0, 0.0, 0.0, 90.0]);
    let mv = Move {
        tcp: true,
        ..g01(4, start, end, 1000.0)
    };
    let (s, limits) = run(vec![mv], &m);
    let peak = peak_speed(&s, Axis::C);
    assert!(
        peak <= 150.0 * (1.0 + 1e-9) && peak > 0.9 * 150.0,
        "C peak {peak} deg/s"
    );
    assert!(peak_speed(&s, Axis::X) <= 500.0 && peak_speed(&s, Axis::Y) <= 500.0);
    assert_eq!(limits.first().map(|l| l.axis), Some(Axis::C), "{limits:?}");
}

/// `mtsim analyze` names the block and the axis that held its feed.
#[test]
fn analyze_reports_the_blocks_and_axes_that_held_the_feed() {
    let dir = common::scratch("feed", "analyze");
    std::fs::write(
        dir.join("p.nc"),
        "G90 G94 G21\nG01 X0 Y0 Z0 A0 C0 F1000\nG01 C90 F20000\nG01 X10 F1000\nM30\n",
    )
    .unwrap();
    let s = common::write_scenario(&dir, &common::trt_ac(), "[program]\nfile = \"p.nc\"\n");
    let out = common::mtsim(&["analyze", s.to_str().unwrap(), "--json"]);
    let v = common::stdout_json(&out);
    let blocks = v["feed_limits"]["blocks"].as_array().expect("a list");
    assert_eq!(blocks.len(), 1, "{v}");
    assert_eq!(blocks[0]["line"], 3);
    assert_eq!(blocks[0]["axis"], "C");
    assert_eq!(blocks[0]["limit"], "velocity");
    assert!((blocks[0]["planned_per_min"].as_f64().unwrap() - 9000.0).abs() < 1e-9);
    let text = common::mtsim(&["analyze", s.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("line 3: F20000.0 -> 9000.0/min, C velocity limit"),
        "{text}"
    );
}

/// Path control at a 90° corner X then Y, at F 6 000 on fast axes: G64 without P passes the
/// corner moving; G61 (exact path) and G61.1 (exact stop) stop there; G64 P blends the corner
/// with an arc P from it (the lines between setpoints, its chords, a sagitta further in).
#[test]
fn path_control_modes_at_a_corner() {
    let accel = [20000.0, 20000.0, 20000.0, 3600.0, 7200.0];
    let m = machine(FAST, accel);
    let (a, b, c) = (q(&[0.0]), q(&[20.0]), q(&[20.0, 20.0]));
    let corner = |path: PathControl| {
        let first = Move {
            path,
            ..g01(1, a, b, 6000.0)
        };
        let (s, _) = run(vec![first, g01(2, b, c, 6000.0)], &m);
        // Deviation of the line between consecutive setpoints from the corner (20, 0).
        let mut deviation = f64::INFINITY;
        let mut slowest = f64::INFINITY;
        for w in s.windows(2) {
            let (p0, p1) = (w[0].q, w[1].q);
            let (dx, dy) = (p1[Axis::X] - p0[Axis::X], p1[Axis::Y] - p0[Axis::Y]);
            let len2 = dx * dx + dy * dy;
            if len2 > 0.0 {
                let t =
                    (((20.0 - p0[Axis::X]) * dx + (0.0 - p0[Axis::Y]) * dy) / len2).clamp(0.0, 1.0);
                let (x, y) = (p0[Axis::X] + t * dx, p0[Axis::Y] + t * dy);
                deviation = deviation.min((x - 20.0).hypot(y));
            }
            if p0[Axis::X] > 19.0 && p0[Axis::Y] < 1.0 {
                slowest = slowest.min(len2.sqrt() / PERIOD);
            }
        }
        (deviation, slowest)
    };
    let (blend_dev, blend) = corner(PathControl::BLEND);
    assert!(
        blend > 10.0 && blend_dev > 1e-3,
        "G64 passes the corner at {blend} mm/s, {blend_dev} mm"
    );
    for exact in [PathControl::ExactPath, PathControl::ExactStop] {
        let (dev, slowest) = corner(exact);
        assert!(
            dev < 1e-9 && slowest < 2.0,
            "{exact:?}: {dev} mm, {slowest} mm/s"
        );
    }
    for tol in [0.001, 0.005] {
        let (dev, slowest) = corner(PathControl::Blend {
            tolerance_mm: Some(tol),
            naive_cam_mm: None,
        });
        // The corner speed that just meets P: μ √2 T/4 = P (the junction rule before blending).
        let mu = 4.0 * tol / PERIOD / 2f64.sqrt();
        // The blend arc passes P from the corner (src/motion/blend.rs); the lines between
        // setpoints are chords of it, a sagitta (vT)²/(8R) further in: R = P/(√2 − 1), and
        // v at most the arc's centripetal speed sqrt(√3/2 · amax · R).
        let radius = tol / (2f64.sqrt() - 1.0);
        let v = (0.75f64.sqrt() * 20000.0 * radius).sqrt();
        let sagitta = (v * PERIOD).powi(2) / (8.0 * radius);
        assert!(
            dev <= (tol + sagitta) * (1.0 + 1e-9),
            "P{tol}: the command cuts the corner by {dev} mm (sagitta {sagitta} mm)"
        );
        // Period-averaged speeds around the corner: above a fifth of μ, below G64 without P.
        assert!(
            slowest < blend && slowest > 0.2 * mu,
            "P{tol}: {slowest} mm/s, μ {mu}"
        );
    }
    // Collinear blocks under G61 do not stop.
    let first = Move {
        path: PathControl::ExactPath,
        ..g01(1, a, b, 6000.0)
    };
    let (s, _) = run(vec![first, g01(2, b, q(&[40.0]), 6000.0)], &m);
    let through = s
        .windows(2)
        .filter(|w| (w[0].q[Axis::X] - 20.0).abs() < 2.0)
        .map(|w| (w[1].q[Axis::X] - w[0].q[Axis::X]) / PERIOD)
        .fold(f64::INFINITY, f64::min);
    assert!(
        (through - 100.0).abs() < 1e-6,
        "collinear G61 junction at {through} mm/s"
    );
}

/// Planning without sampling (`Interpolator::plan_block`, what `analyze` runs, block by block
/// by reference) notes the same blocks, axes and speeds as the sampled run: 300 blocks
/// alternating between a diagonal held by Y's velocity (closed form 6 000 √2 mm/min), a pure
/// C move held at 9 000 deg/min, and a slow move that is not held, with the look-ahead window
/// (16 blocks) refilled many times.
#[test]
fn planning_without_sampling_notes_the_same_feed_limits() {
    let mut v = FAST;
    v[1] = 6000.0;
    let m = machine(v, ACCEL);
    let mut blocks = Vec::new();
    let mut at = q(&[0.0; 5]);
    for k in 0..300 {
        let (end, feed) = match k % 3 {
            0 => (at + q(&[2.0, 2.0]), 20000.0),
            1 => (at + q(&[0.0, 0.0, 0.0, 0.0, 0.0, 9.0]), 20000.0),
            _ => (at + q(&[0.5]), 100.0),
        };
        blocks.push(g01(k + 1, at, end, feed));
        at = end;
    }
    let (_, sampled) = run(blocks.clone(), &m);
    let options = InterpolationOptions {
        record_feed_limits: true,
        ..InterpolationOptions::default()
    };
    let mut it = Interpolator::new(std::iter::empty(), &m, options).unwrap();
    for b in &blocks {
        it.plan_block(b).unwrap();
    }
    let planned = it.take_feed_limits();
    assert!(it.next().is_none(), "nothing to sample after planning");
    assert_eq!(planned.len(), 200, "the diagonal and the C moves");
    let key = |l: &FeedLimit| (l.line, l.axis, l.limit, l.planned_per_min.to_bits());
    assert_eq!(
        planned.iter().map(key).collect::<Vec<_>>(),
        sampled.iter().map(key).collect::<Vec<_>>()
    );
    for l in &planned {
        let expected = if l.axis == Axis::Y {
            6000.0 * 2f64.sqrt()
        } else {
            9000.0
        };
        assert!((l.planned_per_min - expected).abs() < 1e-6, "{l:?}");
    }
}

/// A block the planner refuses (no F word on a feed move) ends planning with its error,
/// located at its line, as it ends the sampled run.
#[test]
fn planning_without_sampling_stops_at_a_block_it_cannot_plan() {
    let m = machine(FAST, ACCEL);
    // Past the look-ahead that `Interpolator::new` plans.
    let mut blocks: Vec<Move> = (0..1000)
        .map(|k| g01(k + 1, q(&[k as f64]), q(&[k as f64 + 1.0]), 1000.0))
        .collect();
    blocks[700].feed = Feed::None;
    let options = InterpolationOptions {
        record_feed_limits: true,
        ..InterpolationOptions::default()
    };
    let mut one = Interpolator::new(std::iter::empty(), &m, options.clone()).unwrap();
    let by_reference = blocks.iter().find_map(|b| one.plan_block(b).err());
    let mut it = Interpolator::new(blocks.into_iter().map(Ok), &m, options).unwrap();
    let e = it
        .find_map(|s| s.err())
        .expect("the sampled run fails")
        .to_string();
    assert!(e.contains("line 701") && e.contains("feed rate"), "{e}");
    assert_eq!(by_reference.map(|e| e.to_string()), Some(e));
}

/// The least distance from the point (x, y) of the lines between consecutive setpoints (the
/// command the servo follows), mm.
fn passes_from(s: &[Setpoint], x: f64, y: f64) -> f64 {
    let mut deviation = f64::INFINITY;
    for w in s.windows(2) {
        let (p0, p1) = (w[0].q, w[1].q);
        let (dx, dy) = (p1[Axis::X] - p0[Axis::X], p1[Axis::Y] - p0[Axis::Y]);
        let len2 = dx * dx + dy * dy;
        if len2 > 0.0 {
            let t = (((x - p0[Axis::X]) * dx + (y - p0[Axis::Y]) * dy) / len2).clamp(0.0, 1.0);
            deviation = deviation.min((p0[Axis::X] + t * dx - x).hypot(p0[Axis::Y] + t * dy - y));
        }
    }
    deviation
}

/// LinuxCNC's rule for G64 (`[control] max_feed_override`, docs/interpolation.md): a 90°
/// corner of X and Y at 20 mm/s and 300 mm/s² becomes an arc `ℓ = v_s²/(½ a)` long with
/// `v_s = min(F · override, 20 mm/s)`, i.e. `R = ℓ/(π/2)`, passing `R (√2 − 1)` from the
/// corner: 0.70319 mm at F1000 (v_s held to 20), 0.17580 mm at F300 (v_s 10); under G64
/// P0.1 the tolerance binds (0.1 mm); without the override G64 keeps the junction rule.
#[test]
fn g64_without_p_blends_an_arc_as_long_as_the_feed_at_its_override_needs() {
    let control = |ovr: &str| {
        let mut text =
            "name = \"test\"\nkinematics = \"trt-ac\"\ninterpolation_period_ms = 1.0\n".to_string();
        text += ovr;
        for axis in ["X", "Y", "Z", "A", "C"] {
            text += &format!(
                "[axes.{axis}]\nmin = -10000\nmax = 10000\nmax_velocity = 1200\nmax_acceleration = 300\nmax_jerk = 1e9\n"
            );
        }
        Machine::from_toml(Path::new("test.toml"), &text, None).expect("test machine is valid")
    };
    let linuxcnc = control("[control]\nmax_feed_override = 2.0\n");
    let (a, b, c) = (q(&[0.0]), q(&[20.0]), q(&[20.0, 20.0]));
    let corner = |path: PathControl, feed: f64, m: &Machine| {
        let first = Move {
            path,
            ..g01(1, a, b, feed)
        };
        let (s, _) = run(vec![first, g01(2, b, c, feed)], m);
        passes_from(&s, 20.0, 0.0)
    };
    let quarter = std::f64::consts::FRAC_PI_2;
    for (feed, v_s) in [(1000.0, 20.0), (300.0, 10.0)] {
        let radius = v_s * v_s / (0.5 * 300.0) / quarter;
        let expected = radius * (2f64.sqrt() - 1.0);
        // The lines between setpoints are chords, a sagitta (vT)²/(8R) inside the arc.
        let sagitta = (feed / 60.0 * PERIOD).powi(2) / (8.0 * radius);
        let dev = corner(PathControl::BLEND, feed, &linuxcnc);
        assert!(
            (dev - expected).abs() <= sagitta + 1e-9,
            "F{feed}: {dev} mm from the corner, expected {expected} mm"
        );
    }
    let tight = PathControl::Blend {
        tolerance_mm: Some(0.1),
        naive_cam_mm: None,
    };
    let dev = corner(tight, 1000.0, &linuxcnc);
    assert!((dev - 0.1).abs() < 1e-4, "G64 P0.1: {dev} mm");
    let dev = corner(PathControl::BLEND, 1000.0, &control(""));
    assert!(dev < 1e-3, "G64 without the override: {dev} mm");
}
