//! `mtsim fit`: the location errors of the rotary axes (and optionally backlash and servo
//! gain) from measured ball-bar traces, with what the tests can and cannot separate.
//!
//! # Model
//!
//! For each pair (scenario, measured trace) and each direction in the trace, the scenario
//! is simulated once (interpolator, servo models) and the actual axis positions of the
//! measured revolution are kept. The predicted deviation at a measured θ is
//!
//! ```text
//! dL(θ; p) = | tool(q) − T_tilt(q; p) T_C(q; p) (pivot + O + s) | − L + b_k
//! ```
//!
//! binned like the ball bar (0.05 deg) and interpolated at θ: p the location errors, b_k the
//! bar-length offset of trace k, s its table-ball placement error (`--setup`). Location
//! errors act after the servo, so this is exactly what `simulate` with the fitted errors
//! gives. Backlash and servo gain (`--backlash`, `--servo-gain`) act inside the servo: their
//! sensitivities come from re-simulating with each one stepped.
//!
//! # Estimation and identifiability
//!
//! Gauss–Newton on the stacked residuals `r = measured − dL` with the Jacobian J by
//! central differences (1 um, 1 urad). Each column is scaled to unit norm (J_s = J D⁻¹)
//! and J_s is decomposed, `J_s = U Σ Vᵀ`. Singular values below [`NULL_TOLERANCE`] σ_max
//! span the null space: moving the parameters along `D⁻¹ v` leaves every trace unchanged,
//! so the tests cannot separate those parameters. They are reported as combinations
//! (reduced row-echelon form of the null basis, orientation errors as pivots), marked
//! `identifiable: false`, and given no value. The step is the truncated pseudo-inverse
//! solution; then each pivot is moved back to its prior value along its null direction, so
//! the machine-file fragment carries each inseparable combination in the remaining
//! parameter (a C-axis offset "as seen at the ball height", for example).
//!
//! A parameter that moves the traces by less than [`MIN_VISIBILITY`] (RMS, per unit) is not
//! seen at all (the backlash of an axis perpendicular to the bar, for example) and is a null
//! direction on its own.
//!
//! Standard errors: `σ² = |r|² / (n − rank)`, `Cov = σ² D⁻¹ V_r Σ_r⁻² V_rᵀ D⁻¹`.
//!
//! # What to measure next
//!
//! For a cone, candidate extra tests (another height of the centre, the other standard
//! α/β, a centre off the C axis) are scored by the null space of the enlarged sensitivity
//! matrix (geometric part, programmed timing); the best is suggested.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::{DMatrix, DVector, Point3, Vector3};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::input::program::{ConeTest, Direction};
use crate::input::scenario::{Program, Scenario};
use crate::kinematics::{LocationErrors, LocationParam};
use crate::measure::ballbar::{deviation_mm, BallbarRun, BIN_DEG, N_BINS};
use crate::measure::{is_measured, BarGeometry, CircleFrame};
use crate::motion::work;
use crate::pipeline::{self, RunOptions, Sample, Sink, Timing};
use crate::program;
use crate::report::{create_dir, write_atomic};
use crate::study::simulate::bar_geometry;
use crate::{Axis, AxisVec};

/// Singular values below this fraction of the largest (of the column-scaled sensitivity
/// matrix) span the null space. Exact degeneracies of the ideal test sit at ~1e-10; some are
/// broken only by second-order effects such as the servo lag of the recorded motion
/// (~1e-5, e.g. the table-ball placement against the A-axis errors with `--setup`), which
/// no real noise level resolves; genuine information starts near 1e-3.
pub const NULL_TOLERANCE: f64 = 1e-4;
/// Smallest RMS change of the traces, um per unit of a parameter (um, urad, mdeg, 1/s),
/// for the parameter to count as seen at all.
pub const MIN_VISIBILITY: f64 = 0.01;
/// Entries of a null direction below this fraction of its largest (column-scaled) are
/// rounding noise and dropped.
const NULL_ENTRY: f64 = 1e-4;
/// Finite-difference step of the location errors, um or urad.
const GEOMETRY_STEP: f64 = 1.0;
/// Finite-difference steps of backlash (um, or mdeg) and servo gain (1/s).
const BACKLASH_STEP: f64 = 2.0;
const GAIN_STEP: f64 = 0.5;

/// Files `fit` writes.
pub const FIT_JSON: &str = "fit.json";
pub const FRAGMENT_FILE: &str = "location-errors.toml";
pub const FIT_PLOT: &str = "fit.svg";

/// One point of a measured trace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasuredPoint {
    pub theta_deg: f64,
    pub deviation_um: f64,
    pub direction: Direction,
}

/// A measured trace: CSV with `theta_deg`, `deviation_um` and optionally `direction`.
#[derive(Clone, Debug)]
pub struct MeasuredTrace {
    pub path: PathBuf,
    pub points: Vec<MeasuredPoint>,
}

