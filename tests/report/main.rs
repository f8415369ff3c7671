//! The report stage (`src/report/`): the HTML report (also in a real browser) and the trace
//! written as Parquet.

#[path = "../common/mod.rs"]
mod common;

mod check_html;
mod cut_html;
mod html;
mod trace_parquet;
