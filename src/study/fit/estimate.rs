//! The estimation: stacked measurements, the model for all rows, sensitivities (central
//! differences; servo parameters by re-simulation) and the Gauss–Newton iterations.
//! Inputs: the (scenario, trace) pairs and parameters. Output: the estimate and its Jacobian.

use nalgebra::{DMatrix, DVector, Vector3};

use super::decomposition::Decomposition;
use super::measured::{MeasuredPoint, MeasuredTrace};
use super::model::{predict, record, with_servo, Run};
use super::params::{Param, BACKLASH_STEP, GAIN_STEP, GEOMETRY_STEP};
use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::input::scenario::Scenario;
use crate::kinematics::LocationErrors;
use crate::pipeline::Timing;
use crate::study::simulate::bar_geometry;

/// The fit problem: the stacked measured points and the parameters.
pub(super) struct Problem<'a> {
    pub inputs: &'a [(Scenario, MeasuredTrace)],
    pub params: Vec<Param>,
    pub servo_params: Vec<Param>,
    pub measured: Vec<MeasuredPoint>,
    pub y: DVector<f64>,
    pub prior: LocationErrors,
}

/// The estimate (deltas from the prior, parameter units) with its linearisation.
pub(super) struct Solution {
    pub x: DVector<f64>,
    pub decomposition: Decomposition,
}

impl<'a> Problem<'a> {
    /// Stacks the measured points by (trace, direction); returns the runs, not yet simulated.
    pub fn new(
        inputs: &'a [(Scenario, MeasuredTrace)],
        params: Vec<Param>,
        servo_params: Vec<Param>,
    ) -> Result<(Problem<'a>, Vec<Run>)> {
        let mut measured = Vec::new();
        let mut runs = Vec::new();
        for (k, (scenario, trace)) in inputs.iter().enumerate() {
            let geometry = bar_geometry(scenario).ok_or_else(|| {
                Error::invalid(
                    &scenario.path,
                    "`mtsim fit` needs a cone or circle test (a measured circle)",
                )
            })?;
            for direction in [Direction::Ccw, Direction::Cw] {
                let rows: Vec<usize> = trace
                    .points
                    .iter()
                    .filter(|p| p.direction == direction)
                    .map(|p| {
                        measured.push(*p);
                        measured.len() - 1
                    })
                    .collect();
                if !rows.is_empty() {
                    runs.push(Run {
                        trace: k,
                        direction,
                        geometry,
                        samples: Vec::new(),
                        rows,
                    });
                }
            }
        }
        let (n, np) = (measured.len(), params.len());
        if n <= np {
            return Err(Error::usage(format!(
                "{n} measured points cannot determine {np} parameters"
            )));
        }
        let y = DVector::from_iterator(n, measured.iter().map(|p| p.deviation_um));
        let prior = inputs[0].0.machine.kinematics.location_errors;
        let problem = Problem {
            inputs,
            params,
            servo_params,
            measured,
            y,
            prior,
        };
        Ok((problem, runs))
    }

    pub fn n(&self) -> usize {
        self.measured.len()
    }

    pub fn location_of(&self, x: &DVector<f64>) -> LocationErrors {
        let mut loc = self.prior;
        for (j, p) in self.params.iter().enumerate() {
            if let Param::Location(lp) = p {
                loc.set(*lp, self.prior.get(*lp) + x[j]);
            }
        }
        loc
    }

    fn servo_values(&self, x: &DVector<f64>) -> Vec<f64> {
        self.params
            .iter()
            .enumerate()
            .filter(|(_, p)| p.is_servo())
            .map(|(j, _)| x[j])
            .collect()
    }

    /// The model for all rows, with the runs' recorded samples.
    pub fn model(&self, runs: &[Run], x: &DVector<f64>) -> Result<DVector<f64>> {
        let loc = self.location_of(x);
        let mut out = DVector::zeros(self.n());
        for run in runs {
            let k = run.trace;
            let mut offset = 0.0;
            let mut setup = Vector3::zeros();
            for (j, p) in self.params.iter().enumerate() {
                match p {
                    Param::BarOffset(kk) if *kk == k => offset = x[j],
                    Param::Setup(kk, i) if *kk == k => setup[*i] = x[j],
                    _ => {}
                }
            }
            let thetas: Vec<f64> = run
                .rows
                .iter()
                .map(|&r| self.measured[r].theta_deg)
                .collect();
            let pred = predict(
                &run.geometry,
                &run.samples,
                run.direction,
                &loc,
                &setup,
                &thetas,
            )?;
            for (i, &r) in run.rows.iter().enumerate() {
                out[r] = pred[i] + offset;
            }
        }
        Ok(out)
    }

    /// Simulates every run with the servo parameters of `x` (one stepped by `extra`).
    pub fn simulate(
        &self,
        runs: &mut [Run],
        x: &DVector<f64>,
        extra: Option<(Param, f64)>,
    ) -> Result<()> {
        let mut values = self.servo_values(x);
        if let Some((p, step)) = extra {
            let i = self
                .servo_params
                .iter()
                .position(|q| *q == p)
                .expect("a servo parameter");
            values[i] += step;
        }
        for run in runs.iter_mut() {
            let (scenario, _) = &self.inputs[run.trace];
            let machine = with_servo(&scenario.machine, &self.servo_params, &values);
            run.samples = record(
                scenario,
                &machine,
                run.direction,
                Timing::Planned {
                    twins: false,
                    settle: false,
                },
            )?;
        }
        Ok(())
    }

