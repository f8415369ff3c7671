//! The sample budget of a run: how many interpolation periods one run may take, estimated
//! before sampling for a generated test (here; a G-code file's read-ahead is in
//! `motion::work`) and counted while sampling for any program.
//!
//! A generated cone or circle runs the arc `2π r (1 + 2 lead / 360°)` at the feed F, so
//!
//! ```text
//! machine time  T ≈ 2π r (1 + lead/180°) / (F / 60)      s   (r mm, F mm/min)
//! samples       n ≈ T / Δt                                   (Δt the interpolation period, s)
//! ```
//!
//! a lower bound (acceleration ramps only add to it). A run whose estimate exceeds
//! `[simulate] max_samples` (default [`DEFAULT_MAX_SAMPLES`], 10⁹) is refused before it starts;
//! the pipeline stops any run, a G-code file's too, whose count passes it.

use std::f64::consts::PI;

use crate::error::{Error, Result};
use crate::input::scenario::Scenario;
pub use crate::input::scenario::DEFAULT_MAX_SAMPLES;

/// A generated test's measured revolution in closed form (`program::TestProgram::revolution`):
/// the tool tip's circle of `radius_mm` about the workpiece at `feed_mm_min`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Revolution {
    /// Radius of the measured circle, mm.
    pub radius_mm: f64,
    /// The program's feed along it, mm/min.
    pub feed_mm_min: f64,
    /// The scenario table that gives it, for messages: `[program.cone]`.
    pub table: &'static str,
}

/// A generated test's expected work.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleEstimate {
    /// Tool-tip path of one run, lead-in and lead-out included, mm.
    pub path_mm: f64,
    /// The program's feed, mm/min.
    pub feed_mm_min: f64,
    /// Machine time of that path at that feed, s.
    pub machine_time_s: f64,
    /// Interpolation periods in that time.
    pub samples: f64,
}

impl SampleEstimate {
    /// The work of a generated test whose measured revolution is `revolution`, on `scenario`'s
    /// machine, with `lead_deg` before and after the measured revolution.
    pub fn of(scenario: &Scenario, revolution: &Revolution, lead_deg: f64) -> SampleEstimate {
        let (radius_mm, feed_mm_min) = (revolution.radius_mm, revolution.feed_mm_min);
        let path_mm = 2.0 * PI * radius_mm * (1.0 + lead_deg.max(0.0) / 180.0);
        let machine_time_s = path_mm / (feed_mm_min / 60.0);
        SampleEstimate {
            path_mm,
            feed_mm_min,
            machine_time_s,
            samples: machine_time_s / scenario.machine.interpolation_period_s,
        }
    }
}

/// Refuses a generated test whose estimated samples exceed the scenario's budget, naming
/// the estimate and what to change; otherwise returns the budget, for the pipeline to
/// count any run against. `revolution` is the test's measured revolution in closed form
/// (None for a G-code file, counted while it runs).
pub fn check_up_front(
    scenario: &Scenario,
    revolution: Option<Revolution>,
    lead_deg: f64,
) -> Result<u64> {
    let max = scenario.simulate.max_samples;
    let Some(revolution) = revolution else {
        return Ok(max);
    };
    let e = SampleEstimate::of(scenario, &revolution, lead_deg);
    if e.samples <= max as f64 {
        return Ok(max);
    }
    let table = revolution.table;
    Err(Error::invalid(
        &scenario.path,
        format!(
            "the run needs about {:.3e} samples, more than the budget of {max} ([simulate] max_samples): \
             {:.1} mm of path at feed_mm_min = {} is {} of machine time, sampled every {} ms",
            e.samples,
            e.path_mm,
            e.feed_mm_min,
            duration(e.machine_time_s),
            scenario.machine.interpolation_period_s * 1e3,
        ),
    )
    .with_help(format!(
        "raise {table} feed_mm_min, lengthen the machine's interpolation_period_ms, \
         or raise [simulate] max_samples"
    )))
}

/// The error of a run stopped when its sample count passed `max_samples`, at source line
/// `line` of `program` and machine time `time_s`.
pub fn exceeded(program: &std::path::Path, max_samples: u64, line: usize, time_s: f64) -> Error {
    Error::invalid(
        program,
        format!(
            "the run passed its budget of {max_samples} samples ([simulate] max_samples) at program line {line}, \
             after {} of machine time",
            duration(time_s)
        ),
    )
    .with_help("shorten the program (loops, feeds near zero), lengthen the machine's interpolation_period_ms, or raise [simulate] max_samples")
}

/// `s` as seconds, hours or years, whichever reads best.
pub fn duration(s: f64) -> String {
    const HOUR: f64 = 3600.0;
    const YEAR: f64 = 365.25 * 24.0 * HOUR;
    if s < HOUR {
        format!("{s:.1} s")
    } else if s < YEAR {
        format!("{:.1} h", s / HOUR)
    } else {
        format!("{:.1} years", s / YEAR)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_in_their_unit() {
        assert_eq!(duration(36.4), "36.4 s");
        assert_eq!(duration(7200.0), "2.0 h");
        assert_eq!(duration(2.0 * 365.25 * 86400.0), "2.0 years");
    }
}
