//! The Siemens Sinumerik front end: each part of `tests/program/siemens_parts/NN-name/`
//! written by hand in LinuxCNC RS274/NGC (`linuxcnc.ngc`) and in Sinumerik
//! (`siemens.mpf`) gives the same canonical moves (same kinds, positions and arc centres
//! within 1e-6 mm); and constructs whose results are worked out by hand here.

use std::path::{Path, PathBuf};

use ngc::{read_file_with, read_str_with, AxisVec, Dialect, Error, Motion, Move, Options, UserM};

fn parts_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/program/siemens_parts")
}

/// The options both dialects of a part read with: the part's tool table (`tools.tbl`) if
/// it has one, work offsets G55 (100 50 0), G56 (-20 30 -5), G57 (0 0 10), and M428/M429
/// mapped to TCP on/off (LinuxCNC has no TCP code of its own).
fn options(dialect: Dialect, dir: &Path) -> Options {
    let mut o = Options {
        dialect,
        search_path: vec![dir.to_path_buf()],
        ..Options::default()
    };
    if let Ok(text) = std::fs::read_to_string(dir.join("tools.tbl")) {
        o.tools = ngc::parse_tool_table(&text).expect("tools.tbl");
    }
    o.set_work_offset(2, AxisVec::xyzabc([100.0, 50.0, 0.0, 0.0, 0.0, 0.0]));
    o.set_work_offset(3, AxisVec::xyzabc([-20.0, 30.0, -5.0, 0.0, 0.0, 0.0]));
    o.set_work_offset(4, AxisVec::xyzabc([0.0, 0.0, 10.0, 0.0, 0.0, 0.0]));
    o.user_m.insert(428, UserM::TcpOn);
    o.user_m.insert(429, UserM::TcpOff);
    o
}

fn read(path: &Path, o: &Options) -> Vec<Move> {
    read_file_with(path, o)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("{e}"))
}

fn moves(text: &str) -> Vec<Move> {
    read_str_with(
        Path::new("t.mpf"),
        text,
        &options(Dialect::Siemens, Path::new(".")),
    )
    .collect::<Result<Vec<_>, _>>()
    .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"))
}

fn error(text: &str) -> (usize, usize, String) {
    let err = read_str_with(
        Path::new("t.mpf"),
        text,
        &options(Dialect::Siemens, Path::new(".")),
    )
    .find_map(|m| m.err())
    .unwrap_or_else(|| panic!("expected an error in {text:?}"));
    match err {
        Error::Syntax(s) => (s.line, s.column, s.message),
        other => panic!("expected a syntax error, got {other:?}"),
    }
}

fn centre(m: &Move) -> Option<[f64; 3]> {
    match m.motion {
        Motion::Arc { center_mm, .. } => Some(center_mm),
        _ => None,
    }
}

/// The first difference between two move lists, if any.
/// Path control is compared too, except in drilling cycles (`cycles`): LinuxCNC runs a
/// canned cycle's moves in exact stop, and the Sinumerik manual does not say.
fn difference(a: &[Move], b: &[Move], cycles: bool) -> Option<String> {
    if a.len() != b.len() {
        return Some(format!("{} moves against {}", a.len(), b.len()));
    }
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        let close = |p: [f64; 9], q: [f64; 9]| p.iter().zip(&q).all(|(u, v)| (u - v).abs() <= 1e-6);
        let same_arc = match (x.motion, y.motion) {
            (
                Motion::Arc {
                    clockwise: c1,
                    plane: p1,
                    ..
                },
                Motion::Arc {
                    clockwise: c2,
                    plane: p2,
                    ..
                },
            ) => {
                c1 == c2
                    && p1 == p2
                    && centre(x)
                        .zip(centre(y))
                        .is_some_and(|(u, v)| u.iter().zip(&v).all(|(s, t)| (s - t).abs() <= 1e-6))
            }
            (Motion::Dwell { seconds: s }, Motion::Dwell { seconds: t }) => (s - t).abs() < 1e-9,
            _ => true,
        };
        if x.kind() != y.kind()
            || !close(x.start.0, y.start.0)
            || !close(x.end.0, y.end.0)
            || !same_arc
            || x.tcp != y.tcp
            || (x.path != y.path && !cycles)
            || x.feed
                .rate()
                .zip(y.feed.rate())
                .is_some_and(|(f, g)| (f - g).abs() > 1e-9)
        {
            return Some(format!("move {k}:\n linuxcnc line {} {:?} {:?}->{:?} tcp {} {:?} F{:?}\n siemens  line {} {:?} {:?}->{:?} tcp {} {:?} F{:?}", x.line, x.motion, x.start.to_xyzabc(), x.end.to_xyzabc(), x.tcp, x.path, x.feed, y.line, y.motion, y.start.to_xyzabc(), y.end.to_xyzabc(), y.tcp, y.path, y.feed));
        }
    }
    None
}

