//! The Fanuc and Haas dialects as CAM posts write them (issue 28): the start-up state and
//! the units warning, codes with no effect on the motion, D and H on their own, M97, G80
//! leaving G00/G01 in effect, tapping and fine boring. Expected positions are worked out
//! by hand in the comments, from the manuals docs/gcode.md names.

use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, Error, Motion, MoveKind, Options, Tool, Units};

fn opts(dialect: Dialect) -> Options {
    Options {
        dialect,
        ..Options::default()
    }
}

/// The moves and notices of `text`.
fn read(text: &str, o: &Options) -> (Vec<ngc::Move>, Vec<ngc::Notice>) {
    let mut it = read_str_with(Path::new("t.nc"), text, o);
    let moves = it
        .by_ref()
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"));
    (moves, it.notices().to_vec())
}

fn error_with(text: &str, o: &Options) -> (usize, String) {
    match read_str_with(Path::new("t.nc"), text, o).find_map(|m| m.err()) {
        Some(Error::Syntax(s)) => (s.line, s.message),
        other => panic!("expected a syntax error, got {other:?}"),
    }
}

fn xyz(m: &ngc::Move) -> [f64; 3] {
    let r = |v: f64| (v * 1e6).round() / 1e6;
    [r(m.end[Axis::X]), r(m.end[Axis::Y]), r(m.end[Axis::Z])]
}

#[test]
fn a_control_that_starts_in_inch_reads_inches_and_a_program_without_units_is_warned_about() {
    let text = "G90 G0 X1 Y2\nG1 Z-0.5 F10\n";
    let (m, notices) = read(text, &opts(Dialect::Haas));
    assert_eq!(xyz(&m[0]), [1.0, 2.0, 0.0]);
    let warned: Vec<_> = notices.iter().filter(|n| n.warning).collect();
    assert_eq!(warned.len(), 1, "one warning: {notices:?}");
    assert_eq!(warned[0].line, 1);
    assert!(
        warned[0].message.contains("read in mm"),
        "{}",
        warned[0].message
    );
    assert!(warned[0].message.contains("start_units"));
    let mut o = opts(Dialect::Haas);
    o.start_state.units = Units::Inch;
    let (m, notices) = read(text, &o);
    // 1 in = 25.4 mm; F10 in/min = 254 mm/min.
    assert_eq!(xyz(&m[0]), [25.4, 50.8, 0.0]);
    assert_eq!(xyz(&m[1]), [25.4, 50.8, -12.7]);
    assert_eq!(m[1].feed, ngc::Feed::PerMinute(254.0));
    assert!(notices
        .iter()
        .any(|n| n.warning && n.message.contains("inches (G20)")));
    // Stated units: no warning, and G21 overrides the inch start.
    let (m, notices) = read("G21 G0 X1\n", &o);
    assert_eq!(xyz(&m[0]), [1.0, 0.0, 0.0]);
    assert!(notices.iter().all(|n| !n.warning));
    // G91 at start: the second move adds.
    o.start_state.distance = ngc::Distance::Incremental;
    let (m, _) = read("G20 G0 X1\nX1\n", &o);
    assert_eq!(xyz(&m[1]), [50.8, 0.0, 0.0]);
}

#[test]
fn machine_codes_and_smoothing_codes_are_accepted_with_one_notice_each() {
    let text = "G20\nM11\nG05.1 Q1\nG187 P1 E0.001\nM31\nG0 X1\nM10\nM11\nM12 M13\nM88\nM33\nM30\n";
    let (m, notices) = read(text, &opts(Dialect::Haas));
    assert_eq!(m.len(), 1);
    let codes: Vec<&str> = notices
        .iter()
        .map(|n| n.message.split_whitespace().next().unwrap())
        .collect();
    assert_eq!(
        codes,
        ["M11", "G05.1", "G187", "M31", "M10", "M12", "M13", "M88", "M33"]
    );
    assert!(notices.iter().all(|n| !n.warning));
    // Fanuc has the rotary clamp, not the Haas chip conveyor.
    let (_, msg) = error_with("G21\nM31\n", &opts(Dialect::Fanuc));
    assert!(msg.contains("unsupported code `M31`"), "{msg}");
    read("G21\nM10\nM11\nG0 X1\n", &opts(Dialect::Fanuc));
}

