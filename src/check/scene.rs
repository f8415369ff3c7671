//! Collision scene: table, cradle, workpiece (cone frustum or ball bar), tool stack and
//! spindle, posed by forward kinematics from the axis positions.
//!
//! Frames are those of [`crate::kinematics`]: a body fixed to the table sits at
//! `m = pivot + R(q) p`; a cradle body at `m = pivot + R_tilt(q) p` (no C); the tool stack
//! at `m = (X, Y, Z) + p` with the tool axis along +Z and the tip at the origin of its frame.
//! The ball bar is posed from both ends: its origin at the pivot ball (fixed to the table)
//! and its +Z toward the tool ball (at the tool tip).
//!
//! On a `[kinematics]` chain every body rides on the links up to the one it is attached to
//! ([`linked`]): the table on the table axes, cradle boxes on those up to their `link`,
//! head boxes on the head axes up to theirs, the tool stack and spindle on the whole head,
//! so a head turning moves the spindle housing and the holder.
//!
//! The bodies are rapier kinematic rigid bodies whose colliders carry [`InteractionGroups`]
//! that encode which parts may touch (see [`groups`]); every collider pair the groups allow
//! is monitored. A cutter/workpiece pair is *cutting* (its depth is engagement); every
//! other pair is a *collision* pair. Distances are parry GJK/EPA queries on exact convex
//! shapes (see [`shapes`]), except a cylinder against the frustum, which has a certified
//! closed form ([`frustum`]). The streaming, conservative-advancement check is in
//! [`monitor`].

pub mod frustum;
pub mod linked;
pub mod monitor;
mod plane;
pub mod prism;
pub mod shapes;
pub mod snapshot;

use nalgebra::{Isometry3, Point3, Vector3};
use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::shape::SharedShape;
use rapier3d_f64::dynamics::{RigidBodyBuilder, RigidBodyHandle, RigidBodySet};
use rapier3d_f64::geometry::{
    ColliderBuilder, ColliderHandle, ColliderSet, Group, InteractionGroups, InteractionTestMode,
};
use serde::Serialize;

pub use crate::input::scene::{
    ConeSetup, CradleBox, DepthTolerance, SceneConfig, SpindleConfig, SpindleShape, TableAxis,
    TableConfig, ToolConfig, WorkpieceConfig, WorkpieceKind,
};
pub use monitor::{EngagementSummary, EventKind, SceneEvent, SceneMonitor, SceneReport};
pub use shapes::{signed_distance, z_cylinder, Circle, CircleHull};

use crate::error::{Error, Result};
use crate::input::machine::Machine;
use crate::kinematics::{CradleTablePoses, Kinematics, Layout};
use crate::{Axis, AxisVec};
use linked::{LinkedBodies, Rides};

/// Collision groups. A pair of colliders is monitored when each one's membership meets the
/// other's filter (rapier's `InteractionTestMode::And`).
///
/// | part                          | member of  | filter (may touch)                          |
/// |-------------------------------|------------|---------------------------------------------|
/// | table, cradle boxes           | TABLE      | CUTTER, TOOL, BAR, BALL                     |
/// | riser, ball-bar post          | FIXTURE    | CUTTER, TOOL, BAR, BALL                     |
/// | frustum                       | WORKPIECE  | CUTTER, TOOL, BALL                          |
/// | cutter                        | CUTTER     | TABLE, FIXTURE, WORKPIECE                   |
/// | shank, holder, spindle        | TOOL       | TABLE, FIXTURE, WORKPIECE, BAR, BALL        |
/// | bar                           | BAR        | TABLE, FIXTURE, TOOL                        |
/// | pivot ball                    | BALL       | TOOL, CUTTER                                |
/// | tool ball                     | BALL       | TABLE, FIXTURE, WORKPIECE                   |
///
/// So parts on one body never pair, the balls are joined to the bar, and the tool ball is
/// joined to the shank.
pub mod groups {
    use rapier3d_f64::geometry::Group;
    pub const TABLE: Group = Group::GROUP_1;
    pub const FIXTURE: Group = Group::GROUP_2;
    pub const WORKPIECE: Group = Group::GROUP_3;
    pub const CUTTER: Group = Group::GROUP_4;
    pub const TOOL: Group = Group::GROUP_5;
    pub const BAR: Group = Group::GROUP_6;
    pub const BALL: Group = Group::GROUP_7;
}

/// What carries a part, and so how it is posed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Carrier {
    Table = 0,
    Cradle = 1,
    Tool = 2,
    Bar = 3,
    /// Head parts, carried by the head axes up to their link.
    Head = 4,
}

/// Bodies in the scene (one per [`Carrier`]).
const BODIES: usize = 5;

/// Whether touching is cutting or a collision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PairKind {
    /// Cutter against workpiece: the depth is engagement.
    Cutting,
    /// Anything else.
    Collision,
}

/// The signed distance of one monitored pair at the current pose.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairClearance {
    pub bodies: [String; 2],
    pub kind: PairKind,
    /// Clearance, mm; negative = penetration depth.
    pub distance_mm: f64,
}

/// One collider of the scene.
struct Part {
    name: String,
    carrier: Carrier,
    handle: ColliderHandle,
    shape: SharedShape,
    /// Pose in the carrier's frame.
    local: Pose,
    /// Bound on this part's displacement (mm) per |dXYZ| (mm), |d tilt| (rad), |dC| (rad).
    motion: [f64; 3],
    /// For the cutter: the cutter eroded by [`CUTTER_SKIN_MM`], used for the cutting pair.
    eroded: Option<SharedShape>,
    skin_mm: f64,
    /// The part as a shape [`frustum::signed_distance`] takes, in the part's local frame
    /// (filled in by [`Builder::finish`]; for the cutter, of the eroded shape).
    analytic: Option<Analytic>,
    /// The part as a right prism (its own shape, not eroded), for the closed-form distance
    /// of parallel prisms ([`prism`]).
    prism: Option<prism::Prism>,
}

/// A part whose distance to a frustum has a certified closed-form query.
#[derive(Clone, Copy, Debug)]
enum Analytic {
    /// A coaxial two-circle hull, in the part's local frame.
    Frustum(frustum::Frustum),
    /// A parry cylinder (axis along its local Y): half height and radius, mm.
    Cylinder(f64, f64),
}

