//! Scenario files (TOML): a machine, a program (generated or a G-code file) and options.
//!
//! Paths are relative to the scenario file; absolute paths work too. Unknown keys are
//! errors that name the key and its line. See `docs/scenario-format.md`.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::input::exact;
use crate::input::lead_in::LeadIn;
use crate::input::machine::{Machine, MachineBase};
use crate::input::program::{CircleTest, ConeTest, Direction, NcOptions};
use crate::input::reader::reader_options;
pub use crate::input::reader::{ReaderSection, ToolEntry};
use crate::input::scene::{ConeSetup, ToolConfig, ToolShape, WorkpieceConfig, WorkpieceKind};
pub use crate::input::toml_text::resolve;
use crate::input::toml_text::{self, value_error};
use crate::Plane;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    machine: String,
    program: ProgramSection,
    #[serde(default)]
    machine_overrides: Option<toml::Table>,
    #[serde(default)]
    simulate: SimulateSection,
    #[serde(default)]
    ballbar: BallbarSection,
    /// What stands on the table; defaults to the cone frustum for a cone program.
    workpiece: Option<WorkpieceConfig>,
    /// The tool, replacing the machine file's `[tool]`.
    tool: Option<ToolConfig>,
    #[serde(default)]
    check: CheckSection,
    #[serde(default)]
    reader: ReaderSection,
}

/// `[check]`: options of `mtsim check`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CheckSection {
    /// Near-miss clearance, mm; the machine's `[scene] near_miss_mm` when absent.
    pub near_miss_mm: Option<f64>,
    /// Check collisions in the scene (false: axis limits only).
    pub collisions: bool,
}

/// `[check]` resolved: the near-miss clearance given, or the machine's `[scene]` one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckOptions {
    /// Near-miss clearance, mm.
    pub near_miss_mm: f64,
    /// Check collisions in the scene (false: axis limits only).
    pub collisions: bool,
}

impl Default for CheckSection {
    fn default() -> Self {
        CheckSection {
            near_miss_mm: None,
            collisions: true,
        }
    }
}

/// The file format of `mtsim simulate`'s trace (`[simulate] trace_format`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum TraceFormat {
    /// `trace.csv`: one text row per sample, fixed decimals per column.
    #[default]
    Csv,
    /// `trace.parquet`: the same columns as f64 (the direction as text, the line as an
    /// unsigned integer), for Spark, Dask, pandas and Polars; no text formatting.
    Parquet,
}

impl TraceFormat {
    /// The trace's file name in the output folder.
    pub const fn file_name(self) -> &'static str {
        match self {
            TraceFormat::Csv => "trace.csv",
            TraceFormat::Parquet => "trace.parquet",
        }
    }
}

/// Default `[simulate] max_samples` (input/budget.rs): 10⁹ samples, 11.6 days of machine
/// time at a 1 ms period; on one core about 6 min of `check` (programmed timing, 3·10⁶
/// samples/s) and well over an hour of `simulate` (servo models and trace).
pub const DEFAULT_MAX_SAMPLES: u64 = 1_000_000_000;

/// Default `[simulate] max_trace_rows`: 10⁷ rows, about 2 GB of `trace.csv` with five axes
/// (2.8 h of machine time traced every 1 ms period).
pub const DEFAULT_MAX_TRACE_ROWS: u64 = 10_000_000;

