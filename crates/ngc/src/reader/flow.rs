//! Program flow of the ISO family: o-word `if`/`elseif`/`else`, `while`/`do`/`repeat`
//! loops with `break`/`continue`, Fanuc macro B `IF [..] GOTO n`, `IF [..] THEN`,
//! `WHILE [..] DO m` … `END m` and `GOTO n`. Loops and jumps seek back by byte offset; the
//! blocks they run again count against the block budget (crate `budget`) as they are read,
//! and a structure still open at the end of the text is an error at its opening line.

use crate::error::Error;
use crate::expr::Eval;
use crate::lex::{is_blank, lex, Lexed, LineError, LineResult};

use super::oword::{macro_line, oline};
use super::state::{kw_name, shift, Cursor, IsoReader, Kw, Loop, LoopKind, Macro, OLine, OpenIf};

impl IsoReader {
    /// A backward jump from the line at `here`: the construct a spent budget names (the
    /// blocks themselves are counted as they run, in [`IsoReader::step`]).
    pub(super) fn backward(&mut self, here: Cursor, span: std::ops::Range<usize>) {
        self.repeating = Some((here, span));
    }

    /// Moves the cursor forward from the line after `from` to the first o-word line with
    /// `label` and a keyword in `kws`; the cursor is left on that line.
    pub(super) fn skip_to(
        &mut self,
        from: Cursor,
        label: &str,
        kws: &[Kw],
        span: std::ops::Range<usize>,
    ) -> LineResult<()> {
        let mut c = match self.line_at(from) {
            Some((_, next)) => next,
            None => from,
        };
        while let Some((line, next)) = self.line_at(c) {
            if let Ok(Some(o)) = oline(line) {
                if o.label == label && kws.contains(&o.kw) {
                    self.cursor = c;
                    return Ok(());
                }
            }
            c = next;
        }
        Err(LineError::new(
            span,
            format!(
                "no matching `o{label} {}` after this line: expected the block to be closed",
                kw_name(kws[kws.len() - 1])
            ),
            "unclosed block",
        ))
    }

    /// Same for Fanuc `END m`.
    pub(super) fn skip_to_end(
        &mut self,
        from: Cursor,
        m: &str,
        span: std::ops::Range<usize>,
    ) -> LineResult<()> {
        let mut c = match self.line_at(from) {
            Some((_, next)) => next,
            None => from,
        };
        while let Some((line, next)) = self.line_at(c) {
            if let Some((Macro::End, _, k)) = macro_line(line) {
                if line[k..].trim().trim_start_matches('0') == m {
                    self.cursor = c;
                    return Ok(());
                }
            }
            c = next;
        }
        Err(LineError::new(
            span,
            format!("no `END {m}` after this WHILE: expected the loop to be closed"),
            "unclosed loop",
        ))
    }

    pub(super) fn eval_bracket(&mut self, line: &str, at: usize) -> LineResult<(f64, usize)> {
        self.interp.refresh_system_parameters();
        let mut e = Eval::new(line, at, &self.interp.params, self.dialect.table().macro_b);
        e.skip_blanks();
        if line.as_bytes().get(e.i) != Some(&b'[') {
            let end = (e.i + 1).min(line.len());
            return Err(LineError::new(
                e.i.min(end)..end,
                "expected `[condition]`",
                "expected `[`",
            ));
        }
        let v = e.value()?;
        Ok((v, e.i))
    }

