//! **study** — beside the pipeline: whole runs and many runs.
//! Inputs: scenarios; the pipeline and its sinks; the analytic cone path.
//! Outputs: reversal analyses, `simulate` runs with their files, sweeps over a parameter and placement maps.

pub mod diagnose;
pub mod feed;
pub mod placement;
pub mod reversals;
pub mod simulate;
pub mod sweep;
