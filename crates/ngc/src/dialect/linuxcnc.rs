//! LinuxCNC 2.9 (RS274/NGC as its G-code manual describes it; `rs274` is the reference the
//! conformance test runs): o-words, `#<named>` parameters, lathe diameter mode, probing,
//! splines, polar words, rotated work systems.

use crate::code::{GCode, MotionMode};
use crate::dialect::table::{
    common_g_code, common_no_motion_g, no_machine_m, ArcRadiusRule, DwellUnit, Table,
};

pub(super) const TABLE: Table = Table {
    // rs274's initial retract mode is the R plane.
    start_retract_r: true,
    g_code,
    refusal,
    feed_before_units: true,
    dwell_p: DwellUnit::Seconds,
    dwell_x_seconds: false,
    dwell_beside_motion: true,
    g49_cancels_tcp: false,
    arc_turns: true,
    arc_radius: ArcRadiusRule::Linuxcnc,
    zero_off_plane_offset: false,
    arc_r_over_offsets: false,
    m98_repeats_in_p: false,
    polar_words: true,
    rotated_work_systems: true,
    machine_m: no_machine_m,
    no_motion_g: common_no_motion_g,
    local_subprogram_m97: false,
    m16_tool_change: false,
    offset_words_alone: false,
    g80_keeps_motion: false,
    g92_s_limits_spindle: false,
    g53_absolute_in_g91: false,
    leader_before_percent: false,
    g87_back_bore: false,
    modal_state_m70_m73: true,
    peck_settings: None,
    reference_all_without_axes: true,
    whole_numbers_are_increments: false,
    macro_b: false,
};

fn g_code(code: u32) -> Option<GCode> {
    use MotionMode::*;
    Some(match code {
        411 => GCode::CutterComp(3),
        421 => GCode::CutterComp(4),
        431 => GCode::ToolLength(1),
        432 => GCode::ToolLength(2),
        591..=593 => GCode::Coord(code - 591 + 7),
        382..=385 => GCode::Motion(Some(Probe(code))),
        50..=52 => GCode::Motion(Some(Spline(code))),
        53 => GCode::NurbsEnd,
        70 | 80 => GCode::Diameter(code == 70),
        330 | 331 => GCode::Motion(Some(SpindleSync(code))),
        _ => return common_g_code(code),
    })
}

fn refusal(code: u32) -> Option<(&'static str, &'static str)> {
    Some(match code {
        434 | 435 => (" (LinuxCNC has no G43.4; TCP is switched by the scenario option or a user M code such as M428)", "map the TCP M codes in the scenario (user_m_codes)"),
        2340 => (" (G234 is Haas TCP)", "set dialect = \"haas\""),
        682 | 690 | 531 => (" (G68.2, G53.1 and G69 are Fanuc and Haas codes)", "set dialect = \"fanuc\" or \"haas\""),
        2540 | 2550 => (" (G254/G255 are Haas dynamic work offsets)", "set dialect = \"haas\""),
        _ => return None,
    })
}
