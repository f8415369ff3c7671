//! **numeric** — layer 0: the small numeric helpers every stage may use; it imports no stage.
//! Inputs: f64 values (angles in deg, lengths, exponents).
//! Outputs: f64 results bit for bit the same on every CPU, and fixed-decimal text.

pub mod fixed;
mod pair;
pub mod trig;

pub use fixed::{push_fixed, push_fixed_bytes, push_fixed_bytes_const};
pub use pair::{F64x2, LaneOps};
pub use trig::{sin_cos_deg, sin_cos_deg_pair, wrap_360};
