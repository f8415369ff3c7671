//! The stream of canonical moves that every program source yields.

use crate::error::Result;
use ngc::Move;

/// A stream of canonical moves; yields at most one error, then stops.
pub type Moves<'a> = Box<dyn Iterator<Item = Result<Move>> + 'a>;
