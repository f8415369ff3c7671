//! Fanuc and Haas `,R` / `,C` between two G01 lines (next to arcs: corner_arcs.rs), and G16 / G15 polar coordinates. The
//! expected points are worked by hand: a corner of turn θ rounded with r touches each
//! line r·tan(θ/2) from the corner, the arc's centre r off the first line on the inside;
//! a chamfer's ends are c from the corner along each line; a polar point is
//! (r cos a, r sin a) about the work (local) origin.

use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, Motion, Move, Options};

pub(super) fn read(dialect: Dialect, text: &str) -> Result<Vec<Move>, String> {
    let options = Options {
        dialect,
        ..Options::default()
    };
    read_str_with(Path::new("t.nc"), text, &options)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| e.to_string())
}

pub(super) fn xy(p: ngc::AxisVec) -> [f64; 2] {
    [p[Axis::X], p[Axis::Y]]
}

pub(super) fn close(a: [f64; 2], b: [f64; 2]) {
    assert!(
        (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9,
        "{a:?} != {b:?}"
    );
}

pub(super) fn centre(m: &Move) -> ([f64; 2], bool) {
    match m.motion {
        Motion::Arc {
            clockwise,
            center_mm,
            ..
        } => ([center_mm[0], center_mm[1]], clockwise),
        ref other => panic!("expected an arc, got {other:?}"),
    }
}

#[test]
fn a_right_angle_rounded_with_r2_is_cut_2_mm_back_on_each_line() {
    // (0,0) → (10,0) → (10,10): tangent points (8,0) and (10,2), centre (8,2), G03.
    let text = "G21 G90 G17 G54\nG0 X0. Y0. Z1.\nG1 Z-1. F300\nG1 X10. ,R2. F500\nY10.\nM30\n";
    for dialect in [Dialect::Fanuc, Dialect::Haas] {
        let m = read(dialect, text).unwrap();
        assert_eq!(m.len(), 5, "{m:?}");
        close(xy(m[2].start), [0.0, 0.0]);
        close(xy(m[2].end), [8.0, 0.0]);
        assert_eq!(m[3].line, 4);
        close(xy(m[3].start), [8.0, 0.0]);
        close(xy(m[3].end), [10.0, 2.0]);
        assert_eq!(centre(&m[3]), ([8.0, 2.0], false));
        assert_eq!(m[3].end[Axis::Z], -1.0);
        assert_eq!(m[3].feed, ngc::Feed::PerMinute(500.0));
        close(xy(m[4].start), [10.0, 2.0]);
        close(xy(m[4].end), [10.0, 10.0]);
    }
}

#[test]
fn rounding_and_chamfer_follow_offsets_inches_and_chained_corners() {
    // G52 X100. Y50.; inches: (0,0) → (1,0) ,R0.1 → (1,-1) ,C0.2 → (0,-1). A right turn
    // at (1,0): tangent points 0.1 in back, centre (0.9,-0.1) in, clockwise; the chamfer
    // at (1,-1) from (1,-0.8) to (0.8,-1) in. Machine mm: + (100, 50) · 25.4.
    let text = "G20 G90 G17 G54\nG52 X100. Y50.\nG0 X0. Y0. Z0.\n\
                G1 X1. ,R0.1 F20.\nY-1. ,C0.2\nX0.\nM30\n";
    let m = read(Dialect::Fanuc, text).unwrap();
    let mm = |x: f64, y: f64| [(100.0 + x) * 25.4, (50.0 + y) * 25.4];
    assert_eq!(m.len(), 6, "{m:?}");
    close(xy(m[1].end), mm(0.9, 0.0));
    close(xy(m[2].end), mm(1.0, -0.1));
    let (c, clockwise) = centre(&m[2]);
    close(c, mm(0.9, -0.1));
    assert!(clockwise);
    close(xy(m[3].start), mm(1.0, -0.1));
    close(xy(m[3].end), mm(1.0, -0.8));
    assert_eq!(m[4].motion, Motion::Linear);
    close(xy(m[4].end), mm(0.8, -1.0));
    close(xy(m[5].start), mm(0.8, -1.0));
    close(xy(m[5].end), mm(0.0, -1.0));
}

#[test]
fn a_60_degree_corner_rounded_with_r3_touches_r_tan_30_from_it() {
    // (0,0) → (10,0) → (15, 5√3): t = 3 tan 30° = √3; centre (10 − √3, 3).
    let s3 = 3f64.sqrt();
    let text = format!(
        "G21 G90 G17\nG0 X0. Y0. Z0.\nG1 X10. ,R3. F500\nX15. Y{:.15}\nM30\n",
        5.0 * s3
    );
    let m = read(Dialect::Fanuc, &text).unwrap();
    close(xy(m[1].end), [10.0 - s3, 0.0]);
    close(centre(&m[2]).0, [10.0 - s3, 3.0]);
    close(xy(m[3].start), [10.0 + s3 / 2.0, 1.5]);
}

#[test]
fn corner_words_are_refused_where_the_rule_does_not_hold() {
    let head = "G21 G90 G17\nG0 X0. Y0. Z0.\n";
    for (tail, line, says) in [
        ("G1 X10. ,R2. F500\nG0 Y10.\nM30\n", 4, "rapid"),
        (
            "G1 X10. ,C2. F500\nG3 X0. Y10. R10.\nM30\n",
            4,
            "next to an arc",
        ),
        ("G1 X10. ,R2. F500\nM8\nY10.\nM30\n", 4, "does not move"),
        ("G1 X3. ,R5. F500\nY10.\nM30\n", 4, "does not fit"),
        ("G1 X10. ,C11. F500\nY10.\nM30\n", 4, "does not fit"),
        ("G1 X10. ,R2. F500\nZ-5.\nM30\n", 4, "off the"),
        ("G1 X10. ,R2. F500\nX20. Z-5.\nM30\n", 4, "off the"),
        ("G1 X10. ,R2. ,C1. F500\nY10.\nM30\n", 3, "in one block"),
        (
            "G0 X10. ,R2.\nG1 Y10. F500\nM30\n",
            3,
            "without a G01 or G02/G03 move",
        ),
        (
            "G41 D1 G1 X10. ,R2. F500\nY10.\nM30\n",
            3,
            "cutter compensation",
        ),
    ] {
        let text = format!("{head}{tail}");
        let e = read(Dialect::Fanuc, &text).unwrap_err();
        assert!(e.contains(says), "{tail:?}: {e}");
        assert!(e.contains(&format!("t.nc:{line}:")), "{tail:?}: {e}");
    }
    let e = read(Dialect::Linuxcnc, "G0 X0 Y0\nG1 X10 ,R2 F500\nY10\nM2\n").unwrap_err();
    assert!(e.contains("in a linuxcnc program"), "{e}");
}

#[test]
fn g16_bolt_holes_are_r_cos_a_r_sin_a_about_the_origin() {
    // Radius 50 at 0°, 60°, 120° (the radius kept from the current point), then 240° by
    // G91 Y120. on a G01 move.
    let text = "G21 G90 G17 G54\nG0 X0. Y0. Z10.\nG16\nG99 G81 X50. Y0. Z-5. R2. F100\n\
                Y60.\nY120.\nG80\nG91 G1 Y120. F500\nG90 G15\nG0 X5. Y5.\nM30\n";
    let m = read(Dialect::Fanuc, text).unwrap();
    let h = 50.0 * 3f64.sqrt() / 2.0;
    let feeds: Vec<[f64; 2]> = m
        .iter()
        .filter(|m| m.motion == Motion::Linear && m.line < 8)
        .map(|m| xy(m.end))
        .collect();
    assert_eq!(feeds.len(), 3, "{m:?}");
    close(feeds[0], [50.0, 0.0]);
    close(feeds[1], [25.0, h]);
    close(feeds[2], [-25.0, h]);
    close(xy(m.iter().find(|m| m.line == 8).unwrap().end), [-25.0, -h]);
    close(xy(m.last().unwrap().end), [5.0, 5.0]);
}

#[test]
fn g16_measures_from_the_g52_origin_and_in_the_g18_plane() {
    // Local origin (10,10): radius 10 at 90° → (10, 20); radius only (angle kept, 90°):
    // radius 4 → (10, 14).
    let text = "G21 G90 G17\nG52 X10. Y10.\nG0 X0. Y0. Z0.\nG16\nG1 X10. Y90. F500\nX4.\n\
                G15\nG52 X0 Y0\nG18 G16\nG1 Z10. X30.\nM30\n";
    let m = read(Dialect::Fanuc, text).unwrap();
    let at = |line: usize| m.iter().find(|m| m.line == line).unwrap();
    close(xy(at(5).end), [10.0, 20.0]);
    close(xy(at(6).end), [10.0, 14.0]);
    // G18: Z is the radius, X the angle from +Z towards +X: (Z, X) = 10 (cos 30°, sin 30°).
    let e = at(10).end;
    assert!(
        (e[Axis::Z] - 10.0 * 3f64.sqrt() / 2.0).abs() < 1e-9,
        "{e:?}"
    );
    assert!((e[Axis::X] - 5.0).abs() < 1e-9, "{e:?}");
    // An incremental radius is refused, naming G91.
    let e = read(
        Dialect::Fanuc,
        "G21 G90 G0 X10. Y0.\nG16\nG91 G1 X5. Y10. F500\n",
    );
    assert!(e.unwrap_err().contains("incremental (G91) polar radius"));
}

#[test]
fn whole_numbers_are_increments_for_corner_sizes_and_polar_angles() {
    // Fanuc in the least input increment: `,R2000` is 2 mm; under G20 and G16 `X10000` is
    // 1 in, `Y90000` 90° (0.001°, not a length's 0.0001 in).
    let options = Options {
        dialect: Dialect::Fanuc,
        control: ngc::ControlParameters {
            whole_numbers: Some(ngc::WholeNumbers::Increments),
            ..Default::default()
        },
        ..Options::default()
    };
    let read = |text: &str| {
        read_str_with(Path::new("t.nc"), text, &options)
            .collect::<Result<Vec<_>, _>>()
            .unwrap()
    };
    let m = read("G21 G90 G17\nG0 X0 Y0 Z0\nG1 X10000 ,R2000 F500\nY10000\nM30\n");
    close(xy(m[1].end), [8.0, 0.0]);
    close(centre(&m[2]).0, [8.0, 2.0]);
    let m = read("G20 G90 G17\nG0 X0 Y0 Z0\nG16\nG1 X10000 Y90000 F20\nM30\n");
    close(xy(m[1].end), [0.0, 25.4]);
}

#[test]
fn a_corner_word_in_a_lathe_cycle_shape_is_refused_not_a_crash() {
    let text = "G21 G18 G90\nG0 X50 Z2\nG71 U5 R1\nG71 P10 Q20 U0 W0 F100\nN10 G0 X20\n\
                G1 Z-10 ,C1.\nX40 Z-20\nN20 Z-30\nG70 P10 Q20\nM30\n";
    let e = read(Dialect::Fanuc, text).unwrap_err();
    assert!(
        e.contains("`,C1.` here: corner rounding and chamfer are read only"),
        "{e}"
    );
}
