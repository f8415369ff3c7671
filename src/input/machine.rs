//! Machine description files (TOML): layout, axis limits and per-axis drive parameters.
//!
//! Every key and its unit is documented in `docs/machine-format.md`. Unknown keys are
//! errors that name the key and its line.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::input::component_errors;
use crate::input::drive::{AxisDrive, DriveConfig, FrictionConfig, ServoConfig};
use crate::input::exact;
use crate::input::geometry_errors::{self, GeometryErrors};
use crate::input::scene::{SceneConfig, ToolConfig};
use crate::input::toml_text::{self, value_error};
use crate::kinematics::pole::MAX_POLE_TOLERANCE_DEG;
use crate::kinematics::{Chain, Kinematics, Layout, Link};
use crate::Axis;

/// `[start]`: the modal state the control powers up in, before a program states it (a
/// control's setup: Haas setting 9 "Dimensioning", Fanuc parameter 0000 bit INI for the
/// units); what is not given is every dialect's factory state, mm, G90, G17, G94.
#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StartSection {
    /// "mm" or "inch".
    pub units: Option<ngc::Units>,
    /// "absolute" or "incremental".
    pub distance: Option<ngc::Distance>,
    /// "XY", "ZX" or "YZ".
    pub plane: Option<ngc::Plane>,
    /// "per-minute", "per-revolution" or "inverse-time".
    pub feed_mode: Option<ngc::StartFeed>,
}

/// The deepest look-ahead `[control] lookahead_blocks` takes: the planner holds about 1.5
/// times it in blocks, so this bounds its memory (a few MB) whatever the program's length.
pub const MAX_LOOKAHEAD_BLOCKS: usize = 10_000;

/// `[control]`: the control's parameters that change a program's moves, set by the machine
/// builder where a program cannot see them: how its planner runs the moves
/// (docs/interpolation.md) and the reader's settings (docs/machine-format.md); what is not
/// given is the dialect's rule, with a notice where that rule is a setting of the control.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControlSection {
    /// Share of each axis's `max_acceleration` a rapid (G00) may use, in (0, 1]. LinuxCNC
    /// 2.9 runs its G0 at 0.5 (measured, black box: docs/interpolation.md); default 1.
    pub rapid_acceleration_share: f64,
    /// The path tolerance (mm) of blending when a program sets none (a G64 without P, or a
    /// dialect's blending mode without its tolerance word); absent: no tolerance bound (the
    /// corner keeps the junction rule unless `max_feed_override` is given).
    pub path_tolerance_mm: Option<f64>,
    /// The control's highest feed override (LinuxCNC: `[DISPLAY] MAX_FEED_OVERRIDE`), > 0.
    /// When given, the planner blends as LinuxCNC 2.9 does: a G64 corner without a tolerance
    /// is blended too, each blend arc at most as long as the feed times this override needs
    /// ([`crate::motion::blend::arc_length_for_speed`], docs/interpolation.md); absent: a
    /// corner without a tolerance keeps the junction rule.
    pub max_feed_override: Option<f64>,
    /// G73 retract after each peck, mm (Fanuc parameter 5114, Haas Setting 22).
    pub g73_retract_mm: Option<f64>,
    /// G83 clearance above each peck's depth where the rapid down stops, mm (Fanuc
    /// parameter 5115).
    pub g83_clearance_mm: Option<f64>,
    /// G83 retract height above R, mm (Haas Setting 52).
    pub g83_above_r_mm: Option<f64>,
    /// G28/G30 without axis words: `"all"` axes return, or `"none"`.
    pub g28_without_axes: Option<ReferenceWithoutAxes>,
    /// Dimension words without a decimal point (`Z50`): `"increments"` (0.001 mm, 0.0001
    /// in, 0.001 deg: Fanuc parameter 3401#0 = 0, Haas Setting 162 off) or `"units"` (DPI
    /// = 1, Setting 162 on). Absent: the dialect's default (Fanuc, Haas: increments).
    pub whole_numbers: Option<WholeNumbersKey>,
    /// How many blocks the control's planner looks ahead (Fanuc's AI contour control, the
    /// Heidenhain look-ahead, Sinumerik's LookAhead buffer), in [1, 10,000]; absent: 256.
    /// The planner keeps the machine able to stop within them, so a program of tiny blocks
    /// runs below its F when their sum is shorter than the stopping distance
    /// (docs/interpolation.md, "Look-ahead").
    pub lookahead_blocks: Option<usize>,
}

