//! The one pipeline every command runs:
//!
//! ```text
//! canonical moves ─► setpoints ─► actual axis positions ─► sinks
//!   (program)         (motion)       (drive)               (measure, check, report)
//! ```
//!
//! Two timings feed it. *Programmed*: the moves sampled at the time their words ask for,
//! with no planning and no servo (what the program demands, for `check`). *Planned*: the
//! look-ahead interpolator and the servo models (what the machine does, for `simulate` and
//! `check --dynamics`). Every stage streams: one move, one setpoint, one sample at a time,
//! so memory does not grow with the program. No stage reaches back.

use std::path::PathBuf;

use crate::drive::Drives;
use crate::error::Result;
use crate::input::machine::Machine;
use crate::motion::interpolation::{InterpolationOptions, Interpolator};
use crate::motion::sampling::NominalSampler;
use crate::program::Moves;
use crate::AxisVec;

/// What every sink sees, once per interpolation period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Index of the sample in its run, from 0.
    pub index: u64,
    /// Time, s, counted from the run's `start_time_s`.
    pub time_s: f64,
    /// Source line of the move being executed.
    pub line: usize,
    /// 0-based position of that move in the stream.
    pub block_index: u64,
    /// The setpoint, mm and deg.
    pub commanded: AxisVec,
    /// The table-side axis positions, mm and deg (the setpoint under programmed timing),
    /// with each axis's position error (pitch, worm gear: `machine.geometry.tables`) added
    /// for its direction of motion.
    pub actual: AxisVec,
    /// `commanded - actual` as the drives report it, mm and deg.
    pub following_error: AxisVec,
    /// The linear twin's actual positions (the drives without dry friction and backlash),
    /// with the direction-free (mean) part of the position errors; `actual` when no twin runs.
    pub linear: AxisVec,
}

/// A consumer of samples: the ball bar, the limits monitor, the collision scene, the trace.
pub trait Sink {
    fn push(&mut self, sample: &Sample) -> Result<()>;
}

/// How samples are timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Timing {
    /// At the timing the program's words ask for; no planning, no servo.
    Programmed,
    /// Look-ahead interpolation and the servo models.
    Planned {
        /// Also run the linear twins, for [`Sample::linear`].
        twins: bool,
        /// After the last setpoint, hold it until every axis has settled (for at most
        /// [`SETTLE_S`]), so that an overshoot at the end is seen too.
        settle: bool,
    },
}

/// Longest time the drives are given to settle after the last setpoint, s.
pub const SETTLE_S: f64 = 2.0;

/// Options of one run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub timing: Timing,
    /// Treat every feed move as tool-centre-point controlled (as if G43.4 were on).
    pub force_tcp: bool,
    /// Added to every sample's time, s (runs of one study follow each other).
    pub start_time_s: f64,
    /// The program's name, for messages.
    pub program_path: PathBuf,
}

/// What a run did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunStats {
    pub samples: u64,
    /// Time of the last sample, s (including `start_time_s`).
    pub end_time_s: f64,
}

/// Runs `moves` on `machine` and hands every sample to each sink in turn. `progress` is told
/// the time now and then.
pub fn run(
    moves: Moves<'_>,
    machine: &Machine,
    options: &RunOptions,
    sinks: &mut [&mut dyn Sink],
    progress: &dyn Fn(f64),
) -> Result<RunStats> {
    let t0 = options.start_time_s;
    let mut stats = RunStats {
        samples: 0,
        end_time_s: t0,
    };
    // Position-dependent errors of the axes (pitch, worm gear), for their direction of motion.
    let mut position_errors = machine.geometry.position_errors();
    let mut emit = |sample: &Sample, stats: &mut RunStats| -> Result<()> {
        for sink in sinks.iter_mut() {
            sink.push(sample)?;
        }
        stats.samples += 1;
        stats.end_time_s = sample.time_s;
        if sample.index % 4096 == 0 {
            progress(sample.time_s);
        }
        Ok(())
    };
    match options.timing {
        Timing::Programmed => {
            for (k, s) in
                NominalSampler::new(moves, machine, machine.interpolation_period_s).enumerate()
            {
                let s = s?;
                let actual = position_errors.apply(&s.q);
                let sample = Sample {
                    index: k as u64,
                    time_s: t0 + s.time_s,
                    line: s.line,
                    block_index: s.block_index,
                    commanded: s.q,
                    actual,
                    following_error: AxisVec::ZERO,
                    linear: position_errors.apply_mean(&s.q),
                };
                emit(&sample, &mut stats)?;
            }
        }
        Timing::Planned { twins, settle } => {
            let interpolation = InterpolationOptions {
                force_tcp: options.force_tcp,
                program_path: options.program_path.clone(),
                ..InterpolationOptions::default()
            };
            let mut setpoints = Interpolator::new(moves, machine, interpolation)?.peekable();
            let first = match setpoints.peek() {
                Some(Ok(sp)) => sp.q,
                Some(Err(_)) => {
                    return Err(setpoints
                        .next()
                        .expect("peeked")
                        .expect_err("peeked an error"))
                }
                None => return Ok(stats),
            };
            let mut drives = Drives::new(machine, &first, false)?;
            let mut linear = if twins {
                Some(Drives::new(machine, &first, true)?)
            } else {
                None
            };
            let mut last = None;
            for (k, sp) in setpoints.enumerate() {
                let sp = sp?;
                let t = t0 + sp.time_s;
                let state = drives.step(&sp.q, t)?;
                let actual = position_errors.apply(&state.actual);
                let twin = match linear.as_mut() {
                    Some(d) => position_errors.apply_mean(&d.step_actual(&sp.q, t)?),
                    None => actual,
                };
                let sample = Sample {
                    index: k as u64,
                    time_s: t,
                    line: sp.line,
                    block_index: sp.block_index,
                    commanded: sp.q,
                    actual,
                    following_error: state.following_error,
                    linear: twin,
                };
                emit(&sample, &mut stats)?;
                if settle {
                    last = Some(sample);
                }
            }
            // The setpoints end at rest, the axes not yet: hold the last setpoint until
            // every axis has settled, for at most SETTLE_S.
            if let (true, Some(end)) = (settle, last) {
                let period = machine.interpolation_period_s;
                for k in 1..=(SETTLE_S / period).round() as u64 {
                    let t = end.time_s + k as f64 * period;
                    let state = drives.step(&end.commanded, t)?;
                    let actual = position_errors.apply(&state.actual);
                    let twin = match linear.as_mut() {
                        Some(d) => position_errors.apply_mean(&d.step_actual(&end.commanded, t)?),
                        None => actual,
                    };
                    let sample = Sample {
                        index: end.index + k,
                        time_s: t,
                        actual,
                        following_error: state.following_error,
                        linear: twin,
                        ..end
                    };
                    emit(&sample, &mut stats)?;
                    if state.settled {
                        break;
                    }
                }
            }
        }
    }
    Ok(stats)
}
