//! The tokenizer: one source line into words and parameter assignments.
//!
//! Plain numbers are read without touching the parameter store, so programs without
//! parameters or expressions pay nothing for them. A word's value may also be `[expr]`,
//! `#param` or a function (`X[#1+2]`, `Y#<_y>`, `Z-SIN[30]`).

use std::ops::Range;

use crate::byte_words::{below_first, bytes_equal, first_byte, load, ONES};
use crate::expr::{function_at, Eval, ExprError, Param, Params};

/// Word letters the reader knows.
pub const EXPECTED_WORDS: &str = "G M N F S T X Y Z A B C U V W I J K R P Q L H D E @ ^";

/// The letter a Fanuc/Haas `,R` (corner rounding, crate::corner) is lexed as.
pub const CORNER_ROUND: char = 'r';
/// The letter a Fanuc/Haas `,C` (chamfer, crate::corner) is lexed as.
pub const CORNER_CHAMFER: char = 'c';

/// An error on one line; `span` is a byte range in that line.
#[derive(Debug)]
pub struct LineError {
    pub span: Range<usize>,
    pub message: String,
    pub label: String,
    pub help: Option<String>,
}

impl LineError {
    pub fn new(span: Range<usize>, message: impl Into<String>, label: impl Into<String>) -> Self {
        LineError {
            span,
            message: message.into(),
            label: label.into(),
            help: None,
        }
    }

    pub fn help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }
}

impl From<ExprError> for LineError {
    fn from(e: ExprError) -> LineError {
        LineError::new(e.span, e.message, e.label)
    }
}

pub type LineResult<T> = std::result::Result<T, LineError>;

/// One word: a letter and its value.
#[derive(Clone, Copy, Debug)]
pub struct Word<'l> {
    /// Upper-case letter.
    pub letter: char,
    pub value: f64,
    /// The number as written, or "" when the value was computed.
    pub number: &'l str,
    /// Letter through value, bytes in the line.
    pub span: (usize, usize),
}

impl Word<'_> {
    /// A placeholder for fixed buffers.
    pub const EMPTY: Word<'static> = Word {
        letter: ' ',
        value: 0.0,
        number: "",
        span: (0, 0),
    };

    pub fn span(&self) -> Range<usize> {
        self.span.0..self.span.1
    }

    /// True when the value came from an expression or parameter.
    pub fn computed(&self) -> bool {
        self.number.is_empty()
    }

    /// A G word's code in tenths (`G51.1` is 511), `(value · 10).round() as u32`; `None`
    /// for another letter, a computed value or a negative one.
    ///
    /// `f64::round` without its library call: with `x = 10 · value ≥ 0` below 2^32 and `t`
    /// its truncation (`x as i64`, exact), `x - t` is exact (the fraction of `x`), and the
    /// result is `t + 1` from one half up (half away from zero). From 2^32 - 1/2 on, both
    /// saturate to `u32::MAX`.
    #[inline]
    pub fn g_tenths(&self) -> Option<u32> {
        if self.letter != 'G' || self.computed() || !(self.value >= 0.0) {
            return None;
        }
        let x = self.value * 10.0;
        if !(x < 4_294_967_296.0) {
            return Some(u32::MAX);
        }
        let t = x as i64;
        let rounded = t + i64::from(x - t as f64 >= 0.5);
        Some(rounded.min(u32::MAX as i64) as u32)
    }
}

/// What a source line holds.
pub enum Lexed<'l> {
    /// Nothing but blanks and comments, or a deleted block.
    Nothing,
    /// A `%` line.
    Percent,
    Words {
        words: Vec<Word<'l>>,
        assigns: Vec<(Param, f64)>,
    },
}

