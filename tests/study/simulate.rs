//! `simulate` end to end: the spec's closed forms for a planar circle through the whole
//! pipeline (generated G-code → reader → interpolator → servos → kinematics → ball bar),
//! and faults injected on one axis of the five-axis cone.

use std::path::{Path, PathBuf};

use mtsim::input::scenario::Scenario;
use mtsim::measure::ballbar::EventKind;
use mtsim::study::reversals::angular_distance_deg;
use mtsim::study::simulate::{simulate, SimulationSummary};

use crate::common;

use common::{machine, scenario_text, scratch};

/// Writes and runs a scenario; returns the summary and the output folder.
fn run(name: &str, body: &str) -> (SimulationSummary, PathBuf) {
    let dir = scratch("sim", name);
    let path = dir.join("scenario.toml");
    std::fs::write(&path, body).unwrap();
    let scenario = Scenario::load(&path).unwrap();
    let out = dir.join("out");
    let summary = simulate(&scenario, &out, false, &|_| {}).unwrap();
    (summary, out)
}

/// Overrides that make every axis of `axes` an ideal first-order loop without friction.
fn first_order(axes: &[&str], kv: &[f64], ff: f64) -> String {
    let mut s = String::new();
    for (a, k) in axes.iter().zip(kv) {
        s += &format!(
            "[machine_overrides.axes.{a}.servo]\nmodel = \"first-order\"\nkv_per_s = {k}\nvelocity_feedforward = {ff}\nacceleration_feedforward = {ff}\n\
             [machine_overrides.axes.{a}.friction]\ncoulomb_n = 0.0\n"
        );
    }
    s
}

fn circle(feed: f64, directions: &str, overrides: &str) -> String {
    scenario_text(
        &machine("vmc-3axis"),
        &format!("[program.circle]\nplane = \"XY\"\nradius_mm = 50.0\nfeed_mm_min = {feed}\ndirections = {directions}\ncenter_mm = [0.0, 0.0, 0.0]\n{overrides}"),
    )
}

/// (direction, θ deg, deviation um, centred deviation um) rows of a trace: `trace.csv` holds
/// dL, and each run's centring is in `summary.json` (`ballbar.runs[k].centring`), applied
/// here as `dL - (a cos θ + b sin θ)`.
fn trace(out: &Path) -> Vec<(String, f64, f64, f64)> {
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let centring = |direction: &str| {
        let runs = summary["ballbar"]["runs"].as_array().unwrap();
        let run = runs.iter().find(|r| r["direction"] == direction).unwrap();
        let c = &run["centring"];
        (c["a_um"].as_f64().unwrap(), c["b_um"].as_f64().unwrap())
    };
    let mut r = csv::Reader::from_path(out.join("trace.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |name: &str| {
        h.iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("column {name}"))
    };
    assert!(col("deviation_um") > 0 && !h.iter().any(|c| c == "deviation_centred_um"));
    let (d, t, raw) = (col("direction"), col("theta_deg"), col("deviation_um"));
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            let (theta, dev): (f64, f64) = (rec[t].parse().unwrap(), rec[raw].parse().unwrap());
            let (a, b) = centring(&rec[d]);
            let centred = dev - (a * theta.to_radians().cos() + b * theta.to_radians().sin());
            (rec[d].to_string(), theta, dev, centred)
        })
        .collect()
}

#[test]
fn a_pure_p_loop_shrinks_the_circle_by_the_closed_form_in_both_directions() {
    // dr = r (1/sqrt(1 + (w/Kv)^2) - 1), w = v/r.
    for feed in [1000.0, 3000.0] {
        let w = feed / 60.0 / 50.0;
        let want = 50.0 * (1.0 / (1.0 + (w / 30.0_f64).powi(2)).sqrt() - 1.0) * 1e3;
        let (s, _) = run(
            &format!("p{feed}"),
            &circle(
                feed,
                "[\"ccw\", \"cw\"]",
                &first_order(&["X", "Y", "Z"], &[30.0; 3], 0.0),
            ),
        );
        let b = s.ballbar.unwrap();
        for got in [b.radial_max_um, b.radial_min_um] {
            assert!(
                (got - want).abs() <= 0.03 * want.abs(),
                "F{feed}: {got} um vs {want} um"
            );
        }
        // Uniform: the same for CW and CCW, no shape.
        assert!(b.hysteresis_um.unwrap() < 0.03 * want.abs(), "{b:?}");
    }
}

