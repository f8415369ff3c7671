//! G-code files, read by the `ngc` interpreter crate, as a stream of canonical moves.
//!
//! The reader starts from all axes at zero: the machine position before a program runs is
//! not known, so the first move only brings the machine to the program's start.

use std::path::Path;

use super::Moves;
use crate::error::Result;
use crate::AxisVec;

/// Streams the moves of the file at `path`; memory does not grow with its length.
pub fn read_file(path: &Path) -> Result<Moves<'static>> {
    let moves = ngc::read_file(path, AxisVec::ZERO)?;
    Ok(Box::new(moves.map(|m| m.map_err(Into::into))))
}

/// Streams the moves of `text`, reported as the contents of `path`.
pub fn read_str<'a>(path: &'a Path, text: &'a str) -> Moves<'a> {
    Box::new(ngc::read_str(path, text, AxisVec::ZERO).map(|m| m.map_err(Into::into)))
}
