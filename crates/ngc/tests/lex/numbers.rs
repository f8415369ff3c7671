//! Numbers in words are read exactly: the value of `X<decimal>` is the correctly rounded
//! f64 of the decimal, the same as Rust's `str::parse::<f64>` (itself correctly rounded),
//! whether the reader takes its fast path (up to 19 digits, value exact as an integer over
//! a power of ten) or the general one.

use std::path::Path;

use ngc::{read_str, Axis, AxisVec};
use proptest::prelude::*;

/// The X of `G1 X<number>` in G21 G90 with no offsets: the number's value plus zero.
fn x_of(number: &str) -> f64 {
    let text = format!("G21 G90\nG1 X{number} F100\n");
    let moves: Vec<_> = read_str(Path::new("n.ngc"), &text, AxisVec::ZERO)
        .collect::<Result<_, _>>()
        .unwrap_or_else(|e| panic!("{number}: {e}"));
    moves[0].end[Axis::X]
}

/// The reader's X (program value + work offset 0) of `number`: the parse plus zero, which
/// turns -0 into +0 and changes nothing else.
fn expected(number: &str) -> f64 {
    number.parse::<f64>().unwrap() + 0.0
}

#[test]
fn hand_picked_decimals_read_as_the_correctly_rounded_f64() {
    for number in [
        "0",
        "-0",
        "+0",
        "0.1",
        "-0.1",
        ".5",
        "5.",
        "-.25",
        "+7",
        "1.0000",
        "0.3",
        "123.4567",
        "-99999.9999",
        "9007199254740992",
        "9007199254740993",
        "0.1234567890123456789",
        "1234567890123456789",
        "12345678901234567890",
        "0.0000000000000000000001",
        "0.00000000000000000000001",
        "4.35",
        "2.675",
        "1e0",
    ] {
        if number.contains('e') {
            continue; // not a G-code number
        }
        assert_eq!(
            x_of(number).to_bits(),
            expected(number).to_bits(),
            "{number}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn any_decimal_reads_as_str_parse_gives(
        sign in prop::sample::select(vec!["", "-", "+"]),
        int in "[0-9]{0,21}",
        point in any::<bool>(),
        frac in "[0-9]{0,25}",
    ) {
        let frac = if point { frac } else { String::new() };
        prop_assume!(!int.is_empty() || !frac.is_empty());
        let number = format!("{sign}{int}{}{frac}", if point { "." } else { "" });
        prop_assert_eq!(x_of(&number).to_bits(), expected(&number).to_bits(), "{}", number);
    }

    #[test]
    fn short_decimals_as_a_post_writes_them_read_exactly(
        v in -1.0e6f64..1.0e6,
        digits in 0usize..7,
    ) {
        let number = format!("{v:.digits$}");
        prop_assert_eq!(x_of(&number).to_bits(), expected(&number).to_bits(), "{}", number);
    }
}
