//! Scenario files (TOML): a machine, a program (generated or a G-code file) and options.
//!
//! Paths are relative to the scenario file; absolute paths work too. Unknown keys are
//! errors that name the key and its line. See `docs/scenario-format.md`.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use serde::Deserialize;

use crate::cone::{ConeTest, NcOptions};
use crate::error::{Error, Result};
use crate::machine::Machine;
use crate::toml_input::{self, value_error};

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    machine: String,
    program: ProgramSection,
    #[serde(default)]
    machine_overrides: Option<toml::Table>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProgramSection {
    /// A G-code file.
    file: Option<String>,
    /// The generated cone-frustum test; with `file`, only its geometry is used (for θ).
    cone: Option<ConeSection>,
}

/// `[program.cone]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConeSection {
    pub half_apex_deg: f64,
    pub inclination_deg: f64,
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
    /// The generated cone-frustum test.
    Cone { cone: ConeTest, nc: NcOptions },
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
}

impl Scenario {
    pub fn load(path: &Path) -> Result<Scenario> {
        let text = toml_input::read_text(path)?;
        let file: ScenarioFile = toml_input::parse(path, &text)?;
        let machine_path = resolve(path, &file.machine);
        let machine_text = toml_input::read_text(&machine_path).map_err(|e| match e {
            Error::Read { source, .. } => value_error(
                path,
                &text,
                "",
                "machine",
                format!(
                    "cannot read machine file {}: {source}",
                    machine_path.display()
                ),
            ),
            other => other,
        })?;
        let machine = Machine::from_toml(
            &machine_path,
            &machine_text,
            file.machine_overrides
                .as_ref()
                .map(|o| (path, text.as_str(), o)),
        )?;
        let program = match (&file.program.file, &file.program.cone) {
            (Some(f), cone) => Program::File {
                path: resolve(path, f),
                cone: cone
                    .as_ref()
                    .map(|c| validate_cone(path, &text, c))
                    .transpose()?
                    .map(|(c, _)| c),
            },
            (None, Some(c)) => {
                let (cone, nc) = validate_cone(path, &text, c)?;
                Program::Cone { cone, nc }
            }
            (None, None) => {
                return Err(Error::invalid(
                    path,
                    "[program] needs `file = \"...\"` or a [program.cone] table",
                )
                .with_help("see docs/scenario-format.md"))
            }
        };
        Ok(Scenario {
            path: path.to_path_buf(),
            machine,
            program,
        })
    }

    /// The cone geometry, if the scenario has one.
    pub fn cone(&self) -> Option<&ConeTest> {
        match &self.program {
            Program::Cone { cone, .. } => Some(cone),
            Program::File { cone, .. } => cone.as_ref(),
        }
    }
}

/// A path from a scenario, relative to the scenario's folder unless absolute.
pub fn resolve(scenario: &Path, relative: &str) -> PathBuf {
    let p = Path::new(relative);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        scenario.parent().unwrap_or(Path::new(".")).join(p)
    }
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
    if !(c.feed_mm_min.is_finite() && c.feed_mm_min > 0.0) {
        return Err(err(
            "feed_mm_min",
            format!("must be a positive feed in mm/min, got {}", c.feed_mm_min),
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