/// `[simulate]`: options of `mtsim simulate`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimulateSection {
    /// Interpolate with tool-centre-point control (the tip on the straight line in the
    /// table frame, inverse kinematics every period) instead of joint space.
    pub tcp: bool,
    /// Write every n-th sample to the trace (1: every interpolation period).
    pub trace_every: usize,
    /// The trace's file: `trace.csv` (text, rounded to the printed decimals) or
    /// `trace.parquet` (the same columns as IEEE f64, as computed).
    pub trace_format: TraceFormat,
    /// Path before and after the measured revolution, deg, so that the trace leaves out the
    /// start and stop transients.
    /// A circle test sizes it from the feed, the axes' limits and the servo loops when the
    /// scenario does not give it ([`LeadIn`]).
    pub lead_deg: f64,
    /// A circle test's lead-in, as run (set when the scenario is loaded; none for a cone or
    /// a file).
    #[serde(skip)]
    pub lead_in: Option<LeadIn>,
    /// For a file program: the source lines (first, last) whose blocks the ball bar
    /// measures; every block after the first when absent.
    #[serde(deserialize_with = "exact::option_array")]
    pub measure_lines: Option<[usize; 2]>,
    /// Most interpolation periods one run may take (input/budget.rs): a generated test
    /// estimated above it is refused before it starts, any run stopped when it passes it.
    pub max_samples: u64,
    /// Most rows the trace may hold (program/work.rs): a run estimated above it is refused
    /// before it starts, and stopped when its trace passes it. About 210 bytes a row in
    /// `trace.csv` with five axes, as much again in the temporary file while it is written.
    pub max_trace_rows: u64,
}

impl Default for SimulateSection {
    fn default() -> Self {
        SimulateSection {
            tcp: false,
            trace_every: 1,
            trace_format: TraceFormat::Csv,
            lead_deg: 20.0,
            lead_in: None,
            measure_lines: None,
            max_samples: DEFAULT_MAX_SAMPLES,
            max_trace_rows: DEFAULT_MAX_TRACE_ROWS,
        }
    }
}

/// `[ballbar]`: the virtual ball bar.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BallbarSection {
    /// Table-side ball, table frame, mm; defaults to the cone's base centre or the circle's centre.
    #[serde(deserialize_with = "exact::option_array")]
    pub pivot_mm: Option<[f64; 3]>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProgramSection {
    /// A G-code file.
    file: Option<String>,
    /// The generated cone-frustum test; with `file`, only its geometry is used (for θ).
    cone: Option<ConeSection>,
    /// The planar circular test (ISO 230-4).
    circle: Option<CircleSection>,
}

/// `[program.circle]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CircleSection {
    /// "XY", "ZX" or "YZ" (G17, G18, G19).
    #[serde(default = "default_plane")]
    pub plane: String,
    pub radius_mm: f64,
    #[serde(default = "default_feed")]
    pub feed_mm_min: f64,
    /// "ccw" or "cw"; see also `directions`.
    pub direction: Option<String>,
    /// Both directions for hysteresis: `["ccw", "cw"]`.
    pub directions: Option<Vec<String>>,
    #[serde(deserialize_with = "exact::array")]
    pub center_mm: [f64; 3],
}

fn default_plane() -> String {
    "XY".into()
}

/// `[program.cone]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConeSection {
    pub half_apex_deg: f64,
    pub inclination_deg: f64,
    #[serde(deserialize_with = "exact::array")]
    pub center_mm: [f64; 3],
    pub ballbar_length_mm: f64,
    #[serde(default = "default_segments")]
    pub segments: usize,
    #[serde(default = "default_feed")]
    pub feed_mm_min: f64,
    /// Write G93 inverse-time feed.
    #[serde(default)]
    pub inverse_time: bool,
    /// Write a tool-centre-point (G43.4) program.
    #[serde(default)]
    pub tcp: bool,
    /// Directions `simulate` runs: `["ccw"]` (default), `["cw"]` or `["ccw", "cw"]`.
    pub directions: Option<Vec<String>>,
}

fn default_segments() -> usize {
    360
}
fn default_feed() -> f64 {
    1000.0
}

/// What a scenario runs.
#[derive(Clone, Debug)]
pub enum Program {
    /// The generated cone-frustum test, run in `directions` by `simulate`.
    Cone {
        cone: ConeTest,
        nc: NcOptions,
        directions: Vec<Direction>,
    },
    /// The planar circular test.
    Circle {
        circle: CircleTest,
        directions: Vec<Direction>,
    },
    /// A G-code file, with the cone geometry when the scenario gives it.
    File {
        path: PathBuf,
        cone: Option<ConeTest>,
    },
}

