//! The reader: what it accepts, what it computes, and where it reports errors.
//!
//! Expected values are written out by hand (closed-form arc centres, inch conversions,
//! exact decimal parses), never taken from the reader itself.

use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::path::Path;

use approx::assert_relative_eq;
use ngc::{read_file, read_str, AxisVec, Error, Feed, Motion, Move, Plane};
use proptest::prelude::*;

const PATH: &str = "test.nc";

/// All blocks of a program that must read without error.
fn read(text: &str) -> Vec<Move> {
    read_from(text, AxisVec::ZERO)
}

fn read_from(text: &str, start: AxisVec) -> Vec<Move> {
    read_str(Path::new(PATH), text, start)
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"))
}

/// The error of a program that must fail: (line, column, message).
fn error(text: &str) -> (usize, usize, String) {
    let mut blocks = read_str(Path::new(PATH), text, AxisVec::ZERO);
    let err = blocks
        .find_map(|b| b.err())
        .unwrap_or_else(|| panic!("expected an error in {text:?}"));
    assert!(
        blocks.next().is_none(),
        "the reader must stop after an error"
    );
    match err {
        Error::Syntax(s) => {
            assert_eq!(s.path, Path::new(PATH));
            (s.line, s.column, s.message)
        }
        other => panic!("expected Error::Syntax, got {other:?}"),
    }
}

/// Asserts the error position and that the message contains `needle`.
fn assert_error(text: &str, line: usize, column: usize, needle: &str) {
    let (l, c, message) = error(text);
    assert_eq!(
        (l, c),
        (line, column),
        "wrong position for {text:?}: {message}"
    );
    assert!(
        message.contains(needle),
        "message for {text:?} should contain {needle:?}: {message}"
    );
}

fn xyz(x: f64, y: f64, z: f64) -> AxisVec {
    AxisVec::xyzabc([x, y, z, 0.0, 0.0, 0.0])
}

fn center(block: &Move) -> [f64; 3] {
    match block.motion {
        Motion::Arc { center_mm, .. } => center_mm,
        other => panic!("expected an arc, got {other:?}"),
    }
}

// ---------------------------------------------------------------- good programs

#[test]
fn decimal_words_parse_to_the_nearest_f64() {
    let b = read("G1 X0.1 Y123.456789012345 Z-.5 A+7. B0.30000000000000004 F100");
    assert_eq!(b.len(), 1);
    assert_eq!(b[0].end.0[0].to_bits(), 0.1_f64.to_bits());
    assert_eq!(b[0].end.0[1].to_bits(), 123.456789012345_f64.to_bits());
    assert_eq!(b[0].end.0[2], -0.5);
    assert_eq!(b[0].end.0[3], 7.0);
    assert_eq!(b[0].end.0[4].to_bits(), (0.1_f64 + 0.2).to_bits());
    assert_eq!(b[0].feed, Feed::PerMinute(100.0));
}

#[test]
fn modal_state_carries_over_between_blocks() {
    let b = read("G01 X1 F500\nY2\nG00 Z3\nX4\nG1 A10 C-20\n");
    assert_eq!(b.len(), 5);
    let motions: Vec<_> = b.iter().map(|b| b.motion).collect();
    assert_eq!(
        motions,
        [
            Motion::Linear,
            Motion::Linear,
            Motion::Rapid,
            Motion::Rapid,
            Motion::Linear
        ]
    );
    assert_eq!(b[1].start, xyz(1.0, 0.0, 0.0));
    assert_eq!(b[1].end, xyz(1.0, 2.0, 0.0));
    assert_eq!(b[3].end, xyz(4.0, 2.0, 3.0));
    assert_eq!(b[4].end, AxisVec::xyzabc([4.0, 2.0, 3.0, 10.0, 0.0, -20.0]));
    // F stays in effect across the rapids, which carry none themselves.
    assert!(b.iter().all(|b| !b.tcp
        && b.feed
            == match b.motion {
                Motion::Rapid => Feed::None,
                _ => Feed::PerMinute(500.0),
            }));
    // Each block starts where the previous one ended.
    for pair in b.windows(2) {
        assert_eq!(pair[1].start, pair[0].end);
    }
}

