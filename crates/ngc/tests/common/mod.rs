//! What several of the reader's test files share: the cutter-compensation set-up.

use ngc::{Dialect, Options, Tool};

/// A G42 path of lines and arcs with a plunge, read with tool 1 (10 mm diameter).
pub const G42_ARCS: &str = "G21 G17 G90 G40\nT1 M6\nG0 X-30 Y0 Z5\nG42 D1 G1 X-20 Y0 F100\nG1 Z-2\nG2 X0 Y20 I20 J0\nG1 X30 Y20\nG2 X40 Y10 I0 J-10\nG1 X40 Y-10\nG1 X-20 Y-10\nG40 G0 X-40 Y-20\nM2\n";

/// The LinuxCNC dialect with tool 1 in the table: 10 mm diameter, no length.
pub fn compensated_options() -> Options {
    Options {
        dialect: Dialect::Linuxcnc,
        tools: vec![Tool {
            number: 1,
            length_mm: 0.0,
            diameter_mm: 10.0,
        }],
        ..Options::default()
    }
}
