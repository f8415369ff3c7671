//! The secondary linear axes U V W (LinuxCNC's axes 7 to 9, parallel to X Y Z): read in mm
//! or inches, absolute or incremental, through the work offsets, G92, G28/G30 and G10 L2/L20
//! with LinuxCNC's parameter numbers (`#5221`-`#5229` = G54 X Y Z A B C U V W, `#5211`-`#5219`
//! G92, `#5161`-`#5169` G28, `#5181`-`#5189` G30, `#5420`-`#5428` the current position).
//! Expected values are worked out by hand in the comments. (rs274 standalone cannot be the
//! reference here: its axis mask is X Y Z A B C, it refuses U V W as "Bad character".)

use std::path::Path;

use ngc::{read_str_with, Axis, AxisVec, Dialect, Error, Motion, Options, Plane};

/// A nine-axis LinuxCNC machine (axis_9axis), all offsets zero.
fn nine() -> Options {
    Options {
        dialect: Dialect::Linuxcnc,
        axes: Axis::ALL.to_vec(),
        ..Options::default()
    }
}

fn moves(text: &str, o: &Options) -> Vec<ngc::Move> {
    read_str_with(Path::new("t.ngc"), text, o)
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"))
}

fn error(text: &str, o: &Options) -> (usize, usize, String) {
    match read_str_with(Path::new("t.ngc"), text, o).find_map(|m| m.err()) {
        Some(Error::Syntax(s)) => (s.line, s.column, s.message),
        other => panic!("expected a syntax error in {text:?}, got {other:?}"),
    }
}

/// End U V W of each move, rounded to 1e-9 mm.
fn uvw(m: &[ngc::Move]) -> Vec<[f64; 3]> {
    let r = |v: f64| (v * 1e9).round() / 1e9 + 0.0;
    m.iter()
        .map(|m| Axis::SECONDARY.map(|a| r(m.end[a])))
        .collect()
}

#[test]
fn the_axis_order_and_letters_are_linuxcncs() {
    let letters: String = Axis::ALL.iter().map(|a| a.letter()).collect();
    assert_eq!(letters, "XYZABCUVW");
    for (k, a) in Axis::ALL.into_iter().enumerate() {
        assert_eq!(a.index(), k);
        assert_eq!(Axis::from_letter(a.letter().to_ascii_lowercase()), Some(a));
    }
    for a in Axis::SECONDARY {
        assert!(a.is_secondary() && !a.is_rotary());
        assert_eq!(a.unit(), "mm");
    }
}

#[test]
fn u_v_w_move_in_mm_and_inches_absolute_and_incremental() {
    let text = "\
G21 G90 G0 U10 V-5 W2.5
G91 G1 U1 V1 W-1 F100
G20 G1 U1
G90 G1 V1
G21 G0 U0 V0 W0
";
    assert_eq!(
        uvw(&moves(text, &nine())),
        [
            [10.0, -5.0, 2.5],
            [11.0, -4.0, 1.5], // G91: +1 mm each
            [36.4, -4.0, 1.5], // G20 G91: +1 in = 25.4 mm
            [36.4, 25.4, 1.5], // G20 G90: V = 1 in
            [0.0, 0.0, 0.0],
        ]
    );
}

