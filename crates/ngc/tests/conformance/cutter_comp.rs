//! Cutter radius compensation G41/G42/G41.1/G42.1/G40 in the XY plane. The expected end
//! points were recorded from LinuxCNC 2.9's `rs274` run on the same programs (tool table
//! `T1 P1 D0.39370078740157477` = 10 mm diameter, as rs274 reads the table in inches;
//! output rounded to 1e-4 mm), and the simple ones are checked by hand in the comments.

use std::path::Path;

use crate::common::{compensated_options, G42_ARCS};
use ngc::{read_str_with, Axis, Dialect, Error, Motion, MoveKind, Options};

const G41_LINES: &str = "G21 G17 G90 G40\nT1 M6\nG0 X-20 Y-20\nG41 D1 G1 X0 Y0 F100\nG1 X50 Y0\nG1 X50 Y30\nG1 X20 Y30\nG1 X0 Y0\nG40 G1 X-20 Y-20\nM2\n";
const G41_1_BUMP: &str = "G21 G17 G90\nG0 X0 Y-20\nG41.1 D8 G1 X0 Y0 F200\nG1 X20 Y0\nG3 X40 Y0 I10 J0\nG1 X40 Y30\nG1 X0 Y30\nG1 X0 Y0\nG40 G1 X-10 Y-10\nM2\n";
const CONCAVE_LINE_ARC: &str = "G21 G17 G90\nT1 M6\nG0 X0 Y-20\nG41 D1 G1 X0 Y0 F100\nG1 X30 Y0\nG2 X30 Y40 I20 J20\nG1 X30 Y60\nG1 X0 Y60\nG40 G1 X-10 Y70\nM2\n";
const CONCAVE_ARC_ARC: &str = "G21 G17 G90\nT1 M6\nG0 X-10 Y-20\nG41 D1 G1 X0 Y0 F100\nG2 X20 Y0 I10 J0\nG2 X30 Y-10 I0 J-10\nG1 X30 Y-30\nG40 G1 X40 Y-40\nM2\n";

fn opts() -> Options {
    compensated_options()
}

fn moves(text: &str) -> Vec<ngc::Move> {
    let m: Vec<ngc::Move> = read_str_with(Path::new("t.ngc"), text, &opts())
        .collect::<Result<_, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"));
    // The compensated path is continuous: every move starts where the previous one ended.
    for w in m.windows(2) {
        assert_eq!(w[1].start, w[0].end, "discontinuity at line {}", w[1].line);
    }
    m
}

/// (kind, X, Y, Z, arc centre X Y and clockwise), rounded to 1e-4 as rs274 prints.
type Row = (MoveKind, [f64; 3], Option<([f64; 2], bool)>);

fn rows(m: &[ngc::Move]) -> Vec<Row> {
    let r = |v: f64| {
        let x = (v * 1e4).round() / 1e4;
        if x == 0.0 {
            0.0
        } else {
            x
        }
    };
    m.iter()
        .map(|m| {
            let arc = match m.motion {
                Motion::Arc {
                    clockwise,
                    center_mm,
                    ..
                } => Some(([r(center_mm[0]), r(center_mm[1])], clockwise)),
                _ => None,
            };
            (
                m.kind(),
                [r(m.end[Axis::X]), r(m.end[Axis::Y]), r(m.end[Axis::Z])],
                arc,
            )
        })
        .collect()
}

use MoveKind::{Arc, Feed, Rapid};

#[test]
fn g41_lines_convex_entry_corner_and_concave_corners_match_rs274() {
    let m = moves(G41_LINES);
    assert_eq!(
        rows(&m),
        [
            (Rapid, [-20.0, -20.0, 0.0], None),
            // Entry: the end offset 5 mm left of the entry direction (1, 1)/√2:
            // 5 (-1, 1)/√2 = (-3.5355, 3.5355).
            (Feed, [-3.5355, 3.5355, 0.0], None),
            // Right turn with the tool on the left: convex, an arc about the corner (0, 0),
            // clockwise, to 5 mm left of +X.
            (Arc, [0.0, 5.0, 0.0], Some(([0.0, 0.0], true))),
            // Left turns: concave, the offset lines y = 5 and x = 45 meet at (45, 5).
            (Feed, [45.0, 5.0, 0.0], None),
            (Feed, [45.0, 25.0, 0.0], None),
            (Feed, [22.6759, 25.0, 0.0], None),
            // Last compensated move before G40: 5 mm left of (0, 0) along (-2, -3)/√13.
            (Feed, [4.1603, -2.7735, 0.0], None),
            // Exit move: uncompensated.
            (Feed, [-20.0, -20.0, 0.0], None),
        ]
    );
}

