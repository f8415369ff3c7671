//! The scene as a picture: every body's shape and pose in the machine frame at one sample,
//! kept for the deepest collisions of a run, and the tool tip's path thinned to a bounded
//! number of points. The check stage fills them; the report stage draws them
//! (`check --html`, [`crate::report::check_html`]).
//!
//! Memory stays flat in program length: at most [`SHOWN_DEFAULT`] (or the caller's number)
//! snapshots, each a few dozen bodies, and at most [`PATH_POINTS`] points of the path. The
//! path keeps every `stride`-th sample; when it is full, every other point is dropped and
//! the stride doubled, so the kept points stay evenly spaced in samples over the whole run.

use parry3d_f64::math::Pose;
use parry3d_f64::shape::SharedShape;
use serde::Serialize;

use super::{BodyPoses, Carrier, CircleHull, Scene};
use crate::AxisVec;

/// How many of the deepest collisions `check --html` shows.
pub const SHOWN_DEFAULT: usize = 20;
/// The tool tip's path is kept to at most this many points.
pub const PATH_POINTS: usize = 4096;

/// A body's shape in its own frame, mm.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum BodyShape {
    /// A box of half extents along its frame's X, Y, Z.
    Cuboid { half_mm: [f64; 3] },
    /// A cylinder along its frame's Y, centred on its origin.
    Cylinder { half_height_mm: f64, radius_mm: f64 },
    /// A sphere about its origin.
    Ball { radius_mm: f64 },
    /// The convex hull of two circles: centre, unit normal and radius of each.
    CircleHull {
        circles: [([f64; 3], [f64; 3], f64); 2],
    },
}

impl BodyShape {
    fn of(shape: &SharedShape) -> Option<BodyShape> {
        if let Some(c) = shape.as_cuboid() {
            let h = c.half_extents;
            return Some(BodyShape::Cuboid {
                half_mm: [h.x, h.y, h.z],
            });
        }
        if let Some(c) = shape.as_cylinder() {
            return Some(BodyShape::Cylinder {
                half_height_mm: c.half_height,
                radius_mm: c.radius,
            });
        }
        if let Some(b) = shape.as_ball() {
            return Some(BodyShape::Ball {
                radius_mm: b.radius,
            });
        }
        let hull = shape.as_shape::<CircleHull>()?;
        let circle = |k: usize| {
            let c = &hull.circles[k];
            (
                [c.centre.x, c.centre.y, c.centre.z],
                [c.normal.x, c.normal.y, c.normal.z],
                c.radius,
            )
        };
        Some(BodyShape::CircleHull {
            circles: [circle(0), circle(1)],
        })
    }
}

/// One body of the scene where it stood.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlacedBody {
    pub name: String,
    /// What carries it: `table`, `cradle`, `tool`, `bar` or `head`.
    pub carrier: &'static str,
    pub shape: BodyShape,
    /// Its frame's origin in the machine frame, mm.
    pub position_mm: [f64; 3],
    /// Its frame's rotation from the machine frame, a unit quaternion (x, y, z, w).
    pub rotation_xyzw: [f64; 4],
}

/// The scene at the deepest sample of one collision.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CollisionPose {
    /// The colliding pair, as the violation names it.
    pub bodies: [String; 2],
    /// Penetration depth at this sample, mm (the violation's worst).
    pub depth_mm: f64,
    pub time_s: f64,
    /// Program line of the violation's first sample.
    pub line: usize,
    /// Axis positions (mm, deg), by axis name.
    pub axes: Vec<(String, f64)>,
    /// The tool tip (the tool body's origin) in the machine frame, mm.
    pub tip_mm: [f64; 3],
    pub bodies_placed: Vec<PlacedBody>,
}

/// The pictures of a check: the deepest collisions and the tool tip's path.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CollisionViews {
    /// Deepest first (ties: earliest first).
    pub collisions: Vec<CollisionPose>,
    /// The tool tip in the machine frame, mm, every `path_stride`-th sample.
    pub tip_path_mm: Vec<[f64; 3]>,
    pub path_stride: u64,
}

fn carrier_name(c: Carrier) -> &'static str {
    match c {
        Carrier::Table => "table",
        Carrier::Cradle => "cradle",
        Carrier::Tool => "tool",
        Carrier::Bar => "bar",
        Carrier::Head => "head",
    }
}

