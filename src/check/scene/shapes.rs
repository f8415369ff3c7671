//! Convex shapes of the scene and the one signed-distance query every check uses.
//!
//! parry's cylinders are aligned to their local Y axis; every cylinder of the scene is
//! made by [`z_cylinder`], which rotates it once so that its extent is along Z. The
//! workpiece frustum and its riser have no parry primitive: [`CircleHull`] is the convex
//! hull of two circles in space, with an exact support function, so the cutter's flank
//! can be tangent to the frustum without faceting error.

use parry3d_f64::bounding_volume::{Aabb, BoundingSphere};
use parry3d_f64::mass_properties::MassProperties;
use parry3d_f64::math::{Pose, Real, Rotation, Vector};
use parry3d_f64::query::details::contact_support_map_support_map_with_params;
use parry3d_f64::query::details::local_ray_intersection_with_support_map_with_params;
use parry3d_f64::query::gjk::{GJKResult, VoronoiSimplex};
use parry3d_f64::query::point::local_point_projection_on_support_map;
use parry3d_f64::query::{PointProjection, PointQuery, Ray, RayCast, RayIntersection};
use parry3d_f64::shape::{FeatureId, Shape, ShapeType, SharedShape, SupportMap, TypedShape};

/// A cylinder of `radius_mm` whose axis is the local Z axis, spanning `z_from_mm..z_to_mm`.
///
/// parry's [`parry3d_f64::shape::Cylinder`] spans `-half_height..half_height` along Y; the
/// returned pose rotates it by +90 deg about X (which carries +Y onto +Z) and moves its
/// centre to `z = (z_from + z_to) / 2`. Compose the pose with the carrying body's pose.
pub fn z_cylinder(z_from_mm: f64, z_to_mm: f64, radius_mm: f64) -> (SharedShape, Pose) {
    let half_height = 0.5 * (z_to_mm - z_from_mm).abs();
    let centre = 0.5 * (z_from_mm + z_to_mm);
    let pose = Pose::from_parts(
        Vector::new(0.0, 0.0, centre),
        Rotation::from_rotation_x(std::f64::consts::FRAC_PI_2),
    );
    (SharedShape::cylinder(half_height, radius_mm), pose)
}

/// A box of full side lengths `size_mm` centred at `centre_mm` (parry's cuboid takes half
/// extents).
pub fn cuboid(centre_mm: [f64; 3], size_mm: [f64; 3]) -> (SharedShape, Pose) {
    (
        SharedShape::cuboid(0.5 * size_mm[0], 0.5 * size_mm[1], 0.5 * size_mm[2]),
        Pose::from_translation(Vector::from_array(centre_mm)),
    )
}

/// One circle in space: centre, unit normal, radius (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Circle {
    pub centre: Vector,
    pub normal: Vector,
    pub radius: f64,
}

impl Circle {
    /// The point of the circle farthest along `dir`:
    /// `c + r * unit(dir - (dir . n) n)`, or the centre when `dir` is along the normal.
    fn support(&self, dir: Vector) -> Vector {
        let in_plane = dir - self.normal * dir.dot(self.normal);
        match in_plane.try_normalize() {
            Some(u) => self.centre + u * self.radius,
            None => self.centre,
        }
    }
}

/// The convex hull of two circles: a frustum when they are coaxial, a cylinder when their
/// radii are also equal, a skewed riser otherwise.
///
/// Support function: `s(d) = argmax(d . s0(d), d . s1(d))` over the two circles' support
/// points; the hull's support point is the better of its parts', which is exact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircleHull {
    pub circles: [Circle; 2],
}

impl SupportMap for CircleHull {
    fn local_support_point(&self, dir: Vector) -> Vector {
        let a = self.circles[0].support(dir);
        let b = self.circles[1].support(dir);
        if a.dot(dir) >= b.dot(dir) {
            a
        } else {
            b
        }
    }
}

impl CircleHull {
    fn aabb(&self) -> Aabb {
        let mut mins = Vector::ZERO;
        let mut maxs = Vector::ZERO;
        for i in 0..3 {
            let mut axis = Vector::ZERO;
            axis[i] = 1.0;
            maxs[i] = self.local_support_point(axis)[i];
            mins[i] = self.local_support_point(-axis)[i];
        }
        Aabb::new(mins, maxs)
    }
}

impl RayCast for CircleHull {
    fn cast_local_ray_and_get_normal(
        &self,
        ray: &Ray,
        max_time_of_impact: Real,
        solid: bool,
    ) -> Option<RayIntersection> {
        local_ray_intersection_with_support_map_with_params(
            self,
            &mut VoronoiSimplex::new(),
            ray,
            max_time_of_impact,
            solid,
        )
    }
}

impl PointQuery for CircleHull {
    fn project_local_point(&self, pt: Vector, solid: bool) -> PointProjection {
        local_point_projection_on_support_map(self, &mut VoronoiSimplex::new(), pt, solid)
    }

    fn project_local_point_and_get_feature(&self, pt: Vector) -> (PointProjection, FeatureId) {
        (self.project_local_point(pt, false), FeatureId::Unknown)
    }
}

impl Shape for CircleHull {
    fn compute_local_aabb(&self) -> Aabb {
        self.aabb()
    }

