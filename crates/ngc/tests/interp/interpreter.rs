//! The interpreter: parameters and expressions, control flow, offsets, tools, cycles,
//! dialects. Expected positions are worked out by hand in the comments (and, for the
//! LinuxCNC programs, agree with LinuxCNC 2.9's `rs274` run on the same text).

use std::path::Path;

use ngc::{
    read_str_with, Axis, AxisVec, Dialect, Error, Motion, MoveKind, Options, PathControl, Tool,
    UserM,
};

fn opts(dialect: Dialect) -> Options {
    Options {
        dialect,
        ..Options::default()
    }
}

fn moves_with(text: &str, o: &Options) -> Vec<ngc::Move> {
    read_str_with(Path::new("t.ngc"), text, o)
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"))
}

fn cnc(text: &str) -> Vec<ngc::Move> {
    moves_with(text, &opts(Dialect::Linuxcnc))
}

fn fanuc(text: &str) -> Vec<ngc::Move> {
    moves_with(text, &opts(Dialect::Fanuc))
}

fn error_with(text: &str, o: &Options) -> (usize, usize, String) {
    let err = read_str_with(Path::new("t.ngc"), text, o)
        .find_map(|m| m.err())
        .unwrap_or_else(|| panic!("expected an error in {text:?}"));
    match err {
        Error::Syntax(s) => (s.line, s.column, s.message),
        other => panic!("expected a syntax error, got {other:?}"),
    }
}

fn xyz(m: &ngc::Move) -> [f64; 3] {
    let r = |v: f64| (v * 1e6).round() / 1e6;
    [r(m.end[Axis::X]), r(m.end[Axis::Y]), r(m.end[Axis::Z])]
}

#[test]
fn expressions_follow_linuxcnc_precedence_and_functions_in_degrees() {
    // 1 + 2*3**2/6 - 4 MOD 3 = 1 + 18/6 - 1 = 3.
    // SIN[30] + COS[60] * ATAN[1]/[1] = 0.5 + 0.5 * 45 = 23.
    // ABS[-2] + SQRT[16] + FIX[2.7] + FUP[2.1] + ROUND[2.5] = 2 + 4 + 2 + 3 + 3 = 14.
    let m = cnc("G0 X[1 + 2 * 3 ** 2 / 6 - 4 MOD 3] Y[SIN[30] + COS[60] * ATAN[1]/[1]] Z[ABS[-2] + SQRT[16] + FIX[2.7] + FUP[2.1] + ROUND[2.5]]\n");
    assert_eq!(xyz(&m[0]), [3.0, 23.0, 14.0]);
    // Logic: 1 EQ 1 AND 0 OR 1 XOR 1 = ((1 AND 0) OR 1) XOR 1 = 0; comparisons give 1/0.
    let m = cnc("G0 X[1 EQ 1 AND 0 OR 1 XOR 1] Y[2 GT 1] Z[[2 NE 2] + [3 LE 3] * 2 + [1 GE 2] + [1 LT 2]]\n");
    assert_eq!(xyz(&m[0]), [0.0, 1.0, 3.0]);
    // -7 MOD 3 is 2 in LinuxCNC (the result takes the divisor's sign).
    let m = cnc("G0 X[-7 MOD 3] Y-[2] Z-#1\n");
    assert_eq!(xyz(&m[0]), [2.0, -2.0, 0.0]);
}

#[test]
fn parameters_are_read_before_the_line_sets_them() {
    // On one line, `#1 = 2` takes effect after X#1 is read: X uses the old #1 = 5.
    let m = cnc("#1 = 5\n#<len> = 3\n#<_g> = 0.5\nG0 X#1 Y[#<len> + #<_g>] #1 = 2\nG0 X#1\n");
    assert_eq!(xyz(&m[0]), [5.0, 3.5, 0.0]);
    assert_eq!(xyz(&m[1]), [2.0, 3.5, 0.0]);
    let (line, col, msg) = error_with("G0 X#<nope>\n", &opts(Dialect::Linuxcnc));
    assert_eq!((line, col), (1, 5));
    assert!(msg.contains("not defined"), "{msg}");
    let (_, _, msg) = error_with("G0 X[1/0]\n", &opts(Dialect::Linuxcnc));
    assert!(msg.contains("division by zero"), "{msg}");
    let (_, _, msg) = error_with("G0 X[SQRT[-1]]\n", &opts(Dialect::Linuxcnc));
    assert!(msg.contains("zero or more"), "{msg}");
}