impl Scene {
    /// Every body's shape and machine-frame pose at axis positions `q` (mm, deg).
    pub fn placed_bodies(&self, q: &AxisVec) -> Vec<PlacedBody> {
        let mut poses = BodyPoses::new(q);
        self.parts
            .iter()
            .filter_map(|part| {
                let pose: Pose = self.body_pose(part.carrier as usize, &mut poses) * part.local;
                let r = pose.rotation;
                Some(PlacedBody {
                    name: part.name.clone(),
                    carrier: carrier_name(part.carrier),
                    shape: BodyShape::of(&part.shape)?,
                    position_mm: [pose.translation.x, pose.translation.y, pose.translation.z],
                    rotation_xyzw: [r.x, r.y, r.z, r.w],
                })
            })
            .collect()
    }

    /// The tool body's origin (the tip of the scenario's tool) in the machine frame at `q`, mm.
    pub fn tip_mm(&self, q: &AxisVec) -> [f64; 3] {
        let t = self
            .body_pose(Carrier::Tool as usize, &mut BodyPoses::new(q))
            .translation;
        [t.x, t.y, t.z]
    }
}

/// The deepest collisions of a run, at most `capacity` of them.
#[derive(Debug)]
pub(crate) struct DeepestCollisions {
    capacity: usize,
    kept: Vec<CollisionPose>,
}

impl DeepestCollisions {
    pub(crate) fn new(capacity: usize) -> DeepestCollisions {
        DeepestCollisions {
            capacity,
            kept: Vec::with_capacity(capacity),
        }
    }

    /// Whether a collision `depth_mm` deep at `time_s` would be kept.
    pub(crate) fn admits(&self, depth_mm: f64, time_s: f64) -> bool {
        self.capacity > 0
            && (self.kept.len() < self.capacity
                || self
                    .kept
                    .last()
                    .is_some_and(|w| deeper(depth_mm, time_s, w.depth_mm, w.time_s)))
    }

    /// Keeps `pose` if it is among the deepest (call [`Self::admits`] first to skip building
    /// it).
    pub(crate) fn offer(&mut self, pose: CollisionPose) {
        if !self.admits(pose.depth_mm, pose.time_s) {
            return;
        }
        let at = self
            .kept
            .iter()
            .position(|k| deeper(pose.depth_mm, pose.time_s, k.depth_mm, k.time_s))
            .unwrap_or(self.kept.len());
        self.kept.insert(at, pose);
        self.kept.truncate(self.capacity);
    }

    pub(crate) fn into_vec(self) -> Vec<CollisionPose> {
        self.kept
    }
}

/// Deeper first, then earlier.
fn deeper(d: f64, t: f64, other_d: f64, other_t: f64) -> bool {
    d > other_d || (d == other_d && t < other_t)
}

/// The tool tip's path, thinned to at most [`PATH_POINTS`] points.
#[derive(Debug)]
pub struct TipPath {
    points: Vec<[f64; 3]>,
    stride: u64,
    seen: u64,
}

impl Default for TipPath {
    fn default() -> Self {
        TipPath {
            points: Vec::with_capacity(PATH_POINTS),
            stride: 1,
            seen: 0,
        }
    }
}

impl TipPath {
    /// Whether the next sample is one the path keeps (then [`Self::push`] it).
    #[inline]
    pub fn wants_next(&mut self) -> bool {
        let wanted = self.seen % self.stride == 0;
        self.seen += 1;
        wanted
    }

    pub fn push(&mut self, tip_mm: [f64; 3]) {
        if self.points.len() == PATH_POINTS {
            // Keep samples 0, 2·stride, 4·stride, ...: every other point.
            let mut k = 0;
            self.points.retain(|_| {
                k += 1;
                k % 2 == 1
            });
            self.stride *= 2;
            if (self.seen - 1) % self.stride != 0 {
                return;
            }
        }
        self.points.push(tip_mm);
    }

    /// The points and the stride (in samples) between them.
    pub fn finish(self) -> (Vec<[f64; 3]>, u64) {
        (self.points, self.stride)
    }
}