impl Analytic {
    fn of(shape: &SharedShape) -> Option<Analytic> {
        if let Some(c) = shape.as_cylinder() {
            return Some(Analytic::Cylinder(c.half_height, c.radius));
        }
        let hull = shape.as_shape::<CircleHull>()?;
        let [c0, c1] = hull.circles;
        if c0.normal.cross(c1.normal).length() > 1e-12 {
            return None;
        }
        frustum::Frustum::from_circles(c0.centre, c0.radius, c1.centre, c1.radius, c0.normal)
            .map(Analytic::Frustum)
    }
}

/// Warm starts of one pair's queries: GJK's direction, and the certifying direction of
/// [`frustum::signed_distance`].
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Warm {
    gjk: Option<Vector>,
    /// The certifying direction and the cylinder's centre it was found at, in the frustum's
    /// frame.
    normal: Option<(Vector, Vector)>,
    /// Whether the last query was answered by the closed form of parallel prisms, which
    /// costs no more than a look at the plane bound ([`prism`]).
    prism: bool,
}

/// The cutter/workpiece distance is measured from the cutter eroded by this much (mm), less
/// this much: the distance to the cutter with its rims rounded by this radius (error at most
/// 0.42 times it, at the rims only). The flank sits tangent to the frustum, where GJK/EPA on
/// touching shapes is slow and fragile; the eroded cutter stands off, so GJK alone answers.
pub const CUTTER_SKIN_MM: f64 = 0.01;

/// One monitored pair (indices into the parts).
#[derive(Clone, Copy, Debug)]
struct Pair {
    a: usize,
    b: usize,
    kind: PairKind,
}

/// The bar between the balls: pivot-ball centre in the table frame, mm.
#[derive(Clone, Copy, Debug)]
struct BarEnds {
    pivot: Vector3<f64>,
}

/// The body poses of one sample, each computed when first asked for.
pub(crate) struct BodyPoses<'a> {
    q: &'a AxisVec,
    chain: Option<(Isometry3<f64>, Isometry3<f64>)>,
    poses: [Option<Pose>; BODIES],
}

impl<'a> BodyPoses<'a> {
    pub(crate) fn new(q: &'a AxisVec) -> BodyPoses<'a> {
        BodyPoses {
            q,
            chain: None,
            poses: [None; BODIES],
        }
    }
}

/// The collision scene of one machine, tool and workpiece.
pub struct Scene {
    kinematics: Kinematics,
    /// The cradle's and the table's poses, the lines taken once from the kinematics.
    chain: CradleTablePoses,
    tilt_axis: Option<Axis>,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    body_handles: [RigidBodyHandle; BODIES],
    parts: Vec<Part>,
    pairs: Vec<Pair>,
    /// The bodies' links: every body's on a general chain, the head boxes' on a named layout.
    linked: Option<LinkedBodies>,
    bar: Option<BarEnds>,
    near_miss_mm: f64,
    engagement_resolution_mm: f64,
    /// A collision's reported depth `W` is within `mm + relative · W` of its deepest
    /// sample's.
    depth_tolerance: DepthTolerance,
}

impl Scene {
    /// Builds the scene of `machine` (its `[scene]` geometry) with `tool` and `workpiece`.
    /// `near_miss_mm` is the clearance below which a collision pair is a near miss.
    pub fn new(
        machine: &Machine,
        tool: &ToolConfig,
        workpiece: &WorkpieceConfig,
        near_miss_mm: f64,
    ) -> Result<Scene> {
        let path = machine.path.as_path();
        let scene = &machine.scene;
        // The machine's [scene] and [tool] and the scenario's [tool] and [workpiece] were
        // checked when their files were read (input/scene.rs); the clearance is an argument.
        if !(near_miss_mm.is_finite() && near_miss_mm >= 0.0) {
            return Err(Error::invalid(
                path,
                format!("near-miss threshold must be a clearance >= 0 mm, got {near_miss_mm}"),
            ));
        }
        let mut builder = Builder::new(machine.kinematics);
        builder.linked = linked_bodies(machine)?;
        let all_tool = groups::CUTTER | groups::TOOL | groups::BAR | groups::BALL;

        builder.add_table(machine, workpiece, all_tool)?;
        builder.add_tool_stack(machine, tool, workpiece);
        let bar = builder.add_workpiece(machine, tool, workpiece, all_tool)?;
        let mut built = builder.finish(bar, near_miss_mm, scene.engagement_resolution_mm);
        built.depth_tolerance = DepthTolerance {
            mm: scene.depth_tolerance_mm,
            relative: scene.depth_tolerance_relative,
        };
        Ok(built)
    }

    /// The near-miss threshold, mm.
    pub fn near_miss_mm(&self) -> f64 {
        self.near_miss_mm
    }

    /// The tolerance of a collision's reported depth (`[scene] depth_tolerance_mm` and
    /// `depth_tolerance_relative`).
    pub fn depth_tolerance(&self) -> DepthTolerance {
        self.depth_tolerance
    }

    /// Sets the tolerance of a collision's reported depth ([`DepthTolerance::EXACT`]
    /// measures every sample that could be deeper).
    pub fn set_depth_tolerance(&mut self, tolerance: DepthTolerance) {
        self.depth_tolerance = tolerance;
    }

    /// Names of the monitored pairs, in the order [`Scene::clearances`] reports them.
    pub fn pair_names(&self) -> Vec<[String; 2]> {
        self.pairs.iter().map(|p| self.pair_bodies(p)).collect()
    }