#[test]
fn full_feedforward_with_an_ideal_inner_loop_removes_the_radial_error() {
    let (s, _) = run(
        "ff",
        &circle(
            1000.0,
            "[\"ccw\"]",
            &first_order(&["X", "Y", "Z"], &[30.0; 3], 1.0),
        ),
    );
    let b = s.ballbar.unwrap();
    assert!(
        b.radial_max_um.abs() < 0.1 && b.radial_min_um.abs() < 0.1,
        "{b:?}"
    );
}

#[test]
fn a_gain_mismatch_draws_an_ellipse_at_45_or_135_deg_that_flips_with_direction() {
    // Peak-to-peak about v |1/Kvx - 1/Kvy| = 16.67 mm/s (1/27 - 1/30) s = 61.7 um.
    let want = 1000.0 / 60.0 * (1.0 / 27.0 - 1.0 / 30.0) * 1e3;
    let (s, out) = run(
        "mismatch",
        &circle(
            1000.0,
            "[\"ccw\", \"cw\"]",
            &first_order(&["X", "Y", "Z"], &[30.0, 27.0, 30.0], 0.0),
        ),
    );
    let g = s.ballbar.unwrap().circular_deviation_um;
    assert!((g - want).abs() <= 0.1 * want, "G {g} um vs {want} um");
    // The major axis from a fit of a cos 2θ + b sin 2θ to each run's centred trace.
    let rows = trace(&out);
    let mut angles = Vec::new();
    for dir in ["ccw", "cw"] {
        let (mut a, mut b) = (0.0, 0.0);
        for (_, t, _, c) in rows.iter().filter(|r| r.0 == dir) {
            let t2 = 2.0 * t.to_radians();
            a += c * t2.cos();
            b += c * t2.sin();
        }
        let major = (0.5 * b.atan2(a).to_degrees()).rem_euclid(180.0);
        angles.push(major);
    }
    for (dir, major) in ["ccw", "cw"].iter().zip(&angles) {
        let off = (major - 45.0).abs().min((major - 135.0).abs());
        assert!(off < 0.1 * 45.0, "{dir}: major axis at {major} deg");
    }
    assert!(
        angular_distance_deg(2.0 * angles[0], 2.0 * angles[1]) > 150.0,
        "the tilt flips: {angles:?}"
    );
}

/// A circle of radius `r` mm at `feed` mm/min, both directions, on the three-axis VMC.
fn circle_r(r: f64, feed: f64, overrides: &str) -> String {
    scenario_text(
        &machine("vmc-3axis"),
        &format!("[program.circle]\nplane = \"XY\"\nradius_mm = {r}\nfeed_mm_min = {feed}\ndirections = [\"ccw\", \"cw\"]\ncenter_mm = [0.0, 0.0, 0.0]\n{overrides}"),
    )
}

/// The closed-form radius loss of equal first-order loops, um: `r (1/sqrt(1 + (ω/Kv)²) − 1)`.
fn radius_loss_um(r: f64, feed: f64, kv: f64) -> f64 {
    let w = feed / 60.0 / r;
    r * (1.0 / (1.0 + (w / kv).powi(2)).sqrt() - 1.0) * 1e3
}