    /// Executes an o-word line at `here` (cursor already past it, at `next`).
    pub(super) fn o_word(
        &mut self,
        line: &str,
        o: OLine,
        here: Cursor,
        next: Cursor,
    ) -> LineResult<bool> {
        let label = o.label.clone();
        match o.kw {
            Kw::Number => {
                if !self.dialect.table().macro_b {
                    return Err(LineError::new(o.span, "o-word without a keyword: expected `o<label> sub`, `call`, `if`, `while` ...", "no keyword")
                        .help("LinuxCNC o-words need a keyword; for Fanuc programs set dialect = \"fanuc\""));
                }
                // Fanuc program number: nothing to do.
            }
            Kw::Sub => {
                // A definition met in the flow: skip over it.
                self.skip_to(here, &label, &[Kw::EndSub], o.span)?;
                let (_, after) = self.line_at(self.cursor).expect("found");
                self.cursor = after;
            }
            Kw::EndSub | Kw::Return => {
                let value = self.optional_value(line, o.rest)?;
                if !self.ret(value) {
                    return Err(LineError::new(
                        o.span.clone(),
                        format!(
                            "`{}` outside a subroutine: expected it only in a called subroutine",
                            &line[o.span.clone()]
                        ),
                        "not in a subroutine",
                    ));
                }
            }
            Kw::Call => self.o_call(line, &o, &label, here, next)?,
            Kw::If => {
                let (c, _) = self.eval_bracket(line, o.rest)?;
                self.ifs.push(OpenIf {
                    label: label.clone(),
                    taken: c != 0.0,
                    head: (here, o.span.clone()),
                });
                if c == 0.0 {
                    self.skip_to(here, &label, &[Kw::ElseIf, Kw::Else, Kw::EndIf], o.span)?;
                }
            }
            Kw::ElseIf | Kw::Else => self.o_else(line, &o, &label, here)?,
            Kw::EndIf => match self.ifs.last() {
                Some(open) if open.label == label => {
                    self.ifs.pop();
                }
                _ => {
                    return Err(LineError::new(
                        o.span,
                        "`endif` without a matching `if`",
                        "no if",
                    ))
                }
            },
            Kw::While => self.o_while(line, &o, label, here)?,
            Kw::EndWhile => match self.loops.last() {
                Some(l) if l.label == label => {
                    let start = l.start;
                    self.backward(here, o.span);
                    self.cursor = start;
                }
                _ => {
                    return Err(LineError::new(
                        o.span,
                        "`endwhile` without a matching `while`",
                        "no while",
                    ))
                }
            },
            Kw::Do => self.loops.push(Loop {
                label,
                kind: LoopKind::Do,
                start: next,
                head: (here, o.span),
            }),
            Kw::Repeat => {
                let (n, _) = self.eval_bracket(line, o.rest)?;
                let n = if n.is_finite() && n > 0.0 {
                    n.round() as u64
                } else {
                    0
                };
                // Every pass runs at least its `endrepeat` line.
                self.budget.check_passes(
                    n.saturating_sub(1),
                    "this o-word repeat",
                    o.span.clone(),
                )?;
                if n == 0 {
                    self.skip_to(here, &label, &[Kw::EndRepeat], o.span)?;
                    let (_, after) = self.line_at(self.cursor).expect("found");
                    self.cursor = after;
                } else {
                    self.loops.push(Loop {
                        label,
                        kind: LoopKind::Repeat(n - 1),
                        start: next,
                        head: (here, o.span),
                    });
                }
            }
            Kw::EndRepeat => match self.loops.last_mut() {
                Some(Loop {
                    label: l,
                    kind: LoopKind::Repeat(left),
                    start,
                    ..
                }) if *l == label => {
                    if *left > 0 {
                        *left -= 1;
                        let start = *start;
                        self.backward(here, o.span);
                        self.cursor = start;
                    } else {
                        self.loops.pop();
                    }
                }
                _ => {
                    return Err(LineError::new(
                        o.span,
                        "`endrepeat` without a matching `repeat`",
                        "no repeat",
                    ))
                }
            },
            Kw::Break | Kw::Continue => self.o_break(line, &o, &label, here)?,
        }
        Ok(false)
    }

    /// `o.. elseif [cond]` / `o.. else`: taken when no branch of the `if` was.
    pub(super) fn o_else(
        &mut self,
        line: &str,
        o: &OLine,
        label: &str,
        here: Cursor,
    ) -> LineResult<()> {
        let Some(OpenIf {
            label: l, taken, ..
        }) = self.ifs.last().cloned()
        else {
            return Err(LineError::new(
                o.span.clone(),
                "`else` without `if`: expected a matching `o.. if`",
                "no if",
            ));
        };
        if l != label {
            return Err(LineError::new(
                o.span.clone(),
                format!("`o{label}` does not match the open `o{l} if`"),
                "label mismatch",
            ));
        }
        if taken {
            self.skip_to(here, &label, &[Kw::EndIf], o.span.clone())?;
        } else if o.kw == Kw::Else {
            self.ifs.last_mut().expect("checked").taken = true;
        } else {
            let (c, _) = self.eval_bracket(line, o.rest)?;
            if c != 0.0 {
                self.ifs.last_mut().expect("checked").taken = true;
            } else {
                self.skip_to(
                    here,
                    &label,
                    &[Kw::ElseIf, Kw::Else, Kw::EndIf],
                    o.span.clone(),
                )?;
            }
        }
        Ok(())
    }

