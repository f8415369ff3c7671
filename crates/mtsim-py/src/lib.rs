//! **mtsim-py** — the `mtsim` Python package's native module, `mtsim._native`.
//! Inputs: scenarios as paths or dicts, options as keywords; runs with the GIL released.
//! Outputs: the commands' `--json` documents as dicts and lists, traces as Arrow streams.
//!
//! The package's Python part (`python/mtsim/`) wraps these functions: it turns the
//! trace stream into a `pyarrow.Table`, holds the docstrings and the exception classes.

mod arrow_stream;
mod errors;
mod json;
mod scenario;
mod scratch;
mod to_toml;

use std::panic::AssertUnwindSafe;
use std::path::PathBuf;

use mtsim::check::CheckOptions;
use mtsim::cli::{block_rows, AnalyzeFindings};
use mtsim::error::Error;
use mtsim::input::scenario::TraceFormat;
use mtsim::measure::cut::CutOptions;
use mtsim::report::cut::{CutJson, SURFACE_PARQUET};
use mtsim::study::fit::{FitOptions, MeasuredTrace};
use mtsim::study::param::{write_outputs, Study};
use mtsim::study::simulate::TRACE_PARQUET_FILE;
use pyo3::prelude::*;
use serde::Serialize;

use arrow_stream::{ArrowStream, Batches};
use errors::Texts;
use scenario::ScenarioInput;
use scratch::Scratch;

/// Runs `f` with the GIL released. An mtsim error becomes its Python exception; a
/// panic is caught here and raised as `MtsimError`, so none crosses into Python.
fn run<T: Send>(
    py: Python<'_>,
    texts: &Texts,
    f: impl FnOnce() -> mtsim::Result<T> + Send,
) -> PyResult<T> {
    match py.detach(|| std::panic::catch_unwind(AssertUnwindSafe(f))) {
        Ok(Ok(value)) => Ok(value),
        Ok(Err(e)) => Err(errors::to_py_err(&e, texts)),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(errors::internal(format!(
                "internal error in mtsim (please report it): {what}"
            )))
        }
    }
}

fn to_json<T: Serialize>(value: &T) -> serde_json::Value {
    serde_json::to_value(value).expect("plain data serializes")
}

/// Simulates a scenario: returns (summary, trace stream). See `mtsim.simulate`.
#[pyfunction]
#[pyo3(signature = (scenario, *, output=None, timing=false))]
fn simulate<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    output: Option<PathBuf>,
    timing: bool,
) -> PyResult<(Bound<'py, PyAny>, ArrowStream)> {
    let input = ScenarioInput::from_py(scenario)?;
    let (summary, batches) = run(py, &input.texts(), || {
        let mut scenario = input.load()?;
        // The Parquet trace is read back column by column, as it was written.
        scenario.simulate.trace_format = TraceFormat::Parquet;
        let dir = Scratch::begin(output.as_deref())?;
        let summary = mtsim::study::simulate::simulate(&scenario, dir.path(), timing, &|_| {})?;
        let batches = Batches::read_trace_parquet(&dir.path().join(TRACE_PARQUET_FILE))?;
        Ok((to_json(&summary), batches))
    })?;
    Ok((json::to_py(py, &summary)?, ArrowStream::new(batches)))
}

/// Predicts the machined cone: (the cut.json figures, the surface stream). See `mtsim.cut`.
#[pyfunction]
#[pyo3(signature = (scenario, *, output=None, theta_step_deg=None, heights_mm=None,
                    height_step_mm=None, commanded=false, budget=true))]
#[allow(clippy::too_many_arguments)]
fn cut<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    output: Option<PathBuf>,
    theta_step_deg: Option<f64>,
    heights_mm: Option<Vec<f64>>,
    height_step_mm: Option<f64>,
    commanded: bool,
    budget: bool,
) -> PyResult<(Bound<'py, PyAny>, ArrowStream)> {
    let input = ScenarioInput::from_py(scenario)?;
    let (figures, batches) = run(py, &input.texts(), || {
        let scenario = input.load()?;
        let defaults = CutOptions::default();
        let options = CutOptions {
            theta_step_deg: theta_step_deg.unwrap_or(defaults.theta_step_deg),
            heights_mm: heights_mm.unwrap_or_default(),
            height_step_mm: height_step_mm.unwrap_or(defaults.height_step_mm),
            commanded,
            direction: None,
        };
        let dir = Scratch::begin(output.as_deref())?;
        let (cut, figures) = mtsim::study::cut::cut_into(
            &scenario,
            options,
            budget,
            (dir.path(), "Cut cone"),
            &|_| {},
        )?;
        let batches = Batches::read_parquet(&dir.path().join(SURFACE_PARQUET))?;
        let doc = CutJson {
            figures,
            budget: cut.budget,
        };
        Ok((to_json(&doc), batches))
    })?;
    Ok((json::to_py(py, &figures)?, ArrowStream::new(batches)))
}

