//! `mtsim cut`: one run of a cone scenario's program through the pipeline into the cut
//! surface (`measure::cut`), with the reversal angles its marks are read at, the ball bar's
//! reading of the same run (to draw beside the cut) and the cut's error budget
//! (`study::cut_budget`, its runs riding the same pass).
//!
//! The run is `simulate`'s (the same program, lead, interpolator, servo and settle gate for a
//! file program), in one direction: one piece is cut by one pass. With `commanded` the
//! samples are the interpolator's setpoints alone (no servo), which is all the cut reads then.

use std::cell::RefCell;

use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::input::scenario::Scenario;
use crate::measure::cut::CutFigures;
use crate::measure::cut::{CutOptions, CutSurface};
use crate::pipeline::{Sink, Timing};
use crate::program::{self, test_of};
use crate::report::cut::{write_cut_files, CutBeside};
use crate::report::cut_budget::CutBudget;
use crate::study::budget::{BudgetPlan, BudgetStepper};
use crate::study::cut_budget::{assemble, CutBudgetRuns};
use crate::study::reversals::reversals_deg;
use crate::study::simulate::{
    analysed_along, analyses, ballbar_sink, bar_geometry, directions_of, run_options, Gate,
};

/// What a cut run gives.
pub struct CutRun {
    pub surface: CutSurface,
    /// The cut's error budget (`study::cut_budget`); None with `commanded`, without a
    /// budget asked for, or when one of its runs failed (said in `warnings`).
    pub budget: Option<CutBudget>,
    /// The ball bar's radial deviation dL of the same run, µm, binned over θ (`N_BINS` bins,
    /// raw: not centred); None when the bar's samples leave a gap.
    pub ballbar_um: Option<Vec<f64>>,
    /// Machine time of the run, s, and its samples.
    pub sim_time_s: f64,
    pub setpoints: u64,
    /// What the user should know (a start-up transient left out, a feed held below F).
    pub warnings: Vec<String>,
}

/// Cuts `scenario`'s cone with `options`, with the error budget when `with_budget` (and the
/// cut is not `commanded`: the program alone has nothing to split). `progress` is told the
/// machine time now and then.
pub fn run_cut(
    scenario: &Scenario,
    options: CutOptions,
    with_budget: bool,
    progress: &dyn Fn(f64),
) -> Result<CutRun> {
    let test = test_of(scenario);
    let cone = *test.cone().ok_or_else(|| {
        Error::usage(format!(
            "{}: no cone to cut: the cut needs the cone's geometry, a [program.cone] table \
             (beside [program] file for a program file that cuts a cone)",
            scenario.path.display()
        ))
    })?;
    let planned = directions_of(scenario);
    let direction: Direction = options.direction.unwrap_or(planned[0]);
    if test.planned_directions().is_none() && !planned.contains(&direction) {
        return Err(Error::usage(format!(
            "--direction {}: a program file runs as it was written; leave --direction out",
            format!("{direction:?}").to_lowercase()
        )));
    }
    let (along, done) = analyses(scenario)?;
    let commanded = options.commanded;
    let geometry = bar_geometry(scenario);
    let plan = match geometry.filter(|_| with_budget && !commanded) {
        Some(g) => Some(BudgetPlan::new(scenario, g)?),
        None => None,
    };
    let mut run_options = run_options(scenario, 0.0)?;
    run_options.timing = if commanded {
        Timing::Setpoints
    } else {
        // The linear twins give each axis's lost motion, which the marks are read across.
        Timing::Planned {
            twins: true,
            settle: false,
        }
    };
    let budget_run = (plan.as_ref()).map(|p| RefCell::new(p.start(direction, run_options.timing)));
    let mut budget_cuts = match (&plan, &budget_run) {
        (Some(plan), Some(run)) => Some(CutBudgetRuns::new(scenario, &cone, plan, &options, run)?),
        _ => None,
    };
    let mut surface = CutSurface::new(scenario, &cone, options, Vec::new())?;
    let mut run = program::scenario_run(scenario, direction, scenario.simulate.lead_deg)?;
    if let Some(along) = &along {
        run.moves = analysed_along(run.moves, along);
    }
    surface.start_run(direction, run.measured);
    if let Some(b) = budget_cuts.as_mut() {
        b.start_run(direction, run.measured);
    }
    let mut ballbar = geometry.map(|g| ballbar_sink(g, direction, run.measured, 1));
    let mut warnings = Vec::new();
    let stats = {
        let mut sinks: Vec<&mut dyn Sink> = vec![&mut surface];
        if let Some(b) = budget_cuts.as_mut() {
            sinks.push(b);
        }
        if let Some(b) = ballbar.as_mut() {
            sinks.push(b);
        }
        // The budget's servos take every setpoint, before any settle gate.
        let mut stepper = budget_run.as_ref().map(BudgetStepper);
        let stepper = stepper.as_mut().map(|s| s as &mut dyn Sink);
        let gate = Gate {
            scenario,
            measured: run.measured,
            geometry,
        };
        gate.run(
            run.moves,
            &run_options,
            sinks,
            stepper.into_iter().collect(),
            &mut warnings,
            progress,
        )?
    };
    surface.end_run();
    warnings.extend(
        stats
            .feed_reductions
            .iter()
            .map(crate::motion::FeedReduction::describe),
    );
    let reversals = match (done, along) {
        (Some(done), _) => done,
        (None, Some(along)) => {
            let rode = std::mem::replace(
                &mut *along.borrow_mut(),
                crate::study::reversals::MoveAnalysis::new(&scenario.machine, None),
            );
            reversals_deg(rode.finish())
        }
        (None, None) => Vec::new(),
    };
    surface.set_reversals(reversals);
    let cuts = budget_cuts.map(CutBudgetRuns::finish);
    let budget = match (cuts, budget_run.map(|r| r.into_inner().finish())) {
        (Some(cuts), Some(Ok(done))) => Some(assemble(cuts, &surface, done.moved())),
        (_, Some(Err(why))) => {
            warnings.push(format!("no error budget: one of its runs failed ({why})"));
            None
        }
        _ => None,
    };
    let ballbar_um = ballbar.and_then(|b| b.run.trace_um(false).ok());
    Ok(CutRun {
        surface,
        budget,
        ballbar_um,
        sim_time_s: stats.end_time_s,
        setpoints: stats.samples,
        warnings,
    })
}

