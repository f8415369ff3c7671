//! Calls of the ISO family: LinuxCNC `o<name> call [args]` with its own locals, Fanuc
//! `M98 P<n> L<count>` (shared variables), `G65 P<n> L<count> A..Z` (a macro with locals
//! `#1`-`#33`), Haas `M97 P<n> L<count>` (a local subprogram at `N<n>`), and their returns
//! (`endsub`, `return`, `M99`). A subroutine is found in a loaded text or in a file on the
//! search path (loaded once, streamed); every repeated pass counts against the block budget,
//! and a repeat count the budget cannot hold is refused at the call.

use std::collections::HashMap;

use crate::expr::{Eval, Param};
use crate::lex::{LineError, LineResult};
use crate::source::{FileLines, Source};

use super::oword::oline;
use super::state::{Cursor, Frame, IsoReader, Kw, OLine, Program};

impl IsoReader {
    /// The file subroutine index of program `file`.
    pub(super) fn subs(&mut self, file: usize) -> &HashMap<String, Cursor> {
        if self.programs[file].subs.is_none() {
            let mut map = HashMap::new();
            let mut c = Cursor {
                file,
                offset: 0,
                line: 1,
            };
            let fanuc = self.dialect.table().macro_b;
            while let Some((line, next)) = self.line_at(c) {
                if let Ok(Some(o)) = oline(line) {
                    if o.kw == Kw::Sub || (fanuc && o.kw == Kw::Number) {
                        map.entry(o.label).or_insert(next);
                    }
                }
                c = next;
            }
            self.programs[file].subs = Some(map);
        }
        self.programs[file].subs.as_ref().expect("built above")
    }

    /// Where subroutine `label` starts in program `file`, if it is there; a file that could
    /// not be read to its end while indexing it is an error at the call's `span`.
    pub(super) fn sub_in(
        &mut self,
        file: usize,
        label: &str,
        span: &std::ops::Range<usize>,
    ) -> LineResult<Option<Cursor>> {
        let found = self.subs(file).get(label).copied();
        match self.io_error.take() {
            Some(e) => Err(LineError::new(
                span.clone(),
                format!(
                    "subroutine file {}: {e}",
                    self.programs[file].path.display()
                ),
                "unreadable subroutine file",
            )),
            None => Ok(found),
        }
    }