#[test]
fn incremental_moves_accumulate_on_every_axis_from_the_start_position() {
    let start = AxisVec::xyzabc([100.0, 0.0, 0.0, 0.0, 0.0, 350.0]);
    let b = read_from("G91 G1 X0.1 C5 F100\nX0.1 C5\nX0.1 C5\nG90 X0\n", start);
    assert_eq!(b.len(), 4);
    assert_eq!(b[0].start, start);
    // Sums written out in the same order the controller adds them.
    assert_eq!(b[2].end.0[0], 100.0 + 0.1 + 0.1 + 0.1);
    assert_eq!(b[2].end.0[5], 365.0, "rotary axes are incremental too");
    assert_eq!(b[3].end.0[0], 0.0, "G90 returns to absolute");
    assert_eq!(b[3].end.0[5], 365.0);
}

#[test]
fn inch_words_are_converted_to_mm_and_rotary_words_stay_in_degrees() {
    let b = read("G20 G1 X1 Y0.5 C90 F10\nG91 Z-2\nG21 G90 X1\n");
    assert_eq!(b[0].end, AxisVec::xyzabc([25.4, 12.7, 0.0, 0.0, 0.0, 90.0]));
    assert_eq!(
        b[0].feed,
        Feed::PerMinute(254.0),
        "F 10 in/min is 254 mm/min"
    );
    assert_eq!(b[1].end.0[2], -50.8);
    assert_eq!(b[2].end.0[0], 1.0, "G21 reads mm again");
    assert_eq!(
        b[2].feed,
        Feed::PerMinute(254.0),
        "the feed in effect stays in mm/min"
    );
}

#[test]
fn inch_arc_offsets_and_radius_are_converted() {
    let b = read("G20 G17 G2 X2 Y0 I1 J0 F1\nG3 X0 Y0 R1\n");
    assert_relative_eq!(center(&b[0])[0], 25.4);
    assert_relative_eq!(center(&b[1])[0], 25.4);
    assert_relative_eq!(b[1].arc_sweep_rad().unwrap(), PI);
}

#[test]
fn arc_centre_from_i_j_is_incremental_from_the_start() {
    // From (10, 0): a quarter circle about the origin to (0, 10).
    let b = read_from(
        "G17 G3 X0 Y10 I-10 J0 F200\nG2 X10 Y0 I0 J-10\n",
        xyz(10.0, 0.0, 0.0),
    );
    assert_eq!(
        b[0].motion,
        Motion::Arc {
            clockwise: false,
            plane: Plane::XY,
            center_mm: [0.0, 0.0, 0.0]
        }
    );
    assert_relative_eq!(b[0].arc_sweep_rad().unwrap(), FRAC_PI_2);
    assert_eq!(center(&b[1]), [0.0, 0.0, 0.0]);
    assert_relative_eq!(b[1].arc_sweep_rad().unwrap(), -FRAC_PI_2);
}

#[test]
fn arc_centre_from_r_takes_the_short_arc_for_positive_r_and_the_long_arc_for_negative() {
    // From (0, 0) to (10, 10) with |R| = 10 the two candidate centres are (10, 0) and (0, 10).
    // Clockwise short arc: centre on the right of the chord, (10, 0).
    let cases = [
        ("G2 X10 Y10 R10", [10.0, 0.0], -FRAC_PI_2),
        ("G2 X10 Y10 R-10", [0.0, 10.0], -3.0 * FRAC_PI_2),
        ("G3 X10 Y10 R10", [0.0, 10.0], FRAC_PI_2),
        ("G3 X10 Y10 R-10", [10.0, 0.0], 3.0 * FRAC_PI_2),
    ];
    for (block, expected, sweep) in cases {
        let b = read(&format!("F100 {block}"));
        let c = center(&b[0]);
        assert_relative_eq!(c[0], expected[0], epsilon = 1e-12);
        assert_relative_eq!(c[1], expected[1], epsilon = 1e-12);
        assert_relative_eq!(b[0].arc_sweep_rad().unwrap(), sweep, epsilon = 1e-12);
    }
}

