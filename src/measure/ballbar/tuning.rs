//! The event detector's settings: gaps, windows, thresholds.

/// Largest angular gap between filled bins a run may have, deg.
pub const MAX_GAP_DEG: f64 = 10.0;
/// Highest harmonic of the smooth shape removed before looking for events.
pub const SMOOTH_ORDER: usize = 6;
/// Half-width of the running-median baseline for spikes, deg.
pub const BASELINE_HALF_WINDOW_DEG: f64 = 5.0;
/// Steps: the level on each side is the median over a window this far from the step, deg...
pub const STEP_GAP_DEG: f64 = 3.0;
/// ...and this wide, deg.
pub const STEP_WINDOW_DEG: f64 = 6.0;
/// Events must exceed this many noise standard deviations...
pub const NOISE_FACTOR: f64 = 6.0;
/// ...and at least this height for a spike, um...
pub const SPIKE_FLOOR_UM: f64 = 0.5;
/// ...or this height for a step, um.
pub const STEP_FLOOR_UM: f64 = 1.0;
