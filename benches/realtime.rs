//! Release-mode benchmark of the pipeline, run by `cargo bench --bench realtime`.
//!
//! Prints, in one run, for the bundled `cone-15-10` scenario with every nonlinearity on (dry
//! friction and backlash on all five axes, the linear twin beside it):
//! - `simulate` real-time factors (simulated machine seconds per CPU second of the running
//!   thread, so that other load on the machine does not count) with the full 1 ms trace
//!   (as `trace.csv` and as `trace.parquet`), the trace decimated to one row per second, and
//!   the trace off (header only);
//! - the same cone in 36,000 segments against its 360 segments (fine/coarse ratio), as
//!   generated moves and as the G-code file the post-processor writes (read by the
//!   interpreter, as a user's fine-segment program is);
//! - peak memory (VmHWM) of `mtsim simulate` for a program of 1 and of 20 revolutions, to
//!   show that memory stays flat as the program grows;
//! - `check` with collisions on at 1 ms sampling: the real-time factor (per CPU second of
//!   the running thread, like `simulate`), samples per second and the geometric queries made.
//!
//! - whole `mtsim simulate` processes with the full trace (CSV, Parquet), decimated and off:
//!   CPU time of the child process, real-time factor, and the trace's rows and MB per CPU
//!   second (its cost: the difference to the trace-off process).
//!
//! `MTSIM_BENCH_SMOKE=1` runs each simulate case once, the whole processes three times, and
//! skips the rest (a CI smoke run); `MTSIM_BENCH_ONLY=process` runs only the whole processes;
//! `MTSIM_BENCH_ONLY=off` runs only the simulate cases whose name contains `off`
//! (`file-fine`: the 36,000-block file alone);
//! `MTSIM_BENCH_ONLY=budget` runs only `simulate` with the error budget against
//! `--no-budget`, side by side;
//! `MTSIM_BENCH_RUNS=N` runs each simulate case N times (for profiling).
//! It prints figures; it asserts nothing (timing is not a test).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use mtsim::check::{check, CheckOptions};
use mtsim::input::scenario::Scenario;
use mtsim::study::simulate::{simulate, simulate_with};

mod common;
use common::{cpu_now, process_cpu_s, root};

/// Median and best real-time factor of `runs` simulations of `scenario` (CPU time).
fn simulate_rtf(scenario: &Path, out: &Path, runs: usize) -> (f64, f64, f64) {
    let scenario = Scenario::load(scenario).unwrap();
    let mut rtf = Vec::new();
    let mut sim_time = 0.0;
    for _ in 0..runs {
        let t = cpu_now();
        let s = simulate(&scenario, out, false, &|_| {}).unwrap();
        let cpu = cpu_now() - t;
        sim_time = s.sim_time_s;
        rtf.push(s.sim_time_s / cpu.max(1e-9));
    }
    let best = rtf.iter().cloned().fold(0.0, f64::max);
    (sim_time, median(rtf), best)
}

/// `simulate` with and without the error budget side by side (runs alternating, so that a
/// drift in the machine's load hits both): the median CPU time of each, ms, and their ratio.
fn budget_cost(scenario: &Path, out: &Path, runs: usize) -> (f64, f64, f64) {
    let scenario = Scenario::load(scenario).unwrap();
    let (mut with, mut without) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        for (budget, times) in [(false, &mut without), (true, &mut with)] {
            let t = cpu_now();
            simulate_with(&scenario, out, false, budget, &|_| {}).unwrap();
            times.push(cpu_now() - t);
        }
    }
    let (with, without) = (median(with), median(without));
    (without * 1e3, with * 1e3, with / without.max(1e-9))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mtsim-bench-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The 15/10 cone with dry friction and backlash on every axis.