#[test]
fn haas_m16_changes_the_tool_as_m06_does() {
    let mut o = opts(Dialect::Haas);
    o.tools = vec![Tool {
        number: 7,
        length_mm: 80.0,
        diameter_mm: 8.0,
    }];
    // After the change tool 7 is active; G43 H7 then Z0 puts machine Z at its 80 mm length.
    let text = |m: &str| format!("G21 G90\nT7 {m}\nG0 X1\nG43 H7 G0 Z0\n");
    for code in ["M06", "M16"] {
        let (m, notices) = read(&text(code), &o);
        assert_eq!(m[0].tool, 7, "{code}: {m:?}");
        assert_eq!(xyz(&m[0]), [1.0, 0.0, 0.0]);
        assert_eq!(m[1].tool, 7);
        assert_eq!(m[1].tool_length_mm, 80.0);
        assert_eq!(xyz(&m[1]), [1.0, 0.0, 80.0]);
        assert!(
            !notices.iter().any(|n| n.message.contains("M16")),
            "{notices:?}"
        );
    }
    // Without the change, T7 alone leaves no tool active (tool 0).
    let (m, _) = read("G21 G90\nT7\nG0 X1\n", &o);
    assert_eq!(m[0].tool, 0);
    // Under cutter compensation M16 is refused as M06 is.
    let (line, msg) = error_with("G21 G90 G17\nT7 D7 M06\nG41 G1 X10 F100\nM16\n", &o);
    assert_eq!(line, 4);
    assert!(msg.contains("cannot change tools"), "{msg}");
}

#[test]
fn d_and_h_stand_alone_in_the_fanuc_family() {
    let mut o = opts(Dialect::Haas);
    o.tools = vec![
        Tool {
            number: 17,
            length_mm: 100.0,
            diameter_mm: 10.0,
        },
        Tool {
            number: 3,
            length_mm: 50.0,
            diameter_mm: 6.0,
        },
    ];
    // D17 alone, G41 without D: the 5 mm radius of tool 17 on the left of +X, so Y + 5.
    let (m, _) = read(
        "G21 G90 G17\nT17 D17 M06\nG0 X0 Y0 Z0\nG41 G1 X10 Y0 F100\nX20\nG40 G0 X30\n",
        &o,
    );
    assert!(m.iter().any(|m| xyz(m) == [10.0, 5.0, 0.0]), "{m:?}");
    // H3 alone under G43 H17: the length becomes tool 3's, 50 mm: Z0 is machine Z 50.
    let (m, _) = read("G21 G90\nG43 H17 G0 Z0\nH3\nG0 Z0 X1\n", &o);
    assert_eq!(xyz(&m[0]), [0.0, 0.0, 100.0]);
    assert_eq!(xyz(&m[1]), [1.0, 0.0, 50.0]);
    // LinuxCNC keeps refusing a D or an H no code uses.
    let (_, msg) = error_with("G21\nG1 X1 H1 F100\n", &opts(Dialect::Linuxcnc));
    assert!(msg.contains("`H` without G43"), "{msg}");
    let (_, msg) = error_with("G21\nD1\n", &opts(Dialect::Linuxcnc));
    assert!(msg.contains("`D` with no code that uses it"), "{msg}");
}

#[test]
fn m97_runs_a_local_subprogram_l_times() {
    // N100 moves 1 mm along X incrementally: called 3 times, then X 3 -> the main Y move.
    let text = "G21 G90 G0 X0\nM97 P100 L3\nG90 G0 Y5\nM30\nN100 G91 G1 X1 F100\nM99\n";
    let (m, _) = read(text, &opts(Dialect::Haas));
    let ends: Vec<[f64; 3]> = m.iter().map(xyz).collect();
    assert_eq!(
        ends,
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [3.0, 5.0, 0.0]
        ]
    );
    let (line, msg) = error_with("G21\nM97 P200\nM30\n", &opts(Dialect::Haas));
    assert_eq!(line, 2);
    assert!(msg.contains("no block with sequence number N200"), "{msg}");
    let (_, msg) = error_with("G21\nM97\n", &opts(Dialect::Haas));
    assert!(msg.contains("M97 without P"), "{msg}");
}