    /// Puts `tool` in the spindle, its tip `tip_below_mm` below the tool body's origin (the
    /// Z point, where the tip of the tool the scene was built with sits): the cutter, shank
    /// and holder take its dimensions; the spindle stays. A ball-bar scene has no cutter and
    /// keeps its tool ball at the Z point, so only its shank and holder change. The caller
    /// validates `tool` (see [`ToolConfig::for_table_tool`]).
    pub fn set_tool(&mut self, tool: &ToolConfig, tip_below_mm: f64) {
        let shift = Pose::from_translation(Vector::new(0.0, 0.0, -tip_below_mm));
        let body = *self.bodies[self.body_handles[Carrier::Tool as usize]].position();
        let flutes = tool.flute_length_mm;
        let shank_top = flutes + tool.shank_length_mm;
        for part in &mut self.parts {
            if part.carrier != Carrier::Tool {
                continue;
            }
            let (shape, local) = match part.name.as_str() {
                "cutter" => z_cylinder(0.0, flutes, 0.5 * tool.cutter_diameter_mm),
                "shank" => z_cylinder(flutes, shank_top, 0.5 * tool.shank_diameter_mm),
                "holder" => z_cylinder(
                    tool.holder_bottom_mm(),
                    tool.gauge_length_mm,
                    0.5 * tool.holder_diameter_mm,
                ),
                _ => continue,
            };
            if part.eroded.is_some() {
                let skin = CUTTER_SKIN_MM
                    .min(0.25 * tool.cutter_diameter_mm)
                    .min(0.25 * flutes);
                let (eroded, _) =
                    z_cylinder(skin, flutes - skin, 0.5 * tool.cutter_diameter_mm - skin);
                part.eroded = Some(eroded);
                part.skin_mm = skin;
            }
            part.shape = shape.clone();
            part.local = shift * local;
            if let Some(linked) = self.linked.filter(|_| !self.kinematics.has_closed_form()) {
                // On a chain the tool's lever arms about the head's rotaries change with it.
                part.motion = linked.weights(Rides::Tool, &aabb_corners(&part.shape, &part.local));
            }
            // The closed-form distance takes the new cylinder's dimensions.
            part.analytic = Analytic::of(part.eroded.as_ref().unwrap_or(&part.shape));
            part.prism = prism::Prism::of(&part.shape);
            if let Some(collider) = self.colliders.get_mut(part.handle) {
                collider.set_shape(shape);
                collider.set_position_wrt_parent(part.local);
                collider.set_position(body * part.local);
            }
        }
    }

    /// Poses every body by forward kinematics at `q` (mm, deg).
    pub fn set_axes(&mut self, q: &AxisVec) {
        let poses = self.body_poses(q);
        for (handle, pose) in self.body_handles.iter().zip(poses) {
            if let Some(body) = self.bodies.get_mut(*handle) {
                body.set_position(pose, false);
            }
        }
        self.bodies
            .propagate_modified_body_positions_to_colliders(&mut self.colliders);
    }

    /// Signed distance of every monitored pair at the pose of the last [`Scene::set_axes`].
    pub fn clearances(&mut self) -> Vec<PairClearance> {
        self.pairs
            .iter()
            .map(|pair| {
                let (a, b) = (&self.parts[pair.a], &self.parts[pair.b]);
                let poses = (
                    self.colliders[a.handle].position(),
                    self.colliders[b.handle].position(),
                );
                let distance_mm = pair_distance(pair, a, b, poses.0, poses.1, &mut Warm::default());
                PairClearance {
                    bodies: self.pair_bodies(pair),
                    kind: pair.kind,
                    distance_mm,
                }
            })
            .collect()
    }

    fn pair_bodies(&self, pair: &Pair) -> [String; 2] {
        [
            self.parts[pair.a].name.clone(),
            self.parts[pair.b].name.clone(),
        ]
    }

    /// The pose of body `carrier` (in the machine frame) at the sample of `poses`.
    pub(crate) fn body_pose(&self, carrier: usize, poses: &mut BodyPoses) -> Pose {
        if let Some(p) = poses.poses[carrier] {
            return p;
        }
        if let Some(p) = self.linked_pose(carrier, poses) {
            poses.poses[carrier] = Some(p);
            return p;
        }
        let q = poses.q;
        let (cradle, table) = *poses.chain.get_or_insert_with(|| self.chain.poses(q));
        let pose = |iso: &Isometry3<f64>| {
            let c = iso.rotation.coords; // (i, j, k, w)
            Pose::from_parts(
                to_vector(&iso.translation.vector),
                Rotation::from_xyzw(c.x, c.y, c.z, c.w),
            )
        };
        let tip = Vector3::new(q.0[0], q.0[1], q.0[2]);
        let p = match carrier {
            0 => pose(&table),
            1 => pose(&cradle),
            2 => Pose::from_translation(to_vector(&tip)),
            _ => match &self.bar {
                Some(ends) => {
                    let a = table.translation.vector + table.rotation * ends.pivot;
                    let dir = to_vector(&(tip - a));
                    let rotation = match dir.try_normalize() {
                        Some(d) => Rotation::from_rotation_arc(Vector::Z, d),
                        None => Rotation::IDENTITY,
                    };
                    Pose::from_parts(to_vector(&a), rotation)
                }
                None => Pose::IDENTITY,
            },
        };
        poses.poses[carrier] = Some(p);
        p
    }

    /// The pose of body `carrier` through the chain's links: every body on a general chain,
    /// the head boxes on a named layout; `None` for the rest.
    fn linked_pose(&self, carrier: usize, poses: &mut BodyPoses) -> Option<Pose> {
        let linked = self.linked.as_ref()?;
        let q = poses.q;
        let general = !self.kinematics.has_closed_form();
        let iso = match carrier {
            4 => linked.pose(Rides::Head, q),
            _ if !general => return None,
            0 => linked.pose(Rides::Table, q),
            1 => linked.pose(Rides::Cradle, q),
            2 => linked.pose(Rides::Tool, q),
            _ => {
                // The bar: from the pivot ball (on the table) toward the tool ball (the tip).
                let ends = self.bar.as_ref()?;
                let a = linked.pose(Rides::Table, q) * Point3::from(ends.pivot);
                let tip = self.body_pose(2, poses).translation;
                let dir = tip - to_vector(&a.coords);
                let rotation = match dir.try_normalize() {
                    Some(d) => Rotation::from_rotation_arc(Vector::Z, d),
                    None => Rotation::IDENTITY,
                };
                return Some(Pose::from_parts(to_vector(&a.coords), rotation));
            }
        };
        Some(to_pose(&iso))
    }

