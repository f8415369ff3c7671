//! The HEIDENHAIN Klartext (TNC 640 conversational) front end: program text in, the same
//! canonical moves as the G-code dialects out. Input: a program (streamed block by block)
//! and the reader options; output: [`Move`]s, through the shared interpreter's phases.
//!
//! ```text
//! Klartext block ─► text (number, `;`, `~`) ─► keyword ─┬─ flow: LBL, CALL LBL/PGM, FN 9-12
//!                                                         ├─ Q parameters (qparam)
//!                                                         └─ contour / cycles / frames ─►
//!   typed words (G1 X.. Y.., G2 I J, G52, G68.2, G43.4 …) ─► Interp::block ─► Move queue
//! ```
//!
//! Every construct becomes words of the G codes the interpreter already runs (so a Klartext
//! move and its G-code twin leave as the same canonical move); the front end keeps what
//! Klartext adds: the pole `CC`, the tangent for `CT`, the corner held for `RND`/`CHF`, the
//! feed that `FMAX` leaves untouched, the datum shift and working plane, the cycle
//! defined by `CYCL DEF`. The file is streamed (jumps seek to byte offsets; the label index
//! keeps offsets), and calls nest at most `max_call_depth` deep.

mod approach;
mod contour;
mod cycle_moves;
mod cycle_pos;
mod cycles;
mod frames;
mod front;
mod milling;
mod pattern;
mod qparam;
mod slots;
mod state;
mod studs;
mod surface_normal;
mod sysread;
mod text;
mod threads;
mod transform;
mod word_map;

use std::collections::{HashMap, VecDeque};
use std::ops::Range;
use std::path::Path;

use crate::canon::Move;
use crate::error::{Error, Result};
use crate::interp::{Interp, Stop};
use crate::lex::{LineError, LineResult, Word};
use crate::notice::Notice;
use crate::options::Options;
use crate::source::{quoted_at, syntax_error, FileLines, Source};

pub(crate) use front::FRONT_END;
use qparam::Qparams;
pub(crate) use state::Reader;
use state::{refusal, unexpected, Block, Contour, Cursor, Cycle, Extras, Frame, Frames, Program};

impl Reader {
    pub(crate) fn new(path: &Path, source: Source, options: &Options) -> Reader {
        let interp = Interp::new(options);
        let start = interp.program_position();
        Reader {
            programs: vec![Program {
                path: path.to_path_buf(),
                source,
                labels: None,
            }],
            cursor: Cursor {
                file: 0,
                offset: 0,
                line: 1,
            },
            frames: Vec::new(),
            interp,
            queue: VecDeque::new(),
            notices: Vec::new(),
            q: Qparams::new(),
            path: Contour::new(start),
            frames_state: Frames::default(),
            cycle: Cycle::default(),
            pattern: Vec::new(),
            tools: options.tools.clone(),
            rewritten: Vec::new(),
            table: options.table,
            chain_rotaries: match options.aligner {
                Some(_) => options
                    .axes
                    .iter()
                    .copied()
                    .filter(|a| a.is_rotary())
                    .collect(),
                None => Vec::new(),
            },
            search_path: options.search_path.clone(),
            tool: (0, 0.0, 0.0),
            inch: false,
            spindle_rpm: 0.0,
            shortest: false,
            modal_cycle: false,
            finished: false,
            flushed: false,
            budget: crate::budget::Budget::new(options.max_blocks),
            repeating: None,
            max_call_depth: options.max_call_depth,
            text: String::new(),
            buf: String::new(),
            toks: Vec::new(),
            words: Vec::new(),
            ends: Vec::new(),
            noticed: Vec::new(),
        }
    }

    pub(crate) fn notices(&self) -> &[Notice] {
        &self.notices
    }

    /// Reads the block at the cursor into `self.text` (its lines joined, comments dropped);
    /// returns the block's first line and the cursor after it, `None` at the end.
    fn read_block(&mut self) -> Result<Option<(Cursor, Cursor)>> {
        let here = self.cursor;
        let mut c = here;
        self.text.clear();
        let mut in_comment = false;
        for k in 0..=text::MAX_BLOCK_LINES {
            let program = &mut self.programs[c.file];
            let read = program.source.line(c.offset, &mut self.buf);
            let (line, len) = match read {
                Ok(Some(l)) => l,
                Ok(None) if k == 0 => return Ok(None),
                Ok(None) => break,
                Err(e) => {
                    return Err(Error::Read {
                        path: program.path.clone(),
                        source: std::io::Error::new(e.kind(), format!("line {}: {e}", c.line)),
                    })
                }
            };
            let ((body, continued), comment_goes_on) = text::strip_comment_in(line, in_comment);
            in_comment = comment_goes_on;
            if k > 0 {
                self.text.push(' ');
            }
            if self.text.len() + body.len() > crate::source::MAX_LINE_BYTES {
                break;
            }
            self.text.push_str(body);
            c = Cursor {
                file: c.file,
                offset: c.offset + len,
                line: c.line + 1,
            };
            if !continued {
                break;
            }
        }
        Ok(Some((here, c)))
    }

