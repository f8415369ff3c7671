//! Read rate of the G-code reader (`cargo bench --bench read`), with criterion.
//!
//! The same toolpath is read in each dialect (LinuxCNC, Fanuc, Haas, Heidenhain Klartext),
//! and each dialect's time is printed against the Fanuc front end's (issue 29: within 2×).
//!
//! A 100,000-block G01 program with six axis words and an F word per block, read from
//! memory into canonical moves; criterion reports the throughput in blocks per second.
//! The same program through the Siemens Sinumerik front end is measured beside it (goal:
//! within 2x of the Fanuc reader). The generated cone (360 blocks) is measured beside it: the moves the generator feeds
//! straight into the pipeline, against writing the same program as text and reading it back.
//!
//! Then, against LinuxCNC's interpreter (issue 9, item 17): a 1,000,000-block G01 file on
//! disk is read by `ngc::read_file` (streaming, into canonical moves; and with the Siemens
//! front end), by `mtsim blocks
//! --csv` (reading and printing every move to a file), and by `rs274` when it is installed
//! (interpreting and printing its canonical calls to a file, as docs/rs274.md runs it).
//! Wall and CPU time are printed (CPU: this thread for the reader, the child process for
//! the others; the fair figure when the machine is shared) and the ratios; the goal is
//! the reader ≥ 20× faster than rs274. `MTSIM_BENCH_VS_ONLY=1` skips the criterion part;
//! `MTSIM_BENCH_SMOKE=1` skips it too and reads a 100,000-block file once each (a CI smoke
//! run: every reader still runs and agrees on the block count).
//!
//! Last, `mtsim analyze` of a 300,000-block file of the same kind as a whole process against
//! `rs274` reading it (issue 27: at least 10x faster), CPU time of the child processes.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use criterion::{criterion_group, Criterion, Throughput};
use mtsim::input::scenario::Scenario;
use mtsim::input::Program;
use mtsim::program::cone::{write_program, ConePath, ConeProgram};
use mtsim::AxisVec;

mod common;
use common::{children_cpu_s, median_cpu_s, process_cpu_s};

const BLOCKS: usize = 100_000;

fn g01_program() -> String {
    let mut text = String::from("G21 G90 G94 G17\n");
    for i in 0..BLOCKS {
        let t = i as f64 * 1e-3;
        text.push_str(&format!(
            "G01 X{:.4} Y{:.4} Z{:.4} A{:.4} C{:.4} F{:.3}\n",
            100.0 * t.cos(),
            100.0 * t.sin(),
            -0.5 * t,
            15.0 * (2.0 * t).sin(),
            t.to_degrees(),
            1000.0 + (i % 7) as f64
        ));
    }
    text.push_str("M30\n");
    text
}

/// The toolpath of [`g01_program`] in each dialect: the same G-code text for LinuxCNC,
/// Fanuc and Haas, numbered `L` blocks for Heidenhain Klartext.
fn dialect_programs() -> Vec<(&'static str, ngc::Dialect, String)> {
    let g = g01_program();
    let mut h = String::from("0 BEGIN PGM BENCH MM\n");
    for (k, line) in g.lines().skip(1).take(BLOCKS).enumerate() {
        let words: Vec<&str> = line.split(' ').skip(1).collect();
        let signed: Vec<String> = words
            .iter()
            .map(|w| match w.as_bytes().get(1) {
                Some(b'-') | None => w.to_string(),
                _ if w.starts_with('F') => w.to_string(),
                _ => format!("{}+{}", &w[..1], &w[1..]),
            })
            .collect();
        h.push_str(&format!("{} L {}\n", k + 1, signed.join(" ")));
    }
    h.push_str(&format!("{} END PGM BENCH MM\n", BLOCKS + 1));
    vec![
        ("linuxcnc", ngc::Dialect::Linuxcnc, g.clone()),
        ("fanuc", ngc::Dialect::Fanuc, g.clone()),
        ("haas", ngc::Dialect::Haas, g),
        ("heidenhain", ngc::Dialect::Heidenhain, h),
    ]
}

fn read_dialect(dialect: ngc::Dialect, text: &str) -> usize {
    let options = ngc::Options {
        dialect,
        ..ngc::Options::default()
    };
    ngc::read_str_with(Path::new("bench"), text, &options)
        .map(|m| black_box(m.unwrap()))
        .count()
}

