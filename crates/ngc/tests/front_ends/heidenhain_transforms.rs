//! HEIDENHAIN cycles 8 MIRROR IMAGE, 11 SCALING and 26 AXIS-SPECIFIC SCALING (TNC 640
//! cycle programming manual, "Coordinate transformation cycles"): positions worked out by
//! hand from w = d + M Rz(rot) S(p) (datum d, mirror M: x' = −x, rotation, scaling
//! S: x' = s x, or cc + f (x − cc) for cycle 26), arcs and compensation turned over by a
//! mirror of one axis, and the refusals.

use ngc::{Motion, Move};

use super::klartext_setup::{in_program, klartext_options, near, read_named, xyz};

fn run(body: &str) -> Result<Vec<Move>, (usize, String)> {
    read_named("t.h", &in_program(body), &klartext_options())
}

fn moves(body: &str) -> Vec<Move> {
    run(body).unwrap_or_else(|e| panic!("{e:?}"))
}

/// An arc's direction (clockwise) and centre X Y.
fn arc(m: &Move) -> (bool, [f64; 2]) {
    match m.motion {
        Motion::Arc {
            clockwise,
            center_mm,
            ..
        } => (clockwise, [center_mm[0], center_mm[1]]),
        other => panic!("not an arc: {other:?}"),
    }
}

#[test]
fn mirror_about_the_shifted_datum_flips_positions_and_arc_direction() {
    // Datum X+50; mirror X: program (10, 5) is at (50 − 10, 5) = (40, 5). The half circle
    // DR+ about the program pole (0, 5) to (−10, 5) goes through program (0, 15): at
    // (40, 5) → (50, 15) → (60, 5), clockwise about (50, 5). Cancelled: (10, 5) → (60, 5).
    let m = moves(
        "2 CYCL DEF 7.0 DATUM SHIFT\n3 CYCL DEF 7.1 X+50\n4 CYCL DEF 8.0 MIRROR IMAGE\n\
         5 CYCL DEF 8.1 X\n6 L X+10 Y+5 Z+0 R0 F100\n7 CC X+0 Y+5\n8 C X-10 Y+5 DR+\n\
         9 CYCL DEF 8.0 MIRROR IMAGE\n10 CYCL DEF 8.1\n11 L X+10 Y+5",
    );
    let ends: Vec<[f64; 3]> = m.iter().map(xyz).collect();
    let at = |p: [f64; 3]| ends.iter().position(|e| near(*e, p));
    let first = at([40.0, 5.0, 0.0]).unwrap_or_else(|| panic!("{ends:?}"));
    assert!(near(ends[first + 1], [60.0, 5.0, 0.0]), "{ends:?}");
    assert_eq!(arc(&m[first + 1]), (true, [50.0, 5.0]));
    assert!(near(*ends.last().unwrap(), [60.0, 5.0, 0.0]), "{ends:?}");
    // Both axes mirrored: a half turn, the direction kept: (−10, −5) + datum.
    let m = moves(
        "2 CYCL DEF 8.0 MIRROR IMAGE\n3 CYCL DEF 8.1 X Y\n4 L X+10 Y+5 Z+0 R0 F100\n\
         5 CC X+0 Y+5\n6 C X-10 Y+5 DR+",
    );
    let n = m.len();
    assert!(
        near(xyz(&m[n - 2]), [-10.0, -5.0, 0.0]),
        "{:?}",
        xyz(&m[n - 2])
    );
    assert!(near(xyz(&m[n - 1]), [10.0, -5.0, 0.0]));
    assert_eq!(arc(&m[n - 1]), (false, [0.0, -5.0]));
}

#[test]
fn mirror_of_one_axis_puts_the_tool_on_the_other_side() {
    // RL along +Y puts a tool of radius 5 at x = −5 in the program; mirrored in X the path
    // runs +Y at x = 0 and the tool is at x = +5 (the TNC's RL becomes RR).
    let m = moves(
        "2 CYCL DEF 8.0 MIRROR IMAGE\n3 CYCL DEF 8.1 X\n4 L X+0 Y-20 Z+0 R0 F100\n\
         5 L X+0 Y+0 RL\n6 L X+0 Y+20\n7 L X+0 Y+40\n8 L X+0 Y+60 R0",
    );
    let along: Vec<[f64; 3]> = m
        .iter()
        .map(xyz)
        .filter(|p| (p[1] - 20.0).abs() < 1e-9)
        .collect();
    assert_eq!(
        along.len(),
        1,
        "{:?}",
        m.iter().map(xyz).collect::<Vec<_>>()
    );
    assert!(near(along[0], [5.0, 20.0, 0.0]), "{along:?}");
}

