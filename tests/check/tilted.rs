//! Tilted cylinders (a tool stack on a tilted table: the axes not parallel, so GJK/EPA
//! answers, `src/check/scene/shapes.rs`) against a box and against the table's cylinder,
//! checked against dense sampling of the cylinder's surface written here.
//!
//! The cylinder stands in the top face of a part whose other faces are far away (the way
//! out through any of them is longer than 100 mm, the depths here at most 30 mm), so its
//! signed distance is that of its lowest point to the top face: `top − min z` deep, or
//! `min z − top` clear. The lowest point of a cylinder lies on one of its rims; the rims
//! are sampled at `N` points each (and the mantle's lines and the caps' radii for good
//! measure), so the sampled lowest point is at most `r (1 − cos(π/N))` above the true one.

use mtsim::check::scene::{signed_distance, z_cylinder};
use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::shape::SharedShape;

use super::equivalence::Lcg;

/// Points per rim.
const N: usize = 7200;

/// The lowest z of the cylinder of half height `h` and radius `r` (its axis parry's local
/// Y) at `pose`, from `N` points on each rim, 64 along each of 360 mantle lines and 32 on
/// each of 360 radii of each cap.
fn sampled_lowest_z(pose: &Pose, h: f64, r: f64) -> f64 {
    let z = |p: Vector| (pose.translation + pose.rotation * p).z;
    let mut lowest = f64::INFINITY;
    for k in 0..N {
        let a = std::f64::consts::TAU * k as f64 / N as f64;
        let (s, c) = a.sin_cos();
        for y in [-h, h] {
            lowest = lowest.min(z(Vector::new(r * c, y, r * s)));
        }
        if k % (N / 360) == 0 {
            for i in 0..=64 {
                let y = -h + 2.0 * h * i as f64 / 64.0;
                lowest = lowest.min(z(Vector::new(r * c, y, r * s)));
            }
            for i in 0..=32 {
                let rho = r * i as f64 / 32.0;
                for y in [-h, h] {
                    lowest = lowest.min(z(Vector::new(rho * c, y, rho * s)));
                }
            }
        }
    }
    lowest
}

/// The scene's signed distance of a tilted cylinder (tilt 2° to 80° from vertical, any
/// azimuth, radius 3-60 mm, half height 5-150 mm) whose lowest point is up to 30 mm deep in
/// or 10 mm above the top (z = 0) of a box 600 × 600 × 300 mm and of a table cylinder of
/// radius 250 mm, 60 mm thick, near their middle, equals the sampled `top − min z` (deep)
/// or `min z − top` (clear): never nearer than the sampling's error, and within 1e-6 mm
/// and 1e-7 of the depth.
#[test]
fn a_tilted_cylinder_in_a_box_and_in_a_table_is_as_deep_as_its_sampled_lowest_point() {
    let (table, table_pose) = z_cylinder(-60.0, 0.0, 250.0);
    let block = SharedShape::cuboid(300.0, 300.0, 150.0);
    let block_pose = Pose::from_translation(Vector::new(0.0, 0.0, -150.0));
    let mut rng = Lcg(42);
    let (mut deep, mut worst) = (0, 0.0f64);
    for case in 0..400 {
        let (h, r) = (rng.range(5.0, 150.0), rng.range(3.0, 60.0));
        let (tilt, azimuth) = (
            rng.range(2.0, 80.0).to_radians(),
            rng.range(0.0, std::f64::consts::TAU),
        );
        let axis = Vector::new(
            tilt.sin() * azimuth.cos(),
            tilt.sin() * azimuth.sin(),
            tilt.cos(),
        );
        let rotation = Rotation::from_rotation_arc(Vector::Y, axis);
        // Placed so that its lowest point is near the wanted height (the assertion takes the
        // sampled one, not this).
        let reach_down = h * tilt.cos() + r * tilt.sin();
        let lowest = rng.range(-30.0, 10.0);
        let centre = Vector::new(
            rng.range(-30.0, 30.0),
            rng.range(-30.0, 30.0),
            lowest + reach_down,
        );
        let pose = Pose::from_parts(centre, rotation);
        let cylinder = SharedShape::cylinder(h, r);
        let sampled = sampled_lowest_z(&pose, h, r);
        let error = r * (1.0 - (std::f64::consts::PI / N as f64).cos());
        for (name, part, part_pose) in
            [("box", &block, &block_pose), ("table", &table, &table_pose)]
        {
            // Either way round: the tool as shape 2 (as the scene pairs it) and as shape 1.
            let mut warm = None;
            let d = signed_distance(
                part_pose,
                part.as_ref(),
                &pose,
                cylinder.as_ref(),
                &mut warm,
            );
            let mut warm = None;
            let e = signed_distance(
                &pose,
                cylinder.as_ref(),
                part_pose,
                part.as_ref(),
                &mut warm,
            );
            let allowed = 1e-6 + 1e-7 * sampled.abs();
            for got in [d, e] {
                // The true lowest point is at most `error` below the sampled one.
                let off = (got - sampled).max(sampled - error - got).max(0.0);
                assert!(
                    off <= allowed,
                    "case {case} {name}: tilt {:.1}° h {h:.2} r {r:.2}: {got} vs sampled {sampled}",
                    tilt.to_degrees()
                );
                worst = worst.max(off);
            }
            deep += usize::from(sampled < 0.0);
        }
    }
    eprintln!("tilted cylinders: {deep} of 800 deep; largest difference {worst:.2e} mm");
    assert!(deep > 400, "{deep}");
}
