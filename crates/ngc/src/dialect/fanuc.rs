//! Fanuc (Series 0i/30i, custom macro B): O program numbers, M98/M99 subprograms, G65
//! macro calls, `IF`/`WHILE`, G43.4/G43.5 TCP, G68.2/G53.1 tilted work planes; dwell P in
//! ms or X in s.

use crate::code::GCode;
use crate::dialect::table::{common_g_code, ArcRadiusRule, DwellUnit, Table};
use crate::units::FANUC_ARC_RADIUS_TOLERANCE_MM;

pub(super) const TABLE: Table = Table {
    start_retract_r: false,
    g_code,
    refusal,
    feed_before_units: false,
    dwell_p: DwellUnit::Milliseconds,
    dwell_x_seconds: true,
    dwell_beside_motion: false,
    g49_cancels_tcp: true,
    arc_turns: false,
    arc_radius: ArcRadiusRule::Absolute(FANUC_ARC_RADIUS_TOLERANCE_MM),
    zero_off_plane_offset: true,
    polar_words: false,
    rotated_work_systems: false,
    macro_b: true,
};

/// The codes of the Fanuc family (Haas reads them too, see `haas.rs`).
pub(super) fn g_code(code: u32) -> Option<GCode> {
    Some(match code {
        434 | 435 => GCode::Tcp(true),
        440 => GCode::ToolLength(4),
        51 | 80 => GCode::Control(code),
        682 => GCode::Tilt(true),
        690 => GCode::Tilt(false),
        531 => GCode::AlignRotary,
        _ => return common_g_code(code),
    })
}

/// The refusals of the Fanuc family.
pub(super) fn refusal(code: u32) -> Option<(&'static str, &'static str)> {
    Some(match code {
        2340 => (" (G234 is Haas TCP)", "set dialect = \"haas\""),
        2540 | 2550 => (
            " (G254/G255 are Haas dynamic work offsets)",
            "set dialect = \"haas\"",
        ),
        330 | 331 | 70 => (
            " (G7, G33 and G33.1 are read in the LinuxCNC dialect)",
            "set dialect = \"linuxcnc\"",
        ),
        _ => return None,
    })
}
