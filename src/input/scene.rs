//! The `[scene]`, `[tool]` and `[workpiece]` tables: geometry in mm, with defaults that fit
//! the bundled trt-ac machine (pivot at the machine origin) running the 15/10 and 45/30
//! cone tests centred at table (0, 0, 200) mm with a 20 mm cutter. Every key is documented
//! in `docs/scene.md`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::input::exact;
use crate::input::toml_text::value_error;

/// `[scene]`: machine geometry for collision checks.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SceneConfig {
    /// The rotary table, in the table frame.
    pub table: TableConfig,
    /// Boxes of the trunnion/cradle, in the cradle frame (the table frame before the C
    /// rotation): they tilt with A (or B) but do not turn with C. On a `[kinematics]` chain,
    /// boxes given at home in the machine frame, carried by the table axes up to their `link`.
    pub cradle: Vec<CradleBox>,
    /// Head parts (a ram, a fork, a motor housing): boxes given at home in the machine frame,
    /// carried by the head axes up to their `link` (on the named layouts X, Y or Z).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub head: Vec<CradleBox>,
    /// The spindle nose/head above the gauge line, moving with X Y Z.
    pub spindle: SpindleConfig,
    /// A clearance below this (mm) is a near miss.
    pub near_miss_mm: f64,
    /// Resolution of the reported cutter engagement depth, mm: the monitor re-measures the
    /// cutter/workpiece pair once the bodies could have moved this far.
    pub engagement_resolution_mm: f64,
    /// Tolerance of a collision's reported deepest penetration `W`, mm, with
    /// `depth_tolerance_relative`: `W` is the depth at one of the event's samples, and no
    /// sample of the event is deeper than `W + depth_tolerance_mm + depth_tolerance_relative
    /// · W` (both 0: every sample that could be deeper is measured).
    pub depth_tolerance_mm: f64,
    /// The share of the depth itself in a collision's depth tolerance (0.01: 1 %).
    pub depth_tolerance_relative: f64,
}

/// The tolerance of a collision's reported deepest penetration `W`: no sample of the event
/// is deeper than `W + mm + relative · W`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DepthTolerance {
    pub mm: f64,
    pub relative: f64,
}

impl DepthTolerance {
    /// Measure every sample that could be deeper.
    pub const EXACT: DepthTolerance = DepthTolerance {
        mm: 0.0,
        relative: 0.0,
    };

    /// How much deeper than `worst_mm` (>= 0) a sample of the event may be, mm.
    #[inline]
    pub fn at(&self, worst_mm: f64) -> f64 {
        self.mm + self.relative * worst_mm.max(0.0)
    }
}

/// `[scene] depth_tolerance_mm` when absent, mm: a hundredth of a millimetre, below what a
/// collision's depth says about the program (how far the parts run into each other).
pub const DEFAULT_DEPTH_TOLERANCE_MM: f64 = 0.01;

/// `[scene] depth_tolerance_relative` when absent: 1 % of the depth, so that a part pushed
/// deeper sample by sample is measured about once per 1 % of growth (a few hundred times
/// from 0.01 mm to 100 mm deep) instead of at every sample (docs/scene.md).
pub const DEFAULT_DEPTH_TOLERANCE_RELATIVE: f64 = 0.01;

impl Default for SceneConfig {
    fn default() -> Self {
        SceneConfig {
            table: TableConfig::default(),
            cradle: vec![
                CradleBox {
                    name: "cradle floor".into(),
                    center_mm: [0.0, 0.0, -150.0],
                    size_mm: [500.0, 400.0, 60.0],
                    link: None,
                },
                CradleBox {
                    name: "cradle wall +X".into(),
                    center_mm: [280.0, 0.0, -60.0],
                    size_mm: [60.0, 400.0, 240.0],
                    link: None,
                },
                CradleBox {
                    name: "cradle wall -X".into(),
                    center_mm: [-280.0, 0.0, -60.0],
                    size_mm: [60.0, 400.0, 240.0],
                    link: None,
                },
            ],
            head: Vec::new(),
            spindle: SpindleConfig::default(),
            near_miss_mm: 2.0,
            engagement_resolution_mm: 1.0,
            depth_tolerance_mm: DEFAULT_DEPTH_TOLERANCE_MM,
            depth_tolerance_relative: DEFAULT_DEPTH_TOLERANCE_RELATIVE,
        }
    }
}

/// `[scene.table]`: a cylinder about the table frame's Z axis (the C axis), or about its X
/// axis (a faceplate on A, as on LinuxCNC's table-dual-rotary sample).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TableConfig {
    /// Height of the top surface in the table frame, mm (along X for a faceplate).
    pub top_z_mm: f64,
    pub radius_mm: f64,
    pub thickness_mm: f64,
    /// The table's axis in the table frame.
    pub axis: TableAxis,
}

