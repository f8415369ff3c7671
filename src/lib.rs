//! mtsim: a machine-tool motion simulator with servo dynamics.
//!
//! The data flow is one-way: program source (G-code file or generator) → blocks →
//! interpolator → per-axis servo → actual axis positions → forward kinematics → ball bar,
//! limits monitor, collision scene → reports.

pub mod axis;
pub mod error;
pub mod gcode;
pub mod interpolation;
pub mod kinematics;
pub mod machine;
pub mod scene;
pub mod servo;
pub mod toml_input;

pub use axis::{Axis, AxisVec};
pub use error::{Error, Result};