/// A loaded, validated scenario.
#[derive(Clone, Debug)]
pub struct Scenario {
    pub path: PathBuf,
    pub machine: Machine,
    pub program: Program,
    pub simulate: SimulateSection,
    /// Table-side ball of the virtual ball bar, table frame, mm.
    pub ballbar_pivot_mm: Option<Vector3<f64>>,
    /// What stands on the table, with the cone filled in from the program.
    pub workpiece: WorkpieceConfig,
    /// The tool in the spindle (the scenario's, else the machine's).
    pub tool: ToolConfig,
    pub check: CheckOptions,
    /// How a program file is read: dialect, axes, tools, offsets, search path.
    pub reader: ngc::Options,
    /// Scene geometry of inline tools beyond length and diameter, by tool number.
    pub tool_shapes: std::collections::BTreeMap<u32, ToolShape>,
}

/// `[simulate] tcp = true` applies only to a program written for tool-centre-point control:
/// a generated cone without `[program.cone] tcp` and a circle test are joint-space programs
/// (machine X Y Z), which TCP would read as tool-tip positions. A file is checked as it
/// streams (`program::validate::checked`).
fn refuse_tcp_on_a_joint_space_test(
    path: &Path,
    text: &str,
    program: &Program,
    tcp: bool,
) -> Result<()> {
    let why = match program {
        _ if !tcp => return Ok(()),
        Program::Cone { nc, .. } if !nc.tcp => {
            "the generated cone is written in joint space (machine X Y Z A C); set \
             [program.cone] tcp = true to generate its G43.4 program"
        }
        Program::Circle { .. } => {
            "the circle test is written in machine X Y Z with the rotary axes at rest (joint space)"
        }
        _ => return Ok(()),
    };
    Err(value_error(
        path,
        text,
        "simulate",
        "tcp",
        format!("applies only to programs written for tool-centre-point control: {why}"),
    ))
}

impl Scenario {
    pub fn load(path: &Path) -> Result<Scenario> {
        let text = toml_text::read_text(path)?;
        Scenario::from_toml(path, &text, None)
    }

    /// The scenario whose file at `path` holds `text` (paths inside it are relative to `path`;
    /// the machine file it names is read).
    pub fn from_text(path: &Path, text: &str) -> Result<Scenario> {
        Scenario::from_toml(path, text, None)
    }

    /// Parses `text` as the scenario file `path` (relative paths inside it resolve from
    /// `path`'s folder). `machine` is the machine file's path and text when the caller has
    /// them (the Python package's dict scenarios); otherwise the file the scenario's
    /// `machine` key names is read.
    pub fn from_toml(path: &Path, text: &str, machine: Option<(&Path, &str)>) -> Result<Scenario> {
        Scenario::with_machine(path, text, machine).map(|(s, _)| s)
    }

    /// [`Scenario::from_toml`], with the machine file as it was read: the base on which
    /// [`Scenario::from_tree`] builds more scenarios without reading it again.
    pub fn with_machine(
        path: &Path,
        text: &str,
        machine: Option<(&Path, &str)>,
    ) -> Result<(Scenario, MachineBase)> {
        let file: ScenarioFile = toml_text::parse(path, text)?;
        let (machine_path, machine_text) = match machine {
            Some((p, t)) => (p.to_path_buf(), t.to_string()),
            None => read_machine(path, text, &file.machine)?,
        };
        let overrides = file.machine_overrides.as_ref();
        let base = MachineBase::new(&machine_path, machine_text, overrides.map(|_| path))?;
        let machine = base.machine(overrides.map(|o| (path, Some(text), o)))?;
        let scenario = Scenario::assemble(path, Source::Text(text), file, machine)?;
        Ok((scenario, base))
    }

