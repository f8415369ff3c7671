//! Collision scene of table, workpiece, tool, holder and spindle (placeholder: configuration types only).

use serde::Deserialize;

/// `[scene]`: machine geometry for collision checks.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SceneConfig {}

/// `[tool]`: the tool in the spindle.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ToolConfig {}
