//! LinuxCNC's blend sizing (`[control] max_feed_override`, docs/interpolation.md "Corner
//! blending") against figures worked by hand: a sharp corner passed at the speed its arc
//! allows, a corner between rapids in a plane tilted across three axes sized from that
//! plane's limits, and line-arc corners where the arc curves the same way as the turn.

use std::f64::consts::PI;
use std::path::Path;

use mtsim::input::machine::Machine;
use mtsim::motion::interpolation::{InterpolationOptions, Interpolator, Setpoint};
use mtsim::Axis;

const PERIOD: f64 = 1e-3;

/// An X Y Z machine with every axis at `v` mm/s and `a` mm/s² (jerk out of the way), under
/// LinuxCNC's planner rules with the highest feed override `ovr`.
fn machine(v: f64, a: f64, ovr: f64) -> Machine {
    let mut text = format!(
        "name = \"test\"\nkinematics = \"xyz\"\ninterpolation_period_ms = 1.0\ndialect = \"linuxcnc\"\n[control]\nmax_feed_override = {ovr}\n"
    );
    for axis in ["X", "Y", "Z"] {
        text += &format!(
            "[axes.{axis}]\nmin = -10000\nmax = 10000\nmax_velocity = {}\nmax_acceleration = {a}\nmax_jerk = 1e9\n",
            v * 60.0
        );
    }
    Machine::from_toml(Path::new("test.toml"), &text, None).expect("test machine is valid")
}

/// The setpoints of the G-code `program` on `machine`.
fn run(program: &str, machine: &Machine) -> Vec<Setpoint> {
    let options = ngc::Options {
        dialect: ngc::Dialect::Linuxcnc,
        ..ngc::Options::default()
    };
    let moves = ngc::read_str_with(Path::new("p.ngc"), program, &options)
        .map(|m| m.map_err(mtsim::error::Error::from));
    Interpolator::new(moves, machine, InterpolationOptions::default())
        .unwrap()
        .map(|s| s.unwrap())
        .collect()
}

