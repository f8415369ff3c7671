//! The ball-bar trace that the geometric errors alone give: the programmed path (no servo)
//! through the actual chain, for `mtsim analyze`.
//!
//! `dL_g(θ) = dL(actual chain, axes with their table errors) − dL(nominal chain, commanded
//! axes)`, sample by sample along the programmed motion: the geometric errors' share of the
//! trace, without the program's own path deviation. The figures are its range (max − min, the radial deviation F)
//! and the range after the ISO 230-4 centring (`dL − a cos θ − b sin θ`, the circular
//! deviation G that this part contributes).

use serde::Serialize;

use crate::error::Result;
use crate::input::program::Direction;
use crate::input::scenario::Scenario;
use crate::measure::ballbar::{deviation_mm, BallbarRun};
use crate::measure::{is_measured, BarGeometry};
use crate::motion::work;
use crate::pipeline::{self, RunOptions, Sample, Sink, Timing};
use crate::program;
use crate::study::simulate::bar_geometry;

/// The geometric part of the ball-bar trace, um.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GeometricTrace {
    pub min_um: f64,
    pub max_um: f64,
    /// max − min of the raw trace.
    pub peak_to_peak_um: f64,
    /// max − min after removing the least-squares centring: what it adds to G.
    pub circular_deviation_um: f64,
}

/// The geometric part of the scenario's trace (one CCW revolution, programmed timing), or
/// `None` when the machine has no geometric errors or the program no measured circle.
pub fn geometric_trace(scenario: &Scenario) -> Result<Option<GeometricTrace>> {
    let m = &scenario.machine;
    if m.kinematics.location_errors.is_zero() && m.geometry.tables.is_empty() {
        return Ok(None);
    }
    let Some(geometry) = bar_geometry(scenario) else {
        return Ok(None);
    };
    let run = program::scenario_run(scenario, Direction::Ccw, scenario.simulate.lead_deg)?;
    let mut sink = GeometricSink {
        geometry,
        nominal: geometry.kinematics.with_location_errors(Default::default()),
        measured: run.measured,
        run: BallbarRun::new(Direction::Ccw),
    };
    let options = RunOptions {
        timing: Timing::Programmed,
        force_tcp: scenario.simulate.tcp,
        start_time_s: 0.0,
        program_path: scenario.path.clone(),
        max_samples: work::check_up_front(scenario, scenario.simulate.lead_deg)?,
    };
    pipeline::run(
        run.moves,
        m,
        &options,
        &mut [&mut sink as &mut dyn Sink],
        &|_| {},
    )?;
    let range = |v: &[f64]| {
        v.iter()
            .fold((f64::MAX, f64::MIN), |(l, h), x| (l.min(*x), h.max(*x)))
    };
    let (lo, hi) = range(&sink.run.trace_um(false)?);
    let (clo, chi) = range(&sink.run.trace_um(true)?);
    Ok(Some(GeometricTrace {
        min_um: lo,
        max_um: hi,
        peak_to_peak_um: hi - lo,
        circular_deviation_um: chi - clo,
    }))
}

/// Pushes `dL(actual chain, actual axes) − dL(nominal chain, commanded axes)` against θ.
struct GeometricSink {
    geometry: BarGeometry,
    nominal: crate::kinematics::Kinematics,
    measured: Option<crate::input::program::MeasuredLines>,
    run: BallbarRun,
}

impl Sink for GeometricSink {
    fn push(&mut self, s: &Sample) -> Result<()> {
        if is_measured(s, self.measured) {
            let g = &self.geometry;
            let actual = deviation_mm(&g.kinematics, &s.actual, &g.pivot_table_mm, g.length_mm);
            let nominal = deviation_mm(&self.nominal, &s.commanded, &g.pivot_table_mm, g.length_mm);
            let theta = g.frame.theta_deg(&self.nominal.forward(&s.commanded).tip);
            self.run.push(theta, (actual - nominal) * 1e3);
        }
        Ok(())
    }
}