    /// `o.. while [cond]`: the loop's head, or the tail of an `o.. do` loop.
    pub(super) fn o_while(
        &mut self,
        line: &str,
        o: &OLine,
        label: String,
        here: Cursor,
    ) -> LineResult<()> {
        let top_do = matches!(self.loops.last(), Some(Loop { label: l, kind: LoopKind::Do, .. }) if *l == label);
        let (c, _) = self.eval_bracket(line, o.rest)?;
        if top_do {
            if c != 0.0 {
                self.backward(here, o.span.clone());
                self.cursor = self.loops.last().expect("checked").start;
            } else {
                self.loops.pop();
            }
        } else if c != 0.0 {
            let again = matches!(self.loops.last(), Some(Loop { label: l, kind: LoopKind::While, .. }) if *l == label);
            if !again {
                self.loops.push(Loop {
                    label,
                    kind: LoopKind::While,
                    start: here,
                    head: (here, o.span.clone()),
                });
            }
        } else {
            if matches!(self.loops.last(), Some(l) if l.label == label) {
                self.loops.pop();
            }
            self.skip_to(here, &label, &[Kw::EndWhile], o.span.clone())?;
            let (_, after) = self.line_at(self.cursor).expect("found");
            self.cursor = after;
        }
        Ok(())
    }

    /// `o.. break` / `o.. continue`: out of, or to the end of, the loop `label`.
    pub(super) fn o_break(
        &mut self,
        line: &str,
        o: &OLine,
        label: &str,
        here: Cursor,
    ) -> LineResult<()> {
        let Some(l) = self.loops.iter().rev().find(|l| l.label == label).cloned() else {
            return Err(LineError::new(
                o.span.clone(),
                format!("`{}` outside loop `o{label}`", &line[o.span.clone()]),
                "not in this loop",
            ));
        };
        let end = match l.kind {
            LoopKind::While => Kw::EndWhile,
            LoopKind::Do => Kw::While,
            _ => Kw::EndRepeat,
        };
        self.skip_to(here, &label, &[end], o.span.clone())?;
        if o.kw == Kw::Break {
            while let Some(top) = self.loops.pop() {
                if top.label == label {
                    break;
                }
            }
            let (_, after) = self.line_at(self.cursor).expect("found");
            self.cursor = after;
        }
        Ok(())
    }

    pub(super) fn optional_value(&mut self, line: &str, at: usize) -> LineResult<Option<f64>> {
        let b = line.as_bytes();
        let mut i = at;
        while i < b.len() && is_blank(b[i]) {
            i += 1;
        }
        if b.get(i) == Some(&b'[') {
            Ok(Some(self.eval_bracket(line, i)?.0))
        } else {
            Ok(None)
        }
    }

    /// A Fanuc macro statement line.
    pub(super) fn macro_statement(
        &mut self,
        line: &str,
        m: Macro,
        at: usize,
        rest: usize,
        here: Cursor,
        next: Cursor,
    ) -> LineResult<()> {
        let span = at..rest;
        let number_after = |s: &str| -> LineResult<String> {
            let t = s.trim();
            if t.is_empty() || !t.bytes().all(|b| b.is_ascii_digit()) {
                return Err(LineError::new(
                    span.clone(),
                    format!("`{}`: expected a number after it", &line[span.clone()]),
                    "expected a number",
                ));
            }
            let t = t.trim_start_matches('0');
            Ok(if t.is_empty() { "0".into() } else { t.into() })
        };
        match m {
            Macro::Goto => {
                let n = number_after(&line[rest..])?;
                self.goto(&n, here, span)
            }
            Macro::If => {
                let (c, after) = self.eval_bracket(line, rest)?;
                let tail = line[after..].trim_start();
                let upper = tail.to_ascii_uppercase();
                if let Some(target) = upper.strip_prefix("GOTO") {
                    if c != 0.0 {
                        let n = number_after(target)?;
                        return self.goto(&n, here, span);
                    }
                    Ok(())
                } else if upper.starts_with("THEN") {
                    if c != 0.0 {
                        let off = line.len() - tail.len() + 4;
                        let stmt = &line[off..];
                        match lex(stmt, &self.interp.params, true).map_err(|e| shift(e, off))? {
                            Lexed::Words { words, assigns } if words.is_empty() => {
                                for (p, v) in assigns {
                                    self.interp.check_assign(stmt, &p, v)?;
                                    self.interp.params.set(&p, v);
                                }
                                self.interp.parameters_changed();
                            }
                            Lexed::Nothing => {}
                            _ => {
                                return Err(LineError::new(
                                    off..line.len(),
                                    "expected an assignment `#n = value` after THEN",
                                    "not an assignment",
                                ))
                            }
                        }
                    }
                    Ok(())
                } else {
                    Err(LineError::new(
                        after..line.len(),
                        "expected `GOTO n` or `THEN #n = value` after `IF [condition]`",
                        "expected GOTO or THEN",
                    ))
                }
            }
            Macro::While => {
                let (c, after) = self.eval_bracket(line, rest)?;
                let tail = line[after..].trim_start();
                let Some(m) = tail
                    .to_ascii_uppercase()
                    .strip_prefix("DO")
                    .map(|s| s.trim().trim_start_matches('0').to_string())
                else {
                    return Err(LineError::new(
                        after..line.len(),
                        "expected `DO m` after `WHILE [condition]`",
                        "expected DO",
                    ));
                };
                let again = matches!(self.loops.last(), Some(l) if l.label == m && l.start == here);
                if c != 0.0 {
                    if !again {
                        self.loops.push(Loop {
                            label: m,
                            kind: LoopKind::FanucDo,
                            start: here,
                            head: (here, span.clone()),
                        });
                    }
                } else {
                    if again {
                        self.loops.pop();
                    }
                    self.skip_to_end(here, &m, span)?;
                    let (_, after) = self.line_at(self.cursor).expect("found");
                    self.cursor = after;
                }
                let _ = next;
                Ok(())
            }
            Macro::End => {
                let m = number_after(&line[rest..])?;
                match self.loops.last() {
                    Some(l) if l.label == m => {
                        let start = l.start;
                        self.backward(here, span);
                        self.cursor = start;
                        Ok(())
                    }
                    _ => Err(LineError::new(
                        span,
                        format!("`END {m}` without a matching `WHILE [..] DO {m}`"),
                        "no WHILE",
                    )),
                }
            }
        }
    }