#[test]
fn half_circle_by_r_has_its_centre_on_the_chord() {
    let b = read("G2 X10 R5 F100");
    assert_eq!(center(&b[0]), [5.0, 0.0, 0.0]);
    assert_relative_eq!(b[0].arc_sweep_rad().unwrap(), -PI);
}

#[test]
fn full_circles_by_i_j_k() {
    let b = read_from(
        "G2 I5 F100\nG3 X10 Y0 I-5 J0\nG18 G3 K-5\n",
        xyz(10.0, 0.0, 0.0),
    );
    assert_eq!(b.len(), 3);
    assert_eq!(b[0].end, b[0].start);
    assert_eq!(center(&b[0]), [15.0, 0.0, 0.0]);
    assert_eq!(b[0].arc_sweep_rad(), Some(-TAU));
    assert_eq!(center(&b[1]), [5.0, 0.0, 0.0]);
    assert_eq!(b[1].arc_sweep_rad(), Some(TAU));
    assert_eq!(
        b[2].motion,
        Motion::Arc {
            clockwise: false,
            plane: Plane::ZX,
            center_mm: [10.0, 0.0, -5.0]
        }
    );
}

#[test]
fn arcs_in_the_zx_and_yz_planes() {
    // G18: u = Z, v = X. From the origin, counter-clockwise half circle to Z = 10.
    let b = read("G18 G3 X0 Z10 K5 F100\nG19 G2 Y10 Z10 J5 K0\n");
    assert_eq!(center(&b[0]), [0.0, 0.0, 5.0]);
    assert_relative_eq!(b[0].arc_sweep_rad().unwrap(), PI);
    // G19: u = Y, v = Z. From (0, 0, 10) clockwise half circle about (0, 5, 10) to Y = 10.
    assert_eq!(center(&b[1]), [0.0, 5.0, 10.0]);
    assert_relative_eq!(b[1].arc_sweep_rad().unwrap(), -PI);
}

#[test]
fn helical_arc_moves_the_normal_axis_linearly_and_keeps_the_start_normal_in_the_centre() {
    let b = read_from("G17 G2 X20 Y10 Z-5 I0 J-10 F100", xyz(10.0, 20.0, 3.0));
    assert_eq!(b[0].end, xyz(20.0, 10.0, -5.0));
    assert_eq!(center(&b[0]), [10.0, 10.0, 3.0]);
}

#[test]
fn inverse_time_feed_is_read_per_block_and_not_converted() {
    let b = read("G20 G93 G1 X1 F2\nX2 F0.5\nG0 X0\nG94 G1 X1 F10\n");
    assert_eq!(b[0].feed, Feed::InverseTime(2.0));
    assert_eq!(b[1].feed, Feed::InverseTime(0.5));
    assert_eq!((b[2].motion, b[2].feed), (Motion::Rapid, Feed::None));
    assert_eq!(b[3].feed, Feed::PerMinute(254.0));
}

#[test]
fn dwell_by_p_in_ms_and_by_x_in_s() {
    let b = read_from("G04 P500\nG4 X2.5\nG20 G4 X1\n", xyz(1.0, 2.0, 3.0));
    assert_eq!(b[0].motion, Motion::Dwell { seconds: 0.5 });
    assert_eq!(b[1].motion, Motion::Dwell { seconds: 2.5 });
    assert_eq!(
        b[2].motion,
        Motion::Dwell { seconds: 1.0 },
        "X of G04 is a time, never inches"
    );
    assert!(b
        .iter()
        .all(|b| b.start == xyz(1.0, 2.0, 3.0) && b.end == b.start));
}

#[test]
fn g43_4_turns_tool_centre_point_control_on_and_g49_off() {
    let b = read("G1 X1 F100\nG43.4 H1\nX2\nG49\nX3\n");
    let tcp: Vec<bool> = b.iter().map(|b| b.tcp).collect();
    assert_eq!(tcp, [false, true, false]);
}

