//! Constructs real Klartext and Sinumerik posts write (issue 41): circles in the planes
//! Z X and Y Z, the drilling cycles 202, 206, 209 and 240, `Z + Q13` with blanks; Sinumerik
//! arrays, `ISVAR`, the system variables given a value, and the refusals that name what is
//! not given (a GUD variable, tool management, a cycle with its manual section). Every
//! position is worked out by hand in the comments.

use ngc::{Axis, Dialect, Feed, Motion, Move, Options, Plane};

use super::klartext_setup::{in_program, klartext_options, near, read_named, xyz};

fn klartext(body: &str) -> Result<Vec<Move>, (usize, String)> {
    read_named("t.h", &in_program(body), &klartext_options())
}

fn sinumerik(text: &str) -> Result<Vec<Move>, (usize, String)> {
    let o = Options {
        dialect: Dialect::Siemens,
        ..Options::default()
    };
    read_named("t.mpf", text, &o)
}

/// Feed moves and rapids along Z alone: (rapid, Z, feed).
fn z_path(m: &[Move]) -> Vec<(bool, f64, Feed)> {
    m.iter()
        .filter(|m| !matches!(m.motion, Motion::Dwell { .. }))
        .map(|m| (m.motion == Motion::Rapid, m.end[Axis::Z], m.feed))
        .collect()
}

#[test]
fn a_circle_about_a_pole_in_x_z_turns_in_the_plane_z_x() {
    // Fusion's lead-in: from (491, -15, 197) about CC X+483 Z+197 by IPA+90 DR+. In the
    // plane Z X the angle 0 lies on +Z and DR+ turns from +Z to +X (G18 G3): the start
    // (dz 0, dx 8) is at 90°, the end at 180°: (dz -8, dx 0) = X 483, Z 189.
    let m = klartext(
        "2 L X+491 Y-15 Z+197 R0 FMAX\n3 CC X+483 Z+197\n4 CP IPA+90 DR+ F1000\n5 L X+479 Z+189",
    )
    .unwrap();
    assert!(near(xyz(&m[1]), [483.0, -15.0, 189.0]), "{:?}", xyz(&m[1]));
    match m[1].motion {
        Motion::Arc {
            clockwise,
            plane,
            center_mm,
        } => {
            assert!(!clockwise);
            assert_eq!(plane, Plane::ZX);
            assert!((center_mm[0] - 483.0).abs() < 1e-9 && (center_mm[2] - 197.0).abs() < 1e-9);
        }
        other => panic!("not an arc: {other:?}"),
    }
    // The plane X Y again for the next block: a line, then a circle about an X Y pole.
    assert!(near(xyz(&m[2]), [479.0, -15.0, 189.0]));
    let m = klartext(
        "2 L X+10 Y+0 Z+0 R0 F100\n3 CC X+0 Z+0\n4 C X+0 Z+10 DR-\n5 CC X+5 Y+0\n6 C X+5 Y+5 DR+",
    )
    .unwrap();
    // C DR- about (x 0, z 0) from (dz 0, dx 10) at 90° to (dz 10, dx 0) at 0°: clockwise.
    assert!(matches!(
        m[1].motion,
        Motion::Arc {
            clockwise: true,
            plane: Plane::ZX,
            ..
        }
    ));
    assert!(near(xyz(&m[1]), [0.0, 0.0, 10.0]));
    assert!(matches!(
        m[2].motion,
        Motion::Arc {
            clockwise: false,
            plane: Plane::XY,
            ..
        }
    ));
}

#[test]
fn a_circle_in_y_z_and_a_polar_line_about_its_pole() {
    // CC Y+0 Z+0: the plane Y Z, angle 0 on +Y. From (0, 10, 0) CP PA+90 DR+ to (0, 0, 10);
    // LP PR+5 PA+0 then to Y 5, Z 0.
    let m =
        klartext("2 L X+0 Y+10 Z+0 R0 F100\n3 CC Y+0 Z+0\n4 CP PA+90 DR+\n5 LP PR+5 PA+0").unwrap();
    assert!(near(xyz(&m[1]), [0.0, 0.0, 10.0]), "{:?}", xyz(&m[1]));
    assert!(matches!(
        m[1].motion,
        Motion::Arc {
            clockwise: false,
            plane: Plane::YZ,
            ..
        }
    ));
    assert!(near(xyz(&m[2]), [0.0, 5.0, 0.0]), "{:?}", xyz(&m[2]));
    // Radius compensation or CT outside X Y is refused by name.
    let (line, msg) =
        klartext("2 L X+10 Y+0 Z+0 RL F100\n3 CC X+0 Z+0\n4 C X+0 Z+10 DR-").unwrap_err();
    assert_eq!(line, 5);
    assert!(msg.contains("`C` outside the plane X Y"), "{msg}");
}