/// The same toolpath read in every dialect, thread CPU time best of 5, and each dialect's
/// time against the Fanuc front end's (the goal: within 2×).
fn dialects_side_by_side() {
    let programs = dialect_programs();
    let mut fanuc = None;
    for (name, dialect, text) in &programs {
        let (wall, cpu) = best_of(5, thread_cpu_s, || {
            assert_eq!(read_dialect(*dialect, text), BLOCKS)
        });
        let t = cpu.unwrap_or(wall);
        if *name == "fanuc" {
            fanuc = Some(t);
        }
        let ratio = fanuc.map_or(String::new(), |f| format!(" ({:.2}× Fanuc)", t / f));
        println!("read {BLOCKS} blocks, {name:>10}: {:.1} ms{ratio}", t * 1e3);
    }
}

fn read(c: &mut Criterion) {
    let mut group = c.benchmark_group("read per dialect");
    group.sample_size(10);
    group.throughput(Throughput::Elements(BLOCKS as u64));
    for (name, dialect, text) in dialect_programs() {
        group.bench_function(name, |b| {
            b.iter(|| assert_eq!(read_dialect(dialect, &text), BLOCKS))
        });
    }
    group.finish();

    let text = g01_program();
    let mut group = c.benchmark_group("read");
    group.sample_size(10);
    group.throughput(Throughput::Elements(BLOCKS as u64));
    group.bench_function("100k G01 blocks", |b| {
        b.iter(|| {
            let moves = ngc::read_str(Path::new("bench.nc"), black_box(&text), AxisVec::ZERO);
            let mut n = 0usize;
            for m in moves {
                black_box(m.unwrap());
                n += 1;
            }
            assert_eq!(n, BLOCKS);
        })
    });
    // The same program read by the Siemens Sinumerik front end (goal: within 2x of Fanuc).
    let siemens = ngc::Options {
        dialect: ngc::Dialect::Siemens,
        ..ngc::Options::default()
    };
    // Sinumerik says G71 for metric (G21 is ISO mode's).
    let sinumerik_text = text.replacen("G21", "G71", 1);
    group.bench_function("100k G01 blocks, Siemens front end", |b| {
        b.iter(|| {
            let moves =
                ngc::read_str_with(Path::new("bench.mpf"), black_box(&sinumerik_text), &siemens);
            let n = moves.map(|m| black_box(m.unwrap())).count();
            assert_eq!(n, BLOCKS);
        })
    });
    group.finish();

    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scenario = Scenario::load(&root.join("scenarios/cone-15-10.toml")).unwrap();
    let Program::Cone { cone, nc, .. } = &scenario.program else {
        panic!("the bundled cone scenario has a cone program")
    };
    let path = ConePath::new(*cone, &scenario.machine);
    let mut group = c.benchmark_group("cone program");
    group.sample_size(20);
    group.throughput(Throughput::Elements(nc.segments as u64 + 1));
    group.bench_function("generated moves", |b| {
        b.iter(|| {
            let program = ConeProgram::new(&path, &scenario.machine.name, nc);
            program.moves().map(black_box).count()
        })
    });
    group.bench_function("text written and read back", |b| {
        b.iter(|| {
            let (text, _) = write_program(&path, &scenario.machine.name, nc);
            ngc::read_str(Path::new("cone.nc"), &text, AxisVec::ZERO)
                .map(|m| black_box(m.unwrap()))
                .count()
        })
    });
    group.finish();
}

/// Blocks of the file read by both mtsim and rs274 (a tenth in a smoke run).
fn big_blocks() -> usize {
    if smoke() {
        100_000
    } else {
        1_000_000
    }
}

/// `MTSIM_BENCH_SMOKE` is set (and not 0).
fn smoke() -> bool {
    std::env::var("MTSIM_BENCH_SMOKE").is_ok_and(|v| !v.is_empty() && v != "0")
}

/// A G01 file of [`big_blocks`] blocks, X Y Z with 4 decimals and a varying F, as the
/// measurement in docs/rs274.md §5.
/// `metric` is the first block's metric code: G21 (ISO), G71 (Sinumerik).
fn write_big_file(path: &Path, metric: &str) {
    write_g01_file(path, metric, big_blocks());
}