    /// The scenario whose file at `path` would hold the TOML tree `tree`, on the machine
    /// file `machine` (the one its `machine` key names, read once for many scenarios: a
    /// study's points). It is [`Scenario::from_toml`] of the tree's text, without writing
    /// and reading that text: only a tree that is refused is written out, so that its error
    /// points at the line, column and key of the text, as `from_toml`'s does.
    pub fn from_tree(path: &Path, tree: &toml::Table, machine: &MachineBase) -> Result<Scenario> {
        Scenario::from_tree_unplaced(path, tree, machine).or_else(|_| {
            let text = toml::to_string(tree).map_err(|e| Error::invalid(path, e.to_string()))?;
            Scenario::from_toml(path, &text, Some((machine.path(), machine.text())))
        })
    }

    /// [`Scenario::from_tree`] whose errors name no place.
    fn from_tree_unplaced(
        path: &Path,
        tree: &toml::Table,
        machine: &MachineBase,
    ) -> Result<Scenario> {
        let file = ScenarioFile::deserialize(toml::Value::Table(tree.clone()))
            .map_err(|e| Error::invalid(path, e.to_string()))?;
        let overrides = file.machine_overrides.as_ref();
        let m = machine.machine(overrides.map(|o| (path, None, o)))?;
        Scenario::assemble(path, Source::Tree(tree), file, m)
    }

    /// The validated scenario of `file` on `machine`; `source` is where `file` was read
    /// from, for the places of errors.
    fn assemble(
        path: &Path,
        source: Source,
        file: ScenarioFile,
        machine: Machine,
    ) -> Result<Scenario> {
        let text = source.text();
        let program = program_of(path, text, &file)?;
        let sim = &file.simulate;
        if sim.trace_every == 0 {
            return Err(value_error(
                path,
                text,
                "simulate",
                "trace_every",
                "must be at least 1".into(),
            ));
        }
        if !(sim.lead_deg.is_finite() && (0.0..=180.0).contains(&sim.lead_deg)) {
            return Err(value_error(
                path,
                text,
                "simulate",
                "lead_deg",
                format!("must be in [0, 180] deg, got {}", sim.lead_deg),
            ));
        }
        for (key, value) in [
            ("max_samples", sim.max_samples),
            ("max_trace_rows", sim.max_trace_rows),
        ] {
            if value == 0 {
                return Err(value_error(
                    path,
                    text,
                    "simulate",
                    key,
                    "must be at least 1".into(),
                ));
            }
        }
        if let Some([a, b]) = sim.measure_lines {
            if a == 0 || b < a {
                return Err(value_error(path, text, "simulate", "measure_lines", format!("expected [first, last] source lines with 1 <= first <= last, got [{a}, {b}]")));
            }
        }
        if let Some(p) = file.ballbar.pivot_mm {
            if !p.iter().all(|v| v.is_finite()) {
                return Err(value_error(
                    path,
                    text,
                    "ballbar",
                    "pivot_mm",
                    "must be three finite numbers (mm)".into(),
                ));
            }
        }
        if let Some(w) = &file.workpiece {
            w.validate(path, text, "workpiece")?;
        }
        if let Some(t) = &file.tool {
            t.validate(path, text, "tool")?;
        }
        if let Some(d) = file.check.near_miss_mm {
            if !(d.is_finite() && d >= 0.0) {
                return Err(value_error(
                    path,
                    text,
                    "check",
                    "near_miss_mm",
                    format!("must be a clearance >= 0 mm, got {d}"),
                ));
            }
        }
        let cone = match &program {
            Program::Cone { cone, .. } => Some(*cone),
            Program::File { cone, .. } => *cone,
            Program::Circle { .. } => None,
        };
        let mut workpiece = file.workpiece.clone().unwrap_or_else(|| WorkpieceConfig {
            kind: if cone.is_some() {
                WorkpieceKind::ConeFrustum
            } else {
                WorkpieceKind::None
            },
            ..WorkpieceConfig::default()
        });
        if let Some(c) = cone {
            workpiece.cone = ConeSetup {
                half_apex_deg: c.half_apex_deg,
                inclination_deg: c.inclination_deg,
                center_mm: c.center_mm.into(),
                ballbar_length_mm: c.ballbar_length_mm,
            };
        } else if workpiece.kind != WorkpieceKind::None {
            return Err(value_error(
                path,
                text,
                "workpiece",
                "kind",
                "a cone-frustum or ball-bar workpiece needs a [program.cone]".into(),
            ));
        }
        refuse_what_the_layout_cannot_give(path, &file, &program, &machine)?;
        let reader = reader_options(path, text, &file.reader, &machine)?;
        source.check_numbers(path)?;
        refuse_tcp_on_a_joint_space_test(path, text, &program, file.simulate.tcp)?;
        let mut simulate = file.simulate;
        if let Program::Circle { circle, .. } = &program {
            let lead = match source.has("simulate", "lead_deg") {
                true => LeadIn::given(circle, &machine, simulate.lead_deg)?,
                false => LeadIn::sized(circle, &machine)?,
            };
            simulate.lead_deg = lead.deg;
            simulate.lead_in = Some(lead);
        }
        let tool_shapes = file
            .reader
            .tools
            .iter()
            .map(|t| (t.number, t.shape()))
            .collect();
        let check = CheckOptions {
            near_miss_mm: file
                .check
                .near_miss_mm
                .unwrap_or(machine.scene.near_miss_mm),
            collisions: file.check.collisions,
        };
        Ok(Scenario {
            reader,
            tool_shapes,
            path: path.to_path_buf(),
            tool: file.tool.unwrap_or_else(|| machine.tool.clone()),
            machine,
            program,
            simulate,
            ballbar_pivot_mm: file.ballbar.pivot_mm.map(Vector3::from),
            workpiece,
            check,
        })
    }

