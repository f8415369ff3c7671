//! The program stage (`src/program/`, and the `ngc` crate's reader through it): the
//! canonical moves `mtsim` reads from G-code, against LinuxCNC's `rs274`, its sample programs
//! and values worked out by hand; the scenario's `[reader]` options; programs it cannot read.

#[path = "../common/mod.rs"]
mod common;

mod blocks;
mod bounded;
mod conformance;
mod corpus;
mod cross_dialect;
mod file_analysis;
mod heidenhain_corpus;
mod reader_options;
mod rotary_travel;
mod shared_corpus;
mod siemens_corpus;
mod test_programs;
mod unreadable;