#[test]
fn mirror_acts_outside_the_rotation() {
    // ROT+30, mirror X: Rz(30°)(10, 0) = (8.660…, 5), mirrored (−8.660…, 5). (A mirror
    // inside the rotation would give (−8.660…, −5).)
    let c = 10.0 * 30f64.to_radians().cos();
    let m = moves(
        "2 CYCL DEF 10.0 ROTATION\n3 CYCL DEF 10.1 ROT+30\n4 CYCL DEF 8.0 MIRROR IMAGE\n\
         5 CYCL DEF 8.1 X\n6 L X+10 Y+0 Z+0 R0 FMAX",
    );
    let last = xyz(m.last().unwrap());
    assert!(near(last, [-c, 5.0, 0.0]), "{last:?}");
}

#[test]
fn a_move_after_the_mirror_starts_from_the_position_in_the_mirrored_frame() {
    // At (10, 0) before the mirror: the program position is then (−10, 0); IX+5 goes to
    // program (−5, 0), at (5, 0).
    let m = moves(
        "2 L X+10 Y+0 Z+0 R0 FMAX\n3 CYCL DEF 8.0 MIRROR IMAGE\n4 CYCL DEF 8.1 X\n5 L IX+5 F100",
    );
    let last = xyz(m.last().unwrap());
    assert!(near(last, [5.0, 0.0, 0.0]), "{last:?}");
}

#[test]
fn scaling_scales_coordinates_radii_and_corners_about_the_datum() {
    // Datum X+10, SCL 2: program (5, 3, 1) at (10 + 10, 6, 2).
    let m = moves(
        "2 CYCL DEF 7.0 DATUM SHIFT\n3 CYCL DEF 7.1 X+10\n4 CYCL DEF 11.0 SCALING\n\
         5 CYCL DEF 11.1 SCL 2\n6 L X+5 Y+3 Z+1 R0 FMAX",
    );
    assert!(near(xyz(m.last().unwrap()), [20.0, 6.0, 2.0]));
    // CR R+5 DR- from (0, 0) to (10, 0), scaled by 2: from (0, 0) to (20, 0) about
    // (10, 0), clockwise (through (10, 10)).
    let m = moves(
        "2 CYCL DEF 11.0 SCALING\n3 CYCL DEF 11.1 SCL2\n4 L X+0 Y+0 Z+0 R0 F100\n\
         5 CR X+10 Y+0 R+5 DR-",
    );
    let last = m.last().unwrap();
    assert!(near(xyz(last), [20.0, 0.0, 0.0]));
    assert_eq!(arc(last), (true, [10.0, 0.0]));
    // RND R2 at the corner (10, 0) of +X then +Y, scaled by 0.5: the corner at (5, 0), the
    // rounding of radius 1 from (4, 0) to (5, 1) about (4, 1), counter-clockwise.
    let m = moves(
        "2 CYCL DEF 11.0 SCALING\n3 CYCL DEF 11.1 SCL 0.5\n4 L X+0 Y+0 Z+0 R0 F100\n\
         5 L X+10 Y+0\n6 RND R2\n7 L X+10 Y+10",
    );
    let k = m
        .iter()
        .position(|m| matches!(m.motion, Motion::Arc { .. }))
        .expect("the rounding arc");
    assert!(
        near(xyz(&m[k - 1]), [4.0, 0.0, 0.0]),
        "{:?}",
        xyz(&m[k - 1])
    );
    assert!(near(xyz(&m[k]), [5.0, 1.0, 0.0]));
    assert_eq!(arc(&m[k]), (false, [4.0, 1.0]));
    assert!(near(xyz(&m[k + 1]), [5.0, 5.0, 0.0]));
    // SCL 1 ends it.
    let m = moves(
        "2 CYCL DEF 11.0 SCALING\n3 CYCL DEF 11.1 SCL 3\n4 CYCL DEF 11.0 SCALING\n\
         5 CYCL DEF 11.1 SCL 1\n6 L X+5 Y+3 Z+1 R0 FMAX",
    );
    assert!(near(xyz(m.last().unwrap()), [5.0, 3.0, 1.0]));
}

