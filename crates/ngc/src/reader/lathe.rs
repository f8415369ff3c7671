//! The Fanuc family's lathe stock-removal cycles as blocks of a program: G71/G72 P Q (rough
//! about the finishing shape in blocks N`P` to N`Q`, then go on after N`Q`), their two-block
//! format's first block (`G71 U R`, `G72 W R`: depth and retract), and G70 P Q (run blocks
//! N`P` to N`Q` as they are, then back to the start point). The moves are the interpreter's
//! (`interp/stock_removal.rs`); here the profile blocks are found and read.
//!
//! The profile is read by a copy of the interpreter from the cycle's start point, so that
//! roughing leaves the modal state as the cycle block left it; G70 reads it with the
//! interpreter itself, as the control executes those blocks.

use std::collections::VecDeque;

use super::state::{Cursor, IsoReader};
use crate::axis::Axis;
use crate::interp::{Interp, StockRemoval};
use crate::lex::{lex_with, Lexed, LineError, LineResult, Word};

/// What a lathe cycle block asks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum LatheCycle {
    /// `G71 U R` / `G72 W R`: the depth and retract of the next rough cycle.
    Depth { facing: bool },
    /// `G71 P Q` / `G72 P Q`: rough about blocks P to Q.
    Rough { facing: bool },
    /// `G70 P Q`: finish along blocks P to Q.
    Finish,
}

/// Retract e when neither the block nor the machine gives it, mm: LinuxCNC's peck
/// clearance (the Fanuc parameter 5133 and Haas Setting 73 are the builder's).
const DEFAULT_RETRACT_MM: f64 = crate::options::PECK_CLEARANCE_MM;

fn word(words: &[Word], letter: char) -> Option<f64> {
    words.iter().find(|w| w.letter == letter).map(|w| w.value)
}

impl LatheCycle {
    /// The lathe cycle of a block: G70/G71/G72 with P and Q, or G71 with U and R / G72
    /// with W and R (and no P); `None` for every other block (Haas mill G70/G71 bolt
    /// patterns have neither).
    pub(super) fn of(words: &[Word]) -> Option<LatheCycle> {
        let g = words
            .iter()
            .find(|w| w.letter == 'G' && matches!(w.number.as_bytes(), [b'7', b'0'..=b'2']))?;
        let has = |l: char| words.iter().any(|w| w.letter == l);
        let facing = g.number == "72";
        match (g.number, has('P') && has('Q')) {
            ("70", true) => Some(LatheCycle::Finish),
            (_, true) => Some(LatheCycle::Rough { facing }),
            ("71", false) if has('U') && has('R') => Some(LatheCycle::Depth { facing }),
            ("72", false) if has('W') && has('R') => Some(LatheCycle::Depth { facing }),
            _ => None,
        }
    }
}