#[test]
fn every_part_gives_the_same_moves_in_linuxcnc_and_siemens() {
    let mut parts: Vec<PathBuf> = std::fs::read_dir(parts_dir())
        .expect("tests/program/siemens_parts")
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    parts.sort();
    let mut failures = Vec::new();
    for part in &parts {
        let lcnc = read(
            &part.join("linuxcnc.ngc"),
            &options(Dialect::Linuxcnc, part),
        );
        let sie = read(&part.join("siemens.mpf"), &options(Dialect::Siemens, part));
        assert!(
            lcnc.len() >= 3,
            "{}: too few moves to compare",
            part.display()
        );
        if let Some(d) = difference(&lcnc, &sie, part.ends_with("04-drilling")) {
            failures.push(format!("{}: {d}", part.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        parts.len() >= 10,
        "expected at least 10 parts, found {}",
        parts.len()
    );
    eprintln!(
        "siemens parts: {} of {} identical",
        parts.len() - failures.len(),
        parts.len()
    );
}

fn ends(ms: &[Move]) -> Vec<[f64; 3]> {
    ms.iter()
        .map(|m| {
            let e = m.end.to_xyzabc();
            [e[0], e[1], e[2]].map(|v| (v * 1e9).round() / 1e9 + 0.0)
        })
        .collect()
}

#[test]
fn extended_work_offsets_g505_to_g599_are_the_fanuc_extended_offsets() {
    // G505 is extended offset 1, whose X Y Z the parameters 7001-7003 hold.
    let mut o = options(Dialect::Siemens, Path::new("."));
    o.parameters
        .extend([(7001, 10.0), (7002, 20.0), (7003, -5.0)]);
    let ms: Vec<Move> = read_str_with(Path::new("t.mpf"), "G505 G0 X1 Y1 Z1\nG54 X1\nM30\n", &o)
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(ends(&ms), vec![[11.0, 21.0, -4.0], [1.0, 21.0, -4.0]]);
}

#[test]
fn gotob_loops_and_if_gotof_jumps_run_the_blocks_a_control_would() {
    // R1 counts 1, 2, 3: three moves X1 X2 X3, then the jump skips X99.
    let ms = moves(
        "R1=0\nTOP: R1=R1+1\nG1 X=R1 F100\nIF R1<3 GOTOB TOP\nGOTOF N90\nG1 X99\nN90 G0 Z7\nM30\n",
    );
    assert_eq!(
        ends(&ms),
        vec![
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [3.0, 0.0, 7.0]
        ]
    );
}

#[test]
fn scale_rotation_about_x_and_mirror_map_points_as_the_frame_chain_says() {
    // SCALE X2 Y2: a CR=5 arc from (0,0) to (10,0) lands from (0,0) to (20,0), radius 10,
    // centre (10,0). ROT X90: frame Y10 is work Z10 (Rx(90) e_y = e_z).
    let ms = moves("G17 G0 X0 Y0\nSCALE X2 Y2\nG2 X10 Y0 CR=5 F100\nROT X90\nG1 X0 Y10 Z0\nM30\n");
    let e = ends(&ms);
    assert_eq!(e[1], [20.0, 0.0, 0.0]);
    let c = centre(&ms[1]).unwrap();
    assert!((c[0] - 10.0).abs() < 1e-9 && c[1].abs() < 1e-9, "{c:?}");
    assert_eq!(e[2], [0.0, 0.0, 10.0]);
}

#[test]
fn tools_by_name_cycle800_reset_and_machine_m_codes_read_with_notices() {
    let o = options(Dialect::Siemens, Path::new("."));
    let mut r = read_str_with(
        Path::new("t.mpf"),
        "T=\"DRILL 8.5\" M6\nCYCLE800()\nM50\nG0 X1\nM30\n",
        &o,
    );
    let ms: Vec<Move> = r.by_ref().collect::<Result<_, _>>().unwrap();
    assert_eq!(ms[0].tool, 1001);
    let notes: Vec<&str> = r.notices().iter().map(|n| n.message.as_str()).collect();
    assert!(
        notes
            .iter()
            .any(|n| n.contains("DRILL 8.5") && n.contains("T1001")),
        "{notes:?}"
    );
    assert!(notes.iter().any(|n| n.contains("M50")), "{notes:?}");
}

#[test]
fn what_is_not_read_is_refused_with_line_column_and_the_construct_named() {
    let cases: [(&str, usize, usize, &str); 10] = [
        ("G1 X1 F1\nG2 X10 AR=90 CR=5\n", 2, 8, "AR=90 with CR="),
        (
            "G1 X1 F1\nCIP X10 Y0 I1=5 J1=0\n",
            2,
            5,
            "CIP with its start, intermediate and end points on one line",
        ),
        (
            "G1 X1 A3=0 B3=0 C3=1 F1\n",
            1,
            7,
            "A3= B3= C3= (the tool's direction vector) without TRAORI",
        ),
        (
            "G0 X1\nN20 R1=$P_UIFR[1,X,TR]\n",
            2,
            8,
            "system variable `$P_UIFR`",
        ),
        (
            "G0 X1\nCYCLE83(10,0,1,-20)\n",
            2,
            1,
            "CYCLE83 without a first drilling depth",
        ),
        ("N10 G33 Z-10 K1\n", 1, 5, "`G33`"),
        ("DEF POINT PT\n", 1, 5, "DEF POINT"),
        ("R1=GETT(\"A\")\n", 1, 4, "`GETT`"),
        (
            "G1 X1 F1\nCYCLE800(1,\"TC1\",0,27,0,0,0,0,30,0,0,0,0,-1)\n",
            2,
            1,
            "CYCLE800 swivel mode 27",
        ),
        ("NOSUCHPROG\n", 1, 1, "`NOSUCHPROG` is neither"),
    ];
    for (text, line, column, named) in cases {
        let (l, c, m) = error(text);
        assert_eq!((l, c), (line, column), "{text:?}: {m}");
        assert!(m.contains(named), "{text:?}: {m}");
    }
}

#[test]
fn loops_and_nesting_are_bounded() {
    let mut o = options(Dialect::Siemens, Path::new("."));
    o.max_blocks = 1000;
    let err = read_str_with(Path::new("t.mpf"), "LOOP\nG0 X1\nENDLOOP\n", &o)
        .find_map(|m| m.err())
        .expect("an endless loop is an error");
    assert!(
        err.to_string().contains("more than 1000 blocks executed"),
        "{err}"
    );
    let deep = "IF 1\n".repeat(17) + &"ENDIF\n".repeat(17);
    let (line, _, m) = error(&deep);
    assert_eq!(line, 17, "{m}");
    assert!(m.contains("nested deeper than 16"), "{m}");
    // A subprogram that calls itself stops at the call depth.
    let dir = std::env::temp_dir().join(format!("ngc-siemens-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("SELF.SPF"), "G1 X1 F1\nSELF\nM17\n").unwrap();
    let err = read_str_with(
        Path::new("t.mpf"),
        "SELF\nM30\n",
        &options(Dialect::Siemens, &dir),
    )
    .find_map(|m| m.err())
    .expect("endless recursion is an error");
    assert!(err.to_string().contains("nested deeper"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_long_program_file_streams_and_jumps_back_by_offset() {
    // 200 000 blocks inside a WHILE run twice: 400 000 moves, read from the file.
    let dir = std::env::temp_dir().join(format!("ngc-siemens-long-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut text = String::from("DEF INT CNT=0\nWHILE CNT<2\nCNT=CNT+1\n");
    for k in 0..200_000 {
        text.push_str(&format!("G1 X{} Y=CNT F1000\n", k % 100));
    }
    text.push_str("ENDWHILE\nM30\n");
    let path = dir.join("LONG.MPF");
    std::fs::write(&path, text).unwrap();
    let o = options(Dialect::Siemens, &dir);
    let mut n = 0;
    let mut last = None;
    for m in read_file_with(&path, &o).unwrap() {
        last = Some(m.unwrap());
        n += 1;
    }
    assert_eq!(n, 400_000);
    assert_eq!(last.unwrap().end.to_xyzabc()[1], 2.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Wall time of the Siemens front end against the Fanuc reader on the same 1M-block G01
/// file (`cargo test --release -p ngc --test front_ends siemens::timing -- --ignored --nocapture`;
/// the benchmark `benches/read.rs` measures the same).
#[test]
#[ignore]
fn timing_against_fanuc() {
    let dir = std::env::temp_dir().join(format!("ngc-siemens-time-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut text = String::from("G71 G90 G94 G17\n");
    for i in 0..1_000_000 {
        let t = i as f64 * 1e-3;
        text.push_str(&format!(
            "G1 X{:.4} Y{:.4} Z{:.4} F{:.1}\n",
            100.0 * t.cos(),
            100.0 * t.sin(),
            -0.5 * t,
            1000.0 + (i % 7) as f64
        ));
    }
    text.push_str("M30\n");
    let path = dir.join("big.mpf");
    std::fs::write(&path, &text).unwrap();
    let nc = dir.join("big.nc");
    std::fs::write(&nc, text.replacen("G71", "G21", 1)).unwrap();
    let time = |d: Dialect| {
        let path = if d == Dialect::Siemens { &path } else { &nc };
        let o = Options {
            dialect: d,
            ..Options::default()
        };
        (0..3)
            .map(|_| {
                let t = std::time::Instant::now();
                let n = read_file_with(path, &o)
                    .unwrap()
                    .inspect(|m| assert!(m.is_ok()))
                    .count();
                assert_eq!(n, 1_000_000);
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let (f, s) = (time(Dialect::Fanuc), time(Dialect::Siemens));
    eprintln!("fanuc {f:.3} s, siemens {s:.3} s, ratio {:.2}", s / f);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn deep_or_overflowing_expressions_and_garbage_are_errors_not_crashes() {
    let minus = format!("R1={}1\n", "-".repeat(100_000));
    assert!(error(&minus).2.contains("nested deeper"));
    let parens = format!("R1={}1{}\n", "(".repeat(100), ")".repeat(100));
    assert!(error(&parens).2.contains("nested deeper"));
    assert!(error("R1=1EX300*1EX300\n").2.contains("finite"));
    // Every byte sequence of a few kinds of garbage reads or fails, never panics.
    let pieces = [
        "G1", "X", "=", "AC(", ")", "R1", "IF", "ENDIF", "WHILE", "ENDFOR", "\"", ";", "é", "[",
        "$", "N", ":", "-", "1.", "CR=", "TRANS", "MCALL", "CYCLE81(", ",", "CIP", "I1=", "TURN=",
        "AP=", "RP=", "G111", "G2", "DEFINE", "AS", "$P_UIFR[", "CTRANS(", "CROT(", "CASE", "OF",
        "GOTOF", "G54",
    ];
    let mut state: u64 = 7;
    for _ in 0..3000 {
        let mut text = String::new();
        for _ in 0..12 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            text.push_str(pieces[(state >> 33) as usize % pieces.len()]);
            if state & 1 == 0 {
                text.push(' ');
            }
            if state & 6 == 0 {
                text.push('\n');
            }
        }
        let o = Options {
            max_blocks: 100,
            ..options(Dialect::Siemens, Path::new("."))
        };
        let _ = read_str_with(Path::new("t.mpf"), &text, &o)
            .take(1000)
            .count();
    }
}

#[test]
fn cycle800_axis_by_axis_is_the_tilted_plane_a_then_b_then_c_about_the_new_axes() {
    // Mode 57, B90 about Y, zero point X0 = (10, 0, 0) before and Z1 = 2 after the turn:
    // R = Ry(90) takes e_z to e_x and e_x to -e_z, origin (10,0,0) + R (0,0,2) = (12,0,0).
    // Z5 is work (17, 0, 0); X5 is work (12, 0, -5).
    let ms = moves("CYCLE800(0,\"TC1\",0,57,10,0,0,0,90,0,0,0,2,0)\nG1 X0 Y0 Z5 F100\nX5 Z0\nCYCLE800()\nG1 X1 Y2 Z3\nM30\n");
    let e = ends(&ms);
    assert_eq!(e[0], [17.0, 0.0, 0.0]);
    assert_eq!(e[1], [12.0, 0.0, -5.0]);
    assert_eq!(e[2], [1.0, 2.0, 3.0]);
    // A30 then C90 about the turned Z: R = Rx(30) Rz(90) takes e_x to Rx(30) e_y =
    // (0, cos 30, sin 30), so X10 is work (0, 8.660254038, 5).
    let ms = moves("CYCLE800(0,\"\",0,57,0,0,0,30,0,90,0,0,0,0)\nG1 X10 Y0 Z0 F100\nM30\n");
    let e = ends(&ms);
    assert!(
        (e[0][1] - 10.0 * 30f64.to_radians().cos()).abs() < 1e-9
            && (e[0][2] - 5.0).abs() < 1e-9
            && e[0][0].abs() < 1e-9,
        "{e:?}"
    );
}

#[test]
fn trailing_comments_block_numbers_and_lower_case_read_in_plain_and_translated_blocks() {
    // A plain block (handed on as written) and a translated one (R parameter), each with
    // a comment holding parentheses and a quote.
    let ms = moves("n10 g1 x10 f100 ; move (fast) \"q\"\nN20 R1=4 G1 Y=R1 ; (y) \"q\"\nm30\n");
    assert_eq!(ends(&ms), vec![[10.0, 0.0, 0.0], [10.0, 4.0, 0.0]]);
}

/// `CALL "/_N_SPF_DIR/_N_HOLE_SPF"` runs HOLE.SPF (the path's last part in the control's
/// internal form); `DEF STRING[20] NAME` and the blank's `WORKPIECE(…)` (for the control's
/// simulation display) are accepted with a notice; a system variable is
/// refused naming what it is.
#[test]
fn an_indirect_call_and_display_only_definitions_are_read() {
    let dir = std::env::temp_dir().join(format!("ngc-siemens-call-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("HOLE.SPF"), "G91 G1 Z-2 F100\nZ2\nG90\nM17\n").unwrap();
    let program = "DEF STRING[20] NAME=\"PART 1\"\nWORKPIECE(,\"\",,\"BOX\",112,0,-50,-80,-50,-50,50,50)\nG0 X10 Y5 Z3\nCALL \"/_N_SPF_DIR/_N_HOLE_SPF\"\nG0 X20\nM30\n";
    let m: Vec<Move> = read_str_with(
        Path::new("t.mpf"),
        program,
        &options(Dialect::Siemens, &dir),
    )
    .collect::<Result<_, _>>()
    .unwrap_or_else(|e| panic!("{e}"));
    let z: Vec<f64> = m.iter().map(|m| m.end[ngc::Axis::Z]).collect();
    assert_eq!(z, [3.0, 1.0, 3.0, 3.0]);
    assert_eq!(m[3].end[ngc::Axis::X], 20.0);
    let err = read_str_with(
        Path::new("t.mpf"),
        "R1=$MN_USER_DATA_INT[0]\nM30\n",
        &options(Dialect::Siemens, &dir),
    )
    .find_map(|m| m.err())
    .expect("a system variable mtsim does not have is refused");
    assert!(err.to_string().contains("general machine data"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A G1 with no F in effect is the reader's error at its line and column, so no feed move
/// leaves the reader without a feed; a G0 carries none.
#[test]
fn a_feed_move_with_no_feed_in_effect_is_an_error_at_its_line() {
    let (line, column, message) = error("G0 X1\nG1 X10\n");
    assert_eq!((line, column), (2, 1), "{message}");
    assert!(message.contains("no feed"), "{message}");
    let m = moves("G0 X1\nG1 X10 F300\n");
    assert_eq!(
        (m[0].feed, m[1].feed),
        (ngc::Feed::None, ngc::Feed::PerMinute(300.0))
    );
}

/// `G641 ADIS=0.1` (the rounding distance of path blending) and `WORKPIECE(…)` are read with
/// a notice each and no motion of their own: the move after them is the program's own.
#[test]
fn blending_distances_and_the_blank_are_read_with_notices() {
    let o = options(Dialect::Siemens, Path::new("."));
    let mut r = read_str_with(
        Path::new("t.mpf"),
        "WORKPIECE(,\"\",,\"BOX\",112,0,-50,-80,-50,-50,50,50)\nG641 ADIS=0.1 ADISPOS=R1+0.2\nG1 X10 F100\nM30\n",
        &o,
    );
    let ms: Vec<Move> = r.by_ref().collect::<Result<_, _>>().unwrap();
    assert_eq!(ms.len(), 1);
    assert_eq!(ms[0].end[ngc::Axis::X], 10.0);
    let notes: Vec<&str> = r.notices().iter().map(|n| n.message.as_str()).collect();
    for name in ["WORKPIECE", "ADIS=", "ADISPOS="] {
        assert!(notes.iter().any(|n| n.contains(name)), "{name}: {notes:?}");
    }
}

/// `CYCLE832(0.01, _FINISH, 1)`: the corners of the continuous-path modes are blended
/// within 0.01 mm (the planner's G64 P0.01), through a later G642 too; G60 stops;
/// `CYCLE832()` deselects the tolerance (the machine's default again).
#[test]
fn cycle832_gives_the_blending_tolerance() {
    let m = moves(
        "G17 G90 G54 G71\nG0 X0 Y0 Z10\nCYCLE832(0.01,_FINISH,1)\nG1 X10 F500\n\
         G642\nG1 Y10\nG60\nG1 X0\nG64\nCYCLE832()\nG1 Y0\nM30\n",
    );
    let at = |line: usize| m.iter().find(|m| m.line == line).unwrap().path;
    let tol = ngc::PathControl::Blend {
        tolerance_mm: Some(0.01),
        naive_cam_mm: None,
    };
    assert_eq!(at(4), tol);
    assert_eq!(at(6), tol);
    assert_eq!(at(8), ngc::PathControl::ExactPath);
    assert_eq!(at(11), ngc::PathControl::BLEND);
}

/// The Z levels and feeds of the moves of `line`: (Z, F or None for a rapid or dwell).
fn z_feeds(m: &[Move], line: usize) -> Vec<(f64, Option<f64>)> {
    m.iter()
        .filter(|m| m.line == line && !matches!(m.motion, Motion::Dwell { .. }))
        .map(|m| ((m.end[ngc::Axis::Z] * 1e9).round() / 1e9, m.feed.rate()))
        .collect()
}

/// CYCLE85 bores in at FFR and out at RFF; CYCLE89 in and out at F; CYCLE84 taps in at
/// pitch × SST and out at pitch × SST1 (MPIT 10: the M10 coarse pitch 1.5 mm); each then
/// rises to RTP at rapid, and the programmed F holds again after it (Siemens Cycles
/// manual, CYCLE84, CYCLE85, CYCLE89: RTP 10, RFP 0, SDIS 2, DP −20).
#[test]
fn boring_and_tapping_cycles_feed_in_and_out_at_their_own_feeds() {
    let m = moves(
        "G17 G90 G54 G71\nG0 X10 Y10 Z50\nF250\n\
         CYCLE85(10,0,2,-20,,1,100,300)\nCYCLE89(10,0,2,-15,,0.5)\n\
         CYCLE84(10,0,2,-20,,0,3,10,,0,200,400)\nCYCLE84(10,0,2,-20,,0,3,,1.25,0,200)\n\
         G1 X20\nM30\n",
    );
    assert_eq!(
        z_feeds(&m, 4),
        [
            (2.0, None),
            (-20.0, Some(100.0)),
            (2.0, Some(300.0)),
            (10.0, None)
        ]
    );
    assert_eq!(
        z_feeds(&m, 5),
        [
            (2.0, None),
            (-15.0, Some(250.0)),
            (2.0, Some(250.0)),
            (10.0, None)
        ]
    );
    assert_eq!(
        z_feeds(&m, 6),
        [
            (2.0, None),
            (-20.0, Some(300.0)),
            (2.0, Some(600.0)),
            (10.0, None)
        ]
    );
    assert_eq!(
        z_feeds(&m, 7),
        [
            (2.0, None),
            (-20.0, Some(250.0)),
            (2.0, Some(250.0)),
            (10.0, None)
        ]
    );
    assert_eq!(z_feeds(&m, 8), [(10.0, Some(250.0))]);
    let dwell = m
        .iter()
        .find(|m| m.line == 4 && matches!(m.motion, Motion::Dwell { .. }));
    assert!(matches!(dwell.unwrap().motion, Motion::Dwell { seconds } if seconds == 1.0));
}