    /// [`warm_bounds`] of pair `i` at the sample of `poses`.
    pub(crate) fn warm_bounds(
        &self,
        i: usize,
        poses: &mut BodyPoses,
        warm: &Warm,
    ) -> Option<(f64, f64)> {
        warm.normal?;
        let pair = self.pairs[i];
        let (a, b) = (&self.parts[pair.a], &self.parts[pair.b]);
        let pose_a = self.body_pose(a.carrier as usize, poses) * a.local;
        let pose_b = self.body_pose(b.carrier as usize, poses) * b.local;
        warm_bounds(&pair, a, b, &pose_a, &pose_b, warm)
    }

    /// Poses of the table, cradle, tool, bar and head frames in the machine frame at `q`.
    fn body_poses(&self, q: &AxisVec) -> [Pose; BODIES] {
        let mut poses = BodyPoses::new(q);
        [0, 1, 2, 3, 4].map(|carrier| self.body_pose(carrier, &mut poses))
    }

    /// The monitor's motion between two samples on a general chain ([`LinkedBodies::motion`]).
    #[inline]
    pub(crate) fn chain_motion(&self, a: &AxisVec, b: &AxisVec) -> Option<[f64; 3]> {
        self.linked
            .as_ref()
            .filter(|_| !self.kinematics.has_closed_form())
            .map(|l| l.motion(a, b))
    }
}

/// The frustum of the machining test: the path cone offset one cutter radius inward.
///
/// In the cone frame (axis a = Ry(-beta) z through O) the tool tip runs on the circle of
/// radius `L cos(alpha)` at height `L sin(alpha)`, with the tool axis along the generatrix
/// of the path cone (apex at height `L / sin(alpha)`, half angle alpha). The cutter's flank
/// (radius R) is tangent to the cone of the same half angle whose surface lies R inside,
/// measured perpendicular to the generatrix: its apex is `R / sin(alpha)` lower, so its
/// radius at height z is `((L - R) / sin(alpha) - z) tan(alpha)` and the base radius is
/// `(L - R) / cos(alpha)`.
struct Frustum {
    base: Circle,
    top: Circle,
}

impl Frustum {
    fn new(
        cone: &ConeSetup,
        tool: &ToolConfig,
        top_height_mm: Option<f64>,
        path: &std::path::Path,
    ) -> Result<Frustum> {
        let alpha = cone.half_apex_deg.to_radians();
        let beta = cone.inclination_deg.to_radians();
        let l = cone.ballbar_length_mm;
        let r = 0.5 * tool.cutter_diameter_mm;
        if l <= r {
            return Err(Error::invalid(path, format!("the ball-bar length ({l} mm) must exceed the cutter radius ({r} mm) for the frustum to exist")));
        }
        let axis = Vector::new(-beta.sin(), 0.0, beta.cos());
        let o = Vector::from_array(cone.center_mm);
        let base_radius = (l - r) / alpha.cos();
        // Default: halfway between the measured circle's plane and the top of the flank
        // contact, keeping the shank's lower rim clear of the top face.
        let height = top_height_mm.unwrap_or_else(|| {
            l * alpha.sin() + 0.5 * (tool.flute_length_mm * alpha.cos() - r * alpha.sin())
        });
        let top_radius = base_radius - height * alpha.tan();
        if top_radius <= 0.0 {
            return Err(Error::invalid(path, format!(
                "workpiece.top_height_mm = {height} mm reaches past the frustum's apex at {:.3} mm: lower it",
                base_radius / alpha.tan()
            )));
        }
        Ok(Frustum {
            base: Circle {
                centre: o,
                normal: axis,
                radius: base_radius,
            },
            top: Circle {
                centre: o + axis * height,
                normal: axis,
                radius: top_radius,
            },
        })
    }
}

/// Displacement weights of the bar, whose ends move independently: with `a` the pivot end
/// and `b` the tool end, a point of the bar (within `L + r` of `a`) moves at most
/// `|da| + (L + r) |d dir|`, and `|d dir| <= 2 (|da| + |db|) / L`; `|db| = |dXYZ|`,
/// `|da| <= |O| |d tilt| + rho_O |dC|`.
fn bar_motion(layout: Layout, o: Vector3<f64>, length: f64, r_bar: f64) -> [f64; 3] {
    let k = 1.0 + 2.0 * (length + r_bar) / length;
    [
        k,
        k * o.norm(),
        k * from_table_axis(layout, [o.x, o.y, o.z]),
    ]
}

/// [`bar_motion`] on a general chain: the pivot end moves at most `w_a · (Σ|Δlin|, Σ|Δθ|)`
/// (a table point at O), the tool end `w_b · (…)` (the tool body's origin), and a point of the
/// bar at most `k (|da| + |db|)`.
fn chain_bar_motion(linked: &LinkedBodies, o: Vector3<f64>, length: f64, r_bar: f64) -> [f64; 3] {
    let k = 1.0 + 2.0 * (length + r_bar) / length;
    let a = linked.weights(Rides::Table, &[Point3::from(o)]);
    let b = linked.weights(Rides::Tool, &[Point3::origin()]);
    [k * (a[0] + b[0]), k * (a[1] + b[1]), k * (a[2] + b[2])]
}

/// The eight corners of the bounding box of `shape` at `local`, mm.
fn aabb_corners(shape: &SharedShape, local: &Pose) -> Vec<Point3<f64>> {
    let aabb = shape.compute_aabb(local);
    (0..8)
        .map(|i| {
            Point3::new(
                if i & 1 == 0 { aabb.mins.x } else { aabb.maxs.x },
                if i & 2 == 0 { aabb.mins.y } else { aabb.maxs.y },
                if i & 4 == 0 { aabb.mins.z } else { aabb.maxs.z },
            )
        })
        .collect()
}

/// The lever arm (mm per rad of the table axis) of a cylinder on the table whose axis is
/// (nearly) the table axis: turning the table by `φ` turns the cylinder about its own axis,
/// which leaves it where it was, and about the line between the two axes. With `p` a point
/// of the cylinder's axis and `d_S`, `d_C` the two unit directions (same sense), a point `x`
/// of the cylinder turned about the table axis lies within
/// `|φ| (dist(p, table axis) + |d_C − d_S| |x − p|)` of where turning it about its own axis
/// puts it, so the set moves by at most that much (its Hausdorff distance). `None` for
/// other shapes. 0 for the table itself (its cylinder is about the table axis); the caller
/// keeps the smaller of this and the plain lever arm, both bounds.
fn turned_cylinder(layout: Layout, shape: &SharedShape, local: &Pose) -> Option<f64> {
    let cylinder = shape.as_cylinder()?;
    let table_axis = match layout.table_axis() {
        Some(Axis::A) => Vector::X,
        _ => Vector::Z,
    };
    let mut d = local.rotation * Vector::Y;
    if d.dot(table_axis) < 0.0 {
        d = -d;
    }
    let p = local.translation;
    let off_axis = (p - table_axis * p.dot(table_axis)).length();
    let reach = cylinder.half_height.hypot(cylinder.radius);
    Some(off_axis + (table_axis - d).length() * reach)
}

/// Distance of table point `p` (mm) from the table axis: C (the table's Z), or A (its X)
/// for trt-ab.
fn from_table_axis(layout: Layout, p: [f64; 3]) -> f64 {
    match layout.table_axis() {
        Some(Axis::A) => p[1].hypot(p[2]),
        _ => p[0].hypot(p[1]),
    }
}

/// Collects parts and derives the monitored pairs from their groups.
struct Builder {
    kinematics: Kinematics,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    body_handles: [RigidBodyHandle; BODIES],
    parts: Vec<Part>,
    groups: Vec<InteractionGroups>,
    bar_motion: Option<[f64; 3]>,
    linked: Option<LinkedBodies>,
}

impl Builder {
    fn new(kinematics: Kinematics) -> Builder {
        let mut bodies = RigidBodySet::new();
        let body_handles: [RigidBodyHandle; BODIES] =
            std::array::from_fn(|_| bodies.insert(RigidBodyBuilder::kinematic_position_based()));
        Builder {
            kinematics,
            bodies,
            colliders: ColliderSet::new(),
            body_handles,
            parts: Vec::new(),
            groups: Vec::new(),
            bar_motion: None,
            linked: None,
        }
    }

