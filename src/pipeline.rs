//! The one pipeline every command runs:
//!
//! ```text
//! canonical moves ─► setpoints ─► actual axis positions ─► sinks
//!   (program)         (motion)       (drive)               (measure, check, report)
//! ```
//!
//! Three timings feed it. *Programmed*: the moves sampled at the time their words ask for,
//! with no planning and no servo (what the program demands, `check --programmed`).
//! *Setpoints*: the look-ahead interpolator alone (what the control commands, `check`).
//! *Planned*: the interpolator and the servo models (what the machine does, for `simulate`
//! and `check --dynamics`). Every stage streams: one move, one setpoint, one sample at a time,
//! so memory does not grow with the program. No stage reaches back.

use std::path::PathBuf;

use crate::drive::{DriveLanes, Drives};
use crate::error::Result;
use crate::input::budget;
use crate::input::machine::Machine;
use crate::kinematics::error_table::PositionErrors;
use crate::motion::feed_held::FeedReduction;
use crate::motion::interpolation::{InterpolationOptions, Interpolator, Setpoint};
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

impl Sample {
    /// A sample at time `t0` (s) with every position zero, to be written in place.
    #[inline(always)]
    pub(crate) fn blank(t0: f64) -> Sample {
        Sample {
            index: 0,
            time_s: t0,
            line: 0,
            block_index: 0,
            commanded: AxisVec::ZERO,
            actual: AxisVec::ZERO,
            following_error: AxisVec::ZERO,
            linear: AxisVec::ZERO,
        }
    }
}

/// A consumer of samples: the ball bar, the limits monitor, the collision scene, the trace.
pub trait Sink {
    fn push(&mut self, sample: &Sample) -> Result<()>;

    /// [`Sink::push`] of each of `samples` in order (a sink may take them in one call: the
    /// points of [`run_lanes`] take a few samples at a time).
    fn push_many(&mut self, samples: &[Sample]) -> Result<()> {
        samples.iter().try_for_each(|s| self.push(s))
    }
}

/// How samples are timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Timing {
    /// At the timing the program's words ask for; no planning, no servo.
    Programmed,
    /// The look-ahead interpolator's setpoints, as the control commands them; no servo.
    Setpoints,
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
    /// Most samples the run may take ([`crate::input::budget`]); passing it stops the run
    /// with an error that names the line reached.
    pub max_samples: u64,
}

