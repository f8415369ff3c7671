//! `simulate`'s `check.json`: the run's own setpoints checked as they are made
//! (`src/check/of_run.rs`), against closed forms of the programmed path and against
//! `mtsim check` where the two must agree.

use crate::common;

use common::{mtsim, scratch, stdout_json};

/// Runs `simulate` on `scenario` into `dir/out`; returns the exit code and `check.json`.
fn simulate_check(dir: &std::path::Path, scenario: &str) -> (i32, serde_json::Value) {
    let out_dir = dir.join("out");
    let out = mtsim(&[
        "simulate",
        scenario,
        "-o",
        out_dir.to_str().unwrap(),
        "--no-budget",
        "-q",
        "--no-timing",
    ]);
    let code = out.status.code().unwrap();
    assert!(
        code == 0 || code == 1,
        "exit {code}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read(out_dir.join("check.json")).unwrap();
    (code, serde_json::from_slice(&text).unwrap())
}

fn axis<'a>(v: &'a serde_json::Value, a: &str, key: &str) -> f64 {
    v["axes"][a][key]
        .as_f64()
        .unwrap_or_else(|| panic!("{a}.{key}: {v}"))
}

/// A G-code program on the three-axis machine (limits 3000 mm/s², 50,000 mm/s³ on X Y Z).
fn vmc_program(name: &str, program: &str) -> (std::path::PathBuf, String) {
    let dir = scratch("of-run", name);
    let s = common::file_scenario(&dir, program);
    (dir, s)
}

#[test]
fn a_straight_move_peaks_at_its_feed_and_its_s_curve_acceleration() {
    // The first move (the rapid from the reader's zero to Z100) is not checked: Z stands at
    // 100 mm from the first checked sample on, and never moves.
    let (dir, s) = vmc_program("line", "G00 X0 Y0 Z100\nG01 X200 F6000\n");
    let (code, v) = simulate_check(&dir, &s);
    assert_eq!(code, 0, "{v}");
    assert_eq!(v["timing"], "run");
    assert!(v["violations"].as_array().unwrap().is_empty(), "{v}");
    // X from 0 to 200 mm at F6000 = 100 mm/s: the peak speed is F (the cruise, where the
    // difference of two samples is exact to rounding).
    assert!(
        (axis(&v, "X", "peak_velocity_per_min") - 6000.0).abs() < 1e-6,
        "{v}"
    );
    assert!(axis(&v, "X", "min").abs() < 1e-9 && (axis(&v, "X", "max") - 200.0).abs() < 1e-9);
    // A jerk-limited start to v = 100 mm/s with j = 50,000 mm/s³ and a = 3000 mm/s²
    // (v < a²/j = 180 mm/s): no constant-acceleration phase, the peak is sqrt(v j) =
    // 2236.07 mm/s². A second difference averages the acceleration over two periods, within
    // one of the peak: between sqrt(v j) - j T and sqrt(v j).
    let (peak, jt) = ((100.0f64 * 50_000.0).sqrt(), 50_000.0 * 1e-3);
    let a = axis(&v, "X", "peak_acceleration_per_s2");
    assert!(
        a <= peak * (1.0 + 1e-9) && a >= peak - jt,
        "{a} against {peak}"
    );
    // The jerk, averaged likewise, never exceeds its limit.
    assert!(
        axis(&v, "X", "peak_jerk_per_s3") <= 50_000.0 * (1.0 + 1e-6),
        "{v}"
    );
    // The first checked sample is the first move's last one, within a period of the move's
    // end, which it reaches at a junction speed of at most a T (the planner's corner cap):
    // at most a T·T + a T²/2 = 4.5 µm short of 100 mm.
    assert!((axis(&v, "Z", "max") - 100.0).abs() < 1e-9, "{v}");
    let short = 100.0 - axis(&v, "Z", "min");
    assert!(
        (0.0..=1.5 * 3000.0 * 1e-6 * (1.0 + 1e-9)).contains(&short),
        "{short} mm"
    );
    assert!(axis(&v, "Z", "peak_velocity_per_min") < 1e-6, "{v}");
    // One sample a period from the first move's last one to the end: at least the cruise's
    // 200 mm / 100 mm/s = 2 s.
    let samples = v["samples"].as_u64().unwrap();
    assert!((2000..3000).contains(&samples), "{samples}");
}

#[test]
fn a_circle_peaks_at_its_feed_on_the_axis_that_crosses_its_quadrant() {
    // A full circle of radius 50 mm about (0, 0) at F3000 (50 mm/s): at X = -50 the tool
    // moves along -Y alone, at the full feed.
    let (dir, s) = vmc_program("circle", "G00 X50 Y0 Z100\nG03 X50 Y0 I-50 J0 F3000\n");
    let (code, v) = simulate_check(&dir, &s);
    assert_eq!(code, 0, "{v}");
    // The sample nearest X = -50 is within half a period (ω = 1 rad/s: 0.5 mrad) of it:
    // Y's speed there is F cos(0.5e-3) = F (1 - 1.25e-7).
    let vy = axis(&v, "Y", "peak_velocity_per_min");
    assert!(
        vy <= 3000.0 * (1.0 + 1e-9) && vy >= 3000.0 * (1.0 - 1e-6),
        "{vy}"
    );
    // The circle's extent, within a sample's chord sagitta (r (1 - cos 0.5e-3) = 6 nm).
    assert!((axis(&v, "X", "min") + 50.0).abs() < 1e-5, "{v}");
    assert!((axis(&v, "Y", "min") + 50.0).abs() < 1e-5, "{v}");
    assert!((axis(&v, "Y", "max") - 50.0).abs() < 1e-5, "{v}");
}

