//! Prints the canonical moves of a program, one line each:
//! `cargo run -p ngc --example ngc_blocks -- FILE [linuxcnc|fanuc|haas] [TOOL_TABLE]`.

use std::path::Path;

use ngc::{parse_tool_table, read_file_with, Axis, Dialect, Options};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(file) = args.get(1) else {
        eprintln!("usage: ngc_blocks FILE [linuxcnc|fanuc|haas] [TOOL_TABLE]");
        std::process::exit(2);
    };
    let mut options = Options::default();
    options.dialect = match args.get(2).map(String::as_str) {
        Some("linuxcnc") => Dialect::Linuxcnc,
        Some("haas") => Dialect::Haas,
        _ => Dialect::Fanuc,
    };
    if let Some(table) = args.get(3) {
        let text = std::fs::read_to_string(table).unwrap_or_default();
        options.tools = parse_tool_table(&text).unwrap_or_else(|(line, m)| {
            eprintln!("{table}:{line}: {m}");
            std::process::exit(2)
        });
    }
    if let Some(dirs) = std::env::var_os("NGC_PATH") {
        options.search_path = std::env::split_paths(&dirs).collect();
    }
    let moves = match read_file_with(Path::new(file), &options) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2)
        }
    };
    if std::env::var_os("NGC_COUNT").is_some() {
        let t = std::time::Instant::now();
        let n = moves.filter(|m| m.is_ok()).count();
        let s = t.elapsed().as_secs_f64();
        println!("{n} moves in {s:.3} s: {:.0} blocks/s", n as f64 / s);
        return;
    }
    for m in moves {
        match m {
            Ok(m) => {
                let e: Vec<String> = Axis::ALL
                    .iter()
                    .map(|&a| format!("{:.4}", m.end[a]))
                    .collect();
                println!(
                    "{} {} {} F{:?} T{}",
                    m.line,
                    m.kind().name(),
                    e.join(" "),
                    m.feed,
                    m.tool
                );
            }
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(2)
            }
        }
    }
}