/// What a run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunStats {
    pub samples: u64,
    /// Time of the last sample, s (including `start_time_s`).
    pub end_time_s: f64,
    /// Feed blocks the planner ran below their F word, per axis and limit (planned timing).
    pub feed_reductions: Vec<FeedReduction>,
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
        feed_reductions: Vec::new(),
    };
    // Position-dependent errors of the axes (pitch, worm gear), for their direction of motion.
    let mut position_errors = machine.geometry.position_errors();
    let mut emit = |sample: &Sample, stats: &mut RunStats| -> Result<()> {
        if stats.samples >= options.max_samples {
            return Err(budget::exceeded(
                &options.program_path,
                options.max_samples,
                sample.line,
                sample.time_s - t0,
            ));
        }
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
        Timing::Programmed => run_programmed(
            moves,
            machine,
            t0,
            &mut position_errors,
            &mut emit,
            &mut stats,
        )?,
        Timing::Setpoints => {
            let mut setpoints = Interpolator::new(moves, machine, interpolation(options, machine))?;
            let mut sample = Sample::blank(t0);
            let mut k = 0u64;
            while let Some(sp) = setpoints.next().transpose()? {
                sample.index = k;
                sample.time_s = t0 + sp.time_s;
                sample.line = sp.line;
                sample.block_index = sp.block_index;
                sample.commanded = sp.q;
                at_commanded(&mut sample, &mut position_errors);
                emit(&sample, &mut stats)?;
                k += 1;
            }
            stats.feed_reductions = setpoints.feed_reductions();
        }
        Timing::Planned { twins, settle } => {
            // One setpoint at a time, moved as little as possible (no `Peekable` or
            // `Enumerate` layers: each is another copy of the setpoint and its `Result`).
            let mut setpoints = Interpolator::new(moves, machine, interpolation(options, machine))?;
            let Some(first) = setpoints.next().transpose()? else {
                return Ok(stats);
            };
            let mut drives = Drives::new(machine, &first.q, false)?;
            let mut linear = if twins {
                Some(Drives::new(machine, &first.q, true)?)
            } else {
                None
            };
            // One sample for the whole run, its vectors written in place by the drives.
            let mut sample = Sample {
                index: 0,
                time_s: t0 + first.time_s,
                line: first.line,
                block_index: first.block_index,
                commanded: first.q,
                actual: first.q,
                following_error: AxisVec::ZERO,
                linear: first.q,
            };
            let mut next = Some(first);
            let mut k = 0u64;
            while let Some(sp) = next {
                sample.index = k;
                sample.time_s = t0 + sp.time_s;
                sample.line = sp.line;
                sample.block_index = sp.block_index;
                sample.commanded = sp.q;
                drive_sample(
                    &mut sample,
                    &mut drives,
                    linear.as_mut(),
                    &mut position_errors,
                )?;
                emit(&sample, &mut stats)?;
                next = setpoints.next().transpose()?;
                k += 1;
            }
            stats.feed_reductions = setpoints.feed_reductions();
            // The setpoints end at rest, the axes not yet: hold the last setpoint until
            // every axis has settled, for at most SETTLE_S.
            if settle {
                let period = machine.interpolation_period_s;
                let (end_index, end_time_s) = (sample.index, sample.time_s);
                for k in 1..=(SETTLE_S / period).round() as u64 {
                    sample.index = end_index + k;
                    sample.time_s = end_time_s + k as f64 * period;
                    let settled = drive_sample(
                        &mut sample,
                        &mut drives,
                        linear.as_mut(),
                        &mut position_errors,
                    )?;
                    emit(&sample, &mut stats)?;
                    if settled {
                        break;
                    }
                }
            }
        }
    }
    Ok(stats)
}