/// A G01 file of `blocks` blocks of [`write_big_file`]'s kind.
fn write_g01_file(path: &Path, metric: &str, blocks: usize) {
    use std::io::Write;
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    writeln!(out, "{metric} G90 G94 G17").unwrap();
    // A fixed linear congruential sequence: the same file on every run.
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..blocks {
        writeln!(
            out,
            "G1 X{:.4} Y{:.4} Z{:.4} F{:.1}",
            200.0 * next() - 100.0,
            200.0 * next() - 100.0,
            -50.0 * next(),
            500.0 + 1000.0 * next()
        )
        .unwrap();
    }
    writeln!(out, "M2").unwrap();
}

/// CPU time of the calling thread, s (`/proc/thread-self/schedstat`, ns on the CPU).
fn thread_cpu_s() -> Option<f64> {
    let t = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    Some(t.split_whitespace().next()?.parse::<f64>().ok()? * 1e-9)
}

/// Wall and CPU time of `f`, s: the best of `runs` each. `cpu` reads a CPU clock (this
/// thread's, or the children's); CPU time is the fair figure on a loaded machine, where
/// the wall time depends on the other work.
fn best_of(runs: usize, cpu: fn() -> Option<f64>, mut f: impl FnMut()) -> (f64, Option<f64>) {
    let mut wall = f64::INFINITY;
    let mut best_cpu: Option<f64> = None;
    for _ in 0..runs {
        let (t, c) = (Instant::now(), cpu());
        f();
        wall = wall.min(t.elapsed().as_secs_f64());
        if let (Some(c0), Some(c1)) = (c, cpu()) {
            best_cpu = Some(best_cpu.map_or(c1 - c0, |b| b.min(c1 - c0)));
        }
    }
    (wall, best_cpu)
}

/// `  name  wall s  (M blocks/s)  cpu s  (M blocks/s)`.
fn line(name: &str, (wall, cpu): (f64, Option<f64>)) {
    let rate = |s: f64| big_blocks() as f64 / s / 1e6;
    match cpu {
        Some(c) => println!(
            "  {name:<26} wall {wall:>7.3} s {:>6.2} M blocks/s   cpu {c:>7.3} s {:>6.2} M blocks/s",
            rate(wall),
            rate(c)
        ),
        None => println!("  {name:<26} wall {wall:>7.3} s {:>6.2} M blocks/s", rate(wall)),
    }
}

fn rs274_binary() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("rs274"))
        .find(|p| p.is_file())
}

