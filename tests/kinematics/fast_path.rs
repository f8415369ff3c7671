//! A named layout's closed forms are the fast path of its chain: the rotation the
//! interpolator applies every sample (`Kinematics::turned_to_machine`, one `sin_cos` per
//! angle, the rotations one after the other), the frames the collision monitor bounds the
//! tool's relative motion in (`Kinematics::into_table_frames`), and the rotation matrix the
//! ball bar reads (`Kinematics::table_rotation`) all agree with the chain the layout is read
//! as (`Kinematics::chain`, a product of exponentials through Rodrigues' formula) to within
//! 10⁻¹² mm on points up to 500 mm from the pivot. They differ in the last bits only, from
//! the order of the floating-point operations; the largest difference is printed.

use mtsim::kinematics::{Kinematics, Layout};
use mtsim::{Axis, AxisVec};
use nalgebra::{Point3, Vector3};

/// Every layout with a chain, at a pivot off the origin.
fn machines() -> Vec<Kinematics> {
    Layout::ALL
        .into_iter()
        .map(|l| Kinematics::new(l, Vector3::new(12.5, -40.0, 80.0)))
        .filter(|k| k.chain().is_some())
        .collect()
}

/// Axis positions spread over the rotaries' turns (deterministic, no two alike).
fn poses() -> Vec<AxisVec> {
    (0..400)
        .map(|i| {
            let f = i as f64;
            let mut q = AxisVec::ZERO;
            q[Axis::X] = 300.0 * (0.37 * f).sin();
            q[Axis::Y] = -250.0 * (0.11 * f).cos();
            q[Axis::Z] = 120.0 * (0.23 * f).sin();
            q[Axis::A] = (73.3 * f) % 720.0 - 360.0;
            q[Axis::B] = (41.9 * f) % 240.0 - 120.0;
            q[Axis::C] = (97.1 * f) % 1080.0 - 540.0;
            q
        })
        .collect()
}

/// Table-frame points up to 500 mm from the pivot.
fn points() -> [[f64; 3]; 4] {
    [
        [0.0, 0.0, 0.0],
        [100.0, -50.0, 200.0],
        [-300.0, 250.0, -120.0],
        [499.0, 0.0, 0.0],
    ]
}

#[test]
fn the_written_out_rotation_is_the_chain_within_a_picometre() {
    let mut worst = 0.0f64;
    for k in machines() {
        let chain = k.chain().unwrap();
        for q in poses() {
            let table = chain.table_pose(&q);
            for p in points() {
                let by_chain = table * Point3::from(Vector3::from(p) + k.pivot_mm);
                let fast = k.turned_to_machine(&q, p);
                let by_matrix = k.table_to_machine(&q, &Point3::from(p));
                for i in 0..3 {
                    let d = (fast[i] - by_chain[i]).abs();
                    worst = worst.max(d).max((by_matrix[i] - by_chain[i]).abs());
                    assert!(
                        d < 1e-12,
                        "{:?} at {q:?}, p {p:?}: {fast:?} against the chain's {by_chain}",
                        k.layout
                    );
                    assert!((by_matrix[i] - by_chain[i]).abs() < 1e-12);
                }
            }
        }
    }
    println!("largest difference from the chain: {worst:e} mm");
}

#[test]
fn the_table_and_cradle_frames_are_the_chains() {
    let mut worst = 0.0f64;
    for k in machines() {
        let chain = k.chain().unwrap();
        let tilt = k.layout.tilt_axis();
        for q in poses() {
            let u = Vector3::new(12.0, -250.0, 80.0);
            let [table, cradle] = k.into_table_frames(&q, u);
            let by_chain = chain.table_pose(&q).rotation.inverse_transform_vector(&u);
            // The cradle: the table with its own axis at 0 (xyza has none: the machine's).
            let mut only_tilt = q;
            match (tilt, k.layout.table_axis()) {
                (Some(_), Some(t)) => only_tilt[t] = 0.0,
                _ => only_tilt = AxisVec::ZERO,
            }
            let cradle_by_chain = chain
                .table_pose(&only_tilt)
                .rotation
                .inverse_transform_vector(&u);
            worst = worst
                .max((table - by_chain).norm())
                .max((cradle - cradle_by_chain).norm());
            assert!((table - by_chain).norm() < 1e-12, "{:?} {q:?}", k.layout);
            assert!(
                (cradle - cradle_by_chain).norm() < 1e-12,
                "{:?} {q:?}",
                k.layout
            );
        }
    }
    println!("largest difference from the chain: {worst:e} mm");
}

#[test]
fn tcp_per_sample_is_tcp_axes_within_a_picometre() {
    for k in machines() {
        for q in poses() {
            let slow = k.tcp_axes(&q, 85.0);
            let fast = k.tcp_axes_per_sample(&q, 85.0);
            for a in Axis::ALL {
                assert!((slow[a] - fast[a]).abs() < 1e-12, "{:?} {a}", k.layout);
            }
        }
    }
}