/// Where the lexer reads parameter values: a store as it stands (`&Params`), or one the
/// reader brings up to date only when a line asks for it (its system parameters,
/// `#5420` and `#<_x>`, docs/performance.md "Session 27").
///
/// Every read of a parameter or value on a line needs a `#` or a `[` there (a function
/// name counts only before `[`), so the lexer asks for the store exactly at the first one
/// it evaluates, and calls [`ParamSource::mentioned`] for one in a comment or after `;`:
/// a store brought up to date at either is the store brought up to date before a line that
/// holds `#` or `[` anywhere (lexing reads parameters and changes none).
pub trait ParamSource {
    /// The store, up to date.
    fn params(&mut self) -> &Params;
    /// The line holds `#` or `[` where the lexer evaluates nothing.
    fn mentioned(&mut self) {}
}

impl ParamSource for &Params {
    fn params(&mut self) -> &Params {
        self
    }
}

/// True when `bytes` holds a `#` or a `[`, 8 bytes at a time ([`crate::byte_words`]).
pub(crate) fn has_hash_or_bracket(bytes: &[u8]) -> bool {
    let mut chunks = bytes.chunks_exact(8);
    for chunk in &mut chunks {
        if marks(load(chunk)) != 0 {
            return true;
        }
    }
    chunks.remainder().iter().any(|&c| c == b'#' || c == b'[')
}

/// The `#`s and `[`s of word `w` ([`bytes_equal`]).
#[inline(always)]
fn marks(w: u64) -> u64 {
    bytes_equal(w, b'#') | bytes_equal(w, b'[')
}

/// The index of the first `)` in `bytes` (the rest of a line after a comment's `(`), and
/// whether a `#` or a `[` comes before it; `None` without one. 8 bytes at a time
/// ([`crate::byte_words`]): the lowest set byte of the `)` test is the first `)`, and a set
/// byte of the `#`/`[` test below it, false or not, means a true one below it.
#[inline(always)]
fn comment_end(bytes: &[u8]) -> Option<(usize, bool)> {
    let mut chunks = bytes.chunks_exact(8);
    let (mut at, mut marked) = (0, false);
    for chunk in &mut chunks {
        let w = load(chunk);
        let close = bytes_equal(w, b')');
        if close != 0 {
            return Some((
                at + first_byte(close),
                marked || below_first(marks(w), close) != 0,
            ));
        }
        marked |= marks(w) != 0;
        at += 8;
    }
    let rest = chunks.remainder().len();
    if rest > 0 && bytes.len() >= 8 {
        // The last 8 bytes, the `8 - rest` already looked at shifted out: they hold no `)`
        // (so no false close byte above them), and a false mark above a mark of theirs
        // comes with `marked` already set.
        let w = load(&bytes[bytes.len() - 8..]) >> (8 * (8 - rest));
        let close = bytes_equal(w, b')') & (u64::MAX >> (8 * (8 - rest)));
        if close == 0 {
            return None;
        }
        return Some((
            at + first_byte(close),
            marked || below_first(marks(w), close) != 0,
        ));
    }
    for (k, &c) in chunks.remainder().iter().enumerate() {
        if c == b')' {
            return Some((at + k, marked));
        }
        marked |= c == b'#' || c == b'[';
    }
    None
}

pub fn is_blank(c: u8) -> bool {
    c == b' ' || c == b'\t'
}

/// Splits a line into words and assignments, dropping comments.
pub fn lex<'l>(line: &'l str, params: &Params, fanuc: bool) -> LineResult<Lexed<'l>> {
    lex_with(line, params, fanuc, Vec::new())
}

