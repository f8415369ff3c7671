//! What a new user meets first: right figures by default, clear errors for bad programs,
//! and a command line that behaves as documented.

use crate::common;

use common::{mtsim, scratch, stdout_json};

fn g_um(v: &serde_json::Value) -> f64 {
    v["ballbar"]["circular_deviation_um"].as_f64().unwrap()
}

#[test]
fn the_file_program_gives_the_g_of_its_generated_twin() {
    // The bundled G-code file is the post-processor's output for the same cone as
    // cone-15-10-yt25.toml, without a lead arc: its start-up transient must not count.
    let dir = scratch("usability", "twin");
    let file = mtsim(&[
        "simulate",
        "scenarios/file-cone-15-10-yt25.toml",
        "-o",
        dir.join("file").to_str().unwrap(),
        "--json",
        "--no-timing",
    ]);
    let twin = mtsim(&[
        "simulate",
        "scenarios/cone-15-10-yt25.toml",
        "-o",
        dir.join("twin").to_str().unwrap(),
        "--json",
        "--no-timing",
    ]);
    let (g_file, g_twin) = (g_um(&stdout_json(&file)), g_um(&stdout_json(&twin)));
    assert!(
        (g_file - g_twin).abs() < 0.10 * g_twin,
        "file G {g_file} um vs twin G {g_twin} um"
    );
    // ... and it says what it did.
    let err = String::from_utf8_lossy(&file.stderr);
    assert!(
        err.contains("start-up transient") && err.contains("measure_lines"),
        "{err}"
    );
    let summary = stdout_json(&file);
    assert!(summary["warnings"][0]
        .as_str()
        .unwrap()
        .contains("deg of the measured revolution"));
}

#[test]
fn measuring_from_the_first_feed_block_warns_that_one_spot_dominates_g() {
    // measure_lines set to the first and last feed block of the lead-less file: the rapid's
    // settling is then measured, as asked, and makes nearly all of G.
    let dir = scratch("usability", "spot");
    let program = std::fs::read_to_string("scenarios/programs/cone-15-10-yt25.nc").unwrap();
    let lines: Vec<&str> = program.lines().collect();
    let first = 1 + lines.iter().position(|l| l.starts_with("G01")).unwrap();
    let last = 1 + lines.iter().rposition(|l| l.starts_with("G01")).unwrap();
    std::fs::write(dir.join("p.nc"), &program).unwrap();
    let scenario = dir.join("s.toml");
    std::fs::write(
        &scenario,
        format!(
            "machine = \"{}\"\n[program]\nfile = \"p.nc\"\n[program.cone]\nhalf_apex_deg = 15.0\n\
             inclination_deg = 10.0\ncenter_mm = [0.0, -25.0, 200.0]\nballbar_length_mm = 100.0\n\
             [simulate]\nmeasure_lines = [{first}, {last}]\n",
            common::trt_ac()
        ),
    )
    .unwrap();
    let out = mtsim(&[
        "simulate",
        scenario.to_str().unwrap(),
        "-o",
        dir.join("out").to_str().unwrap(),
        "--json",
        "--no-timing",
    ]);
    let v = stdout_json(&out);
    assert!(
        g_um(&v) > 500.0,
        "the transient is measured: G {}",
        g_um(&v)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("one spot dominates G"), "{err}");
    assert!(err.contains("θ = 0.0°") || err.contains("θ = 359"), "{err}");
}

