//! The measurement seam: what reads the samples of a test's runs.
//!
//! The pipeline hands every [`Sample`](crate::pipeline::Sample) to every
//! [`Sink`](crate::pipeline::Sink) and knows nothing else of them. A measurement is a sink with
//! a name, built for a scenario's test (from the test's geometry: [`TestProgram`]), told when
//! each run starts and ends, and read out as one JSON document when the runs are over:
//!
//! ```text
//! program/tests (the test) ──► REGISTRY: build(scenario, test) ──► Box<dyn Measurement>
//!                                                                        │ start_run
//! pipeline::run ──── every sample ──────────────────────────────────────►│ push
//!                                                                        │ end_run
//! simulate: summary.json "measurements": { name: finish() } ◄────────────┘
//! ```
//!
//! `simulate` builds every registered measurement that applies, feeds it beside the ball bar
//! (inside the settle gate of a file program, as the ball bar), and writes each one's document
//! under its name in `summary.json`'s `measurements` (left out when none applies). A new
//! measurement is one file in `measure/` implementing [`Measurement`] and one line in
//! [`REGISTRY`]; the pipeline and `simulate` do not change. The cut cone (`measure::cut`)
//! is not one of them: its marks need the reversal analysis and its error budget the
//! budget's own runs, so `simulate --cut` runs `cut`'s own path (`study::cut::cut_into`).
//!
//! The ball bar is a measurement too ([`BallbarSink`]); `simulate` builds it itself rather than
//! through the registry, because the trace, the diagnostics and the report are all read from
//! its bins, typed.

use crate::error::{Error, Result};
use crate::input::program::{Direction, MeasuredLines};
use crate::input::scenario::Scenario;
use crate::measure::ballbar::analyse;
use crate::measure::sink::BallbarSink;
use crate::pipeline::Sink;
use crate::program::TestProgram;

/// A measurement of a test's runs: a sink with a name and a read-out.
pub trait Measurement: Sink {
    /// Its name in `summary.json` and in messages: `"ballbar"`.
    fn name(&self) -> &'static str;

    /// A run in `direction` starts; `measured` are the program's lines of the measured
    /// revolution (None: every move after the first).
    fn start_run(&mut self, _direction: Direction, _measured: Option<MeasuredLines>) {}

    /// The run that started last has ended.
    fn end_run(&mut self) -> Result<()> {
        Ok(())
    }

    /// What it measured over all runs, as one JSON document.
    fn finish(&self) -> Result<serde_json::Value>;
}

/// Builds a measurement for a scenario's test, or `None` where it does not apply.
pub type Build = fn(&Scenario, &dyn TestProgram) -> Option<Box<dyn Measurement>>;

/// Every measurement `simulate` takes beside the ball bar, by name: one line each.
pub const REGISTRY: &[(&str, Build)] = &[];

/// The registered measurements that apply to `scenario`'s test, in the registry's order.
pub fn for_scenario(scenario: &Scenario, test: &dyn TestProgram) -> Vec<Box<dyn Measurement>> {
    REGISTRY
        .iter()
        .filter_map(|(_, build)| build(scenario, test))
        .collect()
}

/// The ball bar of one run as a measurement: its ISO 230-4 figures of that run (G, F, the
/// centring), without events (those need the reversal analysis `simulate` gives it).
impl Measurement for BallbarSink {
    fn name(&self) -> &'static str {
        "ballbar"
    }

    fn finish(&self) -> Result<serde_json::Value> {
        let figures = analyse(std::slice::from_ref(&self.run), &[])?.runs;
        serde_json::to_value(figures).map_err(|e| Error::usage(e.to_string()))
    }
}
