//! Program section repeats (Job planning, "Program section repetition"):
//!
//! - `REPEATB label P=n`: the block carrying `label` (searched back first, then on) runs
//!   n times;
//! - `REPEAT label P=n`: the section from `label` (before the `REPEAT`) to the line before
//!   the `REPEAT`, or to the first `ENDLABEL:` line in between, runs n times;
//! - `REPEAT start end P=n`: the section from the line of `start` to the line of `end`,
//!   both included, runs n times.
//!
//! `P` defaults to 1. After the last pass the program goes on after the `REPEAT` line. A
//! section is a byte range `[start, end)` of its program level's text: the reader reaching
//! `end` ends a pass. Passes nest (a section may hold another `REPEAT`) at most
//! [`MAX_STRUCTURES`] deep, and every pass counts its blocks against `max_blocks`.

use std::ops::Range;

use super::expr::{expr, Scan};
use super::flow::targets;
use super::state::Section;
use super::{Reader, MAX_STRUCTURES};
use crate::lex::{LineError, LineResult};

/// A line of a level's text that carries a label: offset, 1-based number, length in bytes.
type Found = (usize, usize, usize);

impl Reader {
    /// `REPEAT`/`REPEATB` (`kw`, at byte `at`) with a start label: the scanner is after
    /// the keyword.
    pub(super) fn section_repeat(&mut self, kw: &str, sc: &mut Scan, at: usize) -> LineResult<()> {
        let Some((start_label, s_at)) = sc.ident() else {
            return Err(sc.err(
                at,
                format!("{kw} without a label: expected `{kw} label P=n`"),
                "no label",
            ));
        };
        let start_span = s_at..sc.at;
        let start_label = start_label.to_string();
        let mut end_label: Option<(String, Range<usize>)> = None;
        let mut passes = 1.0;
        while !sc.done() {
            let Some((w, w_at)) = sc.ident() else {
                return Err(sc.err(
                    sc.at,
                    format!("expected `P=count` or an end label after `{kw} {start_label}`"),
                    "unexpected",
                ));
            };
            if w == "P" && sc.eat(b'=') {
                passes = expr(sc, &self.vars)?;
            } else if kw == "REPEAT" && end_label.is_none() && w != "P" {
                end_label = Some((w.to_string(), w_at..sc.at));
            } else {
                return Err(sc.err(
                    w_at,
                    format!("`{w}`: expected `P=count` after `{kw} {start_label}`"),
                    "unexpected",
                ));
            }
        }
        let span = at..sc.at;
        if !(passes.is_finite() && passes >= 0.0 && passes.fract() == 0.0) {
            return Err(LineError::new(
                span,
                format!("{kw} P={passes}: expected a whole number of passes, 0 or more"),
                "bad repeat count",
            ));
        }
        let passes = passes as u64;
        let (repeat_at, repeat_line) = self.line_start;
        let here = self.level().offset;
        // The start label: before the REPEAT line, or (REPEATB, or with an end label) after.
        let mut start = self.label_line(&start_label, 0, 1, Some(repeat_at), true);
        if start.is_none() && (kw == "REPEATB" || end_label.is_some()) {
            start = self.label_line(&start_label, here, repeat_line + 1, None, false);
        }
        let Some(start) = start else {
            return Err(LineError::new(start_span, format!("{kw} {start_label}: no label `{start_label}:` or block `{start_label}` {} in this program", if kw == "REPEAT" && end_label.is_none() { "before this line" } else { "anywhere" }), "unknown label"));
        };
        let end = match (&end_label, kw) {
            (_, "REPEATB") => start.0 + start.2,
            (Some((label, end_span)), _) => {
                let found = self.label_line(label, start.0, start.1, None, false);
                let Some(found) = found else {
                    return Err(LineError::new(end_span.clone(), format!("REPEAT {start_label} {label}: no label `{label}:` at or after `{start_label}`"), "unknown label"));
                };
                found.0 + found.2
            }
            (None, _) => {
                match self.label_line("ENDLABEL", start.0, start.1, Some(repeat_at), false) {
                    Some(found) => found.0 + found.2,
                    None => repeat_at,
                }
            }
        };
        if passes == 0 || end <= start.0 {
            return Ok(());
        }
        // Every pass runs at least one line of the section.
        self.budget
            .check_passes(passes, &format!("this {kw}"), span.clone())?;
        let level = self.levels.last_mut().expect("the main program level");
        if level.sections.len() == MAX_STRUCTURES {
            return Err(LineError::new(
                span,
                format!("section repeats nested deeper than {MAX_STRUCTURES}"),
                "too deep",
            ));
        }
        let back = (level.offset, level.line);
        let site = (repeat_at, repeat_line, span);
        level.sections.push(Section {
            start: (start.0, start.1),
            end,
            left: passes - 1,
            back,
            site: site.clone(),
        });
        (level.offset, level.line) = (start.0, start.1);
        self.repeating = Some((self.levels.len() - 1, site));
        Ok(())
    }

    /// At the end of a pass of the innermost section of the current level: the next pass,
    /// or on after its `REPEAT` line (and so on outwards, where sections end together).
    #[inline]
    pub(super) fn section_end(&mut self) {
        let depth = self.levels.len() - 1;
        let level = self.levels.last_mut().expect("the main program level");
        while let Some(section) = level.sections.last_mut() {
            if level.offset != section.end {
                return;
            }
            if section.left > 0 {
                section.left -= 1;
                (level.offset, level.line) = section.start;
                self.repeating = Some((depth, section.site.clone()));
                return;
            }
            (level.offset, level.line) = section.back;
            level.sections.pop();
        }
    }

    /// The line of the current level carrying `target` (a label or `N` number), from byte
    /// `from` (line number `line`) on: the first one, or with `last` the last one before
    /// byte `before`; the search stops at `before` if given.
    pub(super) fn label_line(
        &mut self,
        target: &str,
        from: usize,
        line: usize,
        before: Option<usize>,
        last: bool,
    ) -> Option<Found> {
        let level = self.levels.last_mut()?;
        let (mut offset, mut line) = (from, line);
        let mut found = None;
        let mut buf = String::new();
        loop {
            if before.is_some_and(|b| offset >= b) {
                return found;
            }
            let n = level.source.line(offset, &mut buf).ok()?;
            if n == 0 {
                return found;
            }
            buf.make_ascii_uppercase();
            let (number, label) = targets(&buf);
            if number == Some(target) || label == Some(target) {
                found = Some((offset, line, n));
                if !last {
                    return found;
                }
            }
            offset += n;
            line += 1;
        }
    }
}
