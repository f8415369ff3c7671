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

/// The kind of a canonical move, as `mtsim blocks` prints it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MoveKind {
    /// G00 and every traverse the interpreter makes at rapid (G28, G53 G00, cycle retracts).
    Rapid,
    /// Straight feed move (G01, cycle feeds).
    Feed,
    /// Circular or helical feed move (G02/G03).
    Arc,
    /// Dwell (G04, cycle dwells).
    Dwell,
}

impl MoveKind {
    /// `rapid`, `feed`, `arc` or `dwell`.
    pub const fn name(self) -> &'static str {
        match self {
            MoveKind::Rapid => "rapid",
            MoveKind::Feed => "feed",
            MoveKind::Arc => "arc",
            MoveKind::Dwell => "dwell",
        }
    }
}

/// Path-control mode (LinuxCNC group 13): how consecutive moves join.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathControl {
    /// G61: exact path. The tool follows the programmed corners exactly (it slows to a stop
    /// at a corner that is not tangent); no blending.
    ExactPath,
    /// G61.1: exact stop. Every move ends at rest.
    ExactStop,
    /// G64: blending. Corners may be rounded by at most `tolerance_mm` (G64 P, `None`: as
    /// fast as possible, any deviation the planner needs); collinear short moves may be merged
    /// within `naive_cam_mm` (G64 Q, `None`: no merging).
    Blend {
        tolerance_mm: Option<f64>,
        naive_cam_mm: Option<f64>,
    },
}

impl PathControl {
    /// G64 without P or Q: LinuxCNC's default.
    pub const BLEND: PathControl = PathControl::Blend {
        tolerance_mm: None,
        naive_cam_mm: None,
    };

    /// True for G61 and G61.1: the planner must not round corners.
    pub const fn is_exact(self) -> bool {
        !matches!(self, PathControl::Blend { .. })
    }
}

impl Default for PathControl {
    fn default() -> PathControl {
        PathControl::BLEND
    }
}

/// How F is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FeedMode {
    /// G94: F is a rate in mm/min (deg counted as mm for mixed moves).
    PerMinute,
    /// G93: F is the inverse of the block time, 1/min.
    InverseTime,
}

/// A move's feed, resolved by the reader from the F word in effect, the feed mode (G93,
/// G94, G95's F × S) and the units (in/min converted under G20): what the planner runs a
/// feed move at, as a number. A rapid and a dwell have none; a feed move always has one
/// (the reader refuses a G01, G02 or G03 without a positive F in effect, with its file,
/// line and column).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Feed {
    /// A rapid (each axis at its maximum velocity) or a dwell: no path feed.
    #[default]
    None,
    /// G94: the path speed, mm/min (deg counted as mm for mixed moves).
    PerMinute(f64),
    /// G93: the inverse of the block time, 1/min.
    InverseTime(f64),
}

impl Feed {
    /// F: mm/min under G94, 1/min under G93; `None` for a rapid or a dwell.
    pub const fn rate(self) -> Option<f64> {
        match self {
            Feed::None => None,
            Feed::PerMinute(f) | Feed::InverseTime(f) => Some(f),
        }
    }

    /// How F is read; `None` for a rapid or a dwell.
    pub const fn mode(self) -> Option<FeedMode> {
        match self {
            Feed::None => None,
            Feed::PerMinute(_) => Some(FeedMode::PerMinute),
            Feed::InverseTime(_) => Some(FeedMode::InverseTime),
        }
    }
}

/// One canonical move: an executable block with modal state resolved. Positions are
/// absolute machine coordinates, mm and deg: work offsets (G54-G59.3, G92, G52) and the
/// tool length offset (G43) are already applied, so `end` is where the machine axes go.
///
/// Build one with struct-update syntax so that fields added later keep code compiling:
/// `Move { line, motion, start, end, feed: Feed::PerMinute(600.0), ..Move::default() }`.
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
    /// The feed of a feed move, resolved ([`Feed`]); [`Feed::None`] for a rapid or a dwell.
    pub feed: Feed,
    /// G43.4 tool-centre-point control active: X Y Z are the tool tip in the table frame.
    pub tcp: bool,
    /// Active tool number (the T of the last M6 or M61 Q), 0 for no tool.
    pub tool: u32,
    /// Tool length offset in effect along Z, mm (G43 H, G43.1, G43.2; 0 after G49). Already
    /// added to `end[Z]`; under TCP it is the tool length the kinematics use.
    pub tool_length_mm: f64,
    /// Path-control mode in effect for this move: how it joins the next.
    pub path: PathControl,
}

impl Default for Move {
    /// A rapid of length zero at the origin, line 0, no feed, no tool, G64 blending.
    fn default() -> Move {
        Move {
            line: 0,
            motion: Motion::Rapid,
            start: AxisVec::ZERO,
            end: AxisVec::ZERO,
            feed: Feed::None,
            tcp: false,
            tool: 0,
            tool_length_mm: 0.0,
            path: PathControl::BLEND,
        }
    }
}

impl Move {
    /// What kind of move this is: rapid, feed, arc or dwell.
    pub const fn kind(&self) -> MoveKind {
        match self.motion {
            Motion::Rapid => MoveKind::Rapid,
            Motion::Linear => MoveKind::Feed,
            Motion::Arc { .. } => MoveKind::Arc,
            Motion::Dwell { .. } => MoveKind::Dwell,
        }
    }

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
