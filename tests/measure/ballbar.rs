//! The virtual ball bar against independently computed values.

use mtsim::input::Direction;
use mtsim::kinematics::{Kinematics, Layout};
use mtsim::measure::ballbar::{
    analyse, deviation_mm, BallbarRun, CircleFrame, EventKind, TraceEvent,
};
use mtsim::Plane;
use mtsim::{Axis, AxisVec};
use nalgebra::{Point3, Vector3};

// ---------------------------------------------------------------- helpers

/// The spec's cone 15/10 at YT = -25 mm, ZT = 200 mm, L = 100 mm.
const ALPHA_DEG: f64 = 15.0;
const BETA_DEG: f64 = 10.0;
const CENTER: [f64; 3] = [0.0, -25.0, 200.0];
const L: f64 = 100.0;

/// Rotation about table Y by `deg`, as a plain matrix (row-major), applied to `v`.
fn ry(deg: f64, v: [f64; 3]) -> [f64; 3] {
    let (s, c) = deg.to_radians().sin_cos();
    [c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]]
}
fn rx(deg: f64, v: [f64; 3]) -> [f64; 3] {
    let (s, c) = deg.to_radians().sin_cos();
    [v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]]
}
fn rz(deg: f64, v: [f64; 3]) -> [f64; 3] {
    let (s, c) = deg.to_radians().sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]
}
fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// The spec's `P(theta) = O + Ry(-beta) (r cos theta, r sin theta, h)`, table frame.
fn cone_point(theta_deg: f64) -> [f64; 3] {
    let (r, h) = (
        L * ALPHA_DEG.to_radians().cos(),
        L * ALPHA_DEG.to_radians().sin(),
    );
    let t = theta_deg.to_radians();
    add(CENTER, ry(-BETA_DEG, [r * t.cos(), r * t.sin(), h]))
}

fn angle_distance(a: f64, b: f64) -> f64 {
    ((a - b + 180.0).rem_euclid(360.0) - 180.0).abs()
}

/// Deterministic uniform noise with standard deviation `sd` (xorshift64).
struct Noise(u64, f64);
impl Noise {
    fn new(sd: f64) -> Self {
        Noise(0x9E37_79B9_7F4A_7C15, sd)
    }
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        let u = (self.0 >> 11) as f64 / (1u64 << 53) as f64; // [0, 1)
        (2.0 * u - 1.0) * 3f64.sqrt() * self.1
    }
}

/// An ellipse-like servo-lag shape: peak-to-peak 62 um, axes at 45/135 deg.
fn ellipse(theta_deg: f64) -> f64 {
    31.0 * (2.0 * (theta_deg - 45.0)).to_radians().cos()
}

/// A friction-like spike: onset at `onset_deg`, rising and decaying exponentially
/// (time constants 0.3 and 0.8 deg of travel), peak 4 um about 0.47 deg after the onset,
/// in the direction of travel.
fn friction_spike(theta_deg: f64, onset_deg: f64, direction: Direction) -> f64 {
    let s = match direction {
        Direction::Ccw => (theta_deg - onset_deg).rem_euclid(360.0),
        Direction::Cw => (onset_deg - theta_deg).rem_euclid(360.0),
    };
    if s > 20.0 {
        return 0.0;
    }
    let (tr, td) = (0.3, 0.8);
    let shape = |s: f64| (-s / td).exp() - (-s / tr).exp();
    let s_peak = (td / tr).ln() * tr * td / (td - tr);
    4.0 * shape(s) / shape(s_peak)
}

/// One revolution sampled every 0.01 deg, in the run's direction of travel.
fn run_of(direction: Direction, mut trace: impl FnMut(f64) -> f64) -> BallbarRun {
    let mut run = BallbarRun::new(direction);
    for k in 0..36_000 {
        let theta = match direction {
            Direction::Ccw => k as f64 * 0.01,
            Direction::Cw => 360.0 - k as f64 * 0.01,
        };
        run.push(theta, trace(theta));
    }
    run
}