impl Default for ControlSection {
    fn default() -> Self {
        ControlSection {
            rapid_acceleration_share: 1.0,
            path_tolerance_mm: None,
            max_feed_override: None,
            g73_retract_mm: None,
            g83_clearance_mm: None,
            g83_above_r_mm: None,
            g28_without_axes: None,
            whole_numbers: None,
            lookahead_blocks: None,
        }
    }
}

/// What G28/G30 without axis words move.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ReferenceWithoutAxes {
    All,
    None,
}

/// The `whole_numbers` key's values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WholeNumbersKey {
    Increments,
    Units,
}

/// Longest peck retract or clearance accepted, mm (Haas Setting 22's range is 0 to 29.9999 in).
const MAX_PECK_SETTING_MM: f64 = 760.0;

impl ControlSection {
    /// The section's values checked (each in [0, 760] mm), as the reader takes them.
    fn validate(&self, path: &Path, text: &str) -> Result<ngc::ControlParameters> {
        let keys = [
            ("g73_retract_mm", self.g73_retract_mm),
            ("g83_clearance_mm", self.g83_clearance_mm),
            ("g83_above_r_mm", self.g83_above_r_mm),
        ];
        for (key, value) in keys {
            if let Some(v) = value.filter(|v| !(0.0..=MAX_PECK_SETTING_MM).contains(v)) {
                let message =
                    format!("{key} = {v}: expected a distance in [0, {MAX_PECK_SETTING_MM}] mm");
                return Err(value_error(path, text, "control", key, message));
            }
        }
        Ok(ngc::ControlParameters {
            g73_retract_mm: self.g73_retract_mm,
            g83_clearance_mm: self.g83_clearance_mm,
            g83_above_r_mm: self.g83_above_r_mm.unwrap_or(0.0),
            reference_all_without_axes: self
                .g28_without_axes
                .map(|r| r == ReferenceWithoutAxes::All),
            whole_numbers: self.whole_numbers.map(|w| match w {
                WholeNumbersKey::Increments => ngc::WholeNumbers::Increments,
                WholeNumbersKey::Units => ngc::WholeNumbers::Units,
            }),
        })
    }
}

/// The `kinematics` key: a named layout (`"trt-ac"`) or a `[kinematics]` chain table
/// (the kinematic-chains spec).
#[derive(Clone, Debug)]
pub enum KinematicsSpec {
    Named(Layout),
    Chain(ChainFile),
}

/// A `[kinematics]` table as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChainFile {
    /// The axes that carry the workpiece, from the bed outward.
    #[serde(default)]
    pub table: Vec<String>,
    /// The axes that carry the tool, from the bed outward.
    #[serde(default)]
    pub head: Vec<String>,
    /// The spindle gauge point, machine frame, all axes at 0, mm.
    #[serde(default, deserialize_with = "exact::array")]
    pub gauge_point_mm: [f64; 3],
    /// Unit vector from the tool tip toward the spindle, all axes at 0.
    #[serde(default = "default_tool_direction", deserialize_with = "exact::array")]
    pub tool_direction: [f64; 3],
    /// Within this angle of the pole the inner rotary holds, deg (the kinematic-chains
    /// spec, "Poles, as controls handle them"); default
    /// [`crate::kinematics::DEFAULT_POLE_TOLERANCE_DEG`].
    #[serde(default)]
    pub pole_tolerance_deg: Option<f64>,
}

fn default_tool_direction() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

impl<'de> Deserialize<'de> for KinematicsSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Spec;
        impl<'de> serde::de::Visitor<'de> for Spec {
            type Value = KinematicsSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a layout name such as \"trt-ac\" or a [kinematics] table")
            }
            fn visit_str<E: serde::de::Error>(
                self,
                v: &str,
            ) -> std::result::Result<Self::Value, E> {
                Layout::deserialize(serde::de::value::StrDeserializer::<E>::new(v))
                    .map(KinematicsSpec::Named)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> std::result::Result<Self::Value, A::Error> {
                ChainFile::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(KinematicsSpec::Chain)
            }
        }
        d.deserialize_any(Spec)
    }
}

