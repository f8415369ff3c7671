//! The error budget of a part program's contour error: what each mechanism of the machine adds
//! to it, by counterfactual runs, as `study::budget` does for the ball bar and
//! `study::cut_budget` for the cut.
//!
//! # The runs
//!
//! The ball bar's plan without a bar ([`BudgetPlan::for_positions`]): the same setpoints drive
//! the ideal machine (actual = commanded, nominal chain) plus one mechanism at a time, each
//! run's servos stepped by [`BudgetRun`] on every setpoint. At each feed sample, each run's
//! positions `q_k` give a contour error vector `e_k` (from the nearest point of the programmed
//! path to the tool tip, `measure::contour`), through the nominal chain, or through the chain
//! with the location errors for the geometric run. The runs, and what each is measured
//! against, are the bar's: the program against nothing, the servos' common lag against the
//! program, an axis's servo against the common lag, its backlash and friction against its
//! servo, the geometric errors and each error table against the program.
//!
//! # The rows
//!
//! With `e` the full run's contour error vector, over the feed samples,
//!
//! ```text
//! c_program = e_program          c_k = e_k − e_base(k)
//! rms_k = sqrt(mean |c_k|²)      max_k = max |c_k|
//! share_k = Σ <c_k, e> / Σ |e|²  interaction_share = 1 − Σ_k share_k
//! ```
//!
//! Each row is projected on the full error, so the shares and the interplay add to 1, and a
//! part that works against the error is negative. Were the tip linear in the positions and
//! the nearest point fixed, the rows would add up to `e` exactly; what they do not explain
//! is the mechanisms acting together.

use std::cell::RefCell;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::measure::contour::ContourGauge;
use crate::pipeline::Sample;
use crate::report::run::BudgetMechanism;
use crate::study::budget::{BudgetPlan, BudgetRun, CaseInfo};
use crate::AxisVec;

/// One row of the contour error's budget.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContourBudgetRow {
    pub mechanism: BudgetMechanism,
    /// The axis letter; None for the program, the servos' common lag and the geometric errors.
    pub axis: Option<String>,
    /// `sqrt(mean |c|²)` and `max |c|` over the feed samples, µm.
    pub rms_um: f64,
    pub max_um: f64,
    /// `Σ <c, e> / Σ |e|²`: the part of the full contour error the row explains.
    pub share: f64,
}

/// The contour error's budget (`measurements.contour.budget` in `summary.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContourBudget {
    /// The full run's contour error over the samples every run measured: RMS, µm.
    pub rms_um: f64,
    pub samples: u64,
    pub rows: Vec<ContourBudgetRow>,
    /// `1 − Σ share`.
    pub interaction_share: f64,
}

/// The sums a row needs.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    dot: f64,
    square: f64,
    max: f64,
}

/// The budget's runs of a part program, fed each measured feed sample with its full error.
pub struct ContourBudgetRuns<'a, 'p> {
    run: &'a RefCell<BudgetRun<'p>>,
    cases: Vec<CaseInfo>,
    positions: Vec<AxisVec>,
    errors: Vec<Vector3<f64>>,
    sums: Vec<Sums>,
    full_square: f64,
    samples: u64,
    /// A run's sample off the contour where the full run's is on it (or a servo failed).
    incomplete: bool,
}

impl<'a, 'p> ContourBudgetRuns<'a, 'p> {
    /// The runs of `plan`, their servos stepped in `run`.
    pub fn new(plan: &BudgetPlan, run: &'a RefCell<BudgetRun<'p>>) -> Self {
        let cases = plan.cases();
        let n = cases.len();
        ContourBudgetRuns {
            run,
            cases,
            positions: Vec::with_capacity(n),
            errors: vec![Vector3::zeros(); n],
            sums: vec![Sums::default(); n],
            full_square: 0.0,
            samples: 0,
            incomplete: false,
        }
    }

    /// Takes sample `s`, read by `gauge` with the full run's error `full` (mm), into every run.
    pub fn record(&mut self, gauge: &ContourGauge<'_>, s: &Sample, full: &Vector3<f64>) {
        if self.incomplete {
            return;
        }
        let mut run = self.run.borrow_mut();
        if run
            .measured_positions(&s.commanded, &mut self.positions)
            .is_none()
        {
            self.incomplete = true;
            return;
        }
        for (k, (case, q)) in self.cases.iter().zip(&self.positions).enumerate() {
            match gauge.error_at(s, q, case.errors.as_ref()) {
                Some(e) => self.errors[k] = e,
                None => {
                    self.incomplete = true;
                    return;
                }
            }
        }
        for (k, case) in self.cases.iter().enumerate() {
            let c = match case.base {
                None => self.errors[k],
                Some(b) => self.errors[k] - self.errors[b],
            } * 1e3;
            let sums = &mut self.sums[k];
            sums.dot += c.dot(&(full * 1e3));
            sums.square += c.norm_squared();
            sums.max = sums.max.max(c.norm());
        }
        self.full_square += full.norm_squared() * 1e6;
        self.samples += 1;
    }

    /// What the runs summed, free of the runs' servos; None when a run could not be measured
    /// where the full one was, or nothing was measured.
    pub fn finish(self) -> Option<ContourBudgetSums> {
        if self.incomplete || self.samples == 0 {
            return None;
        }
        Some(ContourBudgetSums {
            cases: self.cases,
            sums: self.sums,
            full_square: self.full_square,
            samples: self.samples,
        })
    }
}

/// The sums of the budget's runs over a run ([`ContourBudgetRuns::finish`]).
pub struct ContourBudgetSums {
    cases: Vec<CaseInfo>,
    sums: Vec<Sums>,
    full_square: f64,
    samples: u64,
}

impl ContourBudgetSums {
    /// The budget, with rows for the mechanisms on the axes the program `moved`.
    pub fn budget(&self, moved: &[crate::Axis]) -> ContourBudget {
        let n = self.samples as f64;
        let rows: Vec<ContourBudgetRow> = self
            .cases
            .iter()
            .zip(&self.sums)
            .filter(|(case, _)| case.axis.is_none_or(|a| moved.contains(&a)))
            .map(|(case, sums)| ContourBudgetRow {
                mechanism: case.mechanism,
                axis: case.axis.map(|a| a.to_string()),
                rms_um: (sums.square / n).sqrt(),
                max_um: sums.max,
                share: match self.full_square > 0.0 {
                    true => sums.dot / self.full_square,
                    false => 0.0,
                },
            })
            .collect();
        ContourBudget {
            rms_um: (self.full_square / n).sqrt(),
            samples: self.samples,
            interaction_share: 1.0 - rows.iter().map(|r| r.share).sum::<f64>(),
            rows,
        }
    }
}
