//! What the ISO family's reader does before the first block: a program in another
//! control's language (Siemens Sinumerik's `TRAORI`, `CYCLE800`) is refused before any move,
//! and the Fanuc family's tape leader before the first `%` is skipped.

use std::io::Read;
use std::path::Path;
use std::rc::Rc;

use crate::error::Error;
use crate::lex::LineError;
use crate::source::{Source, FILE_BUFFER_BYTES};

use super::state::{Cursor, IsoReader};

impl IsoReader {
    /// Refuses a program written in another control's language: Siemens Sinumerik
    /// (`TRAORI`, `CYCLE800`), before any move (a Heidenhain program never gets here: it is
    /// read by its own front end, chosen in `reader::read_with`). A program of the `siemens`
    /// dialect is read by the Sinumerik front end instead.
    pub(super) fn foreign_language(&mut self) -> Option<Error> {
        // A cheap screen first, so that a streamed file is read whole only when it fails.
        let suspect = match &self.programs[0].source {
            Source::Text(text) => may_be_foreign(text.as_bytes()),
            Source::File(_) => file_may_be_foreign(&self.programs[0].path).unwrap_or(false),
        };
        if !suspect {
            return None;
        }
        let text: Rc<str> = match &self.programs[0].source {
            Source::Text(text) => Rc::clone(text),
            Source::File(_) => {
                let bytes = std::fs::read(&self.programs[0].path).ok()?;
                String::from_utf8_lossy(&bytes).into()
            }
        };
        let text = &text;
        // The first Siemens word in the file.
        let first = SIEMENS_TOKENS
            .iter()
            .filter_map(|&t| text.find(t).map(|k| (k, t)))
            .min();
        if let Some((k, token)) = first {
            let line_start = text[..k].rfind('\n').map_or(0, |n| n + 1);
            let line_no = text[..line_start].matches('\n').count() + 1;
            let c = Cursor {
                file: 0,
                offset: line_start,
                line: line_no,
            };
            let col = k - line_start;
            return Some(self.syntax_in(c.file, text, c.offset, LineError::new(col..col + token.len(), format!("`{token}` is Siemens Sinumerik: this program is in the Siemens language, expected G-code in the RS274/NGC, Fanuc or Haas language"), "Siemens Sinumerik").help("set dialect = \"siemens\" in the scenario's [reader] to read it with the Sinumerik front end")));
        }
        None
    }

    /// Fanuc family: text before the program's first `%` line (within its first 64 lines)
    /// is the tape leader, which the control skips (a CAM system's listing header).
    pub(super) fn skip_leader(&mut self) {
        let mut c = self.cursor;
        let mut text_before = false;
        // A first line that starts like G-code (or `%`, a comment, a block delete) has no
        // leader before it: nothing is read ahead.
        while let Some((line, next)) = self.line_at(c) {
            let t = line.trim_start_matches(['\u{feff}', ' ', '\t']);
            if let Some(first) = t.chars().next() {
                if "%OoNnGgMmTtXxYyZzFfSs(;#/".contains(first) {
                    return;
                }
                break;
            }
            c = next;
        }
        for _ in 0..64 {
            let Some((line, next)) = self.line_at(c) else {
                return;
            };
            let t = line.trim();
            if t == "%" {
                if text_before {
                    self.cursor = c;
                }
                return;
            }
            text_before |= !t.is_empty();
            c = next;
        }
    }
}

/// Siemens Sinumerik words [`foreign_language`](IsoReader::foreign_language) refuses.
pub(super) const SIEMENS_TOKENS: [&str; 5] = ["TRAORI", "traori", "Traori", "CYCLE800", "cycle800"];

/// True when `bytes` may hold a Siemens token. Every token begins with `tra` or `cyc` in
/// one case or the other, so the screen folds each run of 64 start positions, branch free
/// (vectorised), for those three letters (case folded: `b | 0x20`), and looks closer only
/// where one begins. Letters alone (a `T` or `C` word, a comment) do not stop it: a
/// five-axis program has a `C` on nearly every line.
///
/// Where the CPU has AVX2 the same fold runs 32 positions to an instruction instead of 16
/// (docs/performance.md "Session 27"): the screen reads the whole file once per reader.
pub(super) fn may_be_foreign(bytes: &[u8]) -> bool {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, just tested.
        return unsafe { may_be_foreign_avx2(bytes) };
    }
    screen(bytes)
}