/// The spec's reversal angles for 15/10 at YT = -25 mm.
fn cone_reversals() -> Vec<(Axis, Vec<f64>)> {
    vec![
        (Axis::X, vec![148.71, 252.74]),
        (Axis::Y, vec![146.91, 338.05]),
        (Axis::Z, vec![144.25, 324.25]),
        (Axis::A, vec![0.0, 180.0]),
    ]
}

fn describe(events: &[TraceEvent]) -> String {
    format!("{events:#?}")
}

// ---------------------------------------------------------------- deviation and theta

#[test]
fn deviation_is_the_excess_length_after_the_table_turns() {
    // Hand-built pose of the cone path at theta = 70 deg, with the tool ball pushed out to
    // L + 0.01 mm along the bar; A and C from the spec's inverse kinematics.
    let pivot_machine = [12.0, -30.0, 40.0];
    let kin = Kinematics::new(Layout::TrtAc, Vector3::from(pivot_machine));
    let p = cone_point(70.0);
    let apex = add(
        CENTER,
        ry(-BETA_DEG, [0.0, 0.0, L / ALPHA_DEG.to_radians().sin()]),
    );
    let t = scale(sub(apex, p), 1.0 / norm(sub(apex, p)));
    let a_deg = t[2].acos().to_degrees();
    let c_deg = t[0].atan2(t[1]).to_degrees();
    let tip_table = add(CENTER, scale(sub(p, CENTER), (L + 0.01) / L));
    let tip_machine = add(pivot_machine, rx(a_deg, rz(c_deg, tip_table)));
    let mut q = AxisVec::ZERO;
    q[Axis::X] = tip_machine[0];
    q[Axis::Y] = tip_machine[1];
    q[Axis::Z] = tip_machine[2];
    q[Axis::A] = a_deg;
    q[Axis::C] = c_deg;
    assert!(
        a_deg > 10.0 && c_deg.abs() > 10.0,
        "the pose must turn the table"
    );

    let dev_um = 1000.0 * deviation_mm(&kin, &q, &Point3::from(CENTER), L);
    assert!((dev_um - 10.0).abs() < 1e-6, "deviation {dev_um} um");
}

#[test]
fn theta_of_the_cone_point_is_theta() {
    let frame = CircleFrame::cone(CENTER, BETA_DEG);
    for theta in [0.0, 1e-7, 37.5, 90.0, 148.71, 180.0, 252.74, 300.0, 359.99] {
        let got = frame.theta_deg(&Point3::from(cone_point(theta)));
        assert!((0.0..360.0).contains(&got), "{got} out of [0, 360)");
        assert!(
            angle_distance(got, theta) < 1e-9,
            "theta {theta}: got {got}"
        );
    }
}

#[test]
fn planar_theta_runs_from_the_first_axis_toward_the_second() {
    let c = [10.0, 20.0, 30.0];
    let cases = [
        (Plane::XY, [1.0, 0.0, 0.0], 0.0),
        (Plane::XY, [0.0, 1.0, 5.0], 90.0),
        (Plane::ZX, [0.0, 0.0, 1.0], 0.0),
        (Plane::ZX, [1.0, 7.0, 0.0], 90.0),
        (Plane::YZ, [0.0, 1.0, 0.0], 0.0),
        (Plane::YZ, [3.0, 0.0, 1.0], 90.0),
        (Plane::XY, [-1.0, -1.0, 0.0], 225.0),
    ];
    for (plane, d, want) in cases {
        let frame = CircleFrame::planar(c, plane);
        let got = frame.theta_deg(&Point3::new(c[0] + d[0], c[1] + d[1], c[2] + d[2]));
        assert!(
            angle_distance(got, want) < 1e-9,
            "{plane:?} {d:?}: {got} != {want}"
        );
    }
}

// ---------------------------------------------------------------- centring and figures

