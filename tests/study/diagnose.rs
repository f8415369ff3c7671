//! Diagnostics against injected errors: each error is put into the actual positions of a
//! synthetic circle (r = 50 mm, F1000, plane XY), the bar length is computed from them
//! exactly, and the estimate from the trace must return the injected value.

use std::path::Path;

use mtsim::input::program::CircleTest;
use mtsim::input::scenario::Scenario;
use mtsim::input::Direction;
use mtsim::measure::BallbarRun;
use mtsim::study::diagnose::diagnose_circle;
use mtsim::study::simulate::simulate;
use mtsim::Plane;

use crate::common;

const R: f64 = 50.0; // mm
const V: f64 = 1000.0 / 60.0; // mm/s

fn circle() -> CircleTest {
    CircleTest {
        plane: Plane::XY,
        center_mm: [0.0, 0.0, 0.0],
        radius_mm: R,
        feed_mm_min: 1000.0,
    }
}

/// Injected errors.
struct Errors {
    scale_u: f64,      // ε_u
    scale_v: f64,      // ε_v
    squareness: f64,   // α, rad: u_act = u + α v
    lag_u_s: f64,      // T_u = 1/Kv_u
    lag_v_s: f64,      // T_v
    cyclic_um: f64,    // A: e(u) = A cos(2π u / p + φ) along u
    cyclic_pitch: f64, // p, mm
}

/// One revolution every 0.01 deg; the bar length from the erroneous actual point, um.
fn run(direction: Direction, e: &Errors) -> BallbarRun {
    let mut run = BallbarRun::new(direction);
    let sign = match direction {
        Direction::Ccw => 1.0,
        Direction::Cw => -1.0,
    };
    for k in 0..36_000 {
        let t = (k as f64 * 0.01).to_radians();
        let u = R * t.cos();
        // The exact steady state of a first-order loop G = 1/(1 + sT) on u = R cos ωt:
        // amplitude 1/sqrt(1 + (ωT)²), phase lag atan(ωT), in the run's direction.
        let w = V / R;
        let lagged = |tau: f64, f: fn(f64) -> f64| {
            R * f(t - sign * (w * tau).atan()) / (1.0 + (w * tau).powi(2)).sqrt()
        };
        let (ul, vl) = (lagged(e.lag_u_s, f64::cos), lagged(e.lag_v_s, f64::sin));
        let mut ua = ul * (1.0 + e.scale_u) + e.squareness * vl;
        let va = vl * (1.0 + e.scale_v);
        ua += e.cyclic_um * 1e-3 * (std::f64::consts::TAU * u / e.cyclic_pitch + 0.3).cos();
        let dl_um = (ua.hypot(va) - R) * 1e3;
        run.push(k as f64 * 0.01, dl_um);
    }
    run
}

fn close(got: f64, want: f64, rel: f64) -> bool {
    (got - want).abs() <= rel * want.abs()
}

#[test]
fn scale_squareness_and_cyclic_errors_are_estimated_from_the_trace() {
    let e = Errors {
        scale_u: 20e-6,
        scale_v: -10e-6,
        squareness: 50e-6,
        lag_u_s: 0.0,
        lag_v_s: 0.0,
        cyclic_um: 2.0,
        cyclic_pitch: 10.0,
    };
    let runs = [run(Direction::Ccw, &e), run(Direction::Cw, &e)];
    let d = diagnose_circle(&runs, &circle()).unwrap();
    assert!(
        close(d.scale_mismatch_ppm, 30.0, 0.03),
        "{}",
        d.scale_mismatch_ppm
    );
    assert!(
        close(d.squareness_urad, 50.0, 0.02),
        "{}",
        d.squareness_urad
    );
    assert!(d.servo_mismatch_ms.abs() < 1e-3, "{}", d.servo_mismatch_ms);
    let x = d
        .cyclic
        .iter()
        .find(|c| c.axis == "X")
        .expect("cyclic error on X");
    println!(
        "scale {} ppm, squareness {} urad, cyclic {x:?}",
        d.scale_mismatch_ppm, d.squareness_urad
    );
    assert!(close(x.pitch_mm, 10.0, 0.01), "{x:?}");
    assert!(close(x.amplitude_um, 2.0, 0.10), "{x:?}");
    assert!(d.cyclic.iter().all(|c| c.axis != "Y"), "{:?}", d.cyclic);
}