impl IsoReader {
    /// Runs a lathe cycle block at `here`.
    pub(super) fn lathe_cycle(
        &mut self,
        cycle: LatheCycle,
        line: &str,
        words: &[Word],
        here: Cursor,
    ) -> LineResult<()> {
        let span = words
            .iter()
            .find(|w| w.letter == 'G')
            .map(|w| w.span())
            .unwrap_or(0..line.len());
        let scale = self.interp.scale();
        if !self.lathe.warned {
            self.lathe.warned = true;
            self.notices.push(crate::notice::Notice {
                path: self.programs[here.file].path.clone(),
                line: here.line,
                message: if self.interp.is_lathe() {
                    "a lathe cycle: X is read as written (a diameter moves the machine's X by \
                     the diameter, not the radius); G98/G99 are the lathe's feed modes \
                     (docs/gcode.md, \"Lathe stock removal\")"
                        .to_string()
                } else {
                    format!(
                        "a lathe cycle on a machine with a Y axis: this program is read with \
                         the {} mill's codes, so X is read as written (not a diameter), \
                         G98/G99 as the mill's return levels and F per minute unless G95; a \
                         machine file with X and Z only reads them as a lathe's \
                         (docs/gcode.md, \"Lathe stock removal\")",
                        self.dialect.name()
                    )
                },
                warning: true,
            });
        }
        if let LatheCycle::Depth { facing } = cycle {
            let depth = word(words, if facing { 'W' } else { 'U' }).unwrap_or(0.0);
            self.lathe.depth_mm = Some(depth * scale);
            self.lathe.retract_mm = word(words, 'R').map(|r| r * scale);
            return Ok(());
        }
        // The block's own F, S, T and M words take effect first (the roughing feed).
        let own: Vec<Word> = words
            .iter()
            .filter(|w| matches!(w.letter, 'F' | 'S' | 'T' | 'M'))
            .copied()
            .collect();
        if !own.is_empty() {
            let path = self.programs[here.file].path.clone();
            let mut ignored = VecDeque::new();
            self.interp.block(
                line,
                &own,
                here.line,
                &mut ignored,
                &mut self.notices,
                &path,
            )?;
            self.queue.extend(ignored);
        }
        let (ns, nf) = (
            word(words, 'P').unwrap_or(0.0),
            word(words, 'Q').unwrap_or(0.0),
        );
        let lines = self.profile_lines(here, ns, nf, span.clone())?;
        let start = self.interp.position();
        match cycle {
            LatheCycle::Rough { facing } => {
                let depth = word(words, 'D').map(|d| d * scale).or(self.lathe.depth_mm);
                let Some(depth_mm) = depth.filter(|d| *d > 0.0) else {
                    return Err(LineError::new(span, format!("G7{} without a depth of cut: expected D on the block or a `G7{} {} R` block before it (the depth is radial, > 0)", 1 + u8::from(facing), 1 + u8::from(facing), if facing { "W" } else { "U" }), "no depth"));
                };
                let cycle = StockRemoval {
                    facing,
                    depth_mm,
                    retract_mm: self.lathe.retract_mm.unwrap_or(DEFAULT_RETRACT_MM),
                    allowance_mm: [
                        word(words, 'U').unwrap_or(0.0) * scale,
                        word(words, 'W').unwrap_or(0.0) * scale,
                    ],
                };
                let mut probe = self.interp.clone();
                let mut profile = VecDeque::new();
                let path = self.programs[here.file].path.clone();
                run_lines(&mut probe, &mut self.notices, &path, &lines, &mut profile)?;
                let profile: Vec<_> = profile.into();
                self.interp
                    .stock_removal(&cycle, &profile, here.line, &mut self.queue, span)?;
                self.lathe.facing = facing;
                // On after the profile's last block.
                self.cursor = lines.last().map(|l| l.2).unwrap_or(self.cursor);
            }
            LatheCycle::Finish => {
                let path = self.programs[here.file].path.clone();
                run_lines(
                    &mut self.interp,
                    &mut self.notices,
                    &path,
                    &lines,
                    &mut self.queue,
                )?;
                let across = if self.lathe.facing { Axis::Z } else { Axis::X };
                self.interp
                    .return_to_start(start, across, here.line, &mut self.queue);
            }
            LatheCycle::Depth { .. } => unreachable!("handled above"),
        }
        Ok(())
    }

    /// The lines of blocks N`ns` to N`nf` of the current program: text, cursor, and the
    /// cursor after it.
    fn profile_lines(
        &mut self,
        here: Cursor,
        ns: f64,
        nf: f64,
        span: std::ops::Range<usize>,
    ) -> LineResult<Vec<(String, Cursor, Cursor)>> {
        let name = |n: f64| format!("{}", n.round() as i64);
        let Some(mut c) = self.sequence_line(here.file, &name(ns)) else {
            return Err(LineError::new(
                span,
                format!(
                    "no block N{} for P{}: expected the finishing shape's first block",
                    name(ns),
                    name(ns)
                ),
                "unknown P",
            ));
        };
        let mut lines = Vec::new();
        while let Some((text, next)) = self.line_at(c) {
            let text = text.to_string();
            let last = sequence_number(&text) == Some(nf.round() as i64);
            lines.push((text, c, next));
            if last {
                return Ok(lines);
            }
            if lines.len() > 10_000 {
                break;
            }
            c = next;
        }
        Err(LineError::new(
            span,
            format!(
                "no block N{} for Q{} after N{}: expected the finishing shape's last block",
                name(nf),
                name(nf),
                name(ns)
            ),
            "unknown Q",
        ))
    }
}

/// Runs `lines` (plain blocks) through `interp`, queueing its moves in `queue`.
fn run_lines(
    interp: &mut Interp,
    notices: &mut Vec<crate::notice::Notice>,
    path: &std::path::Path,
    lines: &[(String, Cursor, Cursor)],
    queue: &mut VecDeque<Move>,
) -> LineResult<()> {
    {
        for (text, at, _) in lines {
            let lexed = lex_with(text, &interp.params, true, Vec::new())
                .map_err(|e| at_line(e, at.line))?;
            if let Lexed::Words { words, assigns } = lexed {
                if !assigns.is_empty() {
                    return Err(LineError::new(0..text.len(), format!("line {}: a parameter assignment in a lathe cycle's shape: expected motion blocks only", at.line), "assignment in a shape"));
                }
                interp
                    .block(text, &words, at.line, queue, notices, path)
                    .map_err(|e| at_line(e, at.line))?;
            }
        }
        Ok(())
    }
}

use crate::canon::Move;

/// An error in a shape block, reported at the cycle block with the shape's line named.
fn at_line(e: LineError, line: usize) -> LineError {
    let message = format!("in the shape block at line {line}: {}", e.message);
    LineError::new(0..0, message, "in a lathe shape")
}

/// The sequence number N n a line starts with.
fn sequence_number(line: &str) -> Option<i64> {
    let t = line.trim_start();
    let rest = t.strip_prefix(['N', 'n'])?;
    let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    digits.parse().ok()
}