#[test]
fn comments_block_delete_sequence_numbers_and_percent_lines() {
    let program = "\
%
O1000 (TEST PROGRAM)
N10 G21 G90 G94 G17 ; set up
/N20 G1 X99 F1
  N30 G1 X1 F100 (move) Y2 (two comments)
(a line of comment only)
N40 M30
N50 G1 X2
%
";
    let b = read(program);
    assert_eq!(b.len(), 1);
    assert_eq!(b[0].line, 5);
    assert_eq!(b[0].end, xyz(1.0, 2.0, 0.0));
    assert_eq!(
        b[0].feed,
        Feed::PerMinute(100.0),
        "the deleted block's F1 is not read"
    );
}

#[test]
fn reading_stops_at_m30_m02_and_the_closing_percent() {
    assert_eq!(
        read("G0 X1\nM30\nG0 X2\n#1 = 5 this is not read\n").len(),
        1
    );
    assert_eq!(read("G0 X1 M02\nG0 X2\n").len(), 1);
    assert_eq!(read("%\nG0 X1\n%\nG0 X2 ###\n").len(), 1);
}

#[test]
fn line_numbers_count_blank_lines_comments_and_crlf_endings() {
    let b = read("\r\n(comment)\r\n\r\nG0 X1\r\n; x\r\n\n\tG0 X2\r\n");
    let lines: Vec<usize> = b.iter().map(|b| b.line).collect();
    assert_eq!(lines, [4, 7]);
}

#[test]
fn lower_case_words_and_blanks_inside_words_are_read() {
    let b = read("g1 x 1.5 y-2 f 100");
    assert_eq!(b[0].end, xyz(1.5, -2.0, 0.0));
}

#[test]
fn codes_that_cancel_unmodelled_features_and_s_t_m_words_are_accepted() {
    let b = read("G40 G49 G80 G54 G17 G90 G94 G21\nT1 M06\nS1000 M03 M08\nM00\nM01\nM04\nG1 X1 F100 M05 M09\n");
    assert_eq!(b.len(), 1);
    assert_eq!(b[0].line, 7);
}

#[test]
fn blocks_that_only_change_modal_state_produce_nothing() {
    assert!(read("G90\nG17 G21\nF100\nG1\nG43.4\nG49\n").is_empty());
}

#[test]
fn a_file_with_tcp_and_inverse_time_reads_block_by_block() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/five_axis_tcp.nc");
    let b: Vec<Move> = read_file(&path, AxisVec::ZERO)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    let lines: Vec<usize> = b.iter().map(|b| b.line).collect();
    assert_eq!(lines, [8, 10, 11, 12, 13, 15]);
    assert_eq!(b[0].end, xyz(0.0, 0.0, 50.0));
    assert!(!b[0].tcp && b[1].tcp && b[4].tcp && !b[5].tcp);
    assert_eq!(b[2].end, AxisVec::xyzabc([10.0, 0.0, 10.0, 5.0, 0.0, 90.0]));
    assert_eq!(b[2].feed, Feed::InverseTime(2.5));
    assert_eq!(b[4].feed, Feed::PerMinute(1000.0));
    assert_eq!(b[5].motion, Motion::Dwell { seconds: 0.25 });
}

#[test]
fn a_200k_block_program_streams() {
    let mut text = String::from("G90 G1 F1000\n");
    for i in 0..200_000 {
        text.push_str(&format!("N{i} X{i}.5 Y-{i}.25\n"));
    }
    text.push_str("M30\n");
    let mut count = 0;
    let mut last = None;
    for block in read_str(Path::new(PATH), &text, AxisVec::ZERO) {
        let block = block.unwrap();
        count += 1;
        last = Some(block);
    }
    assert_eq!(count, 200_000);
    let last = last.unwrap();
    assert_eq!(last.line, 200_001);
    assert_eq!(last.end, xyz(199_999.5, -199_999.25, 0.0));
}

// ---------------------------------------------------------------- errors

#[test]
fn a_missing_file_is_a_read_error() {
    let err = read_file(Path::new("/nonexistent/dir/x.nc"), AxisVec::ZERO).err();
    assert!(matches!(err, Some(Error::Read { .. })));
}

#[test]
fn the_example_error_is_on_line_3_column_5() {
    assert_error(
        "G21\nG90 (absolute)\nG01 X1.2.3 F100\n",
        3,
        5,
        "malformed number `1.2.3`",
    );
}