    fn add(
        &mut self,
        name: &str,
        carrier: Carrier,
        shape: SharedShape,
        local: Pose,
        member: Group,
        filter: Group,
    ) {
        let groups = InteractionGroups::new(member, filter, InteractionTestMode::And);
        let collider = ColliderBuilder::new(shape.clone())
            .position(local)
            .collision_groups(groups)
            .density(0.0)
            .build();
        let handle = self.colliders.insert_with_parent(
            collider,
            self.body_handles[carrier as usize],
            &mut self.bodies,
        );
        let general = !self.kinematics.has_closed_form();
        let rides = match carrier {
            Carrier::Table => Rides::Table,
            Carrier::Cradle => Rides::Cradle,
            Carrier::Tool => Rides::Tool,
            Carrier::Head | Carrier::Bar => Rides::Head,
        };
        let motion = match (carrier, &self.linked) {
            (Carrier::Bar, _) => self.bar_motion.unwrap_or([0.0; 3]),
            (Carrier::Head, Some(linked)) => linked.weights(rides, &aabb_corners(&shape, &local)),
            (_, Some(linked)) if general => linked.weights(rides, &aabb_corners(&shape, &local)),
            _ => self.trt_motion(carrier, &shape, &local),
        };
        self.parts.push(Part {
            name: name.to_string(),
            carrier,
            handle,
            shape,
            local,
            motion,
            eroded: None,
            skin_mm: 0.0,
            analytic: None,
            prism: None,
        });
        self.groups.push(groups);
    }

    /// Adds `boxes` (cradle or head boxes) to `carrier`.
    fn add_boxes(&mut self, boxes: &[&CradleBox], carrier: Carrier, member: Group, filter: Group) {
        for b in boxes {
            let (shape, local) = shapes::cuboid(b.center_mm, b.size_mm);
            self.add(&b.name, carrier, shape, local, member, filter);
        }
    }

    /// A part's motion weights on a named layout: the tool stack moves with X Y Z, table
    /// and cradle parts by their lever arms about the pivot and the C axis.
    fn trt_motion(&self, carrier: Carrier, shape: &SharedShape, local: &Pose) -> [f64; 3] {
        match carrier {
            Carrier::Tool | Carrier::Head => [1.0, 0.0, 0.0],
            Carrier::Bar => self.bar_motion.unwrap_or([0.0; 3]),
            Carrier::Table | Carrier::Cradle => {
                // Points at distance |p| from the pivot and rho from the C axis move at
                // most |p| |d tilt| + rho |dC| (cradle parts do not turn with C).
                let aabb = shape.compute_aabb(&local);
                let (mut far, mut rho) = (0.0f64, 0.0f64);
                for i in 0..8 {
                    let x = if i & 1 == 0 { aabb.mins.x } else { aabb.maxs.x };
                    let y = if i & 2 == 0 { aabb.mins.y } else { aabb.maxs.y };
                    let z = if i & 4 == 0 { aabb.mins.z } else { aabb.maxs.z };
                    far = far.max((x * x + y * y + z * z).sqrt());
                    rho = rho.max(from_table_axis(self.kinematics.layout, [x, y, z]));
                }
                if carrier == Carrier::Table {
                    [
                        0.0,
                        far,
                        turned_cylinder(self.kinematics.layout, shape, local)
                            .map_or(rho, |w| w.min(rho)),
                    ]
                } else {
                    [0.0, far, 0.0]
                }
            }
        }
    }

