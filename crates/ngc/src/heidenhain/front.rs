//! The Klartext front end's entry in `reader::FRONT_ENDS`: it reads a program of the
//! `heidenhain` dialect, and any program whose first line with more than blanks opens a
//! Klartext program (`BEGIN PGM`), whatever the dialect named.

use super::state::Reader;
use super::text;
use crate::canon::Move;
use crate::error::Result;
use crate::front_end::{FrontEnd, Registration};
use crate::notice::Notice;
use crate::options::{Dialect, Options};

pub(crate) const FRONT_END: Registration = Registration {
    dialect: |d| d == Dialect::Heidenhain,
    first_line: Some(opens_program),
    open: |path, input, options| {
        let source = input.into_source(path)?;
        let options = Options {
            dialect: Dialect::Heidenhain,
            ..options.clone()
        };
        Ok(Box::new(Reader::new(path, source, &options)))
    },
};

/// True when `line`, the first line with more than blanks, opens a Klartext program:
/// `BEGIN PGM`, with or without a block number.
fn opens_program(_path: &std::path::Path, line: &str) -> bool {
    let rest = &line[text::after_block_number(line)..];
    rest.len() >= 9 && rest.as_bytes()[..9].eq_ignore_ascii_case(b"BEGIN PGM")
}

impl FrontEnd for Reader {
    fn next_move(&mut self) -> Option<Result<Move>> {
        Iterator::next(self)
    }

    fn notices(&self) -> &[Notice] {
        Reader::notices(self)
    }
}
