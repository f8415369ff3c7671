//! The modal interpreter's phases: parameters and flow, offsets, tools and cycles, lathe
//! codes, the secondary axes U V W, tilted work planes, and LinuxCNC remaps with their
//! stdglue handlers.

mod bolt_patterns;
mod control_parameters;
mod corner_arcs;
mod corner_polar;
mod interpreter;
mod lathe;
mod lathe_cycles;
mod lathe_feed;
mod mirror_scale;
mod remap_glue;
mod secondary_axes;
mod tilted;
mod traps;
mod traps_iso;
