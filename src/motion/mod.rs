//! **motion** — stage 2: canonical moves in, setpoints out.
//! Inputs: a stream of [`crate::program::Move`]s and the machine's axis limits.
//! Outputs: commanded axis positions every interpolation period — planned (jerk-limited look-ahead) or at programmed timing.

pub mod blend;
pub mod feed_held;
pub mod interpolation;
mod profile;
pub mod sampling;
pub mod work;

pub use feed_held::{FeedReduction, FeedReductions};
pub use interpolation::{overlap, InterpolationOptions, Interpolator, Setpoint};
pub use sampling::NominalSampler;
