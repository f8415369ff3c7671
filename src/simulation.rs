//! `mtsim simulate`: the whole pipeline, streamed.
//!
//! program (generated or file) → blocks → interpolator (setpoints every period) → one
//! servo per axis → actual axis positions → forward kinematics → virtual ball bar → trace,
//! figures and plot. Memory does not grow with the program: setpoints are consumed as
//! they come, the ball bar keeps fixed θ bins, and the trace goes to disk as it is made.
//!
//! The trace's centred deviation needs the least-squares centre of the whole run, known
//! only at its end, so the trace is written raw to a temporary file first and completed
//! from it line by line; `trace.csv` appears only when complete.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::{Point3, Vector3};
use serde::Serialize;

use crate::analysis::{analyse_blocks, analyse_circle, analyse_cone, Analysis};
use crate::axis::{Axis, AxisVec};
use crate::ballbar::{
    analyse_events_of, deviation_mm, BallbarResult, BallbarRun, CircleFrame, Direction,
};
use crate::circle;
use crate::cone::{self, ConePath, MeasuredLines, NcOptions};
use crate::error::{Error, Result};
use crate::gcode::{self, Block};
use crate::interpolation::{InterpolationOptions, Interpolator};
use crate::machine::Machine;
use crate::report::{push_fixed, temporary_path};
use crate::scenario::{Program, Scenario};
use crate::servo::AxisServo;

/// The virtual ball bar of a test: the measured circle, the table ball and the bar length.
#[derive(Clone, Copy, Debug)]
pub struct BallbarSetup {
    pub frame: CircleFrame,
    /// Table-side ball, table frame, mm.
    pub pivot_table_mm: Point3<f64>,
    /// Nominal bar length L, mm.
    pub length_mm: f64,
}

/// One program to run: generated text or a file, the lines of its measured revolution.
struct RunPlan {
    direction: Direction,
    source: ProgramSource,
    /// Lines whose samples enter the ball bar; `None`: every feed move after the first block.
    measured: Option<MeasuredLines>,
}

enum ProgramSource {
    Text(String),
    File(PathBuf),
}

/// What a simulation found.
#[derive(Clone, Debug, Serialize)]
pub struct SimulationSummary {
    /// Simulated machine time over all runs, s.
    pub sim_time_s: f64,
    /// Simulated seconds per wall-clock second (null with `--no-timing`).
    pub realtime_factor: Option<f64>,
    /// Wall-clock time of the simulation, s (null with `--no-timing`).
    pub wall_time_s: Option<f64>,
    /// Interpolation periods simulated.
    pub setpoints: u64,
    /// The ball-bar figures and events; null when the program has no measured circle.
    pub ballbar: Option<BallbarResult>,
    /// Each axis's reversal angles from the analysis, deg (what the spikes are attributed to).
    pub reversals_deg: std::collections::BTreeMap<String, Vec<f64>>,
    /// The directions run.
    pub directions: Vec<Direction>,
}

/// Files a simulation writes into its output folder.
pub const TRACE_FILE: &str = "trace.csv";
pub const SUMMARY_FILE: &str = "summary.json";
pub const PLOT_FILE: &str = "ballbar.svg";