#[test]
fn g42_with_arcs_a_plunge_and_convex_corners_matches_rs274() {
    let m = moves(G42_ARCS);
    assert_eq!(
        rows(&m),
        [
            (Rapid, [-30.0, 0.0, 5.0], None),
            (Feed, [-20.0, -5.0, 5.0], None),
            // The plunge waits at the compensated point.
            (Feed, [-20.0, -5.0, -2.0], None),
            (Arc, [-15.0, 0.0, -2.0], Some(([-20.0, 0.0], false))),
            // The R20 clockwise arc with the tool on its inside: R15.
            (Arc, [0.0, 15.0, -2.0], Some(([0.0, 0.0], true))),
            (Feed, [30.0, 15.0, -2.0], None),
            // The R10 clockwise arc with the tool outside: R15.
            (Arc, [35.0, 10.0, -2.0], Some(([30.0, 10.0], true))),
            (Feed, [35.0, -5.0, -2.0], None),
            (Feed, [-20.0, -5.0, -2.0], None),
            (Rapid, [-40.0, -20.0, -2.0], None),
        ]
    );
}

#[test]
fn g41_1_takes_the_diameter_from_d_and_matches_rs274() {
    // D8: radius 4. The G3 bump around (30, 0) has the tool outside (radius 14).
    let m = moves(G41_1_BUMP);
    assert_eq!(
        rows(&m),
        [
            (Rapid, [0.0, -20.0, 0.0], None),
            (Feed, [-4.0, 0.0, 0.0], None),
            (Arc, [0.0, 4.0, 0.0], Some(([0.0, 0.0], true))),
            (Feed, [20.0, 4.0, 0.0], None),
            (Arc, [24.0, 0.0, 0.0], Some(([20.0, 0.0], true))),
            (Arc, [36.0, 0.0, 0.0], Some(([30.0, 0.0], false))),
            (Feed, [36.0, 26.0, 0.0], None),
            (Feed, [4.0, 26.0, 0.0], None),
            (Feed, [4.0, 0.0, 0.0], None),
            (Feed, [-10.0, -10.0, 0.0], None),
        ]
    );
}

#[test]
fn concave_corners_with_arcs_meet_where_the_offset_paths_cross_as_in_rs274() {
    // Line (1, 0) into the R28.284 clockwise arc about (50, 20) turning 135 deg left; the
    // tool (left of a clockwise arc) is outside it: offset radius 33.284. The offset line
    // y = 5 meets that circle at x = 50 - sqrt(33.284² - 15²) = 20.2873, and the offset
    // line x = 25 of the next move at y = 20 + sqrt(33.284² - 25²) = 41.9737.
    assert_eq!(
        rows(&moves(CONCAVE_LINE_ARC)),
        [
            (Rapid, [0.0, -20.0, 0.0], None),
            (Feed, [-5.0, 0.0, 0.0], None),
            (Arc, [0.0, 5.0, 0.0], Some(([0.0, 0.0], true))),
            (Feed, [20.2873, 5.0, 0.0], None),
            (Arc, [25.0, 41.9737, 0.0], Some(([50.0, 20.0], true))),
            (Feed, [25.0, 55.0, 0.0], None),
            (Feed, [0.0, 55.0, 0.0], None),
            (Feed, [-10.0, 70.0, 0.0], None),
        ]
    );
    // Two clockwise R10 arcs meeting at a 90 deg concave corner: offset circles of radius
    // 15 about (10, 0) and (20, -10) cross at (24.3541, 4.3541) (rs274).
    assert_eq!(
        rows(&moves(CONCAVE_ARC_ARC)),
        [
            (Rapid, [-10.0, -20.0, 0.0], None),
            (Feed, [-4.9443, 1.2918, 0.0], None),
            (Arc, [24.3541, 4.3541, 0.0], Some(([10.0, 0.0], true))),
            (Arc, [35.0, -10.0, 0.0], Some(([20.0, -10.0], true))),
            (Feed, [35.0, -30.0, 0.0], None),
            (Feed, [40.0, -40.0, 0.0], None),
        ]
    );
}

