//! What the report of a run shows, as typed values: the run folder read back
//! ([`RunFolder`]) and the diagnosis of it ([`Diagnosis`]).
//!
//! The folder's JSON files are read with serde into the types that wrote them: `test.json`
//! into [`TestParameters`], `check.json` into [`CheckReport`], and the part of
//! `summary.json` the page shows into [`RunSummary`] (the ball-bar result is
//! [`BallbarResult`] itself). The summary as a whole is `study::simulate::SimulationSummary`,
//! a layer above the report: [`RunSummary`] names the fields of it the report reads, and
//! serde refuses a summary that lacks one.
//!
//! [`Diagnosis`] is filled by `study::diagnose::diagnose_run` (the analyses: the 2θ fit,
//! the spot that dominates G, the reversal each mark is attributed to); the HTML page only
//! puts it into words and tables.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::test_info::{TestParameters, TEST_FILE};
use super::trace::{read_trace, Trace};
use crate::check::CheckReport;
use crate::error::{Error, Result};
use crate::measure::ballbar::TraceEvent;
use crate::measure::BallbarResult;

pub use super::files::SUMMARY_FILE;
/// The limits and collision summary a simulation leaves beside its trace.
pub const CHECK_FILE: &str = "check.json";

/// The part of `summary.json` the report shows.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct RunSummary {
    /// Simulated machine time over all runs, s.
    pub sim_time_s: f64,
    /// Interpolation periods simulated.
    pub setpoints: u64,
    /// The ball-bar figures and marks; None without a measured circle.
    pub ballbar: Option<BallbarResult>,
    /// Each axis's reversal angles, deg, by axis letter.
    pub reversals_deg: BTreeMap<String, Vec<f64>>,
    /// Each axis's lost motion at a reversal as the machine file sets it (mm or deg); empty
    /// for a folder made before it was written.
    #[serde(default)]
    pub reversal_values: BTreeMap<String, MachineReversal>,
    /// Each axis's reversal value B as the trace shows it; empty for an older folder.
    #[serde(default)]
    pub reversal_b: Vec<AxisReversal>,
    /// What makes G, by counterfactual runs; None for an older folder or a run without it
    /// (`--no-budget`).
    #[serde(default)]
    pub error_budget: Option<ErrorBudget>,
    /// The diagnostics from the trace; None without a measured circle or in an older
    /// folder.
    #[serde(default)]
    pub diagnostics: Option<RunDiagnostics>,
    /// The program's pole passages (their messages); empty when it passes none.
    #[serde(default)]
    pub poles: Vec<String>,
}

/// The part of `summary.json`'s `diagnostics` the report reads.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
pub struct RunDiagnostics {
    /// A circle test's figures; None for a cone or a file program.
    #[serde(default)]
    pub circle: Option<CircleFigures>,
}

/// A circle test's Ballbar figures (`study::diagnose::CircleDiagnostics`): each None when
/// the data cannot separate it (`null` in the file), with the reason in `not_measured`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
pub struct CircleFigures {
    /// `ε_u − ε_v`, ppm.
    pub scale_mismatch_ppm: Option<f64>,
    /// The apparent scale mismatch of the servo mismatch, taken out of the above, ppm.
    #[serde(default)]
    pub servo_scale_ppm: Option<f64>,
    /// Squareness, µrad (= µm/m).
    pub squareness_urad: Option<f64>,
    /// `T_u − T_v`, ms, and its oval's peak-to-peak, µm.
    pub servo_mismatch_ms: Option<f64>,
    pub servo_mismatch_pp_um: Option<f64>,
    /// Why a figure is not measured, by its field name.
    #[serde(default)]
    pub not_measured: BTreeMap<String, String>,
}

/// An axis's lost motion at a reversal from the machine file, in its unit (mm or deg):
/// the part of `summary.json`'s `reversal_values` the report reads.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct MachineReversal {
    /// The backlash gap (0 when the drive has none or a fully-closed loop bridges it).
    pub backlash: f64,
    /// The drive's elastic wind-up by friction, `2 Fc / k`.
    pub elastic: f64,
    /// ISO 230-2 B: backlash + elastic.
    pub b: f64,
}