/// [`run`] under planned timing with twins, for several points that share `moves`: one
/// interpolation pass, its setpoints fed to the points' drives ([`DriveLanes`], one machine
/// per point, alike but for their drives: each distinct drive of an axis stepped once) and
/// each point's samples to its own sink.
/// `options.timing` is not read (planned, twins, no settling). Returns the run's figures
/// (the same for every point) and which points failed (their drives diverged; their
/// samples stopped there): a failed point is run alone for its error.
pub fn run_lanes(
    moves: Moves<'_>,
    machines: &[&Machine],
    options: &RunOptions,
    sinks: &mut [&mut dyn Sink],
    progress: &dyn Fn(f64),
) -> Result<(RunStats, Vec<bool>)> {
    let t0 = options.start_time_s;
    let mut stats = RunStats {
        samples: 0,
        end_time_s: t0,
        feed_reductions: Vec::new(),
    };
    let machine = machines[0];
    let mut setpoints = Interpolator::new(moves, machine, interpolation(options, machine))?;
    let Some(first) = setpoints.next().transpose()? else {
        return Ok((stats, vec![false; machines.len()]));
    };
    let mut lanes = DriveLanes::new(machines, &first.q)?;
    let mut errors: Vec<PositionErrors> = machines
        .iter()
        .map(|m| m.geometry.position_errors())
        .collect();
    // Setpoints go to the drives a block at a time, each distinct servo through the whole
    // block (its state stays in cache), then to the points. Memory: one block, whatever
    // the program's length.
    let mut block: Vec<Setpoint> = Vec::with_capacity(LANE_BLOCK);
    let mut block_q: Vec<AxisVec> = Vec::with_capacity(LANE_BLOCK);
    let mut block_t: Vec<f64> = Vec::with_capacity(LANE_BLOCK);
    // The block's samples: what the points share written once a block, each point's
    // drive outputs over them in turn.
    let mut samples: Vec<Sample> = Vec::with_capacity(LANE_BLOCK);
    let mut alive = vec![true; machines.len()];
    let mut next = Some(first);
    let mut k = 0u64;
    while next.is_some() {
        block.clear();
        while let Some(sp) = next.take() {
            if stats.samples >= options.max_samples {
                return Err(budget::exceeded(
                    &options.program_path,
                    options.max_samples,
                    sp.line,
                    t0 + sp.time_s - t0,
                ));
            }
            stats.samples += 1;
            stats.end_time_s = t0 + sp.time_s;
            block.push(sp);
            if block.len() == LANE_BLOCK {
                next = setpoints.next().transpose()?;
                break;
            }
            next = setpoints.next().transpose()?;
        }
        block_q.clear();
        block_q.extend(block.iter().map(|sp| sp.q));
        block_t.clear();
        block_t.extend(block.iter().map(|sp| t0 + sp.time_s));
        lanes.step_block(&block_q, &block_t);
        samples.clear();
        samples.extend(block.iter().enumerate().map(|(j, sp)| Sample {
            index: k + j as u64,
            time_s: block_t[j],
            line: sp.line,
            block_index: sp.block_index,
            commanded: sp.q,
            // Axes without a drive stay at their setpoint.
            actual: sp.q,
            following_error: AxisVec::ZERO,
            linear: sp.q,
        }));
        for (i, sink) in sinks.iter_mut().enumerate() {
            if !alive[i] {
                continue;
            }
            // A point stops at the setpoint where one of its drives or twins failed.
            let completed = lanes.completed(i).min(block.len());
            alive[i] = completed == block.len();
            // Every axis with a position-error table is a driven axis (the tables are
            // refused on others), so the point's drive outputs overwrite whatever the last
            // point's errors left in the block's samples. A few samples at a time, so that
            // they are still in the L1 cache when the sink reads them.
            for start in (0..completed).step_by(SINK_CHUNK) {
                let chunk = start..(start + SINK_CHUNK).min(completed);
                let samples = &mut samples[chunk.clone()];
                for (a, actual, following_error, linear) in lanes.outputs(i) {
                    let outputs = actual[chunk.clone()]
                        .iter()
                        .zip(&following_error[chunk.clone()])
                        .zip(&linear[chunk.clone()]);
                    for (sample, ((&actual, &following_error), &linear)) in
                        samples.iter_mut().zip(outputs)
                    {
                        sample.actual[a] = actual;
                        sample.following_error[a] = following_error;
                        sample.linear[a] = linear;
                    }
                }
                for sample in samples.iter_mut() {
                    errors[i].apply_in_place(&mut sample.actual);
                    errors[i].apply_mean_in_place(&mut sample.linear);
                }
                sink.push_many(samples)?;
            }
        }
        if k / 4096 != (k + block.len() as u64) / 4096 || k == 0 {
            progress(stats.end_time_s);
        }
        k += block.len() as u64;
    }
    stats.feed_reductions = setpoints.feed_reductions();
    let failed = alive.iter().map(|&a| !a).collect();
    Ok((stats, failed))
}

/// Setpoints handed to the drives of [`run_lanes`] at a time.
const LANE_BLOCK: usize = crate::drive::lanes::BLOCK;

/// Samples of a block a point's drive outputs are written into and pushed to its sink at
/// a time in [`run_lanes`]: 32 samples (10 kB) stay in the L1 cache between the two, where
/// a whole block (82 kB), written axis by axis, did not.
const SINK_CHUNK: usize = 32;

