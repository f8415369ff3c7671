//! **measure** — a sink: actual axis positions in, what a virtual ball bar reads out.
//! Inputs: [`crate::pipeline::Sample`]s, the measured circle's frame, the bar's pivot and length, each axis's reversal angles.
//! Outputs: the deviation trace in θ bins, ISO 230-4 figures (G, F, H), and spikes and steps attributed to axes.

pub mod attribution;
pub mod ballbar;
pub mod bar;
pub mod contour;
pub mod cut;
pub mod feed;
pub mod measurement;
pub mod settle;
pub mod shared;
pub mod sink;
pub mod theta;

pub use crate::input::program::Direction;
pub use ballbar::{BallbarResult, BallbarRun, CircleFrame};
pub use measurement::Measurement;
pub use sink::{is_measured, BallbarSink, BarGeometry, BarReading, CommandMaps, CommandedReading};