/// Runs the scenario and writes `trace.csv`, `summary.json` and `ballbar.svg` to `out_dir`.
/// `progress` is told the simulated time, s, now and then.
pub fn simulate(
    scenario: &Scenario,
    out_dir: &Path,
    timing: bool,
    progress: &dyn Fn(f64),
) -> Result<SimulationSummary> {
    let machine = &scenario.machine;
    let (plans, setup, analysis) = plan(scenario)?;
    let reversals: Vec<(Axis, Vec<f64>)> = analysis
        .axes
        .iter()
        .map(|a| (a.axis, a.reversals_deg.clone()))
        .collect();
    std::fs::create_dir_all(out_dir).map_err(|source| Error::Write {
        path: out_dir.to_path_buf(),
        source,
    })?;
    let trace_path = out_dir.join(TRACE_FILE);
    let raw_path = out_dir.join("trace.csv.raw.tmp");
    let write_err = |path: &Path| {
        let path = path.to_path_buf();
        move |source| Error::Write {
            path: path.clone(),
            source,
        }
    };
    let mut raw = BufWriter::new(File::create(&raw_path).map_err(write_err(&raw_path))?);
    let axes = machine.axes();
    let mut header = String::from("direction,time_s,line,theta_deg");
    for a in axes {
        let u = a.unit();
        let _ = write!(header, ",{a}_cmd_{u},{a}_act_{u},{a}_ferr_{u}");
    }
    header.push_str(",nonlinear_um,deviation_um");

    let started = Instant::now();
    let mut runs = Vec::new();
    let mut signatures = Vec::new();
    let mut sim_time_s = 0.0;
    let mut setpoints = 0u64;
    let mut row: Vec<f64> = Vec::with_capacity(6 + 3 * axes.len());
    let kin = machine.kinematics;
    for plan in &plans {
        let blocks: Box<dyn Iterator<Item = Result<Block>>> = match &plan.source {
            ProgramSource::Text(text) => {
                Box::new(gcode::read_str(&scenario.path, text, AxisVec::ZERO))
            }
            ProgramSource::File(path) => Box::new(gcode::read_file(path, AxisVec::ZERO)?),
        };
        let options = InterpolationOptions {
            force_tcp: scenario.simulate.tcp,
            program_path: scenario.path.clone(),
            ..InterpolationOptions::default()
        };
        let mut interpolator = Interpolator::new(blocks, machine, options)?.peekable();
        let first = match interpolator.peek() {
            Some(Ok(sp)) => sp.q,
            Some(Err(_)) => {
                return Err(interpolator
                    .next()
                    .expect("peeked")
                    .expect_err("peeked an error"))
            }
            None => continue,
        };
        let mut servos = machine_servos(machine, &first, false)?;
        // The linear twin: the same drives without dry friction and backlash, stepped on the
        // same setpoints. Trace minus twin is what the nonlinearities alone do to the trace.
        let mut twins = machine_servos(machine, &first, true)?;
        let mut run = BallbarRun::new(plan.direction);
        let mut signature = BallbarRun::new(plan.direction);
        let run_start_s = sim_time_s;
        let mut last_t = 0.0;
        for (k, sp) in interpolator.enumerate() {
            let sp = sp?;
            let t = run_start_s + sp.time_s;
            last_t = sp.time_s;
            let mut actual = sp.q;
            let mut ferr = AxisVec::ZERO;
            let mut linear = sp.q;
            for ((servo, twin), &a) in servos.iter_mut().zip(twins.iter_mut()).zip(axes) {
                let state = servo.step(sp.q[a], t)?;
                actual[a] = state.actual;
                ferr[a] = state.following_error;
                linear[a] = twin.step(sp.q[a], t)?.actual;
            }
            setpoints += 1;
            if k % 4096 == 0 {
                progress(t);
            }
            let Some(setup) = &setup else { continue };
            let measured = match plan.measured {
                Some(m) => (m.first..=m.last).contains(&sp.line),
                None => sp.block_index >= 1,
            };
            if !measured {
                continue;
            }
            let theta = setup.frame.theta_deg(&kin.forward(&sp.q).tip);
            let dev_um = deviation_mm(&kin, &actual, &setup.pivot_table_mm, setup.length_mm) * 1e3;
            let nonlinear_um =
                dev_um - deviation_mm(&kin, &linear, &setup.pivot_table_mm, setup.length_mm) * 1e3;
            run.push(theta, dev_um);
            signature.push(theta, nonlinear_um);
            if k % scenario.simulate.trace_every == 0 {
                // Binary now, text once the centring is known (see `complete_trace`).
                row.clear();
                row.extend_from_slice(&[
                    if plan.direction == Direction::Cw {
                        1.0
                    } else {
                        0.0
                    },
                    t,
                    sp.line as f64,
                    theta,
                ]);
                for &a in axes {
                    row.extend_from_slice(&[sp.q[a], actual[a], ferr[a]]);
                }
                row.extend_from_slice(&[nonlinear_um, dev_um]);
                for v in &row {
                    raw.write_all(&v.to_le_bytes())
                        .map_err(write_err(&raw_path))?;
                }
            }
        }
        sim_time_s += last_t;
        if setup.is_some() {
            runs.push(run);
            signatures.push(signature);
        }
    }
    raw.flush().map_err(write_err(&raw_path))?;
    drop(raw);

    // Figures from the trace; spikes and steps from the nonlinear signature, so that the
    // linear response to the program (the lag ellipse, the ripple of 1-deg blocks) is not
    // taken for them.
    let ballbar = if runs.is_empty() {
        None
    } else {
        Some(analyse_events_of(&runs, &signatures, &reversals)?)
    };
    complete_trace(&raw_path, &trace_path, &header, axes.len(), &runs)?;
    let _ = std::fs::remove_file(&raw_path);
    if let Some(result) = &ballbar {
        let title = plot_title(scenario);
        crate::plot::write_polar_svg(&out_dir.join(PLOT_FILE), &runs, &reversals, result, &title)?;
    }
    let wall = started.elapsed().as_secs_f64();
    let summary = SimulationSummary {
        sim_time_s,
        realtime_factor: timing.then(|| sim_time_s / wall.max(1e-9)),
        wall_time_s: timing.then_some(wall),
        setpoints,
        ballbar,
        reversals_deg: reversals
            .iter()
            .map(|(a, r)| (a.to_string(), r.clone()))
            .collect(),
        directions: plans.iter().map(|p| p.direction).collect(),
    };
    let json = serde_json::to_string_pretty(&summary).expect("plain data serializes");
    crate::report::write_atomic(&out_dir.join(SUMMARY_FILE), format!("{json}\n").as_bytes())?;
    Ok(summary)
}

