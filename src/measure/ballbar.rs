//! The virtual ball bar: deviation, the angle theta, streamed runs, ISO 230-4 figures, and
//! spike and step detection with attribution to the reversing axis.
//!
//! One file per concept: `run.rs` the streamed run (θ bins, centring), `result.rs` what a test
//! reports, `figures.rs` G, F, H, `events.rs` spikes and trains, `steps.rs` the joint fit of the
//! smooth shape and steps, `circular.rs` medians and regions around the circle, `tuning.rs` the detector's settings;
//! the measured circle's frame is the test's (`program/tests/frame.rs`).
//!
//! # Deviation
//!
//! One ball sits at `pivot` on the table (table frame T), the other at the tool tip. With
//! actual axis positions q, both are expressed in the machine frame M:
//!
//! ```text
//! p_tool  = (X, Y, Z)                         (actual tool tip)
//! p_pivot = T_tilt(q) T_C(q) (pivot_M + pivot) (Kinematics::actual_table_to_machine: the
//!                                             actual chain, with the location errors)
//! dL      = |p_tool - p_pivot| - L            (mm)
//! ```
//!
//! # Theta
//!
//! A [`CircleFrame`] holds the measured circle's frame in the table frame: an origin o and a
//! rotation R whose columns are the frame's axes. A table point p has frame coordinates
//! `v = R^T (p - o)` and `theta = atan2(v_y, v_x)` in [0, 360) deg: counter-clockwise from the
//! frame's +X seen from its +Z. The cone frame is `o = O`, `R = Ry(-beta)`; a planar circle
//! in G17/G18/G19 uses the plane's two axes in G-code order (X→Y, Z→X, Y→Z).
//!
//! # Runs and centring
//!
//! A [`BallbarRun`] keeps, in O(1) memory in the number of samples, fixed bins of
//! [`BIN_DEG`] and the normal-equation sums of the least-squares fit
//! `dL = r0 + a cos theta + b sin theta`. Each bin holds its sample count and the sums of
//! dL, cos theta and sin theta, so the *centred* bin mean
//! `(sum dL - a sum cos - b sum sin) / n` is exact for the samples it holds. Empty bins are
//! filled by linear interpolation between their filled neighbours (around the circle).
//!
//! # Figures (ISO 230-4), on the binned trace
//!
//! - G, circular deviation: max - min of the centred trace `dL - a cos - b sin`.
//! - F, radial deviation: max and min of the raw trace dL (relative to the nominal length).
//! - H, circular hysteresis: max over theta of `|dL_ccw - dL_cw|`. Both runs share one
//!   pivot, so this is the difference about a common centre.
//!
//! # Events
//!
//! See [`analyse`]: steps are persistent level changes found with far, robust windows; spikes
//! are short excursions above a smooth local baseline; each is attributed to the axis whose
//! reversal angle is nearest to its onset.

mod circular;
mod events;
mod figures;
mod result;
mod run;
mod steps;
pub mod tuning;

pub use super::attribution::{ATTRIBUTION_MAX_DEG, ONSET_SIGMA_DEG};
pub use super::bar::deviation_mm;
pub use super::theta::{angle_distance_deg, theta_sin_cos, BIN_DEG, N_BINS};
pub use crate::program::tests::CircleFrame;
pub use events::TRAIN_GAP_DEG;
pub use figures::{analyse, analyse_events_at, analyse_events_of, attribute};
pub use result::{BallbarResult, EventKind, RunFigures, TraceEvent};
pub use run::{BallbarRun, Centring, ThetaTerms};
pub use tuning::*;
