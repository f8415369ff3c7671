//! Plain `G0`/`G1` blocks (axis words and F only) take a short path through the
//! interpreter. Every program here is read twice: as written, and with an `N` number in
//! front of each block, which sends every block through the general path. The moves must
//! be identical, and an error the same message on the same line (its column moved by the
//! `N` word), in each dialect, on a machine with all six axes and on one with X Y Z only.

use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, Error, Move, Options};

/// The program with `N<k> ` before each block (not before `%` lines), and the length of
/// each prefix by line.
fn numbered(text: &str) -> (String, Vec<usize>) {
    let mut out = String::new();
    let mut widths = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let prefix = if line.trim().is_empty() || line.starts_with('%') {
            String::new()
        } else {
            format!("N{} ", 10 * (k + 1))
        };
        widths.push(prefix.len());
        out.push_str(&prefix);
        out.push_str(line);
        out.push('\n');
    }
    (out, widths)
}

/// The moves, and the error as (line, column, message) if the program stops on one.
fn read(text: &str, options: &Options) -> (Vec<Move>, Option<(usize, usize, String)>) {
    let mut moves = Vec::new();
    for m in read_str_with(Path::new("plain.ngc"), text, options) {
        match m {
            Ok(m) => moves.push(m),
            Err(Error::Syntax(s)) => return (moves, Some((s.line, s.column, s.message))),
            Err(e) => panic!("unexpected error {e}"),
        }
    }
    (moves, None)
}

const PROGRAMS: &[&str] = &[
    // Absolute and modal: G0/G1 written both ways, axis-only blocks, all six axes.
    "G21 G90 G94 G17\nG1 X10 Y-2.5 F600\nY3\nG0 Z5\nX1 Y2 Z3\nG01 A10 C-20 F1200\nG00 B5\nZ-1 X-7.125\nM30\n",
    // Inch, incremental, a second work system and a G92 offset.
    "G20 G91\nG1 X1 Y1 F10\nZ-0.5\nG0 X-1\nG90 G55\nG1 X0.5 F20.5\nG92 X0 Y0\nX1.25 Y-0.75\nG0 Y3\nM2\n",
    // Inverse time, then per minute, then per revolution with the spindle set.
    "G21 G90\nG93 G1 X10 F2\nX20 F4\nG94 F100\nY5\nS1000 M3\nG95 G1 X5 F0.1\nX6\nM2\n",
    // A canned cycle, then plain moves after it.
    "G21 G90 G94\nG0 Z5\nG81 X1 Y1 Z-1 R1 F100\nX2\nG80\nG1 X5 F200\nY5\nG0 Z10\nM2\n",
    // No feed for a feed move.
    "G21 G90 G94\nG0 X1\nG1 X10\n",
    // Inverse time without F in the block.
    "G21 G90 G93\nG1 X1 F1\nX2\n",
    // Feed per revolution with the spindle speed zero.
    "G21 G90 G95\nG1 X1 F0.1\n",
    // A negative feed, then F0.
    "G21 G90 G94\nG1 X1 F-5\n",
    "G21 G90 G94\nG1 X1 F100\nX2 F0\n",
    // A word twice, an axis the XYZ machine lacks, no motion mode.
    "G21 G90 G94\nG1 X1 X2 F100\n",
    "G21 G90 G94\nG1 X1 F100\nA5\n",
    "G21 G90\nX1\n",
    // Rapids need no feed; a rapid after a feed move keeps the feed for the next G1.
    "G21 G90 G94\nG0 X1 Y1\nG1 Z-1 F300\nG0 Z5\nG1 X2\nM2\n",
];

#[test]
fn plain_blocks_read_as_through_the_general_path() {
    for dialect in [Dialect::Linuxcnc, Dialect::Fanuc, Dialect::Haas] {
        for axes in [Axis::ALL.to_vec(), vec![Axis::X, Axis::Y, Axis::Z]] {
            let options = Options {
                dialect,
                axes: axes.clone(),
                ..Options::default()
            };
            for program in PROGRAMS {
                let (with_n, widths) = numbered(program);
                let (moves, error) = read(program, &options);
                let (moves_n, error_n) = read(&with_n, &options);
                let case = format!("{dialect:?}, {} axes:\n{program}", axes.len());
                assert_eq!(moves, moves_n, "{case}");
                match (error, error_n) {
                    (None, None) => assert!(!moves.is_empty(), "{case}"),
                    (Some((line, column, message)), Some((line_n, column_n, message_n))) => {
                        assert_eq!((line, &message), (line_n, &message_n), "{case}");
                        assert_eq!(column + widths[line - 1], column_n, "{case}");
                    }
                    (a, b) => panic!("{case}: {a:?} against {b:?}"),
                }
            }
        }
    }
}
