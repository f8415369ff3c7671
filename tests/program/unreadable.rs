//! `check`, `simulate` and `analyze` on programs they cannot read: exit 2 with the reader's
//! message (file:line:column), and never a "clean" verdict about something not read
//! (issue 9, item 13; the example program was "clean" on a 400 mm axis).

use crate::common;

use std::path::PathBuf;
use std::process::Output;

use common::{machine, mtsim_plain, scratch, trt_ac};

/// Writes `p.ngc` and a scenario running it on `machine_path`; returns the scenario path.
fn setup(name: &str, machine_path: &str, program: &str) -> PathBuf {
    let dir = scratch("unreadable", name);
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    let path = dir.join("s.toml");
    std::fs::write(
        &path,
        format!("machine = {machine_path:?}\n[program]\nfile = \"p.ngc\"\n"),
    )
    .unwrap();
    path
}

fn run(args: &[&str], scenario: &std::path::Path) -> Output {
    let mut all = args.to_vec();
    all.insert(1, scenario.to_str().unwrap());
    mtsim_plain(scenario.parent().unwrap(), &all)
}

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Asserts exit 2, the reader's `p.ngc:line:col` on stderr, and no verdict on stdout.
fn assert_unreadable(out: &Output, at: &str) {
    let (stdout, stderr) = text(out);
    assert_eq!(
        out.status.code(),
        Some(2),
        "stdout: {stdout}\nstderr: {stderr}"
    );
    assert!(stderr.contains(at), "expected `{at}` in: {stderr}");
    assert!(
        !stdout.contains("clean"),
        "a verdict on unread input: {stdout}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// An unknown G code on line 1 (before any motion), then a move 100 mm past the X travel.
const UNKNOWN_CODE_FIRST: &str = "G21 G17.3 G90 G94\nG1 X500 F1000\nM2\n";

#[test]
fn check_exits_2_when_the_first_error_comes_before_the_first_motion() {
    let s = setup("first", &machine("vmc-3axis"), UNKNOWN_CODE_FIRST);
    assert_unreadable(&run(&["check"], &s), "p.ngc:1:5");
    assert_unreadable(&run(&["check", "--json"], &s), "p.ngc:1:5");
    assert_unreadable(&run(&["check", "--dynamics"], &s), "p.ngc:1:5");
}

#[test]
fn check_exits_2_on_an_error_in_the_middle_of_the_program() {
    let program = "G21 G90 G94\nG1 X10 F1000\nG1 X20\nG1 X1.2.3\nG1 X30\nM2\n";
    let s = setup("middle", &machine("vmc-3axis"), program);
    assert_unreadable(&run(&["check"], &s), "p.ngc:4:");
    assert_unreadable(&run(&["check", "--dynamics"], &s), "p.ngc:4:");
}

#[test]
fn a_word_for_an_axis_the_machine_lacks_is_an_error_not_dropped() {
    // B on an A/C machine: line 3, column 8 is the `B30` word.
    let program = "G21 G90 G94\nG1 X10 F1000\nG1 X20 B30\nM2\n";
    let s = setup("b-on-ac", &trt_ac(), program);
    for args in [&["check"][..], &["analyze"], &["simulate", "-o", "out"]] {
        assert_unreadable(&run(args, &s), "p.ngc:3:8");
    }
    // A on the B/C machine.
    let s = setup(
        "a-on-bc",
        &machine("trt-bc"),
        "G21 G90\nG0 A15\nG0 X1\nM2\n",
    );
    assert_unreadable(&run(&["check"], &s), "p.ngc:2:4");
}

#[test]
fn the_start_point_is_checked_even_when_it_is_the_only_move() {
    // The example without the code the reader refused: X500 on a ±400 mm axis.
    let s = setup(
        "only-move",
        &machine("vmc-3axis"),
        "G21 G90 G94\nG1 X500 F1000\nM2\n",
    );
    for args in [&["check", "--json"][..], &["check", "--json", "--dynamics"]] {
        let out = run(args, &s);
        assert_eq!(out.status.code(), Some(1), "{:?}", text(&out));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let travel: Vec<_> = v["violations"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|x| x["kind"] == "travel")
            .collect();
        assert_eq!(travel.len(), 1, "{v}");
        assert_eq!(travel[0]["axis"], "X");
        assert_eq!(travel[0]["worst"], 500.0);
        assert_eq!(travel[0]["limit"], 400.0);
        assert_eq!(travel[0]["line"], 2);
    }
}

#[test]
fn a_program_without_moves_is_not_called_clean() {
    let s = setup(
        "no-moves",
        &machine("vmc-3axis"),
        "G21 G90 G94\n(nothing here)\nM2\n",
    );
    let out = run(&["check"], &s);
    let (stdout, stderr) = text(&out);
    // A motion-free program is bad input (exit 2, docs/cli.md), never "clean".
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(!stdout.contains("clean"), "{stdout}");
    let message = stderr
        .replace('│', " ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    assert!(message.contains("the program has no motion"), "{stderr}");
}

#[test]
fn simulate_exits_2_with_the_readers_message_and_writes_no_summary() {
    let s = setup("simulate", &machine("vmc-3axis"), UNKNOWN_CODE_FIRST);
    let out = run(&["simulate", "-o", "out"], &s);
    assert_unreadable(&out, "p.ngc:1:5");
    assert!(!s.parent().unwrap().join("out/summary.json").exists());

    let program = "G21 G90 G94\nG1 X10 F1000\nG1 X20 Y5\nG1 X1.2.3\nM2\n";
    let s = setup("simulate-middle", &machine("vmc-3axis"), program);
    assert_unreadable(&run(&["simulate", "-o", "out"], &s), "p.ngc:4:");
    assert!(!s.parent().unwrap().join("out/summary.json").exists());
}
