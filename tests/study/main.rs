//! Studies (`src/study/`): `simulate` end to end, the diagnoses and `fit` against injected
//! errors, and the cone-frustum results of the literature (Kato et al.) reproduced.

#[path = "../common/mod.rs"]
mod common;

mod budget;
mod budget_geometry;
mod circle_feed;
mod cone_reference;
mod cut_budget;
mod cut_marks;
mod diagnose;
mod fit;
mod fit_chain;
mod fit_coverage;
mod fit_squareness;
mod kato_reproduction;
mod lanes;
mod param_study;
mod simulate;
