//! mtsim: a machine-tool motion simulator with servo dynamics.
//!
//! The data flow is one-way: program source (G-code file or generator) → blocks →
//! interpolator → per-axis servo → actual axis positions → forward kinematics → ball bar,
//! limits monitor, collision scene → reports.

pub mod analysis;
pub mod axis;
pub mod ballbar;
pub mod check;
pub mod circle;
pub mod cli;
pub mod cone;
pub mod error;
pub mod gcode;
pub mod interpolation;
pub mod kinematics;
pub mod limits;
pub mod machine;
pub mod placement;
pub mod plot;
pub mod report;
pub mod sampling;
pub mod scenario;
pub mod scene;
pub mod servo;
pub mod simulation;
pub mod sweep;
pub mod toml_input;

pub use axis::{Axis, AxisVec};
pub use error::{Error, Result};
