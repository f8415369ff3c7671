//! Sinumerik 840D programs of the kinds CAM posts write (NX, Mastercam, hyperMILL, Fusion
//! 360 Sinumerik posts: headers with `DEF`, `CYCLE832`, `SOFT`/`FFWON`/`COMPCAD`, settable
//! frames written by the program, macros, `CASE` branches, drilling by `MCALL`), each
//! either read with its moves asserted against points worked out by hand from the
//! SINUMERIK 840D sl programming manuals (Fundamentals; Job planning), or refused with
//! its line, column and the construct named (issue 41).

use std::path::Path;

use ngc::{read_str_with, AxisVec, Dialect, Error, Motion, Move, Options};

/// Siemens, G56 = (-20, 30, -5) as the machine's zero offset table gives it, the others 0.
fn options() -> Options {
    let mut o = Options {
        dialect: Dialect::Siemens,
        ..Options::default()
    };
    o.set_work_offset(3, AxisVec::xyzabc([-20.0, 30.0, -5.0, 0.0, 0.0, 0.0]));
    o
}

fn moves(text: &str) -> Vec<Move> {
    read_str_with(Path::new("post.mpf"), text, &options())
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}\n{text}"))
}

fn ends(ms: &[Move]) -> Vec<[f64; 3]> {
    ms.iter()
        .map(|m| {
            let e = m.end.to_xyzabc();
            [e[0], e[1], e[2]].map(|v| (v * 1e9).round() / 1e9 + 0.0)
        })
        .collect()
}

fn refusal(text: &str) -> (usize, usize, String) {
    let err = read_str_with(Path::new("post.mpf"), text, &options())
        .find_map(|m| m.err())
        .unwrap_or_else(|| panic!("expected a refusal of {text:?}"));
    match err {
        Error::Syntax(s) => (s.line, s.column, s.message),
        other => panic!("expected a refusal at a line, got {other:?}"),
    }
}

/// NX-style header: `DEF REAL`, the modal start block with G710 (metric), `FNORM`,
/// `CYCLE832(tol, _ORI_FINISH, 1)` (whose machining type is a macro of the control's cycle
/// definitions), `SOFT FFWON COMPCAD G642`, a tool by name. None of them moves the tool.
#[test]
fn nx_header_with_cycle832_and_dynamics_reads_the_programmed_points() {
    let ms = moves(
        "N10 DEF REAL _camtolerance\nN20 G40 G17 G710 G94 G90 G60 G601 FNORM\nN30 _camtolerance=0.01\n\
         N40 CYCLE832(_camtolerance,_ORI_FINISH,1)\nN50 T=\"EM10\" D1 M6\nN60 SOFT FFWON COMPCAD G642\n\
         N70 G0 X10 Y20 Z50\nN80 G1 Z-2 F500\nN90 CYCLE832(0,_OFF,1)\nN100 G0 Z50\nN110 M30\n",
    );
    assert_eq!(
        ends(&ms),
        vec![[10.0, 20.0, 50.0], [10.0, 20.0, -2.0], [10.0, 20.0, 50.0]]
    );
    assert_eq!(ms[1].feed, ngc::Feed::PerMinute(500.0));
}

/// `$P_UIFR[1] = CTRANS(X,10,Y,20)` then G54: frame point (0,0,5) is work (10,20,5).
#[test]
fn a_written_settable_frame_is_the_zero_offset_of_its_g_code() {
    let ms = moves("$P_UIFR[1]=CTRANS(X,10,Y,20)\nG54 G0 X0 Y0 Z5\nX5\nM30\n");
    assert_eq!(ends(&ms), vec![[10.0, 20.0, 5.0], [15.0, 20.0, 5.0]]);
}