#[test]
fn circles_at_the_feeds_people_test_at_start_at_speed_with_equal_loops() {
    // Equal first-order loops leave a uniform radius loss: G is 0 once the lead-in has
    // reached the feed and the loops have settled.
    for (r, feed, tolerance) in [
        (25.0, 5000.0, 0.01),
        (50.0, 5000.0, 0.01),
        (10.0, 3000.0, 0.02),
    ] {
        let (s, _) = run(
            &format!("speed{r}"),
            &circle_r(r, feed, &first_order(&["X", "Y", "Z"], &[30.0; 3], 0.0)),
        );
        let b = s.ballbar.as_ref().unwrap();
        assert!(
            b.circular_deviation_um < 0.3,
            "r {r} F{feed}: G {} um",
            b.circular_deviation_um
        );
        let want = radius_loss_um(r, feed, 30.0);
        for got in [b.radial_max_um, b.radial_min_um] {
            assert!(
                (got - want).abs() <= tolerance * want.abs(),
                "r {r} F{feed}: {got} um vs {want} um"
            );
        }
        // The lead-in holds at least the time to reach the feed from rest (double S with
        // the arc's a = min(½ amax, ⅓ jmax r / (3 v)), j = ⅓ jmax) plus 5 time constants.
        let lead = s.lead_in.expect("a circle reports its lead-in");
        let v = feed / 60.0;
        let (a, j) = (
            f64::min(1500.0, 50000.0 / 3.0 * r / (3.0 * v)),
            50000.0 / 3.0,
        );
        let t_reach = if v > a * a / j {
            v / a + a / j
        } else {
            2.0 * (v / j).sqrt()
        };
        assert!(
            lead.time_s >= t_reach + 5.0 / 30.0,
            "{lead:?} vs {t_reach} s + 5/Kv"
        );
        let arc_mm = lead.deg.to_radians() * r;
        assert!(arc_mm >= v * t_reach / 2.0 + v * 5.0 / 30.0, "{lead:?}");
        assert!(s.feed_reductions.is_empty(), "{:?}", s.feed_reductions);
    }
}

#[test]
fn a_small_circle_runs_at_its_feed_and_the_servo_mismatch_reads_true() {
    // r 10 mm at F3000: the axes see v²/r = 250 mm/s² and v³/r² = 1.25 m/s³ against 3000 mm/s²
    // and 50 m/s³, so the feed holds. Kv 30/27: T_x − T_y = 1/30 − 1/27 s.
    let (s, _) = run(
        "small",
        &circle_r(
            10.0,
            3000.0,
            &first_order(&["X", "Y", "Z"], &[30.0, 27.0, 30.0], 0.0),
        ),
    );
    assert!(s.feed_reductions.is_empty(), "{:?}", s.feed_reductions);
    let want_ms = (1.0 / 30.0 - 1.0 / 27.0) * 1e3;
    let got = s.diagnostics.unwrap().circle.unwrap().servo_mismatch_ms;
    assert!(
        (got - want_ms).abs() <= 0.05 * want_ms.abs(),
        "{got} ms vs {want_ms} ms"
    );
}

