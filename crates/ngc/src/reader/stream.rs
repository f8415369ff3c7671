//! The streaming core of the ISO family's reader: a line at the cursor, its o-word or macro
//! statement or its words (lexed into a reused buffer), the interpreter's block, and the
//! queue of moves it fills. Every line read counts against the block budget.

use std::collections::VecDeque;
use std::path::Path;
use std::rc::Rc;

use crate::budget::Budget;
use crate::canon::Move;
use crate::error::{Error, Result};
use crate::expr::Params;
use crate::interp::{Interp, Stop};
use crate::lex::{lex_with, Lexed, LineError, LineResult, ParamSource, Word};
use crate::notice::Notice;
use crate::options::Options;
use crate::source::Source;

use super::oword::{after_line_number, macro_line_at, oline};
use super::state::{Cursor, IsoReader, Program};
use crate::front_end::{FrontEnd, Registration};

impl IsoReader {
    pub(super) fn new(path: &Path, source: Source, options: &Options) -> IsoReader {
        IsoReader {
            programs: vec![Program {
                path: path.to_path_buf(),
                source,
                subs: None,
            }],
            cursor: Cursor {
                file: 0,
                offset: 0,
                line: 1,
            },
            interp: Interp::new(options),
            dialect: options.dialect,
            search_path: options.search_path.clone(),
            queue: VecDeque::new(),
            lent: false,
            frames: Vec::new(),
            loops: Vec::new(),
            ifs: Vec::new(),
            budget: Budget::new(options.max_blocks),
            repeating: None,
            max_call_depth: options.max_call_depth,
            finished: false,
            flushed: false,
            percent_seen: false,
            language_checked: false,
            notices: Vec::new(),
            buf: String::new(),
            words: Vec::new(),
            io_error: None,
            remaps: options.remaps.clone(),
            resume: None,
            remaps_noticed: Vec::new(),
            abort: None,
            commit: None,
            modal_remap: None,
            sticky: Default::default(),
            lathe: Default::default(),
            whole_increments: match options.control.whole_numbers {
                Some(w) => w == crate::WholeNumbers::Increments,
                None => options.dialect.table().whole_numbers_are_increments,
            },
            whole_warned: false,
            mirror_scale: Default::default(),
            corner: None,
            fanuc_polar: Default::default(),
        }
    }

    /// Reads on until a move is queued, the program ends, or an error.
    pub(super) fn step(&mut self) -> Result<()> {
        if !self.language_checked {
            self.language_checked = true;
            if let Some(e) = self.foreign_language() {
                self.finished = true;
                return Err(e);
            }
            if self.dialect.table().leader_before_percent {
                self.skip_leader();
            }
        }
        if let Some((here, span, message)) = self.abort.take() {
            self.finished = true;
            return Err(self.error_at(here, LineError::new(span, message, "remap epilog"), ""));
        }
        if let Some(c) = self.commit.take() {
            self.interp.glue_commit(&c);
        }
        if let Some(r) = self.resume.take() {
            let line = r.line.as_str();
            let words: Vec<Word> = r
                .words
                .iter()
                .map(|(letter, value, number, span)| Word {
                    letter: *letter,
                    value: *value,
                    number: &line[number.clone()],
                    span: *span,
                })
                .collect();
            let next = self.cursor;
            // The rest of the block may hold further remapped codes (`S300 M3 F50` with S
            // and F remapped: F, then S, then M3).
            let split = if self.remaps.is_empty() {
                Ok(None)
            } else {
                let busy: Vec<usize> = self.frames.iter().filter_map(|f| f.remap).collect();
                crate::remap::split(&self.remaps, &words, line, &busy, self.modal_remap)
            };
            let result = split.and_then(|s| match s {
                Some(s) => self.run_remap(line, &words, s, r.here, next),
                None => self.run_block(line, &words, r.here, next),
            });
            return result.map_err(|e| {
                self.finished = true;
                self.error_at(r.here, e, line)
            });
        }
        let here = self.cursor;
        let Some((line, next)) = self.line_at(here) else {
            if let Some(e) = self.io_error.take() {
                self.finished = true;
                return Err(Error::Read {
                    path: self.programs[here.file].path.clone(),
                    source: e,
                });
            }
            if let Some(e) = self.unclosed() {
                self.finished = true;
                return Err(e);
            }
            if let Some(f) = self.frames.last() {
                if self.programs[f.start.file].is_empty() || f.start.file != 0 {
                    // A Fanuc subprogram file without M99 returns at its end.
                    if self.dialect.table().macro_b && self.ret(None) {
                        return Ok(());
                    }
                }
            }
            self.finished = true;
            return Ok(());
        };
        let len = line.len();
        if !self.budget.spend_at(here.file == 0, here.offset) {
            self.finished = true;
            let (at, span) = self.repeating.clone().unwrap_or((here, 0..len));
            let line = if at == here {
                self.buf_line(here, len)
            } else {
                String::new()
            };
            return Err(self.error_at(at, self.budget.spent(span), &line));
        }
        // Own the line while the interpreter changes state: share the text (a reference
        // count, no copy), or take the file's line buffer (given back below).
        let owner = match &self.programs[here.file].source {
            Source::Text(text) => LineOwner::Shared(Rc::clone(text)),
            Source::File(_) => LineOwner::Buffer(std::mem::take(&mut self.buf)),
        };
        let line = match &owner {
            LineOwner::Shared(text) => &text[here.offset..here.offset + len],
            LineOwner::Buffer(buf) => buf.as_str(),
        };
        // Field by field (docs/performance.md); the file is the same.
        self.cursor.offset = next.offset;
        self.cursor.line = next.line;
        let result = self.line(line, here, next).map_err(|e| {
            self.finished = true;
            self.error_at(here, e, line)
        });
        if let LineOwner::Buffer(buf) = owner {
            self.buf = buf;
        }
        if result.is_ok() {
            if let Some(e) = self.io_error.take() {
                self.finished = true;
                return Err(Error::Read {
                    path: self.programs[here.file].path.clone(),
                    source: e,
                });
            }
        }
        result?;
        Ok(())
    }