    fn compute_local_bounding_sphere(&self) -> BoundingSphere {
        let aabb = self.aabb();
        BoundingSphere::new(aabb.center(), 0.5 * (aabb.maxs - aabb.mins).length())
    }

    fn clone_dyn(&self) -> Box<dyn Shape> {
        Box::new(*self)
    }

    fn scale_dyn(&self, _scale: Vector, _num_subdivisions: u32) -> Option<Box<dyn Shape>> {
        None
    }

    /// The bodies are kinematic: mass is never used. A box of the hull's bounds stands in.
    fn mass_properties(&self, density: Real) -> MassProperties {
        let aabb = self.aabb();
        let he = aabb.half_extents();
        let mut props = MassProperties::from_cuboid(density, he);
        props.local_com = aabb.center();
        props
    }

    fn shape_type(&self) -> ShapeType {
        ShapeType::Custom
    }

    fn as_typed_shape(&self) -> TypedShape<'_> {
        TypedShape::Custom(self)
    }

    fn ccd_thickness(&self) -> Real {
        self.circles[0].radius.min(self.circles[1].radius)
    }

    fn ccd_angular_thickness(&self) -> Real {
        std::f64::consts::FRAC_PI_4
    }

    fn as_support_map(&self) -> Option<&dyn SupportMap> {
        Some(self as &dyn SupportMap)
    }
}

/// Signed distance between two convex shapes, mm: the clearance when apart, minus the
/// penetration depth when overlapping.
///
/// Apart, GJK gives the clearance. Overlapping, EPA gives a depth `p` and normal `n`; EPA is
/// unreliable when the overlap is a near-tangent line contact (the cutter's flank on the
/// frustum), so the result is checked: shape 2 moved out by `p + m` along `n` must stand
/// off by `m`. If not, the depth is taken as the smallest translation along `n` (or along
/// the warm-start normal) that separates the shapes, found by bisection with GJK; that is
/// an upper bound on the true depth, and equals it along the true contact normal.
///
/// `warm_start` is a direction in shape 1's local frame from the previous query of the
/// same pair; it is replaced by this query's contact normal.
pub fn signed_distance(
    pose1: &Pose,
    shape1: &dyn Shape,
    pose2: &Pose,
    shape2: &dyn Shape,
    warm_start: &mut Option<Vector>,
) -> f64 {
    let (Some(g1), Some(g2)) = (shape1.as_support_map(), shape2.as_support_map()) else {
        unreachable!("every scene shape is convex with a support map");
    };
    let pos12 = pose1.inv_mul(pose2);
    let previous = warm_start.filter(|d| d.is_finite() && d.length_squared() > 0.0);
    let Some((distance, normal)) = gjk_epa(&pos12, g1, g2, previous) else {
        *warm_start = None;
        return 0.0;
    };
    if distance >= 0.0 {
        *warm_start = Some(normal);
        return distance;
    }
    let depth = -distance;
    if (clearance_after_shift(&pos12, g1, g2, normal, depth + PROBE_MM) - PROBE_MM).abs() <= 1e-6 {
        *warm_start = Some(normal);
        return distance;
    }
    let mut best = (
        directional_depth(&pos12, g1, g2, normal, depth + PROBE_MM),
        normal,
    );
    if let Some(n) = previous.and_then(|n| n.try_normalize()) {
        let along = directional_depth(&pos12, g1, g2, n, best.0);
        if along < best.0 {
            best = (along, n);
        }
    }
    *warm_start = Some(best.1);
    -best.0
}

/// Stand-off used to check an EPA depth, mm.
const PROBE_MM: f64 = 1e-3;

/// GJK, then EPA when the shapes overlap: (signed distance, unit normal out of shape 1 in
/// its local frame).
fn gjk_epa(
    pos12: &Pose,
    g1: &dyn SupportMap,
    g2: &dyn SupportMap,
    init: Option<Vector>,
) -> Option<(f64, Vector)> {
    let mut simplex = VoronoiSimplex::new();
    match contact_support_map_support_map_with_params(pos12, g1, g2, 1e12, &mut simplex, init) {
        GJKResult::ClosestPoints(p1, p2, normal) => Some(((p2 - p1).dot(normal), normal)),
        _ => None,
    }
}

/// Clearance (0 if still overlapping) after moving shape 2 by `shift` along `n` (shape 1's
/// local frame).
fn clearance_after_shift(
    pos12: &Pose,
    g1: &dyn SupportMap,
    g2: &dyn SupportMap,
    n: Vector,
    shift: f64,
) -> f64 {
    let moved = Pose::from_translation(n * shift) * *pos12;
    match gjk_epa(&moved, g1, g2, Some(n)) {
        Some((d, _)) => d.max(0.0),
        None => 0.0,
    }
}

/// Smallest translation of shape 2 along `n` that separates the shapes, searched in
/// `[0, upper]` to 1e-9 mm (returns `upper` if even that does not separate them).
fn directional_depth(
    pos12: &Pose,
    g1: &dyn SupportMap,
    g2: &dyn SupportMap,
    n: Vector,
    upper: f64,
) -> f64 {
    let (mut lo, mut hi) = (0.0, upper);
    if clearance_after_shift(pos12, g1, g2, n, hi) <= 0.0 {
        return upper;
    }
    while hi - lo > 1e-9 {
        let mid = 0.5 * (lo + hi);
        if clearance_after_shift(pos12, g1, g2, n, mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}
