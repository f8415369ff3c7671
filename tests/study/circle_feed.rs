//! A circle test's measured revolution at the programmed feed, and its Ballbar figures only
//! where the data separates them: `simulate` end to end, the figures read back from
//! `summary.json` and `trace.csv` and checked against closed forms or values computed here
//! from the trace.

use std::path::{Path, PathBuf};

use mtsim::input::scenario::Scenario;
use mtsim::report::html::render;
use mtsim::report::run::RunFolder;
use mtsim::study::diagnose::diagnose_run;
use mtsim::study::simulate::simulate;

use crate::common::{machine, scenario_text, scratch};

/// A circle of radius `r` at `feed` in `directions` on the three-axis VMC with ideal
/// first-order loops of gains `kv` (X, Y, Z) and no friction; runs it and returns the
/// output folder and its `summary.json`.
fn run_circle(
    name: &str,
    r: f64,
    feed: f64,
    directions: &str,
    kv: [f64; 3],
) -> (PathBuf, serde_json::Value) {
    let mut body = format!(
        "[program.circle]\nplane = \"XY\"\nradius_mm = {r}\nfeed_mm_min = {feed}\ndirections = {directions}\ncenter_mm = [0.0, 0.0, 0.0]\n"
    );
    for (a, k) in ["X", "Y", "Z"].iter().zip(kv) {
        body += &format!(
            "[machine_overrides.axes.{a}.servo]\nmodel = \"first-order\"\nkv_per_s = {k}\n\
             [machine_overrides.axes.{a}.friction]\ncoulomb_n = 0.0\n"
        );
    }
    let dir = scratch("circle-feed", name);
    let path = dir.join("scenario.toml");
    std::fs::write(&path, scenario_text(&machine("vmc-3axis"), &body)).unwrap();
    let scenario = Scenario::load(&path).unwrap();
    let out = dir.join("out");
    simulate(&scenario, &out, false, &|_| {}).unwrap();
    let json = serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    (out, json)
}

/// The report page of the run folder `out`.
fn page(out: &Path) -> String {
    let folder = RunFolder::read(out).unwrap();
    render(&folder, &diagnose_run(&folder), None).unwrap()
}

