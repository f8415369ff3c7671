//! Numbers written without a decimal point, as the Fanuc family reads them.
//!
//! A Fanuc control with parameter 3401#0 (DPI) = 0, the manual's default, and a Haas with
//! Setting 162 (Default to Float) off, the factory default, read a dimension word written
//! without a decimal point in the least input increment, not in whole units:
//!
//! ```text
//! value = written · u,   u = 0.001 mm (G21),  0.0001 in (G20),  0.001 deg (A B C, angles)
//! ```
//!
//! so `Z50` is 0.050 mm and `Z50.` is 50 mm. A control with DPI = 1 (Haas: Setting 162 on)
//! reads both as 50 mm, as LinuxCNC, Heidenhain and Sinumerik always do. The machine file's
//! `[control] whole_numbers` says which a machine does; without it the dialect's default
//! holds, with a warning at the first word it scales.
//!
//! Which words are dimensions (Fanuc 0i-MD B-64304EN, "Decimal point programming"):
//! X Y Z U V W A B C I J K R Q, the dwell's X (in ms: `G04 X1000` is 1 s). Not scaled: F
//! (its increment is 1 mm/min or 0.01 in/min, so `F100` is 100 mm/min either way), the
//! counts and numbers (P L H D T S N O), K where it counts a drilling cycle's repeats, P
//! and Q where a lathe cycle names sequence numbers, and the arguments of a macro call
//! (G65, G66), which mtsim leaves in whole units (docs/gcode.md).

use crate::lex::Word;

/// How a control reads a dimension word written without a decimal point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WholeNumbers {
    /// In the least input increment (Fanuc DPI = 0, Haas Setting 162 off).
    Increments,
    /// In whole mm, inches or degrees (Fanuc DPI = 1, Haas Setting 162 on, LinuxCNC).
    Units,
}

/// The least input increment of a length, mm (IS-B, metric).
const INCREMENT_MM: f64 = 0.001;
/// The least input increment of a length under G20, in.
const INCREMENT_IN: f64 = 0.0001;
/// The least input increment of an angle, deg.
const INCREMENT_DEG: f64 = 0.001;
/// The least input increment of a dwell time, s.
const INCREMENT_S: f64 = 0.001;

/// What the block around the words does, as far as their scale depends on it.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct BlockContext {
    /// G20 in effect for this block.
    pub inch: bool,
    /// A drilling cycle is in effect (modal) before this block.
    pub cycle_modal: bool,
    /// Under Fanuc G16 (crate::fanuc_polar): the letter of the angle word, in 0.001°.
    pub polar_angle: Option<char>,
}

/// Scales `words`' dimension words that were written as whole numbers (no decimal point,
/// not computed) to the least input increment, and returns the first nonzero one scaled
/// (for the warning). Words with a decimal point or a computed value are left as they are.
pub(crate) fn scale_whole_numbers<'l>(
    words: &mut [Word<'l>],
    context: BlockContext,
) -> Option<Word<'l>> {
    let g = |code: &str| {
        words
            .iter()
            .any(|w| w.letter == 'G' && !w.computed() && same_code(w.number, code))
    };
    // A macro call's arguments: left in whole units.
    if g("65") || g("66") || g("66.1") {
        return None;
    }
    let dwell = g("4");
    // G51's I J K (and P) are scaling factors, read by crate::mirror_scale.
    let scaling = g("51");
    let rotation = g("68") || g("68.2") || g("68.3") || g("68.4");
    // G70-G72 name the profile's first and last sequence numbers in P and Q (lathe).
    let lathe_cycle = g("70") || g("71") || g("72");
    let motion_given = g("0") || g("1") || g("2") || g("3");
    let drilling = [
        "73", "74", "76", "81", "82", "83", "84", "85", "86", "87", "88", "89",
    ]
    .iter()
    .any(|c| g(c))
        || (context.cycle_modal && !motion_given);
    let length = if context.inch {
        INCREMENT_IN
    } else {
        INCREMENT_MM
    };
    let mut first = None;
    for w in words.iter_mut() {
        if w.computed() || w.number.contains('.') {
            continue;
        }
        let unit = match w.letter {
            'X' if dwell => INCREMENT_S,
            _ if dwell => continue,
            'A' | 'B' | 'C' => INCREMENT_DEG,
            'I' | 'J' | 'K' if scaling => continue,
            'I' | 'J' | 'K' | 'R' if rotation => INCREMENT_DEG,
            c if Some(c) == context.polar_angle => INCREMENT_DEG,
            'K' if drilling => continue,
            'Q' | 'P' if lathe_cycle => continue,
            'X' | 'Y' | 'Z' | 'U' | 'V' | 'W' | 'I' | 'J' | 'K' | 'R' | 'Q' => length,
            // `,R` and `,C` (crate::corner): lengths.
            crate::lex::CORNER_ROUND | crate::lex::CORNER_CHAMFER => length,
            _ => continue,
        };
        if w.value != 0.0 && first.is_none() {
            first = Some(*w);
        }
        w.value *= unit;
    }
    first
}

