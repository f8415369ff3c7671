//! Canonical moves: what the interpreter emits and the motion planner consumes.

use crate::axis::Plane;
use crate::AxisVec;

/// Start and end closer than this in the arc plane, mm, make a full circle.
pub const FULL_CIRCLE_TOLERANCE_MM: f64 = 1e-9;

/// The motion of a block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// G00: rapid traverse at each axis's maximum velocity.
    Rapid,
    /// G01: linear interpolation at the feed.
    Linear,
    /// G02 (clockwise) or G03 (counter-clockwise) arc in `plane`, seen from the plane's
    /// positive normal.
    ///
    /// The axes outside the plane (the normal axis of a helix, and A B C) move linearly
    /// with the arc angle. When start and end coincide in the plane (within
    /// [`FULL_CIRCLE_TOLERANCE_MM`]) the arc is a full circle.
    Arc {
        clockwise: bool,
        plane: Plane,
        /// Absolute arc centre, mm, in the same coordinates as the block's end point, as
        /// `[X, Y, Z]`. The coordinate along the plane normal is the start point's.
        center_mm: [f64; 3],
    },
    /// G04: dwell, s.
    Dwell { seconds: f64 },
}

/// How F is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FeedMode {
    /// G94: F is a rate in mm/min (deg counted as mm for mixed moves).
    PerMinute,
    /// G93: F is the inverse of the block time, 1/min.
    InverseTime,
}

/// One canonical move: an executable block with modal state resolved. Positions are
/// absolute, mm and deg.
///
/// This is the narrow interface between reading a program and moving the machine (the
/// role of LinuxCNC's canonical machining calls): generators emit it too.
#[derive(Clone, Debug, PartialEq)]
pub struct Move {
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

impl Move {
    /// Signed sweep angle of an arc block, rad: positive counter-clockwise (G03), negative
    /// clockwise (G02), magnitude in (0, 2π]; ±2π for a full circle. `None` for other
    /// motions.
    ///
    /// With centre c and in-plane start s and end e, the sweep is
    /// `atan2(e_v - c_v, e_u - c_u) - atan2(s_v - c_v, s_u - c_u)`, wrapped into the
    /// direction of travel.
    pub fn arc_sweep_rad(&self) -> Option<f64> {
        let Motion::Arc {
            clockwise,
            plane,
            center_mm,
        } = self.motion
        else {
            return None;
        };
        let (u, v, _) = plane.axes();
        let (cu, cv) = (center_mm[u.index()], center_mm[v.index()]);
        let (su, sv) = (self.start[u] - cu, self.start[v] - cv);
        let (eu, ev) = (self.end[u] - cu, self.end[v] - cv);
        let tau = std::f64::consts::TAU;
        if (eu - su).hypot(ev - sv) < FULL_CIRCLE_TOLERANCE_MM {
            return Some(if clockwise { -tau } else { tau });
        }
        let mut sweep = ev.atan2(eu) - sv.atan2(su);
        if clockwise {
            while sweep >= 0.0 {
                sweep -= tau;
            }
        } else {
            while sweep <= 0.0 {
                sweep += tau;
            }
        }
        Some(sweep)
    }
}