    /// Where subroutine `label` starts: this file, a loaded file, or a file on the search
    /// path (`label.ngc`, or for Fanuc `O<label>.nc`), loaded once.
    pub(super) fn find_sub(
        &mut self,
        label: &str,
        span: std::ops::Range<usize>,
    ) -> LineResult<Cursor> {
        let here = self.cursor.file;
        for file in std::iter::once(here).chain(0..self.programs.len()) {
            if let Some(c) = self.sub_in(file, label, &span)? {
                return Ok(c);
            }
        }
        let names = if self.dialect.table().macro_b {
            vec![
                format!("O{label}.nc"),
                format!("o{label}.nc"),
                format!("O{label:0>4}.nc"),
                format!("{label}.nc"),
            ]
        } else {
            vec![format!("{label}.ngc")]
        };
        for dir in self.search_path.clone() {
            for name in &names {
                let path = dir.join(name);
                if !path.exists() {
                    continue;
                }
                let lines = FileLines::open(&path).map_err(|e| {
                    LineError::new(
                        span.clone(),
                        format!("subroutine file {}: {e}", path.display()),
                        "unreadable subroutine file",
                    )
                })?;
                self.programs.push(Program {
                    path,
                    source: Source::File(lines),
                    subs: None,
                });
                let file = self.programs.len() - 1;
                if let Some(c) = self.sub_in(file, label, &span)? {
                    return Ok(c);
                }
                if self.dialect.table().macro_b {
                    // A Fanuc program file without its own O line starts at its top.
                    return Ok(Cursor {
                        file,
                        offset: 0,
                        line: 1,
                    });
                }
            }
        }
        Err(LineError::new(
            span,
            format!("subroutine `{label}` not found: expected it defined in this file or in a file on the subroutine search path"),
            "unknown subroutine",
        )
        .help("set the scenario's subroutine search path, or define the subroutine in the program"))
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn call(
        &mut self,
        label: &str,
        args: &[f64],
        locals: bool,
        repeats: u64,
        here: Cursor,
        next: Cursor,
        span: std::ops::Range<usize>,
    ) -> LineResult<()> {
        // Every pass runs at least its return: a count the budget cannot hold is refused
        // before the first pass.
        self.budget
            .check_passes(repeats, "this subprogram call", span.clone())?;
        let site = (here, span.clone());
        self.repeating = Some(site.clone());
        if self.frames.len() >= self.max_call_depth {
            return Err(LineError::new(
                span,
                format!("subroutines nested deeper than {}: expected the calls to return (endless recursion?)", self.max_call_depth),
                "call depth limit",
            ));
        }
        let start = match label.strip_prefix('N') {
            // Haas M97: a local subprogram at a sequence number of this program.
            Some(n) => self.sequence_line(self.cursor.file, n).ok_or_else(|| {
                LineError::new(
                    span,
                    format!("M97 P{n}: no block with sequence number N{n} in this program"),
                    "unknown sequence number",
                )
                .help("M97 calls a local subprogram that starts at N<n> of the same program")
            })?,
            None => self.find_sub(label, span)?,
        };
        let nlocal = if self.dialect.table().macro_b { 33 } else { 30 };
        let saved = if locals {
            let p = &mut self.interp.params;
            let saved = p.numbered[1..=nlocal].to_vec();
            for k in 1..=nlocal {
                p.numbered[k] = args.get(k - 1).copied().unwrap_or(0.0);
            }
            p.locals.push(HashMap::new());
            saved
        } else {
            Vec::new()
        };
        self.frames.push(Frame {
            ret: next,
            site,
            saved,
            loops: self.loops.len(),
            ifs: self.ifs.len(),
            repeats: repeats.saturating_sub(1),
            start,
            locals,
            restore: None,
            remap: None,
            resume: None,
            epilog: None,
        });
        self.cursor = start;
        Ok(())
    }

    /// Returns from the current subroutine; false in the main program.
    pub(super) fn ret(&mut self, value: Option<f64>) -> bool {
        let Some(frame) = self.frames.last_mut() else {
            return false;
        };
        if frame.repeats > 0 {
            frame.repeats -= 1;
            self.repeating = Some(frame.site.clone());
            self.cursor = frame.start;
            self.loops.truncate(frame.loops);
            self.ifs.truncate(frame.ifs);
            return true;
        }
        let frame = self.frames.pop().expect("checked");
        if let Some(e) = &frame.epilog {
            // The epilog reads the subroutine's parameters before they go.
            let p = &self.interp.params;
            let locals = p.locals.last();
            let remap = &self.remaps[e.remap];
            let result = crate::stdglue::epilog(
                e.handler,
                remap.code,
                remap.ngc.as_deref().unwrap_or(""),
                value,
                e.builtin_used,
                &|k| locals.and_then(|l| l.get(k).copied()),
                &|n| p.numbered.get(n).copied().unwrap_or(0.0),
            );
            match result {
                Ok(crate::stdglue::Commit::KeepMotion) => self.modal_remap = Some(e.remap),
                Ok(c) => self.commit = Some(c),
                Err(m) => {
                    self.abort = Some((
                        e.here,
                        e.span.clone(),
                        format!("{m} (stdglue {}, {})", e.handler.name(), remap.origin),
                    ))
                }
            }
        }
        if frame.locals {
            let p = &mut self.interp.params;
            for (k, v) in frame.saved.iter().enumerate() {
                p.numbered[k + 1] = *v;
            }
            p.locals.pop();
        }
        if let Some(saved) = frame.restore {
            self.interp.restore(&saved);
        }
        self.resume = frame.resume;
        self.loops.truncate(frame.loops);
        self.ifs.truncate(frame.ifs);
        let p = &mut self.interp.params;
        p.set(
            &Param::Named("_value_returned".into()),
            if value.is_some() { 1.0 } else { 0.0 },
        );
        if let Some(v) = value {
            p.set(&Param::Named("_value".into()), v);
        }
        self.cursor = frame.ret;
        true
    }

    /// `o<label> call [args]`: the subroutine called with its arguments.
    pub(super) fn o_call(
        &mut self,
        line: &str,
        o: &OLine,
        label: &str,
        here: Cursor,
        next: Cursor,
    ) -> LineResult<()> {
        self.interp.refresh_system_parameters();
        let mut args = Vec::new();
        let mut e = Eval::new(line, o.rest, &self.interp.params, false);
        loop {
            e.skip_blanks();
            match line.as_bytes().get(e.i) {
                Some(b'[') => args.push(e.value()?),
                Some(b'(') | Some(b';') | None => break,
                _ => {
                    return Err(LineError::new(
                        e.i..e.i + 1,
                        "expected `[argument]` after `call`",
                        "expected `[`",
                    ));
                }
            }
        }
        if args.len() > 30 {
            return Err(LineError::new(
                o.span.clone(),
                "more than 30 arguments: expected at most 30",
                "too many arguments",
            ));
        }
        self.call(label, &args, true, 1, here, next, o.span.clone())?;
        Ok(())
    }
}
