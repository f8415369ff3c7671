//! The error budget of the cut: what each mechanism of the machine changes on the machined
//! surface, by counterfactual cuts, as `study::budget` does for the ball bar.
//!
//! # The runs
//!
//! The runs are the ball bar budget's, one [`BudgetPlan`] for both: the same setpoints (the
//! cut's own run) drive the ideal machine (actual = commanded, nominal chain) plus one
//! mechanism at a time, with each run's servos stepped by [`crate::study::budget::BudgetRun`]
//! on every setpoint. Each run's actual positions `q_k` at a measured sample cut a surface of
//! their own (`measure::cut`), through the nominal chain, or through the chain with the
//! location errors for the geometric run. The runs and what they are measured against are
//! the bar's table (`study::budget`): the program against nothing, the servos' common lag
//! against the program, an axis's servo against the common lag, its backlash and friction
//! against its servo, the geometric errors and each error table against the program.
//!
//! # The rows
//!
//! With `d_k(θ, z)` run k's deviation on the grid and `d(θ, z)` the full cut's, over the grid
//! points every run cut,
//!
//! ```text
//! c_program = d_program            c_k = d_k − d_base(k)
//! rms_k = sqrt(mean c_k²)          pv_k = max c_k − min c_k
//! share_k = <c_k, d> / <d, d>      interaction_share = 1 − Σ_k share_k
//! ```
//!
//! the bar's rule (`study::budget`): each row projected on the full deviation, so that the
//! shares and the interplay add to 1, a part that works against d negative. The bar's
//! curves are centred first (its set-up removes the circle's centre), so its projection is
//! about their means; the cut's d is not centred (its mean is the size error a CMM reports),
//! so the projection is about zero. Were the cut linear in the positions the rows would add
//! up to d exactly; it is a lower envelope (a minimum over the cutter positions), so where a
//! mechanism moves which position cuts a point the rows interact, and that is the
//! interplay's share.
//!
//! `height_change_k = max_θ |c_k(θ, z_top) − c_k(θ, z_bottom)|`: what the row changes along
//! the height at one θ. A ball bar reads one point per θ (the tool tip); a tilt δ of the tool
//! axis in the generatrix plane adds `δ (z − z_tip) / cos α` to d (`cutting-test.md`), seen
//! only here.

use std::cell::RefCell;

use crate::error::Result;
use crate::input::program::{ConeTest, Direction, MeasuredLines};
use crate::input::scenario::Scenario;
use crate::measure::cut::{CutOptions, CutSurface};
use crate::measure::is_measured;
use crate::pipeline::{Sample, Sink};
use crate::report::cut_budget::{CutBudget, CutBudgetRow};
use crate::study::budget::{peak_to_valley, projection_share, BudgetPlan, BudgetRun, CaseInfo};
use crate::{Axis, AxisVec};

/// The budget's cuts of one run, fed the measured samples behind the cut's own (its
/// [`crate::study::budget::BudgetStepper`] in front of any settle gate).
pub struct CutBudgetRuns<'a, 'p> {
    run: &'a RefCell<BudgetRun<'p>>,
    cases: Vec<CaseInfo>,
    surfaces: Vec<CutSurface>,
    measured: Option<MeasuredLines>,
    /// Each run's positions at the current sample (scratch).
    positions: Vec<AxisVec>,
}

impl<'a, 'p> CutBudgetRuns<'a, 'p> {
    /// One cut of `cone` with `options` per run of `plan`, its servos stepped in `run`.
    pub fn new(
        scenario: &Scenario,
        cone: &ConeTest,
        plan: &BudgetPlan,
        options: &CutOptions,
        run: &'a RefCell<BudgetRun<'p>>,
    ) -> Result<CutBudgetRuns<'a, 'p>> {
        let cases = plan.cases();
        // One grid (its columns' sin and cos, the clearance, the rows) made once, copied.
        let blank = CutSurface::new(scenario, cone, options.clone(), Vec::new())?;
        let surfaces = cases
            .iter()
            .map(|c| {
                let mut surface = blank.clone();
                surface.set_commanded(c.errors.is_none());
                if let Some(errors) = c.errors {
                    surface.read_through(errors);
                }
                surface
            })
            .collect();
        Ok(CutBudgetRuns {
            run,
            cases,
            surfaces,
            measured: None,
            positions: Vec::new(),
        })
    }