/// [`screen`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn may_be_foreign_avx2(bytes: &[u8]) -> bool {
    screen(bytes)
}

/// [`may_be_foreign`]'s fold, for any CPU.
#[inline(always)]
fn screen(bytes: &[u8]) -> bool {
    const SHORTEST: usize = 6;
    if bytes.len() < SHORTEST {
        return false;
    }
    // Start positions `0..starts` have the two bytes after them.
    let starts = bytes.len() - 2;
    let mut k = 0;
    while k < starts {
        let end = (k + 64).min(starts);
        let (first, second, third) = (
            &bytes[k..end],
            &bytes[k + 1..end + 1],
            &bytes[k + 2..end + 2],
        );
        let hit = first
            .iter()
            .zip(second)
            .zip(third)
            .fold(false, |hit, ((&x, &y), &z)| {
                let (x, y, z) = (x | 0x20, y | 0x20, z | 0x20);
                hit | ((x == b't') & (y == b'r') & (z == b'a'))
                    | ((x == b'c') & (y == b'y') & (z == b'c'))
            });
        if hit
            && (k..end).any(|i| {
                SIEMENS_TOKENS
                    .iter()
                    .any(|t| bytes[i..].starts_with(t.as_bytes()))
            })
        {
            return true;
        }
        k = end;
    }
    false
}

/// [`may_be_foreign`] over a file, read in fixed chunks that overlap by a token's length.
pub(super) fn file_may_be_foreign(path: &Path) -> std::io::Result<bool> {
    const KEEP: usize = 7;
    let mut file = std::fs::File::open(path)?;
    let mut buf = vec![0u8; FILE_BUFFER_BYTES + KEEP];
    let mut kept = 0;
    loop {
        let n = file.read(&mut buf[kept..])?;
        if n == 0 {
            return Ok(false);
        }
        let end = kept + n;
        if may_be_foreign(&buf[..end]) {
            return Ok(true);
        }
        let keep = KEEP.min(end);
        buf.copy_within(end - keep..end, 0);
        kept = keep;
    }
}

#[cfg(test)]
mod tests {
    use super::{may_be_foreign, screen, SIEMENS_TOKENS};

    /// The screen on every CPU ([`screen`]) and on this one ([`may_be_foreign`]).
    fn both(bytes: &[u8]) -> bool {
        let (plain, here) = (screen(bytes), may_be_foreign(bytes));
        assert_eq!(plain, here, "{:?}", String::from_utf8_lossy(bytes));
        here
    }

    /// Every Siemens token at every offset (across the 64-position runs) of five-axis lines
    /// is found; the same lines without one, full of `T`, `C`, `tra`- and `cyc`-words that
    /// are not tokens, are not.
    #[test]
    fn the_siemens_screen_finds_every_token_at_every_offset_and_nothing_else() {
        let clean = "G01 X0.0072 C-90.0061 F559.386 (THETA 0.010 CENTRE TRACE CYCLE 80)\nT1 M6\n";
        let clean = clean.repeat(3);
        assert!(!both(clean.as_bytes()));
        for token in SIEMENS_TOKENS {
            for at in 0..=clean.len() {
                let mut text = clean.clone();
                text.insert_str(at, token);
                assert!(both(text.as_bytes()), "{token} at {at}");
                // A token cut short is not one.
                let mut text = clean.clone();
                text.insert_str(at, &token[..token.len() - 1]);
                text.insert(at + token.len() - 1, ' ');
                assert!(!both(text.as_bytes()), "{token} cut short at {at}");
            }
        }
        for short in ["", "T", "TRAOR", "cycle8"] {
            assert!(!both(short.as_bytes()), "{short:?}");
        }
    }
}