#[test]
fn a_sign_and_a_q_parameter_apart_are_one_value() {
    let m = klartext("2 Q13 = -4\n3 L X+0 Y+0 Z + Q13 R0 FMAX").unwrap();
    assert_eq!(m[0].end[Axis::Z], -4.0);
}

const CYCLE_AT: &str = "2 TOOL CALL 1 Z S500\n3 L X+5 Y+5 Z+20 R0 FMAX\n";

#[test]
fn cycle_240_centers_to_its_depth_in_one_plunge() {
    // Surface 0, clearance 2, depth -3 at F150, dwell 0.5 s, second clearance 20.
    let m = klartext(&format!(
        "{CYCLE_AT}4 CYCL DEF 240 CENTERING ~\n Q200=+2 ~\n Q343=+0 ~\n Q201=-3 ~\n Q344=-9 ~\n \
         Q206=+150 ~\n Q211=+0.5 ~\n Q203=+0 ~\n Q204=+20\n5 CYCL CALL"
    ))
    .unwrap();
    let z = z_path(&m[1..]);
    assert_eq!(
        z,
        [
            (true, 2.0, Feed::None),
            (false, -3.0, Feed::PerMinute(150.0)),
            (true, 2.0, Feed::None),
            (true, 20.0, Feed::None)
        ]
    );
    assert!(m.iter().any(|m| m.motion == Motion::Dwell { seconds: 0.5 }));
    let (line, msg) = klartext(&format!(
        "{CYCLE_AT}4 CYCL DEF 240 CENTERING ~\n Q200=+2 ~\n Q343=+1 ~\n Q201=-3 ~\n Q344=-9 ~\n \
         Q206=+150 ~\n Q211=+0 ~\n Q203=+0 ~\n Q204=+20\n5 CYCL CALL"
    ))
    .unwrap_err();
    assert_eq!(line, 5);
    assert!(
        msg.contains("Q343") && msg.contains("\"Cycle 240\""),
        "{msg}"
    );
}

#[test]
fn cycle_206_taps_down_and_back_at_its_feed() {
    // F = Q206 = 625 in and out, to -10, then FMAX to the second clearance 10.
    let m = klartext(&format!(
        "{CYCLE_AT}4 CYCL DEF 206 TAPPING NEW ~\n Q200=+2 ~\n Q201=-10 ~\n Q206=+625 ~\n \
         Q211=+0 ~\n Q203=+0 ~\n Q204=+10\n5 CYCL CALL"
    ))
    .unwrap();
    assert_eq!(
        z_path(&m[1..]),
        [
            (true, 2.0, Feed::None),
            (false, -10.0, Feed::PerMinute(625.0)),
            (false, 2.0, Feed::PerMinute(625.0)),
            (true, 10.0, Feed::None)
        ]
    );
}

#[test]
fn cycle_209_breaks_chips_by_its_infeed_and_retract() {
    // S500 × pitch 1 = F500; infeeds of 4 to -10: -4, -8, -10; back by Q256 × pitch = 2 at
    // F500 × Q403 = 1000 after each but the last; at the depth back to 2, then FMAX to 10.
    let m = klartext(&format!(
        "{CYCLE_AT}4 CYCL DEF 209 TAPPING W/ CHIP BRKG ~\n Q200=+2 ~\n Q201=-10 ~\n Q239=+1 ~\n \
         Q203=+0 ~\n Q204=+10 ~\n Q257=+4 ~\n Q256=+2 ~\n Q336=+0 ~\n Q403=+2\n5 CYCL CALL"
    ))
    .unwrap();
    let (f, back) = (Feed::PerMinute(500.0), Feed::PerMinute(1000.0));
    assert_eq!(
        z_path(&m[1..]),
        [
            (true, 2.0, Feed::None),
            (false, -4.0, f),
            (false, -2.0, back),
            (false, -8.0, f),
            (false, -6.0, back),
            (false, -10.0, f),
            (false, 2.0, back),
            (true, 10.0, Feed::None)
        ]
    );
}

