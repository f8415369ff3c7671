//! Release-mode benchmark of `check`, run by `cargo bench --bench check` (pin it to one
//! core: `taskset -c 1 cargo bench --bench check`).
//!
//! For each bundled cone scenario at its nominal feed, three variants: limits + collisions
//! + cutter engagement (the default), collisions with engagement off, and axis limits alone;
//! then a 16,000-block five-axis post program (the 15/10 cone at YT = -25 mm written by
//! `mtsim cone` in 16,000 segments) read from its file and checked with everything on; then
//! the corpus's 4.4-hour Haas UMC-750 NX post (8.9 M samples), limits and collisions beside
//! limits alone (at most three runs each).
//! Prints the real-time factor (simulated machine seconds per **CPU second of the running
//! thread**, `/proc/thread-self/schedstat`, so that other load does not count), samples per
//! second and the geometric queries made. It asserts nothing (timing is not a test).
//!
//! `MTSIM_BENCH_RUNS=N` sets the runs per case (default 15, medians); `MTSIM_BENCH_SMOKE=1`
//! runs each case once over 20 ms of CPU (for CI); `MTSIM_BENCH_ONCE=1` makes each
//! measurement one check (for `valgrind --tool=callgrind`); `MTSIM_BENCH_MIN_CPU_S=S` sets the
//! CPU time a measurement spans (default 0.1 s); `MTSIM_BENCH_ONLY=45-30` runs only the cases
//! whose name contains that text (the name is `scenario, variant`); `MTSIM_BENCH_PROGRAMMED=1`
//! checks at programmed timing instead of the planner's (`check --programmed`).

use std::path::{Path, PathBuf};

use mtsim::check::{check, CheckOptions};
use mtsim::input::scenario::Scenario;

mod common;
use common::{cpu_now, root};

/// CPU time one measurement spans at least, s (`MTSIM_BENCH_MIN_CPU_S` overrides it): the
/// clock advances in scheduler ticks of 4 ms, so 0.1 s reads to about ±4 %.
const MIN_CPU_S: f64 = 0.1;

/// CPU time one measurement of a smoke run spans at least, s: several ticks, so that even
/// the fastest case (under 2 ms a check) gets a finite, if coarse, figure.
const SMOKE_MIN_CPU_S: f64 = 0.02;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The 16,000-segment program of the 15/10 cone at YT = -25 mm, written by `mtsim cone`, and
/// a scenario that checks it from its file.
fn long_program(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("scenarios/cone-15-10-yt25.toml"))
        .unwrap()
        .replace("../machines/", &format!("{}/machines/", root().display()));
    let gen = dir.join("gen-16000.toml");
    std::fs::write(&gen, text.replace("segments = 360", "segments = 16000")).unwrap();
    let nc = dir.join("cone-16000.nc");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_mtsim"))
        .args(["cone", gen.to_str().unwrap(), "-o", nc.to_str().unwrap()])
        .status()
        .unwrap();
    assert!(status.success(), "mtsim cone failed");
    let scenario = dir.join("file-16000.toml");
    std::fs::write(
        &scenario,
        format!(
            "machine = {:?}\n[program]\nfile = {:?}\n[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [0.0, -25.0, 200.0]\nballbar_length_mm = 100.0\n",
            root().join("machines/trt-ac.toml").display().to_string(),
            nc.display().to_string()
        ),
    )
    .unwrap();
    scenario
}

/// The corpus's longest program, the 4.4-hour Haas UMC-750 NX post
/// (`haas_umc750_nx_dhanush_FinalToolPath.nc`, 8.9 M samples), on the bundled B-C trunnion
/// as `tests/program/shared_corpus.rs` reads it: limits and collisions, and limits alone,
/// side by side. None when `shared/corpus` is not above the package (the bench says so).
fn umc750_post(dir: &Path) -> Vec<(String, PathBuf)> {
    let Some(corpus) = root()
        .ancestors()
        .map(|a| a.join("shared/corpus"))
        .find(|c| c.join("manifest.tsv").is_file())
    else {
        println!("check Haas UMC-750 post: skipped, no shared/corpus above the package");
        return Vec::new();
    };
    let program = corpus.join("programs/haas_umc750_nx_dhanush_FinalToolPath.nc");
    let base = format!(
        "machine = {:?}\n[program]\nfile = {:?}\n[reader]\ndialect = \"haas\"\nstart_units = \"inch\"\n",
        root().join("machines/trt-bc.toml").display().to_string(),
        program.display().to_string()
    );
    [
        ("limits + collisions", ""),
        ("limits only", "[check]\ncollisions = false\n"),
    ]
    .iter()
    .map(|(variant, extra)| {
        let path = dir.join(format!("umc750-{}.toml", extra.len()));
        std::fs::write(&path, format!("{base}{extra}")).unwrap();
        (format!("Haas UMC-750 NX post (4.4 h), {variant}"), path)
    })
    .collect()
}

