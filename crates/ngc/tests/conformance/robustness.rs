//! Random and mutated programs never panic and never hang: the reader either yields moves
//! or one error, and stops.
//!
//! CI runs a short run (256 cases per property). The long run of 10^6 cases:
//! `NGC_FUZZ_CASES=1000000 cargo test --release -p ngc --test conformance robustness::` (docs/gcode.md).

use std::path::Path;

use ngc::{read_str_with, Dialect, Options};
use proptest::prelude::*;

const SEED_PROGRAMS: [&str; 6] = [
    "G21 G90 G94 F500\n#1 = 3\no100 sub\nG1 X[#1 * 2] Y#2\no100 endsub\no200 while [#1 GT 0]\n#1 = [#1 - 1]\no100 call [#1] [2]\no200 endwhile\nG0 Z10\nM2\n",
    "O0001\n#1 = 0\nWHILE [#1 LT 3] DO 1\n#1 = #1 + 1\nG0 X#1\nEND 1\nIF [#1 EQ 3] GOTO 20\nN20 M98 P1000 L2\nM30\nO1000\nG91 G0 Y1\nG90\nM99\n",
    "G21 G90 G17 F100\nG0 X0 Y0 Z10\nG98 G83 X3 Y3 Z-3 R2 Q1.2\nG99 G81 X5 Z-4 R1\nG80\nG2 X10 Y0 I5 J0\nG3 X0 Y0 R5\nG10 L2 P2 X1\nG55 G92 X0\nG28\nG4 P1\n",
    "G21 G17 G90 T1 M6\nG0 X-20 Y-20\nG41 D1 G1 X0 Y0 F100\nG1 Z-1\nX50\nG2 X50 Y30 I10 J15\nG3 X20 Y30 R20\nX0 Y0\nG40 G0 X-20 Y-20\nG42.1 D4 G1 X5\nY5\nM2\n",
    "G54 G68.2 X10 Y0 Z5 I30 J45 K0\nG53.1\nG0 X0 Y0 Z10\nG1 Z0 F200\nG2 X10 Y0 I5 J0\nG91 X1 Z1\nG69 G90\nG254 G0 C90\nX5 A20\nG255\nM30\n",
    "%\nG20 G91.1 G0 X1 Y1\nG43 H0 G1 Z-1 F10\nG61.1 G64 P0.1\nG93 G1 X2 A10 F5\nG94 G95 S100 F0.1 G1 Y2\nM3 M8 M48 M62 P1\nG49\n%\n",
];

const ALPHABET: [&str; 46] = [
    "G0", "G1", "G2", "G3", "G4", "G10", "G28", "G43", "G53", "G54", "G81", "G83", "G90", "G91",
    "G92", "G41", "G40", "D1", "G68.2", "G53.1", "G254", "X1", "Y-2.5", "Z", "I1", "J", "R2", "P1",
    "Q0", "L2", "F100", "#1", "#<a>", "=", "[", "]", "+", "*", "/", "o1", "sub", "call", "while",
    "endwhile", "\n", " ",
];

fn options(dialect: Dialect) -> Options {
    Options {
        dialect,
        max_blocks: 2000,
        tools: vec![ngc::Tool {
            number: 1,
            length_mm: 20.0,
            diameter_mm: 10.0,
        }],
        table: Some(ngc::RotaryTable {
            tilt: ngc::Axis::A,
            pivot_mm: [0.0, 0.0, -100.0],
        }),
        ..Options::default()
    }
}

/// Reads `text` to the end or the first error; at most `cap` moves, which must suffice.
fn runs_to_an_end(text: &str, dialect: Dialect) {
    let cap = 1_000_000;
    let mut n = 0;
    let mut errors = 0;
    for m in read_str_with(Path::new("fuzz.ngc"), text, &options(dialect)) {
        n += 1;
        if let Err(e) = m {
            errors += 1;
            if let ngc::Error::Syntax(s) = e {
                // The span can be shown: it lies on character boundaries of the text.
                assert!(
                    s.text.get(s.span.clone()).is_some(),
                    "span {:?} in {:?}",
                    s.span,
                    s.text
                );
            }
        }
        assert!(n < cap, "more than {cap} moves: the reader did not stop");
    }
    assert!(errors <= 1, "at most one error, then the reader stops");
}

fn cases() -> u32 {
    std::env::var("NGC_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256)
}

fn dialects() -> impl Strategy<Value = Dialect> {
    prop_oneof![
        Just(Dialect::Linuxcnc),
        Just(Dialect::Fanuc),
        Just(Dialect::Haas)
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    #[test]
    fn random_text_never_panics(text in "[ -~\n\u{e9}]{0,200}", dialect in dialects()) {
        runs_to_an_end(&text, dialect);
    }

    #[test]
    fn random_token_programs_never_panic(tokens in prop::collection::vec(0..ALPHABET.len(), 0..80), dialect in dialects()) {
        let text: String = tokens.iter().map(|&k| ALPHABET[k]).collect::<Vec<_>>().join(" ");
        runs_to_an_end(&text, dialect);
    }

    #[test]
    fn mutated_programs_never_panic(
        seed in 0..SEED_PROGRAMS.len(),
        edits in prop::collection::vec((0usize..400, 0..ALPHABET.len(), 0u8..3), 1..8),
        dialect in dialects(),
    ) {
        let mut text = SEED_PROGRAMS[seed].to_string();
        for (at, token, op) in edits {
            let at = at % (text.len() + 1);
            let at = (0..=at).rev().find(|&i| text.is_char_boundary(i)).unwrap_or(0);
            match op {
                0 => text.insert_str(at, ALPHABET[token]),
                1 => {
                    let end = (at + 1 + token % 5).min(text.len());
                    if text.is_char_boundary(end) {
                        text.replace_range(at..end, "");
                    }
                }
                _ => text.insert_str(at, &format!("{}", token as f64 * -1.5)),
            }
        }
        runs_to_an_end(&text, dialect);
    }
}
