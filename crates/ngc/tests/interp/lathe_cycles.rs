//! The Fanuc family's lathe stock-removal cycles G71/G72 (type I) and the finishing cycle
//! G70: every move of a small part written out by hand from the cycle's definition
//! (`crates/ngc/src/interp/stock_removal.rs`): layers Δd apart from the start point toward
//! the shape, each cut to where its level meets the shape (shifted by the allowances), a
//! 45° retract by e, back along the cut; then the shape itself and back to the start.

use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, Motion, Options};

fn options(dialect: Dialect) -> Options {
    Options {
        dialect,
        ..Options::default()
    }
}

/// (rapid?, Z, X) of each move after the first, to 1e-9 mm.
fn zx(text: &str, dialect: Dialect) -> Vec<(bool, f64, f64)> {
    let r = |v: f64| (v * 1e9).round() / 1e9 + 0.0;
    read_str_with(Path::new("t.nc"), text, &options(dialect))
        .map(|m| m.unwrap_or_else(|e| panic!("expected the program to read, got: {e}")))
        .skip(1)
        .map(|m| {
            (
                m.motion == Motion::Rapid,
                r(m.end[Axis::Z]),
                r(m.end[Axis::X]),
            )
        })
        .collect()
}

fn error(text: &str) -> String {
    match read_str_with(Path::new("t.nc"), text, &options(Dialect::Fanuc)).find_map(Result::err) {
        Some(e) => e.to_string(),
        None => panic!("expected an error"),
    }
}

/// The shape: from A = (Z2, X50) down to X20, along Z to -10, a taper to (Z-20, X40), and
/// along Z to -30.
const SHAPE: &str = "N10 G0 X20\nG1 Z-10\nX40 Z-20\nN20 Z-30\n";

const R: bool = true;
const F: bool = false;

#[test]
fn g71_roughs_in_layers_then_follows_the_shape_and_g70_finishes() {
    let program = format!(
        "G21 G18 G90\nG0 X50 Z2\nG71 U5 R1\nG71 P10 Q20 U0 W0 F100\n{SHAPE}G70 P10 Q20\nM30\n"
    );
    // X is a diameter: the radial depth U5 steps 10 in X, the retract R1 is 2 in X and 1
    // in Z. Levels X40 (meets the taper's top corner, Z-20) and X30 (on the taper:
    // Z = -10 - 10·(X - 20)/20 = -15); X20 is the shape's start, left to the shape pass.
    let mut expected = Vec::new();
    for (x, z) in [(40.0, -20.0), (30.0, -15.0)] {
        expected.extend([
            (R, 2.0, x),
            (F, z, x),
            (R, z + 1.0, x + 2.0),
            (R, 2.0, x + 2.0),
        ]);
    }
    // The shape, then back across to X50 and along to Z2; then G70 runs the shape's blocks
    // as written, the same moves, and comes back the same way.
    let shape_and_back = [
        (R, 2.0, 20.0),
        (F, -10.0, 20.0),
        (F, -20.0, 40.0),
        (F, -30.0, 40.0),
        (R, -30.0, 50.0),
        (R, 2.0, 50.0),
    ];
    expected.extend(shape_and_back);
    expected.extend(shape_and_back);
    assert_eq!(zx(&program, Dialect::Fanuc), expected);
}

#[test]
fn the_allowances_shift_the_shape_and_d_gives_the_depth_on_one_block() {
    // Haas's one-block form: D the depth; U0.5 W0.2 leave stock on X and Z.
    let program = format!("G21 G18 G90\nG0 X50 Z2\nG71 P10 Q20 D10 U0.5 W0.2 F100\n{SHAPE}M30\n");
    let m = zx(&program, Dialect::Haas);
    // D10 steps 20 in X: one level, X30 (X20.5, the shifted start, ends them), which meets
    // the shifted taper (Z-9.8 … -19.8 from X20.5 to X40.5) at Z = -9.8 - 10·9.5/20.
    assert_eq!(m[1], (F, -14.55, 30.0));
    // The retract without a first block: 0.254 mm, 0.508 in X.
    assert_eq!(m[2], (R, -14.296, 30.508));
    // The shape pass, shifted.
    assert_eq!(
        m[4..8],
        [
            (R, 2.2, 20.5),
            (F, -9.8, 20.5),
            (F, -19.8, 40.5),
            (F, -29.8, 40.5)
        ]
    );
}

