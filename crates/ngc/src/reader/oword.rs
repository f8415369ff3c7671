//! The o-word and macro statement lines of the ISO family: `o<label> keyword …` (LinuxCNC)
//! and Fanuc macro B's `IF`, `WHILE`, `END`, `GOTO`, read before the words of a block.

use crate::lex::{is_blank, LineError, LineResult};

use super::state::{Kw, Macro, OLine, KEYWORDS};

/// Skips blanks and an `N<digits>` word; returns the index after them.
pub(super) fn after_line_number(b: &[u8]) -> usize {
    let mut i = 0;
    while i < b.len() && is_blank(b[i]) {
        i += 1;
    }
    if i < b.len() && (b[i] == b'N' || b[i] == b'n') {
        let mut k = i + 1;
        while k < b.len() && (b[k].is_ascii_digit() || b[k] == b'.') {
            k += 1;
        }
        if k > i + 1 {
            i = k;
            while i < b.len() && is_blank(b[i]) {
                i += 1;
            }
        }
    }
    i
}

/// Reads an o-word line header, if the line is one.
pub(super) fn oline(line: &str) -> LineResult<Option<OLine>> {
    let b = line.as_bytes();
    let i = after_line_number(b);
    if !matches!(b.get(i), Some(b'o' | b'O')) {
        return Ok(None);
    }
    let start = i;
    let mut k = i + 1;
    while k < b.len() && is_blank(b[k]) {
        k += 1;
    }
    let label = if b.get(k) == Some(&b'<') {
        let Some(close) = line[k..].find('>') else {
            return Err(LineError::new(
                start..line.len(),
                "unclosed o-word name: expected `>` after `o<name`",
                "no `>`",
            ));
        };
        let name: String = line[k + 1..k + close]
            .chars()
            .filter(|c| !c.is_whitespace())
            .map(|c| c.to_ascii_lowercase())
            .collect();
        k += close + 1;
        name
    } else {
        let d = k;
        while k < b.len() && b[k].is_ascii_digit() {
            k += 1;
        }
        if d == k && b.get(k).is_some_and(u8::is_ascii_alphabetic) {
            // `OFinal ToolPath`: a program name where the number would be (a CAM post's
            // header), read as a Fanuc program number line; the rest of the line is its name.
            let end = line[k..].find(['(', ';']).map_or(line.len(), |e| k + e);
            return Ok(Some(OLine {
                label: line[k..end].trim().to_ascii_lowercase(),
                kw: Kw::Number,
                rest: line.len(),
                span: start..end,
            }));
        }
        if d == k {
            return Err(LineError::new(
                start..k.max(start + 1),
                "o-word without a label: expected `o<number>` or `o<name>`",
                "no label",
            ));
        }
        line[d..k].trim_start_matches('0').to_string()
    };
    while k < b.len() && is_blank(b[k]) {
        k += 1;
    }
    let ks = k;
    while k < b.len() && b[k].is_ascii_alphabetic() {
        k += 1;
    }
    let word = line[ks..k].to_ascii_lowercase();
    let kw = if word.is_empty() {
        Kw::Number
    } else {
        match KEYWORDS.iter().find(|(w, _)| *w == word) {
            Some(&(_, kw)) => kw,
            None => {
                return Err(LineError::new(
                    ks..k,
                    format!("unknown o-word keyword `{}`: expected one of sub endsub call return if elseif else endif while endwhile do repeat endrepeat break continue", &line[ks..k]),
                    "unknown keyword",
                ))
            }
        }
    };
    Ok(Some(OLine {
        label,
        kw,
        rest: k,
        span: start..k,
    }))
}

pub(super) fn macro_line(line: &str) -> Option<(Macro, usize, usize)> {
    macro_line_at(line, after_line_number(line.as_bytes()))
}

/// [`macro_line`], with the index after the line number already known (`after_line_number`).
pub(super) fn macro_line_at(line: &str, i: usize) -> Option<(Macro, usize, usize)> {
    let b = line.as_bytes();
    let mut k = i;
    while k < b.len() && b[k].is_ascii_alphabetic() {
        k += 1;
    }
    if k - i < 2 {
        // A word letter and its number (`G1`): the common case, no keyword.
        return None;
    }
    let word = &line[i..k];
    let m = [
        ("IF", Macro::If),
        ("WHILE", Macro::While),
        ("END", Macro::End),
        ("GOTO", Macro::Goto),
    ]
    .into_iter()
    .find(|(w, _)| word.eq_ignore_ascii_case(w))?
    .1;
    Some((m, i, k))
}