/// The axis a table's cylinder turns about, in the table frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TableAxis {
    /// A rotary table about Z (C), its top face up.
    #[default]
    Z,
    /// A faceplate about X (A), its face toward +X.
    X,
}

impl Default for TableConfig {
    fn default() -> Self {
        TableConfig {
            top_z_mm: 0.0,
            radius_mm: 200.0,
            thickness_mm: 60.0,
            axis: TableAxis::Z,
        }
    }
}

/// `[[scene.cradle]]` or `[[scene.head]]`: one box, in the cradle frame (a named layout's
/// cradle) or at home in the machine frame (attached to a chain's `link`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CradleBox {
    pub name: String,
    #[serde(deserialize_with = "exact::array")]
    pub center_mm: [f64; 3],
    /// Full side lengths along X, Y, Z, mm.
    #[serde(deserialize_with = "exact::array")]
    pub size_mm: [f64; 3],
    /// The axis the box is attached after ("B"): it moves with that axis and those between
    /// it and the bed on its side of the chain, not with those beyond.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub link: Option<String>,
}

/// Shape of the spindle nose.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpindleShape {
    Cylinder,
    Box,
}

/// `[scene.spindle]`: the spindle nose/head, from the gauge line up along +Z.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpindleConfig {
    pub shape: SpindleShape,
    /// Diameter of a cylindrical nose, mm.
    pub diameter_mm: f64,
    /// Side lengths along machine X and Y of a box nose, mm.
    #[serde(deserialize_with = "exact::array")]
    pub box_mm: [f64; 2],
    /// Length above the gauge line, mm.
    pub length_mm: f64,
}

impl Default for SpindleConfig {
    fn default() -> Self {
        SpindleConfig {
            shape: SpindleShape::Cylinder,
            diameter_mm: 120.0,
            box_mm: [160.0, 160.0],
            length_mm: 250.0,
        }
    }
}

/// `[tool]`: the tool stack, along the tool axis (+Z) from the tool tip. A scenario may
/// override it with its own `[tool]` table.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ToolConfig {
    pub cutter_diameter_mm: f64,
    /// Cutter (flutes) from the tip, mm.
    pub flute_length_mm: f64,
    pub shank_diameter_mm: f64,
    /// Shank above the flutes (including the part inside the holder), mm.
    pub shank_length_mm: f64,
    pub holder_diameter_mm: f64,
    /// Holder below the spindle nose, mm.
    pub holder_length_mm: f64,
    /// Spindle nose (gauge line) to tool tip, mm.
    pub gauge_length_mm: f64,
}

impl Default for ToolConfig {
    fn default() -> Self {
        ToolConfig {
            cutter_diameter_mm: 20.0,
            flute_length_mm: 40.0,
            shank_diameter_mm: 20.0,
            shank_length_mm: 60.0,
            holder_diameter_mm: 50.0,
            holder_length_mm: 60.0,
            gauge_length_mm: 140.0,
        }
    }
}

impl ToolConfig {
    /// Height of the holder's bottom face above the tool tip, mm.
    pub fn holder_bottom_mm(&self) -> f64 {
        self.gauge_length_mm - self.holder_length_mm
    }
}

/// Geometry a scenario's inline tool (`[reader] tools = [...]`) may give beyond the tool
/// table's length and diameter, mm. Absent keys come from the scenario's `[tool]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ToolShape {
    pub flute_length_mm: Option<f64>,
    pub shank_diameter_mm: Option<f64>,
    pub holder_diameter_mm: Option<f64>,
    pub holder_length_mm: Option<f64>,
}

