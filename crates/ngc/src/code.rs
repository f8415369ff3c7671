//! What the G and M codes of a block mean, independent of how a dialect writes them: the
//! modal groups of RS274/NGC (the NIST RS274/NGC v3 report, table 4; LinuxCNC's G-code
//! manual, "Modal Groups") and the codes of each group as typed values.
//!
//! A dialect's code table (crate `dialect`) maps a written number to a [`GCode`]; the
//! interpreter's phases act on the [`GCode`], never on the number. This module names no
//! other of the crate but `axis`: the tables and the phases both build on it.

use crate::axis::Plane;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MotionMode {
    Rapid,
    Linear,
    Arc {
        clockwise: bool,
    },
    /// Canned cycle G73, G81-G89: the code ×10.
    Cycle(u32),
    /// Spindle-synchronised motion (LinuxCNC): G33 (330), G33.1 (331); see `spindle_sync.rs`.
    SpindleSync(u32),
    /// Straight probe G38.2-G38.5 (LinuxCNC): the code ×10 (see `probe.rs`).
    Probe(u32),
    /// Splines G5 (50), G5.1 (51), NURBS G5.2 (52) (LinuxCNC, see `spline.rs`).
    Spline(u32),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FeedRead {
    PerMinute,
    InverseTime,
    PerRevolution,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum NonModal {
    Dwell,
    G10,
    G28,
    G28_1,
    G30,
    G30_1,
    G52,
    G53,
    G92,
    G92_1,
    G92_2,
    G92_3,
    /// Haas mill G70: bolt-hole circle (the active cycle at L holes on a circle).
    BoltCircle,
    /// Haas mill G71: bolt-hole arc (L holes K degrees apart).
    BoltArc,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum GCode {
    Motion(Option<MotionMode>),
    NonModal(NonModal),
    Plane(Plane),
    Distance(bool),
    ArcDistance(bool),
    Feed(FeedRead),
    Units(bool),
    CutterComp(u32),
    /// G43 (0), G43.1 (1), G43.2 (2), G44 (4), G49 (9), TCP on/off.
    ToolLength(u32),
    Tcp(bool),
    Coord(u32),
    /// G54.1 P / G154 P: extended offsets.
    CoordExtended,
    Path(u32),
    Retract(bool),
    /// Fanuc G05.1 (AI contour control, Q) and G08 (look-ahead, P); Haas G103 (block
    /// look-ahead, P): accepted, no effect on the canonical moves. Haas G187 (P accuracy
    /// level, E corner tolerance) sets the blending tolerance.
    Control(u32),
    /// Fanuc G68.2 (true, tilted work plane) and G69 (false, cancel; it cancels G68 too).
    Tilt(bool),
    /// Fanuc and Haas G68: 2-D coordinate rotation in the selected plane (X Y centre, R).
    Rotate2d,
    /// Fanuc G53.1: rotary axes to the tilted plane.
    AlignRotary,
    /// Haas G254 (true, dynamic work offset) and G255 (false).
    Dwo(bool),
    /// LinuxCNC G7 (true: X words are diameters) and G8 (false: radii).
    Diameter(bool),
    /// LinuxCNC G5.3: the end of a NURBS (G5.2) block sequence; motion group.
    NurbsEnd,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Group {
    Control,
    Tilt,
    AlignRotary,
    Dwo,
    Motion,
    NonModal,
    Plane,
    Distance,
    ArcDistance,
    Feed,
    Units,
    CutterComp,
    ToolLength,
    Coord,
    Path,
    Retract,
    Diameter,
}

impl GCode {
    pub(crate) fn group(self) -> Group {
        match self {
            GCode::Motion(_) | GCode::NurbsEnd => Group::Motion,
            // G4 cannot share a block with a motion code: P and X would be ambiguous.
            GCode::NonModal(NonModal::Dwell) => Group::Motion,
            GCode::NonModal(_) => Group::NonModal,
            GCode::Plane(_) => Group::Plane,
            GCode::Distance(_) => Group::Distance,
            GCode::ArcDistance(_) => Group::ArcDistance,
            GCode::Feed(_) => Group::Feed,
            GCode::Units(_) => Group::Units,
            GCode::CutterComp(_) => Group::CutterComp,
            GCode::ToolLength(_) | GCode::Tcp(_) => Group::ToolLength,
            GCode::Coord(_) | GCode::CoordExtended => Group::Coord,
            GCode::Path(_) => Group::Path,
            GCode::Retract(_) => Group::Retract,
            GCode::Control(_) => Group::Control,
            GCode::Tilt(_) | GCode::Rotate2d => Group::Tilt,
            GCode::AlignRotary => Group::AlignRotary,
            GCode::Dwo(_) => Group::Dwo,
            GCode::Diameter(_) => Group::Diameter,
        }
    }
}

/// M-code groups (LinuxCNC's modal groups 4, 6, 7, 8, 9, 10); two of one group may not
/// share a block.
pub(crate) fn m_group(code: u32) -> Option<u8> {
    Some(match code {
        0 | 1 | 2 | 30 | 60 | 98 | 99 => 4,
        6 | 61 => 6,
        3 | 4 | 5 | 19 => 7,
        7 | 8 | 9 => 8,
        48..=53 => 9,
        _ => return None,
    })
}