    /// The run in `direction` starts (`measured`: its measured lines).
    pub fn start_run(&mut self, direction: Direction, measured: Option<MeasuredLines>) {
        self.measured = measured;
        for s in &mut self.surfaces {
            s.start_run(direction, measured);
        }
    }

    /// The run has ended: every cut's columns are computed; the cuts, done.
    pub fn finish(mut self) -> BudgetCuts {
        for s in &mut self.surfaces {
            s.end_run();
        }
        BudgetCuts {
            cases: self.cases,
            surfaces: self.surfaces,
        }
    }
}

/// The budget's cuts of a run, done: one per run of the plan.
pub struct BudgetCuts {
    cases: Vec<CaseInfo>,
    surfaces: Vec<CutSurface>,
}

impl Sink for CutBudgetRuns<'_, '_> {
    fn push(&mut self, s: &Sample) -> Result<()> {
        if !is_measured(s, self.measured) {
            return Ok(());
        }
        let mut run = self.run.borrow_mut();
        if run
            .measured_positions(&s.commanded, &mut self.positions)
            .is_none()
        {
            return Ok(());
        }
        // A nominal-chain cut reads `commanded`, the geometric one `actual`: both are q_k
        // (and so is the linear twin's: no lost motion of its own).
        for (surface, q) in self.surfaces.iter_mut().zip(&self.positions) {
            surface.push_positions(q);
        }
        Ok(())
    }
}

/// The budget from the runs' cuts beside the `full` one, with the axes
/// the program `moved` (rows are made only for those); see the module's doc.
pub fn assemble(runs: BudgetCuts, full: &CutSurface, moved: &[Axis]) -> CutBudget {
    let d: &[f64] = &full.envelope.values;
    let runs_d: Vec<&[f64]> = runs
        .surfaces
        .iter()
        .map(|s| &s.envelope.values[..])
        .collect();
    // The points every run cut.
    let used: Vec<usize> = (0..d.len())
        .filter(|&p| d[p].is_finite() && runs_d.iter().all(|v| v[p].is_finite()))
        .collect();
    // Those points of `v`: `v` itself when they are all of them (no copy), else into `out`.
    let pick = |v: &'_ [f64], out: &'_ mut Vec<f64>| {
        if used.len() != v.len() {
            out.clear();
            out.extend(used.iter().map(|&p| v[p]));
        }
    };
    let (mut d_picked, mut c_picked) = (Vec::new(), Vec::new());
    pick(d, &mut d_picked);
    let d_used: &[f64] = if used.len() == d.len() { d } else { &d_picked };
    let rows_n = full.envelope.rows.len();
    let mut rows = Vec::new();
    for (k, case) in runs.cases.iter().enumerate() {
        if case.axis.is_some_and(|a| !moved.contains(&a)) {
            continue;
        }
        let c: Vec<f64> = match case.base {
            None => runs_d[k].to_vec(),
            Some(b) => runs_d[k]
                .iter()
                .zip(runs_d[b])
                .map(|(v, w)| v - w)
                .collect(),
        };
        pick(&c, &mut c_picked);
        let c_used: &[f64] = if used.len() == c.len() { &c } else { &c_picked };
        let height_change_um = (0..full.envelope.column_count())
            .map(|j| c[j * rows_n + rows_n - 1] - c[j * rows_n])
            .filter(|v| v.is_finite())
            .fold(0.0, |m: f64, v| m.max(v.abs()));
        rows.push(CutBudgetRow {
            mechanism: case.mechanism,
            axis: case.axis.map(|a| a.to_string()),
            rms_um: rms(c_used),
            pv_um: peak_to_valley(c_used),
            share: projection_share(c_used, d_used, false),
            height_change_um,
            contribution_um: c,
        });
    }
    CutBudget {
        rms_um: rms(d_used),
        pv_um: peak_to_valley(d_used),
        points: used.len(),
        interaction_share: 1.0 - rows.iter().map(|r| r.share).sum::<f64>(),
        rows,
    }
}

/// `sqrt(mean v²)`; 0 for none.
fn rms(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}
