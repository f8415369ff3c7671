//! Haas (NGC control): the Fanuc family's codes and macros, plus G234 TCP, G254/G255
//! dynamic work offsets, G154 P extended offsets, G103/G187; dwell P in s with a decimal
//! point, ms without.

use crate::code::GCode;
use crate::dialect::fanuc;
use crate::dialect::table::{DwellUnit, Table};

pub(super) const TABLE: Table = Table {
    dwell_p: DwellUnit::MillisecondsUnlessDecimal,
    g_code,
    ..fanuc::TABLE
};

fn g_code(code: u32) -> Option<GCode> {
    Some(match code {
        2340 => GCode::Tcp(true),
        1540 => GCode::CoordExtended,
        1030 | 1870 => GCode::Control(code),
        2540 => GCode::Dwo(true),
        2550 => GCode::Dwo(false),
        _ => return fanuc::g_code(code),
    })
}
