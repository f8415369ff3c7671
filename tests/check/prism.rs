//! The closed-form distance of parallel prisms (`src/check/scene/prism.rs`) against values
//! worked by hand and against parry's support maps and GJK on random poses.
//!
//! On random poses the closed form's answer `d` with its direction `n` is checked from
//! outside it: the gap along `n` taken from parry's support points,
//! `g_n = n·t − h_A(n) − h_B(−Rᵀ n)`, must equal `d` (so the signed distance is at least
//! `d`: `g_n` never exceeds it), and no other direction may give a larger gap (the signed
//! distance is the largest gap over all directions; 600 random directions plus the axis and
//! the section's coordinate directions). Apart, GJK's distance (of two points of the
//! shapes, so never below the true one) must lie within 1e-6 mm + 1e-7 of it above `d`.

use mtsim::check::scene::prism::{self, Prism, SNAP_MM};
use mtsim::check::scene::{signed_distance, z_cylinder};
use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::shape::SharedShape;

use super::equivalence::Lcg;

/// The gap between `a` at `pa` and `b` at `pb` along unit `n` (out of `a`, in `a`'s frame),
/// from parry's support points.
fn gap(a: &SharedShape, pa: &Pose, b: &SharedShape, pb: &Pose, n: Vector) -> f64 {
    let rel = pa.inv_mul(pb);
    let (sa, sb) = (a.as_support_map().unwrap(), b.as_support_map().unwrap());
    let into_b = rel.rotation.inverse() * -n;
    n.dot(rel.translation)
        - n.dot(sa.local_support_point(n))
        - into_b.dot(sb.local_support_point(into_b))
}

/// A table (z from -60 to 0, radius 200) and a shank (radius 10, 40 to 100 mm above the tip)
/// standing in it: the shank spanning the table's whole thickness is 60 mm deep (up and down
/// both 60 mm out), 1 mm higher 59 mm (up), beside the table 5 mm clear (radially), above
/// it 3 mm clear; a table tilted by 1 mrad is not parallel.
#[test]
fn parallel_cylinders_and_boxes_give_the_distances_worked_by_hand() {
    let (table, table_local) = z_cylinder(-60.0, 0.0, 200.0);
    let (shank, shank_local) = z_cylinder(40.0, 100.0, 10.0);
    let (pt, ps) = (Prism::of(&table).unwrap(), Prism::of(&shank).unwrap());
    let at = |x: f64, tip_z: f64| Pose::from_translation(Vector::new(x, 0.0, tip_z)) * shank_local;
    for (x, tip, want) in [
        (50.0, -100.0, -60.0),
        (50.0, -99.0, -59.0),
        (215.0, -80.0, 5.0),
        (0.0, -37.0, 3.0),
        // Off the rim on both counts: 3-4-5 in (radial, axial).
        (213.0, -36.0, 5.0),
    ] {
        let (d, _) = prism::signed_distance(&pt, &table_local, &ps, &at(x, tip)).unwrap();
        assert!((d - want).abs() < 1e-12, "x {x} tip {tip}: {d} vs {want}");
    }
    let tilted = Pose::from_rotation(Rotation::from_rotation_y(1e-3)) * table_local;
    assert!(prism::signed_distance(&pt, &tilted, &ps, &at(50.0, -99.0)).is_none());
    // A box 100 x 40 x 240 mm centred at (280, 0, -60) (the default trunnion wall) and the
    // shank beside its -X face, 2 mm clear, past its corner (9, 12) mm from the axis (15 less
    // the radius), and its axis 10 mm inside the -X face (20 mm deep: out through that face).
    let wall = SharedShape::cuboid(50.0, 20.0, 120.0);
    let wall_pose = Pose::from_translation(Vector::new(280.0, 0.0, -60.0));
    let pw = Prism::of(&wall).unwrap();
    for (x, y, want) in [(218.0, 0.0, 2.0), (221.0, 32.0, 5.0), (240.0, 0.0, -20.0)] {
        let pose = Pose::from_translation(Vector::new(x, y, -150.0)) * shank_local;
        let (d, _) = prism::signed_distance(&pw, &wall_pose, &ps, &pose).unwrap();
        assert!((d - want).abs() < 1e-12, "({x}, {y}): {d} vs {want}");
        let (e, _) = prism::signed_distance(&ps, &pose, &pw, &wall_pose).unwrap();
        assert!(
            (e - want).abs() < 1e-12,
            "({x}, {y}) swapped: {e} vs {want}"
        );
    }
    assert!(prism::signed_distance(&pw, &wall_pose, &pw, &wall_pose).is_none());
}

