//! Units and tolerances shared by the reader and the interpreter: leaf constants, so the
//! modules that read a block and those that interpret it both depend on this one.

/// Millimetres per inch (exact by definition).
pub const MM_PER_INCH: f64 = 25.4;

/// An R arc's |R| may be shorter than half its chord by at most this much, mm (the centre is
/// then the chord's midpoint).
pub const ARC_RADIUS_TOLERANCE_MM: f64 = 1e-3;

/// Fanuc and Haas: radii at the start and end of an I J K arc may differ by at most this
/// much, mm (LinuxCNC's rule is in docs/gcode.md). Fanuc sets the limit per machine
/// (parameter 3410, alarm PS0020); no documented default was found, so this is chosen to
/// accept what real controls are shown to accept: a Haas UMC-750 runs NX post output with
/// differences up to 4.9 µm (issue 9), and inch output rounded to 0.0001 in moves a radius
/// by up to about 3.6 µm. 10 µm accepts both and is half of Okuma's documented 20 µm.
pub const FANUC_ARC_RADIUS_TOLERANCE_MM: f64 = 0.01;

/// An arc in an oblique plane (G02/G03 under G68.2 or G254 with the table tilted off a
/// machine plane) runs as chords whose sagitta `r (1 − cos(Δφ/2))` is at most this, mm.
pub const OBLIQUE_ARC_CHORD_TOLERANCE_MM: f64 = 1e-3;
