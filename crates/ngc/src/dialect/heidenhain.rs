//! HEIDENHAIN Klartext: the interpreter's table for the words its front end (crate module
//! `heidenhain`) emits: the Fanuc family's codes with G41.1/G42.1 (compensation by
//! diameter: the tool radius plus `DR`), dwell in s.

use crate::code::GCode;
use crate::dialect::fanuc;
use crate::dialect::table::{DwellUnit, Table};

pub(crate) const TABLE: Table = Table {
    g_code,
    dwell_p: DwellUnit::Seconds,
    ..fanuc::TABLE
};

fn g_code(code: u32) -> Option<GCode> {
    match code {
        411 => Some(GCode::CutterComp(3)),
        421 => Some(GCode::CutterComp(4)),
        _ => fanuc::g_code(code),
    }
}