#[test]
fn programs_without_motion_or_with_absurd_moves_exit_2_with_file_line_column() {
    let x308 = format!("G01 X1{} F100\n", "0".repeat(308));
    let cases: [(&str, &str, &str); 4] = [
        ("empty", "", "p.nc:1:1: the program has no motion"),
        (
            "no-motion",
            "G21 G90\nG00 X0 Y0\nM30\n",
            "p.nc:1:1: the program has no motion",
        ),
        ("x308", &x308, "p.nc:1:5: this move takes X 1.0e308 mm"),
        // 1000 mm of X on an 800 mm travel (-400 .. 400): longer than the envelope.
        (
            "long",
            "G00 X0\nG01 X-1000 F1000\n",
            "p.nc:2:5: this move takes X 1000 mm",
        ),
    ];
    for (name, program, expected) in cases {
        let dir = scratch("usability", name);
        let s = common::file_scenario(&dir, program);
        for command in ["analyze", "check", "simulate"] {
            let started = std::time::Instant::now();
            let out = common::mtsim_plain(
                &dir,
                &[command, &s, "-o", "out"][..if command == "simulate" { 4 } else { 2 }],
            );
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{name} {command}: {err}");
            assert!(err.contains(expected), "{name} {command}: {err}");
            assert!(
                err.len() < 4000,
                "{name} {command}: no 300-digit numbers in the message"
            );
            assert!(
                started.elapsed().as_secs() < 20,
                "{name} {command}: refused before sampling"
            );
        }
        assert!(
            !dir.join("out/trace.csv").exists(),
            "{name}: no empty outputs"
        );
    }
}

#[test]
fn simulate_reports_a_travel_overrun_as_check_does() {
    // X to 500 mm on a -400 .. 400 mm axis: within the envelope's length, beyond its end.
    let dir = scratch("usability", "overrun");
    let s = common::file_scenario(&dir, "G00 X0 Y0 Z100\nG01 X500 F6000\n");
    let check = mtsim(&["check", &s, "--json"]);
    assert_eq!(check.status.code(), Some(1));
    let out = mtsim(&["simulate", &s, "-o", dir.join("out").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("does not fit the machine") && err.contains("travel"),
        "{err}"
    );
    assert!(err.contains("limit 400.000, excess 100.000"), "{err}");
    let checked: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("out/check.json")).unwrap()).unwrap();
    assert_eq!(checked["axes"]["X"]["max"].as_f64(), Some(500.0));
    // --quiet keeps stderr free of the warning, not the exit code.
    let quiet = mtsim(&[
        "simulate",
        &s,
        "-o",
        dir.join("out").to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(quiet.status.code(), Some(1));
    assert!(
        quiet.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&quiet.stderr)
    );
}

#[test]
fn negative_option_values_parse_and_get_a_range_error() {
    let out = mtsim(&["check", "scenarios/cone-15-10.toml", "--near-miss", "-5"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr)
        .contains("--near-miss -5: expected a clearance >= 0 mm"));
    let out = mtsim(&[
        "sweep",
        "scenarios/cone-15-10.toml",
        "--vary",
        "center_y",
        "--from",
        "-10",
        "--to",
        "10",
        "--step",
        "-1",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("step > 0"));
}

#[test]
fn a_near_miss_over_the_whole_run_is_reported_as_the_whole_run() {
    // 50 mm is more than the shank ever stands off the cone (18 mm): one span, the whole run.
    let out = mtsim(&["check", "scenarios/cone-15-10.toml", "--near-miss", "50"]);
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.contains("nearmiss") && l.contains("shank / workpiece"))
        .unwrap();
    assert!(line.contains("the whole run, t 0.000.."), "{line}");
    // The table says its units, and explains the cutting.
    assert!(
        text.contains("unit") && text.contains("(/min)") && text.contains("(/s²)"),
        "{text}"
    );
    assert!(text.contains("expected, not a violation"), "{text}");
}

#[test]
fn completions_and_a_man_page_are_generated() {
    let bash = mtsim(&["completions", "bash"]);
    assert!(bash.status.success());
    let bash = String::from_utf8_lossy(&bash.stdout);
    for sub in ["simulate", "check", "report", "sweep"] {
        assert!(bash.contains(sub), "bash completion lacks {sub}");
    }
    let man = mtsim(&["man"]);
    assert!(man.status.success());
    let man = String::from_utf8_lossy(&man.stdout);
    assert!(
        man.contains(".TH mtsim 1") && man.contains("SUBCOMMANDS"),
        "{man}"
    );
    assert_eq!(mtsim(&["completions", "tcsh"]).status.code(), Some(2));
}