fn all_nonlinear(dir: &Path) -> PathBuf {
    let mut s = std::fs::read_to_string(root().join("scenarios/cone-15-10.toml")).unwrap();
    s = s.replace("../machines/", &format!("{}/machines/", root().display()));
    for a in ["X", "Y", "Z"] {
        s += &format!("[machine_overrides.axes.{a}.drive]\nbacklash_mm = 0.003\n[machine_overrides.axes.{a}.friction]\ncoulomb_n = 200.0\n");
    }
    for a in ["A", "C"] {
        s += &format!("[machine_overrides.axes.{a}.drive]\nbacklash_deg = 0.002\n[machine_overrides.axes.{a}.friction]\ncoulomb_nm = 20.0\n");
    }
    let path = dir.join("nonlinear.toml");
    std::fs::write(&path, s).unwrap();
    path
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Peak resident memory of a child `mtsim` run, kB, polled from /proc.
fn peak_rss_kb(args: &[&str]) -> Option<u64> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_mtsim"))
        .args(args)
        .stdout(std::process::Stdio::null())
        .spawn()
        .ok()?;
    let status = format!("/proc/{}/status", child.id());
    let mut peak = None;
    loop {
        if let Ok(text) = std::fs::read_to_string(&status) {
            if let Some(kb) = text
                .lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
            {
                peak = Some(kb);
            }
        }
        if child.try_wait().ok()?.is_some() {
            return peak;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// A scenario that runs the cone of `nonlinear` (the text of [`all_nonlinear`]'s scenario)
/// in `segments` blocks as the G-code file the post-processor writes, with the same machine
/// overrides.
fn cone_file_scenario(dir: &Path, nonlinear: &str, segments: usize) -> PathBuf {
    use mtsim::input::scenario::Program;
    let generated = dir.join(format!("generated-{segments}.toml"));
    let body = nonlinear.replace("segments = 360", &format!("segments = {segments}"));
    std::fs::write(&generated, &body).unwrap();
    let scenario = Scenario::load(&generated).unwrap();
    let Program::Cone { cone, nc, .. } = &scenario.program else {
        panic!("the bench's scenario is a generated cone");
    };
    let path = mtsim::program::cone::ConePath::new(*cone, &scenario.machine);
    let (program, _) = mtsim::program::cone::write_program(&path, &scenario.machine.name, nc);
    let nc_path = dir.join(format!("cone-{segments}.nc"));
    std::fs::write(&nc_path, program).unwrap();
    let machine_line = body.lines().find(|l| l.starts_with("machine")).unwrap();
    let overrides = &body[body.find("[machine_overrides").unwrap()..];
    let file = dir.join(format!("file-{segments}.toml"));
    std::fs::write(
        &file,
        format!(
            "{machine_line}\n[program]\nfile = {:?}\n[program.cone]\nhalf_apex_deg = {:?}\ninclination_deg = {:?}\ncenter_mm = [{:?}, {:?}, {:?}]\nballbar_length_mm = {:?}\n{overrides}",
            nc_path.display().to_string(),
            cone.half_apex_deg,
            cone.inclination_deg,
            cone.center_mm[0],
            cone.center_mm[1],
            cone.center_mm[2],
            cone.ballbar_length_mm,
        ),
    )
    .unwrap();
    file
}

/// A G-code file of `revolutions` turns of the 15/10 cone (360 blocks each), C continuous.
fn long_program(dir: &Path, revolutions: usize) -> PathBuf {
    let base =
        std::fs::read_to_string(root().join("scenarios/programs/cone-15-10-yt25.nc")).unwrap();
    let moves: Vec<&str> = base.lines().filter(|l| l.starts_with("G01")).collect();
    let mut out = String::new();
    for l in base.lines().take_while(|l| !l.starts_with("G01")) {
        out.push_str(l);
        out.push('\n');
    }
    for r in 0..revolutions {
        for m in &moves {
            // Shift C by a full turn per revolution so that the axis keeps turning one way.
            let words: Vec<String> = m
                .split_whitespace()
                .map(|w| match w.strip_prefix('C') {
                    Some(v) if !w.starts_with("(") => {
                        format!("C{:.4}", v.parse::<f64>().unwrap() - 360.0 * r as f64)
                    }
                    _ => w.to_string(),
                })
                .collect();
            out.push_str(&words.join(" "));
            out.push('\n');
        }
    }
    out.push_str("M30\n");
    let nc = dir.join(format!("long-{revolutions}.nc"));
    std::fs::write(&nc, out).unwrap();
    let scenario = dir.join(format!("long-{revolutions}.toml"));
    std::fs::write(
        &scenario,
        format!(
            "machine = {:?}\n[program]\nfile = {:?}\n[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [0.0, -25.0, 200.0]\nballbar_length_mm = 100.0\n[simulate]\ntrace_every = 1000\n",
            root().join("machines/trt-ac.toml").display().to_string(),
            nc.display().to_string()
        ),
    )
    .unwrap();
    scenario
}

/// Whole `mtsim simulate` processes (issue 27: at least 1,000x real time per CPU second with
/// the full trace): the cases `cases` (full trace as CSV, as Parquet, decimated, off), each
/// the median CPU time of `runs` processes, every run into a fresh folder; the trace's cost is
/// the difference to the trace-off process, its throughput in rows and MB per CPU second.
fn whole_processes(dir: &Path, cases: &[(&str, PathBuf)], runs: usize) {
    let sim_time = Scenario::load(&cases[0].1)
        .ok()
        .and_then(|s| simulate(&s, &dir.join("process-probe"), false, &|_| {}).ok())
        .map_or(f64::NAN, |s| s.sim_time_s);
    // Run r of every case in turn (the load of a shared machine drifts), each into a fresh
    // folder: replacing the last run's files costs the kernel time too. The median of the
    // runs of a case is its figure (one run slowed by another process's burst does not move it).
    let outs: Vec<PathBuf> = (0..cases.len())
        .map(|k| dir.join(format!("process-{k}")))
        .collect();
    for out in &outs {
        let _ = std::fs::remove_dir_all(out);
    }
    let mut times = vec![Some(Vec::new()); cases.len()];
    for r in 0..runs {
        for (k, (_, path)) in cases.iter().enumerate() {
            let out = outs[k].join(r.to_string());
            let t = process_cpu_s(
                &[
                    "simulate".as_ref(),
                    path.as_os_str(),
                    "-o".as_ref(),
                    out.as_os_str(),
                    "--no-timing".as_ref(),
                    // simulate alone, as the goal was set: the error budget's own cost is
                    // the budget case's (its ratio against this, goal <= 3x).
                    "--no-budget".as_ref(),
                ],
                1,
            );
            times[k] = times[k].take().zip(t).map(|(mut v, t)| {
                v.push(t);
                v
            });
        }
    }
    let cpu: Vec<(Option<f64>, PathBuf)> = times
        .into_iter()
        .zip(&outs)
        .map(|(t, out)| (t.map(median), out.join("0")))
        .collect();
    let off = cpu.last().and_then(|(t, _)| *t);
    for ((name, _), (t, out)) in cases.iter().zip(&cpu) {
        let Some(t) = t else {
            println!("whole mtsim simulate process, {name}: no /proc, not measured");
            continue;
        };
        let trace = ["trace.csv", "trace.parquet"]
            .iter()
            .map(|f| out.join(f))
            .find(|f| f.exists());
        let throughput = match (trace, off) {
            (Some(file), Some(off)) if *name != cases[cases.len() - 1].0 => {
                let bytes = std::fs::metadata(&file).map_or(0, |m| m.len());
                let rows = mtsim::report::trace::read_trace(out)
                    .ok()
                    .flatten()
                    .map_or(0, |t| t.runs.iter().map(|r| r.time_s.len()).sum::<usize>());
                let cost = (t - off).max(1e-6);
                format!(
                    "; the trace {:.1} ms: {rows} rows, {:.2} M rows/s, {:.0} MB/s",
                    cost * 1e3,
                    rows as f64 / cost / 1e6,
                    bytes as f64 / cost / 1e6
                )
            }
            _ => String::new(),
        };
        let rtf = sim_time / t;
        let goal = if name.starts_with("full") {
            format!(
                " (goal >= 1,000x: {})",
                if rtf >= 1000.0 { "met" } else { "NOT met" }
            )
        } else {
            String::new()
        };
        println!(
            "whole mtsim simulate process (--no-budget), cone-15-10 all nonlinear, {name}: {:.1} ms CPU (median of {runs}), {rtf:.0}x real time per CPU second{goal}{throughput}",
            t * 1e3
        );
    }
}

fn main() {
    let dir = scratch("run");

    let smoke = std::env::var("MTSIM_BENCH_SMOKE").is_ok_and(|v| !v.is_empty() && v != "0");
    let runs = std::env::var("MTSIM_BENCH_RUNS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(if smoke { 1 } else { 7 });

    // 1. simulate, all nonlinearities on: full trace, decimated, off; fine against coarse.
    let base = all_nonlinear(&dir);
    let text = std::fs::read_to_string(&base).unwrap();
    let variant = |name: &str, extra: &str, segments: usize| {
        let path = dir.join(format!("{name}.toml"));
        let body = text.replace("segments = 360", &format!("segments = {segments}"));
        std::fs::write(&path, format!("{body}{extra}")).unwrap();
        path
    };
    let cases = [
        ("full 1 ms trace", variant("full", "", 360)),
        (
            "full 1 ms trace as Parquet",
            variant("parquet", "[simulate]\ntrace_format = \"parquet\"\n", 360),
        ),
        (
            "trace decimated to 1 s",
            variant("decimated", "[simulate]\ntrace_every = 1000\n", 360),
        ),
        (
            "trace off",
            variant("off", "[simulate]\ntrace_every = 1000000000000\n", 360),
        ),
        ("36,000 segments, full trace", variant("fine", "", 36_000)),
    ];
    let mut full_rtf = 0.0;
    // `MTSIM_BENCH_ONLY=off` runs only the cases whose name contains `off` (for profiling).
    let only = std::env::var("MTSIM_BENCH_ONLY").unwrap_or_default();
    for (name, path) in cases
        .iter()
        .filter(|(name, _)| name.contains(only.as_str()))
    {
        let (sim_time, med, best) = simulate_rtf(path, &dir.join("out"), runs);
        let ratio = if name.starts_with("36,000") {
            format!("; 360/36,000-segment time ratio {:.2}", full_rtf / med)
        } else {
            String::new()
        };
        if *name == "full 1 ms trace" {
            full_rtf = med;
        }
        println!(
            "simulate cone-15-10, friction + backlash on X Y Z A C, linear twin, {name}: {sim_time:.2} s machine time; real-time factor (per CPU second) median {med:.0}x, best {best:.0}x ({runs} runs){ratio}"
        );
    }
    // The error budget's cost: `simulate` with it against `simulate --no-budget`, on the
    // bundled cone (friction on every axis) and with every nonlinearity on (`MTSIM_BENCH_ONLY=budget`).
    if only.is_empty() || only == "budget" {
        let stock = root().join("scenarios/cone-15-10.toml");
        for (name, path) in [
            ("cone-15-10 as bundled (friction on X Y Z A C)", stock),
            (
                "cone-15-10, friction + backlash on X Y Z A C",
                cases[0].1.clone(),
            ),
        ] {
            let (without, with, ratio) = budget_cost(&path, &dir.join("out-budget"), runs);
            println!(
                "simulate {name}, full trace: without the error budget {without:.1} ms CPU, with it {with:.1} ms (median of {runs}); ratio {ratio:.2} (goal <= 3: {})",
                if ratio <= 3.0 { "met" } else { "NOT met" }
            );
        }
    }
    // The same two cones as G-code files, full trace: the interpreter reads every block.
    // `MTSIM_BENCH_ONLY=file-fine` runs the 36,000-block file alone (for profiling).
    if only.is_empty() || "file".contains(only.as_str()) || only == "file-fine" {
        let coarse = cone_file_scenario(&dir, &text, 360);
        let fine = cone_file_scenario(&dir, &text, 36_000);
        let (coarse_time, coarse_med, _) = if only == "file-fine" {
            (f64::NAN, f64::NAN, f64::NAN)
        } else {
            simulate_rtf(&coarse, &dir.join("out"), runs)
        };
        let (fine_time, fine_med, fine_best) = simulate_rtf(&fine, &dir.join("out"), runs);
        println!(
            "simulate cone-15-10 as a G-code file, friction + backlash on X Y Z A C, linear twin, full trace: 360 blocks {coarse_time:.2} s machine time, median {coarse_med:.0}x; 36,000 blocks {fine_time:.2} s, median {fine_med:.0}x, best {fine_best:.0}x ({runs} runs); 360/36,000-block time ratio {:.2}",
            coarse_med / fine_med
        );
    }
    if only.is_empty() || only == "process" {
        whole_processes(&dir, &cases[..4], if smoke { 3 } else { 15 });
    }
    if smoke || only == "process" || only == "budget" {
        let _ = std::fs::remove_dir_all(&dir);
        return;
    }

    // 2. memory against program length.
    for revolutions in [1, 20] {
        let s = long_program(&dir, revolutions);
        let out = dir.join(format!("out-long-{revolutions}"));
        let t = Instant::now();
        let kb = peak_rss_kb(&[
            "simulate",
            s.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--no-timing",
        ]);
        println!(
            "simulate a {revolutions}-revolution file program ({} blocks): peak memory {} kB, {:.2} s wall",
            revolutions * 360,
            kb.map_or("unknown".into(), |k| k.to_string()),
            t.elapsed().as_secs_f64()
        );
    }

    // 3. check at 1 ms sampling: collisions with cutter engagement (the default), collisions
    // without engagement tracking, and axis limits alone.
    let base = std::fs::read_to_string(root().join("scenarios/cone-15-10.toml"))
        .unwrap()
        .replace("../machines/", &format!("{}/machines/", root().display()));
    let variants = [
        (
            "limits + collisions + cutter engagement (1 mm)",
            String::new(),
        ),
        (
            "limits + collisions, engagement off",
            "[machine_overrides.scene]\nengagement_resolution_mm = 1e9\n".to_string(),
        ),
        ("limits only", "[check]\ncollisions = false\n".to_string()),
    ];
    for (name, extra) in variants {
        let path = dir.join("check.toml");
        std::fs::write(&path, format!("{base}{extra}")).unwrap();
        let scenario = Scenario::load(&path).unwrap();
        let mut rates = Vec::new();
        let mut report = None;
        for _ in 0..20 {
            // Thread CPU time, which the kernel updates at scheduler ticks (4 ms): one
            // measurement repeats the check until it has run for 0.1 s of CPU.
            let (t, mut n) = (cpu_now(), 0u32);
            let mut r;
            loop {
                r = check(&scenario, &CheckOptions::default()).unwrap();
                n += 1;
                if cpu_now() - t >= 0.1 {
                    break;
                }
            }
            rates.push(r.sim_time_s * n as f64 / (cpu_now() - t));
            report = Some(r);
        }
        let r = report.unwrap();
        let rtf = median(rates.clone());
        println!(
            "check cone-15-10, {name}: {} samples over {:.2} s; real-time factor median {:.0}x, best {:.0}x; {:.2} M samples/s; {} geometric queries ({:.3} per sample)",
            r.samples,
            r.sim_time_s,
            rtf,
            rates.iter().cloned().fold(0.0, f64::max),
            r.samples as f64 * rtf / r.sim_time_s / 1e6,
            r.scene_queries.unwrap_or(0),
            r.scene_queries.unwrap_or(0) as f64 / r.samples as f64
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