    pub(super) fn line(&mut self, line: &str, here: Cursor, next: Cursor) -> LineResult<()> {
        let b = line.as_bytes();
        let first = after_line_number(b);
        match b.get(first) {
            Some(b'o' | b'O') => {
                if let Some(o) = oline(line)? {
                    self.o_word(line, o, here, next)?;
                    return Ok(());
                }
            }
            Some(b'/') => return Ok(()),
            Some(c) if self.dialect.table().macro_b && c.is_ascii_alphabetic() => {
                if let Some((m, at, rest)) = macro_line_at(line, first) {
                    return self.macro_statement(line, m, at, rest, here, next);
                }
            }
            _ => {}
        }
        let words = reuse(std::mem::take(&mut self.words));
        // The system parameters are brought up to date only for a line that holds `#` or
        // `[` (crate::lex::ParamSource), found as the lexer meets it.
        let params = Refreshing {
            interp: &mut self.interp,
            fresh: false,
        };
        let lexed = lex_with(line, params, self.dialect.table().macro_b, words)?;
        match lexed {
            Lexed::Nothing => Ok(()),
            Lexed::Percent => {
                if self.percent_seen {
                    self.finished = true;
                } else {
                    self.percent_seen = true;
                }
                Ok(())
            }
            Lexed::Words { mut words, assigns } => {
                // No step below adds a corner word or one of these G codes (docs/performance.md
                // "Session 27"): what the block lacks now it lacks there.
                let rare = rare_words(&words);
                if self.whole_increments {
                    self.scale_whole_numbers(line, &mut words, here);
                }
                let corner = if rare.corner {
                    self.corner_word(line, &mut words)?
                } else {
                    None
                };
                if !assigns.is_empty() {
                    for (p, v) in &assigns {
                        self.interp.check_assign(line, p, *v)?;
                        self.interp.params.set(p, *v);
                    }
                    self.interp.parameters_changed();
                }
                if words.is_empty() {
                    self.words = reuse(words);
                    return Ok(());
                }
                if self.dialect.table().macro_b
                    && self.fanuc_polar_block(line, &mut words, rare.polar)?
                {
                    self.words = reuse(words);
                    return Ok(());
                }
                if self.dialect.table().macro_b
                    && self.mirror_scale_block(line, &mut words, rare.mirror_scale)?
                {
                    self.words = reuse(words);
                    return Ok(());
                }
                let remap = if self.remaps.is_empty() {
                    None
                } else {
                    let busy: Vec<usize> = self.frames.iter().filter_map(|f| f.remap).collect();
                    if !busy.is_empty() && crate::remap::uses_builtin(&self.remaps, &words, &busy) {
                        if let Some(e) = self
                            .frames
                            .iter_mut()
                            .rev()
                            .find(|f| f.remap.is_some())
                            .and_then(|f| f.epilog.as_mut())
                        {
                            e.builtin_used = true;
                        }
                    }
                    if self.modal_remap.is_some() && crate::remap::sets_motion(&words) {
                        self.modal_remap = None;
                    }
                    crate::remap::split(&self.remaps, &words, line, &busy, self.modal_remap)?
                };
                let before = self.queue.len();
                let result = match remap {
                    Some(s) => self.run_remap(line, &words, s, here, next),
                    None => self.run_block_of(line, &words, here, next, rare.lathe_cycle),
                };
                self.words = reuse(words);
                // Not `result`: that copied the whole (large) result on every block.
                result?;
                if corner.is_some() || self.corner.is_some() {
                    self.corner_after(line, corner, before, here)?;
                }
                Ok(())
            }
        }
    }