    fn finish(
        self,
        bar: Option<BarEnds>,
        near_miss_mm: f64,
        engagement_resolution_mm: f64,
    ) -> Scene {
        let mut parts = self.parts;
        for part in &mut parts {
            part.analytic = Analytic::of(part.eroded.as_ref().unwrap_or(&part.shape));
            part.prism = prism::Prism::of(&part.shape);
        }
        let mut pairs = Vec::new();
        for a in 0..parts.len() {
            for b in a + 1..parts.len() {
                if parts[a].carrier == parts[b].carrier || !self.groups[a].test(self.groups[b]) {
                    continue;
                }
                let cutting = |x: usize, y: usize| {
                    self.groups[x].memberships == groups::CUTTER
                        && self.groups[y].memberships == groups::WORKPIECE
                };
                let kind = if cutting(a, b) || cutting(b, a) {
                    PairKind::Cutting
                } else {
                    PairKind::Collision
                };
                pairs.push(Pair { a, b, kind });
            }
        }
        let mut scene = Scene {
            chain: self.kinematics.cradle_table_poses(),
            tilt_axis: self.kinematics.layout.tilt_axis(),
            kinematics: self.kinematics,
            bodies: self.bodies,
            colliders: self.colliders,
            body_handles: self.body_handles,
            parts,
            pairs,
            bar,
            near_miss_mm,
            engagement_resolution_mm,
            depth_tolerance: DepthTolerance {
                mm: crate::input::scene::DEFAULT_DEPTH_TOLERANCE_MM,
                relative: crate::input::scene::DEFAULT_DEPTH_TOLERANCE_RELATIVE,
            },
            linked: self.linked,
        };
        scene.set_axes(&AxisVec::ZERO);
        scene
    }

    /// The table (a cylinder about its axis, Z or X) and the cradle's boxes. A riser or a
    /// ball-bar post stands on the table top, so it needs a table about Z.
    fn add_table(
        &mut self,
        machine: &Machine,
        workpiece: &WorkpieceConfig,
        all_tool: Group,
    ) -> Result<()> {
        let path = machine.path.as_path();
        let t = &machine.scene.table;
        let (shape, local) = z_cylinder(t.top_z_mm - t.thickness_mm, t.top_z_mm, t.radius_mm);
        let local = match t.axis {
            TableAxis::Z => local,
            // Ry(90 deg) takes the cylinder's +Z to +X.
            TableAxis::X => {
                Pose::from_parts(
                    Vector::ZERO,
                    Rotation::from_rotation_arc(Vector::Z, Vector::X),
                ) * local
            }
        };
        let stands_on_top = workpiece.kind == WorkpieceKind::BallBar
            || (workpiece.kind == WorkpieceKind::ConeFrustum && workpiece.riser);
        if t.axis != TableAxis::Z && stands_on_top {
            return Err(Error::invalid(path, "a riser or ball-bar post stands on a table about Z, but scene.table.axis is \"x\" (a faceplate): set workpiece.riser = false, or use a table about Z"));
        }
        self.add(
            "table",
            Carrier::Table,
            shape,
            local,
            groups::TABLE,
            all_tool,
        );
        let cradle = cradle_boxes(machine);
        self.add_boxes(&cradle, Carrier::Cradle, groups::TABLE, all_tool);
        Ok(())
    }

    /// The tool stack, tip at the origin, axis +Z: the cutter (or the ball of a ball bar),
    /// shank, holder and spindle, then the head's boxes.
    fn add_tool_stack(
        &mut self,
        machine: &Machine,
        tool: &ToolConfig,
        workpiece: &WorkpieceConfig,
    ) {
        let scene = &machine.scene;
        let ball_bar = workpiece.kind == WorkpieceKind::BallBar;
        let sides = groups::TABLE | groups::FIXTURE | groups::WORKPIECE;
        if ball_bar {
            let shape = SharedShape::ball(0.5 * workpiece.ball_diameter_mm);
            self.add(
                "tool ball",
                Carrier::Tool,
                shape,
                Pose::IDENTITY,
                groups::BALL,
                sides,
            );
        } else {
            let (shape, local) =
                z_cylinder(0.0, tool.flute_length_mm, 0.5 * tool.cutter_diameter_mm);
            self.add("cutter", Carrier::Tool, shape, local, groups::CUTTER, sides);
            let skin = CUTTER_SKIN_MM
                .min(0.25 * tool.cutter_diameter_mm)
                .min(0.25 * tool.flute_length_mm);
            let (eroded, _) = z_cylinder(
                skin,
                tool.flute_length_mm - skin,
                0.5 * tool.cutter_diameter_mm - skin,
            );
            if let Some(cutter) = self.parts.last_mut() {
                cutter.eroded = Some(eroded);
                cutter.skin_mm = skin;
            }
        }
        let tool_filter = sides | groups::BAR | groups::BALL;
        let shank_top = tool.flute_length_mm + tool.shank_length_mm;
        let (shape, local) = z_cylinder(
            tool.flute_length_mm,
            shank_top,
            0.5 * tool.shank_diameter_mm,
        );
        self.add(
            "shank",
            Carrier::Tool,
            shape,
            local,
            groups::TOOL,
            tool_filter,
        );
        let (shape, local) = z_cylinder(
            tool.holder_bottom_mm(),
            tool.gauge_length_mm,
            0.5 * tool.holder_diameter_mm,
        );
        self.add(
            "holder",
            Carrier::Tool,
            shape,
            local,
            groups::TOOL,
            tool_filter,
        );
        let sp = &scene.spindle;
        let top = tool.gauge_length_mm + sp.length_mm;
        let (shape, local) = match sp.shape {
            SpindleShape::Cylinder => z_cylinder(tool.gauge_length_mm, top, 0.5 * sp.diameter_mm),
            SpindleShape::Box => shapes::cuboid(
                [0.0, 0.0, 0.5 * (tool.gauge_length_mm + top)],
                [sp.box_mm[0], sp.box_mm[1], sp.length_mm],
            ),
        };
        self.add(
            "spindle",
            Carrier::Tool,
            shape,
            local,
            groups::TOOL,
            tool_filter,
        );
        let head: Vec<&CradleBox> = scene.head.iter().collect();
        self.add_boxes(&head, Carrier::Head, groups::TOOL, tool_filter);
    }

