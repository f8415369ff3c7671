//! A program file is streamed line by line (jumps seek back by byte offset) while a string
//! is read in memory: both must give the same moves and the same errors, byte for byte,
//! for every kind of jump (o-word loops, calls, Fanuc WHILE/GOTO/M98), CRLF line ends and
//! invalid UTF-8.

use std::path::{Path, PathBuf};

use ngc::{read_file_with, read_str_with, Dialect, Error, Move, Options};
use proptest::prelude::*;

/// What a read gives: its moves, then the error as (line, column, message, span, text).
#[derive(Debug, PartialEq)]
struct Outcome {
    moves: Vec<Move>,
    error: Option<(usize, usize, String, std::ops::Range<usize>, String)>,
}

fn outcome(results: impl Iterator<Item = ngc::Result<Move>>) -> Outcome {
    let mut moves = Vec::new();
    let mut error = None;
    for r in results {
        match r {
            Ok(m) => moves.push(m),
            Err(Error::Syntax(s)) => {
                error = Some((s.line, s.column, s.message, s.span, s.text));
            }
            Err(e) => panic!("unexpected error {e}"),
        }
    }
    Outcome { moves, error }
}

/// A scratch folder for this test process.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ngc-streaming-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Reads `bytes` as a file and as a string (invalid UTF-8 replaced, as the reader does).
fn both(path: &Path, bytes: &[u8], options: &Options) -> (Outcome, Outcome) {
    std::fs::write(path, bytes).unwrap();
    let from_file = outcome(read_file_with(path, options).unwrap());
    let text = String::from_utf8_lossy(bytes);
    let from_str = outcome(read_str_with(path, &text, options));
    (from_file, from_str)
}

fn data(dir: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data")
        .join(dir)
}

#[test]
fn every_conformance_program_reads_the_same_from_the_file_and_from_memory() {
    let mut options = Options {
        dialect: Dialect::Linuxcnc,
        search_path: vec![data("conformance-subs")],
        ..Options::default()
    };
    let mut count = 0;
    for dir in [
        "conformance",
        "conformance-errors",
        "conformance-pending",
        "conformance-subs",
    ] {
        let mut files: Vec<_> = std::fs::read_dir(data(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("ngc" | "nc")))
            .collect();
        files.sort();
        for path in files {
            for dialect in [Dialect::Linuxcnc, Dialect::Fanuc] {
                options.dialect = dialect;
                let bytes = std::fs::read(&path).unwrap();
                let from_file = outcome(read_file_with(&path, &options).unwrap());
                let text = String::from_utf8_lossy(&bytes);
                let from_str = outcome(read_str_with(&path, &text, &options));
                assert_eq!(from_file, from_str, "{} ({dialect:?})", path.display());
                count += 1;
            }
        }
    }
    assert!(count >= 200, "only {count} programs read");
}

/// Programs with every kind of backward and forward jump.
const JUMPS: [&str; 6] = [
    "G21 G90\n#1 = 0\no100 while [#1 LT 5]\nG1 X[#1] F100\n#1 = [#1 + 1]\no100 endwhile\no200 repeat [3]\nG1 Y[#1] F100\n#1 = [#1 + 1]\no200 endrepeat\nM2\n",
    "G21\no<sq> sub\nG1 X[#1] Y[#2] F100\no<sq> endsub\no<sq> call [1] [2]\no<sq> call [3] [4]\no300 do\n#5 = [#5 + 1]\nG1 Z[#5]\no300 while [#5 LT 4]\nM2\n",
    "G21\n#1 = 1\no1 if [#1 EQ 2]\nG1 X1 F1\no1 elseif [#1 EQ 1]\nG1 X2 F1\no1 else\nG1 X3 F1\no1 endif\no2 while [1]\n#1=[#1+1]\no2 if [#1 GT 3]\no2 break\no2 endif\nG1 Y[#1]\no2 endwhile\nM2\n",
    "O1000\n#1 = 0\nWHILE [#1 LT 3] DO 1\nG1 X#1 F100\n#1 = #1 + 1\nEND 1\nN50 G1 Y1\n#2 = #2 + 1\nIF [#2 LT 3] GOTO 50\nM98 P2000 L2\nM30\nO2000\nG91 G1 Z-1\nG90\nM99\n",
    "G21\nG1 X1 F100\no9 while [1]\nG1 X2\no9 endwhile\n",
    "G21\nG1 X1 F100\nG1 X2 Y\u{e9}\n",
];

/// Moves of each of [`JUMPS`], counted by hand: 5 + 3 loop passes; 2 calls + 4 do-while
/// passes; the elseif branch + 2 passes before the break; 3 WHILE passes + 3 GOTO passes +
/// 2 M98 repeats; X1, the endless loop's first pass and 334 more (then the block budget's
/// error: the main program's first pass is free, the comment line of the invalid UTF-8
/// variant included; counted pass i's while, `G1 X2` and endwhile are blocks 3i - 2, 3i - 1
/// and 3i, and at most 1001 blocks run, so the last move is pass 334's, block 1001); the
/// move before the bad word.
const MOVES: [usize; 6] = [8, 6, 3, 8, 336, 1];

