//! Phases 3 and 8: the modal state saved and restored (M70-M73), the program end (M2,
//! M30) and subprogram flow (Fanuc M98/M99, and the G65 macro call, which the block runs
//! before reading its words: its letters are arguments).

use std::collections::VecDeque;

use super::{Interp, Stop};
use crate::block::{integer, Block};
use crate::canon::Move;
use crate::lex::{LineError, LineResult, Word};

impl Interp {
    /// Phase 3: M70 saves the modal state, M71 forgets it, M72 restores it; M73 saves it
    /// for the subroutine's return. Only where the dialect reads them so (LinuxCNC; on Haas
    /// M73/M74 are the tool air blast).
    pub(super) fn save_and_restore(&mut self, b: &Block) -> LineResult<Stop> {
        let mut stop = Stop::None;
        if !self.dialect.table().modal_state_m70_m73 {
            return Ok(stop);
        }
        for &(code, w) in b.m.iter() {
            match code {
                70 => self.saved = Some(Box::new(self.save())),
                71 => self.saved = None,
                72 => match self.saved.clone() {
                    Some(s) => self.restore(&s),
                    None => {
                        return Err(LineError::new(
                            w.span(),
                            "M72 with no state saved: expected an M70 before it",
                            "nothing saved",
                        ))
                    }
                },
                73 => stop = Stop::SaveForReturn(Box::new(self.save())),
                _ => {}
            }
        }
        Ok(stop)
    }

    /// Phase 8: M2/M30 end the program (the compensated moves flushed), M98 calls a
    /// subprogram, M99 returns; otherwise `stop` (phase 3's).
    pub(super) fn program_flow(
        &mut self,
        b: &Block,
        queue: &mut VecDeque<Move>,
        stop: Stop,
    ) -> LineResult<Stop> {
        for &(code, w) in b.m.iter() {
            match code {
                2 | 30 => {
                    self.finish(queue);
                    return Ok(Stop::End);
                }
                98 => {
                    let p = b.get('P').ok_or_else(|| {
                        LineError::new(
                            w.span(),
                            "M98 without P: expected `M98 P<program number>`",
                            "no P",
                        )
                    })?;
                    if !self.dialect.table().macro_b {
                        return Err(LineError::new(
                            w.span(),
                            "M98 in a LinuxCNC program: expected `o<name> call`",
                            "Fanuc code",
                        )
                        .help("set dialect = \"fanuc\" for Fanuc programs"));
                    }
                    let mut program = p.value.round() as u64;
                    let mut repeats = b.get('L').map_or(1, |l| l.value.round() as u64);
                    let digits = p.number.trim_start_matches(['+', '-']).len();
                    if self.dialect.table().m98_repeats_in_p
                        && b.get('L').is_none()
                        && (digits > 4 || program > 9999)
                    {
                        // Fanuc `M98 Prrrrpppp`: the repeat count, then the 4-digit program
                        // number (0i-MD "Subprogram": `M98 P30100` runs O0100 three times).
                        repeats = (program / 10_000).max(1);
                        program %= 10_000;
                    }
                    return Ok(Stop::Call {
                        label: format!("{program}"),
                        repeats,
                        args: Vec::new(),
                        locals: false,
                        span: w.span(),
                    });
                }
                97 if self.dialect.table().local_subprogram_m97 => {
                    let p = b.get('P').ok_or_else(|| {
                        LineError::new(
                            w.span(),
                            "M97 without P: expected `M97 P<sequence number>` (a local subprogram at N<sequence number> of this program)",
                            "no P",
                        )
                    })?;
                    let n = integer(&p, b.line)?;
                    let repeats = b.get('L').map_or(1, |l| l.value.round() as u64);
                    return Ok(Stop::Call {
                        label: format!("N{n}"),
                        repeats,
                        args: Vec::new(),
                        locals: false,
                        span: w.span(),
                    });
                }
                99 => return Ok(Stop::Return { span: w.span() }),
                _ => {}
            }
        }
        Ok(stop)
    }

    /// The G65 word of a block, in a dialect with macro calls.
    pub(super) fn macro_call<'l>(&self, words: &[Word<'l>]) -> Option<Word<'l>> {
        if !self.dialect.table().macro_b {
            return None;
        }
        words
            .iter()
            .find(|w| w.letter == 'G' && w.value == 65.0)
            .copied()
    }

    /// Fanuc `G65 P<program> [L<count>] <arguments>`: a macro call with its own locals;
    /// argument specification I (A→#1, B→#2, C→#3, I→#4, J→#5, K→#6, D→#7, E→#8, F→#9,
    /// H→#11, M→#13, Q→#17, R→#18, S→#19, T→#20, U→#21, V→#22, W→#23, X→#24, Y→#25, Z→#26)
    /// and II (A B C, then up to ten I J K sets, #4-#33), mixed: a variable given twice
    /// takes the later word (Fanuc 0i operator's manual, "Custom macro": "Argument
    /// specification").
    pub(super) fn g65(&mut self, line: &str, words: &[Word], g65: Word) -> LineResult<Stop> {
        let mut args = vec![0.0; 33];
        let mut program = None;
        let mut repeats = 1;
        let (mut ijk_set, mut ijk_last) = (0, None);
        for w in words {
            let slot = match w.letter {
                'P' => {
                    program = Some(integer(w, line)?);
                    continue;
                }
                'L' => {
                    repeats = integer(w, line)?.max(1);
                    continue;
                }
                'N' => continue,
                'G' if w.span == g65.span => continue,
                'A' => 1,
                'B' => 2,
                'C' => 3,
                'I' | 'J' | 'K' => {
                    // Argument specification II: the n-th I J K set is #(4+3(n−1)) to
                    // #(6+3(n−1)); a letter not after the last one of its set starts the
                    // next set (`I1 J2 K3 I4`: #4 #5 #6 #7).
                    let at = (w.letter as u8 - b'I') as usize;
                    if ijk_last.is_some_and(|last| at <= last) {
                        ijk_set += 1;
                    }
                    ijk_last = Some(at);
                    if ijk_set >= 10 {
                        return Err(LineError::new(w.span(), format!("`{}` in a G65 block: an eleventh I J K set; expected at most ten (#4 to #33)", &line[w.span()]), "too many arguments"));
                    }
                    4 + 3 * ijk_set + at
                }
                'D' => 7,
                'E' => 8,
                'F' => 9,
                'H' => 11,
                'M' => 13,
                'Q' => 17,
                'R' => 18,
                'S' => 19,
                'T' => 20,
                'U' => 21,
                'V' => 22,
                'W' => 23,
                'X' => 24,
                'Y' => 25,
                'Z' => 26,
                _ => {
                    return Err(LineError::new(w.span(), format!("`{}` in a G65 block: expected P, L and arguments A-Z (not G, L, N, O, P)", &line[w.span()]), "not a G65 argument"));
                }
            };
            args[slot - 1] = w.value;
        }
        let Some(p) = program else {
            return Err(LineError::new(
                g65.span(),
                "G65 without P: expected `G65 P<program number>`",
                "no P",
            ));
        };
        Ok(Stop::Call {
            label: p.to_string(),
            repeats,
            args,
            locals: true,
            span: g65.span(),
        })
    }
}
