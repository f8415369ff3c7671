//! The shape of a dialect's table, and the codes all dialects share: the leaf the three
//! dialect files build their tables from.

use crate::axis::Plane;
use crate::code::{FeedRead, GCode, MotionMode, NonModal};

/// What one control does, as the interpreter needs it.
#[derive(Debug)]
pub(crate) struct Table {
    // Start-up modal state.
    /// G99 (retract to R) at start-up; otherwise G98 (the initial level).
    pub start_retract_r: bool,

    // Code table.
    /// The control's own G codes (code ×10); the codes all three share are in
    /// [`common_g_code`].
    pub g_code: fn(u32) -> Option<GCode>,
    /// The control's refusals of codes it does not have: why, and what to do.
    pub refusal: fn(u32) -> Option<(&'static str, &'static str)>,
    /// F is set before G20/G21 take effect (LinuxCNC's order of execution); otherwise F is
    /// read in the units the block selects.
    pub feed_before_units: bool,
    /// G4's P: its unit.
    pub dwell_p: DwellUnit,
    /// G4 X is a dwell time in seconds (Fanuc), not an axis word.
    pub dwell_x_seconds: bool,
    /// G4 may share a block with G0-G3 (LinuxCNC: group 0); otherwise it is in the motion
    /// group.
    pub dwell_beside_motion: bool,
    /// G49 also cancels TCP (G43.4/G43.5/G234).
    pub g49_cancels_tcp: bool,
    /// G2/G3 P: the number of turns.
    pub arc_turns: bool,
    /// How far the radii at the start and the end of an I J K arc may differ.
    pub arc_radius: ArcRadiusRule,
    /// An arc with both R and I J K takes R and ignores I J K (Fanuc 0i, Haas); otherwise
    /// an error (LinuxCNC).
    pub arc_r_over_offsets: bool,
    /// An off-plane centre offset of zero (`K0` in G17) is accepted.
    pub zero_off_plane_offset: bool,
    /// Polar coordinates `@` `^` (LinuxCNC).
    pub polar_words: bool,
    /// Rotated work systems (G10 L2 R).
    pub rotated_work_systems: bool,
    /// The control's machine M codes that do not move the axes (brakes, chip conveyor,
    /// coolant options): their meaning. Accepted with a notice.
    pub machine_m: fn(u32) -> Option<&'static str>,
    /// G codes accepted with no effect on the canonical moves (look-ahead, smoothing,
    /// spindle modes), code ×10: their meaning, for the notice.
    pub no_motion_g: fn(u32) -> Option<&'static str>,
    /// `M97 P<n>` calls sequence number N<n> of the same program (Haas local subprogram).
    pub local_subprogram_m97: bool,
    /// M16 changes the tool as M06 does (Haas mills' alternative tool-change code).
    pub m16_tool_change: bool,
    /// `M98 P` of more than 4 digits holds the repeat count before the 4-digit program
    /// number (Fanuc); otherwise P is the program number alone (Haas: 5-digit numbers, L
    /// repeats).
    pub m98_repeats_in_p: bool,
    /// D and H words stand on their own (Fanuc family): D selects the cutter offset a later
    /// G41/G42 uses, H the length offset (applied at once while G43/G44 is in effect).
    pub offset_words_alone: bool,
    /// G80 cancels only the canned cycle: the G00-G03 mode before it is in effect again
    /// (Fanuc family: groups 01 and 09 apart); otherwise no motion mode is left (LinuxCNC).
    pub g80_keeps_motion: bool,
    /// G92 S with no axis word is the spindle speed limit (Fanuc M series, constant surface
    /// speed), not a coordinate shift.
    pub g92_s_limits_spindle: bool,
    /// G53 in G91 moves to the machine coordinates given, as in G90 (Haas: its posts
    /// write `G91 G28 X0 Y0` then `G53 G00 Z0`); otherwise it is an error (LinuxCNC, and
    /// Fanuc, whose manuals give G53 as an absolute command only).
    pub g53_absolute_in_g91: bool,
    /// Text before a program's first `%` line is the tape leader, skipped (Fanuc family).
    pub leader_before_percent: bool,
    /// G87 is back boring (Fanuc); otherwise, where the dialect has G87, boring with a
    /// manual retract (Haas, whose back boring is G77).
    pub g87_back_bore: bool,
    /// M70-M73 save and restore the modal state (LinuxCNC); otherwise they are the
    /// builder's machine codes (Haas M73/M74: tool air blast on/off).
    pub modal_state_m70_m73: bool,
    /// The control's settings for the G73 chip-breaking retract and the G83 re-approach
    /// clearance, named in the notice when the machine file gives neither (Fanuc parameters
    /// 5114 and 5115); `None`: fixed by the control (LinuxCNC: 0.010 in, its G-code manual).
    pub peck_settings: Option<(&'static str, &'static str)>,
    /// G28/G30 without axis words send every axis to the reference position (LinuxCNC,
    /// Haas); otherwise they move no axis (Fanuc: only the axes named return).
    pub reference_all_without_axes: bool,
    /// A dimension word without a decimal point is in the least input increment (Fanuc
    /// parameter 3401#0 = 0, Haas Setting 162 off: their defaults); otherwise whole units.
    pub whole_numbers_are_increments: bool,

