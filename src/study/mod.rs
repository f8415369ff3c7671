//! **study** — beside the pipeline: whole runs and many runs.
//! Inputs: scenarios; the pipeline and its sinks; the analytic cone path.
//! Outputs: reversal analyses, `simulate` runs with their files, sweeps, placement maps and batches, whole or in shards.

pub mod analysis;
pub mod batch;
pub mod budget;
pub mod chain_events;
pub mod contour_budget;
pub mod cut;
pub mod cut_budget;
pub mod diagnose;
pub mod feed;
pub mod fit;
pub mod geometry;
pub mod lanes;
pub mod lost_motion;
pub mod param;
pub mod placement;
pub mod reversals;
pub mod shard;
pub mod simulate;
pub mod sweep;