/// A run killed at any time leaves no temporary file once the next run has run: its
/// half-written files are in the staged folder beside `out`, never in `out`. A file of the
/// user's with a temporary-looking name is theirs (no manifest lists it) and stays.
#[test]
fn a_killed_run_leaves_no_temporary_file_after_the_next_run() {
    let dir = scratch("usability", "stale");
    let out_dir = dir.join("out");
    std::fs::create_dir_all(&out_dir).unwrap();
    std::fs::write(out_dir.join("notes.tmp"), b"mine").unwrap();
    std::fs::write(out_dir.join("summary.json.tmp"), b"mine too").unwrap();
    let args = [
        "simulate",
        "scenarios/circle-iso230-4.toml",
        "-o",
        out_dir.to_str().unwrap(),
        "--no-timing",
        "--html",
    ];
    for delay_ms in [5, 40, 120, 300] {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_mtsim"))
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let _ = child.kill();
        child.wait().unwrap();
        let out = mtsim(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let mut left: Vec<String> = std::fs::read_dir(&out_dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp"))
            .collect();
        left.sort();
        assert_eq!(
            left,
            ["notes.tmp", "summary.json.tmp"],
            "killed after {delay_ms} ms"
        );
        let beside: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(beside, ["out"], "killed after {delay_ms} ms");
    }
    assert_eq!(
        std::fs::read(out_dir.join("summary.json.tmp")).unwrap(),
        b"mine too"
    );
}

#[test]
fn every_file_the_repository_points_to_exists() {
    // Paths like `docs/model.md` or `../machines/trt-ac.toml` in the machine, scenario and
    // doc files and the sources must name files in the repository (`path/to/...` examples
    // aside; the tests name missing files on purpose and are not scanned).
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("README.md")];
    for folder in ["machines", "scenarios", "docs", "src", "crates/ngc/src"] {
        let mut stack = vec![root.join(folder)];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    stack.push(p);
                } else if p
                    .extension()
                    .is_some_and(|x| ["md", "toml", "rs"].contains(&x.to_str().unwrap()))
                {
                    files.push(p);
                }
            }
        }
    }
    let mut missing = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        for token in text.split(|c: char| c.is_whitespace() || "`\"'()[]<>,;:*".contains(c)) {
            let token = token.trim_end_matches('.');
            let is_path = token.contains('/')
                && !token.contains("://")
                && !token.contains('{')
                && [".md", ".toml", ".nc"].iter().any(|e| token.ends_with(e))
                && !token.starts_with("/tmp")
                && !token.starts_with("path/to/")
                && !token.contains("...");
            if !is_path {
                continue;
            }
            let here = file.parent().unwrap().join(token.trim_start_matches('/'));
            let from_root = root.join(token.trim_start_matches('/'));
            if !(here.exists() || from_root.exists()) {
                missing.push(format!(
                    "{}: {token}",
                    file.strip_prefix(root).unwrap().display()
                ));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "pointers to files that are not in the repository:\n{}",
        missing.join("\n")
    );
}

#[test]
fn the_cutting_depth_on_clean_cones_is_the_sag_between_blocks_and_falls_as_one_over_n_squared() {
    // Joint-space interpolation between the program's end points lets the tip sag off the
    // cone by ~ c·(Δθ)²: twice the segments, a quarter of the depth. The same sag draws the
    // block-period sawtooth on the polar plot.
    let dir = scratch("usability", "sag");
    let depth = |segments: usize| -> f64 {
        let s = dir.join(format!("s{segments}.toml"));
        std::fs::write(
            &s,
            format!(
                "machine = \"{}\"\n[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\n\
                 center_mm = [0.0, -25.0, 200.0]\nballbar_length_mm = 100.0\nsegments = {segments}\n",
                common::trt_ac()
            ),
        )
        .unwrap();
        let v = stdout_json(&mtsim(&["check", s.to_str().unwrap(), "--json"]));
        v["engagement"][0]["max_depth_mm"].as_f64().unwrap()
    };
    let (d360, d720) = (depth(360), depth(720));
    assert!(d360 > 0.005 && d360 < 0.05, "{d360} mm");
    let ratio = d360 / d720;
    assert!(
        (3.5..4.5).contains(&ratio),
        "depth ratio {ratio} ({d360} / {d720} mm)"
    );
}

