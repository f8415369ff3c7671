//! The seam between a control's program language and the rest of the crate: a front end
//! turns one program's text into the canonical moves of the shared interpreter.
//!
//! ```text
//!  read_with ─► FRONT_ENDS (crate `reader`), asked in order ─► the first that claims the
//!  program (by the dialect named, or by the program's first line) opens it ─► Box<dyn
//!  FrontEnd> ─► Move, Move, … (or one error, then the end)
//! ```
//!
//! Each dialect family implements [`FrontEnd`] in its own folder and exports one
//! [`Registration`]: the ISO G-code family (LinuxCNC, Fanuc, Haas) in `reader/`, HEIDENHAIN
//! Klartext in `heidenhain/`, Siemens Sinumerik in `siemens/`. A new control is a new folder
//! and one line in the list `reader::FRONT_ENDS` (and its name in [`Dialect`]).

use std::path::Path;

use crate::canon::Move;
use crate::error::Result;
use crate::notice::Notice;
use crate::options::{Dialect, Options};
use crate::source::{FileLines, Source};

/// One program being read by a control's front end.
pub(crate) trait FrontEnd {
    /// The next move, or the error that ends the program; `None` after the end (or after
    /// the error).
    fn next_move(&mut self) -> Option<Result<Move>>;

    /// The next move, lent: as [`FrontEnd::next_move`], kept in `slot` until the next call.
    /// A front end that holds its moves in a queue of its own lends them in place instead
    /// (the move is large; docs/performance.md).
    fn next_ref<'a>(&'a mut self, slot: &'a mut Option<Move>) -> Option<Result<&'a Move>> {
        match self.next_move()? {
            Ok(m) => Some(Ok(slot.insert(m))),
            Err(e) => Some(Err(e)),
        }
    }

    /// What was accepted without being simulated, so far.
    fn notices(&self) -> &[Notice];
}

/// The program a front end opens.
pub(crate) enum Input {
    /// The file at the program's path, not opened yet.
    File,
    /// The program's text, in memory or as a file already opened for streaming.
    Source(Source),
}

impl Input {
    /// The program as lines at byte offsets (crate `source`): the file opened now if it was
    /// not.
    pub(crate) fn into_source(self, path: &Path) -> std::io::Result<Source> {
        match self {
            Input::File => Ok(Source::File(FileLines::open(path)?)),
            Input::Source(source) => Ok(source),
        }
    }
}

/// How a front end is found and opened: the entry a dialect family adds to
/// `reader::FRONT_ENDS`.
pub(crate) struct Registration {
    /// True for the dialects this front end reads (the options' `dialect`).
    pub(crate) dialect: fn(Dialect) -> bool,
    /// True when the program's file name or its first line with more than blanks opens a
    /// program of this language, whatever the dialect named (`None`: no such sign).
    pub(crate) first_line: Option<fn(&Path, &str) -> bool>,
    /// The front end reading the program at `path`.
    pub(crate) open: fn(&Path, Input, &Options) -> std::io::Result<Box<dyn FrontEnd>>,
}
