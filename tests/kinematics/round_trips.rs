//! Forward and inverse kinematics: round trips on every layout, and the spec's conventions.

use mtsim::kinematics::{Branch, Kinematics, Layout, ToolPose};
use mtsim::{Axis, AxisVec};
use nalgebra::{Point3, Vector3};
use proptest::prelude::*;

fn kin(layout: Layout) -> Kinematics {
    Kinematics::new(layout, Vector3::new(12.5, -40.0, 80.0))
}

fn unit_axis(polar_deg: f64, azimuth_deg: f64) -> Vector3<f64> {
    let (p, a) = (polar_deg.to_radians(), azimuth_deg.to_radians());
    Vector3::new(p.sin() * a.cos(), p.sin() * a.sin(), p.cos())
}

proptest! {
    /// FK(IK(p, t)) = (p, t) to 1e-9, on both branches and both tilting layouts.
    #[test]
    fn forward_of_inverse_is_identity(
        px in -300.0..300.0f64, py in -300.0..300.0f64, pz in -100.0..400.0f64,
        polar in 0.5..89.0f64, azimuth in -180.0..180.0f64, previous_c in -720.0..720.0f64,
        secondary in any::<bool>(), bc in any::<bool>(),
    ) {
        let k = kin(if bc { Layout::TrtBc } else { Layout::TrtAc });
        let pose = ToolPose { tip: Point3::new(px, py, pz), axis: unit_axis(polar, azimuth) };
        let branch = if secondary { Branch::Secondary } else { Branch::Primary };
        let q = k.inverse(&pose, branch, previous_c);
        let back = k.forward(&q);
        prop_assert!((back.tip - pose.tip).norm() < 1e-9, "tip {:?} vs {:?}", back.tip, pose.tip);
        prop_assert!((back.axis - pose.axis).norm() < 1e-9, "axis {:?} vs {:?}", back.axis, pose.axis);
        // C is unwrapped to within half a turn of the reference.
        prop_assert!((q[Axis::C] - previous_c).abs() <= 180.0 + 1e-9);
        // The branch fixes the tilt's sign.
        let tilt = q[k.layout.tilt_axis().unwrap()];
        let sign_ok = if secondary { tilt <= 0.0 } else { tilt >= 0.0 };
        prop_assert!(sign_ok, "tilt {} on {:?}", tilt, branch);
    }

    /// IK(FK(q)) = q on the chosen branch.
    #[test]
    fn inverse_of_forward_is_identity(
        x in -300.0..300.0f64, y in -300.0..300.0f64, z in -100.0..400.0f64,
        tilt in 0.5..120.0f64, c in -400.0..400.0f64, secondary in any::<bool>(), bc in any::<bool>(),
    ) {
        let k = kin(if bc { Layout::TrtBc } else { Layout::TrtAc });
        let mut q = AxisVec::ZERO;
        q[Axis::X] = x; q[Axis::Y] = y; q[Axis::Z] = z; q[Axis::C] = c;
        q[k.layout.tilt_axis().unwrap()] = if secondary { -tilt } else { tilt };
        let branch = if secondary { Branch::Secondary } else { Branch::Primary };
        let back = k.inverse(&k.forward(&q), branch, c + 3.0);
        for axis in k.layout.axes() {
            prop_assert!((back[*axis] - q[*axis]).abs() < 1e-9, "{} {} vs {}", axis, back[*axis], q[*axis]);
        }
    }
}

#[test]
fn spec_convention_a_point_on_the_table_appears_at_rx_a_rz_c_p() {
    // A = 90, C = 90: Rz(90) maps table +X to +Y; Rx(90) maps +Y to +Z.
    let k = Kinematics::new(Layout::TrtAc, Vector3::zeros());
    let mut q = AxisVec::ZERO;
    q[Axis::A] = 90.0;
    q[Axis::C] = 90.0;
    let m = k.table_to_machine(&q, &Point3::new(10.0, 0.0, 0.0));
    assert!((m - Point3::new(0.0, 0.0, 10.0)).norm() < 1e-12, "{m:?}");
}