#[test]
fn system_parameters_report_position_tool_and_work_system() {
    let mut o = opts(Dialect::Linuxcnc);
    o.set_work_offset(2, AxisVec::xyzabc([10.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    // After G55 G0 X5 the program X is 5 (machine 15); #5420 reads 5, #5220 reads 2.
    let m = moves_with("G55 G0 X5\nG0 Y#5420 Z#5220\nG0 X#<_x>\n", &o);
    assert_eq!(xyz(&m[0]), [15.0, 0.0, 0.0]);
    assert_eq!(xyz(&m[1]), [15.0, 5.0, 2.0]);
    assert_eq!(xyz(&m[2]), [15.0, 5.0, 2.0]);
}

#[test]
fn o_word_subroutines_loops_and_branches() {
    let text = "\
o100 sub
  G1 X[#1 * 2] Y#2
  o100 return [#1 + #2]
o100 endsub
F100
#3 = 0
o200 while [#3 LT 3]
  #3 = [#3 + 1]
  o210 if [#3 EQ 2]
    G0 Z20
  o210 elseif [#3 EQ 3]
    G0 Z30
  o210 else
    G0 Z10
  o210 endif
o200 endwhile
o100 call [3] [4]
G1 X#<_value> Y#1
o300 repeat [2]
  G91 G1 X1
o300 endrepeat
G90
#4 = 0
o400 do
  #4 = [#4 + 1]
  G1 Y[#4 * 10]
  o420 if [#4 GE 2]
    o400 break
  o420 endif
o400 while [#4 LT 10]
M2
";
    let z: Vec<[f64; 3]> = cnc(text).iter().map(xyz).collect();
    assert_eq!(
        z,
        [
            [0.0, 0.0, 10.0],
            [0.0, 0.0, 20.0],
            [0.0, 0.0, 30.0],
            [6.0, 4.0, 30.0], // call [3] [4]: X = 2 * 3, Y = 4
            [7.0, 0.0, 30.0], // X = returned 3 + 4; #1 is the caller's again (0)
            [8.0, 0.0, 30.0], // repeat 2 × G91 X1
            [9.0, 0.0, 30.0],
            [9.0, 10.0, 30.0], // do: #4 = 1
            [9.0, 20.0, 30.0], // #4 = 2, break
        ]
    );
}

#[test]
fn subroutine_files_load_from_the_search_path() {
    let dir = std::env::temp_dir().join(format!("ngc-subs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("square.ngc"),
        "o<square> sub\nG1 X#1 F100\nG1 Y#1\no<square> endsub\n",
    )
    .unwrap();
    let mut o = opts(Dialect::Linuxcnc);
    o.search_path = vec![dir.clone()];
    let m = moves_with("o<square> call [5]\no<square> call [7]\nM2\n", &o);
    let ends: Vec<[f64; 3]> = m.iter().map(xyz).collect();
    assert_eq!(
        ends,
        [
            [5.0, 0.0, 0.0],
            [5.0, 5.0, 0.0],
            [7.0, 5.0, 0.0],
            [7.0, 7.0, 0.0]
        ]
    );
    let (line, _, msg) = error_with("o<missing> call\n", &o);
    assert_eq!(line, 1);
    assert!(msg.contains("`missing` not found"), "{msg}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn endless_loops_and_recursion_stop_with_a_clear_error() {
    let mut o = opts(Dialect::Linuxcnc);
    o.max_blocks = 1000;
    let (line, _, msg) = error_with("o1 while [1]\no1 endwhile\n", &o);
    assert_eq!(line, 2);
    assert!(msg.contains("more than 1000 blocks executed"), "{msg}");
    let (_, _, msg) = error_with(
        "o<r> sub\no<r> call\no<r> endsub\no<r> call\n",
        &opts(Dialect::Linuxcnc),
    );
    assert!(msg.contains("nested deeper than 64"), "{msg}");
    let (_, _, msg) = error_with(
        "N1 GOTO 1\n",
        &Options {
            max_blocks: 50,
            ..opts(Dialect::Fanuc)
        },
    );
    assert!(msg.contains("more than 50 blocks executed"), "{msg}");
}

#[test]
fn fanuc_macros_subprograms_goto_and_while() {
    let text = "\
O0001
#1 = 0
WHILE [#1 LT 3] DO 1
  #1 = #1 + 1
  G0 X#1
END 1
IF [#1 EQ 3] GOTO 20
G0 Y99
N20 M98 P1000 L2
IF [#1 GT 0] THEN #2 = 5 * 2
G0 Z#2
M30
O1000
G91 G0 Y1
G90
M99
";
    let ends: Vec<[f64; 3]> = fanuc(text).iter().map(xyz).collect();
    assert_eq!(
        ends,
        [
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [3.0, 1.0, 0.0],
            [3.0, 2.0, 0.0],
            [3.0, 2.0, 10.0],
        ]
    );
}

#[test]
fn work_offsets_g92_g52_g53_and_g10_give_machine_coordinates() {
    let mut o = opts(Dialect::Linuxcnc);
    o.set_work_offset(1, AxisVec::xyzabc([100.0, 50.0, -200.0, 0.0, 0.0, 0.0]));
    let text = "\
G0 X1 Y2 Z3
G55 G0 X1
G10 L2 P2 X10 Y20
G0 X1 Y1
G10 L20 P0 X0 Y0
G0 X2 Y3
G54
G92 X0 Y0
G0 X5 Y5
G92.1
G53 G0 X7 Y8 Z9
G52 X1
G0 X0 Y0 Z0
";
    let ends: Vec<[f64; 3]> = moves_with(text, &o).iter().map(xyz).collect();
    assert_eq!(
        ends,
        [
            [101.0, 52.0, -197.0], // G54 = (100, 50, -200)
            [1.0, 52.0, -197.0],   // G55 is zero; Y Z stay where they are
            [11.0, 21.0, -197.0],  // G55 = (10, 20)
            [13.0, 24.0, -197.0],  // L20 made (11, 21) the origin of G55
            [18.0, 29.0, -197.0],  // G92 made machine (13, 24) the origin under G54: +(5, 5)
            [7.0, 8.0, 9.0],       // G53: machine coordinates
            [101.0, 50.0, -200.0], // G52 X1 shifts G54 by 1 in X
        ]
    );
}

#[test]
fn g28_goes_through_the_intermediate_point_to_the_stored_position() {
    let mut o = opts(Dialect::Linuxcnc);
    o.set_reference(false, AxisVec::xyzabc([0.0, 0.0, 100.0, 0.0, 0.0, 0.0]));
    let m = moves_with(
        "G0 X10 Y10 Z10\nG28 Z20\nG0 X5\nG28.1\nG0 X0 Y0 Z0\nG28\n",
        &o,
    );
    let ends: Vec<[f64; 3]> = m.iter().map(xyz).collect();
    assert_eq!(
        ends,
        [
            [10.0, 10.0, 10.0],
            [10.0, 10.0, 20.0],
            [10.0, 10.0, 100.0],
            [5.0, 10.0, 100.0],
            [0.0, 0.0, 0.0],
            [5.0, 10.0, 100.0]
        ]
    );
    assert!(m.iter().all(|m| m.kind() == MoveKind::Rapid));
}

#[test]
fn tool_length_offsets_add_to_machine_z() {
    let mut o = opts(Dialect::Linuxcnc);
    o.tools = vec![
        Tool {
            number: 1,
            length_mm: 50.0,
            diameter_mm: 6.0,
        },
        Tool {
            number: 2,
            length_mm: 80.0,
            diameter_mm: 10.0,
        },
    ];
    let text = "T1 M6\nG43 G0 Z10\nT2 M6 G43 H2\nG0 Z10\nG43.1 Z5\nG0 Z10\nG43.2 H1\nG0 Z10\nG49 G0 Z10\nM61 Q1\n";
    let m = moves_with(text, &o);
    let z: Vec<(f64, u32, f64)> = m
        .iter()
        .map(|m| (m.end[Axis::Z], m.tool, m.tool_length_mm))
        .collect();
    assert_eq!(
        z,
        [
            (60.0, 1, 50.0),
            (90.0, 2, 80.0),
            (15.0, 2, 5.0),
            (65.0, 2, 55.0),
            (10.0, 2, 0.0)
        ]
    );
    let (_, _, msg) = error_with("T3\n", &o);
    assert!(msg.contains("tool 3 is not in the tool table"), "{msg}");
}

#[test]
fn canned_cycles_expand_as_linuxcnc_does() {
    // rs274 2.9 on this text: G98 retracts to the initial Z (10), G99 to R; G83 pecks by Q
    // and returns to R, re-entering 0.254 mm (0.010 in) above the last depth.
    let text = "G21 G90 G17 G94 F100\nG0 X0 Y0 Z10\nG98 G81 X1 Y2 Z-3 R2\nG99 G83 X3 Y3 Z-3 R2 Q1.2\nG80\n";
    let got: Vec<(MoveKind, [f64; 3])> = cnc(text).iter().map(|m| (m.kind(), xyz(m))).collect();
    use MoveKind::{Feed as F, Rapid as R};
    let want = [
        (R, [0.0, 0.0, 10.0]),
        (R, [1.0, 2.0, 10.0]),
        (R, [1.0, 2.0, 2.0]),
        (F, [1.0, 2.0, -3.0]),
        (R, [1.0, 2.0, 10.0]),
        (R, [3.0, 3.0, 10.0]),
        (R, [3.0, 3.0, 2.0]),
        (F, [3.0, 3.0, 0.8]),
        (R, [3.0, 3.0, 2.0]),
        (R, [3.0, 3.0, 1.054]),
        (F, [3.0, 3.0, -0.4]),
        (R, [3.0, 3.0, 2.0]),
        (R, [3.0, 3.0, -0.146]),
        (F, [3.0, 3.0, -1.6]),
        (R, [3.0, 3.0, 2.0]),
        (R, [3.0, 3.0, -1.346]),
        (F, [3.0, 3.0, -2.8]),
        (R, [3.0, 3.0, 2.0]),
        (R, [3.0, 3.0, -2.546]),
        (F, [3.0, 3.0, -3.0]),
        (R, [3.0, 3.0, 2.0]),
    ];
    assert_eq!(got, want);
    // Incremental with L3: R and Z relative, holes 10 mm apart.
    let m = cnc("G0 Z1\nF100 G91 G98 G81 X10 Z-3 R-2 L3\n");
    let bottoms: Vec<[f64; 3]> = m
        .iter()
        .filter(|m| m.kind() == MoveKind::Feed)
        .map(xyz)
        .collect();
    assert_eq!(
        bottoms,
        [[10.0, 0.0, -4.0], [20.0, 0.0, -4.0], [30.0, 0.0, -4.0]]
    );
    assert!(m[1..].iter().all(|m| m.path == PathControl::ExactPath));
}

#[test]
fn dialects_read_g4_p_in_their_units() {
    let dwell = |text: &str, d: Dialect| match moves_with(text, &opts(d))[0].motion {
        Motion::Dwell { seconds } => seconds,
        other => panic!("{other:?}"),
    };
    assert_eq!(dwell("G4 P2\n", Dialect::Linuxcnc), 2.0);
    assert_eq!(dwell("G4 P2\n", Dialect::Fanuc), 0.002);
    assert_eq!(dwell("G4 X2\n", Dialect::Fanuc), 2.0);
    assert_eq!(dwell("G4 P2.5\n", Dialect::Haas), 2.5);
    assert_eq!(dwell("G4 P250\n", Dialect::Haas), 0.25);
}

#[test]
fn tcp_codes_follow_the_dialect_and_user_m_codes() {
    assert!(moves_with("G234 G0 X1\n", &opts(Dialect::Haas))[0].tcp);
    assert!(fanuc("G43.5 H1 G0 X1\n")[0].tcp);
    let (_, _, msg) = error_with("G43.4\n", &opts(Dialect::Linuxcnc));
    assert!(msg.contains("M428"), "{msg}");
    let mut o = opts(Dialect::Linuxcnc);
    o.user_m.insert(428, UserM::TcpOn);
    o.user_m.insert(429, UserM::TcpOff);
    let m = moves_with("M428\nG0 X1\nM429\nG0 X2\nM101\n", &o);
    assert_eq!((m[0].tcp, m[1].tcp), (true, false));
    let mut it = read_str_with(Path::new("t.ngc"), "M101\nM101\nG0 X1\n", &o);
    while it.next().is_some() {}
    let accepted = it.notices().iter().filter(|n| !n.warning).count();
    assert_eq!(accepted, 1, "one notice per user code");
    let (_, _, msg) = error_with("M428\n", &opts(Dialect::Linuxcnc));
    assert!(msg.contains("unsupported code `M428`"), "{msg}");
}

#[test]
fn path_control_modes_reach_the_moves() {
    let m = cnc("G61 G0 X1\nG61.1 G0 X2\nG64 P0.01 Q0.005 G0 X3\nG64 G0 X4\n");
    assert_eq!(m[0].path, PathControl::ExactPath);
    assert_eq!(m[1].path, PathControl::ExactStop);
    assert_eq!(
        m[2].path,
        PathControl::Blend {
            tolerance_mm: Some(0.01),
            naive_cam_mm: Some(0.005)
        }
    );
    assert_eq!(m[3].path, PathControl::BLEND);
    // G95: F per revolution times S.
    let m = cnc("G95 S1000 F0.1 G1 X1\n");
    assert_eq!(m[0].feed, ngc::Feed::PerMinute(100.0));
    // G20 G90.1: absolute arc centre in inches.
    let m = cnc("G20 G90.1 G0 X1 Y0\nG3 X0 Y1 I0 J0 F10\n");
    let Motion::Arc { center_mm, .. } = m[1].motion else {
        panic!()
    };
    assert_eq!(center_mm, [0.0, 0.0, 0.0]);
    // G18: arc in the ZX plane about Y.
    let m = cnc("G18 G0 X1 Z0\nG2 X0 Z1 I-1 K0 F10\n");
    let Motion::Arc { center_mm, .. } = m[1].motion else {
        panic!()
    };
    assert_eq!(center_mm, [0.0, 0.0, 0.0]);
}

#[test]
fn words_the_machine_or_block_cannot_use_are_errors() {
    let o = Options {
        axes: vec![Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::C],
        ..opts(Dialect::Linuxcnc)
    };
    let (line, col, msg) = error_with("G0 X1\nG0 B5\n", &o);
    assert_eq!((line, col), (2, 4));
    assert!(msg.contains("no B axis"), "{msg}");
    let (_, _, msg) = error_with("G0 X1 Q2\n", &o);
    assert!(msg.contains("`Q` with no code that uses it"), "{msg}");
    let (_, _, msg) = error_with("G1 X1 D2 F1\n", &o);
    assert!(msg.contains("`D`"), "{msg}");
}

#[test]
fn other_controls_languages_are_read_or_refused_at_their_first_line() {
    // A Klartext program goes to the Heidenhain front end whatever the dialect named,
    // with or without block numbers.
    for text in [
        "BEGIN PGM PART MM\nL X+10 FMAX\nEND PGM PART MM\n",
        "0  BEGIN PGM PART MM\n1  L X+10 FMAX\n2  END PGM PART MM\n",
    ] {
        let moves: Vec<_> = read_str_with(Path::new("t.h"), text, &Options::default())
            .collect::<Result<_, _>>()
            .unwrap();
        assert_eq!(moves.len(), 1, "{text}");
        assert_eq!(moves[0].end[ngc::Axis::X], 10.0);
    }
    let (line, col, msg) = error_with("N10 G0 X0\nN20 TRAORI\nN30 G1 X1\n", &Options::default());
    assert_eq!((line, col), (2, 5));
    assert!(msg.contains("Siemens"), "{msg}");
    assert!(
        read_str_with(Path::new("t"), "G0 X1\nCYCLE800()\n", &Options::default())
            .next()
            .unwrap()
            .is_err(),
        "no move before the refusal"
    );
}

#[test]
fn linuxcnc_g4_shares_a_block_with_a_rapid_and_x_stays_an_axis() {
    // LinuxCNC's skeleton.ngc: `G04 P.001 G0 X1.0 Y1.0` dwells 1 ms, then moves.
    let m = cnc("G04 P.001 G0 X1.0 Y1.0\n");
    assert_eq!(m[0].motion, Motion::Dwell { seconds: 0.001 });
    assert_eq!(xyz(&m[1]), [1.0, 1.0, 0.0]);
    let (_, _, msg) = error_with("G1 G4 P1\n", &opts(Dialect::Fanuc));
    assert!(msg.contains("same modal group"), "{msg}");
}

#[test]
fn fanuc_g65_passes_arguments_as_local_variables() {
    // G65 P9010 A2 X5: #1 = 2, #24 = 5 inside O9010; the caller's #1 is untouched.
    let text = "#1 = 7\nG65 P9010 A2 X5\nG0 Z#1\nM30\nO9010\nG0 X[#24 * #1] Y#1\nM99\n";
    let ends: Vec<[f64; 3]> = fanuc(text).iter().map(xyz).collect();
    assert_eq!(ends, [[10.0, 2.0, 0.0], [10.0, 2.0, 7.0]]);
}

#[test]
fn linuxcnc_arc_radius_tolerance_matches_rs274() {
    // Bisected with rs274 2.9: G3 from (R, 0) about the origin to (-(R + d), 0).
    let arc = |r: f64, d: f64, units: &str| {
        let text = format!("{units} F100\nG0 X{r} Y0\nG3 X-{} Y0 I-{r} J0\n", r + d);
        read_str_with(Path::new("t.ngc"), &text, &opts(Dialect::Linuxcnc)).all(|m| m.is_ok())
    };
    assert!(arc(10.0, 0.0282, "G21"));
    assert!(!arc(10.0, 0.0283, "G21"));
    assert!(arc(100.0, 0.09, "G21"), "0.09 % of the radius");
    assert!(!arc(100.0, 0.11, "G21"));
    assert!(arc(1000.0, 0.9, "G21"));
    assert!(!arc(1000.0, 1.1, "G21"));
    assert!(arc(1.0, 0.0028, "G20"));
    assert!(!arc(1.0, 0.00285, "G20"));
    // Fanuc family: 0.01 mm (docs/gcode.md). The Haas UMC-750 of issue 9 accepts an NX
    // post's inch arcs whose radii differ by up to 4.9 µm = 0.000193 in.
    let fanuc_arc = |d: f64, units: &str, dialect: Dialect| {
        read_str_with(
            Path::new("t"),
            &format!("{units} F100\nG0 X10 Y0\nG3 X-{} Y0 I-10 J0\n", 10.0 + d),
            &opts(dialect),
        )
        .all(|m| m.is_ok())
    };
    assert!(fanuc_arc(0.0049, "G21", Dialect::Fanuc));
    assert!(fanuc_arc(0.000193, "G20", Dialect::Haas));
    assert!(fanuc_arc(0.0099, "G21", Dialect::Haas));
    assert!(!fanuc_arc(0.0101, "G21", Dialect::Fanuc));
    // 0.0004 in = 10.16 µm.
    assert!(!fanuc_arc(0.0004, "G20", Dialect::Haas));
}

#[test]
fn post_processor_control_codes_are_accepted() {
    // Fanuc G05.1 Q1 (AI contour control) and G08 P1 (look-ahead): no effect on moves.
    assert_eq!(xyz(&fanuc("G05.1 Q1\nG08 P1\nG0 X1\n")[0]), [1.0, 0.0, 0.0]);
    // Haas G187 E sets the blending tolerance; G103 P is accepted.
    let m = moves_with("G187 P1 E0.01\nG103 P15\nG0 X1\n", &opts(Dialect::Haas));
    assert_eq!(
        m[0].path,
        PathControl::Blend {
            tolerance_mm: Some(0.01),
            naive_cam_mm: None
        }
    );
    // M70 saves, M72 restores the modal state (here G91 back to G90).
    let m = cnc("M70\nG91\nG0 X1\nM72\nG0 X5\n");
    assert_eq!(xyz(&m[1]), [5.0, 0.0, 0.0]);
}