/// [`lex`], with the words collected in `words` (cleared first): the reader hands the
/// same buffer back for every block, so that a block costs no allocation. Inlined into the
/// reader (docs/performance.md).
#[inline(always)]
pub fn lex_with<'l, P: ParamSource>(
    line: &'l str,
    mut params: P,
    fanuc: bool,
    mut words: Vec<Word<'l>>,
) -> LineResult<Lexed<'l>> {
    words.clear();
    let bytes = line.as_bytes();
    let mut i = 0;
    while i < bytes.len() && is_blank(bytes[i]) {
        i += 1;
    }
    let percent = bytes.get(i) == Some(&b'%');
    if percent {
        i += 1;
    } else if bytes.get(i) == Some(&b'/') {
        // Block delete with the optional-block-skip switch on: the block is not executed.
        return Ok(Lexed::Nothing);
    }
    let mut assigns = Vec::new();
    while i < bytes.len() {
        let c = bytes[i];
        if is_blank(c) {
            i += 1;
        } else if c == b'(' {
            // A byte search: `)` is ASCII, so it cannot sit inside a multi-byte character.
            match comment_end(&bytes[i + 1..]) {
                Some((close, marked)) => {
                    if marked {
                        params.mentioned();
                    }
                    i += close + 2
                }
                None => {
                    return Err(LineError::new(
                        i..line.len(),
                        "unclosed comment: expected `)` before the end of the line",
                        "this comment is not closed",
                    )
                    .help("close the comment with `)` on the same line"))
                }
            }
        } else if c == b';' {
            if has_hash_or_bracket(&bytes[i + 1..]) {
                params.mentioned();
            }
            break;
        } else if c == b'/' {
            return Err(LineError::new(
                i..i + 1,
                "block delete `/` in the middle of a block: expected it only at the start",
                "block delete here",
            )
            .help("move `/` to the start of the line to skip the whole block"));
        } else if c == b'%' {
            return Err(LineError::new(
                i..i + 1,
                "`%` inside a block: expected `%` alone on its own line",
                "unexpected `%`",
            ));
        } else if c == b'#' {
            let mut e = Eval::new(line, i, params.params(), fanuc);
            let p = e.param()?;
            e.skip_blanks();
            if line.as_bytes().get(e.i) != Some(&b'=') {
                return Err(LineError::new(
                    i..e.i,
                    format!(
                        "parameter `{}` outside a word: expected `=` and a value to assign",
                        &line[i..e.i]
                    ),
                    "expected `=`",
                ));
            }
            e.i += 1;
            let v = if fanuc { e.binary(0)? } else { e.value()? };
            if !v.is_finite() {
                return Err(LineError::new(i..e.i, "value is not finite", "not finite"));
            }
            assigns.push((p, v));
            i = e.i;
        } else if c.is_ascii_alphabetic() || c == b'@' || c == b'^' || (c == b'$' && !fanuc) {
            // `@` and `^`: LinuxCNC polar radius and angle; `$`: its spindle selector.
            let w = lex_word(line, i, &mut params, fanuc)?;
            i = w.span.1;
            words.push(w);
            // The blank after a word, skipped here rather than by a turn of the loop.
            if bytes.get(i) == Some(&b' ') {
                i += 1;
            }
        } else if c == b','
            && matches!(
                bytes.get(i + 1).map(u8::to_ascii_uppercase),
                Some(b'R' | b'C')
            )
        {
            // Fanuc and Haas `,R` / `,C` after a G01: corner rounding or chamfer to the
            // next move (crate::corner), lexed as [`CORNER_ROUND`] and [`CORNER_CHAMFER`].
            let mut w = lex_word(line, i + 1, &mut params, fanuc)?;
            w.letter = match w.letter {
                'R' => CORNER_ROUND,
                _ => CORNER_CHAMFER,
            };
            w.span.0 = i;
            i = w.span.1;
            words.push(w);
        } else {
            let (ch, span) = char_at(line, i);
            return Err(LineError::new(
                span,
                format!(
                    "unexpected character `{}`: expected a word (one of {EXPECTED_WORDS} followed by a number), a comment `( )` or `;`",
                    ch.escape_debug()
                ),
                "unexpected character",
            ));
        }
    }
    if percent {
        if let Some(word) = words.first() {
            return Err(LineError::new(
                word.span(),
                "word on a `%` line: expected `%` alone on its line",
                "move this word to its own line",
            ));
        }
        return Ok(Lexed::Percent);
    }
    if words.is_empty() && assigns.is_empty() {
        Ok(Lexed::Nothing)
    } else {
        Ok(Lexed::Words { words, assigns })
    }
}