    /// An error at `err.span` of the block at `here`.
    fn error_at(&self, here: Cursor, err: LineError) -> Error {
        let program = &self.programs[here.file];
        let first = self.text.lines().next().unwrap_or("");
        let (text, start) = quoted_at(program.source.quoted(&program.path), here.line, first);
        let mut err = err;
        // A span past the first line (a joined continuation line) marks the whole line.
        if err.span.end > first.len() {
            err.span = err.span.start.min(first.len())..first.len();
        }
        syntax_error(&program.path, text, start, err)
    }

    /// Reads on until a move is queued, the program ends, or an error.
    fn step(&mut self) -> Result<()> {
        let Some((here, next)) = self.read_block()? else {
            // The end of a called file returns; the end of the main program ends.
            if !self.ret_from_program() {
                self.finished = true;
            }
            let here = self.cursor;
            let b = Block {
                text: "",
                toks: &[],
                line: here.line,
            };
            approach::unfinished(self)
                .and_then(|()| contour::release(self, &b))
                .map_err(|e| self.error_at(here, e))?;
            return self.run_words(here);
        };
        self.cursor = next;
        if !self.budget.spend_at(here.file == 0, here.offset) {
            self.finished = true;
            let (at, span) = self.repeating.clone().unwrap_or((here, 0..0));
            let err = self.budget.spent(span);
            return Err(if at == here {
                self.error_at(here, err)
            } else {
                let program = &self.programs[at.file];
                let (text, start) = quoted_at(program.source.quoted(&program.path), at.line, "");
                syntax_error(&program.path, text, start, err)
            });
        }
        let result = self.block(here);
        let result = result.and_then(|()| self.run_words_line(here));
        result.map_err(|e| {
            self.finished = true;
            self.error_at(here, e)
        })
    }

    /// Runs the words emitted so far through the interpreter (outside any block).
    fn run_words(&mut self, here: Cursor) -> Result<()> {
        self.run_words_line(here)
            .map_err(|e| self.error_at(here, e))
    }

