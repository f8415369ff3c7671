//! Kinematics (`src/kinematics/`): forward and inverse transforms of every layout, the sample
//! machine files converted from LinuxCNC's, and the geometric errors of the rotary axes.

#[path = "../common/mod.rs"]
mod common;

mod chain_cone;
mod chain_location;
mod chain_planes;
mod chain_poles;
mod chains;
mod fast_path;
mod geometric_errors;
mod linear_errors;
mod linuxcnc_formulas;
mod linuxcnc_samples;
mod pole_passage;
mod reading;
mod round_trips;
mod trivial;
mod trt_ab;
mod uvw;
mod written_out;
