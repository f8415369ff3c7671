//! Expressions nest at most `MAX_NESTING` levels (brackets, function arguments, leading
//! signs and `#` indirections together): at the limit the value is computed, one level
//! beyond it is an error at the column where that level opens, and 20,000 levels are the
//! same error, never a stack overflow (issue 26, item 2).

use std::path::Path;

use ngc::{read_str, Axis, AxisVec, Error, MAX_NESTING};

/// An opening of one nesting level, its text and what it does to the value inside it.
struct Level {
    open: &'static str,
    close: &'static str,
    apply: fn(f64) -> f64,
}

const BRACKET: Level = Level {
    open: "[",
    close: "]",
    apply: |v| v,
};
const ABS: Level = Level {
    open: "ABS[",
    close: "]",
    apply: f64::abs,
};
const MINUS: Level = Level {
    open: "-",
    close: "",
    apply: |v| -v,
};
const FIX: Level = Level {
    open: "FIX[",
    close: "]",
    apply: f64::floor,
};

/// `G1 X<levels around inner> F100`: the program, and the X the levels give, applied
/// from the innermost outwards in f64 here.
fn program(levels: &[&Level], inner: f64) -> (String, f64) {
    let mut text = String::from("G21 G90\nG1 X");
    let mut value = inner;
    for l in levels {
        text.push_str(l.open);
    }
    text.push_str(&inner.to_string());
    for l in levels.iter().rev() {
        text.push_str(l.close);
        value = (l.apply)(value);
    }
    text.push_str(" F100\nM2\n");
    (text, value)
}

/// The X of the single move, or the error's (line, column, message).
fn read(text: &str) -> Result<f64, (usize, usize, String)> {
    let mut x = None;
    for m in read_str(Path::new("deep.ngc"), text, AxisVec::ZERO) {
        match m {
            Ok(m) => x = Some(m.end[Axis::X]),
            Err(Error::Syntax(s)) => return Err((s.line, s.column, s.message)),
            Err(e) => panic!("unexpected error {e}"),
        }
    }
    Ok(x.expect("one move"))
}

/// `n` levels cycling through `pattern`.
fn cycle<'a>(pattern: &[&'a Level], n: usize) -> Vec<&'a Level> {
    pattern.iter().copied().cycle().take(n).collect()
}

/// Column (1-based) of the opening of level `k` (0-based) on the `G1 X` line.
fn column_of(levels: &[&Level], k: usize) -> usize {
    "G1 X".len() + 1 + levels[..k].iter().map(|l| l.open.len()).sum::<usize>()
}

fn assert_refused(levels: &[&Level]) {
    let (text, _) = program(levels, 2.5);
    let (line, column, message) = read(&text).expect_err("too deep");
    assert_eq!(line, 2);
    assert_eq!(column, column_of(levels, MAX_NESTING), "{message}");
    assert!(
        message.contains(&format!("nested deeper than {MAX_NESTING} levels")),
        "{message}"
    );
}

const PATTERNS: [&[&Level]; 3] = [
    &[&BRACKET],
    &[&ABS],
    &[&BRACKET, &MINUS, &ABS, &MINUS, &FIX],
];

#[test]
fn the_limit_is_a_hundred_levels() {
    assert_eq!(MAX_NESTING, 100);
}

#[test]
fn values_at_the_limit_are_computed() {
    for pattern in PATTERNS {
        let levels = cycle(pattern, MAX_NESTING);
        let (text, x) = program(&levels, 2.5);
        assert_eq!(read(&text), Ok(x), "{}", &text[..40]);
    }
    // The mixed pattern at the limit, 20 rounds of `[-ABS[-FIX[`, by hand: FIX[2.5] = 2,
    // then -ABS[-2] = -2 and every later round keeps -2.
    let (text, x) = program(&cycle(PATTERNS[2], MAX_NESTING), 2.5);
    assert_eq!((read(&text), x), (Ok(-2.0), -2.0));
}

#[test]
fn one_level_beyond_the_limit_is_refused_where_it_opens() {
    for pattern in PATTERNS {
        assert_refused(&cycle(pattern, MAX_NESTING + 1));
    }
}

#[test]
fn twenty_thousand_levels_are_refused_not_a_stack_overflow() {
    for pattern in PATTERNS {
        assert_refused(&cycle(pattern, 20_000));
    }
}

#[test]
fn twenty_thousand_leading_signs_or_indirections_are_refused() {
    // The bracket is the first level, the 100th `-` the 101st.
    let signs = format!("G1 X[{}1] F100\n", "-".repeat(20_000));
    let (line, column, _) = read(&signs).expect_err("too deep");
    assert_eq!((line, column), (1, 5 + MAX_NESTING));
    // `#1 = 1`, so `##1` is `#1` again; the 101st `#` of the chain opens one level too many.
    let hashes = format!("#1 = 1\nG1 X{}1 F100\n", "#".repeat(20_000));
    let (line, column, message) = read(&hashes).expect_err("too deep");
    assert_eq!((line, column), (2, 5 + MAX_NESTING), "{message}");
    let at_limit = format!("#1 = 1\nG1 X{}1 F100\n", "#".repeat(MAX_NESTING));
    assert_eq!(read(&at_limit), Ok(1.0));
}

#[test]
fn deep_conditions_and_call_arguments_are_refused_too() {
    let deep = format!("{}1{}", "[".repeat(20_000), "]".repeat(20_000));
    for text in [
        format!("o1 if {deep}\nG1 X1 F100\no1 endif\nM2\n"),
        format!("o1 sub\nG1 X1 F100\no1 endsub\no1 call {deep}\nM2\n"),
        format!("#1 = {deep}\nM2\n"),
    ] {
        let (_, _, message) = read(&text).expect_err("too deep");
        assert!(message.contains("nested deeper than"), "{message}");
    }
}

#[test]
fn twenty_thousand_nested_blocks_need_no_recursion() {
    // o-word blocks are jumps by label, not recursion: 20,000 nested `if`s run to their move.
    let n = 20_000;
    let mut text = String::from("G21 G90\n");
    for k in 1..=n {
        text.push_str(&format!("o{k} if [1]\n"));
    }
    text.push_str("G1 X4 F100\n");
    for k in (1..=n).rev() {
        text.push_str(&format!("o{k} endif\n"));
    }
    text.push_str("M2\n");
    let mut moves = read_str(Path::new("blocks.ngc"), &text, AxisVec::ZERO)
        .collect::<Result<Vec<_>, _>>()
        .unwrap();
    assert_eq!(moves.len(), 1);
    assert_eq!(moves.pop().unwrap().end[Axis::X], 4.0);
}
