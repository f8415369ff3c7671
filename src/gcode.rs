//! G-code reader (types only so far; the reader is being written).
//!
//! Numbers are kept as exact f64 as written; inch input (G20) is converted to mm.

use crate::axis::AxisVec;

/// The motion of a block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// G00: rapid traverse at each axis's maximum velocity.
    Rapid,
    /// G01: linear interpolation at the feed.
    Linear,
    /// G02 (clockwise) or G03 (counter-clockwise) arc in `plane`, seen from the plane's
    /// positive normal.
    Arc {
        clockwise: bool,
        plane: Plane,
        /// Absolute arc centre, mm, in the same coordinates as the block's end point.
        center_mm: [f64; 3],
    },
    /// G04: dwell, s.
    Dwell { seconds: f64 },
}

/// Arc plane: G17 (XY), G18 (ZX) or G19 (YZ).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plane {
    XY,
    ZX,
    YZ,
}

/// How F is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FeedMode {
    /// G94: F is a rate in mm/min (deg counted as mm for mixed moves).
    PerMinute,
    /// G93: F is the inverse of the block time, 1/min.
    InverseTime,
}

/// One executable block, with modal state resolved. Positions are absolute, mm and deg.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// 1-based source line of the block.
    pub line: usize,
    pub motion: Motion,
    /// Axis positions at the start of the block (the previous block's end).
    pub start: AxisVec,
    /// Axis positions at the end of the block.
    pub end: AxisVec,
    /// F in effect: mm/min in G94 (converted from in/min under G20), 1/min in G93.
    /// `None` when no F has been programmed (fine for G00 and G04).
    pub feed: Option<f64>,
    pub feed_mode: FeedMode,
    /// G43.4 tool-centre-point control active: X Y Z are the tool tip in the table frame.
    pub tcp: bool,
}

/// Placeholder until the reader lands.
pub fn read_file(
    path: &std::path::Path,
    _start: AxisVec,
) -> crate::error::Result<std::vec::IntoIter<crate::error::Result<Block>>> {
    Err(crate::error::Error::invalid(
        path,
        "the G-code reader is not available yet",
    ))
}

impl Plane {
    /// Placeholder until the reader lands: (u, v, normal).
    pub fn axes(self) -> (crate::axis::Axis, crate::axis::Axis, crate::axis::Axis) {
        use crate::axis::Axis;
        match self {
            Plane::XY => (Axis::X, Axis::Y, Axis::Z),
            Plane::ZX => (Axis::Z, Axis::X, Axis::Y),
            Plane::YZ => (Axis::Y, Axis::Z, Axis::X),
        }
    }
}