    /// The workpiece: a cone frustum (on its riser if it has one) or a ball bar's pivot
    /// ball, post and bar; where the bar's pivot is for a ball bar.
    fn add_workpiece(
        &mut self,
        machine: &Machine,
        tool: &ToolConfig,
        workpiece: &WorkpieceConfig,
        all_tool: Group,
    ) -> Result<Option<BarEnds>> {
        let path = machine.path.as_path();
        let t = &machine.scene.table;
        let sides = groups::TABLE | groups::FIXTURE | groups::WORKPIECE;
        let cone = &workpiece.cone;
        let o = Vector3::from(cone.center_mm);
        match workpiece.kind {
            WorkpieceKind::None => {}
            WorkpieceKind::ConeFrustum => {
                cone.check(path)?;
                let f = Frustum::new(cone, tool, workpiece.top_height_mm, path)?;
                let hull = CircleHull {
                    circles: [f.base, f.top],
                };
                self.add(
                    "workpiece",
                    Carrier::Table,
                    SharedShape::new(hull),
                    Pose::IDENTITY,
                    groups::WORKPIECE,
                    groups::CUTTER | groups::TOOL | groups::BALL,
                );
                if workpiece.riser {
                    let lowest = o.z - f.base.radius * f.base.normal.x.hypot(f.base.normal.y);
                    if lowest <= t.top_z_mm {
                        return Err(Error::invalid(path, format!(
                                "the cone's base circle reaches down to z = {lowest:.3} mm in the table frame, at or below the table top ({} mm): raise the cone centre or lower scene.table.top_z_mm",
                                t.top_z_mm
                            )));
                    }
                    let foot = Circle {
                        centre: Vector::new(o.x, o.y, t.top_z_mm),
                        normal: Vector::Z,
                        radius: f.base.radius,
                    };
                    let riser = CircleHull {
                        circles: [f.base, foot],
                    };
                    self.add(
                        "riser",
                        Carrier::Table,
                        SharedShape::new(riser),
                        Pose::IDENTITY,
                        groups::FIXTURE,
                        all_tool,
                    );
                }
            }
            WorkpieceKind::BallBar => {
                cone.check(path)?;
                let r_ball = 0.5 * workpiece.ball_diameter_mm;
                let length = cone.ballbar_length_mm;
                if length <= 2.0 * r_ball {
                    return Err(Error::invalid(path, format!("the ball-bar length ({length} mm) must exceed the ball diameter ({} mm)", workpiece.ball_diameter_mm)));
                }
                let post_top = o.z - r_ball;
                if post_top <= t.top_z_mm {
                    return Err(Error::invalid(path, format!(
                            "the pivot ball at z = {} mm in the table frame does not clear the table top ({} mm): raise the cone centre or lower scene.table.top_z_mm",
                            o.z, t.top_z_mm
                        )));
                }
                let ball = SharedShape::ball(r_ball);
                let at_o = Pose::from_translation(Vector::new(o.x, o.y, o.z));
                self.add(
                    "pivot ball",
                    Carrier::Table,
                    ball,
                    at_o,
                    groups::BALL,
                    groups::TOOL | groups::CUTTER,
                );
                let (shape, local) =
                    z_cylinder(t.top_z_mm, post_top, 0.5 * workpiece.post_diameter_mm);
                let local = Pose::from_translation(Vector::new(o.x, o.y, 0.0)) * local;
                self.add(
                    "post",
                    Carrier::Table,
                    shape,
                    local,
                    groups::FIXTURE,
                    all_tool,
                );
                let r_bar = 0.5 * workpiece.bar_diameter_mm;
                let (shape, local) = z_cylinder(r_ball, length - r_ball, r_bar);
                self.bar_motion = Some(match &self.linked {
                    Some(linked) if !machine.kinematics.has_closed_form() => {
                        chain_bar_motion(linked, o, length, r_bar)
                    }
                    _ => bar_motion(machine.kinematics.layout, o, length, r_bar),
                });
                self.add(
                    "bar",
                    Carrier::Bar,
                    shape,
                    local,
                    groups::BAR,
                    sides | groups::TOOL,
                );
                return Ok(Some(BarEnds { pivot: o }));
            }
        }
        Ok(None)
    }
}

/// Signed distance of `pair` (parts `a`, `b` at world poses `pa`, `pb`), mm. A cutting
/// pair is measured from the eroded cutter (see [`CUTTER_SKIN_MM`]). Two prisms with
/// parallel axes (a cylinder against a cylinder or a box) take their closed form
/// ([`prism::signed_distance`]); a cylinder against a frustum takes the certified closed
/// form ([`frustum::signed_distance`]) when its bounds meet; parry's GJK/EPA
/// ([`signed_distance`]) answers the rest.
fn pair_distance(pair: &Pair, a: &Part, b: &Part, pa: &Pose, pb: &Pose, warm: &mut Warm) -> f64 {
    warm.prism = false;
    if let (PairKind::Collision, Some(prism_a), Some(prism_b)) = (pair.kind, a.prism, b.prism) {
        if let Some((d, n)) = prism::signed_distance(&prism_a, pa, &prism_b, pb) {
            // The direction that attains it separates the two (GJK's next start).
            warm.gjk = Some(n);
            warm.prism = true;
            return d;
        }
    }
    let skin = if pair.kind == PairKind::Cutting {
        a.skin_mm + b.skin_mm
    } else {
        0.0
    };
    let analytic = match (a.analytic, b.analytic) {
        (Some(Analytic::Frustum(f)), Some(Analytic::Cylinder(h, r))) => Some((f, pa, h, r, pb)),
        (Some(Analytic::Cylinder(h, r)), Some(Analytic::Frustum(f))) => Some((f, pb, h, r, pa)),
        _ => None,
    };
    if let Some((f, frustum_pose, half_height, radius, cylinder_pose)) = analytic {
        // The cylinder in the frustum's frame; parry's cylinder axis is its local Y.
        let rel = frustum_pose.inv_mul(cylinder_pose);
        let cylinder = frustum::Cylinder {
            c: rel.translation,
            t: rel.rotation * Vector::Y,
            half_height,
            radius,
        };
        // The frustum is symmetric about its axis: the direction found last time, turned
        // about the axis as far as the cylinder's centre has turned since, is nearly the
        // one that certifies now (the table turns under the tool on the cone test).
        let start = warm.normal.map(|(n, c)| f.turned(n, c, cylinder.c));
        if let Some((d, n)) = frustum::signed_distance(&f, &cylinder, start) {
            warm.normal = Some((n, cylinder.c));
            return d - skin;
        }
        warm.normal = None;
    }
    if pair.kind == PairKind::Cutting {
        let shape = |p: &Part| p.eroded.as_ref().unwrap_or(&p.shape).clone();
        return signed_distance(pa, shape(a).as_ref(), pb, shape(b).as_ref(), &mut warm.gjk) - skin;
    }
    signed_distance(pa, a.shape.as_ref(), pb, b.shape.as_ref(), &mut warm.gjk)
}

/// Certified bounds `lo <= sd <= hi` (mm) on the signed distance of a cylinder/frustum pair
/// (`pair`, parts `a`, `b` at world poses `pa`, `pb`) from its warm start alone
/// ([`frustum::bounds`] at the last certifying direction, turned with the cylinder about the
/// frustum's axis): a few support evaluations instead of a query. `None` without a warm
/// start or for other shapes. The skin of a cutting pair is taken off as in
/// [`pair_distance`], whose answer lies within these bounds.
fn warm_bounds(
    pair: &Pair,
    a: &Part,
    b: &Part,
    pa: &Pose,
    pb: &Pose,
    warm: &Warm,
) -> Option<(f64, f64)> {
    let (n, from) = warm.normal?;
    let (f, frustum_pose, half_height, radius, cylinder_pose) = match (a.analytic, b.analytic) {
        (Some(Analytic::Frustum(f)), Some(Analytic::Cylinder(h, r))) => (f, pa, h, r, pb),
        (Some(Analytic::Cylinder(h, r)), Some(Analytic::Frustum(f))) => (f, pb, h, r, pa),
        _ => return None,
    };
    let rel = frustum_pose.inv_mul(cylinder_pose);
    let cylinder = frustum::Cylinder {
        c: rel.translation,
        t: rel.rotation * Vector::Y,
        half_height,
        radius,
    };
    let skin = match pair.kind {
        PairKind::Cutting => a.skin_mm + b.skin_mm,
        PairKind::Collision => 0.0,
    };
    let (lo, hi) = frustum::bounds(&f, &cylinder, f.turned(n, from, cylinder.c))?;
    Some((lo - skin, hi - skin))
}

fn to_vector(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

fn to_pose(iso: &Isometry3<f64>) -> Pose {
    let c = iso.rotation.coords; // (i, j, k, w)
    Pose::from_parts(
        to_vector(&iso.translation.vector),
        Rotation::from_xyzw(c.x, c.y, c.z, c.w),
    )
}

/// The cradle boxes the scene builds: all on a named layout; on a general chain those with
/// a `link` (the default trunnion, written for the tilting tables, is not built there).
fn cradle_boxes(machine: &Machine) -> Vec<&CradleBox> {
    let scene = &machine.scene;
    if !machine.kinematics.has_closed_form()
        && scene.cradle == crate::input::scene::SceneConfig::default().cradle
    {
        return Vec::new();
    }
    scene.cradle.iter().collect()
}

/// The links the bodies ride on: on a general chain, its actual chain with the cradle boxes
/// on the table axes up to their `link` and the head boxes on the head axes up to theirs;
/// on a named layout, only when it has head boxes (on X, Y or Z). One link per list.
fn linked_bodies(machine: &Machine) -> Result<Option<LinkedBodies>> {
    let k = &machine.kinematics;
    let scene = &machine.scene;
    let path = machine.path.as_path();
    let general = !k.has_closed_form();
    let chain = match (k.actual_chain(), k.chain()) {
        (Some(actual), _) => actual,
        (None, Some(named)) if !scene.head.is_empty() => named,
        (None, None) if !scene.head.is_empty() => {
            return Err(Error::invalid(path, format!("[[scene.head]] boxes ride on the head's axes, which the {} layout does not model", k.layout.name())));
        }
        _ => {
            // A named layout's cradle is its tilting axis's: a `link` must name it.
            for b in &scene.cradle {
                if let Some(link) = &b.link {
                    let tilt = k.layout.tilt_axis().map(|a| a.to_string());
                    if tilt.as_deref() != Some(link.as_str()) {
                        return Err(Error::invalid(path, format!("scene.cradle box {:?}: link = {link:?}, but the cradle of the {} layout rides on its tilting axis ({}): remove the key", b.name, k.layout.name(), tilt.unwrap_or_else(|| "none".into()))));
                    }
                }
            }
            return Ok(None);
        }
    };
    let one_link = |section: &str,
                    boxes: &[&CradleBox],
                    links: &[crate::kinematics::Link]|
     -> Result<usize> {
        let mut found: Option<(String, usize)> = None;
        for b in boxes {
            let Some(link) = &b.link else {
                return Err(Error::invalid(path, format!("{section} box {:?}: give `link`, the axis it is attached after (one of {})", b.name, names(links))));
            };
            let n = Axis::from_letter(link.chars().next().unwrap_or(' '))
                .filter(|_| link.chars().count() == 1)
                .and_then(|a| LinkedBodies::prefix(links, a))
                .ok_or_else(|| Error::invalid(path, format!("{section} box {:?}: link = {link:?} is not an axis of that side of the chain (one of {})", b.name, names(links))))?;
            match &found {
                Some((first, _)) if first != link => {
                    return Err(Error::invalid(path, format!("{section} boxes must all ride on one link; {:?} names {link:?}, an earlier box {first:?}", b.name)));
                }
                _ => found = Some((link.clone(), n)),
            }
        }
        Ok(found.map_or(0, |(_, n)| n))
    };
    let cradle: Vec<&CradleBox> = if general {
        cradle_boxes(machine)
    } else {
        Vec::new()
    };
    let cradle_links = one_link("scene.cradle", &cradle, chain.table())?;
    let head: Vec<&CradleBox> = scene.head.iter().collect();
    let head_links = one_link("scene.head", &head, chain.head())?;
    Ok(Some(LinkedBodies::new(
        machine,
        chain,
        cradle_links,
        head_links,
    )))
}

fn names(links: &[crate::kinematics::Link]) -> String {
    let v: Vec<String> = links.iter().map(|l| l.axis.to_string()).collect();
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}
