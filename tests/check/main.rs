//! The check stage (`src/check/`): `mtsim check` against answers known in advance, the
//! bounded collision check against brute force, the collision scene, checks as the moves stream
//! in, and the tool the program puts in the spindle.

#[path = "../common/mod.rs"]
mod common;

mod chain_scene;
mod command;
mod equivalence;
mod of_run;
mod prism;
mod scene;
mod streamed;
mod tilted;
mod tool_change;
mod views;
