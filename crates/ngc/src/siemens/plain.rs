//! Blocks of plain ISO words (`N10 G1 X10.5 Y-2 F300`) that mean the same to the
//! interpreter as written: handed to it unchanged, without the Sinumerik parse. Most
//! blocks of a CAM program are such blocks (docs/performance.md).

use super::Reader;
use crate::lex::LineResult;

/// Letters a plain block may hold: each means in Fanuc's codes what it means here.
const PLAIN_LETTERS: &[u8] = b"NGXYZABCIJKFS";
/// Most G codes a plain block holds.
const MAX_CODES: usize = 8;

impl Reader {
    /// Runs `line` as written when it is a plain block and the modal state needs no
    /// translation; `None` otherwise (nothing done).
    pub(super) fn plain(&mut self, line: &str, line_no: usize) -> Option<LineResult<bool>> {
        if !self.frame.is_identity()
            || !self.macros.is_empty()
            || self.feed_in_mm
            || self.modal_call.is_some()
            || self.held.is_some()
            || self.rounding_modal.is_some()
            || self.absolute != self.interp_absolute
            || self.motion != self.interp_motion
            || self.normal != self.interp_normal
        {
            return None;
        }
        let (codes, n) = plain_codes(line.as_bytes())?;
        let (mut motion, mut absolute, mut normal) = (self.motion, self.absolute, self.normal);
        for &g in &codes[..n] {
            match g {
                0..=3 => motion = g as u8,
                90 | 91 => absolute = g == 90,
                17..=19 => normal = (19 - g) as usize,
                40..=42 | 94 | 95 => {}
                // A settable frame the program wrote is selected by `words`.
                54..=57 if self.settable.iter().all(Option::is_none) => {}
                _ => return None,
            }
        }
        (self.motion, self.interp_motion) = (motion, motion);
        (self.absolute, self.interp_absolute) = (absolute, absolute);
        (self.normal, self.interp_normal) = (normal, normal);
        Some(self.run_text(line, line_no).map(|_| true))
    }
}

/// The G codes of `line` when it holds only words of [`PLAIN_LETTERS`] with plain numbers
/// (G and N whole), blanks and a trailing `;` comment.
fn plain_codes(line: &[u8]) -> Option<([u16; MAX_CODES], usize)> {
    let mut codes = [0u16; MAX_CODES];
    let mut n = 0;
    let mut i = 0;
    while i < line.len() {
        let c = line[i].to_ascii_uppercase();
        if c == b' ' || c == b'\t' {
            i += 1;
            continue;
        }
        if c == b';' {
            break;
        }
        if !PLAIN_LETTERS.contains(&c) {
            return None;
        }
        i += 1;
        let whole = c == b'G' || c == b'N';
        if !whole && matches!(line.get(i), Some(b'-' | b'+')) {
            i += 1;
        }
        let start = i;
        let mut value: u32 = 0;
        while let Some(&d) = line.get(i) {
            if d.is_ascii_digit() {
                value = value.saturating_mul(10).saturating_add((d - b'0') as u32);
            } else if d != b'.' || whole {
                break;
            }
            i += 1;
        }
        if i == start || !line[start..i].iter().any(u8::is_ascii_digit) {
            return None;
        }
        if c == b'G' {
            if n == MAX_CODES || value > 999 {
                return None;
            }
            codes[n] = value as u16;
            n += 1;
        }
    }
    Some((codes, n))
}
