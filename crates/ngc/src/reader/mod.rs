//! The reader: a program's text in, its canonical moves out, through the front end of its
//! control's language, chosen once (crate `front_end`).
//!
//! ```text
//! read_*_with ─► FRONT_ENDS, in order: Siemens (dialect), Klartext (dialect or `BEGIN PGM`
//!                on the first line), the ISO G-code family (every other program)
//!             ─► Box<dyn FrontEnd> ─► Moves (an iterator of Move, or one error)
//! ```
//!
//! The ISO G-code family's front end lives here:
//!
//! ```text
//! text ─► line ─► o-word / macro statement? ─► flow (jump, loop: flow.rs; call: calls.rs)
//!                └► lex (words, assignments) ─► remap? (remap.rs) ─► interp ─► Move queue
//! ```
//!
//! (`stream.rs` the streaming core, `oword.rs` the o-word and macro line syntax,
//! `language.rs` the foreign-language screen and tape leader, `state.rs` the state they
//! share.) A program file is streamed line by line through a fixed buffer: jumps (loops,
//! calls, GOTO) seek back to a byte offset, as LinuxCNC re-reads its file by offset, and the
//! subroutine index keeps offsets, not text. Subroutine files are streamed the same way.
//! Moves are streamed, never collected, so memory grows neither with the file nor with the
//! moves. A line longer than [`MAX_LINE_BYTES`](crate::MAX_LINE_BYTES) is a read error, and
//! only regular files are read (a device such as `/dev/zero`, a FIFO or a folder is
//! refused). Every executed block counts against the reader option `max_blocks` (crate
//! `budget`).

mod calls;
mod corner;
mod fanuc_polar;
mod flow;
mod language;
mod lathe;
mod oword;
mod remap;
mod state;
mod stream;

use std::path::Path;

use crate::axis::AxisVec;
use crate::canon::Move;
use crate::error::{Error, Result};
use crate::front_end::{FrontEnd, Input, Registration};
use crate::notice::Notice;
use crate::options::Options;
use crate::source::Source;

/// The front ends, asked in this order: the first whose dialect is the options' one, or
/// whose language the program's first line opens, reads the program. A new control adds
/// its folder and one line here.
const FRONT_ENDS: [&Registration; 3] = [
    &crate::siemens::FRONT_END,
    &crate::heidenhain::FRONT_END,
    &stream::FRONT_END,
];

/// Streams the moves of a file with default options, from `start`.
pub fn read_file(path: &Path, start: AxisVec) -> Result<Moves> {
    read_file_with(
        path,
        &Options {
            start,
            ..Options::default()
        },
    )
}

/// Streams the moves of `text`, reported as the contents of `path`, with default options.
pub fn read_str(path: &Path, text: &str, start: AxisVec) -> Moves {
    read_str_with(
        path,
        text,
        &Options {
            start,
            ..Options::default()
        },
    )
}

/// Streams the moves of the file at `path`, reading it line by line (memory does not grow
/// with the file).
pub fn read_file_with(path: &Path, options: &Options) -> Result<Moves> {
    read_with(path, Input::File, options).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })
}

/// Streams the moves of `text`, reported as the contents of `path`.
pub fn read_str_with(path: &Path, text: &str, options: &Options) -> Moves {
    read_with(path, Input::Source(Source::Text(text.into())), options)
        .expect("a text source opens no file")
}

/// The program at `path` read by the first of [`FRONT_ENDS`] that claims it: by the
/// dialect named, or else by its file name and first line with more than blanks (read once,
/// only when a front end asks).
fn read_with(path: &Path, input: Input, options: &Options) -> std::io::Result<Moves> {
    let mut input = input;
    let mut first: Option<Option<String>> = None;
    for front in FRONT_ENDS {
        let mut claimed = (front.dialect)(options.dialect);
        if let (false, Some(opens)) = (claimed, front.first_line) {
            if first.is_none() {
                let source = std::mem::replace(&mut input, Input::File).into_source(path)?;
                let (source, line) = first_line(source);
                input = Input::Source(source);
                first = Some(line);
            }
            claimed = first
                .as_ref()
                .is_some_and(|l| l.as_deref().is_some_and(|l| opens(path, l)));
        }
        if claimed {
            return Ok(Moves {
                front: (front.open)(path, input, options)?,
                slot: None,
            });
        }
    }
    unreachable!("the ISO front end, last, claims every program")
}

/// The first line of `source` with more than blanks (`None` when there is none or it
/// cannot be read; the front end then meets the read error itself), and the source.
fn first_line(mut source: Source) -> (Source, Option<String>) {
    let mut buf = String::new();
    let mut offset = 0;
    let found = loop {
        match source.line(offset, &mut buf) {
            Ok(Some((line, len))) => {
                if !line.trim().is_empty() {
                    break Some(line.to_string());
                }
                offset += len;
            }
            _ => break None,
        }
    };
    (source, found)
}

/// The canonical moves of a program, in order, from its control's front end. Yields `Err`
/// at most once, then `None`; stops after M02, M30 or a closing `%` (or the front end's
/// end of program).
pub struct Moves {
    front: Box<dyn FrontEnd>,
    /// A move lent by [`Moves::next_ref`] from a front end that hands moves out by value.
    slot: Option<Move>,
}

impl Moves {
    /// What was accepted without being simulated (user M codes, at most one notice per
    /// code), so far.
    pub fn notices(&self) -> &[Notice] {
        self.front.notices()
    }

    /// The next move, lent in place: as [`Iterator::next`], without moving the (large) move
    /// out of the reader's queue; it leaves the queue at the next call of either.
    pub fn next_ref(&mut self) -> Option<Result<&Move>> {
        self.front.next_ref(&mut self.slot)
    }
}

impl Iterator for Moves {
    type Item = Result<Move>;

    fn next(&mut self) -> Option<Result<Move>> {
        self.front.next_move()
    }
}
