//! Haas (NGC control): the Fanuc family's codes and macros, plus G234 TCP, G254/G255
//! dynamic work offsets, G154 P extended offsets, G103/G187; dwell P in s with a decimal
//! point, ms without.

use crate::code::{GCode, MotionMode, NonModal};
use crate::dialect::fanuc;
use crate::dialect::table::{DwellUnit, Table};

pub(super) const TABLE: Table = Table {
    dwell_p: DwellUnit::MillisecondsUnlessDecimal,
    g_code,
    machine_m,
    no_motion_g,
    local_subprogram_m97: true,
    m98_repeats_in_p: false,
    m16_tool_change: true,
    g53_absolute_in_g91: true,
    g87_back_bore: false,
    peck_settings: Some(("Setting 22", "its G83 clearance")),
    reference_all_without_axes: true,
    whole_numbers_are_increments: true,
    refusal,
    ..fanuc::TABLE
};

/// Haas codes mtsim does not run, with both of their Haas meanings (the dialect reads mill
/// and lathe programs; Haas mill and lathe operator's manuals, "G-codes"), then the Fanuc
/// family's refusals.
fn refusal(code: u32) -> Option<(&'static str, &'static str)> {
    const HELP: &str =
        "post the holes as a canned cycle at each position, the turning as G00/G01 moves";
    Some(match code {
        720 => (" (Haas lathe: end face stock removal cycle; Haas mill: bolt holes along an angle, whose first hole's place the sources mtsim follows do not state) is not supported by mtsim", HELP),
        _ => return fanuc::refusal(code),
    })
}

fn g_code(code: u32) -> Option<GCode> {
    Some(match code {
        2340 => GCode::Tcp(true),
        1540 => GCode::CoordExtended,
        1030 | 1870 => GCode::Control(code),
        2540 => GCode::Dwo(true),
        2550 => GCode::Dwo(false),
        770 => GCode::Motion(Some(MotionMode::Cycle(770))),
        700 => GCode::NonModal(NonModal::BoltCircle),
        710 => GCode::NonModal(NonModal::BoltArc),
        _ => return fanuc::g_code(code),
    })
}

/// Haas G codes with no effect on the canonical moves, then the Fanuc family's.
fn no_motion_g(code: u32) -> Option<&'static str> {
    Some(match code {
        1030 => "G103 block look-ahead limit",
        1870 => "G187 smoothness and accuracy level (the E corner tolerance is applied)",
        _ => return fanuc::no_motion_g(code),
    })
}

/// The Haas NGC mill's machine M codes that do not move the axes (Haas Mill Operator's
/// Manual, "M-codes"): accepted with a notice.
fn machine_m(code: u32) -> Option<&'static str> {
    Some(match code {
        10 => "M10 engage 4th axis brake",
        11 => "M11 release 4th axis brake",
        12 => "M12 engage 5th axis brake",
        13 => "M13 release 5th axis brake",
        17 => "M17 unclamp the pallet (pallet changer)",
        18 => "M18 clamp the pallet (pallet changer)",
        21..=28 => "M21-M28 optional user M function (relay)",
        31 => "M31 chip conveyor / auger forward",
        33 => "M33 chip conveyor / auger stop",
        34 => "M34 coolant spigot increment",
        35 => "M35 coolant spigot decrement",
        36 => "M36 pallet part ready",
        41 => "M41 low gear override",
        42 => "M42 high gear override",
        46 => "M46 jump if pallet loaded",
        48 => "M48 check that the program suits the loaded pallet",
        49 => "M49 set the status of a pallet",
        50 => "M50 pallet change",
        51..=58 => "M51-M58 set an optional user M code relay",
        59 => "M59 set output relay",
        61..=68 => "M61-M68 clear an optional user M code relay",
        69 => "M69 clear output relay",
        73 => "M73 tool air blast on",
        74 => "M74 tool air blast off",
        75 => "M75 set G35/G136 reference point",
        78 => "M78 alarm if skip signal found",
        79 => "M79 alarm if skip signal not found",
        80 => "M80 automatic door open",
        81 => "M81 automatic door close",
        82 => "M82 tool unclamp",
        83 => "M83 automatic air gun on",
        84 => "M84 automatic air gun off",
        86 => "M86 tool clamp",
        88 => "M88 through-spindle coolant on",
        89 => "M89 through-spindle coolant off",
        76 => "M76 control display inactive",
        77 => "M77 control display active",
        95 => "M95 sleep mode",
        130 => "M130 display media",
        138 => "M138 spindle speed variation on",
        139 => "M139 spindle speed variation off",
        158 => "M158 mist condenser on",
        159 => "M159 mist condenser off",
        _ => return fanuc::machine_m(code),
    })
}