#[test]
fn a_gain_mismatch_is_an_oval_at_45_deg_that_flips_and_an_apparent_scale_mismatch() {
    // Kv 30 and 27 1/s: T_u - T_v = -3.704 ms, peak-to-peak v |T_u - T_v| = 61.73 um.
    // At second order the mismatch also shows as a scale mismatch, in both directions. With
    // φ = atan(ωT) and amplitude cos φ, u = R cos φ_u cos(θ - φ_u), v = R cos φ_v sin(θ - φ_v):
    // |p|²/R² = [cos²φ_u (1 + cos(2θ - 2φ_u)) + cos²φ_v (1 - cos(2θ - 2φ_v))] / 2, whose cos 2θ
    // term is (cos²φ_u cos 2φ_u - cos²φ_v cos 2φ_v)/2 ≈ 3 (φ_v² - φ_u²)/2, so
    // ε_u - ε_v = 2 a2 / R = (3/2) ω² (T_v² - T_u²) = 43.44 ppm.
    let (tu, tv) = (1.0 / 30.0, 1.0 / 27.0);
    let e = Errors {
        scale_u: 0.0,
        scale_v: 0.0,
        squareness: 0.0,
        lag_u_s: tu,
        lag_v_s: tv,
        cyclic_um: 0.0,
        cyclic_pitch: 10.0,
    };
    let d = diagnose_circle(
        &[run(Direction::Ccw, &e), run(Direction::Cw, &e)],
        &circle(),
    )
    .unwrap();
    let want_ms = (tu - tv) * 1e3;
    assert!(
        close(d.servo_mismatch_ms, want_ms, 0.02),
        "{}",
        d.servo_mismatch_ms
    );
    assert!(
        close(d.servo_mismatch_pp_um, 61.73, 0.02),
        "{}",
        d.servo_mismatch_pp_um
    );
    // The apparent scale mismatch is said and taken out of the scale mismatch.
    let w = V / R;
    let apparent = 1.5 * w * w * (tv * tv - tu * tu) * 1e6;
    assert!(
        close(d.servo_scale_ppm, apparent, 0.03),
        "{} vs {apparent}",
        d.servo_scale_ppm
    );
    assert!(
        d.scale_mismatch_ppm.abs() <= 0.03 * apparent,
        "{}",
        d.scale_mismatch_ppm
    );
    assert!(d.squareness_urad.abs() < 0.5, "{}", d.squareness_urad);
    assert!(d.not_measured.is_empty(), "{:?}", d.not_measured);
}

#[test]
fn squareness_and_a_gain_mismatch_together_are_told_apart_by_the_two_directions() {
    // 50 µrad of squareness on Kv 30/27: the oval that flips is the mismatch, the one that
    // stays is the squareness.
    let (tu, tv) = (1.0 / 30.0, 1.0 / 27.0);
    let e = Errors {
        scale_u: 0.0,
        scale_v: 0.0,
        squareness: 50e-6,
        lag_u_s: tu,
        lag_v_s: tv,
        cyclic_um: 0.0,
        cyclic_pitch: 10.0,
    };
    let d = diagnose_circle(
        &[run(Direction::Ccw, &e), run(Direction::Cw, &e)],
        &circle(),
    )
    .unwrap();
    assert!(
        close(d.squareness_urad, 50.0, 0.02),
        "{}",
        d.squareness_urad
    );
    assert_eq!(d.squareness_um_per_m, d.squareness_urad);
    let want_ms = (tu - tv) * 1e3;
    assert!(
        close(d.servo_mismatch_ms, want_ms, 0.02),
        "{}",
        d.servo_mismatch_ms
    );
}

#[test]
fn one_direction_gives_no_squareness_mismatch_or_scale_and_says_why() {
    // Kv 30/27 alone in one direction: its oval at 45° reads as -1,234 µrad of squareness if
    // taken for one. Each direction alone: every figure the flip separates is NaN (null in
    // summary.json) with the reason; the cyclic search and harmonics still run.
    let e = Errors {
        scale_u: 0.0,
        scale_v: 0.0,
        squareness: 0.0,
        lag_u_s: 1.0 / 30.0,
        lag_v_s: 1.0 / 27.0,
        cyclic_um: 0.0,
        cyclic_pitch: 10.0,
    };
    for direction in [Direction::Ccw, Direction::Cw] {
        let d = diagnose_circle(&[run(direction, &e)], &circle()).unwrap();
        for (field, value) in [
            ("squareness_urad", d.squareness_urad),
            ("squareness_um_per_m", d.squareness_um_per_m),
            ("servo_mismatch_ms", d.servo_mismatch_ms),
            ("servo_mismatch_pp_um", d.servo_mismatch_pp_um),
            ("scale_mismatch_ppm", d.scale_mismatch_ppm),
            ("servo_scale_ppm", d.servo_scale_ppm),
        ] {
            assert!(value.is_nan(), "{field}: {value}");
            assert!(
                d.not_measured[field].starts_with("needs both directions"),
                "{field}: {:?}",
                d.not_measured
            );
        }
        let json = serde_json::to_value(&d).unwrap();
        assert!(json["squareness_urad"].is_null() && json["servo_mismatch_ms"].is_null());
        assert_eq!(d.harmonics.len(), 1);
    }
}