fn xyz(s: &Setpoint) -> [f64; 3] {
    [s.q[Axis::X], s.q[Axis::Y], s.q[Axis::Z]]
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// The least distance from `corner` of the lines between consecutive setpoints (the
/// command the servo follows; mm), the path speed there (mm/s) and the largest speed of any
/// one axis over the run (mm/s).
fn at_corner(s: &[Setpoint], corner: [f64; 3]) -> (f64, f64, f64) {
    let (mut best, mut speed) = (f64::INFINITY, 0.0);
    for w in s.windows(2) {
        let (p0, p1) = (xyz(&w[0]), xyz(&w[1]));
        let step: Vec<f64> = (0..3).map(|i| p1[i] - p0[i]).collect();
        let len2: f64 = step.iter().map(|x| x * x).sum();
        if len2 == 0.0 {
            continue;
        }
        let along: f64 = (0..3).map(|i| (corner[i] - p0[i]) * step[i]).sum::<f64>() / len2;
        let t = along.clamp(0.0, 1.0);
        let d = distance(corner, [0, 1, 2].map(|i| p0[i] + t * step[i]));
        if d < best {
            (best, speed) = (d, len2.sqrt() / PERIOD);
        }
    }
    let axis_peak = s
        .windows(2)
        .flat_map(|w| (0..3).map(move |i| (xyz(&w[1])[i] - xyz(&w[0])[i]).abs() / PERIOD))
        .fold(0.0, f64::max);
    (best, speed, axis_peak)
}

/// 150° turns of X and Y at F1000 (20 mm/s, 300 mm/s², override 2: `v_s` = 20 mm/s) under
/// G64. Into a 30 mm block: the arc `ℓmax = v_s²/(½ a)` long would be `R = ℓmax/θ` = 1.0186
/// mm; LinuxCNC lays the larger `R = v_s²/(√3/2 · a)` = 1.5396 mm that passes at `v_s`, so
/// the path passes `R (1/cos 75° − 1)` = 4.409 mm from the corner, at the feed (16.67
/// mm/s). Into an 8 mm block the blend passes a quarter of it, 2.000 mm, from the corner
/// (LinuxCNC: 4.4090 and 2.0001 mm).
#[test]
fn a_150_degree_corner_is_blended_for_the_speed_it_passes_at() {
    let m = machine(20.0, 300.0, 2.0);
    let corner = [20.0, 0.0, 0.0];
    let radius = 20.0 * 20.0 / (3f64.sqrt() / 2.0 * 300.0);
    let by_speed = radius * (1.0 / (75f64).to_radians().cos() - 1.0);
    assert!((by_speed - 4.409).abs() < 5e-4, "by hand: {by_speed}");
    for (length, expected) in [(30.0, by_speed), (8.0, 2.0)] {
        let (c, s) = (150f64.to_radians().cos(), 150f64.to_radians().sin());
        let program = format!(
            "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG1 X20 F1000\nG1 X{:.6} Y{:.6}\nM2\n",
            20.0 + length * c,
            length * s
        );
        let (dev, speed, _) = at_corner(&run(&program, &m), corner);
        // The chords between setpoints 17 um apart lie within 0.04 um of the arc.
        assert!(
            (dev - expected).abs() < 1e-4,
            "{length} mm: {dev} mm from the corner, expected {expected}"
        );
        if length > 10.0 {
            assert!(
                (speed - 1000.0 / 60.0).abs() < 0.01,
                "passes at {speed} mm/s"
            );
        }
    }
}

/// Rapids along `u1 = (1, 1, 0)/√2` then turning 120° in the plane of `u1` and
/// `n = (−1, 1, −2)/√6` (axes at 25 mm/s, 750 mm/s², override 1.2). Each axis moves
/// `w = sqrt(u1_i² + n_i²) = √(2/3)` per unit of that plane, so the plane's limits are
/// `√(3/2)` times the axes': `v_s` = 30.62 mm/s, `a` = 918.6 mm/s². The blend
/// `R = max(ℓmax/θ, v_s²/(√3/2 a))` = `v_s²/(√3/2 a)` = 1.1785 mm passes `R (1/cos 60° − 1)
/// = R` from the corner, at 30.62 mm/s, no axis above its 25 mm/s.
#[test]
fn a_corner_between_rapids_in_a_tilted_plane_takes_that_planes_limits() {
    let m = machine(25.0, 750.0, 1.2);
    let s = 40.0 / 2f64.sqrt();
    let program = format!(
        "G21 G90 G17 G64\nG0 X0 Y0 Z0\nG0 X{s:.6} Y{s:.6}\nG0 X0 Z{:.6}\nM2\n",
        -s
    );
    let (dev, speed, axis_peak) = at_corner(&run(&program, &m), [s, s, 0.0]);
    let scale = 1.5f64.sqrt();
    let (v_s, a) = (25.0 * scale, 750.0 * scale);
    let radius = (v_s * v_s / (0.5 * a) / (2.0 * PI / 3.0)).max(v_s * v_s / (0.75f64.sqrt() * a));
    assert!((radius - 1.178_511).abs() < 1e-6, "by hand: {radius}");
    assert!(
        (dev - radius).abs() < 2e-4,
        "{dev} mm from the corner, expected {radius}"
    );
    assert!(
        (speed - v_s).abs() < 0.02,
        "passes at {speed} mm/s, expected {v_s}"
    );
    assert!(axis_peak <= 25.0 + 1e-6, "an axis at {axis_peak} mm/s");
}

/// The distance from the corner of a blend of radius `R` tangent to a line that turns `θ`
/// into an arc of radius `r` curving the same way, touching the arc's circle from inside:
/// its centre is `d` back along the line and `R` toward the turn, with
/// `d = r sin θ − sqrt(r² sin²θ − 2 r R (1 − cos θ))` (|centre − arc centre| = r − R).
fn same_way_distance(r: f64, theta: f64, radius: f64) -> f64 {
    let (sin, cos) = theta.sin_cos();
    let d = r * sin - ((r * sin).powi(2) - 2.0 * r * radius * (1.0 - cos)).sqrt();
    d.hypot(radius) - radius
}

/// A line along +X turning 90° left into a quarter circle of radius 10 (G3, the same way),
/// then out of it 90° left into a line (F600 at override 2: `v_s` 20 mm/s; 300 mm/s²).
/// The turn is padded by part of the arc, `pad = min(k sweep, (π − θ)/4)`, `k` 1/6 into
/// the arc and 1/3 out of it: 15° and 22.5°; the blends are `r sin(pad/2)/tan(θe/2)` =
/// 1.0016 and 1.3036 mm (`θe = θ + pad`; the speed's `v_s²/(√3/2 a)` = 1.5396 mm is larger),
/// 454.9 and 610.6 um from the corners (LinuxCNC: 455.0 and 610.7 um). Under G64 P0.05 the
/// tolerance binds: `R = P cos(θe/2)/(1 − cos(θe/2))`.
#[test]
fn same_way_line_arc_corners_are_blended_inside_the_arc() {
    let m = machine(20.0, 300.0, 2.0);
    let run_at = |p: &str| {
        let program = format!(
            "G21 G90 G17 G64{p}\nG0 X0 Y0 Z0\nG1 X20 F600\nG3 X10 Y10 I-10 J0\nG1 X10 Y-5\nM2\n"
        );
        let s = run(&program, &m);
        [[20.0, 0.0, 0.0], [10.0, 10.0, 0.0]].map(|c| at_corner(&s, c).0)
    };
    let (r, theta) = (10.0, PI / 2.0);
    let pads = [
        (PI / 2.0 / 6.0).min(PI / 8.0),
        (PI / 2.0 / 3.0).min(PI / 8.0),
    ];
    let geometric = pads.map(|pad| r * (0.5 * pad).sin() / (0.5 * (theta + pad)).tan());
    let expected = geometric.map(|radius| same_way_distance(r, theta, radius));
    assert!((expected[0] - 0.4549).abs() < 1e-4 && (expected[1] - 0.6106).abs() < 1e-4);
    for (dev, want) in run_at("").into_iter().zip(expected) {
        assert!(
            (dev - want).abs() < 1e-4,
            "G64: {dev} mm from the corner, expected {want}"
        );
    }
    let tolerance = pads.map(|pad| {
        let half_cos = (0.5 * (theta + pad)).cos();
        same_way_distance(r, theta, 0.05 * half_cos / (1.0 - half_cos))
    });
    for (dev, want) in run_at(" P0.05").into_iter().zip(tolerance) {
        assert!(
            (dev - want).abs() < 1e-4,
            "P0.05: {dev} mm from the corner, expected {want}"
        );
    }
}
