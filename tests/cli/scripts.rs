//! The command line as scripts use it: JSON shapes, exit codes and error messages.

use crate::common;

use common::{mtsim, scratch, stdout_json, trt_ac, write_scenario, CONE_15_10};

/// Writes a scenario for the bundled trt-ac machine with `body` after its `machine =` line.
fn scenario(dir: &std::path::Path, body: &str) -> String {
    write_scenario(dir, &trt_ac(), body).display().to_string()
}

#[test]
fn analyze_json_gives_every_axis_with_sorted_reversals_in_0_360() {
    let v = stdout_json(&mtsim(&["analyze", "scenarios/cone-15-10.toml", "--json"]));
    for axis in ["X", "Y", "Z", "A", "C"] {
        let a = &v["axes"][axis];
        for key in ["min", "max", "range", "peak_speed_per_min"] {
            assert!(a[key].is_f64(), "{axis}.{key} in {a}");
        }
        let r: Vec<f64> = a["reversals_deg"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert!(
            r.windows(2).all(|w| w[0] <= w[1]) && r.iter().all(|t| (0.0..360.0).contains(t)),
            "{axis}: {r:?}"
        );
    }
    // The spec's table: X reverses at 131.15 and 228.85 deg on the 15/10 cone at YT = 0.
    let x: Vec<f64> = v["axes"]["X"]["reversals_deg"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(
        (x[0] - 131.15).abs() < 0.05 && (x[1] - 228.85).abs() < 0.05,
        "{x:?}"
    );
    assert!(v["min_linear_separation_deg"].as_f64().unwrap() < 1e-6);
}

#[test]
fn sweep_json_reports_rows_and_the_coincidence() {
    let v = stdout_json(&mtsim(&[
        "sweep",
        "scenarios/cone-15-10.toml",
        "--vary",
        "center_y",
        "--from",
        "-30",
        "--to",
        "-15",
        "--step",
        "1",
        "--json",
    ]));
    assert_eq!(v["param"], "center_y");
    assert_eq!(v["rows"].as_array().unwrap().len(), 16);
    assert!(v["rows"][0]["reversals_deg"]["X"].is_array());
    let c = &v["coincidences"][0];
    assert!((c["value"].as_f64().unwrap() - -22.3).abs() < 0.11, "{c}");
    assert!(
        (c["theta_deg"].as_f64().unwrap() - 147.0).abs() < 0.5,
        "{c}"
    );
    assert!(c["spread_deg"].as_f64().unwrap() < 0.5);
}

#[test]
fn sweep_writes_a_csv_and_an_svg() {
    let dir = scratch("cli", "sweep");
    let out = mtsim(&[
        "sweep",
        "scenarios/cone-45-30.toml",
        "--vary",
        "center_y",
        "--from",
        "-60",
        "--to",
        "-40",
        "--step",
        "2",
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("sweep-center_y.csv")).unwrap();
    assert!(csv.starts_with("center_y,axis,reversal_deg,spread_deg"));
    let svg = std::fs::read_to_string(dir.join("sweep-center_y.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("X, Y, Z coincide"));
}

#[test]
fn cone_writes_360_g01_blocks_with_the_parameters_in_the_header() {
    let dir = scratch("cli", "cone");
    let nc = dir.join("cone.nc");
    let out = mtsim(&[
        "cone",
        "scenarios/cone-15-10.toml",
        "-o",
        nc.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&nc).unwrap();
    assert_eq!(text.lines().filter(|l| l.starts_with("G01")).count(), 360);
    assert!(text.contains("HALF APEX ANGLE 15.0000 DEG, INCLINATION 10.0000 DEG"));
    // The start point: A = alpha + beta = 25 deg, C = -90 deg (the spec).
    let start = text.lines().find(|l| l.starts_with("G00")).unwrap();
    assert!(
        start.contains("A25.0000") && start.contains("C-90.0000"),
        "{start}"
    );
    assert!(!dir.join("cone.nc.tmp").exists());
}

#[test]
fn a_missing_scenario_exits_2_and_names_the_file() {
    let out = mtsim(&["analyze", "no/such/scenario.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such/scenario.toml"));
}

#[test]
fn an_unknown_key_exits_2_and_names_the_key_and_line() {
    let dir = scratch("cli", "unknown");
    let s = scenario(&dir, &format!("{CONE_15_10}feed_rate = 3.0\n"));
    let out = mtsim(&["analyze", &s]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("feed_rate") && err.contains(":7:"), "{err}");
}

#[test]
fn a_half_apex_angle_outside_0_90_exits_2_and_names_the_key_and_line() {
    let dir = scratch("cli", "apex");
    let s = scenario(&dir, "[program.cone]\nhalf_apex_deg = 95.0\ninclination_deg = 10.0\ncenter_mm = [0.0, 0.0, 200.0]\nballbar_length_mm = 100.0\n");
    let out = mtsim(&["analyze", &s]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("half_apex_deg") && err.contains(":3:") && err.contains("(0, 90)"),
        "{err}"
    );
}

#[test]
fn nan_and_syntax_errors_exit_2_without_a_panic() {
    let dir = scratch("cli", "nan");
    for body in [
        "[program.cone]\nhalf_apex_deg = nan\ninclination_deg = 10.0\ncenter_mm = [0.0, 0.0, 200.0]\nballbar_length_mm = 100.0\n",
        "[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [0.0, nan, 200.0]\nballbar_length_mm = 100.0\n",
        "[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [0.0, 0.0]\nballbar_length_mm = 100.0\n",
        "[program.cone\nhalf_apex_deg = 15.0\n",
        "[program]\n",
    ] {
        let s = scenario(&dir, body);
        let out = mtsim(&["analyze", &s]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{body}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn a_bad_machine_override_exits_2() {
    let dir = scratch("cli", "override");
    let s = scenario(
        &dir,
        &format!("{CONE_15_10}[machine_overrides.axes.X]\nmin = 500.0\n"),
    );
    let out = mtsim(&["analyze", &s]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("max"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_sweep_range_that_breaks_the_geometry_exits_2() {
    let out = mtsim(&[
        "sweep",
        "scenarios/cone-15-10.toml",
        "--vary",
        "half_apex",
        "--from",
        "80",
        "--to",
        "95",
        "--step",
        "5",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("half_apex_deg"));
}

#[test]
fn simulate_writes_the_trace_summary_and_plot_and_repeats_byte_for_byte() {
    let (a, b) = (scratch("cli", "sim-a"), scratch("cli", "sim-b"));
    for dir in [&a, &b] {
        let out = mtsim(&[
            "simulate",
            "scenarios/circle-iso230-4.toml",
            "-o",
            dir.to_str().unwrap(),
            "--no-timing",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    for file in ["trace.csv", "summary.json", "ballbar.svg"] {
        let (x, y) = (
            std::fs::read(a.join(file)).unwrap(),
            std::fs::read(b.join(file)).unwrap(),
        );
        assert!(x == y, "{file} differs between two runs");
    }
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    assert!(v["sim_time_s"].as_f64().unwrap() > 0.0);
    assert!(
        v["realtime_factor"].is_null(),
        "--no-timing leaves the timing out"
    );
    let bb = &v["ballbar"];
    for key in [
        "circular_deviation_um",
        "radial_max_um",
        "radial_min_um",
        "hysteresis_um",
    ] {
        assert!(bb[key].is_f64(), "{key}: {bb}");
    }
    let spike = &bb["spikes"][0];
    assert!(
        spike["theta_deg"].is_f64() && spike["height_um"].is_f64() && spike["axis"].is_string()
    );
    assert!(["spike", "step"].contains(&spike["kind"].as_str().unwrap()));
    let header = std::fs::read_to_string(a.join("trace.csv"))
        .unwrap()
        .lines()
        .next()
        .unwrap()
        .to_string();
    for col in ["theta_deg", "deviation_um"] {
        assert!(header.split(',').any(|c| c == col), "{header}");
    }
    // The centre is in summary.json, not a column (docs/simulation.md, "Outputs").
    assert!(!header.contains("deviation_centred_um"), "{header}");
    assert!(bb["runs"][0]["centring"]["a_um"].is_f64());
    assert!(!a.join("trace.csv.tmp").exists());
}

#[test]
fn simulate_reports_the_real_time_factor_by_default() {
    let dir = scratch("cli", "sim-rtf");
    let out = mtsim(&[
        "simulate",
        "scenarios/cone-45-30.toml",
        "-o",
        dir.to_str().unwrap(),
        "--json",
    ]);
    let v = stdout_json(&out);
    assert!(v["realtime_factor"].as_f64().unwrap() > 0.0);
    assert!(
        v["hysteresis_um"].is_null() || v["ballbar"]["hysteresis_um"].is_null(),
        "one direction: H is null"
    );
}

#[test]
fn a_diverging_servo_exits_3_and_names_the_axis() {
    // A velocity loop far too fast for its 1 ms period rings up past the drive's 0.5 mm alarm.
    let dir = scratch("cli", "diverge");
    let s = scenario(
        &dir,
        &format!("{CONE_15_10}[machine_overrides.axes.Y.servo]\nvelocity_bandwidth_hz = 3000.0\nservo_period_ms = 1.0\nfollowing_error_limit_mm = 0.5\n"),
    );
    let out = mtsim(&["simulate", &s, "-o", dir.join("out").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(err.contains("axis Y"), "{err}");
    assert!(!dir.join("out/trace.csv").exists(), "no partial trace");
}

#[test]
fn a_bad_direction_exits_2_and_names_the_key() {
    let dir = scratch("cli", "direction");
    let s = scenario(&dir, &format!("{CONE_15_10}directions = [\"up\"]\n"));
    let out = mtsim(&["simulate", &s, "-o", dir.join("out").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("directions") && err.contains(":7:"), "{err}");
}