#[test]
fn a_travel_overrun_is_flagged_as_check_flags_it() {
    // X to 500 mm on a -400 .. 400 mm axis.
    let (dir, s) = vmc_program("overrun", "G00 X0 Y0 Z100\nG01 X500 F6000\n");
    let check = mtsim(&["check", &s, "--json"]);
    assert_eq!(check.status.code(), Some(1));
    let check: serde_json::Value = serde_json::from_slice(&check.stdout).unwrap();
    let (code, v) = simulate_check(&dir, &s);
    assert_eq!(code, 1);
    let (ours, theirs) = (
        v["violations"].as_array().unwrap(),
        check["violations"].as_array().unwrap(),
    );
    assert_eq!(ours.len(), 1, "{v}");
    assert_eq!(ours.len(), theirs.len());
    for key in ["kind", "axis", "line", "worst", "limit"] {
        assert_eq!(ours[0][key], theirs[0][key], "{key}");
    }
    assert_eq!(ours[0]["worst"].as_f64(), Some(500.0));
    // Both checks see the X move alone, from rest to rest: the same peaks.
    for key in ["peak_velocity_per_min", "max"] {
        let (a, b) = (axis(&v, "X", key), axis(&check, "X", key));
        assert!((a - b).abs() <= 1e-9 * b.abs(), "{key}: {a} against {b}");
    }
}

#[test]
fn both_directions_of_a_cone_test_are_checked_each_on_its_own_clock() {
    // Two runs, each starting from the reader's zero: the counter-clockwise run ends at
    // its lead-out's end, the clockwise one starts at its own lead-in's start, elsewhere.
    // The jump between them is no motion, so the test stays clean, and both runs' samples
    // are counted.
    let dir = scratch("of-run", "both");
    let s = "scenarios/cone-15-10-offset.toml";
    let (code, v) = simulate_check(&dir, s);
    assert_eq!(code, 0, "{v}");
    let out = mtsim(&[
        "simulate",
        s,
        "-o",
        dir.join("out2").to_str().unwrap(),
        "--no-budget",
        "--json",
        "--no-timing",
    ]);
    let summary = stdout_json(&out);
    let (checked, setpoints) = (
        v["samples"].as_u64().unwrap(),
        summary["setpoints"].as_u64().unwrap(),
    );
    // Each run's first move (the rapid to the start) is left out but for its last sample.
    assert!(
        checked < setpoints && checked * 10 > setpoints * 9,
        "{checked} of {setpoints}"
    );
    assert_eq!(summary["directions"].as_array().unwrap().len(), 2);
}

/// The fork head's 15/10 cone at O = 0, both directions, written into `dir`.
fn fork_head_cone(dir: &std::path::Path, directions: &str) -> String {
    let path = dir.join("fork.toml");
    std::fs::write(
        &path,
        format!(
            "machine = {:?}\n[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [0.0, 0.0, 0.0]\nballbar_length_mm = 100.0\nfeed_mm_min = 2000.0\ndirections = {directions}\n[check]\ncollisions = false\n",
            common::machine("fork-head-ca")
        ),
    )
    .unwrap();
    path.display().to_string()
}

#[test]
fn a_clockwise_revolution_keeps_c_within_its_travel_in_the_run_and_in_check() {
    // C of ±360 deg turns one whole revolution a direction, from −90 deg at θ = 0: the
    // clockwise run starts a turn up (270 → −90 deg), so the run's C stays within
    // −90 − lead .. 270 + lead and both checks are clean. (Started at −90 deg, it reached
    // −462 deg with its lead arc.)
    let dir = scratch("of-run", "fork-cw");
    let s = fork_head_cone(&dir, "[\"ccw\", \"cw\"]");
    let (code, v) = simulate_check(&dir, &s);
    assert_eq!(code, 0, "{v}");
    let (min, max) = (axis(&v, "C", "min"), axis(&v, "C", "max"));
    assert!(min > -120.0 && max < 300.0, "C {min}..{max}");
    let checked = stdout_json(&mtsim(&["check", &s, "--json"]));
    assert_eq!(checked["violations"].as_array().unwrap().len(), 0);
    // `check` plans each direction's revolution without leads: −90 .. 270 deg exactly.
    assert!(
        (axis(&checked, "C", "min") + 90.0).abs() < 1e-6,
        "{checked}"
    );
    assert!(
        (axis(&checked, "C", "max") - 270.0).abs() < 1e-6,
        "{checked}"
    );
}

#[test]
fn check_plans_every_direction_the_scenario_runs() {
    // The clockwise revolution mirrors the counter-clockwise one, at the same planner's
    // timing: checked in both directions, twice the samples of one (within a sample each).
    let dir = scratch("of-run", "check-dirs");
    let both = fork_head_cone(&dir, "[\"ccw\", \"cw\"]");
    let two = stdout_json(&mtsim(&["check", &both, "--json"]));
    let dir1 = scratch("of-run", "check-dirs1");
    let ccw = fork_head_cone(&dir1, "[\"ccw\"]");
    let one = stdout_json(&mtsim(&["check", &ccw, "--json"]));
    let (n2, n1) = (
        two["samples"].as_u64().unwrap(),
        one["samples"].as_u64().unwrap(),
    );
    assert!(n2.abs_diff(2 * n1) <= 2, "{n2} against 2 x {n1}");
    let (t2, t1) = (
        two["sim_time_s"].as_f64().unwrap(),
        one["sim_time_s"].as_f64().unwrap(),
    );
    assert!((t2 - 2.0 * t1).abs() < 0.005, "{t2} against 2 x {t1}");
}
