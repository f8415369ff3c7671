//! Haas mill bolt-hole patterns G70 and G71: the active canned cycle at each hole, the holes
//! placed by hand here, `c + I (cos a_k, sin a_k)` with `a_k = J + k·360/L` (G70) or
//! `J + k·K` (G71); and the lathe meanings of the same codes refused.

use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, Error, Motion, Options};

fn haas() -> Options {
    Options {
        dialect: Dialect::Haas,
        ..Options::default()
    }
}

fn moves(text: &str) -> Vec<ngc::Move> {
    read_str_with(Path::new("t.nc"), text, &haas())
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"))
}

fn error(text: &str) -> (usize, String) {
    match read_str_with(Path::new("t.nc"), text, &haas()).find_map(|m| m.err()) {
        Some(Error::Syntax(s)) => (s.line, s.message),
        Some(other) => panic!("expected a syntax error, got {other:?}"),
        None => panic!("expected an error in {text:?}"),
    }
}

/// `v` to 1e-9 mm, without a negative zero.
fn r(v: f64) -> f64 {
    (v * 1e9).round() / 1e9 + 0.0
}

/// The hole bottoms (X Y of every feed move that ends at Z = `bottom`), to 1e-9 mm.
fn bottoms(m: &[ngc::Move], bottom: f64) -> Vec<[f64; 2]> {
    m.iter()
        .filter(|m| m.motion == Motion::Linear && (m.end[Axis::Z] - bottom).abs() < 1e-9)
        .map(|m| [r(m.end[Axis::X]), r(m.end[Axis::Y])])
        .collect()
}

/// Holes about `c` at radius `i` and the angles `deg`, to 1e-9 mm.
fn holes(c: [f64; 2], i: f64, deg: &[f64]) -> Vec<[f64; 2]> {
    deg.iter()
        .map(|a| {
            let a = a.to_radians();
            [r(c[0] + i * a.cos()), r(c[1] + i * a.sin())]
        })
        .collect()
}

#[test]
fn g70_drills_l_holes_evenly_round_a_circle_with_the_active_cycle() {
    // L0 on the cycle block: no hole at the centre. Four holes from 0°, 90° apart.
    let m = moves("G21 G90 G17 G54\nG0 X0 Y0 Z50\nG81 G98 Z-5 R2 F100 L0\nG70 I10 J0 L4\nG80\n");
    assert_eq!(
        bottoms(&m, -5.0),
        holes([0.0, 0.0], 10.0, &[0.0, 90.0, 180.0, 270.0])
    );
    // Each hole as G81 drills it: over it at the G98 level, down to R, feed, back up.
    let after: Vec<[f64; 3]> = m
        .iter()
        .skip(1)
        .take(4)
        .map(|m| [m.end[Axis::X], m.end[Axis::Y], m.end[Axis::Z]])
        .collect();
    assert_eq!(
        after,
        [
            [10.0, 0.0, 50.0],
            [10.0, 0.0, 2.0],
            [10.0, 0.0, -5.0],
            [10.0, 0.0, 50.0]
        ]
    );
}

#[test]
fn g71_drills_an_arc_of_holes_k_degrees_apart_about_the_block_s_centre() {
    // Centre X30 Y-20 given in the G71 block, J45 K-30: 45°, 15°, −15° (K negative turns
    // clockwise).
    let m = moves(
        "G21 G90 G17\nG0 X0 Y0 Z50\nG83 G99 Z-8 R1 Q3 F100 L0\nG71 X30 Y-20 I20 J45 K-30 L3\n",
    );
    // G83 pecks: the bottom is reached once per hole.
    assert_eq!(
        bottoms(&m, -8.0),
        holes([30.0, -20.0], 20.0, &[45.0, 15.0, -15.0])
    );
}

#[test]
fn a_pattern_in_g91_places_its_holes_about_the_current_position() {
    // G91: R is 48 below the initial level 50 (R = 2), Z 7 below R (−5); the centre is
    // where the tool is, (5, 5).
    let m = moves("G21 G90 G17\nG0 X5 Y5 Z50\nG91 G81 G98 Z-7 R-48 F100 L0\nG70 I10 J30 L3\n");
    assert_eq!(
        bottoms(&m, -5.0),
        holes([5.0, 5.0], 10.0, &[30.0, 150.0, 270.0])
    );
}

#[test]
fn what_a_pattern_cannot_mean_here_is_refused_with_its_reason() {
    for (text, line, says) in [
        ("G0 X0 Y0 Z50\nG70 I10 L4\n", 2, "no canned cycle active"),
        (
            "G0 X0 Y0 Z50\nG81 Z-5 R2 F100 L0\nG70 I10\n",
            3,
            "without L",
        ),
        (
            "G0 X0 Y0 Z50\nG81 Z-5 R2 F100 L0\nG71 I10 J0 L3\n",
            3,
            "without K",
        ),
        (
            "G0 X0 Y0 Z50\nG81 Z-5 R2 F100 L0\nG70 I10 L0\n",
            3,
            "whole number of holes",
        ),
        // With P and Q they are the lathe's cycles, run about the shape N10-N20.
        ("G71 P10 Q20 D1\n", 1, "no block N10 for P10"),
        ("G70 P10 Q20\n", 1, "no block N10 for P10"),
        (
            "G0 X0 Y0 Z50\nG81 Z-5 R2 F100 L0\nG72 I10 J30 L3\n",
            3,
            "bolt holes along an angle",
        ),
    ] {
        let (l, message) = error(text);
        assert_eq!(l, line, "{text:?}: {message}");
        assert!(message.contains(says), "{text:?}: {message}");
    }
}