#[test]
fn a_clean_circle_has_no_errors() {
    let e = Errors {
        scale_u: 0.0,
        scale_v: 0.0,
        squareness: 0.0,
        lag_u_s: 0.0,
        lag_v_s: 0.0,
        cyclic_um: 0.0,
        cyclic_pitch: 10.0,
    };
    let d = diagnose_circle(
        &[run(Direction::Ccw, &e), run(Direction::Cw, &e)],
        &circle(),
    )
    .unwrap();
    assert!(d.scale_mismatch_ppm.abs() < 0.01 && d.squareness_urad.abs() < 0.01);
    assert!(
        d.servo_mismatch_ms.abs() < 1e-6 && d.cyclic.is_empty(),
        "{d:?}"
    );
}

#[test]
fn simulate_reports_the_servo_mismatch_of_a_kv_30_27_circle_in_summary_json() {
    let dir = common::scratch("diag", "mismatch");
    let mut body = String::from(
        "[program.circle]\nplane = \"XY\"\nradius_mm = 50.0\nfeed_mm_min = 1000.0\ndirections = [\"ccw\", \"cw\"]\ncenter_mm = [0.0, 0.0, 0.0]\n",
    );
    for (a, kv) in [("X", 30.0), ("Y", 27.0), ("Z", 30.0)] {
        body += &format!(
            "[machine_overrides.axes.{a}.servo]\nmodel = \"first-order\"\nkv_per_s = {kv}\n[machine_overrides.axes.{a}.friction]\ncoulomb_n = 0.0\n"
        );
    }
    let path = common::write_scenario(&dir, &common::machine("vmc-3axis"), &body);
    let scenario = Scenario::load(Path::new(&path)).unwrap();
    simulate(&scenario, &dir.join("out"), false, &|_| {}).unwrap();
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("out/summary.json")).unwrap()).unwrap();
    let ms = json["diagnostics"]["circle"]["servo_mismatch_ms"]
        .as_f64()
        .unwrap();
    let want = (1.0 / 30.0 - 1.0 / 27.0) * 1e3;
    assert!(
        (ms - want).abs() < 0.05 * want.abs(),
        "{ms} ms vs {want} ms"
    );
    // Every axis reports its reversal value.
    assert!(
        json["reversal_values"]["X"]["b"].is_number(),
        "{}",
        json["reversal_values"]
    );
}

/// The 2θ fit of trace rows returns an injected ellipse `A cos 2(θ − φ)` exactly, on rows
/// that cover the circle unevenly (the bins' Fourier sums would not).
#[test]
fn the_two_theta_fit_of_uneven_rows_returns_the_injected_ellipse() {
    use mtsim::study::diagnose::ellipse_um;
    for (amplitude, axis_deg) in [(3.0, 30.0), (0.8, 120.0), (2.5, 179.0)] {
        // 700 rows crowded towards 0° (θ = 300 u², u in [0, 1]).
        let theta: Vec<f64> = (0..700)
            .map(|i| 300.0 * (i as f64 / 699.0).powi(2))
            .collect();
        let dev: Vec<f64> = theta
            .iter()
            .map(|t| amplitude * (2.0 * (t - axis_deg) as f64).to_radians().cos())
            .collect();
        let (a, phi) = ellipse_um(&theta, &dev).unwrap();
        assert!((a - amplitude).abs() < 1e-9, "{a} vs {amplitude}");
        assert!((phi - axis_deg).abs() < 1e-7, "{phi} vs {axis_deg}");
    }
    // Fewer than 8 rows: no fit.
    assert!(ellipse_um(&[0.0, 10.0, 20.0], &[1.0, 2.0, 3.0]).is_none());
}