#[test]
fn unsupported_constructs_are_reported_at_their_word() {
    let cases: &[(&str, usize, usize, &str)] = &[
        (
            "G0 X#1\nG0 X#<nope>\n",
            2,
            5,
            "parameter `#<nope>` is not defined",
        ),
        ("G0 X0\nM98 P1000\n", 2, 1, "subroutine `1000` not found"),
        (
            "G90\nG12 X0 Y0 Z-5 R1 F100\n",
            2,
            1,
            "unsupported code `G12`",
        ),
        (
            "G17 G68.3 X0 Y0 R30\n",
            1,
            5,
            "`G68.3` (G68.x other than G68.2",
        ),
        (
            "G68.2 X0 Y0 Z0 I0 J45 K0\nG53.1\n",
            2,
            1,
            "G53.1 on a machine without a rotary table",
        ),
        ("G41.1 D5\n", 1, 1, "unsupported code `G41.1`"),
        (
            "G1 F100\nG19 G42 X0\n",
            2,
            5,
            "cutter radius compensation in G19",
        ),
        ("G1 U5\n", 1, 4, "`U5`: this machine has no U axis"),
        // (M10/M11 and G05 are Fanuc rotary clamps and high-speed mode: tests/fanuc_haas.rs.)
        ("M31\n", 1, 1, "unsupported code `M31`"),
        ("G06\n", 1, 1, "unsupported code `G06`"),
        ("G1.5\n", 1, 1, "unsupported code `G1.5`"),
        ("G-1\n", 1, 1, "unsupported code `G-1`"),
    ];
    for &(text, line, column, needle) in cases {
        assert_error(text, line, column, needle);
    }
}

#[test]
fn malformed_words_are_reported_with_what_was_expected() {
    let cases: &[(&str, usize, usize, &str)] = &[
        ("G1 X1.2.3 F100\n", 1, 4, "malformed number `1.2.3`"),
        ("G1 X F100\n", 1, 4, "`X` has no number"),
        ("G1 X- F100\n", 1, 4, "malformed number `-`"),
        ("G1 X. F100\n", 1, 4, "malformed number `.`"),
        ("G1 X1-2 F100\n", 1, 4, "malformed number `1-2`"),
        ("G1 X1 F100 *\n", 1, 12, "unexpected character `*`"),
        ("G1 X1 F100 (no end\n", 1, 12, "unclosed comment"),
        ("G1 X1 / Y2 F100\n", 1, 7, "block delete `/` in the middle"),
        ("G1 X1 % F100\n", 1, 7, "`%` inside a block"),
        ("% G1\n", 1, 3, "word on a `%` line"),
        ("N10.5 G0 X0\n", 1, 1, "expected a whole number after `N`"),
        ("T-1\n", 1, 1, "expected a whole number after `T`"),
        ("G0 X1é\n", 1, 6, "unexpected character `é`"),
        (&format!("G0 X1{}\n", "0".repeat(400)), 1, 4, "too large"),
    ];
    for &(text, line, column, needle) in cases {
        assert_error(text, line, column, needle);
    }
}

#[test]
fn words_in_the_wrong_place_or_twice_are_errors() {
    let cases: &[(&str, usize, usize, &str)] = &[
        (
            "G1 X1 Y2 X3 F100\n",
            1,
            10,
            "repeated `X` word (first `X1`)",
        ),
        ("G1 F100 X1 F200\n", 1, 12, "repeated `F` word"),
        (
            "G0 G1 X1 F100\n",
            1,
            4,
            "`G0` and `G1` are in the same modal group",
        ),
        ("G90 G91\n", 1, 5, "same modal group"),
        ("G20 G21\n", 1, 5, "same modal group"),
        ("G17 G18\n", 1, 5, "same modal group"),
        ("G93 G94\n", 1, 5, "same modal group"),
        ("G43.4 G49\n", 1, 7, "same modal group"),
        ("G1 G4 P100\n", 1, 4, "same modal group"),
        ("M03 M05\n", 1, 5, "same group"),
        ("M00 M30\n", 1, 5, "same group"),
        // (`H` alone is a Fanuc length offset number: tests/fanuc_haas.rs.)
        ("G1 X1 P5 F100\n", 1, 7, "`P` with no code that uses it"),
        ("G0 X1 I5\n", 1, 7, "`I5` outside an arc"),
        ("G4\n", 1, 1, "without a time"),
        ("G4 P1 X1\n", 1, 7, "both P and X"),
        ("G4 Y1\n", 1, 4, "`Y1` in a G04 block"),
        ("G4 P-5\n", 1, 4, "negative dwell"),
        // F0 sets no feed, as in LinuxCNC ("Cannot do G1 with zero feed rate").
        ("G1 X1 F0\n", 1, 1, "no feed programmed (or F0)"),
        ("G0 X1 F0\nG1 X2\n", 2, 1, "no feed programmed (or F0)"),
        ("G1 X1 F-1\n", 1, 7, "expected a feed of zero or more"),
        ("S-100\n", 1, 1, "negative spindle speed"),
    ];
    for &(text, line, column, needle) in cases {
        assert_error(text, line, column, needle);
    }
}

