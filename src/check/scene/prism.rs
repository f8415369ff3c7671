//! The signed distance of two right prisms whose axes are parallel, in closed form: a
//! cylinder against a cylinder, or a cylinder against a box with one of its edges along the
//! cylinder's axis. On a three-axis machine, and on a five-axis one whose table is level,
//! the table, the tool stack and the cradle boxes all stand that way, and GJK/EPA (deep
//! penetrations cost EPA about 30 µs) is not needed.
//!
//! A prism is a convex section `P` swept along its axis over `[−h, h]`. Two prisms with
//! parallel axes, B's centre at `c` in A's frame, overlap where `c` lies in the Minkowski
//! difference `(P_A ⊕ −P_B) × [−(h_A + h_B), h_A + h_B]`, a prism again, so the signed
//! distance (the clearance, or minus the penetration depth) is that of the point `c` to it.
//! Of a product of convex sets, with `ρ` the section's signed distance at `c`'s section
//! coordinates and `ζ = |c_axis| − (h_A + h_B)`:
//!
//! ```text
//! sd = hypot(max(ρ, 0), max(ζ, 0))   when ρ > 0 or ζ > 0 (apart)
//! sd = max(ρ, ζ)                      otherwise (the shallower way out)
//! ```
//!
//! Two discs of radii `r_A`, `r_B` give the disc of radius `r_A + r_B`:
//! `ρ = |c_section| − (r_A + r_B)`. A rectangle of half sides `(e_i, e_j)` and a disc of
//! radius `r` give the rectangle rounded by `r`: `ρ = sd_rect(c_i, c_j) − r`, with
//! `sd_rect` the rectangle's 2-D signed distance.
//!
//! Axes that are parallel only to the last bits are snapped: turning one prism about its
//! centre by the small angle `θ` between the axes moves its points by at most `θ·reach`
//! (its largest distance from the centre), and the signed distance, as a function of the
//! two sets, moves by at most the Hausdorff distance between them. The closed form is
//! used only where `θ·reach` is at most [`SNAP_MM`].

use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::shape::SharedShape;

/// How far (mm) the snap of nearly parallel axes may move a prism's points: the closed form
/// is then within this much of the exact signed distance.
pub const SNAP_MM: f64 = 1e-9;

/// A scene part that is a right prism, in its local frame (parry's shapes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Prism {
    /// A cylinder along its local Y axis: half height and radius, mm.
    Cylinder { half_height: f64, radius: f64 },
    /// A box: half side lengths along its local X, Y, Z, mm.
    Cuboid { half: [f64; 3] },
}

impl Prism {
    /// The prism of a parry cylinder or cuboid, `None` for other shapes.
    pub fn of(shape: &SharedShape) -> Option<Prism> {
        if let Some(c) = shape.as_cylinder() {
            return Some(Prism::Cylinder {
                half_height: c.half_height,
                radius: c.radius,
            });
        }
        shape.as_cuboid().map(|b| Prism::Cuboid {
            half: b.half_extents.to_array(),
        })
    }

    /// Largest distance of a point of the prism from its centre, mm.
    fn reach(&self) -> f64 {
        match *self {
            Prism::Cylinder {
                half_height,
                radius,
            } => norm2(half_height, radius),
            Prism::Cuboid { half } => (half[0].powi(2) + half[1].powi(2) + half[2].powi(2)).sqrt(),
        }
    }
}

/// Signed distance (mm) of prisms `a` at pose `pa` and `b` at `pb`, with the unit direction
/// out of `a` toward `b` in `a`'s frame that attains it (a separating direction for the
/// plane bound and GJK's warm start), when their axes are parallel (to [`SNAP_MM`]) and
/// one of them is a cylinder; `None` otherwise.
pub fn signed_distance(a: &Prism, pa: &Pose, b: &Prism, pb: &Pose) -> Option<(f64, Vector)> {
    match (*a, *b) {
        (
            Prism::Cylinder {
                half_height: ha,
                radius: ra,
            },
            Prism::Cylinder {
                half_height: hb,
                radius: rb,
            },
        ) => {
            // B in A's frame; both axes along Y.
            let rel = pa.inv_mul(pb);
            let t = rel.rotation * Vector::Y;
            if !snaps(norm2(t.x, t.z), t.y, b.reach()) {
                return None;
            }
            let c = rel.translation;
            let (radial, out) = disc(c.x, c.z, ra + rb);
            Some(combine(
                radial,
                Vector::new(out.0, 0.0, out.1),
                c.y.abs() - (ha + hb),
                Vector::new(0.0, sign(c.y), 0.0),
            ))
        }
        (Prism::Cylinder { .. }, Prism::Cuboid { half }) => {
            // The cylinder in the box's frame; the direction comes out of the box.
            let rel = pb.inv_mul(pa);
            let (d, n) = cylinder_box(a, &rel, half)?;
            Some((d, rel.rotation.inverse() * -n))
        }
        (Prism::Cuboid { half }, Prism::Cylinder { .. }) => cylinder_box(b, &pa.inv_mul(pb), half),
        (Prism::Cuboid { .. }, Prism::Cuboid { .. }) => None,
    }
}