/// mtsim's reader and `mtsim blocks` against rs274 on the same 1M-block file.
fn versus_rs274() {
    let dir = std::env::temp_dir().join(format!("mtsim-bench-read-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let program = dir.join("big.ngc");
    write_big_file(&program, "G21");
    let mb = std::fs::metadata(&program).unwrap().len() as f64 / 1e6;
    let (runs, rs_runs) = if smoke() { (1, 1) } else { (3, 2) };
    println!(
        "\n{}k-block G01 file ({mb:.1} MB), best of {runs} (rs274: of {rs_runs}), wall and CPU time:",
        big_blocks() / 1000
    );

    let reader = best_of(runs, thread_cpu_s, || {
        let moves = ngc::read_file(&program, AxisVec::ZERO).unwrap();
        let n = moves.map(|m| black_box(m.unwrap())).count();
        assert_eq!(n, big_blocks());
    });
    line("ngc::read_file", reader);
    let siemens = ngc::Options {
        dialect: ngc::Dialect::Siemens,
        ..ngc::Options::default()
    };
    let mpf = dir.join("big.mpf");
    write_big_file(&mpf, "G71");
    let sinumerik = best_of(runs, thread_cpu_s, || {
        let moves = ngc::read_file_with(&mpf, &siemens).unwrap();
        let n = moves.map(|m| black_box(m.unwrap())).count();
        assert_eq!(n, big_blocks());
    });
    line("ngc::read_file (Siemens)", sinumerik);
    println!(
        "  Siemens front end {:.2}x the Fanuc reader's wall time (goal <= 2x)",
        sinumerik.0 / reader.0
    );

    let scenario = vmc_scenario(&dir, "big.ngc");
    let blocks = best_of(runs, children_cpu_s, || {
        let status = Command::new(env!("CARGO_BIN_EXE_mtsim"))
            .args(["blocks", scenario.to_str().unwrap(), "--csv"])
            .stdout(std::fs::File::create(dir.join("blocks.csv")).unwrap())
            .status()
            .unwrap();
        assert!(status.success());
    });
    line("mtsim blocks --csv > file", blocks);

    match rs274_binary() {
        None => println!("  rs274: not installed (package linuxcnc-uspace), comparison skipped"),
        Some(rs274) => {
            let rs = best_of(rs_runs, children_cpu_s, || {
                run_rs274(&rs274, &dir, &program)
            });
            line("rs274 (output file)", rs);
            let verdict = |ratio: f64| {
                if ratio >= 20.0 {
                    "meets the goal"
                } else {
                    "BELOW the goal"
                }
            };
            let wall = rs.0 / reader.0;
            println!(
                "  reader {wall:.1}x faster than rs274 in wall time ({}; goal >= 20x); mtsim blocks {:.1}x",
                verdict(wall),
                rs.0 / blocks.0
            );
            if let (Some(r), Some(rs_cpu), Some(b)) = (reader.1, rs.1, blocks.1) {
                let cpu = rs_cpu / r;
                println!(
                    "  reader {cpu:.1}x faster than rs274 in CPU time ({}); mtsim blocks {:.1}x",
                    verdict(cpu),
                    rs_cpu / b
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scenario in `dir` that runs the file `program` (in `dir`) on the three-axis VMC.
fn vmc_scenario(dir: &Path, program: &str) -> PathBuf {
    let scenario = dir.join(format!("{program}.toml"));
    let machine = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/vmc-3axis.toml");
    std::fs::write(
        &scenario,
        format!(
            "machine = {:?}\n[program]\nfile = {program:?}\n",
            machine.display().to_string()
        ),
    )
    .unwrap();
    scenario
}

/// Runs `rs274` on `program` (printing its canonical calls to a file in `dir`).
fn run_rs274(rs274: &Path, dir: &Path, program: &Path) {
    let (var, tools) = (dir.join("p.var"), dir.join("tool.tbl"));
    std::fs::write(&tools, "").unwrap();
    std::fs::write(&var, "").unwrap();
    let status = Command::new(rs274)
        .env("HOME", dir)
        .arg("-t")
        .arg(&tools)
        .arg("-v")
        .arg(&var)
        .args(["-n", "2", "-g"])
        .arg(program)
        .arg(dir.join("rs274.out"))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "rs274 failed on the benchmark file");
}

/// Blocks of the file `mtsim analyze` reads against rs274 (issue 27: at least 10x faster).
const ANALYZE_BLOCKS: usize = 300_000;

/// `mtsim analyze` of a 300,000-block G01 file as a whole process (reading, the reversals,
/// the feed limits, the notices, the printed table) against `rs274` reading the same file:
/// CPU time of the child processes, the median of several runs of each.
fn analyze_versus_rs274() {
    let dir = std::env::temp_dir().join(format!("mtsim-bench-analyze-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let program = dir.join("analyze.ngc");
    write_g01_file(&program, "G21", ANALYZE_BLOCKS);
    let scenario = vmc_scenario(&dir, "analyze.ngc");
    let runs = if smoke() { 3 } else { 10 };
    let analyze = process_cpu_s(&["analyze".as_ref(), scenario.as_os_str()], runs);
    let rs = rs274_binary()
        .and_then(|rs274| median_cpu_s(runs.min(3), || run_rs274(&rs274, &dir, &program)));
    let rate = |s: f64| ANALYZE_BLOCKS as f64 / s / 1e6;
    match (analyze, rs) {
        (Some(a), Some(r)) => println!(
            "\nmtsim analyze, {}k-block G01 file, whole process: {a:.3} s CPU ({:.2} M blocks/s); rs274 {r:.3} s ({:.2} M blocks/s); analyze {:.1}x faster (goal >= 10x: {})",
            ANALYZE_BLOCKS / 1000,
            rate(a),
            rate(r),
            r / a,
            if r / a >= 10.0 { "met" } else { "NOT met" }
        ),
        (Some(a), None) => println!(
            "\nmtsim analyze, {}k-block G01 file, whole process: {a:.3} s CPU ({:.2} M blocks/s); rs274 not installed, comparison skipped",
            ANALYZE_BLOCKS / 1000,
            rate(a)
        ),
        _ => println!("\nmtsim analyze: no /proc, CPU time not measured"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, read);

fn main() {
    if std::env::var_os("MTSIM_BENCH_VS_ONLY").is_none() && !smoke() {
        benches();
        Criterion::default().configure_from_args().final_summary();
    }
    dialects_side_by_side();
    versus_rs274();
    analyze_versus_rs274();
}