/// An axis's reversal value B (ISO 230-2) as the trace shows it: the lost motion that
/// the axis's own backlash and friction runs of the error budget make on the bar, fitted
/// with the bar's sensitivity to the axis (see `study::budget`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisReversal {
    pub axis: String,
    /// The fitted lost motion, µm: along the axis for a linear one, of arc at the bar's
    /// length for a rotary one (0 for an axis without backlash and dry friction). None when
    /// the bar does not see the axis while it moves.
    pub b_um: Option<f64>,
    /// The peak-to-valley the axis's lost motion makes on the bar (radial), µm.
    pub step_um: Option<f64>,
    /// Reversals of the axis where the bar sees it (normalised sensitivity at least 0.5),
    /// over all runs.
    pub reversals: usize,
}

/// A mechanism of the error budget: what one counterfactual run adds to the ideal machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BudgetMechanism {
    /// The ideal machine's own curve (actual = commanded): chord and joint-space
    /// interpolation error, passage through a pole.
    #[serde(rename = "program")]
    ProgramPath,
    /// One axis's servo loop (lag and gain) without its nonlinearities.
    Servo,
    /// One axis's backlash, on its servo.
    Backlash,
    /// One axis's dry friction and its lost motion (elastic wind-up, pre-sliding), on its servo.
    Friction,
    /// The location errors of the rotary axes.
    Geometric,
    /// One axis's position-error table.
    ErrorTable,
    /// The squareness of the linear axes (`EC0Y`, `EB0Z`, `EA0Z`).
    Squareness,
    /// One linear axis's component errors (ISO 230-1: positioning, straightness, angular).
    ComponentErrors,
}

impl BudgetMechanism {
    /// The mechanism in words.
    pub fn name(self) -> &'static str {
        match self {
            BudgetMechanism::ProgramPath => "the program's own path",
            BudgetMechanism::Servo => "servo lag and gain",
            BudgetMechanism::Backlash => "backlash",
            BudgetMechanism::Friction => "friction and its lost motion",
            BudgetMechanism::Geometric => "geometric (location) errors",
            BudgetMechanism::ErrorTable => "position-error table",
            BudgetMechanism::Squareness => "squareness",
            BudgetMechanism::ComponentErrors => "positioning, straightness and angular errors",
        }
    }
}

/// One row of the error budget.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BudgetRow {
    pub mechanism: BudgetMechanism,
    /// The axis letter; None for the program and the geometric errors.
    pub axis: Option<String>,
    /// The contribution curve's peak-to-valley over the revolution that gives G, µm.
    pub pv_um: f64,
    /// `<c − c̄, d − d̄> / <d − d̄, d − d̄>`: the part of the full curve d (centred) the
    /// contribution c explains; negative for a part that works against G.
    pub share: f64,
}

/// What makes G, from counterfactual runs (`study::budget`): each mechanism's share of the
/// full run's curve, and what is left to their interplay, so that the shares and
/// `interaction_share` add to 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorBudget {
    /// G of the revolution the shares are taken over, µm.
    pub g_um: f64,
    pub rows: Vec<BudgetRow>,
    /// `1 − Σ share`.
    pub interaction_share: f64,
}

/// A run folder read back: what `mtsim simulate -o DIR` wrote.
#[derive(Clone, Debug)]
pub struct RunFolder {
    pub dir: PathBuf,
    pub summary: RunSummary,
    /// None for a folder made before `test.json` was written.
    pub test: Option<TestParameters>,
    /// None for a folder without `check.json`.
    pub check: Option<CheckReport>,
    /// None for a folder without a trace file.
    pub trace: Option<Trace>,
    /// Inline SVG documents found beside the trace: (file name, text).
    pub svgs: Vec<(String, String)>,
    /// Every CSV, JSON, SVG, NC and Parquet file in the folder (for the links).
    pub files: Vec<String>,
    /// The cut cone of a `simulate --cut` run (`cut.json`, read by `report::html` as
    /// `report::cut::CutJson`); None without.
    pub cut: Option<serde_json::Value>,
}

/// The JSON file at `path` as a `T`; None when there is no such file.
fn read_json<T: DeserializeOwned>(path: &Path) -> Result<Option<T>> {
    match std::fs::read_to_string(path) {
        Ok(text) => serde_json::from_str(&text)
            .map(Some)
            .map_err(|e| Error::invalid(path, format!("unexpected contents: {e}"))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(Error::Read {
            path: path.to_path_buf(),
            source,
        }),
    }
}

/// The names of the files in `dir` that end in one of `extensions`, sorted.
pub fn file_names(dir: &Path, extensions: &[&str]) -> Result<Vec<String>> {
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .map_err(|source| Error::Read {
            path: dir.to_path_buf(),
            source,
        })?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| extensions.iter().any(|ext| n.ends_with(ext)))
        .collect();
    files.sort();
    Ok(files)
}