#[test]
fn g80_leaves_the_motion_mode_of_group_01_in_the_fanuc_family() {
    let text = "G21 G90 G0 X0 Y0 Z10\nG1 F100\nG98 G81 X1 Z-1 R1\nG80\nA5.\n";
    let (m, _) = read(text, &opts(Dialect::Fanuc));
    let last = m.last().unwrap();
    // G1 was in effect before the cycle: the A move feeds.
    assert_eq!(last.end[Axis::A], 5.0);
    assert_eq!(last.kind(), MoveKind::Feed);
    let (_, msg) = error_with(text, &opts(Dialect::Linuxcnc));
    assert!(msg.contains("no motion mode"), "{msg}");
}

#[test]
fn tapping_feeds_in_and_out_and_fine_boring_shifts_off_the_wall() {
    // G84 at X1, R 2, Z -5, G98 from Z 10: rapid to R, feed to -5, dwell 0.5 s (P500 ms),
    // feed back to R, rapid to the initial level.
    let text = "G21 G90 G0 X0 Y0 Z10\nG98 G84 X1 Z-5 R2 P500 F100\nG80\n";
    let (m, _) = read(text, &opts(Dialect::Fanuc));
    let got: Vec<(MoveKind, [f64; 3])> = m.iter().map(|m| (m.kind(), xyz(m))).collect();
    use MoveKind::{Feed as F, Rapid as R};
    assert_eq!(got[1..3], [(R, [1.0, 0.0, 10.0]), (R, [1.0, 0.0, 2.0])]);
    assert_eq!(got[3], (F, [1.0, 0.0, -5.0]));
    assert_eq!(m[4].motion, Motion::Dwell { seconds: 0.5 });
    assert_eq!(got[5..], [(F, [1.0, 0.0, 2.0]), (R, [1.0, 0.0, 10.0])]);
    // G76 with Q0.3 under G99: feed to the bottom, shift +X 0.3, rapid to R, shift back.
    let text = "G21 G90 G0 X0 Y0 Z10\nG99 G76 X1 Z-5 R2 Q0.3 F100\n";
    let (m, _) = read(text, &opts(Dialect::Haas));
    let got: Vec<[f64; 3]> = m[3..].iter().map(xyz).collect();
    assert_eq!(
        got,
        [
            [1.0, 0.0, -5.0],
            [1.3, 0.0, -5.0],
            [1.3, 0.0, 2.0],
            [1.0, 0.0, 2.0]
        ]
    );
    // G82 P in ms on Fanuc: P250 dwells 0.25 s.
    let (m, _) = read("G21 G0 Z10\nG82 Z-1 R1 P250 F100\n", &opts(Dialect::Fanuc));
    assert!(m
        .iter()
        .any(|m| m.motion == Motion::Dwell { seconds: 0.25 }));
}

#[test]
fn spindle_limits_and_program_names_are_not_moves() {
    // G92 S3000 alone: the spindle limit, no offset; X1 stays at machine X 1.
    let (m, _) = read(
        "G21 G90\nG92 S3000\nG96 S200 M3\nG0 X1\nG97 S1000\n",
        &opts(Dialect::Fanuc),
    );
    assert_eq!(xyz(&m[0]), [1.0, 0.0, 0.0]);
    // A CAM listing before `%` and a program name after O.
    let text = "Information listing created by someone\nDate 15-Apr-2023\n\n%\nOFinal ToolPath\nG21 G0 X2\nM30\n%\n";
    let (m, _) = read(text, &opts(Dialect::Haas));
    assert_eq!(xyz(&m[0]), [2.0, 0.0, 0.0]);
}