/// Writing the active frame changes nothing until its G code is programmed again (Job
/// planning, "Frames": a settable frame becomes active with G54 … G599).
#[test]
fn a_settable_frame_takes_effect_when_its_g_code_is_programmed_again() {
    let ms = moves("G54 G0 X1 Y0 Z0\n$P_UIFR[1]=CTRANS(X,10)\nG0 X1\nG54 X1\nM30\n");
    assert_eq!(
        ends(&ms),
        vec![[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [11.0, 0.0, 0.0]]
    );
}

/// `CTRANS(X,100,Y,50):CROT(Z,90)`: offset, then a quarter turn about Z; frame X10 is
/// (100,50) + Rz(90)(10,0) = (100, 60).
#[test]
fn a_settable_frame_with_a_rotation_turns_the_programmed_points() {
    let ms = moves("$P_UIFR[2]=CTRANS(X,100,Y,50):CROT(Z,90)\nG55 G0 X10 Y0 Z0\nY10\nM30\n");
    // Y10 in the frame: (100,50) + Rz(90)(10,10) = (100-10, 50+10).
    assert_eq!(ends(&ms), vec![[100.0, 60.0, 0.0], [90.0, 60.0, 0.0]]);
}

/// A component write starts from the machine's offset: G56 is (-20,30,-5); `TR` of X
/// becomes 7 and `FI` adds 0.5, so frame (1,2,3) is work (8.5, 32, -2).
#[test]
fn frame_components_coarse_and_fine_offset_add() {
    let ms = moves("$P_UIFR[3,X,TR]=7\n$P_UIFR[3,X,FI]=0.5\nG56 G0 X1 Y2 Z3\nM30\n");
    assert_eq!(ends(&ms), vec![[8.5, 32.0, -2.0]]);
}

/// `CTRANS(X,10):CMIRROR(X)`: frame X5 is work 10 - 5 = 5; a clockwise arc in the frame
/// turns counter-clockwise at the work: G2 from frame (0,0) to (10,0) with CR=5 has its
/// centre at frame (5,0), work (5,0), and ends at work (0,0).
#[test]
fn a_mirroring_settable_frame_flips_x_and_the_arc_direction() {
    let ms = moves(
        "$P_UIFR[4]=CTRANS(X,10):CMIRROR(X)\nG57 G17 G1 X0 Y0 Z0 F100\nG2 X10 Y0 CR=5\nM30\n",
    );
    assert_eq!(ends(&ms), vec![[10.0, 0.0, 0.0], [0.0, 0.0, 0.0]]);
    match ms[1].motion {
        Motion::Arc {
            clockwise,
            center_mm,
            ..
        } => {
            assert!(!clockwise, "the mirror turns G2 into G3");
            assert!((center_mm[0] - 5.0).abs() < 1e-9 && center_mm[1].abs() < 1e-9);
        }
        other => panic!("expected an arc, got {other:?}"),
    }
}

/// A programmable frame acts inside the settable one: `CROT(Z,90)` as G54's frame, then
/// `TRANS X10`: frame (0,0,0) is Rz(90)(10,0,0) = (0,10,0).
#[test]
fn the_programmable_frame_acts_inside_the_settable_frame() {
    let ms = moves("$P_UIFR[1]=CROT(Z,90)\nG54\nTRANS X10\nG0 X0 Y0 Z0\nX1\nM30\n");
    assert_eq!(ends(&ms), vec![[0.0, 10.0, 0.0], [0.0, 11.0, 0.0]]);
}

/// `$P_UIFR[99]=CTRANS()` clears G599's frame (the DMG run-in programs' first block);
/// `$P_PFRAME = CTRANS(X,5):CROT(Z,90)` is the programmable frame: X1 is (5, 1).
#[test]
fn an_empty_ctrans_clears_and_p_pframe_sets_the_programmable_frame() {
    let ms = moves("$P_UIFR[99]=CTRANS()\nG599 G0 X1 Y2 Z3\n$P_PFRAME=CTRANS(X,5):CROT(Z,90)\nG0 X1 Y0 Z0\nM30\n");
    assert_eq!(ends(&ms), vec![[1.0, 2.0, 3.0], [5.0, 1.0, 0.0]]);
}

/// `DEFINE LIFT AS G0 Z50` and `DEFINE FAST AS F2000`: the names are replaced by their
/// text (Job planning, "Macro technique").
#[test]
fn define_macros_are_replaced_by_their_text() {
    let ms = moves(
        "DEFINE LIFT AS G0 Z50\nDEFINE FAST AS F2000\nG0 X0 Y0 Z5\nG1 X10 FAST ; FAST here\nLIFT\nM30\n",
    );
    assert_eq!(
        ends(&ms),
        vec![[0.0, 0.0, 5.0], [10.0, 0.0, 5.0], [10.0, 0.0, 50.0]]
    );
    assert_eq!(ms[1].feed, ngc::Feed::PerMinute(2000.0));
}

/// `CASE R1 OF 1 GOTOF .. 2 GOTOF .. DEFAULT GOTOF ..`: R1 = 2 jumps to MARK2 (X2, then
/// X3); R1 = 5 takes DEFAULT (X3 only); no match and no DEFAULT runs on.
#[test]
fn case_jumps_to_the_matching_constant_or_default() {
    let prog = |r: i32| {
        format!("R1={r}\nCASE R1 OF 1 GOTOF MARK1 2 GOTOF MARK2 DEFAULT GOTOF MARK3\nMARK1: G0 X1\nMARK2: G0 X2\nMARK3: G0 X3\nM30\n")
    };
    let xs = |ms: Vec<Move>| ends(&ms).iter().map(|e| e[0]).collect::<Vec<_>>();
    assert_eq!(xs(moves(&prog(2))), vec![2.0, 3.0]);
    assert_eq!(xs(moves(&prog(5))), vec![3.0]);
    assert_eq!(xs(moves(&prog(1))), vec![1.0, 2.0, 3.0]);
    let ms = moves("R1=9\nCASE R1 OF 1 GOTOF MARK1\nG0 X7\nMARK1: G0 X8\nM30\n");
    assert_eq!(xs(ms), vec![7.0, 8.0]);
}

/// Mastercam-style drilling: `MCALL CYCLE81(RTP 10, RFP 0, SDIS 2, DP -5)` at two holes,
/// then `MCALL` off: each hole is G0 to Z2, G1 to Z-5, G0 to Z10.
#[test]
fn mcall_cycle81_drills_every_position_until_mcall_alone() {
    let ms = moves(
        "G0 X0 Y0 Z20\nG1 F200\nMCALL CYCLE81(10,0,2,-5)\nG0 X10 Y10\nX20\nMCALL\nG0 X0\nM30\n",
    );
    assert_eq!(
        ends(&ms),
        vec![
            [0.0, 0.0, 20.0],
            [10.0, 10.0, 20.0],
            [10.0, 10.0, 2.0],
            [10.0, 10.0, -5.0],
            [10.0, 10.0, 10.0],
            [20.0, 10.0, 10.0],
            [20.0, 10.0, 2.0],
            [20.0, 10.0, -5.0],
            [20.0, 10.0, 10.0],
            [0.0, 10.0, 10.0],
        ]
    );
}

/// Fusion-style blocks: `SUPA G0 Z0 D0` (machine Z0), `X=IC(5)`, `Y=AC(3)` under G90 and
/// G91, an arc by I J (incremental centre) and `MSG`, `STOPRE`, `G64`, `IF`/`ELSE`.
#[test]
fn ac_ic_and_an_arc_by_centre_read_as_the_manual_has_them() {
    let ms = moves(
        "MSG(\"OP1\")\nSTOPRE\nG64\nG90 G17 G0 X10 Y10 Z5\nG1 X=IC(5) Y=AC(3) F100\nG91 X=AC(1) Y2\nG90\n\
         R2=1\nIF R2==1\nG2 X21 Y5 I10 J0\nELSE\nG0 X99\nENDIF\nM30\n",
    );
    // (10,10) → (15,3) → (1,5) under G91 with Y=AC(3)... X=AC(1), Y+2 → a half circle
    // clockwise about (1+10, 5) = (11,5) to (21,5).
    let e = ends(&ms);
    assert_eq!(e.len(), 4, "{e:?}");
    assert_eq!(e[0], [10.0, 10.0, 5.0]);
    assert_eq!(e[1], [15.0, 3.0, 5.0]);
    assert_eq!(e[2], [1.0, 5.0, 5.0]);
    assert_eq!(e[3], [21.0, 5.0, 5.0]);
    match ms[3].motion {
        Motion::Arc {
            clockwise,
            center_mm,
            ..
        } => {
            assert!(clockwise);
            assert!((center_mm[0] - 11.0).abs() < 1e-9 && (center_mm[1] - 5.0).abs() < 1e-9);
        }
        other => panic!("expected an arc, got {other:?}"),
    }
}

/// Constructs the reader does not simulate are refused at their line and column with the
/// construct named: each would otherwise move the tool somewhere other than the control.
#[test]
fn unsimulated_constructs_are_refused_by_name_at_line_and_column() {
    let cases: [(&str, usize, usize, &str); 12] = [
        (
            "G0 C10\nG0 C=DC(350)\n",
            2,
            6,
            "`DC(..)` (a rotary axis position",
        ),
        (
            "G0 X1\nG91 G1 AP=45 RP=10 F100\n",
            2,
            8,
            "AP=/RP= under G91",
        ),
        (
            "G0 X0 Y0 Z0\nG1 F100\nCIP X10 Y0 Z10 I1=5 J1=5 K1=5\n",
            3,
            5,
            "CIP through points whose circle lies in a plane other",
        ),
        (
            "G0 X0 Y0\nG1 X10 F100\nCT X20 Y0\n",
            3,
            4,
            "CT to an end point on the tangent's line",
        ),
        (
            "G0 X10 Y0\nG2 X10 Y0 Z-3 CR=5 TURN=2 F100\n",
            2,
            20,
            "without I J K (or with CR=)",
        ),
        (
            "G0 X1 Y1 Z20\nCYCLE78(10,0,2,-20,,5,1.5,0,100,500,0,0)\n",
            2,
            1,
            "`CYCLE78`",
        ),
        (
            "CYCLE71(10,0,2,-5,0,0,100,50,0,2,50,5,0,200,11,5)\n",
            1,
            1,
            "`CYCLE71`",
        ),
        (
            "CYCLE72(\"KONTUR\",10,0,2,-5,1,0.1,0.1,100,100,11,41,1,2,100,1,101)\n",
            1,
            1,
            "`CYCLE72`",
        ),
        (
            "TRAORI\nG1 X1 A3=0 B3=0 C3=1 F100\n",
            2,
            7,
            "no rotary axes mtsim can turn",
        ),
        (
            "$P_UIFR[1]=CTRANS(X,10):CSCALE(X,2):CROT(Z,30)\n",
            1,
            37,
            "CROT after",
        ),
        ("$P_UIFR[1]=$P_UIFR[2]\n", 1, 12, "`$P_UIFR`"),
        ("DEFINE LIFT\n", 1, 8, "expected `AS`"),
    ];
    for (text, line, column, named) in cases {
        let (l, c, m) = refusal(text);
        assert!(m.contains(named), "{text:?}: {m}");
        assert_eq!((l, c), (line, column), "{text:?}: {m}");
    }
}

/// `G53`/`SUPA` suppress the frames for their block (Fundamentals, "Settable zero offset
/// … G53, G500, SUPA, G153"): under `TRANS X10` and G54 = CTRANS(Y,5), `G53 G0 X0 Y0 Z0`
/// is machine (0,0,0); the next block is in the frames again, its X3 the work X 13, and
/// Y, not programmed, stays where SUPA left it (0).
#[test]
fn g53_and_supa_blocks_are_machine_coordinates_under_frames() {
    let ms = moves("$P_UIFR[1]=CTRANS(Y,5)\nG54\nTRANS X10\nG0 X1 Y0 Z0\nG53 G0 X0 Y0 Z0\nSUPA G0 X2\nG0 X3\nM30\n");
    assert_eq!(
        ends(&ms),
        vec![
            [11.0, 5.0, 0.0],
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [13.0, 0.0, 0.0]
        ]
    );
}

/// `CIP` (Fundamentals, "Circular interpolation with intermediate and end points"): from
/// (0,0,0) through (5,5) to (10,0) is the upper half of the circle about (5,0) of radius 5,
/// clockwise seen from +Z (G2); in G18 through (X5,Z5) to (X10,Z0) the circle about
/// (5,0,0) turns counter-clockwise seen from +Y (Z to the right, X up: (0,0) → (5,5) →
/// (0,10)); under G91 the intermediate point is incremental from the start.
#[test]
fn cip_is_the_circle_through_the_three_points() {
    let arc = |m: &Move| match m.motion {
        Motion::Arc {
            clockwise,
            center_mm,
            ..
        } => (clockwise, center_mm.map(|v| (v * 1e9).round() / 1e9 + 0.0)),
        other => panic!("expected an arc, got {other:?}"),
    };
    let ms =
        moves("G17 G0 X0 Y0 Z0\nG1 F100\nCIP X10 Y0 I1=5 J1=5\nX0 Y0 I1=5 J1=-5\nG1 X1\nM30\n");
    assert_eq!(
        ends(&ms),
        vec![
            [0.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0]
        ]
    );
    assert_eq!(arc(&ms[1]), (true, [5.0, 0.0, 0.0]));
    // CIP is modal: the next block, through (5,-5) back to (0,0), is the lower half.
    assert_eq!(arc(&ms[2]), (true, [5.0, 0.0, 0.0]));
    assert!(matches!(ms[3].motion, Motion::Linear));
    let ms = moves("G0 X0 Y0 Z0\nG18 G1 F100\nCIP X10 Z0 I1=5 K1=5\nM30\n");
    assert_eq!(ends(&ms)[1], [10.0, 0.0, 0.0]);
    assert_eq!(arc(&ms[1]), (false, [5.0, 0.0, 0.0]));
    let ms = moves("G0 X20 Y0 Z0\nG91 G1 F100\nCIP X10 Y0 I1=5 J1=5\nM30\n");
    assert_eq!(ends(&ms)[1], [30.0, 0.0, 0.0]);
    assert_eq!(arc(&ms[1]), (true, [25.0, 0.0, 0.0]));
}

/// `TURN=n` (Fundamentals, "Helical interpolation"): n full circles, then the arc to the
/// end, the helix axis moving with the angle. From (10,0,0) about (0,0), `G2 X10 Y0 Z-3
/// TURN=2` is three full circles of 1 mm each; `G3 X0 Y10 Z-5 TURN=1` turns 2π + π/2, so
/// the full circle ends at Z = -5 · 2π / 2.5π = -4 and the quarter at (0,10,-5).
#[test]
fn turn_adds_full_circles_to_a_helix() {
    let ms = moves("G17 G0 X10 Y0 Z0\nG2 X10 Y0 Z-3 I-10 J0 TURN=2 F100\nM30\n");
    assert_eq!(
        ends(&ms),
        vec![
            [10.0, 0.0, 0.0],
            [10.0, 0.0, -1.0],
            [10.0, 0.0, -2.0],
            [10.0, 0.0, -3.0]
        ]
    );
    for m in &ms[1..] {
        match m.motion {
            Motion::Arc {
                clockwise,
                center_mm,
                ..
            } => assert!(clockwise && center_mm[0].abs() < 1e-9 && center_mm[1].abs() < 1e-9),
            other => panic!("expected an arc, got {other:?}"),
        }
    }
    let ms = moves("G17 G0 X10 Y0 Z0\nG3 X0 Y10 Z-5 I-10 J0 TURN=1 F100\nM30\n");
    assert_eq!(
        ends(&ms),
        vec![[10.0, 0.0, 0.0], [10.0, 0.0, -4.0], [0.0, 10.0, -5.0]]
    );
    assert!(matches!(
        ms[2].motion,
        Motion::Arc {
            clockwise: false,
            ..
        }
    ));
}

/// Polar coordinates (Fundamentals, "Polar coordinates"): with no pole the zero point is
/// the pole, `G1 AP=90 RP=10` is (0,10); `G111 X10 Y10` sets the pole, `AP=0 RP=5` is
/// (15,10); `G3 AP=90` (RP=5 kept) turns about the pole to (10,15); `AP=IC(90)` adds 90°:
/// (5,10); `G112 X5` puts the pole at (15,10) and `RP=2` (AP=180 kept) is (13,10); in G18
/// the angle runs from Z towards X: pole (0,0), `AP=90 RP=4` is X4 Z0.
#[test]
fn polar_coordinates_about_the_pole() {
    let ms = moves(
        "G17 G90 G0 X0 Y0 Z0\nG1 AP=90 RP=10 F100\nG111 X10 Y10\nG1 AP=0 RP=5\nG3 AP=90\n\
         G1 AP=IC(90)\nG112 X5\nRP=2\nG18\nG111 Z0 X0\nG1 AP=90 RP=4\nM30\n",
    );
    assert_eq!(
        ends(&ms),
        vec![
            [0.0, 0.0, 0.0],
            [0.0, 10.0, 0.0],
            [15.0, 10.0, 0.0],
            [10.0, 15.0, 0.0],
            [5.0, 10.0, 0.0],
            [13.0, 10.0, 0.0],
            [4.0, 10.0, 0.0],
        ]
    );
    match ms[3].motion {
        Motion::Arc {
            clockwise,
            center_mm,
            ..
        } => assert!(
            !clockwise && (center_mm[0] - 10.0).abs() < 1e-9 && (center_mm[1] - 10.0).abs() < 1e-9
        ),
        other => panic!("expected an arc, got {other:?}"),
    }
}

/// `CT` (Fundamentals, "Circular interpolation with tangential transition"): after G1
/// along +X to (10,0), `CT X20 Y10` is the quarter circle about (10,10) of radius 10,
/// counter-clockwise (the end lies to the left); CT is modal, and the next block leaves
/// (20,10) along +Y: chord d = (-10,10), normal n = (-1,0), λ = |d|²/(2 d·n) = 200/20 = 10,
/// so the centre is (10,10) again, counter-clockwise.
#[test]
fn ct_continues_the_path_tangentially() {
    let ms = moves("G17 G0 X0 Y0 Z0\nG1 X10 F100\nCT X20 Y10\nX10 Y20\nG1 X0\nM30\n");
    assert_eq!(
        ends(&ms),
        vec![
            [0.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [20.0, 10.0, 0.0],
            [10.0, 20.0, 0.0],
            [0.0, 20.0, 0.0]
        ]
    );
    for m in &ms[2..4] {
        match m.motion {
            Motion::Arc {
                clockwise,
                center_mm,
                ..
            } => assert!(
                !clockwise
                    && (center_mm[0] - 10.0).abs() < 1e-9
                    && (center_mm[1] - 10.0).abs() < 1e-9,
                "{m:?}"
            ),
            other => panic!("expected an arc, got {other:?}"),
        }
    }
    // Turning right: after G1 along +X, CT X20 Y-10 is clockwise about (10,-10).
    let ms = moves("G17 G0 X0 Y0 Z0\nG1 X10 F100\nCT X20 Y-10\nM30\n");
    assert!(matches!(
        ms[2].motion,
        Motion::Arc { clockwise: true, center_mm, .. }
            if (center_mm[0] - 10.0).abs() < 1e-9 && (center_mm[1] + 10.0).abs() < 1e-9
    ));
}