/// The character at byte `i` of `line` and its byte range.
pub fn char_at(line: &str, i: usize) -> (char, Range<usize>) {
    let c = line[i..].chars().next().unwrap_or(' ');
    (c, i..i + c.len_utf8())
}

/// Reads the word whose letter is at byte `start`. Blanks between the letter and the number
/// are allowed; the number is `[+-]digits[.digits]` with at least one digit, or a value.
/// Inlined: its result is large (docs/performance.md).
#[inline(always)]
fn lex_word<'l, P: ParamSource>(
    line: &'l str,
    start: usize,
    params: &mut P,
    fanuc: bool,
) -> LineResult<Word<'l>> {
    let bytes = line.as_bytes();
    // An ASCII letter, `@`, `^` or `$` (the caller's test).
    let letter = bytes[start].to_ascii_uppercase() as char;
    let mut i = start + 1;
    while i < bytes.len() && is_blank(bytes[i]) {
        i += 1;
    }
    let number_start = i;
    let (end, fast) = scan_number(bytes, i);
    i = end;
    // SAFETY: `number_start` follows ASCII bytes (the letter, blanks) and `i` a run of the
    // ASCII bytes `0-9 . + -` from it (or is it): both are character boundaries.
    let number = unsafe { line.get_unchecked(number_start..i) };
    // The common case, a plain decimal number (so not a computed value), read and checked
    // in one pass: nothing more to look at.
    if let (Some(value), true) = (fast, known_letter(letter)) {
        return Ok(Word {
            letter,
            value,
            number,
            span: (start, i),
        });
    }
    let span = start..if number.is_empty() { start + 1 } else { i };
    let text = &line[span.clone()];
    if !known_letter(letter) {
        return Err(LineError::new(
            span,
            format!("unsupported word `{text}`: expected one of {EXPECTED_WORDS}"),
            "unsupported word",
        )
        .help("docs/gcode.md lists the supported dialect; remove the word or post-process the program without it"));
    }
    // A computed value: `[`, `#`, a sign before either, or a function name.
    let sign_then =
        |k: usize| matches!(bytes.get(k), Some(b'[' | b'#')) || function_at(line, k).is_some();
    let computed = (number.is_empty() && (sign_then(number_start)))
        || ((number == "-" || number == "+") && sign_then(i));
    if computed {
        let mut e = Eval::new(line, number_start, params.params(), fanuc);
        let value = e.value()?;
        return Ok(Word {
            letter,
            value,
            number: "",
            span: (start, e.i),
        });
    }
    if !is_decimal(number) {
        let what = if number.is_empty() {
            format!("`{letter}` has no number")
        } else {
            format!("malformed number `{number}` in `{text}`")
        };
        return Err(LineError::new(
            span,
            format!("{what}: expected a decimal number after `{letter}`, such as `{letter}1.5` or `{letter}-2`"),
            "malformed word",
        )
        .help("write numbers as digits with at most one decimal point, e.g. `X-12.345`"));
    }
    let value: f64 = number.parse().map_err(|_| {
        LineError::new(
            span.clone(),
            format!("malformed number `{number}`: expected a decimal number"),
            "malformed number",
        )
    })?;
    if !value.is_finite() {
        return Err(LineError::new(
            span,
            format!("number `{number}` is too large: expected a finite value"),
            "too large",
        ));
    }
    Ok(Word {
        letter,
        value,
        number,
        span: (start, span.end),
    })
}

/// Word letters that [`lex_word`] accepts.
const WORD_LETTERS: &str = "GMNOFSTXYZABCUVWIJKRPQLHDE";

/// [`WORD_LETTERS`] `A` to `Z` as bits (`A` = bit 0).
const KNOWN_LETTERS: u32 = letter_mask(WORD_LETTERS);

const fn letter_mask(letters: &str) -> u32 {
    let b = letters.as_bytes();
    let mut mask = 0;
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_uppercase() {
            mask |= 1 << (b[i] - b'A');
        }
        i += 1;
    }
    mask
}