impl MeasuredTrace {
    /// Reads a measured trace. Other columns (such as those of `trace.csv`) are ignored.
    pub fn read(path: &Path) -> Result<MeasuredTrace> {
        let text = crate::input::toml_text::read_text(path)?;
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let Some((_, header)) = lines.next() else {
            return Err(
                Error::invalid(path, "the measured trace is empty").with_help(
                    "give a CSV with columns theta_deg, deviation_um and optionally direction",
                ),
            );
        };
        let cols: Vec<&str> = header.split(',').map(str::trim).collect();
        let find = |name: &str| cols.iter().position(|c| *c == name);
        let (Some(ct), Some(cd)) = (find("theta_deg"), find("deviation_um")) else {
            return Err(Error::invalid(
                path,
                format!("the header `{header}` lacks theta_deg or deviation_um"),
            )
            .with_help(
                "give a CSV with columns theta_deg, deviation_um and optionally direction",
            ));
        };
        let cdir = find("direction");
        let mut points = Vec::new();
        let mut offset = header.len() + 1;
        for (_, line) in lines {
            let start = text[offset.min(text.len())..]
                .find(line)
                .map_or(offset, |i| offset + i);
            offset = start + line.len();
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let at = |i: usize, what: &str| {
                let col_start = start
                    + fields[..i.min(fields.len())]
                        .iter()
                        .map(|f| f.len() + 1)
                        .sum::<usize>();
                Error::at(
                    path,
                    &text,
                    col_start..col_start + fields.get(i).map_or(1, |f| f.len().max(1)),
                    what.to_string(),
                    "here",
                )
            };
            let number = |i: usize, name: &str| -> Result<f64> {
                match fields.get(i).map(|f| f.parse::<f64>()) {
                    Some(Ok(v)) if v.is_finite() => Ok(v),
                    _ => Err(at(i, &format!("`{name}` must be a finite number"))),
                }
            };
            let theta_deg = number(ct, "theta_deg")?;
            let deviation_um = number(cd, "deviation_um")?;
            let direction = match cdir.map(|i| (i, fields.get(i).copied().unwrap_or(""))) {
                None => Direction::Ccw,
                Some((_, "ccw")) => Direction::Ccw,
                Some((_, "cw")) => Direction::Cw,
                Some((i, _)) => return Err(at(i, "`direction` must be ccw or cw")),
            };
            points.push(MeasuredPoint {
                theta_deg,
                deviation_um,
                direction,
            });
        }
        if points.len() < 12 {
            return Err(Error::invalid(
                path,
                format!(
                    "the measured trace holds {} points; give at least 12 over a revolution",
                    points.len()
                ),
            ));
        }
        Ok(MeasuredTrace {
            path: path.to_path_buf(),
            points,
        })
    }
}

/// What to estimate besides the location errors and the bar-length offsets.
#[derive(Clone, Copy, Debug, Default)]
pub struct FitOptions {
    /// The table ball's placement error on the table, per trace (three translations).
    pub setup: bool,
    /// Per-axis backlash.
    pub backlash: bool,
    /// Per-axis servo position-loop gain.
    pub servo_gain: bool,
}

/// One parameter of the fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Param {
    Location(LocationParam),
    BarOffset(usize),
    Setup(usize, usize),
    Backlash(Axis),
    Gain(Axis),
}

impl Param {
    fn name(&self) -> String {
        match self {
            Param::Location(p) => p.name().to_string(),
            Param::BarOffset(k) => format!("bar_offset[{k}]"),
            Param::Setup(k, i) => format!("setup_{}[{k}]", ["x", "y", "z"][*i]),
            Param::Backlash(a) => format!("backlash_{a}"),
            Param::Gain(a) => format!("kv_{a}"),
        }
    }
    fn unit(&self) -> &'static str {
        match self {
            Param::Location(p) => p.unit(),
            Param::BarOffset(_) | Param::Setup(..) => "um",
            Param::Backlash(a) if a.is_rotary() => "mdeg",
            Param::Backlash(_) => "um",
            Param::Gain(_) => "1/s",
        }
    }
    /// Pivot preference when naming a null direction: lower first.
    fn pivot_class(&self) -> u8 {
        match self {
            Param::Location(p) if !p.is_position() => 0,
            Param::Location(_) => 1,
            _ => 2,
        }
    }
}

/// A parameter's estimate.
#[derive(Clone, Debug, Serialize)]
pub struct ParamEstimate {
    pub name: String,
    pub unit: String,
    /// The estimate; null when the tests cannot separate this parameter.
    pub value: Option<f64>,
    pub standard_error: Option<f64>,
    pub identifiable: bool,
    /// What the machine-file fragment carries (the prior for an inseparable pivot).
    pub fragment_value: f64,
}

/// A direction in parameter space that the tests cannot see.
#[derive(Clone, Debug, Serialize)]
pub struct NullDirection {
    /// Parameter → coefficient (per unit of the pivot parameter, which has 1).
    pub direction: BTreeMap<String, f64>,
    pub description: String,
}

/// One trace's fit.
#[derive(Clone, Debug, Serialize)]
pub struct TraceFit {
    pub scenario: PathBuf,
    pub measured: PathBuf,
    pub points: usize,
    /// Null when the tests cannot separate it (with `--setup`, for example).
    pub bar_offset_um: Option<f64>,
    pub residual_rms_um: f64,
    pub measured_rms_um: f64,
}