#[test]
fn cycle_202_bores_leaves_the_wall_and_returns_to_the_centre() {
    // To -12 at F80, dwell 1 s, 0.2 mm off the wall in +X (Q214 = 3), up to 2 at Q208 = 500,
    // FMAX to 30, back over the centre (5, 5).
    let m = klartext(&format!(
        "{CYCLE_AT}4 CYCL DEF 202 BORING ~\n Q200=+2 ~\n Q201=-12 ~\n Q206=+80 ~\n Q211=+1 ~\n \
         Q208=+500 ~\n Q203=+0 ~\n Q204=+30 ~\n Q214=+3 ~\n Q336=+0\n5 CYCL CALL"
    ))
    .unwrap();
    let ends: Vec<[f64; 3]> = m[1..]
        .iter()
        .filter(|m| !matches!(m.motion, Motion::Dwell { .. }))
        .map(xyz)
        .collect();
    let expected = [
        [5.0, 5.0, 2.0],
        [5.0, 5.0, -12.0],
        [5.2, 5.0, -12.0],
        [5.2, 5.0, 2.0],
        [5.2, 5.0, 30.0],
        [5.0, 5.0, 30.0],
    ];
    assert_eq!(ends.len(), expected.len(), "{ends:?}");
    for (got, want) in ends.iter().zip(expected) {
        assert!(near(*got, want), "{got:?} against {want:?}");
    }
    assert!(m.iter().any(|m| m.motion == Motion::Dwell { seconds: 1.0 }));
    assert_eq!(m[5].feed, Feed::PerMinute(500.0));
}

#[test]
fn old_cycles_2_and_17_tap_from_where_they_start_and_13_does_not_move() {
    // From Z 2 (set-up clearance 2 above the surface 0): cycle 2 feeds at F100 to -12,
    // dwells 0.5 s, feeds back to 2; cycle 17 at pitch 1.5 × S500 = F750 to -10 and back.
    let m = klartext(&format!(
        "{CYCLE_AT}4 L Z+2 FMAX\n5 CYCL DEF 2.0 TAPPING\n6 CYCL DEF 2.1 SET UP 2\n\
         7 CYCL DEF 2.2 DEPTH -12\n8 CYCL DEF 2.3 DWELL 0.5\n9 CYCL DEF 2.4 F100\n10 CYCL CALL\n\
         11 CYCL DEF 13.0 ORIENTATION\n12 CYCL DEF 13.1 ANGLE 180\n\
         13 CYCL DEF 17.0 RIGID TAPPING\n14 CYCL DEF 17.1 SET UP 2\n15 CYCL DEF 17.2 DEPTH -10\n\
         16 CYCL DEF 17.3 PITCH +1.5\n17 CYCL CALL"
    ))
    .unwrap();
    let (f100, f750) = (Feed::PerMinute(100.0), Feed::PerMinute(750.0));
    let path = z_path(&m[2..]);
    assert_eq!(
        path,
        [
            (true, 2.0, Feed::None),
            (false, -12.0, f100),
            (false, 2.0, f100),
            (true, 2.0, Feed::None),
            (false, -10.0, f750),
            (false, 2.0, f750)
        ]
    );
    assert!(m.iter().any(|m| m.motion == Motion::Dwell { seconds: 0.5 }));
}

