//! Per-axis servo drive models (placeholder: configuration types only).

use std::path::Path;

use serde::Deserialize;

use crate::axis::Axis;
use crate::error::Result;

/// `[axes.X.servo]`: position and velocity loops.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ServoConfig {
    /// "first-order" or "cascade".
    pub model: String,
    /// Position-loop gain Kv, 1/s.
    pub kv_per_s: f64,
    /// Velocity feedforward, fraction 0..1.
    pub velocity_feedforward: f64,
    /// Acceleration feedforward, fraction 0..1.
    pub acceleration_feedforward: f64,
}

impl Default for ServoConfig {
    fn default() -> Self {
        ServoConfig {
            model: "first-order".into(),
            kv_per_s: 30.0,
            velocity_feedforward: 0.0,
            acceleration_feedforward: 0.0,
        }
    }
}

/// `[axes.X.drive]`: mechanics between motor and table.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DriveConfig {
    /// Backlash of a linear axis, mm.
    pub backlash_mm: f64,
    /// Backlash of a rotary axis, deg.
    pub backlash_deg: f64,
}

/// `[axes.X.friction]`: friction on the table side.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrictionConfig {
    /// Coulomb friction of a linear axis, N.
    pub coulomb_n: f64,
    /// Coulomb friction of a rotary axis, N m.
    pub coulomb_nm: f64,
}

/// Checks the drive parameters of one axis; errors name the key in `[section.servo]` etc.
pub fn validate(
    _path: &Path,
    _text: &str,
    _section: &str,
    _axis: Axis,
    _servo: &ServoConfig,
    _drive: &DriveConfig,
    _friction: &FrictionConfig,
) -> Result<()> {
    Ok(())
}