/// `letter` is one of [`WORD_LETTERS`]: a bit test for `A` to `Z`, a search otherwise.
#[inline]
fn known_letter(letter: char) -> bool {
    if letter.is_ascii_uppercase() {
        KNOWN_LETTERS >> (letter as u32 - 'A' as u32) & 1 == 1
    } else {
        // LinuxCNC polar radius `@` and angle `^`, and the spindle selector `$`.
        WORD_LETTERS.contains(letter) || matches!(letter, '@' | '^' | '$')
    }
}

/// Exact powers of ten, `10^k` for `k` ≤ 22 (the largest exactly representable in f64).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// The end of the number that starts at byte `start` (the run of `0-9 . + -` there), and
/// its value when it is a plain decimal `[+-]? digits* ( . digits* )?` (at least one digit)
/// that is quick to read exactly; `None` for anything else, which the caller reads the
/// slow way. One pass over the bytes.
///
/// With the digits as an integer `m` and `f` digits after the point, the value is
/// `m / 10^f`. When `m ≤ 2^53` and `f ≤ 22`, both `m` and `10^f` are exact f64, and IEEE
/// division rounds their exact quotient correctly (Clinger's fast path), so the result is
/// the same f64 as `str::parse` gives: the correctly rounded value of the decimal.
#[inline(always)]
pub(crate) fn scan_number(b: &[u8], start: usize) -> (usize, Option<f64>) {
    let mut i = start;
    let negative = b.get(i) == Some(&b'-');
    if negative || b.get(i) == Some(&b'+') {
        i += 1;
    }
    if let Some(read) = scan_short_decimal(b, i) {
        let (end, v) = read;
        return (end, Some(if negative { -v } else { v }));
    }
    let digits_start = i;
    let mut m: u64 = 0;
    let mut point = None;
    while i < b.len() {
        let c = b[i];
        let d = c.wrapping_sub(b'0');
        if d < 10 {
            // Wraps only past 19 digits, which are refused below.
            m = m.wrapping_mul(10).wrapping_add(d as u64);
        } else if c == b'.' && point.is_none() {
            point = Some(i);
        } else {
            break;
        }
        i += 1;
    }
    let mut end = i;
    while end < b.len() && matches!(b[end], b'0'..=b'9' | b'.' | b'+' | b'-') {
        end += 1;
    }
    let n = i - digits_start;
    if end != i || n == 0 || n > 19 || (n == 1 && point.is_some()) {
        return (end, None);
    }
    let fraction = point.map_or(0, |p| i - p - 1);
    if m > 1 << 53 || fraction > 22 {
        return (end, None);
    }
    // (m ≤ 2^53: as an i64, one conversion instruction, the same exact value.)
    let v = m as i64 as f64 / POW10[fraction];
    (end, Some(if negative { -v } else { v }))
}

/// [`scan_number`]'s common case, without a loop or a branch per byte: at most 7 digits,
/// then (or not) a point and at most 7 digits, each part read from an 8-byte window of the
/// line (so the byte after it is in the window too). Returns the end and the value (no
/// sign), or `None` for anything else (a number near the end of the line, more digits, a
/// run of `0-9 . + -` that goes on), which the byte loop reads.
///
/// A number of `k` ≤ 7 digits at the start of a window: its digits are the window's bytes
/// minus `'0'`, shifted up by `8 - k` bytes (so that zeros lead), then combined in pairs,
/// fours and eight by three multiplications (Lemire's eight-digit method). With `f` digits
/// after the point, `m = int · 10^f + frac` is the same integer as the byte loop's, and the
/// value `m / 10^f` is the same division.
#[inline(always)]
fn scan_short_decimal(b: &[u8], i: usize) -> Option<(usize, f64)> {
    const POW10_INT: [u64; 8] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000];
    let w = window(b, i)?;
    let n_int = leading_digits(w);
    if n_int == 8 {
        return None;
    }
    let after = i + n_int;
    match b[after] {
        b'.' => {
            let w2 = window(b, after + 1)?;
            let n_frac = leading_digits(w2);
            let end = after + 1 + n_frac;
            if n_frac == 8 || n_int + n_frac == 0 || continues_number(b[end]) {
                return None;
            }
            let m = digits_value(w, n_int) * POW10_INT[n_frac] + digits_value(w2, n_frac);
            // (m < 10^14 < 2^53: exact.)
            Some((end, m as i64 as f64 / POW10[n_frac]))
        }
        c if n_int > 0 && !continues_number(c) => {
            Some((after, digits_value(w, n_int) as i64 as f64))
        }
        _ => None,
    }
}

