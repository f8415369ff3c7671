//! **check** — sinks: axis positions in, limit violations and collisions out.
//! Inputs: [`crate::pipeline::Sample`]s (commanded at programmed timing, or actual with `--dynamics`), the machine, tool and workpiece.
//! Outputs: a [`CheckReport`]: travel, velocity and acceleration per axis, collisions and near misses in the rapier/parry scene.

pub mod limits;
pub mod of_run;
pub mod run;
pub mod scene;
pub mod units;

pub use run::{
    check, check_observed, check_reference, check_with, CheckOptions, CheckReport, CheckTiming,
    SceneQueries,
};