#[test]
fn work_offsets_g92_and_g10_act_on_u_v_w_with_linuxcncs_parameter_numbers() {
    let mut o = nine();
    // G54 U V W = 100, 200, 300 (#5227-#5229); G55 U = 7 (#5247).
    o.parameters
        .extend([(5227, 100.0), (5228, 200.0), (5229, 300.0), (5247, 7.0)]);
    let text = "\
G54 G0 U1 V2 W3
G55 G0 U1
G10 L2 P2 U10 V20 W30
G0 U0 V0 W0
G10 L20 P2 U1
G0 U0
G92 W10
G0 W5
G0 X#5219
G92.1
G0 Y#5249 Z#5229
";
    let m = moves(text, &o);
    assert_eq!(
        uvw(&m),
        [
            [101.0, 202.0, 303.0], // G54
            [8.0, 202.0, 303.0],   // G55 U = 7
            [10.0, 20.0, 30.0],    // G10 L2 P2 made G55 (10, 20, 30)
            [9.0, 20.0, 30.0],     // L20: machine U 10 is program U 1, so G55 U = 9
            [9.0, 20.0, 25.0],     // G92 W10 at program W 0: G92 W = -10, so W5 is machine 25
            [9.0, 20.0, 25.0],     // the X Y Z moves: U V W stay
            [9.0, 20.0, 25.0],
        ]
    );
    // #5219 = G92 W = -10 (read before G92.1); #5249 = G55 W = 30, #5229 = G54 W = 300.
    assert_eq!(m[5].end[Axis::X], -10.0);
    assert_eq!([m[6].end[Axis::Y], m[6].end[Axis::Z]], [30.0, 300.0]);
}

#[test]
fn g28_and_g30_go_to_the_stored_u_v_w_and_g28_1_stores_them() {
    let mut o = nine();
    let mut home = AxisVec::ZERO;
    home[Axis::U] = 40.0;
    home[Axis::W] = -12.0;
    o.set_reference(false, home); // #5167 = 40, #5169 = -12
    o.parameters.push((5188, 3.5)); // G30 V
    let text = "\
G0 U10 V10 W10
G28 U20
G28
G30
G0 U1 V2 W3
G28.1
G0 U0 V0 W0
G28
";
    assert_eq!(
        uvw(&moves(text, &o)),
        [
            [10.0, 10.0, 10.0],
            [20.0, 10.0, 10.0], // G28 U20: through U 20 ...
            [40.0, 10.0, 10.0], // ... to the stored U only
            [40.0, 0.0, -12.0], // G28 without words: every axis home (V 0, W -12)
            [0.0, 3.5, 0.0],    // G30: every axis to #5181-#5189
            [1.0, 2.0, 3.0],
            [0.0, 0.0, 0.0],
            [1.0, 2.0, 3.0], // G28 to what G28.1 stored
        ]
    );
}

#[test]
fn the_current_position_parameters_hold_u_v_w_in_program_units() {
    let mut o = nine();
    o.parameters.push((5228, 100.0)); // G54 V
                                      // #5426-#5428 and #<_u> #<_v> #<_w>: the program position, in inches under G20.
    let text = "\
G0 U25.4 V50.8 W-50.8
G20
G0 X#5426 Y#5427 Z#<_w>
";
    let m = moves(text, &o);
    let last = m.last().unwrap();
    // Machine V is 150.8; the program position U = 1 in, V = 50.8 / 25.4 = 2 in, W = -2 in,
    // read back as inches: mm again.
    let r = |v: f64| (v * 1e9).round() / 1e9;
    assert_eq!(
        [
            r(last.end[Axis::X]),
            r(last.end[Axis::Y]),
            r(last.end[Axis::Z])
        ],
        [25.4, 50.8, -50.8]
    );
}

#[test]
fn an_arc_in_xy_moves_u_v_along_with_it() {
    // foam.ngc's arc: from (35, 60) to (60, 35) clockwise, R25, centre (35, 35); U V go
    // from (35, 60) to (60, 35) in a straight line with the arc angle.
    let m = moves("G0 X35 Y60 U35 V60\nG2 R25 X60 Y35 U60 V35 F200\n", &nine());
    let arc = &m[1];
    match arc.motion {
        Motion::Arc {
            clockwise,
            plane,
            center_mm,
        } => {
            assert!(clockwise);
            assert_eq!(plane, Plane::XY);
            assert!((center_mm[0] - 35.0).abs() < 1e-9 && (center_mm[1] - 35.0).abs() < 1e-9);
        }
        other => panic!("expected an arc, got {other:?}"),
    }
    assert_eq!(uvw(&m[1..]), [[60.0, 35.0, 0.0]]);
}

