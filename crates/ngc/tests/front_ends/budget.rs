//! One budget of executed blocks (the reader option `max_blocks`) bounds every construct
//! that runs blocks again: subprogram repeats (M98 P L, G65 P L, Haas M97 P L, Siemens
//! `L10 P..`), repeated sections (Sinumerik `REPEAT`/`REPEATB`, Klartext `CALL LBL n REP m`),
//! loops and jumps. A huge count is refused at once at its own line; small counts give
//! exactly the passes the manuals describe, counted by hand below; and a structure left
//! open at the end of the program is an error at its opening line.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use ngc::{read_str_with, Axis, Dialect, Error, Move, Options, Tool};

/// Well under what a huge count would take to run: refusing it must not run its passes.
const QUICK: Duration = Duration::from_secs(5);

fn opts(dialect: Dialect) -> Options {
    Options {
        dialect,
        search_path: vec![scratch()],
        tools: vec![Tool {
            number: 1,
            length_mm: 0.0,
            diameter_mm: 10.0,
        }],
        ..Options::default()
    }
}

/// A folder of this process's subprogram files.
fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ngc-budget-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn name(dialect: Dialect) -> &'static str {
    match dialect {
        Dialect::Siemens => "t.mpf",
        Dialect::Heidenhain => "t.h",
        _ => "t.nc",
    }
}

fn moves_with(text: &str, o: &Options) -> Vec<Move> {
    read_str_with(Path::new(name(o.dialect)), text, o)
        .collect::<Result<_, _>>()
        .unwrap_or_else(|e| panic!("{text:?}: {e}"))
}

fn moves(text: &str, dialect: Dialect) -> Vec<Move> {
    moves_with(text, &opts(dialect))
}

/// (line, column, message) of the error that stops `text`, and how long reading took.
fn error_with(text: &str, o: &Options) -> ((usize, usize, String), Duration) {
    let t = Instant::now();
    let err = read_str_with(Path::new(name(o.dialect)), text, o)
        .find_map(Result::err)
        .unwrap_or_else(|| panic!("expected an error in {text:?}"));
    let took = t.elapsed();
    match err {
        Error::Syntax(s) => ((s.line, s.column, s.message), took),
        other => panic!("{other}"),
    }
}

fn error(text: &str, dialect: Dialect) -> (usize, usize, String) {
    let (e, took) = error_with(text, &opts(dialect));
    assert!(took < QUICK, "{text:?} took {took:?}");
    e
}

fn x(m: &Move) -> f64 {
    m.end[Axis::X]
}

/// The X ends of `moves`, rounded to 1e-9 mm.
fn xs(moves: &[Move]) -> Vec<f64> {
    moves.iter().map(|m| (x(m) * 1e9).round() / 1e9).collect()
}

#[test]
fn the_default_budget_is_two_million_blocks() {
    assert_eq!(Options::default().max_blocks, 2_000_000);
    assert_eq!(ngc::MAX_BLOCKS, 2_000_000);
}

#[test]
fn huge_subprogram_repeat_counts_are_refused_at_once_at_the_call() {
    // (program, dialect, line and column of the call word)
    let cases = [
        (
            "O0001\nG1 X1 F100\nM98 P1000 L99999999\nM30\nO1000\nG91 G1 X1\nG90\nM99\n",
            Dialect::Fanuc,
            3,
            1,
        ),
        (
            "O0001\nG1 X1 F100\nG65 P1000 L99999999 A1\nM30\nO1000\nG91 G1 X#1\nG90\nM99\n",
            Dialect::Fanuc,
            3,
            1,
        ),
        (
            "O0001\nG1 X1 F100\nM97 P100 L99999999\nM30\nN100 G91 G1 X1\nG90\nM99\n",
            Dialect::Haas,
            3,
            1,
        ),
    ];
    for (text, dialect, line, column) in cases {
        let (l, c, m) = error(text, dialect);
        assert_eq!((l, c), (line, column), "{text:?}: {m}");
        assert!(m.contains("99999999 passes"), "{m}");
        assert!(m.contains("max_blocks"), "{m}");
    }
}

