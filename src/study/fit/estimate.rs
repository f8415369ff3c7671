//! The estimation: stacked measurements, the model for all rows, sensitivities (central
//! differences; servo parameters by re-simulation) and the Gauss–Newton iterations.
//! Inputs: the (scenario, trace) pairs and parameters. Output: the estimate and its Jacobian.

use nalgebra::{DMatrix, DVector, Vector3};

use super::decomposition::Decomposition;
use super::measured::{MeasuredPoint, MeasuredTrace};
use super::model::{predict, record, with_servo, Run};
use super::params::{Param, BACKLASH_STEP, CONVERGED_UM, GAIN_STEP, GEOMETRY_STEP, MAX_ITERATIONS};
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

/// The estimate (deltas from the prior, parameter units) with its linearisations.
pub(super) struct Solution {
    pub x: DVector<f64>,
    /// All parameters at the nominal machine: what the tests separate.
    pub structural: Decomposition,
    /// At the estimate, the null directions' pivots and the dropped columns left out:
    /// the covariance and the bootstrap.
    pub local: Decomposition,
    /// The columns left out for not acting ([`Decomposition::dropped`]).
    pub dropped: Vec<bool>,
    /// The columns held at the prior: the dropped ones and the null directions' pivots.
    pub fixed: Vec<bool>,
    /// Each column's RMS at the nominal machine, um per unit.
    pub visibility: Vec<f64>,
    /// The last Jacobian (at the estimate).
    pub jac: DMatrix<f64>,
    /// Gauss–Newton iterations taken.
    pub iterations: usize,
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
            let machine = with_servo(&scenario.machine, &self.servo_params, &values)?;
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

    /// Geometric sensitivities (location errors, bar offsets, placement) by central
    /// differences about `x`.
    fn geometric_columns(
        &self,
        runs: &[Run],
        x: &DVector<f64>,
        jac: &mut DMatrix<f64>,
    ) -> Result<()> {
        for (j, p) in self.params.iter().enumerate() {
            if p.is_servo() {
                continue;
            }
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[j] += GEOMETRY_STEP;
            xm[j] -= GEOMETRY_STEP;
            let col = (self.model(runs, &xp)? - self.model(runs, &xm)?) / (2.0 * GEOMETRY_STEP);
            jac.set_column(j, &col);
        }
        Ok(())
    }

    /// `x` at the nominal machine: every location error and placement shift zero (the
    /// servo parameters and bar offsets as in `x`).
    fn nominal(&self, x: &DVector<f64>) -> DVector<f64> {
        let mut x0 = x.clone();
        for (j, p) in self.params.iter().enumerate() {
            match p {
                Param::Location(lp) => x0[j] = -self.prior.get(*lp),
                Param::Setup(..) => x0[j] = 0.0,
                _ => {}
            }
        }
        x0
    }

    /// The value of parameter `p` in the scenarios' machine (the prior), parameter units.
    pub fn prior_value(&self, p: &Param) -> f64 {
        let machine = &self.inputs[0].0.machine;
        match p {
            Param::Location(lp) => self.prior.get(*lp),
            Param::Backlash(a) => machine.drive(*a).backlash_mm_or_deg * 1e3,
            Param::Gain(a) => machine.drive(*a).kv_per_s,
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
    ///
    /// What the tests separate is decided once, at the nominal machine (the structural
    /// decomposition, whose null space does not depend on the estimate): the pivot of each
    /// null direction stays at its prior, so the others carry the combination. The
    /// estimate is then Gauss–Newton on the full nonlinear model, the Jacobian taken
    /// afresh at each iterate, with the step halved until the residual falls: a table
    /// ball 1 mm from where the scenario says changes the trace by ~s²/L = 10 um at second
    /// order, far beyond one linearisation.
    pub fn solve(&self, runs: &mut [Run]) -> Result<Solution> {
        let (n, np) = (self.n(), self.params.len());
        let mut x = DVector::<f64>::zeros(np);
        let mut jac = DMatrix::<f64>::zeros(n, np);
        self.servo_columns(runs, &x, &mut jac)?;
        self.geometric_columns(runs, &self.nominal(&x), &mut jac)?;
        let dropped = Decomposition::dropped(&jac, &self.params);
        let visibility: Vec<f64> = (0..np)
            .map(|c| jac.column(c).norm() / (n.max(1) as f64).sqrt())
            .collect();
        let structural = Decomposition::new(&jac, &dropped);
        let (_, pivots) = structural.null_rref(&self.params);
        // The location errors' pivots are held (the fragment's basic solution). The
        // placement's and bar offsets' are left free: their null directions are exact only
        // at the nominal ball, and a ball 1 mm off bends them by ~s/L, so holding
        // setup_z at 0 when the ball sits 0.4 mm lower biases EY0A by ~0.1 um. The
        // truncated step follows them instead.
        let mut fixed = dropped.clone();
        for &p in &pivots {
            if matches!(
                self.params[p],
                Param::Location(_) | Param::Backlash(_) | Param::Gain(_)
            ) {
                fixed[p] = true;
            }
        }
        let outer = if self.servo_params.is_empty() { 1 } else { 3 };
        let mut local = None;
        let mut iterations = 0;
        for round in 0..outer {
            if round > 0 {
                self.servo_columns(runs, &x, &mut jac)?;
            }
            let d = self.gauss_newton(runs, &mut x, &mut jac, &fixed, &mut iterations)?;
            local = Some(d);
            if !self.servo_params.is_empty() {
                self.keep_physical(&mut x);
                self.simulate(runs, &x, None)?;
            }
        }
        Ok(Solution {
            x,
            structural,
            local: local.expect("at least one round"),
            dropped,
            fixed,
            visibility,
            jac,
            iterations,
        })
    }

    /// Gauss–Newton on the recorded runs, the parameters marked `fixed` held; returns the
    /// decomposition of the last Jacobian. The recorded motion belongs to the servo
    /// parameters of the entry `x`: until the next simulation their changes enter linearly,
    /// through their columns of `jac`.
    fn gauss_newton(
        &self,
        runs: &[Run],
        x: &mut DVector<f64>,
        jac: &mut DMatrix<f64>,
        fixed: &[bool],
        iterations: &mut usize,
    ) -> Result<Decomposition> {
        let x_sim = x.clone();
        let servo = DMatrix::from_fn(self.n(), self.params.len(), |i, j| {
            if self.params[j].is_servo() {
                jac[(i, j)]
            } else {
                0.0
            }
        });
        let residual = |x: &DVector<f64>| -> Result<DVector<f64>> {
            Ok(&self.y - self.model(runs, x)? - &servo * (x - &x_sim))
        };
        let mut last = None;
        for _ in 0..MAX_ITERATIONS {
            *iterations += 1;
            self.geometric_columns(runs, x, jac)?;
            let d = Decomposition::new(jac, fixed);
            let r = residual(x)?;
            let cost = r.norm_squared();
            let dx = d.solve(&r);
            let mut step = 1.0;
            let mut accepted = false;
            for _ in 0..10 {
                let trial = &*x + &dx * step;
                if residual(&trial)?.norm_squared() <= cost {
                    *x = trial;
                    accepted = true;
                    break;
                }
                step *= 0.5;
            }
            let moved = (&*jac * (&dx * step)).norm() / (self.n() as f64).sqrt();
            last = Some(d);
            if !accepted || moved < CONVERGED_UM {
                break;
            }
        }
        Ok(last.expect("at least one iteration"))
    }
}