#[test]
fn spec_inverse_formulas_a_is_acos_k_and_c_is_atan2_i_j() {
    let k = Kinematics::new(Layout::TrtAc, Vector3::zeros());
    let t = unit_axis(25.0, 180.0); // leaning toward table -X, as at the cone's θ = 0
    let pose = ToolPose {
        tip: Point3::new(1.0, 2.0, 3.0),
        axis: t,
    };
    let q = k.inverse(&pose, Branch::Primary, 0.0);
    assert!((q[Axis::A] - t.z.acos().to_degrees()).abs() < 1e-12);
    assert!((q[Axis::C] - t.x.atan2(t.y).to_degrees()).abs() < 1e-12);
    assert!((q[Axis::A] - 25.0).abs() < 1e-12 && (q[Axis::C] - -90.0).abs() < 1e-12);
}

#[test]
fn c_is_kept_when_the_tool_axis_is_along_the_table_z() {
    let k = Kinematics::new(Layout::TrtAc, Vector3::zeros());
    let pose = ToolPose {
        tip: Point3::new(5.0, 6.0, 7.0),
        axis: Vector3::z(),
    };
    let q = k.inverse(&pose, Branch::Primary, 123.4);
    assert_eq!(q[Axis::C], 123.4);
    assert_eq!(q[Axis::A], 0.0);
    // The tip turns with the kept C: (x, y) rotated by 123.4 deg.
    let (s, c) = 123.4f64.to_radians().sin_cos();
    assert!((q[Axis::X] - (5.0 * c - 6.0 * s)).abs() < 1e-12);
    assert!((q[Axis::Y] - (5.0 * s + 6.0 * c)).abs() < 1e-12);
}

#[test]
fn the_secondary_branch_is_the_primary_with_negative_tilt_and_c_plus_180() {
    let k = Kinematics::new(Layout::TrtAc, Vector3::zeros());
    let pose = ToolPose {
        tip: Point3::new(30.0, -20.0, 150.0),
        axis: unit_axis(40.0, 60.0),
    };
    let p = k.inverse(&pose, Branch::Primary, 0.0);
    let s = k.inverse(&pose, Branch::Secondary, p[Axis::C] + 180.0);
    assert!((s[Axis::A] + p[Axis::A]).abs() < 1e-12);
    assert!((s[Axis::C] - p[Axis::C] - 180.0).abs() < 1e-9);
}

#[test]
fn the_three_axis_layout_is_the_identity() {
    let k = Kinematics::new(Layout::Xyz, Vector3::zeros());
    let pose = ToolPose {
        tip: Point3::new(1.5, -2.5, 3.5),
        axis: Vector3::z(),
    };
    let q = k.inverse(&pose, Branch::Primary, 0.0);
    assert_eq!((q[Axis::X], q[Axis::Y], q[Axis::Z]), (1.5, -2.5, 3.5));
    assert_eq!(k.forward(&q), pose);
}

proptest! {
    /// The ball bar's rotations near the commanded pose: sin and cos of `r + δ` from those of
    /// `r` agree with `sin_cos` to a few ulp (|δ| up to 0.01 rad by the series, beyond it by
    /// `sin_cos` itself), so the bar length moves by less than 1e-13 mm.
    #[test]
    fn sin_cos_near_a_reference_angle_match_sin_cos(r in -7.0f64..7.0, d in -0.02f64..0.02) {
        let (s, c) = mtsim::kinematics::add_small_angle(r + d, r, r.sin_cos());
        let (s_ref, c_ref) = (r + d).sin_cos();
        prop_assert!((s - s_ref).abs() <= 1e-15, "sin: {s} vs {s_ref}");
        prop_assert!((c - c_ref).abs() <= 1e-15, "cos: {c} vs {c_ref}");
    }

    /// The rotation from those sines and cosines is the table rotation at the pose.
    #[test]
    fn rotation_near_the_command_is_the_table_rotation(
        a in -120.0f64..120.0, c in -720.0f64..720.0, da in -0.05f64..0.05, dc in -0.05f64..0.05
    ) {
        for layout in [Layout::TrtAc, Layout::TrtBc] {
            let k = kin(layout);
            let tilt = layout.tilt_axis().unwrap();
            let mut q = AxisVec::ZERO;
            q[tilt] = a;
            q[Axis::C] = c;
            let mut near = q;
            near[tilt] += da;
            near[Axis::C] += dc;
            let at = k.rotary_sin_cos(&q);
            let r = k.rotation_of(&k.rotary_sin_cos_near(&near, &q, &at));
            let p = Vector3::new(100.0, -60.0, 200.0);
            prop_assert!((r * p - k.table_rotation(&near) * p).norm() < 1e-12);
        }
    }
}