/// G with and without one spot: a unit sine every degree with 10 µm added at θ = 100°.
#[test]
fn one_spot_that_makes_most_of_g_is_found_with_g_without_it() {
    use mtsim::study::diagnose::g_without_peak;
    let theta: Vec<f64> = (0..360).map(f64::from).collect();
    let dev: Vec<f64> = theta
        .iter()
        .map(|t| t.to_radians().sin() + if *t == 100.0 { 10.0 } else { 0.0 })
        .collect();
    let (g, g_rest, spot) = g_without_peak(&theta, &dev, 5.0).unwrap();
    let peak = 100f64.to_radians().sin() + 10.0;
    assert!((g - (peak + 1.0)).abs() < 1e-12, "{g}");
    // Without 95°..105° the band is the sine's: 1 at 90°, −1 at 270°.
    assert!((g_rest - 2.0).abs() < 1e-12, "{g_rest}");
    assert_eq!(spot, 100.0);
}

/// The findings of a run folder read from its summary: a mark of no axis is placed by the
/// nearest reversal of any axis, a mark of an axis by that axis's nearest reversal; H and
/// the mean radius error are named when large.
#[test]
fn a_run_folder_is_diagnosed_from_its_typed_summary() {
    use mtsim::report::run::{Finding, RunFolder, RunSummary};
    let summary: RunSummary = serde_json::from_str(
        r#"{
        "sim_time_s": 12.5, "setpoints": 12501, "realtime_factor": null,
        "reversals_deg": {"X": [0.0, 180.0], "Y": [90.0, 270.0]},
        "ballbar": {
            "circular_deviation_um": 10.0, "radial_max_um": 5.0, "radial_min_um": -5.0,
            "hysteresis_um": 4.0,
            "spikes": [
                {"theta_deg": 104.0, "peak_deg": 104.5, "height_um": 2.0, "width_deg": 1.0,
                 "extent_deg": 1.0, "kind": "spike", "direction": "ccw", "axis": null,
                 "confidence": 0.0, "candidates": [], "ambiguous": false},
                {"theta_deg": 181.5, "peak_deg": 181.5, "height_um": -1.0, "width_deg": 0.0,
                 "extent_deg": 0.0, "kind": "step", "direction": "cw", "axis": "X",
                 "confidence": 0.9, "candidates": ["X"], "ambiguous": false}
            ],
            "runs": [
                {"direction": "ccw", "samples": 100,
                 "centring": {"r0_um": -2.5, "a_um": 0.0, "b_um": 0.0},
                 "circular_deviation_um": 10.0, "radial_max_um": 5.0, "radial_min_um": -5.0,
                 "noise_um": 0.1}
            ]
        }}"#,
    )
    .unwrap();
    let folder = RunFolder {
        dir: "run".into(),
        summary,
        test: None,
        check: None,
        trace: None,
        svgs: Vec::new(),
        files: Vec::new(),
        cut: None,
    };
    let d = mtsim::study::diagnose::diagnose_run(&folder);
    assert_eq!(d.marks.len(), 2);
    assert_eq!(d.marks[0].number, 1);
    let (axis, distance) = d.marks[0].nearest.clone().unwrap();
    assert_eq!(axis, "Y");
    assert!((distance - 14.0).abs() < 1e-12);
    assert_eq!(d.marks[0].reversal, None);
    let (at, distance) = d.marks[1].reversal.unwrap();
    assert_eq!(at, 180.0);
    assert!((distance - 1.5).abs() < 1e-12);
    // No trace: no spot and no 2θ finding; the two marks, H (4 > 0.3 G), r0 (|−2.5| > 1).
    assert_eq!(d.findings.len(), 4, "{:?}", d.findings);
    // The marks grouped: X's step (the machine's lost motion unknown here), then the mark
    // of no axis.
    assert!(
        matches!(&d.findings[0], Finding::AxisMarks(g) if g.axis == "X" && g.numbers == [2] && g.machine.is_empty()),
        "{:?}",
        d.findings
    );
    assert_eq!(
        d.findings[1],
        Finding::Unattributed {
            numbers: vec![1],
            largest_um: 2.0
        }
    );
    assert_eq!(d.findings[2], Finding::Hysteresis { h_um: 4.0 });
    assert_eq!(
        d.findings[3],
        Finding::RadiusOffset {
            direction: "ccw".into(),
            r0_um: -2.5
        }
    );
}
