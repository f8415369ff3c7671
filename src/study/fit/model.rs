//! The fit's model: each (trace, direction) simulated once and its measured revolution
//! recorded; the deviation predicted at measured θ for given location errors and placement.
//! Inputs: scenarios, machines, parameters. Outputs: recorded runs and predicted traces.

use nalgebra::{Point3, Vector3};

use super::params::Param;
use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::input::scenario::Scenario;
use crate::kinematics::LocationErrors;
use crate::measure::ballbar::{deviation_mm, BallbarRun, BIN_DEG, N_BINS};
use crate::measure::{is_measured, BarGeometry, CircleFrame};
use crate::motion::work;
use crate::pipeline::{self, RunOptions, Sample, Sink, Timing};
use crate::program;
use crate::study::simulate::bar_geometry;
use crate::AxisVec;

/// One direction of one trace: the recorded actual motion and the measured points it meets.
#[derive(Clone)]
pub(super) struct Run {
    pub trace: usize,
    pub direction: Direction,
    pub geometry: BarGeometry,
    pub samples: Vec<Recorded>,
    /// Indices into the stacked measured points.
    pub rows: Vec<usize>,
}

/// One sample of the measured revolution as simulated.
#[derive(Clone, Copy, Debug)]
pub(super) struct Recorded {
    pub theta_deg: f64,
    pub time_s: f64,
    pub commanded: AxisVec,
    pub actual: AxisVec,
}

/// Records θ and the actual axis positions of the measured revolution.
struct Recorder {
    frame: CircleFrame,
    kinematics: crate::kinematics::Kinematics,
    measured: Option<crate::input::program::MeasuredLines>,
    samples: Vec<Recorded>,
}

impl Sink for Recorder {
    fn push(&mut self, s: &Sample) -> Result<()> {
        if is_measured(s, self.measured) {
            let theta = self
                .frame
                .theta_deg(&self.kinematics.forward(&s.commanded).tip);
            self.samples.push(Recorded {
                theta_deg: theta,
                time_s: s.time_s,
                commanded: s.commanded,
                actual: s.actual,
            });
        }
        Ok(())
    }
}

/// Runs `scenario` (with `machine` in place of its own) in `direction` and records it.
pub(super) fn record(
    scenario: &Scenario,
    machine: &crate::input::Machine,
    direction: Direction,
    timing: Timing,
) -> Result<Vec<Recorded>> {
    let mut sc = scenario.clone();
    sc.machine = machine.clone();
    let geometry = bar_geometry(&sc).ok_or_else(|| {
        Error::invalid(
            &scenario.path,
            "`mtsim fit` needs a cone or circle test (a measured circle)",
        )
    })?;
    let run = program::scenario_run(&sc, direction, sc.simulate.lead_deg)?;
    let mut rec = Recorder {
        frame: geometry.frame,
        kinematics: machine.kinematics,
        measured: run.measured,
        samples: Vec::new(),
    };
    let options = RunOptions {
        timing,
        force_tcp: sc.simulate.tcp,
        start_time_s: 0.0,
        program_path: sc.path.clone(),
        max_samples: work::check_up_front(&sc, sc.simulate.lead_deg)?,
    };
    pipeline::run(run.moves, machine, &options, &mut [&mut rec], &|_| {})?;
    Ok(rec.samples)
}

/// dL at the θ of each of `thetas`, um, for location errors `loc` and table-ball shift
/// `setup_um`, binned like the ball bar and interpolated.
pub(super) fn predict(
    geometry: &BarGeometry,
    samples: &[Recorded],
    direction: Direction,
    loc: &LocationErrors,
    setup_um: &Vector3<f64>,
    thetas: &[f64],
) -> Result<Vec<f64>> {
    let kin = geometry.kinematics.with_location_errors(*loc);
    let ball = Point3::from(geometry.pivot_table_mm.coords + setup_um * 1e-3);
    let mut run = BallbarRun::new(direction);
    for s in samples {
        run.push(
            s.theta_deg,
            deviation_mm(&kin, &s.actual, &ball, geometry.length_mm) * 1e3,
        );
    }
    let bins = run.trace_um(false)?;
    Ok(thetas
        .iter()
        .map(|t| {
            let x = t.rem_euclid(360.0) / BIN_DEG - 0.5;
            let i = x.floor();
            let f = x - i;
            let i0 = (i as i64).rem_euclid(N_BINS as i64) as usize;
            let i1 = (i0 + 1) % N_BINS;
            bins[i0] * (1.0 - f) + bins[i1] * f
        })
        .collect())
}

/// The machine with the servo parameters of `values` added to its resolved drives
/// (backlash in um or mdeg, Kv in 1/s); a value out of its key's range is an error.
pub(super) fn with_servo(
    base: &crate::input::Machine,
    params: &[Param],
    values: &[f64],
) -> Result<crate::input::Machine> {
    let mut m = base.clone();
    for (p, v) in params.iter().zip(values) {
        let (axis, changed) = match p {
            Param::Backlash(a) => {
                let d = m.drive(*a);
                (
                    *a,
                    d.with_backlash_mm_or_deg(d.backlash_mm_or_deg + v * 1e-3),
                )
            }
            Param::Gain(a) => (*a, m.drive(*a).with_kv_per_s(m.drive(*a).kv_per_s + v)),
            _ => continue,
        };
        m.axis_mut(axis).drive = changed.map_err(|p| p.of_axis(axis))?;
    }
    Ok(m)
}
