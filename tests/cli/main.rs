//! The command line (`src/cli/`) as users and scripts meet it: JSON shapes, exit codes, error
//! messages (insta snapshots in `snapshots/`), a new user's first runs, sharded runs merged
//! back, the Dask example, and every command the docs show.

#[path = "../common/mod.rs"]
mod common;

mod bad_inputs;
mod bounds;
mod campaign;
mod cut;
mod dask_example;
mod docs_commands;
mod hostile;
mod messages;
mod run_folders;
mod scale_out;
mod scripts;
mod shard_provenance;
mod tcp_option;
mod usability;