/// A suggested additional test.
#[derive(Clone, Debug, Serialize)]
pub struct Suggestion {
    pub half_apex_deg: f64,
    pub inclination_deg: f64,
    pub center_mm: [f64; 3],
    pub ballbar_length_mm: f64,
    /// Inseparable combinations left with this test added (now: `null_dimensions`).
    pub null_dimensions_after: usize,
    pub text: String,
}

/// The result of `fit`, as written to fit.json.
#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    pub layout: String,
    pub parameters: Vec<ParamEstimate>,
    pub traces: Vec<TraceFit>,
    pub residual_rms_um: f64,
    /// Singular values of the column-scaled sensitivity matrix, relative to the largest.
    pub singular_values_relative: Vec<f64>,
    pub null_dimensions: usize,
    pub unidentifiable: Vec<NullDirection>,
    pub suggestion: Option<Suggestion>,
    /// The `[location_errors]` fragment (also written to location-errors.toml).
    pub fragment: String,
}

/// One direction of one trace: the recorded actual motion and the measured points it meets.
struct Run {
    trace: usize,
    direction: Direction,
    geometry: BarGeometry,
    samples: Vec<(f64, AxisVec)>,
    /// Indices into the stacked measured points.
    rows: Vec<usize>,
}

/// Records θ and the actual axis positions of the measured revolution.
struct Recorder {
    frame: CircleFrame,
    kinematics: crate::kinematics::Kinematics,
    measured: Option<crate::input::program::MeasuredLines>,
    samples: Vec<(f64, AxisVec)>,
}

impl Sink for Recorder {
    fn push(&mut self, s: &Sample) -> Result<()> {
        if is_measured(s, self.measured) {
            let theta = self
                .frame
                .theta_deg(&self.kinematics.forward(&s.commanded).tip);
            self.samples.push((theta, s.actual));
        }
        Ok(())
    }
}

/// Runs `scenario` (with `machine` in place of its own) in `direction` and records it.
fn record(
    scenario: &Scenario,
    machine: &crate::input::Machine,
    direction: Direction,
    timing: Timing,
) -> Result<Vec<(f64, AxisVec)>> {
    let mut sc = scenario.clone();
    sc.machine = machine.clone();
    let geometry = bar_geometry(&sc).ok_or_else(|| {
        Error::invalid(
            &scenario.path,
            "`mtsim fit` needs a cone or circle test (a measured circle)",
        )
    })?;
    let run = program::scenario_run(&sc, direction, sc.simulate.lead_deg)?;
    let mut rec = Recorder {
        frame: geometry.frame,
        kinematics: machine.kinematics,
        measured: run.measured,
        samples: Vec::new(),
    };
    let options = RunOptions {
        timing,
        force_tcp: sc.simulate.tcp,
        start_time_s: 0.0,
        program_path: sc.path.clone(),
        max_samples: work::check_up_front(&sc, sc.simulate.lead_deg)?,
    };
    pipeline::run(run.moves, machine, &options, &mut [&mut rec], &|_| {})?;
    Ok(rec.samples)
}

/// dL at the θ of each of `thetas`, um, for location errors `loc` and table-ball shift
/// `setup_um`, binned like the ball bar and interpolated.
fn predict(
    geometry: &BarGeometry,
    samples: &[(f64, AxisVec)],
    direction: Direction,
    loc: &LocationErrors,
    setup_um: &Vector3<f64>,
    thetas: &[f64],
) -> Result<Vec<f64>> {
    let kin = geometry.kinematics.with_location_errors(*loc);
    let ball = Point3::from(geometry.pivot_table_mm.coords + setup_um * 1e-3);
    let mut run = BallbarRun::new(direction);
    for (theta, q) in samples {
        run.push(
            *theta,
            deviation_mm(&kin, q, &ball, geometry.length_mm) * 1e3,
        );
    }
    let bins = run.trace_um(false)?;
    Ok(thetas
        .iter()
        .map(|t| {
            let x = t.rem_euclid(360.0) / BIN_DEG - 0.5;
            let i = x.floor();
            let f = x - i;
            let i0 = (i as i64).rem_euclid(N_BINS as i64) as usize;
            let i1 = (i0 + 1) % N_BINS;
            bins[i0] * (1.0 - f) + bins[i1] * f
        })
        .collect())
}

/// The machine with the servo parameters of `values` applied.
fn with_servo(
    base: &crate::input::Machine,
    params: &[Param],
    values: &[f64],
) -> crate::input::Machine {
    let mut m = base.clone();
    for (p, v) in params.iter().zip(values) {
        match p {
            Param::Backlash(a) => {
                let d = &mut m.axis_mut(*a).drive;
                if a.is_rotary() {
                    d.backlash_deg = Some(d.backlash_deg.unwrap_or(0.0) + v * 1e-3);
                } else {
                    d.backlash_mm = Some(d.backlash_mm.unwrap_or(0.0) + v * 1e-3);
                }
            }
            Param::Gain(a) => m.axis_mut(*a).servo.kv_per_s += v,
            _ => {}
        }
    }
    m
}

