//! A Klartext block as text: physical lines joined at `~`, the block number and the
//! `;` comment dropped, split into tokens; a token's letters and its value.
//!
//! HEIDENHAIN TNC 640 Klartext programming manual, "Fundamentals: NC program structure":
//! a block starts with its number, a `;` starts a comment, and a block that ends with `~`
//! goes on in the next line (cycle parameters, one per line).

use std::ops::Range;

use crate::lex::{LineError, LineResult};

use super::qparam::Qparams;

/// Most physical lines one block may take (a cycle definition has a few dozen).
pub(super) const MAX_BLOCK_LINES: usize = 1000;

/// The byte just after the block number and its blanks (0 without a number).
pub(super) fn after_block_number(line: &str) -> usize {
    let b = line.as_bytes();
    let lead = b.iter().take_while(|c| c.is_ascii_whitespace()).count();
    let digits = b[lead..].iter().take_while(|c| c.is_ascii_digit()).count();
    if digits == 0 {
        return lead;
    }
    let end = lead + digits;
    match b.get(end) {
        None => end,
        Some(c) if c.is_ascii_whitespace() => {
            end + b[end..]
                .iter()
                .take_while(|c| c.is_ascii_whitespace())
                .count()
        }
        // `5X` is not a number but the start of something else.
        Some(_) => lead,
    }
}

/// `line` without its `;` comment (a `;` inside `"…"` is text), and whether it ends with
/// `~` (the block goes on in the next line).
pub(super) fn strip_comment(line: &str) -> (&str, bool) {
    strip_comment_in(line, false).0
}

/// [`strip_comment`] of a line that may go on a comment (`in_comment`): such a line is
/// all comment. Also returns whether the next line is in a comment.
pub(super) fn strip_comment_in(line: &str, in_comment: bool) -> ((&str, bool), bool) {
    let continued = line.trim_end().ends_with('~');
    if in_comment {
        return (("", continued), continued);
    }
    let mut end = line.len();
    if !line.contains('"') {
        end = line.find(';').unwrap_or(end);
    } else {
        let mut quoted = false;
        for (k, c) in line.bytes().enumerate() {
            match c {
                b'"' => quoted = !quoted,
                b';' if !quoted => {
                    end = k;
                    break;
                }
                _ => {}
            }
        }
    }
    let mut body = &line[..end];
    let commented = end < line.len();
    if continued && !commented {
        body = body.trim_end().trim_end_matches('~');
    }
    // A line that is all comment goes on as comment (a long comment wrapped at `~`); after
    // words (`Q200=+2 ;SET-UP CLEARANCE ~`) the block goes on.
    let all_comment = body[after_block_number(body)..].trim().is_empty();
    ((body, continued), continued && commented && all_comment)
}

/// The tokens of a block: byte ranges of its blank-separated words (a `"…"` name is one).
pub(super) fn tokens(text: &str, from: usize, out: &mut Vec<Range<usize>>) {
    out.clear();
    let b = text.as_bytes();
    let mut k = from;
    while k < b.len() {
        if b[k].is_ascii_whitespace() {
            k += 1;
            continue;
        }
        let start = k;
        let mut quoted = false;
        while k < b.len() && (quoted || !b[k].is_ascii_whitespace()) {
            if b[k] == b'"' {
                quoted = !quoted;
            }
            k += 1;
        }
        // Older controls print `X + 10` and `Z 25.000`: a sign or number joins the
        // address letters before it.
        let joins = |prev: &str| {
            let (letters, rest) = split_word(prev);
            JOINED.iter().any(|l| l.eq_ignore_ascii_case(letters))
                && matches!(rest.trim(), "" | "+" | "-")
        };
        let first = b[start];
        // `Z + Q13`: a Q parameter after a sign that stands alone joins it too.
        let after_sign = out.last().is_some_and(|p| {
            matches!(
                text[p.clone()].trim_end().as_bytes().last(),
                Some(b'+' | b'-')
            )
        });
        if matches!(first, b'+' | b'-' | b'.')
            || first.is_ascii_digit()
            || (after_sign && matches!(first, b'Q' | b'q'))
        {
            if let Some(prev) = out.last_mut() {
                if joins(&text[prev.clone()]) {
                    prev.end = k;
                    continue;
                }
            }
        }
        out.push(start..k);
    }
}

/// Address letters whose value may follow after blanks.
const JOINED: [&str; 24] = [
    "X", "Y", "Z", "A", "B", "C", "IX", "IY", "IZ", "IA", "IB", "IC", "PR", "PA", "IPR", "IPA",
    "R", "F", "S", "DL", "DR", "ROT", "LEN", "CCA",
];

/// A token's leading letters and the rest: `IX+10` → (`IX`, `+10`), `DR-` → (`DR`, `-`).
pub(super) fn split_word(token: &str) -> (&str, &str) {
    let n = token
        .bytes()
        .take_while(|c| c.is_ascii_alphabetic())
        .count();
    (&token[..n], &token[n..])
}

/// A signed number or Q parameter (`+10`, `-2.5`, `.5`, `+Q1`, `-QL3`, `QR2`) at `span`.
pub(super) fn value(rest: &str, q: &Qparams, span: Range<usize>) -> LineResult<f64> {
    // Most values: a plain decimal, read as the G-code lexer reads one.
    if let (end, Some(v)) = crate::lex::scan_number(rest.as_bytes(), 0) {
        if end == rest.len() {
            return Ok(v);
        }
    }
    if rest.contains(' ') {
        let joined: String = rest.chars().filter(|c| *c != ' ').collect();
        return value(&joined, q, span);
    }
    let (sign, body) = match rest.as_bytes().first() {
        Some(b'+') => (1.0, &rest[1..]),
        Some(b'-') => (-1.0, &rest[1..]),
        _ => (1.0, rest),
    };
    if body.starts_with(['Q', 'q']) {
        return Ok(sign * q.get_ref(body, span)?);
    }
    match body.parse::<f64>() {
        Ok(v) if v.is_finite() && !body.starts_with(['+', '-']) => Ok(sign * v),
        _ => Err(LineError::new(
            span,
            format!("`{rest}`: expected a number such as +10.5 or a Q parameter such as +Q1"),
            "expected a number",
        )),
    }
}