/// The commanded tool speed between consecutive rows of each run of `trace.csv`,
/// `hypot(ΔX_cmd, ΔY_cmd) / Δt`, mm/min: (smallest, largest) over all runs.
fn trace_speed_range(out: &Path) -> (f64, f64) {
    let mut r = csv::Reader::from_path(out.join("trace.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |name: &str| h.iter().position(|c| c == name).unwrap();
    let (d, t, x, y) = (
        col("direction"),
        col("time_s"),
        col("X_cmd_mm"),
        col("Y_cmd_mm"),
    );
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut previous: Option<(String, f64, f64, f64)> = None;
    for rec in r.records() {
        let rec = rec.unwrap();
        let now: (String, f64, f64, f64) = (
            rec[d].to_string(),
            rec[t].parse().unwrap(),
            rec[x].parse().unwrap(),
            rec[y].parse().unwrap(),
        );
        if let Some(p) = previous.as_ref().filter(|p| p.0 == now.0) {
            let v = (now.2 - p.2).hypot(now.3 - p.3) / (now.1 - p.1) * 60.0;
            lo = lo.min(v);
            hi = hi.max(v);
        }
        previous = Some(now);
    }
    (lo, hi)
}

/// r 10 mm at F7000 and F10000: near the axes' limits, where the planner holds the feed.
/// The measured revolution runs at one speed from its start (the lead-in reached it), and
/// `at_feed` and `feed_min_mm_min` say what the trace's commanded positions say.
#[test]
fn held_circles_run_their_measured_revolution_at_one_speed_and_say_whether_it_is_f() {
    for feed in [7000.0, 10000.0] {
        let (out, json) = run_circle(
            &format!("held-{feed}"),
            10.0,
            feed,
            "[\"ccw\", \"cw\"]",
            [30.0; 3],
        );
        let (lo, hi) = trace_speed_range(&out);
        let b = &json["ballbar"];
        let at_feed = b["at_feed"]
            .as_bool()
            .expect("a generated circle says at_feed");
        let feed_min = b["feed_min_mm_min"].as_f64().unwrap();
        let feed_max = b["feed_max_mm_min"].as_f64().unwrap();
        println!("F{feed}: trace {lo:.1}..{hi:.1} mm/min, summary {feed_min:.1}..{feed_max:.1}, at_feed {at_feed}");
        // The trace's positions have 6 decimals (1 nm on a 1-ms step of about 0.1 mm).
        assert!((feed_min - lo).abs() <= 1e-3 * lo, "{feed_min} vs {lo}");
        assert!((feed_max - hi).abs() <= 1e-3 * hi, "{feed_max} vs {hi}");
        let within = |v: f64| (v - feed).abs() <= 0.01 * feed;
        assert_eq!(at_feed, within(lo) && within(hi), "F{feed}: {lo}..{hi}");
        // Whatever speed the planner holds the circle at, the lead-in brought the tool to it:
        // the measured revolution does not accelerate (it started at 2,638 mm/min).
        assert!(hi - lo <= 0.002 * hi, "F{feed}: {lo}..{hi} mm/min");
        // And the lead-in says the speed it reached, not the one it planned.
        let reached = json["lead_in"]["reached_mm_min"].as_f64().unwrap();
        assert!((reached - lo).abs() <= 0.002 * lo, "{reached} vs {lo}");
        assert_eq!(
            json["lead_in"]["whole_turns"],
            serde_json::Value::Bool(true)
        );
        // A held feed is said, on the page's G and in the warnings.
        assert_eq!(page(&out).contains("data-warning=\"feed\""), !at_feed);
        if !at_feed {
            let warnings = json["warnings"].as_array().unwrap();
            assert!(
                warnings
                    .iter()
                    .any(|w| w.as_str().unwrap().contains("did not reach the programmed")),
                "{warnings:?}"
            );
        }
    }
}

/// r 10 mm at F3000 is far from every limit: the tool runs at F over the whole revolution.
#[test]
fn a_circle_the_machine_can_hold_is_at_feed() {
    let (out, json) = run_circle("free", 10.0, 3000.0, "[\"ccw\"]", [30.0; 3]);
    let (lo, hi) = trace_speed_range(&out);
    assert!(
        (lo - 3000.0).abs() < 1.0 && (hi - 3000.0).abs() < 1.0,
        "{lo}..{hi}"
    );
    assert_eq!(json["ballbar"]["at_feed"], serde_json::Value::Bool(true));
    assert!(!page(&out).contains("data-warning=\"feed\""));
}

/// One direction cannot tell a servo mismatch from squareness: with Kv 30/27 both are null
/// with the reason, never a number (they read −1,234 µrad and 0.0 ms).
#[test]
fn a_one_direction_circle_gives_null_squareness_and_mismatch_with_the_reason() {
    let (out, json) = run_circle("one-way", 50.0, 1000.0, "[\"ccw\"]", [30.0, 27.0, 30.0]);
    let c = &json["diagnostics"]["circle"];
    for field in [
        "squareness_urad",
        "squareness_um_per_m",
        "servo_mismatch_ms",
        "servo_mismatch_pp_um",
        "scale_mismatch_ppm",
    ] {
        assert!(c[field].is_null(), "{field}: {}", c[field]);
        let why = c["not_measured"][field].as_str().unwrap();
        assert!(why.starts_with("needs both directions"), "{field}: {why}");
    }
    // The page says the same, and gives no number.
    let page = page(&out);
    for key in ["squareness", "servo-mismatch", "scale-mismatch"] {
        let cell = format!("data-circle=\"{key}\">not measured: needs both directions");
        assert!(page.contains(&cell), "{key}");
    }
}

/// Both directions with Kv 30/27 at r 50 mm F1000: the mismatch against the closed form
/// `T_x − T_y = 1/Kv_x − 1/Kv_y` = −3.704 ms within 2 %, no squareness (below 1 µrad), and
/// the apparent scale mismatch `(3/2) ω² (T_y² − T_x²)` = 43.4 ppm taken out of the scale.
#[test]
fn a_two_direction_circle_gives_the_kv_mismatch_in_ms() {
    let (_, json) = run_circle(
        "two-way",
        50.0,
        1000.0,
        "[\"ccw\", \"cw\"]",
        [30.0, 27.0, 30.0],
    );
    let c = &json["diagnostics"]["circle"];
    let (tx, ty) = (1.0 / 30.0, 1.0 / 27.0);
    let want_ms = (tx - ty) * 1e3;
    let ms = c["servo_mismatch_ms"].as_f64().unwrap();
    assert!(
        (ms - want_ms).abs() <= 0.02 * want_ms.abs(),
        "{ms} ms vs {want_ms} ms"
    );
    let squareness = c["squareness_urad"].as_f64().unwrap();
    assert!(squareness.abs() < 1.0, "{squareness} µrad");
    let w = 1000.0 / 60.0 / 50.0;
    let apparent = 1.5 * w * w * (ty * ty - tx * tx) * 1e6;
    let servo_scale = c["servo_scale_ppm"].as_f64().unwrap();
    assert!(
        (servo_scale - apparent).abs() <= 0.03 * apparent,
        "{servo_scale} vs {apparent}"
    );
    let scale = c["scale_mismatch_ppm"].as_f64().unwrap();
    assert!(scale.abs() <= 0.03 * apparent, "{scale} ppm");
    assert!(c.get("not_measured").is_none(), "{c}");
}
