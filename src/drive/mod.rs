//! **drive** — stage 3: setpoints in, actual axis positions out.
//! Inputs: one setpoint per interpolation period for every axis, and each axis's drive configuration from `input`.
//! Outputs: the table-side (actual) position and following error of every axis, from per-axis servo models.

pub mod drives;
mod exp;
pub mod lane_drive;
pub mod lane_servo;
pub mod lane_step;
mod lane_substep;
pub mod lanes;
mod period_map;
pub mod presliding;
mod product;
pub mod servo;
mod simd;

pub use drives::{Drives, DrivesState};
pub use lanes::DriveLanes;
pub use presliding::{Presliding, ReversalValue};
pub use servo::{AxisServo, ServoState};