/// Fits location errors (and the options) to `(scenario, measured trace)` pairs and writes
/// fit.json, location-errors.toml and fit.svg into `out_dir`.
pub fn fit(
    inputs: &[(Scenario, MeasuredTrace)],
    options: &FitOptions,
    out_dir: &Path,
) -> Result<FitReport> {
    let Some((first, _)) = inputs.first() else {
        return Err(Error::usage(
            "give at least one SCENARIO --measured TRACE.csv pair",
        ));
    };
    let layout = first.machine.kinematics.layout;
    if layout.tilt_axis().is_none() {
        return Err(Error::invalid(
            &first.path,
            "`mtsim fit` needs a machine with rotary axes (trt-ac or trt-bc)",
        ));
    }
    for (s, _) in inputs {
        if s.machine.kinematics.layout != layout {
            return Err(Error::invalid(
                &s.path,
                format!(
                    "all scenarios of one fit must use one machine layout; the first uses {}",
                    layout.name()
                ),
            ));
        }
    }
    let prior = first.machine.kinematics.location_errors;
    // Parameters.
    let mut params: Vec<Param> = LocationParam::ALL
        .into_iter()
        .filter(|p| layout.axes().contains(&p.axis()))
        .map(Param::Location)
        .collect();
    for k in 0..inputs.len() {
        params.push(Param::BarOffset(k));
        if options.setup {
            params.extend((0..3).map(|i| Param::Setup(k, i)));
        }
    }
    let servo_params: Vec<Param> = layout
        .axes()
        .iter()
        .flat_map(|&a| {
            let mut v = Vec::new();
            if options.backlash {
                v.push(Param::Backlash(a));
            }
            if options.servo_gain {
                v.push(Param::Gain(a));
            }
            v
        })
        .collect();
    params.extend(servo_params.iter().copied());
    let np = params.len();

    // Stacked measurements.
    let mut measured = Vec::new();
    let mut runs: Vec<Run> = Vec::new();
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
    let n = measured.len();
    if n <= np {
        return Err(Error::usage(format!(
            "{n} measured points cannot determine {np} parameters"
        )));
    }
    let y = DVector::from_iterator(n, measured.iter().map(|p| p.deviation_um));

    let mut x = DVector::<f64>::zeros(np); // deltas from the prior, in parameter units
    let location_of = |x: &DVector<f64>| {
        let mut loc = prior;
        for (j, p) in params.iter().enumerate() {
            if let Param::Location(lp) = p {
                loc.set(*lp, prior.get(*lp) + x[j]);
            }
        }
        loc
    };
    let servo_values = |x: &DVector<f64>| -> Vec<f64> {
        params
            .iter()
            .enumerate()
            .filter(|(_, p)| matches!(p, Param::Backlash(_) | Param::Gain(_)))
            .map(|(j, _)| x[j])
            .collect()
    };
    // The model for all rows, with the runs' recorded samples.
    let model = |runs: &[Run], x: &DVector<f64>| -> Result<DVector<f64>> {
        let loc = location_of(x);
        let mut out = DVector::zeros(n);
        for run in runs {
            let k = run.trace;
            let offset = params
                .iter()
                .position(|p| *p == Param::BarOffset(k))
                .map_or(0.0, |j| x[j]);
            let mut setup = Vector3::zeros();
            for (j, p) in params.iter().enumerate() {
                if let Param::Setup(kk, i) = p {
                    if *kk == k {
                        setup[*i] = x[j];
                    }
                }
            }
            let thetas: Vec<f64> = run.rows.iter().map(|&r| measured[r].theta_deg).collect();
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
    };
    let simulate_all =
        |runs: &mut [Run], x: &DVector<f64>, extra: Option<(Param, f64)>| -> Result<()> {
            let mut values = servo_values(x);
            if let Some((p, step)) = extra {
                let i = servo_params
                    .iter()
                    .position(|q| *q == p)
                    .expect("a servo parameter");
                values[i] += step;
            }
            for run in runs.iter_mut() {
                let (scenario, _) = &inputs[run.trace];
                let machine = with_servo(&scenario.machine, &servo_params, &values);
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
        };

    simulate_all(&mut runs, &x, None)?;
    let outer = if servo_params.is_empty() { 1 } else { 3 };
    let mut jac = DMatrix::<f64>::zeros(n, np);
    let mut decomposition = None;
    for _ in 0..outer {
        // Servo sensitivities by re-simulation.
        let base = model(&runs, &x)?;
        for (j, p) in params.iter().enumerate() {
            if !matches!(p, Param::Backlash(_) | Param::Gain(_)) {
                continue;
            }
            let step = if matches!(p, Param::Backlash(_)) {
                BACKLASH_STEP
            } else {
                GAIN_STEP
            };
            let mut stepped: Vec<Run> = runs
                .iter()
                .map(|r| Run {
                    trace: r.trace,
                    direction: r.direction,
                    geometry: r.geometry,
                    samples: Vec::new(),
                    rows: r.rows.clone(),
                })
                .collect();
            simulate_all(&mut stepped, &x, Some((*p, step)))?;
            let m = model(&stepped, &x)?;
            jac.set_column(j, &((m - &base) / step));
        }
        // Geometric sensitivities at the nominal machine (all location errors and setup
        // shifts zero): the structural linearisation, whose null space does not depend on
        // the estimate. The model is linear in the errors to ~1e-5, so a few fixed-Jacobian
        // (chord) iterations converge.
        let mut x0 = x.clone();
        for (j, p) in params.iter().enumerate() {
            match p {
                Param::Location(lp) => x0[j] = -prior.get(*lp),
                Param::Setup(..) => x0[j] = 0.0,
                _ => {}
            }
        }
        for (j, p) in params.iter().enumerate() {
            if matches!(p, Param::Backlash(_) | Param::Gain(_)) {
                continue;
            }
            let mut xp = x0.clone();
            let mut xm = x0.clone();
            xp[j] += GEOMETRY_STEP;
            xm[j] -= GEOMETRY_STEP;
            let col = (model(&runs, &xp)? - model(&runs, &xm)?) / (2.0 * GEOMETRY_STEP);
            jac.set_column(j, &col);
        }
        let d = Decomposition::new(&jac);
        // The recorded motion belongs to the servo parameters of `x_sim`; until the next
        // simulation their changes enter linearly, through their columns.
        let x_sim = x.clone();
        let servo_part = |x: &DVector<f64>| -> DVector<f64> {
            let mut dx = x - &x_sim;
            for (j, p) in params.iter().enumerate() {
                if !matches!(p, Param::Backlash(_) | Param::Gain(_)) {
                    dx[j] = 0.0;
                }
            }
            &jac * dx
        };
        for _ in 0..4 {
            let r = &y - model(&runs, &x)? - servo_part(&x);
            x += d.solve(&r);
        }
        decomposition = Some(d);
        if !servo_params.is_empty() {
            // Keep backlash physical, then re-simulate at the new estimate.
            for (j, p) in params.iter().enumerate() {
                if let Param::Backlash(a) = p {
                    let current = if a.is_rotary() {
                        first.machine.axis(*a).drive.backlash_deg.unwrap_or(0.0) * 1e3
                    } else {
                        first.machine.axis(*a).drive.backlash_mm.unwrap_or(0.0) * 1e3
                    };
                    x[j] = x[j].max(-current);
                }
                if let Param::Gain(a) = p {
                    x[j] = x[j].max(1.0 - first.machine.axis(*a).servo.kv_per_s);
                }
            }
            simulate_all(&mut runs, &x, None)?;
        }
    }
    let d = decomposition.expect("at least one iteration");
    let fitted = model(&runs, &x)?;
    let residual = &y - &fitted;
    let rss = residual.norm_squared();
    let dof = (n - d.rank).max(1);
    let sigma2 = rss / dof as f64;

    // Null directions, named, and the fragment's basic solution.
    let (rows, pivots) = d.null_rref(&params);
    for (row, &pv) in rows.iter().zip(&pivots) {
        let t = x[pv];
        x -= row * t;
    }
    let fitted_basic = model(&runs, &x)?;
    debug_assert!((fitted_basic - &fitted).amax() < 1e-2);
    let cov = d.covariance(sigma2);
    let identifiable = d.identifiable();

    let mut estimates = Vec::new();
    for (j, p) in params.iter().enumerate() {
        let base_value = match p {
            Param::Location(lp) => prior.get(*lp),
            Param::Backlash(a) if a.is_rotary() => {
                first.machine.axis(*a).drive.backlash_deg.unwrap_or(0.0) * 1e3
            }
            Param::Backlash(a) => first.machine.axis(*a).drive.backlash_mm.unwrap_or(0.0) * 1e3,
            Param::Gain(a) => first.machine.axis(*a).servo.kv_per_s,
            _ => 0.0,
        };
        let value = base_value + x[j];
        estimates.push(ParamEstimate {
            name: p.name(),
            unit: p.unit().to_string(),
            value: identifiable[j].then_some(round6(value)),
            standard_error: identifiable[j].then(|| round6(cov[(j, j)].max(0.0).sqrt())),
            identifiable: identifiable[j],
            fragment_value: round6(value),
        });
    }
    let unidentifiable: Vec<NullDirection> = rows
        .iter()
        .zip(&pivots)
        .map(|(row, &pv)| describe_null(row, pv, &params))
        .collect();

    let mut traces = Vec::new();
    for (k, (scenario, trace)) in inputs.iter().enumerate() {
        let idx: Vec<usize> = runs
            .iter()
            .filter(|r| r.trace == k)
            .flat_map(|r| r.rows.clone())
            .collect();
        let rms = |v: &DVector<f64>| {
            (idx.iter().map(|&i| v[i] * v[i]).sum::<f64>() / idx.len() as f64).sqrt()
        };
        let mean = idx.iter().map(|&i| y[i]).sum::<f64>() / idx.len() as f64;
        let centred = DVector::from_iterator(n, (0..n).map(|i| y[i] - mean));
        let j = params
            .iter()
            .position(|p| *p == Param::BarOffset(k))
            .expect("bar offset");
        traces.push(TraceFit {
            scenario: scenario.path.clone(),
            measured: trace.path.clone(),
            points: idx.len(),
            bar_offset_um: identifiable[j].then(|| round6(x[j])),
            residual_rms_um: round6(rms(&residual)),
            measured_rms_um: round6(rms(&centred)),
        });
    }

    let fragment = fragment_text(&params, &estimates, &identifiable, &unidentifiable, layout);
    let suggestion = if d.null_dim() > 0 {
        suggest(inputs, &params)?
    } else {
        None
    };
    let report = FitReport {
        layout: layout.name().to_string(),
        parameters: estimates,
        traces,
        residual_rms_um: round6((rss / n as f64).sqrt()),
        singular_values_relative: d.relative.iter().map(|v| round_sig(*v)).collect(),
        null_dimensions: d.null_dim(),
        unidentifiable,
        suggestion,
        fragment: fragment.clone(),
    };
    create_dir(out_dir)?;
    let json = serde_json::to_string_pretty(&report).expect("plain data serializes");
    write_atomic(&out_dir.join(FIT_JSON), format!("{json}\n").as_bytes())?;
    write_atomic(&out_dir.join(FRAGMENT_FILE), fragment.as_bytes())?;
    let series: Vec<PlotSeries> = runs
        .iter()
        .map(|r| PlotSeries {
            label: format!(
                "{} ({})",
                inputs[r.trace]
                    .1
                    .path
                    .file_name()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                match r.direction {
                    Direction::Ccw => "ccw",
                    Direction::Cw => "cw",
                }
            ),
            points: r
                .rows
                .iter()
                .map(|&i| (measured[i].theta_deg, y[i], fitted[i]))
                .collect(),
        })
        .collect();
    crate::report::fit_plot::write_fit_svg(&out_dir.join(FIT_PLOT), &series)?;
    Ok(report)
}

pub use crate::report::fit_plot::PlotSeries;

fn round6(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

fn round_sig(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let e = v.abs().log10().floor() as i32;
    let s = 10f64.powi(5 - e);
    (v * s).round() / s
}

/// The column-scaled SVD of a sensitivity matrix.
struct Decomposition {
    scale: DVector<f64>,
    u: DMatrix<f64>,
    s: DVector<f64>,
    v: DMatrix<f64>, // columns are right singular vectors (scaled coordinates)
    relative: Vec<f64>,
    rank: usize,
}

impl Decomposition {
    fn new(j: &DMatrix<f64>) -> Decomposition {
        let np = j.ncols();
        let rows = j.nrows().max(1) as f64;
        let mut js = j.clone();
        // A parameter that moves the traces by less than MIN_VISIBILITY (RMS, per unit) is
        // not seen by these tests: its column is dropped and it joins the null space.
        for c in 0..np {
            if js.column(c).norm() / rows.sqrt() < MIN_VISIBILITY {
                js.column_mut(c).fill(0.0);
            }
        }
        let scale = DVector::from_iterator(
            np,
            (0..np).map(|c| {
                let n = js.column(c).norm();
                if n > 0.0 {
                    n
                } else {
                    1.0
                }
            }),
        );
        for c in 0..np {
            let s = scale[c];
            js.column_mut(c).scale_mut(1.0 / s);
        }
        let svd = js.svd(true, true);
        let (u, vt, s) = (
            svd.u.expect("asked for U"),
            svd.v_t.expect("asked for V"),
            svd.singular_values,
        );
        // Sort descending (nalgebra does not promise an order).
        let mut order: Vec<usize> = (0..s.len()).collect();
        order.sort_by(|a, b| s[*b].total_cmp(&s[*a]));
        let u = DMatrix::from_columns(
            &order
                .iter()
                .map(|&i| u.column(i).into_owned())
                .collect::<Vec<_>>(),
        );
        let v = DMatrix::from_columns(
            &order
                .iter()
                .map(|&i| vt.row(i).transpose())
                .collect::<Vec<_>>(),
        );
        let s = DVector::from_iterator(s.len(), order.iter().map(|&i| s[i]));
        let smax = s.iter().cloned().fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        let relative: Vec<f64> = s.iter().map(|v| v / smax).collect();
        let rank = relative.iter().filter(|r| **r >= NULL_TOLERANCE).count();
        Decomposition {
            scale,
            u,
            s,
            v,
            relative,
            rank,
        }
    }

    fn null_dim(&self) -> usize {
        self.v.ncols() - self.rank
    }

    /// Truncated pseudo-inverse solution of `J dx = r`, in parameter units.
    fn solve(&self, r: &DVector<f64>) -> DVector<f64> {
        let mut dx = DVector::zeros(self.v.nrows());
        for i in 0..self.rank {
            let c = self.u.column(i).dot(r) / self.s[i];
            dx += self.v.column(i) * c;
        }
        dx.component_div(&self.scale)
    }

    fn covariance(&self, sigma2: f64) -> DMatrix<f64> {
        let np = self.v.nrows();
        let mut c = DMatrix::zeros(np, np);
        for i in 0..self.rank {
            let v = self.v.column(i).component_div(&self.scale);
            c += &v * v.transpose() * (sigma2 / (self.s[i] * self.s[i]));
        }
        c
    }

    /// A parameter is identifiable when its unit vector has no part in the null space.
    fn identifiable(&self) -> Vec<bool> {
        (0..self.v.nrows())
            .map(|j| {
                let part: f64 = (self.rank..self.v.ncols())
                    .map(|i| self.v[(j, i)].powi(2))
                    .sum();
                part.sqrt() < 1e-3
            })
            .collect()
    }

    /// The null space in reduced row-echelon form, in parameter units: each row has 1 at
    /// its pivot and 0 at the other rows' pivots. Orientation errors are preferred as pivots.
    fn null_rref(&self, params: &[Param]) -> (Vec<DVector<f64>>, Vec<usize>) {
        let mut rows: Vec<DVector<f64>> = (self.rank..self.v.ncols())
            .map(|i| self.v.column(i).into_owned())
            .collect(); // scaled coordinates
        let mut pivots = Vec::new();
        for r in 0..rows.len() {
            let row = rows[r].clone();
            let max = row.amax();
            let candidates =
                (0..row.len()).filter(|j| !pivots.contains(j) && row[*j].abs() > 0.05 * max);
            let Some(pv) = candidates.min_by(|a, b| {
                params[*a]
                    .pivot_class()
                    .cmp(&params[*b].pivot_class())
                    .then(row[*b].abs().total_cmp(&row[*a].abs()))
            }) else {
                continue;
            };
            let lead = row[pv];
            rows[r] /= lead;
            let pivot_row = rows[r].clone();
            for (o, other) in rows.iter_mut().enumerate() {
                if o != r {
                    let f = other[pv];
                    *other -= &pivot_row * f;
                }
            }
            pivots.push(pv);
        }
        // Back to parameter units: x = D⁻¹ x_s, normalised so the pivot's coefficient is 1.
        // Entries below NULL_ENTRY of the row (scaled) are numerical noise.
        let rows = rows
            .into_iter()
            .zip(&pivots)
            .map(|(mut row, &pv)| {
                let max = row.amax();
                row.apply(|v| {
                    if v.abs() < NULL_ENTRY * max {
                        *v = 0.0
                    }
                });
                let phys = row.component_div(&self.scale);
                let lead = phys[pv];
                phys / lead
            })
            .collect();
        (rows, pivots)
    }
}

fn describe_null(row: &DVector<f64>, pivot: usize, params: &[Param]) -> NullDirection {
    let mut direction = BTreeMap::new();
    let mut others = Vec::new();
    for (j, p) in params.iter().enumerate() {
        let c = row[j];
        if j != pivot && c == 0.0 {
            continue;
        }
        direction.insert(p.name(), round_sig(c));
        if j != pivot {
            others.push((j, c));
        }
    }
    let piv = &params[pivot];
    let description = match others.as_slice() {
        [] => format!(
            "{} does not change the traces measurably (less than {MIN_VISIBILITY} um RMS per {}): these tests do not see it",
            piv.name(),
            piv.unit()
        ),
        [(j, c)] => {
            // Invariant: other − c · pivot is what the traces see.
            let other = &params[*j];
            let lever = if piv.unit() == "urad" && other.unit() == "um" {
                format!(" (a lever of {:.1} mm)", (c * 1e3).abs())
            } else {
                String::new()
            };
            format!(
                "{} and {} cannot be separated: only {} {:+.6} {}/{} x {}{} is seen",
                other.name(),
                piv.name(),
                other.name(),
                round_sig(-c),
                other.unit(),
                piv.unit(),
                piv.name(),
                lever
            )
        }
        _ => format!(
            "moving {} by 1 {} together with {} leaves every trace unchanged: the tests cannot separate them",
            piv.name(),
            piv.unit(),
            others
                .iter()
                .map(|(j, c)| format!("{:+.6} {} {}", round_sig(*c), params[*j].unit(), params[*j].name()))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    NullDirection {
        direction,
        description,
    }
}

fn fragment_text(
    params: &[Param],
    estimates: &[ParamEstimate],
    identifiable: &[bool],
    nulls: &[NullDirection],
    layout: crate::kinematics::Layout,
) -> String {
    let mut s = format!(
        "# Location errors fitted by `mtsim fit` ({} machine). Paste into the machine file, or\n\
         # under [machine_overrides.location_errors] in a scenario.\n",
        layout.name()
    );
    if !nulls.is_empty() {
        s.push_str("# The tests cannot separate some parameters; the values marked below carry a\n# combination (see fit.json \"unidentifiable\"):\n");
        for n in nulls {
            s.push_str(&format!("#   {}\n", n.description));
        }
    }
    s.push_str("[location_errors]\n");
    for (j, p) in params.iter().enumerate() {
        if let Param::Location(lp) = p {
            let note = if identifiable[j] {
                ""
            } else {
                "  # not separable: carries a combination"
            };
            s.push_str(&format!(
                "{} = {:.4}{note}\n",
                lp.key(),
                estimates[j].fragment_value
            ));
        }
    }
    s
}

/// Scores candidate extra cone tests by the null space they leave (geometric part only).
fn suggest(inputs: &[(Scenario, MeasuredTrace)], params: &[Param]) -> Result<Option<Suggestion>> {
    let Some((base, cone)) = inputs.iter().find_map(|(s, _)| match &s.program {
        Program::Cone { cone, .. } => Some((s, *cone)),
        _ => None,
    }) else {
        return Ok(None);
    };
    let loc_params: Vec<LocationParam> = params
        .iter()
        .filter_map(|p| match p {
            Param::Location(l) => Some(*l),
            _ => None,
        })
        .collect();
    let sens = |scenario: &Scenario| -> Result<DMatrix<f64>> {
        let g = bar_geometry(scenario).expect("a cone");
        let samples = record(
            scenario,
            &scenario.machine,
            Direction::Ccw,
            Timing::Programmed,
        )?;
        let thetas: Vec<f64> = (0..360).map(|i| i as f64 + 0.5).collect();
        let mut j = DMatrix::zeros(thetas.len(), loc_params.len() + 1);
        let prior = scenario.machine.kinematics.location_errors;
        for (c, lp) in loc_params.iter().enumerate() {
            let p = predict(
                &g,
                &samples,
                Direction::Ccw,
                &prior.with(*lp, prior.get(*lp) + 1.0),
                &Vector3::zeros(),
                &thetas,
            )?;
            let m = predict(
                &g,
                &samples,
                Direction::Ccw,
                &prior.with(*lp, prior.get(*lp) - 1.0),
                &Vector3::zeros(),
                &thetas,
            )?;
            for i in 0..thetas.len() {
                j[(i, c)] = (p[i] - m[i]) / 2.0;
            }
        }
        j.column_mut(loc_params.len()).fill(1.0);
        Ok(j)
    };
    let with_cone = |c: ConeTest| -> Scenario {
        let mut s = base.clone();
        if let Program::Cone { cone, .. } = &mut s.program {
            *cone = c;
        }
        s
    };
    // The present tests' geometric sensitivities (each with its own bar offset).
    let mut blocks = Vec::new();
    for (s, _) in inputs {
        if matches!(s.program, Program::Cone { .. }) {
            blocks.push(sens(s)?);
        }
    }
    let z = cone.center_mm.z;
    let mut candidates = vec![
        ConeTest {
            center_mm: Vector3::new(
                cone.center_mm.x,
                cone.center_mm.y,
                if z > 150.0 { z - 100.0 } else { z + 100.0 },
            ),
            ..cone
        },
        ConeTest {
            center_mm: Vector3::new(cone.center_mm.x, cone.center_mm.y - 50.0, z),
            ..cone
        },
    ];
    if (cone.half_apex_deg - 15.0).abs() < 1e-9 && (cone.inclination_deg - 10.0).abs() < 1e-9 {
        candidates.push(ConeTest {
            half_apex_deg: 45.0,
            inclination_deg: 30.0,
            ..cone
        });
    } else {
        candidates.push(ConeTest {
            half_apex_deg: 15.0,
            inclination_deg: 10.0,
            ..cone
        });
    }
    let stack = |all: &[&DMatrix<f64>]| -> Decomposition {
        let rows: usize = all.iter().map(|b| b.nrows()).sum();
        let nl = loc_params.len();
        let mut j = DMatrix::zeros(rows, nl + all.len());
        let mut r0 = 0;
        for (k, b) in all.iter().enumerate() {
            j.view_mut((r0, 0), (b.nrows(), nl))
                .copy_from(&b.columns(0, nl));
            j.view_mut((r0, nl + k), (b.nrows(), 1)).fill(1.0);
            r0 += b.nrows();
        }
        Decomposition::new(&j)
    };
    // The location errors the present tests leave inseparable.
    let null_now = stack(&blocks.iter().collect::<Vec<_>>()).null_dim();
    if null_now == 0 {
        return Ok(None);
    }
    let mut best: Option<(usize, f64, ConeTest)> = None;
    for c in candidates {
        let extra = sens(&with_cone(c))?;
        let all: Vec<&DMatrix<f64>> = blocks.iter().chain(std::iter::once(&extra)).collect();
        let d = stack(&all);
        let smallest = d
            .relative
            .get(d.rank.saturating_sub(1))
            .copied()
            .unwrap_or(0.0);
        let better = match &best {
            None => true,
            Some((nd, sm, _)) => d.null_dim() < *nd || (d.null_dim() == *nd && smallest > *sm),
        };
        if better {
            best = Some((d.null_dim(), smallest, c));
        }
    }
    Ok(best.map(|(nd, _, c)| Suggestion {
        half_apex_deg: c.half_apex_deg,
        inclination_deg: c.inclination_deg,
        center_mm: c.center_mm.into(),
        ballbar_length_mm: c.ballbar_length_mm,
        null_dimensions_after: nd,
        text: format!(
            "add the cone {}/{} deg at O = ({}, {}, {}) mm, L = {} mm: it leaves {nd} inseparable combination(s) (now {null_now}); check that it fits the machine with `mtsim check`",
            c.half_apex_deg, c.inclination_deg, c.center_mm.x, c.center_mm.y, c.center_mm.z, c.ballbar_length_mm
        ),
    }))
}