#[test]
fn g72_faces_in_layers_along_x() {
    // Facing: A = (Z2, X50); the shape from Z-6 at X50 in to X30, then a taper out to
    // (Z0, X10): monotone in both, Z rising and X falling.
    let program = "G21 G18 G90\nG0 X50 Z2\nG72 W2 R0.5\nG72 P10 Q20 F100\nN10 G0 Z-6\nG1 X30\nN20 X10 Z0\nM30\n";
    let m = zx(program, Dialect::Fanuc);
    // Layers at Z0, Z-2, Z-4 (Z-6 is the shape's start). Z0 meets the taper's end
    // (X10), Z-2 at X = 30 - 20·(4/6), Z-4 at X = 30 - 20·(2/6).
    let hits: Vec<(f64, f64)> = m
        .iter()
        .filter(|s| !s.0)
        .take(3)
        .map(|s| (s.1, s.2))
        .collect();
    let x = |v: f64| (v * 1e9).round() / 1e9;
    assert_eq!(
        hits,
        [
            (0.0, 10.0),
            (-2.0, x(30.0 - 20.0 * 4.0 / 6.0)),
            (-4.0, x(30.0 - 20.0 * 2.0 / 6.0))
        ]
    );
}

#[test]
fn a_pocket_is_roughed_from_above_without_crossing_the_shoulder() {
    // Type II: a shoulder at X40 from Z2 to Z0, a groove at X30 to Z-20, out to X40.
    // D2 steps 4 in X; the retract is 0.254 mm (0.508 in X).
    let program =
        "G21 G18 G90\nG0 X50 Z2\nG71 P10 Q20 D2 F100\nN10 G0 X40\nG1 Z0\nX30\nZ-20\nN20 X40\nM30\n";
    let m = zx(program, Dialect::Haas);
    let (e, ex) = (0.254, 0.508);
    let mut expected = Vec::new();
    // X46, X42: above the whole shape, cut from the start side to its end, Z-20.
    for x in [46.0, 42.0] {
        expected.extend([
            (R, 2.0, x),
            (F, -20.0, x),
            (R, -20.0 + e, x + ex),
            (R, 2.0, x + ex),
        ]);
    }
    // X38, X34: in the groove only, Z0 to Z-20: out to X50, over to Z0, down, across, off,
    // out and back.
    for x in [38.0, 34.0] {
        let here = *expected.last().map(|s: &(bool, f64, f64)| &s.1).unwrap();
        if here != 2.0 || expected.last().unwrap().2 != 50.0 {
            expected.push((R, here, 50.0));
        }
        expected.extend([(R, 0.0, 50.0), (R, 0.0, x + ex), (F, 0.0, x), (F, -20.0, x)]);
        expected.extend([(R, -20.0 + e, x + ex), (R, -20.0 + e, 50.0), (R, 2.0, 50.0)]);
    }
    assert_eq!(m[..expected.len()], expected);
    // Never inside the shoulder (Z in (0, 2], X below 40) on the way.
    assert!(
        m.iter().all(|s| !(s.1 > 1e-9 && s.2 < 40.0 - 1e-9)),
        "{m:?}"
    );
}

#[test]
fn a_shape_that_turns_back_or_a_missing_block_is_refused_by_name() {
    let back =
        "G21 G18\nG0 X50 Z2\nG71 P10 Q20 D2 F100\nN10 G0 X20\nG1 Z-10\nX30 Z-5\nN20 Z-20\nM30\n";
    let e = error(back);
    assert!(e.contains("turns back along Z"), "{e}");
    let e = error("G21 G18\nG0 X50 Z2\nG71 P10 Q30 D2 F100\nN10 G0 X20\nN20 Z-20\nM30\n");
    assert!(e.contains("N30") && e.contains("Q30"), "{e}");
    let e = error("G21 G18\nG0 X50 Z2\nG71 P10 Q20 F100\nN10 G0 X20\nN20 Z-20\nM30\n");
    assert!(e.contains("depth of cut"), "{e}");
}

#[test]
fn u_and_w_are_increments_of_x_and_z_on_a_machine_without_those_axes() {
    // G-code system A: W-12 from Z2 is Z-10, U6 from X20 is X26, also under G90; beside X
    // it is an error; G28 U0 W0 returns X and Z through the current point.
    let mut o = options(Dialect::Fanuc);
    o.axes = vec![Axis::X, Axis::Z];
    o.set_reference(
        false,
        ngc::AxisVec::xyzabc([100.0, 0.0, 300.0, 0.0, 0.0, 0.0]),
    );
    let ends: Vec<(f64, f64)> = read_str_with(
        Path::new("t.nc"),
        "G21 G18 G90\nG0 X20 Z2\nG1 W-12 F100\nU6\nG28 U0 W0\nM30\n",
        &o,
    )
    .map(|m| m.unwrap())
    .map(|m| (m.end[Axis::Z], m.end[Axis::X]))
    .collect();
    assert_eq!(
        ends,
        [
            (2.0, 20.0),
            (-10.0, 20.0),
            (-10.0, 26.0),
            (-10.0, 26.0),
            (300.0, 100.0)
        ]
    );
    let e = read_str_with(Path::new("t.nc"), "G21\nG0 X20 U5\n", &o)
        .find_map(Result::err)
        .unwrap()
        .to_string();
    assert!(e.contains("beside `U5`"), "{e}");
}
