//! Release-mode benchmark of `check`, run by `cargo bench --bench check` (pin it to one
//! core: `taskset -c 1 cargo bench --bench check`).
//!
//! For each bundled cone scenario at its nominal feed, three variants: limits + collisions
//! + cutter engagement (the default), collisions with engagement off, and axis limits alone.
//! Prints the real-time factor (simulated machine seconds per wall second), samples per
//! second and the geometric queries made. It asserts nothing (timing is not a test).

use std::path::PathBuf;
use std::time::Instant;

use mtsim::check::{check, CheckOptions};
use mtsim::input::scenario::Scenario;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
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
    let runs: usize = std::env::var("MTSIM_BENCH_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(15);
    let mut worst = f64::INFINITY;
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
            let path = dir.join(format!("{name}.toml"));
            std::fs::write(&path, format!("{base}{extra}")).unwrap();
            let scenario = Scenario::load(&path).unwrap();
            let mut rates = Vec::new();
            let mut report = None;
            for _ in 0..runs {
                let t = Instant::now();
                let r = check(&scenario, &CheckOptions::default()).unwrap();
                rates.push(r.sim_time_s / t.elapsed().as_secs_f64());
                report = Some(r);
            }
            let r = report.unwrap();
            let rtf = median(rates.clone());
            worst = worst.min(rtf);
            println!(
                "check {name}, {variant}: {} samples over {:.2} s; real-time factor median {:.0}x, best {:.0}x; {:.2} M samples/s; {} queries ({:.4} per sample)",
                r.samples,
                r.sim_time_s,
                rtf,
                rates.iter().cloned().fold(0.0, f64::max),
                r.samples as f64 * rtf / r.sim_time_s / 1e6,
                r.scene_queries.unwrap_or(0),
                r.scene_queries.unwrap_or(0) as f64 / r.samples as f64
            );
        }
    }
    println!("check: lowest real-time factor over the bundled cones {worst:.0}x (goal 10000x)");
    let _ = std::fs::remove_dir_all(&dir);
}
