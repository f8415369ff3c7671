//! `LN` blocks as TNC posts write them (KP "Three-dimensional tool compensation"): with
//! the tool at its nominal size an `LN` is the line to X Y Z; under M128 / `FUNCTION TCPM`
//! its `TX TY TZ` turn the rotary table so that the tool lies along T, with the tip on the
//! path. The rotary angles below are worked by hand for a table-table AC machine
//! (`R_t = Rx(A) Rz(C)`), and the tool direction is checked independently: `R_t T` must be
//! the machine's +Z.

use ngc::{Axis, Motion, Move, Options, RotaryTable};

use super::klartext_setup::{in_program, klartext_options, near, read_named, xyz};

fn table_ac() -> Options {
    Options {
        table: Some(RotaryTable {
            tilt: Axis::A,
            pivot_mm: [0.0; 3],
        }),
        ..klartext_options()
    }
}

fn read(body: &str, o: &Options) -> Result<Vec<Move>, (usize, String)> {
    read_named("ln.h", &in_program(body), o)
}

/// `Rx(a) Rz(c) v`, degrees.
fn rx_rz(a: f64, c: f64, v: [f64; 3]) -> [f64; 3] {
    let (sc, cc) = c.to_radians().sin_cos();
    let w = [cc * v[0] - sc * v[1], sc * v[0] + cc * v[1], v[2]];
    let (sa, ca) = a.to_radians().sin_cos();
    [w[0], ca * w[1] - sa * w[2], sa * w[1] + ca * w[2]]
}

#[test]
fn ln_with_a_nominal_tool_is_the_straight_line_to_its_point() {
    let ln = read(
        "2 L X+0 Y+0 Z+10 R0 FMAX\n3 LN X+10 Y+5 Z-2 NX+0 NY+0.6 NZ+0.8 F500\n4 LN IX+5 NX+0 NY+0 NZ+1",
        &klartext_options(),
    )
    .unwrap();
    let l = read(
        "2 L X+0 Y+0 Z+10 R0 FMAX\n3 L X+10 Y+5 Z-2 F500\n4 L X+15",
        &klartext_options(),
    )
    .unwrap();
    let feeds = |m: &[Move]| -> Vec<[f64; 3]> {
        m.iter()
            .filter(|m| m.motion == Motion::Linear)
            .map(xyz)
            .collect()
    };
    assert_eq!(feeds(&ln).len(), 2);
    assert!(near(feeds(&ln)[0], [10.0, 5.0, -2.0]));
    assert!(near(feeds(&ln)[1], [15.0, 5.0, -2.0]));
    assert_eq!(feeds(&ln), feeds(&l));
}

#[test]
fn ln_tool_direction_under_tcp_turns_the_table_to_it() {
    // T = (sin 30°, 0, cos 30°): tilt acos(T_z) = 30°, C = 90° − atan2(0, 0.5) = 90°.
    let m = read(
        "2 L X+0 Y+0 Z+50 A+0 C+0 R0 FMAX\n3 FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS\n\
         4 LN X+10 Y+0 Z+0 NX+0.5 NY+0 NZ+0.8660254 TX+0.5 TY+0 TZ+0.8660254 F500",
        &table_ac(),
    )
    .unwrap();
    let last = m.iter().rfind(|m| m.line == 5).unwrap();
    assert!(last.tcp);
    assert!((last.end[Axis::A] - 30.0).abs() < 1e-6, "{:?}", last.end);
    assert!((last.end[Axis::C] - 90.0).abs() < 1e-6, "{:?}", last.end);
    // T as written (7 decimals: 1e-8 off the unit vector's cos 30°).
    let t = [0.5, 0.0, 0.8660254];
    let up = rx_rz(last.end[Axis::A], last.end[Axis::C], t);
    assert!(
        up.iter()
            .zip([0.0, 0.0, 1.0])
            .all(|(a, b)| (a - b).abs() < 1e-7),
        "R_t T = {up:?}"
    );
    // Under TCP a move's X Y Z are the tip in the workpiece frame (the machine's inverse
    // kinematics is mtsim's, after the reader): the programmed point.
    assert!(near(xyz(last), [10.0, 0.0, 0.0]), "{:?}", xyz(last));
}

#[test]
fn ln_tool_direction_with_m128_in_the_block_and_c_next_to_its_value() {
    // T = (0, -sin 45°, cos 45°): tilt 45°, C = 90° − atan2(−0.707, 0) = 180°, taken as
    // −180° or 180° next to C = 170°: 180°.
    let m = read(
        "2 L X+0 Y+0 Z+50 A+0 C+170 R0 FMAX\n\
         3 LN X+0 Y+0 Z+5 NX+0 NY+0 NZ+1 TX+0 TY-1 TZ+1 F500 M128",
        &table_ac(),
    )
    .unwrap();
    let last = m.iter().rfind(|m| m.line == 4).unwrap();
    assert!(last.tcp);
    assert!((last.end[Axis::A] - 45.0).abs() < 1e-6, "{:?}", last.end);
    assert!((last.end[Axis::C] - 180.0).abs() < 1e-6, "{:?}", last.end);
}

#[test]
fn ln_constructs_mtsim_does_not_model_are_refused_by_name() {
    let cases = [
        (
            "2 LN X+1 Y+0 Z+0 NX+0 NY+0 NZ+1 TX+0 TY+0 TZ+1 F500",
            &table_ac(),
            "only under M128 or FUNCTION TCPM",
        ),
        (
            "2 TOOL CALL 1 Z S1000 DR+0.1\n3 LN X+1 Y+0 Z+0 NX+0 NY+0 NZ+1 F500",
            &klartext_options(),
            "3D radius compensation",
        ),
        (
            "2 LN X+1 Y+0 Z+0 NX+0 NY+0 NZ+1 RL F500",
            &klartext_options(),
            "RL or RR in an LN block",
        ),
        (
            "2 LN X+1 Y+0 Z+0 A+10 NX+0 NY+0 NZ+1 F500",
            &klartext_options(),
            "come from its tool direction",
        ),
        (
            "2 LN X+1 Y+0 Z+0 NX+0 NY+0 NZ+0 F500",
            &klartext_options(),
            "normal NX NY NZ zero",
        ),
        (
            "2 M128\n3 LN X+1 Y+0 Z+0 NX+0 NY+0 NZ+1 TX+0 TY+0 TZ+1 F500",
            &klartext_options(),
            "no rotary axes",
        ),
    ];
    for (body, o, want) in cases {
        let (line, msg) = read(body, o).expect_err(body);
        assert!(msg.contains(want), "{body}: {msg}");
        assert!(line >= 3, "{body}: line {line}");
    }
}