#[test]
fn centring_recovers_the_offset_through_an_ellipse() {
    let (r0, a, b) = (3.0, 40.0, -25.0);
    let run = run_of(Direction::Ccw, |t| {
        let r = t.to_radians();
        r0 + a * r.cos() + b * r.sin() + 0.1 * ellipse(t)
    });
    let c = run.centring();
    assert!((c.r0_um - r0).abs() < 1e-6, "{c:?}");
    assert!((c.a_um - a).abs() < 1e-6, "{c:?}");
    assert!((c.b_um - b).abs() < 1e-6, "{c:?}");
}

#[test]
fn a_pure_set_up_offset_has_no_circular_deviation() {
    let run = run_of(Direction::Ccw, |t| {
        let r = t.to_radians();
        7.0 + 25.0 * r.cos() - 12.0 * r.sin()
    });
    let result = analyse(&[run], &cone_reversals()).unwrap();
    assert!(result.circular_deviation_um < 1e-6, "{result:?}");
    // F is the raw trace: 7 +- sqrt(25^2 + 12^2) (bin means sit within 0.03 deg of it).
    let amp = (25.0f64 * 25.0 + 12.0 * 12.0).sqrt();
    assert!(
        (result.radial_max_um - (7.0 + amp)).abs() < 1e-3,
        "{result:?}"
    );
    assert!(
        (result.radial_min_um - (7.0 - amp)).abs() < 1e-3,
        "{result:?}"
    );
    assert_eq!(result.hysteresis_um, None);
    assert!(result.events.is_empty(), "{}", describe(&result.events));
}

#[test]
fn a_62_um_ellipse_gives_g_62_um_and_f_from_the_raw_trace() {
    let run = run_of(Direction::Ccw, |t| -2.0 + ellipse(t));
    let result = analyse(&[run], &cone_reversals()).unwrap();
    assert!(
        (result.circular_deviation_um - 62.0).abs() < 1e-3,
        "G = {}",
        result.circular_deviation_um
    );
    assert!((result.radial_max_um - 29.0).abs() < 1e-3, "{result:?}");
    assert!((result.radial_min_um + 33.0).abs() < 1e-3, "{result:?}");
    assert!(result.events.is_empty(), "{}", describe(&result.events));
}

#[test]
fn hysteresis_is_the_largest_difference_between_directions() {
    let ccw = run_of(Direction::Ccw, ellipse);
    let cw = run_of(Direction::Cw, |t| {
        ellipse(t) + if (90.0..270.0).contains(&t) { 5.0 } else { 0.0 }
    });
    let result = analyse(&[ccw, cw], &[]).unwrap();
    let h = result.hysteresis_um.expect("two directions give H");
    // Bin means resolve theta to BIN_DEG: the ellipse slope moves them by < 0.03 um.
    assert!((h - 5.0).abs() < 0.01, "H = {h}");
}

// ---------------------------------------------------------------- events

#[test]
fn friction_spikes_are_found_at_their_reversals_and_attributed() {
    for direction in [Direction::Ccw, Direction::Cw] {
        let mut noise = Noise::new(0.1);
        let run = run_of(direction, |t| {
            ellipse(t)
                + friction_spike(t, 252.74, direction)
                + friction_spike(t, 338.05, direction)
                + noise.next()
        });
        let result = analyse(&[run], &cone_reversals()).unwrap();
        let events = &result.events;
        assert_eq!(events.len(), 2, "{direction:?}: {}", describe(events));
        for (event, (axis, angle)) in events.iter().zip([(Axis::X, 252.74), (Axis::Y, 338.05)]) {
            assert_eq!(event.kind, EventKind::Spike, "{}", describe(events));
            assert_eq!(event.axis, Some(axis), "{}", describe(events));
            assert!(
                angle_distance(event.theta_deg, angle) < 1.0,
                "{direction:?}: onset {} vs {angle}",
                event.theta_deg
            );
            assert!((event.height_um - 4.0).abs() < 0.5, "{}", describe(events));
            assert!(event.confidence > 0.9, "{}", describe(events));
            // The peak lies after the onset in the direction of travel.
            let ahead = match direction {
                Direction::Ccw => event.peak_deg - event.theta_deg,
                Direction::Cw => event.theta_deg - event.peak_deg,
            };
            assert!(ahead > 0.2 && ahead < 0.8, "{}", describe(events));
        }
    }
}