/// A machine file as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineFile {
    /// Free text.
    pub name: String,
    /// A named layout ("xyz", "trt-ac", ...) or a `[kinematics]` chain.
    pub kinematics: KinematicsSpec,
    /// Machine coordinates of the pivot (where the rotary axes cross), mm.
    #[serde(default, deserialize_with = "exact::array")]
    pub pivot_mm: [f64; 3],
    /// Interpolator period, ms.
    #[serde(default = "default_interpolation_period_ms")]
    pub interpolation_period_ms: f64,
    /// One table per axis, keyed by letter: `[axes.X]`.
    pub axes: BTreeMap<String, AxisConfig>,
    /// Collision-scene geometry of the machine; None when the file has no `[scene]` (the
    /// default geometry then stands in for it).
    #[serde(default)]
    pub scene: Option<SceneConfig>,
    /// The tool in the spindle.
    #[serde(default)]
    pub tool: ToolConfig,
    /// G-code dialect of this machine's control, the default for its scenarios:
    /// "linuxcnc", "fanuc" (default), "haas", "heidenhain" or "siemens".
    #[serde(default)]
    pub dialect: Option<ngc::Dialect>,
    /// The modal state the control powers up in.
    #[serde(default)]
    pub start: StartSection,
    /// The control's parameters that change a program's moves.
    #[serde(default)]
    pub control: ControlSection,
    /// G28 reference position, machine X Y Z A B C (mm, deg; U V W: 0). Absent: a
    /// program that uses G28 is refused, naming this key.
    #[serde(default, deserialize_with = "exact::option_array")]
    pub g28_mm: Option<[f64; 6]>,
    /// G30 reference position, as `g28_mm`.
    #[serde(default, deserialize_with = "exact::option_array")]
    pub g30_mm: Option<[f64; 6]>,
    // --- geometric errors (input/geometry_errors.rs) ---
    /// ISO 230-7 location errors of the rotary axes: `EX0C_um = 8.0`.
    #[serde(default)]
    pub location_errors: BTreeMap<String, f64>,
    /// Position-error table files per axis (LinuxCNC compensation format): `C = "c.comp"`.
    #[serde(default)]
    pub error_tables: BTreeMap<String, String>,
    /// ISO 230-1 component-error tables (CSV) of the linear axes: `X = "x-errors.csv"`
    /// (input/component_errors.rs).
    #[serde(default)]
    pub component_errors: BTreeMap<String, String>,
}

fn default_interpolation_period_ms() -> f64 {
    1.0
}

/// Shortest interpolation period, ms: shorter ones only multiply the samples (and the
/// numerical noise of differentiated velocities) without changing what the axes do.
pub const MIN_PERIOD_MS: f64 = 0.01;
/// Longest interpolation period, ms.
pub const MAX_PERIOD_MS: f64 = 100.0;
/// Smallest velocity (per min), acceleration (per s²) and jerk (per s³) limit of an axis,
/// mm or deg: below it an axis barely moves, and a run would take without end.
pub const MIN_AXIS_LIMIT: f64 = 1e-3;

/// Limits and drive parameters of one axis. Linear axes in mm, rotary axes in deg.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisConfig {
    /// Lower travel limit, mm or deg.
    pub min: f64,
    /// Upper travel limit, mm or deg.
    pub max: f64,
    /// A rotary axis that turns without end; `min`/`max` are then not travel limits.
    #[serde(default)]
    pub continuous: bool,
    /// Velocity limit, mm/min or deg/min.
    pub max_velocity: f64,
    /// Acceleration limit, mm/s^2 or deg/s^2.
    pub max_acceleration: f64,
    /// Jerk limit, mm/s^3 or deg/s^3.
    pub max_jerk: f64,
    /// Chains only: unit vector of the axis (rotary: its line; linear: its motion), at
    /// home; default its letter's (X, U, A: +X; Y, V, B: +Y; Z, W, C: +Z).
    #[serde(default, deserialize_with = "exact::option_array")]
    pub direction: Option<[f64; 3]>,
    /// Chains only, rotary axes: a point on the axis line at home, mm; default the origin.
    #[serde(default, deserialize_with = "exact::option_array")]
    pub point_mm: Option<[f64; 3]>,
    /// Linear axes X, Y, Z: the reference point r_J of its `[component_errors]` table
    /// (where it was measured), machine frame at home, mm; default the origin.
    #[serde(default, deserialize_with = "exact::option_array")]
    pub reference_mm: Option<[f64; 3]>,
    #[serde(default)]
    pub servo: ServoConfig,
    #[serde(default)]
    pub drive: DriveConfig,
    #[serde(default)]
    pub friction: FrictionConfig,
}