fn main() {
    let dir = std::env::temp_dir().join(format!("mtsim-bench-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let variants = [
        ("limits + collisions + engagement", ""),
        (
            "limits + collisions, engagement off",
            "[machine_overrides.scene]\nengagement_resolution_mm = 1e9\n",
        ),
        ("limits only", "[check]\ncollisions = false\n"),
    ];
    let smoke = std::env::var("MTSIM_BENCH_SMOKE").is_ok_and(|v| !v.is_empty() && v != "0");
    let runs: usize = if smoke {
        1
    } else {
        std::env::var("MTSIM_BENCH_RUNS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(15)
    };
    // `MTSIM_BENCH_ONCE=1`: one check per measurement, to count its instructions under
    // callgrind.
    let once = std::env::var("MTSIM_BENCH_ONCE").is_ok_and(|v| !v.is_empty() && v != "0");
    let min_cpu_s = match std::env::var("MTSIM_BENCH_MIN_CPU_S") {
        Ok(v) => v.parse().expect("MTSIM_BENCH_MIN_CPU_S: seconds"),
        Err(_) if smoke => SMOKE_MIN_CPU_S,
        Err(_) => MIN_CPU_S,
    };
    let only = std::env::var("MTSIM_BENCH_ONLY").unwrap_or_default();
    let mut cases: Vec<(String, PathBuf)> = Vec::new();
    for name in [
        "cone-15-10",
        "cone-15-10-offset",
        "cone-15-10-yt25",
        "cone-45-30",
    ] {
        let base = std::fs::read_to_string(root().join(format!("scenarios/{name}.toml")))
            .unwrap()
            .replace("../machines/", &format!("{}/machines/", root().display()));
        for (variant, extra) in variants {
            let case = format!("{name}, {variant}");
            if !case.contains(only.as_str()) {
                continue;
            }
            let path = dir.join(format!("{name}-{}.toml", extra.len()));
            std::fs::write(&path, format!("{base}{extra}")).unwrap();
            cases.push((case, path));
        }
    }
    let long = "16,000-block file program (15/10 cone, YT -25), limits + collisions + engagement";
    if long.contains(only.as_str()) {
        cases.push((long.to_string(), long_program(&dir)));
    }
    for (case, path) in umc750_post(&dir) {
        if case.contains(only.as_str()) {
            cases.push((case, path));
        }
    }
    let mut worst = f64::INFINITY;
    for (case, path) in cases {
        // A check of the 4.4-hour post takes seconds: three runs are medians enough.
        let runs = if case.starts_with("Haas") {
            runs.min(3)
        } else {
            runs
        };
        let scenario = Scenario::load(&path).unwrap();
        let mut rates = Vec::new();
        let options = CheckOptions {
            programmed: std::env::var("MTSIM_BENCH_PROGRAMMED")
                .is_ok_and(|v| !v.is_empty() && v != "0"),
            ..CheckOptions::default()
        };
        let mut cpu_s = Vec::new();
        let mut report = None;
        for _ in 0..runs {
            // The kernel updates the thread's CPU time at scheduler ticks (4 ms at 250 Hz),
            // so one measurement repeats the check until it has run for many ticks.
            let (t, mut n) = (cpu_now(), 0u32);
            let mut r;
            loop {
                r = check(&scenario, &options).unwrap();
                n += 1;
                if once || cpu_now() - t >= min_cpu_s {
                    break;
                }
            }
            let cpu = (cpu_now() - t) / n as f64;
            rates.push(r.sim_time_s / cpu);
            cpu_s.push(cpu);
            report = Some(r);
        }
        let r = report.unwrap();
        let rtf = median(rates.clone());
        if !case.starts_with("16,000") && !case.starts_with("Haas") {
            worst = worst.min(rtf);
        }
        println!(
            "check {case}: {} samples over {:.2} s; real-time factor (per CPU second) median {:.0}x, best {:.0}x; {:.2} ms CPU; {:.2} M samples/s; {} queries ({:.4} per sample); {} violations",
            r.samples,
            r.sim_time_s,
            rtf,
            rates.iter().cloned().fold(0.0, f64::max),
            1e3 * median(cpu_s),
            r.samples as f64 * rtf / r.sim_time_s / 1e6,
            r.scene_queries.unwrap_or(0),
            r.scene_queries.unwrap_or(0) as f64 / r.samples as f64,
            r.violations.len()
        );
    }
    if worst.is_finite() {
        println!("check: lowest real-time factor over the bundled cones {worst:.0}x (goal 10000x)");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