    /// Servo sensitivities by re-simulation with each servo parameter stepped.
    fn servo_columns(&self, runs: &[Run], x: &DVector<f64>, jac: &mut DMatrix<f64>) -> Result<()> {
        let base = self.model(runs, x)?;
        for (j, p) in self.params.iter().enumerate() {
            let step = match p {
                Param::Backlash(_) => BACKLASH_STEP,
                Param::Gain(_) => GAIN_STEP,
                _ => continue,
            };
            let mut stepped: Vec<Run> = runs
                .iter()
                .map(|r| Run {
                    samples: Vec::new(),
                    ..r.clone()
                })
                .collect();
            self.simulate(&mut stepped, x, Some((*p, step)))?;
            let m = self.model(&stepped, x)?;
            jac.set_column(j, &((m - &base) / step));
        }
        Ok(())
    }

    /// Geometric sensitivities at the nominal machine (all location errors and placement
    /// shifts zero): the structural linearisation, whose null space does not depend on the
    /// estimate. The model is linear in the errors to ~1e-5, so a few fixed-Jacobian (chord)
    /// iterations converge.
    fn geometric_columns(
        &self,
        runs: &[Run],
        x: &DVector<f64>,
        jac: &mut DMatrix<f64>,
    ) -> Result<()> {
        let mut x0 = x.clone();
        for (j, p) in self.params.iter().enumerate() {
            match p {
                Param::Location(lp) => x0[j] = -self.prior.get(*lp),
                Param::Setup(..) => x0[j] = 0.0,
                _ => {}
            }
        }
        for (j, p) in self.params.iter().enumerate() {
            if p.is_servo() {
                continue;
            }
            let (mut xp, mut xm) = (x0.clone(), x0.clone());
            xp[j] += GEOMETRY_STEP;
            xm[j] -= GEOMETRY_STEP;
            let col = (self.model(runs, &xp)? - self.model(runs, &xm)?) / (2.0 * GEOMETRY_STEP);
            jac.set_column(j, &col);
        }
        Ok(())
    }

    /// The value of parameter `p` in the scenarios' machine (the prior), parameter units.
    pub fn prior_value(&self, p: &Param) -> f64 {
        let machine = &self.inputs[0].0.machine;
        match p {
            Param::Location(lp) => self.prior.get(*lp),
            Param::Backlash(a) if a.is_rotary() => {
                machine.axis(*a).drive.backlash_deg.unwrap_or(0.0) * 1e3
            }
            Param::Backlash(a) => machine.axis(*a).drive.backlash_mm.unwrap_or(0.0) * 1e3,
            Param::Gain(a) => machine.axis(*a).servo.kv_per_s,
            _ => 0.0,
        }
    }

    /// Keeps backlash non-negative and gains above 1/s.
    fn keep_physical(&self, x: &mut DVector<f64>) {
        for (j, p) in self.params.iter().enumerate() {
            match p {
                Param::Backlash(_) => x[j] = x[j].max(-self.prior_value(p)),
                Param::Gain(_) => x[j] = x[j].max(1.0 - self.prior_value(p)),
                _ => {}
            }
        }
    }

    /// Simulates, linearises and iterates (three outer rounds when servo parameters are
    /// fitted, each re-simulating at the new estimate). `runs` come simulated at the prior
    /// and end simulated at the estimate.
    pub fn solve(&self, runs: &mut [Run]) -> Result<Solution> {
        let (n, np) = (self.n(), self.params.len());
        let mut x = DVector::<f64>::zeros(np);
        let outer = if self.servo_params.is_empty() { 1 } else { 3 };
        let mut jac = DMatrix::<f64>::zeros(n, np);
        let mut decomposition = None;
        for _ in 0..outer {
            self.servo_columns(runs, &x, &mut jac)?;
            self.geometric_columns(runs, &x, &mut jac)?;
            let d = Decomposition::new(&jac);
            // The recorded motion belongs to the servo parameters of `x_sim`; until the next
            // simulation their changes enter linearly, through their columns.
            let x_sim = x.clone();
            let servo_part = |x: &DVector<f64>| -> DVector<f64> {
                let mut dx = x - &x_sim;
                for (j, p) in self.params.iter().enumerate() {
                    if !p.is_servo() {
                        dx[j] = 0.0;
                    }
                }
                &jac * dx
            };
            for _ in 0..4 {
                let r = &self.y - self.model(runs, &x)? - servo_part(&x);
                x += d.solve(&r);
            }
            decomposition = Some(d);
            if !self.servo_params.is_empty() {
                self.keep_physical(&mut x);
                self.simulate(runs, &x, None)?;
            }
        }
        Ok(Solution {
            x,
            decomposition: decomposition.expect("at least one iteration"),
        })
    }
}