    /// Dimension words written without a decimal point, in the least input increment
    /// (crate::decimal_point); a warning at the first nonzero one.
    fn scale_whole_numbers(&mut self, line: &str, words: &mut [Word], here: Cursor) {
        let mut context = self.interp.whole_number_context(words);
        context.polar_angle = self.polar_angle_letter(words);
        let first = crate::decimal_point::scale_whole_numbers(words, context);
        if let (Some(word), false) = (first, self.whole_warned) {
            self.whole_warned = true;
            self.notices.push(crate::notice::Notice {
                path: self.programs[here.file].path.clone(),
                line: here.line,
                message: crate::decimal_point::warning(&word, line, context),
                warning: true,
            });
        }
    }

    /// The mirror image and scaling (crate::mirror_scale): true when the block set or
    /// cancelled them (nothing more to do), else its words mapped where they are in effect.
    /// `codes`: the block may set or cancel them ([`RareWords::mirror_scale`]).
    fn mirror_scale_block(
        &mut self,
        line: &str,
        words: &mut [Word],
        codes: bool,
    ) -> LineResult<bool> {
        let haas = self.dialect == crate::options::Dialect::Haas;
        if self.interp.is_lathe() && words.iter().any(|w| w.letter == 'G' && w.value == 50.0) {
            // A lathe's G50 sets the work coordinate system or the spindle speed limit
            // (crate::interp, `lathe_codes`): no scaling there.
            return Ok(false);
        }
        let interp = &self.interp;
        let here = || {
            let p = interp.program_position();
            [p[crate::Axis::X], p[crate::Axis::Y], p[crate::Axis::Z]]
        };
        if codes && self.mirror_scale.command(line, words, haas, here)? {
            return Ok(true);
        }
        if self.mirror_scale.active() {
            let context = self.interp.mirror_scale_context();
            self.mirror_scale.apply(line, words, context)?;
        } else {
            self.mirror_scale.note_unmapped(words);
        }
        Ok(false)
    }

    /// Interprets one block's words and follows its stop (end, call, return).
    pub(super) fn run_block(
        &mut self,
        line: &str,
        words: &[Word],
        here: Cursor,
        next: Cursor,
    ) -> LineResult<()> {
        self.run_block_of(line, words, here, next, true)
    }

    /// [`IsoReader::run_block`], told whether the block may be a lathe cycle
    /// ([`RareWords::lathe_cycle`]): when it cannot, its words are not looked through again.
    fn run_block_of(
        &mut self,
        line: &str,
        words: &[Word],
        here: Cursor,
        next: Cursor,
        may_be_lathe_cycle: bool,
    ) -> LineResult<()> {
        if may_be_lathe_cycle && self.dialect.table().macro_b {
            if let Some(cycle) = super::lathe::LatheCycle::of(words) {
                return self.lathe_cycle(cycle, line, words, here);
            }
        }
        let stop = self.interp.block(
            line,
            words,
            here.line,
            &mut self.queue,
            &mut self.notices,
            &self.programs[here.file].path,
        )?;
        match stop {
            Stop::None => {}
            Stop::End => self.finished = true,
            Stop::Call {
                label,
                repeats,
                args,
                locals,
                span,
            } => {
                self.call(&label, &args, locals, repeats, here, next, span)?;
            }
            Stop::Return { span } => {
                if !self.ret(None) {
                    if self.dialect.table().macro_b {
                        // M99 in the main program: one pass, said so (the control restarts
                        // it, from N<P> with a P word, until the operator stops it).
                        self.finished = true;
                        self.notices.push(crate::notice::Notice {
                            path: self.programs[here.file].path.clone(),
                            line: here.line,
                            message: "M99 in the main program: the control runs it again (from \
                                      the N of its P word, or the start) until stopped; mtsim \
                                      simulates one pass and ends here"
                                .to_string(),
                            warning: true,
                        });
                    } else {
                        return Err(LineError::new(
                            span,
                            "M99 outside a subprogram",
                            "no subprogram",
                        ));
                    }
                }
            }
            Stop::SaveForReturn(saved) => {
                if let Some(f) = self.frames.last_mut() {
                    f.restore = Some(saved);
                }
            }
        }
        Ok(())
    }

