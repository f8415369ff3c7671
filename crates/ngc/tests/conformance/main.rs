//! Against references outside the reader: cutter compensation as LinuxCNC's `rs274` runs
//! it, every conformance program read the same from a file and from memory, and random or
//! mutated programs that give moves or one error, never a panic or a hang.

#[path = "../common/mod.rs"]
mod common;

mod cutter_comp;
mod robustness;
mod streaming;
