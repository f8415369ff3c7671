//! Fanuc and Haas `,R` / `,C` in the reader's stream (the geometry is crate::corner): the
//! word is taken out of its block, the block's G01 line or G02/G03 arc is held off the queue, and the next
//! block's first move decides the corner: the held line shortened, the chamfer or arc, and
//! that move from the tangent point go to the queue in order.

use std::ops::Range;

use crate::corner::Pending;
use crate::error::Error;
use crate::lex::{LineError, LineResult, Word, CORNER_CHAMFER, CORNER_ROUND};

use super::state::{Cursor, IsoReader};

/// A block's `,R` or `,C`: rounding (true) or chamfer, its size (program units), its span.
pub(super) struct CornerWord {
    round: bool,
    size: f64,
    span: Range<usize>,
}

impl IsoReader {
    /// Takes the `,R` / `,C` word out of `words` (None when the block has none).
    pub(super) fn corner_word(
        &self,
        line: &str,
        words: &mut Vec<Word>,
    ) -> LineResult<Option<CornerWord>> {
        let is_corner = |w: &Word| w.letter == CORNER_ROUND || w.letter == CORNER_CHAMFER;
        let Some(k) = words.iter().position(is_corner) else {
            return Ok(None);
        };
        let w = words.remove(k);
        let text = &line[w.span()];
        let err = |m: String| LineError::new(w.span(), m, "corner rounding or chamfer");
        if words.is_empty() {
            return Err(err(format!(
                "`{text}` alone: expected it after a G01 or G02/G03 move in the same block"
            )));
        }
        if let Some(other) = words.iter().find(|w| is_corner(w)) {
            return Err(LineError::new(
                other.span(),
                format!(
                    "`{text}` and `{}` in one block: expected one chamfer `,C` or corner rounding `,R`",
                    &line[other.span()]
                ),
                "second corner word",
            ));
        }
        if !self.dialect.table().macro_b {
            return Err(err(format!(
                "`{text}`: Fanuc/Haas corner rounding or chamfer in a {} program",
                self.dialect.name()
            ))
            .help("write the rounding as a G02/G03 arc, or the chamfer as a G01 move"));
        }
        if !(w.value >= 0.0) {
            return Err(err(format!(
                "`{text}`: expected a chamfer length or corner radius of zero or more"
            )));
        }
        if self.mirror_scale.scaling() {
            return Err(err(format!(
                "`{text}` under scaling (G51): not read; expected G50 before it"
            )));
        }
        if self.interp.glue_view().comp_on {
            return Err(err(format!(
                "`{text}` under cutter compensation (G41/G42): not read; expected G40 before it"
            ))
            .help("write the rounding as a G02/G03 arc, or the chamfer as a G01 move"));
        }
        Ok(Some(CornerWord {
            round: w.letter == CORNER_ROUND,
            size: w.value,
            span: w.span(),
        }))
    }

    /// After a block ran (its moves from `before` in the queue): joins a held line to the
    /// block's first move, and holds the block's line when it has a `,R` / `,C`.
    pub(super) fn corner_after(
        &mut self,
        line: &str,
        word: Option<CornerWord>,
        before: usize,
        here: Cursor,
    ) -> LineResult<()> {
        // The block's own moves, before a held line and its corner join them.
        let new = self.queue.len().saturating_sub(before);
        if let Some(p) = self.corner.take() {
            let Some(next) = self.queue.get(before) else {
                return Err(LineError::new(
                    0..line.len(),
                    format!(
                        "{}: the next block must move along a G01 line or a G02/G03 arc to round or chamfer to; this block does not move",
                        p.name()
                    ),
                    "no move",
                ));
            };
            let (a, b, c) = crate::corner::join(&p, next)
                .map_err(|m| LineError::new(0..line.len(), m, "the next move"))?;
            self.queue[before] = c;
            self.queue.insert(before, a);
            if let Some(b) = b {
                self.queue.insert(before + 1, b);
            }
        }
        let Some(w) = word else {
            return Ok(());
        };
        let name = &line[w.span.clone()];
        let err = |m: String| LineError::new(w.span.clone(), m, "corner rounding or chamfer");
        let view = self.interp.glue_view();
        if view.comp_on {
            return Err(err(format!(
                "`{name}` under cutter compensation (G41/G42): not read; expected G40 before it"
            )));
        }
        let last = self.queue.back().filter(|_| new > 0);
        match last {
            Some(m)
                if matches!(m.motion, crate::Motion::Linear | crate::Motion::Arc { .. })
                    && new == 1 => {}
            _ => {
                return Err(err(format!(
                    "`{name}` in a block without a G01 or G02/G03 move: expected a line or an arc to round or chamfer to the next move"
                )))
            }
        }
        if w.size == 0.0 {
            return Ok(());
        }
        let held = self.queue.pop_back().ok_or_else(|| err(String::new()))?;
        self.corner = Some(Pending {
            round: w.round,
            size_mm: w.size * self.interp.scale(),
            plane: view.plane,
            held,
            word: name.to_string(),
            at: here,
            span: w.span,
            text: line.to_string(),
        });
        Ok(())
    }

    /// The program ended with a line still held: the error at its `,R` / `,C`.
    pub(super) fn corner_unfinished(&mut self) -> Option<Error> {
        let p = self.corner.take()?;
        let err = LineError::new(
            p.span.clone(),
            format!(
                "{}: the program ends after this move; expected a G01 line or G02/G03 arc in the next block to round or chamfer to",
                p.name()
            ),
            "no next move",
        );
        Some(self.error_at(p.at, err, &p.text))
    }
}