#[test]
fn axis_specific_scaling_about_its_centre_inside_the_rotation() {
    // X × 2, Y × 0.5 about (10, 20): program (20, 30) at (10 + 2·10, 20 + 0.5·10).
    let m = moves(
        "2 CYCL DEF 26.0 AXIS-SPECIFIC SCALING\n3 CYCL DEF 26.1 X2 Y0.5 CCX+10 CCY+20\n\
         4 L X+20 Y+30 Z+0 R0 FMAX",
    );
    assert!(near(xyz(m.last().unwrap()), [30.0, 25.0, 0.0]));
    // ROT+90 with X × 2: (5, 0) scaled to (10, 0), then turned to (0, 10).
    let m = moves(
        "2 CYCL DEF 10.0 ROTATION\n3 CYCL DEF 10.1 ROT+90\n4 CYCL DEF 26.0 AXIS-SPECIFIC SCALING\n\
         5 CYCL DEF 26.1 X2\n6 L X+5 Y+0 Z+0 R0 FMAX",
    );
    assert!(
        near(xyz(m.last().unwrap()), [0.0, 10.0, 0.0]),
        "{:?}",
        xyz(m.last().unwrap())
    );
    // An arc in X Y with different factors: refused, naming the rule.
    let (line, msg) = run(
        "2 CYCL DEF 26.0 AXIS-SPECIFIC SCALING\n3 CYCL DEF 26.1 X2 Y0.5\n\
         4 L X+0 Y+0 Z+0 R0 F100\n5 CC X+5 Y+0\n6 C X+10 Y+0 DR+",
    )
    .unwrap_err();
    assert_eq!(line, 7);
    assert!(msg.contains("different factors"), "{msg}");
}

#[test]
fn bore_milling_under_scaling_scales_the_bore_not_the_tool() {
    // SCL 2: a Ø10 bore at program (5, 5) is a Ø20 bore at (10, 10); the Ø10 tool's helix
    // radius is 10 − 5 = 5. Depth −2.5 → −5, set-up clearance 1 → 2, Q204 5 → 10.
    let m = moves(
        "2 CYCL DEF 11.0 SCALING\n3 CYCL DEF 11.1 SCL 2\n4 L X+5 Y+5 Z+10 R0 FMAX\n\
         5 CYCL DEF 208 BORE MILLING ~\n Q200=+1 ~\n Q201=-2.5 ~\n Q206=+300 ~\n Q334=+1 ~\n \
         Q203=+0 ~\n Q204=+5 ~\n Q335=+10 ~\n Q351=-1\n6 CYCL CALL",
    );
    let arcs: Vec<&Move> = m
        .iter()
        .filter(|m| matches!(m.motion, Motion::Arc { .. }))
        .collect();
    assert_eq!(arcs.len(), 6);
    for a in &arcs[1..5] {
        let (cw, c) = arc(a);
        let p = xyz(a);
        assert!(cw && near([c[0], c[1], 0.0], [10.0, 10.0, 0.0]), "{c:?}");
        assert!(
            ((p[0] - 10.0).hypot(p[1] - 10.0) - 5.0).abs() < 1e-9,
            "{p:?}"
        );
    }
    assert!((xyz(arcs[4])[2] + 5.0).abs() < 1e-9);
    assert!(near(xyz(m.last().unwrap()), [10.0, 10.0, 10.0]));
}

#[test]
fn transformations_mtsim_does_not_read_are_refused_by_rule() {
    for (body, needle) in [
        ("2 CYCL DEF 8.0 MIRROR IMAGE\n3 CYCL DEF 8.1 Z", "spindle axis"),
        ("2 CYCL DEF 8.0 MIRROR IMAGE\n3 CYCL DEF 8.1 X C", "rotary"),
        ("2 CYCL DEF 11.0 SCALING\n3 CYCL DEF 11.1 SCL 0", "0.000001"),
        ("2 CYCL DEF 26.0 AXIS-SPECIFIC SCALING\n3 CYCL DEF 26.1 X", "without its factor"),
        (
            "2 CYCL DEF 11.0 SCALING\n3 CYCL DEF 11.1 SCL 2\n4 CYCL DEF 26.0 AXIS-SPECIFIC SCALING\n\
             5 CYCL DEF 26.1 X2",
            "together",
        ),
        (
            "2 L X+0 Y+0 Z+0 R0 F100\n3 L X+10 RL\n4 CYCL DEF 8.0 MIRROR IMAGE\n5 CYCL DEF 8.1 X",
            "radius compensation",
        ),
    ] {
        let (_, msg) = run(body).unwrap_err();
        assert!(msg.contains(needle), "{body}: {msg}");
    }
}
