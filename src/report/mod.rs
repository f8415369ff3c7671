//! **report** — sinks and writers: results in, files out.
//! Inputs: samples (the trace), ball-bar results, check reports.
//! Outputs: CSV, JSON, Parquet and SVG files, each written completely or not at all (temporary file, then rename).

pub mod files;
pub mod fit_plot;
pub mod fixed;
pub mod html;
pub mod parquet;
pub mod plot;
pub mod polar;
pub mod run;
pub mod test_info;
pub mod trace;
pub mod xxh64;

pub use files::{create_dir, temporary_path, write_atomic};
pub use fixed::push_fixed;