/// One axis of a loaded machine: its limits and its drive, resolved (every default applied,
/// in SI units) when the file was read. Linear axes in mm, rotary axes in deg.
#[derive(Clone, Debug, PartialEq)]
pub struct MachineAxis {
    /// Lower and upper travel limit, mm or deg.
    pub min: f64,
    pub max: f64,
    /// A rotary axis that turns without end; `min`/`max` are then not travel limits.
    pub continuous: bool,
    /// Velocity limit, mm/min or deg/min.
    pub max_velocity: f64,
    /// Acceleration limit, mm/s^2 or deg/s^2.
    pub max_acceleration: f64,
    /// Jerk limit, mm/s^3 or deg/s^3.
    pub max_jerk: f64,
    /// The servo, mechanics and friction of `[axes.X.servo]`, `.drive` and `.friction`.
    pub drive: AxisDrive,
}

impl MachineAxis {
    /// True when `value` (mm or deg) lies within the travel, or the axis is continuous.
    pub fn within_travel(&self, value: f64) -> bool {
        self.continuous || (self.min..=self.max).contains(&value)
    }
}

/// A validated machine.
#[derive(Clone, Debug)]
pub struct Machine {
    pub name: String,
    /// The file it came from.
    pub path: PathBuf,
    pub kinematics: Kinematics,
    /// Interpolator period, s.
    pub interpolation_period_s: f64,
    axes: BTreeMap<Axis, MachineAxis>,
    pub scene: SceneConfig,
    /// Whether the machine file gives its `[scene]`; without it, `check` says that the
    /// default geometry stood in for the machine's.
    pub scene_given: bool,
    pub tool: ToolConfig,
    /// Default G-code dialect of the control.
    pub dialect: ngc::Dialect,
    /// The machine file names its control's dialect (`dialect`): the control's factory
    /// settings then hold where `[control]` is silent (a Fanuc's whole numbers in the
    /// least input increment); a machine that names none is a generic control that reads
    /// `Z50` as 50 mm.
    pub dialect_named: bool,
    /// The modal state the control powers up in, as far as the file gives it.
    pub start: StartSection,
    /// The control's parameters (`[control]`), validated.
    pub control: ControlSection,
    /// The reader's part of them.
    pub reader_control: ngc::ControlParameters,
    /// G28 and G30 reference positions, machine X Y Z A B C (mm, deg); U V W at 0;
    /// `None` where the file gives none.
    pub reference_mm: [Option<[f64; 6]>; 2],
    /// Geometric errors; the location errors are also in `kinematics`.
    pub geometry: GeometryErrors,
}

impl Machine {
    /// Loads and validates a machine file.
    pub fn load(path: &Path) -> Result<Machine> {
        let text = toml_text::read_text(path)?;
        Machine::from_toml(path, &text, None)
    }

    /// Parses `text` (the contents of `path`), deep-merging `overrides` over it first.
    /// Errors in the overrides are reported against `overrides.0`, the scenario file.
    pub fn from_toml(
        path: &Path,
        text: &str,
        overrides: Option<(&Path, &str, &toml::Table)>,
    ) -> Result<Machine> {
        MachineBase::new(path, text.to_string(), overrides.map(|o| o.0))?
            .machine(overrides.map(|(scenario, text, o)| (scenario, Some(text), o)))
    }

