//! The HEIDENHAIN Klartext front end: each construct's moves against values worked out by
//! hand, the refusals that name the construct, and the bounds (nesting, loops, lines).

use std::path::Path;

use ngc::{read_str_with, Axis, Error, Motion, Move, Options, RotaryTable, Tool};

use super::klartext_setup::{in_program as program, klartext_options as opts};

fn moves_with(body: &str, o: &Options) -> Vec<Move> {
    read_str_with(Path::new("t.h"), &program(body), o)
        .collect::<Result<_, _>>()
        .unwrap_or_else(|e| panic!("{e}"))
}

fn moves(body: &str) -> Vec<Move> {
    moves_with(body, &opts())
}

/// (line, column, message) of the error the program stops with.
fn error(body: &str) -> (usize, usize, String) {
    let e = read_str_with(Path::new("t.h"), &program(body), &opts())
        .find_map(Result::err)
        .expect("an error");
    match e {
        Error::Syntax(s) => (s.line, s.column, s.message),
        other => panic!("{other}"),
    }
}

fn xy(m: &Move) -> [f64; 2] {
    [m.end[Axis::X], m.end[Axis::Y]]
}

fn near(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9
}

/// An arc's direction and centre X Y.
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
fn fmax_is_for_its_block_alone_and_f_stays() {
    let m = moves("2 L X+0 Y+0 Z+5 R0 F300\n3 L X+10 FMAX\n/4 L X+99\n4 L X+20");
    assert_eq!(m[1].motion, Motion::Rapid);
    assert_eq!(m[2].motion, Motion::Linear);
    assert_eq!(m[2].feed, ngc::Feed::PerMinute(300.0));
}

#[test]
fn polar_line_and_arc_about_the_pole() {
    // LP PR+20 PA+30 from the pole (5, 5): (5 + 20 cos 30°, 5 + 20 sin 30°) = (22.3205…, 15).
    let m =
        moves("2 L X+0 Y+0 R0 F100\n3 CC X+5 Y+5\n4 LP PR+20 PA+30\n5 CP IPA+60 DR+\n6 LP IPR-10");
    assert!(near(xy(&m[1]), [5.0 + 20.0 * 3f64.sqrt() / 2.0, 15.0]));
    // CP IPA+60 to 90°: (5, 25), counter-clockwise about the pole.
    assert!(near(xy(&m[2]), [5.0, 25.0]));
    let (clockwise, centre) = arc(&m[2]);
    assert!(!clockwise && near(centre, [5.0, 5.0]), "{centre:?}");
    // IPR-10: radius 10 at 90°.
    assert!(near(xy(&m[3]), [5.0, 15.0]));
}

#[test]
fn ct_is_tangent_to_the_line_before_it() {
    // From (20, 0) heading +X to (30, 10): centre (20, 10), counter-clockwise.
    let m = moves("2 L X+0 Y+0 R0 F100\n3 L X+20\n4 CT X+30 Y+10");
    let (clockwise, centre) = arc(&m[2]);
    assert!(!clockwise && near(centre, [20.0, 10.0]), "{centre:?}");
}

#[test]
fn rnd_and_chf_cut_the_corner() {
    // A 90° corner at (40, 0): RND R5 touches the lines 5 from the corner (r tan 45°).
    let m = moves("2 L X+0 Y+0 R0 F100\n3 L X+40\n4 RND R5\n5 L Y+40");
    assert!(near(xy(&m[1]), [35.0, 0.0]));
    assert!(near(xy(&m[2]), [40.0, 5.0]));
    let (clockwise, centre) = arc(&m[2]);
    assert!(!clockwise && near(centre, [35.0, 5.0]), "{centre:?}");
    assert!(near(xy(&m[3]), [40.0, 40.0]));
    // A 120° turn (60° between the lines): RND R2 touches them 2 tan 60° = 3.4641 away.
    let m = moves("2 L X+0 Y+0 R0 F100\n3 L X+10\n4 RND R2\n5 L X+5 Y+8.660254037844386");
    let t = 2.0 * 60f64.to_radians().tan();
    assert!(near(xy(&m[1]), [10.0 - t, 0.0]));
    assert!(near(xy(&m[2]), [10.0 - t * 0.5, t * 3f64.sqrt() / 2.0]));
    let m = moves("2 L X+0 Y+0 R0 F100\n3 L X+40\n4 CHF 5\n5 L Y+40");
    assert!(near(xy(&m[1]), [35.0, 0.0]));
    assert!(near(xy(&m[2]), [40.0, 5.0]));
    assert_eq!(m[2].motion, Motion::Linear);
}

