//! mtsim: a machine-tool motion simulator with servo dynamics, for the five-axis
//! cone-frustum test (NAS 979, ISO 10791-7) and its ball-bar version (ISO 10791-6).
//!
//! # The pipeline
//!
//! ```text
//! program ─► motion ─► drive ─► measure, check ─► report
//!  moves     setpoints  actual    ball bar,        CSV, JSON,
//!                       axes      limits, scene    SVG
//! ```
//!
//! Data flows one way and streams; [`pipeline::run`] connects the stages and hands every
//! [`pipeline::Sample`] to a set of [`pipeline::Sink`]s. Beside it, [`input`] reads the plain
//! configuration of every stage, [`study`] runs whole studies (reversal analysis, simulate,
//! sweeps, placement maps) and [`cli`] is the command line. `docs/architecture.md` says
//! where each concept lives.
//!
//! | module | role | main items |
//! |---|---|---|
//! | [`input`] | machine and scenario files | [`input::Machine`], [`input::Scenario`], [`input::ConeTest`] |
//! | [`program`] | NC program → canonical moves | [`program::Move`], [`program::scenario_run`], [`program::cone::ConeProgram`] |
//! | [`motion`] | moves → setpoints | [`motion::Interpolator`], [`motion::NominalSampler`] |
//! | [`drive`] | setpoints → actual positions | [`drive::AxisServo`], [`drive::Drives`] |
//! | [`pipeline`] | the stages connected | [`pipeline::run`], [`pipeline::Sink`] |
//! | [`measure`] | the virtual ball bar | [`measure::BallbarSink`], [`measure::ballbar::analyse`] |
//! | [`check`] | limits and collisions | [`check::check`], [`check::limits::LimitsMonitor`], [`check::scene::Scene`] |
//! | [`report`] | files | [`report::trace::TraceSink`], [`report::polar`], [`report::write_atomic`] |
//! | [`study`] | runs and studies | [`study::reversals`], [`study::simulate::simulate`], [`study::sweep`], [`study::placement`], [`study::fit`] |
//! | [`cli`] | the `mtsim` command | [`cli::main`] |
//! | [`kinematics`] | forward and inverse kinematics, geometric errors | [`kinematics::Kinematics`], [`kinematics::LocationErrors`] |
//! | [`numeric`] | numeric helpers every stage shares | [`numeric::sin_cos_deg`], [`numeric::push_fixed`] |
//!
//! The G-code reader is the `ngc` crate of this workspace; its axis types are re-exported
//! here. Positions are mm and deg at every interface, SI inside the servo models.

pub mod check;
pub mod cli;
pub mod drive;
pub mod error;
pub mod input;
pub mod kinematics;
pub mod measure;
pub mod motion;
pub mod numeric;
pub mod pipeline;
pub mod program;
pub mod report;
pub mod study;

pub use error::{Error, Result};
pub use ngc::{Axis, AxisVec, Plane};