/// One servo per machine axis, at rest at `q`; with `linear`, the linear twins: the same
/// drives without dry friction and backlash.
pub fn machine_servos(machine: &Machine, q: &AxisVec, linear: bool) -> Result<Vec<AxisServo>> {
    machine
        .axes()
        .iter()
        .map(|&a| {
            let c = machine.axis(a);
            let period = machine.interpolation_period_s;
            if linear {
                AxisServo::new(
                    a,
                    &c.servo,
                    &c.drive.without_backlash(a),
                    &c.friction.viscous_only(a),
                    period,
                    q[a],
                )
            } else {
                AxisServo::new(a, &c.servo, &c.drive, &c.friction, period, q[a])
            }
        })
        .collect()
}

fn plot_title(scenario: &Scenario) -> String {
    let name = scenario
        .path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    match &scenario.program {
        Program::Cone { cone, nc, .. } => format!(
            "{name}: cone {}/{} deg, O ({}, {}, {}) mm, L {} mm, F{}",
            cone.half_apex_deg,
            cone.inclination_deg,
            cone.center_mm.x,
            cone.center_mm.y,
            cone.center_mm.z,
            cone.ballbar_length_mm,
            nc.feed_mm_min
        ),
        Program::Circle { circle, .. } => {
            format!(
                "{name}: circle r {} mm, F{} ({:?})",
                circle.radius_mm, circle.feed_mm_min, circle.plane
            )
        }
        Program::File { path, .. } => format!("{name}: {}", path.display()),
    }
}

