//! Release-mode benchmark of a study's points, run by `cargo bench --bench study`.
//!
//! A 1,000-point study of X and Y backlash and kv on the bundled 15/10 cone (every point
//! 41 s of machine time), side by side in one run:
//! - the single-point path (`run_ballbar`, one point at a time) on a subset, extrapolated;
//! - the shared path (`run_ballbar_lanes`: one interpolation pass per group of points, the
//!   drives side by side, twins shared) on a rayon pool of 1 thread and of 2.
//!
//! Figures: CPU seconds of the process (every thread; `/proc/self/stat`), wall seconds, and
//! the real-time factor per point per CPU second (machine seconds of all points / CPU s).
//! `MTSIM_BENCH_SMOKE=1` runs 16 points and 2 single ones (a CI smoke run);
//! `MTSIM_BENCH_POINTS=N` sets the study's size and `MTSIM_BENCH_SINGLE=N` the subset's;
//! `MTSIM_BENCH_ONLY=single|lanes1|lanes2|setup` runs one case (for callgrind); `setup`
//! times only the building of the bundled tolerance study's points' scenarios from its
//! base (`mtsim::study::param`), no simulation.
//! It prints figures; it asserts nothing (timing is not a test).

use std::path::PathBuf;
use std::time::Instant;

use mtsim::input::scenario::Scenario;
use mtsim::study::lanes::run_ballbar_lanes;
use mtsim::study::simulate::run_ballbar;
use mtsim::Axis;

/// CPU time of the whole process, s (user + system, `/proc/self/stat`, clock ticks of
/// 10 ms); wall time where that file does not exist.
fn cpu_now() -> f64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|t| {
            // Fields after the command's closing parenthesis; utime and stime are 14 and 15.
            let rest = &t[t.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some((f[11].parse::<f64>().ok()? + f[12].parse::<f64>().ok()?) / 100.0)
        })
        .unwrap_or_else(|| START.get_or_init(Instant::now).elapsed().as_secs_f64())
}

fn env_usize(name: &str) -> Option<usize> {
    std::env::var(name).ok().and_then(|v| v.parse().ok())
}

/// The study's points: X backlash, Y backlash (0-9 µm each) and kv of X and Y (25-34 /s),
/// kv outermost so that the points of one pass share their linear twins as a grid does.
fn points(base: &Scenario, n: usize) -> Vec<Scenario> {
    (0..n)
        .map(|i| {
            let (bx, by, kv) = (i % 10, (i / 10) % 10, (i / 100) % 10);
            let mut s = base.clone();
            for (axis, backlash) in [(Axis::X, bx), (Axis::Y, by)] {
                let config = s.machine.axis_mut(axis);
                config.drive.backlash_mm = Some(backlash as f64 * 1e-3);
                config.servo.kv_per_s = 25.0 + kv as f64;
            }
            s
        })
        .collect()
}

/// Runs `f` and returns (CPU s, wall s).
fn measure(f: impl FnOnce()) -> (f64, f64) {
    let (c, w) = (cpu_now(), Instant::now());
    f();
    (cpu_now() - c, w.elapsed().as_secs_f64())
}

/// The set-up of a study's points alone: each point's scenario of the bundled tolerance
/// study (`scenarios/studies/tolerance-cone-15-10.toml`) built from its parsed base.
fn setup(root: &std::path::Path, n: usize) {
    let path = root.join("scenarios/studies/tolerance-cone-15-10.toml");
    let study = mtsim::study::param::Study::load(&path, None, Some(n)).unwrap();
    let keys = study.spec.keys();
    let t = measure(|| {
        for p in &study.points {
            study.tree.load_with(&keys, p).unwrap();
        }
    });
    println!(
        "{:<28} {n:>5} points  CPU {:>7.3} s  wall {:>7.3} s  {:>7.1} us CPU/point",
        "set-up only (no simulation)",
        t.0,
        t.1,
        1e6 * t.0 / n as f64
    );
}

fn main() {
    let smoke = std::env::var("MTSIM_BENCH_SMOKE").is_ok_and(|v| !v.is_empty() && v != "0");
    let n = env_usize("MTSIM_BENCH_POINTS").unwrap_or(if smoke { 16 } else { 1000 });
    let n_single = env_usize("MTSIM_BENCH_SINGLE").unwrap_or(if smoke { 2 } else { 20 });
    let only = std::env::var("MTSIM_BENCH_ONLY").unwrap_or_default();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    if only == "setup" {
        return setup(&root, n);
    }
    let base = Scenario::load(&root.join("scenarios/cone-15-10.toml")).unwrap();
    let study = points(&base, n);
    let sim_s = run_ballbar(&study[0], None, &|_| {}).unwrap().sim_time_s;
    println!("study: {n} points of the 15/10 cone, {sim_s:.2} s of machine time each");
    let line = |name: &str, points: usize, (cpu, wall): (f64, f64)| {
        println!(
            "{name:<28} {points:>5} points  CPU {cpu:>7.3} s  wall {wall:>7.3} s  \
             {:>7.1} ms CPU/point  {:>8.0}x real time per point per CPU s",
            1e3 * cpu / points as f64,
            sim_s * points as f64 / cpu.max(1e-9)
        );
    };
    if only.is_empty() || only == "single" {
        // Spread over the grid: every (n / n_single)-th point.
        let step = (n / n_single.max(1)).max(1);
        let subset: Vec<&Scenario> = study.iter().step_by(step).take(n_single).collect();
        let t = measure(|| {
            for s in &subset {
                run_ballbar(s, None, &|_| {}).unwrap();
            }
        });
        line("single (one point a time)", subset.len(), t);
        let per_point = t.0 / subset.len() as f64;
        println!(
            "{:<28} {n:>5} points  CPU {:>7.3} s  (extrapolated)",
            "single, whole study",
            per_point * n as f64
        );
    }
    let mut walls = Vec::new();
    for threads in [1, 2] {
        if !(only.is_empty() || only == format!("lanes{threads}")) {
            continue;
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let t = measure(|| {
            let results = pool.install(|| run_ballbar_lanes(&study, &|_| {}));
            assert!(results.iter().all(|r| r.is_ok()), "a point failed");
        });
        line(&format!("lanes, {threads} thread(s)"), n, t);
        walls.push(t.1);
    }
    if let [one, two] = walls[..] {
        println!("2 threads against 1: {:.2}x faster (wall)", one / two);
    }
}
