//! A certified lower bound on a collision pair's signed distance from one separating
//! direction, kept from the pair's last query: a part held in a collision (or a near miss)
//! while the program runs on need not be measured at every sample to know that it got no
//! deeper (no nearer).
//!
//! For convex parts A and B, with B at the pose `(R, t)` in A's frame, the gap along any unit
//! direction `n` (out of A, in A's frame) is
//!
//! ```text
//! g_n(R, t) = n·t − h_A(n) − h_B(−Rᵀ n)        (h: support function, h_S(u) = max_{x∈S} u·x)
//! ```
//!
//! and it never exceeds the signed distance: apart, the distance is the largest gap over all
//! directions; overlapping, the penetration depth is the smallest overlap `−g_n` over all
//! directions. So `g_n` with the direction of the last query is a lower bound at every later
//! pose, whatever the accuracy of `n`: `h_A(n)` is kept, and each look costs B's pose in A's
//! frame and one support point of B. Moving parallel to the face the query found (a cut
//! along a wall, a table turning under a spindle that sits in it) leaves the bound where it
//! was, where the lever-arm bound grows with the path.
//!
//! When A is a cylinder (its axis parry's local Y) any direction turned about that axis has
//! the same `h_A`, so the direction is turned with B: by the angle from B's centre's
//! azimuth about the axis at the query to its azimuth now (`(x, z)` of the centre, turned
//! as a 2-D vector). A table turning under the tool then leaves the bound where it was, as
//! for a face the tool moves along.

use parry3d_f64::math::{Pose, Vector};

use super::{BodyPoses, Scene};

/// The separating direction of one pair at its last query.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PlaneBound {
    /// The direction, unit, out of A (A's frame).
    n: Vector,
    /// `h_A(n)`, mm.
    support_a: f64,
    /// When A is a cylinder: the unit `(x, z)` of B's centre at the query (A's frame), the
    /// azimuth the direction is turned from.
    azimuth: Option<(f64, f64)>,
}

/// `(x, z)` of `v` as a unit 2-D vector (the azimuth about a cylinder's Y axis), `None` on
/// the axis.
fn azimuth(v: Vector) -> Option<(f64, f64)> {
    let len = super::prism::norm2(v.x, v.z);
    (len > 1e-9).then(|| (v.x / len, v.z / len))
}

impl Scene {
    /// Pair `i`'s parts: B's pose in A's frame at the sample of `poses`.
    fn relative_pose(&self, i: usize, poses: &mut BodyPoses) -> Pose {
        let pair = self.pairs[i];
        let (a, b) = (&self.parts[pair.a], &self.parts[pair.b]);
        let pose_a = self.body_pose(a.carrier as usize, poses) * a.local;
        let pose_b = self.body_pose(b.carrier as usize, poses) * b.local;
        pose_a.inv_mul(&pose_b)
    }

    /// The plane bound of collision pair `i` along `direction` (A's frame; the query's warm
    /// start), or `None` without a usable direction.
    /// `poses` are those of the query.
    pub(crate) fn plane_bound(
        &self,
        i: usize,
        direction: Option<Vector>,
        poses: &mut BodyPoses,
    ) -> Option<PlaneBound> {
        let n = direction?.try_normalize()?;
        let a = &self.parts[self.pairs[i].a];
        let support_a = n.dot(a.shape.as_support_map()?.local_support_point(n));
        let azimuth = match a.shape.as_cylinder() {
            Some(_) => azimuth(self.relative_pose(i, poses).translation),
            None => None,
        };
        support_a.is_finite().then_some(PlaneBound {
            n,
            support_a,
            azimuth,
        })
    }

    /// `g_n`: a lower bound on pair `i`'s signed distance at the sample of `poses`, mm.
    pub(crate) fn plane_lower(&self, i: usize, poses: &mut BodyPoses, plane: &PlaneBound) -> f64 {
        let b = &self.parts[self.pairs[i].b];
        let Some(support) = b.shape.as_support_map() else {
            return f64::NEG_INFINITY;
        };
        let rel = self.relative_pose(i, poses);
        let mut n = plane.n;
        if let (Some((x0, z0)), Some((x1, z1))) = (plane.azimuth, azimuth(rel.translation)) {
            // The 2-D rotation taking the query's azimuth to this one, applied to (n_x, n_z).
            let (cos, sin) = (x0 * x1 + z0 * z1, x0 * z1 - z0 * x1);
            n = Vector::new(cos * n.x - sin * n.z, n.y, sin * n.x + cos * n.z);
        }
        let into_b = rel.rotation.inverse() * -n;
        n.dot(rel.translation) - plane.support_a - into_b.dot(support.local_support_point(into_b))
    }
}
