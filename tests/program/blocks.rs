//! `mtsim blocks`: the interpreter's canonical moves, checked against values worked out by
//! hand from the program's words (issue 9, item 14).

use crate::common;

use std::path::PathBuf;
use std::process::Output;

use common::{mtsim_plain, scratch, trt_ac};

fn setup(name: &str, program: &str) -> PathBuf {
    let dir = scratch("blocks", name);
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    let path = dir.join("s.toml");
    std::fs::write(
        &path,
        format!("machine = {:?}\n[program]\nfile = \"p.ngc\"\n", trt_ac()),
    )
    .unwrap();
    path
}

fn blocks(scenario: &std::path::Path, flag: &[&str]) -> Output {
    let mut args = vec!["blocks", scenario.to_str().unwrap()];
    args.extend_from_slice(flag);
    mtsim_plain(scenario.parent().unwrap(), &args)
}

/// Lengths: (0,0)→(10,10) is √200 mm; (10,10)→(20,10) is 10 mm; the clockwise R10 arc
/// (20,10)→(30,0) about (20,0) is a quarter circle, 5π mm.
const PROGRAM: &str = "\
G21 G90 G17 G94
G0 X0 Y0 Z0
G93
G1 X10 Y10 F2
G1 X20 F0.5
G2 X30 Y0 R10 F3
G1 A30 F2
G94 G1 X0 F100
G20 G1 X1 Z-0.5 F10
G0 C90
M2
";

#[test]
fn csv_rows_give_line_kind_end_point_and_feed_in_mm_per_min() {
    let out = blocks(&setup("csv", PROGRAM), &["--csv"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(
        rows[0].join(","),
        "line,kind,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg,feed_mm_min,dwell_s,tool"
    );
    let expect: [(usize, &str, [f64; 6], Option<f64>); 8] = [
        (2, "rapid", [0.0, 0.0, 0.0, 0.0, 0.0, 0.0], None),
        // G93: F (1/min) times the block length.
        (
            4,
            "feed",
            [10.0, 10.0, 0.0, 0.0, 0.0, 0.0],
            Some(2.0 * 200f64.sqrt()),
        ),
        (
            5,
            "feed",
            [20.0, 10.0, 0.0, 0.0, 0.0, 0.0],
            Some(0.5 * 10.0),
        ),
        (
            6,
            "arc",
            [30.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            Some(3.0 * 5.0 * std::f64::consts::PI),
        ),
        // Only A moves: the length is 30 deg.
        (7, "feed", [30.0, 0.0, 0.0, 30.0, 0.0, 0.0], Some(60.0)),
        (8, "feed", [0.0, 0.0, 0.0, 30.0, 0.0, 0.0], Some(100.0)),
        // Inches: 1 in = 25.4 mm, 10 in/min = 254 mm/min.
        (9, "feed", [25.4, 0.0, -12.7, 30.0, 0.0, 0.0], Some(254.0)),
        (10, "rapid", [25.4, 0.0, -12.7, 30.0, 0.0, 90.0], None),
    ];
    assert_eq!(rows.len(), 1 + expect.len(), "{text}");
    for (row, (line, kind, end, feed)) in rows[1..].iter().zip(expect) {
        assert_eq!(row[0].parse::<usize>().unwrap(), line, "{row:?}");
        assert_eq!(row[1], kind, "{row:?}");
        for (k, want) in end.iter().enumerate() {
            let got: f64 = row[2 + k].parse().unwrap();
            assert!((got - want).abs() < 1e-12, "{row:?}: column {k}");
        }
        match feed {
            None => assert_eq!(row[8], "", "{row:?}"),
            Some(f) => assert!((row[8].parse::<f64>().unwrap() - f).abs() < 1e-9, "{row:?}"),
        }
    }
}

#[test]
fn json_and_table_hold_the_same_rows() {
    let s = setup("json", PROGRAM);
    let out = blocks(&s, &["--json"]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = v.as_array().unwrap();
    assert_eq!(rows.len(), 8);
    assert_eq!(rows[3]["kind"], "arc");
    assert_eq!(rows[3]["line"], 6);
    assert_eq!(rows[7]["c"], 90.0);
    assert!(rows[0]["feed_mm_min"].is_null());
    assert_eq!(rows[0]["tool"], 0);

    let table = String::from_utf8(blocks(&s, &[]).stdout).unwrap();
    assert_eq!(table.lines().count(), 9, "{table}");
    let arc = table.lines().nth(4).unwrap();
    assert!(arc.contains("arc") && arc.contains("47.1239"), "{arc}");
    // Same inputs, same bytes.
    assert_eq!(blocks(&s, &["--csv"]).stdout, blocks(&s, &["--csv"]).stdout);
}

#[test]
fn an_unreadable_program_exits_2_with_file_line_and_column() {
    let s = setup("bad", "G21 G90\nG1 X1 F100\nG1 X1.2.3\nM2\n");
    let out = blocks(&s, &["--csv"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("p.ngc:3:"), "{stderr}");
    // The rows before the error are printed; the bad one is not.
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(stdout.lines().count(), 2, "{stdout}");

    let s = setup("bad-json", "G21 G17.3\nG1 X1 F100\nM2\n");
    let out = blocks(&s, &["--json"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("p.ngc:1:5"));
    assert!(out.stdout.is_empty());
}

#[test]
fn a_tool_centre_point_program_is_printed_in_machine_axes() {
    // The same cone written plainly (machine axes) and as a G43.4 program (the tool tip in
    // the table frame): `blocks` must give the same machine axes for both.
    let rows = |tcp: bool| -> Vec<Vec<f64>> {
        let dir = scratch("blocks", &format!("cone-tcp-{tcp}"));
        let path = dir.join("s.toml");
        std::fs::write(
            &path,
            format!(
                "machine = {:?}\n{}segments = 36\ntcp = {tcp}\n",
                trt_ac(),
                common::CONE_15_10
            ),
        )
        .unwrap();
        let out = blocks(&path, &["--csv"]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout)
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| {
                l.split(',')
                    .skip(2)
                    .take(6)
                    .map(|v| v.parse().unwrap())
                    .collect()
            })
            .collect()
    };
    let (plain, tcp) = (rows(false), rows(true));
    assert_eq!(plain.len(), tcp.len());
    assert!(plain.len() >= 36);
    for (p, t) in plain.iter().zip(&tcp) {
        for (a, b) in p.iter().zip(t) {
            assert!((a - b).abs() < 1e-3, "{p:?} vs {t:?}");
        }
    }
}
