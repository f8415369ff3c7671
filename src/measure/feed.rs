//! The tool's feed over the measured revolution, read from the samples (not from the plan).
//!
//! The commanded tool tip moves along the measured circle of radius r (in the table frame,
//! so relative to the workpiece); between two measured samples its path speed is
//!
//! ```text
//! v = r |Δθ| / Δt      Δθ the change of the commanded θ, wrapped to [−180°, 180°)
//! ```
//!
//! the arc length over the time, exact for an arc and within `(d/r)` relative for a tip
//! `d` off the circle (a joint-space chord: micrometres on tens of millimetres). The meter
//! keeps the smallest and largest v of a run; the test is **at feed** when every v is within
//! [`AT_FEED_TOLERANCE`] of the programmed F.

use serde::{Deserialize, Serialize};

/// At feed: every sample's path speed within this share of the programmed F.
pub const AT_FEED_TOLERANCE: f64 = 0.01;

/// The smallest and largest angular speed of θ over a run's measured samples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FeedMeter {
    /// The previous measured sample: time (s) and θ (deg).
    previous: Option<(f64, f64)>,
    /// Smallest and largest `|Δθ| / Δt`, deg/s; None before two measured samples.
    range_deg_s: Option<(f64, f64)>,
    /// The first `|Δθ| / Δt`, deg/s: the speed the lead-in brought the tool to.
    first_deg_s: Option<f64>,
}

impl FeedMeter {
    /// Takes a measured sample at `time_s` whose commanded θ is `theta_deg`.
    #[inline]
    pub fn take(&mut self, time_s: f64, theta_deg: f64) {
        let previous = self.previous.replace((time_s, theta_deg));
        let Some((t0, theta0)) = previous else {
            return;
        };
        let dt = time_s - t0;
        if !(dt > 0.0 && theta_deg.is_finite() && theta0.is_finite()) {
            return;
        }
        let step = ((theta_deg - theta0 + 180.0).rem_euclid(360.0) - 180.0).abs();
        let rate = step / dt;
        self.first_deg_s.get_or_insert(rate);
        self.range_deg_s = Some(match self.range_deg_s {
            None => (rate, rate),
            Some((lo, hi)) => (lo.min(rate), hi.max(rate)),
        });
    }

    /// Smallest and largest angular speed, deg/s; None before two measured samples.
    pub fn range_deg_s(&self) -> Option<(f64, f64)> {
        self.range_deg_s
    }

    /// The angular speed at the start of the measured revolution, deg/s.
    pub fn first_deg_s(&self) -> Option<f64> {
        self.first_deg_s
    }
}

/// The slowest start of the measured revolution over `meters` (one per run) on a circle of
/// `radius_mm`, mm/min: the speed the lead-in reached, as the samples show it.
pub fn start_mm_min(meters: &[FeedMeter], radius_mm: f64) -> Option<f64> {
    meters
        .iter()
        .filter_map(FeedMeter::first_deg_s)
        .reduce(f64::min)
        .map(|deg_s| deg_s.to_radians() * radius_mm * 60.0)
}

/// The feed the tool ran at over the measured revolutions against the programmed one.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FeedSeen {
    /// Every sample within [`AT_FEED_TOLERANCE`] of the programmed feed.
    pub at_feed: bool,
    /// Smallest and largest path speed over the measured samples, mm/min.
    pub feed_min_mm_min: f64,
    pub feed_max_mm_min: f64,
}

impl FeedSeen {
    /// What `meters` (one per run) saw on a circle of `radius_mm` programmed at
    /// `feed_mm_min`; None when no meter saw two samples.
    pub fn of(meters: &[FeedMeter], radius_mm: f64, feed_mm_min: f64) -> Option<FeedSeen> {
        let (lo, hi) = meters
            .iter()
            .filter_map(FeedMeter::range_deg_s)
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))?;
        let to_mm_min = |deg_s: f64| deg_s.to_radians() * radius_mm * 60.0;
        let (min, max) = (to_mm_min(lo), to_mm_min(hi));
        Some(FeedSeen {
            at_feed: (min - feed_mm_min).abs() <= AT_FEED_TOLERANCE * feed_mm_min
                && (max - feed_mm_min).abs() <= AT_FEED_TOLERANCE * feed_mm_min,
            feed_min_mm_min: min,
            feed_max_mm_min: max,
        })
    }
}
