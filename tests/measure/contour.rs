//! The contour error of a part program without a measured circle (`measure::contour`):
//! `simulate` writes a trace row per period and `contour.csv`, checked against the closed
//! form of a first-order position loop and against distances computed here, in plain Rust,
//! from the trace's actual positions and the program's own geometry.

use std::collections::BTreeMap;
use std::path::Path;

use mtsim::input::scenario::Scenario;
use mtsim::study::simulate::simulate;

use crate::common::{machine, scratch, write_scenario};

/// Loop gain of every axis, 1/s, and the feed, mm/min.
const KV: f64 = 30.0;
const FEED: f64 = 2000.0;
/// Corner radius and side of the rounded square, mm.
const R: f64 = 20.0;
const SIDE: f64 = 100.0;

/// A square of side 100 mm with corners rounded to R 20 mm, counter-clockwise from (20, 0):
/// straights on lines 3, 5, 7, 9 and arcs on lines 4, 6, 8, 10.
const SQUARE: &str = "G21 G90 G17 G94\n\
G0 X20 Y0 Z0\n\
G1 X80 F2000\n\
G3 X100 Y20 I0 J20\n\
G1 Y80\n\
G3 X80 Y100 I-20 J0\n\
G1 X20\n\
G3 X0 Y80 I0 J-20\n\
G1 Y20\n\
G3 X20 Y0 I20 J0\n\
M30\n";

/// The square's path piece by piece, as this test writes it down from the program: a
/// straight from a to b, or a quarter arc about a centre (counter-clockwise from angle a0).
enum Piece {
    Straight([f64; 2], [f64; 2]),
    Arc { centre: [f64; 2], a0_deg: f64 },
}

fn pieces() -> BTreeMap<usize, Piece> {
    use Piece::*;
    let (lo, hi) = (R, SIDE - R);
    BTreeMap::from([
        (3, Straight([lo, 0.0], [hi, 0.0])),
        (
            4,
            Arc {
                centre: [hi, lo],
                a0_deg: -90.0,
            },
        ),
        (5, Straight([SIDE, lo], [SIDE, hi])),
        (
            6,
            Arc {
                centre: [hi, hi],
                a0_deg: 0.0,
            },
        ),
        (7, Straight([hi, SIDE], [lo, SIDE])),
        (
            8,
            Arc {
                centre: [lo, hi],
                a0_deg: 90.0,
            },
        ),
        (9, Straight([0.0, hi], [0.0, lo])),
        (
            10,
            Arc {
                centre: [lo, lo],
                a0_deg: 180.0,
            },
        ),
    ])
}

/// Distance (mm) from p to a piece.
fn distance(piece: &Piece, p: [f64; 2]) -> f64 {
    match *piece {
        Piece::Straight(a, b) => {
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let t =
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            (a[0] + t * dx - p[0]).hypot(a[1] + t * dy - p[1])
        }
        Piece::Arc { centre, a0_deg } => {
            let (x, y) = (p[0] - centre[0], p[1] - centre[1]);
            let mut turned = y.atan2(x).to_degrees() - a0_deg;
            turned = turned.rem_euclid(360.0);
            if turned <= 90.0 {
                (x.hypot(y) - R).abs()
            } else {
                // Nearest end of the quarter.
                let end = |deg: f64| {
                    let a = (a0_deg + deg).to_radians();
                    (centre[0] + R * a.cos() - p[0]).hypot(centre[1] + R * a.sin() - p[1])
                };
                end(0.0).min(end(90.0))
            }
        }
    }
}

/// Reads a CSV file into its header and rows of numbers (the first column, text, left out).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|rec| {
            rec.unwrap()
                .iter()
                .skip(1)
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (header, rows)
}

fn run_square() -> (std::path::PathBuf, serde_json::Value) {
    run_square_with("square", "")
}

