//! `mtsim check` against answers known in advance: windows computed from the path itself,
//! block times from the words, and the exit codes scripts rely on.

use crate::common;

use common::{mtsim, scratch, stdout_json, trt_ac, write_scenario, CONE_15_10};

/// Runs `check --json` on a scenario body (and an NC program, if any); returns exit code and JSON.
fn check(name: &str, body: &str, nc: Option<&str>, extra: &[&str]) -> (i32, serde_json::Value) {
    let dir = scratch("check", name);
    if let Some(nc) = nc {
        std::fs::write(dir.join("p.nc"), nc).unwrap();
    }
    let path = write_scenario(&dir, &trt_ac(), body);
    let mut args = vec!["check", path.to_str().unwrap(), "--json"];
    args.extend_from_slice(extra);
    let out = mtsim(&args);
    let code = out.status.code().unwrap();
    assert!(
        code == 0 || code == 1,
        "exit {code}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (code, serde_json::from_slice(&out.stdout).unwrap())
}

fn violations<'a>(v: &'a serde_json::Value, kind: &str) -> Vec<&'a serde_json::Value> {
    v["violations"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|x| x["kind"] == kind)
        .collect()
}

/// X(θ) of the 15/10 cone at O = (0, 0, 200), L = 100, written out from the spec:
/// X = (Rz(C) P).x with C = atan2(i, j) of t = unit(apex - P).
fn spec_x(theta_deg: f64) -> f64 {
    let (al, be, th) = (
        15f64.to_radians(),
        10f64.to_radians(),
        theta_deg.to_radians(),
    );
    let (r, h, l) = (100.0 * al.cos(), 100.0 * al.sin(), 100.0 / al.sin());
    let ry = |x: f64, y: f64, z: f64| [x * be.cos() - z * be.sin(), y, x * be.sin() + z * be.cos()];
    let p = ry(r * th.cos(), r * th.sin(), h);
    let apex = ry(0.0, 0.0, l);
    let c = (apex[0] - p[0]).atan2(apex[1] - p[1]);
    c.cos() * p[0] - c.sin() * p[1]
}

