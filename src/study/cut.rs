//! `mtsim cut`: one run of a cone scenario's program through the pipeline into the cut
//! surface (`measure::cut`), with the reversal angles its marks are read at.
//!
//! The run is `simulate`'s (the same program, lead, interpolator, servo and settle gate for a
//! file program), in one direction: one piece is cut by one pass. With `commanded` the
//! samples are the interpolator's setpoints alone (no servo), which is all the cut reads then.

use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::input::scenario::Scenario;
use crate::measure::cut::{CutOptions, CutSurface};
use crate::measure::settle::SettleGate;
use crate::pipeline::{self, Sink, Timing};
use crate::program::{self, test_of};
use crate::study::reversals::reversals_deg;
use crate::study::simulate::{
    analysed_along, analyses, bar_geometry, directions_of, gates_transient, run_options,
    transient_warning,
};

/// What a cut run gives.
pub struct CutRun {
    pub surface: CutSurface,
    /// Machine time of the run, s, and its samples.
    pub sim_time_s: f64,
    pub setpoints: u64,
    /// What the user should know (a start-up transient left out, a feed held below F).
    pub warnings: Vec<String>,
}

/// Cuts `scenario`'s cone with `options`. `progress` is told the machine time now and then.
pub fn run_cut(scenario: &Scenario, options: CutOptions, progress: &dyn Fn(f64)) -> Result<CutRun> {
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
    let mut surface = CutSurface::new(scenario, &cone, options, Vec::new())?;
    let mut run = program::scenario_run(scenario, direction, scenario.simulate.lead_deg)?;
    if let Some(along) = &along {
        run.moves = analysed_along(run.moves, along);
    }
    surface.start_run(direction, run.measured);
    let mut run_options = run_options(scenario, 0.0)?;
    run_options.timing = if commanded {
        Timing::Setpoints
    } else {
        Timing::Planned {
            twins: false,
            settle: false,
        }
    };
    let mut warnings = Vec::new();
    let stats = match bar_geometry(scenario).filter(|_| gates_transient(scenario)) {
        Some(g) => {
            let mut gate = SettleGate::new(
                vec![&mut surface as &mut dyn Sink],
                run.measured,
                Box::new(move |s| g.read_commanded(&s.commanded).theta_deg),
            );
            let stats = pipeline::run(
                run.moves,
                &scenario.machine,
                &run_options,
                &mut [&mut gate],
                progress,
            )?;
            warnings.extend(transient_warning(&gate));
            stats
        }
        None => pipeline::run(
            run.moves,
            &scenario.machine,
            &run_options,
            &mut [&mut surface],
            progress,
        )?,
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
    Ok(CutRun {
        surface,
        sim_time_s: stats.end_time_s,
        setpoints: stats.samples,
        warnings,
    })
}
