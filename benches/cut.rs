//! Release-mode benchmark of `cut` beside `simulate`, run by `cargo bench --bench cut`.
//!
//! The 15/10 cone of `scenarios/cone-15-10.toml` in 720 segments: `study::cut::cut_into` at
//! the default grid with its files (`surface.csv`, `surface.parquet`, `cut.json`, the
//! SVGs, `cut.html`) without and with its error budget (`study::cut_budget`), against
//! `study::simulate::simulate_with` without and with its error budget (its trace, summary,
//! plot and test files), alternated in one process, each measurement the CPU time of the
//! running thread (`/proc/thread-self/schedstat`). Prints each median and the ratios (the
//! issue's goal: `cut` at most 2x `simulate`). It asserts nothing (timing is not a test).
//! `MTSIM_BENCH_RUNS=N` sets the runs of each (default 9); `MTSIM_BENCH_SMOKE=1` runs each once.

use mtsim::input::scenario::Scenario;
use mtsim::measure::cut::CutOptions;

mod common;
use common::{cpu_now, root};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// `cut` with its files into `out`, with its error budget or without (`--no-budget`): the
/// command's own path (`study::cut::cut_into`).
fn cut_with_files(scenario: &Scenario, out: &std::path::Path, budget: bool) {
    std::fs::create_dir_all(out).unwrap();
    mtsim::study::cut::cut_into(
        scenario,
        CutOptions::default(),
        budget,
        (out, "cut"),
        &|_| {},
    )
    .unwrap();
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
    // Each of: simulate without and with its budget, cut without and with its budget.
    let mut cpu: [Vec<f64>; 4] = Default::default();
    for _ in 0..runs {
        for (k, times) in cpu.iter_mut().enumerate() {
            let t0 = cpu_now();
            match k {
                0 | 1 => {
                    let sim = dir.join("sim");
                    mtsim::study::simulate::simulate_with(&scenario, &sim, false, k == 1, &|_| {})
                        .unwrap();
                }
                _ => cut_with_files(&scenario, &dir.join("cut"), k == 3),
            }
            times.push(cpu_now() - t0);
        }
    }
    let [s, sb, c, cb] = cpu.map(median);
    println!(
        "cone 15/10, 720 segments, {runs} runs each (median CPU): simulate --no-budget {:.1} ms, \
         simulate {:.1} ms; cut --no-budget {:.1} ms, cut {:.1} ms; cut --no-budget / simulate \
         --no-budget {:.2}, cut / cut --no-budget {:.2}, cut / simulate {:.2}",
        s * 1e3,
        sb * 1e3,
        c * 1e3,
        cb * 1e3,
        c / s,
        cb / c,
        cb / sb
    );
    let _ = std::fs::remove_dir_all(&dir);
}