    /// `tables_files`: the files that name the `[error_tables]` and the
    /// `[component_errors]` (their paths are relative to those files).
    fn validate(
        path: &Path,
        text: &str,
        file: MachineFile,
        tables_files: [&Path; 2],
    ) -> Result<Machine> {
        let [tables_file, components_file] = tables_files;
        let kinematics = kinematics_of(path, text, &file)?;
        let layout = kinematics.layout;
        let mut axes = BTreeMap::new();
        let mut reference_mm = BTreeMap::new();
        for (name, config) in file.axes {
            let section = format!("axes.{name}");
            let axis = match name.chars().collect::<Vec<_>>().as_slice() {
                [c] => Axis::from_letter(*c),
                _ => None,
            };
            let Some(axis) = axis.filter(|a| layout.axes().contains(a)) else {
                let message = format!(
                    "the {} layout has no axis `{name}`; expected one of {}",
                    layout.name(),
                    axis_list(layout)
                );
                return Err(match toml_text::locate_key_header(text, &section) {
                    Some(span) => Error::at(path, text, span, message, "unknown axis"),
                    None => Error::invalid(path, message),
                });
            };
            let drive = check_axis(path, text, &section, axis, &config)?;
            if let Some(r) = config.reference_mm {
                if !matches!(axis, Axis::X | Axis::Y | Axis::Z) || !r.iter().all(|v| v.is_finite())
                {
                    let message = "the reference point of a linear axis X, Y or Z's component \
                                   errors: three finite numbers, mm"
                        .to_string();
                    return Err(value_error(path, text, &section, "reference_mm", message));
                }
                reference_mm.insert(axis, r);
            }
            axes.insert(
                axis,
                MachineAxis {
                    min: config.min,
                    max: config.max,
                    continuous: config.continuous,
                    max_velocity: config.max_velocity,
                    max_acceleration: config.max_acceleration,
                    max_jerk: config.max_jerk,
                    drive,
                },
            );
        }
        for axis in layout.axes() {
            if !axes.contains_key(axis) {
                return Err(Error::invalid(
                    path,
                    format!(
                        "missing table [axes.{axis}]: the {} layout needs axes {}",
                        layout.name(),
                        axis_list(layout)
                    ),
                ));
            }
        }
        let period_ms = file.interpolation_period_ms;
        if !(MIN_PERIOD_MS..=MAX_PERIOD_MS).contains(&period_ms) {
            return Err(value_error(
                path,
                text,
                "",
                "interpolation_period_ms",
                format!(
                    "must be in [{MIN_PERIOD_MS}, {MAX_PERIOD_MS}] ms (controls interpolate every 0.1 to 10 ms), got {period_ms}"
                ),
            ));
        }
        let share = file.control.rapid_acceleration_share;
        if !(share > 0.0 && share <= 1.0) {
            return Err(value_error(
                path,
                text,
                "control",
                "rapid_acceleration_share",
                format!("must be in (0, 1], got {share}"),
            ));
        }
        if let Some(tol) = file.control.path_tolerance_mm {
            if !(tol.is_finite() && tol >= 0.0) {
                return Err(value_error(
                    path,
                    text,
                    "control",
                    "path_tolerance_mm",
                    format!("must be a finite tolerance >= 0 mm, got {tol}"),
                ));
            }
        }
        if let Some(blocks) = file.control.lookahead_blocks {
            if !(1..=MAX_LOOKAHEAD_BLOCKS).contains(&blocks) {
                return Err(value_error(
                    path,
                    text,
                    "control",
                    "lookahead_blocks",
                    format!(
                        "must be a number of blocks in [1, {MAX_LOOKAHEAD_BLOCKS}], got {blocks}"
                    ),
                ));
            }
        }
        if let Some(ovr) = file.control.max_feed_override {
            if !(ovr.is_finite() && ovr > 0.0) {
                return Err(value_error(
                    path,
                    text,
                    "control",
                    "max_feed_override",
                    format!("must be a finite override > 0 (1 = 100 %), got {ovr}"),
                ));
            }
        }
        if !file.pivot_mm.iter().all(|v| v.is_finite()) {
            return Err(value_error(
                path,
                text,
                "",
                "pivot_mm",
                "must be three finite numbers (mm)".into(),
            ));
        }
        let reader_control = file.control.validate(path, text)?;
        let scene_given = file.scene.is_some();
        let scene = file.scene.unwrap_or_default();
        crate::input::scene::validate_machine_tables(path, text, &scene, &file.tool)?;
        let geometry = geometry_errors::validate(
            path,
            text,
            layout,
            kinematics.own_chain(),
            &file.location_errors,
            &file.error_tables,
            tables_file.parent().unwrap_or(Path::new(".")),
        )?;
        let components = component_errors::read(
            path,
            text,
            layout,
            kinematics.chain().as_ref(),
            &file.component_errors,
            &reference_mm,
            components_file.parent().unwrap_or(Path::new(".")),
        )?;
        Ok(Machine {
            name: file.name,
            path: path.to_path_buf(),
            kinematics: kinematics
                .with_location_errors(geometry.location.with_components(components)),
            geometry,
            interpolation_period_s: file.interpolation_period_ms * 1e-3,
            axes,
            scene,
            scene_given,
            tool: file.tool,
            dialect: file.dialect.unwrap_or_default(),
            dialect_named: file.dialect.is_some(),
            start: file.start,
            control: file.control,
            reader_control,
            reference_mm: [file.g28_mm, file.g30_mm],
        })
    }

