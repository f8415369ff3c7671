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
//! On a general `[kinematics]` chain, tool(q) and the table ball are the actual chain's
//! (`Kinematics::actual_chain`), with every rotary's acting parameters ([`chain_parameters`]).
//!
//! binned like the ball bar (0.05 deg) and interpolated at θ: p the location errors, b_k the
//! bar-length offset of trace k, s its table-ball placement error (three translations, fitted
//! per trace unless `--placement-known`: in a real set-up the ball sits 10-20 um from where
//! the scenario says, and an unfitted placement turns into false location errors). Location
//! errors act after the servo, so this is exactly what `simulate` with the fitted errors
//! gives. Backlash and servo gain (`--backlash`, `--servo-gain`) act inside the servo: their
//! sensitivities come from re-simulating with each one stepped.
//!
//! # Estimation and identifiability
//!
//! Gauss–Newton on the stacked residuals `r = measured − dL` with the Jacobian J by
//! central differences (1 um, 1 urad), taken afresh at each iterate ([`estimate`]: a ball
//! 1 mm off is beyond one linearisation). Each column is scaled to unit norm (J_s = J D⁻¹)
//! and J_s is decomposed, `J_s = U Σ Vᵀ`. At the nominal machine, singular values below
//! [`NULL_TOLERANCE`] σ_max span the null space: moving the parameters along `D⁻¹ v` leaves
//! every trace unchanged, so the tests cannot separate those parameters. They are reported
//! as combinations (reduced row-echelon form of the null basis, orientation errors as
//! pivots), marked `identifiable: false`, and given no value. Each location-error pivot is
//! held at its prior, so the machine-file fragment carries each inseparable combination in
//! the remaining parameter (a C-axis offset "as seen at the ball height", for example).
//!
//! A parameter that does not act at all ([`NUMERICAL_ZERO`]), or a servo parameter below
//! [`MIN_VISIBILITY`] (the backlash of an axis perpendicular to the bar), is left out and
//! is a null direction on its own. A location error below [`MIN_VISIBILITY`] is a nuisance
//! ([`nuisance`]): fitted with the others so it does not leak into them, given no value.
//!
//! Standard errors: the largest of the independent-sample one, `σ² = |r|² / (n − rank)`,
//! `Cov = σ² D⁻¹ V_r Σ_r⁻² V_rᵀ D⁻¹`, the one under each run's AR(1) noise model
//! ([`correlated`]), and a block bootstrap along θ ([`noise`]) that holds when the residual
//! is correlated (unmodelled effects, correlated noise).
//!
//! # Checks
//!
//! Each trace is compared with its scenario before fitting ([`conformity`]), and one
//! without commanded columns, matched only weakly, is said so and refused when its fitted
//! bar offset exceeds its own radius change; each trace's noise is estimated from the data
//! (AR(1)) and a residual well above it is reported with what its shape suggests ([`noise`]).
//!
//! # What to measure next
//!
//! For a cone, candidate extra tests (another height of the centre, the other standard
//! α/β, a centre off the C axis) are scored by the null space of the enlarged sensitivity
//! matrix (geometric part, programmed timing); the best is suggested.

mod conformity;
mod correlated;
mod decomposition;
mod estimate;
mod measured;
mod model;
pub mod noise;
mod nuisance;
mod page;
mod params;
mod result;
mod suggest;

use std::path::Path;

use nalgebra::DVector;

use crate::error::{Error, Result};
use crate::input::scenario::Scenario;
use crate::kinematics::{Chain, Kinematics, Layout, LocationParam};
use crate::program::test_of;
use crate::report::fit_plot::{render_fit_svg, PlotSeries};
use crate::report::{create_dir, write_atomic};
pub use correlated::{fit_ar1, ArNoise};
use decomposition::describe_null;
pub use decomposition::NullDirection;
use estimate::{Problem, Solution};
pub use measured::{MeasuredPoint, MeasuredTrace};
use model::Run;
pub use noise::NoiseCheck;
pub(crate) use params::{round6, round_sig, Param};
pub use params::{FitOptions, MIN_VISIBILITY, NULL_TOLERANCE, NUMERICAL_ZERO};
pub use result::{FitReport, ParamEstimate, Suggestion, TraceFit};
use suggest::suggest;