#[test]
fn the_closed_form_of_parallel_prisms_is_the_largest_gap_over_directions_on_random_poses() {
    let mut rng = Lcg(11);
    let (mut apart, mut deep, mut epa_off) = (0, 0, 0.0f64);
    for case in 0..2000 {
        let a = SharedShape::cylinder(rng.range(5.0, 80.0), rng.range(3.0, 200.0));
        let box_b = case % 2 == 1;
        let b = if box_b {
            SharedShape::cuboid(
                rng.range(5.0, 150.0),
                rng.range(5.0, 150.0),
                rng.range(5.0, 150.0),
            )
        } else {
            SharedShape::cylinder(rng.range(5.0, 120.0), rng.range(3.0, 100.0))
        };
        // A anywhere; B's axis along A's (a box's edge k along it, either sense), turned
        // about it at random.
        let axis = rng.direction();
        let ra = Rotation::from_rotation_arc(Vector::Y, axis)
            * Rotation::from_rotation_y(rng.range(0.0, 6.3));
        let k = case % 3;
        let onto_y = match (box_b, k) {
            (false, _) | (true, 1) => Rotation::IDENTITY,
            (true, 0) => Rotation::from_rotation_z(std::f64::consts::FRAC_PI_2),
            _ => Rotation::from_rotation_x(std::f64::consts::FRAC_PI_2),
        };
        let flip = if case % 4 < 2 {
            Rotation::IDENTITY
        } else {
            Rotation::from_rotation_x(std::f64::consts::PI)
        };
        let rb = ra * Rotation::from_rotation_y(rng.range(0.0, 6.3)) * flip * onto_y;
        let pa = Pose::from_parts(
            Vector::new(
                rng.range(-50.0, 50.0),
                rng.range(-50.0, 50.0),
                rng.range(-50.0, 50.0),
            ),
            ra,
        );
        let offset = rng.direction() * rng.range(0.0, 350.0);
        let pb = Pose::from_parts(pa.translation + offset, rb);
        let (prism_a, prism_b) = (Prism::of(&a).unwrap(), Prism::of(&b).unwrap());
        let Some((d, n)) = prism::signed_distance(&prism_a, &pa, &prism_b, &pb) else {
            panic!("case {case}: parallel axes not recognised");
        };
        assert!((n.length() - 1.0).abs() < 1e-12, "case {case}");
        let attained = gap(&a, &pa, &b, &pb, n);
        assert!(
            (attained - d).abs() <= 1e-9,
            "case {case}: {d} attained {attained}"
        );
        let own_axis = pa.rotation * Vector::Y;
        let mut directions: Vec<Vector> = (0..600).map(|_| rng.direction()).collect();
        directions.extend([own_axis, -own_axis]);
        for u in [Vector::X, Vector::Z, -Vector::X, -Vector::Z] {
            directions.push(pa.rotation * u);
            directions.push(pb.rotation * u);
        }
        for m in directions {
            let m_local = pa.rotation.inverse() * m;
            let g = gap(&a, &pa, &b, &pb, m_local);
            assert!(
                g <= d + 1e-9,
                "case {case}: direction {m:?} gives {g} > {d}"
            );
        }
        if d > 1e-3 {
            apart += 1;
            let gjk = signed_distance(&pa, a.as_ref(), &pb, b.as_ref(), &mut None);
            // GJK's distance is that of two points of the shapes (never below the true one)
            // and stops within a relative tolerance.
            assert!(
                gjk >= d - 1e-9 && gjk - d <= 1e-6 + 1e-7 * d,
                "case {case}: GJK {gjk} vs {d}"
            );
        } else if d < -1.0 {
            deep += 1;
            let epa = signed_distance(&pa, a.as_ref(), &pb, b.as_ref(), &mut None);
            epa_off = epa_off.max((epa - d).abs());
        }
        // Tilted out of parallel by far more than the snap allows: no closed form.
        let tilt = Rotation::from_rotation_x(1e-6) * rb;
        let pb_tilted = Pose::from_parts(pb.translation, tilt);
        let reach = 400.0;
        assert!(1e-6 * reach > SNAP_MM);
        assert!(
            prism::signed_distance(&prism_a, &pa, &prism_b, &pb_tilted).is_none(),
            "case {case}"
        );
    }
    eprintln!(
        "parallel prisms: {apart} apart, {deep} over 1 mm deep; EPA off by up to {epa_off:.3} mm"
    );
    assert!(apart > 200 && deep > 200, "{apart} {deep}");
}