    /// The axes of this machine, in X Y Z A B C U V W order.
    pub fn axes(&self) -> &'static [Axis] {
        self.kinematics.layout.axes()
    }

    /// Limits and drive of `axis`; panics if the machine has no such axis (a programming
    /// error: every axis of the layout is checked present on load).
    pub fn axis(&self, axis: Axis) -> &MachineAxis {
        &self.axes[&axis]
    }

    /// Mutable limits and drive of `axis` (for what-if runs such as `fit`, which change the
    /// resolved values through [`AxisDrive::with_backlash_mm_or_deg`] and
    /// [`AxisDrive::with_kv_per_s`]); panics like [`Machine::axis`].
    pub fn axis_mut(&mut self, axis: Axis) -> &mut MachineAxis {
        self.axes
            .get_mut(&axis)
            .expect("every axis of the layout is present")
    }

    /// The drive of `axis` in SI units, as resolved when the file was read
    /// ([`AxisDrive::resolve`]).
    pub fn drive(&self, axis: Axis) -> AxisDrive {
        self.axis(axis).drive
    }

    /// The same machine with every axis's drive at its defaults: what stays when the drives
    /// are set aside (a key of the machines that can share one interpolation pass).
    pub fn with_default_drives(&self) -> Machine {
        let mut bare = self.clone();
        for (axis, config) in bare.axes.iter_mut() {
            config.drive = AxisDrive::default_for(*axis);
        }
        bare
    }

    pub fn has_axis(&self, axis: Axis) -> bool {
        self.axes.contains_key(&axis)
    }
}

/// A machine file read and checked on its own, ready to take a scenario's
/// `[machine_overrides]` again and again: a study's points read the file once.
#[derive(Clone, Debug)]
pub struct MachineBase {
    path: PathBuf,
    text: String,
    /// The file's TOML tree, which the overrides are merged over.
    tree: toml::Table,
    /// The machine as the file alone gives it.
    alone: Machine,
}

impl MachineBase {
    /// The machine file at `path` whose contents are `text`, checked on its own: its errors
    /// point at its own lines. The machine file and its error tables may be any file the
    /// user named: their lines are quoted in a message only when it is the file `shown`.
    pub fn new(path: &Path, text: String, shown: Option<&Path>) -> Result<MachineBase> {
        MachineBase::quoted(path, text).map_err(|e| e.without_source_unless(shown))
    }