impl ToolConfig {
    /// The stack of tool `number` of the tool table, whose length offset is `length_mm` (the
    /// table's `Z`) and diameter `diameter_mm` (`D`), this stack (the scenario's `[tool]`)
    /// being the tool of length offset 0. `path` names the file for errors.
    ///
    /// The spindle does not move when the tool changes, and a length offset L says how much
    /// further the tip reaches below the Z point than this tool's tip does (G43 H adds L to
    /// the Z axis, so that the tip lands on the programmed Z). So the new tool's tip sits L
    /// below this one's and its gauge length is `gauge_length_mm + L`. The holder is this
    /// one's unless `shape` gives it. The cutter has diameter D (this one's when D <= 0) and
    /// this one's flute length, cut to the stick-out below the holder; a plain shank of the
    /// cutter's diameter runs from the flutes up to the gauge line.
    pub fn for_table_tool(
        &self,
        path: &Path,
        number: u32,
        length_mm: f64,
        diameter_mm: f64,
        shape: &ToolShape,
    ) -> Result<ToolConfig> {
        let gauge = self.gauge_length_mm + length_mm;
        let holder_length = shape.holder_length_mm.unwrap_or(self.holder_length_mm);
        let stick_out = gauge - holder_length;
        if !(stick_out > 0.0) {
            return Err(Error::invalid(path, format!(
                "tool T{number}: its length offset {length_mm} mm gives a gauge length of {gauge} mm (the [tool]'s {} mm plus the offset), which the {holder_length} mm holder does not fit: tool lengths are offsets from the [tool], whose tip is the Z point; lengthen [tool] gauge_length_mm or give the tool a shorter holder_length_mm",
                self.gauge_length_mm
            )));
        }
        let cutter = if diameter_mm > 0.0 {
            diameter_mm
        } else {
            self.cutter_diameter_mm
        };
        let flutes = shape
            .flute_length_mm
            .unwrap_or(self.flute_length_mm.min(stick_out));
        let stack = ToolConfig {
            cutter_diameter_mm: cutter,
            flute_length_mm: flutes,
            shank_diameter_mm: shape.shank_diameter_mm.unwrap_or(cutter),
            shank_length_mm: gauge - flutes,
            holder_diameter_mm: shape.holder_diameter_mm.unwrap_or(self.holder_diameter_mm),
            holder_length_mm: holder_length,
            gauge_length_mm: gauge,
        };
        stack
            .validate(path, "", &format!("tool T{number}"))
            .map(|_| stack)
    }
}

/// What stands on the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum WorkpieceKind {
    /// The NAS 979 cone frustum, cut by the cutter's flank.
    ConeFrustum,
    /// The double ball bar: pivot ball on a post, bar, tool ball in place of the cutter.
    BallBar,
    /// Nothing.
    None,
}

/// The cone test's geometry as plain numbers (see `docs/model.md`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConeSetup {
    /// Half apex angle alpha, deg.
    pub half_apex_deg: f64,
    /// Inclination beta of the cone axis (about table Y, apex toward table -X), deg.
    pub inclination_deg: f64,
    /// Base-circle centre O in the table frame, mm.
    #[serde(deserialize_with = "exact::array")]
    pub center_mm: [f64; 3],
    /// Ball-bar length L, mm.
    pub ballbar_length_mm: f64,
}

impl Default for ConeSetup {
    fn default() -> Self {
        ConeSetup {
            half_apex_deg: 15.0,
            inclination_deg: 10.0,
            center_mm: [0.0, 0.0, 200.0],
            ballbar_length_mm: 100.0,
        }
    }
}

/// `[workpiece]` of a scenario.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct WorkpieceConfig {
    pub kind: WorkpieceKind,
    /// Frustum top above the base plane, along the cone axis, mm. Default: halfway between
    /// the measured circle's plane and the end of the cutter's flank contact.
    pub top_height_mm: Option<f64>,
    /// A riser from the base circle down to the table top (frustum and ball-bar post base).
    pub riser: bool,
    pub ball_diameter_mm: f64,
    pub bar_diameter_mm: f64,
    pub post_diameter_mm: f64,
    /// The cone test this workpiece serves; filled in by the caller from the scenario.
    #[serde(skip)]
    pub cone: ConeSetup,
}

impl Default for WorkpieceConfig {
    fn default() -> Self {
        WorkpieceConfig {
            kind: WorkpieceKind::ConeFrustum,
            top_height_mm: None,
            riser: true,
            ball_diameter_mm: 12.7,
            bar_diameter_mm: 8.0,
            post_diameter_mm: 10.0,
            cone: ConeSetup::default(),
        }
    }
}

/// Checks `[scene]` and `[tool]` of a machine file (`text` is its contents), pointing at the
/// offending line.
pub fn validate_machine_tables(
    path: &Path,
    text: &str,
    scene: &SceneConfig,
    tool: &ToolConfig,
) -> Result<()> {
    scene.validate(path, text)?;
    tool.validate(path, text, "tool")
}

fn positive(path: &Path, text: &str, section: &str, key: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(value_error(
            path,
            text,
            section,
            key,
            format!("must be a positive length in mm, got {v}"),
        ))
    }
}

fn finite(path: &Path, text: &str, section: &str, key: &str, values: &[f64]) -> Result<()> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(value_error(
            path,
            text,
            section,
            key,
            "must be finite numbers (mm)".into(),
        ))
    }
}