#[test]
fn stderr_is_silent_without_a_terminal_and_says_more_with_v() {
    // The tests' stderr is a pipe: no progress bar, no spinner, nothing at all on a clean run.
    let dir = scratch("usability", "quiet");
    let out_dir = dir.join("out");
    let plain = mtsim(&[
        "simulate",
        "scenarios/circle-iso230-4.toml",
        "-o",
        out_dir.to_str().unwrap(),
    ]);
    assert!(plain.status.success());
    assert!(
        plain.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&plain.stderr)
    );
    let check = mtsim(&["check", "scenarios/circle-iso230-4.toml"]);
    assert!(
        check.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let verbose = mtsim(&[
        "-v",
        "simulate",
        "scenarios/circle-iso230-4.toml",
        "-o",
        out_dir.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&verbose.stderr);
    assert!(
        err.contains("interpolation periods") && err.contains("test.json"),
        "{err}"
    );
    let verbose = mtsim(&["check", "-v", "scenarios/circle-iso230-4.toml"]);
    assert!(String::from_utf8_lossy(&verbose.stderr).contains("checked "));
}

#[test]
fn quiet_sweep_and_batch_write_their_files_without_a_word() {
    let dir = scratch("usability", "quiet-sweep");
    let out = mtsim(&[
        "--quiet",
        "sweep",
        "scenarios/cone-15-10.toml",
        "--vary",
        "center_y",
        "--from",
        "-10",
        "--to",
        "0",
        "--step",
        "5",
        "-o",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::read_dir(&dir).unwrap().count() >= 3);
}

/// `cone --g93 --tcp` asked for two feed forms at once: refused, never one dropped.
#[test]
fn cone_with_g93_and_tcp_is_refused_not_silently_half_done() {
    let out = mtsim(&["cone", "scenarios/cone-15-10.toml", "--g93", "--tcp"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--g93 with --tcp") && err.contains("choose one"),
        "{err}"
    );
    assert!(out.stdout.is_empty(), "no program written");
    // Each alone still writes its program.
    let g93 = mtsim(&["cone", "scenarios/cone-15-10.toml", "--g93"]);
    assert!(String::from_utf8_lossy(&g93.stdout).contains("G93"));
    let tcp = mtsim(&["cone", "scenarios/cone-15-10.toml", "--tcp"]);
    assert!(String::from_utf8_lossy(&tcp.stdout).contains("G43.4"));
}

/// A program that reverses X 30 times: the table gives the count and the first 8 lines,
/// `--json` lists all 30.
#[test]
fn analyze_gives_a_long_reversal_list_as_its_count_and_first_lines() {
    let dir = scratch("usability", "many-reversals");
    let mut program = String::from("G21 G90 G94\nG0 X0 Y0 Z50\nF1000\n");
    for i in 0..31 {
        program.push_str(&format!("G1 X{}\n", if i % 2 == 0 { 10 } else { 0 }));
    }
    program.push_str("M30\n");
    let scenario = common::file_scenario(&dir, &program);
    let out = mtsim(&["analyze", &scenario]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let x_row = text.lines().find(|l| l.starts_with("X ")).unwrap();
    assert!(
        x_row.contains("30 reversals, the first 8: line 4,"),
        "{x_row}"
    );
    assert_eq!(x_row.matches("line ").count(), 8, "{x_row}");
    let json = stdout_json(&mtsim(&["analyze", &scenario, "--json"]));
    let x = json["axes"]
        .as_array()
        .map(|a| a.iter().find(|a| a["axis"] == "X").unwrap().clone())
        .unwrap_or_else(|| json["axes"]["X"].clone());
    assert_eq!(x["reversal_lines"].as_array().unwrap().len(), 30, "{x}");
}

/// `-v` on simulate gives each stage's wall time; the whole run's real-time factor is printed
/// beside the simulation's own.
#[test]
fn simulate_verbose_gives_stage_times_and_the_whole_runs_factor() {
    let dir = scratch("usability", "verbose");
    let out = mtsim(&[
        "simulate",
        "scenarios/circle-iso230-4.toml",
        "-o",
        dir.join("out").to_str().unwrap(),
        "-v",
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    for stage in [
        "stages (wall): read ",
        "simulation (",
        "check ",
        "whole run ",
    ] {
        assert!(err.contains(stage), "{stage}: {err}");
    }
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("x for the whole run (") && text.contains("the simulation alone"),
        "{text}"
    );
}