/// A cylinder at pose `rel` in a box's frame (half sides `half`) whose axis lies along one
/// of the box's axes: the signed distance and the unit direction out of the box, in its
/// frame.
fn cylinder_box(cylinder: &Prism, rel: &Pose, half: [f64; 3]) -> Option<(f64, Vector)> {
    let Prism::Cylinder {
        half_height,
        radius,
    } = *cylinder
    else {
        return None;
    };
    let t = (rel.rotation * Vector::Y).to_array();
    // The box axis the cylinder's runs along, and the two across it.
    let k = (0..3).fold(0, |k, m| if t[m].abs() > t[k].abs() { m } else { k });
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    if !snaps(norm2(t[i], t[j]), t[k], cylinder.reach()) {
        return None;
    }
    let c = rel.translation.to_array();
    let (qi, qj) = (c[i].abs() - half[i], c[j].abs() - half[j]);
    let (rect, (ui, uj)) = if qi > 0.0 || qj > 0.0 {
        let (oi, oj) = (qi.max(0.0), qj.max(0.0));
        let len = norm2(oi, oj);
        (len, (sign(c[i]) * oi / len, sign(c[j]) * oj / len))
    } else if qi >= qj {
        (qi, (sign(c[i]), 0.0))
    } else {
        (qj, (0.0, sign(c[j])))
    };
    let mut across = [0.0; 3];
    across[i] = ui;
    across[j] = uj;
    let mut along = [0.0; 3];
    along[k] = sign(c[k]);
    Some(combine(
        rect - radius,
        Vector::from_array(across),
        c[k].abs() - (half[k] + half_height),
        Vector::from_array(along),
    ))
}

/// Whether axes at sine `cross` and cosine `dot` of each other may be snapped parallel: the
/// angle, at most `π/2 · cross` (anti-parallel counts as parallel), times the reach of the
/// prism turned, is within [`SNAP_MM`].
fn snaps(cross: f64, dot: f64, reach: f64) -> bool {
    dot.abs() > 0.5 && cross * std::f64::consts::FRAC_PI_2 * reach <= SNAP_MM
}

/// Signed distance of the point `(x, y)` to the disc of radius `r` about the origin, with
/// the unit direction away from the centre (`(1, 0)` at the centre).
fn disc(x: f64, y: f64, r: f64) -> (f64, (f64, f64)) {
    let len = norm2(x, y);
    let dir = if len > 0.0 {
        (x / len, y / len)
    } else {
        (1.0, 0.0)
    };
    (len - r, dir)
}

/// The signed distance to a product of a section (signed distance `radial`, outward
/// direction `across`) and an interval (`axial`, `along`), with the direction that
/// attains it (see the module's doc).
fn combine(radial: f64, across: Vector, axial: f64, along: Vector) -> (f64, Vector) {
    if radial > 0.0 || axial > 0.0 {
        let (r, z) = (radial.max(0.0), axial.max(0.0));
        let d = norm2(r, z);
        (d, (across * r + along * z) / d)
    } else if radial >= axial {
        (radial, across)
    } else {
        (axial, along)
    }
}

/// `sqrt(x² + y²)`: lengths of the scene (mm, far from overflow), without `hypot`'s care,
/// which costs as much as the rest of a query.
#[inline]
pub(crate) fn norm2(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// `+1` or `−1`, `+1` at zero.
fn sign(x: f64) -> f64 {
    if x < 0.0 {
        -1.0
    } else {
        1.0
    }
}