/// Files `fit` writes.
pub const FIT_JSON: &str = "fit.json";
pub const FRAGMENT_FILE: &str = "location-errors.toml";
pub const FIT_PLOT: &str = "fit.svg";
pub const FIT_PAGE: &str = "fit.html";

/// Fits location errors (the placement and the options) to `(scenario, measured trace)`
/// pairs and writes fit.json, location-errors.toml, fit.svg and fit.html into `out_dir`.
pub fn fit(
    inputs: &[(Scenario, MeasuredTrace)],
    options: &FitOptions,
    out_dir: &Path,
) -> Result<FitReport> {
    let layout = common_layout(inputs)?;
    let kinematics = inputs[0].0.machine.kinematics;
    let (params, servo_params) = parameters(&kinematics, inputs.len(), has_circle(inputs), options);
    let (problem, mut runs) = Problem::new(inputs, params, servo_params)?;
    problem.simulate(&mut runs, &DVector::zeros(problem.params.len()), None)?;
    for (k, (scenario, trace)) in inputs.iter().enumerate() {
        let own: Vec<&Run> = runs.iter().filter(|r| r.trace == k).collect();
        conformity::check(scenario, trace, &own, &problem.measured)?;
    }
    let solution = problem.solve(&mut runs)?;
    let (mut report, fitted) = assemble(&problem, &runs, solution, layout, options)?;
    report.cautions.extend(chain_cautions(&kinematics));
    write_outputs(out_dir, &report, &problem, &runs, &fitted)?;
    Ok(report)
}

/// The one machine layout of all scenarios (a machine with rotary axes).
fn common_layout(inputs: &[(Scenario, MeasuredTrace)]) -> Result<Layout> {
    let Some((first, _)) = inputs.first() else {
        return Err(Error::usage(
            "give at least one SCENARIO --measured TRACE.csv pair",
        ));
    };
    let layout = first.machine.kinematics.layout;
    let chain = first.machine.kinematics.own_chain();
    let chain_rotaries = chain.map_or(0, |c| c.rotaries().count());
    // Circles alone fit the linear axes' squareness, on any machine.
    if layout.tilt_axis().is_none() && chain_rotaries == 0 && !has_circle(inputs) {
        return Err(Error::invalid(
            &first.path,
            "`mtsim fit` needs a machine with rotary axes (trt-ac, trt-bc, or a [kinematics] chain with rotaries), or circle tests (for the squareness of X, Y and Z)",
        ));
    }
    for (s, _) in inputs {
        if s.machine.kinematics.layout != layout || s.machine.kinematics.own_chain() != chain {
            return Err(Error::invalid(
                &s.path,
                format!(
                    "all scenarios of one fit must use one machine layout; the first uses {}",
                    layout.name()
                ),
            ));
        }
    }
    Ok(layout)
}

/// True when a pair is a circle test: the Ballbar user's test of the linear axes'
/// squareness (ISO 230-4), whose three errors the fit then estimates too.
fn has_circle(inputs: &[(Scenario, MeasuredTrace)]) -> bool {
    inputs.iter().any(|(s, _)| test_of(s).circle().is_some())
}

/// The parameters: location errors (with the squareness of the linear axes the chain has,
/// when a circle is among the tests: `squareness`), then per trace its bar offset (and
/// placement), then the servo parameters (also returned alone). On a general chain every
/// rotary's six location errors but those along its own line ([`chain_parameters`]).
fn parameters(
    kinematics: &Kinematics,
    traces: usize,
    squareness: bool,
    options: &FitOptions,
) -> (Vec<Param>, Vec<Param>) {
    let layout = kinematics.layout;
    let mut location: Vec<LocationParam> = match kinematics.own_chain() {
        Some(chain) => chain_parameters(chain),
        None => LocationParam::ALL
            .into_iter()
            .filter(|p| layout.axes().contains(&p.axis()))
            .collect(),
    };
    if squareness {
        let chain = kinematics.chain();
        let linear = |p: &LocationParam| chain.is_some_and(|c| c.link(p.axis()).is_some());
        location.extend(LocationParam::SQUARENESS.into_iter().filter(linear));
    }
    let mut params: Vec<Param> = location.into_iter().map(Param::Location).collect();
    for k in 0..traces {
        params.push(Param::BarOffset(k));
        if !options.placement_known {
            params.extend((0..3).map(|i| Param::Setup(k, i)));
        }
    }
    let servo: Vec<Param> = layout
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
    params.extend(servo.iter().copied());
    (params, servo)
}