#[test]
fn q_parameters_fn_and_formulas() {
    let m = moves(
        "2 FN 0: Q1 = +3\n3 FN 8: Q2 = +Q1 LEN +4\n4 FN 13: Q3 = +0 ANG +1\n\
         5 Q4 = (Q2 + 1) * 2 ^ 2 - SQRT(16) / 4\n6 L X+Q2 Y+Q3 Z+Q4 R0 FMAX",
    );
    // 3 LEN 4 = 5; 0 ANG 1 = 90°; (5 + 1) · 4 − 1 = 23.
    assert_eq!(
        [m[0].end[Axis::X], m[0].end[Axis::Y], m[0].end[Axis::Z]],
        [5.0, 90.0, 23.0]
    );
}

#[test]
fn fn_jumps_loop_to_a_label() {
    // Q1 counts 1..3: three moves of IX+10.
    let m = moves(
        "2 L X+0 Y+0 R0 F100\n3 FN 0: Q1 = +0\n4 LBL 1\n5 L IX+10\n6 FN 1: Q1 = +Q1 + +1\n\
         7 FN 12: IF +Q1 LT +3 GOTO LBL 1\n8 L Y+5",
    );
    assert_eq!(m.len(), 5);
    assert_eq!(m[3].end[Axis::X], 30.0);
}

#[test]
fn subprograms_and_section_repeats() {
    let m = moves(
        "2 L X+0 Y+0 R0 F100\n3 CALL LBL 5\n4 CALL LBL 5 REP 2\n5 LBL 7\n6 L IY+1\n\
         7 CALL LBL 7 REP 1\n8 M30\n9 LBL 5\n10 L IX+1\n11 LBL 0",
    );
    // One call, then two passes of the subprogram; the section 6 runs twice.
    let ends: Vec<_> = m.iter().map(|m| xy(m)).collect();
    assert_eq!(
        ends[1..],
        [[1.0, 0.0], [2.0, 0.0], [3.0, 0.0], [3.0, 1.0], [3.0, 2.0]]
    );
}

