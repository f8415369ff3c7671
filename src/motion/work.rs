//! The work a run will do, known before it samples: a lower bound on its machine time, from
//! the program and the machine, checked against the run's budget (`input::budget`).
//!
//! A generated test's path is known in closed form ([`budget::SampleEstimate`]). A G-code
//! file is read once ahead of the run (the moves only: no planning, no servo), and each
//! canonical move adds its programmed duration ([`block_duration_s`]):
//!
//! ```text
//! t_feed  = L / F            (G94; L the length F is the rate of: docs/interpolation.md)
//! t_feed  = 1 / F   min      (G93)
//! t_rapid = max_i |Δq_i| / v_max,i
//! t_dwell = P
//! ```
//!
//! The first move, which only places the machine (its start is unknown), adds nothing.
//! That is the time `check --programmed` takes, and a lower bound on the planner's (it
//! never exceeds F or an axis's top speed, and adds ramps). A program whose sum already passes
//! the budget would pass it when run: it is refused before the first sample, with the line
//! reached. The read stops there, so a program that loops for ever is refused after
//! `max_samples · Δt` of machine time has been read, not sampled.

use std::f64::consts::TAU;
use std::path::Path;

use crate::error::{Error, Result};
use crate::input::budget;
use crate::input::program::Direction;
use crate::input::scenario::Scenario;
use crate::motion::sampling::block_duration_s;
use crate::program::{file, test_of, validate, Move};

/// What the read-ahead of a file program found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FileWork {
    /// Canonical moves read.
    pub moves: u64,
    /// Programmed machine time of those moves (the first excepted), s.
    pub machine_time_s: f64,
}

/// Reads `scenario`'s file program ahead of its run and adds up its least machine time,
/// stopping with an error as soon as that passes the sample budget.
///
/// A file's moves are lent by the reader and checked in place ([`validate::move_checker`],
/// the checks `program::scenario_run` makes as its moves stream): the same moves and the
/// same first error, without copying each move through the run's iterator layers
/// (docs/performance.md "Session 27: the fine file below 1.5").
pub fn read_ahead(scenario: &Scenario) -> Result<FileWork> {
    let mut work = WorkSum::new(scenario);
    let test = test_of(scenario);
    let Some(path) = test.file() else {
        let run = crate::program::scenario_run(scenario, Direction::Ccw, 0.0)?;
        for m in run.moves {
            work.add(&m?)?;
        }
        return Ok(work.work);
    };
    let machine = &scenario.machine;
    let mut reader = file::read_moves(path, &scenario.reader)?;
    let mut checker = validate::move_checker(path, machine, scenario.simulate.tcp);
    while let Some(m) = reader.next_ref() {
        let m = m?;
        checker.check(m)?;
        work.add(m)?;
    }
    checker.end()?;
    Ok(work.work)
}

/// The read-ahead's running sum of [`read_ahead`], refused once past the sample budget.
struct WorkSum<'a> {
    scenario: &'a Scenario,
    work: FileWork,
}

impl<'a> WorkSum<'a> {
    fn new(scenario: &'a Scenario) -> Self {
        WorkSum {
            scenario,
            work: FileWork::default(),
        }
    }

    /// Adds move `m`'s least duration; an error once the sum passes the budget.
    fn add(&mut self, m: &Move) -> Result<()> {
        let machine = &self.scenario.machine;
        let work = &mut self.work;
        // The first move only places the machine: its start is unknown, and no run samples
        // the path to it.
        let t = if work.moves == 0 {
            0.0
        } else {
            block_duration_s(m, machine)?
        };
        work.moves += 1;
        work.machine_time_s += t;
        let samples = work.machine_time_s / machine.interpolation_period_s;
        if samples > self.scenario.simulate.max_samples as f64 {
            return Err(over_budget(self.scenario, work, m.line, samples));
        }
        Ok(())
    }
}

fn over_budget(scenario: &Scenario, work: &FileWork, line: usize, samples: f64) -> Error {
    let message = format!(
        "the program needs more than {:.3e} samples, over the budget of {} ([simulate] max_samples of {}): \
         read ahead to this line, its {} moves take at least {} of machine time, sampled every {} ms",
        samples,
        scenario.simulate.max_samples,
        scenario.path.display(),
        work.moves,
        budget::duration(work.machine_time_s),
        scenario.machine.interpolation_period_s * 1e3,
    );
    let program = test_of(scenario)
        .file()
        .map_or_else(|| scenario.path.clone(), Path::to_path_buf);
    Error::Located {
        path: program,
        line,
        column: 1,
        message,
        help: Some(
            "shorten the program (a loop without end? feeds near zero?), lengthen the machine's \
             interpolation_period_ms, or raise [simulate] max_samples"
                .into(),
        ),
    }
}

/// Refuses a traced run whose samples would pass the budget ([`check_up_front`]) or whose
/// trace would pass `[simulate] max_trace_rows`: the measured revolution's least machine time
/// over the period and `trace_every`, in every direction (`2π r / F` for a generated test;
/// a file's rows are counted while it runs).
pub fn check_trace_up_front(scenario: &Scenario, lead_deg: f64) -> Result<()> {
    let sim = &scenario.simulate;
    let test = test_of(scenario);
    // A file's measured revolution starts where its axes have settled, known only while it
    // runs: its rows are counted then (report/trace.rs).
    let Some(revolution) = test.revolution() else {
        return Ok(());
    };
    budget::check_up_front(scenario, Some(revolution), lead_deg)?;
    let measured_time_s = TAU * revolution.radius_mm / (revolution.feed_mm_min / 60.0);
    let directions = test.directions().len();
    let rows = measured_time_s / scenario.machine.interpolation_period_s / sim.trace_every as f64
        * directions as f64;
    if rows <= sim.max_trace_rows as f64 {
        return Ok(());
    }
    Err(Error::invalid(
        &scenario.path,
        format!(
            "the trace would hold about {rows:.3e} rows, more than the budget of {} ([simulate] max_trace_rows): \
             {} of measured machine time in {directions} direction(s), sampled every {} ms, {} traced",
            sim.max_trace_rows,
            budget::duration(measured_time_s),
            scenario.machine.interpolation_period_s * 1e3,
            traced(sim.trace_every),
        ),
    )
    .with_help("raise [simulate] trace_every or max_trace_rows, or shorten the measured revolution (a higher feed)"))
}

/// `every sample`, `every 2nd sample`, ...: what the trace keeps.
fn traced(n: usize) -> String {
    if n == 1 {
        return "every sample".into();
    }
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("every {n}{suffix} sample")
}

/// The sample budget of a run of `scenario`, after checking its estimate: the closed form of a
/// generated test, the read-ahead of a file ([`read_ahead`]).
pub fn check_up_front(scenario: &Scenario, lead_deg: f64) -> Result<u64> {
    check_up_front_timed(scenario, lead_deg).map(|(budget, _)| budget)
}

/// [`check_up_front`], with the run's least machine time (s): the closed form of a generated
/// test ([`budget::SampleEstimate`]), the read-ahead's sum for a file. For a progress bar.
pub fn check_up_front_timed(scenario: &Scenario, lead_deg: f64) -> Result<(u64, f64)> {
    let revolution = test_of(scenario).revolution();
    let least_s = match revolution {
        None => read_ahead(scenario)?.machine_time_s,
        Some(r) => budget::SampleEstimate::of(scenario, &r, lead_deg).machine_time_s,
    };
    Ok((
        budget::check_up_front(scenario, revolution, lead_deg)?,
        least_s,
    ))
}
