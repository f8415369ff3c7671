//! The tests a scenario can run, each behind one trait: [`TestProgram`].
//!
//! A test is what a scenario's `[program]` names: the generated cone frustum (`cone.rs`), the
//! ISO 230-4 circle (`circle.rs`) or a G-code file (`file.rs`). Each answers the questions the
//! rest of the house asks of a program, so that no stage matches on which test it is:
//!
//! ```text
//! run          the canonical moves of one direction (with its lead-in and measured lines)
//! directions   the directions `simulate` runs
//! revolution   the measured revolution in closed form (radius r, feed F): the sample budget
//!              n ≈ 2π r (1 + lead/180°) / (F/60) / Δt before a run starts
//! bar          the ball bar it is measured with: the circle's frame (θ), table ball, length
//! description  what the report's test parameters say of it, and its plot title
//! ```
//!
//! plus what only some tests have (a generated cone, an ISO 230-4 circle, a program file),
//! asked as options. A new test is one file here implementing the trait, its `[program.*]`
//! table in `input/scenario.rs` (where every scenario key is read), and one line in [`of`].

pub mod circle;
pub mod cone;
pub mod file;
pub mod frame;
pub mod interface;

use crate::input::program::ConeTest;
use crate::input::scenario::{Program, Scenario};

pub use frame::CircleFrame;
pub use interface::{BarSetup, Run, TestDescription, TestProgram};

/// The registry: the test a scenario's program is. One line per test.
pub fn of(program: &Program) -> Box<dyn TestProgram + '_> {
    match program {
        Program::Cone {
            cone,
            nc,
            directions,
        } => Box::new(cone::Cone {
            cone,
            nc,
            directions,
        }),
        Program::Circle { circle, directions } => Box::new(circle::Circle { circle, directions }),
        Program::File { path, cone } => Box::new(file::File {
            path,
            cone: cone.as_ref(),
        }),
    }
}

/// The test `scenario` runs.
pub fn test_of(scenario: &Scenario) -> Box<dyn TestProgram + '_> {
    of(&scenario.program)
}

/// The geometry of a generated cone, to change it (a placement map's cells, `fit`'s suggested
/// tests); `None` for any other test.
pub fn generated_cone_mut(program: &mut Program) -> Option<&mut ConeTest> {
    match program {
        Program::Cone { cone, .. } => Some(cone),
        Program::Circle { .. } | Program::File { .. } => None,
    }
}