#[test]
fn huge_siemens_and_heidenhain_repeats_are_refused_at_once_at_their_line() {
    std::fs::write(scratch().join("L10.SPF"), "G91 G1 X1 F100\nG90\nM17\n").unwrap();
    let (l, c, m) = error("G1 X0 F100\nL10 P99999999\nM30\n", Dialect::Siemens);
    assert_eq!((l, c), (2, 1), "{m}");
    assert!(m.contains("max_blocks"), "{m}");
    let (l, c, m) = error(
        "G1 X0 F100\nLAB1: G91 X1\nG90\nREPEAT LAB1 P=99999999\nM30\n",
        Dialect::Siemens,
    );
    assert_eq!((l, c), (4, 1), "{m}");
    assert!(
        m.contains("99999999 passes") && m.contains("max_blocks"),
        "{m}"
    );
    let (l, c, m) = error(
        "G1 X0 F100\nN20 LAB1: G91 X1\nG90\nN40 REPEATB LAB1 P=1000000000\nM30\n",
        Dialect::Siemens,
    );
    assert_eq!((l, c), (4, 5), "{m}");
    assert!(m.contains("1000000000 passes"), "{m}");
    // Klartext allows at most REP 65534: a budget of 1000 refuses it at the CALL.
    let o = Options {
        max_blocks: 1000,
        ..opts(Dialect::Heidenhain)
    };
    let text = "0 BEGIN PGM T MM\n1 L X0 Y0 F100\n2 LBL 1\n3 L IX+1\n4 CALL LBL 1 REP 65534\n5 END PGM T MM\n";
    let ((l, c, m), took) = error_with(text, &o);
    assert!(took < QUICK);
    assert_eq!((l, c), (5, 3), "{m}");
    assert!(
        m.contains("65534 passes") && m.contains("max_blocks"),
        "{m}"
    );
}

#[test]
fn endless_loops_and_jumps_stop_at_the_budget_at_the_jumping_line() {
    let small = |dialect| Options {
        max_blocks: 10_000,
        ..opts(dialect)
    };
    // (program, dialect, line and column of the construct that goes back)
    let cases = [
        (
            "G1 X1 F100\no1 while [1]\nG91 X1\no1 endwhile\n",
            Dialect::Linuxcnc,
            4,
            1,
        ),
        (
            "G1 X1 F100\no1 do\nG91 X1\no1 while [1]\n",
            Dialect::Linuxcnc,
            4,
            1,
        ),
        (
            "G1 X1 F100\no1 repeat [1000000000]\nG91 X1\no1 endrepeat\n",
            Dialect::Linuxcnc,
            2,
            1,
        ),
        (
            "G1 X1 F100\nWHILE [1] DO 1\nG91 X1\nEND 1\n",
            Dialect::Fanuc,
            4,
            1,
        ),
        ("G1 X1 F100\nN10 G91 X1\nGOTO 10\n", Dialect::Fanuc, 3, 1),
        (
            "G1 X1 F100\nLAB1: G91 X1\nGOTOB LAB1\n",
            Dialect::Siemens,
            3,
            7,
        ),
        (
            "G1 X1 F100\nLOOP\nG91 X1\nENDLOOP\n",
            Dialect::Siemens,
            4,
            1,
        ),
        (
            "G1 X1 F100\nR1=0\nWHILE R1<1\nG91 X1\nENDWHILE\n",
            Dialect::Siemens,
            5,
            1,
        ),
        // A macro call in an endless loop: blocks 1-2, then 6 a pass (WHILE, G65, the three
        // lines of O2, END), so block 10001 is the third of a pass, in O2, and the last
        // construct met is the G65 call.
        (
            "O1\nG1 X1 F100\nWHILE [1] DO 1\nG65 P2 A1\nEND 1\nM30\nO2\nG91 G1 X#1\nG90\nM99\n",
            Dialect::Fanuc,
            4,
            1,
        ),
    ];
    for (text, dialect, line, column) in cases {
        let ((l, c, m), took) = error_with(text, &small(dialect));
        assert!(took < QUICK, "{text:?} took {took:?}");
        assert_eq!((l, c), (line, column), "{text:?}: {m}");
        assert!(m.contains("max_blocks"), "{text:?}: {m}");
    }
    let o = Options {
        max_blocks: 10_000,
        ..opts(Dialect::Heidenhain)
    };
    let text = "0 BEGIN PGM T MM\n1 L X0 Y0 F100\n2 LBL 1\n3 L IX+1\n4 FN 9: IF +0 EQU +0 GOTO LBL 1\n5 END PGM T MM\n";
    let ((l, _, m), _) = error_with(text, &o);
    assert_eq!(l, 5, "{m}");
    assert!(m.contains("more than 10000 blocks executed"), "{m}");
}