    /// The cone geometry, if the scenario has one.
    pub fn cone(&self) -> Option<&ConeTest> {
        match &self.program {
            Program::Cone { cone, .. } => Some(cone),
            Program::File { cone, .. } => cone.as_ref(),
            Program::Circle { .. } => None,
        }
    }
}

/// The program of a scenario file: a circle, a generated cone, or a G-code file (with the
/// cone's geometry when the file gives it).
fn program_of(path: &Path, text: &str, file: &ScenarioFile) -> Result<Program> {
    Ok(match (&file.program.file, &file.program.cone) {
        _ if file.program.circle.is_some() => {
            if file.program.file.is_some() || file.program.cone.is_some() {
                return Err(Error::invalid(
                    path,
                    "[program] takes one of `file`, [program.cone] or [program.circle]",
                ));
            }
            let c = file.program.circle.as_ref().expect("checked above");
            let (circle, directions) = validate_circle(path, text, c)?;
            Program::Circle { circle, directions }
        }
        (Some(f), cone) => Program::File {
            path: resolve(path, f),
            cone: cone
                .as_ref()
                .map(|c| validate_cone(path, text, c))
                .transpose()?
                .map(|(c, _)| c),
        },
        (None, Some(c)) => {
            let (cone, nc) = validate_cone(path, text, c)?;
            let directions =
                parse_directions(path, text, CONE, "directions", c.directions.as_deref())?;
            Program::Cone {
                cone,
                nc,
                directions,
            }
        }
        (None, None) => {
            return Err(Error::invalid(
                path,
                "[program] needs `file = \"...\"` or a [program.cone] table",
            )
            .with_help("see docs/scenario-format.md"))
        }
    })
}

/// Where a scenario's values were read from: its text, which errors point into, or a TOML
/// tree that has none (its errors name no place).
#[derive(Clone, Copy)]
enum Source<'a> {
    Text(&'a str),
    Tree(&'a toml::Table),
}

impl Source<'_> {
    /// The text errors point into; empty for a tree.
    fn text(&self) -> &str {
        match self {
            Source::Text(t) => t,
            Source::Tree(_) => "",
        }
    }

    /// [`toml_text::check_numbers`].
    fn check_numbers(&self, path: &Path) -> Result<()> {
        match self {
            Source::Text(t) => toml_text::check_numbers(path, t),
            Source::Tree(t) => toml_text::check_tree_numbers(path, t),
        }
    }

    /// Whether the scenario gives `key` in `[section]`.
    fn has(&self, section: &str, key: &str) -> bool {
        match self {
            Source::Text(t) => toml_text::locate_key(t, section, key).is_some(),
            Source::Tree(t) => t
                .get(section)
                .and_then(toml::Value::as_table)
                .is_some_and(|s| s.contains_key(key)),
        }
    }
}