/// The square on the first-order machine with the extra TOML `extra` (more overrides).
fn run_square_with(name: &str, extra: &str) -> (std::path::PathBuf, serde_json::Value) {
    let dir = scratch("contour", name);
    std::fs::write(dir.join("p.nc"), SQUARE).unwrap();
    let mut body = String::from("[program]\nfile = \"p.nc\"\n");
    for a in ["X", "Y", "Z"] {
        body += &format!(
            "[machine_overrides.axes.{a}.servo]\nmodel = \"first-order\"\nkv_per_s = {KV}\n\
             [machine_overrides.axes.{a}.friction]\ncoulomb_n = 0.0\n"
        );
    }
    body += extra;
    let path = write_scenario(&dir, &machine("vmc-3axis"), &body);
    let scenario = Scenario::load(&path).unwrap();
    let out = dir.join("out");
    simulate(&scenario, &out, false, &|_| {}).unwrap();
    let summary =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    (out, summary)
}

/// The trace has a row per period; `contour.csv` a row per feed sample, each equal to the
/// distance computed here from the trace's actual X and Y; on the arcs' and straights'
/// middles, the closed form of a first-order loop: 0 on a straight, and on an arc of
/// radius R at speed v the steady circle of radius `R / sqrt(1 + (v / (R Kv))²)`.
#[test]
fn rounded_square_matches_a_first_order_loop() {
    let (out, summary) = run_square();
    let (trace_header, trace) = read_csv(&out.join("trace.csv"));
    let setpoints = summary["setpoints"].as_u64().unwrap() as usize;
    assert_eq!(trace.len(), setpoints, "one trace row per period");
    // Columns after `direction` (dropped by read_csv).
    let col = |name: &str| trace_header.iter().position(|c| c == name).unwrap() - 1;
    let (t, line, x, y) = (col("time_s"), col("line"), col("X_act_mm"), col("Y_act_mm"));
    let (_, contour) = read_csv(&out.join("contour.csv"));
    let pieces = pieces();
    let feed_rows = trace
        .iter()
        .filter(|r| pieces.contains_key(&(r[line] as usize)))
        .count();
    assert_eq!(contour.len(), feed_rows, "a contour row per feed sample");

    // Every row against the distance to the piece of its line and its neighbours.
    let by_time: BTreeMap<i64, &Vec<f64>> = trace
        .iter()
        .map(|r| ((r[t] * 1e4).round() as i64, r))
        .collect();
    let mut worst_gap_um: f64 = 0.0;
    for c in &contour {
        let row = by_time[&((c[0] * 1e4).round() as i64)];
        let l = c[1] as usize;
        assert_eq!(row[line] as usize, l);
        let p = [row[x], row[y]];
        let expected = [l - 1, l, l + 1]
            .iter()
            .filter_map(|k| pieces.get(k))
            .map(|piece| distance(piece, p))
            .fold(f64::INFINITY, f64::min);
        // contour.csv holds 4 decimals of µm.
        worst_gap_um = worst_gap_um.max((c[2] - expected * 1e3).abs());
    }
    assert!(
        worst_gap_um < 1e-3,
        "contour.csv against distances computed here: {worst_gap_um} µm"
    );

    // Closed forms at each piece's middle sample.
    let v = FEED / 60.0;
    let on_arc_um = R * (1.0 - 1.0 / (1.0 + (v / (R * KV)).powi(2)).sqrt()) * 1e3;
    assert!(on_arc_um > 20.0, "a figure worth testing: {on_arc_um} µm");
    for (&l, piece) in &pieces {
        let rows: Vec<&Vec<f64>> = contour.iter().filter(|c| c[1] as usize == l).collect();
        let middle = rows[rows.len() / 2][2];
        let expected = match piece {
            Piece::Straight(..) => 0.0,
            Piece::Arc { .. } => on_arc_um,
        };
        assert!(
            (middle - expected).abs() < 0.1,
            "line {l}: contour {middle} µm against the closed form {expected} µm"
        );
    }
    // The summary's figures and worst places.
    let c = &summary["measurements"]["contour"];
    let max = contour.iter().map(|r| r[2]).fold(0.0, f64::max);
    assert!((c["max_um"].as_f64().unwrap() - max).abs() < 1e-3);
    assert_eq!(c["samples"].as_u64().unwrap() as usize, contour.len());
    assert!(out.join("contour.svg").exists());
}

/// The budget's rows of a run's `summary.json`: (mechanism, axis or "", row).
fn budget_rows(summary: &serde_json::Value) -> Vec<(String, String, serde_json::Value)> {
    let budget = &summary["measurements"]["contour"]["budget"];
    budget["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let axis = r["axis"].as_str().unwrap_or("").to_string();
            (
                r["mechanism"].as_str().unwrap().to_string(),
                axis,
                r.clone(),
            )
        })
        .collect()
}