#[test]
fn a_spike_between_two_close_reversals_has_low_confidence() {
    // 45/30 at YT = -50: X reverses at 155.80, Y at 154.47 and Z at 153.43 deg.
    let reversals = vec![
        (Axis::X, vec![155.80, 282.67]),
        (Axis::Y, vec![154.47, 347.17]),
        (Axis::Z, vec![153.43, 333.43]),
    ];
    let run = run_of(Direction::Ccw, |t| {
        ellipse(t) + friction_spike(t, 155.135, Direction::Ccw)
    });
    let result = analyse(&[run], &reversals).unwrap();
    assert_eq!(result.events.len(), 1, "{}", describe(&result.events));
    let event = result.events[0];
    assert!(
        matches!(event.axis, Some(Axis::X | Axis::Y)),
        "{}",
        describe(&result.events)
    );
    // Both reversals lie within the tie tolerance of the mark: it is reported as ambiguous,
    // with both axes as candidates and no more than moderate confidence in the leading one.
    assert!(
        event.ambiguous && event.candidates.contains(Axis::X) && event.candidates.contains(Axis::Y),
        "{}",
        describe(&result.events)
    );
    assert!(event.confidence < 0.75, "{}", describe(&result.events));
}

#[test]
fn a_backlash_step_is_a_step_of_its_height_at_the_reversals() {
    let mut noise = Noise::new(0.1);
    let run = run_of(Direction::Ccw, |t| {
        ellipse(t)
            + if (90.0..270.0).contains(&t) {
                4.0
            } else {
                -4.0
            }
            + noise.next()
    });
    // A planar XY circle: X reverses at 90 and 270 deg, Y at 0 and 180 deg.
    let reversals = vec![(Axis::X, vec![90.0, 270.0]), (Axis::Y, vec![0.0, 180.0])];
    let result = analyse(&[run], &reversals).unwrap();
    let events = &result.events;
    assert_eq!(events.len(), 2, "{}", describe(events));
    for (event, (angle, height)) in events.iter().zip([(90.0, 8.0), (270.0, -8.0)]) {
        assert_eq!(event.kind, EventKind::Step, "{}", describe(events));
        assert_eq!(event.axis, Some(Axis::X), "{}", describe(events));
        assert!(
            angle_distance(event.theta_deg, angle) < 1.0,
            "{}",
            describe(events)
        );
        assert!(
            (event.height_um - height).abs() < 0.5,
            "{}",
            describe(events)
        );
    }
}

#[test]
fn a_clean_noisy_circle_has_no_events() {
    let mut noise = Noise::new(0.1);
    let run = run_of(Direction::Cw, |t| 1.5 + ellipse(t) + noise.next());
    let result = analyse(&[run], &cone_reversals()).unwrap();
    assert!(result.events.is_empty(), "{}", describe(&result.events));
    assert!(result.runs[0].noise_um > 0.02 && result.runs[0].noise_um < 0.1);
}

#[test]
fn a_partial_revolution_is_an_error_not_a_panic() {
    let mut run = BallbarRun::new(Direction::Ccw);
    for k in 0..1000 {
        run.push(k as f64 * 0.1, 0.0);
    }
    run.push(f64::NAN, 1.0);
    assert_eq!(run.rejected(), 1);
    let err = analyse(&[run], &[]).unwrap_err().to_string();
    assert!(err.contains("full revolution"), "{err}");
    assert!(analyse(&[], &[]).is_err());
}