#[test]
fn the_program_end_closes_compensation_like_g40() {
    // No G40: the last move still ends 5 mm left of its direction (+X): (10, 5).
    let m = moves("T1 M6\nG0 X-10 Y-10\nG41 D1 G1 X0 Y0 F100\nX10\nM2\n");
    assert_eq!(rows(&m).last().unwrap().1, [10.0, 5.0, 0.0]);
    let m = moves("T1 M6\nG0 X-10 Y-10\nG41 D1 G1 X0 Y0 F100\nX10\n");
    assert_eq!(rows(&m).last().unwrap().1, [10.0, 5.0, 0.0]);
}

#[test]
fn after_g40_a_move_without_x_y_returns_to_the_programmed_point() {
    // rs274: after G40 the current point is the programmed one, so `G1 Z-5` runs from the
    // compensated (10, 5) back to (10, 0).
    let m = moves("T1 M6\nG0 X-10 Y-10\nG41 D1 G1 X0 Y0 F100\nX10\nG40\nG1 Z-5\nX20\nM2\n");
    let r = rows(&m);
    assert_eq!(r[r.len() - 2].1, [10.0, 0.0, -5.0]);
    assert_eq!(r[r.len() - 1].1, [20.0, 0.0, -5.0]);
}

#[test]
fn an_arc_entry_move_keeps_the_end_one_radius_off_and_finds_a_new_centre() {
    // G41 with a clockwise R10 arc from (0, 0) to (20, 0): the tool is outside, so the end
    // moves 5 mm away from the centre (10, 0) to (25, 0); the arc from (0, 0) to (25, 0)
    // through the same centre line has its centre at (12.5, 0) (rs274).
    let m = moves("T1 M6\nG0 X0 Y0\nG41 D1 G2 X20 Y0 I10 F100\nM2\n");
    assert_eq!(
        rows(&m)[1],
        (Arc, [25.0, 0.0, 0.0], Some(([12.5, 0.0], true)))
    );
}

#[test]
fn a_half_turn_goes_round_the_end_as_in_rs274() {
    // X10 then back to X0 with G41: a 180 deg convex corner, an arc about (10, 0) from
    // (10, 5) to (10, -5), then the line back at Y -5 (rs274).
    let m = moves("T1 M6\nG0 X-10 Y-10\nG41 D1 G1 X0 Y0 F100\nX10\nX0\nM2\n");
    let r = rows(&m);
    assert_eq!(r[4], (Arc, [10.0, -5.0, 0.0], Some(([10.0, 0.0], true))));
    assert_eq!(r[5], (Feed, [0.0, -5.0, 0.0], None));
}

#[test]
fn compensation_refuses_what_it_cannot_do() {
    let err = |text: &str| {
        let e = read_str_with(Path::new("t.ngc"), text, &opts())
            .find_map(|m| m.err())
            .unwrap_or_else(|| panic!("expected an error in {text:?}"));
        match e {
            Error::Syntax(s) => (s.line, s.message),
            other => panic!("expected a syntax error, got {other:?}"),
        }
    };
    // rs274: "Length of cutter compensation entry move is not greater than the tool radius".
    let (line, msg) = err("T1 M6\nG0 X0 Y0\nG41 D1 G1 X3 Y0 F100\n");
    assert_eq!(line, 3);
    assert!(msg.contains("entry move"), "{msg}");
    // Tool radius 5 inside an R4 counter-clockwise arc with G41.
    let (_, msg) = err("T1 M6\nG0 X-10 Y-10\nG41 D1 G1 X0 Y0 F100\nX10\nG3 X18 Y0 I4 J0\n");
    assert!(msg.contains("arc radius"), "{msg}");
    let (_, msg) = err("G1 X0 D1 F100\n");
    assert!(msg.contains("`D` with no code"), "{msg}");
    let (_, msg) = err("T1 M6\nG41 D1\nG42 D1\n");
    assert!(msg.contains("while it is on"), "{msg}");
    let (_, msg) = err("T1 M6\nG0 X-10 Y-10\nG41 D1 G1 X0 Y0 F100\nG81 X5 Y5 Z-1 R1\n");
    assert!(msg.contains("canned cycle"), "{msg}");
    // rs274: "The move just after exiting cutter compensation mode must be straight".
    let (line, msg) = err("T1 M6\nG0 X-10 Y-10\nG41 D1 G1 X0 Y0 F100\nX10\nG40\nG2 X20 Y0 R5\n");
    assert_eq!(line, 6);
    assert!(msg.contains("must be straight"), "{msg}");
    // rs274: "Straight feed in concave corner cannot be reached by the tool without
    // gouging", at the block after the 3 mm step (the step's compensated line, from (15, 5)
    // to (15, 3), would run backwards).
    let (line, msg) = err("T1 M6\nG0 X-20 Y0\nG41 D1 G1 X0 Y0 F100\nX20\nY3\nX40\n");
    assert_eq!(line, 6);
    assert!(msg.contains("gouging"), "{msg}");
}

