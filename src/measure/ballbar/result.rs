//! What a ball-bar test reports: each run's figures, the test's ISO 230-4 figures, and the
//! spikes and steps attributed to axes.

use serde::{Deserialize, Serialize};

use super::run::Centring;
use crate::input::program::Direction;
use crate::measure::attribution::AxisSet;
use crate::Axis;

/// Spike or step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EventKind {
    /// A short excursion that returns to the baseline.
    Spike,
    /// A persistent level change.
    Step,
}

/// A spike or step found in a centred trace.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TraceEvent {
    /// Onset angle, deg: where the event leaves the baseline (a step's position).
    pub theta_deg: f64,
    /// Angle of the peak (spike) or the step position, deg.
    pub peak_deg: f64,
    /// Height, um: a spike's signed peak above the baseline; a step's signed level change in
    /// the direction of travel.
    pub height_um: f64,
    /// Full width at half height, deg (0 for a step).
    pub width_deg: f64,
    /// The arc the mark covers from its first onset to its last peak, deg: more than the
    /// width for a train of spikes (stick-slip or ringing after a reversal), 0 for a step.
    pub extent_deg: f64,
    pub kind: EventKind,
    pub direction: Direction,
    /// The leading axis: the one whose reversal (where the bar can see it) is nearest the
    /// onset, within [`ATTRIBUTION_MAX_DEG`](crate::measure::attribution::ATTRIBUTION_MAX_DEG); see [`super::attribution`].
    pub axis: Option<Axis>,
    /// 0..1: the Gaussian likelihood share of that axis among all sensitive axes' nearest
    /// reversals (onset uncertainty [`ONSET_SIGMA_DEG`](crate::measure::attribution::ONSET_SIGMA_DEG)) and "no axis" at [`ATTRIBUTION_MAX_DEG`](crate::measure::attribution::ATTRIBUTION_MAX_DEG).
    pub confidence: f64,
    /// Every axis the mark may come from: those reversing within the tie tolerance of the
    /// leading one, where the bar can see them (the leading axis included).
    pub candidates: AxisSet,
    /// More than one candidate: the trace cannot tell these axes apart here.
    pub ambiguous: bool,
}

/// Figures of one run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunFigures {
    pub direction: Direction,
    pub samples: u64,
    pub centring: Centring,
    pub circular_deviation_um: f64,
    pub radial_max_um: f64,
    pub radial_min_um: f64,
    /// Noise standard deviation estimated from the binned trace, um.
    pub noise_um: f64,
}

/// The ISO 230-4 figures and the events of one test.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BallbarResult {
    /// G: the largest over the runs, um.
    pub circular_deviation_um: f64,
    /// F max: the largest over the runs, um.
    pub radial_max_um: f64,
    /// F min: the smallest over the runs, um.
    pub radial_min_um: f64,
    /// H between the first CCW and the first CW run, um; None with one direction.
    pub hysteresis_um: Option<f64>,
    /// Whether the tool ran at the programmed feed over the measured revolutions, and its
    /// slowest and fastest speed there (`measure::feed`); left out without a nominal feed
    /// (a file program).
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub feed: Option<crate::measure::feed::FeedSeen>,
    /// Spikes and steps of all runs, by run then theta.
    #[serde(rename = "spikes")]
    pub events: Vec<TraceEvent>,
    pub runs: Vec<RunFigures>,
}