/// Cuts `scenario`'s cone ([`run_cut`]) and writes the cut's files into `dir`
/// (`report::cut`, the page titled `title`): what `mtsim cut` and `simulate --cut` both do.
pub fn cut_into(
    scenario: &Scenario,
    options: CutOptions,
    with_budget: bool,
    (dir, title): (&std::path::Path, &str),
    progress: &dyn Fn(f64),
) -> Result<(CutRun, CutFigures)> {
    let cut = run_cut(scenario, options, with_budget, progress)?;
    let figures = cut.surface.figures();
    let beside = CutBeside {
        budget: cut.budget.as_ref(),
        ballbar_um: cut.ballbar_um.as_deref(),
    };
    write_cut_files(dir, title, &cut.surface, &figures, beside)?;
    Ok((cut, figures))
}

/// `simulate --cut`: the cut of the scenario's cone by `cut`'s own path ([`cut_into`], the
/// default grid, the error budget `with_budget`), its files written into the run's folder
/// `dir`, its document (cut.json's) under `measurements.cut`. It is a pass of its own over
/// the first direction (the same program, interpolator and servos as the run's, so the same
/// samples): its marks read the linear twins and its budget its own counterfactual runs. A
/// scenario without a cone has nothing to cut: a warning.
pub fn cut_beside(
    scenario: &Scenario,
    dir: &std::path::Path,
    with_budget: bool,
    progress: &dyn Fn(f64),
) -> Result<crate::study::simulate::Beside> {
    let name = "cut".to_string();
    if test_of(scenario).cone().is_none() {
        return Ok(crate::study::simulate::Beside {
            name,
            json: None,
            warnings: vec!["--cut: the scenario has no cone to cut ([program.cone])".into()],
        });
    }
    let stem = scenario
        .path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let title = format!("Cut cone: {stem}");
    let (cut, figures) = cut_into(
        scenario,
        CutOptions::default(),
        with_budget,
        (dir, &title),
        progress,
    )?;
    let doc = crate::report::cut::CutJson {
        figures,
        budget: cut.budget,
    };
    Ok(crate::study::simulate::Beside {
        name,
        json: Some(serde_json::to_value(doc).expect("plain data serializes")),
        warnings: cut.warnings,
    })
}
