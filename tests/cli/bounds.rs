//! Input that the keys cannot mean and work without bound, through the binary: a point key
//! with other than 3 values, values no machine has (a feed of 1e308, a period of 1e-9 ms,
//! limits of 5e-324) and runs past the sample budget all exit 2 with the file, line and key,
//! or the estimate and what to change, before any long work.

use crate::common;

use std::f64::consts::PI;
use std::path::Path;
use std::time::{Duration, Instant};

use common::{mtsim_plain, scratch, trt_ac, write_scenario, CONE_15_10};

/// The arguments of `command` on scenario `s` (simulate writes into `dir/out`).
fn args<'a>(command: &'a str, s: &'a str) -> Vec<&'a str> {
    match command {
        "simulate" => vec![command, s, "-o", "out"],
        _ => vec![command, s],
    }
}

/// Runs `mtsim args..` in `dir`; returns the exit code and stderr. Every case here must be
/// refused at once: a run that started sampling would take minutes to years.
fn refused(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let start = Instant::now();
    let out = mtsim_plain(dir, args);
    assert!(
        start.elapsed() < Duration::from_secs(20),
        "{args:?} took {:?}",
        start.elapsed()
    );
    let err = String::from_utf8_lossy(&out.stderr).replace('│', " ");
    // One line: the message as miette wraps it, joined back.
    (
        out.status.code(),
        err.split_whitespace().collect::<Vec<_>>().join(" "),
    )
}

/// Writes the bundled trt-ac machine with `from` replaced by `to` as `dir/m.toml` and a cone
/// scenario on it; returns the scenario's name.
fn on_machine(dir: &Path, from: &str, to: &str) -> &'static str {
    let machine = std::fs::read_to_string(trt_ac()).unwrap();
    assert!(machine.contains(from), "{from}");
    std::fs::write(dir.join("m.toml"), machine.replacen(from, to, 1)).unwrap();
    write_scenario(dir, "m.toml", CONE_15_10);
    "s.toml"
}

#[test]
fn every_point_key_takes_exactly_its_number_of_values() {
    let cone_with = |center: &str| CONE_15_10.replace("[0.0, 0.0, 200.0]", center);
    let cases: [(&str, String, &str, &str); 6] = [
        (
            "cone-4",
            cone_with("[0.0, 0.0, 200.0, 5.0]"),
            "s.toml:5:13:",
            "`program.cone.center_mm`: invalid length 4, expected exactly 3 values",
        ),
        (
            "cone-5",
            cone_with("[0.0, 0.0, 200.0, 5.0, 6.0]"),
            "s.toml:5:13:",
            "`program.cone.center_mm`: invalid length 5, expected exactly 3 values",
        ),
        (
            "cone-2",
            cone_with("[0.0, 0.0]"),
            "s.toml:5:13:",
            "`program.cone.center_mm`: invalid length 2, expected exactly 3 values",
        ),
        (
            "pivot-4",
            format!("{CONE_15_10}[ballbar]\npivot_mm = [0, 0, 0, 1]\n"),
            "s.toml:8:12:",
            "`ballbar.pivot_mm`: invalid length 4, expected exactly 3 values",
        ),
        (
            "circle-4",
            "[program.circle]\nradius_mm = 50\ncenter_mm = [0, 0, 100, 1]\n".into(),
            "s.toml:4:13:",
            "`program.circle.center_mm`: invalid length 4, expected exactly 3 values",
        ),
        (
            "offset-5",
            format!("{CONE_15_10}[reader.work_offsets]\nG54 = [1, 2, 3, 4, 5]\n"),
            "s.toml:8:7:",
            "`reader.work_offsets.G54`: invalid length 5, expected exactly 6 values",
        ),
    ];
    for (name, body, at, message) in cases {
        let dir = scratch("bounds", name);
        write_scenario(&dir, &trt_ac(), &body);
        let (code, err) = refused(&dir, &["check", "s.toml"]);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert!(err.contains(at) && err.contains(message), "{name}: {err}");
    }
    let dir = scratch("bounds", "machine-pivot-4");
    let s = on_machine(
        &dir,
        "pivot_mm = [0.0, 0.0, 0.0]",
        "pivot_mm = [0.0, 0.0, 0.0, 9.0]",
    );
    let (code, err) = refused(&dir, &["check", s]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("m.toml:7:12:") && err.contains("`pivot_mm`: invalid length 4"),
        "{err}"
    );
}

