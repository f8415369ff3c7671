//! Read rate of the G-code reader (`cargo bench --bench read`), with criterion.
//!
//! A 100,000-block G01 program with six axis words and an F word per block, read from
//! memory into canonical moves; criterion reports the throughput in blocks per second.
//! The generated cone (360 blocks) is measured beside it: the moves the generator feeds
//! straight into the pipeline, against writing the same program as text and reading it back.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
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

criterion_group!(benches, read);
criterion_main!(benches);