    fn run_words_line(&mut self, here: Cursor) -> LineResult<()> {
        if self.ends.is_empty() {
            self.words.clear();
            return Ok(());
        }
        let path = &self.programs[here.file].path;
        let text = std::mem::take(&mut self.text);
        let mut start = 0;
        let mut result = Ok(());
        for &(end, line_no) in &self.ends {
            if let Err(e) = self.frames_state.map.apply(&mut self.words[start..end]) {
                result = Err(e);
                break;
            }
            let stop = self.interp.block(
                &text,
                &self.words[start..end],
                line_no,
                &mut self.queue,
                &mut self.notices,
                path,
            );
            start = end;
            match stop {
                Ok(Stop::End) => self.finished = true,
                Ok(_) => {}
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        self.text = text;
        self.words.clear();
        self.ends.clear();
        result
    }

    /// One block: the keyword's handler.
    fn block(&mut self, here: Cursor) -> LineResult<()> {
        let from = text::after_block_number(&self.text);
        let mut toks = std::mem::take(&mut self.toks);
        text::tokens(&self.text, from, &mut toks);
        let text = std::mem::take(&mut self.text);
        let b = Block {
            text: &text,
            toks: &toks,
            line: here.line,
        };
        let result = self.dispatch(&b, here);
        self.text = text;
        self.toks = toks;
        result
    }

    fn dispatch(&mut self, b: &Block, here: Cursor) -> LineResult<()> {
        let Some(first) = b.toks.first() else {
            return Ok(());
        };
        // Most blocks of most programs.
        if matches!(b.tok(0), "L" | "l") {
            return contour::block(self, b, "L");
        }
        // The keyword, upper case, without allocating (keywords are short).
        let mut upper = [0u8; 16];
        let raw = b.tok(0).as_bytes();
        let n = raw.len().min(16);
        for (u, c) in upper.iter_mut().zip(&raw[..n]) {
            *u = c.to_ascii_uppercase();
        }
        let key = std::str::from_utf8(&upper[..n]).unwrap_or("");
        approach::pending_refused(self, b, key)?;
        // Everything but a corner element releases the held line.
        if !matches!(key, "RND" | "CHF" | "L" | "LP") {
            self.release_held(b)?;
        }
        match key {
            "L" | "LP" | "CC" | "C" | "CR" | "CT" | "CP" | "RND" | "CHF" => {
                contour::block(self, b, key)
            }
            "LN" => surface_normal::ln(self, b),
            "APPR" => approach::appr(self, b),
            "DEP" => approach::dep(self, b),
            "BEGIN" => self.begin_pgm(b),
            "END" if b.is(1, "PGM") => {
                if !self.ret_from_program() {
                    self.finished = true;
                }
                Ok(())
            }
            "BLK" | "TOOL" if b.is(1, "FORM") || b.is(1, "DEF") => Ok(()),
            "PATTERN" if b.is(1, "DEF") => pattern::define(self, b),
            "TOOL" if b.is(1, "CALL") => self.tool_call(b),
            "FN" => self.fn_block(b, here, 1),
            _ if key.starts_with("FN")
                && key[2..]
                    .trim_end_matches(':')
                    .bytes()
                    .all(|c| c.is_ascii_digit()) =>
            {
                self.fn_block(b, here, 0)
            }
            "LBL" => {
                label_mark(b, 1)?;
                self.label(b.tok(1) == "0")
            }
            // `LBL1`: a label glued to its number (its jumps find it, `find_label`).
            _ if key.len() > 3 && key.starts_with("LBL") => {
                label_mark(b, 0)?;
                self.label(&key[3..] == "0")
            }
            "CALL" if b.is(1, "LBL") => self.call_label(b, here),
            "CALL" if b.is(1, "PGM") => self.call_program(b, here),
            "CYCL" | "CYCLE" if b.is(1, "CALL") => self.cycle_call(b),
            "CYCL" | "CYCLE" => cycles::block(self, b),
            "PLANE" => frames::plane(self, b),
            "FUNCTION" => frames::function(self, b),
            "STOP" => self.m_only(b, 1),
            "*" => Ok(()),
            // A hidden block (`/85 M30`) is skipped, as the G-code reader skips `/` blocks.
            _ if key.starts_with('/') => Ok(()),
            _ if key.starts_with('*') => Ok(()),
            _ if key.starts_with('Q') && b.text[first.clone()].contains('=')
                || key.starts_with('Q') && b.is(1, "=")
                || key.starts_with('Q') && b.tok(1).starts_with('=') =>
            {
                self.assign(b)
            }
            _ if key.starts_with('M')
                && key[1..].bytes().all(|c| c.is_ascii_digit())
                && key.len() > 1 =>
            {
                self.m_only(b, 0)
            }
            _ => Err(refusal(b, 0)),
        }
    }

    fn begin_pgm(&mut self, b: &Block) -> LineResult<()> {
        if !b.is(1, "PGM") {
            return Err(refusal(b, 0));
        }
        let unit = (2..b.toks.len()).find(|&k| b.is(k, "MM") || b.is(k, "INCH"));
        let Some(k) = unit else {
            return Err(LineError::new(
                b.span(0),
                "BEGIN PGM without MM or INCH: expected `BEGIN PGM name MM` or `… INCH`",
                "no unit",
            ));
        };
        if self.frames.iter().any(|f| f.program) {
            return Ok(());
        }
        self.inch = b.is(k, "INCH");
        let code = if self.inch { "20" } else { "21" };
        self.gword(code, b.span(k));
        self.end_block(b.line);
        Ok(())
    }

    /// `TOOL CALL n Z S.. F.. DL.. DR..`: T, M6, G43 H (the length as the tool table has
    /// it; `DL` through the datum, `DR` in the compensation's diameter).
    fn tool_call(&mut self, b: &Block) -> LineResult<()> {
        let mut number = None;
        let (mut dl, mut dr) = (0.0, 0.0);
        for k in 2..b.toks.len() {
            let t = b.tok(k);
            let (name, rest) = text::split_word(t);
            let span = b.span(k);
            match name.to_ascii_uppercase().as_str() {
                "" if t.starts_with('"') => number = Some(0),
                "" => {
                    let v = text::value(t, &self.q, span.clone())?;
                    if v < 0.0 || v.fract() != 0.0 || v > 1e9 {
                        return Err(LineError::new(
                            span,
                            format!("`{t}`: expected a tool number"),
                            "not a tool number",
                        ));
                    }
                    number = Some(v as u32);
                }
                "Z" if rest.is_empty() => {}
                "X" | "Y" if rest.is_empty() => {
                    return Err(LineError::new(
                        span,
                        format!("TOOL CALL with tool axis {t}: only tool axis Z is supported"),
                        "tool axis not Z",
                    )
                    .help("program the part with tool axis Z"));
                }
                "S" => {
                    let v = text::value(rest, &self.q, span.clone())?;
                    self.spindle_rpm = v;
                    self.word('S', v, span);
                }
                "F" => self.path.tool_feed = Some(text::value(rest, &self.q, span)?),
                "DL" => dl = text::value(rest, &self.q, span)?,
                "DR" => dr = text::value(rest, &self.q, span)?,
                "DR2" | "QS" => {}
                _ => {
                    return Err(unexpected(
                        b,
                        k,
                        "TOOL CALL",
                        "a tool number, the axis Z, S, F, DL, DR or DR2",
                    ))
                }
            }
        }
        if let Some(n) = number {
            sysread::unchanged(self, n, b.span(2))?;
            self.tool = (n, dl, dr);
            if n > 0 {
                self.word('T', n as f64, b.span(0));
                self.word('M', 6.0, b.span(0));
                self.gword("43", b.span(0));
                self.word('H', n as f64, b.span(0));
            } else {
                self.note(b, "TOOL CALL of a named tool: read with length and radius zero (mtsim's tool table is by number)");
            }
            self.end_block(b.line);
            if dl != self.frames_state.dl {
                self.frames_state.dl = dl;
                frames::apply(self, b)?;
            }
        } else {
            self.end_block(b.line);
        }
        Ok(())
    }

    /// The diameter for compensation: the tool table's, plus 2 `DR`.
    fn comp_diameter(&self) -> f64 {
        let d = self
            .tools
            .iter()
            .find(|t| t.number == self.tool.0)
            .map_or(0.0, |t| t.diameter_mm);
        let scale = if self.inch {
            crate::units::MM_PER_INCH
        } else {
            1.0
        };
        d / scale + 2.0 * self.tool.2
    }

    /// `Q1 = formula`.
    fn assign(&mut self, b: &Block) -> LineResult<()> {
        let start = b.toks[0].start;
        let eq = b.text[start..]
            .find('=')
            .map(|k| start + k)
            .unwrap_or(start);
        let name = b.text[start..eq].trim();
        let v = self.q.formula(&b.text[eq + 1..], eq + 1)?;
        self.q.set_ref(name, v, start..eq)
    }

    /// `FN n: …`.
    fn fn_block(&mut self, b: &Block, here: Cursor, at: usize) -> LineResult<()> {
        let t = b.tok(at).trim_start_matches(['F', 'N', 'f', 'n']);
        let digits = t.bytes().take_while(|c| c.is_ascii_digit()).count();
        let n: u32 = t[..digits].parse().map_err(|_| {
            LineError::new(
                b.span(1),
                format!(
                    "`FN {}`: expected a function number such as `FN 0:`",
                    b.tok(1)
                ),
                "expected FN n",
            )
        })?;
        let colon = b.text[b.toks[at].start..]
            .find(':')
            .map(|k| b.toks[at].start + k + 1);
        let rest_at = colon.unwrap_or(b.toks[at].end);
        let rest = &b.text[rest_at..];
        match n {
            0..=8 | 13 => {
                let eq = rest.find('=').ok_or_else(|| LineError::new(b.span(1), format!("FN {n} without `=`: expected `FN {n}: Q1 = …`"), "expected ="))?;
                let name = rest[..eq].trim();
                let v = self.fn_value(n, &rest[eq + 1..], rest_at + eq + 1)?;
                self.q.set_ref(name, v, rest_at..rest_at + eq)
            }
            9..=12 => self.fn_jump(b, n, rest, rest_at, here),
            14 => Err(LineError::new(b.span(0), format!("the program raises an error: {}", rest.trim()), "FN 14 error")),
            15 | 16 => Ok(()),
            17 => sysread::write(self, b, rest, rest_at),
            18 => sysread::read(self, b, rest, rest_at),
            _ => Err(LineError::new(b.spans(0, 1), format!("`FN {n}` is not supported: mtsim reads FN 0-16 (arithmetic, trigonometry, jumps, error and print), FN 17 (the tool table, ID50) and FN 18 (system data); FN 17 of other data, FN 19 PLC, FN 20 WAIT FOR, FN 26-28 tables and the others are refused"), "FN not supported")
                .help("docs/gcode.md lists the Heidenhain constructs mtsim reads")),
        }
    }

    /// The value of `FN n: Q = rhs` (rhs at byte `at`): `a + b`, `a DIV b`, `SQRT a`,
    /// `a LEN b` (√(a² + b²)), `a ANG b` (the angle of the point (a, b), deg), ….
    fn fn_value(&self, n: u32, rhs: &str, at: usize) -> LineResult<f64> {
        let upper = rhs.to_ascii_uppercase();
        let split = |op: &str| {
            upper
                .find(op)
                .map(|k| (&rhs[..k], at + k + op.len(), &rhs[k + op.len()..]))
        };
        let bad = || {
            LineError::new(
                at..at + rhs.len(),
                format!("FN {n}: expected its operands and operator (docs/gcode.md)"),
                "bad FN",
            )
        };
        let f = |s: &str, k: usize| self.q.formula(s, k);
        Ok(match n {
            0 => f(rhs, at)?,
            1..=4 | 8 | 13 => {
                let op = [
                    "", " + ", " - ", " * ", "DIV", "", "", "", "LEN", "", "", "", "", "ANG",
                ][n as usize];
                // A sign after a blank is the operand's: split at the operator between blanks.
                let (a, k, c) = split(op).or_else(|| split(op.trim())).ok_or_else(bad)?;
                let (x, y) = (f(a, at)?, f(c, k)?);
                match n {
                    1 => x + y,
                    2 => x - y,
                    3 => x * y,
                    4 => x / y,
                    8 => x.hypot(y),
                    _ => y.atan2(x).to_degrees(),
                }
            }
            5..=7 => {
                let name = ["SQRT", "SIN", "COS"][(n - 5) as usize];
                let (_, k, a) = split(name).ok_or_else(bad)?;
                let x = f(a, k)?;
                match n {
                    5 => x.sqrt(),
                    6 => x.to_radians().sin(),
                    _ => x.to_radians().cos(),
                }
            }
            _ => return Err(bad()),
        })
    }

    /// `FN 9-12: IF a EQU|NE|GT|LT b GOTO LBL n`.
    fn fn_jump(
        &mut self,
        b: &Block,
        n: u32,
        rest: &str,
        at: usize,
        here: Cursor,
    ) -> LineResult<()> {
        let upper = rest.to_ascii_uppercase();
        let op = ["EQU", "NE", "GT", "LT"][(n - 9) as usize];
        let bad = || {
            LineError::new(
                at..b.text.len(),
                format!("FN {n}: expected `IF a {op} b GOTO LBL n`"),
                "bad jump",
            )
        };
        let if_at = upper.find("IF").ok_or_else(bad)?;
        let op_at = upper.find(&format!(" {op} ")).ok_or_else(bad)?;
        let goto = upper.find("GOTO").ok_or_else(bad)?;
        let a = self.q.formula(&rest[if_at + 2..op_at], at)?;
        let c = self.q.formula(&rest[op_at + op.len() + 2..goto], at)?;
        let taken = match n {
            9 => a == c,
            10 => a != c,
            11 => a > c,
            _ => a < c,
        };
        if !taken {
            return Ok(());
        }
        let label = rest[goto + 4..].trim();
        let label = label
            .strip_prefix("LBL")
            .or_else(|| label.strip_prefix("lbl"))
            .unwrap_or(label)
            .trim();
        let span = at + goto..b.text.len();
        let label = self.label_name(label, span.clone())?;
        let target = self.find_label(here.file, &label, span.clone())?;
        if target.offset <= here.offset {
            self.backward(here, span);
        }
        self.cursor = target;
        Ok(())
    }

    /// A label as the index keeps it: a number (also from a Q parameter), or a name.
    fn label_name(&self, text: &str, span: Range<usize>) -> LineResult<String> {
        let t = text.trim();
        if t.starts_with('"') {
            return Ok(t.trim_matches('"').to_string());
        }
        if t.starts_with(['Q', 'q']) {
            return Ok(format!("{}", self.q.get_ref(t, span)?));
        }
        match t.parse::<f64>() {
            Ok(v) => Ok(format!("{v}")),
            Err(_) => Err(LineError::new(
                span,
                format!("`{t}`: expected a label number or \"name\""),
                "expected a label",
            )),
        }
    }

    /// `LBL n`: a mark; `LBL 0` ends the subprogram being run.
    fn label(&mut self, zero: bool) -> LineResult<()> {
        match self.frames.last() {
            Some(f) if zero && !f.program => {
                self.end_pass();
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// One pass of the innermost label call is done: the next pass, or back after the call.
    fn end_pass(&mut self) {
        let Some(f) = self.frames.last_mut() else {
            return;
        };
        if f.repeats > 0 {
            f.repeats -= 1;
            self.cursor = f.target;
            self.repeating = Some((f.call, f.call_span.clone()));
            return;
        }
        self.cursor = f.ret;
        self.frames.pop();
    }

    /// `CALL LBL n [REP m]`: runs from `LBL n` to `LBL 0` (a subprogram) or back to this
    /// line (a section repeat), m + 1 times in all.
    fn call_label(&mut self, b: &Block, here: Cursor) -> LineResult<()> {
        // Back at the call of the innermost frame: one pass of a section repeat is done.
        if self
            .frames
            .last()
            .is_some_and(|f| f.call == here && !f.program)
        {
            self.end_pass();
            return Ok(());
        }
        let label = self.label_name(b.tok(2), b.span(2))?;
        // Passes run by jumping to the label: one, or m for `REP m` (a section repeat runs
        // once on its own before its CALL, so m + 1 times in all).
        let mut passes = 1;
        if b.is(3, "REP") {
            let (rep, span) = match b.tok(4) {
                "" => (b.tok(3).get(3..).unwrap_or(""), b.span(3)),
                t => (t, b.span(4)),
            };
            // `REP 20/20`: the TNC shows the repeats left after the slash.
            let rep = rep.split('/').next().unwrap_or(rep);
            let v = text::value(rep, &self.q, span.clone())?;
            if v < 0.0 || v.fract() != 0.0 || v > 65534.0 {
                return Err(LineError::new(
                    span,
                    format!("REP {rep}: expected a whole number of repeats 0-65534"),
                    "bad repeat count",
                ));
            }
            passes = v as u64;
        }
        if passes == 0 {
            return Ok(());
        }
        let repeats = passes - 1;
        let call_span = b.spans(0, b.toks.len() - 1);
        // Every pass runs at least the label's `LBL 0` or its `CALL`.
        self.budget
            .check_passes(passes, "this label call", call_span.clone())?;
        let target = self.find_label(here.file, &label, b.span(2))?;
        self.push_frame(
            b,
            Frame {
                ret: self.cursor,
                call: here,
                call_span: call_span.clone(),
                target,
                repeats,
                program: false,
            },
        )?;
        self.backward(here, call_span);
        self.cursor = target;
        Ok(())
    }

    fn push_frame(&mut self, b: &Block, f: Frame) -> LineResult<()> {
        if self.frames.len() >= self.max_call_depth {
            return Err(LineError::new(
                b.spans(0, b.toks.len() - 1),
                format!(
                    "calls nested more than {} deep: expected the calls to return",
                    self.max_call_depth
                ),
                "call depth",
            )
            .help("the limit is the reader option max_call_depth (docs/gcode.md)"));
        }
        self.frames.push(f);
        Ok(())
    }

    /// `CALL PGM file`: the file (beside the calling program, or on the search path) runs to
    /// its `END PGM`, then the caller goes on.
    fn call_program(&mut self, b: &Block, here: Cursor) -> LineResult<()> {
        // A drive or folder prefix (`TNC:\\parts\\plan.h`): the file name is looked up.
        let name = b.tok(2).trim_matches('"');
        let name = name.rsplit(['\\', '/']).next().unwrap_or(name);
        if name.is_empty() {
            return Err(LineError::new(
                b.spans(0, 1),
                "CALL PGM without a file: expected `CALL PGM name`",
                "no file",
            ));
        }
        let dir = self.programs[here.file]
            .path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let mut candidates = Vec::new();
        for d in std::iter::once(&dir).chain(&self.search_path) {
            candidates.push(d.join(name));
            if Path::new(name).extension().is_none() {
                candidates.push(d.join(format!("{name}.h")));
                candidates.push(d.join(format!("{name}.H")));
            }
        }
        let found = candidates.iter().find(|p| p.is_file()).cloned();
        let Some(path) = found else {
            return Err(LineError::new(
                b.span(2),
                format!("`CALL PGM {name}`: no such file beside the program or on the search path"),
                "file not found",
            ));
        };
        let file = match self.programs.iter().position(|p| p.path == path) {
            Some(k) => k,
            None => {
                let lines = FileLines::open(&path).map_err(|e| {
                    LineError::new(
                        b.span(2),
                        format!("`CALL PGM {name}`: cannot read {}: {e}", path.display()),
                        "unreadable file",
                    )
                })?;
                self.programs.push(Program {
                    path,
                    source: Source::File(lines),
                    labels: None,
                });
                self.programs.len() - 1
            }
        };
        let target = Cursor {
            file,
            offset: 0,
            line: 1,
        };
        self.push_frame(
            b,
            Frame {
                ret: self.cursor,
                call: here,
                call_span: b.spans(0, b.toks.len() - 1),
                target,
                repeats: 0,
                program: true,
            },
        )?;
        self.cursor = target;
        Ok(())
    }

    /// At `END PGM` or the end of a file: back to the caller of a called program.
    fn ret_from_program(&mut self) -> bool {
        while let Some(f) = self.frames.pop() {
            if f.program {
                self.cursor = f.ret;
                return true;
            }
        }
        false
    }

    /// The line after `LBL label` in `file`.
    fn find_label(&mut self, file: usize, label: &str, span: Range<usize>) -> LineResult<Cursor> {
        if self.programs[file].labels.is_none() {
            let mut map = HashMap::new();
            let mut c = Cursor {
                file,
                offset: 0,
                line: 1,
            };
            let mut buf = String::new();
            while let Ok(Some((line, len))) = self.programs[file].source.line(c.offset, &mut buf) {
                let next = Cursor {
                    file,
                    offset: c.offset + len,
                    line: c.line + 1,
                };
                let rest = &line[text::after_block_number(line)..];
                let (body, _) = text::strip_comment(rest);
                let mut words = body.split_whitespace();
                // `LBL 1`, or `LBL1` as some posts write it.
                let first = words.next().unwrap_or("");
                let glued = first
                    .get(..3)
                    .filter(|k| k.eq_ignore_ascii_case("LBL") && first.len() > 3)
                    .map(|_| &first[3..]);
                let name = match glued {
                    Some(l) => Some(l),
                    None if first.eq_ignore_ascii_case("LBL") => words.next(),
                    None => None,
                };
                {
                    if let Some(l) = name {
                        let key = if l.starts_with('"') {
                            l.trim_matches('"').to_string()
                        } else {
                            l.parse::<f64>().map_or(l.to_string(), |v| format!("{v}"))
                        };
                        map.entry(key).or_insert(next);
                    }
                }
                c = next;
            }
            self.programs[file].labels = Some(map);
        }
        self.programs[file]
            .labels
            .as_ref()
            .and_then(|m| m.get(label).copied())
            .ok_or_else(|| {
                LineError::new(
                    span,
                    format!("no `LBL {label}` in this program"),
                    "unknown label",
                )
            })
    }

    /// A backward jump or call from the block at `here`: the construct a spent budget names
    /// (the blocks themselves are counted as they are read, in `step`).
    fn backward(&mut self, here: Cursor, span: Range<usize>) {
        self.repeating = Some((here, span));
    }

    /// `CYCL CALL [F] [M…]`: the defined cycle here.
    fn cycle_call(&mut self, b: &Block) -> LineResult<()> {
        if b.is(2, "POS") {
            return cycle_pos::call(self, b);
        }
        if b.is(2, "PAT") {
            return pattern::call(self, b);
        }
        let mut e = Extras::default();
        for k in 2..b.toks.len() {
            let (name, _) = text::split_word(b.tok(k));
            if name.eq_ignore_ascii_case("F") {
                continue;
            }
            if !contour::m_word(self, b, k, &mut e)? {
                return Err(unexpected(b, k, "CYCL CALL", "F or M functions"));
            }
        }
        cycles::call(self, b)?;
        contour::run_extras(self, b, &e, None)
    }

    /// A block of M functions alone (`M5`, `STOP M0`).
    fn m_only(&mut self, b: &Block, from: usize) -> LineResult<()> {
        let mut m = Extras::default();
        for k in from..b.toks.len() {
            let (name, _) = text::split_word(b.tok(k));
            if m.m140.is_some() && name.eq_ignore_ascii_case("F") {
                // `M140 MB 50 F750`: the retraction's feed.
                self.note(
                    b,
                    "M140 … F: mtsim retracts at rapid, not at the block's feed",
                );
                continue;
            }
            if !contour::m_word(self, b, k, &mut m)? {
                return Err(unexpected(b, k, "an M block", "M functions"));
            }
        }
        contour::run_extras(self, b, &m, None)
    }

    /// The approach held by `APPR`, now that the first element's tangent `t` at P_A is
    /// known (`None`: an element outside the plane X Y); contour elements call it.
    fn approach(&mut self, b: &Block, t: Option<[f64; 2]>) -> LineResult<()> {
        approach::run(self, b, t)
    }

    /// Runs the rest of the words of a held line, if any.
    fn release_held(&mut self, b: &Block) -> LineResult<()> {
        contour::release(self, b)
    }

    /// A notice, once per message.
    fn note(&mut self, b: &Block, message: &str) {
        if !self.noticed.iter().any(|m| m == message) {
            self.noticed.push(message.to_string());
            self.notices.push(Notice {
                path: self.programs[self.cursor.file].path.clone(),
                line: b.line,
                message: message.to_string(),
                warning: false,
            });
        }
    }

    // Word emission: the words of one interpreter block, then `end_block`.

    fn word(&mut self, letter: char, value: f64, span: Range<usize>) {
        self.words.push(Word {
            letter,
            value,
            number: "",
            span: (span.start, span.end),
        });
    }

    /// A G word; `code` as written (`"1"`, `"41.1"`).
    fn gword(&mut self, code: &'static str, span: Range<usize>) {
        let value = match code {
            "0" => 0.0,
            "1" => 1.0,
            "2" => 2.0,
            "3" => 3.0,
            _ => code.parse().unwrap_or(0.0),
        };
        self.words.push(Word {
            letter: 'G',
            value,
            number: code,
            span: (span.start, span.end),
        });
    }

    fn end_block(&mut self, line_no: usize) {
        let end = self.words.len();
        let last = self.ends.last().map_or(0, |e| e.0);
        if end > last {
            self.ends.push((end, line_no));
        }
    }

    /// The interpreter's program position, after a block that moved in a way the front end
    /// does not follow (machine coordinates, a frame change).
    fn sync_position(&mut self, b: &Block) -> LineResult<()> {
        self.run_words_line(Cursor {
            file: self.cursor.file,
            offset: 0,
            line: b.line,
        })?;
        let p = self.program_position();
        self.path.set_position(p);
        Ok(())
    }

    /// The interpreter's program position in the program's coordinates (before the
    /// mirror image and scaling, `transform`).
    fn program_position(&self) -> crate::axis::AxisVec {
        use crate::axis::Axis;
        let mut p = self.interp.program_position();
        let q = self
            .frames_state
            .map
            .inverse([p[Axis::X], p[Axis::Y], p[Axis::Z]]);
        (p[Axis::X], p[Axis::Y], p[Axis::Z]) = (q[0], q[1], q[2]);
        p
    }
}

impl Iterator for Reader {
    type Item = Result<Move>;

    fn next(&mut self) -> Option<Result<Move>> {
        loop {
            if let Some(m) = self.queue.pop_front() {
                return Some(Ok(m));
            }
            if self.finished {
                if !self.flushed {
                    self.flushed = true;
                    self.interp.finish(&mut self.queue);
                    continue;
                }
                return None;
            }
            if let Err(e) = self.step() {
                self.queue.clear();
                self.interp.discard();
                self.flushed = true;
                self.finished = true;
                return Some(Err(e));
            }
        }
    }
}

/// Checks a label mark: `LBL n` or `LBL "name"` (the label at token `at` = 1), or `LBL1`
/// glued (`at` = 0), and nothing after it: a repeat written on the mark, or a mark without
/// its label, is refused, never read as a mark. A quoted name may hold spaces.
fn label_mark(b: &Block, at: usize) -> LineResult<()> {
    let label = b.tok(at);
    if at == 1 {
        if label.is_empty() {
            return Err(LineError::new(
                b.span(0),
                "`LBL`: expected a label number or \"name\"".to_string(),
                "expected a label",
            ));
        }
        if label.starts_with('"') {
            return Ok(());
        }
        if label.parse::<f64>().is_err() {
            return Err(LineError::new(
                b.span(1),
                format!("`{label}`: expected a label number or \"name\""),
                "expected a label",
            ));
        }
    }
    let after = b.tok(at + 1);
    if after.is_empty() {
        return Ok(());
    }
    let mark = if at == 1 {
        format!("LBL {label}")
    } else {
        label.to_string()
    };
    Err(LineError::new(
        b.span(at + 1),
        format!(
            "`{after}` after `{mark}`: a label takes nothing after its number or \"name\" \
             (a repeat is `CALL {mark} REP n`)"
        ),
        "nothing may follow",
    ))
}