#[test]
fn a_feed_beyond_any_machine_says_so() {
    let dir = scratch("bounds", "feed-1e308");
    write_scenario(
        &dir,
        &trt_ac(),
        &format!("{CONE_15_10}feed_mm_min = 1e308\n"),
    );
    let (code, err) = refused(&dir, &["check", "s.toml"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("s.toml:7:1:"), "{err}");
    assert!(
        err.contains("feed 1e308 mm/min is beyond any machine (at most 1000000 mm/min)"),
        "{err}"
    );
}

#[test]
fn periods_and_axis_limits_no_machine_has_are_refused_at_their_own_key() {
    for period in ["1e-9", "5e-324", "0.009"] {
        let dir = scratch("bounds", &format!("period-{period}"));
        let s = on_machine(
            &dir,
            "interpolation_period_ms = 1.0",
            &format!("interpolation_period_ms = {period}"),
        );
        for command in ["check", "simulate"] {
            let (code, err) = refused(&dir, &args(command, s));
            assert_eq!(code, Some(2), "{period} {command}: {err}");
            assert!(err.contains("m.toml:8:1:"), "{period} {command}: {err}");
            assert!(
                err.contains("`interpolation_period_ms`: must be in [0.01, 100] ms"),
                "{err}"
            );
            assert!(!err.contains("[axes."), "{period}: {err}");
        }
    }
    for (key, line) in [("max_acceleration", 19), ("max_jerk", 20)] {
        let dir = scratch("bounds", key);
        let machine = std::fs::read_to_string(trt_ac()).unwrap();
        let original = machine.lines().nth(line - 1).unwrap();
        assert!(original.starts_with(key), "{original}");
        let s = on_machine(&dir, original, &format!("{key} = 5e-324"));
        let (code, err) = refused(&dir, &args("simulate", s));
        assert_eq!(code, Some(2), "{key}: {err}");
        assert!(err.contains(&format!("m.toml:{line}:1:")), "{key}: {err}");
        assert!(
            err.contains(&format!("`axes.X.{key}`: must be a finite number >= 0.001")),
            "{err}"
        );
    }
}

/// `feed_mm_min = 0.001` is a valid feed, but the 15/10 cone's circle (r = L cos α) then
/// takes a year of machine time: refused up front with the estimate
/// n = 2π r (1 + lead/180°) / (F/60) / Δt, lead 0 for `check` and 20° for `simulate`.
#[test]
fn a_generated_test_over_the_sample_budget_is_refused_up_front_with_its_estimate() {
    let dir = scratch("bounds", "feed-slow");
    write_scenario(
        &dir,
        &trt_ac(),
        &format!("{CONE_15_10}feed_mm_min = 0.001\n"),
    );
    let r_mm = 100.0 * 15f64.to_radians().cos();
    for (command, lead_deg) in [("check", 0.0), ("simulate", 20.0)] {
        let samples = 2.0 * PI * r_mm * (1.0 + lead_deg / 180.0) / (0.001 / 60.0) / 1e-3;
        let (code, err) = refused(&dir, &args(command, "s.toml"));
        assert_eq!(code, Some(2), "{command}: {err}");
        assert!(
            err.contains(&format!("the run needs about {samples:.3e} samples")),
            "{command}: {err}"
        );
        assert!(
            err.contains("budget of 1000000000 ([simulate] max_samples)"),
            "{err}"
        );
        assert!(
            err.contains("feed_mm_min = 0.001") && err.contains("years of machine time"),
            "{err}"
        );
        assert!(err.contains("raise [program.cone] feed_mm_min"), "{err}");
    }
    // The circle: 2π r at F, r = 50 mm.
    let circle = "[program.circle]\nradius_mm = 50\nfeed_mm_min = 0.001\ncenter_mm = [0, 0, 100]\n";
    write_scenario(
        &dir,
        &trt_ac(),
        &format!("{circle}[check]\ncollisions = false\n"),
    );
    let samples = 2.0 * PI * 50.0 / (0.001 / 60.0) / 1e-3;
    let (code, err) = refused(&dir, &["check", "s.toml"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains(&format!("the run needs about {samples:.3e} samples")),
        "{err}"
    );
    assert!(err.contains("raise [program.circle] feed_mm_min"), "{err}");
    // The budget is the scenario's to set, at least 1 sample.
    write_scenario(
        &dir,
        &trt_ac(),
        &format!("{CONE_15_10}feed_mm_min = 0.001\n[simulate]\nmax_samples = 0\n"),
    );
    let (code, err) = refused(&dir, &["check", "s.toml"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("`simulate.max_samples`: must be at least 1"),
        "{err}"
    );
}

/// A G-code file is read ahead of its run and each move adds its programmed time (the time
/// `check --programmed` takes, a lower bound on the planner's): the bundled program's 360 feed
/// blocks run 2π·96.5926 mm at F1000 with the deg counted as mm, 36.41 s, 36,416 samples at
/// 1 ms by `check --programmed`. A budget of 1000 is refused by the read-ahead, in its first
/// second of program; a budget of 36,416 passes the read-ahead and `check --programmed`, and
/// stops `check` and `simulate`, whose planner ramps take longer, while they run, with the
/// line reached.
#[test]
fn a_file_program_past_the_budget_is_refused_by_reading_ahead_or_stopped_where_it_passes() {
    let program =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/programs/cone-15-10-yt25.nc");
    let dir = scratch("bounds", "file-budget");
    let body = |max: u64| {
        format!("[program]\nfile = {:?}\n[check]\ncollisions = false\n[simulate]\nmax_samples = {max}\n", program.display().to_string())
    };
    write_scenario(&dir, &trt_ac(), &body(1000));
    for command in ["check", "simulate"] {
        let (code, err) = refused(&dir, &args(command, "s.toml"));
        assert_eq!(code, Some(2), "{command}: {err}");
        assert!(
            err.contains("cone-15-10-yt25.nc:19:1: the program needs more than"),
            "{err}"
        );
        assert!(
            err.contains("over the budget of 1000 ([simulate] max_samples of s.toml): read ahead to this line"),
            "{err}"
        );
    }
    write_scenario(&dir, &trt_ac(), &body(36_416));
    let out = mtsim_plain(&dir, &["check", "--programmed", "s.toml"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("36416 samples"), "{text}");
    for command in ["check", "simulate"] {
        let (code, err) = refused(&dir, &args(command, "s.toml"));
        assert_eq!(code, Some(2), "{command}: {err}");
        assert!(
            err.contains(
                "the run passed its budget of 36416 samples ([simulate] max_samples) at program line"
            ),
            "{err}"
        );
    }
}

/// The read-ahead checks each move as the run does, before adding its time: a move beyond
/// the travel envelope (X 100 m on a machine of under 1 m) is refused as such, not as the
/// 100 min at F1000 that would pass a budget of 1000 samples on that same line.
#[test]
fn a_bad_move_is_refused_by_the_read_ahead_before_its_time_counts() {
    let dir = scratch("bounds", "file-bad-move-budget");
    std::fs::write(
        dir.join("bad.nc"),
        "G21 G90 G94\nG1 X0 Y0 Z0 F1000\nG1 X100000\nM30\n",
    )
    .unwrap();
    let body = "[program]\nfile = \"bad.nc\"\n[check]\ncollisions = false\n[simulate]\nmax_samples = 1000\n";
    write_scenario(&dir, &trt_ac(), body);
    let (code, err) = refused(&dir, &args("simulate", "s.toml"));
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("bad.nc:3:"), "{err}");
    assert!(err.contains("beyond the travel envelope"), "{err}");
    assert!(!err.contains("budget"), "{err}");
}

/// A program that loops without end is refused by the read-ahead, not sampled for hours:
/// each pass of `o100 while [1]` moves 10 mm and back at F10 (120 s), so 10⁹ samples at
/// 1 ms (10⁶ s) are passed after 8,334 passes, 16,668 moves with the first rapid, long
/// before the interpreter's block budget (`max_blocks`, 2·10⁶ blocks run again: four a
/// pass). A loop of short moves meets that budget first, and the reader names the loop.
#[test]
fn a_program_that_loops_without_end_is_refused_after_reading_not_sampling() {
    let dir = scratch("bounds", "endless-loop");
    std::fs::write(
        dir.join("loop.ngc"),
        "G21 G90 G17\nG0 X0 Y0 Z0\nF10\no100 while [1]\nG1 X10\nG1 X0\no100 endwhile\nM2\n",
    )
    .unwrap();
    write_scenario(
        &dir,
        &trt_ac(),
        "[program]\nfile = \"loop.ngc\"\n[check]\ncollisions = false\n",
    );
    for command in ["check", "simulate"] {
        let (code, err) = refused(&dir, &args(command, "s.toml"));
        assert_eq!(code, Some(2), "{command}: {err}");
        assert!(
            err.contains("loop.ngc:5:1: the program needs more than 1.000e9 samples, over the budget of 1000000000"),
            "{command}: {err}"
        );
        assert!(
            err.contains("read ahead to this line, its 16668 moves"),
            "{command}: {err}"
        );
        assert!(err.contains("277.8 h of machine time"), "{err}");
    }
}

/// A file program's trace rows are counted while it runs: the bundled file cone traces
/// about 36,260 rows, so a budget of 20,000 stops it on its way round.
#[test]
fn a_file_programs_trace_stops_at_its_row_budget() {
    let program =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/programs/cone-15-10-yt25.nc");
    let dir = scratch("bounds", "file-trace-rows");
    write_scenario(
        &dir,
        &trt_ac(),
        &format!(
            "[program]\nfile = {:?}\n[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\n\
             center_mm = [0.0, -25.0, 200.0]\nballbar_length_mm = 100.0\n[simulate]\nmax_trace_rows = 20000\n",
            program.display().to_string()
        ),
    );
    let (code, err) = refused(&dir, &args("simulate", "s.toml"));
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains(
            "the trace passed its budget of 20000 rows ([simulate] max_trace_rows) at program line"
        ),
        "{err}"
    );
    assert!(!dir.join("out").exists(), "a stopped run leaves no folder");
}

/// `simulate`'s trace has a budget of its own: the 15/10 cone's measured revolution is
/// 2π·100·cos 15° mm at F1000, 36.41 s, 36,413 rows at 1 ms; a budget of 10,000 rows is
/// refused before the run with that estimate, 40,000 rows pass.
#[test]
fn a_trace_over_its_row_budget_is_refused_up_front() {
    let dir = scratch("bounds", "trace-rows");
    let rows = 2.0 * PI * 100.0 * 15f64.to_radians().cos() / (1000.0 / 60.0) / 1e-3;
    for (max, every, refused_expected) in [
        (10_000u64, 1u64, true),
        (40_000, 1, false),
        (10_000, 4, false),
    ] {
        write_scenario(
            &dir,
            &trt_ac(),
            &format!("{CONE_15_10}[simulate]\nmax_trace_rows = {max}\ntrace_every = {every}\n"),
        );
        let (code, err) = refused(&dir, &args("simulate", "s.toml"));
        if refused_expected {
            assert_eq!(code, Some(2), "{err}");
            assert!(
                err.contains(&format!("the trace would hold about {rows:.3e} rows, more than the budget of {max} ([simulate] max_trace_rows)")),
                "{err}"
            );
            assert!(!dir.join("out").exists(), "a refused run leaves no folder");
        } else {
            assert_eq!(code, Some(0), "{max} {every}: {err}");
            let trace = std::fs::read_to_string(dir.join("out/trace.csv")).unwrap();
            let n = trace.lines().count() as u64 - 1;
            assert!(
                n <= max && (n + 1) as f64 >= rows / every as f64,
                "{n} rows"
            );
        }
    }
}

/// Every bundled scenario's runs stay far below the default budget: `check` counts each
/// run's samples, at most 1e6 (0.1 % of 1e9).
#[test]
fn the_bundled_scenarios_stay_far_below_the_budget() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut seen = 0;
    for entry in std::fs::read_dir(root.join("scenarios")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let out = mtsim_plain(root, &["check", path.to_str().unwrap()]);
        let text = String::from_utf8_lossy(&out.stdout);
        let samples: u64 = text
            .split_once(" samples")
            .and_then(|(head, _)| head.rsplit(' ').next()?.parse().ok())
            .unwrap_or_else(|| panic!("{}: {text}", path.display()));
        assert!(
            samples > 1000 && samples <= 1_000_000,
            "{}: {samples}",
            path.display()
        );
        seen += 1;
    }
    assert!(seen >= 5, "{seen} scenarios");
}

#[test]
fn input_files_that_are_not_regular_files_are_refused_by_name_before_they_are_read() {
    let dir = scratch("bounds", "devzero");
    // The machine file, an error table of a machine, and a measured trace of `fit`, each
    // pointed at /dev/zero (endless) and at a folder.
    for target in ["/dev/zero", "/tmp"] {
        write_scenario(&dir, target, CONE_15_10);
        let (code, err) = refused(&dir, &["check", "s.toml"]);
        assert_eq!(code, Some(2), "{target}: {err}");
        assert!(
            err.contains(target) && err.contains("not a regular file"),
            "{target}: {err}"
        );

        let machine = std::fs::read_to_string(trt_ac()).unwrap();
        std::fs::write(
            dir.join("m.toml"),
            format!("{machine}\n[error_tables]\nX = \"{target}\"\n"),
        )
        .unwrap();
        write_scenario(&dir, "m.toml", CONE_15_10);
        let (code, err) = refused(&dir, &["check", "s.toml"]);
        assert_eq!(code, Some(2), "error table {target}: {err}");
        assert!(
            err.contains("not a regular file"),
            "error table {target}: {err}"
        );

        write_scenario(&dir, &trt_ac(), CONE_15_10);
        let (code, err) = refused(&dir, &["fit", "s.toml", "--measured", target, "-o", "fit"]);
        assert_eq!(code, Some(2), "measured {target}: {err}");
        assert!(
            err.contains(target) && err.contains("not a regular file"),
            "measured {target}: {err}"
        );
    }
}

#[test]
fn a_machine_file_or_error_table_that_is_not_one_is_named_never_quoted() {
    let dir = scratch("bounds", "noecho");
    let secret = "root:$6$secretsecret:19000:0:99999:7:::\ndaemon:*:19000:0:99999:7:::\n";
    std::fs::write(dir.join("shadow"), secret).unwrap();
    // As the machine file: a TOML syntax error on line 1, column 40.
    write_scenario(&dir, "shadow", CONE_15_10);
    let (code, err) = refused(&dir, &["check", "s.toml"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("shadow:1:40:"), "{err}");
    assert!(
        !err.contains("secretsecret") && !err.contains("daemon"),
        "{err}"
    );
    // As an error table of a good machine: not a number on line 1, column 1.
    let machine = std::fs::read_to_string(trt_ac()).unwrap();
    std::fs::write(
        dir.join("m.toml"),
        format!("{machine}\n[error_tables]\nX = \"shadow\"\n"),
    )
    .unwrap();
    write_scenario(&dir, "m.toml", CONE_15_10);
    let (code, err) = refused(&dir, &["check", "s.toml"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("shadow:1:1:"), "{err}");
    assert!(
        !err.contains("secretsecret") && !err.contains("daemon"),
        "{err}"
    );
}

/// `analyze` lists an axis's first 10,000 reversals and counts the rest, so that its memory
/// does not grow with a program of reversing moves: 12,001 feed blocks between X0 and X1
/// turn X at the end of every block but the last, 12,000 times.
#[test]
fn analyze_lists_the_first_ten_thousand_reversals_and_counts_the_rest() {
    let dir = scratch("bounds", "reversal-cap");
    let mut program = String::from("G21 G90\nG0 X0 Y0 Z100\nF1000\n");
    for k in 0..12_001 {
        program.push_str(if k % 2 == 0 { "G1 X1\n" } else { "G1 X0\n" });
    }
    program.push_str("M2\n");
    std::fs::write(dir.join("zigzag.ngc"), program).unwrap();
    write_scenario(&dir, &trt_ac(), "[program]\nfile = \"zigzag.ngc\"\n");
    let out = mtsim_plain(&dir, &["analyze", "s.toml", "--json"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let x = &json["axes"]["X"];
    assert_eq!(x["reversal_lines"].as_array().unwrap().len(), 10_000);
    assert_eq!(x["reversals_not_listed"], 2_000);
    let text =
        String::from_utf8_lossy(&mtsim_plain(&dir, &["analyze", "s.toml"]).stdout).to_string();
    assert!(
        text.contains("; and 2000 more not listed"),
        "{}",
        &text[..text.len().min(400)]
    );
}
