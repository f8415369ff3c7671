//! Tilted planes and tool-centre-point control on a fork head (C then A through (0, 0, 200),
//! t = Rz(C) Rx(A) z), checked with the spec's forward kinematics written out in
//! `chain_cone.rs` and against hand-computed axis values.
//!
//! Part 16 of the cross-dialect set (`tests/program/dialects/16-tilted-plane/`): the plane
//! tilted 30° about X (`G68.2 J30`, `PLANE SPATIAL SPA+30`, `CYCLE800(… 30 …)`), its normal
//! `t = Rx(30°) z = (0, −1/2, √3/2)`. The fork's two solutions are (A 30, C 0) and (A −30,
//! C 180); from A 0, C 0 the nearest is (30, 0). The tool tip holds (0, 0, 50) while the head
//! turns: the tip sits at `XYZ + (0,0,200) + Rx(30)(0,0,−200) = XYZ + (0, 100, 26.795)`, so
//! X 0, Y −100, Z 23.205. The square that follows lies in the tilted plane.

use crate::common;

use std::path::Path;

use common::{mtsim_plain, scratch};
use mtsim::{Axis, AxisVec};

use super::chain_cone::load;

const FORK: &str = "machines/fork-head-ca.toml";

/// `mtsim blocks --json` of `program` on the fork head, read in `dialect`, with tool 1 of
/// length 0.
fn blocks(dir: &Path, program: &Path, dialect: &str) -> Vec<serde_json::Value> {
    blocks_with_tool(dir, program, dialect, 0.0)
}

/// [`blocks`] with tool 1 `tool_length_mm` long.
fn blocks_with_tool(
    dir: &Path,
    program: &Path,
    dialect: &str,
    tool_length_mm: f64,
) -> Vec<serde_json::Value> {
    let m = Path::new(env!("CARGO_MANIFEST_DIR")).join(FORK);
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "machine = {:?}\n[program]\nfile = {:?}\n[reader]\ndialect = \"{dialect}\"\ntools = [{{ number = 1, length_mm = {tool_length_mm:?}, diameter_mm = 10.0 }}]\n[check]\ncollisions = false\n",
            m.display().to_string(),
            program.display().to_string()
        ),
    )
    .unwrap();
    let v = common::stdout_json(&mtsim_plain(dir, &["blocks", "s.toml", "--json"]));
    v.as_array().unwrap().clone()
}

fn axes(row: &serde_json::Value) -> AxisVec {
    let mut q = AxisVec::ZERO;
    for (axis, key) in [
        (Axis::X, "x"),
        (Axis::Y, "y"),
        (Axis::Z, "z"),
        (Axis::A, "a"),
        (Axis::C, "c"),
    ] {
        q[axis] = row[key].as_f64().unwrap();
    }
    q
}

#[test]
fn a_tilted_plane_on_a_fork_head_turns_it_by_the_nearest_solution_in_every_dialect() {
    let (s30, c30) = 30f64.to_radians().sin_cos();
    // Rx(30°) p: the feature frame's points in the workpiece frame.
    let rx = |p: [f64; 3]| [p[0], c30 * p[1] - s30 * p[2], s30 * p[1] + c30 * p[2]];
    let square = [
        [0.0, 0.0, 10.0],
        [0.0, 0.0, 0.0],
        [20.0, 0.0, 0.0],
        [20.0, 20.0, 0.0],
        [0.0, 20.0, 0.0],
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 10.0],
    ];
    let (_, spec) = load(FORK);
    let part = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/program/dialects/16-tilted-plane");
    for (file, dialect) in [
        ("fanuc.nc", "fanuc"),
        ("haas.nc", "haas"),
        ("heidenhain.h", "heidenhain"),
        ("siemens.mpf", "siemens"),
    ] {
        let dir = scratch("chain-plane", dialect);
        let rows = blocks(&dir, &part.join(file), dialect);
        let turn = rows
            .iter()
            .position(|r| (r["a"].as_f64().unwrap() - 30.0).abs() < 1e-9)
            .unwrap_or_else(|| panic!("{file}: no block turns A to 30: {rows:?}"));
        let q = axes(&rows[turn]);
        let expected = [0.0, -100.0, 50.0 - (200.0 - 200.0 * c30)];
        for (got, want) in [
            (q[Axis::X], expected[0]),
            (q[Axis::Y], expected[1]),
            (q[Axis::Z], expected[2]),
            (q[Axis::C], 0.0),
        ] {
            assert!((got - want).abs() < 1e-9, "{file}: turned to {q:?}");
        }
        for (k, p) in square.iter().enumerate() {
            let q = axes(&rows[turn + 1 + k]);
            let (tip, t) = spec.tool_in_workpiece(&q);
            let want = rx(*p);
            for i in 0..3 {
                assert!(
                    (tip[i] - want[i]).abs() < 1e-9,
                    "{file}: block {k}: tip {tip:?}, expected {want:?}"
                );
            }
            let normal = [0.0, -s30, c30];
            for i in 0..3 {
                assert!(
                    (t[i] - normal[i]).abs() < 1e-12,
                    "{file}: block {k}: tool {t:?}"
                );
            }
        }
    }
}

#[test]
fn g53_1_takes_the_solution_nearest_the_rotaries_where_they_stand() {
    // From C 170 the other solution, (A −30, C 180), moves the rotaries 40° against 200°.
    let dir = scratch("chain-plane", "nearest");
    let program = dir.join("p.nc");
    std::fs::write(
        &program,
        "G21 G90 G94 G17\nG00 X0 Y0 Z50. A0 C170.\nG68.2 X0 Y0 Z0 I0 J30. K0\nG53.1\nG69\nM30\n",
    )
    .unwrap();
    let rows = blocks(&dir, &program, "fanuc");
    let q = axes(&rows[1]);
    assert_eq!(rows[1]["line"], 4);
    let z = 50.0 - (200.0 - 200.0 * 30f64.to_radians().cos());
    for (got, want) in [
        (q[Axis::A], -30.0),
        (q[Axis::C], 180.0),
        (q[Axis::X], 0.0),
        (q[Axis::Y], -100.0),
        (q[Axis::Z], z),
    ] {
        assert!((got - want).abs() < 1e-9, "turned to {q:?}");
    }
}

#[test]
fn g43_4_on_a_fork_head_places_the_tip_of_a_50_mm_tool() {
    // The tip at the workpiece origin, A 30, C 0, tool 50 mm: the tip sits at
    // XYZ + (0,0,200) + Rx(30°)(0, 0, −250) = XYZ + (0, 125, 200 − 250 cos 30°).
    let dir = scratch("chain-plane", "tcp");
    let program = dir.join("p.nc");
    std::fs::write(
        &program,
        "G21 G90 G94 G17\nG43.4 H1\nG01 X0 Y0 Z0 A30. C0 F500\nG01 X10.\nM30\n",
    )
    .unwrap();
    let rows = blocks_with_tool(&dir, &program, "fanuc", 50.0);
    let c30 = 30f64.to_radians().cos();
    for (row, x) in [(&rows[0], 0.0), (&rows[1], 10.0)] {
        let q = axes(row);
        for (got, want) in [
            (q[Axis::X], x),
            (q[Axis::Y], -125.0),
            (q[Axis::Z], -(200.0 - 250.0 * c30)),
        ] {
            assert!((got - want).abs() < 1e-9, "line {}: {q:?}", row["line"]);
        }
    }
}
