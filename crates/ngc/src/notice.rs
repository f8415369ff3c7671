//! What the reader reports beside its moves: things accepted but not simulated.

use std::path::PathBuf;

/// Something the reader accepted but did not simulate (a user M code, a message).
#[derive(Clone, Debug, PartialEq)]
pub struct Notice {
    pub path: PathBuf,
    pub line: usize,
    pub message: String,
    /// A warning (the program may be read at the wrong scale), not only a code accepted
    /// without effect on the motion.
    pub warning: bool,
}
