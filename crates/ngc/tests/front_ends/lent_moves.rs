//! `Moves::next_ref` lends each move in place: it must give the moves and the error that
//! `Iterator::next` gives, in order, in every front end (G-code with moves held back by
//! cutter compensation and released at its end, Sinumerik, Heidenhain Klartext), and the
//! two may be mixed on one reader.

use std::path::Path;

use crate::common::{compensated_options, G42_ARCS};
use ngc::{read_str_with, Dialect, Move, Options};

/// Programs of each front end, with the options they are read with.
fn programs() -> Vec<(&'static str, &'static str, Options)> {
    let compensated = compensated_options();
    let dialect = |dialect| Options {
        dialect,
        ..Options::default()
    };
    vec![
        ("comp.ngc", G42_ARCS, compensated),
        (
            "plain.nc",
            "G21 G90 G94\nG1 X1 Y2 F600\nG0 Z5\nG4 P0.5\nG3 X0 Y3 I-1 J0.5\nM30\n",
            dialect(Dialect::Fanuc),
        ),
        (
            "bad.nc",
            "G21 G90\nG1 X1 F100\nG1 Y2\nG1 Z3\nG1 X1Q\nG1 X5\nM30\n",
            dialect(Dialect::Fanuc),
        ),
        (
            "t.mpf",
            "G71 G90 G94\nG1 X10 Y5 F800\nG0 Z20\nG2 X20 Y15 I10 J0\nM30\n",
            dialect(Dialect::Siemens),
        ),
        (
            "t.h",
            "0 BEGIN PGM T MM\n1 TOOL CALL 1 Z S1000\n2 L X+10 Y+5 F800\n3 L Z+20 FMAX\n\
             4 L IX+7 IY-2\n5 END PGM T MM\n",
            dialect(Dialect::Heidenhain),
        ),
    ]
}

/// Each move (or the error's text) as `next` gives them.
fn by_value(name: &str, text: &str, options: &Options) -> Vec<Result<Move, String>> {
    read_str_with(Path::new(name), text, options)
        .map(|m| m.map_err(|e| e.to_string()))
        .collect()
}

#[test]
fn lent_moves_are_the_moves_the_iterator_gives() {
    for (name, text, options) in programs() {
        let expected = by_value(name, text, &options);
        assert!(expected.iter().filter(|m| m.is_ok()).count() >= 3, "{name}");
        let mut moves = read_str_with(Path::new(name), text, &options);
        let mut lent = Vec::new();
        while let Some(m) = moves.next_ref() {
            lent.push(m.cloned().map_err(|e| e.to_string()));
        }
        assert_eq!(lent, expected, "{name}: next_ref");
        assert!(
            moves.next_ref().is_none() && moves.next().is_none(),
            "{name}"
        );
        // Alternating: a lent move leaves the queue when `next` is called after it.
        let mut moves = read_str_with(Path::new(name), text, &options);
        let mut mixed = Vec::new();
        for k in 0.. {
            let m = if k % 2 == 0 {
                moves.next_ref().map(|m| m.cloned())
            } else {
                moves.next()
            };
            let Some(m) = m else { break };
            mixed.push(m.map_err(|e| e.to_string()));
        }
        assert_eq!(mixed, expected, "{name}: next_ref and next in turn");
    }
}

#[test]
fn the_bad_program_ends_with_its_error_after_the_moves_before_it() {
    let (name, text, options) = programs().swap_remove(2);
    let got = by_value(name, text, &options);
    assert_eq!(got.len(), 4, "{got:?}");
    let error = got[3].as_ref().unwrap_err();
    assert!(error.contains("bad.nc:5"), "{error}");
}
