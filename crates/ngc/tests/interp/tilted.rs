//! Tilted work planes (G68.2 / G53.1 / G69) and dynamic work offsets (Haas G254 / G255).
//! Every expected position is worked out by hand in the comments from the rotations
//! Rx, Ry, Rz and the table-table chain `m = pivot + R_t(q) (x₀ - pivot)`.

use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, Error, Motion, Options, Plane, RotaryTable};

fn opts(dialect: Dialect, table: Option<RotaryTable>) -> Options {
    Options {
        dialect,
        table,
        ..Options::default()
    }
}

fn ac(pivot_mm: [f64; 3]) -> Option<RotaryTable> {
    Some(RotaryTable {
        tilt: Axis::A,
        pivot_mm,
    })
}

fn moves(text: &str, o: &Options) -> Vec<ngc::Move> {
    read_str_with(Path::new("t.nc"), text, o)
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"))
}

fn error(text: &str, o: &Options) -> (usize, String) {
    let err = read_str_with(Path::new("t.nc"), text, o)
        .find_map(|m| m.err())
        .unwrap_or_else(|| panic!("expected an error in {text:?}"));
    match err {
        Error::Syntax(s) => (s.line, s.message),
        other => panic!("expected a syntax error, got {other:?}"),
    }
}

/// End X Y Z A B C rounded to 1e-9.
fn end(m: &ngc::Move) -> [f64; 6] {
    m.end.to_xyzabc().map(|v| {
        let r = (v * 1e9).round() / 1e9;
        if r == 0.0 {
            0.0
        } else {
            r
        }
    })
}

