//! The front ends behind `FrontEnd`: HEIDENHAIN Klartext, Siemens Sinumerik, the Fanuc and
//! Haas dialects as CAM posts write them, moves lent in place by every front end, and the
//! one budget of executed blocks every front end counts.

#[path = "../common/mod.rs"]
mod common;

mod budget;
mod fanuc_haas;
mod heidenhain;
mod heidenhain_transforms;
mod klartext_constructs;
mod klartext_posts;
mod klartext_setup;
mod lent_moves;
mod milling_cycles;
mod posts;
mod siemens;
mod siemens_contour;
mod siemens_cycles;
mod siemens_machine_words;
mod siemens_orientation;
mod siemens_posts;
mod slot_stud_cycles;
mod surface_normal;
mod thread_cycles;