/// Refuses, with what to do instead, what a machine's layout cannot give: the generated
/// cone-frustum test needs a tilting rotary table; a machine whose rotaries are world
/// coordinates with no modelled chain (xyzabc, a robot's world axes) has no ball bar,
/// circle or cone test, tool-centre-point control or collision scene.
fn refuse_what_the_layout_cannot_give(
    path: &Path,
    file: &ScenarioFile,
    program: &Program,
    machine: &Machine,
) -> Result<()> {
    let layout = machine.kinematics.layout;
    if let Some(chain) = machine.kinematics.own_chain() {
        return refuse_what_a_chain_cannot_give(path, program, machine, chain);
    }
    if matches!(program, Program::Cone { .. }) && layout.tilt_axis().is_none() {
        return Err(Error::invalid(
            path,
            format!(
                "[program.cone] needs a machine with a tilting rotary table, but {} has the {} layout",
                machine.path.display(),
                layout.name()
            ),
        )
        .with_help("use a trt-ac, trt-bc or trt-ab machine (machines/trt-ac.toml), or a G-code `file`"));
    }
    if file.check.collisions && !layout.has_collision_scene() {
        return Err(Error::invalid(
            path,
            format!(
                "the collision scene ([check] collisions = true, the default) cannot be computed on {} ({} layout): {}",
                machine.path.display(),
                layout.name(),
                if let Some(why) = layout.tool_pose_unmodelled() {
                    format!("{why}, so the tool's pose is unknown")
                } else {
                    "the scene models a milling tool along +Z, not a lathe's turning tool and chuck".to_string()
                }
            ),
        )
        .with_help("set [check] collisions = false: axis limits are still checked"));
    }
    let Some(why) = layout.tool_pose_unmodelled() else {
        return Ok(());
    };
    let asked = if file.ballbar.pivot_mm.is_some() {
        Some("a ball bar ([ballbar] pivot_mm)")
    } else if file.program.cone.is_some() {
        Some("the cone-frustum test's ball bar ([program.cone])")
    } else if file.program.circle.is_some() {
        Some("the circular test's ball bar ([program.circle])")
    } else if file.reader.tcp || file.simulate.tcp {
        Some("tool-centre-point control (TCP: [reader] tcp or [simulate] tcp)")
    } else {
        None
    };
    match asked {
        Some(what) => Err(Error::invalid(
            path,
            format!(
                "{what} cannot be computed on {} ({} layout): {why}",
                machine.path.display(),
                layout.name()
            ),
        )
        .with_help("leave out [ballbar], [program.cone], [program.circle] and TCP: axis limits, timing and the trace are computed on every axis")),
        None => Ok(()),
    }
}

/// [`refuse_what_the_layout_cannot_give`] on a general `[kinematics]` chain: the cone
/// needs every pose within the chain's reach. (The circular test runs with the rotaries held
/// at 0, TCP through the chain, the collision scene with bodies on the chain's links.)
fn refuse_what_a_chain_cannot_give(
    path: &Path,
    program: &Program,
    machine: &Machine,
    chain: &crate::kinematics::Chain,
) -> Result<()> {
    if let Program::Cone { cone, .. } = program {
        let poses = cone.poses();
        let unreachable = (0..360).find_map(|k| {
            let pose = poses.pose((k as f64).to_radians());
            crate::kinematics::chain_inverse::solutions(chain, &pose, 0.0, &crate::AxisVec::ZERO)
                .err()
                .map(|e| format!("at θ = {k} deg: {e}"))
        });
        if let Some(why) = unreachable {
            return Err(Error::invalid(
                path,
                format!(
                    "[program.cone] cannot be generated on {}: {why}",
                    machine.path.display()
                ),
            )
            .with_help("a smaller half apex angle or inclination keeps the tool within the rotaries' reach"));
        }
    }
    Ok(())
}