#[test]
fn modal_errors_name_the_block() {
    let cases: &[(&str, usize, usize, &str)] = &[
        ("G90\n  X10\n", 2, 3, "axis word with no motion mode"),
        ("G1 X10\n", 1, 1, "feed move with no feed programmed"),
        (
            "G0 X1\nG2 X2 I0.5\n",
            2,
            1,
            "feed move with no feed programmed",
        ),
        ("G93 G1 X1 F2\nG1 X2\n", 2, 1, "without F"),
        ("G93 G1 X1 F2\nX2\n", 2, 1, "without F"),
        // Switching feed mode drops the F of the old mode.
        (
            "G1 X1 F100\nG93\nG94\nX2\n",
            4,
            1,
            "feed move with no feed programmed",
        ),
    ];
    for &(text, line, column, needle) in cases {
        assert_error(text, line, column, needle);
    }
}

#[test]
fn inconsistent_arcs_are_errors_naming_the_line() {
    let cases: &[(&str, usize, usize, &str)] = &[
        // Start radius 5, end radius 6.
        (
            "F100\nG2 X11 Y0 I5 J0\n",
            2,
            1,
            "radius at the start is 5.000000 mm but at the end 6.000000 mm",
        ),
        ("F100\nG2 X10 Y0\n", 2, 1, "arc without a centre"),
        ("F100\nG2 X10 Y0 I0 J0\n", 2, 1, "arc of radius zero"),
        (
            "F100\nG17 G2 X10 Y0 I5 K1\n",
            2,
            18,
            "`K1` is not in the arc plane G17 (XY)",
        ),
        (
            "F100\nG2 X10 Y0 R4.9\n",
            2,
            11,
            "shorter than half the chord",
        ),
        ("F100\nG2 Z5 R10\n", 2, 7, "R arc whose end is its start"),
        ("F100\nG2 X10 R0\n", 2, 8, "arc of radius zero"),
    ];
    for &(text, line, column, needle) in cases {
        assert_error(text, line, column, needle);
    }
    // Within the 1e-3 mm tolerance the arc is accepted.
    assert_eq!(read("F100 G2 X10.0009 Y0 I5 J0").len(), 1);
    assert_eq!(read("F100 G2 X10.0019 R5").len(), 1);
}

/// An arc with both R and I J K: Fanuc and Haas take R ("the arc specified by address R
/// takes precedence, the other addresses are ignored"), LinuxCNC refuses it.
#[test]
fn an_arc_with_r_and_i_j_k_takes_r_on_fanuc_and_haas_and_is_an_error_on_linuxcnc() {
    // From (0, 0) to (10, 0) with R5: the centre is (5, 0) whatever I5 J3 would say.
    let text = "F100\nG2 X10 Y0 I5 J3 R5\n";
    for dialect in [ngc::Dialect::Fanuc, ngc::Dialect::Haas] {
        let options = ngc::Options {
            dialect,
            ..ngc::Options::default()
        };
        let moves: Vec<Move> = ngc::read_str_with(Path::new(PATH), text, &options)
            .collect::<Result<_, _>>()
            .unwrap();
        match moves[0].motion {
            Motion::Arc { center_mm, .. } => assert_eq!((center_mm[0], center_mm[1]), (5.0, 0.0)),
            ref m => panic!("{dialect:?}: expected an arc, got {m:?}"),
        }
    }
    let options = ngc::Options {
        dialect: ngc::Dialect::Linuxcnc,
        ..ngc::Options::default()
    };
    let err = ngc::read_str_with(Path::new(PATH), text, &options)
        .find_map(|m| m.err())
        .unwrap();
    assert!(err.to_string().contains("both R and I J K"), "{err}");
}

