//! **input** — the plain configuration of every stage, read from TOML and validated.
//! Inputs: machine files, scenario files (paths relative to the scenario), `[machine_overrides]`.
//! Outputs: plain values — [`Machine`], [`Scenario`], drive, scene, tool and test parameters; imports no stage.

pub mod budget;
pub mod component_errors;
pub mod drive;
pub mod exact;
pub mod geometry_errors;
pub mod lead_in;
pub mod machine;
pub mod overrides;
pub mod program;
pub mod reader;
pub mod scenario;
pub mod scene;
pub mod toml_text;

pub use machine::{AxisConfig, Machine, MachineAxis};
pub use program::{CircleTest, ConeTest, Direction, MeasuredLines, NcOptions};
pub use scenario::{Program, Scenario};