/// Writes `trace.csv` (atomically) from the binary rows of the raw trace, appending the
/// centred deviation `dL - (r0 + a cos θ + b sin θ)` of each row's run.
fn complete_trace(
    raw_path: &Path,
    trace_path: &Path,
    header: &str,
    n_axes: usize,
    runs: &[BallbarRun],
) -> Result<()> {
    let tmp = temporary_path(trace_path);
    let read_err = |source| Error::Write {
        path: raw_path.to_path_buf(),
        source,
    };
    let write_err = |source| Error::Write {
        path: tmp.clone(),
        source,
    };
    let mut reader = BufReader::new(File::open(raw_path).map_err(read_err)?);
    let mut out = BufWriter::new(File::create(&tmp).map_err(write_err)?);
    writeln!(out, "{header},deviation_centred_um").map_err(write_err)?;
    let centring = |d: Direction| {
        runs.iter()
            .find(|r| r.direction() == d)
            .map(|r| r.centring())
    };
    let (ccw, cw) = (centring(Direction::Ccw), centring(Direction::Cw));
    let width = 6 + 3 * n_axes;
    let mut bytes = vec![0u8; 8 * width];
    let mut line = String::new();
    loop {
        match reader.read_exact(&mut bytes) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => break,
            Err(e) => return Err(read_err(e)),
        }
        let v: Vec<f64> = bytes
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        let cw_row = v[0] == 1.0;
        let (theta, dev) = (v[3], v[width - 1]);
        let c = if cw_row { cw } else { ccw };
        let centred = c.map_or(dev, |c| dev - c.offset_um(theta));
        line.clear();
        line.push_str(if cw_row { "cw" } else { "ccw" });
        for (value, decimals) in [(v[1], 4), (v[2], 0), (theta, 4)] {
            line.push(',');
            push_fixed(&mut line, value, decimals);
        }
        for k in 0..n_axes {
            for (j, decimals) in [6, 6, 7].into_iter().enumerate() {
                line.push(',');
                push_fixed(&mut line, v[4 + 3 * k + j], decimals);
            }
        }
        for value in [v[width - 2], dev, centred] {
            line.push(',');
            push_fixed(&mut line, value, 4);
        }
        line.push('\n');
        out.write_all(line.as_bytes()).map_err(write_err)?;
    }
    out.flush().map_err(write_err)?;
    drop(out);
    std::fs::rename(&tmp, trace_path).map_err(|source| Error::Write {
        path: trace_path.to_path_buf(),
        source,
    })
}

/// The programs to run, the ball bar and the reversal analysis of a scenario.
fn plan(scenario: &Scenario) -> Result<(Vec<RunPlan>, Option<BallbarSetup>, Analysis)> {
    let machine = &scenario.machine;
    let lead = scenario.simulate.lead_deg;
    let pivot_override = scenario.ballbar_pivot_mm.map(Point3::from);
    Ok(match &scenario.program {
        Program::Cone {
            cone,
            nc,
            directions,
        } => {
            let path = ConePath::new(*cone, machine);
            let plans = directions
                .iter()
                .map(|&direction| {
                    let options = NcOptions {
                        lead_deg: lead,
                        clockwise: direction == Direction::Cw,
                        ..*nc
                    };
                    let (text, measured) = cone::write_program(&path, &machine.name, &options);
                    RunPlan {
                        direction,
                        source: ProgramSource::Text(text),
                        measured: Some(measured),
                    }
                })
                .collect();
            let setup = BallbarSetup {
                frame: cone.circle_frame(),
                pivot_table_mm: pivot_override.unwrap_or(Point3::from(cone.center_mm)),
                length_mm: cone.ballbar_length_mm,
            };
            (plans, Some(setup), analyse_cone(&path, nc.feed_mm_min))
        }
        Program::Circle { circle, directions } => {
            let plans = directions
                .iter()
                .map(|&direction| {
                    let (text, measured) =
                        circle::write_program(circle, direction == Direction::Cw, lead);
                    RunPlan {
                        direction,
                        source: ProgramSource::Text(text),
                        measured: Some(measured),
                    }
                })
                .collect();
            // The circle is programmed in machine coordinates, with any rotary axes at zero.
            let center_table = Vector3::from(circle.center_mm) - machine.kinematics.pivot_mm;
            let frame = CircleFrame::planar(center_table.into(), circle.plane);
            let analysis = analyse_circle(circle, machine.axes());
            let setup = BallbarSetup {
                frame,
                pivot_table_mm: pivot_override.unwrap_or(Point3::from(center_table)),
                length_mm: circle.radius_mm,
            };
            (plans, Some(setup), analysis)
        }
        Program::File { path, cone } => {
            let frame = cone.map(|c| c.circle_frame());
            let analysis = analyse_blocks(
                gcode::read_file(path, AxisVec::ZERO)?,
                machine,
                frame.as_ref(),
            )?;
            let measured = scenario
                .simulate
                .measure_lines
                .map(|[first, last]| MeasuredLines { first, last });
            let plans = vec![RunPlan {
                direction: Direction::Ccw,
                source: ProgramSource::File(path.clone()),
                measured,
            }];
            let setup = cone.map(|c| BallbarSetup {
                frame: c.circle_frame(),
                pivot_table_mm: pivot_override.unwrap_or(Point3::from(c.center_mm)),
                length_mm: c.ballbar_length_mm,
            });
            (plans, setup, analysis)
        }
    })
}