#[test]
fn g53_in_g91_goes_to_machine_coordinates_on_haas_only() {
    // G54 X offset 100: G53 X5 is machine X 5 whatever the distance mode.
    let mut o = opts(Dialect::Haas);
    o.set_work_offset(1, ngc::AxisVec::xyzabc([100.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    let (m, _) = read("G21 G90 G0 X1\nG91 G53 G0 X5\n", &o);
    assert_eq!(xyz(&m[1]), [5.0, 0.0, 0.0]);
    o.dialect = Dialect::Fanuc;
    let (_, msg) = error_with("G21 G91 G53 G0 X5\n", &o);
    assert!(msg.contains("G53 in G91"), "{msg}");
}

/// The kinds and end points of `m`.
fn path(m: &[ngc::Move]) -> Vec<(MoveKind, [f64; 3])> {
    m.iter().map(|m| (m.kind(), xyz(m))).collect()
}

#[test]
fn back_boring_shifts_off_the_wall_goes_down_through_the_hole_and_feeds_up() {
    use MoveKind::{Feed as F, Rapid as R};
    // Fanuc G87 at X5, from the initial level Z10: shift Q1.5 along +X, rapid down to
    // R -20 (below the part), shift back, feed up to the bore's top Z -2, dwell 1 s
    // (P1000 ms), shift off, rapid up to Z10, shift back.
    let text = "G21 G90 G0 X0 Y0 Z10\nG98 G87 X5 Y0 Z-2 R-20 Q1.5 P1000 F100\nG80\n";
    let (m, _) = read(text, &opts(Dialect::Fanuc));
    let got = path(&m);
    assert_eq!(
        got[1..6],
        [
            (R, [5.0, 0.0, 10.0]),
            (R, [6.5, 0.0, 10.0]),
            (R, [6.5, 0.0, -20.0]),
            (R, [5.0, 0.0, -20.0]),
            (F, [5.0, 0.0, -2.0]),
        ]
    );
    assert_eq!(m[6].motion, Motion::Dwell { seconds: 1.0 });
    assert_eq!(
        got[7..],
        [
            (R, [6.5, 0.0, -2.0]),
            (R, [6.5, 0.0, 10.0]),
            (R, [5.0, 0.0, 10.0]),
        ]
    );
    // The shift as I J (incremental, any direction in the plane): I-1 J2 from X5 Y5.
    let text = "G21 G90 G0 X0 Y0 Z10\nG87 X5 Y5 Z-2 R-20 I-1 J2 F100\n";
    let (m, _) = read(text, &opts(Dialect::Fanuc));
    let got: Vec<[f64; 3]> = m[2..4].iter().map(xyz).collect();
    assert_eq!(got, [[4.0, 7.0, 10.0], [4.0, 7.0, -20.0]]);
    // Haas back boring is G77, the same moves (no dwell); R above Z is refused.
    let text = "G21 G90 G0 X0 Y0 Z10\nG77 X5 Y0 Z-2 R-20 Q1.5 F100\n";
    let (m, _) = read(text, &opts(Dialect::Haas));
    let ends: Vec<[f64; 3]> = m[1..].iter().map(xyz).collect();
    assert_eq!(
        ends,
        [
            [5.0, 0.0, 10.0],
            [6.5, 0.0, 10.0],
            [6.5, 0.0, -20.0],
            [5.0, 0.0, -20.0],
            [5.0, 0.0, -2.0],
            [6.5, 0.0, -2.0],
            [6.5, 0.0, 10.0],
            [5.0, 0.0, 10.0]
        ]
    );
    let (line, msg) = error_with(
        "G21 G90 G0 Z10\nG87 X5 Z-20 R-2 Q1 F100\n",
        &opts(Dialect::Fanuc),
    );
    assert_eq!(line, 2);
    assert!(msg.contains("back boring"), "{msg}");
    // LinuxCNC has no G87.
    let (_, msg) = error_with(
        "G21 G0 Z10\nG87 X5 Z-2 R-20 F100\n",
        &opts(Dialect::Linuxcnc),
    );
    assert!(msg.contains("G87"), "{msg}");
}

#[test]
fn boring_with_a_manual_retract_feeds_in_dwells_and_is_retracted_with_a_notice() {
    use MoveKind::{Feed as F, Rapid as R};
    // Fanuc G88 P2000 (ms) under G98 from Z10: rapid to R 2, feed to -5, dwell 2 s, the
    // manual retract simulated as a rapid to the initial level.
    let text = "G21 G90 G0 X0 Y0 Z10\nG98 G88 X1 Z-5 R2 P2000 F100\nG80\n";
    let (m, notices) = read(text, &opts(Dialect::Fanuc));
    let got = path(&m);
    assert_eq!(
        got[1..4],
        [
            (R, [1.0, 0.0, 10.0]),
            (R, [1.0, 0.0, 2.0]),
            (F, [1.0, 0.0, -5.0])
        ]
    );
    assert_eq!(m[4].motion, Motion::Dwell { seconds: 2.0 });
    assert_eq!(got[5], (R, [1.0, 0.0, 10.0]));
    assert_eq!(got.len(), 6);
    let manual: Vec<_> = notices
        .iter()
        .filter(|n| n.message.contains("manual retract"))
        .collect();
    assert_eq!(manual.len(), 1, "{notices:?}");
    assert_eq!(manual[0].line, 2);
    // Haas G87: bore in, manual retract, no dwell; G99 returns to R. Haas G88 P2. dwells 2 s.
    let text = "G21 G90 G0 X0 Y0 Z10\nG99 G87 X1 Z-5 R2 F100\nG88 X3 P2.\n";
    let (m, notices) = read(text, &opts(Dialect::Haas));
    let got = path(&m);
    assert_eq!(
        got[1..],
        [
            (R, [1.0, 0.0, 10.0]),
            (R, [1.0, 0.0, 2.0]),
            (F, [1.0, 0.0, -5.0]),
            (R, [1.0, 0.0, 2.0]),
            (R, [3.0, 0.0, 2.0]),
            (F, [3.0, 0.0, -5.0]),
            (MoveKind::Dwell, [3.0, 0.0, -5.0]),
            (R, [3.0, 0.0, 2.0]),
        ]
    );
    assert_eq!(m[7].motion, Motion::Dwell { seconds: 2.0 });
    let manual = notices
        .iter()
        .filter(|n| n.message.contains("manual retract"))
        .count();
    assert_eq!(manual, 2, "one notice each for G87 and G88: {notices:?}");
}

#[test]
fn m73_and_m74_are_the_tool_air_blast_on_haas_and_save_the_modal_state_only_in_linuxcnc() {
    // Haas: M73/M74 are machine codes (tool air blast on/off), accepted with a notice. An
    // M73 in a subprogram does not restore G90 on its return: X1 after it is incremental.
    let text = "G21 G90 G0 X5\nM98 P100\nG0 X1\nM30\nO100\nM73\nG91\nM74\nM99\n";
    let (m, notices) = read(text, &opts(Dialect::Haas));
    assert_eq!(xyz(m.last().unwrap())[0], 6.0);
    for code in ["M73 tool air blast on", "M74 tool air blast off"] {
        assert!(
            notices.iter().any(|n| n.message.starts_with(code)),
            "{code}: {notices:?}"
        );
    }
    // Fanuc: M70-M73 are the builder's codes, refused unless mapped.
    let (line, msg) = error_with("G21 G0 X1\nM73\n", &opts(Dialect::Fanuc));
    assert_eq!(line, 2);
    assert!(msg.contains("M73"), "{msg}");
    // LinuxCNC: M73 in a subroutine restores G90 on return, so X1 is absolute.
    let text = "G21 G90 G0 X5\no100 call\nG0 X1\nM2\no100 sub\nM73\nG91\no100 endsub\n";
    let text = format!(
        "o100 sub\nM73\nG91\no100 endsub\n{}",
        &text[..text.find("M2").unwrap() + 3]
    );
    let (m, _) = read(&text, &opts(Dialect::Linuxcnc));
    assert_eq!(xyz(m.last().unwrap())[0], 1.0);
}

/// Refusals name what the construct is in a Fanuc: G43.5's I J K are the tool-axis vector
/// (not arc words), `,R` and `,C` the corner rounding and chamfer (not stray characters),
/// refused where the next block has no line to round or chamfer to.
#[test]
fn refusals_name_the_fanuc_meaning_of_the_construct() {
    let o = opts(Dialect::Fanuc);
    for (text, line, says) in [
        (
            "G21 G90\nG43.5 H1 I0 J0 K1\n",
            2,
            "under G43.5: Fanuc's tool-axis direction vector",
        ),
        (
            "G21 G90\nG43.5 H1\nG1 X10 I0 J0.5 K0.8 F100\n",
            3,
            "tool-axis direction vector",
        ),
        (
            "G21 G90\nG1 X10 Y0 ,R2 F100\n",
            2,
            "corner rounding `,R2` (line 2): the program ends",
        ),
        (
            "G21 G90\nG1 X10 Y0 ,C1 F100\nM30\n",
            3,
            "chamfer `,C1` (line 2)",
        ),
    ] {
        let (l, message) = error_with(text, &o);
        assert_eq!(l, line, "{text:?}: {message}");
        assert!(message.contains(says), "{text:?}: {message}");
    }
    // After G49 I J K are arc words again: a G02 with I J reads.
    let (m, _) = read(
        "G21 G90\nG43.5 H1\nG49\nG0 X10 Y0\nG2 X0 Y-10 I-10 J0 F100\n",
        &o,
    );
    assert_eq!(xyz(&m[1]), [0.0, -10.0, 0.0]);
}