#[test]
fn a_circle_too_small_for_the_axis_jerk_is_held_and_says_so() {
    // r 1 mm at F3000: the axis jerk v³/r² = 125 m/s³ is above the 50 m/s³ limit. The planner
    // keeps v³ |q'''| within ⅓ jmax (|q'''| = 1/r², raised by at most 10 % between samples).
    let (s, _) = run(
        "held",
        &circle_r(1.0, 3000.0, &first_order(&["X", "Y", "Z"], &[30.0; 3], 0.0)),
    );
    let held = s.feed_reductions.first().expect("the feed is held");
    let bound = (50000.0_f64 / 3.0).cbrt() * 60.0;
    assert!(
        held.planned_per_min <= bound && held.planned_per_min >= 0.95 * bound,
        "{held:?} vs {bound} mm/min"
    );
    assert_eq!(held.programmed_per_min, 3000.0);
    assert!(
        ["X", "Y"].contains(&held.axis.to_string().as_str()),
        "{held:?}"
    );
    assert_eq!(format!("{:?}", held.limit), "Jerk");
    assert!(
        s.warnings.iter().any(|w| w.contains("jerk limit holds")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn backlash_on_x_in_a_semi_closed_loop_steps_the_trace_by_b_plus_2ff_over_k_at_x_reversals() {
    // b = 10 um, Fc = 150 N, k = 200 N/um: b + 2 Fc / k = 11.5 um. Only X has friction.
    let overrides =
        "[machine_overrides.axes.X.drive]\nbacklash_mm = 0.010\nstiffness_n_per_um = 200.0\n\
                     [machine_overrides.axes.X.friction]\ncoulomb_n = 150.0\n\
                     [machine_overrides.axes.Y.friction]\ncoulomb_n = 0.0\n";
    let (s, _) = run("backlash", &circle(1000.0, "[\"ccw\", \"cw\"]", overrides));
    let b = s.ballbar.unwrap();
    let steps: Vec<_> = b
        .events
        .iter()
        .filter(|e| e.kind == EventKind::Step)
        .collect();
    assert!(!steps.is_empty(), "{:?}", b.events);
    for e in &steps {
        assert_eq!(e.axis.map(|a| a.to_string()).as_deref(), Some("X"), "{e:?}");
        let near = [0.0, 180.0]
            .iter()
            .map(|r| angular_distance_deg(e.theta_deg, *r))
            .fold(f64::INFINITY, f64::min);
        assert!(near < 3.0, "{e:?}");
        assert!(
            (e.height_um.abs() - 11.5).abs() < 0.1 * 11.5,
            "step {} um vs 11.5 um",
            e.height_um
        );
    }
    // Backlash adds about b to the hysteresis.
    assert!(b.hysteresis_um.unwrap() > 10.0, "{b:?}");
}

/// The 15/10 cone half-way between the coincidences, both directions, with dry friction
/// only on `faulty` (N) and none elsewhere.
fn cone_with_friction(faulty: Option<(&str, f64)>) -> String {
    let mut s = scenario_text(
        &common::trt_ac(),
        "[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [0.0, -49.8, 200.0]\nballbar_length_mm = 100.0\ndirections = [\"ccw\", \"cw\"]\n",
    );
    for a in ["X", "Y", "Z", "A", "C"] {
        let key = if "AC".contains(a) {
            "coulomb_nm"
        } else {
            "coulomb_n"
        };
        let f = faulty.filter(|(f, _)| *f == a).map_or(0.0, |(_, v)| v);
        s += &format!("[machine_overrides.axes.{a}.friction]\n{key} = {f}\n");
    }
    s
}

/// Analytic reversal angles of the offset cone (`mtsim analyze`), deg.
fn reversals_of(axis: &str) -> Vec<f64> {
    match axis {
        "X" => vec![158.71, 275.30],
        "Y" => vec![144.48, 316.61],
        _ => unreachable!(),
    }
}

#[test]
fn friction_on_one_axis_marks_the_cone_trace_at_that_axis_reversals_and_nowhere_else() {
    let (clean, clean_out) = run("cone-clean", &cone_with_friction(None));
    assert!(
        clean.ballbar.as_ref().unwrap().events.is_empty(),
        "{:?}",
        clean.ballbar
    );
    let clean_rows = trace(&clean_out);
    for axis in ["X", "Y"] {
        let (s, out) = run(
            &format!("cone-{axis}"),
            &cone_with_friction(Some((axis, 200.0))),
        );
        let revs = reversals_of(axis);
        // 1. The detector: every event belongs to this axis, within 3 deg of its reversals.
        let events = &s.ballbar.unwrap().events;
        assert!(events.len() >= 4, "{axis}: {events:?}");
        for e in events {
            let near = revs
                .iter()
                .map(|r| angular_distance_deg(e.theta_deg, *r))
                .fold(f64::INFINITY, f64::min);
            assert!(
                near < 3.0 && e.axis.map(|a| a.to_string()).as_deref() == Some(axis),
                "{axis}: {e:?}"
            );
        }
        // The main mark of each reversal (a spike, or a step where the lost motion dominates
        // along the bar) lies just after it, in the direction of travel.
        for dir in [mtsim::input::Direction::Ccw, mtsim::input::Direction::Cw] {
            for r in &revs {
                let main = events
                    .iter()
                    .filter(|e| e.direction == dir && angular_distance_deg(e.peak_deg, *r) < 3.0)
                    .max_by(|a, b| a.height_um.abs().total_cmp(&b.height_um.abs()))
                    .unwrap_or_else(|| panic!("{axis} {dir:?}: no mark at {r}: {events:?}"));
                let after = match dir {
                    mtsim::input::Direction::Ccw => main.peak_deg - r,
                    mtsim::input::Direction::Cw => r - main.peak_deg,
                };
                assert!(
                    after > 0.0 && after < 3.0,
                    "{axis} {dir:?}: mark at {} for a reversal at {r}",
                    main.peak_deg
                );
                assert!(
                    main.height_um.abs() > 1.0 && main.height_um.abs() < 20.0,
                    "implausible height {main:?}"
                );
            }
        }
        // 2. Independently of the detector: the raw trace minus the friction-free run, in
        // 0.5-deg bins, changes abruptly (> 0.3 um between neighbours) only next to a reversal.
        let rows = trace(&out);
        assert_eq!(rows.len(), clean_rows.len());
        for dir in ["ccw", "cw"] {
            let mut bins = vec![(0.0, 0usize); 720];
            for (r, c) in rows.iter().zip(&clean_rows).filter(|(r, _)| r.0 == dir) {
                let b = &mut bins[((r.1 / 0.5) as usize).min(719)];
                b.0 += r.2 - c.2;
                b.1 += 1;
            }
            let mean: Vec<f64> = bins.iter().map(|(s, n)| s / (*n).max(1) as f64).collect();
            let mut marked = 0;
            for i in 0..720 {
                let jump = (mean[(i + 1) % 720] - mean[i]).abs();
                let theta = (i as f64 + 1.0) * 0.5;
                let near = revs
                    .iter()
                    .map(|r| angular_distance_deg(theta, *r))
                    .fold(f64::INFINITY, f64::min);
                if jump > 0.3 {
                    marked += 1;
                    assert!(
                        near < 3.0,
                        "{axis} {dir}: a {jump:.2} um jump at {theta} deg, away from {revs:?}"
                    );
                }
            }
            assert!(marked >= 2, "{axis} {dir}: friction left no mark");
        }
    }
}

#[test]
fn the_bar_is_blind_to_z_on_the_cone_because_it_stays_perpendicular_to_the_tool_axis() {
    // The bar O→P is perpendicular to the generatrix, which is the tool axis, i.e. machine Z:
    // a Z error changes the bar length only to second order (e²/2L).
    let mut body = cone_with_friction(Some(("Z", 600.0)));
    body += "[machine_overrides.axes.Z.drive]\nbacklash_mm = 0.010\n";
    let (_, out) = run("cone-z", &body);
    let (_, clean_out) = run("cone-z-clean", &cone_with_friction(None));
    let (rows, clean) = (trace(&out), trace(&clean_out));
    let worst = rows
        .iter()
        .zip(&clean)
        .map(|(r, c)| (r.2 - c.2).abs())
        .fold(0.0, f64::max);
    assert!(worst < 0.01, "the bar saw {worst} um of a Z fault");
    // ... although Z itself moved differently by more than the backlash.
    let z = |out: &Path| -> Vec<f64> {
        let mut r = csv::Reader::from_path(out.join("trace.csv")).unwrap();
        let col = r
            .headers()
            .unwrap()
            .iter()
            .position(|c| c == "Z_act_mm")
            .unwrap();
        r.records()
            .map(|rec| rec.unwrap()[col].parse().unwrap())
            .collect()
    };
    let dz = z(&out)
        .iter()
        .zip(z(&clean_out))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(dz > 0.010, "Z moved only {dz} mm differently");
}