#[test]
fn a_loop_counts_every_block_it_runs_exactly() {
    // `o1 while` .. `o1 endwhile` around one move. The main program's first pass is free:
    // G1 X0 and the first pass's while, move and endwhile cost nothing. Every pass after it
    // reads its lines again: counted pass k's while, move and endwhile are blocks 3k-2,
    // 3k-1 and 3k. A budget of 22 blocks runs 7 counted passes (21 blocks) and stops at the
    // 8th one's move (block 23): the first move, the free pass's and 7 more.
    let o = Options {
        max_blocks: 22,
        ..opts(Dialect::Linuxcnc)
    };
    let text = "G1 X0 F100\no1 while [1]\nG91 X1\no1 endwhile\n";
    let all: Vec<_> = read_str_with(Path::new("t.ngc"), text, &o).collect();
    let ok = all.iter().filter(|m| m.is_ok()).count();
    assert_eq!(
        ok,
        1 + 1 + 7,
        "the first move, the free pass and 7 counted passes"
    );
    assert!(all.last().unwrap().is_err());
    // One block more runs the 8th counted pass's move (block 23), and stops at its endwhile.
    let o = Options {
        max_blocks: 23,
        ..o
    };
    assert_eq!(
        read_str_with(Path::new("t.ngc"), text, &o)
            .filter(|m| m.is_ok())
            .count(),
        10
    );
}

#[test]
fn small_subprogram_repeats_run_exactly_their_passes() {
    // M98 P1000 L3: the subprogram's one incremental move three times.
    let m = moves(
        "O0001\nG1 X0 F100\nM98 P1000 L3\nM30\nO1000\nG91 G1 X1\nG90\nM99\n",
        Dialect::Fanuc,
    );
    assert_eq!(xs(&m), [0.0, 1.0, 2.0, 3.0]);
    // G65 P1000 L2 A5: two passes with #1 = 5.
    let m = moves(
        "O0001\nG1 X0 F100\nG65 P1000 L2 A5\nM30\nO1000\nG91 G1 X#1\nG90\nM99\n",
        Dialect::Fanuc,
    );
    assert_eq!(xs(&m), [0.0, 5.0, 10.0]);
    // Haas M97 P100 L4: the local subprogram at N100 four times.
    let m = moves(
        "O0001\nG1 X0 F100\nM97 P100 L4\nM30\nN100 G91 G1 X2\nG90\nM99\n",
        Dialect::Haas,
    );
    assert_eq!(xs(&m), [0.0, 2.0, 4.0, 6.0, 8.0]);
    // Siemens L11 P3: the subprogram file three times.
    std::fs::write(scratch().join("L11.SPF"), "G91 G1 X1 F100\nG90\nM17\n").unwrap();
    let m = moves("G1 X0 F100\nL11 P3\nM30\n", Dialect::Siemens);
    assert_eq!(xs(&m), [0.0, 1.0, 2.0, 3.0]);
    // o-word repeat [3].
    let m = moves(
        "G1 X0 F100\no1 repeat [3]\nG91 X1\nG90\no1 endrepeat\nM2\n",
        Dialect::Linuxcnc,
    );
    assert_eq!(xs(&m), [0.0, 1.0, 2.0, 3.0]);
    // Klartext section repeat: the section runs once, then REP 2 more times.
    let m = moves(
        "0 BEGIN PGM T MM\n1 L X0 Y0 F100\n2 LBL 1\n3 L IX+1\n4 CALL LBL 1 REP 2\n5 END PGM T MM\n",
        Dialect::Heidenhain,
    );
    assert_eq!(xs(&m), [0.0, 1.0, 2.0, 3.0]);
}

