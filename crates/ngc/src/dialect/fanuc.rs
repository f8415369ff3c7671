//! Fanuc (Series 0i/30i, custom macro B): O program numbers, M98/M99 subprograms, G65
//! macro calls, `IF`/`WHILE`, G43.4/G43.5 TCP, G68.2/G53.1 tilted work planes; dwell P in
//! ms or X in s.

use crate::code::{GCode, MotionMode};
use crate::dialect::table::{common_g_code, common_no_motion_g, ArcRadiusRule, DwellUnit, Table};
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
    arc_r_over_offsets: true,
    m98_repeats_in_p: true,
    polar_words: false,
    rotated_work_systems: false,
    machine_m,
    no_motion_g,
    local_subprogram_m97: false,
    m16_tool_change: false,
    offset_words_alone: true,
    g80_keeps_motion: true,
    g92_s_limits_spindle: true,
    g53_absolute_in_g91: false,
    leader_before_percent: true,
    g87_back_bore: true,
    modal_state_m70_m73: false,
    peck_settings: Some(("parameter 5114", "parameter 5115")),
    reference_all_without_axes: false,
    whole_numbers_are_increments: true,
    macro_b: true,
};

/// The codes of the Fanuc family (Haas reads them too, see `haas.rs`).
pub(super) fn g_code(code: u32) -> Option<GCode> {
    Some(match code {
        434 | 435 => GCode::Tcp(true),
        440 => GCode::ToolLength(4),
        50 | 51 | 80 | 500 => GCode::Control(code),
        740 | 760 | 840 | 870 | 880 => GCode::Motion(Some(MotionMode::Cycle(code))),
        680 => GCode::Rotate2d,
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

/// The Fanuc family's G codes that change how the control runs the path, not the path
/// (docs/gcode.md gives each one's manual section).
pub(super) fn no_motion_g(code: u32) -> Option<&'static str> {
    Some(match code {
        50 => "G05 high-speed machining mode (look-ahead, smoothing)",
        51 => "G05.1 AI contour control (look-ahead, smoothing)",
        80 => "G08 look-ahead control",
        500 => "G50 scaling cancel (with S on a lathe: the spindle speed limit)",
        _ => return common_no_motion_g(code),
    })
}

/// The Fanuc 0i/30i machine M codes of a typical builder's mill (the M codes other than
/// M00-M09, M30, M98, M99 are the machine tool builder's).
pub(super) fn machine_m(code: u32) -> Option<&'static str> {
    Some(match code {
        10 => "M10 rotary axis clamp (brake on)",
        11 => "M11 rotary axis unclamp (brake off)",
        _ => return None,
    })
}
