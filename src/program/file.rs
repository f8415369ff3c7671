//! G-code files, read by the `ngc` interpreter crate, as a stream of canonical moves.
//!
//! The scenario's reader options (dialect, machine axes, tools, work offsets, subroutine
//! path, user M codes, and the machine's rotary table for G68.2/G53.1 and G254) go to the
//! interpreter unchanged; `Options::default()` starts from all
//! axes at zero, as the machine position before a program runs is not known.

use std::path::Path;

use super::moves::Moves;
use crate::error::Result;

/// Streams the moves of the file at `path`; memory does not grow with the number of moves.
pub fn read_file(path: &Path, options: &ngc::Options) -> Result<Moves<'static>> {
    let moves = ngc::read_file_with(path, options)?;
    Ok(Box::new(moves.map(|m| m.map_err(Into::into))))
}

/// The interpreter's own stream of the file at `path`, its errors not yet converted (for
/// [`super::validate::checked`], which converts them without a layer of its own).
pub fn read_moves(path: &Path, options: &ngc::Options) -> Result<ngc::Moves> {
    Ok(ngc::read_file_with(path, options)?)
}

/// Streams the moves of `text`, reported as the contents of `path`, with default options.
pub fn read_str<'a>(path: &'a Path, text: &'a str) -> Moves<'a> {
    Box::new(ngc::read_str(path, text, ngc::AxisVec::ZERO).map(|m| m.map_err(Into::into)))
}

/// The reader's warnings about the file at `path`. The one warning there is, a program that
/// moves before it states its units, is given with the first block that queues a move, so
/// the read stops at the first move: a command that only prints warnings does not read the
/// whole program once more.
pub fn warnings(path: &Path, options: &ngc::Options) -> Result<Vec<ngc::Notice>> {
    let mut moves = ngc::read_file_with(path, options)?;
    let _ = moves.next();
    Ok(moves
        .notices()
        .iter()
        .filter(|n| n.warning)
        .cloned()
        .collect())
}