/// A general chain's location-error parameters: each rotary's six (EVERY), but for a
/// component along its own line, which moves or turns the line along itself.
fn chain_parameters(chain: &Chain) -> Vec<LocationParam> {
    LocationParam::EVERY
        .into_iter()
        .filter(|p| {
            chain.link(p.axis()).is_some_and(|l| {
                l.axis.is_rotary() && l.direction[p.component()].abs() < 1.0 - 1e-12
            })
        })
        .collect()
}

/// On a general chain, what no ball-bar test separates: a rotary line along no machine axis
/// takes three offsets and three tilts ([`chain_parameters`]) of which only the two across
/// the line act, so each triple is seen as two combinations at most (the rank report names
/// them).
fn chain_cautions(kinematics: &Kinematics) -> Vec<String> {
    let Some(chain) = kinematics.own_chain() else {
        return Vec::new();
    };
    chain
        .rotaries()
        .filter(|(_, l)| l.direction.iter().all(|c| c.abs() < 1.0 - 1e-12))
        .map(|(_, l)| {
            let a = l.axis;
            format!(
                "{a}'s line ({:.4}, {:.4}, {:.4}) lies along no machine axis: of EX0{a}, EY0{a}, \
                 EZ0{a} only the two offsets across the line act, and of EA0{a}, EB0{a}, EC0{a} \
                 only the two tilts across it, so no test separates each triple into more than \
                 two combinations",
                l.direction.x, l.direction.y, l.direction.z
            )
        })
        .collect()
}

/// Turns the solution into the report (and the fitted model, for the plots).
fn assemble(
    problem: &Problem,
    runs: &[Run],
    solution: Solution,
    layout: Layout,
    options: &FitOptions,
) -> Result<(FitReport, DVector<f64>)> {
    let n = problem.n();
    let x = &solution.x;
    let fitted = problem.model(runs, x)?;
    let residual = &problem.y - &fitted;
    let rss = residual.norm_squared();
    let local = &solution.local;
    let sigma2 = rss / (n - local.rank).max(1) as f64;

    // Null directions, named; their pivots were held at the prior by the solve, so `x` is
    // the fragment's basic solution.
    let (rows, pivots) = solution.structural.null_rref(&problem.params);
    let thetas: Vec<f64> = problem.measured.iter().map(|p| p.theta_deg).collect();
    let (boot, blocks) = noise::bootstrap_errors(local, runs, &thetas, &residual);
    let ar_runs: Vec<_> = runs
        .iter()
        .map(|r| {
            (
                noise::theta_order(r, &thetas),
                noise::run_noise(r, &thetas, &residual),
            )
        })
        .collect();
    let correlated_se = correlated::ar_standard_errors(local, &ar_runs);
    let nuisance = nuisance::mask(&problem.params, &solution);
    let identifiable: Vec<bool> = solution
        .structural
        .identifiable()
        .into_iter()
        .zip(&nuisance)
        .map(|(i, nu)| i && !nu)
        .collect();
    let errors = StandardErrors {
        white: local
            .covariance(sigma2)
            .diagonal()
            .map(|v| v.max(0.0).sqrt()),
        bootstrap: boot,
        correlated: correlated_se,
    };
    let estimates = estimates(problem, x, &errors, &identifiable);
    let mut unidentifiable: Vec<NullDirection> = rows
        .iter()
        .zip(&pivots)
        .map(|(row, &pv)| describe_null(row, pv, &problem.params))
        .collect();
    unidentifiable.extend(nuisance::describe(
        &problem.params,
        &solution,
        &nuisance,
        &errors.total(),
        &identifiable,
    ));
    // The basic solution: each free pivot (placement) moved back to zero along its null
    // direction, so the bar offset carries what it cannot be told from.
    let mut basic = x.clone();
    for (row, &pv) in rows.iter().zip(&pivots) {
        if !solution.fixed[pv] {
            let t = basic[pv];
            basic -= row * t;
        }
    }
    let traces = trace_fits(problem, runs, x, &basic, &identifiable, &residual, &blocks);
    let notes = conformity::weak_matches(problem.inputs, &traces)?;
    let fragment = fragment_text(
        &problem.params,
        &estimates,
        &identifiable,
        &nuisance,
        &unidentifiable,
        layout,
    );
    let suggestion = if solution.structural.null_dim() > 0 || nuisance.contains(&true) {
        suggest(problem.inputs, &problem.params)?
    } else {
        None
    };
    let report = FitReport {
        layout: layout.name().to_string(),
        placement_fitted: !options.placement_known,
        warnings: warnings(&traces),
        cautions: cautions(&estimates),
        notes,
        parameters: estimates,
        traces,
        residual_rms_um: round6((rss / n as f64).sqrt()),
        iterations: solution.iterations,
        singular_values_relative: solution
            .structural
            .relative
            .iter()
            .map(|v| round_sig(*v))
            .collect(),
        null_dimensions: solution.structural.null_dim(),
        unidentifiable,
        suggestion,
        fragment,
    };
    Ok((report, fitted))
}

