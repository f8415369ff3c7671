//! A G-code file is checked against the machine as its moves stream into the run (no pass
//! of its own): a bad move or a bad line near the end of a long program is still bad input,
//! exit code 2 with file:line:column, and no output file is written.

use crate::common;

use std::path::Path;

/// `blocks` G01 blocks zig-zagging 0.1 mm in X at 6 m/min (1 ms each), then `last`.
fn long_program(blocks: usize, last: &str) -> String {
    let mut text = String::from("G21 G90 G94\nG00 X0 Y0 Z0\n");
    for i in 0..blocks {
        text.push_str(if i % 2 == 0 {
            "G01 X0.1 F6000\n"
        } else {
            "G01 X0 F6000\n"
        });
    }
    text.push_str(last);
    text.push_str("M30\n");
    text
}

#[test]
fn a_bad_move_or_line_near_the_end_of_a_long_program_exits_2_and_writes_nothing() {
    const BLOCKS: usize = 20_000;
    // The bad line is line 2 + BLOCKS + 1 (two header lines, then the blocks).
    let line = BLOCKS + 3;
    let cases = [
        (
            "envelope",
            "G01 X-1000 F1000\n",
            format!("p.nc:{line}:5: this move takes X 1000 mm"),
        ),
        (
            "syntax",
            "G01 X1 Q2\n",
            format!("p.nc:{line}:8: `Q` with no code that uses it"),
        ),
    ];
    for (name, last, expected) in cases {
        let dir = common::scratch("streamed-checks", name);
        let s = common::file_scenario(&dir, &long_program(BLOCKS, last));
        for args in [
            &["analyze", &s][..],
            &["check", &s, "--html", "check.html"][..],
            &["simulate", &s, "-o", "out", "--html"][..],
        ] {
            let out = common::mtsim_plain(&dir, args);
            let err = unwrapped(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{name} {}: {err}", args[0]);
            assert!(err.contains(&expected), "{name} {}: {err}", args[0]);
            assert!(out.stdout.is_empty(), "{name} {}: nothing printed", args[0]);
        }
        let mut written: Vec<_> = walk(&dir);
        written.retain(|p| !p.ends_with("p.nc") && !p.ends_with("s.toml"));
        assert!(written.is_empty(), "{name}: files written: {written:?}");
    }
}

#[test]
fn a_program_whose_only_moves_go_nowhere_is_still_refused_at_its_end() {
    let dir = common::scratch("streamed-checks", "no-motion");
    let mut program = String::from("G21 G90\n");
    for _ in 0..1000 {
        program.push_str("G00 X0 Y0\n");
    }
    let s = common::file_scenario(&dir, &program);
    for command in ["analyze", "check"] {
        let out = common::mtsim_plain(&dir, &[command, &s]);
        let err = unwrapped(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{command}: {err}");
        assert!(
            err.contains("p.nc:1:1: the program has no motion"),
            "{command}: {err}"
        );
    }
    // `blocks` prints the interpreter's output as it is: 1000 rapids that stay put.
    let out = common::mtsim_plain(&dir, &["blocks", &s, "--csv"]);
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 1001);
}

/// The message on stderr as one line (the diagnostic wraps long lines in a frame).
fn unwrapped(stderr: &[u8]) -> String {
    String::from_utf8_lossy(stderr)
        .replace('│', " ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// Every file under `dir`.
fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files.extend(walk(&path));
        } else {
            files.push(path);
        }
    }
    files
}