#[test]
fn fn_17_writes_the_tool_table_and_a_changed_tool_is_not_used() {
    // Tool-table upkeep: other tools' geometry and columns that do not move the axes.
    let m = klartext(
        "2 Q8 = 10\n3 FN 17: SYSWRITE ID50 NR1 IDXQ8 = +0\n4 FN 17: SYSWRITE ID50 NR16 IDXQ8 = +0.1\n\
         5 L X+1 Y+0 Z+0 R0 FMAX",
    )
    .unwrap();
    assert_eq!(m.last().unwrap().end[Axis::X], 1.0);
    // FN 18 with IDX in a Q parameter reads that tool (tool 1: R = 10 / 2).
    let m = klartext("2 Q1 = 1\n3 FN 18: SYSREAD Q2 = ID50 NR2 IDXQ1\n4 L X+Q2 Y+0 Z+0 R0 FMAX")
        .unwrap();
    assert_eq!(m.last().unwrap().end[Axis::X], 5.0);
    // A tool whose length FN 17 changed is not called or read.
    let (line, msg) =
        klartext("2 FN 17: SYSWRITE ID50 NR1 IDX1 = +50\n3 TOOL CALL 1 Z S100").unwrap_err();
    assert_eq!(line, 4);
    assert!(
        msg.contains("FN 17 changed this tool's geometry at line 3"),
        "{msg}"
    );
    let (line, msg) = klartext("2 FN 17: SYSWRITE ID210 NR1 = +1").unwrap_err();
    assert_eq!(line, 3);
    assert!(msg.contains("other than the tool table"), "{msg}");
}

#[test]
fn a_cycle_not_read_is_refused_with_its_manual_section() {
    let (line, msg) = klartext("2 CYCL DEF 204 BACK BORING ~\n Q200=+2 ~\n Q249=+5").unwrap_err();
    assert_eq!(line, 3);
    assert!(
        msg.contains("`CYCL DEF 204 BACK BORING`: the Heidenhain cycle 204 BACK BORING is not supported (TNC 640 cycle programming manual, \"Cycles: drilling\", \"Cycle 204\")"),
        "{msg}"
    );
}

#[test]
fn sinumerik_arrays_are_defined_set_and_read() {
    // AR[1] = 0.3 from the list, MAT[1,2] = 7 set, TWO all 2 by REP: X = 0.3 + 7 + 2 = 9.3.
    let m = sinumerik(
        "DEF REAL AR[3]=(0.5,0.3), MAT[2,3], TWO[2]=REP(2)\nDEF INT KK=1\nMAT[KK,KK+1]=7\n\
         G0 X=AR[KK]+MAT[1,2]+TWO[1] Y=AR[2] Z=MAT[0,0]\nM30\n",
    )
    .unwrap();
    assert!(near(xyz(&m[0]), [9.3, 0.0, 0.0]), "{:?}", xyz(&m[0]));
    // Out of range, too many values, and a name no DEF gives (a GUD variable).
    let (line, msg) = sinumerik("DEF REAL AR[3]\nR1=AR[3]\n").unwrap_err();
    assert_eq!(line, 2);
    assert!(msg.contains("outside the array `AR`"), "{msg}");
    let (_, msg) = sinumerik("DEF REAL AR[2]=(1,2,3)\n").unwrap_err();
    assert!(msg.contains("3 values for the 2 elements"), "{msg}");
    let (line, msg) = sinumerik("N10 G0 X0\nIZMERENO_XT[0]=0\n").unwrap_err();
    assert_eq!(line, 2);
    assert!(
        msg.contains("`IZMERENO_XT` is not defined in this program")
            && msg.contains("global user variable (GUD)"),
        "{msg}"
    );
}

#[test]
fn isvar_and_the_system_variables_given_a_value() {
    // ISVAR of a defined name is TRUE, of a GUD name (not given) FALSE; the machine is in
    // mm ($MN_SCALING_SYSTEM_IS_METRIC = 1) and no block search runs ($P_SEARCH = 0).
    let m = sinumerik(
        "DEF REAL HAVE\nR1=0\nIF ISVAR(\"HAVE\") AND NOT ISVAR(\"SCHLEIFEN_AKTIV\")\nR1=R1+1\nENDIF\n\
         IF $MN_SCALING_SYSTEM_IS_METRIC==1\nR1=R1+10\nENDIF\nIF $P_SEARCH\nR1=R1+100\nENDIF\nG0 X=R1\nM30\n",
    )
    .unwrap();
    assert_eq!(m[0].end[Axis::X], 11.0);
    let (line, msg) = sinumerik("DEF INT TNUM\nTNUM=GETT(\"DRILL\")\n").unwrap_err();
    assert_eq!(line, 2);
    assert!(
        msg.contains("`GETT`") && msg.contains("tool list is not given"),
        "{msg}"
    );
}
