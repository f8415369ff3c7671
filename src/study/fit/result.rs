//! What `fit` reports (fit.json): each parameter's estimate, each trace's fit and noise,
//! the suggestion, warnings. Inputs: none (plain serializable types). Output: [`FitReport`].

use std::path::PathBuf;

use serde::Serialize;

use super::decomposition::NullDirection;
use super::noise::NoiseCheck;

/// A parameter's estimate.
#[derive(Clone, Debug, Serialize)]
pub struct ParamEstimate {
    pub name: String,
    pub unit: String,
    /// The estimate; null when the tests cannot separate this parameter.
    pub value: Option<f64>,
    /// The largest of `standard_error_white`, `standard_error_correlated` and the block
    /// bootstrap's.
    pub standard_error: Option<f64>,
    /// As if the residual were independent from sample to sample.
    pub standard_error_white: Option<f64>,
    /// Under the AR(1) model of each run's residual (correlated noise).
    pub standard_error_correlated: Option<f64>,
    pub identifiable: bool,
    /// What the machine-file fragment carries (the prior for an inseparable pivot).
    pub fragment_value: f64,
}

/// One trace's fit.
#[derive(Clone, Debug, Serialize)]
pub struct TraceFit {
    pub scenario: PathBuf,
    pub measured: PathBuf,
    pub points: usize,
    /// How the trace was matched to its scenario: "commanded" (its commanded axis columns
    /// agree with the scenario's) or "weakly" (no commanded columns: only its directions,
    /// its duration when it has `time_s`, and the fit's bar offset against its own radius
    /// change could be checked).
    pub matched: String,
    /// The trace's own radius change: the peak-to-valley of its deviation, um.
    pub radius_change_um: f64,
    /// Null when the tests cannot separate it (from the placement, for example).
    pub bar_offset_um: Option<f64>,
    /// The bar offset of the fragment's basic solution (carrying any combination), um.
    pub bar_offset_basic_um: f64,
    pub residual_rms_um: f64,
    pub measured_rms_um: f64,
    /// The residual against the noise estimated from the trace.
    pub noise: NoiseCheck,
    /// Block length of the bootstrap, points (largest over the directions).
    pub bootstrap_block_points: usize,
}

/// A suggested additional test.
#[derive(Clone, Debug, Serialize)]
pub struct Suggestion {
    pub half_apex_deg: f64,
    pub inclination_deg: f64,
    pub center_mm: [f64; 3],
    pub ballbar_length_mm: f64,
    /// Inseparable combinations left with this test added (now: `null_dimensions`).
    pub null_dimensions_after: usize,
    pub text: String,
}

/// The result of `fit`, as written to fit.json.
#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    pub layout: String,
    /// Whether the table ball's placement was fitted (not `--placement-known`).
    pub placement_fitted: bool,
    /// Residuals well above the noise, named by trace (also printed on stderr).
    pub warnings: Vec<String>,
    /// What a fitted value may mean besides its name (backlash against lost motion).
    pub cautions: Vec<String>,
    /// How each trace was matched to its scenario, when only weakly (also on stderr).
    pub notes: Vec<String>,
    pub parameters: Vec<ParamEstimate>,
    pub traces: Vec<TraceFit>,
    pub residual_rms_um: f64,
    /// Gauss–Newton iterations the estimate took (over all outer rounds).
    pub iterations: usize,
    /// Singular values of the column-scaled sensitivity matrix, relative to the largest.
    pub singular_values_relative: Vec<f64>,
    pub null_dimensions: usize,
    pub unidentifiable: Vec<NullDirection>,
    pub suggestion: Option<Suggestion>,
    /// The `[location_errors]` fragment (also written to location-errors.toml).
    pub fragment: String,
}