/// `written` (a G word's number as written) is the code `code`: leading zeros aside, so
/// `04` is `4` and `068.2` is `68.2`.
fn same_code(written: &str, code: &str) -> bool {
    let digits = written.strip_prefix('+').unwrap_or(written);
    let trimmed = digits.trim_start_matches('0');
    let trimmed = if trimmed.is_empty() || trimmed.starts_with('.') {
        &digits[digits.len() - trimmed.len() - 1..]
    } else {
        trimmed
    };
    trimmed == code
}

/// The warning at the first word scaled: what it was read as and how to change it.
pub(crate) fn warning(word: &Word, line: &str, context: BlockContext) -> String {
    let text = &line[word.span()];
    let (unit, digits) = match word.letter {
        'A' | 'B' | 'C' => ("deg", 3),
        _ if context.inch => ("in", 4),
        _ => ("mm", 3),
    };
    format!(
        "`{text}` has no decimal point: read in the least input increment, {:.digits$} {unit} \
         (Fanuc parameter 3401#0 DPI = 0, Haas Setting 162 off: the controls' defaults); \
         on a machine that reads it as {} {unit}, set `whole_numbers = \"units\"` in the \
         machine file's [control], or write `{}{}.`",
        word.value, word.number, word.letter, word.number
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::Params;
    use crate::lex::{lex, Lexed};

    fn scaled(line: &str, context: BlockContext) -> Vec<(char, f64)> {
        let params = Params::default();
        let Ok(Lexed::Words { mut words, .. }) = lex(line, &params, true) else {
            panic!("`{line}` did not lex to words");
        };
        scale_whole_numbers(&mut words, context);
        words.iter().map(|w| (w.letter, w.value)).collect()
    }

    fn value(words: &[(char, f64)], letter: char) -> f64 {
        words.iter().find(|(l, _)| *l == letter).unwrap().1
    }

    #[test]
    fn whole_lengths_are_micrometres_and_written_points_stay() {
        let w = scaled("G01 X10 Y20. Z-5 F100", BlockContext::default());
        assert_eq!(value(&w, 'X'), 10.0 * 0.001);
        assert_eq!(value(&w, 'Y'), 20.0);
        assert_eq!(value(&w, 'Z'), -5.0 * 0.001);
        assert_eq!(value(&w, 'F'), 100.0);
        assert_eq!(value(&w, 'G'), 1.0);
    }

    #[test]
    fn inches_angles_and_dwells_take_their_own_increments() {
        let inch = BlockContext {
            inch: true,
            ..BlockContext::default()
        };
        let w = scaled("G01 X10 C90000", inch);
        assert_eq!(value(&w, 'X'), 10.0 * 0.0001);
        assert_eq!(value(&w, 'C'), 90000.0 * 0.001);
        let w = scaled("G04 X1500", BlockContext::default());
        assert_eq!(value(&w, 'X'), 1.5);
        let w = scaled("G68 X0 Y0 R45000", inch);
        assert_eq!(value(&w, 'R'), 45.0);
    }

    #[test]
    fn counts_sequence_numbers_and_macro_arguments_are_not_dimensions() {
        let w = scaled("G81 X10. Y0 Z-2000 R1000 K3 F80", BlockContext::default());
        assert_eq!(value(&w, 'K'), 3.0);
        assert_eq!(value(&w, 'Z'), -2.0);
        assert_eq!(value(&w, 'R'), 1.0);
        let modal = BlockContext {
            cycle_modal: true,
            ..BlockContext::default()
        };
        assert_eq!(value(&scaled("X20. K2", modal), 'K'), 2.0);
        let w = scaled("G71 P100 Q200 U400 W100 F0.2", BlockContext::default());
        assert_eq!(value(&w, 'P'), 100.0);
        assert_eq!(value(&w, 'Q'), 200.0);
        assert_eq!(value(&w, 'U'), 0.4);
        let w = scaled("G65 P9010 A10 X5", BlockContext::default());
        assert_eq!(value(&w, 'A'), 10.0);
        assert_eq!(value(&w, 'X'), 5.0);
    }

    #[test]
    fn g_codes_are_matched_with_leading_zeros() {
        assert!(same_code("04", "4"));
        assert!(same_code("4", "4"));
        assert!(same_code("068.2", "68.2"));
        assert!(!same_code("40", "4"));
        assert!(same_code("00", "0"));
        assert!(same_code("0", "0"));
    }
}