#[test]
fn sinumerik_section_repeats_run_the_section_again_p_times() {
    // REPEAT LAB1 P=2: lines 2-3 (two moves, +1 then +10) run once on the way and twice
    // more; then line 5.
    let m = moves(
        "G1 X0 F100\nLAB1: G91 X1\nX10\nREPEAT LAB1 P=2\nG90 X0\nM30\n",
        Dialect::Siemens,
    );
    assert_eq!(xs(&m), [0.0, 1.0, 11.0, 12.0, 22.0, 23.0, 33.0, 0.0]);
    // Without P the section runs once more.
    let m = moves(
        "G1 X0 F100\nLAB1: G91 X1\nREPEAT LAB1\nM30\n",
        Dialect::Siemens,
    );
    assert_eq!(xs(&m), [0.0, 1.0, 2.0]);
    // REPEATB LAB1 P=3: the block at LAB1 alone three times more (not the X10 after it).
    let m = moves(
        "G1 X0 F100\nLAB1: G91 X1\nX10\nREPEATB LAB1 P=3\nM30\n",
        Dialect::Siemens,
    );
    assert_eq!(xs(&m), [0.0, 1.0, 11.0, 12.0, 13.0, 14.0]);
    // REPEAT START END P=2: lines 3-4 inclusive twice more, not line 2 or 5.
    let m = moves(
        "G1 X0 F100\nG91 X100\nSTART: X1\nEND1: X10\nX1000\nREPEAT START END1 P=2\nM30\n",
        Dialect::Siemens,
    );
    assert_eq!(
        xs(&m),
        [0.0, 100.0, 101.0, 111.0, 1111.0, 1112.0, 1122.0, 1123.0, 1133.0]
    );
    // REPEAT LAB1 with ENDLABEL between: the section ends at the ENDLABEL line.
    let m = moves(
        "G1 X0 F100\nLAB1: G91 X1\nENDLABEL: X10\nX100\nREPEAT LAB1 P=1\nM30\n",
        Dialect::Siemens,
    );
    assert_eq!(xs(&m), [0.0, 1.0, 11.0, 111.0, 112.0, 122.0]);
    // Nested: the inner REPEATB runs in each pass of the outer section.
    let m = moves(
        "G1 X0 F100\nLBA: G91 X1\nREPEATB LBA P=1\nREPEAT LBA P=1\nM30\n",
        Dialect::Siemens,
    );
    // Pass 1: X1, repeat X1; outer repeat: X1, inner repeat X1.
    assert_eq!(xs(&m), [0.0, 1.0, 2.0, 3.0, 4.0]);
    // P=0 runs nothing more; an unknown label is an error at the label.
    let m = moves(
        "G1 X0 F100\nLAB1: G91 X1\nREPEAT LAB1 P=0\nM30\n",
        Dialect::Siemens,
    );
    assert_eq!(xs(&m), [0.0, 1.0]);
    let (l, c, msg) = error("G1 X0 F100\nREPEAT NOWHERE P=2\nM30\n", Dialect::Siemens);
    assert_eq!((l, c), (2, 8), "{msg}");
    // A REPEAT with a label opens no REPEAT-UNTIL structure: an IF skipped over it still
    // finds its ENDIF.
    let m = moves(
        "G1 X0 F100\nLAB1: G91 X1\nIF 0\nREPEAT LAB1 P=5\nENDIF\nM30\n",
        Dialect::Siemens,
    );
    assert_eq!(xs(&m), [0.0, 1.0]);
}

