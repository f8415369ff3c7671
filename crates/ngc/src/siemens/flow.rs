//! Program flow (Job planning, "Program sequence control"): `IF`/`ELSE`/`ENDIF`,
//! `WHILE`/`ENDWHILE`, `FOR`/`ENDFOR`, `REPEAT`/`UNTIL`, `LOOP`/`ENDLOOP`, and the jumps
//! `GOTOF`/`GOTOB`/`GOTO`/`GOTOC` to a label (`NAME:`) or block number (`N100`).
//!
//! A structure is entered by evaluating its head; a false head skips forward to its
//! partner, counting the structures nested on the way. Loops go back by byte offset; the
//! blocks they run again count against the block budget (crate `budget`).

use super::expr::Scan;
use super::state::Structure;
use super::{Reader, MAX_STRUCTURES};
use crate::lex::{LineError, LineResult};

/// What opens or closes a structure, as the first statement of a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mark {
    Open,
    Else,
    Close,
    Other,
}

/// The first statement of an upper-cased line after `/`, its block number and its label:
/// its keyword and where the keyword starts.
pub(super) fn head(line: &str) -> (Mark, &str, usize) {
    let mut sc = Scan::new(line);
    skip_number_and_label(&mut sc);
    let Some((kw, at)) = sc.ident() else {
        return (Mark::Other, "", sc.at);
    };
    let mark = match kw {
        // `IF cond GOTOF label` is a jump, not a structure.
        "IF" => {
            if line[sc.at..].contains("GOTO") {
                Mark::Other
            } else {
                Mark::Open
            }
        }
        // `REPEAT label P=n` repeats a section (repeat.rs): it opens nothing.
        "REPEAT" => {
            if sc.done() {
                Mark::Open
            } else {
                Mark::Other
            }
        }
        "WHILE" | "FOR" | "LOOP" => Mark::Open,
        "ELSE" => Mark::Else,
        "ENDIF" | "ENDWHILE" | "ENDFOR" | "UNTIL" | "ENDLOOP" => Mark::Close,
        _ => Mark::Other,
    };
    (mark, kw, at)
}

/// Skips `/`, `N123` or `:123`, and a label `NAME:`.
pub(super) fn skip_number_and_label(sc: &mut Scan) {
    sc.eat(b'/');
    let save = sc.at;
    if let Some((w, _)) = sc.ident() {
        let n = w.strip_prefix('N');
        if !n.is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit())) {
            sc.at = save;
        }
    } else if sc.eat(b':') {
        sc.number();
    }
    let save = sc.at;
    if sc.ident().is_some() && sc.eat(b':') {
        return;
    }
    sc.at = save;
}

/// The block number (`N100`) and label (`NAME`) of an upper-cased line.
pub(super) fn targets(line: &str) -> (Option<&str>, Option<&str>) {
    let mut sc = Scan::new(line);
    sc.eat(b'/');
    let save = sc.at;
    let mut number = None;
    if let Some((w, _)) = sc.ident() {
        if w.strip_prefix('N')
            .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
        {
            number = Some(w);
        } else {
            sc.at = save;
        }
    }
    let label = match sc.ident() {
        Some((w, _)) if sc.eat(b':') => Some(w),
        _ => None,
    };
    (number, label)
}

impl Reader {
    /// Opens a structure, bounded to [`MAX_STRUCTURES`].
    pub(super) fn open(&mut self, s: Structure, span: std::ops::Range<usize>) -> LineResult<()> {
        let level = self.level();
        if level.structures.len() == MAX_STRUCTURES {
            return Err(LineError::new(
                span,
                format!("control structures nested deeper than {MAX_STRUCTURES}"),
                "too deep",
            ));
        }
        level.structures.push(s);
        let (offset, line) = self.line_start;
        self.level().opened.push((offset, line, span));
        Ok(())
    }

    /// Opens `s` again with the opening line it had (a loop going round).
    pub(super) fn reopen(&mut self, s: Structure, head: (usize, usize, std::ops::Range<usize>)) {
        let level = self.level();
        level.structures.push(s);
        level.opened.push(head);
    }

    /// True when a closing keyword at depth 0 follows the structure opened on the line at
    /// byte `offset` of the current level.
    pub(super) fn closed_after(&mut self, offset: usize) -> bool {
        let mut depth = 0usize;
        let mut buf = String::new();
        let level = self.level();
        let mut at = offset;
        let mut first = true;
        loop {
            let n = level.source.line(at, &mut buf).unwrap_or(0);
            if n == 0 {
                return false;
            }
            at += n;
            if std::mem::take(&mut first) {
                continue;
            }
            buf.make_ascii_uppercase();
            match head(&buf).0 {
                Mark::Open => depth += 1,
                Mark::Close if depth == 0 => return true,
                Mark::Close => depth -= 1,
                _ => {}
            }
        }
    }