    // Parameter and subprogram syntax.
    /// Fanuc macro B: `#1`-`#33` locals per call, `IF [..] GOTO`, `WHILE [..] DO`, `O`
    /// program numbers, M98/M99 subprograms, G65 macro calls; otherwise LinuxCNC's o-words
    /// (`o<name> sub`, `call`, `if`, `while`) and `#<named>` parameters.
    pub macro_b: bool,
}

/// The unit of a dwell's P word.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DwellUnit {
    Seconds,
    Milliseconds,
    /// Seconds when P has a decimal point, milliseconds without (Haas).
    MillisecondsUnlessDecimal,
}

/// How far an I J K arc's radius at its end may differ from that at its start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum ArcRadiusRule {
    /// LinuxCNC 2.9, measured with rs274 (docs/gcode.md): an error only when the difference
    /// exceeds both 0.02·√2 mm (0.002·√2 in under G20) and 0.1 % of the start radius.
    Linuxcnc,
    /// A fixed tolerance, mm.
    Absolute(f64),
}

/// The G codes (code ×10) every dialect reads the same way: RS274/NGC's core.
pub(crate) fn common_g_code(code: u32) -> Option<GCode> {
    use MotionMode::*;
    Some(match code {
        0 => GCode::Motion(Some(Rapid)),
        10 => GCode::Motion(Some(Linear)),
        20 => GCode::Motion(Some(Arc { clockwise: true })),
        30 => GCode::Motion(Some(Arc { clockwise: false })),
        40 => GCode::NonModal(NonModal::Dwell),
        100 => GCode::NonModal(NonModal::G10),
        170 => GCode::Plane(Plane::XY),
        180 => GCode::Plane(Plane::ZX),
        190 => GCode::Plane(Plane::YZ),
        200 => GCode::Units(true),
        210 => GCode::Units(false),
        280 => GCode::NonModal(NonModal::G28),
        281 => GCode::NonModal(NonModal::G28_1),
        300 => GCode::NonModal(NonModal::G30),
        301 => GCode::NonModal(NonModal::G30_1),
        400 => GCode::CutterComp(0),
        410 => GCode::CutterComp(1),
        420 => GCode::CutterComp(2),
        430 => GCode::ToolLength(0),
        490 => GCode::ToolLength(9),
        520 => GCode::NonModal(NonModal::G52),
        530 => GCode::NonModal(NonModal::G53),
        540..=590 if code % 10 == 0 => GCode::Coord((code - 530) / 10),
        541 => GCode::CoordExtended,
        610 => GCode::Path(0),
        611 => GCode::Path(1),
        640 => GCode::Path(4),
        730 => GCode::Motion(Some(Cycle(730))),
        800 => GCode::Motion(None),
        810 | 820 | 830 | 850 | 860 | 890 => GCode::Motion(Some(Cycle(code))),
        900 => GCode::Distance(true),
        910 => GCode::Distance(false),
        901 => GCode::ArcDistance(true),
        911 => GCode::ArcDistance(false),
        920 => GCode::NonModal(NonModal::G92),
        921 => GCode::NonModal(NonModal::G92_1),
        922 => GCode::NonModal(NonModal::G92_2),
        923 => GCode::NonModal(NonModal::G92_3),
        930 => GCode::Feed(FeedRead::InverseTime),
        940 => GCode::Feed(FeedRead::PerMinute),
        950 => GCode::Feed(FeedRead::PerRevolution),
        960 | 970 => GCode::Control(code),
        980 => GCode::Retract(false),
        990 => GCode::Retract(true),
        _ => return None,
    })
}

/// Refusals every dialect shares, after its own: why, and what to do.
pub(crate) fn common_refusal(code: u32) -> Option<(&'static str, &'static str)> {
    Some(match code {
        680 => (
            " (2D coordinate rotation G68 is a Fanuc and Haas code; LinuxCNC turns a work system with G10 L2 R)",
            "set dialect = \"fanuc\" or \"haas\", or rotate with G10 L2 R",
        ),
        681..=689 => (
            " (G68.x other than G68.2 are not supported: G68.1 is a lathe's rotation, G68.3 and G68.4 tilt the plane by the tool axis)",
            "post-process the program with G68.2 or without the rotation",
        ),
        740 | 840 | 870 | 880 => (
            " (this canned cycle is not supported in this dialect; G73 G81 G82 G83 G85 G86 G89 are, and G74 G76 G84 G87 G88 in the fanuc and haas dialects)",
            "",
        ),
        _ => return None,
    })
}

/// No machine M codes beyond the shared ones.
pub(crate) fn no_machine_m(_: u32) -> Option<&'static str> {
    None
}

/// The G codes every dialect accepts without effect on the motion: G96/G97 (constant
/// surface speed and its cancel: the spindle speed, not the path).
pub(crate) fn common_no_motion_g(code: u32) -> Option<&'static str> {
    Some(match code {
        960 => "G96 constant surface speed (spindle speed only)",
        970 => "G97 constant spindle speed (cancels G96)",
        _ => return None,
    })
}
