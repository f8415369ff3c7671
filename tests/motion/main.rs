//! The motion stage (`src/motion/`): the interpolator's setpoints against closed-form profiles,
//! the feed held to the machine's limits, and the path-control modes.

#[path = "../common/mod.rs"]
mod common;

mod blend_sizing;
mod feed_held;
mod interpolation;
mod linuxcnc_planner;
mod overlap;