    /// Skips forward past the partner of the structure just refused: the first `ELSE`
    /// (when `to_else`) or closing keyword at this depth. Returns the keyword found.
    pub(super) fn skip(
        &mut self,
        to_else: bool,
        span: std::ops::Range<usize>,
    ) -> LineResult<String> {
        let mut depth = 0usize;
        let mut buf = String::new();
        loop {
            let level = self.level();
            let n = level.source.line(level.offset, &mut buf).unwrap_or(0);
            if n == 0 {
                return Err(LineError::new(span, "no closing keyword (ENDIF, ENDWHILE, ENDFOR, UNTIL, ENDLOOP) for this structure before the end of the program", "unclosed structure"));
            }
            level.offset += n;
            level.line += 1;
            buf.make_ascii_uppercase();
            let (mark, kw, _) = head(&buf);
            match mark {
                Mark::Open => depth += 1,
                Mark::Else if depth == 0 && to_else => return Ok(kw.to_string()),
                Mark::Close if depth == 0 => return Ok(kw.to_string()),
                Mark::Close => depth -= 1,
                _ => {}
            }
        }
    }

    /// A backward jump from the current line: the construct a spent budget names (the
    /// blocks themselves are counted as they are read, in `step`).
    pub(super) fn backward(&mut self, span: std::ops::Range<usize>) {
        let (offset, line) = self.line_start;
        self.repeating = Some((self.levels.len() - 1, (offset, line, span)));
    }

    /// `GOTOF`/`GOTOB`/`GOTO`/`GOTOC` to `target` (a label or `N` number). `Ok(false)`:
    /// not found, for `GOTOC` to go on.
    pub(super) fn jump(
        &mut self,
        kind: &str,
        target: &str,
        span: std::ops::Range<usize>,
    ) -> LineResult<bool> {
        let forward = kind != "GOTOB";
        let backward = kind != "GOTOF";
        if forward {
            if let Some(at) = self.find(target, None) {
                (self.level().offset, self.level().line) = at;
                return Ok(true);
            }
        }
        if backward {
            let here = self.level().offset;
            if let Some(at) = self.find(target, Some(here)) {
                self.backward(span.clone());
                (self.level().offset, self.level().line) = at;
                return Ok(true);
            }
        }
        if kind == "GOTOC" {
            return Ok(false);
        }
        Err(LineError::new(
            span,
            format!(
                "{kind} {target}: no label `{target}:` or block `{target}` {} in this program",
                if forward && backward {
                    "anywhere"
                } else if forward {
                    "further on"
                } else {
                    "earlier"
                }
            ),
            "unknown jump target",
        ))
    }

    /// The place (offset, line) of the line carrying `target`: the first after the current
    /// line (`before` None), or the last before byte `before`.
    fn find(&mut self, target: &str, before: Option<usize>) -> Option<(usize, usize)> {
        let level = self.levels.last()?;
        let (from, line) = match before {
            None => (level.offset, level.line),
            Some(_) => (0, 1),
        };
        self.label_line(target, from, line, before, before.is_some())
            .map(|(offset, line, _)| (offset, line))
    }

    /// `CASE expr OF c1 GOTOF l1 c2 GOTOB l2 … DEFAULT GOTOF l` (Job planning, "Program
    /// branch (CASE ... OF ... DEFAULT ...)"): jumps to the label of the first constant
    /// equal to the expression, else to DEFAULT's; with neither, the next block runs.
    pub(super) fn case_statement(&mut self, sc: &mut Scan, at: usize) -> LineResult<()> {
        let v = super::expr::expr(sc, &self.vars)?;
        if !sc.keyword("OF") {
            return Err(sc.err(
                at,
                "expected `CASE expression OF constant GOTOF label …`",
                "CASE",
            ));
        }
        let mut chosen = None;
        while !sc.done() {
            let matches = if sc.keyword("DEFAULT") {
                true
            } else {
                let neg = sc.eat(b'-');
                let Some((_, c)) = sc.number() else {
                    return Err(sc.err(sc.at, "expected a numeric constant, or DEFAULT, in CASE (a string constant is not supported)", "CASE"));
                };
                (if neg { -c } else { c }) == v
            };
            let Some((kind, k_at)) = sc
                .ident()
                .filter(|(k, _)| matches!(*k, "GOTOF" | "GOTOB" | "GOTO" | "GOTOC"))
            else {
                return Err(sc.err(
                    sc.at,
                    "expected GOTOF or GOTOB and a label after a CASE constant",
                    "CASE",
                ));
            };
            let Some((target, t_at)) = sc.ident() else {
                return Err(sc.err(k_at, format!("{kind} without a target"), "no target"));
            };
            if matches && chosen.is_none() {
                chosen = Some((kind.to_string(), target.to_string(), t_at..sc.at));
            }
        }
        if let Some((kind, target, span)) = chosen {
            self.jump(&kind, &target, span)?;
        }
        Ok(())
    }
}
