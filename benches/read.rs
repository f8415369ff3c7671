//! Read rate of the G-code reader (`cargo bench --bench read`), with criterion.
//!
//! A 100,000-block G01 program with six axis words and an F word per block, read from
//! memory into canonical moves; criterion reports the throughput in blocks per second.
//! The generated cone (360 blocks) is measured beside it: the moves the generator feeds
//! straight into the pipeline, against writing the same program as text and reading it back.
//!
//! Then, against LinuxCNC's interpreter (issue 9, item 17): a 1,000,000-block G01 file on
//! disk is read by `ngc::read_file` (streaming, into canonical moves), by `mtsim blocks
//! --csv` (reading and printing every move to a file), and by `rs274` when it is installed
//! (interpreting and printing its canonical calls to a file, as docs/rs274.md runs it).
//! The ratios are printed; the goal is mtsim ≥ 20× faster than rs274.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use criterion::{criterion_group, Criterion, Throughput};
use mtsim::input::scenario::Scenario;
use mtsim::input::Program;
use mtsim::program::cone::{write_program, ConePath, ConeProgram};
use mtsim::AxisVec;

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

fn read(c: &mut Criterion) {
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

/// Blocks of the file read by both mtsim and rs274.
const BIG_BLOCKS: usize = 1_000_000;

/// A G01 file of [`BIG_BLOCKS`] blocks, X Y Z with 4 decimals and a varying F, as the
/// measurement in docs/rs274.md §5.
fn write_big_file(path: &Path) {
    use std::io::Write;
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    writeln!(out, "G21 G90 G94 G17").unwrap();
    // A fixed linear congruential sequence: the same file on every run.
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..BIG_BLOCKS {
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

/// Wall time of `f`, s: the best of `runs`.
fn best_of(runs: usize, mut f: impl FnMut()) -> f64 {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
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
    write_big_file(&program);
    let mb = std::fs::metadata(&program).unwrap().len() as f64 / 1e6;
    println!("\n1M-block G01 file ({mb:.1} MB), wall time, best of 3 (rs274: of 2):");

    let reader_s = best_of(3, || {
        let moves = ngc::read_file(&program, AxisVec::ZERO).unwrap();
        let n = moves.map(|m| black_box(m.unwrap())).count();
        assert_eq!(n, BIG_BLOCKS);
    });
    println!(
        "  ngc::read_file            {reader_s:>7.3} s  {:>6.2} M blocks/s",
        BIG_BLOCKS as f64 / reader_s / 1e6
    );

    let scenario = dir.join("s.toml");
    let machine = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/vmc-3axis.toml");
    std::fs::write(
        &scenario,
        format!(
            "machine = {:?}\n[program]\nfile = \"big.ngc\"\n",
            machine.display().to_string()
        ),
    )
    .unwrap();
    let blocks_s = best_of(3, || {
        let status = Command::new(env!("CARGO_BIN_EXE_mtsim"))
            .args(["blocks", scenario.to_str().unwrap(), "--csv"])
            .stdout(std::fs::File::create(dir.join("blocks.csv")).unwrap())
            .status()
            .unwrap();
        assert!(status.success());
    });
    println!(
        "  mtsim blocks --csv > file {blocks_s:>7.3} s  {:>6.2} M blocks/s",
        BIG_BLOCKS as f64 / blocks_s / 1e6
    );

    match rs274_binary() {
        None => println!("  rs274: not installed (package linuxcnc-uspace), comparison skipped"),
        Some(rs274) => {
            let var = dir.join("p.var");
            let tools = dir.join("tool.tbl");
            std::fs::write(&tools, "").unwrap();
            let rs_s = best_of(2, || {
                std::fs::write(&var, "").unwrap();
                let status = Command::new(&rs274)
                    .env("HOME", &dir)
                    .arg("-t")
                    .arg(&tools)
                    .arg("-v")
                    .arg(&var)
                    .args(["-n", "2", "-g"])
                    .arg(&program)
                    .arg(dir.join("rs274.out"))
                    .stdin(Stdio::null())
                    .stdout(Stdio::null())
                    .stderr(Stdio::null())
                    .status()
                    .unwrap();
                assert!(status.success(), "rs274 failed on the benchmark file");
            });
            println!(
                "  rs274 (output file)       {rs_s:>7.3} s  {:>6.2} M blocks/s",
                BIG_BLOCKS as f64 / rs_s / 1e6
            );
            let ratio = rs_s / reader_s;
            println!(
                "  reader {ratio:.1}x faster than rs274 ({}; goal >= 20x); mtsim blocks {:.1}x",
                if ratio >= 20.0 {
                    "meets the goal"
                } else {
                    "BELOW the goal"
                },
                rs_s / blocks_s
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, read);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    versus_rs274();
}