impl SceneConfig {
    /// Range checks; `text` is the contents of `path` (used to point at the line).
    pub fn validate(&self, path: &Path, text: &str) -> Result<()> {
        let t = &self.table;
        finite(path, text, "scene.table", "top_z_mm", &[t.top_z_mm])?;
        positive(path, text, "scene.table", "radius_mm", t.radius_mm)?;
        positive(path, text, "scene.table", "thickness_mm", t.thickness_mm)?;
        for (section, boxes) in [("scene.cradle", &self.cradle), ("scene.head", &self.head)] {
            for b in boxes {
                finite(path, text, section, "center_mm", &b.center_mm)?;
                for v in b.size_mm {
                    positive(path, text, section, "size_mm", v)?;
                }
            }
        }
        let s = &self.spindle;
        positive(path, text, "scene.spindle", "diameter_mm", s.diameter_mm)?;
        positive(path, text, "scene.spindle", "box_mm", s.box_mm[0])?;
        positive(path, text, "scene.spindle", "box_mm", s.box_mm[1])?;
        positive(path, text, "scene.spindle", "length_mm", s.length_mm)?;
        if !(self.near_miss_mm.is_finite() && self.near_miss_mm >= 0.0) {
            return Err(value_error(
                path,
                text,
                "scene",
                "near_miss_mm",
                format!("must be a clearance >= 0 mm, got {}", self.near_miss_mm),
            ));
        }
        for (key, v, what) in [
            (
                "depth_tolerance_mm",
                self.depth_tolerance_mm,
                "a length >= 0 mm",
            ),
            (
                "depth_tolerance_relative",
                self.depth_tolerance_relative,
                "a share >= 0",
            ),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(value_error(
                    path,
                    text,
                    "scene",
                    key,
                    format!("must be {what}, got {v}"),
                ));
            }
        }
        positive(
            path,
            text,
            "scene",
            "engagement_resolution_mm",
            self.engagement_resolution_mm,
        )
    }
}

impl ToolConfig {
    /// Range and consistency checks for the `[section]` table of `path`.
    pub fn validate(&self, path: &Path, text: &str, section: &str) -> Result<()> {
        positive(
            path,
            text,
            section,
            "cutter_diameter_mm",
            self.cutter_diameter_mm,
        )?;
        positive(path, text, section, "flute_length_mm", self.flute_length_mm)?;
        positive(
            path,
            text,
            section,
            "shank_diameter_mm",
            self.shank_diameter_mm,
        )?;
        positive(path, text, section, "shank_length_mm", self.shank_length_mm)?;
        positive(
            path,
            text,
            section,
            "holder_diameter_mm",
            self.holder_diameter_mm,
        )?;
        positive(
            path,
            text,
            section,
            "holder_length_mm",
            self.holder_length_mm,
        )?;
        positive(path, text, section, "gauge_length_mm", self.gauge_length_mm)?;
        if self.holder_bottom_mm() <= 0.0 {
            return Err(value_error(path, text, section, "holder_length_mm", format!(
                "the holder ({} mm) must be shorter than the gauge length ({} mm): shorten the holder or lengthen gauge_length_mm",
                self.holder_length_mm, self.gauge_length_mm
            )));
        }
        if self.flute_length_mm + self.shank_length_mm < self.holder_bottom_mm() {
            return Err(value_error(path, text, section, "shank_length_mm", format!(
                "flutes + shank ({} mm) do not reach the holder, whose bottom is {} mm above the tip: lengthen the shank or the holder",
                self.flute_length_mm + self.shank_length_mm,
                self.holder_bottom_mm()
            )));
        }
        Ok(())
    }
}

impl WorkpieceConfig {
    /// Range checks for the `[section]` table of a scenario file.
    pub fn validate(&self, path: &Path, text: &str, section: &str) -> Result<()> {
        if let Some(h) = self.top_height_mm {
            positive(path, text, section, "top_height_mm", h)?;
        }
        positive(
            path,
            text,
            section,
            "ball_diameter_mm",
            self.ball_diameter_mm,
        )?;
        positive(path, text, section, "bar_diameter_mm", self.bar_diameter_mm)?;
        positive(
            path,
            text,
            section,
            "post_diameter_mm",
            self.post_diameter_mm,
        )
    }
}

impl ConeSetup {
    /// Checks the numbers a caller filled in; `path` names the scenario.
    pub fn check(&self, path: &Path) -> Result<()> {
        let ok = self.half_apex_deg.is_finite()
            && self.half_apex_deg > 0.0
            && self.half_apex_deg < 90.0
            && self.inclination_deg.is_finite()
            && self.inclination_deg.abs() < 90.0
            && self.center_mm.iter().all(|v| v.is_finite())
            && self.ballbar_length_mm.is_finite()
            && self.ballbar_length_mm > 0.0;
        if ok {
            Ok(())
        } else {
            Err(Error::invalid(path, format!(
                "cone setup out of range: half apex angle must be in (0, 90) deg, inclination in (-90, 90) deg, ball-bar length > 0 mm, all finite; got {self:?}"
            )))
        }
    }
}
