//! Release-mode benchmark of a study's points, run by `cargo bench --bench study`.
//!
//! A 1,000-point study of X and Y backlash and kv on the bundled 15/10 cone (every point
//! 41 s of machine time), side by side in one run:
//! - the single-point path (`run_ballbar`, one point at a time) on a subset, extrapolated;
//! - the shared path (`run_ballbar_lanes`: one interpolation pass per group of points, each
//!   distinct drive of an axis stepped once) on a rayon pool of 1 thread and of 2.
//!
//! Two studies: `grid` (X and Y backlash 0-9 µm in steps of 1, kv of X and Y together
//! 25-34 /s: a pass's points share most of their drives) and `random` (X and Y backlash and
//! kv each uniform and independent over the same ranges, as a tolerance study draws them:
//! every point's X and Y drives are its own). `MTSIM_BENCH_STUDY=grid|random` runs one.
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

/// The grid study's points: X backlash, Y backlash (0-9 µm each) and kv of X and Y
/// (25-34 /s), kv outermost as a grid's loops run.
fn grid_points(base: &Scenario, n: usize) -> Vec<Scenario> {
    (0..n)
        .map(|i| {
            let (bx, by, kv) = (i % 10, (i / 10) % 10, (i / 100) % 10);
            let kv = 25.0 + kv as f64;
            with_drives(base, [bx as f64 * 1e-3, by as f64 * 1e-3], [kv, kv])
        })
        .collect()
}

/// The random study's points: X and Y backlash uniform in 0-9 µm and kv of X and of Y
/// uniform in 25-34 /s, independent (splitmix64, seed 27).
fn random_points(base: &Scenario, n: usize) -> Vec<Scenario> {
    let mut state = 27u64;
    let mut uniform = |low: f64, high: f64| {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        low + (high - low) * (z >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let backlash_mm = [uniform(0.0, 0.009), uniform(0.0, 0.009)];
            let kv = [uniform(25.0, 34.0), uniform(25.0, 34.0)];
            with_drives(base, backlash_mm, kv)
        })
        .collect()
}

/// `base` with X and Y backlash (mm) and kv (1/s) as given.
fn with_drives(base: &Scenario, backlash_mm: [f64; 2], kv_per_s: [f64; 2]) -> Scenario {
    let mut s = base.clone();
    for (k, axis) in [Axis::X, Axis::Y].into_iter().enumerate() {
        let d = s.machine.drive(axis);
        let d = d.with_backlash_mm_or_deg(backlash_mm[k]).unwrap();
        s.machine.axis_mut(axis).drive = d.with_kv_per_s(kv_per_s[k]).unwrap();
    }
    s
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
    let which = std::env::var("MTSIM_BENCH_STUDY").unwrap_or_default();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    if only == "setup" {
        return setup(&root, n);
    }
    let base = Scenario::load(&root.join("scenarios/cone-15-10.toml")).unwrap();
    let sim_s = run_ballbar(&base, None, &|_| {}).unwrap().sim_time_s;
    let studies: [(&str, fn(&Scenario, usize) -> Vec<Scenario>); 2] =
        [("grid", grid_points), ("random", random_points)];
    for (name, points) in studies {
        if which.is_empty() || which == name {
            run_study(name, &points(&base, n), sim_s, n_single, &only);
        }
    }
}

/// Runs the cases of one study and prints their figures.
fn run_study(name: &str, study: &[Scenario], sim_s: f64, n_single: usize, only: &str) {
    let n = study.len();
    println!("{name} study: {n} points of the 15/10 cone, {sim_s:.2} s of machine time each");
    let line = |name: &str, points: usize, (cpu, wall): (f64, f64)| {
        println!(
            "{name:<28} {points:>5} points  CPU {cpu:>7.3} s  wall {wall:>7.3} s  \
             {:>7.1} ms CPU/point  {:>8.0}x real time per point per CPU s",
            1e3 * cpu / points as f64,
            sim_s * points as f64 / cpu.max(1e-9)
        );
    };
    if only.is_empty() || only == "single" {
        // Spread over the study: every (n / n_single)-th point.
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
            let results = pool.install(|| run_ballbar_lanes(study, &|_| {}));
            assert!(results.iter().all(|r| r.is_ok()), "a point failed");
        });
        line(&format!("lanes, {threads} thread(s)"), n, t);
        walls.push(t.1);
    }
    if let [one, two] = walls[..] {
        println!("2 threads against 1: {:.2}x faster (wall)", one / two);
    }
}