#[test]
fn a_called_program_runs_to_its_end_then_the_caller_goes_on() {
    let dir = std::env::temp_dir().join(format!("ngc-klartext-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("SUB.h"),
        "0 BEGIN PGM SUB MM\n1 L IX+7\n2 END PGM SUB MM\n",
    )
    .unwrap();
    let main = dir.join("MAIN.h");
    std::fs::write(
        &main,
        program("2 L X+0 Y+0 R0 F100\n3 CALL PGM SUB\n4 L Y+1"),
    )
    .unwrap();
    let m: Vec<_> = ngc::read_file_with(&main, &opts())
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(xy(&m[1]), [7.0, 0.0]);
    assert_eq!(xy(&m[2]), [7.0, 1.0]);
    std::fs::write(&main, program("3 CALL PGM NOWHERE")).unwrap();
    let e = ngc::read_file_with(&main, &opts())
        .unwrap()
        .find_map(Result::err)
        .unwrap();
    assert!(e.to_string().contains("CALL PGM NOWHERE"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn drilling_cycle_200_pecks_as_the_manual_draws_it() {
    let m = moves(
        "2 L X+5 Y+5 Z+20 R0 FMAX\n3 CYCL DEF 200 DRILLING ~\n Q200=+2 ;SET-UP ~\n Q201=-7 ~\n \
         Q206=+100 ~\n Q202=+3 ~\n Q210=+0 ~\n Q203=+1 ~\n Q204=+10 ~\n Q211=+0.25\n4 CYCL CALL",
    );
    let z: Vec<_> = m[1..]
        .iter()
        .map(|m| (m.motion == Motion::Rapid, m.end[Axis::Z]))
        .collect();
    // Surface 1, clearance to 3, pecks of 3 to -6, a = 2 above the depth reached; 2nd
    // set-up clearance 11.
    let expected = [
        (true, 3.0),
        (false, -2.0),
        (true, 3.0),
        (true, 0.0),
        (false, -5.0),
        (true, 3.0),
        (true, -3.0),
        (false, -6.0),
    ];
    assert_eq!(z[..8], expected);
    assert_eq!(m[9].motion, Motion::Dwell { seconds: 0.25 });
    assert_eq!(z[9..], [(true, 3.0), (true, 11.0)]);
}

#[test]
fn rigid_tapping_207_feeds_at_pitch_times_speed_in_and_out() {
    // S500 × 1.25 mm = 625 mm/min, to Q203 + Q201 = -10 and back to 2, then 10.
    let m = moves(
        "2 TOOL CALL 1 Z S500\n3 L X+5 Y+5 Z+20 R0 FMAX\n4 CYCL DEF 207 RIGID TAPPING NEW ~\n \
         Q200=+2 ~\n Q201=-10 ~\n Q239=+1.25 ~\n Q203=+0 ~\n Q204=+10\n5 CYCL CALL",
    );
    let z: Vec<_> = m[1..]
        .iter()
        .map(|m| (m.motion == Motion::Rapid, m.end[Axis::Z], m.feed))
        .collect();
    assert_eq!(z[0].1, 2.0);
    assert_eq!(z[1], (false, -10.0, ngc::Feed::PerMinute(625.0)));
    assert_eq!(z[2], (false, 2.0, ngc::Feed::PerMinute(625.0)));
    assert_eq!((z[3].0, z[3].1), (true, 10.0));
}

#[test]
fn datum_shift_and_rotation_move_the_program_frame() {
    // Datum (10, 5), then 90°: program (1, 0) is at (10, 6).
    let m = moves(
        "2 CYCL DEF 7.0 DATUM SHIFT\n3 CYCL DEF 7.1 X+10\n4 CYCL DEF 7.2 Y+5\n\
         5 CYCL DEF 10.0 ROTATION\n6 CYCL DEF 10.1 ROT+90\n7 L X+1 Y+0 Z+0 R0 FMAX",
    );
    assert!(near(xy(&m[0]), [10.0, 6.0]), "{:?}", xy(&m[0]));
}

#[test]
fn plane_spatial_euler_and_vector_give_the_same_tilt() {
    let table = Options {
        table: Some(RotaryTable {
            tilt: Axis::A,
            pivot_mm: [0.0; 3],
        }),
        ..opts()
    };
    // Tilted 30° about X four ways: the table turns the same each time.
    let turned = |plane: &str| {
        let m = moves_with(
            &format!("2 L X+0 Y+0 Z+50 A+0 C+0 R0 FMAX\n3 {plane}"),
            &table,
        );
        let last = m.last().unwrap().end;
        [last[Axis::A], last[Axis::C]]
    };
    // The tool axis normal to the plane: A ±30° (C turns the table to match).
    let spatial = turned("PLANE SPATIAL SPA+30 SPB+0 SPC+0 TURN FMAX");
    assert!((spatial[0].abs() - 30.0).abs() < 1e-9, "{spatial:?}");
    for plane in [
        "PLANE EULER EULPR+0 EULNU+30 EULROT+0 TURN FMAX",
        "PLANE VECTOR BX+1 BY+0 BZ+0 NX+0 NY-0.5 NZ+0.8660254037844386 TURN FMAX",
        "PLANE RELATIV SPA+30 TURN FMAX",
    ] {
        let got = turned(plane);
        assert!(near(got, spatial), "{plane}: {got:?} against {spatial:?}");
    }
    // Without a rotary table TURN is refused by name; STAY is read.
    let (line, _, msg) = error("2 PLANE SPATIAL SPA+30 SPB+0 SPC+0 TURN");
    assert_eq!(line, 3);
    assert!(msg.contains("PLANE") && msg.contains("TURN"), "{msg}");
    moves("2 PLANE SPATIAL SPA+30 SPB+0 SPC+0 STAY\n3 PLANE RESET STAY");
}

#[test]
fn unsupported_constructs_are_refused_by_name_at_their_line() {
    for (body, name) in [
        ("2 APPR PLT PR+10 PA+10 LEN 5 RL", "APPR PLT"),
        ("2 TCH PROBE 400", "TCH PROBE"),
        ("2 CYCL DEF 204 BACK BORING", "CYCL DEF 204 BACK BORING"),
        ("2 FN 18: SYSREAD Q1 = ID270", "FN 18"),
        ("2 FL X+10", "FL"),
        ("2 L X+10 M92", "M92"),
        ("2 PATTERN DEF", "PATTERN DEF"),
    ] {
        let (line, _, msg) = error(body);
        assert_eq!(line, 3, "{body}");
        assert!(msg.contains(name), "{body}: {msg}");
        assert!(!msg.contains("unexpected character"), "{msg}");
    }
}

/// A label mark is `LBL n` or `LBL "name"` and nothing else: a repeat written on the mark,
/// or a mark without its label, is refused at its line, never read as a mark.
#[test]
fn a_label_mark_with_words_after_it_or_none_is_refused() {
    for (body, column, said) in [
        ("2 LBL 1 REP 3", 9, "`REP` after `LBL 1`"),
        ("2 LBL", 3, "expected a label number"),
        ("2 LBL X", 7, "`X`: expected a label number"),
    ] {
        let (line, col, msg) = error(body);
        assert_eq!((line, col), (3, column), "{body}: {msg}");
        assert!(msg.contains(said), "{body}: {msg}");
    }
    // Named marks may hold spaces.
    assert!(!moves("2 LBL \"A B\"\n3 L X+1 R0 F100\n4 LBL 0").is_empty());
}

#[test]
fn endless_loops_and_deep_calls_stop_at_the_limits() {
    let o = Options {
        max_blocks: 1000,
        ..opts()
    };
    let text = program("2 LBL 1\n3 L IX+1 F100\n4 FN 9: IF +0 EQU +0 GOTO LBL 1");
    let e = read_str_with(Path::new("t.h"), &text, &o)
        .find_map(Result::err)
        .unwrap();
    assert!(e.to_string().contains("1000"), "{e}");
    let o = Options {
        max_call_depth: 2,
        ..opts()
    };
    let text = program("2 CALL LBL 1\n3 M30\n4 LBL 1\n5 CALL LBL 2\n6 LBL 0\n7 LBL 2\n8 CALL LBL 3\n9 LBL 0\n10 LBL 3\n11 LBL 0");
    let e = read_str_with(Path::new("t.h"), &text, &o)
        .find_map(Result::err)
        .unwrap();
    assert!(e.to_string().contains("nested more than 2"), "{e}");
}

/// Cycle 1 PECKING from Z5 with set-up clearance 5 (surface Z0), depth -7, plunging depth
/// 3, dwell 0.5 s, F100 (TNC 426/430 manual, "PECKING (Cycle 1)"; advanced stop distance
/// t = 0.6 mm for a hole up to 30 mm): feed to -3, rapid to 5, rapid to -3 + 0.6 = -2.4,
/// feed to -6, rapid to 5, rapid to -5.4, feed to -7, dwell, rapid to 5.
#[test]
fn cycle_1_pecks_as_the_manual_describes() {
    let m = moves(
        "2 L X+10 Y+20 Z+5 R0 FMAX\n3 CYCL DEF 1.0 PECKING\n4 CYCL DEF 1.1 DIST5\n5 CYCL DEF 1.2 DEPTH-7\n6 CYCL DEF 1.3 PLNGNG3\n7 CYCL DEF 1.4 DWELL0.5\n8 CYCL DEF 1.5 F100\n9 L M99",
    );
    let path: Vec<(ngc::MoveKind, f64)> = m
        .iter()
        .skip_while(|m| m.line < 10)
        .map(|m| (m.kind(), m.end[Axis::Z]))
        .filter(|(k, _)| *k != ngc::MoveKind::Dwell)
        .collect();
    use ngc::MoveKind::{Feed, Rapid};
    let want = [
        (Rapid, 5.0),
        (Feed, -3.0),
        (Rapid, 5.0),
        (Rapid, -2.4),
        (Feed, -6.0),
        (Rapid, 5.0),
        (Rapid, -5.4),
        (Feed, -7.0),
        (Rapid, 5.0),
    ];
    assert_eq!(path.len(), want.len(), "{path:?}");
    for (got, want) in path.iter().zip(want) {
        assert!(got.0 == want.0 && (got.1 - want.1).abs() < 1e-9, "{path:?}");
    }
    let dwell: Vec<_> = m
        .iter()
        .filter_map(|m| match m.motion {
            Motion::Dwell { seconds } => Some(seconds),
            _ => None,
        })
        .collect();
    assert_eq!(dwell, [0.5]);
    assert!(m.iter().all(|m| near(xy(m), [10.0, 20.0]) || m.line < 3));
}

/// FN 18 SYSREAD: ID270 the position in the active system, ID240 the REF position, ID50
/// the tool table (T1: length 0, Ø10 → R 5), ID20 NR1 the tool; others refused by ID.
#[test]
fn fn_18_reads_the_position_and_tool_data() {
    let m = moves(
        "2 CYCL DEF 7.0 DATUM SHIFT\n3 CYCL DEF 7.1 X+100\n4 L X+10 Y+20 Z+30 R0 FMAX\n5 FN 18: SYSREAD Q1 = ID270 NR1 IDX1\n6 FN18: SYSREAD Q2 = ID240 NR1 IDX1\n7 FN 18: SYSREAD Q3 = ID50 NR2 IDX1\n8 FN 18: SYSREAD Q4 = ID20 NR1\n9 L X+Q1 Y+Q2 Z+Q3 FMAX\n10 L X+Q4 FMAX",
    );
    // Q1 = 10 (work), Q2 = 110 (REF: the datum shift 100 added), Q3 = 5, Q4 = 1; the
    // datum shift puts the program's X+10 at machine X110.
    let n = m.len();
    assert!(near(xy(&m[n - 2]), [110.0, 110.0]), "{:?}", m[n - 2].end);
    assert!((m[n - 2].end[Axis::Z] - 5.0).abs() < 1e-9);
    assert!((m[n - 1].end[Axis::X] - 101.0).abs() < 1e-9);
    let (line, _, message) = error("2 FN 18: SYSREAD Q1 = ID990 NR1");
    assert_eq!(line, 3);
    assert!(
        message.contains("ID990") && message.contains("FN 18: SYSREAD"),
        "{message}"
    );
}

/// `LBL1` glued to its number is a label, and `CALL LBL 1 REP 2/2` repeats twice (the
/// number after the slash is the count the TNC shows left).
#[test]
fn glued_labels_and_rep_with_a_slash_are_read() {
    let m = moves("2 L X+0 Y+0 Z+0 R0 FMAX\n3 LBL1\n4 L IX+1 F100\n5 CALL LBL 1 REP 2/2");
    let xs: Vec<f64> = m.iter().skip(1).map(|m| m.end[Axis::X]).collect();
    assert_eq!(xs, [1.0, 2.0, 3.0]);
}

/// `FQ53` is the feed held in Q53, as `F+Q53`.
#[test]
fn a_feed_in_a_q_parameter_is_read() {
    let m = moves("2 Q53 = 250\n3 L X+0 Y+0 Z+5 R0 FMAX\n4 L X+10 FQ53\n5 L X+30 F+Q53");
    let feeds: Vec<Option<f64>> = m.iter().skip(1).map(|m| m.feed.rate()).collect();
    assert_eq!(feeds, [Some(250.0), Some(250.0)]);
}

/// A straight line with no F in effect (none in the block, none before it, no FMAX) is the
/// reader's error at its line, so no feed move leaves the reader without a feed.
#[test]
fn a_feed_move_with_no_feed_in_effect_is_an_error_at_its_line() {
    // (Source line 3: the program's BEGIN PGM and TOOL CALL come first.)
    let (line, _, message) = error("2 L X+10 Y+0 Z+0 R0");
    assert_eq!(line, 3, "{message}");
    // With an F before it, the feed move carries that number; the FMAX move carries none.
    let m = moves("2 L X+0 Y+0 Z+5 R0 FMAX\n3 L X+10 F250\n4 L X+20");
    assert_eq!(m[0].feed, ngc::Feed::None);
    assert_eq!(m[1].feed, ngc::Feed::PerMinute(250.0));
    assert_eq!(m[2].feed, ngc::Feed::PerMinute(250.0));
}

/// Options with a tool of diameter 0: the compensated path is the programmed one, so the
/// approach and departure points are the tool's.
fn zero_radius() -> Options {
    Options {
        tools: vec![Tool {
            number: 1,
            length_mm: 0.0,
            diameter_mm: 0.0,
        }],
        ..opts()
    }
}

/// The TNC 640 manual's approach paths ("Contour approach and departure"), each from
/// P_S to the auxiliary point P_H and on to the first contour point P_A (10, 20), whose
/// element runs +X (the tool's side under RR is −Y).
#[test]
fn appr_lt_ln_ct_lct_reach_the_contour_through_the_auxiliary_point() {
    let o = zero_radius();
    // LT: P_H 15 back along the first element's tangent (+X): (−5, 20). P_S → P_H at the
    // feed before (300), P_H → P_A at F100 with Z.
    let m = moves_with(
        "2 L X+40 Y+10 Z+0 R0 F300\n3 APPR LT X+10 Y+20 Z-10 LEN15 RR F100\n4 L X+30 Y+20",
        &o,
    );
    assert!(near(xy(&m[1]), [-5.0, 20.0]), "{:?}", m[1].end);
    assert_eq!(m[1].feed, ngc::Feed::PerMinute(300.0));
    assert!(near(xy(&m[2]), [10.0, 20.0]) && (m[2].end[Axis::Z] + 10.0).abs() < 1e-9);
    assert_eq!(m[2].feed, ngc::Feed::PerMinute(100.0));
    assert!(near(xy(&m[3]), [30.0, 20.0]));
    // LN: P_H LEN + tool radius (0) off the contour on the tool's side: (10, 5).
    let m = moves_with(
        "2 L X+40 Y+10 R0 F300\n3 APPR LN X+10 Y+20 LEN15 RR F100\n4 L X+30 Y+20",
        &o,
    );
    assert!(near(xy(&m[1]), [10.0, 5.0]) && near(xy(&m[2]), [10.0, 20.0]));
    // CT, R+10 under RR: centre (10, 10) on the tool's side, clockwise; CCA 180 back from
    // P_A: P_H = (10, 0). After FMAX, P_S → P_H is rapid.
    let m = moves_with(
        "2 L X+40 Y+10 R0 FMAX\n3 APPR CT X+10 Y+20 CCA180 R+10 RR F100\n4 L X+30 Y+20",
        &o,
    );
    assert_eq!(m[1].motion, Motion::Rapid);
    assert!(near(xy(&m[1]), [10.0, 0.0]), "{:?}", m[1].end);
    let (clockwise, centre) = arc(&m[2]);
    assert!(clockwise && near(centre, [10.0, 10.0]) && near(xy(&m[2]), [10.0, 20.0]));
    // LCT, R10 under RR: centre (10, 10), clockwise. From P_S (10, −10), 20 below the
    // centre, the tangent touches at −90° − acos(10/20) = −150°: (10 − 5√3, 5).
    let m = moves_with(
        "2 L X+10 Y-10 R0 F300\n3 APPR LCT X+10 Y+20 R10 RR F100\n4 L X+30 Y+20",
        &o,
    );
    assert!(
        near(xy(&m[1]), [10.0 - 5.0 * 3f64.sqrt(), 5.0]),
        "{:?}",
        m[1].end
    );
    assert_eq!(m[1].feed, ngc::Feed::PerMinute(100.0));
    let (clockwise, centre) = arc(&m[2]);
    assert!(clockwise && near(centre, [10.0, 10.0]) && near(xy(&m[2]), [10.0, 20.0]));
    // The first element an arc: C about (10, 30) counter-clockwise from P_A heads +X.
    let m = moves_with(
        "2 L X+40 Y+10 R0 F300\n3 APPR LT X+10 Y+20 LEN15 RR F100\n4 CC X+10 Y+30\n5 C X+20 Y+30 DR+",
        &o,
    );
    assert!(near(xy(&m[1]), [-5.0, 20.0]), "{:?}", m[1].end);
}

/// Departure from the last contour point P_E (30, 20), the last element running +X under
/// RR (the tool's side −Y).
#[test]
fn dep_lt_ln_ct_lct_leave_the_contour_as_the_manual_draws_them() {
    let o = zero_radius();
    let body = |dep: &str| {
        format!("2 L X+0 Y+20 R0 F300\n3 APPR LT X+10 Y+20 LEN10 RR F100\n4 L X+30 Y+20\n5 {dep}\n6 L Z+50 R0 FMAX")
    };
    // LT: LEN 12.5 on along +X.
    let m = moves_with(&body("DEP LT LEN12.5 R0 F200"), &o);
    assert!(near(xy(&m[4]), [42.5, 20.0]), "{:?}", m[4].end);
    assert_eq!(m[4].feed, ngc::Feed::PerMinute(200.0));
    // LN: LEN 20 (+ radius 0) to the tool's side: (30, 0).
    let m = moves_with(&body("DEP LN LEN+20 F200"), &o);
    assert!(near(xy(&m[4]), [30.0, 0.0]), "{:?}", m[4].end);
    // CT, R+8: centre (30, 12), clockwise 180°: (30, 4).
    let m = moves_with(&body("DEP CT CCA180 R+8 F200"), &o);
    let (clockwise, centre) = arc(&m[4]);
    assert!(clockwise && near(centre, [30.0, 12.0]) && near(xy(&m[4]), [30.0, 4.0]));
    // LCT to (46, 12), 16 right of the centre (30, 12): the arc leaves at 60° (acos(8/16)),
    // (34, 12 + 4√3), then a line to P_N.
    let m = moves_with(&body("DEP LCT X+46 Y+12 R8 R0 F200"), &o);
    let (clockwise, centre) = arc(&m[4]);
    assert!(clockwise && near(centre, [30.0, 12.0]), "{centre:?}");
    assert!(
        near(xy(&m[4]), [34.0, 12.0 + 4.0 * 3f64.sqrt()]),
        "{:?}",
        m[4].end
    );
    assert!(near(xy(&m[5]), [46.0, 12.0]) && m[5].motion == Motion::Linear);
}

#[test]
fn appr_and_dep_refuse_what_the_manual_does_not_allow() {
    for (body, said) in [
        (
            "2 L X+0 Y+0 R0 F100\n3 APPR CT X+10 Y+20 CCA90 R+5 R0\n4 L X+20",
            "with R0",
        ),
        (
            "2 L X+0 Y+0 R0 F100\n3 APPR LT X+10 Y+20 RL\n4 L X+20",
            "LEN",
        ),
        (
            "2 L X+0 Y+0 R0 F100\n3 APPR LT X+10 Y+20 LEN5 RL\n4 M3",
            "after APPR",
        ),
        ("2 DEP LT LEN5", "no contour element"),
        (
            "2 L X+0 Y+0 R0 F100\n3 APPR LT X+10 Y+20 LEN5 RL\n4 END PGM T MM",
            "`END` after APPR",
        ),
        // A file that ends without END PGM, its APPR waiting.
        (
            "0 BEGIN PGM T MM\n1 APPR LT X+10 Y+20 LEN5 RL",
            "ends after the APPR",
        ),
        (
            "2 L X+0 Y+0 R0 F100\n3 APPR CT X+10 Y+20 CCA400 R+5 RL\n4 L X+20",
            "360",
        ),
    ] {
        let text = match body.starts_with("0 BEGIN") {
            true => format!("{body}\n"),
            false => program(body),
        };
        let e = read_str_with(Path::new("t.h"), &text, &zero_radius())
            .find_map(Result::err)
            .expect("an error");
        assert!(e.to_string().contains(said), "{body}: {e}");
    }
}

/// `CYCL CALL POS`: cycle 200 at each position, its Z an added shift of the surface
/// Q203 (CP "Calling cycles"); above the surface the plane first, below it up the tool
/// axis to the set-up clearance first.
#[test]
fn cycl_call_pos_runs_the_cycle_at_the_position_with_its_positioning_logic() {
    let m = moves(
        "2 L X+5 Y+5 Z+20 R0 FMAX\n3 CYCL DEF 200 DRILLING ~\n Q200=+2 ~\n Q201=-7 ~\n \
         Q206=+100 ~\n Q202=+7 ~\n Q210=+0 ~\n Q203=+0 ~\n Q204=+10 ~\n Q211=+0\n\
         4 CYCL CALL POS X+30 Y+40 Z+1 FMAX\n5 CYCL CALL POS X+50 Y+40 Z-5 FMAX\n\
         6 L Z-20 FMAX\n7 CYCL CALL POS X+70 Y+40 Z+0 FMAX",
    );
    let mut path: Vec<(bool, [f64; 3])> = Vec::new();
    for mv in &m[1..] {
        let p = [mv.end[Axis::X], mv.end[Axis::Y], mv.end[Axis::Z]];
        if path.last().map_or(true, |l| l.1 != p) && mv.motion != (Motion::Dwell { seconds: 0.0 }) {
            path.push((mv.motion == Motion::Rapid, p));
        }
    }
    // Surface 0 + 1: the plane first at Z 20, then clearance 3, depth 1 - 7, back to 3,
    // second clearance 1 + 10.
    // Surface −5: the plane at 11, then −3, −12, −3, 5. Then down to −20: below the
    // surface 0, up to its clearance 2 first, then the plane, depth −7, 2, 10.
    let want = [
        (true, [30.0, 40.0, 20.0]),
        (true, [30.0, 40.0, 3.0]),
        (false, [30.0, 40.0, -6.0]),
        (true, [30.0, 40.0, 3.0]),
        (true, [30.0, 40.0, 11.0]),
        (true, [50.0, 40.0, 11.0]),
        (true, [50.0, 40.0, -3.0]),
        (false, [50.0, 40.0, -12.0]),
        (true, [50.0, 40.0, -3.0]),
        (true, [50.0, 40.0, 5.0]),
        (true, [50.0, 40.0, -20.0]),
        (true, [50.0, 40.0, 2.0]),
        (true, [70.0, 40.0, 2.0]),
        (false, [70.0, 40.0, -7.0]),
        (true, [70.0, 40.0, 2.0]),
        (true, [70.0, 40.0, 10.0]),
    ];
    assert_eq!(path.len(), want.len(), "{path:?}");
    for (got, want) in path.iter().zip(want) {
        let close = (0..3).all(|k| (got.1[k] - want.1[k]).abs() < 1e-9);
        assert!(got.0 == want.0 && close, "{path:?}");
    }
    // All three coordinates are required.
    let (line, _, msg) = error("2 CYCL DEF 200 DRILLING\n3 CYCL CALL POS X+1 Y+2");
    assert!(line == 4 && msg.contains("X, Y and Z"), "{msg}");
}

/// The bottom of each hole cycle 200 drills (its feed moves' ends) for `pattern`.
fn holes(pattern: &str) -> Vec<[f64; 3]> {
    let m = moves(&format!(
        "2 L X+0 Y+0 Z+20 R0 FMAX\n3 CYCL DEF 200 DRILLING ~\n Q200=+2 ~\n Q201=-5 ~\n \
         Q206=+100 ~\n Q202=+5 ~\n Q210=+0 ~\n Q203=+0 ~\n Q204=+10 ~\n Q211=+0\n\
         4 PATTERN DEF ~\n{pattern}\n5 CYCL CALL PAT FMAX"
    ));
    m.iter()
        .filter(|m| m.motion == Motion::Linear)
        .map(|m| [m.end[Axis::X], m.end[Axis::Y], m.end[Axis::Z]])
        .collect()
}

fn same(got: &[[f64; 3]], want: &[[f64; 3]]) -> bool {
    got.len() == want.len()
        && got
            .iter()
            .zip(want)
            .all(|(g, w)| (0..3).all(|k| (g[k] - w[k]).abs() < 1e-9))
}

/// PATTERN DEF with CYCL CALL PAT: the cycle at every point, in order (KP "Pattern
/// definition PATTERN DEF"), the pattern's Z an added shift of the surface.
#[test]
fn cycl_call_pat_drills_at_every_point_of_the_pattern() {
    // POS (10, 10); ROW from (0, 50) spaced 20 turned 90°: x stays 0, y 50, 70, 90; CIRC
    // about (100, 0), Ø40 from 90° in 4: (100, 20), (80, 0), (100, −20), (120, 0), its
    // surface −2 so its depth −7.
    let got = holes(
        " POS1 (X+10 Y+10 Z+0) ~\n ROW1 (X+0 Y+50 D+20 NUMX3 ROT+90 Z+0) ~\n \
         CIRC1 (X+100 Y+0 D40 START+90 NUM4 Z-2)",
    );
    let want = [
        [10.0, 10.0, -5.0],
        [0.0, 50.0, -5.0],
        [0.0, 70.0, -5.0],
        [0.0, 90.0, -5.0],
        [100.0, 20.0, -7.0],
        [80.0, 0.0, -7.0],
        [100.0, -20.0, -7.0],
        [120.0, 0.0, -7.0],
    ];
    assert!(same(&got, &want), "{got:?}");
    // FRAME: a 3 × 3 grid's border, row by row; PITCHCIRC: 30° steps from 0 on Ø20.
    let got = holes(
        " FRAME1 (X+0 Y+0 DX+10 DY+10 NUMX3 NUMY3 ROT+0 ROTX+0 ROTY+0 Z+0) ~\n \
         PITCHCIRC1 (X+0 Y+0 D20 START+0 STEP30 NUM2 Z+0)",
    );
    let want = [
        [0.0, 0.0, -5.0],
        [10.0, 0.0, -5.0],
        [20.0, 0.0, -5.0],
        [0.0, 10.0, -5.0],
        [20.0, 10.0, -5.0],
        [0.0, 20.0, -5.0],
        [10.0, 20.0, -5.0],
        [20.0, 20.0, -5.0],
        [10.0, 0.0, -5.0],
        [5.0 * 3f64.sqrt(), 5.0, -5.0],
    ];
    assert!(same(&got, &want), "{got:?}");
    // PAT 2 × 2 turned 90° about its start.
    let got = holes(" PAT1 (X+0 Y+0 DX+10 DY+5 NUMX2 NUMY2 ROT+90 Z+0)");
    let want = [
        [0.0, 0.0, -5.0],
        [0.0, 10.0, -5.0],
        [-5.0, 0.0, -5.0],
        [-5.0, 10.0, -5.0],
    ];
    assert!(same(&got, &want), "{got:?}");
    let (_, _, msg) = error("2 PATTERN DEF ~\n PAT1 (X+0 Y+0 DX+1 DY+1 NUMX2 NUMY2 ROTX+5)");
    assert!(msg.contains("ROTX"), "{msg}");
}

/// With a Ø10 tool under RR (entered on the move P_S (0, 30) → P_H (0, 20), longer than the
/// radius, as the interpreter's entry move needs) the contour and the departure run 5 right of
/// the programmed path: the element +X along y = 20 at y = 15, to (30, 15), and DEP LT's
/// tangent extension to (42.5, 15).
#[test]
fn appr_and_dep_run_compensated_by_the_tool_radius() {
    let m = moves(
        "2 L X+0 Y+30 R0 F300\n3 APPR LT X+10 Y+20 LEN10 RR F100\n4 L X+30 Y+20\n\
         5 DEP LT LEN12.5 R0 F200\n6 L Z+50 R0 FMAX",
    );
    let ends: Vec<[f64; 2]> = m.iter().map(xy).collect();
    assert!(ends.iter().any(|p| near(*p, [30.0, 15.0])), "{ends:?}");
    assert!(ends.iter().any(|p| near(*p, [42.5, 15.0])), "{ends:?}");
}

/// `CYCL DEF 32.1 T0.05` is the contour tolerance the planner blends corners within (as
/// LinuxCNC's G64 P0.05); `TA` (the rotary axes' tolerance) is not it; `32.1` without T
/// hands the corners back to the machine's default.
#[test]
fn cycle_32_sets_the_path_tolerance() {
    let m = moves(
        "2 L X+0 Y+0 Z+10 R0 FMAX\n3 CYCL DEF 32.0 TOLERANCE\n4 CYCL DEF 32.1 T0.05 HSC-MODE:1 TA0.5\n\
         5 L X+10 F500\n6 CYCL DEF 32.0 TOLERANCE\n7 CYCL DEF 32.1\n8 L Y+10",
    );
    let at = |line: usize| m.iter().find(|m| m.line == line).unwrap().path;
    // File lines: the body's block 5 is line 6 (BEGIN PGM and TOOL CALL come first).
    assert_eq!(
        at(6),
        ngc::PathControl::Blend {
            tolerance_mm: Some(0.05),
            naive_cam_mm: None
        }
    );
    assert_eq!(at(9), ngc::PathControl::BLEND);
    let (line, _, message) = error("2 CYCL DEF 32.0 TOLERANCE\n3 CYCL DEF 32.1 T-1");
    assert_eq!(line, 4);
    assert!(
        message.contains("expected a tolerance of 0 mm or more"),
        "{message}"
    );
}