/// The contour error's budget by counterfactual runs: on a machine whose axes are identical
/// first-order loops, the servos' common lag is the whole error (share 1) and no row names
/// backlash or friction; with 10 µm of backlash on X alone, an X backlash row appears (and
/// no Y one) whose largest part is b/2 = 5 µm, the closed form of a table held half the
/// backlash behind its motor, normal to the square's Y straights, where the full run reads
/// 5 µm too.
#[test]
fn the_budget_names_only_the_mechanisms_the_machine_has() {
    let (_, clean) = run_square_with("budget-clean", "");
    let rows = budget_rows(&clean);
    assert!(
        rows.iter().all(|(m, _, _)| m == "program" || m == "servo"),
        "{rows:?}"
    );
    let common = rows
        .iter()
        .find(|(m, a, _)| m == "servo" && a.is_empty())
        .unwrap();
    assert!((common.2["share"].as_f64().unwrap() - 1.0).abs() < 1e-6);

    let b_um = 10.0;
    let extra = format!(
        "[machine_overrides.axes.X.drive]\nbacklash_mm = {}\n",
        b_um / 1e3
    );
    let (out, with_backlash) = run_square_with("budget-backlash", &extra);
    let rows = budget_rows(&with_backlash);
    let backlash: Vec<_> = rows.iter().filter(|(m, _, _)| m == "backlash").collect();
    assert_eq!(backlash.len(), 1, "{rows:?}");
    assert_eq!(backlash[0].1, "X");
    assert!(rows.iter().all(|(m, _, _)| m != "friction"));
    let max = backlash[0].2["max_um"].as_f64().unwrap();
    assert!((max - b_um / 2.0).abs() < 0.01, "X backlash row: {max} µm");
    // The shares and the interplay add to 1.
    let budget = &with_backlash["measurements"]["contour"]["budget"];
    let shares: f64 = rows
        .iter()
        .map(|(_, _, r)| r["share"].as_f64().unwrap())
        .sum();
    let total = shares + budget["interaction_share"].as_f64().unwrap();
    assert!((total - 1.0).abs() < 1e-9);
    // The full run on the middle of the Y straights (lines 5 and 9).
    let (_, contour) = read_csv(&out.join("contour.csv"));
    for l in [5, 9] {
        let rows: Vec<&Vec<f64>> = contour.iter().filter(|c| c[1] as usize == l).collect();
        let middle = rows[rows.len() / 2][2];
        assert!((middle - b_um / 2.0).abs() < 0.1, "line {l}: {middle} µm");
    }
}

/// A part program's `trace.parquet` (no ball bar: nothing held for a centring, each block
/// written as it fills, its centred column NaN) reads back with one row per period and the
/// same actual positions as its `trace.csv`.
#[test]
fn a_part_programs_parquet_trace_holds_the_csv_traces_rows() {
    use mtsim::report::trace::read_trace;
    let (csv_out, summary) = run_square_with("parquet-csv", "");
    let (pq_out, _) = run_square_with("parquet-pq", "[simulate]\ntrace_format = \"parquet\"\n");
    assert!(pq_out.join("trace.parquet").exists() && !pq_out.join("trace.csv").exists());
    let (csv, pq) = (
        read_trace(&csv_out).unwrap().unwrap(),
        read_trace(&pq_out).unwrap().unwrap(),
    );
    let setpoints = summary["setpoints"].as_u64().unwrap() as usize;
    assert_eq!(pq.runs.len(), 1);
    assert_eq!(pq.runs[0].time_s.len(), setpoints);
    assert!(pq.runs[0].deviation_centred_um.iter().all(|v| v.is_nan()));
    for (k, axis) in csv.axes.iter().enumerate() {
        let (a, b) = (&csv.runs[0].actual[k], &pq.runs[0].actual[k]);
        let worst = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        // The CSV holds 6 decimals, the Parquet file the f64 itself.
        assert!(worst <= 5e-7, "{axis}: {worst}");
    }
    assert!(pq_out.join("contour.csv").exists());
}