#[test]
fn a_u_v_w_word_the_machine_lacks_is_an_error_never_dropped() {
    // The default reader options are a six-axis machine X Y Z A B C.
    let (line, column, message) = error("G0 X1\nG1 X2 V3 F100\n", &Options::default());
    assert_eq!((line, column), (2, 7));
    assert!(
        message.contains("`V3`: this machine has no V axis (it has X Y Z A B C)"),
        "{message}"
    );
    // A foam cutter (X Y U V) has no W, and no Z.
    let foam = Options {
        axes: vec![Axis::X, Axis::Y, Axis::U, Axis::V],
        ..nine()
    };
    assert_eq!(uvw(&moves("G0 X1 Y2 U3 V4\n", &foam)), [[3.0, 4.0, 0.0]]);
    let (_, column, message) = error("G0 U1 W1\n", &foam);
    assert_eq!(column, 7);
    assert!(message.contains("no W axis (it has X Y U V)"), "{message}");
}

#[test]
fn words_that_would_be_lost_are_refused() {
    // A canned cycle places the hole with the plane's axes only.
    let (line, column, message) = error("G0 Z10\nG81 X1 Y1 Z-1 R2 U5 F100\n", &nine());
    assert_eq!((line, column), (2, 18));
    assert!(
        message.contains("`U5` in a canned cycle: expected only X Y Z"),
        "{message}"
    );
    // mtsim's tool length offset is along Z only (LinuxCNC's G43.1 takes any axis).
    let (_, column, message) = error("G43.1 Z1 W2\n", &nine());
    assert_eq!(column, 10);
    assert!(
        message.contains("`W2` in a G43.1 block: expected only Z"),
        "{message}"
    );
    // And so are its tools: G10 L1 sets a length along Z and a radius.
    let (_, column, message) = error("G10 L1 P1 Z5 W2\n", &nine());
    assert_eq!(column, 14);
    assert!(
        message.contains("`W2` in a G10 L1/L10 block: expected only Z"),
        "{message}"
    );
}

#[test]
fn a_probe_sets_the_u_v_w_probe_parameters() {
    // The probe never trips (as in rs274): #5067-#5069 are the programmed U V W.
    let m = moves(
        "G0 U1\nG38.3 U5 V6 W7 F100\nG0 X#5067 Y#5068 Z#5069\n",
        &nine(),
    );
    let last = m.last().unwrap();
    assert_eq!(
        [last.end[Axis::X], last.end[Axis::Y], last.end[Axis::Z]],
        [5.0, 6.0, 7.0]
    );
}

#[test]
fn cutter_compensation_offsets_the_plane_and_keeps_u_v_w() {
    // A left-compensated (G41.1, diameter 2: radius 1) counter-clockwise square from (0, 0):
    // every corner turns left, inside the path, so the offset lines y = 1, x = 9, y = 9 meet
    // at (9, 1) and (9, 9). U V W are not in the plane: they end where the words say.
    let m = moves(
        "G21 G90 G17\nG0 X0 Y0\nG41.1 D2\nG1 X10 Y0 U5 F100\nG1 X10 Y10 U7\nG1 X0 Y10 W3\nG40\nG0 X-5 Y-5 U0\n",
        &nine(),
    );
    let r = |v: f64| (v * 1e9).round() / 1e9 + 0.0;
    let xy: Vec<[f64; 2]> = m
        .iter()
        .map(|m| [r(m.end[Axis::X]), r(m.end[Axis::Y])])
        .collect();
    assert_eq!(
        xy,
        [[0.0, 0.0], [9.0, 1.0], [9.0, 9.0], [0.0, 9.0], [-5.0, -5.0]]
    );
    assert_eq!(
        uvw(&m),
        [
            [0.0, 0.0, 0.0],
            [5.0, 0.0, 0.0],
            [7.0, 0.0, 0.0],
            [7.0, 0.0, 3.0],
            [0.0, 0.0, 3.0],
        ]
    );
}