#[test]
fn file_errors_point_into_the_file_with_crlf_endings() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad_macro_crlf.nc");
    let results: Vec<_> = read_file(&path, AxisVec::ZERO).unwrap().collect();
    assert_eq!(results.len(), 2, "one block, then the error, then nothing");
    assert!(results[0].is_ok());
    match &results[1] {
        Err(err @ Error::Syntax(s)) => {
            assert_eq!((s.line, s.column), (4, 10));
            let shown = err.to_string();
            assert!(
                shown.contains("bad_macro_crlf.nc:4:10: parameter `#5` outside a word"),
                "{shown}"
            );
        }
        other => panic!("expected an error at the macro, got {other:?}"),
    }
}

#[test]
fn errors_carry_the_span_and_help() {
    let err = read_str(Path::new(PATH), "G0 X0\nG12 X1 Y1 Z-3 R1\n", AxisVec::ZERO)
        .find_map(|b| b.err())
        .unwrap();
    let Error::Syntax(s) = &err else {
        panic!("expected a syntax error, got {err:?}")
    };
    assert_eq!(&s.text[s.span.clone()], "G12");
    assert!(
        s.help.as_deref().unwrap_or("").contains("docs/gcode.md"),
        "{s:?}"
    );
    assert!(err.to_string().starts_with("test.nc:2:1:"), "{err}");
}

// ---------------------------------------------------------------- robustness

/// Words and fragments that exercise the interpreter more than random characters do.
fn fragment() -> impl Strategy<Value = String> {
    prop_oneof![
        "[ -~]{0,6}",
        prop::sample::select(vec![
            "G0", "G1", "G2", "G3", "G4", "G17", "G18", "G19", "G20", "G21", "G90", "G91", "G93",
            "G94", "G43.4", "G49", "M30", "M2", "M3", "%", "/", "(", ")", ";", "#1", "F", "P",
            "H1", "R", "I", "J", "K", "X", "Y", "Z", "A", "B", "C", " ", "N10", "O1",
        ])
        .prop_map(String::from),
        (
            prop::sample::select(vec!["X", "Y", "Z", "A", "C", "I", "J", "K", "R", "F", "P"]),
            -1e6f64..1e6
        )
            .prop_map(|(l, v)| format!("{l}{v}")),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn random_printable_garbage_never_panics(lines in prop::collection::vec("[ -~\t]{0,60}", 0..20)) {
        let text = lines.join("\n");
        let results: Vec<_> = read_str(Path::new(PATH), &text, AxisVec::ZERO).collect();
        // At most one error, and only as the last item.
        let errors = results.iter().filter(|r| r.is_err()).count();
        prop_assert!(errors <= 1);
        if errors == 1 {
            prop_assert!(results.last().unwrap().is_err());
        }
    }

    #[test]
    fn random_word_soup_never_panics_and_positions_stay_finite(
        lines in prop::collection::vec(prop::collection::vec(fragment(), 0..8), 0..20)
    ) {
        let text: Vec<String> = lines.iter().map(|l| l.join(" ")).collect();
        let text = text.join("\n");
        for result in read_str(Path::new(PATH), &text, AxisVec::ZERO) {
            match result {
                Ok(block) => {
                    prop_assert!(block.end.is_finite());
                    if let Motion::Arc { center_mm, .. } = block.motion {
                        prop_assert!(center_mm.iter().all(|v| v.is_finite()));
                    }
                }
                Err(Error::Syntax(s)) => {
                    prop_assert!(s.line >= 1 && s.column >= 1);
                }
                Err(other) => prop_assert!(false, "unexpected error kind {other:?}"),
            }
        }
    }
}
