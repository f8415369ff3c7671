//! Reads a G-code file and prints its move count and read rate (for profiling the reader):
//! `cargo run --release -p ngc --example read -- program.ngc`.

use std::path::PathBuf;
use std::time::Instant;

fn main() {
    let Some(path) = std::env::args_os().nth(1).map(PathBuf::from) else {
        eprintln!("usage: read FILE");
        std::process::exit(2);
    };
    let t = Instant::now();
    let moves = match ngc::read_file(&path, ngc::AxisVec::ZERO) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let mut n = 0usize;
    for m in moves {
        if let Err(e) = m {
            eprintln!("{e}");
            std::process::exit(2);
        }
        n += 1;
    }
    let s = t.elapsed().as_secs_f64();
    println!("{n} moves in {s:.3} s: {:.3} M moves/s", n as f64 / s / 1e6);
}