#[test]
fn summary_json_has_the_contract_keys() {
    let run = run_of(Direction::Ccw, |t| {
        ellipse(t) + friction_spike(t, 252.74, Direction::Ccw)
    });
    let result = analyse(&[run], &cone_reversals()).unwrap();
    let json = serde_json::to_value(&result).unwrap();
    for key in [
        "circular_deviation_um",
        "radial_max_um",
        "radial_min_um",
        "hysteresis_um",
    ] {
        assert!(json.get(key).is_some(), "missing {key} in {json}");
    }
    assert!(json["hysteresis_um"].is_null());
    let spike = &json["spikes"][0];
    assert_eq!(spike["kind"], "spike");
    assert_eq!(spike["axis"], "X");
    assert!(spike["theta_deg"].is_number() && spike["height_um"].is_number());
}

// ---------------------------------------------------------------- polar plot

#[test]
fn the_plot_scale_is_the_smallest_1_2_5_step_that_fits() {
    use mtsim::report::polar::scale_um_per_div;
    // Four divisions each side of the nominal circle.
    assert_eq!(scale_um_per_div(31.0), 10.0);
    assert_eq!(scale_um_per_div(20.0), 5.0);
    assert_eq!(scale_um_per_div(3.0), 1.0);
    assert_eq!(scale_um_per_div(7.9), 2.0);
    assert_eq!(scale_um_per_div(0.0), 0.1);
    assert_eq!(scale_um_per_div(f64::NAN), 0.1);
}

#[test]
fn the_polar_plot_is_written_atomically_and_deterministically() {
    let spikes = |t: f64, d: Direction| friction_spike(t, 252.74, d) + friction_spike(t, 338.05, d);
    let ccw = run_of(Direction::Ccw, |t| ellipse(t) + spikes(t, Direction::Ccw));
    let cw = run_of(Direction::Cw, |t| {
        -ellipse(t)
            + 3.0
            + spikes(t, Direction::Cw)
            + if (90.0..270.0).contains(&t) { 2.0 } else { 0.0 }
    });
    let runs = [ccw, cw];
    let reversals = cone_reversals();
    let result = analyse(&runs, &reversals).unwrap();

    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    let first = dir.join("ballbar-polar-1.svg");
    let second = dir.join("ballbar-polar-2.svg");
    for path in [&first, &second] {
        mtsim::report::polar::write_polar_svg(
            path,
            &runs,
            &reversals,
            &result,
            "cone 15/10, YT -25 mm",
        )
        .unwrap();
    }
    let svg = std::fs::read_to_string(&first).unwrap();
    assert_eq!(
        svg,
        std::fs::read_to_string(&second).unwrap(),
        "renders differ"
    );
    assert!(
        !dir.join("ballbar-polar-1.svg.tmp").exists(),
        "temporary file left behind"
    );
    // Largest |d| about the common centre is below 40 µm: 10 µm per division, and the
    // rings say so, from -40 to +40 µm.
    assert!(svg.contains("scale: 10 µm per division"), "no scale text");
    assert!(!svg.contains(" um"), "µm, never um");
    let texts = svg_texts(&svg);
    for letter in ["X", "Y", "Z", "A"] {
        assert!(texts.iter().any(|t| t == letter), "no tick label {letter}");
    }
    for ring in ["+40 µm", "+10 µm", "0 µm", "−10 µm", "−40 µm"] {
        assert!(texts.iter().any(|t| t == ring), "no ring label {ring}");
    }
    assert!(
        texts.iter().any(|t| t == "1"),
        "the first event is not numbered"
    );
    assert!(svg.contains("H = "), "no hysteresis figure");
}

#[test]
fn an_unwritable_plot_path_is_a_write_error() {
    let run = run_of(Direction::Ccw, ellipse);
    let result = analyse(std::slice::from_ref(&run), &[]).unwrap();
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("no-such-dir/plot.svg");
    let err = mtsim::report::polar::write_polar_svg(&path, &[run], &[], &result, "t").unwrap_err();
    assert!(matches!(err, mtsim::Error::Write { .. }), "{err:?}");
}

/// The contents of the SVG's text elements, trimmed.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim().to_string())
        })
        .collect()
}