/// `c` continues a run of `0-9 . + -` (a number the fast paths do not read).
#[inline(always)]
fn continues_number(c: u8) -> bool {
    matches!(c, b'0'..=b'9' | b'.' | b'+' | b'-')
}

/// Bytes `b[i..i + 8]` as a little-endian word (the first byte lowest), if there are 8.
#[inline(always)]
fn window(b: &[u8], i: usize) -> Option<u64> {
    let chunk: [u8; 8] = b.get(i..i + 8)?.try_into().ok()?;
    Some(u64::from_le_bytes(chunk))
}

/// How many of the first bytes of `w` are the digits `0`-`9` (0-8).
#[inline(always)]
fn leading_digits(w: u64) -> usize {
    // Digit bytes become 0-9. A byte of `a` is above 9 when its high bit is set, or its
    // low 7 bits plus 0x76 reach 0x80 (at most 0xf5: no carry into the next byte).
    let a = w ^ (ONES * b'0' as u64);
    let above_9 = (((a & (ONES * 0x7f)) + ONES * 0x76) | a) & (ONES * 0x80);
    (above_9.trailing_zeros() / 8) as usize
}

/// The value of the first `k` (0-7) bytes of `w`, all digits.
#[inline(always)]
fn digits_value(w: u64, k: usize) -> u64 {
    if k == 0 {
        return 0;
    }
    let v = (w & 0x0F0F_0F0F_0F0F_0F0F) << (8 * (8 - k));
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    (v & 0x0000_00FF_0000_00FF)
        .wrapping_mul(100 + (1_000_000 << 32))
        .wrapping_add(((v >> 16) & 0x0000_00FF_0000_00FF).wrapping_mul(1 + (10_000 << 32)))
        >> 32
}

/// `[+-]? digits* ( . digits* )?` with at least one digit.
pub fn is_decimal(s: &str) -> bool {
    let s = s.strip_prefix(['+', '-']).unwrap_or(s);
    let (int, frac) = s.split_once('.').unwrap_or((s, ""));
    let digits = |p: &str| p.bytes().all(|b| b.is_ascii_digit());
    digits(int) && digits(frac) && int.len() + frac.len() > 0
}

#[cfg(test)]
mod tests {
    use super::{comment_end, has_hash_or_bracket, scan_number, Word};

    /// A G word's tenths are `(value · 10).round() as u32` at and around every half, for
    /// small and huge values, infinity and the signed zeros.
    #[test]
    fn g_tenths_round_as_the_library_round() {
        let mut values = vec![0.0, -0.0, 0.049_999_999_999_999_996, 0.05, 51.1, 68.2, 1e15];
        values.extend([
            4.294_967_295e8,
            4.294_967_295_5e8,
            1e19,
            1e20,
            f64::MAX,
            f64::INFINITY,
        ]);
        for k in 0..4000 {
            let half = (k as f64 + 0.5) / 10.0;
            values.extend([half, half.next_up(), half.next_down(), k as f64 / 10.0]);
        }
        for v in values {
            let w = Word {
                letter: 'G',
                value: v,
                number: "1",
                span: (0, 1),
            };
            let expected = (v >= 0.0).then(|| (v * 10.0).round() as u32);
            assert_eq!(w.g_tenths(), expected, "{v:e}");
        }
        let m = Word {
            letter: 'M',
            ..Word::EMPTY
        };
        assert_eq!(m.g_tenths(), None);
    }

