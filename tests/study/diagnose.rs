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
    let w = V / R;
    let apparent = 1.5 * w * w * (tv * tv - tu * tu) * 1e6;
    assert!(
        close(d.scale_mismatch_ppm, apparent, 0.03),
        "{} vs {apparent}",
        d.scale_mismatch_ppm
    );
    assert!(d.squareness_urad.abs() < 0.5, "{}", d.squareness_urad);
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