/// Each parameter's three standard errors, parameter units.
struct StandardErrors {
    /// As if the residual were independent from point to point.
    white: DVector<f64>,
    /// Circular block bootstrap of the residual along θ.
    bootstrap: DVector<f64>,
    /// Under the AR(1) model of each run's residual.
    correlated: DVector<f64>,
}

impl StandardErrors {
    /// The largest of the three: each holds where the others may not.
    fn total(&self) -> DVector<f64> {
        self.white
            .zip_zip_map(&self.bootstrap, &self.correlated, |a, b, c| a.max(b).max(c))
    }
}

/// Each parameter's value and standard errors (none when the tests cannot separate it).
fn estimates(
    problem: &Problem,
    x: &DVector<f64>,
    errors: &StandardErrors,
    identifiable: &[bool],
) -> Vec<ParamEstimate> {
    let total = errors.total();
    problem
        .params
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let value = problem.prior_value(p) + x[j];
            let shown = |v: f64| identifiable[j].then(|| round6(v));
            ParamEstimate {
                name: p.name(),
                unit: p.unit().to_string(),
                value: shown(value),
                standard_error: shown(total[j]),
                standard_error_white: shown(errors.white[j]),
                standard_error_correlated: shown(errors.correlated[j]),
                identifiable: identifiable[j],
                fragment_value: round6(value),
            }
        })
        .collect()
}

/// Each trace's offset, residual and noise check.
fn trace_fits(
    problem: &Problem,
    runs: &[Run],
    x: &DVector<f64>,
    basic: &DVector<f64>,
    identifiable: &[bool],
    residual: &DVector<f64>,
    blocks: &[usize],
) -> Vec<TraceFit> {
    let thetas: Vec<f64> = problem.measured.iter().map(|p| p.theta_deg).collect();
    let y = &problem.y;
    let mut traces = Vec::new();
    for (k, (scenario, trace)) in problem.inputs.iter().enumerate() {
        let own: Vec<&Run> = runs.iter().filter(|r| r.trace == k).collect();
        let idx: Vec<usize> = own.iter().flat_map(|r| r.rows.clone()).collect();
        let m = idx.len() as f64;
        let mean = idx.iter().map(|&i| y[i]).sum::<f64>() / m;
        let rms =
            |f: &dyn Fn(usize) -> f64| (idx.iter().map(|&i| f(i).powi(2)).sum::<f64>() / m).sqrt();
        let j = problem
            .params
            .iter()
            .position(|p| *p == Param::BarOffset(k))
            .expect("bar offset");
        let (lo, hi) = idx.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &i| {
            (lo.min(y[i]), hi.max(y[i]))
        });
        traces.push(TraceFit {
            scenario: scenario.path.clone(),
            measured: trace.path.clone(),
            points: idx.len(),
            matched: if trace.commanded_axes.is_empty() {
                "weakly".to_string()
            } else {
                "commanded".to_string()
            },
            radius_change_um: round6(hi - lo),
            bar_offset_um: identifiable[j].then(|| round6(x[j])),
            bar_offset_basic_um: round6(basic[j]),
            residual_rms_um: round6(rms(&|i| residual[i])),
            measured_rms_um: round6(rms(&|i| y[i] - mean)),
            noise: noise::check_trace(&own, &thetas, residual).rounded(),
            bootstrap_block_points: runs
                .iter()
                .zip(blocks)
                .filter(|(r, _)| r.trace == k)
                .map(|(_, b)| *b)
                .max()
                .unwrap_or(1),
        });
    }
    traces
}

