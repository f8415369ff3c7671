//! **report** — sinks, writers and pages: results in, files out; nothing is analysed here.
//! Inputs: samples (the trace), typed results (ball-bar result, check report, test parameters, diagnosis).
//! Outputs: CSV, JSON, Parquet, SVG and HTML files, each written completely or not at all (temporary file, then rename).
//!
//! The report is a layer below `study` (`tests/architecture.rs`), so what it renders is typed
//! at its layer or below: the ball bar's [`BallbarResult`](crate::measure::BallbarResult),
//! [`CheckReport`](crate::check::CheckReport), [`test_info::TestParameters`], and, defined
//! here for the caller to fill, [`run::RunSummary`] (the part of `summary.json` a page shows)
//! and [`run::Diagnosis`] (filled by `study::diagnose`). Run folders are read back with serde
//! into those types ([`run::RunFolder`]), traces through [`trace::read_trace`].

pub mod budget_table;
pub mod check_html;
pub mod circle_figures;
pub mod contour;
pub mod cut;
pub mod cut_budget;
pub mod cut_html;
pub mod cut_plots;
pub mod cut_tip;
pub mod escape;
pub mod files;
pub mod fit_plot;
pub mod html;
pub mod manifest;
pub mod parquet;
pub mod plot;
pub mod polar;
pub mod run;
pub mod run_dir;
pub mod test_info;
mod thrift_compact;
pub mod trace;
pub mod trace_centring;
pub mod trace_parquet;
mod trace_rows;
pub mod written;

pub use files::{create_dir, temporary_path, write_atomic};
pub use run_dir::RunDir;