    /// Fanuc GOTO n: the line with sequence number N n in the current program.
    pub(super) fn goto(
        &mut self,
        n: &str,
        here: Cursor,
        span: std::ops::Range<usize>,
    ) -> LineResult<()> {
        match self.sequence_line(here.file, n) {
            Some(c) => {
                if c.offset <= here.offset {
                    self.backward(here, span);
                }
                self.cursor = c;
                Ok(())
            }
            None => Err(LineError::new(
                span,
                format!("GOTO {n}: no block with sequence number N{n} in this program"),
                "unknown target",
            )),
        }
    }

    /// The first line of `file` that starts with sequence number N`n` (leading zeros
    /// ignored).
    pub(super) fn sequence_line(&mut self, file: usize, n: &str) -> Option<Cursor> {
        let mut c = Cursor {
            file,
            offset: 0,
            line: 1,
        };
        while let Some((line, next)) = self.line_at(c) {
            let b = line.as_bytes();
            let mut i = 0;
            while i < b.len() && is_blank(b[i]) {
                i += 1;
            }
            if matches!(b.get(i), Some(b'N' | b'n')) {
                let d = i + 1;
                let mut k = d;
                while k < b.len() && b[k].is_ascii_digit() {
                    k += 1;
                }
                let t = line[d..k].trim_start_matches('0');
                if k > d && (t == n || (t.is_empty() && n == "0")) {
                    return Some(c);
                }
            }
            c = next;
        }
        None
    }

    /// At the end of a text: the innermost `if`, loop or `WHILE` opened in it that has no
    /// closing line anywhere after its head, as an error at its opening line. (A loop left
    /// by a jump, as Fanuc allows, has its closing line and is not reported.)
    pub(super) fn unclosed(&mut self) -> Option<Error> {
        let (loops_from, ifs_from) = self.frames.last().map_or((0, 0), |f| (f.loops, f.ifs));
        let mut open: Vec<(Cursor, std::ops::Range<usize>, String, Vec<Kw>)> = Vec::new();
        for l in &self.loops[loops_from.min(self.loops.len())..] {
            let ends = match l.kind {
                LoopKind::While => vec![Kw::EndWhile],
                LoopKind::Do => vec![Kw::While],
                LoopKind::Repeat(_) => vec![Kw::EndRepeat],
                LoopKind::FanucDo => Vec::new(),
            };
            open.push((l.head.0, l.head.1.clone(), l.label.clone(), ends));
        }
        for i in &self.ifs[ifs_from.min(self.ifs.len())..] {
            open.push((i.head.0, i.head.1.clone(), i.label.clone(), vec![Kw::EndIf]));
        }
        // Innermost first: the one opened last.
        open.sort_by_key(|(c, ..)| std::cmp::Reverse((c.file, c.offset)));
        let cursor = self.cursor;
        for (head, span, label, ends) in open {
            let closed = if ends.is_empty() {
                self.skip_to_end(head, &label, span.clone()).is_ok()
            } else {
                self.skip_to(head, &label, &ends, span.clone()).is_ok()
            };
            self.cursor = cursor;
            if self.io_error.take().is_some() || closed {
                continue;
            }
            let closing = if ends.is_empty() {
                format!("END {label}")
            } else {
                format!("o{label} {}", kw_name(ends[0]))
            };
            let err = LineError::new(
                span,
                format!("this structure is never closed: expected `{closing}` before the end of the program"),
                "unclosed structure",
            );
            return Some(self.error_at(head, err, ""));
        }
        None
    }
}