/// The path and text of the machine file a scenario names; a file that cannot be read is
/// an error at the scenario's `machine` key.
fn read_machine(path: &Path, text: &str, machine: &str) -> Result<(PathBuf, String)> {
    let machine_path = resolve(path, machine);
    let machine_text = toml_text::read_text(&machine_path).map_err(|e| match e {
        Error::Read { source, .. } => value_error(
            path,
            text,
            "",
            "machine",
            format!(
                "cannot read machine file {}: {source}",
                machine_path.display()
            ),
        ),
        other => other,
    })?;
    Ok((machine_path, machine_text))
}

const CONE: &str = "program.cone";

fn validate_cone(path: &Path, text: &str, c: &ConeSection) -> Result<(ConeTest, NcOptions)> {
    let err = |key: &str, message: String| value_error(path, text, CONE, key, message);
    let cone = ConeTest {
        half_apex_deg: c.half_apex_deg,
        inclination_deg: c.inclination_deg,
        center_mm: Vector3::from(c.center_mm),
        ballbar_length_mm: c.ballbar_length_mm,
    };
    check_cone(&cone).map_err(|(key, message)| err(key, message))?;
    if !(3..=1_000_000).contains(&c.segments) {
        return Err(err(
            "segments",
            format!("must be between 3 and 1000000 blocks, got {}", c.segments),
        ));
    }
    check_feed(c.feed_mm_min).map_err(|m| err("feed_mm_min", m))?;
    if c.inverse_time && c.tcp {
        return Err(err(
            "inverse_time",
            "cannot be set with tcp = true: the G43.4 program feeds the tool tip in mm/min (G94); choose one".into(),
        ));
    }
    let nc = NcOptions {
        segments: c.segments,
        feed_mm_min: c.feed_mm_min,
        inverse_time: c.inverse_time,
        tcp: c.tcp,
        lead_deg: 0.0,
        clockwise: false,
    };
    Ok((cone, nc))
}

/// Fastest feed a generated test may ask for, mm/min: beyond the rapid traverse of any
/// machine tool (about 1e5 mm/min on the fastest linear-motor machines).
pub const MAX_FEED_MM_MIN: f64 = 1e6;

/// Checks a generated test's feed: positive and at most [`MAX_FEED_MM_MIN`].
fn check_feed(feed_mm_min: f64) -> std::result::Result<(), String> {
    if !(feed_mm_min.is_finite() && feed_mm_min > 0.0) {
        Err(format!(
            "must be a positive feed in mm/min, got {feed_mm_min}"
        ))
    } else if feed_mm_min > MAX_FEED_MM_MIN {
        Err(format!(
            "feed {feed_mm_min:e} mm/min is beyond any machine (at most {MAX_FEED_MM_MIN} mm/min)"
        ))
    } else {
        Ok(())
    }
}

/// Checks the cone geometry; on failure gives the offending key and what was expected.
pub fn check_cone(cone: &ConeTest) -> std::result::Result<(), (&'static str, String)> {
    if !(cone.half_apex_deg > 0.0 && cone.half_apex_deg < 90.0) {
        return Err((
            "half_apex_deg",
            format!(
                "the half apex angle must be in (0, 90) deg, got {}",
                cone.half_apex_deg
            ),
        ));
    }
    if !(cone.inclination_deg > -90.0 && cone.inclination_deg < 90.0) {
        return Err((
            "inclination_deg",
            format!(
                "the inclination must be in (-90, 90) deg, got {}",
                cone.inclination_deg
            ),
        ));
    }
    if !cone.center_mm.iter().all(|v| v.is_finite()) {
        return Err((
            "center_mm",
            "must be three finite numbers [XT, YT, ZT] in mm".into(),
        ));
    }
    if !(cone.ballbar_length_mm.is_finite() && cone.ballbar_length_mm > 0.0) {
        return Err((
            "ballbar_length_mm",
            format!(
                "must be a positive length in mm, got {}",
                cone.ballbar_length_mm
            ),
        ));
    }
    Ok(())
}