    fn quoted(path: &Path, text: String) -> Result<MachineBase> {
        let file: MachineFile = toml_text::parse(path, &text)?;
        let alone = Machine::validate(path, &text, file, [path, path])?;
        let tree = toml_text::numbers_checked(path, &text)?;
        Ok(MachineBase {
            path: path.to_path_buf(),
            text,
            tree,
            alone,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The file's contents.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The file's TOML tree.
    pub fn tree(&self) -> &toml::Table {
        &self.tree
    }

    /// The machine, with `overrides` merged over the file when a scenario gives them
    /// (its path, text when there is one, and `[machine_overrides]` table: see
    /// [`MachineBase::overridden`]); errors are quoted only from the scenario's lines.
    pub fn machine(
        &self,
        overrides: Option<(&Path, Option<&str>, &toml::Table)>,
    ) -> Result<Machine> {
        match overrides {
            None => Ok(self.alone.clone()),
            Some((scenario, text, o)) => self
                .overridden(scenario, text, o)
                .map_err(|e| e.without_source_unless(Some(scenario))),
        }
    }

    /// The machine with the `[machine_overrides]` table `overrides` of the scenario file
    /// `scenario` merged over the file. With the scenario's text, an error the overrides
    /// make points at its key there; without it (a scenario built from a tree) it names no
    /// place: read the tree's text then for the place.
    fn overridden(
        &self,
        scenario: &Path,
        scenario_text: Option<&str>,
        overrides: &toml::Table,
    ) -> Result<Machine> {
        // Error-table paths are relative to the file that names them.
        let named_by = |key: &str| match overrides.contains_key(key) {
            true => scenario,
            false => self.path.as_path(),
        };
        let tables_files = [named_by("error_tables"), named_by("component_errors")];
        let mut merged = self.tree.clone();
        deep_merge(&mut merged, overrides);
        let file = match scenario_text {
            Some(text) => toml_text::parse_overridden::<MachineFile>(&merged, scenario, text),
            None => MachineFile::deserialize(toml::Value::Table(merged))
                .map_err(|e| Error::invalid(scenario, e.to_string())),
        }
        .map_err(|e| {
            e.with_help("[machine_overrides] takes the same keys as a machine file; see docs/machine-format.md")
        })?;
        // Range errors in overridden values point at the scenario file; the machine is still
        // the machine file's (test.json names it, the scenario hash reads it).
        let mut machine =
            Machine::validate(scenario, scenario_text.unwrap_or(""), file, tables_files)?;
        machine.path = self.path.clone();
        Ok(machine)
    }
}

/// The machine's kinematics: its named layout, or its `[kinematics]` chain (run as the
/// named layout it is written as, if any).
fn kinematics_of(path: &Path, text: &str, file: &MachineFile) -> Result<Kinematics> {
    let chain = match &file.kinematics {
        KinematicsSpec::Named(layout) => {
            for (name, config) in &file.axes {
                let key = match (config.direction, config.point_mm) {
                    (Some(_), _) => "direction",
                    (None, Some(_)) => "point_mm",
                    (None, None) => continue,
                };
                return Err(value_error(
                    path,
                    text,
                    &format!("axes.{name}"),
                    key,
                    format!(
                        "only a [kinematics] chain takes axis directions and points; the {} layout fixes them",
                        layout.name()
                    ),
                ));
            }
            return Ok(Kinematics::new(*layout, Vector3::from(file.pivot_mm)));
        }
        KinematicsSpec::Chain(chain) => chain,
    };
    let tolerance = pole_tolerance_deg(path, text, chain.pole_tolerance_deg)?;
    if file.pivot_mm != [0.0; 3] {
        return Err(value_error(
            path,
            text,
            "",
            "pivot_mm",
            "a [kinematics] chain places its rotary lines by their `point_mm`; remove `pivot_mm`"
                .into(),
        ));
    }
    let link = |key: &str, name: &String| -> Result<Link> {
        let fail = |message: String| value_error(path, text, "kinematics", key, message);
        let axis = match name.chars().collect::<Vec<_>>().as_slice() {
            [c] => Axis::from_letter(*c),
            _ => None,
        }
        .ok_or_else(|| {
            fail(format!(
                "`{name}` is not an axis letter (X Y Z A B C U V W)"
            ))
        })?;
        let config = file.axes.get(name).ok_or_else(|| {
            fail(format!(
                "axis {name} of the chain has no [axes.{name}] table"
            ))
        })?;
        let home = match axis {
            Axis::X | Axis::U | Axis::A => Vector3::x(),
            Axis::Y | Axis::V | Axis::B => Vector3::y(),
            _ => Vector3::z(),
        };
        let direction = config.direction.map_or(home, Vector3::from);
        if axis.is_rotary() {
            let point = config.point_mm.map_or(Vector3::zeros(), Vector3::from);
            Ok(Link::rotary(axis, direction, point))
        } else if config.point_mm.is_some() {
            Err(value_error(
                path,
                text,
                &format!("axes.{name}"),
                "point_mm",
                "a linear axis has no line to place; remove `point_mm`".into(),
            ))
        } else {
            Ok(Link::linear(axis, direction))
        }
    };
    let table = chain
        .table
        .iter()
        .map(|n| link("table", n))
        .collect::<Result<Vec<_>>>()?;
    let head = chain
        .head
        .iter()
        .map(|n| link("head", n))
        .collect::<Result<Vec<_>>>()?;
    let chain = Chain::new(
        &table,
        &head,
        Vector3::from(chain.gauge_point_mm),
        Vector3::from(chain.tool_direction),
    )
    .map_err(|e| value_error(path, text, "kinematics", "head", e.0))?;
    Ok(Kinematics::from_chain(chain).with_pole_tolerance(tolerance))
}

/// `[kinematics] pole_tolerance_deg`, checked once: finite, above 0, at most
/// [`MAX_POLE_TOLERANCE_DEG`]; the default when not given.
fn pole_tolerance_deg(path: &Path, text: &str, given: Option<f64>) -> Result<f64> {
    let Some(deg) = given else {
        return Ok(crate::kinematics::DEFAULT_POLE_TOLERANCE_DEG);
    };
    if deg.is_finite() && deg > 0.0 && deg <= MAX_POLE_TOLERANCE_DEG {
        return Ok(deg);
    }
    Err(value_error(
        path,
        text,
        "kinematics",
        "pole_tolerance_deg",
        format!(
            "must be an angle in deg above 0 and at most {MAX_POLE_TOLERANCE_DEG} (the tool direction may deviate by it near the pole), got {deg}"
        ),
    ))
}

fn axis_list(layout: Layout) -> String {
    layout
        .axes()
        .iter()
        .map(|a| a.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Checks the limits of `[axes.X]` and its drive tables, and resolves the drive.
fn check_axis(
    path: &Path,
    text: &str,
    section: &str,
    axis: Axis,
    c: &AxisConfig,
) -> Result<AxisDrive> {
    let unit = axis.unit();
    let positive = |key: &str, v: f64, what: &str| {
        if v.is_finite() && v >= MIN_AXIS_LIMIT {
            Ok(())
        } else {
            Err(value_error(
                path,
                text,
                section,
                key,
                format!("must be a finite number >= {MIN_AXIS_LIMIT} ({what}), got {v}"),
            ))
        }
    };
    positive("max_velocity", c.max_velocity, &format!("{unit}/min"))?;
    positive(
        "max_acceleration",
        c.max_acceleration,
        &format!("{unit}/s^2"),
    )?;
    positive("max_jerk", c.max_jerk, &format!("{unit}/s^3"))?;
    for (key, v) in [("min", c.min), ("max", c.max)] {
        if !v.is_finite() {
            return Err(value_error(
                path,
                text,
                section,
                key,
                format!("must be a finite number ({unit}), got {v}"),
            ));
        }
    }
    if c.min >= c.max {
        return Err(value_error(
            path,
            text,
            section,
            "max",
            format!("must be greater than min ({} {unit}), got {}", c.min, c.max),
        ));
    }
    if c.continuous && !axis.is_rotary() {
        return Err(value_error(
            path,
            text,
            section,
            "continuous",
            "only a rotary axis can be continuous".into(),
        ));
    }
    crate::input::drive::validate(path, text, section, axis, &c.servo, &c.drive, &c.friction)
}

/// Merges `overlay` into `base`: tables merge key by key, any other value replaces.
pub fn deep_merge(base: &mut toml::Table, overlay: &toml::Table) {
    for (key, value) in overlay {
        match (base.get_mut(key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => deep_merge(b, o),
            _ => {
                base.insert(key.clone(), value.clone());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The machine loader calls [`crate::input::drive::validate`], so a bad drive key in a
    /// machine file is reported at its line.
    #[test]
    fn machine_files_report_drive_errors_at_their_line() {
        let axis = |name: &str, extra: &str| {
            format!("[axes.{name}]\nmin = -100\nmax = 100\nmax_velocity = 10000\nmax_acceleration = 1000\nmax_jerk = 10000\n{extra}")
        };
        let head = "name = \"m\"\nkinematics = \"xyz\"\n";
        let text = format!(
            "{head}{}{}{}",
            axis("X", "[axes.X.servo]\nmodel = \"cascade\"\n"),
            axis("Y", ""),
            axis("Z", "[axes.Z.drive]\nbacklash_deg = 0.1\n")
        );
        match Machine::from_toml(Path::new("m.toml"), &text, None) {
            Err(Error::Located { line, message, .. }) => {
                assert_eq!(line, 24);
                assert!(
                    message.starts_with("`axes.Z.drive.backlash_deg`: is a rotary-axis key"),
                    "{message}"
                );
            }
            other => panic!("expected an error at a line, got {other:?}"),
        }
    }
}