/// The same three programs through `rs274` itself when it is installed (CI installs it):
/// every canonical end point and arc centre agrees within rs274's 4-decimal rounding.
#[test]
fn the_programs_agree_with_rs274_when_it_is_installed() {
    let rs274 = Path::new("/usr/bin/rs274");
    if !rs274.exists() {
        if std::env::var_os("CI").is_some() {
            panic!("rs274 is missing but CI is set: install linuxcnc-uspace");
        }
        eprintln!("skipped: /usr/bin/rs274 not installed (Debian package linuxcnc-uspace)");
        return;
    }
    for (k, text) in [
        G41_LINES,
        G42_ARCS,
        G41_1_BUMP,
        CONCAVE_LINE_ARC,
        CONCAVE_ARC_ARC,
    ]
    .iter()
    .enumerate()
    {
        let dir = std::env::temp_dir().join(format!("ngc-cutter-comp-{}-{k}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("p.var"), "").unwrap();
        // rs274 reads tool-table diameters in inches: 10 mm.
        std::fs::write(dir.join("tool.tbl"), "T1 P1 D0.39370078740157477 Z0\n").unwrap();
        std::fs::write(dir.join("p.ngc"), text).unwrap();
        let status = std::process::Command::new(rs274)
            .current_dir(&dir)
            .env("HOME", &dir)
            .args([
                "-t", "tool.tbl", "-v", "p.var", "-n", "2", "-g", "p.ngc", "out.txt",
            ])
            .stdin(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .unwrap();
        assert!(status.success(), "rs274 failed on program {k}");
        let out = std::fs::read_to_string(dir.join("out.txt")).unwrap();
        let mut theirs = Vec::new();
        for line in out.lines() {
            let Some(open) = line.find('(') else { continue };
            let name = line[..open].split_whitespace().last().unwrap_or("");
            let args: Vec<f64> = line[open + 1..line.len() - 1]
                .split(',')
                .filter_map(|a| a.trim().parse().ok())
                .collect();
            match name {
                "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" => {
                    theirs.push(([args[0], args[1], args[2]], None))
                }
                "ARC_FEED" => theirs.push((
                    [args[0], args[1], args[5]],
                    Some(([args[2], args[3]], args[4] < 0.0)),
                )),
                _ => {}
            }
        }
        let ours = moves(text);
        assert_eq!(ours.len(), theirs.len(), "program {k}: {out}");
        for (m, (end, arc)) in ours.iter().zip(&theirs) {
            for (a, want) in [Axis::X, Axis::Y, Axis::Z].iter().zip(end) {
                assert!(
                    (m.end[*a] - want).abs() < 1e-4,
                    "program {k} line {}: {:?} vs {end:?}",
                    m.line,
                    m.end
                );
            }
            match (m.motion, arc) {
                (
                    Motion::Arc {
                        clockwise,
                        center_mm,
                        ..
                    },
                    Some((c, cw)),
                ) => {
                    assert_eq!(clockwise, *cw, "program {k} line {}", m.line);
                    assert!(
                        (center_mm[0] - c[0]).abs() < 1e-4 && (center_mm[1] - c[1]).abs() < 1e-4
                    );
                }
                (Motion::Arc { .. }, None) | (_, Some(_)) => {
                    panic!("program {k} line {}: arc mismatch", m.line)
                }
                _ => {}
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// A lathe profile under G18 with tools whose orientation comes from the tool table (Q2 and
/// Q7, nose radius 0.8 and 0.4 mm): compensation runs on the nose centre and every move sent
/// out is shifted to the tool's control point (orientation 2: X − r, Z − r; 7: Z − r).
/// Expected: rs274 with the same tool table (tests/data/conformance/comp_lathe_tool_table_q.ngc).
#[test]
fn lathe_tools_compensate_the_nose_centre_and_shift_by_their_orientation() {
    let table = "T4 P4 D1.6 Q2\nT5 P5 D0.8 Q7\n";
    let o = Options {
        dialect: Dialect::Linuxcnc,
        tools: ngc::parse_tool_table(table).unwrap(),
        tool_orientations: ngc::parse_tool_orientations(table).unwrap(),
        ..Options::default()
    };
    assert_eq!(o.tool_orientations, [(4, 2), (5, 7)]);
    let (line, msg) = ngc::parse_tool_orientations("T1 D1\nT2 D1 Q12\n").unwrap_err();
    assert_eq!(line, 2);
    assert!(msg.contains("Q0 to Q9"), "{msg}");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/data/conformance/comp_lathe_tool_table_q.ngc"),
    )
    .unwrap();
    let m: Vec<ngc::Move> = read_str_with(Path::new("t.ngc"), &text, &o)
        .collect::<Result<_, _>>()
        .unwrap();
    let r = |v: f64| (v * 1e4).round() / 1e4 + 0.0;
    // (X, Z) of each end and (X, Z) of each arc centre, as rs274 prints them.
    let got: Vec<([f64; 2], Option<[f64; 2]>)> = m
        .iter()
        .map(|m| {
            let c = match m.motion {
                Motion::Arc { center_mm, .. } => Some([r(center_mm[0]), r(center_mm[2])]),
                _ => None,
            };
            ([r(m.end[Axis::X]), r(m.end[Axis::Z])], c)
        })
        .collect();
    let expected: [([f64; 2], Option<[f64; 2]>); 18] = [
        ([8.0, 0.0], None),
        ([1.7, -1.6], None),
        ([-1.6, 1.7], Some([1.7, 1.7])),
        ([-1.6, 24.2], None),
        ([-6.8, 29.4], Some([-6.8, 24.2])),
        ([-13.6, 36.2], Some([-6.8, 36.2])),
        ([-13.6, 43.2], None),
        ([8.0, 44.0], None),
        ([8.0, 46.0], None),
        ([-8.0, 46.0], None),
        ([-10.0, 46.0], None),
        ([-12.9, 43.1], Some([-10.0, 43.1])),
        ([-12.9, 36.6], None),
        ([-5.9839, 30.2], Some([-6.5, 36.5791])),
        ([-0.4, 24.6], Some([-6.0, 24.6])),
        ([-0.4, 2.1], None),
        ([2.5, -0.8], Some([2.5, 2.1])),
        ([8.0, 0.0], None),
    ];
    assert_eq!(got, expected);
}

/// The geometry of every compensated move, checked against the programmed path computed here
/// from the program's own numbers: a straight move's tool-centre line lies parallel to the
/// programmed line at distance r (both ends), on the tool's side; an arc keeps the programmed
/// centre and ends at radius R − r (tool inside) or R + r (outside); a corner arc is centred
/// on the programmed corner with radius r. Shapes with convex and concave corners, both
/// sides (G41, G42), tool radius 5 mm.
#[test]
fn every_compensated_element_lies_one_tool_radius_off_the_programmed_path() {
    let shapes: [&[El]; 3] = [
        // A rectangle with a concave notch.
        &[
            ([60.0, 0.0], None),
            ([60.0, 40.0], None),
            ([40.0, 40.0], None),
            ([40.0, 25.0], None),
            ([20.0, 25.0], None),
            ([20.0, 40.0], None),
            ([0.0, 40.0], None),
            ([0.0, 0.1], None),
        ],
        // Lines and arcs of both senses, convex and concave joins.
        &[
            ([40.0, 0.0], None),
            ([60.0, 20.0], Some(([40.0, 20.0], false))),
            ([60.0, 40.0], None),
            ([40.0, 60.0], Some(([60.0, 60.0], true))),
            ([0.0, 60.0], None),
            ([-20.0, 30.0], None),
        ],
        // A slanted hexagon-like outline.
        &[
            ([30.0, 5.0], None),
            ([50.0, 30.0], None),
            ([35.0, 55.0], None),
            ([5.0, 50.0], None),
            ([-10.0, 25.0], None),
        ],
    ];
    let r = 5.0;
    for shape in shapes {
        for left in [true, false] {
            let mut text = String::from("G21 G17 G90\nT1 M6\nG0 X-30 Y-30\n");
            text += &format!("{} D1 G1 X0 Y0 F100\n", if left { "G41" } else { "G42" });
            for (end, arc) in shape {
                match arc {
                    None => text += &format!("G1 X{} Y{}\n", end[0], end[1]),
                    Some((c, cw)) => {
                        text += &format!(
                            "{} X{} Y{} I{} J{}\n",
                            if *cw { "G2" } else { "G3" },
                            end[0],
                            end[1],
                            c[0] - prev_end(shape, end)[0],
                            c[1] - prev_end(shape, end)[1]
                        )
                    }
                }
            }
            text += "G40 G0 X-40 Y-40\nM2\n";
            let m = moves(&text);
            // Programmed element of line 5 + k is shape[k], from shape[k-1] (or the origin).
            for mv in &m {
                let Some(k) = mv.line.checked_sub(5).filter(|&k| k < shape.len()) else {
                    continue;
                };
                let from = if k == 0 { [0.0, 0.0] } else { shape[k - 1].0 };
                let (to, arc) = shape[k];
                let end = [mv.end[Axis::X], mv.end[Axis::Y]];
                let start = [mv.start[Axis::X], mv.start[Axis::Y]];
                match (mv.motion, arc) {
                    (
                        Motion::Arc {
                            center_mm,
                            clockwise,
                            ..
                        },
                        _,
                    ) if center_mm[0] == from[0]
                        && center_mm[1] == from[1]
                        && arc.is_none_or(|(c, _)| c != from) =>
                    {
                        // A corner arc about the programmed corner: radius r, turning away
                        // from the tool (clockwise for G41).
                        assert_eq!(clockwise, left, "{text}");
                        assert!(
                            (dist(end, from) - r).abs() < 1e-9
                                && (dist(start, from) - r).abs() < 1e-9,
                            "{text}"
                        );
                    }
                    (
                        Motion::Arc {
                            center_mm,
                            clockwise,
                            ..
                        },
                        Some((c, cw)),
                    ) => {
                        assert_eq!(
                            (center_mm[0], center_mm[1], clockwise),
                            (c[0], c[1], cw),
                            "{text}"
                        );
                        let inside = left != cw;
                        let expected = dist(to, c) + if inside { -r } else { r };
                        assert!((dist(end, c) - expected).abs() < 1e-9, "{text}");
                    }
                    (Motion::Linear, None) => {
                        // Signed distance of both ends from the programmed line, + on the left.
                        let d = [to[0] - from[0], to[1] - from[1]];
                        let len = d[0].hypot(d[1]);
                        let side =
                            |p: [f64; 2]| (d[0] * (p[1] - from[1]) - d[1] * (p[0] - from[0])) / len;
                        let want = if left { r } else { -r };
                        assert!(
                            (side(end) - want).abs() < 1e-9 && (side(start) - want).abs() < 1e-9,
                            "{text}\nline {}: {start:?} -> {end:?}",
                            mv.line
                        );
                    }
                    other => panic!("unexpected move {other:?} at line {}\n{text}", mv.line),
                }
            }
        }
    }
}

/// A programmed element: end X, Y, and for an arc its centre X, Y and clockwise.
type El = ([f64; 2], Option<([f64; 2], bool)>);

fn dist(p: [f64; 2], q: [f64; 2]) -> f64 {
    (p[0] - q[0]).hypot(p[1] - q[1])
}

/// The start of the element ending at `end` in `shape` (the origin for the first).
fn prev_end(shape: &[El], end: &[f64; 2]) -> [f64; 2] {
    let k = shape.iter().position(|(e, _)| e == end).unwrap();
    if k == 0 {
        [0.0, 0.0]
    } else {
        shape[k - 1].0
    }
}

/// A rapid round a convex corner goes straight to the next offset start (no arc), and a
/// concave corner is cut for rapids as for feeds. Expected: rs274 on the same program
/// (G41.1 D4: r = 2).
#[test]
fn a_rapid_goes_round_a_convex_corner_straight() {
    let m = moves("G21 G90 G17\nG0 X0 Y0\nG41.1 D4\nG0 X10 Y0\nG0 X10 Y-10\nG1 X20 Y-10 F100\nG0 X20 Y-20\nG40 G0 X0 Y-30\nM2\n");
    let ends: Vec<(MoveKind, [f64; 3])> = rows(&m).into_iter().map(|(k, e, _)| (k, e)).collect();
    assert_eq!(
        ends,
        [
            (Rapid, [0.0, 0.0, 0.0]),
            (Rapid, [10.0, 2.0, 0.0]),
            (Rapid, [12.0, 0.0, 0.0]),
            (Rapid, [12.0, -8.0, 0.0]),
            (Feed, [20.0, -8.0, 0.0]),
            (Rapid, [22.0, -10.0, 0.0]),
            (Rapid, [22.0, -20.0, 0.0]),
            (Rapid, [0.0, -30.0, 0.0]),
        ]
    );
}