#[test]
fn jumps_read_the_same_with_lf_crlf_and_invalid_utf8() {
    let dir = scratch("jumps");
    for (k, program) in JUMPS.iter().enumerate() {
        let dialect = if program.contains("WHILE") {
            Dialect::Fanuc
        } else {
            Dialect::Linuxcnc
        };
        let options = Options {
            dialect,
            max_blocks: 1001,
            ..Options::default()
        };
        let crlf = program.replace('\n', "\r\n");
        let mut invalid = b"(\xff\xfe comment)\n".to_vec();
        invalid.extend_from_slice(program.as_bytes());
        for (variant, bytes) in [
            ("lf", program.as_bytes().to_vec()),
            ("crlf", crlf.into_bytes()),
            ("invalid", invalid),
        ] {
            let (from_file, from_str) = both(&dir.join(format!("p{k}.ngc")), &bytes, &options);
            assert_eq!(from_file, from_str, "program {k}, {variant}");
            assert_eq!(from_file.moves.len(), MOVES[k], "program {k} {variant}");
            assert_eq!(from_file.error.is_some(), k >= 4, "program {k} {variant}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_error_deep_in_a_streamed_file_points_at_its_line_in_the_whole_text() {
    let dir = scratch("deep");
    let path = dir.join("deep.ngc");
    let mut text = String::from("G21 G90\n");
    for i in 0..20_000 {
        text.push_str(&format!("G1 X{}.5 F600\n", i % 100));
    }
    text.push_str("G1 X1 Q\n");
    std::fs::write(&path, &text).unwrap();
    let out = outcome(read_file_with(&path, &Options::default()).unwrap());
    assert_eq!(out.moves.len(), 20_000);
    let (line, column, _, span, shown) = out.error.expect("an error on the last line");
    assert_eq!((line, column), (20_002, 7));
    assert_eq!(shown, text);
    assert_eq!(&shown[span], "Q");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_siemens_word_far_down_a_file_is_refused_before_any_move() {
    let dir = scratch("siemens");
    let path = dir.join("s.ngc");
    let mut text = String::from("G21 G90\n");
    for _ in 0..30_000 {
        // Long enough that the word falls past the first read chunk.
        text.push_str("G1 X1.25 Y2.5 F600\n");
    }
    text.push_str("TRAORI\n");
    std::fs::write(&path, &text).unwrap();
    let first = read_file_with(&path, &Options::default())
        .unwrap()
        .next()
        .unwrap();
    match first {
        Err(Error::Syntax(s)) => {
            assert_eq!((s.line, s.column), (30_002, 1));
            assert!(s.message.contains("Siemens"), "{}", s.message);
        }
        other => panic!("expected the Siemens refusal first, got {other:?}"),
    }
    // The first Siemens word in the file is the one shown.
    std::fs::write(&path, "G0 X1\nCYCLE800(0)\nG0 X2\nTRAORI\n").unwrap();
    match read_file_with(&path, &Options::default()).unwrap().next() {
        Some(Err(Error::Syntax(s))) => {
            assert_eq!((s.line, s.column), (2, 1));
            assert!(s.message.contains("`CYCLE800`"), "{}", s.message);
        }
        other => panic!("expected the Siemens refusal, got {other:?}"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

fn line() -> impl Strategy<Value = String> {
    prop_oneof![
        (-1000i32..1000, -1000i32..1000).prop_map(|(x, y)| format!("G1 X{x}.5 Y{y} F100")),
        Just("#1 = [#1 + 1]".to_string()),
        Just("o1 while [#1 LT 3]".to_string()),
        Just("o1 endwhile".to_string()),
        Just("o2 repeat [2]".to_string()),
        Just("o2 endrepeat".to_string()),
        Just("o<s> call [1]".to_string()),
        Just("o<s> sub".to_string()),
        Just("G1 Z[#1] F50".to_string()),
        Just("o<s> endsub".to_string()),
        Just("( comment )".to_string()),
        Just(String::new()),
        "[ -~]{0,12}",
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn random_programs_with_jumps_read_the_same_from_a_file(
        lines in prop::collection::vec(line(), 0..30),
        crlf in any::<bool>(),
    ) {
        let dir = scratch("prop");
        let end = if crlf { "\r\n" } else { "\n" };
        let text = lines.join(end);
        let options = Options {
            dialect: Dialect::Linuxcnc,
            max_blocks: 200,
            ..Options::default()
        };
        let (from_file, from_str) = both(&dir.join("p.ngc"), text.as_bytes(), &options);
        prop_assert_eq!(from_file, from_str);
    }
}