/// Checks limits and collisions: the `check --json` document. See `mtsim.check`.
#[pyfunction]
#[pyo3(signature = (scenario, *, dynamics=false, programmed=false, near_miss_mm=None))]
fn check<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    dynamics: bool,
    programmed: bool,
    near_miss_mm: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let input = ScenarioInput::from_py(scenario)?;
    let report = run(py, &input.texts(), || {
        if dynamics && programmed {
            return Err(Error::usage(
                "dynamics and programmed exclude each other: the servo's positions have no programmed timing",
            ));
        }
        if let Some(d) = near_miss_mm.filter(|d| !(d.is_finite() && *d >= 0.0)) {
            return Err(Error::usage(format!(
                "near_miss_mm {d}: expected a clearance >= 0 mm"
            )));
        }
        let options = CheckOptions {
            dynamics,
            programmed,
            near_miss_mm,
            // The Python result is the JSON document, which holds no pictures.
            collision_poses: 0,
        };
        Ok(to_json(&mtsim::check::check(&input.load()?, &options)?))
    })?;
    json::to_py(py, &report)
}

/// The reversal analysis: the `analyze --json` document. See `mtsim.analyze`.
#[pyfunction]
fn analyze<'py>(py: Python<'py>, scenario: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let input = ScenarioInput::from_py(scenario)?;
    let document = run(py, &input.texts(), || {
        Ok(AnalyzeFindings::of(&input.load()?)?.json())
    })?;
    json::to_py(py, &document)
}

/// The canonical moves: the `blocks --json` rows. See `mtsim.blocks`.
#[pyfunction]
fn blocks<'py>(py: Python<'py>, scenario: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let input = ScenarioInput::from_py(scenario)?;
    let rows = run(py, &input.texts(), || {
        Ok(to_json(&block_rows(&input.load()?)?))
    })?;
    json::to_py(py, &rows)
}

/// Fits location errors to measured traces: the `fit --json` document. See `mtsim.fit`.
#[pyfunction]
#[pyo3(signature = (scenarios, measured, *, output=None, placement_known=false, backlash=false, servo_gain=false))]
#[allow(clippy::too_many_arguments)]
fn fit<'py>(
    py: Python<'py>,
    scenarios: Vec<Bound<'py, PyAny>>,
    measured: Vec<PathBuf>,
    output: Option<PathBuf>,
    placement_known: bool,
    backlash: bool,
    servo_gain: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let inputs = scenarios
        .iter()
        .map(ScenarioInput::from_py)
        .collect::<PyResult<Vec<_>>>()?;
    let texts: Texts = inputs.iter().flat_map(ScenarioInput::texts).collect();
    let report = run(py, &texts, || {
        if inputs.len() != measured.len() || inputs.is_empty() {
            return Err(Error::usage(format!(
                "give one measured trace per scenario, in order (got {} scenarios and {} traces)",
                inputs.len(),
                measured.len()
            )));
        }
        let pairs = inputs
            .iter()
            .zip(&measured)
            .map(|(s, m)| Ok((s.load()?, MeasuredTrace::read(m)?)))
            .collect::<mtsim::Result<Vec<_>>>()?;
        let options = FitOptions {
            placement_known,
            backlash,
            servo_gain,
        };
        let dir = Scratch::begin(output.as_deref())?;
        let report = mtsim::study::fit::fit(&pairs, &options, dir.path())?;
        Ok(to_json(&report))
    })?;
    json::to_py(py, &report)
}

/// Runs a study file: (study.json document, rows stream). See `mtsim.study`.
#[pyfunction]
#[pyo3(signature = (study, *, output=None, samples=None, g_limit_um=None))]
fn study<'py>(
    py: Python<'py>,
    study: PathBuf,
    output: Option<PathBuf>,
    samples: Option<usize>,
    g_limit_um: Option<f64>,
) -> PyResult<(Bound<'py, PyAny>, ArrowStream)> {
    let (summary, batches) = run(py, &Texts::default(), || {
        if let Some(g) = g_limit_um {
            if !(g.is_finite() && g > 0.0) {
                return Err(Error::usage(format!(
                    "g_limit_um {g}: expected a G limit > 0 um"
                )));
            }
        }
        let study = Study::load(&study, g_limit_um, samples)?;
        let rows = study.run(0..study.points.len(), &|| {});
        let dir = Scratch::begin(output.as_deref())?;
        let summary = write_outputs(dir.path(), &study.header, &rows)?;
        let batches = Batches::read_parquet(&dir.path().join("rows.parquet"))?;
        Ok((to_json(&summary), batches))
    })?;
    Ok((json::to_py(py, &summary)?, ArrowStream::new(batches)))
}

/// The `mtsim` command line on `args` (without the program name), in this process;
/// returns its exit code. See `mtsim.run_command`.
#[pyfunction]
fn run_command(py: Python<'_>, args: Vec<String>) -> PyResult<i32> {
    let args: Vec<String> = std::iter::once("mtsim".to_string()).chain(args).collect();
    run(py, &Vec::new(), || Ok(mtsim::cli::main_with(args)))
}

/// A scenario or machine dict as the TOML text it is read as (the text the line and
/// column of a dict's errors refer to). See `mtsim.to_toml`.
#[pyfunction]
#[pyo3(name = "to_toml")]
fn toml_of(value: &Bound<'_, PyAny>) -> PyResult<String> {
    to_toml::dict_to_toml(value, "the value")
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(cut, m)?)?;
    m.add_function(wrap_pyfunction!(analyze, m)?)?;
    m.add_function(wrap_pyfunction!(blocks, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(study, m)?)?;
    m.add_function(wrap_pyfunction!(toml_of, m)?)?;
    m.add_function(wrap_pyfunction!(run_command, m)?)?;
    m.add_class::<ArrowStream>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