#[test]
fn a_lowered_x_limit_is_crossed_inside_the_theta_window_computed_from_the_path() {
    let (code, v) = check(
        "travel",
        &format!("{CONE_15_10}[machine_overrides.axes.X]\nmax = 50.0\n"),
        None,
        &[],
    );
    assert_eq!(code, 1);
    // The window where X > 50 mm on the exact path: sign changes of X - 50 on a 0.1-deg
    // grid, bisected on the spec's formula.
    let above = |t: f64| spec_x(t) > 50.0;
    let mut crossings = Vec::new();
    for k in 0..3600 {
        let (mut lo, mut hi) = (k as f64 * 0.1, (k + 1) as f64 * 0.1);
        if above(lo) != above(hi) {
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if above(mid) == above(lo) {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            crossings.push(0.5 * (lo + hi));
        }
    }
    assert_eq!(crossings.len(), 2, "{crossings:?}");
    let (enter, leave) = (crossings[0], crossings[1]);
    let peak = (0..36000)
        .map(|k| spec_x(k as f64 * 0.01))
        .fold(f64::NEG_INFINITY, f64::max);
    let t = violations(&v, "travel");
    assert_eq!(t.len(), 1, "{t:?}");
    assert_eq!(t[0]["axis"], "X");
    let (start, end) = (
        t[0]["theta_start_deg"].as_f64().unwrap(),
        t[0]["theta_end_deg"].as_f64().unwrap(),
    );
    // 1 ms samples are 0.01 deg apart; the 1-deg joint-space chords stay within 0.05 deg.
    assert!(
        (start - enter).abs() < 0.05 && (end - leave).abs() < 0.05,
        "{start}..{end} vs {enter}..{leave}"
    );
    assert!(
        (t[0]["worst"].as_f64().unwrap() - peak).abs() < 0.01,
        "{} vs {peak}",
        t[0]
    );
    assert_eq!(t[0]["limit"].as_f64().unwrap(), 50.0);
    assert!(v["axes"]["X"]["margin"].as_f64().unwrap() < -17.0);
}

#[test]
fn a_mid_block_travel_excursion_that_the_end_points_miss_is_found() {
    // Under G43.4 the tip stays at table (100, 0, 50) while C turns from -90 to +90 deg:
    // machine X = 100 cos C is 0 at both ends and 100 mm half way, past the 50 mm limit.
    let nc = "G21 G90 G94\nG43.4 H1\nG00 X100 Y0 Z50 A0 C-90\nG01 C90 F1000\nG49\nM30\n";
    let body = "[program]\nfile = \"p.nc\"\n[machine_overrides.axes.X]\nmax = 50.0\n";
    let (code, v) = check("midblock", body, Some(nc), &["--programmed"]);
    assert_eq!(code, 1);
    let t = violations(&v, "travel");
    assert_eq!(t.len(), 1, "{t:?}");
    assert_eq!(t[0]["line"], 4);
    assert!(
        (t[0]["worst"].as_f64().unwrap() - 100.0).abs() < 1e-3,
        "{}",
        t[0]
    );
    // The block takes 180 deg / F1000 = 10.8 s (mixed rule for a pure rotary move); X passes
    // 50 mm at C = -60 and +60 deg, i.e. from 1/6 to 5/6 of the block.
    let (t0, t1) = (
        t[0]["time_start_s"].as_f64().unwrap(),
        t[0]["time_end_s"].as_f64().unwrap(),
    );
    assert!(
        (t0 - 1.8).abs() < 0.002 && (t1 - 9.0).abs() < 0.002,
        "{t0}..{t1}"
    );
    assert!(
        t[0]["theta_start_deg"].is_null(),
        "a file without geometry has no theta"
    );
}

#[test]
fn inverse_time_blocks_that_are_too_short_exceed_the_velocity_limit() {
    // G93 F600: the block takes 1/600 min = 0.1 s, so 100 mm of X is 60000 mm/min.
    let nc = "G21 G90 G94\nG00 X0 Y0 Z100 A0 C0\nG93 G01 X100 F600\nM30\n";
    let (code, v) = check(
        "g93",
        "[program]\nfile = \"p.nc\"\n",
        Some(nc),
        &["--programmed"],
    );
    assert_eq!(code, 1);
    let vel = violations(&v, "velocity");
    assert_eq!(vel.len(), 1, "{vel:?}");
    assert_eq!(
        (vel[0]["axis"].as_str(), vel[0]["line"].as_u64()),
        (Some("X"), Some(3))
    );
    assert!(
        (vel[0]["worst"].as_f64().unwrap() - 60000.0).abs() < 1.0,
        "{}",
        vel[0]
    );
    assert_eq!(vel[0]["limit"].as_f64().unwrap(), 30000.0);
}

#[test]
fn a_tcp_move_that_asks_too_much_of_c_exceeds_its_velocity_limit() {
    // The tip moves 1 mm at F1000 (0.06 s) while C turns 90 deg: 90000 deg/min against 9000.
    let nc = "G21 G90 G94\nG43.4 H1\nG00 X100 Y0 Z50 A0 C0\nG01 X101 C90 F1000\nG49\nM30\n";
    let (code, v) = check(
        "tcp",
        "[program]\nfile = \"p.nc\"\n",
        Some(nc),
        &["--programmed"],
    );
    assert_eq!(code, 1);
    let c: Vec<_> = violations(&v, "velocity")
        .into_iter()
        .filter(|x| x["axis"] == "C")
        .collect();
    assert_eq!(c.len(), 1, "{v}");
    assert!(
        (c[0]["worst"].as_f64().unwrap() - 90000.0).abs() < 50.0,
        "{}",
        c[0]
    );
}

#[test]
fn the_near_miss_threshold_is_honoured() {
    let (_, clean) = check("nm-ref", CONE_15_10, None, &[]);
    let smallest = clean["min_clearance_mm"].as_f64().unwrap();
    assert!(smallest > 2.0, "the bundled set-up is clear: {smallest}");
    let above = format!("{}", smallest + 0.5);
    let below = format!("{}", smallest - 0.5);
    let (code, v) = check("nm-above", CONE_15_10, None, &["--near-miss", &above]);
    assert_eq!(code, 1);
    let nm = violations(&v, "near_miss");
    assert!(
        !nm.is_empty()
            && nm
                .iter()
                .all(|x| x["worst"].as_f64().unwrap() < smallest + 0.5)
    );
    // Below the threshold the pair is measured at every sample, so the worst near miss is
    // at most the clean run's smallest clearance (an upper bound from sparser queries) and
    // within the 1 um that 1 ms sampling allows of it.
    assert!(
        nm.iter().any(|x| {
            let worst = x["worst"].as_f64().unwrap();
            worst <= smallest + 1e-9 && smallest - worst < 1e-3
        }),
        "smallest {smallest}, near misses {nm:?}"
    );
    let (code, v) = check("nm-below", CONE_15_10, None, &["--near-miss", &below]);
    assert_eq!(code, 0, "{v}");
}

#[test]
fn a_short_tool_drives_the_holder_into_the_frustum() {
    // A frustum 45 mm tall (along its axis; the tip runs at L sin 15 deg = 25.9 mm) and a
    // tool whose 50 mm holder starts 10 mm above the tip: the holder reaches far past the
    // cutter's 10 mm radius while the flank is tangent to the frustum, so it hits the
    // frustum above the tip.
    let body = format!(
        "{CONE_15_10}[workpiece]\nkind = \"cone-frustum\"\ntop_height_mm = 45.0\n\
         [tool]\ncutter_diameter_mm = 20.0\nflute_length_mm = 8.0\nshank_diameter_mm = 20.0\nshank_length_mm = 2.0\nholder_diameter_mm = 50.0\nholder_length_mm = 30.0\ngauge_length_mm = 40.0\n"
    );
    let (code, v) = check("short-tool", &body, None, &[]);
    assert_eq!(code, 1);
    let c = violations(&v, "collision");
    assert!(
        c.iter().any(|x| x["bodies"]
            .as_array()
            .unwrap()
            .iter()
            .any(|b| b == "holder")),
        "{v}"
    );
}

/// The depth tolerance of the collisions is in the output: `collision_depth_tolerance` in
/// the JSON (the documented defaults, 0.01 mm + 1 %, or the machine's `[scene]` values) and
/// a line of the text when there is a collision; 0 and 0 give exact depths.
#[test]
fn the_collision_depth_tolerance_is_reported() {
    let body = format!(
        "{CONE_15_10}[workpiece]\nkind = \"cone-frustum\"\ntop_height_mm = 45.0\n\
         [tool]\ncutter_diameter_mm = 20.0\nflute_length_mm = 8.0\nshank_diameter_mm = 20.0\nshank_length_mm = 2.0\nholder_diameter_mm = 50.0\nholder_length_mm = 30.0\ngauge_length_mm = 40.0\n"
    );
    let (_, v) = check("tolerance-default", &body, None, &[]);
    assert_eq!(v["collision_depth_tolerance"]["mm"], 0.01, "{v}");
    assert_eq!(v["collision_depth_tolerance"]["relative"], 0.01, "{v}");
    let exact = format!(
        "{body}[machine_overrides.scene]\ndepth_tolerance_mm = 0.0\ndepth_tolerance_relative = 0.0\n"
    );
    let (_, w) = check("tolerance-exact", &exact, None, &[]);
    assert_eq!(w["collision_depth_tolerance"]["mm"], 0.0, "{w}");
    assert_eq!(w["collision_depth_tolerance"]["relative"], 0.0, "{w}");
    let dir = scratch("check", "tolerance-text");
    let path = write_scenario(&dir, &trt_ac(), &body);
    let text =
        String::from_utf8_lossy(&mtsim(&["check", path.to_str().unwrap()]).stdout).into_owned();
    assert!(
        text.contains("no sample of the collision is deeper by more than 0.01 mm + 1 % of it"),
        "{text}"
    );
    // A clean check says nothing of it.
    let path = write_scenario(&dir, &trt_ac(), CONE_15_10);
    let text =
        String::from_utf8_lossy(&mtsim(&["check", path.to_str().unwrap()]).stdout).into_owned();
    assert!(!text.contains("collision depths"), "{text}");
}

#[test]
fn dynamics_catches_an_overshoot_that_the_commanded_path_does_not_have() {
    // A fast move ends exactly at the X limit; full velocity feedforward with a slow velocity
    // loop rings past it after the setpoints have stopped.
    let nc = "G21 G90 G94\nG00 X0 Y0 Z100 A0 C0\nG01 X100 F20000\nM30\n";
    let body = "[program]\nfile = \"p.nc\"\n[machine_overrides.axes.X]\nmax = 100.0\n\
                [machine_overrides.axes.X.servo]\nkv_per_s = 30.0\nvelocity_bandwidth_hz = 10.0\nvelocity_feedforward = 1.0\n\
                [machine_overrides.axes.X.friction]\ncoulomb_n = 0.0\n";
    let (code, v) = check("overshoot", body, Some(nc), &[]);
    assert_eq!(code, 0, "the program itself stays inside: {v}");
    let (code, v) = check("overshoot-dyn", body, Some(nc), &["--dynamics"]);
    assert_eq!(code, 1);
    let t = violations(&v, "travel");
    assert!(!t.is_empty(), "{v}");
    assert!(t
        .iter()
        .all(|x| x["axis"] == "X" && x["worst"].as_f64().unwrap() > 100.0));
    assert_eq!(v["dynamics"], true);
}

#[test]
fn every_bundled_scenario_checks_clean() {
    for s in [
        "cone-15-10",
        "cone-45-30",
        "cone-15-10-offset",
        "cone-15-10-yt25",
        "circle-iso230-4",
        "file-cone-15-10-yt25",
    ] {
        let out = mtsim(&["check", &format!("scenarios/{s}.toml")]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{s}: {}",
            String::from_utf8_lossy(&out.stdout)
        );
    }
}

#[test]
fn bad_input_exits_2() {
    let out = mtsim(&["check", "scenarios/cone-15-10.toml", "--near-miss", "-1"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn the_placement_map_marks_where_the_cone_fits_and_what_limits_it() {
    // The 45/30 cone: at the C axis the tool needs Y down to -293.185 mm (the spec's range),
    // inside the -350 mm travel; 300 mm off the axis along -Y it cannot fit.
    let dir = scratch("check", "placement");
    let out = mtsim(&[
        "sweep",
        "scenarios/cone-45-30.toml",
        "--feasibility",
        "--vary",
        "center_x,center_y",
        "--from",
        "0,-300",
        "--to",
        "0,0",
        "--step",
        "1,300",
        "--json",
        "-o",
        dir.to_str().unwrap(),
    ]);
    let v = stdout_json(&out);
    let cells = v["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 2);
    let at = |y: f64| cells.iter().find(|c| c["y"].as_f64() == Some(y)).unwrap();
    assert_eq!(at(0.0)["fits"], true, "{}", at(0.0));
    // The margin at the axis is the smaller of the Y travel margin (350 - 293.185) and the
    // smallest clearance; it is positive.
    let m = at(0.0)["margin_mm"].as_f64().unwrap();
    assert!(m > 0.0 && m <= 350.0 - 293.185 + 1e-6, "{m}");
    assert_eq!(at(-300.0)["fits"], false);
    // Named first; and the cone base (radius (L − R)/cos α) reaches past the table's edge.
    let limiting = at(-300.0)["limiting"].as_str().unwrap();
    assert!(limiting.starts_with("Y travel; cone base"), "{limiting}");
    assert!(limiting.ends_with("over the table edge"), "{limiting}");
    assert!(at(-300.0)["margin_mm"].as_f64().unwrap() < 0.0);
    let svg = std::fs::read_to_string(dir.join("placement.svg")).unwrap();
    assert!(svg.contains("does not fit") && svg.contains("margin"));
    assert!(std::fs::read_to_string(dir.join("placement.csv"))
        .unwrap()
        .starts_with("center_x,center_y,margin_mm,fits"));
}

#[test]
fn the_planner_holds_a_too_short_g93_block_at_the_x_limit_and_says_so() {
    // G93 F100 asks 600 mm of X in 0.6 s (60000 mm/min); the planner runs X at its 30000
    // (reached after 57 mm: (v/2)(v/a + a/j) with v 500 mm/s, a 3000 mm/s², j 50000 mm/s³).
    let dir = scratch("check", "g93-planned");
    let nc = "G21 G90 G94\nG00 X-300 Y0 Z100 A0 C0\nG93 G01 X300 F100\nM30\n";
    std::fs::write(dir.join("p.nc"), nc).unwrap();
    let path = write_scenario(&dir, &trt_ac(), "[program]\nfile = \"p.nc\"\n");
    let out = mtsim(&["check", path.to_str().unwrap(), "--json"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["timing"], "planned");
    let held = &v["feed_reductions"][0];
    assert_eq!(
        (held["axis"].as_str(), held["limit"].as_str()),
        (Some("X"), Some("velocity"))
    );
    assert_eq!(held["first_line"].as_u64(), Some(3));
    assert!(
        (held["planned_per_min"].as_f64().unwrap() - 30000.0).abs() < 1e-6,
        "{held}"
    );
    assert!(
        (held["programmed_per_min"].as_f64().unwrap() - 60000.0).abs() < 1e-6,
        "{held}"
    );
    let peak = v["axes"]["X"]["peak_velocity_per_min"].as_f64().unwrap();
    assert!((29990.0..=30000.0 * (1.0 + 1e-9)).contains(&peak), "{peak}");
    assert!(
        stderr.contains("feed held") && stderr.contains("X velocity limit"),
        "{stderr}"
    );
}

/// The largest per-junction velocity step of `axis_index` (X Y Z A C: 0..5) over a cone
/// program written by `mtsim cone`, per s: at block k the axis runs at `F d_i / L` with
/// `L = sqrt(Σ d²)` (deg counted as mm).
fn largest_junction_step(nc: &str, axis_index: usize) -> f64 {
    let mut previous: Option<[f64; 5]> = None;
    let mut velocities = Vec::new();
    for line in nc.lines() {
        if !(line.starts_with("G00") || line.starts_with("G01")) {
            continue;
        }
        let word = |letter: char| -> f64 {
            let w = line
                .split_whitespace()
                .find(|w| w.starts_with(letter))
                .unwrap();
            w[1..].parse().unwrap()
        };
        let q = [word('X'), word('Y'), word('Z'), word('A'), word('C')];
        if let (Some(p), true) = (previous, line.starts_with("G01")) {
            let d: Vec<f64> = (0..5).map(|i| q[i] - p[i]).collect();
            let l = d.iter().map(|x| x * x).sum::<f64>().sqrt();
            velocities.push(word('F') / 60.0 * d[axis_index] / l);
        }
        previous = Some(q);
    }
    velocities
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(0.0, f64::max)
}

#[test]
fn check_measures_the_accelerations_the_planners_samples_reach_on_the_cone() {
    let dir = scratch("check", "cone-accel");
    let path = write_scenario(&dir, &trt_ac(), CONE_15_10);
    let nc = dir.join("cone.nc");
    let out = mtsim(&["cone", path.to_str().unwrap(), "-o", nc.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    // A junction's velocity step, taken within one 1 ms period, or split over two when the
    // junction falls inside one: the sampled acceleration is between half of step/T and
    // the limit.
    let step = largest_junction_step(&std::fs::read_to_string(&nc).unwrap(), 0);
    assert!(step > 1.0, "{step} mm/s");
    let (code, v) = check("cone-accel", CONE_15_10, None, &[]);
    assert_eq!(code, 0, "{v}");
    assert_eq!(v["timing"], "planned");
    let x = &v["axes"]["X"];
    let peak = x["peak_acceleration_per_s2"].as_f64().unwrap();
    assert!(
        peak >= 0.5 * step / 1e-3 && peak <= 3000.0 * (1.0 + 1e-9),
        "X peak {peak} mm/s² against a junction step of {step} mm/s"
    );
    assert!(x["peak_jerk_per_s3"].as_f64().unwrap() > 0.0, "{x}");
    // At programmed timing the table says that junctions are not measured.
    let out = mtsim(&["check", path.to_str().unwrap(), "--programmed"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("accelerations at junctions between blocks are not measured"),
        "{text}"
    );
}

#[test]
fn an_inch_program_read_as_mm_that_leaves_the_travel_is_told_it_would_fit_in_inches() {
    // Written in inches, no G20: read in mm (the start unit), Y runs 3..6 mm, below the
    // lowered Y minimum of 50 mm. Read in inches, Y runs 76.2..152.4 mm, X 25.4..101.6,
    // Z 12.7..50.8: all within the travel (X ±400, Y 50..350, Z -150..450).
    let nc = "G90 G94 G17\nG00 X1. Y3. Z2.\nG01 Z0.5 F20\nG01 X4. Y6.\nG00 Z2.\nM30\n";
    let body = "[program]\nfile = \"p.nc\"\n[reader]\ndialect = \"fanuc\"\n\
                [machine_overrides.axes.Y]\nmin = 50.0\n";
    let (code, v) = check("inch_as_mm", body, Some(nc), &[]);
    assert_eq!(code, 1);
    let t = violations(&v, "travel");
    assert!(!t.is_empty(), "{v}");
    let note = t[0]["other_unit"]
        .as_str()
        .expect("the other unit is named");
    for part in [
        "reads in mm",
        "inch scale (×25.4)",
        "X 25.400 .. 101.600 mm",
        "Y 76.200 .. 152.400 mm",
        "Z 12.700 .. 50.800 mm",
    ] {
        assert!(note.contains(part), "{part}: {note}");
    }
    // The same program stating G21 is in mm on purpose: no note.
    let (code, v) = check("mm_stated", body, Some(&format!("G21 {nc}")), &[]);
    assert_eq!(code, 1);
    assert!(violations(&v, "travel")
        .iter()
        .all(|t| t.get("other_unit").is_none()));
    // An mm program read as inches (the control starts in inch): X 10..20 reads as
    // 254..508 mm, past X's 400 mm maximum; read in mm X 10..20, Y 2, Z 5 fit, and the
    // note says ÷25.4.
    let nc = "G90 G94 G17\nG00 X10. Y2. Z5.\nG01 X20. F20\nM30\n";
    let body =
        "[program]\nfile = \"p.nc\"\n[reader]\ndialect = \"fanuc\"\nstart_units = \"inch\"\n";
    let (code, v) = check("mm_as_inch", body, Some(nc), &[]);
    assert_eq!(code, 1);
    let note = violations(&v, "travel")[0]["other_unit"]
        .as_str()
        .unwrap_or_default()
        .to_string();
    for part in [
        "reads in inches",
        "mm scale (÷25.4)",
        "X 10.000 .. 20.000 mm",
    ] {
        assert!(note.contains(part), "{part}: {v}");
    }
}

/// A machine file without `[scene]` is checked against the default geometry, and `check`
/// says so, naming the file (JSON and text); a machine that gives its scene, or a check
/// without collisions, says nothing of a stand-in.
#[test]
fn a_machine_without_a_scene_is_said_to_be_checked_against_a_stand_in() {
    // trt-ac gives no [scene]: the default stands in.
    let (_, v) = check("stand-in", CONE_15_10, None, &[]);
    let note = v["scene_stand_in"].as_str().expect("a stand-in note");
    assert!(
        note.contains("trt-ac.toml") && note.contains("[scene]"),
        "{note}"
    );
    let dir = scratch("check", "stand-in-text");
    let path = write_scenario(&dir, &trt_ac(), CONE_15_10);
    let text =
        String::from_utf8_lossy(&mtsim(&["check", path.to_str().unwrap()]).stdout).into_owned();
    assert!(
        text.contains("note: collisions were checked against a stand-in"),
        "{text}"
    );
    // With the scene given in the scenario's overrides, or collisions off: no note.
    let (_, v) = check(
        "scene-given",
        &format!("{CONE_15_10}[machine_overrides.scene.table]\nradius_mm = 200.0\n"),
        None,
        &[],
    );
    assert!(v.get("scene_stand_in").is_none(), "{v}");
    let (_, v) = check(
        "no-collisions",
        &format!("{CONE_15_10}[check]\ncollisions = false\n"),
        None,
        &[],
    );
    assert!(v.get("scene_stand_in").is_none(), "{v}");
    // The head-table machine ships its scene.
    let dir = scratch("check", "head-table");
    let path = write_scenario(&dir, &common::machine("head-table-b45-c"), "[program.circle]\nplane = \"XY\"\nradius_mm = 50.0\nfeed_mm_min = 1000.0\ncenter_mm = [0.0, 0.0, 100.0]\n");
    let o = mtsim(&["check", path.to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_default();
    assert!(
        v.is_object() && v.get("scene_stand_in").is_none(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