#[test]
fn a_structure_open_at_the_end_of_the_program_is_an_error_at_its_opening_line() {
    let cases = [
        ("G1 X1 F100\no1 if [1]\nG1 X2\n", Dialect::Linuxcnc, 2, 1),
        ("G1 X1 F100\no7 do\nG1 X2\n", Dialect::Linuxcnc, 2, 1),
        (
            "G1 X1 F100\no3 repeat [2]\nG1 X2\n",
            Dialect::Linuxcnc,
            2,
            1,
        ),
        ("G1 X1 F100\no3 while [1]\nG1 X2\n", Dialect::Linuxcnc, 2, 1),
        ("G1 X1 F100\nWHILE [1] DO 1\nG1 X2\n", Dialect::Fanuc, 2, 1),
        ("G1 X1 F100\nIF 1\nG1 X2\n", Dialect::Siemens, 2, 1),
        (
            "G1 X1 F100\nR1=1\nWHILE R1>0\nG1 X2\n",
            Dialect::Siemens,
            3,
            1,
        ),
        ("G1 X1 F100\nFOR R2=1 TO 3\nG1 X2\n", Dialect::Siemens, 2, 1),
        ("G1 X1 F100\nN20 REPEAT\nG1 X2\n", Dialect::Siemens, 2, 5),
        ("G1 X1 F100\nLOOP\nG1 X2\n", Dialect::Siemens, 2, 1),
    ];
    for (text, dialect, line, column) in cases {
        let (l, c, m) = error(text, dialect);
        assert_eq!((l, c), (line, column), "{text:?}: {m}");
        assert!(m.contains("never closed"), "{text:?}: {m}");
    }
    // A loop left by a jump has its closing line: no error (Fanuc allows GOTO out of a
    // WHILE), and the moves are the two passes and the move after the jump.
    let m = moves(
        "#1=0\nWHILE [1] DO 1\n#1=#1+1\nG1 X#1 F100\nIF [#1 GE 2] GOTO 50\nEND 1\nN50 G1 X9\n",
        Dialect::Fanuc,
    );
    assert_eq!(xs(&m), [1.0, 2.0, 9.0]);
}

/// A straight program longer than the whole budget reads whole: its first pass is free.
/// The same lines repeated by a loop draw on the budget and stop.
#[test]
fn a_straight_program_longer_than_the_budget_reads_whole() {
    let mut body = String::new();
    for i in 0..3000 {
        body.push_str(&format!("G1 X{}\n", i % 7));
    }
    let options = Options {
        max_blocks: 100,
        ..opts(Dialect::Linuxcnc)
    };
    let straight = format!("G21 G90 G94\nF1000\n{body}M2\n");
    let moves: Vec<Move> = read_str_with(Path::new("long.ngc"), &straight, &options)
        .collect::<Result<_, _>>()
        .expect("a straight program repeats nothing");
    // One move per G1: X changes at every step (i % 7).
    assert_eq!(moves.len(), 3000);
    let looped = format!("G21 G90 G94\nF1000\no100 repeat [5]\n{body}o100 endrepeat\nM2\n");
    let err = read_str_with(Path::new("loop.ngc"), &looped, &options)
        .find_map(|m| m.err())
        .map(|e| e.to_string());
    assert!(
        err.as_deref().is_some_and(|e| e.contains("max_blocks")),
        "{err:?}"
    );
}