#[test]
fn g68_2_with_a_90_degree_tilt_turns_program_z_into_machine_minus_y() {
    // I0 J90 K0: R_f = Rx(90) maps e_x → e_x, e_y → e_z, e_z → -e_y. No table: a pure
    // rotation of the work coordinates.
    let o = opts(Dialect::Fanuc, None);
    let m = moves(
        "G68.2 X0 Y0 Z0 I0 J90 K0\nG1 Z10 F100\nX5\nY7\nG69\nG1 Z10\n",
        &o,
    );
    assert_eq!(end(&m[0]), [0.0, -10.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(end(&m[1]), [5.0, -10.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(end(&m[2]), [5.0, -10.0, 7.0, 0.0, 0.0, 0.0]);
    // After G69 program and machine coordinates agree again (Y keeps its machine value).
    assert_eq!(end(&m[3]), [5.0, -10.0, 10.0, 0.0, 0.0, 0.0]);
}

#[test]
fn g68_2_euler_angles_are_zxz_and_the_origin_is_in_work_coordinates() {
    // I90 J90 K0: Rz(90) Rx(90) e_z = Rz(90) (0, -1, 0) = (1, 0, 0): program Z is machine X.
    // Origin (10, 20, 30) in G54, which is (100, 0, -50) in the machine.
    let mut o = opts(Dialect::Fanuc, None);
    o.set_work_offset(1, ngc::AxisVec::xyzabc([100.0, 0.0, -50.0, 0.0, 0.0, 0.0]));
    let m = moves("G54 G68.2 X10 Y20 Z30 I90 J90 K0\nG0 X0 Y0 Z0\nZ4\n", &o);
    assert_eq!(end(&m[0]), [110.0, 20.0, -20.0, 0.0, 0.0, 0.0]);
    assert_eq!(end(&m[1]), [114.0, 20.0, -20.0, 0.0, 0.0, 0.0]);
    // Incremental moves are along the tilted axes too: I90 alone is Rz(90), X → Y.
    let m = moves("G68.2 I90\nG91 G1 X3 F100\n", &opts(Dialect::Haas, None));
    assert_eq!(end(&m[0]), [0.0, 3.0, 0.0, 0.0, 0.0, 0.0]);
}

#[test]
fn g53_1_turns_the_table_so_that_the_plane_normal_is_the_tool_axis() {
    // J90: the feature Z axis is t = (0, -1, 0) in the table frame. A = acos(0) = 90,
    // C = 90 - atan2(-1, 0) = 180. Check: Rz(180) t = (0, 1, 0), Rx(90) (0, 1, 0) = (0, 0, 1).
    // From C = 0, +180 and -180 are equally near; the unwrap (as mtsim's kinematics) gives -180.
    let o = opts(Dialect::Fanuc, ac([0.0, 0.0, 0.0]));
    let m = moves("G68.2 X0 Y0 Z0 I0 J90 K0\nG53.1\nG1 Z10 F100\nX4\n", &o);
    assert_eq!(m[0].kind(), ngc::MoveKind::Rapid);
    assert_eq!(end(&m[0]), [0.0, 0.0, 0.0, 90.0, 0.0, -180.0]);
    // Program +Z is now machine +Z; program +X is Rx(90) Rz(180) e_x = -e_x.
    assert_eq!(end(&m[1]), [0.0, 0.0, 10.0, 90.0, 0.0, -180.0]);
    assert_eq!(end(&m[2]), [-4.0, 0.0, 10.0, 90.0, 0.0, -180.0]);
    // I90 J90: t = (1, 0, 0). AC: A = 90, C = 90 - 0 = 90 (Rz(90) t = e_y, Rx(90) e_y = e_z).
    let m = moves("G68.2 I90 J90 K0\nG53.1\n", &o);
    assert_eq!(end(&m[0]), [0.0, 0.0, 0.0, 90.0, 0.0, 90.0]);
    // BC: B = 90, C = 180 - 0 = 180, i.e. -180 (Rz(180) t = -e_x, Ry(90) (-e_x) = e_z).
    let bc = Some(RotaryTable {
        tilt: Axis::B,
        pivot_mm: [0.0; 3],
    });
    let m = moves("G68.2 I90 J90 K0\nG53.1\n", &opts(Dialect::Fanuc, bc));
    assert_eq!(end(&m[0]), [0.0, 0.0, 0.0, 0.0, 90.0, -180.0]);
}

#[test]
fn g53_1_about_an_offset_pivot_keeps_the_linear_axes_and_maps_the_part_through_the_table() {
    // Pivot (0, 0, -100), G68.2 J90 origin 0: after G53.1 (A90 C180) the program origin,
    // a table point at x₀ = (0, 0, 0), is at pivot + Rx(90) Rz(180) (0, 0, 100)
    // = (0, 0, -100) + (0, -100, 0) = (0, -100, -100).
    let o = opts(Dialect::Fanuc, ac([0.0, 0.0, -100.0]));
    let m = moves("G68.2 I0 J90 K0\nG53.1\nG0 X0 Y0 Z5\n", &o);
    assert_eq!(end(&m[0])[..3], [0.0, 0.0, 0.0]);
    assert_eq!(end(&m[1]), [0.0, -100.0, -95.0, 90.0, 0.0, -180.0]);
}

#[test]
fn g254_with_c_at_90_degrees_turns_a_program_x_move_into_machine_y() {
    // Pivot (100, 50, 0), G54 (100, 50, -20): program (10, 0, 0) is x₀ = (110, 50, -20),
    // d = (10, 0, -20) from the pivot; at C = 90, Rz(90) d = (0, 10, -20), so the machine
    // goes to (100, 60, -20).
    let mut o = opts(Dialect::Haas, ac([100.0, 50.0, 0.0]));
    o.set_work_offset(1, ngc::AxisVec::xyzabc([100.0, 50.0, -20.0, 0.0, 0.0, 0.0]));
    let m = moves(
        "G54 G254\nG0 X10 Y0 Z0\nC90\nG1 X13 F100\nG255\nG0 X0\n",
        &o,
    );
    assert_eq!(end(&m[0]), [110.0, 50.0, -20.0, 0.0, 0.0, 0.0]);
    // Turning C carries the programmed point with the table.
    assert_eq!(end(&m[1]), [100.0, 60.0, -20.0, 0.0, 0.0, 90.0]);
    // X 10 → 13 in the table frame: machine Y 60 → 63.
    assert_eq!(end(&m[2]), [100.0, 63.0, -20.0, 0.0, 0.0, 90.0]);
    // G255: X is a plain work coordinate again, 0 + 100.
    assert_eq!(end(&m[3]), [100.0, 63.0, -20.0, 0.0, 0.0, 90.0]);
    // A tilt: pivot 0, A = 90 takes table point (0, 0, 10) to Rx(90) (0, 0, 10) = (0, -10, 0);
    // the tool length offset (T1, 50 mm) is added along machine Z after the map.
    let mut o = opts(Dialect::Haas, ac([0.0; 3]));
    o.tools = vec![ngc::Tool {
        number: 1,
        length_mm: 50.0,
        diameter_mm: 10.0,
    }];
    let m = moves("T1 M6\nG43 H1 G254\nG0 A90\nZ10\n", &o);
    assert_eq!(end(&m[1]), [0.0, -10.0, 50.0, 90.0, 0.0, 0.0]);
}

#[test]
fn arcs_in_a_tilted_plane_go_to_the_machine_plane_their_normal_turns_into() {
    // No table, J90: program Z → machine -Y, so G17 arcs lie in the machine ZX plane, seen
    // from -Y: a counter-clockwise program arc is clockwise about +Y. G3 from (10, 0, 0) to
    // (0, 10, 0) about the origin: machine (10, 0, 0) → (0, 0, 10).
    let m = moves(
        "G68.2 I0 J90 K0\nG0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0 F100\n",
        &opts(Dialect::Fanuc, None),
    );
    assert_eq!(end(&m[1]), [0.0, 0.0, 10.0, 0.0, 0.0, 0.0]);
    assert_eq!(
        m[1].motion,
        Motion::Arc {
            clockwise: true,
            plane: Plane::ZX,
            center_mm: [0.0, 0.0, 0.0]
        }
    );
    let sweep = m[1].arc_sweep_rad().unwrap();
    assert!(
        (sweep + std::f64::consts::FRAC_PI_2).abs() < 1e-12,
        "{sweep}"
    );
    // After G53.1 (A90 C180) program X → machine -X, Y → machine -Y: a G17 arc stays a
    // clockwise G17 arc, turned by 180 deg. G2 (10, 0) → (0, -10) about (0, 0) is machine
    // (-10, 0) → (0, 10).
    let m = moves(
        "G68.2 I0 J90 K0\nG53.1\nG0 X10 Y0 Z0\nG2 X0 Y-10 R10 F100\n",
        &opts(Dialect::Fanuc, ac([0.0; 3])),
    );
    assert_eq!(end(&m[1])[..3], [-10.0, 0.0, 0.0]);
    assert_eq!(end(&m[2])[..3], [0.0, 10.0, 0.0]);
    match m[2].motion {
        Motion::Arc {
            clockwise,
            plane,
            center_mm,
        } => {
            assert!(clockwise);
            assert_eq!(plane, Plane::XY);
            assert!(center_mm.iter().all(|c| c.abs() < 1e-9), "{center_mm:?}");
        }
        other => panic!("expected an arc, got {other:?}"),
    }
}

#[test]
fn tilted_frames_refuse_what_they_cannot_do() {
    let fanuc = opts(Dialect::Fanuc, ac([0.0; 3]));
    let (line, msg) = error("G0 X0\nG53.1\n", &fanuc);
    assert_eq!(line, 2);
    assert!(msg.contains("G68.2"), "{msg}");
    let (_, msg) = error("G254\n", &opts(Dialect::Haas, None));
    assert!(msg.contains("rotary table"), "{msg}");
    let (_, msg) = error("G68.2 I0 J90 K0\n", &opts(Dialect::Linuxcnc, None));
    assert!(msg.contains("G68.2"), "{msg}");
    let (_, msg) = error("G68.2 X10 I0 J90 K0 G1 F100\n", &fanuc);
    assert!(msg.contains("block of its own"), "{msg}");
    let (_, msg) = error("G68.2 J90\nG10 L2 P1 X5\n", &fanuc);
    assert!(msg.contains("G68.2 or G254 active"), "{msg}");
    let (_, msg) = error("G68.2 I0 J90 K0 C10\n", &fanuc);
    assert!(msg.contains("G68.2 block"), "{msg}");
    let (_, msg) = error("G68.2 I0 J90 K0\nG81 X0 Y0 Z-5 R2 F100\n", &fanuc);
    assert!(msg.contains("canned cycle"), "{msg}");
}

#[test]
fn an_arc_in_an_oblique_plane_runs_as_chords_on_its_circle() {
    // J45 without G53.1: R_f = Rx(45), the G17 normal is (0, -sin 45°, cos 45°) in the
    // machine. The quarter circle of radius 10 about the origin, program (10 cos φ,
    // 10 sin φ, 0), is machine (10 cos φ, 10 sin φ cos 45°, 10 sin φ sin 45°): every chord end
    // 10 from the origin with Y = Z. Chords of sagitta ≤ 0.001 mm: Δφ ≤ 2 acos(1 − 1e-4)
    // = 0.0282845 rad, so ⌈(π/2) / 0.0282845⌉ = 56 chords.
    let m = moves(
        "G21 G68.2 I0 J45 K0\nG0 X10 Y0 Z0\nG3 X0 Y10 I-10 F100\n",
        &opts(Dialect::Fanuc, None),
    );
    let arc = &m[1..];
    assert_eq!(arc.len(), 56);
    let s = std::f64::consts::FRAC_1_SQRT_2 * 10.0;
    let last = arc.last().unwrap().end;
    assert!((last[Axis::X]).abs() < 1e-9 && (last[Axis::Y] - s).abs() < 1e-9);
    assert!((last[Axis::Z] - s).abs() < 1e-9);
    for c in arc {
        assert_eq!(c.motion, Motion::Linear);
        let [x, y, z] = [c.end[Axis::X], c.end[Axis::Y], c.end[Axis::Z]];
        assert!(((x * x + y * y + z * z).sqrt() - 10.0).abs() < 1e-9);
        assert!((y - z).abs() < 1e-9);
        // The chord's midpoint is within 0.001 mm of the circle.
        let mid = [0, 1, 2].map(|k| (c.start.0[k] + c.end.0[k]) / 2.0);
        let r = (mid[0] * mid[0] + mid[1] * mid[1] + mid[2] * mid[2]).sqrt();
        assert!(10.0 - r <= 1e-3 + 1e-12, "sagitta {}", 10.0 - r);
    }
}

// G68: 2-D coordinate rotation (Fanuc and Haas). machine X Y = offset + c + Rot(R)(p − c),
// Rot(R) counter-clockwise seen from +Z: Rot(90)(x, y) = (−y, x), Rot(180)(x, y) = (−x, −y).

#[test]
fn g68_turns_program_x_y_about_its_centre_and_g69_cancels() {
    let m = moves(
        "G90 G17 G54\nG0 X1 Y1\nG68 X10 Y0 R90\nG1 X20 Y0 F100\nG91 X5\nG90 X10 Y10\nG69\nG1 X3 Y4\n",
        &opts(Dialect::Fanuc, None),
    );
    // X20 Y0: p − c = (10, 0) → (0, 10) → + c = (10, 10).
    assert_eq!(end(&m[1]), [10.0, 10.0, 0.0, 0.0, 0.0, 0.0]);
    // G91 X5: the increment (5, 0) turns to (0, 5).
    assert_eq!(end(&m[2]), [10.0, 15.0, 0.0, 0.0, 0.0, 0.0]);
    // X10 Y10: p − c = (0, 10) → (−10, 0) → (0, 0).
    assert_eq!(end(&m[3]), [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    // After G69 program and machine coordinates agree again.
    assert_eq!(end(&m[4]), [3.0, 4.0, 0.0, 0.0, 0.0, 0.0]);
}

#[test]
fn g68_without_a_centre_turns_about_the_current_position_in_the_work_system() {
    // G55 is X100 Y50 (G10 L2 P2). At program (10, 10), R180: X20 Y10 is p − c = (10, 0)
    // → (−10, 0) → c + that = (0, 10) program → (100, 60) machine.
    let m = moves(
        "G10 L2 P2 X100 Y50\nG55 G0 X10 Y10\nG68 R180\nG1 X20 Y10 F100\n",
        &opts(Dialect::Haas, None),
    );
    assert_eq!(end(&m[0]), [110.0, 60.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(end(&m[1]), [100.0, 60.0, 0.0, 0.0, 0.0, 0.0]);
}

#[test]
fn g68_turns_arcs_and_reads_inches() {
    // R90 about the origin: X10 Y0 → (0, 10); the quarter arc to X0 Y10 (centre I-10 J0
    // from (10, 0), the origin) ends at Rot(90)(0, 10) = (−10, 0).
    let m = moves(
        "G21 G90 G17\nG68 X0 Y0 R90\nG0 X10 Y0\nG3 X0 Y10 I-10 J0 F100\n",
        &opts(Dialect::Fanuc, None),
    );
    assert_eq!(end(&m[0]), [0.0, 10.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(end(&m[1]), [-10.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    // Inches: the centre X1 is 25.4 mm; X2 Y0 is p − c = (25.4, 0) → (0, 25.4) → (25.4, 25.4).
    let m = moves(
        "G20 G90 G17\nG68 X1 Y0 R90\nG1 X2 Y0 F10\n",
        &opts(Dialect::Fanuc, None),
    );
    assert_eq!(end(&m[0]), [25.4, 25.4, 0.0, 0.0, 0.0, 0.0]);
}

#[test]
fn what_g68_cannot_mean_here_is_refused_with_its_reason() {
    let o = opts(Dialect::Fanuc, None);
    for (text, line, says) in [
        ("G68 X0 Y0\n", 1, "G68 without R"),
        (
            "G68 X0 Y0 I0 J0 K1 R10\n",
            1,
            "three-dimensional coordinate conversion",
        ),
        ("G18\nG68 X0 Z0 R10\n", 2, "outside the G17 plane"),
        ("G68 X0 Y0 R10\nG19\n", 2, "the plane may not change"),
        (
            "G68 X0 Y0 R10\nG81 X1 Y1 Z-1 R1 F100\n",
            2,
            "rotated work system (G68",
        ),
        (
            "G68 X0 Y0 R10\nG68.2 X0 Y0 Z0 I0 J30 K0\n",
            2,
            "G68.2 while G68",
        ),
        ("G1 G68 X0 Y0 R10 F100\n", 1, "in a G68 block"),
    ] {
        let (l, message) = error(text, &o);
        assert_eq!(l, line, "{text:?}: {message}");
        assert!(message.contains(says), "{text:?}: {message}");
    }
}
