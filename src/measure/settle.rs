//! The start-up transient of a file program, kept out of the measured revolution.
//!
//! A generated test runs a lead arc before the measured revolution, so the axes have
//! settled when θ = 0 comes. A G-code file often has none: the rapid to the start point
//! ends, and the first feed block begins, while the axes still lag behind the rapid by up
//! to millimetres. Measured from its first feed block, the bundled 15/10 cone file read
//! G = 900 µm instead of the 25 µm of its generated twin.
//!
//! [`SettleGate`] passes samples to the sinks behind it, except the measured samples from
//! the first one until the drives have settled: until every axis's following error changes
//! by less than [`SETTLED_RATE`] (mm/s or deg/s), at most for [`MAX_SKIP_DEG`] of θ so that
//! the gap stays one the ball bar interpolates over. The residual lag decays as e^(−Kv t):
//! its rate is Kv times the residual, so a rate below 0.25 mm/s at Kv = 30/s leaves < 10 µm
//! of residual lag, most of it along the path (which the bar does not see). Steady
//! contouring changes the following error by about a/Kv ≈ 0.1 mm/s on the cone (a = v²/r).
//! The θ skipped is reported, so the user knows what the gate did.

use crate::error::Result;
use crate::input::program::MeasuredLines;
use crate::measure::is_measured;
use crate::pipeline::{Sample, Sink};
use crate::AxisVec;

/// Settled when every axis's following error changes slower than this, mm/s (deg/s).
pub const SETTLED_RATE: f64 = 0.25;
/// Most θ left out, deg (the ball bar interpolates gaps up to 10 deg).
pub const MAX_SKIP_DEG: f64 = 6.0;

/// Drops the measured samples of the start-up transient; passes everything else on.
pub struct SettleGate<'a> {
    sinks: Vec<&'a mut dyn Sink>,
    measured: Option<MeasuredLines>,
    /// θ of the measured circle of a sample (None: no circle, nothing skipped by θ).
    theta_deg: Box<dyn Fn(&Sample) -> f64 + 'a>,
    previous: Option<(f64, AxisVec)>,
    first_theta_deg: Option<f64>,
    settled: bool,
    /// θ travelled while skipping, deg, and samples skipped.
    pub skipped_deg: f64,
    pub skipped_samples: u64,
}

impl<'a> SettleGate<'a> {
    pub fn new(
        sinks: Vec<&'a mut dyn Sink>,
        measured: Option<MeasuredLines>,
        theta_deg: Box<dyn Fn(&Sample) -> f64 + 'a>,
    ) -> SettleGate<'a> {
        SettleGate {
            sinks,
            measured,
            theta_deg,
            previous: None,
            first_theta_deg: None,
            settled: false,
            skipped_deg: 0.0,
            skipped_samples: 0,
        }
    }

    /// Whether `s` is still in the transient (and records it).
    fn in_transient(&mut self, s: &Sample) -> bool {
        if self.settled || !is_measured(s, self.measured) {
            return false;
        }
        let theta = (self.theta_deg)(s);
        let first = *self.first_theta_deg.get_or_insert(theta);
        let travelled = {
            let d = (theta - first).rem_euclid(360.0);
            d.min(360.0 - d)
        };
        let rate = self.previous.map(|(t, fe)| {
            let dt = s.time_s - t;
            if dt > 0.0 {
                (s.following_error - fe)
                    .0
                    .iter()
                    .fold(0.0f64, |m, v| m.max(v.abs()))
                    / dt
            } else {
                f64::INFINITY
            }
        });
        self.previous = Some((s.time_s, s.following_error));
        if rate.is_some_and(|r| r < SETTLED_RATE) || travelled >= MAX_SKIP_DEG {
            self.settled = true;
            return false;
        }
        self.skipped_deg = travelled;
        self.skipped_samples += 1;
        true
    }
}

impl Sink for SettleGate<'_> {
    fn push(&mut self, s: &Sample) -> Result<()> {
        if self.in_transient(s) {
            return Ok(());
        }
        for sink in self.sinks.iter_mut() {
            sink.push(s)?;
        }
        Ok(())
    }
}