/// A warning per trace whose residual is well above its noise.
fn warnings(traces: &[TraceFit]) -> Vec<String> {
    traces
        .iter()
        .filter(|t| !t.noise.suggests.is_empty())
        .map(|t| {
            format!(
                "{}: the residual ({:.3} um RMS) is {:.1} times the noise estimated from the trace \
                 ({:.3} um): the model misses something; the standard errors come from the block \
                 bootstrap. The residual suggests: {}",
                t.measured.display(),
                t.residual_rms_um,
                t.noise.ratio,
                t.noise.noise_um,
                t.noise.suggests.join("; ")
            )
        })
        .collect()
}

/// What fitted servo parameters may stand for besides their name.
fn cautions(estimates: &[ParamEstimate]) -> Vec<String> {
    estimates
        .iter()
        .filter(|e| {
            // Only a backlash the fit claims: positive and beyond twice its standard error.
            e.name.starts_with("backlash_")
                && e.value
                    .zip(e.standard_error)
                    .is_some_and(|(v, se)| v > 2.0 * se)
        })
        .map(|e| {
            format!(
                "{} = {} {} is the lost motion at the reversal: backlash and friction's elastic \
                 pre-sliding give the same step in a ball-bar trace, so these tests cannot \
                 separate them",
                e.name,
                e.value.unwrap_or(0.0),
                e.unit
            )
        })
        .collect()
}

/// Writes fit.json, location-errors.toml, fit.svg and fit.html.
fn write_outputs(
    out_dir: &Path,
    report: &FitReport,
    problem: &Problem,
    runs: &[Run],
    fitted: &DVector<f64>,
) -> Result<()> {
    create_dir(out_dir)?;
    let json = serde_json::to_string_pretty(report).expect("plain data serializes");
    write_atomic(&out_dir.join(FIT_JSON), format!("{json}\n").as_bytes())?;
    write_atomic(&out_dir.join(FRAGMENT_FILE), report.fragment.as_bytes())?;
    let series: Vec<PlotSeries> = runs
        .iter()
        .map(|r| {
            let (scenario, trace) = &problem.inputs[r.trace];
            PlotSeries {
                label: format!(
                    "{} (trace {}, {})",
                    file_name(&scenario.path),
                    file_name(&trace.path),
                    noise::direction_name(r.direction)
                ),
                points: r
                    .rows
                    .iter()
                    .map(|&i| (problem.measured[i].theta_deg, problem.y[i], fitted[i]))
                    .collect(),
            }
        })
        .collect();
    let svg = render_fit_svg(&series)?;
    write_atomic(&out_dir.join(FIT_PLOT), svg.as_bytes())?;
    let html = page::render(report, &svg);
    write_atomic(&out_dir.join(FIT_PAGE), html.as_bytes())
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn fragment_text(
    params: &[Param],
    estimates: &[ParamEstimate],
    identifiable: &[bool],
    nuisance: &[bool],
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
            } else if nuisance[j] {
                "  # barely seen: the fit's nuisance value, not a measurement"
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
