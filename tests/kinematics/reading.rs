//! The bar's reading of the rotaries, two angles at a time: each angle's sine and cosine
//! the bits of the one-angle formulas, and within a few ulp of the library's `sin_cos`.

use mtsim::kinematics::{add_small_angle, Kinematics, Layout};
use mtsim::numeric::sin_cos_deg;
use mtsim::AxisVec;
use nalgebra::Vector3;

const LAYOUTS: [Layout; 5] = [
    Layout::TrtAc,
    Layout::TrtBc,
    Layout::TrtAb,
    Layout::Xyza,
    Layout::Xyz,
];

fn bits((s, c): (f64, f64)) -> (u64, u64) {
    (s.to_bits(), c.to_bits())
}

/// `got` is within `ulps` ulp (of the angle in radians, at least of 1) of the library's sine
/// and cosine of `deg` in radians; an axis the layout lacks (`axis` None) is not checked.
fn assert_near_library(axis: Option<mtsim::Axis>, got: (f64, f64), deg: f64, ulps: f64) {
    if axis.is_none() {
        return;
    }
    let x = deg.to_radians();
    let (s, c) = x.sin_cos();
    let tol = ulps * f64::EPSILON * x.abs().max(1.0);
    let (ds, dc) = ((got.0 - s).abs(), (got.1 - c).abs());
    assert!(ds <= tol && dc <= tol, "{axis:?} at {deg}°: {ds:e} {dc:e}");
}

/// Commanded rotaries over several turns, and actual ones off them by steps inside and
/// beyond the series' 0.01 rad (0.573°).
fn poses() -> impl Iterator<Item = (f64, f64, f64, f64)> {
    (0..4_000).map(|k| {
        let t = k as f64;
        let (table, tilt) = (0.731 * t - 1400.0, 95.0 * (0.013 * t).sin());
        let steps = [0.0, 1e-9, -3e-4, 0.2, -0.57, 0.58, -2.0, 45.0];
        let (d_table, d_tilt) = (steps[k % 8], steps[(k / 8) % 8]);
        (table, tilt, table + d_table, tilt + d_tilt)
    })
}

#[test]
fn the_commanded_rotaries_are_each_angles_sin_cos_deg() {
    for layout in LAYOUTS {
        let k = Kinematics::new(layout, Vector3::new(10.0, -20.0, 30.0));
        for (table, tilt, _, _) in poses() {
            let mut q = AxisVec::ZERO;
            let (table_axis, tilt_axis) = (layout.table_axis(), layout.tilt_axis());
            if let Some(a) = table_axis {
                q[a] = table;
            }
            if let Some(a) = tilt_axis {
                q[a] = tilt;
            }
            let at = k.rotary_sin_cos(&q);
            let want = |a: Option<_>, deg: f64| sin_cos_deg(a.map_or(0.0, |_| deg));
            assert_eq!(
                bits(at.c),
                bits(want(table_axis, table)),
                "{layout:?} {table}"
            );
            assert_eq!(
                bits(at.tilt),
                bits(want(tilt_axis, tilt)),
                "{layout:?} {tilt}"
            );
            // And the closed form: the library's sine and cosine of each angle in radians,
            // whose conversion rounds by half an ulp of the radians.
            assert_near_library(table_axis, at.c, table, 2.0);
            assert_near_library(tilt_axis, at.tilt, tilt, 2.0);
        }
    }
}

#[test]
fn the_actual_rotaries_near_the_command_are_each_angles_add_small_angle() {
    for layout in LAYOUTS {
        let k = Kinematics::new(layout, Vector3::zeros());
        let (table_axis, tilt_axis) = (layout.table_axis(), layout.tilt_axis());
        for (table, tilt, table_q, tilt_q) in poses() {
            let (mut command, mut q) = (AxisVec::ZERO, AxisVec::ZERO);
            if let Some(a) = table_axis {
                (command[a], q[a]) = (table, table_q);
            }
            if let Some(a) = tilt_axis {
                (command[a], q[a]) = (tilt, tilt_q);
            }
            let at = k.rotary_sin_cos(&command);
            let near = k.rotary_sin_cos_near(&q, &command, &at);
            let one = |a: Option<_>, angle: f64, reference: f64, at: (f64, f64)| match a {
                None => at,
                Some(_) => add_small_angle(angle.to_radians(), reference.to_radians(), at),
            };
            let (want_c, want_tilt) = (
                one(table_axis, table_q, table, at.c),
                one(tilt_axis, tilt_q, tilt, at.tilt),
            );
            assert_eq!(bits(near.c), bits(want_c), "{layout:?} {table} → {table_q}");
            assert_eq!(
                bits(near.tilt),
                bits(want_tilt),
                "{layout:?} {tilt} → {tilt_q}"
            );
            // Within a few ulp of the library at the actual angles.
            assert_near_library(table_axis, near.c, table_q, 4.0);
            assert_near_library(tilt_axis, near.tilt, tilt_q, 4.0);
        }
    }
}