/// The interpolator's options for a run on `machine` (its control's look-ahead depth).
fn interpolation(options: &RunOptions, machine: &Machine) -> InterpolationOptions {
    InterpolationOptions {
        force_tcp: options.force_tcp,
        program_path: options.program_path.clone(),
        ..InterpolationOptions::for_machine(machine)
    }
}

/// One interpolation period of the drives (and of their linear twins) towards
/// `sample.commanded`, reached at `sample.time_s`, written into the sample's actual,
/// following-error and linear vectors with the position errors applied. Returns whether
/// every axis has settled.
#[inline]
fn drive_sample(
    sample: &mut Sample,
    drives: &mut Drives,
    twins: Option<&mut Drives>,
    errors: &mut PositionErrors,
) -> Result<bool> {
    // Axes without a drive stay at their setpoint.
    sample.actual = sample.commanded;
    let settled = drives.step_into(
        &sample.commanded,
        sample.time_s,
        &mut sample.actual,
        &mut sample.following_error,
    )?;
    errors.apply_in_place(&mut sample.actual);
    match twins {
        Some(d) => {
            sample.linear = sample.commanded;
            d.step_actual_into(&sample.commanded, sample.time_s, &mut sample.linear)?;
            errors.apply_mean_in_place(&mut sample.linear);
        }
        None => sample.linear = sample.actual,
    }
    Ok(settled)
}

/// A sample without a servo: the table at the setpoint, with the position errors for its
/// direction of motion (`actual`) and their mean (`linear`).
#[inline(always)]
fn at_commanded(sample: &mut Sample, errors: &mut PositionErrors) {
    sample.actual = sample.commanded;
    errors.apply_in_place(&mut sample.actual);
    sample.linear = sample.commanded;
    errors.apply_mean_in_place(&mut sample.linear);
}

/// The emitter of [`run`]: hands a sample to every sink and counts it.
type Emit<'e> = dyn FnMut(&Sample, &mut RunStats) -> Result<()> + 'e;

/// [`Timing::Programmed`]: the moves sampled at their programmed timing, one sample for
/// the whole run written field by field (a sample built anew and moved is a copy whose loads
/// wait on the stores just made).
fn run_programmed(
    moves: Moves<'_>,
    machine: &Machine,
    t0: f64,
    errors: &mut PositionErrors,
    emit: &mut Emit<'_>,
    stats: &mut RunStats,
) -> Result<()> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX, checked at run time just above.
        return unsafe { run_programmed_avx(moves, machine, t0, errors, emit, stats) };
    }
    run_programmed_inline(moves, machine, t0, errors, emit, stats)
}

/// [`run_programmed`] compiled for AVX: the sample's positions are then written 32 bytes
/// at a time, as the limits monitor (AVX) reads them; 16-byte stores read back by a
/// 32-byte load stall store forwarding. No FMA: the figures are those of the plain build.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn run_programmed_avx(
    moves: Moves<'_>,
    machine: &Machine,
    t0: f64,
    errors: &mut PositionErrors,
    emit: &mut Emit<'_>,
    stats: &mut RunStats,
) -> Result<()> {
    run_programmed_inline(moves, machine, t0, errors, emit, stats)
}

#[inline(always)]
fn run_programmed_inline(
    moves: Moves<'_>,
    machine: &Machine,
    t0: f64,
    errors: &mut PositionErrors,
    emit: &mut Emit<'_>,
    stats: &mut RunStats,
) -> Result<()> {
    let mut sample = Sample::blank(t0);
    let mut sampler = NominalSampler::new(moves, machine, machine.interpolation_period_s);
    let mut k = 0u64;
    while let Some(at) = sampler.next_into(&mut sample.commanded)? {
        sample.index = k;
        sample.time_s = t0 + at.time_s;
        sample.line = at.line;
        sample.block_index = at.block_index;
        at_commanded(&mut sample, errors);
        emit(&sample, stats)?;
        k += 1;
    }
    Ok(())
}