    /// Reads on until a move is queued (`Ok` with an empty queue: the program has ended).
    /// After an error the queue is empty and the reader done.
    pub(super) fn fill_queue(&mut self) -> Result<()> {
        while self.queue.is_empty() {
            if self.finished {
                if let Some(e) = self.corner_unfinished() {
                    self.queue.clear();
                    self.interp.discard();
                    self.flushed = true;
                    return Err(e);
                }
                if self.flushed {
                    return Ok(());
                }
                // A compensated element still held ends as at G40.
                self.flushed = true;
                self.interp.finish(&mut self.queue);
                continue;
            }
            if let Err(e) = self.step() {
                self.queue.clear();
                self.corner = None;
                self.interp.discard();
                self.flushed = true;
                return Err(e);
            }
        }
        Ok(())
    }
}

/// What a block's words hold that the reader's rarer steps look for, found in one pass
/// (each step looked through the words again, about 200 instructions a block; the lathe
/// cycle's test about 50 more).
#[derive(Clone, Copy, Debug, Default)]
struct RareWords {
    /// A corner rounding or chamfer word (crate::corner).
    corner: bool,
    /// G15 or G16 (crate::fanuc_polar).
    polar: bool,
    /// A code that sets or cancels the mirror image or scaling (crate::mirror_scale:
    /// G50, G51, G50.1, G51.1, G100, G101).
    mirror_scale: bool,
    /// G70, G71 or G72 (a lathe cycle's code, `reader::lathe::LatheCycle::of`, which reads
    /// only `G70`-`G72` as written: in tenths 700, 710, 720).
    lathe_cycle: bool,
}

fn rare_words(words: &[Word]) -> RareWords {
    let mut rare = RareWords::default();
    for w in words {
        match w.letter {
            'G' => match w.g_tenths() {
                Some(150 | 160) => rare.polar = true,
                Some(500 | 501 | 510 | 511 | 1000 | 1010) => rare.mirror_scale = true,
                Some(700 | 710 | 720) => rare.lathe_cycle = true,
                _ => {}
            },
            crate::lex::CORNER_ROUND | crate::lex::CORNER_CHAMFER => rare.corner = true,
            _ => {}
        }
    }
    rare
}

/// An emptied vector of words, its allocation kept, for words that borrow another line.
/// (Collecting a vector's own `into_iter` into the same layout reuses its allocation.)
pub(super) fn reuse<'a, 'b>(mut words: Vec<Word<'a>>) -> Vec<Word<'b>> {
    words.clear();
    words.into_iter().map(|_| Word::EMPTY).collect()
}

/// The line being interpreted, owned apart from the reader's state.
pub(super) enum LineOwner {
    Shared(Rc<str>),
    Buffer(String),
}

/// The interpreter's parameters for the lexer, its system parameters brought up to date at
/// the lexer's first need of them (crate::lex::ParamSource).
struct Refreshing<'a> {
    interp: &'a mut Interp,
    fresh: bool,
}

impl ParamSource for Refreshing<'_> {
    fn params(&mut self) -> &Params {
        self.mentioned();
        &self.interp.params
    }

    fn mentioned(&mut self) {
        if !self.fresh {
            self.fresh = true;
            self.interp.refresh_system_parameters();
        }
    }
}

/// The ISO G-code family reads every dialect no other front end claims: it is the last of
/// `reader::FRONT_ENDS`.
pub(crate) const FRONT_END: Registration = Registration {
    dialect: |_| true,
    first_line: None,
    open: |path, input, options| {
        let source = input.into_source(path)?;
        Ok(Box::new(IsoReader::new(path, source, options)))
    },
};

impl FrontEnd for IsoReader {
    fn next_move(&mut self) -> Option<Result<Move>> {
        if std::mem::take(&mut self.lent) {
            self.queue.pop_front();
        }
        if let Err(e) = self.fill_queue() {
            return Some(Err(e));
        }
        self.queue.pop_front().map(Ok)
    }

    /// The next move, lent in place: without moving the (large) move out of the reader's
    /// queue; it leaves the queue at the next call of either.
    fn next_ref<'a>(&'a mut self, _slot: &'a mut Option<Move>) -> Option<Result<&'a Move>> {
        if std::mem::take(&mut self.lent) {
            self.queue.pop_front();
        }
        if let Err(e) = self.fill_queue() {
            return Some(Err(e));
        }
        self.lent = true;
        self.queue.front().map(Ok)
    }

    fn notices(&self) -> &[Notice] {
        &self.notices
    }
}