const CIRCLE: &str = "program.circle";

fn validate_circle(
    path: &Path,
    text: &str,
    c: &CircleSection,
) -> Result<(CircleTest, Vec<Direction>)> {
    let err = |key: &str, message: String| value_error(path, text, CIRCLE, key, message);
    let plane = match c.plane.to_ascii_uppercase().as_str() {
        "XY" | "G17" => Plane::XY,
        "ZX" | "XZ" | "G18" => Plane::ZX,
        "YZ" | "G19" => Plane::YZ,
        other => {
            return Err(err(
                "plane",
                format!("expected \"XY\", \"ZX\" or \"YZ\", got \"{other}\""),
            ))
        }
    };
    if !(c.radius_mm.is_finite() && c.radius_mm > 0.0) {
        return Err(err(
            "radius_mm",
            format!("must be a positive radius in mm, got {}", c.radius_mm),
        ));
    }
    check_feed(c.feed_mm_min).map_err(|m| err("feed_mm_min", m))?;
    if !c.center_mm.iter().all(|v| v.is_finite()) {
        return Err(err(
            "center_mm",
            "must be three finite numbers [X, Y, Z] in mm".into(),
        ));
    }
    let directions = match (&c.direction, &c.directions) {
        (Some(_), Some(_)) => {
            return Err(err(
                "directions",
                "give `direction` or `directions`, not both".into(),
            ))
        }
        (Some(d), None) => parse_directions(
            path,
            text,
            CIRCLE,
            "direction",
            Some(std::slice::from_ref(d)),
        )?,
        (None, d) => parse_directions(path, text, CIRCLE, "directions", d.as_deref())?,
    };
    let circle = CircleTest {
        plane,
        center_mm: c.center_mm,
        radius_mm: c.radius_mm,
        feed_mm_min: c.feed_mm_min,
    };
    Ok((circle, directions))
}

/// `["ccw", "cw"]` → directions; default `["ccw"]`; no repeats.
fn parse_directions(
    path: &Path,
    text: &str,
    section: &str,
    key: &str,
    words: Option<&[String]>,
) -> Result<Vec<Direction>> {
    let Some(words) = words else {
        return Ok(vec![Direction::Ccw]);
    };
    let mut out = Vec::new();
    for w in words {
        let d = match w.to_ascii_lowercase().as_str() {
            "ccw" => Direction::Ccw,
            "cw" => Direction::Cw,
            other => {
                return Err(value_error(
                    path,
                    text,
                    section,
                    key,
                    format!("expected \"ccw\" or \"cw\", got \"{other}\""),
                ))
            }
        };
        if out.contains(&d) || out.len() == 2 {
            return Err(value_error(
                path,
                text,
                section,
                key,
                "each direction at most once".into(),
            ));
        }
        out.push(d);
    }
    if out.is_empty() {
        return Err(value_error(
            path,
            text,
            section,
            key,
            "needs at least one direction".into(),
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bundled scenarios, one with `[machine_overrides]`, build from their trees without
    /// the text (the fall-back that writes it is for refused trees only), to the same
    /// scenario.
    #[test]
    fn bundled_scenarios_build_from_their_trees() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        for (name, overrides) in [
            ("cone-15-10.toml", ""),
            ("circle-iso230-4.toml", ""),
            (
                "cone-15-10.toml",
                "[machine_overrides.axes.X.drive]\nbacklash_mm = 0.003\n",
            ),
        ] {
            let path = root.join("scenarios").join(name);
            let text = toml_text::read_text(&path).unwrap() + "\n" + overrides;
            let (by_text, machine) = Scenario::with_machine(&path, &text, None).unwrap();
            let tree: toml::Table = toml::from_str(&text).unwrap();
            let by_tree = Scenario::from_tree_unplaced(&path, &tree, &machine).unwrap();
            assert_eq!(format!("{by_tree:?}"), format!("{by_text:?}"), "{name}");
        }
    }
}