    /// The first `)` of every short text of `)`, `#`, `[` and filler, and whether a `#` or
    /// `[` comes before it, as a byte loop finds them.
    #[test]
    fn a_comment_ends_at_its_first_close_with_its_marks_before_it() {
        let alphabet = [b')', b'#', b'[', b'x', b'(', b'\xff', b'\x22', b'\x5a'];
        for len in 0..=19 {
            // Every text of up to 3 special bytes at any places, the rest filler.
            for a in 0..len.max(1) {
                for b in a..len.max(1) {
                    for (ca, cb) in [(0, 1), (1, 0), (0, 2), (2, 0), (1, 1), (0, 0), (5, 0)] {
                        let mut text: Vec<u8> = (0..len).map(|k| alphabet[3 + k % 5]).collect();
                        if len > 0 {
                            text[a] = alphabet[ca];
                            text[b] = alphabet[cb];
                        }
                        let close = text.iter().position(|&c| c == b')');
                        let expected =
                            close.map(|k| (k, text[..k].iter().any(|&c| c == b'#' || c == b'[')));
                        assert_eq!(comment_end(&text), expected, "{text:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_hash_or_bracket_is_found_at_every_place_of_every_short_line() {
        // Bytes next to `#` (0x23) and `[` (0x5b), and ones whose difference from them
        // borrows across bytes in the 8-byte test.
        let filler = b"G1X-0.5\"$ZZ\\\x01\xff";
        for len in 0..=24 {
            let line: Vec<u8> = (0..len).map(|k| filler[k % filler.len()]).collect();
            assert!(!has_hash_or_bracket(&line), "{len}: none in {line:?}");
            for at in 0..len {
                for c in [b'#', b'['] {
                    let mut with = line.clone();
                    with[at] = c;
                    assert!(has_hash_or_bracket(&with), "{} at {at} of {len}", c as char);
                }
            }
        }
    }

    /// Every plain decimal of 0-9 digits before and after the point, each with a sign or
    /// not, followed by what may end a number (or continue it): the end is the end of the
    /// run of `0-9 . + -`, and a value, when given, is `str::parse`'s of that run, which is
    /// a plain decimal; a plain decimal of at most 15 digits always gets one.
    #[test]
    fn numbers_read_in_8_byte_windows_end_and_round_as_the_byte_loop() {
        let digits = "1234567890";
        for n_int in 0..=9 {
            for n_frac in 0..=9 {
                for point in [false, true] {
                    if !point && n_frac > 0 || n_int + n_frac == 0 {
                        continue;
                    }
                    let number = format!(
                        "{}{}{}",
                        &digits[..n_int],
                        if point { "." } else { "" },
                        &digits[10 - n_frac..]
                    );
                    for sign in ["", "-", "+"] {
                        for tail in ["", " ", " X1.5 Y2", "X", "+1", ".5", "-", ";(c)  "] {
                            let text = format!("{sign}{number}{tail}");
                            let b = text.as_bytes();
                            let run = b
                                .iter()
                                .skip(sign.len())
                                .take_while(|c| matches!(c, b'0'..=b'9' | b'.' | b'+' | b'-'))
                                .count();
                            let (end, value) = scan_number(b, 0);
                            assert_eq!(end, sign.len() + run, "end of {text:?}");
                            let run_text = &text[sign.len()..sign.len() + run];
                            let n_digits = run_text.bytes().filter(u8::is_ascii_digit).count();
                            let plain = n_digits > 0
                                && run_text.bytes().all(|c| c.is_ascii_digit() || c == b'.')
                                && run_text.matches('.').count() <= 1;
                            match value {
                                Some(v) => {
                                    assert!(plain, "{text:?} read as {v}");
                                    let expected: f64 =
                                        format!("{sign}{run_text}").parse().unwrap();
                                    assert_eq!(v.to_bits(), expected.to_bits(), "{text:?}");
                                }
                                None => assert!(!plain || n_digits > 15, "{text:?} not read"),
                            }
                        }
                    }
                }
            }
        }
    }
}
