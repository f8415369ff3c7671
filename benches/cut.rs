//! Release-mode benchmark of `cut` beside `simulate`, run by `cargo bench --bench cut`.
//!
//! The 15/10 cone of `scenarios/cone-15-10.toml` in 720 segments: `study::cut::run_cut` at
//! the default grid with its files (`surface.csv`, `surface.parquet`, `cut.json`, the two
//! SVGs) against `study::simulate::simulate_with` without the error budget (its trace,
//! summary, plot and test files), alternated in one process, each measurement the CPU time
//! of the running thread (`/proc/thread-self/schedstat`). Prints each median and the ratio
//! (the goal: at most 2). It asserts nothing (timing is not a test).
//! `MTSIM_BENCH_RUNS=N` sets the runs of each (default 9); `MTSIM_BENCH_SMOKE=1` runs each once.

use std::path::PathBuf;
use std::time::Instant;

use mtsim::input::scenario::Scenario;
use mtsim::measure::cut::CutOptions;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// CPU time of the calling thread, s; wall time where schedstat does not exist.
fn cpu_now() -> f64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse::<f64>().ok())
        .map(|ns| ns * 1e-9)
        .unwrap_or_else(|| START.get_or_init(Instant::now).elapsed().as_secs_f64())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let dir = std::env::temp_dir().join(format!("mtsim-bench-cut-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(root().join("scenarios/cone-15-10.toml"))
        .unwrap()
        .replace("../machines/", &format!("{}/machines/", root().display()))
        .replace("segments = 360", "segments = 720");
    let path = dir.join("cone-720.toml");
    std::fs::write(&path, text).unwrap();
    let scenario = Scenario::load(&path).unwrap();
    let runs = if std::env::var_os("MTSIM_BENCH_SMOKE").is_some() {
        1
    } else {
        std::env::var("MTSIM_BENCH_RUNS")
            .ok()
            .and_then(|n| n.parse().ok())
            .unwrap_or(9)
    };
    let (mut simulate, mut cut) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let t0 = cpu_now();
        mtsim::study::simulate::simulate_with(&scenario, &dir.join("sim"), false, false, &|_| {})
            .unwrap();
        let t1 = cpu_now();
        let run = mtsim::study::cut::run_cut(&scenario, CutOptions::default(), &|_| {}).unwrap();
        let out = dir.join("cut");
        std::fs::create_dir_all(&out).unwrap();
        mtsim::report::cut::write_cut_files(&out, "cut", &run.surface, &run.surface.figures())
            .unwrap();
        let t2 = cpu_now();
        simulate.push(t1 - t0);
        cut.push(t2 - t1);
    }
    let (s, c) = (median(simulate), median(cut));
    println!(
        "cone 15/10, 720 segments, {runs} runs each: simulate (no budget) {:.1} ms, cut {:.1} ms, ratio {:.2}",
        s * 1e3,
        c * 1e3,
        c / s
    );
    let _ = std::fs::remove_dir_all(&dir);
}
