//! The measure stage (`src/measure/`): the virtual ball bar against independently computed
//! values, and the attribution of its trace's marks to axes.

#[path = "../common/mod.rs"]
mod common;

mod attribution;
mod ballbar;
mod contour;
mod cut;
mod cut_envelope;
mod measurement;
mod shared;