/// (name, text) of each of `files` in `dir` that `inline` accepts and that can be read.
pub fn svg_texts(
    dir: &Path,
    files: &[String],
    inline: &dyn Fn(&str) -> bool,
) -> Vec<(String, String)> {
    files
        .iter()
        .filter(|n| inline(n))
        .filter_map(|n| Some((n.clone(), std::fs::read_to_string(dir.join(n)).ok()?)))
        .collect()
}

impl RunFolder {
    /// Reads the run folder `dir`.
    pub fn read(dir: &Path) -> Result<RunFolder> {
        let summary_path = dir.join(SUMMARY_FILE);
        let summary = read_json(&summary_path)?.ok_or_else(|| {
            Error::invalid(
                &summary_path,
                "no summary.json: not a run folder".to_string(),
            )
            .with_help("give the folder `mtsim simulate SCENARIO -o FOLDER` wrote")
        })?;
        let files = file_names(dir, &[".csv", ".json", ".svg", ".nc", ".parquet"])?;
        let svgs = svg_texts(dir, &files, &|name| {
            name == "ballbar.svg"
                || name == super::contour::CONTOUR_PLOT_FILE
                || name == "placement.svg"
                || (name.starts_with("sweep-") && name.ends_with(".svg"))
        });
        Ok(RunFolder {
            dir: dir.to_path_buf(),
            summary,
            test: read_json(&dir.join(TEST_FILE))?,
            check: read_json(&dir.join(CHECK_FILE))?,
            trace: read_trace(dir)?,
            svgs,
            files,
            cut: read_json(&dir.join("cut.json"))?,
        })
    }
}

/// One mark (spike or step) of the ball-bar result, with where it sits among the reversals.
#[derive(Clone, Debug, PartialEq)]
pub struct Mark {
    /// 1, 2, ... in the order of the result's marks (the numbers on the plot).
    pub number: usize,
    pub event: TraceEvent,
    /// For a mark of an axis: that axis's reversal nearest the mark, (θ, distance), deg.
    pub reversal: Option<(f64, f64)>,
    /// For a mark of no axis: the nearest reversal of any axis, (axis letter, distance deg).
    pub nearest: Option<(String, f64)>,
    /// The trace's centred deviation nearest the mark's peak in its run, µm (where the plot
    /// labels it); None without a trace of that run.
    pub trace_um: Option<f64>,
}

/// One finding about the run, in the order the page lists them.
#[derive(Clone, Debug, PartialEq)]
pub enum Finding {
    /// No measured circle: nothing else is diagnosed.
    NoCircle,
    /// One spot makes most of G in a run (the trace's `direction` text).
    DominantSpot {
        direction: String,
        theta_deg: f64,
        g_um: f64,
        g_without_um: f64,
    },
    /// The 2θ (elliptical) part of a run's centred trace is large against G.
    Elliptical {
        direction: String,
        amplitude_um: f64,
        long_axis_deg: f64,
    },
    /// The marks of one kind at one axis's reversals (or at reversals of axes the trace
    /// cannot tell apart: `axis` names them all, joined by "/"), grouped.
    AxisMarks(AxisMarks),
    /// The marks no axis reverses near, grouped.
    Unattributed {
        /// The marks' numbers.
        numbers: Vec<usize>,
        /// The largest |height|, µm.
        largest_um: f64,
    },
    /// H is large against G.
    Hysteresis { h_um: f64 },
    /// A run's mean radius is off the bar length by more than 1 µm.
    RadiusOffset { direction: String, r0_um: f64 },
    /// A cone without tool-centre-point control: the block sawtooth is real.
    BlockSawtooth,
    /// Nothing stands out.
    Nothing,
}

/// The marks of one kind at the reversals of one axis (or of candidates that cannot be
/// told apart), with what the machine file says about that axis's lost motion.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisMarks {
    /// The axis, or the candidates joined by "/".
    pub axis: String,
    pub kind: crate::measure::ballbar::EventKind,
    /// The marks' numbers (as on the plot).
    pub numbers: Vec<usize>,
    /// The largest |height|, µm.
    pub largest_um: f64,
    /// B as the trace shows it, for a single axis, µm.
    pub b_um: Option<f64>,
    /// The machine file's lost motion of each axis named (in its unit, mm or deg); empty
    /// for a folder without it.
    pub machine: Vec<(String, MachineReversal)>,
}

/// The diagnosis of a run folder: its marks (for the table and the plot) and findings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diagnosis {
    pub marks: Vec<Mark>,
    pub findings: Vec<Finding>,
}
